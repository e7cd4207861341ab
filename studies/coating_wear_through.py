"""Coating wear-through: a hard coating on a soft substrate, where and when it wears through.

The scene ``steady/examples/coating_transient.toml`` (a flat disk punch, the
epoxy-cylinder load) with a homogeneous coating of thickness ``t`` over a
substrate whose wear coefficient is ``k_s = r k_c`` (``r`` = 10 and 100) is
worn from flat across the interface by :func:`transient.runin.run_in` on the
square grid, and by the axisymmetric reference
:class:`transient.axisymmetric.CoatedAxisymmetricRunIn` (80 graded rings),
which is exact up to its rings and costs a second: the 2-d run gives each
pixel's wear-through distance (the map), the reference the sweep over the
thickness.  Recorded against ``t`` (units of ``f* = pbar a / E*``):

- where and when the coating wears through: the distance at which each pixel's
  worn depth passes ``t`` (the rim first), the rim's and the last pixel's;
- the friction proxy (the rms slope over ``grad_f0``) along the run, and its
  peak while the wear-through front sweeps the face;
- the distance to the substrate's steady state: the face's deviation from
  eq. 10 (which coating and substrate share) and the distance after which the
  rms slope and the face stay within 1 % of it; the lowest ring pressure at
  the crossings (the worn-through rim unloads towards ``pbar / r``).

Distances are in the coating's ``s*_c = a / (k_c E*)``.  What to expect
(docs/model.md, "The coated reference"; docs/studies.md, "Coating
wear-through").

Run::

    python studies/coating_wear_through.py            # n = 48, about 75 s on one core
    python studies/coating_wear_through.py --quick    # n = 20, about 10 s
    python studies/coating_wear_through.py --plot-only

Writes ``OUT/coating_wear_through.h5`` and ``OUT/coating_wear_through.png``.
"""

import dataclasses
import math
import sys

import numpy as np
import scipy.optimize
import study_io

NAME = "coating_wear_through"
PARAMS = {"scene": "coating_transient.toml", "n": 48, "tol": 1e-4, "ratios": [10.0, 100.0],
          "thicknesses": [0.25, 0.5, 1.0], "map_thickness": 0.5,
          "sweep": [0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0], "rings": 80,
          "points": 160, "within": 0.01}
QUICK = {"scene": "coating_transient.toml", "n": 20, "tol": 1e-3, "ratios": [10.0],
         "thicknesses": [0.5], "map_thickness": 0.5, "sweep": [0.25, 0.5, 1.0], "rings": 24,
         "points": 40, "within": 0.01}

#: History datasets kept from each 2-d run, their normalisation and units.
_KEPT = {"normalised_rms_slope": "1 (rms slope / grad_f0)",
         "face_deviation": "1 (rms of f - f_inf over the rms of f_inf)",
         "worn_depth_mean": "f* (pbar a / E*)"}
# How far past the coating's last crossing (in e-folding distances of the
# substrate) the steady search looks.
_DECAYS = 25.0


def coated_scene(scene, thickness, ratio):
    """``scene`` with its coating ``thickness`` f* thick over a substrate ``ratio`` times softer.

    ``f*`` is ``pbar a / E*`` with ``pbar = F / (pi a^2)``, the reference's
    unit; the coating keeps the scene's coefficient.
    """
    k_c = scene.wear.coefficients[1]
    f_star = scene.normal_force / (math.pi * scene.outline.scale * scene.E_star)
    return dataclasses.replace(
        scene, wear=dataclasses.replace(scene.wear, coefficients=(ratio * k_c, k_c)),
        depth=dataclasses.replace(scene.depth, thicknesses=(thickness * f_star,)))


