"""Load step: a run-in whose normal force doubles or halves on the way, against constant load.

The scene ``steady/examples/voronoi_transient.toml`` (400 Voronoi seeds, 30 %
of phase 1 with ``k_1/k_0 = 10``, 10 N on the epoxy cylinder) is worn from
flat by :func:`transient.runin.run_in` three times: at constant load, and
with a ``[load] programme`` that steps the force to twice (step up) or half
(step down) of it at ``s_b`` (in ``s* = a / (k_min E*)``), once the face is
close to steady.  Each run ends on the steady face of its last force (eq. 9;
the linear law's face scales with the load).  The study records the
histories (rms slope, face deviation from the final steady face, contact
fraction, force) and the distance after the step at which each run is back
within 1 % of its steady state (:meth:`transient.result.RunResult.run_in_distance`),
against the run-in distance from flat at constant load.

What to expect (docs/model.md, "Load programmes"): the deviation is linear
in the face while the whole face is in contact, so after a step up from the
steady face it is the run-in from flat times ``|1 - F_1/F_2| = 1/2``; a step
down lifts the rim off (the increment is the flat punch's pressure under a
negative force, singular at the rim) and settles later.

Run::

    python studies/load_step.py            # n = 96, three run-ins, about 1 min on one core
    python studies/load_step.py --quick    # n = 40, a few seconds
    python studies/load_step.py --plot-only

Writes ``OUT/load_step.h5`` and ``OUT/load_step.png``.
"""

import dataclasses
import sys

import numpy as np
import study_io

NAME = "load_step"
PARAMS = {"scene": "voronoi_transient.toml", "n": 192, "scheme": "esdirk3", "tol": 1e-5,
          "step_at": 3.0, "factors": [2.0, 0.5], "within": 0.01}
QUICK = {"scene": "voronoi_transient.toml", "n": 40, "scheme": "esdirk3", "tol": 1e-3,
         "step_at": 3.0, "factors": [2.0, 0.5], "within": 0.01}

#: History datasets kept for each run, and their units.
_KEPT = {"distance": "s*", "force": "N", "rms_slope": "1", "face_deviation": "1",
         "contact_fraction": "1"}


def _run(scene, n, scheme, tol, within):
    """One run-in of ``scene`` from flat to steady: its history and run-in distance."""
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import wear_problem_of

    problem = wear_problem_of(scene, n=n)
    result = run_in(problem, np.zeros(problem.shape), RunOptions(scheme=scheme, tol=tol))
    if not result.success:
        raise ValueError(f"run-in ended {result.status}: {result.message}")
    found = result.run_in_distance(within)
    if not found.reached:
        raise ValueError(found.message)
    s_star = result.distance_scale
    history = dict(result.history)
    history.setdefault("force", np.full(len(history["distance"]), scene.normal_force))
    out = {name: np.asarray(history[name], dtype=float) for name in _KEPT}
    out["distance"] = out["distance"] / s_star
    out.update(s_within=found.distance_s_star, steps=result.steps,
               wall_time=result.wall_time, s_star=s_star)
    return out


def compute(path, params):
    """The constant-load run and one run per load factor; write HDF5."""
    from steady.load_programme import LoadProgramme
    from transient.scene import load_transient_scene, wear_problem_of

    scene, _, _ = load_transient_scene(study_io.ROOT / "steady" / "examples" / params["scene"])
    s_star = wear_problem_of(scene, n=params["n"]).distance_scale
    force = scene.normal_force
    scenes = {"constant": scene}
    for factor in params["factors"]:
        programme = LoadProgramme(force, ((params["step_at"] * s_star, factor * force),))
        scenes[f"factor_{factor:g}"] = dataclasses.replace(scene, load_programme=programme)
    datasets, attrs = {}, {"s_star": (s_star, "m"), "initial_force": (force, "N")}
    for name, case in scenes.items():
        v = _run(case, params["n"], params["scheme"], params["tol"], params["within"])
        for field, unit in _KEPT.items():
            datasets[f"{name}/{field}"] = (v[field], unit)
        # The distance back within the band, from the step (from s = 0 at constant load).
        start = 0.0 if name == "constant" else params["step_at"]
        attrs[f"{name}_resettle"] = (v["s_within"] - start, "s*")
        attrs[f"{name}_steps"] = (v["steps"], "1")
        attrs[f"{name}_wall_time"] = (v["wall_time"], "s")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Force and rms slope, face deviation after the step, contact fraction."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    s_b, within = p["step_at"], p["within"]
    names = ["constant"] + [f"factor_{f:g}" for f in p["factors"]]
    labels = {"constant": f"constant {a['initial_force']:g} N"}
    labels.update({f"factor_{f:g}": f"{a['initial_force']:g} N -> {f * a['initial_force']:g} N"
                   for f in p["factors"]})
    fig = study_io.figure(13.0, 4.2)
    ax_slope, ax_dev, ax_contact = fig.subplots(1, 3)
    ax_force = ax_slope.twinx()
    for j, name in enumerate(names):
        s = d[f"{name}/distance"]
        ax_slope.plot(s, d[f"{name}/rms_slope"], color=f"C{j}", lw=1.2, label=labels[name])
        ax_force.step(s, d[f"{name}/force"], where="post", color=f"C{j}", lw=0.8, ls=":")
        ax_contact.plot(s, d[f"{name}/contact_fraction"], color=f"C{j}", lw=1.2)
        start = 0.0 if name == "constant" else s_b
        after = s > start
        ax_dev.semilogy(s[after] - start, d[f"{name}/face_deviation"][after], color=f"C{j}",
                        lw=1.2, label=f"{labels[name]}: within {within:.0%} after "
                                      f"{a[f'{name}_resettle']:.3g} s*")
    s0, dev0 = d["constant/distance"], d["constant/face_deviation"]
    for f in p["factors"]:
        factor = abs(1 - 1 / f)
        if f > 1:
            ax_dev.semilogy(s0[s0 > 0], factor * dev0[s0 > 0], "k--", lw=0.8,
                            label=f"from flat x |1 - F1/F2| = {factor:g}")
    ax_dev.axhline(within, color="k", lw=0.6, ls=":")
    for ax in (ax_slope, ax_contact):
        ax.axvline(s_b, color="0.6", lw=0.6)
        ax.set_xlabel(r"sliding distance / $s^* = a/(k_{min} E^*)$")
    ax_slope.set_ylabel("rms slope of the face")
    ax_force.set_ylabel("normal force (N), dotted")
    ax_slope.legend(fontsize=7, loc="lower right")
    ax_slope.set_title(f"n = {p['n']}, {p['scheme']}, tol = {p['tol']:g}; load step at "
                       f"{s_b:g} s*", fontsize=9)
    ax_dev.set_xlabel(r"distance since the step (from flat: since $s = 0$) / $s^*$")
    ax_dev.set_ylabel("face deviation from the final steady face")
    ax_dev.set_ylim(1e-5, 1.0)
    ax_dev.legend(fontsize=7)
    ax_dev.set_title("back to steady after the step", fontsize=9)
    ax_contact.set_ylabel("contact fraction of the face")
    ax_contact.set_title("a step down lifts the rim off", fontsize=9)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
