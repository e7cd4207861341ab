"""A counter-body of finite thickness: where the half-space result holds, and the run-in.

The paper's Fig. 3 Voronoi punch (``steady/examples/voronoi_biphasic.toml``:
40^2 seeds on a disk of radius 4 mm, grain size ``g = 2 a / 40 = 0.2 mm``,
``k_1 / k_0 = 10``) and the rods of Fig. 7-8 (``rods_steel_in_brass.toml``:
five rods of radius 2.5 mm in a disk of radius ``a = 10 mm``) on a layer
bonded to a rigid flat (``[counterbody] thickness``, ``poisson``), of
thickness 0.1 to 10 times the grain size (Voronoi) or the punch radius
(rods), with ``nu = 0.5`` (rubber) and 0.3.  For each: the steady face's rms
slope (energy-corrected, with its error bar) over the half-space's
``grad_f0`` of the same load, against the half-space's value; and the run-in
distance from a flat face over the half-space's, on a coarser grid: the
distance after which the face stays within 1 % of the steady face (the face
criterion of :meth:`transient.result.RunResult.run_in_distance`).

Run::

    python studies/counterbody_thickness.py            # about 2 min on 2 cores
    python studies/counterbody_thickness.py --quick    # a few seconds
    python studies/counterbody_thickness.py --plot-only

Writes ``OUT/counterbody_thickness.h5`` and ``OUT/counterbody_thickness.png``.
"""

import dataclasses
import sys
import time

import numpy as np
import study_io
from matplotlib.ticker import NullFormatter, ScalarFormatter

from steady.scene import load_scene
from steady.solution import solve_scene

NAME = "counterbody_thickness"
#: The faces: scene file and the length the thickness is measured in (m).
FACES = {"voronoi": ("voronoi_biphasic.toml", "grain size 2a/40"),
         "rods": ("rods_steel_in_brass.toml", "punch radius a")}
PARAMS = {"n": {"voronoi": 128, "rods": 96}, "runin_n": {"voronoi": 80, "rods": 40},
          "ratios": [0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0], "poissons": [0.5, 0.3],
          "tol": 1e-3, "band": 0.01}
QUICK = {"n": {"voronoi": 80, "rods": 32}, "runin_n": {"voronoi": 80, "rods": 24},
         "ratios": [0.5, 5.0], "poissons": [0.5], "tol": 1e-3, "band": 0.01,
         "runin_faces": ["rods"]}


def _length(key, scene):
    """The length the thickness is measured in, m."""
    if key == "voronoi":
        return 2 * scene.outline.radius / np.sqrt(scene.geometry.n_seeds)
    return scene.outline.radius


def _run_in_distance(scene, n, tol, band):
    """Sliding distance (m) after which the face stays within ``band`` of the steady face.

    The face criterion of the run-in distance alone (the history's
    ``face_deviation``: the rms of the face minus the steady face over the
    steady face's rms); the friction proxy's rim-layer correction is the
    half-space's, not a thin layer's.
    """
    from transient.initial_face import flat
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    problem = wear_problem_of(scene, n=n)
    result = run_in(problem, flat(problem.grid), RunOptions(tol=tol))
    if not result.success:
        raise ValueError(f"run-in on {scene.counterbody.describe()}: {result.message}")
    distance, deviation = result.history["distance"], result.history["face_deviation"]
    outside = np.flatnonzero(~(deviation <= band))
    if outside.size == 0:
        return float(distance[0])
    if outside[-1] + 1 >= distance.size:
        raise ValueError(f"run-in on {scene.counterbody.describe()} ends {deviation[-1]:.3g} "
                         f"from the steady face")
    return float(distance[outside[-1] + 1])


