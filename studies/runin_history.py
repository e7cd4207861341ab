"""Run-in: rms slope against sliding distance, from a flat face to the steady state.

Follows the run-in (:mod:`transient`: implicit SDIRK2 steps with error
control, from a flat initial face, until the wear rates equalise) of

- the two insert cases of the paper's Fig. 5b: 40^2 Voronoi seeds,
  ``rho_2 = 0.3``, ``k_2 / k_1 = 0.1`` and ``10`` (seed 1000);
- the two rods scenes of Fig. 7-8 (``studies/scenes/rods_*.toml``),

and plots the normalised rms slope ``rms / grad_f0`` against the sliding
distance in units of ``s* = a / (k_min E*)``, with the steady value of the same
grid (eq. 9, plain pixel rms slope, as the transient measures it) as the
asymptote.  The cases run in parallel as a resumable sweep
(:mod:`steady.sweep`).

Run::

    python studies/runin_history.py            # n = 128: 25 s on 2 cores
    python studies/runin_history.py --quick    # a few seconds
    python studies/runin_history.py --plot-only

Writes ``out/runin_history.h5`` (and the sweep file ``out/runin_sweep_n<n>.h5``)
and ``docs/figures/runin_history.png``.
"""

import functools
import pathlib
import sys

import numpy as np
import study_io

from steady.grid import pixel_size
from steady.halfspace import HalfSpace
from steady.phases import Voronoi
from steady.scene import load_scene
from steady.sweep import run_sweep

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

_UNITS = {"distance": "s*", "normalised_rms_slope": "grad_f0", "spread": "1",
          "steady_plain": "grad_f0", "steady_corrected": "grad_f0", "face_error": "1",
          "rms_slope_error": "1", "steps": "1", "solves": "1", "wall_time": "s"}


def _problem(case, n, n_seeds, fill, seed):
    """The wear problem of a case on the ``n x n`` grid."""
    from transient.problem import WearProblem

    spec = CASES[case]
    if spec["kind"] == "voronoi":
        labels = Voronoi(n_seeds, (1 - fill, fill), seed).labels(n)
        # pbar = 1 Pa, a = 1 m, E* = 1 Pa: the normalised history.
        return WearProblem(HalfSpace(n, pixel_size(n, 1.0), 1.0), labels,
                           [1.0, spec["ratio"]], np.pi, 1.0)
    scene = load_scene(study_io.ROOT / "studies" / "scenes" / spec["scene"])
    return WearProblem.from_scene(scene, n=n)


def run_case(point, *, n, n_seeds, fill, seed, tol):
    """One run-in from a flat face (sweep task)."""
    from steady.basis import PhaseBasis
    from transient.comparison import compare_with_steady
    from transient.initial_face import flat
    from transient.runin import RunOptions, run_in

    problem = _problem(point["case"], n, n_seeds, fill, seed)
    result = run_in(problem, flat(n, problem.radius), RunOptions(tol=tol))
    if not result.success:
        raise RuntimeError(f"run-in of {point['case']} ended {result.status}: "
                           f"{result.message}")
    steady = problem.solve_steady()
    comparison = compare_with_steady(result, steady, problem)
    corrected = PhaseBasis(problem.labels, problem.radius, problem.halfspace.E_star,
                           faces=False).rms_slopes([problem.wear_coefficients],
                                                   problem.normal_force)
    h = result.history
    return {"distance": h["distance"] / result.run_in_distance,
            "normalised_rms_slope": h["normalised_rms_slope"], "spread": h["spread"],
            "steady_plain": steady.rms_slope_plain / steady.reference_slope,
            "steady_corrected": corrected.normalised[0],
            "face_error": comparison.face_error,
            "rms_slope_error": comparison.rms_slope_error,
            "steps": result.steps, "solves": result.solves, "wall_time": result.wall_time}


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
        for key in ("distance", "normalised_rms_slope", "spread"):
            datasets[f"{c}/{key}"] = (v[key], _UNITS[key])
        for key in ("steady_plain", "steady_corrected", "face_error", "rms_slope_error",
                    "steps", "solves", "wall_time"):
            attrs[f"{c}_{key}"] = (v[key].item(), _UNITS[key])
    return study_io.write_study(path, NAME, params, datasets, attrs)


TITLES = {"voronoi_k0.1": "Voronoi, $\\rho_2$ = 0.3, $k_2/k_1$ = 0.1",
          "voronoi_k10": "Voronoi, $\\rho_2$ = 0.3, $k_2/k_1$ = 10",
          "rods_steel_in_brass": "steel rods in brass", "rods_brass_in_steel":
          "brass rods in steel"}


def plot(path, png):
    """Histories with their steady asymptotes, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    fig = study_io.figure(7.5, 4.3)
    ax = fig.subplots()
    for j, c in enumerate(a["params"]["cases"]):
        s, y = d[f"{c}/distance"], d[f"{c}/normalised_rms_slope"]
        pos = s > 0
        ax.semilogx(s[pos], y[pos], ".-", ms=2, lw=0.8, color=f"C{j}",
                    label=f"{TITLES[c]}: {int(a[f'{c}_steps'])} steps, face error "
                          f"{a[f'{c}_face_error']:.0e}")
        ax.axhline(a[f"{c}_steady_plain"], color=f"C{j}", ls="--", lw=0.8)
        ax.axhline(a[f"{c}_steady_corrected"], color=f"C{j}", ls=":", lw=0.8)
    # The last step of each run is a jump of ~1e8 s* to the steady state.
    ax.set_xlim(right=100.0)
    ax.set_xlabel(r"sliding distance / $s^* = a / (k_{min} E^*)$")
    ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$ (pixel rms)")
    ax.set_title(f"run-in from a flat face, n = {a['n']}; dashed: steady face (eq. 9), same "
                 "pixel rms;\ndotted: steady face, energy-corrected rms (the converged value)",
                 fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True)


if __name__ == "__main__":
    sys.exit(main())
