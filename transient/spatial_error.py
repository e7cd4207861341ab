"""The run-in history's grid error from the same run on two coarser grids.

The per-step error bar of the history (:mod:`transient.history`) covers
the rim layer and the estimator's error on the phase map; it does not see
everything the grid changes in the dynamics: how the phases' boundaries and
the face's outline fall on the pixels (their rasterised areas, the worn
steps while they are narrower than a few pixels).  The plainest measure of
what the grid does is the same run on coarser grids: :func:`spatial_error`
rasterises the scene's phase geometry at about ``3 n / 4`` and ``n / 2``
(:func:`companion_grids`), runs each with the same options, and returns, at
every recorded distance of the main run, ``max_m |S_n - S_m|`` over the
companions.

The plain difference, not a Richardson extrapolation: the run-in
distances of the shipped scenes do not converge at an order under
refinement.  Their grid error is the rasterisation's, of the same size on
every grid and of either sign (docs/model.md, "The companion runs": the
Voronoi scene's ``s_1%`` is between 51723 and 52249 m on every grid from
n = 48 to 256, without a trend), so a first-order extrapolation from
``n/2`` would state the difference itself and one from ``3n/4`` three
times it.  Two companions at different
ratios sample that scatter twice.  They cost about ``(3/4)^2 + (1/2)^2``,
0.8 of the main run.
"""

from __future__ import annotations

import dataclasses
import logging
import types

import numpy as np

from steady.outline import FaceGrid

from . import run_in_distance
from .runin import run_in
from .scene import wear_problem_of

__all__ = ["SpatialError", "companion_grids", "spatial_error"]

logger = logging.getLogger(__name__)

#: History dataset the companion run's error goes into.
DATASET = "rms_slope_spatial_error"
#: History datasets of the companions' deviations from their own steady states (the larger of
#: the two the run-in distance is made of), their least and greatest at each recorded distance.
DEVIATION_DATASETS = ("companion_deviation_low", "companion_deviation_high")


@dataclasses.dataclass(frozen=True, eq=False)
class SpatialError:
    """The companion runs on coarser grids and the error bar they give.

    Attributes
    ----------
    grids : tuple of int
        The companions' grids ``m``, finer first.
    runs : tuple of transient.result.RunResult
        The companion runs themselves, in the order of :attr:`grids`.
    rms_slope : ndarray, shape (G, K)
        Their rms slopes at the main run's recorded distances (linear in
        ``log s`` between their own points; beyond a companion's end its
        last value if it ended steady, else NaN).
    error : ndarray, shape (K,)
        ``max_m |S_n - S_m|`` at the main run's recorded distances; 0 at
        ``s = 0``, where each is the initial face's own value.
    deviation_low, deviation_high : ndarray, shape (K,), or None
        The least and the greatest over the companions of their deviation
        from the steady state, ``max(d_S, d_f)`` of
        :func:`transient.run_in_distance.deviations` (each companion
        against its own grid's steady state), at the main run's recorded
        distances (``log`` of it linear in ``s`` between the companion's
        points).  The run-in distance within ``x`` of the companions lies
        between the distances where these two enter ``x``.  None when a run
        lacks the deviations.
    """

    grids: tuple
    runs: tuple
    rms_slope: np.ndarray
    error: np.ndarray
    deviation_low: np.ndarray | None = None
    deviation_high: np.ndarray | None = None

    def attach(self, result):
        """``result`` with its history's ``rms_slope_spatial_error`` filled from :attr:`error`.

        Parameters
        ----------
        result : transient.result.RunResult
            The main run this error belongs to.

        Returns
        -------
        transient.result.RunResult
        """
        if len(self.error) != len(result.history["distance"]):
            raise ValueError(f"the spatial error has {len(self.error)} points, the run's history "
                             f"{len(result.history['distance'])}: not the same run")
        history = dict(result.history)
        history[DATASET] = np.array(self.error, dtype=float)
        for name, value in zip(DEVIATION_DATASETS, (self.deviation_low, self.deviation_high),
                               strict=True):
            if value is not None:
                history[name] = np.array(value, dtype=float)
        return dataclasses.replace(result, history=types.MappingProxyType(history))