def compute(path, params):
    """Steady rms slopes and run-in distances on each layer; write HDF5."""
    datasets, attrs = {}, {}
    start = time.perf_counter()
    ratios = np.asarray(params["ratios"], dtype=float)
    for key, (file, _) in FACES.items():
        scene = load_scene(study_io.ROOT / "steady" / "examples" / file)
        length = _length(key, scene)
        half = solve_scene(scene, n=params["n"][key])
        attrs[f"{key}_halfspace_rms_slope"] = (half.normalised_rms_slope, "1")
        attrs[f"{key}_halfspace_rms_slope_error"] = (half.rms_slope_error
                                                     / half.reference_slope, "1")
        attrs[f"{key}_length"] = (length, "m")
        runs = key in params.get("runin_faces", FACES)
        if runs:
            s_half = _run_in_distance(scene, params["runin_n"][key], params["tol"],
                                      params["band"])
            attrs[f"{key}_halfspace_run_in_distance"] = (s_half, "m")
        for nu in params["poissons"]:
            slopes, errors, distances = [], [], []
            for ratio in ratios:
                layer = dataclasses.replace(scene, thickness=ratio * length, poisson=nu)
                res = solve_scene(layer, n=params["n"][key])
                slopes.append(res.normalised_rms_slope)
                errors.append(res.rms_slope_error / res.reference_slope)
                if runs:
                    distances.append(_run_in_distance(layer, params["runin_n"][key],
                                                      params["tol"], params["band"]) / s_half)
            datasets[f"{key}/nu{nu:g}/rms_slope"] = (np.asarray(slopes), "1")
            datasets[f"{key}/nu{nu:g}/rms_slope_error"] = (np.asarray(errors), "1")
            if runs:
                datasets[f"{key}/nu{nu:g}/run_in_distance"] = (np.asarray(distances), "1")
    datasets["thickness_ratio"] = (ratios, "1")
    attrs["run_time"] = (time.perf_counter() - start, "s")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Rms slope and run-in distance against the thickness, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    ratios = d["thickness_ratio"]
    fig = study_io.figure(10.0, 7.0)
    axes = fig.subplots(2, 2)
    for col, (key, (_, words)) in enumerate(FACES.items()):
        ax_slope, ax_run = axes[0, col], axes[1, col]
        hs, hs_err = a[f"{key}_halfspace_rms_slope"], a[f"{key}_halfspace_rms_slope_error"]
        ax_slope.axhspan(hs - hs_err, hs + hs_err, color="0.85")
        ax_slope.axhline(hs, color="0.4", lw=0.8, label="half-space")
        ax_run.axhline(1.0, color="0.4", lw=0.8, label="half-space")
        for i, nu in enumerate(p["poissons"]):
            group = f"{key}/nu{nu:g}"
            ax_slope.errorbar(ratios, d[f"{group}/rms_slope"], d[f"{group}/rms_slope_error"],
                              color=f"C{i}", marker="o", ms=3, lw=1.0, capsize=2,
                              label=f"layer, nu = {nu:g}")
            if f"{group}/run_in_distance" in d:
                ax_run.plot(ratios, d[f"{group}/run_in_distance"], color=f"C{i}", marker="o",
                            ms=3, lw=1.0, label=f"layer, nu = {nu:g}")
        for ax in (ax_slope, ax_run):
            ax.set_xscale("log")
            ax.set_xticks(ratios, [f"{r:g}" for r in ratios])
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(f"thickness / {words}")
            ax.legend(fontsize=8)
        ax_slope.set_ylabel(r"rms slope / $\nabla f_0$ (half-space's)")
        ax_slope.set_title(f"{key}: steady face, n = {p['n'][key]}", fontsize=9)
        ax_run.set_yscale("log")
        ax_run.yaxis.set_major_formatter(ScalarFormatter())
        ax_run.yaxis.set_minor_formatter(NullFormatter())
        ax_run.set_ylabel("run-in distance / half-space's (1 %)")
        ax_run.set_title(f"{key}: run-in from flat, n = {p['runin_n'][key]}", fontsize=9)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
