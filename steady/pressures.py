"""Steady pressure on each phase (paper eq. 7).

In the steady state every point wears at the same rate, ``k_i p_i^m = C``,
and the phases together carry the normal force.
"""

from __future__ import annotations

import numpy as np

__all__ = ["phase_pressures"]


def phase_pressures(counts, wear_coefficients, normal_force, pixel_area, *, exponent=1.0):
    """Steady pressure on each phase (eq. 7, generalised to ``k p^m = C``).

    Parameters
    ----------
    counts : array_like, shape (P,), int
        Face pixels of each phase.
    wear_coefficients : array_like, shape (P,), 1/Pa
        ``k_i``, positive.
    normal_force : float, N
    pixel_area : float, m^2
        ``h^2``.
    exponent : float, optional
        ``m`` in ``dw/ds = k p^m`` (default 1, Archard).

    Returns
    -------
    ndarray, shape (P,), Pa
        ``p_i = F k_i^(-1/m) / sum_j A_j k_j^(-1/m)`` with
        ``A_j = counts_j h^2``, so that ``sum_i A_i p_i = F``.
    """
    k = np.asarray(wear_coefficients, dtype=float)
    # Scale by the smallest k first: k^(-1/m) of extreme ratios stays finite.
    weights = (k / k.min()) ** (-1.0 / exponent)
    return normal_force * weights / (pixel_area * np.dot(counts, weights))
