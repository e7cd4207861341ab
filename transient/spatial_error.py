"""The run-in history's spatial error bar from the same run on a coarser grid.

The per-step error bar of the history (:mod:`transient.history`) covers
the rim layer and the estimator's error on the phase map; it does not see
everything the grid changes in the dynamics (the interior phase
boundaries' worn steps while they are narrower than a few pixels).  The
plainest measure of what the grid does is the same run on a coarser grid:
:func:`spatial_error` rasterises the scene's phase geometry at ``n // 2``
(or the coarsest admissible grid above it), runs it with the same options,
and returns, at every recorded distance of the main run, the first-order
error ``|S_n - S_m| * m / (n - m)`` (``= |S_n - S_n/2|`` for ``m = n/2``;
:func:`steady.rms_slope.ladder_error`).  It costs about a quarter of the
main run.
"""

from __future__ import annotations

import dataclasses
import logging
import types

import numpy as np

from steady.outline import FaceGrid
from steady.rms_slope import ladder_error

from .runin import run_in
from .scene import wear_problem_of

__all__ = ["SpatialError", "companion_grid", "spatial_error"]

logger = logging.getLogger(__name__)

#: History dataset the companion run's error goes into.
DATASET = "rms_slope_spatial_error"
#: History dataset the companion's error of the face deviation goes into.
FACE_DATASET = "face_deviation_spatial_error"
#: History dataset the companion's error of the rms slope's relative deviation goes into.
SLOPE_DEVIATION_DATASET = "rms_slope_deviation_spatial_error"


@dataclasses.dataclass(frozen=True, eq=False)
class SpatialError:
    """The companion run on a coarser grid and the error bar it gives.

    Attributes
    ----------
    grid : int
        The companion's grid ``m``.
    run : transient.result.RunResult
        The companion run itself.
    rms_slope : ndarray, shape (K,)
        Its rms slope at the main run's recorded distances (linear in
        ``log s`` between its own points; beyond its end its last value if
        it ended steady, else NaN).
    error : ndarray, shape (K,)
        ``|S_n - S_m| * m / (n - m)`` at the main run's recorded distances;
        0 at ``s = 0``, where both are the initial face's own value.
    face_deviation_error : ndarray, shape (K,), or None
        ``|D_n - D_m| * m / (n - m)`` of the history's ``face_deviation``
        (the face's distance from the steady face, relative to its relief),
        likewise; None when either run lacks it.
    slope_deviation_error : ndarray, shape (K,), or None
        The same of the rms slope's relative deviation from each run's own
        steady value, ``S / S_inf - 1`` (the grids' different steady values
        left out: what the run-in distance sees); None when either run
        lacks ``steady_rms_slope``.
    """

    grid: int
    run: object
    rms_slope: np.ndarray
    error: np.ndarray
    face_deviation_error: np.ndarray | None = None
    slope_deviation_error: np.ndarray | None = None

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
        for name, value in ((FACE_DATASET, self.face_deviation_error),
                            (SLOPE_DEVIATION_DATASET, self.slope_deviation_error)):
            if value is not None:
                history[name] = np.array(value, dtype=float)
        return dataclasses.replace(result, history=types.MappingProxyType(history))


