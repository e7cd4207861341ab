"""The Voronoi sweep shared by the studies of Fig. 4, Fig. 5, the claims and the design table.

One sweep file holds, for a grid ``n`` and a list of wear ratios, the
normalised rms slope of biphasic Voronoi maps at every (coarseness level,
fill factor, realisation) computed so far (:func:`steady.voronoi_sweep.voronoi_sweep`;
one :class:`steady.basis.PhaseBasis` per map gives every wear ratio).  The
studies ask for the points they need; points already in the file are not
computed again, so that the studies share one sweep and an interrupted
sweep resumes.

Full settings: ``n = 512`` (the energy-corrected estimator's error is below
the realisation scatter there; 160^2 seeds need ``n >= 320``), wear ratios
``10^-4 .. 10^4`` in quarter decades, the paper's four coarseness levels
(20^2, 40^2, 80^2, 160^2 seeds), ``rho_2 = 0.05 .. 0.95`` in steps of 0.05,
10 realisations (seeds 1000..1009; realisation ``i`` uses the same seed
points at every fill factor and relabels them).
"""

from __future__ import annotations

import pathlib

import numpy as np

from steady.voronoi_sweep import collect_voronoi, voronoi_sweep

__all__ = ["FULL", "QUICK", "SWEEP", "index_of", "sweep_data", "sweep_path"]

#: The sweep file of a full run, in the studies' output directory (``--out``).
SWEEP = "voronoi_sweep_n{n}.h5"

FULL = {
    "n": 512,
    "ratios": np.logspace(-4, 4, 33).tolist(),
    "levels": [400, 1600, 6400, 25600],
    "fill_factors": np.round(np.arange(1, 20) * 0.05, 10).tolist(),
    "seeds": list(range(1000, 1010)),
}

QUICK = {
    "n": 64,
    "ratios": np.logspace(-3, 3, 7).tolist(),
    "levels": [25, 100],
    "fill_factors": [0.1, 0.3, 0.5, 0.7, 0.9],
    "seeds": [3001, 3002, 3003],
}


def sweep_path(params, output):
    """Path of the sweep file of a study run.

    ``params['sweep']`` if given (:func:`study_io.run_study` gives
    ``OUT/voronoi_sweep_n<n>.h5`` to full runs), else beside ``output``.
    """
    if params.get("sweep"):
        return pathlib.Path(params["sweep"])
    quick = "quick_" if params.get("quick") else ""
    return pathlib.Path(output).with_name(f"voronoi_sweep_{quick}n{params['n']}.h5")


def sweep_data(params, output, *, levels, fill_factors, seeds, workers=None, scheduler=None,
               progress=False):
    """Run (or reuse) the sweep points and return them as arrays.

    Returns
    -------
    steady.voronoi_sweep.VoronoiData
    """
    path = sweep_path(params, output)
    sweep = voronoi_sweep(path, n=params["n"], ratios=params["ratios"], n_seeds=levels,
                          fill_factors=fill_factors, seeds=seeds, workers=workers,
                          scheduler=scheduler, progress=progress)
    return collect_voronoi(sweep, levels, fill_factors, seeds)


def index_of(values, target):
    """Index of the value nearest to ``target`` (relative, for log-spaced ratios)."""
    values = np.asarray(values, dtype=float)
    i = int(np.argmin(np.abs(np.log(values / target))))
    if abs(values[i] / target - 1) > 1e-6:
        raise ValueError(f"{target} is not among the swept values {values.tolist()}")
    return i
