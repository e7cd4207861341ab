"""Command line: run-in of the punch described by a scene file.

Usage (``runin-transient`` once installed, or ``python -m transient``)::

    runin-transient SCENE.toml -o RUN.h5 [--resume] [--force] [--plot RUN.png]
                    [--scheme NAME] [--tol T] [--spread-tol T] [--shape-tol T]
                    [--jump-spread T] [--max-distance S] [--max-steps N]
                    [--checkpoint-interval SEC] [-v]

Starts from the scene's initial face (``[initial_face]``, flat by default),
wears it until the wear rates equalise (``[transient]`` options, overridden
by the flags), compares the final face with the closed-form steady face
(eq. 9), prints the agreement and stores everything in ``RUN.h5``.  The file
is checkpointed atomically while the run goes on; ``--resume`` continues a
killed, stopped or failed run, ``--force`` starts over.  A progress bar is
drawn when stderr is a terminal.

Exit status: 0 steady state reached; 1 run stopped or failed (resumable);
2 bad input (``error: ...`` on stderr).
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
import os
import pathlib
import shutil
import sys

import numpy as np

from steady.command_line import program_name

__all__ = ["build_parser", "main"]

logger = logging.getLogger(__name__)


class _Parser(argparse.ArgumentParser):
    """Argument errors as ``error: ...`` on stderr, exit status 2."""

    def error(self, message):
        self.exit(2, f"error: {message}\n{self.format_usage()}")


def _positive(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (v > 0 and not math.isnan(v)):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def build_parser():
    """The argument parser of ``runin-transient`` (``python -m transient``)."""
    p = _Parser(prog=program_name("python -m transient"),
                description="Run-in wear of a multi-phase punch on an elastic half-space, "
                            "from its initial face to the steady state.")
    p.add_argument("scene", type=pathlib.Path, help="scene file (.toml)")
    p.add_argument("-o", "--output", type=pathlib.Path, required=True,
                   help="HDF5 run file (checkpointed while running)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run stored in the output file (starts afresh if it "
                        "does not exist)")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--plot", type=pathlib.Path, metavar="PNG",
                   help="draw the history and the final face into this PNG (from RUN.h5)")
    from .stepping import SCHEMES

    p.add_argument("--scheme", choices=sorted(SCHEMES),
                   help="integrator (overrides [transient] scheme)")
    p.add_argument("--tol", type=_positive, help="local error per step, shape rms / f*")
    p.add_argument("--spread-tol", type=_positive,
                   help="steady when (max - min) / mean of k p^m is below this")
    p.add_argument("--shape-tol", type=_positive,
                   help="... and the shape changes less than this (f*) per s*")
    p.add_argument("--jump-spread", type=float, metavar="SPREAD",
                   help="jump to the steady state once the spread is below this (inf: at "
                        "once, 0: never)")
    p.add_argument("--max-distance", type=_positive, help="stop beyond this distance (s*)")
    p.add_argument("--max-steps", type=int, help="stop after this many steps")
    p.add_argument("--checkpoint-interval", type=float, metavar="SEC",
                   help="wall-clock seconds between checkpoints (0: every step)")
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="log progress (-v) or details (-vv) to stderr")
    return p


def _options(settings, args):
    overrides = {"scheme": args.scheme, "tol": args.tol, "spread_tol": args.spread_tol,
                 "shape_tol": args.shape_tol, "max_distance": args.max_distance,
                 "max_steps": args.max_steps, "checkpoint_interval": args.checkpoint_interval,
                 "jump_spread": args.jump_spread}
    overrides = {k: v for k, v in overrides.items() if v is not None}
    return dataclasses.replace(settings.options, **overrides)


def _inputs(scene, problem):
    """Root attributes and datasets that identify the run's inputs."""
    attrs = {"scene": scene.text, "scene_path": str(scene.source_path or ""),
             "n": problem.n, "radius": scene.radius, "normal_force": scene.normal_force,
             "E_star": scene.E_star, "exponent": scene.exponent,
             "wear_coefficients": problem.wear_coefficients}
    return attrs, {"phase": problem.labels}


def _check_same_inputs(path, attrs, arrays, stored_attrs, stored_arrays, stored, h0):
    for key in ("n", "radius", "normal_force", "E_star", "exponent"):
        if stored_attrs.get(key) != attrs[key]:
            raise ValueError(f"{str(path)!r} was run with {key} = {stored_attrs.get(key)!r}, "
                             f"the scene has {attrs[key]!r}; use --force to start over")
    if not np.array_equal(np.asarray(stored_attrs.get("wear_coefficients")),
                          attrs["wear_coefficients"]):
        raise ValueError(f"{str(path)!r} was run with other wear coefficients "
                         f"({stored_attrs.get('wear_coefficients')!r}); use --force")
    if not np.array_equal(stored_arrays.get("phase"), arrays["phase"]):
        raise ValueError(f"{str(path)!r} was run with another phase map; use --force")
    face_mask = arrays["phase"] >= 0
    if not np.array_equal(stored.initial_height[face_mask], h0[face_mask]):
        raise ValueError(f"{str(path)!r} was run from another initial face; use --force")