def companion_grid(geometry, n, outline=None):
    """Grid of the companion run: ``n // 2`` if admissible, else the coarsest above.

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
    int

    Raises
    ------
    ValueError
        No grid below ``n`` is admissible (e.g. a pixel map at its own
        size, or an outline that needs ``n`` pixels); the message names
        the minimum.

    Examples
    --------
    >>> from steady.phases import Voronoi
    >>> companion_grid(Voronoi(400, (0.7, 0.3), 2029), 128), companion_grid(
    ...     Voronoi(400, (0.7, 0.3), 2029), 64)
    (64, 40)
    """
    for m in range(max(n // 2, 2), n):
        try:
            geometry.check_grid(m if outline is None else FaceGrid(outline, m))
        except ValueError:
            continue
        return m
    if outline is None:
        minimum = geometry.min_grid()
    else:
        minimum = max(geometry.min_grid(outline), outline.min_grid())
    what = "this phase map" if outline is None else f"this phase map on the {outline.describe()}"
    raise ValueError(f"no grid coarser than n = {n} is admissible for {what} "
                     f"(minimum {minimum}): no companion run")


def spatial_error(scene, initial, options, result, *, grid=None, on_step=None):
    """Run ``scene`` on a coarser grid and measure the history's spatial error against it.

    Parameters
    ----------
    scene : steady.scene.Scene
        The scene of the main run (its phase geometry is rasterised at the
        companion's grid).
    initial : transient.scene.InitialFace or callable
        The initial face: an object with ``recession(grid)`` (the scene's
        ``[initial_face]``), or ``initial(grid) -> ndarray`` (``grid`` the
        companion's :class:`steady.outline.FaceGrid`).  It
        must exist on the companion's grid: a recession file of the main grid
        (``kind = "file"``) does not, and raises ``ValueError``.
    options : transient.options.RunOptions
        The main run's options (the same distances, tolerance, scheme).
    result : transient.result.RunResult
        The main run.
    grid : int, optional
        Companion grid; default :func:`companion_grid` of ``n``.
    on_step : callable, optional
        Passed to :func:`transient.runin.run_in` (progress).

    Returns
    -------
    SpatialError
        ``.attach(result)`` puts the error into the history as
        ``rms_slope_spatial_error``.

    Examples
    --------
    >>> from steady import examples
    >>> from transient import RunOptions, run_in
    >>> from transient.scene import load_transient_scene, wear_problem_of
    >>> scene, _, initial = load_transient_scene(examples.path("voronoi_transient"))
    >>> options = RunOptions(tol=1e-2)
    >>> problem = wear_problem_of(scene, n=64)
    >>> result = run_in(problem, initial.recession(problem.grid), options)
    >>> companion = spatial_error(scene, initial, options, result)
    >>> result = companion.attach(result)
    >>> error = result.history["rms_slope_spatial_error"]
    >>> companion.grid, error.shape == result.history["distance"].shape
    (40, True)
    """
    n = max(result.recession.shape)
    outline = scene.outline
    m = companion_grid(scene.geometry, n, outline) if grid is None else int(grid)
    if not 2 <= m < n:
        raise ValueError(f"companion grid must lie in [2, {n}), got {m}")
    build = initial.recession if hasattr(initial, "recession") else initial
    problem = wear_problem_of(scene, n=m)
    logger.info("companion run on n = %d (main run n = %d)", m, n)
    coarse = run_in(problem, build(problem.grid), options, on_step=on_step)
    if not coarse.success:
        logger.warning("companion run %s: %s", coarse.status, coarse.message)
    values = _at(coarse.history["distance"], coarse.history["rms_slope"],
                 result.history["distance"], steady=coarse.success)
    main = result.history["rms_slope"]
    error = np.array([ladder_error([m, n], [sc, sn]) for sc, sn in zip(values, main,
                                                                        strict=True)])
    face_error = slope_error = None
    if "face_deviation" in coarse.history and "face_deviation" in result.history:
        face = _at(coarse.history["distance"], coarse.history["face_deviation"],
                   result.history["distance"], steady=coarse.success)
        face_error = _ladder(m, n, face, result.history["face_deviation"])
    if np.isfinite(coarse.steady_rms_slope) and np.isfinite(result.steady_rms_slope):
        slope_error = _ladder(m, n, values / coarse.steady_rms_slope,
                              main / result.steady_rms_slope)
    return SpatialError(grid=m, run=coarse, rms_slope=values, error=error,
                        face_deviation_error=face_error, slope_deviation_error=slope_error)


def _ladder(m, n, coarse, fine):
    """First-order error of each value of ``fine`` (grid ``n``) from ``coarse`` (grid ``m``)."""
    return np.array([ladder_error([m, n], [c, f]) for c, f in zip(coarse, fine, strict=True)])


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
    pos_d, pos_v = distance[positive], values[positive]
    inside = (targets > 0) & (targets <= pos_d[-1] * (1 + 1e-12))
    out[inside] = np.interp(np.log(targets[inside]), np.log(pos_d), pos_v)
    if steady:
        out[targets > pos_d[-1]] = pos_v[-1]
    return out
