"""Run-in speed under sliding kinematics: a pin on a disk beside the translation.

What it reproduces
    docs/benchmarks.md, "Sliding kinematics": the shipped scene
    ``steady/examples/voronoi_transient.toml`` (its ``[transient]`` settings,
    flat start to the steady state, load 10 N) at ``--n``, run in once as it
    is (a translation) and once with ``[sliding] kind = "pin_on_disk"`` at
    each ``--track-radius`` (m), in one process, the cases taken in turn
    ``--repeat`` times (the best wall time of each is reported, so that the
    first run's set-up of the transforms does not count against one case):
    accepted steps, contact solves, solver iterations, iterations per solve
    and wall time, and the run's final face against the closed-form steady
    face.

How to run
    python studies/benchmarks/bench_sliding.py --n 256 --track-radius 0.006 0.02  # ~5 min
    python studies/benchmarks/bench_sliding.py --n 40 --track-radius 0.02 --repeat 1  # seconds

Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import time

import numpy as np

from steady import examples
from steady.sliding import PinOnDisk
from steady.solution import solve
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of

SCENE = examples.path("voronoi_transient")


def measure(scene, options, initial, n):
    """One run-in: its counters, wall time and the face's distance to the closed form."""
    problem = wear_problem_of(scene, n=n)
    start = time.perf_counter()
    result = run_in(problem, initial.recession(problem.grid), options)
    wall = time.perf_counter() - start
    mask = problem.face_mask
    steady = solve(problem.problem, face_only=True).face

    def shape(f):
        g = np.where(mask, f, 0.0)
        return g[mask] - g[mask].mean()

    a, b = shape(result.face), shape(steady)
    gap = float(np.sqrt(np.mean((a - b) ** 2) / np.mean(b ** 2)))
    return dict(steps=result.steps, solves=result.solves, iterations=result.iterations,
                per_solve=result.iterations / result.solves, wall=wall, gap=gap)


def main(argv=None):
    """Run the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=256)
    parser.add_argument("--track-radius", type=float, nargs="+", default=[0.006, 0.02])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args(argv)
    scene, options, initial = load_transient_scene(SCENE)
    cases = [("translation", scene)] + [
        (f"pin_on_disk R = {r:g} m", dataclasses.replace(scene, sliding=PinOnDisk(r)))
        for r in args.track_radius]
    print(f"{platform.processor() or platform.machine()}, n = {args.n}, {SCENE.name}, "
          f"F_N = {scene.normal_force:g} N")
    print("| kinematics | steps | solves | iterations | per solve | wall (s) | face vs "
          "closed form |")
    print("|---|---|---|---|---|---|---|")
    rows = {}
    for _ in range(args.repeat):
        for name, case in cases:
            row = measure(case, options, initial, args.n)
            if name in rows:
                row["wall"] = min(row["wall"], rows[name]["wall"])
            rows[name] = row
    for name, row in rows.items():
        print(f"| {name} | {row['steps']} | {row['solves']} | {row['iterations']} | "
              f"{row['per_solve']:.2f} | {row['wall']:.1f} | {row['gap']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