class _Progress:
    """tqdm bar: steps, distance in s*, wear-rate spread (quiet unless stderr is a tty)."""

    def __init__(self, start):
        from tqdm import tqdm

        # Some terminals report no size (tqdm then draws nothing): fall back to 100 x 40.
        cols, rows = shutil.get_terminal_size((100, 40))
        self.bar = tqdm(desc="run-in", unit="step", initial=start, file=sys.stderr,
                        disable=not sys.stderr.isatty(), ncols=cols if cols > 0 else 100,
                        nrows=rows if rows > 0 else 40)

    def __call__(self, run):
        self.bar.update(run.steps - self.bar.n)
        self.bar.set_postfix_str(f"s={run.s / run.s_star:.4g} s*, "
                                 f"spread={run.history['spread'][-1]:.2e}", refresh=False)

    def close(self):
        self.bar.close()


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    from .comparison import compare_with_steady
    from .output import read_run, write_run
    from .problem import WearProblem
    from .runin import run_in
    from .scene import load_transient_scene

    scene, settings, initial = load_transient_scene(args.scene)
    options = _options(settings, args)
    out = args.output
    if args.plot is not None and args.plot.exists() and not args.force:
        raise ValueError(f"{str(args.plot)!r} exists; use --force to overwrite it")
    if out.exists() and not (args.resume or args.force):
        raise ValueError(f"{str(out)!r} exists; use --resume to continue it or --force to "
                         f"start over")
    problem = WearProblem.from_scene(scene)
    h0 = initial.height(problem.n, scene.radius)
    attrs, arrays = _inputs(scene, problem)

    resume = None
    if args.resume and out.exists() and not args.force:
        resume, stored_attrs, stored_arrays = read_run(out)
        _check_same_inputs(out, attrs, arrays, stored_attrs, stored_arrays, resume, h0)
        logger.info("resuming %s at s = %.6g s* (%s)", out, resume.distance /
                    resume.run_in_distance, resume.status)
    run_attrs = dict(attrs, options=repr(options))

    def checkpoint(result):
        write_run(out, result, attrs=run_attrs, arrays=arrays)

    bar = _Progress(0 if resume is None else resume.steps)
    try:
        result = run_in(problem, h0, options, resume=resume, on_step=bar,
                        on_checkpoint=checkpoint)
    finally:
        bar.close()
    comparison = None
    if result.success:
        comparison = compare_with_steady(result, problem.solve_steady(), problem)
        run_attrs.update({"steady_rms_slope": comparison.steady_rms_slope})
    write_run(out, result, attrs=run_attrs, arrays=arrays, comparison=comparison)
    print(f"{result.status}: {result.message}")
    print(f"scheme {result.scheme}: {result.steps} steps ({result.rejected} rejected, "
          f"{result.failures} failed), {result.solves} contact solves, "
          f"{result.iterations} solver iterations, {result.wall_time:.3g} s")
    print(f"scales: f* = {result.depth_scale:.4g} m, s* = {result.run_in_distance:.4g} m, "
          f"fastest relaxation h/(k_max E*) = {result.fast_distance:.4g} m")
    if comparison is not None:
        print("agreement with the steady face (eq. 9):")
        print(comparison.summary())
    if args.plot is not None:
        from .plotting import plot_run  # deferred: matplotlib is slow to import

        plot_run(out, args.plot)
        print(f"figure: {args.plot}")
    if not result.success:
        print(f"error: run {result.status}: {result.message}; continue with --resume",
              file=sys.stderr)
        return 1
    return 0


def main(argv=None):
    """Entry point of ``runin-transient`` and ``python -m transient``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 steady state reached, 1 run stopped or failed
        (resumable), 2 bad input, 130 interrupted.
    """
    args = build_parser().parse_args(argv)
    level = (logging.WARNING, logging.INFO, logging.DEBUG)[min(args.verbose, 2)]
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    try:
        return run(args)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader of stdout went away (e.g. `| head`): nothing left to say.
        sys.stdout = open(os.devnull, "w")
        return 0
    except KeyboardInterrupt:
        print("error: interrupted; the last checkpoint can be continued with --resume",
              file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
