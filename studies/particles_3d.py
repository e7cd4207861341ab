"""Spherical particles: when the paper's columnar (2-d) theory holds for a 3-d microstructure.

The paper's theory takes columnar rods: every section of the punch is the
same map, and the worn face reaches the steady face of that map (eq. 7, 9).
Particles in a matrix are not columnar: as the face wears down it meets
new particles and leaves old ones.  Here a punch of random non-overlapping
spheres (:class:`steady.depth_maps.Spheres`, volume fraction 0.3, wear
ratio 10, the particles harder: ``k`` ten times smaller than the matrix's)
is worn from flat through several particle diameters (package
``transient``, a depth run), and its rms slope is compared with

(a) the quasi-steady prediction of each section: the steady face of the
    section at the current worn depth, extruded as rods (the history's
    ``quasi_steady_rms_slope``);
(b) the paper's rods of the same area fraction: random circular inclusions
    of the same radius and fraction (:class:`steady.inclusions.Inclusions`,
    steady, several seeds) and the section at the initial surface extruded.

The run-in depth, the worn depth over which a face reaches its steady state,
is a few ``f* = pbar a / E*``.  The ratio ``r / f*`` of the particle radius
to it is varied at a fixed sphere map (radius ``0.08 a``) by the load
(``f*`` is proportional to it; the normalised problem depends on
``F / E*`` only through ``f*``).  Figures per ratio, over the worn depths
past ``settle`` f* (the run-in from flat) up to the end of the run,
sampled uniformly in depth:

- ``tracking``: rms of ``S - Q`` over the mean of ``Q`` (``S`` the face's
  rms slope, ``Q`` the quasi-steady one);
- ``q_scatter``, ``s_scatter``: standard deviation over mean of ``Q`` and
  of ``S`` (how much the sections differ, and how much of it the face
  shows);
- ``mean_ratio``: mean ``S`` over mean ``Q``; ``over_inclusions``: mean
  ``S`` over the steady value of the circular inclusions;
- ``face_fraction``: mean particle area fraction of the worn face's
  section (the hard particles stand proud of the face and it lingers in
  them: above the volume fraction once the relief, of order ``f*``, is
  comparable with the particles), and the fine-grain rods' rms slope at
  that fraction (:func:`steady.reference.fine_grain_rms_slope`).

Run::

    python studies/particles_3d.py            # n = 64, six ratios, 5.5 min (one core)
    python studies/particles_3d.py --quick    # n = 32, two ratios, 7 s of CPU

Writes ``OUT/particles_3d.h5`` and ``OUT/particles_3d.png``.
"""

import dataclasses
import logging
import math
import sys
import warnings

import numpy as np
import study_io
from matplotlib.colors import ListedColormap

from steady.depth_maps import Spheres
from steady.inclusions import Inclusions
from steady.reference import fine_grain_rms_slope
from steady.scene import load_scene, problem_of
from steady.solution import solve
from steady.validity import ValidityWarning

NAME = "particles_3d"
logger = logging.getLogger(__name__)
SCENE = study_io.ROOT / "steady" / "examples" / "spheres_transient.toml"
PARAMS = {"n": 64, "radius_over_a": 0.08, "volume_fraction": 0.3, "seed": 2031,
          "coefficients": [1.0e-12, 1.0e-13],
          "radius_over_f_star": [0.125, 0.25, 0.5, 1.0, 2.0, 4.0],
          "settle": 4.0, "diameters": 3.0, "tol": 1e-4, "inclusion_seeds": [6101, 6102, 6103],
          "samples": 200}
QUICK = {"n": 32, "radius_over_a": 0.125, "volume_fraction": 0.3, "seed": 2031,
         "coefficients": [1.0e-12, 1.0e-13], "radius_over_f_star": [0.5, 4.0],
         "settle": 2.0, "diameters": 1.0, "tol": 1e-3, "inclusion_seeds": [6101],
         "samples": 40}


def case_scene(params, ratio):
    """The sphere scene at ``r / f* = ratio``: the example's punch, load scaled to give ``f*``.

    Returns the scene, ``f*`` (m) and the mean worn depth at which the run
    ends, ``settle f* + diameters 2 r`` (m).
    """
    base = load_scene(SCENE, extra_sections=("transient", "initial_face"))
    a = base.outline.scale
    r = params["radius_over_a"] * a
    f_star = r / ratio
    # f* = pbar a / E* with pbar = F / (pi a^2) on the disk.
    force = f_star * math.pi * a * base.E_star
    end = params["settle"] * f_star + params["diameters"] * 2.0 * r
    geometry = Spheres(r, params["volume_fraction"], params["seed"], end + 2.0 * r + 0.5 * a)
    wear = dataclasses.replace(base.wear, coefficients=tuple(params["coefficients"]))
    scene = dataclasses.replace(base, geometry=geometry, normal_force=force, n=params["n"],
                                wear=wear)
    return scene, f_star, end


