"""Calibrated error bar: the run-in distance's +- against finer grids, tighter steps, a reference.

Each row runs a shipped run-in scene as ``runin-transient`` does by default
(its own grid ``n`` and tolerance, then the companion runs on about
``3 n / 4`` and ``n / 2``, :mod:`transient.spatial_error`) and compares its
run-in distances within 1 % and 0.1 %, ``s +- bar``, with a reference that
has neither its grid's nor its steps' error as far as they can be measured:
the same scene on the finest grid of its ladder (256 for the Voronoi and
tilted scenes, 384 for the tread block, 288 for the micrograph) at a
hundredth of the tolerance (and of ``jump_spread``, so that it follows the
dynamics to 0.1 %), or, for the homogeneous epoxy disk, the
axisymmetric reference (:mod:`transient.axisymmetric`, 600 graded rings,
converged to 1e-6 s*).  A bar is calibrated when it covers the difference
(``ratio = bar / |s - s_ref| >= 1``) and is not a blanket (``ratio`` up to
about 3).

Run::

    python studies/calibrate_error_bar.py            # 10 rows, about 4 min on 2 cores
    python studies/calibrate_error_bar.py --quick    # two coarse rows, a few seconds
    python studies/calibrate_error_bar.py --plot-only

Writes ``OUT/calibrate_error_bar.h5`` (one dataset per column, the table on
stdout) and ``OUT/calibrate_error_bar.png`` (the ratios, one marker per row
and tolerance, the band ``1 <= ratio <= 3`` shaded).
"""

import dataclasses
import math
import sys
import time

import numpy as np
import study_io

from steady import examples
from transient import run_in
from transient.axisymmetric import AxisymmetricRunIn
from transient.run_in_distance import TOLERANCES, run_in_distance
from transient.scene import load_transient_scene, wear_problem_of
from transient.spatial_error import spatial_error

NAME = "calibrate_error_bar"
#: (scene, n) rows; the disk's reference is the axisymmetric one.
PARAMS = {"rows": [["voronoi_transient", 64], ["voronoi_transient", 128],
                   ["tilted_transient", 64], ["tilted_transient", 128],
                   ["tread_block_transient", 192], ["micrograph_steady", 96],
                   ["micrograph_steady", 144], ["epoxy_cylinder", 64],
                   ["epoxy_cylinder", 96], ["epoxy_cylinder", 128]],
          "reference_grids": {"voronoi_transient": 256, "tilted_transient": 256,
                              "tread_block_transient": 384, "micrograph_steady": 288},
          "tol_factor": 0.01, "rings": 600}
QUICK = {"rows": [["voronoi_transient", 48], ["epoxy_cylinder", 32]],
         "reference_grids": {"voronoi_transient": 96}, "tol_factor": 0.1, "rings": 150}
#: The disk scene, whose reference is the axisymmetric run-in.
DISK = "epoxy_cylinder"


def axisymmetric_distances(rings, tolerances=TOLERANCES):
    """Run-in distances (s*) of the homogeneous disk from flat, by root finding on the rings.

    The deviations are the run's: ``|S/S_inf - 1|`` and the rms of ``f - f_inf`` over that
    of ``f_inf`` (means removed, area weighted), their larger one against ``within``.
    """
    import scipy.optimize

    model = AxisymmetricRunIn(rings=rings)
    end = model.state(60 * model.distance_scale)
    areas = model.areas / model.areas.sum()
    shape_rms = math.sqrt(areas @ (end.face - areas @ end.face) ** 2)

    def deviation(s, within):
        state = model.state(s * model.distance_scale)
        diff = state.face - end.face
        face = math.sqrt(areas @ (diff - areas @ diff) ** 2) / shape_rms
        return max(abs(state.rms_slope / end.rms_slope - 1), face) - within

    found = []
    grid = np.geomspace(0.3, 10.0, 80)
    for within in tolerances:
        d = np.array([deviation(s, within) for s in grid])
        i = np.flatnonzero(d > 0)[-1]
        found.append(scipy.optimize.brentq(deviation, grid[i], grid[i + 1], args=(within,),
                                           xtol=1e-10))
    return np.array(found)


def _run(name, n, tol_factor=1.0):
    """The scene's run on ``n`` (tolerance times ``tol_factor``), with its inputs."""
    scene, options, initial = load_transient_scene(examples.path(name))
    # A tighter tolerance follows the dynamics further before the jump to the steady state.
    options = dataclasses.replace(options, tol=options.tol * tol_factor,
                                  jump_spread=options.jump_spread * tol_factor)
    problem = wear_problem_of(scene, n=n)
    return scene, options, initial, run_in(problem, initial.recession(problem.grid), options)


