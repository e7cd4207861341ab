"""The counter-body: an elastic half-space, or a layer of finite thickness on a rigid flat.

:class:`Counterbody` is the ``[counterbody]`` section as a value: the
effective modulus ``E* = E / (1 - nu^2)`` and, for a layer, its thickness
``t`` and Poisson's ratio ``nu``.  The layer is bonded to a rigid flat and
frictionless on top; ``E*`` keeps its meaning, so that a thick layer tends
to the half-space.  :meth:`Counterbody.operator` is the one place a grid's
elastic operator is made: the half-space (:class:`steady.halfspace.HalfSpace`)
or the layer (:class:`LayeredHalfSpace`, same interface).

The layer's compliance to a surface pressure ``cos(q . x)`` is the
half-space's ``2 / (E* |q|)`` times :func:`fourier_factor` of ``q t``
(Carbone & Mangialardi, J. Mech. Phys. Solids 56, 2008, eq. A.30,
doi:10.1016/j.jmps.2007.07.006)::

    phi(k) = ((3 - 4 nu) sinh 2k - 2k) / ((3 - 4 nu) cosh 2k + 2 k^2 + 5 - 12 nu + 8 nu^2)

It tends to 1 for ``k -> infinity`` (short waves do not reach the base) and
to 0 for ``k -> 0``: ``(1 - 2 nu) k / (2 (1 - nu)^2)`` for a compressible
layer (its uniaxial compression), ``2 k^3 / 3`` for an incompressible one
(squeeze flow under a pressure gradient), the closed form at ``nu = 1/2``
with no division by ``1 - 2 nu``.

In real space the layer's displacement under a point force ``F`` is
``F / (pi E*)`` times ``1 / r + c(r)``, with the correction

    c(r) = integral_0^inf (phi(q t) - 1) J0(q r) dq = C(r / t) / t,

smooth and finite at ``r = 0`` and tending to ``-1 / r`` far out.  The
pixel influence coefficients of the layer are Love's exact ones of ``1/r``
(:mod:`steady.halfspace`) plus the pixel integrals of ``c``, taken by
Gauss-Legendre quadrature (docs/model.md, "Counter-body of finite
thickness", states their accuracy).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math

import numpy as np
import scipy.interpolate
import scipy.special

from .halfspace import HalfSpace, _corner_sum
from .periodic import PeriodicHalfSpace
from .schema import Key

__all__ = ["POISSON", "THICKNESS", "Counterbody", "LayeredHalfSpace", "correction_kernel",
           "fourier_factor"]

logger = logging.getLogger(__name__)

#: ``[counterbody] thickness``: the layer's thickness; absent, a half-space.
THICKNESS = Key("thickness", "number", unit="m", low=0.0,
                doc="thickness of a layer bonded to a rigid flat, optional (absent: a "
                    "half-space); needs poisson")
#: ``[counterbody] poisson``: the layer's Poisson's ratio, only with a thickness.
POISSON = Key("poisson", "number", unit="1", low=0.0, high=0.5, low_open=False,
              high_open=False,
              doc="Poisson's ratio nu of the layer (0.5: incompressible), with a thickness "
                  "only")
_MODULUS = Key("E_star", "number", unit="Pa", low=0.0)

# Below q t = 1 the numerator's terms cancel (to O(k^3) at nu = 1/2): there it is
# summed as 2k (s - 1) + s (sinh 2k - 2k), the bracket from its series below 2k = 1.
_SMALL_K = 1.0
_SINH_TERMS = 12

# The correction C(rho) is tabulated for rho = r / t in [0, _RHO_TABLE]: beyond it the
# layer's total kernel 1/rho + C is zero.  phi(k) / k is even and analytic in k, so that
# the total kernel decays exponentially, about as exp(-0.76 rho): 1e-12 at rho = 33.
_RHO_TABLE = 60.0
_RHO_FINE = 10.0
_RHO_STEP = 0.0125
_RHO_COARSE_STEP = 0.1
# The q t integral stops at 37: its integrand decays as exp(-q t), exp(-37) = 9e-17.
_K_MAX = 37.0
_K_PANEL = 0.25
_K_POINTS = 12
# Pixels whose centre lies within _NEAR_RHO thicknesses plus one pixel of the observation
# point take c with many points; beyond, the total kernel (smooth on the scale of r).
_NEAR_RHO = 24.0
_FAR_POINTS = 6


def fourier_factor(k, poisson):
    """The layer's compliance over the half-space's for the mode ``q t = k``.

    Parameters
    ----------
    k : float or ndarray, dimensionless
        ``|q| t``: wavenumber (rad/m) times thickness (m), ``>= 0``.
    poisson : float
        Poisson's ratio ``nu`` in ``[0, 0.5]``.

    Returns
    -------
    float or ndarray, dimensionless
        ``phi(k)`` in ``[0, 1)`` (Carbone & Mangialardi 2008, eq. A.30, as
        the inverse of their stiffness ratio), evaluated without overflow
        for large ``k`` and without cancellation for small ``k``.

    Notes
    -----
    For ``k -> 0``: ``(1 - 2 nu) k / (2 (1 - nu)^2)``, and ``2 k^3 / 3`` at
    ``nu = 1/2``.  For ``k -> infinity``: ``1 - O(k^2 exp(-2k))``.

    Examples
    --------
    >>> print(f"{fourier_factor(1e-3, 0.3):.6e} {fourier_factor(1e-3, 0.5):.6e}")
    4.081633e-04 6.666655e-10
    >>> float(fourier_factor(800.0, 0.5))
    1.0
    """
    k = np.asarray(k, dtype=float)
    nu = float(poisson)
    s = 3.0 - 4.0 * nu
    offset = 5.0 - 12.0 * nu + 8.0 * nu * nu
    out = np.empty_like(k)
    small = k <= _SMALL_K
    ks = k[small]
    x = 2.0 * ks
    # sinh x - x: its series below x = 1, directly above (no cancellation there).
    bracket = np.where(x < 1.0, _sinh_minus_x_series(np.minimum(x, 1.0)), np.sinh(x) - x)
    out[small] = ((2.0 * (s - 1.0)) * ks + s * bracket) / (s * np.cosh(x) + 2.0 * ks * ks
                                                          + offset)
    kl = k[~small]
    # Numerator and denominator over cosh 2k: e = exp(-2k), no overflow.
    e = np.exp(-2.0 * kl)
    out[~small] = (s * (1.0 - e * e) - 4.0 * kl * e) / (s * (1.0 + e * e)
                                                     + (4.0 * kl * kl + 2.0 * offset) * e)
    return out if out.ndim else float(out)


def _sinh_minus_x_series(x):
    """``sinh x - x`` for ``|x| <= 1``: its Taylor series, to round-off."""
    term = x ** 3 / 6.0
    total = term.copy()
    x2 = x * x
    for j in range(2, _SINH_TERMS):
        term = term * x2 / ((2 * j) * (2 * j + 1))
        total += term
    return total


def correction_kernel(rho, poisson):
    """``C(rho)`` and ``C'(rho)``: the layer's point-force correction in units of the thickness.

    ``c(r) = C(r / t) / t`` (module notes), computed as
    ``-1 / sqrt(1 + rho^2) + integral_0^inf R(k) J0(k rho) dk`` with
    ``R = phi - 1 + exp(-k)``: the subtracted term's transform is closed, and
    ``R`` is smooth, zero at 0 and decays as ``exp(-k)``.  The integral is
    Gauss-Legendre on panels of ``q t`` (``J0' = -J1`` for ``C'``).

    Parameters
    ----------
    rho : ndarray, shape (m,), dimensionless
        ``r / t``, in ``[0, 60]`` (the oscillations beyond are not resolved).
    poisson : float
        Poisson's ratio in ``[0, 0.5]``.

    Returns
    -------
    value, slope : ndarray, shape (m,)
    """
    nodes, weights = np.polynomial.legendre.leggauss(_K_POINTS)
    edges = np.arange(0.0, _K_MAX + _K_PANEL / 2, _K_PANEL)
    half = _K_PANEL / 2
    k = ((edges[:-1, None] + half) + half * nodes[None, :]).ravel()
    w = np.tile(weights * half, edges.size - 1)
    remainder = (fourier_factor(k, poisson) - 1.0 + np.exp(-k)) * w
    rho = np.asarray(rho, dtype=float)
    values = np.empty_like(rho)
    slopes = np.empty_like(rho)
    for chunk in np.array_split(np.arange(rho.size), max(1, rho.size // 100)):
        arg = rho[chunk, None] * k[None, :]
        values[chunk] = scipy.special.j0(arg) @ remainder
        slopes[chunk] = -(scipy.special.j1(arg) * k[None, :]) @ remainder
    root = np.sqrt(1.0 + rho * rho)
    return values - 1.0 / root, slopes + rho / root ** 3


@functools.lru_cache(maxsize=8)
def _correction_table(poisson):
    """Cubic Hermite interpolant of :func:`correction_kernel` on ``[0, _RHO_TABLE]``.

    Values and slopes at the nodes: finer where ``C`` bends on the scale of
    the thickness, coarser beyond, where it is ``-1/rho`` plus a smooth tail.
    """
    rho = np.concatenate([np.arange(0.0, _RHO_FINE, _RHO_STEP),
                          np.arange(_RHO_FINE, _RHO_TABLE + 1e-9, _RHO_COARSE_STEP)])
    values, slopes = correction_kernel(rho, poisson)
    return scipy.interpolate.CubicHermiteSpline(rho, values, slopes)


def _total_kernel(rho, table):
    """``(1/rho + C(rho), d/drho of it)`` for ``rho > 0``: the layer's point-force kernel.

    Zero beyond the table, where it is below 1e-16.
    """
    inside = rho <= _RHO_TABLE
    r_in = np.where(inside, rho, _RHO_TABLE)
    value = np.where(inside, 1.0 / r_in + table(r_in), 0.0)
    slope = np.where(inside, -1.0 / (r_in * r_in) + table(r_in, 1), 0.0)
    return value, slope


def _near_points(h, thickness):
    """Gauss-Legendre points per pixel side for ``c`` there: even, more on thin layers."""
    m = 4 + 2 * math.ceil(1.5 * h / thickness)
    return min(m, 64)


class LayeredHalfSpace(HalfSpace):
    """The elastic operator of a layer on a rigid flat, on an ``nx x ny`` pixel grid.

    :class:`steady.halfspace.HalfSpace` with the layer's influence and
    gradient coefficients: Love's exact pixel integrals of ``1/r`` plus
    the pixel integrals of the smooth correction ``c`` (module notes), so
    that every product, symbol and solver of the half-space applies as it
    is.  Building it costs the tabulation of ``C`` (once per ``nu``) and a
    quadrature per pixel offset.

    Parameters
    ----------
    shape : int or (int, int)
        Pixels along each axis (as :class:`~steady.halfspace.HalfSpace`).
    h : float, m
        Pixel side.
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)`` of the layer.
    thickness : float, m
        The layer's thickness ``t``; at least ``h / 16`` (thinner layers are
        not resolved by the pixel quadrature).
    poisson : float
        Poisson's ratio in ``[0, 0.5]``.
    workers : int, optional
        As :class:`~steady.halfspace.HalfSpace`.

    Raises
    ------
    ValueError
        A thickness below ``h / 16``.

    Examples
    --------
    A thin incompressible layer is far stiffer than the half-space:

    >>> import numpy as np
    >>> from steady.outline import Circle
    >>> grid = Circle(4e-3).grid(32)
    >>> layer = LayeredHalfSpace(grid.shape, grid.h, 1.3e6, 1e-3, 0.5)
    >>> u = layer.displacement(np.where(grid.mask, 1e4, 0.0))
    >>> u_hs = HalfSpace(grid.shape, grid.h, 1.3e6).displacement(np.where(grid.mask, 1e4, 0.0))
    >>> print(f"{u[16, 16] / u_hs[16, 16]:.3f}")
    0.011
    """

    def __init__(self, shape, h, E_star, thickness, poisson, *, workers=-1):
        self.thickness = THICKNESS.parse(thickness, "", scale=False)
        self.poisson = POISSON.parse(poisson, "", scale=False)
        if self.thickness < float(h) / 16:
            raise ValueError(f"a layer of thickness {self.thickness!r} m is not resolved by "
                             f"pixels of {float(h)!r} m: it must be at least h / 16")
        super().__init__(shape, h, E_star, workers=workers)

    def _quadrants(self, gradient):
        """The correction's pixel integrals at offsets ``0..nx`` by ``0..ny`` pixels.

        Returns ``c`` integrated over the pixel, shape ``(nx + 1, ny + 1)``
        (``gradient`` False), else its x- and y-derivatives stacked, shape
        ``(2, nx + 1, ny + 1)``; per unit pressure, m/Pa (1/Pa).  Near pixels
        integrate ``c`` itself; farther ones the layer's whole kernel less
        Love's ``1/r``; beyond the table, minus Love's alone.
        """
        nx, ny = self.shape
        h, t = self.h, self.thickness
        table = _correction_table(self.poisson)
        i, j = np.meshgrid(np.arange(nx + 1) * h, np.arange(ny + 1) * h, indexing="ij")
        distance = np.hypot(i, j)
        near = distance < _NEAR_RHO * t + h
        # Beyond the table the total kernel is zero: the correction is minus Love's 1/r.
        beyond = distance > _RHO_TABLE * t + h
        out = np.zeros((nx + 1, ny + 1)) if not gradient else np.zeros((2, nx + 1, ny + 1))
        for where, m, total in ((near, _near_points(h, t), False),
                                (~near & ~beyond, _FAR_POINTS, True),
                                (beyond, 0, True)):
            if not where.any():
                continue
            if m:
                self._integrate(out, where, i, j, m, total, gradient, table)
            if total:  # the total kernel's integral less Love's 1/r: the correction
                cx, cy, asinh_yx, asinh_xy = self._corners
                if not gradient:
                    love = _corner_sum(cx[:, None] * asinh_yx + cy[None, :] * asinh_xy)
                    out[where] -= love[where]
                else:
                    out[0][where] -= _corner_sum(asinh_yx)[where]
                    out[1][where] -= _corner_sum(asinh_xy)[where]
        return out / (np.pi * self.E_star)

    def _integrate(self, out, where, i, j, m, total, gradient, table):
        """Gauss-Legendre ``m x m`` pixel integrals of ``c`` (or of the total kernel) into ``out``.

        At the offsets ``(i, j)`` (m) selected by ``where``; ``total``: of the
        layer's whole kernel ``1/r + c`` (smooth there), else of ``c``.
        """
        h, t = self.h, self.thickness
        nodes, weights = np.polynomial.legendre.leggauss(m)
        dx = (h / 2) * nodes
        w2 = np.outer(weights, weights).ravel() * (h / 2) ** 2
        ox, oy = (np.repeat(dx, m), np.tile(dx, m))
        xs, ys = i[where], j[where]
        acc = np.empty((xs.size,)) if not gradient else np.empty((2, xs.size))
        for chunk in np.array_split(np.arange(xs.size), max(1, xs.size * m * m // 400000)):
            X = xs[chunk, None] - ox[None, :]
            Y = ys[chunk, None] - oy[None, :]
            r = np.hypot(X, Y)
            rho = r / t
            if total:
                value, slope = _total_kernel(rho, table)
            else:
                value, slope = table(rho), table(rho, 1)
            if not gradient:
                acc[chunk] = (value @ w2) / t
            else:
                radial = slope / (t * t * np.where(r > 0, r, 1.0))
                acc[0, chunk] = (radial * X) @ w2
                acc[1, chunk] = (radial * Y) @ w2
        if gradient:
            out[:, where] = acc
        else:
            out[where] = acc

    @functools.cached_property
    def influence_quadrant(self):
        """Influence coefficients at pixel offsets ``0..nx`` by ``0..ny``, m/Pa: the layer's."""
        quadrant = super().influence_quadrant + self._quadrants(False)
        quadrant.flags.writeable = False
        return quadrant

    def _gradient_quadrants(self):
        """Gradient kernels: the half-space's plus the correction's x- and y-derivatives."""
        gx, gy = super()._gradient_quadrants()
        cx, cy = self._quadrants(True)
        return gx + cx, gy + cy

    @property
    def self_influence(self):
        """Displacement of a pixel per unit pressure on itself, m/Pa."""
        return float(self.influence_quadrant[0, 0])