def run_2d(scene, n, tol, within):
    """The 2-d run of a coated scene: each pixel's wear-through and the normalised history.

    A pixel wears through in the accepted step in which its worn depth
    passes the thickness, linearly interpolated within the step.
    """
    from transient.options import RunOptions
    from transient.run_in_distance import WearThroughMap
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    problem = wear_problem_of(scene, n=n)
    face, t = problem.face_mask, scene.depth.thicknesses[0]
    crossing = WearThroughMap(face, t)
    result = run_in(problem, np.zeros(problem.shape), RunOptions(tol=tol), on_step=crossing)
    if result.status != "steady":
        raise ValueError(f"run-in ended {result.status}: {result.message}")
    s_star = result.distance_scale
    f_star = scene.normal_force / (math.pi * scene.outline.scale * scene.E_star)
    hist = {name: np.asarray(result.history[name], dtype=float) for name in _KEPT}
    hist["worn_depth_mean"] = hist["worn_depth_mean"] / f_star
    hist["distance"] = np.asarray(result.history["distance"], dtype=float) / s_star
    found = result.run_in_distance(within)
    return {"crossing": crossing.distance / s_star,
            "radius": problem.grid.radii / scene.outline.scale,
            "history": hist, "settled": found.distance_s_star if found.reached else math.nan,
            "steps": result.steps, "rejected": result.rejected, "wall_time": result.wall_time}


def reference(thickness, ratio, rings):
    """The axisymmetric reference in its own units (``a = E* = pbar = k_c = 1``)."""
    from transient.axisymmetric import CoatedAxisymmetricRunIn

    return CoatedAxisymmetricRunIn(rings, thickness=thickness, substrate_coefficient=ratio)


def _figures(model, distances):
    """Normalised rms slope and face deviation of the reference at ``distances``."""
    states = [model.state(s) for s in distances]
    return (np.array([st.rms_slope for st in states]) / model.reference_slope,
            np.array([st.face_deviation for st in states]))


def settled_distance(model, within, points):
    """Distance after which the reference's rms slope and face stay within ``within`` of steady.

    The rms slope against its value far past the last crossing (the rings'
    eq. 10 face), the face deviation against 0, searched on ``points``
    distances from the first crossing and refined by Brent's method.
    """
    first, last = model.wear_through_distances()
    end = last + _DECAYS * model.substrate_decay_distance
    steady_slope = _figures(model, [end])[0][0]

    def excess(s):
        slope, deviation = _figures(model, [s])
        return max(abs(slope[0] / steady_slope - 1.0), deviation[0]) / within - 1.0

    grid = np.linspace(first, end, points)
    outside = [s for s in grid if excess(s) > 0]
    if not outside:
        return first
    start = max(outside)
    if start >= grid[-1]:
        raise ValueError(f"the reference is not within {within} of steady by s = {end:.4g} s*")
    return scipy.optimize.brentq(excess, start, grid[grid > start][0], xtol=1e-6)


def peak_slope(model, points):
    """The reference's largest normalised rms slope while the wear-through front sweeps the face.

    Searched on ``16 points`` distances from the first crossing to the last
    and refined by a bounded Brent search between the neighbours of the
    largest: the rms slope has a kink at every ring's crossing, and the spike
    at ``k_s/k_c`` = 100 is narrower than ``points`` distances resolve.
    """
    first, last = model.wear_through_distances()
    points = 16 * points
    s = np.linspace(first, last, points)
    slope, _ = _figures(model, s)
    i = int(np.argmax(slope))
    lo, hi = s[max(i - 1, 0)], s[min(i + 1, points - 1)]
    found = scipy.optimize.minimize_scalar(lambda x: -_figures(model, [x])[0][0],
                                           bounds=(lo, hi), method="bounded",
                                           options={"xatol": 1e-7})
    return float(max(slope[i], -found.fun))


def _sweep(params, ratio):
    """The reference over the thicknesses of ``params['sweep']`` for one ratio."""
    out = {key: [] for key in ("first", "last", "settled", "peak_slope", "minimum_pressure")}
    for t in params["sweep"]:
        model = reference(t, ratio, params["rings"])
        first, last = model.wear_through_distances()
        out["first"].append(first)
        out["last"].append(last)
        out["settled"].append(settled_distance(model, params["within"], params["points"]))
        out["peak_slope"].append(peak_slope(model, params["points"]))
        out["minimum_pressure"].append(model.minimum_crossing_pressure)
    return {key: np.array(v) for key, v in out.items()}


