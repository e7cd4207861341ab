"""Run-in: the friction proxy against sliding distance, from a flat face to the steady state.

Follows the run-in (:mod:`transient`: implicit SDIRK2 steps with error
control, from a flat initial face, until the wear rates equalise) of

- the two insert cases of the paper's Fig. 5b: 40^2 Voronoi seeds,
  ``rho_2 = 0.3``, ``k_2 / k_1 = 0.1`` and ``10`` (seed 1000);
- the two rods scenes of Fig. 7-8 (``steady/examples/rods_*.toml``),

and plots the history's rms slope (the continuum estimate of
:mod:`transient.history`, normalised by ``grad_f0``) against the sliding
distance in units of ``s* = a / (k_min E*)``, with its error band (the
per-step error bar and the companion runs' on about ``3n/4`` and ``n/2``
in quadrature, :mod:`transient.spatial_error`), the plain pixel value faintly, and the
steady module's corrected rms slope with its error bar as the asymptote;
beside it the rms height.  The cases run in parallel as a resumable sweep
(:mod:`steady.sweep`).

Run::

    python studies/runin_history.py            # n = 128: about 45 s on 2 cores
    python studies/runin_history.py --quick    # a few seconds
    python studies/runin_history.py --plot-only

Writes ``OUT/runin_history.h5`` (and the sweep file ``OUT/runin_sweep_n<n>.h5``)
and ``OUT/runin_history.png``.
"""

import functools
import pathlib
import sys
import warnings

import numpy as np
import study_io

from steady.outline import Circle
from steady.phases import Voronoi
from steady.scene import Scene, load_scene
from steady.sweep import run_sweep
from steady.wear import PowerLaw

NAME = "runin_history"
CASES = {
    "voronoi_k0.1": {"kind": "voronoi", "ratio": 0.1},
    "voronoi_k10": {"kind": "voronoi", "ratio": 10.0},
    "rods_steel_in_brass": {"kind": "scene", "scene": "rods_steel_in_brass.toml"},
    "rods_brass_in_steel": {"kind": "scene", "scene": "rods_brass_in_steel.toml"},
}
PARAMS = {"n": 128, "n_seeds": 1600, "fill": 0.3, "seed": 1000, "tol": 1e-5,
          "cases": list(CASES)}
QUICK = {"n": 32, "n_seeds": 100, "fill": 0.3, "seed": 1000, "tol": 1e-3,
         "cases": ["voronoi_k10", "rods_brass_in_steel"]}

_UNITS = {"distance": "s*", "normalised_rms_slope": "grad_f0", "rms_slope_error": "grad_f0",
          "spatial_error": "grad_f0", "rms_slope_plain": "grad_f0", "normalised_rms_height":
          "grad_f0 a", "spread": "1", "steady": "grad_f0", "steady_error": "grad_f0",
          "steady_rms_height": "grad_f0 a", "face_error": "1", "agrees": "1",
          "companion_grid": "1", "steps": "1", "solves": "1", "wall_time": "s",
          "companion_wall_time": "s"}


def _scene(case, n, n_seeds, fill, seed):
    """The scene of a case on the ``n x n`` grid."""
    spec = CASES[case]
    if spec["kind"] == "voronoi":
        # pbar = 1 Pa, a = 1 m, E* = 1 Pa: the normalised history.
        return Scene(outline=Circle(1.0), normal_force=np.pi, E_star=1.0, n=n,
                     wear=PowerLaw((1.0, spec["ratio"])),
                     geometry=Voronoi(n_seeds, (1 - fill, fill), seed))
    return load_scene(study_io.ROOT / "steady" / "examples" / spec["scene"])


