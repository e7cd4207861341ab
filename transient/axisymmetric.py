"""Axisymmetric run-in of the cylinder, homogeneous or coated: the run-in history's reference.

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
  ``sum_j A_j p_j = F`` gives ``p = c - B w``, affine in the recession ``w``,
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

Coating
-------
:class:`CoatedAxisymmetricRunIn` gives a coating of thickness ``t`` and
coefficient ``k_c`` on a substrate ``k_s``: a ring wears with ``k_c`` until
its worn depth reaches ``t``.  Between two crossings ``dw/ds = D (c - B w)``
is linear and propagated exactly as above with ``-D B``; each crossing is
the root, by Brent's method, of the largest coated depth minus ``t`` on the
exact solution.  :func:`coated_reference_history` extrapolates it in the
rings (docs/model.md, "The coated reference").

At ``s = 0`` the face is flat (rms slope 0); for any ``s > 0`` the rim layer
carries a mean-square slope that does not vanish with its width (slope of
order ``K / (E* l^(1/2))`` over the width ``l``, ``K`` the rim's stress
intensity), so the history jumps from 0 to about ``0.848 grad_f0``.
"""

from __future__ import annotations

import bisect
import dataclasses
import math

import numpy as np
import scipy.integrate
import scipy.optimize
import scipy.special

from steady import reference
from steady.schema import Key

__all__ = ["AxisymmetricRunIn", "AxisymmetricState", "CoatedAxisymmetricRunIn",
           "CoatedAxisymmetricState", "CoatedReferenceHistory", "ReferenceHistory",
           "coated_reference_history", "reference_history"]

# Gauss-Legendre points of the ring integrals away from the diagonal.
_GAUSS_POINTS = 12
# Entries within this many rings of the diagonal are integrated adaptively.
_NEAR = 3

# The inputs of the axisymmetric models, each checked through its key.
_RINGS = Key("rings", "integer", low=4, low_open=False)
_GRADING = Key("grading", "number", unit="1", low=1.0, low_open=False)
_RADIUS = Key("radius", "number", unit="m", low=0.0)
_E_STAR = Key("E_star", "number", unit="Pa", low=0.0)
_NORMAL_FORCE = Key("normal_force", "number", unit="N", low=0.0)
_WEAR_COEFFICIENT = Key("wear_coefficient", "number", unit="1/Pa", low=0.0)
_THICKNESS = Key("thickness", "number", unit="m", low=0.0)
_SUBSTRATE_COEFFICIENT = Key("substrate_coefficient", "number", unit="1/Pa", low=0.0)
_DISTANCE = Key("distance", "number", unit="m", low=0.0, low_open=False)
_DISTANCES_S_STAR = Key("distances_s_star", "numbers", unit="s*", low=0.0, low_open=False)


def _distances_s_star(distances):
    """Distances (any sequence or array) checked through their key, as a 1-d float array."""
    try:
        values = np.asarray(distances, dtype=float).tolist()
    except (TypeError, ValueError):
        values = distances  # refused by the key, in its words
    return np.array(_DISTANCES_S_STAR.parse(values, ""), dtype=float)


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
        self.rings = _RINGS.parse(rings, "")
        self.grading = _GRADING.parse(grading, "")
        # Any consistent units are taken: no scale range.
        self.radius = _RADIUS.parse(radius, "", scale=False)
        self.E_star = _E_STAR.parse(E_star, "", scale=False)
        self.normal_force = _NORMAL_FORCE.parse(normal_force, "", scale=False)
        self.wear_coefficient = _WEAR_COEFFICIENT.parse(wear_coefficient, "")
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
        # The zero eigenvalue belongs to a uniform recession (B 1 = 0): the rigid
        # wear, which moves the face and the approach together.  Leaving it
        # out keeps the recessions of the size of the relief at any distance.
        self._forcing[np.argmin(np.abs(self._mu))] = 0.0

    # -- states ----------------------------------------------------------
    def recession(self, distance):
        """Height ``w`` worn off each ring after ``distance`` (m) of sliding, m, shape (N,).

        Up to a constant: the rigid part of the wear is left out.
        """
        s = _DISTANCE.parse(distance, "", scale=False)
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
        w = self.recession(distance)
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
    distance_s_star : ndarray, shape (K,)
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

    distance_s_star: np.ndarray
    rms_slope: np.ndarray
    rms_slope_error: np.ndarray
    rms_height: np.ndarray
    rms_height_error: np.ndarray
    rings: tuple


