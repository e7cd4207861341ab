"""Closed-form reference solutions shared by tests, studies and the command line.

All functions take SI units and return SI units.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate, special

from .pressures import phase_pressures

__all__ = [
    "cylinder_face",
    "cylinder_face_slope",
    "cylinder_rms_slope",
    "fine_grain_rms_slope",
    "flat_punch_approach",
    "flat_punch_pressure",
    "hertz",
    "mean_pressure",
    "pillars_rms_slope",
    "reference_slope",
]


def mean_pressure(normal_force, radius):
    """Mean pressure ``pbar = F_N / (pi a^2)`` on the punch face, Pa.

    The paper prints ``(pi a)^2``; that is a typo.
    """
    return normal_force / (np.pi * radius**2)


def reference_slope(mean_pressure, E_star):
    """Reference slope ``grad_f0 = 4 pbar / (pi E*)`` (eq. 12), dimensionless."""
    return 4.0 * mean_pressure / (np.pi * E_star)


def cylinder_face(r, radius, mean_pressure, E_star):
    """Limiting worn face of a homogeneous cylinder (eq. 10).

    Parameters
    ----------
    r : array_like, m
        Distance from the axis, ``0 <= r <= radius``.
    radius : float, m
    mean_pressure : float, Pa
    E_star : float, Pa

    Returns
    -------
    ndarray, m
        ``f_inf(r) = 4 pbar a / (pi E*) E(r/a)``; ``E`` is the complete
        elliptic integral of the second kind with modulus ``r/a``
        (:func:`scipy.special.ellipe` takes the parameter ``(r/a)^2``).
        NaN outside the face.
    """
    rho = np.asarray(r, dtype=float) / radius
    inside = rho <= 1.0
    m = np.where(inside, rho**2, 0.0)
    return np.where(inside, 4 * mean_pressure * radius / (np.pi * E_star) * special.ellipe(m),
                    np.nan)


def cylinder_face_slope(r, radius, mean_pressure, E_star):
    """Radial derivative of :func:`cylinder_face`, dimensionless.

    ``dE/dk = (E(k) - K(k)) / k``; log-singular at the rim.  Zero on the axis.
    """
    rho = np.asarray(r, dtype=float) / radius
    inside = rho < 1.0
    k = np.where(inside & (rho > 0), rho, 0.5)
    d = (special.ellipe(k**2) - special.ellipk(k**2)) / k
    d = np.where(rho > 0, d, 0.0)
    return np.where(inside, reference_slope(mean_pressure, E_star) * d, np.nan)


def cylinder_rms_slope():
    """Continuum rms slope of the eq. 10 face over the disk, in units of ``grad_f0``.

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
    return reference_slope(mean_pressure, E_star) / _hard_fill_factor(hard_fill_factor)


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
    (Parseval; :mod:`steady.accuracy`).  Split the steady pressure into its
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
