"""Command line: limiting worn face of the punch described by a scene file.

Usage (``runin-steady`` once installed, or ``python -m steady``)::

    runin-steady SCENE.toml -o OUT.h5 [--plot OUT.png] [--force] [--no-slope-error]
                 [--memory-limit GIB] [-v]
    runin-steady SCENE.toml --segmentation SEG.png    # a micrograph's segmentation only

Solves the steady state (eq. 7, 9), writes the HDF5 result
(:mod:`steady.output`), optionally draws the figure from that file, and
prints a short summary.  The run-in sections of a scene (``[transient]``,
``[initial_face]``) are ignored, with a note on stderr.  Everything that can
be checked is checked before the solve: the scene, the output paths (a
directory, an existing file without ``--force``, an unwritable place) and
the memory the grid needs (:func:`steady.memory.steady_memory`).
A failure prints one line ``error: ...`` on stderr; exit status 0, 1 for an
operating-system error or a figure that could not be drawn (the message
says the result is saved), 2 for bad input (nothing written), 130 when
interrupted (:mod:`steady.cli.common`).  The suffix of ``--plot`` is
checked before the solve too (:func:`steady.cli.common.check_figure_path`).
``--segmentation`` draws the segmentation of a ``micrograph`` phase map
over its image (:func:`steady.plotting.segmentation_figure`) before the
solve; without ``-o`` it is all the command writes.
"""

from __future__ import annotations

import logging
import math
import pathlib
import time

from steady.scene import problem_of

from ..memory import check_memory, keep_freed_memory, steady_memory
from ..output import write_result
from ..problem import default_phase_names
from ..scene import load_scene
from ..schema import Key
from ..solution import solve_scene
from .common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_STATUS_EPILOG,
    ArgumentParser,
    CommandError,
    add_grid_flag,
    add_memory_limit,
    check_distinct,
    check_figure_path,
    configure_logging,
    describe_os_error,
    note,
    prepare_output,
    program_name,
    read_input,
    run_command,
)

__all__ = ["build_parser", "main", "summary_lines"]

logger = logging.getLogger(__name__)

#: The depth of the section solved (``--depth``).
_DEPTH = Key("--depth", "number", unit="m", low=0.0, low_open=False)

def build_parser():
    """The argument parser of ``runin-steady`` (``python -m steady``)."""
    parser = ArgumentParser(
        prog=program_name("python -m steady"),
        description="Limiting worn face of a multi-phase punch on an elastic half-space.",
        epilog=EXIT_STATUS_EPILOG)
    parser.add_argument("scene", type=pathlib.Path, help="scene file (.toml)")
    parser.add_argument("-o", "--output", type=pathlib.Path,
                        help="HDF5 result file to write (missing directories are created); "
                             "required unless --segmentation is given")
    parser.add_argument("--plot", type=pathlib.Path, metavar="FIGURE",
                        help="also draw the phase map and the face into this figure (.png, .pdf "
                             "or .svg)")
    parser.add_argument("--segmentation", type=pathlib.Path, metavar="FIGURE",
                        help="draw the segmentation of the micrograph phase map over its image "
                             "into this figure (.png, .pdf or .svg), before the solve (without "
                             "-o: only this)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite existing output files")
    parser.add_argument("--no-slope-error", dest="slope_error", action="store_false",
                        help="skip the corrected rms slope and its error bar, which cost a "
                             "few more solves (rms_slope is then NaN; the plain pixel value is "
                             "still reported as such)")
    parser.add_argument("--depth", type=float, default=0.0, metavar="M",
                        help="for a phase map that changes with depth ([depth], a 3-d map "
                             "kind): solve the section at this worn depth below the initial "
                             "surface, m (default 0, the surface): its quasi-steady face")
    add_grid_flag(parser)
    add_memory_limit(parser)
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log progress (-v) or details (-vv) to stderr")
    return parser


