"""Where the model holds, and the warning when a problem leaves that range.

The model (docs/model.md, "Range of validity") is the linear elastic
half-space under a rigid punch: it keeps the first order in the slope of
the counter-body's surface.  The limiting face's rms slope is its measure;
it is ``S grad_f0``, with ``grad_f0 = 4 pbar / (pi E*)`` for a disk (eq.
12) and ``S`` the normalised rms slope of the microstructure (eq. 15), so
that the mean pressure over the modulus stays in range up to

    pbar / E* = pi SLOPE_LIMIT / (4 S)

(0.248 for a homogeneous disk, 0.154 for the Voronoi punch of the paper's
Fig. 3 with ``S = 1.61``, whose load is 0.153).  A scene or a design query beyond it is still
answered, with a :class:`ValidityWarning`; the commands print it as one
line ``warning: ...`` on stderr and keep their exit status.
"""

from __future__ import annotations

import math
import warnings

__all__ = ["DROPPED_TERMS", "SLOPE_LIMIT", "ValidityWarning", "check_rms_slope",
           "max_pbar_over_estar"]

#: Relative size of the terms the linear half-space drops, ``theta^2 / 2``,
#: at which a face's slope ``theta`` stops being small.
DROPPED_TERMS = 0.05

#: Largest rms slope (rad) of the face for which the linear half-space holds:
#: the terms it drops are of relative order ``theta^2 / 2`` (``1 - cos theta``
#: in the projection of the normal traction and of the surface element), which
#: reach :data:`DROPPED_TERMS` at ``sqrt(0.1) = 0.316`` rad, 18 degrees
#: (docs/model.md, "Range of validity").
SLOPE_LIMIT = math.sqrt(2.0 * DROPPED_TERMS)

_SEE = 'docs/model.md, "Range of validity"'


class ValidityWarning(UserWarning):
    """A problem outside the range where the model holds (docs/model.md, "Range of validity")."""


def max_pbar_over_estar(normalised_rms_slope=1.0, *, factor=4.0 / math.pi):
    """The ``pbar / E*`` at which the face's rms slope reaches :data:`SLOPE_LIMIT`.

    Parameters
    ----------
    normalised_rms_slope : float, optional
        ``S = rms / grad_f0`` of the microstructure (eq. 15); default 1, the
        homogeneous face.
    factor : float, optional
        ``grad_f0`` in units of ``pbar / E*``: ``4 / pi`` for a disk (eq.
        12, the default), :attr:`steady.normalisation.ReferenceSlope.factor`
        for another outline.

    Returns
    -------
    float
        ``SLOPE_LIMIT / (factor S)``.

    Examples
    --------
    >>> print(f"{max_pbar_over_estar():.4f} {max_pbar_over_estar(1.61):.4f}")
    0.2484 0.1543
    """
    return SLOPE_LIMIT / (factor * normalised_rms_slope)


def check_rms_slope(rms_slope, what, *, stacklevel=2):
    """Warn when an rms slope leaves the range of small slopes.

    Parameters
    ----------
    rms_slope : float, dimensionless
        The rms slope of a face (NaN: not known, no warning).
    what : str
        The slope's origin, in words, to start the message (``"the steady
        face of scene.toml"``).
    stacklevel : int, optional
        Passed to :func:`warnings.warn`.

    Returns
    -------
    bool
        Whether the slope lies within :data:`SLOPE_LIMIT` (or is unknown).

    Warns
    -----
    ValidityWarning
        ``rms_slope > SLOPE_LIMIT``; the message names the value and the limit.
    """
    if not rms_slope > SLOPE_LIMIT:
        return True
    warnings.warn(f"{what} has an rms slope of {rms_slope:.3g} rad, beyond the "
                  f"{SLOPE_LIMIT:.3g} rad of small slopes where the linear half-space holds: "
                  f"the numbers are those of the linear model, not of the contact ({_SEE})",
                  ValidityWarning, stacklevel=stacklevel + 1)
    return False
