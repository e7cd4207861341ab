"""Steady pressure on each phase under the power law (paper equation 7).

In the steady state every point wears at the same rate, ``k_i p_i^m = C``,
and the phases together carry the normal force.  :func:`phase_pressures`
is the one place eq. 7 is written, for one set of wear coefficients or for
many rows of them at once (sweeps, :class:`steady.basis.PhaseBasis`); the
power law of :mod:`steady.wear` inverts its steady state with it, and
:func:`steady.wear.pressure_field` spreads a law's phase pressures over the
pixels of a phase map.
"""

from __future__ import annotations

import numpy as np

__all__ = ["phase_pressures"]


def _phase_pressures(counts, k, normal_force, pixel_area, exponent):
    # Scale by the smallest k first: k^(-1/m) of extreme ratios stays finite.
    weights = (k / k.min()) ** (-1.0 / exponent)
    return normal_force * weights / (pixel_area * np.dot(counts, weights))


_phase_pressures_rows = np.vectorize(_phase_pressures, signature="(p),(p),(),(),()->(p)")


def phase_pressures(counts, wear_coefficients, normal_force, pixel_area, *, exponent=1.0):
    """Steady pressure on each phase (eq. 7, generalised to ``k p^m = C``).

    Parameters
    ----------
    counts : array_like, shape (P,) or (..., P)
        Face pixels of each phase (int), or any measure proportional to
        the phase areas (e.g. fill factors with ``pixel_area`` 1).
    wear_coefficients : array_like, shape (P,) or (..., P), 1/Pa
        ``k_i``, positive.  Leading dimensions of ``counts`` and
        ``wear_coefficients`` broadcast: one row per set of phases.
    normal_force : float, N
    pixel_area : float, m^2
        ``h^2``.
    exponent : float, optional
        ``m`` in ``dw/ds = k p^m`` (default 1, Archard).

    Returns
    -------
    ndarray, shape (P,) or (..., P), Pa
        ``p_i = F k_i^(-1/m) / sum_j A_j k_j^(-1/m)`` with
        ``A_j = counts_j h^2``, so that ``sum_i A_i p_i = F``.

    Examples
    --------
    Two phases of equal area, the second wearing ten times faster, carry
    the pressures ``10 : 1``:

    >>> phase_pressures([50, 50], [1e-9, 1e-8], 11.0, 1.0)
    array([0.2 , 0.02])
    """
    counts = np.asarray(counts)
    k = np.asarray(wear_coefficients, dtype=float)
    if counts.ndim == 1 and k.ndim == 1:
        return _phase_pressures(counts, k, normal_force, pixel_area, exponent)
    return _phase_pressures_rows(counts, k, normal_force, pixel_area, exponent)