def run_case(params, ratio):
    """Wear the sphere punch from flat to the end depth; the history figures, normalised."""
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    scene, f_star, end = case_scene(params, ratio)
    problem = wear_problem_of(scene)
    options = RunOptions(tol=params["tol"], end_depth=end)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        result = run_in(problem, np.zeros(problem.shape), options)
    if result.status != "depth":
        raise ValueError(f"r/f* = {ratio:g}: the run ended {result.status!r}: {result.message}")
    h = result.history
    grad = result.reference_slope
    logger.info("r/f* = %g: %d steps, %d rejected, %.0f s", ratio, result.steps, result.rejected,
                result.wall_time)
    return {"worn": np.asarray(h["worn_depth_mean"]) / f_star,
            "slope": np.asarray(h["rms_slope"]) / grad,
            "quasi": np.asarray(h["quasi_steady_rms_slope"]) / grad,
            "fraction": np.asarray(h["phase_fraction"])[:, 1],
            "f_star": problem.depth_scale, "end": end / f_star, "steps": result.steps,
            "rejected": result.rejected}


def inclusion_slopes(params):
    """Steady rms slope / grad_f0 of random circular inclusions of the same radius and fraction.

    On the study's grid, or the inclusions' minimum grid where that is finer.
    """
    scene, _, _ = case_scene(params, 1.0)
    values = []
    for seed in params["inclusion_seeds"]:
        geometry = Inclusions(params["radius_over_a"] * scene.outline.scale, seed,
                              fill_factor=params["volume_fraction"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ValidityWarning)
            n = max(params["n"], geometry.min_grid(scene.outline))
            solution = solve(problem_of(dataclasses.replace(scene, geometry=geometry),
                                                n=n))
        values.append(solution.normalised_rms_slope)
    return np.asarray(values)


def window_figures(run, params):
    """Figures over the worn depths from ``settle`` f* to the end, uniformly sampled in depth."""
    w = np.linspace(params["settle"], run["end"], params["samples"])
    s = np.interp(w, run["worn"], run["slope"])
    q = np.interp(w, run["worn"], run["quasi"])
    fraction = np.interp(w, run["worn"], run["fraction"])
    return {"face_fraction": float(fraction.mean()),
            "tracking": float(np.sqrt(np.mean((s - q) ** 2)) / q.mean()),
            "q_scatter": float(q.std() / q.mean()), "s_scatter": float(s.std() / s.mean()),
            "mean_slope": float(s.mean()), "mean_quasi": float(q.mean())}


def compute(path, params):
    """Every ratio's run and the columnar references; write HDF5."""
    ratios = params["radius_over_f_star"]
    runs = [run_case(params, ratio) for ratio in ratios]
    figures = [window_figures(run, params) for run in runs]
    inclusions = inclusion_slopes(params)
    length = max(len(run["worn"]) for run in runs)

    def padded(key):
        out = np.full((len(runs), length), np.nan)
        for i, run in enumerate(runs):
            out[i, :len(run[key])] = run[key]
        return out

    def column(key):
        return np.array([f[key] for f in figures])

    phi = params["volume_fraction"]
    ratio_k = params["coefficients"][1] / params["coefficients"][0]
    fine = float(fine_grain_rms_slope([1 - phi, phi], [1.0, ratio_k]))
    scene, _, _ = case_scene(params, 1.0)
    section = scene.geometry.labels(scene.grid())
    over_inclusions = column("mean_slope") / inclusions.mean()
    datasets = {
        "radius_over_f_star": (np.asarray(ratios, dtype=float), "1"),
        "worn_depth_mean": (padded("worn"), "f* (mean worn depth over the face; NaN padding)"),
        "rms_slope": (padded("slope"), "grad_f0 (rms slope of the worn face)"),
        "quasi_steady_rms_slope": (padded("quasi"), "grad_f0 (steady face of the section)"),
        "particle_fraction": (padded("fraction"), "1 (area fraction of the particles in the "
                                                  "section at the worn depth)"),
        "end_depth": (np.array([run["end"] for run in runs]), "f*"),
        "steps": (np.array([run["steps"] for run in runs]), "1"),
        "rejected": (np.array([run["rejected"] for run in runs]), "1"),
        "tracking": (column("tracking"), "1 (rms(S - Q) / mean Q over the window)"),
        "q_scatter": (column("q_scatter"), "1 (std Q / mean Q over the window)"),
        "s_scatter": (column("s_scatter"), "1 (std S / mean S over the window)"),
        "mean_slope": (column("mean_slope"), "grad_f0"),
        "mean_quasi": (column("mean_quasi"), "grad_f0"),
        "mean_ratio": (column("mean_slope") / column("mean_quasi"), "1"),
        "over_inclusions": (over_inclusions, "1"),
        "face_fraction": (column("face_fraction"), "1 (mean particle area fraction of the worn "
                                                   "face's section over the window)"),
        "fine_grain_at_face_fraction": (fine_grain_rms_slope(
            np.column_stack([1 - column("face_fraction"), column("face_fraction")]),
            [1.0, ratio_k]), "grad_f0 (fine-grain rods at the face's particle fraction)"),
        "inclusions": (inclusions, "grad_f0 (steady, one value per seed)"),
        "surface_section": (section.astype(np.int8), "1 (phase, -1 off the face)"),
    }
    return study_io.write_study(path, NAME, params, datasets, {
        "surface_quasi_steady": (float(runs[0]["quasi"][0]), "grad_f0"),
        "inclusions_mean": (float(inclusions.mean()), "grad_f0"),
        "fine_grain": (fine, "grad_f0"),
    })


def plot(path, png):
    """The rms slope histories against their quasi-steady values, and the summary figures."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    ratios = d["radius_over_f_star"]
    fig = study_io.figure(13.0, 8.0)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1, 1.1])
    axes = top.subplots(1, len(ratios), sharey=True)
    axes = np.atleast_1d(axes)
    for i, (ax, ratio) in enumerate(zip(axes, ratios, strict=True)):
        w = d["worn_depth_mean"][i] / ratio / 2.0  # f* -> particle diameters
        ax.plot(w, d["quasi_steady_rms_slope"][i], color="0.55", lw=0.9,
                label="Q: quasi-steady (section as rods)")
        ax.plot(w, d["rms_slope"][i], color="C0", lw=1.1, label="S: worn face")
        ax.axvline(p["settle"] / ratio / 2.0, color="k", lw=0.6, ls=":")
        ax.axhline(a["inclusions_mean"], color="C3", lw=0.8, ls="--",
                   label="circular inclusions (steady)")
        ax.set_title(f"r = {ratio:g} f*: tracking {100 * d['tracking'][i]:.1f} %\n"
                     f"scatter Q {100 * d['q_scatter'][i]:.1f} %, S "
                     f"{100 * d['s_scatter'][i]:.1f} %", fontsize=8.5)
        ax.set_xlabel("worn depth / diameter")
    axes[0].set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    axes[0].legend(fontsize=7, loc="lower right")
    ax_map, ax_sum, ax_mean = bottom.subplots(1, 3, width_ratios=[0.8, 1.2, 1.2])
    cmap = ListedColormap(["#bdbdbd", "#252525"])
    ax_map.imshow(np.ma.masked_less(d["surface_section"], 0).T, origin="lower",
                  extent=(-1, 1, -1, 1), cmap=cmap, interpolation="nearest")
    ax_map.set_title(f"surface section, n = {p['n']}:\nspheres r = {p['radius_over_a']:g} a, "
                     f"{100 * p['volume_fraction']:g} % by volume\n(dark: particles, k / 10)",
                     fontsize=8.5)
    ax_map.set_xticks([])
    ax_map.set_yticks([])
    ax_sum.plot(ratios, 100 * d["tracking"], "o-", color="C0", label="tracking rms(S - Q) / Q")
    ax_sum.plot(ratios, 100 * d["q_scatter"], "s--", color="0.45", label="scatter of Q")
    ax_sum.plot(ratios, 100 * d["s_scatter"], "^-", color="C2", label="scatter of S")
    ax_sum.set_xscale("log")
    study_io.plain_log_ticks(ax_sum)
    ax_sum.set_xlabel("particle radius / f*")
    ax_sum.set_ylabel("% of the mean")
    ax_sum.set_title("does the face follow its sections?", fontsize=9)
    ax_sum.legend(fontsize=7.5)
    ax_mean.plot(ratios, d["mean_slope"], "o-", color="C0", label="S: worn face, mean")
    ax_mean.plot(ratios, d["mean_quasi"], "s--", color="0.45", label="Q: sections, mean")
    ax_mean.plot(ratios, d["fine_grain_at_face_fraction"], "x:", color="C1",
                 label="fine-grain rods at the worn face's particle fraction")
    ax_mean.axhline(a["inclusions_mean"], color="C3", ls="--", lw=0.9,
                    label=f"circular inclusions {a['inclusions_mean']:.3f}")
    ax_mean.axhline(a["fine_grain"], color="C1", ls=":", lw=0.9,
                    label=f"fine-grain rods at the volume fraction {a['fine_grain']:.3f}")
    ax_mean.axhline(1.0, color="k", lw=0.6, label="homogeneous")
    ax_mean.set_xscale("log")
    study_io.plain_log_ticks(ax_mean)
    ax_mean.set_xlabel("particle radius / f*")
    ax_mean.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax_mean.set_title("mean over the run past the run-in", fontsize=9)
    ax_mean.legend(fontsize=7)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
