"""Memory of a run-in: an estimate of its peak, counted from the arrays it allocates.

The command ``runin-transient`` compares it with the memory available
(:func:`steady.memory.check_memory`) before a run starts.
"""

from __future__ import annotations

import math

from steady.memory import halfspace_memory, product_memory, slope_estimator_memory

__all__ = ["run_in_memory"]


def run_in_memory(n, snapshots=0, *, periodic=False):
    """Estimated peak memory of a run-in at grid ``n``, bytes.

    Counted from the arrays the run allocates, in bytes per pixel of the
    ``n x n`` grid (8 per float; a rectangular ``nx x ny`` grid is counted
    as the square of as many pixels, as :func:`steady.memory.steady_memory`
    does):

    - the half-space operator with its gradient spectra
      (:func:`steady.memory.halfspace_memory`, 128) and the aliased
      symbol of the Fourier preconditioner (4);
    - the problem's fields: labels, face mask, wear coefficient (17);
    - the run state: face, initial face, pressure, previous face and rate
      (40);
    - the history's slope estimator (:class:`transient.history.FaceEstimator`:
      :class:`steady.rms_slope.SlopeEnergy`), kept (its spectra in single
      precision, about 65, :func:`steady.memory.slope_estimator_memory`);
    - the pressure history of the warm starts
      (:class:`transient.warm_start.WarmStart`: six pressures and their
      products; their differences are formed one at a time): 96;
    - the larger of one step and the slope estimator's work: a step of
      ESDIRK3, the largest, has three stages, each a contact solve
      (pressure, gap, preconditioned residual, direction, its product,
      displacement, shift and warm start: 64), the stages' rates, faces
      and error (64), the transforms of one half-space product
      (:func:`steady.memory.product_memory`, 112), the stitched
      preconditioner's weights, symbols and transforms (48) and the
      gradient of a partial-contact record (64): 352; the estimator
      applied (about 150);
    - one history record computed on the worker thread beside the step
      (on the run's face and pressure, not copied): the estimator applied;
    - every checkpoint's pressure history (six pressures and their
      displacements, handed to the result without a copy, but the warm
      start's next push writes them anew): 96; the file is written as
      HDF5 writes it, not built in memory (:func:`steady.safe_files.atomic_h5`);
    - each snapshot: face and pressure kept (16, shared by every
      checkpoint's result).

    On a periodic cell the operator, its products and the slope estimator
    are the cell's, with no padding (``periodic``: 20, 48 and about 4 kept
    and 100 applied, :mod:`steady.memory`); the rest is the same.

    The sum is multiplied by 1.25 (allocator overhead, short-lived copies
    not listed) and 16 MiB are added for what does not grow with ``n``.
    The closing steady solve of the comparison needs less than one step.
    The estimate is an upper bound of the measured peak within a factor of
    2 (``tests/test_memory.py``; the measured ratios are in
    docs/benchmarks.md, "Memory estimates").

    Parameters
    ----------
    n : int or (int, int)
        Pixels across a square grid, or ``(nx, ny)``.
    snapshots : int, optional
        Snapshots the run stores (default 0).
    periodic : bool, optional
        The grid is a periodic cell's (the outline's ``periodic``), whose
        operator has no padding (default False).

    Returns
    -------
    int

    Examples
    --------
    >>> from steady.text import format_bytes
    >>> print(format_bytes(run_in_memory(512, 3)), format_bytes(run_in_memory(12000)))
    329 MiB 158 GiB
    >>> print(format_bytes(run_in_memory(1024, periodic=True)))
    845 MiB
    """
    n = int(n) if not isinstance(n, (tuple, list)) else math.ceil(math.sqrt(n[0] * n[1]))
    pixels = n * n
    kept, applied = slope_estimator_memory(n, periodic=periodic)
    step = (64 + 64 + 48 + 64) * pixels + product_memory(n, periodic=periodic)
    peak = (halfspace_memory(n, gradient=True, periodic=periodic)
            + (4 + 17 + 40 + 96 + 96) * pixels + kept
            + max(step, applied) + applied + 16 * pixels * int(snapshots))
    return int(1.25 * peak) + 16 * 2 ** 20
