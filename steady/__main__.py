"""Command line: limiting worn face of the punch described by a scene file.

Usage (``runin-steady`` once installed, or ``python -m steady``)::

    runin-steady SCENE.toml -o OUT.h5 [--plot OUT.png] [--force] [--no-slope-error] [-v]

Solves the steady state (eq. 7, 9), writes the HDF5 result
(:mod:`steady.output`), optionally draws the figure from that file, and
prints a short summary.  The run-in sections of a scene (``[transient]``,
``[initial_face]``) are ignored, with a note on stderr.  Bad input gives
``error: ...`` on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import logging
import math
import pathlib
import sys

from .command_line import program_name
from .output import write_result
from .scene import load_scene
from .solution import solve_scene

__all__ = ["build_parser", "main", "summary_lines"]


class _Parser(argparse.ArgumentParser):
    """Argument errors as ``error: ...`` on stderr, exit status 2."""

    def error(self, message):
        self.exit(2, f"error: {message}\n{self.format_usage()}")


def build_parser():
    """The argument parser of ``runin-steady`` (``python -m steady``)."""
    parser = _Parser(
        prog=program_name("python -m steady"),
        description="Limiting worn face of a multi-phase punch on an elastic half-space.")
    parser.add_argument("scene", type=pathlib.Path, help="scene file (.toml)")
    parser.add_argument("-o", "--output", type=pathlib.Path, required=True,
                        help="HDF5 result file to write")
    parser.add_argument("--plot", type=pathlib.Path, metavar="PNG",
                        help="also draw the phase map and the face into this PNG file")
    parser.add_argument("--force", action="store_true",
                        help="overwrite existing output files")
    parser.add_argument("--no-slope-error", dest="slope_error", action="store_false",
                        help="report the plain pixel rms slope only (skips the corrected "
                             "estimate and its error bar, which cost a few more solves)")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log progress (-v) or details (-vv) to stderr")
    return parser


def summary_lines(result):
    """Short human-readable summary of a :class:`~steady.solution.SteadyResult`."""
    fill = ", ".join(f"{v:.4f}" for v in result.fill_factors)
    pressures = ", ".join(f"{v:.6g}" for v in result.phase_pressures)
    if math.isfinite(result.rms_slope_error):
        slope = (f"rms slope        {result.rms_slope:.6g} +- {result.rms_slope_error:.2g}"
                 f"  (plain pixel value {result.rms_slope_plain:.6g})")
    else:
        slope = f"rms slope        {result.rms_slope:.6g}  (plain pixel value, no error estimate)"
    return [
        slope,
        f"grad_f0          {result.reference_slope:.6g}  (4 pbar / (pi E*))",
        f"rms / grad_f0    {result.normalised_rms_slope:.6g}",
        f"fill factors     {fill}",
        f"phase pressures  {pressures} Pa",
    ]


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    outputs = [args.output] + ([args.plot] if args.plot else [])
    # Fail before the solve, not after it.
    for path in outputs:
        if path.exists() and not args.force:
            raise ValueError(f"output {str(path)!r} exists (use --force to overwrite)")
    if args.plot and args.plot.resolve() == args.output.resolve():
        raise ValueError(f"--plot and -o name the same file {str(args.output)!r}")
    scene = load_scene(args.scene)
    if scene.ignored_sections:
        print("note: ignoring run-in sections "
              + ", ".join(f"[{name}]" for name in scene.ignored_sections), file=sys.stderr)
    result = solve_scene(scene, slope_error=args.slope_error)
    lines = summary_lines(result)
    write_result(args.output, result, scene, force=args.force)
    lines.append(f"result           {args.output}")
    if args.plot:
        from .plotting import plot_file  # deferred: matplotlib is slow to import

        plot_file(args.output, args.plot, force=args.force)
        lines.append(f"figure           {args.plot}")
    print("\n".join(lines))
    return 0


def main(argv=None):
    """Entry point of ``runin-steady`` and ``python -m steady``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, 2 for bad input, 1 for an operating-system error.
    """
    args = build_parser().parse_args(argv)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    try:
        return run(args)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"error: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
