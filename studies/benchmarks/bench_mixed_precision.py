"""Mixed precision of the contact products: single-precision direction products, side by side.

What it reproduces
    docs/benchmarks.md, "Mixed precision of the contact products".

    ``--products``: the raw cost of one padded product ``K p`` of
    :class:`steady.halfspace.HalfSpace` (its own product: rows transformed on
    the grid's rows only, columns in place, the lines shared among the threads)
    against the same product in single precision (:class:`SingleHalfSpace`:
    the padded field float32, its transform and the influence spectrum
    complex64 / float32, the same transforms through :mod:`scipy.fft`, which keeps
    single precision), at each of ``--sizes``: CPU and wall time per product
    (the best of ``--repeats`` means of ``--count`` products, the two
    precisions alternated) and the single product's largest error over the
    largest displacement.

    ``--runs``: the run-in cases of ``bench_runin.py --levers`` (the shipped
    Voronoi scene with only ``n`` changed, and the homogeneous 1:2 rectangle
    from flat at ``tol = 1e-4``) at each of ``--sizes``, under four products
    of the contact solver: ``double`` (as shipped); ``mixed`` (each conjugate
    direction's product ``K t`` by :class:`SingleHalfSpace`, except in the
    iterations where the solver takes its preconditioner in double precision
    (a solve that must reduce its first residual by more than
    ``transient.contact._SINGLE_REDUCTION``, as a cold first solve does); the first
    iterate's ``K p`` and every recomputation of ``K p`` in double; the
    solver's bound on the drift of the incrementally updated ``K p`` taken
    with float32's machine epsilon, so that a residual within the tolerance is
    verified on a ``K p`` recomputed in double before a solve ends, and
    ``K p`` is recomputed every 50 iterations as before); ``mixed, step drift``
    (the same products, the drift bound of each single-precision step being
    ``8 eps_32 |tau| max |K t|``, the round-off of that step's update of
    ``K p``, instead of ``8 eps_32 max |K p|``); and ``mixed, unverified``
    (the same products, the drift bound left at float64's: a solve may end on
    the incrementally updated ``K p`` with no bound on the single round-off).
    ``--variants`` runs only those named.  Per run: steps,
    rejected attempts, solves, iterations, products in double and in single, the
    CPU time of the run and of its products, and the history change: the
    largest deviation of the corrected rms slope (``history["rms_slope"]``, in
    ``grad_f0``) at ``s/s* = 1e-4 .. 3`` from the double run of the same case.
    The variants of one case run one after the other in one process, the whole
    set ``--repeats`` times; the table gives the counts of the first repeat
    and, per variant, the ratios of the run's CPU time and of its products'
    to the first variant's run of the same repeat (median and range over the
    repeats).

How to run
    python studies/benchmarks/bench_mixed_precision.py --products --sizes 256 512 1024
    python studies/benchmarks/bench_mixed_precision.py --runs --sizes 256 512 --repeats 3
    python studies/benchmarks/bench_mixed_precision.py --runs --sizes 1024 --repeats 2 \
        --variants double "mixed, step drift"   # ~6 min
    python studies/benchmarks/bench_mixed_precision.py --products --runs --sizes 40 \
        --repeats 1   # smoke test, seconds

Prints the tables in Markdown.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import logging
import os
import platform
import time

import numpy as np
import scipy.fft
from bench_runin import SCENE, history_values, lever_cases, run_counted

from steady.halfspace import _SPLIT_ROWS, HalfSpace
from transient import contact

logger = logging.getLogger("bench_mixed_precision")
VARIANTS = ("double", "mixed", "mixed, step drift", "mixed, unverified")
# The drift bound of the incrementally updated K p (contact._ROUNDING_PER_ITERATION, in units of
# float64's epsilon) rescaled to float32's: a direction product carries float32 round-off.
_SINGLE_ROUNDING = np.finfo(np.float32).eps / np.finfo(np.float64).eps
# Bound of a single-precision product's error, in units of float32's epsilon times the largest
# entry of the product (measured: 3 to 4, ``--products``).
_SINGLE_PRODUCT_ROUNDING = 8.0


class SingleHalfSpace(HalfSpace):
    """:class:`HalfSpace`'s padded product in single precision, by :mod:`scipy.fft`.

    Built from a double-precision operator: the influence spectrum rounded to
    float32 (it is real), the padded rows float32, their spectrum complex64;
    the product's order of transforms (rows on the grid's rows only, then the
    padded columns, the inverse's columns, then the grid's rows), each by
    :mod:`scipy.fft` with the operator's ``workers`` (it keeps single
    precision; ``numpy.fft`` in float32 is slower than in float64 here:
    ``--products``).  :meth:`displacement` returns a float32 view.

    Parameters
    ----------
    halfspace : HalfSpace
        The operator, of fewer than ``_SPLIT_ROWS`` rows (the split product is
        not made single here).
    """

    def __init__(self, halfspace):  # noqa: D107 (the class says it)
        if halfspace.shape[0] >= _SPLIT_ROWS:
            raise ValueError(f"grid of {halfspace.shape[0]} rows: expected fewer than "
                             f"{_SPLIT_ROWS} (no single-precision split product)")
        self.__dict__.update(copy.copy(halfspace).__dict__)
        nx, ny = self.shape
        self._influence_q = halfspace._influence_q.astype(np.float32)
        self._rows = np.zeros((nx, 2 * ny), dtype=np.float32)
        self._work = np.zeros((2 * nx, ny + 1), dtype=np.complex64)

    def displacement(self, pressure_r):
        """``K p`` (m, float32, shape (nx, ny)) of a pressure (Pa, shape (nx, ny))."""
        (nx, ny), w = self.shape, self.workers
        self._rows[:, :ny] = pressure_r
        self._work[:nx] = scipy.fft.rfft(self._rows, axis=1, workers=w)
        self._work[nx:] = 0.0
        q = scipy.fft.fft(self._work, axis=0, workers=w, overwrite_x=True)
        q *= self._influence_q
        cols = scipy.fft.ifft(q, axis=0, workers=w, overwrite_x=True)[:nx]
        return scipy.fft.irfft(cols, n=2 * ny, axis=1, workers=w)[:, :ny]


# -- the raw product ----------------------------------------------------------------------------

def _timed(product, p, count):
    """CPU and wall time (s) per product, the mean of ``count``."""
    cpu, wall = time.process_time(), time.perf_counter()
    for _ in range(count):
        product(p)
    return (time.process_time() - cpu) / count, (time.perf_counter() - wall) / count


def product_table(sizes, repeats, count):
    """Rows: per grid, the best CPU and wall time of a product in each precision, and the error."""
    rows = []
    rng = np.random.default_rng(0)
    for n in sizes:
        double = HalfSpace(n, 1e-5, 1e11)
        single = SingleHalfSpace(double)
        p = rng.random((n, n))
        reference = double.displacement(p).copy()
        error = float(np.abs(single.displacement(p) - reference).max() / np.abs(reference).max())
        best = {name: [np.inf, np.inf] for name in ("double", "single")}
        for _ in range(repeats):
            for name, hs in (("double", double), ("single", single)):
                cpu, wall = _timed(hs.displacement, p, count)
                best[name] = [min(best[name][0], cpu), min(best[name][1], wall)]
        row = dict(n=n, error=error, **{f"{k}_{m}": v for k, (c, w) in best.items()
                                        for m, v in (("cpu", c), ("wall", w))})
        rows.append(row)
        logger.info("products n = %d: %s", n, row)
    return rows


def markdown_products(rows):
    """The raw product table in Markdown."""
    lines = ["| n | padded grid | double: CPU, wall (ms) | single: CPU, wall (ms) "
             "| CPU ratio single / double | wall ratio | single error / max K p |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {2 * r['n']} x {2 * r['n']} | "
                     f"{1e3 * r['double_cpu']:.2f}, {1e3 * r['double_wall']:.2f} | "
                     f"{1e3 * r['single_cpu']:.2f}, {1e3 * r['single_wall']:.2f} | "
                     f"{r['single_cpu'] / r['double_cpu']:.2f} | "
                     f"{r['single_wall'] / r['double_wall']:.2f} | {r['error']:.1e} |")
    return "\n".join(lines)


# -- the runs -----------------------------------------------------------------------------------

@contextlib.contextmanager
def contact_products(variant):
    """The contact solver's products as ``variant`` makes them, timed; yields the counts.

    ``counts``: ``single`` (direction products in single precision), ``accurate``
    (the solver's accuracy switch at the last direction) and
    ``cpu`` (s, the process's CPU time inside the solver's products).
    """
    call = contact._Operator.__call__
    update_direction = contact._update_direction
    rounding = contact._ROUNDING_PER_ITERATION
    singles = {}
    counts = {"single": 0, "cpu": 0.0, "accurate": False, "last_single": False}

    def direction(problem, state, r, active, work, accurate=False):
        # The solver's own accuracy switch (contact._SINGLE_REDUCTION): the direction's
        # product follows the preconditioner's precision.
        counts["accurate"] = accurate
        return update_direction(problem, state, r, active, work, accurate=accurate)

    def timed(self, p, *, contiguous=True):
        start = time.process_time()
        try:
            counts["last_single"] = not (contiguous or variant == "double"
                                         or counts["accurate"])
            if not counts["last_single"]:
                return call(self, p, contiguous=contiguous)
            self.products += 1
            counts["single"] += 1
            hs = self.halfspace
            single = singles.get(id(hs))
            if single is None or single[0] is not hs:
                single = singles[id(hs)] = (hs, SingleHalfSpace(hs))
            return single[1].displacement(p).astype(np.float64)
        finally:
            counts["cpu"] += time.process_time() - start

    take_step, stopping_rule = contact._take_step, contact._stopping_rule
    init, recompute = contact._State.__init__, contact._State.recompute_displacement
    drift = {}

    def fresh(state, p, v):
        init(state, p, v)
        drift[id(state)] = 0.0

    def step(state, q, tau, work):
        take_step(state, q, tau, work)
        if counts["last_single"]:
            drift[id(state)] = drift.get(id(state), 0.0) + (
                _SINGLE_PRODUCT_ROUNDING * np.finfo(np.float32).eps * abs(tau)
                * contact._largest_magnitude(q))

    def refreshed(state, operator):
        recompute(state, operator)
        drift[id(state)] = 0.0

    def rule(residual, tolerance, state):
        # contact._stopping_rule with the single-precision steps' drift added.
        bound = (state.since_full * contact._ROUNDING_PER_ITERATION * np.finfo(float).eps
                 * state.v_max + drift.get(id(state), 0.0))
        if residual <= tolerance and (state.verified or bound < 1e-3 * tolerance):
            return contact._CONVERGED
        if (residual <= tolerance and not state.verified) or state.since_full >= contact._REFRESH:
            return contact._RECOMPUTE
        return contact._ITERATE

    contact._Operator.__call__ = timed
    contact._update_direction = direction
    if variant == "mixed, step drift":
        contact._take_step, contact._stopping_rule = step, rule
        contact._State.__init__, contact._State.recompute_displacement = fresh, refreshed
    if variant == "mixed":
        contact._ROUNDING_PER_ITERATION = rounding * _SINGLE_ROUNDING
    try:
        yield counts
    finally:
        contact._Operator.__call__ = call
        contact._update_direction = update_direction
        contact._take_step, contact._stopping_rule = take_step, stopping_rule
        contact._State.__init__, contact._State.recompute_displacement = init, recompute
        contact._ROUNDING_PER_ITERATION = rounding


def run_table(sizes, repeats, variants=VARIANTS):
    """Rows: per case, variant and repeat, the run's work, CPU times and history change.

    ``variants``: names of :data:`VARIANTS`, the first the base of the change.
    """
    cases = list(lever_cases(SCENE, sizes))
    rows = []
    for repeat in range(repeats):
        for n, case, problem, initial, options in cases:
            base = None
            for variant in variants:
                with contact_products(variant) as counts:
                    result, row = run_counted(problem, initial, options)
                values = history_values(result)
                base = values if base is None else base
                row.update(n=n, case=case, variant=variant, repeat=repeat,
                           single=counts["single"], product_cpu=counts["cpu"],
                           change=float(np.nanmax(np.abs(values - base))))
                rows.append(row)
                logger.info("%s n = %d %s #%d: %s", case, n, variant, repeat, row)
    return rows


def markdown_runs(rows):
    """The run table in Markdown: counts of the first repeat, CPU ratios over all."""
    lines = ["| case | n | products | steps (rejected) | solves | iterations "
             "| products: double, single | CPU (s) | products' CPU share | CPU / first, median "
             "[range] | products' CPU / first | change, grad_f0 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    keys = dict.fromkeys((r["case"], r["n"], r["variant"]) for r in rows)
    for case, n, variant in keys:
        runs = [r for r in rows if (r["case"], r["n"], r["variant"]) == (case, n, variant)]
        doubles = {r["repeat"]: r for r in rows
                   if (r["case"], r["n"], r["variant"]) == (case, n, rows[0]["variant"])}
        ratios = [r["cpu"] / doubles[r["repeat"]]["cpu"] for r in runs]
        product_ratios = [r["product_cpu"] / doubles[r["repeat"]]["product_cpu"] for r in runs]
        first = runs[0]
        lines.append(f"| {case} | {n} | {variant} | {first['steps']} ({first['rejected']}) | "
                     f"{first['solves']} | {first['iterations']} | {first['products']}, "
                     f"{first['single']} | {np.median([r['cpu'] for r in runs]):.1f} | "
                     f"{np.median([r['product_cpu'] / r['cpu'] for r in runs]):.2f} | "
                     f"{np.median(ratios):.2f} [{min(ratios):.2f}, {max(ratios):.2f}] | "
                     f"{np.median(product_ratios):.2f} [{min(product_ratios):.2f}, "
                     f"{max(product_ratios):.2f}] | "
                     f"{max(r['change'] for r in runs):.1e} |")
    return "\n".join(lines)


def main(argv=None):
    """Command line: see the module docstring; returns the tables' rows by name."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--products", action="store_true", help="the raw product table")
    parser.add_argument("--runs", action="store_true", help="the run-in table")
    parser.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS),
                        help="the runs' products, the first the base of the change")
    parser.add_argument("--count", type=int, default=20, help="products per timing")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"numpy {np.__version__}, load average {os.getloadavg()[0]:.1f}")
    tables = {}
    if args.products:
        tables["products"] = product_table(args.sizes, max(args.repeats, 5), args.count)
        print(markdown_products(tables["products"]))
    if args.runs:
        tables["runs"] = run_table(args.sizes, args.repeats, args.variants)
        print(markdown_runs(tables["runs"]))
    return tables


if __name__ == "__main__":
    main()
