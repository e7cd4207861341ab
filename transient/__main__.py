"""Command line: run-in of the punch described by a scene file.

Usage::

    python -m transient SCENE.toml -o RUN.h5 [--resume] [--force] [--plot RUN.png]
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

__all__ = [
    "build_parser",
    "main",
    "plot_run",
]

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
    """The argument parser of ``python -m transient``."""
    p = _Parser(prog="python -m transient",
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


def _inputs(scene, labels):
    """Root attributes and datasets that identify the run's inputs."""
    attrs = {"scene": scene.text, "scene_path": str(scene.source_path or ""),
             "n": scene.n, "radius": scene.radius, "normal_force": scene.normal_force,
             "E_star": scene.E_star, "exponent": scene.exponent,
             "wear_coefficients": np.asarray(scene.wear_coefficients, dtype=float)}
    return attrs, {"phase": labels}


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
    face = arrays["phase"] >= 0
    if not np.array_equal(stored.initial_height[face], h0[face]):
        raise ValueError(f"{str(path)!r} was run from another initial face; use --force")


def plot_run(run_path, png_path):
    """Draw a run file: history (rms slope, spread) and the final face and pressure.

    Parameters
    ----------
    run_path : path-like
        HDF5 file of ``python -m transient``.
    png_path : path-like
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .runin import read_run

    result, attrs, arrays = read_run(run_path)
    h = result.history
    s = h["distance"] / result.run_in_distance
    fig, ax = plt.subplots(2, 2, figsize=(10, 8))
    pos = s > 0
    a = ax[0, 0]
    a.semilogx(s[pos], h["normalised_rms_slope"][pos], ".-", label="K p, exact kernel")
    if "rms_slope_fd" in h:
        a.semilogx(s[pos], h["rms_slope_fd"][pos] / result.reference_slope, "--",
                   label="worn face, finite differences")
    if "steady_rms_slope" in attrs:
        a.axhline(attrs["steady_rms_slope"] / result.reference_slope, color="k", ls=":",
                  label="steady (eq. 9)")
    a.legend(fontsize=8)
    a.set_xlabel("sliding distance / s*")
    a.set_ylabel("rms slope / grad_f0")
    a.set_title(f"{result.scheme}: {result.steps} steps, {result.solves} contact solves")
    a = ax[0, 1]
    a.loglog(s[pos], np.maximum(h["spread"][pos], 1e-17), ".-", label="wear-rate spread")
    sr = h["shape_rate"][pos]
    a.loglog(s[pos], np.maximum(sr, 1e-17), ".-", label="shape change (f* per s*)")
    a.set_xlabel("sliding distance / s*")
    a.legend()
    a.set_title(f"status: {result.status}")
    n = result.height.shape[0]
    radius = float(attrs.get("radius", 1.0))
    ext = [-radius * 1e3, radius * 1e3, -radius * 1e3, radius * 1e3]
    face = result.face_height - np.nanmin(result.face_height)
    im = ax[1, 0].imshow((face / result.depth_scale).T, origin="lower", extent=ext)
    fig.colorbar(im, ax=ax[1, 0], label="face height / f*")
    ax[1, 0].set_title(f"final face (n = {n})")
    pr = np.where(np.isfinite(result.worn_depth), result.pressure / result.mean_pressure,
                  np.nan)
    im = ax[1, 1].imshow(pr.T, origin="lower", extent=ext)
    fig.colorbar(im, ax=ax[1, 1], label="pressure / pbar")
    ax[1, 1].set_title("final pressure")
    for a in ax[1]:
        a.set_xlabel("x (mm)")
        a.set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)


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
    from steady.halfspace import HalfSpace
    from steady.grid import pixel_size
    from steady.solution import solve

    from .runin import compare_with_steady, read_run, run_in, write_run
    from .scene import initial_height, load_transient_scene
    from .stepping import WearProblem

    scene, settings, initial = load_transient_scene(args.scene)
    options = _options(settings, args)
    out = args.output
    if args.plot is not None and args.plot.exists() and not args.force:
        raise ValueError(f"{str(args.plot)!r} exists; use --force to overwrite it")
    if out.exists() and not (args.resume or args.force):
        raise ValueError(f"{str(out)!r} exists; use --resume to continue it or --force to "
                         f"start over")
    n = scene.n
    labels = scene.geometry.labels(n)
    halfspace = HalfSpace(n, pixel_size(n, scene.radius), scene.E_star)
    face = labels >= 0
    k = np.asarray(scene.wear_coefficients, dtype=float)
    wear = np.where(face, k[np.maximum(labels, 0)], 0.0)
    problem = WearProblem(halfspace, wear, face, scene.normal_force, scene.radius,
                          exponent=scene.exponent, contact_rtol=settings.contact_rtol)
    h0 = initial_height(initial, n, scene.radius)
    attrs, arrays = _inputs(scene, labels)

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
        steady = solve(halfspace, labels, k, scene.normal_force, exponent=scene.exponent)
        comparison = compare_with_steady(result, steady, halfspace, labels)
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
        plot_run(out, args.plot)
        print(f"figure: {args.plot}")
    if not result.success:
        print(f"error: run {result.status}: {result.message}; continue with --resume",
              file=sys.stderr)
        return 1
    return 0


def main(argv=None):
    """Entry point of ``python -m transient``; returns the exit status."""
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
