"""Time of the multi-level Otsu thresholds of a micrograph against the number of phases.

What it reproduces
    docs/benchmarks.md, "Micrograph segmentation": :func:`steady.micrograph.segment`
    with Otsu's thresholds (256 histogram bins) on a seeded uniform-noise
    image of ``--size`` x ``--size`` pixels, for each number of phases in
    ``--phases``, the best of ``--repeat`` runs: the sets of thresholds its
    search tries, ``C(256, P - 1)``, the wall time and the time per set, from
    which :data:`steady.micrograph.OTSU_MAX_SETS` was chosen.  The last line
    gives the time that limit and the first refused count would take at the
    time per set of the largest search measured (smaller ones are dominated
    by the histogram and the labelling).

How to run
    python studies/benchmarks/bench_otsu.py --phases 2 3 4 5   # ~15 s
    python studies/benchmarks/bench_otsu.py --phases 2 3 --repeat 1   # a second

Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import math
import platform
import time

import numpy as np

from steady.micrograph import OTSU_MAX_SETS, segment

BINS = 256
SEED = 3517


def main(argv=None):
    """Print the table; return its rows (``phases``, ``sets``, ``wall`` s, ``per_set`` s)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--phases", type=int, nargs="+", default=[2, 3, 4, 5])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args(argv)
    image = np.random.default_rng(SEED).random((args.size, args.size))
    print(f"{platform.processor() or platform.machine()}, {args.size} x {args.size} pixels, "
          f"{BINS} bins")
    print("| phases | sets C(256, P - 1) | wall (s) | per set (s) |")
    print("|---|---|---|---|")
    rows = []
    for phases in args.phases:
        walls = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            segment(image, phases)
            walls.append(time.perf_counter() - start)
        sets = math.comb(BINS, phases - 1)
        row = dict(phases=phases, sets=sets, wall=min(walls), per_set=min(walls) / sets)
        rows.append(row)
        print(f"| {phases} | {sets:.3g} | {row['wall']:.3g} | {row['per_set']:.2g} |",
              flush=True)
    per_set = max(rows, key=lambda row: row["sets"])["per_set"]
    refused = next(p for p in range(2, BINS) if math.comb(BINS, p - 1) > OTSU_MAX_SETS)
    print(f"\nOTSU_MAX_SETS = {OTSU_MAX_SETS:.0e}: {OTSU_MAX_SETS * per_set:.3g} s at "
          f"{per_set:.2g} s per set; {refused} phases, refused, would take "
          f"{math.comb(BINS, refused - 1) * per_set:.3g} s")
    return rows


if __name__ == "__main__":
    main()