def run_case(point, *, n, n_seeds, fill, seed, tol):
    """One run-in from a flat face, its companion on n/2 and the steady state (sweep task)."""
    from steady.solution import solve_scene
    from steady.validity import ValidityWarning
    from transient.comparison import compare_with_steady
    from transient.initial_face import flat
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import wear_problem_of
    from transient.spatial_error import spatial_error

    scene = _scene(point["case"], n, n_seeds, fill, seed)
    problem = wear_problem_of(scene, n=n)
    options = RunOptions(tol=tol)
    result = run_in(problem, flat(problem.grid), options)
    if not result.success:
        raise RuntimeError(f"run-in of {point['case']} ended {result.status}: "
                           f"{result.message}")
    companion = spatial_error(scene, flat, options, result)
    with warnings.catch_warnings():
        # pbar = E* = 1 Pa, the normalised history, is no physical load to check.
        warnings.simplefilter("ignore", ValidityWarning)
        steady = solve_scene(scene, n=n)
    comparison = compare_with_steady(result, steady, problem)
    h = result.history
    g0 = result.reference_slope
    return {"distance": h["distance"] / result.distance_scale,
            "normalised_rms_slope": h["normalised_rms_slope"],
            "rms_slope_error": h["rms_slope_error"] / g0, "spatial_error": companion.error / g0,
            "rms_slope_plain": h["rms_slope_plain"] / g0,
            "normalised_rms_height": h["normalised_rms_height"], "spread": h["spread"],
            "steady": steady.normalised_rms_slope, "steady_error": steady.rms_slope_error / g0,
            "steady_rms_height": steady.normalised_rms_height,
            "face_error": comparison.face_error, "agrees": float(comparison.rms_slope_agrees),
            "companion_grid": min(companion.grids), "steps": result.steps,
            "solves": result.solves, "wall_time": result.wall_time,
            "companion_wall_time": sum(run.wall_time for run in companion.runs)}


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Run (or resume) the cases as a sweep; write their histories."""
    sweep_file = pathlib.Path(params.get("sweep") or pathlib.Path(path).with_name(
        f"runin_sweep{'_quick' if params.get('quick') else ''}_n{params['n']}.h5"))
    settings = {k: params[k] for k in ("n", "n_seeds", "fill", "seed", "tol")}
    task = functools.partial(run_case, **settings)
    sweep = run_sweep(task, [{"case": c} for c in params["cases"]], sweep_file,
                      settings=dict(settings, task="runin_history.run_case"), units=_UNITS,
                      workers=workers, scheduler=scheduler, progress=progress,
                      description="run-in")
    by_case = {p.params["case"]: p.values for p in sweep.read()}
    datasets, attrs = {}, {"n": (params["n"], "1")}
    for c in params["cases"]:
        v = by_case[c]
        for key in ("distance", "normalised_rms_slope", "rms_slope_error", "spatial_error",
                    "rms_slope_plain", "normalised_rms_height", "spread"):
            datasets[f"{c}/{key}"] = (v[key], _UNITS[key])
        for key in ("steady", "steady_error", "steady_rms_height", "face_error", "agrees",
                    "companion_grid", "steps", "solves", "wall_time", "companion_wall_time"):
            attrs[f"{c}_{key}"] = (v[key].item(), _UNITS[key])
    return study_io.write_study(path, NAME, params, datasets, attrs)


TITLES = {"voronoi_k0.1": "Voronoi, $\\rho_2$ = 0.3, $k_2/k_1$ = 0.1",
          "voronoi_k10": "Voronoi, $\\rho_2$ = 0.3, $k_2/k_1$ = 10",
          "rods_steel_in_brass": "steel rods in brass", "rods_brass_in_steel":
          "brass rods in steel"}


def plot(path, png):
    """Histories with their error bands and steady asymptotes, from the HDF5 file."""
    from transient.plotting import draw_rms_slope_history

    d, a = study_io.read_study(path, NAME)
    fig = study_io.figure(12.5, 4.6)
    ax_slope, ax_height = fig.subplots(1, 2, width_ratios=(1.6, 1))
    for j, c in enumerate(a["params"]["cases"]):
        history = {"distance": d[f"{c}/distance"], "rms_slope": d[f"{c}/normalised_rms_slope"],
                   "rms_slope_error": d[f"{c}/rms_slope_error"],
                   "rms_slope_spatial_error": d[f"{c}/spatial_error"],
                   "rms_slope_plain": d[f"{c}/rms_slope_plain"]}
        draw_rms_slope_history(ax_slope, history, 1.0, 1.0, color=f"C{j}",
                               label=f"{TITLES[c]} (steady {a[f'{c}_steady']:.3f} $\\pm$ "
                                     f"{a[f'{c}_steady_error']:.3f})",
                               plain_label="plain pixel value" if j == 0 else "_nolegend_")
        value, error = a[f"{c}_steady"], a[f"{c}_steady_error"]
        ax_slope.axhspan(value - error, value + error, color=f"C{j}", alpha=0.12, lw=0)
        ax_slope.axhline(value, color=f"C{j}", ls="--", lw=0.8)
        s, y = d[f"{c}/distance"], d[f"{c}/normalised_rms_height"]
        pos = (s > 0) & (s < 1e6)
        ax_height.semilogx(s[pos], y[pos], "-", color=f"C{j}", lw=1.2)
        ax_height.axhline(a[f"{c}_steady_rms_height"], color=f"C{j}", ls="--", lw=0.8)
    ax_slope.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax_slope.set_title(f"run-in from a flat face, n = {a['n']}: continuum estimate with its "
                       "error band, plain pixel value faint,\nsteady face (corrected, with its "
                       "error bar) dashed; the open circle is the flat face at s = 0", fontsize=9)
    ax_slope.legend(fontsize=7, loc="lower right")
    ax_height.set_xlabel(r"sliding distance / $s^* = a / (k_{min} E^*)$")
    ax_height.set_ylabel(r"rms height / $(\nabla f^0_\infty a)$, best plane removed")
    ax_height.set_title("rms height; dashed: steady face", fontsize=9)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True)


if __name__ == "__main__":
    sys.exit(main())
