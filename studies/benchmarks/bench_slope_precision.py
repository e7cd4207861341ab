"""The run-in history's corrected estimator in single and in double precision: time and error.

For the shipped Voronoi run-in scene (``steady/examples/voronoi_transient.toml``)
on n = 256, 512, 1024: a run-in from the flat face to 1 s* (the default
integrator, ``tol = 1e-4``) gives real pressures at ``s = 0.01, 0.1, 1 s*`` (plus the
flat punch's at ``s = 0``).  On each, :class:`steady.rms_slope.SlopeEnergy`
with ``precision="double"`` and ``"single"``: the largest relative
difference of ``rms_slope`` and of each integral (``total``, ``face_sum``,
``exterior``, ``corrected``), and of the history's ``rms_slope``
(:meth:`transient.history.FaceEstimator.figures`) in units of its error
bar.  Then the CPU time of one call of each, side by side in turn
(medians), with one FFT thread as the run-in's history thread has: the estimator's
``__call__`` (and its parts: the fine box's gradient, the coarse box's,
the squared pressure jumps) and the whole ``figures``.

Run::

    python studies/benchmarks/bench_slope_precision.py          # about 3 minutes on 2 cores
    python studies/benchmarks/bench_slope_precision.py --n 512  # one grid
    python studies/benchmarks/bench_slope_precision.py --n 64 --repeats 3  # seconds

Prints three Markdown tables.
"""

import argparse
import functools
import pathlib
import platform
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "steady" / "examples" / "voronoi_transient.toml"
GRIDS = [256, 512, 1024]
SNAPSHOTS = (0.01, 0.1, 1.0)  # s*
INTEGRALS = ("rms_slope", "total", "face_sum", "exterior", "corrected")
REPEATS = 7


def run_states(n):
    """The problem, its flat initial face and the pressures and faces of a run-in, at n."""
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import load_transient_scene, wear_problem_of
    from transient.solver import StageSolver

    scene, _, initial = load_transient_scene(SCENE)
    problem = wear_problem_of(scene, n=n)
    h0 = initial.recession(problem.grid)
    result = run_in(problem, h0, RunOptions(
        tol=1e-4, snapshots_s_star=SNAPSHOTS,
        distance_limit=SNAPSHOTS[-1] * problem.distance_scale))
    mask = problem.face_mask
    start = StageSolver(problem).contact(np.where(mask, h0, 0.0))
    states = [(0.0, np.where(mask, h0, 0.0), start.pressure)]
    for d, height, pressure in zip(result.snapshot_distance, result.snapshot_recession,
                                   result.snapshot_pressure, strict=True):
        states.append((float(d), np.where(mask, height, 0.0), np.where(mask, pressure, 0.0)))
    return problem, h0, states


def _alternating(calls, repeats):
    """Median CPU time (s) of each call, the calls made in turn ``repeats`` times.

    The calling thread's CPU time: with one FFT thread all the work is
    done on it, and on a machine shared with other jobs it does not count
    the time the thread waits for a core.
    """
    times = [[] for _ in calls]
    for _ in range(repeats):
        for fn, spent in zip(calls, times, strict=True):
            t = time.thread_time()
            fn()
            spent.append(time.thread_time() - t)
    return [float(np.median(t)) for t in times]