def compute(path, params):
    """Run every row, its companions and its reference; write the table."""
    columns = {key: [] for key in ("n", "within", "distance", "bar", "reference", "ratio",
                                   "grid_bar", "wall", "companion_wall")}
    names, references = [], []
    disk = None
    references_of = {}
    for name, n in params["rows"]:
        started = time.perf_counter()
        scene, options, initial, result = _run(name, n)
        wall = time.perf_counter() - started
        companions = spatial_error(scene, initial, options, result)
        bare = [run_in_distance(result, x) for x in TOLERANCES]
        result = companions.attach(result)
        found = [run_in_distance(result, x) for x in TOLERANCES]
        if name == DISK:
            if disk is None:
                disk = axisymmetric_distances(params["rings"]) * result.distance_scale
            ref, what = disk, f"axisymmetric, {params['rings']} rings"
        else:
            fine = params["reference_grids"][name]
            if (fine, name) not in references_of:
                ref_run = _run(name, fine, params["tol_factor"])[3]
                references_of[fine, name] = [run_in_distance(ref_run, x).distance_m
                                             for x in TOLERANCES]
            ref = references_of[fine, name]
            what = f"n = {fine}, tol x {params['tol_factor']:g}"
        for x, one, plain, s_ref in zip(TOLERANCES, found, bare, ref, strict=True):
            names.append(name)
            references.append(what)
            columns["n"].append(n)
            columns["within"].append(x)
            columns["distance"].append(one.distance_m)
            columns["bar"].append(one.uncertainty_m)
            columns["reference"].append(s_ref)
            columns["ratio"].append(one.uncertainty_m / abs(one.distance_m - s_ref))
            columns["grid_bar"].append(math.sqrt(max(one.uncertainty_m ** 2
                                                     - plain.uncertainty_m ** 2, 0.0)))
            columns["wall"].append(wall)
            columns["companion_wall"].append(sum(r.wall_time for r in companions.runs))
        print(f"{name} n = {n}: done ({companions.grids})", flush=True)
    units = {"n": "1", "within": "1", "distance": "m", "bar": "m", "reference": "m",
             "ratio": "1", "grid_bar": "m", "wall": "s", "companion_wall": "s"}
    datasets = {key: (np.array(value, dtype=float), units[key]) for key, value in columns.items()}
    datasets["scene"] = (np.array(names, dtype=object), "")
    datasets["reference_kind"] = (np.array(references, dtype=object), "")
    study_io.write_study(path, NAME, params, datasets)
    print(table(path))


def table(path):
    """The calibration table in Markdown, from the study file."""
    data, _ = study_io.read_study(path, NAME)
    lines = ["| scene | n | within | s (m) | +- (m) | reference (m) | reference | ratio |",
             "|---|---|---|---|---|---|---|---|"]
    for i in range(len(data["n"])):
        scene = data["scene"][i]
        scene = scene.decode() if isinstance(scene, bytes) else scene
        kind = data["reference_kind"][i]
        kind = kind.decode() if isinstance(kind, bytes) else kind
        lines.append(f"| {scene} | {int(data['n'][i])} | {100 * data['within'][i]:g} % | "
                     f"{data['distance'][i]:.0f} | {data['bar'][i]:.2g} | "
                     f"{data['reference'][i]:.0f} | {kind} | {data['ratio'][i]:.2f} |")
    return "\n".join(lines)


def plot(path, png):
    """Ratio bar / |s - s_ref| of every row, both tolerances, the calibrated band shaded."""
    data, _ = study_io.read_study(path, NAME)
    fig = study_io.figure(6.5, 3.6)
    ax = fig.add_subplot()
    rows = len(data["n"])
    labels = []
    for i in range(rows):
        scene = data["scene"][i]
        scene = scene.decode() if isinstance(scene, bytes) else scene
        labels.append(f"{scene.replace('_transient', '').replace('_steady', '')} "
                      f"{int(data['n'][i])}")
    positions = np.arange(rows)
    for x, marker in zip(TOLERANCES, ("o", "s"), strict=True):
        pick = data["within"] == x
        ax.semilogy(positions[pick], data["ratio"][pick], marker, ls="none",
                    label=f"within {100 * x:g} %")
    for i in np.flatnonzero(~np.isfinite(data["ratio"])):
        # An infinite bar: the widened band is not entered before the run's end.
        ax.annotate("no bound", (positions[i], 1.0), xytext=(0, 4), textcoords="offset points",
                    rotation=90, ha="center", va="bottom", fontsize=7, color="0.3")
    ax.axhspan(1.0, 3.0, color="0.9", zorder=0, label="calibrated: 1 to 3")
    ax.axhline(1.0, color="0.5", lw=0.8)
    ax.set_xticks(positions)
    ax.set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("bar / |s - s_ref|")
    ax.set_title("Run-in distance: stated +- over the actual error", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    study_io.save_figure(fig, png)


def main(argv=None):
    """Command line (module notes)."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