def summary_lines(result, names=None):
    """Short human-readable summary of a :class:`~steady.solution.SteadyResult`.

    Parameters
    ----------
    result : steady.solution.SteadyResult or steady.output.StoredResult
    names : sequence of str, optional
        A name for each phase (a scene's ``[phases] names``); default the
        result's own (a stored result's), else ``("phase 0", "phase 1", ...)``.
    """
    names = tuple(names or getattr(result, "phase_names", None)
                  or default_phase_names(result.n_phases))
    fill = ", ".join(f"{name} {v:.4f}" for name, v in zip(names, result.fill_factors,
                                                            strict=True))
    rows = list(zip(names, result.phase_pressures, result.fill_factors, strict=True))
    pressures = ", ".join(f"{name} {v:.6g}" for name, v, fill in rows if fill > 0) + " Pa"
    absent = [name for name, _, fill in rows if fill == 0]  # a section may lack a phase
    if absent:
        pressures += f"; no pixel in this section: {', '.join(absent)}"
    plain = f"plain pixel value {result.rms_slope_plain:.6g}"
    if math.isnan(result.rms_slope):
        slope = f"rms slope        not estimated  ({plain})"
    elif math.isfinite(result.rms_slope_error):
        slope = (f"rms slope        {result.rms_slope:.6g} +- {result.rms_slope_error:.2g}"
                 f"  ({plain})")
    else:
        slope = f"rms slope        {result.rms_slope:.6g}  (no error bar; {plain})"
    if result.reference_slope_error > 0:
        ref = f"{result.reference_slope:.6g} +- {result.reference_slope_error:.2g}"
    else:
        ref = f"{result.reference_slope:.6g}"
    source = result.reference_slope_source or "disk: 4 pbar / (pi E*) (eq. 12)"
    thickness = getattr(result, "thickness", None)
    layer = ([] if thickness is None else
             [f"counter-body     layer of thickness {thickness:.6g} m on a rigid flat, nu = "
              f"{result.poisson:.6g} (grad_f0 is the half-space's)"])
    return [
        f"face             {result.outline.describe()}, n = {result.n} "
        f"({result.shape[0]} x {result.shape[1]} pixels)",
        *layer,
        slope,
        f"grad_f0          {ref}  ({source})",
        f"rms / grad_f0    {result.normalised_rms_slope:.6g}"
        + ("" if math.isfinite(result.rms_slope)
           else f"  (plain pixel value {result.normalised_rms_slope_plain:.6g})"),
        f"fill factors     {fill}",
        f"phase pressures  {pressures}",
    ]


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    saved = None
    try:
        scene, problem = _check(args)
        logger.info("scene %s checked: %s, n = %d, %d phases", args.scene,
                    scene.outline.describe(), scene.n, scene.n_phases)
        if args.segmentation is not None:
            _draw_segmentation(args, scene)
            if args.output is None:
                print(f"segmentation     {scene.geometry.segmented_image().summary()}\n"
                      f"segmentation PNG {args.segmentation}")
                return EXIT_OK
        started = time.monotonic()
        logger.info("solving the steady state%s", " and the rms slope's error ladder"
                    if args.slope_error else "")
        result = solve_scene(scene, face_only=not args.slope_error, problem=problem)
        logger.info("solved in %.3g s: rms slope %.6g", time.monotonic() - started,
                    result.rms_slope)
        lines = summary_lines(result, scene.phase_names)
        if problem.phases.columns is not None:
            lines.insert(1, f"section          {args.depth:.6g} m below the initial surface: "
                            f"the quasi-steady face of this section")
        segmentation = scene.geometry.segmented_image()
        if segmentation is not None:
            lines.append(f"segmentation     {segmentation.summary()}")
        if args.segmentation is not None:
            lines.append(f"segmentation PNG {args.segmentation}")
        write_result(args.output, result, scene, force=args.force, checked=True)
        saved = args.output
        logger.info("wrote %s", args.output)
        lines.append(f"result           {args.output}")
        if args.plot:
            logger.info("drawing %s", args.plot)
            _plot(args)
            lines.append(f"figure           {args.plot}")
    except KeyboardInterrupt:
        where = "nothing was written" if saved is None else f"the result is in {str(saved)!r}"
        raise CommandError(f"interrupted; {where}", EXIT_INTERRUPTED) from None
    print("\n".join(lines))
    return EXIT_OK


def _check(args):
    """Everything that can fail, checked before the solve, not after it; the scene and problem."""
    check_distinct([("the scene", args.scene), ("-o", args.output), ("--plot", args.plot),
                    ("--segmentation", args.segmentation)])
    for path, what in ((args.plot, "--plot"), (args.segmentation, "--segmentation")):
        if path is not None:
            check_figure_path(path, what)
    scene = read_input(load_scene, args.scene, n=args.n)
    if args.segmentation is not None and scene.geometry.segmented_image() is None:
        raise ValueError(f"--segmentation needs a phase map of kind \"micrograph\", the "
                         f"scene's is {scene.geometry.kind!r}")
    for path, what in ((args.output, "output"), (args.plot, "--plot"),
                       (args.segmentation, "--segmentation")):
        if path is not None:
            prepare_output(path, force=args.force, what=what)
    if scene.ignored_sections:
        note("ignoring run-in sections "
             + ", ".join(f"[{name}]" for name in scene.ignored_sections))
    check_memory(steady_memory(scene.grid().shape, slope_error=args.slope_error,
                               periodic=scene.outline.periodic),
                 f"a steady solve at n = {scene.n}", args.memory_limit)
    _DEPTH.parse(args.depth, "", scale=False)  # a depth has no scale range: 0 is the surface
    # Names a phase without a face pixel before the solve; the solve takes its map.
    problem = problem_of(scene)
    if problem.phases.columns is not None:
        problem = problem.section(args.depth)
    elif args.depth > 0:
        note(f"the phase map does not change with depth: --depth {args.depth:g} m solves the "
             f"same face as the surface")
    return scene, problem


def _draw_segmentation(args, scene):
    """Draw the micrograph's segmentation over its image (before the solve, or alone)."""
    from ..plotting import save_new, segmentation_figure  # deferred: matplotlib is slow

    figure = segmentation_figure(scene.geometry, names=scene.phase_names)
    save_new(figure, args.segmentation, force=True)  # the path was checked before


def _plot(args):
    """Draw the figure of the result just written; the result is saved whatever happens here."""
    from ..plotting import plot_file  # deferred: matplotlib is slow to import

    saved = f"the result is saved in {str(args.output)!r}"
    if args.plot.exists() and not args.force:  # it was not there before the solve
        raise CommandError(f"--plot {str(args.plot)!r} appeared during the solve (use --force "
                           f"to overwrite); {saved}", EXIT_FAILED)
    try:
        plot_file(args.output, args.plot, force=args.force)
    except OSError as err:
        raise CommandError(f"cannot draw the figure: {describe_os_error(err)}; {saved}",
                           EXIT_FAILED) from None
    except ValueError as err:
        raise CommandError(f"cannot draw the figure: {err}; {saved}", EXIT_FAILED) from None


def main(argv=None):
    """The command ``runin-steady`` (``python -m steady``; entered through :mod:`steady.cli.entry`).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, 1 for an operating-system error or a figure that
        could not be drawn (the result is saved), 2 for bad input, 130 when
        interrupted.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.output is None and (args.segmentation is None or args.plot is not None):
        parser.error("the following arguments are required: -o/--output")
    configure_logging(args.verbose)
    keep_freed_memory()  # the solve allocates grid-sized transforms over and over
    return run_command(run, args, verbose=args.verbose)
