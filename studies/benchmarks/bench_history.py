"""Cost of the run-in history's estimator against the contact solves of a step.

For the shipped Voronoi run-in scene (``steady/examples/voronoi_transient.toml``)
on n = 128, 256, 512: the time of one call of
:meth:`transient.history.FaceEstimator.figures` (what the history records
at every accepted step: the corrected rms slope with its error bar, the
plain pixel value, the rms height), of building the estimator once per run,
and of one warm shifted contact solve (an implicit stage); then a real run
(SDIRK2, ``tol = 1e-4``, flat face to 1 s*) with the estimator's calls timed
inside it, as a fraction of the run's wall time.

Run::

    python studies/benchmarks/bench_history.py            # about 5 minutes on 2 cores
    python studies/benchmarks/bench_history.py --quick    # n = 64 and 128, seconds

Prints a Markdown table.
"""

import argparse
import pathlib
import platform
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
GRIDS = [128, 256, 512]
REPEATS = 5


def _median(fn, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def measure(n, distance):
    """Timings on one grid (s): estimator call and build, warm shifted solve, run fractions."""
    from transient import history
    from transient.options import RunOptions
    from transient.runin import run_in
    from transient.scene import load_transient_scene, wear_problem_of
    from transient.solver import StageSolver

    scene, _, initial = load_transient_scene(ROOT / "steady" / "examples" /
                                             "voronoi_transient.toml")
    problem = wear_problem_of(scene, n=n)
    h0 = initial.recession(problem.grid)
    build = _median(lambda: history.FaceEstimator(problem, h0), 3)
    estimator = history.FaceEstimator(problem, h0)
    # A state in the middle of the run-in: 0.1 s*.
    s_star = problem.distance_scale
    mid = run_in(problem, h0, RunOptions(tol=1e-4, snapshots_s_star=(0.1,),
                                         distance_limit=0.1 * s_star, jump_spread=0.0))
    height, pressure = np.where(problem.face_mask, mid.recession, 0.0), mid.pressure
    call = _median(lambda: estimator.figures(0.1 * mid.distance_scale, height, pressure,
                                             mid.approach), REPEATS)
    shift = 1e-2 * mid.distance_scale * problem.wear_field
    solver = StageSolver(problem)
    solve = _median(lambda: solver.contact(height, shift=shift, x0=pressure), 3)
    # A whole run with the estimator's calls timed.
    spent = []
    original = history.FaceEstimator.figures

    def timed(self, *args):
        t = time.perf_counter()
        out = original(self, *args)
        spent.append(time.perf_counter() - t)
        return out

    history.FaceEstimator.figures = timed
    try:
        fresh = wear_problem_of(scene, n=n)
        t = time.perf_counter()
        result = run_in(fresh, h0, RunOptions(tol=1e-4, distance_limit=distance * s_star,
                                              jump_spread=0.0))
        wall = time.perf_counter() - t
    finally:
        history.FaceEstimator.figures = original
    return dict(n=n, build=build, call=call, solve=solve, wall=wall, steps=result.steps,
                solves=result.solves, recorded=len(spent), in_estimator=float(np.sum(spent)))


def main(argv=None):
    """Run the benchmark and print its table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="n = 64 and 128")
    args = parser.parse_args(argv)
    grids, distance = ([64, 128], 0.1) if args.quick else (GRIDS, 1.0)
    print(f"machine: {platform.processor() or platform.machine()}, {platform.platform()}, "
          f"python {sys.version.split()[0]}, numpy {np.__version__}")
    print(f"\nrun: flat face to {distance:g} s*, sdirk2, tol 1e-4\n")
    print("| n | estimator call (ms) | warm shifted solve (ms) | call / solve | estimator build "
          "(ms) | run wall (s) | steps | solves | share of the run in the estimator |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in grids:
        r = measure(n, distance)
        print(f"| {n} | {1e3 * r['call']:.1f} | {1e3 * r['solve']:.1f} | "
              f"{r['call'] / r['solve']:.2f} | {1e3 * r['build']:.0f} | {r['wall']:.1f} | "
              f"{r['steps']} | {r['solves']} | {100 * r['in_estimator'] / r['wall']:.1f} % "
              f"({r['recorded']} calls) |", flush=True)


if __name__ == "__main__":
    main()