def reference_history(distances_s_star, *, rings=1200, grading=4.0):
    """The homogeneous run-in history, second-order extrapolated from ``N/2`` and ``N`` rings.

    Parameters
    ----------
    distances_s_star : array_like, shape (K,)
        Sliding distances in units of ``s* = a / (k E*)``, non-negative: the
        history is normalised, the same for every cylinder.
    rings : int, optional
        The finer ring count ``N`` (default 1200; its time: docs/benchmarks.md,
        "Run-in convergence").
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
    s = _distances_s_star(distances_s_star)
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
    recession = height_f + (height_f - height_c) / 3.0
    return ReferenceHistory(distance_s_star=s, rms_slope=slope,
                            rms_slope_error=np.abs(slope - slope_f),
                            rms_height=recession, rms_height_error=np.abs(recession - height_f),
                            rings=counts)


# A ring whose worn depth is within this fraction of the thickness at a
# crossing is counted through with the ring that crossed (rounding).
_CROSSING_TOLERANCE = 1e-12
# The doubling search for the next crossing gives up after this many doublings.
_MAX_DOUBLINGS = 200


@dataclasses.dataclass(frozen=True)
class CoatedAxisymmetricState(AxisymmetricState):
    """The coated axisymmetric run-in at one sliding distance.

    The fields of :class:`AxisymmetricState`, and:

    Attributes
    ----------
    worn_depth : ndarray, shape (N,), m
        Depth ``w`` worn off each ring from the flat face (not up to a constant).
    mean_worn_depth : float, m
        ``w`` averaged over the disk.
    rim_worn_depth : float, m
        ``w`` of the outermost ring.
    rings_through : int
        Rings whose coating is gone (worn depth at least the thickness).
    face_deviation : float
        Rms over the disk of ``f - f_inf`` over that of ``f_inf`` (means
        removed), the eq. 10 face that coating and substrate both tend to.
    """

    worn_depth: np.ndarray
    mean_worn_depth: float
    rim_worn_depth: float
    rings_through: int
    face_deviation: float


@dataclasses.dataclass
class _Segment:
    """The exact run-in between two crossings: ``dw/ds = D (c - B w)``, ``D`` fixed.

    With ``-D B = V diag(mu) V^-1``:
    ``w(start + tau) = V [e^(mu tau) V^-1 w0 + tau phi(mu tau) V^-1 D c]``.
    """

    start: float
    through: np.ndarray
    mu: np.ndarray
    vectors: np.ndarray
    initial_modes: np.ndarray
    forcing_modes: np.ndarray
    end: float = math.inf

    def worn(self, distance):
        """Worn depth of every ring at ``distance`` (m) inside the segment, m."""
        tau = distance - self.start
        z = self.mu * tau
        small = np.abs(z) < 1e-12
        phi = np.where(small, 1.0 + 0.5 * z, np.expm1(z) / np.where(small, 1.0, z))
        return self.vectors @ (np.exp(z) * self.initial_modes + tau * phi * self.forcing_modes)


class CoatedAxisymmetricRunIn(AxisymmetricRunIn):
    """Run-in of a flat cylindrical punch with a coating on a homogeneous substrate.

    A ring wears with the coating's ``k_c`` while its worn depth is under
    the thickness ``t`` and with the substrate's ``k_s`` after; the run-in
    ``dw/ds = k(w) (c - B w)`` is then linear between two crossings and is
    propagated exactly on each piece (the eigen-decomposition of ``-D B``,
    ``D`` the rings' current coefficients), each crossing located by root
    finding on the exact solution.  Rings cross from the rim inwards.

    Parameters
    ----------
    rings : int, optional
        Number of rings ``N`` (default 160: one eigen-decomposition per ring).
    thickness : float, m
        Coating thickness ``t``.
    substrate_coefficient : float, 1/Pa
        The substrate's ``k_s``.
    grading, radius, E_star, normal_force : optional
        As :class:`AxisymmetricRunIn`.
    wear_coefficient : float, 1/Pa, optional
        The coating's ``k_c`` (default 1); ``distance_scale`` is the
        coating's ``s* = a / (k_c E*)``.

    Raises
    ------
    ValueError
        A thickness or substrate coefficient not positive and finite.

    Examples
    --------
    A coating of a tenth of ``pbar a / E*`` on a substrate wearing ten
    times faster: the rim is through first, the centre last.

    >>> run = CoatedAxisymmetricRunIn(rings=40, thickness=0.1, substrate_coefficient=10.0)
    >>> first, last = run.wear_through_distances()
    >>> print(f"{first:.5f} {last:.4f}")
    0.00980 0.1454
    >>> print(run.state(0.3).rings_through)
    40
    """

    def __init__(self, rings=160, *, thickness, substrate_coefficient, grading=4.0,
                 radius=1.0, E_star=1.0, normal_force=math.pi, wear_coefficient=1.0):
        thickness = _THICKNESS.parse(thickness, "", scale=False)
        substrate_coefficient = _SUBSTRATE_COEFFICIENT.parse(substrate_coefficient, "")
        super().__init__(rings, grading=grading, radius=radius, E_star=E_star,
                         normal_force=normal_force, wear_coefficient=wear_coefficient)
        self.thickness = thickness
        self.substrate_coefficient = substrate_coefficient
        self.crossings = np.full(self.rings, math.inf)
        self.minimum_crossing_pressure = math.inf
        steady_face = reference.disk_face(self.centres, self.radius, self.mean_pressure,
                                          self.E_star)
        self._steady_face = steady_face
        total = float(self.areas.sum())
        shape = steady_face - float(self.areas @ steady_face) / total
        self._steady_shape_rms = math.sqrt(float(self.areas @ shape ** 2) / total)
        self._segments = [self._segment(0.0, np.zeros(self.rings),
                                        np.zeros(self.rings, dtype=bool))]
        self._starts = [0.0]

    # -- pieces ----------------------------------------------------------
    def _segment(self, start, worn, through):
        """The exact piece from ``start`` (m) with worn depth ``worn`` and rings ``through``."""
        k = np.where(through, self.substrate_coefficient, self.wear_coefficient)
        if not through.any():
            mu, vectors = self._mu.copy(), self._vectors
        else:
            mu, vectors = np.linalg.eig(-k[:, None] * self._b)
            if np.max(np.abs(mu.imag)) > 1e-8 * np.max(np.abs(mu.real)):
                raise RuntimeError("the ring generator has complex eigenvalues: refine the rings")
            mu, vectors = mu.real, vectors.real
        # B 1 = 0 exactly, so D B 1 = 0: the uniform wear is a zero mode,
        # kept (the worn depth is absolute) with its eigenvalue set to 0.
        mu[np.argmin(np.abs(mu))] = 0.0
        modes = np.linalg.solve(vectors, np.column_stack([worn, k * self._c]))
        return _Segment(start=float(start), through=through, mu=mu, vectors=vectors,
                        initial_modes=modes[:, 0], forcing_modes=modes[:, 1])

    def _gap(self, segment, distance):
        """Largest worn depth over the coated rings minus the thickness, m."""
        w = segment.worn(distance)
        return float(np.max(w[~segment.through])) - self.thickness

    def _cross(self, segment, distance):
        """End ``segment`` at the crossing at ``distance`` (m) and start the next piece."""
        w = segment.worn(distance)
        through = segment.through | (w >= self.thickness * (1.0 - _CROSSING_TOLERANCE))
        coated = ~segment.through
        through[np.flatnonzero(coated)[np.argmax(w[coated])]] = True
        self.crossings[through & ~segment.through] = distance
        pressure = self._c - self._b @ w
        self.minimum_crossing_pressure = min(self.minimum_crossing_pressure,
                                             float(pressure.min() / self.mean_pressure))
        if np.any(pressure <= 0):
            ring = int(np.argmin(pressure))
            raise RuntimeError(f"ring {ring} lost contact at the crossing at s = {distance!r} m: "
                               "the full-contact model does not hold")
        segment.end = float(distance)
        self._segments.append(self._segment(distance, w, through))
        self._starts.append(float(distance))

    def _advance_to(self, distance):
        """Locate every crossing up to ``distance`` (m); the piece that holds it."""
        while True:
            last = self._segments[-1]
            if distance < last.start:
                return self._segments[bisect.bisect_right(self._starts, distance) - 1]
            if last.through.all() or self._gap(last, distance) < 0:
                return last
            span = distance - last.start
            tau = scipy.optimize.brentq(lambda x, seg=last: self._gap(seg, seg.start + x),
                                        0.0, span, xtol=1e-15 * span,
                                        rtol=4 * np.finfo(float).eps)
            self._cross(last, last.start + tau)

    def _advance_all(self):
        """Locate every crossing (a doubling search ahead of each)."""
        while not self._segments[-1].through.all():
            last = self._segments[-1]
            w0 = last.worn(last.start)
            coated = ~last.through
            rate = (self.substrate_coefficient * last.through + self.wear_coefficient * coated) \
                * (self._c - self._b @ w0)
            span = (self.thickness - np.max(w0[coated])) / np.max(rate[coated])
            for _ in range(_MAX_DOUBLINGS):
                if self._gap(last, last.start + span) >= 0:
                    break
                span *= 2
            else:
                raise RuntimeError(f"no crossing found after s = {last.start!r} m")
            self._advance_to(last.start + span)

    # -- results ---------------------------------------------------------
    def recession(self, distance):
        """Depth ``w`` worn off each ring after ``distance`` (m) of sliding, m, shape (N,).

        Unlike :meth:`AxisymmetricRunIn.recession` this is the absolute worn
        depth from the flat face, rigid wear included: it decides the phase.
        """
        s = _DISTANCE.parse(distance, "", scale=False)
        return self._advance_to(s).worn(s)

    def state(self, distance):
        """The coated run-in after ``distance`` (m) of sliding from the flat face.

        Returns
        -------
        CoatedAxisymmetricState

        Raises
        ------
        RuntimeError
            A ring lost contact: the full-contact model does not hold.
        """
        w = self.recession(distance)
        s = float(distance)
        pressure = self._c - self._b @ w
        if np.any(pressure <= 0):
            raise RuntimeError(f"ring {int(np.argmin(pressure))} pressure not positive at "
                               f"s = {distance!r} m: the full-contact model does not hold")
        approach = (self.normal_force + float(self._load_row @ w)) / self._denominator
        face = approach - w
        total = math.pi * self.radius ** 2
        deviation = face - self._steady_face
        deviation = deviation - float(self.areas @ deviation) / total
        return CoatedAxisymmetricState(
            distance=s, pressure=pressure, approach=approach, face=face,
            rms_slope=self.rms_slope(face), rms_height=self.rms_height(face),
            worn_depth=w, mean_worn_depth=float(self.areas @ w) / total,
            rim_worn_depth=float(w[-1]),
            rings_through=int(np.count_nonzero(self.crossings <= s)),
            face_deviation=math.sqrt(float(self.areas @ deviation ** 2) / total)
            / self._steady_shape_rms)

    def wear_through_distances(self):
        """Distances (m) at which the rim wears through and the coating leaves the contact.

        Returns
        -------
        tuple of float
            The first crossing (the outermost ring) and the last (the
            coating gone from the whole face).
        """
        self._advance_all()
        return float(self.crossings.min()), float(self.crossings.max())

    def crossing_distance(self, radius):
        """Distance (m) at which the coating wears through at ``radius`` (m).

        Linear in ``r`` between the ring centres' crossings, constant beyond
        the outermost and innermost centres: the figure to compare a pixel's
        wear-through with (the rim's crossing differs from that of a pixel
        half a pixel inside it).

        Parameters
        ----------
        radius : array_like, m
            Radii in ``[0, a]``.

        Returns
        -------
        ndarray, shape of ``radius``, m
        """
        r = np.asarray(radius, dtype=float)
        if not np.all(np.isfinite(r) & (r >= 0) & (r <= self.radius)):
            raise ValueError(f"radius must lie in [0, {self.radius!r}] m, got {radius!r}")
        self._advance_all()
        return np.interp(r, self.centres, self.crossings)

    @property
    def substrate_decay_distance(self):
        """Distance (m) over which the last deviation from the steady face decays by ``e``.

        ``-1 / mu`` of the slowest nonzero mode of ``-k_s B``: the approach to
        the substrate's steady state once the coating is gone.
        """
        self._advance_all()
        mu = self._segments[-1].mu
        return float(-1.0 / np.max(mu[mu < 0]))


# The figures of a coated state that the reference history extrapolates, and
# their normalisation (divided by the value of the normalised model).
_COATED_FIGURES = ("rms_slope", "rms_height", "mean_worn_depth", "rim_worn_depth",
                   "face_deviation")


@dataclasses.dataclass(frozen=True)
class CoatedReferenceHistory:
    """Normalised run-in history of a coated cylinder, extrapolated in the rings.

    Units: distances in the coating's ``s* = a / (k_c E*)``, depths and the
    thickness in ``pbar a / E*`` (the depth worn at ``s*`` under the mean
    pressure), the rms slope over ``grad_f0``, the rms height over
    ``grad_f0 a``.  Each ``*_error`` is the estimated error of the value.

    Attributes
    ----------
    distance_s_star : ndarray, shape (K,)
    thickness_f_star : float
    ratio : float
        ``k_s / k_c``.
    first_through, first_through_error : float
        Distance at which the rim wears through.
    last_through, last_through_error : float
        Distance at which the coating is gone from the contact.
    rms_slope, rms_slope_error : ndarray, shape (K,)
    rms_height, rms_height_error : ndarray, shape (K,)
    mean_worn_depth, mean_worn_depth_error : ndarray, shape (K,)
    rim_worn_depth, rim_worn_depth_error : ndarray, shape (K,)
    face_deviation, face_deviation_error : ndarray, shape (K,)
        Rms of ``f - f_inf`` over that of the eq. 10 face (means removed).
    substrate_decay_distance : float
        ``e``-folding distance of the approach to the substrate's steady state.
    minimum_crossing_pressure : float
        Lowest ring pressure over ``pbar`` at the crossings (finer count).
    rings : tuple of int
        The two ring counts ``(N/2, N)``.
    """

    distance_s_star: np.ndarray
    thickness_f_star: float
    ratio: float
    first_through: float
    first_through_error: float
    last_through: float
    last_through_error: float
    rms_slope: np.ndarray
    rms_slope_error: np.ndarray
    rms_height: np.ndarray
    rms_height_error: np.ndarray
    mean_worn_depth: np.ndarray
    mean_worn_depth_error: np.ndarray
    rim_worn_depth: np.ndarray
    rim_worn_depth_error: np.ndarray
    face_deviation: np.ndarray
    face_deviation_error: np.ndarray
    substrate_decay_distance: float
    minimum_crossing_pressure: float
    rings: tuple


def _coated_figures(model, distances):
    """Normalised figures of ``model`` at ``distances`` (units of ``s*``), one row each."""
    depth = model.mean_pressure * model.radius / model.E_star
    scales = {"rms_slope": model.reference_slope,
              "rms_height": model.reference_slope * model.radius,
              "mean_worn_depth": depth, "rim_worn_depth": depth, "face_deviation": 1.0}
    states = [model.state(d * model.distance_scale) for d in distances]
    return {name: np.array([getattr(st, name) for st in states]) / scales[name]
            for name in _COATED_FIGURES}


def coated_reference_history(distances_s_star, *, thickness_f_star, ratio, rings=160,
                             grading=4.0):
    """The coated run-in history, extrapolated from ``N/2`` and ``N`` rings.

    The rings cross one at a time, so while the wear-through front sweeps
    the face (between the first and the last crossing) the figures converge
    at first order in ``1/N``: there the value is the ``N`` rings' and the
    error bar the difference to ``N/2``.  Before the first crossing and after
    the last, and for the two crossing distances, they converge at second
    order (measured, docs/model.md): Richardson's extrapolation of order 2,
    its size the error bar.

    Parameters
    ----------
    distances_s_star : array_like, shape (K,)
        Sliding distances in units of the coating's ``s*``, non-negative.
    thickness_f_star : float
        Coating thickness over ``f* = pbar a / E*``, positive.
    ratio : float
        ``k_s / k_c``, positive.
    rings : int, optional
        The finer ring count ``N`` (default 160; the cost grows as ``N^4``:
        one eigen-decomposition per ring).
    grading : float, optional
        Grading exponent (default 4).

    Returns
    -------
    CoatedReferenceHistory

    Examples
    --------
    >>> ref = coated_reference_history([0.2], thickness_f_star=0.1, ratio=10.0, rings=40)
    >>> print(f"{ref.first_through:.5f} {ref.last_through:.4f} {ref.rms_slope[0]:.4f}")
    0.00984 0.1456 1.0209
    """
    s = _distances_s_star(distances_s_star)
    counts = (int(rings) // 2, int(rings))
    models, figures, through = [], [], []
    for count in counts:
        model = CoatedAxisymmetricRunIn(count, grading=grading, thickness=thickness_f_star,
                                        substrate_coefficient=ratio)
        through.append(np.array(model.wear_through_distances()) / model.distance_scale)
        figures.append(_coated_figures(model, s))
        models.append(model)
    first, last = through[1] + (through[1] - through[0]) / 3.0
    first_error, last_error = np.abs(through[1] - through[0]) / 3.0
    front = (s > min(first, through[1][0])) & (s < max(last, through[1][1]))
    values = {}
    for name in _COATED_FIGURES:
        coarse, fine = figures[0][name], figures[1][name]
        value = np.where(front, fine, fine + (fine - coarse) / 3.0)
        error = np.where(front, np.abs(fine - coarse), np.abs(value - fine))
        if name != "face_deviation":
            # The flat face: no slope, no relief, nothing worn.
            value, error = np.where(s == 0, 0.0, value), np.where(s == 0, 0.0, error)
        values[name], values[name + "_error"] = value, error
    return CoatedReferenceHistory(
        distance_s_star=s, thickness_f_star=float(thickness_f_star), ratio=float(ratio),
        first_through=float(first), first_through_error=float(first_error),
        last_through=float(last), last_through_error=float(last_error),
        substrate_decay_distance=models[1].substrate_decay_distance
        / models[1].distance_scale,
        minimum_crossing_pressure=models[1].minimum_crossing_pressure, rings=counts, **values)
