"""Run-in work of the threshold wear law beside Archard's, on the same scene and grid.

What it reproduces
    docs/benchmarks.md, "Run-in with a threshold wear law": the shipped
    scene ``steady/examples/voronoi_transient.toml`` (its ``[transient]``
    settings, flat start to the steady state, no checkpoints) at each grid
    ``n``, run once with its own law (Archard's, ``k = 1e-13, 1e-12 1/Pa``)
    and once with the threshold law of the same coefficients and the
    thresholds ``THRESHOLDS`` (in units of the mean pressure ``pbar``; the
    flat punch's central pressure, about ``pbar / 2``, lies below both, so
    the pressures cross them).  Per run: status, accepted and rejected
    steps, contact solves, solver iterations, iterations per solve, run-in
    distance (in ``s*``) and wall time; the laws alternate within each grid
    so that both see the same load on the machine.

How to run
    python studies/benchmarks/bench_wear_laws.py --sizes 256 512    # ~10 min on 2 cores
    python studies/benchmarks/bench_wear_laws.py --sizes 32 --out /tmp/b.h5   # seconds

Writes ``--out`` (HDF5: one group per row; refuses to replace a file
without ``--force``) and prints the table in Markdown.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import pathlib
import platform
import sys
import time

import numpy as np

from steady.safe_files import atomic_h5
from steady.wear import ThresholdLaw
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of

# -- parameters -------------------------------------------------------------------
SCENE = (pathlib.Path(__file__).resolve().parents[2] / "steady" / "examples"
         / "voronoi_transient.toml")
SIZES = (256,)
THRESHOLDS = (0.6, 0.8)   # p_th,i / pbar of phases 0 and 1

logger = logging.getLogger("bench_wear_laws")


def laws(scene):
    """The scene's own law and the threshold law of the same coefficients, by name."""
    pbar = scene.normal_force / scene.outline.area
    threshold = ThresholdLaw(scene.wear.coefficients, tuple(t * pbar for t in THRESHOLDS),
                             scene.wear.exponent)
    return {"archard": scene.wear, "threshold": threshold}


def run_row(scene, options, initial, n, name, law):
    """One run to the steady state and its work, a dict."""
    problem = wear_problem_of(dataclasses.replace(scene, wear=law), n=n)
    t = time.perf_counter()
    result = run_in(problem, initial.recession(problem.grid), options)
    wall = time.perf_counter() - t
    return dict(n=n, law=name, status=result.status, steps=result.steps,
                rejected=result.rejected, failures=result.failures, solves=result.solves,
                iterations=result.iterations,
                per_solve=result.iterations / max(result.solves, 1),
                distance=result.distance / result.distance_scale, wall=wall)


def markdown_table(rows):
    """The rows as a Markdown table."""
    lines = ["| n | law | status | steps (rejected) | solves | iterations | per solve | "
             "s / s* | wall (s) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['law']} | {r['status']} | {r['steps']} "
                     f"({r['rejected']}) | {r['solves']} | {r['iterations']} | "
                     f"{r['per_solve']:.1f} | {r['distance']:.3g} | {r['wall']:.1f} |")
    return "\n".join(lines)


def main(argv=None):
    """Command line of the benchmark (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    list of dict
        The rows, Archard's and the threshold law's at each grid.
    """
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--scene", type=pathlib.Path, default=SCENE)
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("bench_wear_laws.h5"))
    parser.add_argument("--force", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    scene, options, initial = load_transient_scene(args.scene)
    options = dataclasses.replace(options, checkpoint_interval=1e9)
    rows = []
    for n in args.sizes:
        for name, law in laws(scene).items():
            rows.append(run_row(scene, options, initial, n, name, law))
            logger.info("%s", rows[-1])
    print(markdown_table(rows))
    meta = dict(machine=platform.processor() or platform.machine(),
                python=platform.python_version(), numpy=np.__version__,
                scene=str(args.scene), thresholds_over_pbar=np.array(THRESHOLDS),
                command=" ".join(sys.argv))
    with atomic_h5(args.out, format="runin.bench_wear_laws", version=1,
                   force=args.force) as f:
        f.attrs["wall_units"] = "s"
        f.attrs["distance_units"] = "s*"
        for key, value in meta.items():
            f.attrs[key] = value
        for i, row in enumerate(rows):
            group = f.create_group(f"{i:03d}")
            for key, value in row.items():
                group.attrs[key] = value
    return rows


if __name__ == "__main__":
    main()
