"""The reference slope of a face outline: the normalisation of rms slopes (equations 12, 15).

The paper normalises the rms slope of a worn face by that of the
homogeneous face of the same outline under the same mean pressure: for a
disk ``grad_f0 = 4 pbar / (pi E*)`` (eq. 12), with ``pbar = F_N / (pi a^2)``.
For any outline the homogeneous steady face is the displacement under the
uniform pressure ``pbar = F_N / A`` (``A`` the outline's area), and its rms
slope is ``S pbar / E*`` with a factor ``S`` that depends only on the
outline's shape (the displacement is ``pbar / E*`` times a function of the
position in units of the outline's size).  ``S`` comes from the outline's
closed form where it has one (:meth:`~steady.outline.Circle.homogeneous_slope_factor`):

- the disk: ``4 / pi`` (eq. 12; :func:`steady.reference.disk_normalised_rms_slope`
  shows that the continuum value is exactly that);
- the rectangle: quadrature of Love's closed-form gradient
  (:func:`steady.reference.rectangle_rms_slope`);
- the annulus: superposed disks (:func:`steady.reference.annulus_rms_slope`);
- any other outline (ellipse, mask): the corrected rms-slope estimator of
  :mod:`steady.rms_slope` on the homogeneous face, with its error bar, on a
  grid of :data:`REFERENCE_GRID` pixels along the longer side (a mask: the
  smallest multiple of its size at least that fine).

:func:`reference_slope` returns the value with its error and a sentence
saying where it came from, which results and command lines report.
"""

from __future__ import annotations

import dataclasses
import functools

from .phases import Homogeneous
from .rms_slope import estimate_rms_slope

__all__ = ["REFERENCE_GRID", "ReferenceSlope", "reference_slope", "slope_factor"]

#: Pixels along the longer side of the grid on which the reference slope of an
#: outline without a closed form is estimated.
REFERENCE_GRID = 512


@dataclasses.dataclass(frozen=True)
class ReferenceSlope:
    """The rms slope of the homogeneous face of an outline under a load.

    Attributes
    ----------
    value : float, dimensionless
        ``S pbar / E*``: the normalisation ``grad_f0`` of rms slopes.
    error : float, dimensionless
        Its uncertainty (0 for a closed form evaluated to round-off).
    mean_pressure : float, Pa
        ``pbar = F_N / A``, ``A`` the outline's exact area.
    factor : float
        ``S``, the rms slope in units of ``pbar / E*``.
    source : str
        Where the value comes from, in words.
    """

    value: float
    error: float
    mean_pressure: float
    factor: float
    source: str


@functools.lru_cache(maxsize=64)
def slope_factor(outline):
    """``(S, error, source)``: the homogeneous face's rms slope in units of ``pbar / E*``.

    Parameters
    ----------
    outline : outline object (:mod:`steady.outline`)

    Returns
    -------
    factor : float
    error : float
        Uncertainty of ``factor``.
    source : str

    Examples
    --------
    >>> from steady.outline import Circle
    >>> factor, error, source = slope_factor(Circle(4e-3))
    >>> print(f"{factor:.12f} {error} {source}")
    1.273239544735 0.0 disk: 4 pbar / (pi E*) (eq. 12)
    """
    closed = outline.homogeneous_slope_factor()
    return closed if closed is not None else _estimated_factor(outline)


def _estimated_factor(outline):
    """``S`` from the corrected estimator on the homogeneous face (no closed form)."""
    # REFERENCE_GRID pixels, or the outline's next accepted grid (a multiple of a mask's size).
    n = outline.grid_at_least(REFERENCE_GRID)
    # Unit load on a unit modulus: the rms slope is S pbar with pbar = 1 / area.
    force = outline.area
    estimate = estimate_rms_slope(Homogeneous(), [1.0], force, outline, 1.0, n)
    source = (f"homogeneous {outline.kind} face: corrected rms-slope estimator at n = "
              f"{estimate.grids[-1]} (grids {', '.join(map(str, estimate.grids))})")
    return float(estimate.rms_slope), float(estimate.error), source


def reference_slope(outline, normal_force, E_star):
    """The reference slope ``grad_f0`` of an outline under a load.

    Parameters
    ----------
    outline : outline object (:mod:`steady.outline`)
    normal_force : float, N
    E_star : float, Pa

    Returns
    -------
    ReferenceSlope
        For a disk, ``4 pbar / (pi E*)`` with ``pbar = F_N / (pi a^2)``,
        exactly as :func:`steady.reference.disk_reference_slope`.

    Examples
    --------
    >>> from steady.outline import Circle
    >>> ref = reference_slope(Circle(4e-3), 10.0, 1.3e6)
    >>> print(f"{ref.value:.6f} {ref.mean_pressure:.2f}")
    0.194848 198943.68
    """
    # For a disk the area is pi a^2: pbar is steady.reference.disk_mean_pressure's, bit for bit.
    pbar = normal_force / outline.area
    factor, error, source = slope_factor(outline)
    value = outline.homogeneous_rms_slope(factor, pbar, E_star)
    return ReferenceSlope(value=float(value), error=float(error * pbar / E_star),
                          mean_pressure=float(pbar), factor=float(factor), source=source)