def _case(scene, params, ratio, t):
    """Datasets and attributes of one 2-d run and the reference at the same thickness."""
    run = run_2d(coated_scene(scene, t, ratio), params["n"], params["tol"], params["within"])
    model = reference(t, ratio, params["rings"])
    first, last = model.wear_through_distances()
    hist = run["history"]
    s = hist["distance"]
    slope, deviation = _figures(model, s)
    tag = f"k{ratio:g}_t{t:g}"
    datasets = {f"{tag}/{name}": (hist[name], unit) for name, unit in _KEPT.items()}
    datasets[f"{tag}/distance"] = (s, "s*_c (a / (k_c E*))")
    datasets[f"{tag}/reference_rms_slope"] = (slope, "1 (rms slope / grad_f0)")
    datasets[f"{tag}/reference_face_deviation"] = (deviation, "1")
    datasets[f"{tag}/crossing"] = (run["crossing"], "s*_c (NaN off the face)")
    datasets[f"{tag}/radius"] = (run["radius"], "a (pixel centre)")
    r = np.linspace(0.0, 1.0, 201)
    datasets[f"{tag}/reference_radius"] = (r, "a")
    datasets[f"{tag}/reference_crossing"] = (model.crossing_distance(r), "s*_c")
    settled = settled_distance(model, params["within"], params["points"])
    face = np.isfinite(run["crossing"])
    error = run["crossing"][face] - model.crossing_distance(np.minimum(run["radius"][face], 1))
    attrs = {f"{tag}_first": (float(np.nanmin(run["crossing"])), "s*_c"),
             f"{tag}_last": (float(np.nanmax(run["crossing"])), "s*_c"),
             f"{tag}_reference_first": (first, "s*_c"), f"{tag}_reference_last": (last, "s*_c"),
             f"{tag}_crossing_rms_error": (float(np.sqrt(np.mean(error ** 2))), "s*_c"),
             f"{tag}_settled": (run["settled"], "s*_c"),
             f"{tag}_reference_settled": (settled, "s*_c"),
             f"{tag}_steps": (run["steps"], "1"), f"{tag}_rejected": (run["rejected"], "1"),
             f"{tag}_wall_time": (run["wall_time"], "s")}
    return datasets, attrs


def compute(path, params):
    """The 2-d runs and the reference sweep for every ratio; write HDF5."""
    from transient.scene import load_transient_scene

    scene, _, _ = load_transient_scene(study_io.ROOT / "steady" / "examples" / params["scene"])
    datasets = {"thickness": (np.array(params["sweep"]), "f* (pbar a / E*)")}
    attrs = {}
    for ratio in params["ratios"]:
        sweep = _sweep(params, ratio)
        units = {"first": "s*_c", "last": "s*_c", "settled": "s*_c", "peak_slope": "1",
                 "minimum_pressure": "1 (lowest ring pressure at a crossing / pbar)"}
        for key, values in sweep.items():
            datasets[f"k{ratio:g}/{key}"] = (values, units[key])
        attrs[f"k{ratio:g}_decay"] = (reference(1.0, ratio, params["rings"])
                                      .substrate_decay_distance, "s*_c")
        for t in params["thicknesses"]:
            d, a = _case(scene, params, ratio, t)
            datasets.update(d)
            attrs.update(a)
    return study_io.write_study(path, NAME, params, datasets, attrs)


def _plot_map(ax, d, ratio, t):
    """The wear-through distance of every pixel of the run with ``ratio`` and thickness ``t``."""
    crossing = d[f"k{ratio:g}_t{t:g}/crossing"]
    image = ax.imshow(crossing.T, origin="lower", extent=(-1, 1, -1, 1), cmap="viridis")
    ax.set_title(f"k_s/k_c = {ratio:g}, t = {t:g} f*: where the coating wears through",
                 fontsize=8)
    ax.set_xlabel("x / a")
    ax.set_ylabel("y / a")
    return image