@dataclasses.dataclass(frozen=True)
class Counterbody:
    """The counter-body the punch slides on: a half-space, or a layer on a rigid flat.

    Parameters
    ----------
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)``, positive and finite.
    thickness : float, m, optional
        Thickness of a layer bonded to a rigid flat (frictionless on top);
        default None, the half-space.
    poisson : float, optional
        Poisson's ratio of the layer in ``[0, 0.5]``: needed with a
        thickness, refused without one.

    Raises
    ------
    ValueError
        A modulus or thickness not positive and finite, a Poisson's ratio
        outside ``[0, 0.5]``, a thickness without a Poisson's ratio or the
        other way round.

    Examples
    --------
    >>> Counterbody(1.3e6).layered
    False
    >>> layer = Counterbody(1.3e6, thickness=2e-3, poisson=0.5)
    >>> print(f"{layer.fourier_factor(500.0):.4f}")
    0.2406
    """

    E_star: float
    thickness: float | None = None
    poisson: float | None = None

    def __post_init__(self):
        """Check the modulus and the layer, each once, here where they enter."""
        object.__setattr__(self, "E_star", _MODULUS.parse(self.E_star, "", scale=False))
        if self.thickness is None:
            if self.poisson is not None:
                raise ValueError(f"[counterbody] poisson = {self.poisson!r} is for a layer: "
                                 f"give its thickness too (absent: a half-space)")
            return
        if self.poisson is None:
            raise ValueError(f"[counterbody] thickness = {self.thickness!r} needs poisson, the "
                             f"layer's Poisson's ratio in [0, 0.5]")
        object.__setattr__(self, "thickness", THICKNESS.parse(self.thickness, "[counterbody]"))
        object.__setattr__(self, "poisson", POISSON.parse(self.poisson, "[counterbody]"))

    @property
    def layered(self):
        """Whether it is a layer of finite thickness."""
        return self.thickness is not None

    def fourier_factor(self, q):
        """Each mode's compliance over the half-space's, for ``|q|`` in rad/m.

        Parameters
        ----------
        q : float or ndarray, rad/m
            Wavenumber magnitude, ``>= 0``.

        Returns
        -------
        float or ndarray
            :func:`fourier_factor` of ``q t``; 1 for the half-space.
        """
        if self.thickness is None:
            return np.ones_like(np.asarray(q, dtype=float)) if np.ndim(q) else 1.0
        return fourier_factor(np.asarray(q, dtype=float) * self.thickness, self.poisson)

    def operator(self, grid, *, workers=-1):
        """The elastic operator of a face's grid: the one place it is chosen.

        Parameters
        ----------
        grid : steady.outline.FaceGrid
            Its outline (``periodic`` or not), shape and pixel size ``h`` (m).
        workers : int, optional
            Threads of the transforms (:mod:`scipy.fft`'s count; default -1, all cores).

        Returns
        -------
        steady.halfspace.HalfSpace
            The zero-padded half-space; :class:`LayeredHalfSpace` for a layer;
            for a periodic cell (``grid.outline.periodic``) the periodic operator
            :class:`steady.periodic.PeriodicHalfSpace`, whose modes a layer
            scales by :meth:`fourier_factor`.

        Examples
        --------
        >>> from steady.outline import Circle, PeriodicCell
        >>> half_space = Counterbody(1e6)
        >>> type(half_space.operator(Circle(4e-3).grid(32))).__name__
        'HalfSpace'
        >>> type(half_space.operator(PeriodicCell(4e-3, 4e-3).grid(32))).__name__
        'PeriodicHalfSpace'
        """
        if grid.outline.periodic:
            factor = self.fourier_factor if self.layered else None
            return PeriodicHalfSpace(grid.shape, grid.h, self.E_star, compliance_factor=factor,
                                     workers=workers)
        if self.thickness is None:
            return HalfSpace(grid.shape, grid.h, self.E_star, workers=workers)
        return LayeredHalfSpace(grid.shape, grid.h, self.E_star, self.thickness, self.poisson,
                                workers=workers)

    def displacement_scale(self, mean_pressure, length):
        """Displacement of the face under ``mean_pressure`` over ``length``, m.

        ``pbar L / E*`` for the half-space; on a layer times the factor of
        the wave ``q = 1 / L``, which is about ``t / L`` (compressible) or
        ``(t / L)^3`` (incompressible) on a thin one.
        """
        scale = mean_pressure * length / self.E_star
        if self.thickness is None:
            return scale
        return scale * self.fourier_factor(1.0 / length)

    def file_attributes(self):
        """``name -> (value, unit, long_name)`` of the layer for result files; empty without."""
        if self.thickness is None:
            return {}
        return {"thickness": (self.thickness, "m",
                              "thickness of the counter-body's layer on a rigid flat"),
                "poisson": (self.poisson, "1", "Poisson's ratio of the counter-body's layer")}

    def describe(self):
        """One line: ``"half-space, E* = 1.3e+06 Pa"`` or the layer's."""
        if self.thickness is None:
            return f"half-space, E* = {self.E_star:.4g} Pa"
        return (f"layer of thickness {self.thickness:.4g} m on a rigid flat, nu = "
                f"{self.poisson:.4g}, E* = {self.E_star:.4g} Pa")
