"""Run-in distance: how far a face slides before it is within 1 % (and 0.1 %) of steady.

From a flat face, :func:`transient.runin.run_in` (ESDIRK3, local error
``tol`` in ``f*``) wears biphasic Voronoi punches to their steady state.
The run-in distance is :meth:`transient.result.RunResult.run_in_distance`:
the distance after which both the friction proxy (the history's continuum
rms slope, :mod:`transient.history`) and the face (its rms deviation from
the steady face of eq. 9 over the steady face's own rms) stay within the
band of the steady state (docs/model.md, "The run-in distance"), with its
bounds from the step errors and the estimator's rim-layer error.
Distances are in ``s* = a / (k_min E*)`` (``k_min`` the smaller wear
coefficient) and, for the epoxy scene (``steady/examples/epoxy_cylinder.toml``:
``a = 4 mm``, ``E* = 1.3 MPa``, its ``k = 1e-13 1/Pa`` for the matrix), in
metres.  Also the mean depth worn off by then, in units of
``f* = pbar a / E*``: it does not depend on the wear coefficients' scale.

Sweeps (around ``k_2/k_1 = 0.1``, ``rho_2 = 0.3``, 20^2 seeds; four
realisations each): the wear ratio ``k_2/k_1 = 0.01 .. 100``, the fill
factor ``rho_2 = 0.1 .. 0.7``, the grain size (10^2, 20^2, 40^2 seeds), the
homogeneous cylinder, and the grids n = 128, 256, 512 for one map of 20^2
and one of 40^2 seeds.

Run::

    python studies/runin_distance.py            # n = 256, 41 run-ins, about 3 min on 2 cores
    python studies/runin_distance.py --quick    # a few seconds
    python studies/runin_distance.py --plot-only

Writes ``OUT/runin_distance.h5`` and ``OUT/runin_distance.png``.
"""

import sys

import numpy as np
import study_io

from steady.outline import Circle
from steady.phases import Homogeneous, Voronoi
from steady.scene import Scene, load_scene
from steady.wear import PowerLaw

NAME = "runin_distance"
BASE = {"ratio": 0.1, "fill": 0.3, "n_seeds": 400}
PARAMS = {"n": 256, "scheme": "esdirk3", "tol": 1e-5, "band": 0.01, "base": BASE,
          "ratios": [0.01, 0.1, 10.0, 100.0], "fills": [0.1, 0.3, 0.5, 0.7],
          "n_seeds": [100, 400, 1600], "seeds": [1000, 1001, 1002, 1003],
          "grids": [128, 256, 512], "grid_levels": [400, 1600], "scene": "epoxy_cylinder.toml"}
QUICK = {"n": 32, "scheme": "esdirk3", "tol": 1e-3, "band": 0.01,
         "base": {"ratio": 0.1, "fill": 0.3, "n_seeds": 25},
         "ratios": [0.1, 10.0], "fills": [0.3], "n_seeds": [25], "seeds": [1000],
         "grids": [32, 48], "grid_levels": [25], "scene": "epoxy_cylinder.toml"}


def _run(case, n, scheme, tol, band):
    """One run-in from a flat face; its history and run-in distances (``band`` and a tenth)."""
    from transient.initial_face import flat
    from transient.options import RunOptions
    from transient.run_in_distance import deviations
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    if case["n_seeds"] == 0:
        geometry, k = Homogeneous(), (1.0,)
    else:
        geometry = Voronoi(case["n_seeds"], (1 - case["fill"], case["fill"]), case["seed"])
        k = (1.0, case["ratio"])
    # a = 1 m, pbar = 1 Pa, E* = 1 Pa: distances come out in units of a / (k E*).
    scene = Scene(outline=Circle(1.0), normal_force=np.pi, E_star=1.0, n=n, wear=PowerLaw(k),
                  geometry=geometry)
    problem = wear_problem_of(scene, n=n)
    result = run_in(problem, flat(problem.grid), RunOptions(scheme=scheme, tol=tol))
    if not result.success:
        raise ValueError(f"run-in of {case} ended {result.status}: {result.message}")
    h = result.history
    s_star, f_star = result.distance_scale, result.depth_scale
    out = {"distance": h["distance"] / s_star,
           "value": h["normalised_rms_slope"],
           "deviation": deviations(result)[0],
           "steady": result.steady_rms_slope / result.reference_slope,
           "steps": result.steps, "wall_time": result.wall_time}
    for key, within in (("s1", band), ("s01", band / 10)):
        found = result.run_in_distance(within)
        if not found.reached:
            raise ValueError(f"run-in of {case}: {found.message}")
        out.update({key: found.distance_s_star, f"{key}_low": found.low_m / s_star,
                    f"{key}_high": found.high_m / s_star,
                    f"{key}_depth": found.mean_worn_depth_m / f_star,
                    f"{key}_rim_depth": found.rim_worn_depth_m / f_star})
    return out


