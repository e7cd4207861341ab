"""The Voronoi sweep: normalised rms slopes of random biphasic maps, resumable.

The steady rms slope of a biphasic punch is ``grad_f0`` times a normalised
value that depends only on the fill factor ``rho_2`` and the wear ratio
``k_2 / k_1`` (eq. 15; ``grad_f0 = 4 pbar / (pi E*)``, eq. 12).  This module
computes that value over random Voronoi maps, all wear ratios of one map at
once (:class:`steady.basis.PhaseBasis`), as a resumable sweep
(:mod:`steady.sweep`):

- :func:`voronoi_slopes`, the task: one map, every wear ratio, on a ladder
  of grids for the error estimate;
- :func:`voronoi_points` and :func:`voronoi_sweep`: the points of a sweep
  over coarseness levels, fill factors and realisations, and its run;
- :func:`collect_voronoi`: the finished points as arrays
  (:class:`VoronoiData`), from which :class:`steady.design.DesignTable`
  and the studies are built.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from .basis import PhaseBasis
from .outline import UNIT_DISK
from .phases import Voronoi
from .problem import FacePhases
from .rms_slope import grid_ladder, ladder_error
from .sweep import run_sweep

__all__ = [
    "VORONOI_SWEEP_VERSION",
    "VoronoiData",
    "collect_voronoi",
    "voronoi_points",
    "voronoi_slopes",
    "voronoi_sweep",
]

#: Layout version of the Voronoi sweep points (part of the sweep settings).
VORONOI_SWEEP_VERSION = 1

#: Name of the task in the sweep settings.  Sweep files store it and a
#: resumed sweep must match it, so it stays this string.
_TASK_NAME = "steady.design.voronoi_slopes"

#: Unit of each result of :func:`voronoi_slopes`.
_VORONOI_UNITS = {"grids": "1", "rms_slope": "grad_f0", "rms_slope_plain": "grad_f0",
                  "error": "grad_f0", "fill_factor": "1"}


def voronoi_slopes(point, *, n, ratios):
    """Normalised rms slopes of one biphasic Voronoi map for many wear ratios.

    The sweep task of :func:`voronoi_sweep` (module level, picklable).

    Parameters
    ----------
    point : mapping
        ``n_seeds`` (int), ``fill_factor`` (``rho_2``, float), ``seed`` (int):
        the map ``Voronoi(n_seeds, (1 - rho_2, rho_2), seed)``; phase 1 of
        the paper is index 0, phase 2 is index 1.
    n : int
        Grid of the values.
    ratios : sequence of float, shape (K,)
        Wear ratios ``k_2 / k_1``.

    Returns
    -------
    dict
        ``grids`` (G,) the ladder of :func:`steady.rms_slope.grid_ladder`;
        ``rms_slope`` (G, K) energy-corrected ``rms / grad_f0`` on each grid;
        ``rms_slope_plain`` (K,) plain pixel value on grid ``n``;
        ``error`` (K,) :func:`steady.rms_slope.ladder_error` of the value on grid ``n`` (for the
        ladder ``n, 2n``: ``2 |S_2n - S_n|``, its first-order error);
        ``fill_factor`` realised ``rho_2`` on grid ``n``.
    """
    rho = float(point["fill_factor"])
    geometry = Voronoi(int(point["n_seeds"]), (1.0 - rho, rho), int(point["seed"]))
    grids = grid_ladder(geometry, n)
    k = np.column_stack([np.ones(len(ratios)), np.asarray(ratios, dtype=float)])
    values, plain, fill = [], None, None
    for m in grids:
        grid = UNIT_DISK.grid(m)
        basis = PhaseBasis(FacePhases(grid, geometry.labels(grid), geometry.n_phases), 1.0,
                           faces=False)
        sweep = basis.rms_slopes(k, np.pi)  # pbar = 1 Pa, E* = 1 Pa
        values.append(sweep.normalised)
        if m == n:
            plain = sweep.rms_slope_plain / sweep.reference_slope
            fill = float(basis.fill_factors[1])
    values = np.asarray(values)
    if grids[-1] == n:
        error = ladder_error(grids, values)
    else:  # ladder n, 2n: first-order error of the coarser value S_n
        error = np.abs(values[1] - values[0]) * grids[1] / (grids[1] - grids[0])
    return {"grids": np.asarray(grids), "rms_slope": values, "rms_slope_plain": plain,
            "error": error, "fill_factor": fill}


def voronoi_points(n_seeds, fill_factors, seeds):
    """Sweep points for every (coarseness, fill factor, realisation)."""
    return [{"n_seeds": int(c), "fill_factor": round(float(r), 10), "seed": int(s)}
            for c in n_seeds for r in fill_factors for s in seeds]


def voronoi_sweep(path, *, n, ratios, n_seeds, fill_factors, seeds, executor=None,
                  workers=None, scheduler=None, progress=False):
    """Run (or resume) the Voronoi sweep into a sweep file.

    Parameters
    ----------
    path : str or path-like
        Sweep file (:mod:`steady.sweep`); its settings are ``n`` and
        ``ratios``, so that sweeps over other coarseness levels, fill
        factors or realisations with the same grid and ratios share it.
    n : int
        Grid of the values (:func:`steady.rms_slope.grid_ladder` adds coarser ones).
    ratios : sequence of float
        Wear ratios ``k_2 / k_1``.
    n_seeds, fill_factors, seeds : sequences
        Coarseness levels, fill factors ``rho_2`` and realisation seeds.
    executor, workers, scheduler, progress
        As :func:`steady.sweep.run_sweep`.

    Returns
    -------
    SweepFile
    """
    ratios = [float(r) for r in ratios]
    settings = {"task": _TASK_NAME, "version": VORONOI_SWEEP_VERSION,
                "n": int(n), "ratios": ratios}
    task = functools.partial(voronoi_slopes, n=int(n), ratios=ratios)
    return run_sweep(task, voronoi_points(n_seeds, fill_factors, seeds), path,
                     settings=settings, units=_VORONOI_UNITS, executor=executor,
                     workers=workers, scheduler=scheduler, progress=progress,
                     description=f"Voronoi sweep n={n}")


@dataclasses.dataclass(frozen=True, eq=False)
class VoronoiData:
    """Values of a Voronoi sweep on a regular (level, fill factor, realisation) grid.

    Attributes
    ----------
    n_seeds : ndarray, shape (C,)
    fill_factors : ndarray, shape (R,)
        Nominal ``rho_2``.
    seeds : ndarray, shape (M,)
    ratios : ndarray, shape (K,)
        ``k_2 / k_1``.
    rms_slope : ndarray, shape (C, R, M, K), grad_f0
        Energy-corrected normalised rms slope on grid ``n``.
    rms_slope_plain : ndarray, shape (C, R, M, K), grad_f0
    error : ndarray, shape (C, R, M, K), grad_f0
        Discretisation error estimate of each value.
    realised : ndarray, shape (C, R, M)
        Realised ``rho_2`` on grid ``n``.
    n : int
    """

    n_seeds: np.ndarray
    fill_factors: np.ndarray
    seeds: np.ndarray
    ratios: np.ndarray
    rms_slope: np.ndarray
    rms_slope_plain: np.ndarray
    error: np.ndarray
    realised: np.ndarray
    n: int

    @property
    def mean(self):
        """Realisation mean, shape (C, R, K)."""
        return self.rms_slope.mean(axis=2)

    @property
    def scatter(self):
        """Realisation standard deviation (ddof 1), shape (C, R, K)."""
        return self.rms_slope.std(axis=2, ddof=1) if self.seeds.size > 1 else \
            np.zeros_like(self.mean)

    @property
    def mean_error(self):
        """Discretisation error of the mean (mean of the errors), shape (C, R, K)."""
        return self.error.mean(axis=2)


def collect_voronoi(sweep_file, n_seeds, fill_factors, seeds):
    """Gather the points of a Voronoi sweep file into arrays.

    Parameters
    ----------
    sweep_file : SweepFile
    n_seeds, fill_factors, seeds : sequences
        The grid of points wanted; every one must be in the file.

    Returns
    -------
    VoronoiData

    Raises
    ------
    ValueError
        A point is missing (the message names it).
    """
    settings = sweep_file.settings
    ratios = np.asarray(settings["ratios"])
    index = {}
    for point in sweep_file.read():
        p = point.params
        index[(p["n_seeds"], round(p["fill_factor"], 10), p["seed"])] = point.values
    shape = (len(n_seeds), len(fill_factors), len(seeds))
    out = {name: np.empty(shape + (ratios.size,)) for name in
           ("rms_slope", "rms_slope_plain", "error")}
    realised = np.empty(shape)
    for ci, c in enumerate(n_seeds):
        for ri, r in enumerate(fill_factors):
            for si, s in enumerate(seeds):
                key = (int(c), round(float(r), 10), int(s))
                if key not in index:
                    raise ValueError(f"sweep file {str(sweep_file.path)!r} has no point "
                                     f"n_seeds={key[0]}, fill_factor={key[1]}, seed={key[2]}")
                v = index[key]
                grids = list(v["grids"])
                top = grids.index(settings["n"])
                out["rms_slope"][ci, ri, si] = v["rms_slope"][top]
                out["rms_slope_plain"][ci, ri, si] = v["rms_slope_plain"]
                out["error"][ci, ri, si] = v["error"]
                realised[ci, ri, si] = v["fill_factor"]
    return VoronoiData(n_seeds=np.asarray(n_seeds), fill_factors=np.asarray(fill_factors),
                       seeds=np.asarray(seeds), ratios=ratios, realised=realised,
                       n=int(settings["n"]), **out)