def companion_grids(geometry, n, outline=None):
    """Grids of the companion runs: about ``3 n / 4`` and ``n / 2``, where admissible.

    Parameters
    ----------
    geometry : phase geometry
        ``check_grid(grid)`` raises ``ValueError`` for inadmissible grids.
    n : int
        The main run's grid (pixels along the longer side).
    outline : outline object, optional
        The face (:mod:`steady.outline`), whose grid must resolve it too
        (``outline.check_grid``); default the unit disk, radius 1 m (the
        grid of a bare ``n``).

    Returns
    -------
    tuple of int
        ``round(3 n / 4)``, or the coarsest admissible grid between it and
        ``n``; then ``n // 2`` if admissible and coarser.  One grid when
        only the first exists.

    Raises
    ------
    ValueError
        No grid below ``n`` is admissible (e.g. a pixel map at its own
        size, or an outline that needs ``n`` pixels); the message names
        the minimum.

    Examples
    --------
    >>> from steady.phases import Voronoi
    >>> voronoi = Voronoi(400, (0.7, 0.3), 2029)
    >>> companion_grids(voronoi, 128), companion_grids(voronoi, 64)
    ((96, 64), (48,))
    """
    def admissible(m):
        try:
            geometry.check_grid(m if outline is None else FaceGrid(outline, m))
        except ValueError:
            return False
        return True

    first = next((m for m in range(max(round(3 * n / 4), 2), n) if admissible(m)), None)
    if first is None:
        if outline is None:
            minimum = geometry.min_grid()
        else:
            minimum = max(geometry.min_grid(outline), outline.min_grid())
        what = ("this phase map" if outline is None
                else f"this phase map on the {outline.describe()}")
        raise ValueError(f"no grid coarser than n = {n} is admissible for {what} "
                         f"(minimum {minimum}): no companion run")
    half = n // 2
    return (first, half) if 2 <= half < first and admissible(half) else (first,)


def spatial_error(scene, initial, options, result, *, grids=None, on_step=None):
    """Run ``scene`` on coarser grids and measure the history's grid error against them.

    Parameters
    ----------
    scene : steady.scene.Scene
        The scene of the main run (its phase geometry is rasterised at the
        companions' grids).
    initial : transient.scene.InitialFace or callable
        The initial face: an object with ``recession(grid)`` (the scene's
        ``[initial_face]``), or ``initial(grid) -> ndarray`` (``grid`` a
        companion's :class:`steady.outline.FaceGrid`).  It must exist on
        the companions' grids: a recession file of the main grid
        (``kind = "file"``) does not, and raises ``ValueError``.
    options : transient.options.RunOptions
        The main run's options (the same distances, tolerance, scheme).
    result : transient.result.RunResult
        The main run.
    grids : sequence of int, optional
        Companion grids, each in ``[2, n)``; default :func:`companion_grids`.
    on_step : callable, optional
        Passed to :func:`transient.runin.run_in` (progress).

    Returns
    -------
    SpatialError
        ``.attach(result)`` puts the errors into the history.

    Examples
    --------
    >>> from steady import examples
    >>> from transient import RunOptions, run_in
    >>> from transient.scene import load_transient_scene, wear_problem_of
    >>> scene, _, initial = load_transient_scene(examples.path("voronoi_transient"))
    >>> options = RunOptions(tol=1e-2)
    >>> problem = wear_problem_of(scene, n=64)
    >>> result = run_in(problem, initial.recession(problem.grid), options)
    >>> companions = spatial_error(scene, initial, options, result)
    >>> result = companions.attach(result)
    >>> error = result.history["rms_slope_spatial_error"]
    >>> companions.grids, error.shape == result.history["distance"].shape
    ((48,), True)
    """
    n = max(result.recession.shape)
    grids = (companion_grids(scene.geometry, n, scene.outline) if grids is None
             else tuple(int(m) for m in grids))
    for m in grids:
        if not 2 <= m < n:
            raise ValueError(f"companion grid must lie in [2, {n}), got {m}")
    build = initial.recession if hasattr(initial, "recession") else initial
    target = result.history["distance"]
    runs, slopes, deviations = [], [], []
    for m in grids:
        problem = wear_problem_of(scene, n=m)
        logger.info("companion run on n = %d (main run n = %d)", m, n)
        coarse = run_in(problem, build(problem.grid), options, on_step=on_step)
        if not coarse.success:
            logger.warning("companion run %s: %s", coarse.status, coarse.message)
        runs.append(coarse)
        h = coarse.history
        slopes.append(_at(h["distance"], h["rms_slope"], target, steady=coarse.success))
        try:
            deviation = run_in_distance.deviations(coarse)[0]
        except ValueError:  # a run without a steady rms slope or face deviation
            continue
        deviations.append(_decay_at(h["distance"], deviation, target, steady=coarse.success))
    main = np.asarray(result.history["rms_slope"], dtype=float)
    low = high = None
    if len(deviations) == len(grids):
        low, high = np.min(deviations, axis=0), np.max(deviations, axis=0)
    return SpatialError(grids=grids, runs=tuple(runs), rms_slope=np.array(slopes),
                        error=_largest(slopes, main), deviation_low=low, deviation_high=high)