def cases(params):
    """The run-in cases of a study run: name -> (case, grid)."""
    base, seeds = params["base"], params["seeds"]
    out = {"homogeneous": ({"n_seeds": 0, "ratio": 1.0, "fill": 0.0, "seed": 0},
                           params["n"])}

    def add(group, **change):
        for seed in seeds:
            case = dict(base, seed=seed, **change)
            out[f"{group}/seed{seed}"] = (case, params["n"])

    for r in params["ratios"]:
        add(f"ratio_{r:g}", ratio=r)
    for f in params["fills"]:
        add(f"fill_{f:g}", fill=f)
    for c in params["n_seeds"]:
        add(f"seeds_{c}", n_seeds=c)
    for level in params["grid_levels"]:
        for g in params["grids"]:
            out[f"grid_{level}_{g}/seed{seeds[0]}"] = (dict(base, seed=seeds[0],
                                                            n_seeds=level), g)
    return out


def compute(path, params):
    """Every case (the base case once per group that holds it); write HDF5."""
    done, datasets, attrs = {}, {}, {}
    for name, (case, n) in cases(params).items():
        key = (tuple(sorted(case.items())), n)
        if key not in done:
            done[key] = _run(case, n, params["scheme"], params["tol"], params["band"])
        v = done[key]
        for field, unit in (("distance", "s*"), ("value", "grad_f0"), ("deviation", "1")):
            datasets[f"{name}/{field}"] = (v[field], unit)
        for field in ("steady", "s1", "s1_low", "s1_high", "s1_depth", "s1_rim_depth", "s01",
                      "s01_low", "s01_high", "s01_depth", "s01_rim_depth", "steps",
                      "wall_time"):
            unit = {"steady": "grad_f0", "steps": "1", "wall_time": "s"}.get(
                field, "f*" if field.endswith("depth") else "s*")
            attrs[f"{name.replace('/', '_')}_{field}"] = (v[field], unit)
    scene = load_scene(study_io.ROOT / "steady" / "examples" / params["scene"])
    radius = scene.outline.radius
    attrs["epoxy_radius"] = (radius, "m")
    attrs["epoxy_E_star"] = (scene.E_star, "Pa")
    attrs["epoxy_k"] = (scene.wear.coefficients[0], "1/Pa")
    attrs["epoxy_depth_scale"] = (scene.normal_force / (np.pi * radius * scene.E_star), "m")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def epoxy_metres(attrs, ratio):
    """``s*`` in metres for the epoxy scene with ``k_1`` its coefficient, ``k_2 = ratio k_1``."""
    k_min = attrs["epoxy_k"] * min(1.0, ratio)
    return attrs["epoxy_radius"] / (k_min * attrs["epoxy_E_star"])


def _group(attrs, params, group):
    """Run-in distances of a group over its realisations: values, lows, highs (s*), depth (f*)."""
    keys = [f"{group}_seed{s}" for s in params["seeds"]]
    return tuple(np.array([attrs[f"{k}_{f}"] for k in keys])
                 for f in ("s1", "s1_low", "s1_high", "s1_depth"))


