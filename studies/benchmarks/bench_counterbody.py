"""Set-up cost of the layered counter-body's operator against one contact solve.

For each grid, a flat disk punch (radius ``a``) on layers of thickness ``2 h``
and ``a / 2`` (``nu = 0.5``): the CPU time to build the layer's influence and
gradient coefficients (:class:`steady.counterbody.LayeredHalfSpace`, the
tabulation of its kernel excluded: it is made once per ``nu``, the first
line), the half-space's (:class:`steady.halfspace.HalfSpace`) and one
contact solve of the flat punch on the layer (:func:`transient.contact.solve_contact`,
its default tolerance), alternated in one process.

Run::

    python studies/benchmarks/bench_counterbody.py            # about a minute
    python studies/benchmarks/bench_counterbody.py --quick    # a few seconds

Prints a Markdown table.
"""

import argparse
import sys
import time

import numpy as np

from steady.counterbody import LayeredHalfSpace
from steady.halfspace import HalfSpace
from steady.outline import Circle
from transient.contact import solve_contact

GRIDS = [64, 128, 256, 512]
QUICK_GRIDS = [32, 64]
POISSON = 0.5


def _cpu(fn, *args):
    """``(fn(*args), CPU seconds)``."""
    start = time.process_time()
    out = fn(*args)
    return out, time.process_time() - start


def _operator(grid, thickness):
    """The layer's operator (the half-space's without a thickness), gradient spectra built."""
    if thickness is None:
        operator = HalfSpace(grid.shape, grid.h, 1.0)
    else:
        operator = LayeredHalfSpace(grid.shape, grid.h, 1.0, thickness, POISSON)
    operator.gradient(np.zeros(grid.shape))
    return operator


def main(argv=None):
    """Print the table; exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small grids only")
    args = parser.parse_args(argv)
    # The kernel's table is made on the first layer of a nu: an 8 x 8 grid here.
    _, table = _cpu(_operator, Circle(1.0).grid(8), 1.0)
    print(f"kernel table (once per nu): {table:.2f} s CPU\n")
    print("| n | t | layer coefficients (s) | half-space (s) | one contact solve on the layer "
          "(s, iterations) |")
    print("|---|---|---|---|---|")
    for n in QUICK_GRIDS if args.quick else GRIDS:
        grid = Circle(1.0).grid(n)
        for label, t in (("2 h", 2 * grid.h), ("a / 2", 0.5)):
            layer, cost = _cpu(_operator, grid, t)
            _, half_cost = _cpu(_operator, grid, None)
            res, solve_cost = _cpu(solve_contact, layer, grid.mask, np.zeros(grid.shape), 1.0)
            print(f"| {n} | {label} | {cost:.3f} | {half_cost:.3f} | {solve_cost:.3f} "
                  f"({res.nit}) |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
