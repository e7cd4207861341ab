"""Run-in convergence: the history's rms slope under grid refinement, against the references.

What it reproduces
    docs/benchmarks.md, "Run-in convergence": the run-in history's rms slope
    (:mod:`transient.history`) at ``s = 0.001, 0.01, 0.1, 1 s*`` (and the
    distances in between) on n = 64, 128, 256, 512, for

    - the homogeneous epoxy cylinder (``steady/examples/epoxy_cylinder.toml``)
      against the axisymmetric reference (:mod:`transient.axisymmetric`,
      1200 graded rings, extrapolated);
    - the shipped Voronoi run-in scene (``steady/examples/voronoi_transient.toml``:
      400 seeds, ``rho_2 = 0.3``, ``k_2/k_1 = 10``);
    - five steel rods in brass (``steady/examples/rods_steel_in_brass.toml``);

    all from the flat face, SDIRK2 at ``tol = 1e-5`` (steps land on the
    distances), run on to the steady state.  Per case and distance: the
    observed order from the three finest grids, the extrapolated value and
    each grid's distance from it, and the per-step error bar.  Beside them
    the calibration of the rim-layer correction: the excess of the
    uncorrected estimator's mean-square slope over the reference
    (homogeneous cylinder) against the layer's resolution ``rho = k E* s / h``,
    with the fit :data:`transient.history.RIM_LAYER_FIT`.

How to run
    python studies/runin_convergence.py             # ~11 to 16 min on 2 cores (n = 512 dominates)
    python studies/runin_convergence.py --quick     # n = 40, 64, 80: half a minute
    python studies/runin_convergence.py --plot-only

Writes ``OUT/runin_convergence.h5`` (the sweep in ``OUT/runin_convergence_sweep.h5``,
resumable) and ``OUT/runin_convergence.png``; prints the table.
"""

import functools
import pathlib
import sys

import numpy as np
import study_io

from steady.scene import load_scene
from steady.sweep import run_sweep

NAME = "runin_convergence"
CASES = {
    "homogeneous": "epoxy_cylinder.toml",
    "voronoi": "voronoi_transient.toml",
    "rods": "rods_steel_in_brass.toml",
}
#: Distances of the table (units of s*); the others feed the calibration.
TABLE = (1e-3, 1e-2, 0.1, 1.0)
DISTANCES = (1e-3, 2e-3, 3e-3, 5e-3, 1e-2, 2e-2, 3e-2, 5e-2, 0.1, 0.3, 1.0, 3.0)
PARAMS = {"grids": [64, 128, 256, 512], "tol": 1e-5, "distances": list(DISTANCES),
          "cases": list(CASES), "reference_rings": 1200}
QUICK = {"grids": [40, 64, 80], "tol": 1e-3, "distances": [1e-3, 1e-2, 0.1, 1.0],
         "cases": ["homogeneous", "voronoi"], "reference_rings": 200}

_UNITS = {"distance": "s*", "rms_slope": "grad_f0", "rms_slope_error": "grad_f0",
          "rms_slope_plain": "grad_f0", "uncorrected": "grad_f0", "rim_excess": "grad_f0^2",
          "rms_height": "grad_f0 a", "rim_layer_pixels": "1", "steady": "grad_f0",
          "steady_error": "grad_f0", "final": "grad_f0", "final_error": "grad_f0",
          "steps": "1", "solves": "1", "wall_time": "s"}


def _scene(case):
    return load_scene(study_io.ROOT / "steady" / "examples" / CASES[case])


def run_case(point, *, tol, distances):
    """One run-in from the flat face on one grid (sweep task)."""
    from steady.rms_slope import SlopeEnergy
    from steady.solution import solve_scene
    from transient.history import rim_layer_excess
    from transient.initial_face import flat
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    scene = _scene(point["case"])
    n = point["n"]
    problem = wear_problem_of(scene, n=n)
    result = run_in(problem, flat(problem.grid), RunOptions(tol=tol, snapshots_s_star=distances))
    if not result.success:
        raise RuntimeError(f"{point}: run-in ended {result.status}: {result.message}")
    g0 = result.reference_slope
    h = result.history
    s = h["distance"] / result.distance_scale
    at = [int(np.argmin(np.abs(s - d))) for d in distances]
    energy = SlopeEnergy(n, problem.halfspace.h, problem.halfspace.E_star)
    face = problem.face_mask
    uncorrected, excess = [], []
    growth = (problem.wear_field * problem.halfspace.E_star / problem.halfspace.h)[
        _rim(face)]
    for d, p in zip(distances, result.snapshot_pressure, strict=True):
        integrals = energy(p, face)
        uncorrected.append(float(integrals.rms_slope) / g0)
        excess.append(float(np.mean(rim_layer_excess(growth * d * result.distance_scale))))
    steady = solve_scene(scene, n=n)
    return {"distance": np.asarray(distances),
            "rms_slope": h["normalised_rms_slope"][at],
            "rms_slope_error": h["rms_slope_error"][at] / g0,
            "rms_slope_plain": h["rms_slope_plain"][at] / g0,
            "uncorrected": np.array(uncorrected), "rim_excess": np.array(excess),
            "rms_height": h["normalised_rms_height"][at],
            "rim_layer_pixels": h["rim_layer_pixels"][at],
            "steady": steady.normalised_rms_slope, "steady_error": steady.rms_slope_error / g0,
            "final": h["normalised_rms_slope"][-1], "final_error": h["rms_slope_error"][-1] / g0,
            "steps": result.steps, "solves": result.solves, "wall_time": result.wall_time}


