"""The command ``runin-design``: the fill factor for a target rms slope, and back.

Usage (``runin-design`` once installed, or ``python -m steady.cli.design``)::

    runin-design --pbar-over-estar 0.08 --wear-ratio 1e-2 --target-slope 1.0
    runin-design --pbar-over-estar 0.08 --wear-ratio 1e-2 --fill-factor 0.1

Answers from the design table (:class:`steady.design.DesignTable`, the one
shipped in the package by default).
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m steady.cli.design: Ctrl-C handled from here on
    from .entry import runin_design

    raise SystemExit(runin_design())

import numpy as np

from ..design import DEFAULT_TABLE, DesignTable
from ..reference import disk_reference_slope, fine_grain_rms_slope
from .common import EXIT_STATUS_EPILOG, ArgumentParser, program_name, read_input, run_command

__all__ = ["build_parser", "main"]


def build_parser():
    """The argument parser of ``runin-design`` (``python -m steady.cli.design``)."""
    parser = ArgumentParser(
        prog=program_name("python -m steady.cli.design"),
        description="Steady rms slope (friction proxy) of a biphasic punch: the fill factor "
                    "rho_1 of phase 1 that gives a target rms slope, or the rms slope of a "
                    "fill factor.  Phase 1 is the hard phase when the wear ratio is below 1.",
        epilog=EXIT_STATUS_EPILOG)
    parser.add_argument("--pbar-over-estar", type=float, required=True,
                        help="mean pressure over the effective modulus, pbar/E*")
    parser.add_argument("--wear-ratio", type=float, required=True,
                        help="k_1/k_0 (below 1: phase 1 wears less than phase 0)")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--target-slope", type=float, help="target steady rms slope")
    what.add_argument("--fill-factor", type=float, help="fill factor rho_1 of phase 1")
    parser.add_argument("--table", default=None,
                        help=f"design table (default {DEFAULT_TABLE})")
    return parser


def main(argv=None):
    """The command ``runin-design``: fill factor for a target rms slope, or the reverse.

    Entered through :mod:`steady.cli.entry` (``python -m steady.cli.design``
    too), which handles Ctrl-C while the modules load.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0; 1 when the operating system refuses to read the
        table; 2 for bad input or an unreadable table (one line ``error:
        ...`` on stderr); 130 when interrupted.
    """
    return run_command(_answer, build_parser().parse_args(argv))


def _answer(args):
    """Print the answer of the design rule for parsed arguments; return the exit status."""
    table = read_input(DesignTable.read, args.table)
    source = (f"table: {table.attrs.get('n_seeds', '?')} Voronoi seeds, "
              f"{table.attrs.get('realisations', '?')} realisations, "
              f"n = {table.attrs.get('n', '?')}")
    if args.target_slope is not None:
        res = table.fill_factor_for(args.pbar_over_estar, args.wear_ratio, args.target_slope)
        g0 = disk_reference_slope(args.pbar_over_estar, 1.0)  # grad_f0 of eq. 12
        lo, hi = res.fill_factor_range
        print(f"fill factor rho_1 = {res.fill_factor:.4g} "
              f"(realisation scatter: {lo:.4g}..{hi:.4g})")
        if len(res.solutions) > 1:
            print("other fill factors reaching the target: "
                  + ", ".join(f"{r:.4g}" for r in res.solutions[:-1]))
        print(f"target {args.target_slope:.4g} = {res.normalised_target:.4g} grad_f0, "
              f"grad_f0 = 4 pbar/(pi E*) = {g0:.4g}; reachable "
              f"{res.reachable[0]:.4g}..{res.reachable[1]:.4g}")
    else:
        if not np.isfinite(args.fill_factor):
            raise ValueError(f"fill factor must be finite, got {args.fill_factor!r}")
        value, sd = table.rms_slope(args.pbar_over_estar, args.wear_ratio, args.fill_factor)
        g0 = disk_reference_slope(args.pbar_over_estar, 1.0)
        fine = fine_grain_rms_slope([1 - args.fill_factor, args.fill_factor],
                                    [1.0, args.wear_ratio])
        print(f"rms slope = {value:.4g} +- {sd:.2g} (realisation scatter); "
              f"{value / g0:.4g} grad_f0, grad_f0 = {g0:.4g}")
        print(f"fine-grain closed form: {g0 * fine:.4g} ({fine:.4g} grad_f0)")
    print(source)
    return 0

