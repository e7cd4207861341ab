"""Command line: limiting worn face of the punch described by a scene file.

Usage (``runin-steady`` once installed, or ``python -m steady``)::

    runin-steady SCENE.toml -o OUT.h5 [--plot OUT.png] [--force] [--no-slope-error]
                 [--memory-limit GIB] [-v]

Solves the steady state (eq. 7, 9), writes the HDF5 result
(:mod:`steady.output`), optionally draws the figure from that file, and
prints a short summary.  The run-in sections of a scene (``[transient]``,
``[initial_face]``) are ignored, with a note on stderr.  Everything that can
be checked is checked before the solve: the scene, the output paths (a
directory, an existing file without ``--force``, an unwritable place) and
the memory the grid needs (:func:`steady.memory.steady_memory`).
A failure prints one line ``error: ...`` on stderr; exit status 0, 1 for an
operating-system error, 2 for bad input, 130 when interrupted
(:mod:`steady.cli.common`).
"""

from __future__ import annotations

import math
import pathlib

from ..memory import check_memory, steady_memory
from ..micrograph import Micrograph
from ..output import write_result
from ..scene import load_scene
from ..solution import solve_scene
from .common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    ArgumentParser,
    CommandError,
    add_memory_limit,
    check_distinct,
    configure_logging,
    describe_os_error,
    note,
    prepare_output,
    program_name,
    run_command,
)

__all__ = ["build_parser", "main", "summary_lines"]

_EPILOG = ("exit status: 0 done, 1 operating-system error (the message says what is saved), "
           "2 bad input (nothing written), 130 interrupted")


def build_parser():
    """The argument parser of ``runin-steady`` (``python -m steady``)."""
    parser = ArgumentParser(
        prog=program_name("python -m steady"),
        description="Limiting worn face of a multi-phase punch on an elastic half-space.",
        epilog=_EPILOG)
    parser.add_argument("scene", type=pathlib.Path, help="scene file (.toml)")
    parser.add_argument("-o", "--output", type=pathlib.Path, required=True,
                        help="HDF5 result file to write (missing directories are created)")
    parser.add_argument("--plot", type=pathlib.Path, metavar="PNG",
                        help="also draw the phase map and the face into this PNG file")
    parser.add_argument("--force", action="store_true",
                        help="overwrite existing output files")
    parser.add_argument("--no-slope-error", dest="slope_error", action="store_false",
                        help="report the plain pixel rms slope only (skips the corrected "
                             "estimate and its error bar, which cost a few more solves)")
    add_memory_limit(parser)
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
    if result.reference_slope_error > 0:
        ref = f"{result.reference_slope:.6g} +- {result.reference_slope_error:.2g}"
    else:
        ref = f"{result.reference_slope:.6g}"
    source = result.reference_slope_source or "disk: 4 pbar / (pi E*) (eq. 12)"
    return [
        f"face             {result.outline.describe()}, n = {result.n} "
        f"({result.shape[0]} x {result.shape[1]} pixels)",
        slope,
        f"grad_f0          {ref}  ({source})",
        f"rms / grad_f0    {result.normalised_rms_slope:.6g}",
        f"fill factors     {fill}",
        f"phase pressures  {pressures} Pa",
    ]


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    # Everything that can fail is checked before the solve, not after it.
    check_distinct([("the scene", args.scene), ("-o", args.output), ("--plot", args.plot)])
    scene = load_scene(args.scene)
    prepare_output(args.output, force=args.force)
    if args.plot is not None:
        prepare_output(args.plot, force=args.force, what="--plot")
    if scene.ignored_sections:
        note("ignoring run-in sections "
             + ", ".join(f"[{name}]" for name in scene.ignored_sections))
    check_memory(steady_memory(scene.grid().shape, slope_error=args.slope_error),
                 f"a steady solve at n = {scene.n}", args.memory_limit)
    scene.phase_labels()  # names a phase without a face pixel before the solve
    saved = None
    try:
        result = solve_scene(scene, slope_error=args.slope_error)
        lines = summary_lines(result)
        if isinstance(scene.geometry, Micrograph):
            lines.append(f"segmentation     {scene.geometry.segmentation.summary()}")
        write_result(args.output, result, scene, force=args.force, checked=True)
        saved = args.output
        lines.append(f"result           {args.output}")
        if args.plot:
            from ..plotting import plot_file  # deferred: matplotlib is slow to import

            try:
                plot_file(args.output, args.plot, force=args.force)
            except OSError as err:
                raise CommandError(f"cannot draw the figure: {describe_os_error(err)}; the "
                                   f"result is saved in {str(saved)!r}", EXIT_FAILED) from None
            lines.append(f"figure           {args.plot}")
    except KeyboardInterrupt:
        where = "nothing was written" if saved is None else f"the result is in {str(saved)!r}"
        raise CommandError(f"interrupted; {where}", EXIT_INTERRUPTED) from None
    print("\n".join(lines))
    return EXIT_OK


def main(argv=None):
    """Entry point of ``runin-steady`` and ``python -m steady``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, 1 for an operating-system error, 2 for bad input,
        130 when interrupted.
    """
    args = build_parser().parse_args(argv)
    configure_logging(args.verbose)
    return run_command(run, args, verbose=args.verbose)
