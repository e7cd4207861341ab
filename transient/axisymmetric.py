"""Axisymmetric run-in of the homogeneous cylinder: the reference of the run-in history.

A homogeneous flat punch stays axisymmetric while it wears, so its run-in is
a one-dimensional problem in the radius.  This module solves it to a
precision the square pixel grid cannot reach near the rim, where the
flat punch's ``(a^2 - r^2)^(-1/2)`` pressure wears off in a layer of width
about ``k E* s``, and serves as the reference of the run-in history
(docs/model.md, "The run-in history"; docs/benchmarks.md, "Run-in
convergence").

Method
------
- *Rings.* The face is cut into ``N`` rings with edges
  ``r_j = a (1 - (1 - j/N)^beta)``, graded towards the rim (``beta = 4``:
  the outermost ring is ``a / N^4`` wide); the pressure is constant on each
  ring.
- *Influence.* The displacement at the centre ``r_i`` of ring ``i`` under a
  unit pressure on ring ``j`` is (eq. 8 integrated over the angle)
  ``4 / (pi E*) * integral over ring j of t K(m) / (r_i + t) dt``,
  ``m = 4 r_i t / (r_i + t)^2``, with ``K`` the complete elliptic integral
  of the first kind (``scipy.special.ellipkm1`` of ``1 - m``, accurate at
  the log singularity ``t -> r_i``): 12-point Gauss-Legendre away from the
  diagonal, adaptive quadrature (:func:`scipy.integrate.quad`) for the seven
  entries nearest to it.
- *Dynamics.* The punch stays in full contact (the pressure of a worn
  homogeneous face is positive everywhere), so ``A p = d - w`` with the load
  ``sum_j A_j p_j = F`` gives ``p = c - B w``, affine in the height ``w``,
  and the run-in ``dw/ds = k p`` is the linear system
  ``dw/ds = -k B w + k c``.  It is integrated *exactly* in the distance:
  with ``-k B = V diag(mu) V^-1``,
  ``w(s) = V diag(s phi(mu s)) V^-1 k c``, ``phi(z) = (e^z - 1)/z``, from
  the flat face ``w(0) = 0``.  The only error is the radial discretisation.
- *Figures.* The face ``f = d - w``; its rms slope over the disk from the
  differences between ring centres (slope squared times ``2 pi r dr``,
  the last half ring at the rim with the last difference), its rms height
  with the ring areas.  Both converge at second order in ``1/N``
  (measured: differences 4.8e-4, 1.2e-4, 3.1e-5 of the normalised rms slope
  at ``s = 1e-3 s*`` for N = 150 -> 300 -> 600 -> 1200, beta = 4), so
  :func:`reference_history` extrapolates ``N/2, N`` (Richardson, order 2)
  and reports the extrapolation's size as its error.

At ``s = 0`` the face is flat (rms slope 0); for any ``s > 0`` the rim layer
carries a mean-square slope that does not vanish with its width (slope of
order ``K / (E* l^(1/2))`` over the width ``l``, ``K`` the rim's stress
intensity), so the history jumps from 0 to about ``0.848 grad_f0``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.integrate
import scipy.special

__all__ = ["AxisymmetricRunIn", "AxisymmetricState", "ReferenceHistory", "reference_history"]

# Gauss-Legendre points of the ring integrals away from the diagonal.
_GAUSS_POINTS = 12
# Entries within this many rings of the diagonal are integrated adaptively.
_NEAR = 3


@dataclasses.dataclass(frozen=True)
class AxisymmetricState:
    """The axisymmetric run-in at one sliding distance.

    Attributes
    ----------
    distance : float, m
    pressure : ndarray, shape (N,), Pa
        Pressure on each ring.
    approach : float, m
        Rigid approach ``d``.
    face : ndarray, shape (N,), m
        Face ``f = d - w`` at the ring centres (the convention of the steady
        face ``f_inf = K p``).
    rms_slope : float
        Rms of ``df/dr`` over the disk.
    rms_height : float, m
        Rms of ``f`` about its mean over the disk.
    """

    distance: float
    pressure: np.ndarray
    approach: float
    face: np.ndarray
    rms_slope: float
    rms_height: float


class AxisymmetricRunIn:
    """Run-in of a homogeneous cylindrical punch from its flat face, on graded rings.

    Parameters
    ----------
    rings : int, optional
        Number of rings ``N`` (default 600).
    grading : float, optional
        Grading exponent ``beta`` of the ring edges
        ``a (1 - (1 - j/N)^beta)`` (default 4).
    radius : float, m, optional
        Punch radius ``a`` (default 1).
    E_star : float, Pa, optional
        Effective modulus (default 1).
    normal_force : float, N, optional
        Default ``pi``: mean pressure 1 Pa for the default radius.
    wear_coefficient : float, 1/Pa, optional
        Archard's ``k`` (default 1): ``s* = a / (k E*)`` is 1 m with the
        defaults.

    Examples
    --------
    The flat punch (eq. 8 on the disk: approach ``F / (2 a E*)``) and the
    rms slope after ``0.1 s*``:

    >>> ref = AxisymmetricRunIn(rings=200)
    >>> flat = ref.state(0.0)
    >>> print(f"{flat.approach / (ref.normal_force / (2 * ref.radius * ref.E_star)):.4f}")
    1.0000
    >>> state = ref.state(0.1 * ref.distance_scale)
    >>> print(f"{state.rms_slope / ref.reference_slope:.3f}")
    0.887
    """

    def __init__(self, rings=600, *, grading=4.0, radius=1.0, E_star=1.0,
                 normal_force=math.pi, wear_coefficient=1.0):
        if isinstance(rings, bool) or int(rings) != rings or rings < 4:
            raise ValueError(f"rings must be an integer >= 4, got {rings!r}")
        if not (math.isfinite(grading) and grading >= 1):
            raise ValueError(f"grading must be a finite number >= 1, got {grading!r}")
        for name, value in (("radius", radius), ("E_star", E_star),
                            ("normal_force", normal_force),
                            ("wear_coefficient", wear_coefficient)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value!r}")
        self.rings = int(rings)
        self.grading = float(grading)
        self.radius = float(radius)
        self.E_star = float(E_star)
        self.normal_force = float(normal_force)
        self.wear_coefficient = float(wear_coefficient)
        j = np.arange(self.rings + 1) / self.rings
        self.edges = self.radius * (1.0 - (1.0 - j) ** self.grading)
        self.centres = 0.5 * (self.edges[1:] + self.edges[:-1])
        self.areas = np.pi * (self.edges[1:] ** 2 - self.edges[:-1] ** 2)
        self.influence = self._influence()
        self._dynamics()

    # -- scales ----------------------------------------------------------
    @property
    def mean_pressure(self):
        """``pbar = F / (pi a^2)``, Pa."""
        return self.normal_force / (math.pi * self.radius ** 2)

    @property
    def reference_slope(self):
        """``grad_f0 = 4 pbar / (pi E*)`` (eq. 12)."""
        return 4.0 * self.mean_pressure / (math.pi * self.E_star)

    @property
    def distance_scale(self):
        """``s* = a / (k E*)``, m."""
        return self.radius / (self.wear_coefficient * self.E_star)

    # -- operator --------------------------------------------------------
    def _influence(self):
        """Displacement at the ring centres per unit pressure on each ring, m/Pa, (N, N)."""
        n = self.rings
        rc, lo, hi = self.centres, self.edges[:-1], self.edges[1:]
        x, wq = np.polynomial.legendre.leggauss(_GAUSS_POINTS)
        t = 0.5 * (hi - lo)[:, None] * x + 0.5 * (hi + lo)[:, None]
        weights = 0.5 * (hi - lo)[:, None] * wq
        matrix = np.einsum("ijq,jq->ij", _ring_kernel(rc[:, None, None], t[None]), weights)
        for i in range(n):
            for j in range(max(0, i - _NEAR), min(n, i + _NEAR + 1)):
                inside = [rc[i]] if lo[j] < rc[i] < hi[j] else None
                matrix[i, j] = scipy.integrate.quad(
                    lambda s, r=rc[i]: _ring_kernel(r, s), lo[j], hi[j], points=inside,
                    limit=200)[0]
        return 4.0 / (math.pi * self.E_star) * matrix

    def _dynamics(self):
        """The affine map ``p = c - B w`` and the eigen-decomposition of ``-k B``."""
        a_inv = np.linalg.inv(self.influence)
        a_inv_one = a_inv.sum(axis=1)
        self._load_row = self.areas @ a_inv
        self._denominator = float(self.areas @ a_inv_one)
        b = a_inv - np.outer(a_inv_one, self._load_row) / self._denominator
        self._b = b
        self._c = a_inv_one * self.normal_force / self._denominator
        mu, vectors = np.linalg.eig(-self.wear_coefficient * b)
        if np.max(np.abs(mu.imag)) > 1e-8 * np.max(np.abs(mu.real)):
            raise RuntimeError("the ring generator has complex eigenvalues: refine the rings")
        self._mu = mu.real
        self._vectors = vectors.real
        self._forcing = np.linalg.solve(self._vectors, self.wear_coefficient * self._c)
        # The zero eigenvalue belongs to a uniform height (B 1 = 0): the rigid
        # wear, which moves the face and the approach together.  Leaving it
        # out keeps the heights of the size of the relief at any distance.
        self._forcing[np.argmin(np.abs(self._mu))] = 0.0

    # -- states ----------------------------------------------------------
    def height(self, distance):
        """Height ``w`` worn off each ring after ``distance`` (m) of sliding, m, shape (N,).

        Up to a constant: the rigid part of the wear is left out.
        """
        s = float(distance)
        if not (math.isfinite(s) and s >= 0):
            raise ValueError(f"distance must be a finite non-negative number, got {distance!r} m")
        z = self._mu * s
        small = np.abs(z) < 1e-12
        phi = np.where(small, 1.0 + 0.5 * z, np.expm1(z) / np.where(small, 1.0, z))
        return self._vectors @ (s * phi * self._forcing)

    def state(self, distance):
        """The run-in after ``distance`` (m) of sliding from the flat face.

        Returns
        -------
        AxisymmetricState

        Raises
        ------
        RuntimeError
            A ring lost contact (not expected for this punch).
        """
        w = self.height(distance)
        pressure = self._c - self._b @ w
        if np.any(pressure <= 0):
            raise RuntimeError(f"ring pressure not positive at s = {distance!r} m: the "
                               "full-contact model does not hold")
        approach = (self.normal_force + float(self._load_row @ w)) / self._denominator
        face = approach - w
        return AxisymmetricState(distance=float(distance), pressure=pressure,
                                 approach=approach, face=face,
                                 rms_slope=self.rms_slope(face),
                                 rms_height=self.rms_height(face))

    def rms_slope(self, face):
        """Rms over the disk of the radial slope of a face given at the ring centres.

        Parameters
        ----------
        face : ndarray, shape (N,), m

        Returns
        -------
        float
            Differences between ring centres, squared, times ``2 pi r dr``
            at the midpoints; the half ring at the rim takes the last
            difference.
        """
        rc = self.centres
        slope = np.diff(face) / np.diff(rc)
        mid = 0.5 * (rc[1:] + rc[:-1])
        energy = np.sum(slope ** 2 * 2 * np.pi * mid * np.diff(rc))
        energy += slope[-1] ** 2 * 2 * np.pi * self.radius * (self.radius - rc[-1])
        return math.sqrt(energy / (math.pi * self.radius ** 2))

    def rms_height(self, face):
        """Rms of a face (m, at the ring centres) about its mean over the disk, m."""
        total = math.pi * self.radius ** 2
        mean = float(self.areas @ face) / total
        return math.sqrt(float(self.areas @ (face - mean) ** 2) / total)


def _ring_kernel(r, t):
    """``t K(m) / (r + t)``, ``m = 4 r t / (r + t)^2``: the angular integral of ``1/|x - x'|``."""
    q = ((r - t) / (r + t)) ** 2
    return t / (r + t) * scipy.special.ellipkm1(q)