def plot(path, png):
    """Wear-through map and by radius; rms slope and face deviation; figures against t."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(14.0, 8.0)
    axes = fig.subplots(2, 3)
    ratios = p["ratios"]
    image = _plot_map(axes[0, 0], d, ratios[-1], p["map_thickness"])
    fig.colorbar(image, ax=axes[0, 0], label=r"wear-through distance / $s^*_c$")
    ax = axes[0, 1]
    for j, ratio in enumerate(ratios):
        tag = f"k{ratio:g}_t{p['map_thickness']:g}"
        face = np.isfinite(d[f"{tag}/crossing"])
        ax.plot(d[f"{tag}/radius"][face], d[f"{tag}/crossing"][face], ".", ms=2,
                color=f"C{j}", label=f"k_s/k_c = {ratio:g}, pixels (n = {p['n']})")
        ax.plot(d[f"{tag}/reference_radius"], d[f"{tag}/reference_crossing"], "k-" if j else "k--",
                lw=0.8, label=f"k_s/k_c = {ratio:g}, axisymmetric reference")
    ax.set_xlabel("radius of the pixel centre / a")
    ax.set_ylabel(r"wear-through distance / $s^*_c$")
    ax.set_title(f"t = {p['map_thickness']:g} f*: the rim first", fontsize=8)
    ax.legend(fontsize=6)
    ax_slope, ax_dev = axes[0, 2], axes[1, 0]
    for i, ratio in enumerate(ratios):
        for j, t in enumerate(p["thicknesses"]):
            tag = f"k{ratio:g}_t{t:g}"
            s = d[f"{tag}/distance"]
            style = dict(color=f"C{j}", lw=1.0, ls="-" if i == len(ratios) - 1 else ":")
            label = f"t = {t:g} f*, k_s/k_c = {ratio:g}"
            ax_slope.plot(s, d[f"{tag}/normalised_rms_slope"], label=label, **style)
            ax_dev.semilogy(s[s > 0], d[f"{tag}/face_deviation"][s > 0], label=label, **style)
            ax_slope.plot(s, d[f"{tag}/reference_rms_slope"], "k,", ms=1)
            ax_dev.semilogy(s[s > 0], d[f"{tag}/reference_face_deviation"][s > 0], "k,")
    ax_slope.set_xlabel(r"sliding distance / $s^*_c = a/(k_c E^*)$")
    ax_slope.set_ylabel(r"rms slope / $\nabla f_0$ (friction proxy)")
    ax_slope.set_title(f"2-d run (lines, n = {p['n']}), reference (black dots)", fontsize=8)
    ax_slope.legend(fontsize=6)
    ax_dev.axhline(p["within"], color="k", lw=0.6, ls=":")
    ax_dev.set_xlabel(r"sliding distance / $s^*_c$")
    ax_dev.set_ylabel(r"face deviation from eq. 10 (rms / rms of eq. 10)")
    ax_dev.set_ylim(1e-4, 10.0)
    ax_dev.set_title("towards the substrate's steady state (lines as above)", fontsize=8)
    _plot_sweep(axes[1, 1], axes[1, 2], d, a, p)
    study_io.save_figure(fig, png, dpi=70)


def _plot_sweep(ax_s, ax_p, d, a, p):
    """Wear-through, coating gone and settled distances, and the peak slope, against t."""
    t = d["thickness"]
    for j, ratio in enumerate(p["ratios"]):
        key = f"k{ratio:g}"
        ls = "-" if j == len(p["ratios"]) - 1 else "--"
        ax_s.loglog(t, d[f"{key}/first"], "C0" + ls, marker=".", label=f"rim through, {ratio:g}")
        ax_s.loglog(t, d[f"{key}/last"], "C1" + ls, marker=".", label=f"coating gone, {ratio:g}")
        ax_s.loglog(t, d[f"{key}/settled"], "C2" + ls, marker=".",
                    label=f"within {p['within']:.0%} of steady, {ratio:g}")
        for th in p["thicknesses"]:
            tag = f"{key}_t{th:g}"
            ax_s.plot([th, th, th], [a[f"{tag}_first"], a[f"{tag}_last"], a[f"{tag}_settled"]],
                      "kx", ms=4)
        ax_p.plot(t, d[f"{key}/peak_slope"], "C3" + ls, marker=".",
                  label=f"peak rms slope, k_s/k_c = {ratio:g}")
    ax_s.set_xlabel(r"coating thickness $t$ / $f^* = \bar p a/E^*$")
    ax_s.set_ylabel(r"sliding distance / $s^*_c$")
    ax_s.set_title("reference (lines; --: k_s/k_c = 10), 2-d runs (x)", fontsize=8)
    ax_s.legend(fontsize=6)
    study_io.plain_log_ticks(ax_s)
    ax_p.set_xscale("log")
    ax_p.set_xlabel(r"coating thickness $t$ / $f^*$")
    ax_p.set_ylabel(r"peak rms slope while the front sweeps / $\nabla f_0$")
    ax_p.axhline(1.0, color="k", lw=0.6, ls=":")
    ax_p.set_title("friction proxy: the spike before the coating is gone", fontsize=8)
    ax_p.legend(fontsize=6)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