def plot(path, png):
    """Histories and the run-in distance against ratio, fill factor and grain size."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    base = p["base"]
    seed0 = p["seeds"][0]
    fig = study_io.figure(13.0, 8.0)
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    names = ["homogeneous"] + [f"ratio_{r:g}/seed{seed0}" for r in p["ratios"]]
    for j, name in enumerate(names):
        s, v = d[f"{name}/distance"], d[f"{name}/deviation"]
        ok = s > 0
        label = ("homogeneous" if name == "homogeneous"
                 else f"$k_2/k_1$ = {name.split('/')[0][6:]}")
        ax.loglog(s[ok], v[ok], color=f"C{j}", lw=1, label=label)
        key = name.replace('/', '_')
        ax.plot([a[f"{key}_s1"], a[f"{key}_s01"]], [p["band"], p["band"] / 10], "o",
                color=f"C{j}", ms=4)
    for band in (p["band"], p["band"] / 10):
        ax.axhline(band, color="k", lw=0.7, ls="--")
    ax.set_ylim(1e-5, 2)
    ax.set_xlabel(r"sliding distance / $s^* = a/(k_{min} E^*)$")
    ax.set_ylabel("deviation from steady: max(rms slope, face)")
    ax.set_title(f"from a flat face, $\\rho_2$ = {base['fill']:g}, "
                 f"{int(round(np.sqrt(base['n_seeds'])))}$^2$ seeds, seed {seed0}, "
                 f"n = {p['n']}; dots: $s_{{1\\%}}$, $s_{{0.1\\%}}$", fontsize=9)
    ax.legend(fontsize=7)
    homog = a["homogeneous_s1"]
    panels = [(axes[0, 1], "ratios", "ratio", r"wear ratio $k_2/k_1$", True),
              (axes[1, 0], "fills", "fill", r"fill factor $\rho_2$", False),
              (axes[1, 1], "n_seeds", "seeds", "mean seed spacing d / a", True)]
    for ax, key, prefix, xlabel, logx in panels:
        xs = np.asarray(p[key], dtype=float)
        x_plot = 2 / np.sqrt(xs) if key == "n_seeds" else xs
        for i, x in enumerate(xs):
            group = f"{prefix}_{int(x) if key == 'n_seeds' else f'{x:g}'}"
            s1, lo, hi, depth = _group(a, p, group)
            hi = np.where(np.isfinite(hi), hi, 10 * s1)  # unresolved upper bound: off scale
            jitter = x_plot[i] * (1 + 0.025 * (np.arange(s1.size) - 0.5 * (s1.size - 1)))
            ax.errorbar(jitter, s1, yerr=[s1 - lo, hi - s1], fmt="o", ms=3.5, color="C0",
                        capsize=2, lw=0.7,
                        label=r"$s_{1\%}/s^*$ (bars: step and rim errors)" if i == 0
                        else "_nolegend_")
            ax.plot(jitter, depth, "s", ms=4, mfc="none", color="C3",
                    label=r"mean worn depth at $s_{1\%}$ / $f^*$" if i == 0 else "_nolegend_")
        ax.axhline(homog, color="0.4", ls="--", lw=0.8, label="homogeneous (both)")
        if logx:
            ax.set_xscale("log")
        ax.set_yscale("log")
        study_io.plain_log_ticks(ax)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(r"$s_{1\%}$ / $s^*$;  worn depth / $f^*$")
        ax.legend(fontsize=7)
    grid = "; ".join(
        f"{int(round(np.sqrt(lv)))}$^2$: " + ", ".join(
            f"{a[f'grid_{lv}_{g}_seed{seed0}_s1']:.3g}" for g in p["grids"])
        for lv in p["grid_levels"])
    axes[0, 1].set_title(f"$\\rho_2$ = {base['fill']:g}, "
                         f"{int(round(np.sqrt(base['n_seeds'])))}$^2$ seeds, {len(p['seeds'])} "
                         f"realisations\n$s_{{1\\%}}$ on n = "
                         f"{', '.join(str(g) for g in p['grids'])} (seed {seed0}): {grid}",
                         fontsize=9)
    axes[1, 0].set_title(f"$k_2/k_1$ = {base['ratio']:g}, "
                         f"{int(round(np.sqrt(base['n_seeds'])))}$^2$ seeds", fontsize=9)
    metres = epoxy_metres(a, base["ratio"])
    axes[1, 1].set_title(f"$k_2/k_1$ = {base['ratio']:g}, $\\rho_2$ = {base['fill']:g}; epoxy "
                         f"scene (a = {a['epoxy_radius'] * 1e3:g} mm): $s^*$ = "
                         f"{metres / 1e3:.3g} km, $f^*$ = {a['epoxy_depth_scale'] * 1e3:.3g} mm",
                         fontsize=9)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