def measure(n, repeats):
    """Errors of single against double precision, and the time of each, on grid n."""
    from transient.history import FaceEstimator

    problem, h0, states = run_states(n)
    mask = problem.face_mask
    double = FaceEstimator(problem, h0, precision="double")
    single = FaceEstimator(problem, h0, precision="single")
    double.workers = single.workers = 1
    errors = dict.fromkeys(INTEGRALS, 0.0)
    in_bar = relative = 0.0
    for distance, height, pressure in states:
        a = double.energy.in_precision("double")(pressure, mask)
        b = double.energy.in_precision("single")(pressure, mask)
        for name in INTEGRALS:
            x, y = float(getattr(a, name)), float(getattr(b, name))
            errors[name] = max(errors[name], abs(y / x - 1.0))
        if distance > 0:
            # The approach only offsets the face (full contact here): 0.
            fa = double.figures(distance, height, pressure, 0.0)
            fb = single.figures(distance, height, pressure, 0.0)
            change = abs(fb["rms_slope"] - fa["rms_slope"])
            relative = max(relative, change / fa["rms_slope"])
            in_bar = max(in_bar, change / fa["rms_slope_error"])
    distance, height, pressure = states[2]
    energy_double = double.energy.in_precision("double")
    energy_single = double.energy.in_precision("single")
    parts = _parts(double.energy, pressure, mask)
    times = _alternating([lambda: double.figures(distance, height, pressure, 0.0),
                          lambda: single.figures(distance, height, pressure, 0.0),
                          lambda: energy_double(pressure, mask),
                          lambda: energy_single(pressure, mask)]
                         + [functools.partial(fn, t) for fn in parts.values()
                            for t in (np.float64, np.float32)], repeats)
    return dict(n=n, errors=errors, relative=relative, in_bar=in_bar,
                figures=tuple(times[0:2]), call=tuple(times[2:4]),
                parts={name: tuple(times[4 + 2 * i:6 + 2 * i]) for i, name in enumerate(parts)})


def _parts(energy, pressure, mask):
    """The parts of one call, each a function of the transforms' dtype: {part: function}."""
    from steady.rms_slope import _jump_sums, edge_jumps

    field = np.where(mask, pressure, 0.0)
    return {"fine box (transforms and products)": lambda t: energy._fine(field, t),
            "coarse box (block moments, transforms)":
                lambda t: energy._coarse(energy._coarse_sources(field), t),
            "squared pressure jumps":
                lambda t: (edge_jumps if t is np.float64 else _jump_sums)(field, mask)}


def main(argv=None):
    """Run the benchmark and print its tables; returns the rows."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, nargs="+", default=GRIDS,
                        help="grids (default %(default)s)")
    parser.add_argument("--repeats", type=int, default=REPEATS,
                        help="timed calls of each kind (default %(default)s)")
    args = parser.parse_args(argv)
    print(f"machine: {platform.processor() or platform.machine()}, {platform.platform()}, "
          f"python {sys.version.split()[0]}, numpy {np.__version__}")
    rows = [measure(n, args.repeats) for n in args.n]
    print(f"\nsingle against double precision, largest relative difference over s = 0 and "
          f"{', '.join(map(str, SNAPSHOTS))} s*\n")
    print("| n | " + " | ".join(INTEGRALS) + " | history rms slope | the same / its error bar |")
    print("|---" * (len(INTEGRALS) + 3) + "|")
    for r in rows:
        print(f"| {r['n']} | " + " | ".join(f"{r['errors'][k]:.1e}" for k in INTEGRALS)
              + f" | {r['relative']:.1e} | {r['in_bar']:.1e} |")
    print(f"\nCPU time, one FFT thread, medians of {args.repeats} calls made in turn, "
          f"s = 0.1 s*\n")
    print("| n | SlopeEnergy double (ms) | single (ms) | single / double | figures double (ms) "
          "| single (ms) | single / double |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        (cd, cs), (fd, fs) = r["call"], r["figures"]
        print(f"| {r['n']} | {1e3 * cd:.1f} | {1e3 * cs:.1f} | {cs / cd:.2f} | {1e3 * fd:.1f} | "
              f"{1e3 * fs:.1f} | {fs / fd:.2f} |")
    print("\nparts of one SlopeEnergy call (ms), double / single; the rest: the squares, sums "
          "and the far tail\n")
    print("| part | " + " | ".join(f"n = {r['n']}" for r in rows) + " |")
    print("|---" * (len(rows) + 1) + "|")
    for name in rows[0]["parts"]:
        print(f"| {name} | " + " | ".join(
            "{:.1f} / {:.1f}".format(*(1e3 * t for t in r["parts"][name])) for r in rows) + " |")
    rest = [tuple(c - sum(p[i] for p in r["parts"].values()) for i, c in enumerate(r["call"]))
            for r in rows]
    print("| the rest | " + " | ".join(f"{1e3 * d:.1f} / {1e3 * s:.1f}" for d, s in rest) + " |")
    return rows


if __name__ == "__main__":
    main()
