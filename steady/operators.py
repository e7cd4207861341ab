"""The elastic operator of a face's grid: the one place that chooses it.

A finite face lies on the half-space, zero padded around it
(:class:`steady.halfspace.HalfSpace`); a periodic cell (an outline whose
``periodic`` is True) repeats, and its operator is the periodic one
(:class:`steady.periodic.PeriodicHalfSpace`).  Every caller that builds the
operator of a grid -- the problem, the steady solve, the sweep basis, the rms
slope estimator -- asks :func:`operator_of`.
"""

from __future__ import annotations

from .halfspace import HalfSpace
from .periodic import PeriodicHalfSpace

__all__ = ["operator_of"]


def operator_of(grid, E_star, *, workers=-1):
    """The elastic operator of a face's grid.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
        The face's grid (its outline, shape and pixel size).
    E_star : float, Pa
        Effective modulus of the counter-body.
    workers : int, optional
        Threads of the transforms (:mod:`scipy.fft`'s count; default -1, all cores).

    Returns
    -------
    steady.halfspace.HalfSpace or steady.periodic.PeriodicHalfSpace
        The periodic operator when ``grid.outline.periodic``, else the
        zero-padded half-space.

    Examples
    --------
    >>> from steady.outline import Circle, PeriodicCell
    >>> type(operator_of(Circle(4e-3).grid(32), 1e6)).__name__
    'HalfSpace'
    >>> type(operator_of(PeriodicCell(4e-3, 4e-3).grid(32), 1e6)).__name__
    'PeriodicHalfSpace'
    """
    if grid.outline.periodic:
        return PeriodicHalfSpace(grid.shape, grid.h, E_star, workers=workers)
    return HalfSpace(grid.shape, grid.h, E_star, workers=workers)