@dataclasses.dataclass(frozen=True)
class ReferenceHistory:
    """Normalised run-in history of the homogeneous cylinder, extrapolated in the rings.

    Attributes
    ----------
    distance : ndarray, shape (K,)
        Sliding distances, units of ``s* = a / (k E*)``.
    rms_slope : ndarray, shape (K,)
        Rms slope of the face over ``grad_f0``.
    rms_slope_error : ndarray, shape (K,)
        Size of the Richardson extrapolation, an estimate of its error.
    rms_height : ndarray, shape (K,)
        Rms height of the face over ``grad_f0 a``.
    rms_height_error : ndarray, shape (K,)
    rings : tuple of int
        The two ring counts ``(N/2, N)``.
    """

    distance: np.ndarray
    rms_slope: np.ndarray
    rms_slope_error: np.ndarray
    rms_height: np.ndarray
    rms_height_error: np.ndarray
    rings: tuple


def reference_history(distances, *, rings=1200, grading=4.0):
    """The homogeneous run-in history, second-order extrapolated from ``N/2`` and ``N`` rings.

    Parameters
    ----------
    distances : array_like, shape (K,)
        Sliding distances in units of ``s*``, non-negative.
    rings : int, optional
        The finer ring count ``N`` (default 1200: about 5 s on 2 cores).
    grading : float, optional
        Grading exponent (default 4).

    Returns
    -------
    ReferenceHistory
        Normalised values; at ``s = 0`` the flat face's exact 0.

    Examples
    --------
    >>> ref = reference_history([0.0, 1.0], rings=200)
    >>> print(f"{ref.rms_slope[0]:.3f} {ref.rms_slope[1]:.4f}")
    0.000 0.9829
    """
    s = np.asarray(distances, dtype=float)
    if s.ndim != 1 or not np.all(np.isfinite(s) & (s >= 0)):
        raise ValueError(f"distances must be a 1-d array of non-negative numbers, got {s!r}")
    values = []
    counts = (int(rings) // 2, int(rings))
    for count in counts:
        model = AxisymmetricRunIn(count, grading=grading)
        states = [model.state(d * model.distance_scale) for d in s]
        values.append((np.array([st.rms_slope for st in states]) / model.reference_slope,
                       np.array([st.rms_height for st in states])
                       / (model.reference_slope * model.radius)))
    (slope_c, height_c), (slope_f, height_f) = values
    slope = slope_f + (slope_f - slope_c) / 3.0
    height = height_f + (height_f - height_c) / 3.0
    return ReferenceHistory(distance=s, rms_slope=slope,
                            rms_slope_error=np.abs(slope - slope_f),
                            rms_height=height, rms_height_error=np.abs(height - height_f),
                            rings=counts)