def _rim(face):
    padded = np.pad(face, 1)
    inner = padded[2:, 1:-1] & padded[:-2, 1:-1] & padded[1:-1, 2:] & padded[1:-1, :-2]
    return face & ~inner


def extrapolate(grids, values):
    """Observed order and extrapolated value from the three finest grids (ratio 2).

    Returns
    -------
    order, extrapolated : float
        ``p = log2(|S_2 - S_1| / |S_3 - S_2|)`` and ``S_3 + (S_3 - S_2) / (2^p - 1)``
        when the differences keep their sign and ``0.5 <= p <= 4``; ``p``
        and NaN when they shrink too slowly (no asymptotic range yet); NaN
        and NaN when they change sign (the staircase's irregular error
        dominates).
    """
    s1, s2, s3 = values[-3:]
    d1, d2 = s2 - s1, s3 - s2
    if d1 * d2 <= 0:
        return np.nan, np.nan
    p = float(np.log2(abs(d1) / abs(d2)))
    if not 0.5 <= p <= 4:
        return p, np.nan
    return p, s3 + d2 / (2 ** p - 1)


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Run (or resume) the runs as a sweep; write the table and the calibration."""
    from transient.axisymmetric import reference_history

    sweep_file = pathlib.Path(params.get("sweep") or pathlib.Path(path).with_name(
        f"{NAME}_sweep{'_quick' if params.get('quick') else ''}.h5"))
    settings = {"tol": params["tol"], "distances": list(params["distances"])}
    task = functools.partial(run_case, tol=params["tol"], distances=tuple(params["distances"]))
    points = [{"case": c, "n": n} for n in sorted(params["grids"], reverse=True)
              for c in params["cases"]]
    sweep = run_sweep(task, points, sweep_file, settings=dict(settings, task=f"{NAME}.run_case"),
                      units=_UNITS, workers=workers, scheduler=scheduler, progress=progress,
                      description="run-in convergence")
    found = {(p.params["case"], p.params["n"]): p.values for p in sweep.read()}
    grids = sorted(params["grids"])
    distances = np.asarray(params["distances"])
    datasets = {"distances": (distances, "s*"), "grids": (np.asarray(grids), "1")}
    attrs = {}
    reference = reference_history(distances, rings=params["reference_rings"])
    datasets["reference/rms_slope"] = (reference.rms_slope, "grad_f0")
    datasets["reference/rms_slope_error"] = (reference.rms_slope_error, "grad_f0")
    datasets["reference/rms_height"] = (reference.rms_height, "grad_f0 a")
    for c in params["cases"]:
        for key in ("rms_slope", "rms_slope_error", "rms_slope_plain", "uncorrected",
                    "rim_excess", "rms_height", "rim_layer_pixels"):
            datasets[f"{c}/{key}"] = (np.array([found[(c, n)][key] for n in grids]),
                                      _UNITS[key])
        for key in ("steady", "steady_error", "final", "final_error", "steps", "solves",
                    "wall_time"):
            datasets[f"{c}/{key}"] = (np.array([found[(c, n)][key] for n in grids],
                                               dtype=float), _UNITS[key])
        values = datasets[f"{c}/rms_slope"][0]
        fits = [extrapolate(grids, values[:, j]) for j in range(len(distances))]
        datasets[f"{c}/order"] = (np.array([f[0] for f in fits]), "1")
        datasets[f"{c}/extrapolated"] = (np.array([f[1] for f in fits]), "grad_f0")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def table(path):
    """The benchmark tables (markdown) from the study file.

    Each value carries its per-step error bar and, in brackets, its distance
    from the target: the axisymmetric reference for the homogeneous
    cylinder, else the extrapolated value, else (no asymptotic range) the
    finest grid's value, marked ``*``.
    """
    d, a = study_io.read_study(path, NAME)
    grids = [int(g) for g in d["grids"]]
    distances = d["distances"]
    shown = [j for j, s in enumerate(distances) if s in TABLE] or list(range(len(distances)))
    lines = []
    for c in a["params"]["cases"]:
        lines.append(f"\n{TITLES[c]}:\n")
        target_name = "axisymmetric" if c == "homogeneous" else "target"
        head = ("| s/s* | " + " | ".join(f"n = {n}" for n in grids)
                + f" | order | extrapolated | {target_name} |")
        lines += [head, "|" + "---|" * (head.count("|") - 1)]
        for j in shown:
            v = d[f"{c}/rms_slope"][:, j]
            e = d[f"{c}/rms_slope_error"][:, j]
            ext = d[f"{c}/extrapolated"][j]
            mark = ""
            if c == "homogeneous":
                target = d["reference/rms_slope"][j]
            elif np.isfinite(ext):
                target = ext
            else:
                target, mark = v[-1], "*"
            cells = [f"{vi:.4f} ± {ei:.4f} ({100 * (vi / target - 1):+.2f} %)"
                     for vi, ei in zip(v, e, strict=True)]
            order = d[f"{c}/order"][j]
            lines.append(f"| {distances[j]:g} | " + " | ".join(cells)
                         + f" | {'-' if not np.isfinite(order) else f'{order:.2f}'} | "
                         + f"{'-' if not np.isfinite(ext) else f'{ext:.4f}'} | "
                         + f"{target:.4f}{mark} |")
        lines.append("| end (steady) | " + " | ".join(
            f"{f:.4f} ± {fe:.4f} (steady module {s:.4f} ± {se:.4f})" for f, fe, s, se in zip(
                d[f"{c}/final"], d[f"{c}/final_error"], d[f"{c}/steady"],
                d[f"{c}/steady_error"], strict=True)) + " | | | |")
    return "\n".join(lines)


TITLES = {"homogeneous": "homogeneous cylinder", "voronoi": "Voronoi scene, $k_2/k_1$ = 10",
          "rods": "steel rods in brass"}


def plot(path, png):
    """Histories on each grid with their error bars, and the rim-layer calibration."""
    from transient.history import RIM_LAYER_FIT, rim_layer_excess

    d, a = study_io.read_study(path, NAME)
    cases = a["params"]["cases"]
    grids = [int(g) for g in d["grids"]]
    s = d["distances"]
    fig = study_io.figure(4.2 * (len(cases) + 1), 4.0)
    axes = fig.subplots(1, len(cases) + 1)
    for ax, c in zip(axes, cases, strict=False):
        for i, n in enumerate(grids):
            y, e = d[f"{c}/rms_slope"][i], d[f"{c}/rms_slope_error"][i]
            ax.errorbar(s * (1 + 0.04 * (i - len(grids) / 2)), y, yerr=e, fmt=".-", ms=3,
                        lw=0.8, capsize=2, color=f"C{i}", label=f"n = {n}")
            ax.semilogx(s, d[f"{c}/uncorrected"][i], ":", lw=0.7, color=f"C{i}")
        if c == "homogeneous":
            ax.semilogx(s, d["reference/rms_slope"], "k-", lw=1.0, label="axisymmetric")
        ext = d[f"{c}/extrapolated"]
        ok = np.isfinite(ext)
        ax.semilogx(s[ok], ext[ok], "kx", ms=6, label="extrapolated")
        ax.set_xscale("log")
        ax.set_xlabel("sliding distance / s*")
        ax.set_ylabel("rms slope / grad_f0")
        ax.set_title(f"{TITLES[c]}\n(dotted: without the rim-layer correction)", fontsize=9)
        ax.legend(fontsize=7)
    ax = axes[-1]
    if "homogeneous" in cases:
        ref = d["reference/rms_slope"]
        for i, n in enumerate(grids):
            rho = d["homogeneous/rim_layer_pixels"][i]
            excess = d["homogeneous/uncorrected"][i] ** 2 - ref ** 2
            ax.loglog(rho, np.maximum(excess, 1e-5), "o", ms=4, color=f"C{i}",
                      label=f"n = {n}")
        rho = np.logspace(-2, 1.5, 100)
        ax.loglog(rho, rim_layer_excess(rho), "k-", lw=1,
                  label="fit {:.3f} / (1 + {:.3f} rho + {:.2f} rho$^2$)".format(*RIM_LAYER_FIT))
        ax.set_xlabel(r"rim layer in pixels, $\rho = k E^* s / h$")
        ax.set_ylabel("excess mean-square slope / grad_f0$^2$")
        ax.set_title("rim layer: uncorrected estimator minus the\naxisymmetric reference",
                     fontsize=9)
        ax.legend(fontsize=7)
    study_io.save_figure(fig, png)
    print(table(path))


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True)


if __name__ == "__main__":
    sys.exit(main())
