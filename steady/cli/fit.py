"""The command ``runin-fit``: wear ratios from a measured worn face (:mod:`steady.fit`).

Usage (``runin-fit`` once installed, or ``python -m steady.cli.fit``)::

    runin-fit SCENE.toml MEASURED -o FIT.h5 [--pixel-size DX [DY]] [--height-scale S]
              [--plot FIT.png] [--shift] [--max-shift M] [--rim-margin M] [--n N]
              [--reference-phase I] [--confidence C] [--force] [--memory-limit GIB] [-v]

Reads the measured map (:func:`steady.fit_files.read_measured`), fits the
scene's steady model to it (:func:`steady.fit.fit_scene`), writes the fit
file (:func:`steady.fit_files.write_fit`), optionally draws its figure and
prints the ratios with their intervals.  Checked before the fit: the paths
(no output may name an input or the other output, ``--plot`` must be a
``.png``, outputs as :func:`steady.cli.common.prepare_output`), the scene,
the measured map and the memory the fit needs
(:func:`steady.memory.fit_memory`).  A failed fit (a fitted pressure not
positive, a ratio the map does not determine, a figure that is not finite)
still writes its file and prints its summary on stdout, then one line
``error: ...`` on stderr, exit status 1.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m steady.cli.fit: Ctrl-C handled from here on
    from .entry import runin_fit

    raise SystemExit(runin_fit())

import pathlib

from ..fit import MAX_SHIFT, RIM_MARGIN, fit_scene
from ..fit_files import plot_fit, read_measured, write_fit
from ..memory import check_memory, fit_memory
from ..scene import load_scene
from .common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_STATUS_EPILOG,
    ArgumentParser,
    CommandError,
    add_memory_limit,
    check_distinct,
    check_figure_path,
    configure_logging,
    describe_os_error,
    key_type,
    note,
    prepare_output,
    program_name,
    read_input,
    run_command,
)

__all__ = ["build_parser", "main"]



def build_parser():
    """The argument parser of ``runin-fit`` (``python -m steady.cli.fit``)."""
    parser = ArgumentParser(
        prog=program_name("python -m steady.cli.fit"),
        description="Wear-coefficient ratios that best explain a measured worn face "
                    "(least squares over the phase pressures of the steady face, eq. 7, 9).",
        epilog=EXIT_STATUS_EPILOG)
    parser.add_argument("scene", type=pathlib.Path,
                        help="scene file (.toml): face outline, phase map, E*, load, exponent")
    parser.add_argument("measured", type=pathlib.Path,
                        help="measured height map: .npy, text grid (.txt .csv .dat .asc) or a "
                             "profilometer file (needs runin[surface])")
    parser.add_argument("-o", "--output", type=pathlib.Path, required=True,
                        help="HDF5 fit file to write")
    parser.add_argument("--pixel-size", type=float, nargs="+", metavar="M",
                        help="pixel size of the map, m (one value, or DX DY); required for "
                             ".npy and text grids")
    parser.add_argument("--height-scale", type=float, default=1.0, metavar="S",
                        help="metres per height unit of a .npy or text grid (default 1; 1e-6 "
                             "for micrometres)")
    parser.add_argument("--plot", type=pathlib.Path, metavar="FIGURE",
                        help="also draw measured, fitted and residual faces into this figure "
                             "(.png, .pdf or .svg)")
    parser.add_argument("--shift", action="store_true",
                        help="search the lateral shift of the phase map that fits best")
    parser.add_argument("--max-shift", type=key_type(MAX_SHIFT), metavar="M",
                        help="search radius of --shift, m (default 5 %% of the face's scale: the "
                             "radius of a disk, else half the longer side of its bounding box)")
    parser.add_argument("--rim-margin", type=key_type(RIM_MARGIN), default=0.0, metavar="M",
                        help="leave out the points within M of the face's rim, m (default 0)")
    parser.add_argument("--n", type=int, help="model grid, pixels along the longer side of "
                                              "the face's box (default: the scene's n)")
    parser.add_argument("--reference-phase", type=int, default=0, metavar="I",
                        help="the phase the ratios refer to (default 0)")
    parser.add_argument("--confidence", type=float, default=0.95,
                        help="level of the intervals (default 0.95)")
    parser.add_argument("--force", action="store_true", help="overwrite existing output files")
    add_memory_limit(parser)
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log progress (-v) or details (-vv) to stderr")
    return parser


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    # Everything that can fail is checked before the fit, not after it.
    check_distinct([("the scene", args.scene), ("the measured map", args.measured),
                    ("-o", args.output), ("--plot", args.plot)])
    if args.plot is not None:
        check_figure_path(args.plot, "--plot")
    if args.pixel_size is not None and len(args.pixel_size) > 2:
        raise ValueError(f"--pixel-size takes one or two values, got {len(args.pixel_size)}")
    prepare_output(args.output, force=args.force)
    if args.plot is not None:
        prepare_output(args.plot, force=args.force, what="--plot")
    scene = read_input(load_scene, args.scene)
    if scene.ignored_sections:
        note("ignoring run-in sections "
             + ", ".join(f"[{name}]" for name in scene.ignored_sections))
    measured = read_input(read_measured, args.measured, pixel_size=args.pixel_size,
                          height_scale=args.height_scale)
    grid = scene.grid(args.n)
    check_memory(fit_memory(grid.shape, scene.n_phases, measured.shape),
                 f"a fit at n = {grid.n} of a {measured.shape[0]} x {measured.shape[1]} map",
                 args.memory_limit)
    saved = None
    try:
        result = fit_scene(scene, measured, n=args.n, search_shift=args.shift,
                           max_shift=args.max_shift, rim_margin=args.rim_margin,
                           reference_phase=args.reference_phase, confidence=args.confidence)
        write_fit(args.output, result, scene, force=args.force, checked=True)
        saved = args.output
        lines = (result.summary_lines(scene.phase_names)
                 + [f"result           {args.output}"])
        if args.plot:
            try:
                plot_fit(args.output, args.plot, force=args.force)
            except OSError as err:
                raise CommandError(f"cannot draw the figure: {describe_os_error(err)}; the "
                                   f"fit is saved in {str(saved)!r}", EXIT_FAILED) from None
            lines.append(f"figure           {args.plot}")
    except KeyboardInterrupt:
        where = "nothing was written" if saved is None else f"the fit is in {str(saved)!r}"
        raise CommandError(f"interrupted; {where}", EXIT_INTERRUPTED) from None
    print("\n".join(lines))
    if not result.success:
        raise CommandError(f"the fit failed: {result.message}; its file is "
                           f"{str(args.output)!r}", EXIT_FAILED)
    return EXIT_OK


def main(argv=None):
    """Entry point of ``runin-fit`` and ``python -m steady.cli.fit``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status (:mod:`steady.cli.common`): 0; 1 when the fit failed
        (a fitted pressure not positive, a ratio the map does not
        determine, a figure that is not finite: the file is written, the
        summary printed, the reason on stderr) or the operating system
        refused a read or write; 2 for bad input, nothing written (a map
        that cannot cover the face, a phase the fit cannot determine,
        heights out of range, too little memory, ...); 130 when
        interrupted.  Every failure ends with one line ``error: ...`` on
        stderr.
    """
    args = build_parser().parse_args(argv)
    configure_logging(args.verbose)
    return run_command(run, args, verbose=args.verbose)

