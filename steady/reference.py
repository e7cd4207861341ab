"""Closed-form reference solutions shared by tests, studies and the command line.

All functions take SI units and return SI units.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import integrate, special

from .pressures import phase_pressures
from .schema import Key

__all__ = [
    "annulus_face",
    "annulus_face_slope",
    "annulus_rms_slope",
    "disk_face",
    "disk_face_slope",
    "disk_mean_pressure",
    "disk_normalised_rms_slope",
    "disk_reference_slope",
    "disk_rms_slope",
    "fine_grain_rms_slope",
    "flat_punch_approach",
    "flat_punch_pressure",
    "hertz",
    "pillars_rms_slope",
    "rectangle_face",
    "rectangle_face_gradient",
    "rectangle_rms_slope",
]


def disk_mean_pressure(normal_force, radius):
    """Mean pressure ``pbar = F_N / (pi a^2)`` on a disk of radius ``a``, Pa.

    The paper prints ``(pi a)^2``; that is a typo.  (Any outline's is
    ``F_N / A``: :attr:`steady.problem.Problem.mean_pressure`.)
    """
    return normal_force / (np.pi * radius**2)


def disk_reference_slope(mean_pressure, E_star):
    """Reference slope of a disk ``grad_f0 = 4 pbar / (pi E*)`` (eq. 12), dimensionless.

    The homogeneous disk's rms slope (:func:`disk_rms_slope`); any outline's
    is :func:`steady.normalisation.reference_slope`.
    """
    return 4.0 * mean_pressure / (np.pi * E_star)


def disk_normalised_rms_slope():
    """Continuum rms slope of the eq. 10 face over the disk, in units of ``grad_f0``, by quadrature.

    Quadrature of ``2 int_0^1 ((E(k) - K(k)) / k)^2 k dk``; the integrand is
    log-squared singular at ``k = 1``.  The value is 1 to quadrature
    accuracy: the paper's 1.0109 (eq. 12) is a grid value.

    Returns
    -------
    float
    """
    def integrand(k):
        return (special.ellipe(k * k) - special.ellipk(k * k)) ** 2 / k

    value, _ = integrate.quad(integrand, 0.0, 1.0, limit=200, epsabs=1e-15, epsrel=1e-13,
                              points=[0.9, 0.99, 0.999])
    return float(np.sqrt(2.0 * value))


def flat_punch_pressure(r, radius, normal_force):
    """Boussinesq pressure under a rigid flat circular punch, Pa.

    ``p(r) = F / (2 pi a sqrt(a^2 - r^2))`` for ``r < a``, zero outside.
    """
    r = np.asarray(r, dtype=float)
    inside = r < radius
    s = np.sqrt(np.where(inside, radius**2 - r**2, 1.0))
    return np.where(inside, normal_force / (2 * np.pi * radius * s), 0.0)


def flat_punch_approach(normal_force, radius, E_star):
    """Rigid approach of a flat circular punch, ``F / (2 a E*)``, m."""
    return normal_force / (2 * radius * E_star)


def hertz(normal_force, sphere_radius, E_star):
    """Hertz contact of a sphere on an elastic half-space.

    Parameters
    ----------
    normal_force : float, N
    sphere_radius : float, m
    E_star : float, Pa

    Returns
    -------
    contact_radius : float, m
        ``(3 F R / (4 E*))^(1/3)``.
    peak_pressure : float, Pa
        ``3 F / (2 pi c^2)``.
    approach : float, m
        ``c^2 / R``.
    """
    c = (3 * normal_force * sphere_radius / (4 * E_star)) ** (1 / 3)
    return c, 3 * normal_force / (2 * np.pi * c**2), c**2 / sphere_radius


def _hard_fill_factor(value):
    if not 0 < value <= 1:
        raise ValueError(f"hard_fill_factor must lie in (0, 1], got {value!r}")
    return value


def pillars_rms_slope(mean_pressure, E_star, hard_fill_factor):
    """Pillars asymptote of eq. 18: ``grad_f0 / rho_2``, the rms slope *over the hard phase*.

    Valid for few hard (low-wear) circular inclusions, ``k_hard / k_matrix
    -> 0``: each pillar carries ``p_2 = pbar / rho_2`` and, by eq. 12, the
    rms slope over its own area is ``4 p_2 / (pi E*)``.  The paper's
    derivation averages over the pillars only; for the rms over the whole
    face see :func:`fine_grain_rms_slope`.
    """
    return disk_reference_slope(mean_pressure, E_star) / _hard_fill_factor(hard_fill_factor)


def fine_grain_rms_slope(fill_factors, wear_coefficients, *, exponent=1.0):
    """Normalised rms slope of a fine-grained multi-phase punch (closed form).

    Parameters
    ----------
    fill_factors : array_like, shape (P,) or (..., P)
        Area fractions ``rho_i``, summing to 1 along the last axis.
    wear_coefficients : array_like, shape (P,) or (..., P), 1/Pa
        ``k_i`` (only their ratios matter).
    exponent : float, optional
        ``m`` of the wear law ``k p^m`` (default 1).

    Returns
    -------
    ndarray or float, dimensionless
        ``rms / grad_f0 = sqrt(1 + (pi^2 / 4) sum_i rho_i (p_i / pbar - 1)^2)``
        with ``p_i ~ k_i^(-1/m)`` (eq. 7): the limit of grains much smaller
        than the punch radius; derivation below.

    Notes
    -----
    Over the whole plane ``int |grad u|^2 dA = (4 / E*^2) int p^2 dA``
    (Parseval; :mod:`steady.rms_slope`).  Split the steady pressure into its
    mean ``pbar`` and the fluctuation ``p - pbar``.  The mean gives the
    homogeneous face (normalised rms slope 1, the fraction ``4 / pi^2`` of
    its plane integral on the face).  When the grains are much smaller than
    the punch, the fluctuation's field stays on the face (up to a rim layer
    about one grain wide) and does not correlate with the smooth mean
    field.  In the pillars limit ``k_2 / k_1 -> 0`` this gives
    ``sqrt(1 + (pi^2 / 4) (1 / rho_2 - 1))``, about ``(pi / 2) / sqrt(rho_2)``,
    not the ``1 / rho_2`` of eq. 18 (:func:`pillars_rms_slope`), which holds
    over the pillars only and would exceed the Parseval bound
    ``(pi / 2) / sqrt(rho_2)`` over the whole face.

    For two phases with ``r = k_2 / k_1`` and Archard's law,
    ``(rms / grad_f0)^2 = 1 + (pi^2 / 4) rho_1 rho_2 (r - 1)^2 / (rho_1 r + rho_2)^2``:
    symmetric under ``(rho_2, r) -> (1 - rho_2, 1 / r)``.  This closed form
    is the check of the design table (:mod:`steady.design`).
    """
    rho = np.asarray(fill_factors, dtype=float)
    # Unit force on unit area: the phase pressures are p_i / pbar.
    p = phase_pressures(rho, wear_coefficients, 1.0, 1.0, exponent=exponent)
    variance = np.sum(rho * (p - 1.0) ** 2, axis=-1)
    return np.sqrt(1.0 + np.pi**2 / 4.0 * variance)


# -- other face outlines: homogeneous faces and their rms-slope factors -------
# The homogeneous face of an outline is the displacement under a uniform
# pressure on it; its rms slope over the outline is ``S pbar / E*`` with a
# factor ``S`` that depends on the outline's shape only (4 / pi for the disk,
# eq. 12).  The factors are the normalisations of the rms slopes of faces that
# are not disks.

# The closed forms check their lengths and modulus through these keys; the
# scale range is a problem's to check (any consistent lengths give the
# rms-slope factors).
_RADIUS = Key("radius", "number", unit="m", low=0.0)
_INNER_RADIUS = Key("inner_radius", "number", unit="m", low=0.0)
_OUTER_RADIUS = Key("outer_radius", "number", unit="m", low=0.0)
_WIDTH = Key("width", "number", unit="m", low=0.0)
_LENGTH = Key("length", "number", unit="m", low=0.0)
_HALF_WIDTH = Key("half_width", "number", unit="m", low=0.0)
_HALF_LENGTH = Key("half_length", "number", unit="m", low=0.0)
_E_STAR = Key("E_star", "number", unit="Pa", low=0.0)
_RATIO = Key("ratio", "number", unit="1", low=0.0, low_open=False, high=1.0)


def _distance(r):
    r = np.asarray(r, dtype=float)
    if np.any(r < 0):
        raise ValueError("r is a distance from the centre and must be >= 0 m")
    return r


def disk_rms_slope():
    """Rms-slope factor ``S`` of the homogeneous disk: ``4 / pi``.

    Under a uniform pressure ``pbar`` on a disk, the rms slope of the face
    over the disk is ``S pbar / E* = 4 pbar / (pi E*)``, the reference slope
    of eq. 12 (:func:`disk_reference_slope`); :func:`disk_normalised_rms_slope` is the
    quadrature that shows it (1 in units of the reference slope).  The
    disk's counterpart of :func:`rectangle_rms_slope` and
    :func:`annulus_rms_slope`.

    Returns
    -------
    float, dimensionless

    Examples
    --------
    >>> print(f"{disk_rms_slope():.15f}")
    1.273239544735163
    """
    return 4.0 / np.pi


def disk_face(r, radius, pressure, E_star):
    """Displacement under a uniform pressure on a disk, inside and outside it.

    Parameters
    ----------
    r : array_like, m
        Distance from the centre of the disk, ``>= 0``, any shape.
    radius : float, m
        Radius ``a`` of the loaded disk.
    pressure : float, Pa
        Uniform pressure ``p`` on the disk.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    ndarray, shape of ``r``, m
        ``u(r) = 4 p a / (pi E*) E(r / a)`` for ``r <= a`` and
        ``u(r) = 4 p r / (pi E*) [E(a / r) - (1 - a^2 / r^2) K(a / r)]``
        for ``r > a``; ``K`` and ``E`` are the complete elliptic integrals
        of the first and second kind written with the modulus (scipy takes
        the parameter, the modulus squared).  Continuous at the rim, where
        ``u = 4 p a / (pi E*)``; ``2 p a / E*`` at the centre; ``F / (pi E* r)``
        far away (``F = pi a^2 p``).  Inside the disk this is the limiting
        face of the homogeneous cylinder (eq. 10).

    Raises
    ------
    ValueError
        If a distance is negative or ``radius`` or ``E_star`` is not
        positive.

    Notes
    -----
    Johnson, *Contact Mechanics* (1985), sec. 3.4; Timoshenko & Goodier,
    *Theory of Elasticity*, load distributed over a part of the boundary of a
    semi-infinite solid.  Outside the disk the bracket is
    ``k^2 (R_F - R_D / 3)`` with Carlson's ``R_F(0, 1 - k^2, 1)`` and
    ``R_D(0, 1 - k^2, 1)``, ``k = a / r``: the same value without the
    cancellation of ``E - (1 - k^2) K`` far from the disk.

    Examples
    --------
    >>> u = disk_face([0.0, 2e-3, 4e-3, 1.0], 2e-3, 1e4, 1e6)
    >>> print(u / (1e4 * 2e-3 / 1e6))  # in units of p a / E*
    [2.         1.27323954 0.51731581 0.002     ]
    """
    r = _distance(r)
    a = _RADIUS.parse(radius, "", scale=False)
    # The rim value; inside, eq. 10 as written.
    rim = 4 * pressure * a / (np.pi * _E_STAR.parse(E_star, "", scale=False))
    inside = r <= a
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(inside, r / a, a / r)
        m1 = (1.0 - k) * (1.0 + k)
        outside = k * (special.elliprf(0.0, m1, 1.0) - special.elliprd(0.0, m1, 1.0) / 3.0)
    return np.where(inside, rim * special.ellipe(np.where(inside, k, 0.0) ** 2), rim * outside)


def disk_face_slope(r, radius, pressure, E_star):
    """Radial derivative of :func:`disk_face`, inside and outside the disk, dimensionless.

    Parameters
    ----------
    r : array_like, m
        Distance from the centre of the disk, ``>= 0``, any shape.
    radius : float, m
        Radius ``a`` of the loaded disk.
    pressure : float, Pa
        Uniform pressure ``p`` on the disk.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    ndarray, shape of ``r``, dimensionless
        ``du/dr = 4 p / (pi E*) (E(k) - K(k)) / k`` with ``k = r / a``
        inside and
        ``du/dr = 4 p / (pi E*) (E(k) - K(k))`` with ``k = a / r`` outside;
        zero at the centre, ``-inf`` at the rim (log-singular from both
        sides), ``-F / (pi E* r^2)`` far away.

    Notes
    -----
    ``E - K = -k^2 R_D(0, 1 - k^2, 1) / 3`` (Carlson), free of the
    cancellation of ``E - K`` at small ``k``.  Derivation of the outside
    branch: with ``g(k) = E(k) - (1 - k^2) K(k)``, ``g'(k) = k K(k)``, so
    ``d(r g(a/r))/dr = g - k g' = E - K``.

    Examples
    --------
    >>> s = disk_face_slope([0.0, 1e-3, 2e-3, 4e-3], 2e-3, 1e4, 1e6)
    >>> print(s / (4 * 1e4 / (np.pi * 1e6)))  # in units of 4 p / (pi E*)
    [ 0.         -0.43657629        -inf -0.21828815]
    """
    r = _distance(r)
    a = _RADIUS.parse(radius, "", scale=False)
    scale = 4.0 * pressure / (np.pi * _E_STAR.parse(E_star, "", scale=False))
    inside = r <= a
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(inside, r / a, a / r)
        rd = special.elliprd(0.0, (1.0 - k) * (1.0 + k), 1.0)
        # (E - K) / k inside, E - K outside; 0.0 - x turns -0 at the centre into 0.
        d = 0.0 - np.where(inside, k, k * k) * rd / 3.0
    return scale * d


def annulus_face(r, inner_radius, outer_radius, pressure, E_star):
    """Displacement under a uniform pressure on an annulus, m.

    The difference of two loaded disks (:func:`disk_face`): uniform
    pressure ``p`` on ``inner_radius < r < outer_radius``.

    Parameters
    ----------
    r : array_like, m
        Distance from the centre, ``>= 0``, any shape.
    inner_radius, outer_radius : float, m
        Radii ``c < a`` of the annulus, ``0 < c < a``.
    pressure : float, Pa
        Uniform pressure ``p`` on the annulus.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    ndarray, shape of ``r``, m
        ``u(r) = u_disk(r; a) - u_disk(r; c)``: continuous everywhere,
        ``2 p (a - c) / E*`` at the centre.

    Raises
    ------
    ValueError
        Unless ``0 < inner_radius < outer_radius``.

    Examples
    --------
    >>> u = annulus_face([0.0, 1e-3, 2e-3], 1e-3, 2e-3, 1e4, 1e6)
    >>> print(u / (1e4 * 2e-3 / 1e6))  # in units of p a / E*
    [1.         1.23181114 1.01458164]
    """
    c, a = _annulus_radii(inner_radius, outer_radius)
    return disk_face(r, a, pressure, E_star) - disk_face(r, c, pressure, E_star)


def annulus_face_slope(r, inner_radius, outer_radius, pressure, E_star):
    """Radial derivative of :func:`annulus_face`, dimensionless.

    Parameters
    ----------
    r : array_like, m
        Distance from the centre, ``>= 0``, any shape.
    inner_radius, outer_radius : float, m
        Radii ``c < a`` of the annulus, ``0 < c < a``.
    pressure : float, Pa
        Uniform pressure ``p`` on the annulus.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    ndarray, shape of ``r``, dimensionless
        ``du_disk(r; a)/dr - du_disk(r; c)/dr`` (:func:`disk_face_slope`);
        ``+inf`` on the inner rim and ``-inf`` on the outer one.

    Examples
    --------
    >>> s = annulus_face_slope([0.5e-3, 1e-3, 1.5e-3, 2e-3], 1e-3, 2e-3, 1e4, 1e6)
    >>> print(s / (4 * 1e4 / (np.pi * 1e6)))  # in units of 4 p / (pi E*)
    [ 0.23543643         inf -0.35846001        -inf]
    """
    c, a = _annulus_radii(inner_radius, outer_radius)
    return disk_face_slope(r, a, pressure, E_star) - disk_face_slope(r, c, pressure, E_star)


def _annulus_radii(inner_radius, outer_radius):
    c = _INNER_RADIUS.parse(inner_radius, "", scale=False)
    a = _OUTER_RADIUS.parse(outer_radius, "", scale=False)
    if not c < a:
        raise ValueError(f"inner_radius must be smaller than outer_radius, got {c!r} m and "
                         f"{a!r} m")
    return c, a


def annulus_rms_slope(ratio):
    """Rms-slope factor ``S`` of the homogeneous annulus.

    The rms of ``|du/dr|`` over the annulus under a uniform pressure
    ``pbar`` is ``S pbar / E*``; ``S`` depends only on the ratio of the
    radii.

    Parameters
    ----------
    ratio : float
        ``inner_radius / outer_radius``, ``0 <= ratio < 1``; 0 is the disk.

    Returns
    -------
    float, dimensionless
        ``S^2 = 32 / (pi^2 (1 - rho^2)) int_rho^1 psi(r)^2 r dr`` (outer radius
        1, ``rho`` the ratio), with ``psi = (E(r) - K(r)) / r - (E(rho/r) -
        K(rho/r))`` the slope of the two disks (:func:`annulus_face_slope`)
        in units of ``4 pbar / (pi E*)``.  ``4 / pi`` at ``ratio = 0``
        (:func:`disk_rms_slope`); tends to the infinite strip's ``2 / sqrt(3)``
        as ``ratio -> 1``.

    Raises
    ------
    ValueError
        If ``ratio`` is outside ``[0, 1)``.
    RuntimeError
        If the quadrature does not converge (not seen for ratios up to
        ``1 - 1e-15``).

    Notes
    -----
    Tanh-sinh quadrature (Takahasi & Mori, Publ. RIMS 9, 1974,
    doi:10.2977/prims/1195192451) on ``[rho, 1]``: the integrand is
    log-squared singular at both rims, and the rule's nodes carry their
    distances to both ends exactly, so the slopes there are evaluated
    without cancellation (through ``R_D(0, 1 - k^2, 1)``).  The step is
    halved until two steps agree to ``1e-12``; the error is then at
    round-off (``~1e-15``; checked against adaptive quadrature).

    Examples
    --------
    >>> print(f"{annulus_rms_slope(0.5):.12f}")
    1.217400850059
    """
    rho = _RATIO.parse(ratio, "")
    span = 1.0 - rho

    def integral(level):
        node, complement, weight = _tanh_sinh(level)
        r = rho + span * node
        to_inner, to_outer = span * node, span * complement
        psi = (-r * special.elliprd(0.0, to_outer * (1.0 + r), 1.0)
               + (rho / r) ** 2 * special.elliprd(0.0, to_inner * (r + rho) / r**2, 1.0)) / 3.0
        return span * np.sum(weight * psi**2 * r)

    value = _converged(integral, "annulus_rms_slope")
    return float(np.sqrt(32.0 / (np.pi**2 * span * (1.0 + rho)) * value))


def _asinh_difference(t, s1, s2, gap):
    """``asinh(s1 / |t|) - asinh(s2 / |t|)`` for ``s1 = s2 + gap``, ``gap > 0``.

    On one side of zero (``s1, s2 >= 0`` or both ``<= 0``) the difference is
    a logarithm of a ratio, taken as ``log1p`` of a sum of positive terms;
    across zero it is a sum of two terms of one sign.  No cancellation, near
    the loaded edges or far from them.  ``+inf`` where ``t = 0`` and the
    interval ``[s2, s1]`` contains 0; finite (``ln |s1 / s2|``) where
    ``t = 0`` and it does not.
    """
    t = np.abs(t)
    above = s2 >= 0
    one_side = above | (s1 <= 0)
    near = np.where(above, s2, -s1)
    far = np.where(above, s1, -s2)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_near, r_far = np.hypot(t, near), np.hypot(t, far)
        # (far + R_far) / (near + R_near) - 1, with
        # R_far - R_near = (far^2 - near^2) / (R_far + R_near).
        ratio_m1 = gap * (1.0 + (near + far) / (r_near + r_far)) / (near + r_near)
        across = np.arcsinh(s1 / t) + np.arcsinh(-s2 / t)
        return np.where(one_side, np.log1p(ratio_m1), across)


def _times(t, value):
    """``t * value`` with the limit 0 where ``t == 0`` (``value`` may be infinite there)."""
    return np.where(t == 0, 0.0, t * np.where(t == 0, 0.0, value))


def _rectangle_offsets(x, y, half_width, half_length):
    a = _HALF_WIDTH.parse(half_width, "", scale=False)
    b = _HALF_LENGTH.parse(half_length, "", scale=False)
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    return x + a, x - a, y + b, y - b, a, b


def _love_gradient(xp, xm, yp, ym, a, b):
    """Gradient of the integral of ``1/r`` over ``|x| < a, |y| < b`` from the edge offsets.

    ``xp = x + a``, ``xm = x - a``, ``yp = y + b``, ``ym = y - b``: passed
    apart so that a caller can place points exponentially close to an edge.
    """
    gx = _asinh_difference(xp, yp, ym, 2 * b) - _asinh_difference(xm, yp, ym, 2 * b)
    gy = _asinh_difference(yp, xp, xm, 2 * a) - _asinh_difference(ym, xp, xm, 2 * a)
    return gx, gy


def rectangle_face(x, y, half_width, half_length, pressure, E_star):
    """Displacement under a uniform pressure on a rectangle (Love's closed form), m.

    Parameters
    ----------
    x, y : array_like, m
        Points, relative to the centre of the rectangle (x along axis 0 of
        the grids), broadcast together; anywhere in the plane, edges and
        corners included.
    half_width : float, m
        Half side ``a`` along x: the load covers ``|x| < a``.
    half_length : float, m
        Half side ``b`` along y: the load covers ``|y| < b``.
    pressure : float, Pa
        Uniform pressure ``p`` on the rectangle.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    ndarray, broadcast shape of ``x`` and ``y``, m
        ``u = p / (pi E*) sum_corners +-F(X, Y)`` with
        ``F(X, Y) = X asinh(Y / |X|) + Y asinh(X / |Y|)`` (0 where ``X`` or
        ``Y`` is 0, its limit), ``X`` in ``{x + a, x - a}``, ``Y`` in
        ``{y + b, y - b}``, sign ``+`` on ``(x + a, y + b)`` and
        ``(x - a, y - b)``.  Continuous everywhere; ``8 p a asinh(1) / (pi E*)``
        at the centre of a square; ``4 p a b / (pi E* r)`` far away.

    Raises
    ------
    ValueError
        If a half side or ``E_star`` is not positive and finite.

    Notes
    -----
    Love, Phil. Trans. R. Soc. A 228 (1929) 377-420,
    doi:10.1098/rsta.1929.0009; Johnson, *Contact Mechanics* (1985),
    sec. 3.9.  :func:`steady.halfspace.pixel_integral` is the square
    pixel's case.  Evaluated as ``X D_X`` and ``Y D_Y`` terms, with ``D``
    the differences of ``asinh`` over the other axis's two edges summed
    without cancellation: far from the rectangle the relative round-off
    grows like ``eps r / min(a, b)``, where the plain corner sum loses
    ``eps (r / min(a, b))^2``.

    Examples
    --------
    >>> u = rectangle_face([0.0, 1e-3, 1e-3], [0.0, 0.0, 3e-3], 1e-3, 3e-3, 1e4, 1e6)
    >>> print(u / (1e4 * 1e-3 / 1e6))  # in units of p a / E*
    [3.56608538 2.715159   1.78304269]
    """
    xp, xm, yp, ym, a, b = _rectangle_offsets(x, y, half_width, half_length)
    integral = (_times(xp, _asinh_difference(xp, yp, ym, 2 * b))
                - _times(xm, _asinh_difference(xm, yp, ym, 2 * b))
                + _times(yp, _asinh_difference(yp, xp, xm, 2 * a))
                - _times(ym, _asinh_difference(ym, xp, xm, 2 * a)))
    return pressure / (np.pi * _E_STAR.parse(E_star, "", scale=False)) * integral


def rectangle_face_gradient(x, y, half_width, half_length, pressure, E_star):
    """Surface gradient ``(du/dx, du/dy)`` of :func:`rectangle_face`, dimensionless.

    Parameters
    ----------
    x, y : array_like, m
        Points, relative to the centre of the rectangle, broadcast together.
    half_width : float, m
        Half side ``a`` along x.
    half_length : float, m
        Half side ``b`` along y.
    pressure : float, Pa
        Uniform pressure ``p`` on the rectangle.
    E_star : float, Pa
        Effective modulus of the half-space.

    Returns
    -------
    gx, gy : ndarray, broadcast shape of ``x`` and ``y``, dimensionless
        ``du/dx = p / (pi E*) sum_corners +-asinh(Y / |X|)`` and
        ``du/dy = p / (pi E*) sum_corners +-asinh(X / |Y|)`` (the corners
        and signs of :func:`rectangle_face`).  Log-singular on the edges:
        the component normal to an edge is infinite on it (``-inf`` on
        ``x = a``, ``+inf`` on ``x = -a``: ``u`` falls outwards), the
        tangential one finite; both are infinite at the corners.  Finite on
        the lines that extend the edges outside the rectangle.  Never NaN.

    Raises
    ------
    ValueError
        If a half side or ``E_star`` is not positive and finite.

    Notes
    -----
    Love (1929), Johnson (1985) sec. 3.9, as :func:`rectangle_face`;
    :func:`steady.halfspace.pixel_integral_gradient` is the square pixel's
    case.  The two terms that share an ``X`` are combined into one
    logarithm of a ratio (no cancellation at an edge's extension or far
    away).

    Examples
    --------
    >>> gx, gy = rectangle_face_gradient([0.0, 0.5e-3, 1e-3], 0.0, 1e-3, 3e-3, 1e4, 1e6)
    >>> print(gx / (1e4 / 1e6), gy)  # gx in units of p / E*
    [ 0.         -0.66726943        -inf] [0. 0. 0.]
    """
    xp, xm, yp, ym, a, b = _rectangle_offsets(x, y, half_width, half_length)
    gx, gy = _love_gradient(xp, xm, yp, ym, a, b)
    scale = pressure / (np.pi * _E_STAR.parse(E_star, "", scale=False))
    return scale * gx, scale * gy


def rectangle_rms_slope(width, length=1.0):
    """Rms-slope factor ``S`` of the homogeneous rectangle ``width x length``.

    The rms of ``|grad u|`` over the rectangle under a uniform pressure
    ``pbar`` is ``S pbar / E*``.  ``S`` depends only on the aspect ratio and
    is symmetric in it.

    Parameters
    ----------
    width, length : float
        The sides (m, or half sides, or any common unit: only
        ``width / length`` matters); ``rectangle_rms_slope(aspect)`` with
        ``length`` at its default 1 takes the aspect ratio, either way up.

    Returns
    -------
    float, dimensionless
        ``S^2 = 1 / (pi^2 A) int_rect |grad G|^2 dA``, ``G`` the integral of
        ``1/r`` over the rectangle (:func:`rectangle_face` in units of
        ``p / (pi E*)``), ``A`` the area.  1.264064510708848 for the square,
        1.251084360516164 at 1:2, 1.235270727397658 at 1:3; tends to the
        infinite strip's ``2 / sqrt(3)`` as the aspect ratio grows (the disk:
        ``4 / pi``, :func:`disk_rms_slope`).

    Raises
    ------
    ValueError
        If a side is not positive and finite.
    RuntimeError
        If the quadrature does not converge (not seen for aspect ratios up
        to ``1e8``).

    Notes
    -----
    Tensor-product tanh-sinh quadrature (Takahasi & Mori, Publ. RIMS 9,
    1974, doi:10.2977/prims/1195192451) of the closed-form gradient
    (:func:`rectangle_face_gradient`) over a quadrant.  The integrand is
    log-squared singular along the edges and more strongly at the corner;
    the rule's nodes crowd the edges doubly exponentially and carry their
    distances to the edges exactly.  The step is halved until two steps
    agree to ``1e-12``; the error is then at round-off, a few ``1e-15``
    (checked by the whole-plane identity ``int |grad u|^2 = 4 pbar^2 A / E*^2``
    with a separate quadrature of the exterior, and by adaptive quadrature).

    Examples
    --------
    >>> print(f"{rectangle_rms_slope(1.0):.12f} {rectangle_rms_slope(2e-3, 6e-3):.12f}")
    1.264064510709 1.235270727398
    """
    w = _WIDTH.parse(width, "", scale=False)
    ln = _LENGTH.parse(length, "", scale=False)
    # Scale-invariant and symmetric: half sides 1 and beta >= 1.
    beta = max(w, ln) / min(w, ln)
    return _rectangle_rms_slope(beta)


@functools.lru_cache(maxsize=32)
def _rectangle_rms_slope(beta):
    def integral(level):
        node, complement, weight = _tanh_sinh(level)
        # Quadrant 0 < x < 1, 0 < y < beta; offsets from the far (x + 1) and
        # near (x - 1 = -(1 - x)) edges.
        xp, xm = (1.0 + node)[:, None], -complement[:, None]
        yp, ym = beta * (1.0 + node)[None, :], -beta * complement[None, :]
        gx, gy = _love_gradient(xp, xm, yp, ym, 1.0, beta)
        return beta * (weight @ (gx * gx + gy * gy) @ weight)

    value = _converged(integral, "rectangle_rms_slope")
    return float(np.sqrt(value / (np.pi**2 * beta)))


#: Tanh-sinh rule: the nodes span |tau| <= _TANH_SINH_SPAN, where the weights
#: fall below 1e-20 and the nodes are ~1e-23 from the ends.
_TANH_SINH_SPAN = 3.5


def _tanh_sinh(level):
    """Tanh-sinh rule on ``[0, 1]`` with step ``2**-level``.

    Returns ``(nodes, 1 - nodes, weights)``, the complements computed
    directly so that they keep their relative accuracy at the upper end.
    """
    step = 2.0**-level
    tau = np.arange(-np.ceil(_TANH_SINH_SPAN / step), np.ceil(_TANH_SINH_SPAN / step) + 1) * step
    u = 0.5 * np.pi * np.sinh(tau)
    weight = step * 0.25 * np.pi * np.cosh(tau) / np.cosh(u) ** 2
    return special.expit(2 * u), special.expit(-2 * u), weight


def _converged(integral, name, *, first=3, last=8, rtol=1e-12):
    """``integral(level)`` at the first level that agrees with the one before to ``rtol``."""
    previous = integral(first)
    for level in range(first + 1, last + 1):
        value = integral(level)
        if abs(value - previous) <= rtol * abs(value):
            return value
        previous = value
    raise RuntimeError(f"{name}: tanh-sinh quadrature did not converge to {rtol:g} by step "
                       f"2**-{last} (last change {abs(value - previous):.1e})")