def _decay_at(distance, deviation, targets, *, steady):
    """A deviation (given at ``distance``, m) at ``targets``: its ``log`` linear in ``s``.

    As :func:`transient.run_in_distance.entry` reads a history between two
    points (exact for an exponential decay); linear where a value is 0.
    Targets beyond the last distance take the last value if the run ended
    steady, else NaN.
    """
    distance = np.asarray(distance, dtype=float)
    deviation = np.asarray(deviation, dtype=float)
    targets = np.asarray(targets, dtype=float)
    if distance.size == 1:  # a run that jumped to its steady state at once
        out = np.full(targets.shape, deviation[0])
        out[targets > distance[0]] = deviation[0] if steady else np.nan
        return out
    right = np.clip(np.searchsorted(distance, targets, side="right"), 1, distance.size - 1)
    left = right - 1
    d0, d1 = deviation[left], deviation[right]
    span = distance[right] - distance[left]
    t = np.clip((targets - distance[left]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
    both = (d0 > 0) & (d1 > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.exp(np.log(np.where(both, d0, 1.0)) * (1 - t)
                      + np.log(np.where(both, d1, 1.0)) * t)
    out = np.where(both, logs, d0 + (d1 - d0) * t)
    beyond = targets > distance[-1] * (1 + 1e-12)
    out[beyond] = deviation[-1] if steady else np.nan
    return out


def _largest(coarse, fine):
    """``max_m |fine - coarse_m|`` (NaN where any companion has no value)."""
    fine = np.asarray(fine, dtype=float)
    return np.max([np.abs(fine - np.asarray(c, dtype=float)) for c in coarse], axis=0)


def _at(distance, values, targets, *, steady):
    """``values`` (given at ``distance``, m) at ``targets``: linear in ``log s``, exact at 0.

    Targets before the first positive distance take its value; targets
    beyond the last distance take the last value if the run ended steady,
    else NaN (the companion run stopped earlier).
    """
    distance = np.asarray(distance, dtype=float)
    values = np.asarray(values, dtype=float)
    targets = np.asarray(targets, dtype=float)
    out = np.full(targets.shape, np.nan)
    out[targets == 0] = values[distance == 0][0] if np.any(distance == 0) else np.nan
    positive = distance > 0
    if not np.any(positive):  # a run that jumped to its steady state at once
        if steady:
            out[targets > 0] = values[-1]
        return out
    pos_d, pos_v = distance[positive], values[positive]
    inside = (targets > 0) & (targets <= pos_d[-1] * (1 + 1e-12))
    out[inside] = np.interp(np.log(targets[inside]), np.log(pos_d), pos_v)
    if steady:
        out[targets > pos_d[-1]] = pos_v[-1]
    return out
