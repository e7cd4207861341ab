"""Command line: run-in of the punch described by a scene file.

Usage (``runin-transient`` once installed, or ``python -m transient``)::

    runin-transient SCENE.toml -o RUN.h5 [--resume | --force] [--plot RUN.png]
                    [--scheme NAME] [--tol T] [--spread-tol T] [--shape-tol T]
                    [--jump-spread T] [--max-distance S] [--max-steps N]
                    [--checkpoint-interval SEC] [--memory-limit GIB] [-v]

Starts from the scene's initial face (``[initial_face]``, flat by default),
wears it until the wear rates equalise (``[transient]`` options, overridden
by the flags), compares the final face with the closed-form steady face
(eq. 9), prints the agreement and stores everything in ``RUN.h5``.  The
face may have any outline of the scene's ``[punch]`` (:mod:`steady.outline`);
the summary names it and the reference slope ``grad_f0`` the rms slopes are
normalised by (the homogeneous face's: eq. 12 for a disk), with its source.  A
progress bar is drawn when stderr is a terminal.

Before the run starts everything that can be checked is: the scene, the
output paths (missing directories are created; a directory, a device, an
unwritable place or ``--plot`` naming the run file are refused), the
memory the grid and the snapshots need (:func:`transient.memory.run_in_memory`) and the
run file's lock: one writer at a time (:class:`transient.output.RunLock`),
a second one is refused at once.

The run file is checkpointed atomically right after the first step and
then every ``checkpoint_interval`` seconds (further apart on fine grids,
so that checkpoints take at most 5 % of the run); the file it replaces is kept as
``RUN.h5.prev``.  Every checkpoint carries checksums, verified by
``--resume``; a damaged file is refused, naming the previous checkpoint if
it is intact.  ``--resume`` continues a killed, stopped or failed run with
the scene's (and the flags') current settings: the inputs that define the
problem (grid, load, phases, wear law, initial face) must be unchanged,
the run settings (scheme, tolerances, limits, snapshots) may change, since
the stored state (face, pressure, previous face and rate, next step) is
what every scheme continues from.  Each part of the run is recorded with
its settings in the root attribute ``settings_history`` (JSON, one entry
per part: steps, distances, status, settings); snapshots requested at
distances the run had already passed are listed in ``snapshots_missing``
and on stderr.  ``--force`` starts over.

Exit status: 0 steady state reached; 1 run stopped or failed (resumable),
or an operating-system error (the message names the last checkpoint);
2 bad input (``error: ...`` on stderr, nothing written), including a run
whose first contact solve fails and a run file another run is writing or
that is damaged; 130 interrupted (the message says whether a checkpoint can
be continued).

A flag that overrides a :class:`transient.runin.RunOptions` field is added
to :func:`build_parser` and to :data:`_OPTION_FLAGS`.  One that adds a
computation after the run reads what it needs from the ``_Job`` (scene,
settings, initial face, problem, options) in ``_run``, stores its figures
through the ``extra_attrs`` of ``_RunFile.write`` and prints them in
``_report``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import logging
import math
import pathlib
import shutil
import signal
import sys
import threading

import numpy as np

from steady.cli.common import (
    EXIT_BAD_INPUT,
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
from steady.memory import check_memory, keep_freed_memory
from steady.text import shorten

from .memory import run_in_memory

__all__ = ["build_parser", "main"]

logger = logging.getLogger(__name__)

#: Flags that override a field of :class:`transient.runin.RunOptions` (same names).
_OPTION_FLAGS = ("scheme", "tol", "spread_tol", "shape_tol", "jump_spread", "max_distance",
                 "max_steps", "checkpoint_interval")

_EPILOG = ("exit status: 0 steady state reached, 1 run stopped or failed (resume it) or an "
           "operating-system error, 2 bad input (nothing written), 130 interrupted")


def _positive(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got "
                                         f"{shorten(text)}") from None
    if not (v > 0 and not math.isnan(v)):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {shorten(text)}")
    return v


def build_parser():
    """The argument parser of ``runin-transient`` (``python -m transient``)."""
    p = ArgumentParser(prog=program_name("python -m transient"),
                       description="Run-in wear of a multi-phase punch on an elastic "
                                   "half-space, from its initial face to the steady state.",
                       epilog=_EPILOG)
    p.add_argument("scene", type=pathlib.Path, help="scene file (.toml)")
    p.add_argument("-o", "--output", type=pathlib.Path, required=True,
                   help="HDF5 run file (checkpointed while running; missing directories "
                        "are created)")
    start = p.add_mutually_exclusive_group()
    start.add_argument("--resume", action="store_true",
                       help="continue the run stored in the output file (starts afresh if "
                            "it does not exist)")
    start.add_argument("--force", action="store_true",
                       help="start over, overwriting existing output files")
    p.add_argument("--plot", type=pathlib.Path, metavar="PNG",
                   help="draw the history and the final face into this PNG (from RUN.h5; an "
                        "existing figure is replaced with --resume or --force)")
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
                   help="wall-clock seconds between checkpoints (0: every step; the first "
                        "one follows the first step)")
    p.add_argument("--spatial-error", action="store_true",
                   help="after the run, run the scene again on about half the grid and store "
                        "the history's spatial error |S_n - S_n/2| as rms_slope_spatial_error "
                        "(about a quarter of the cost)")
    add_memory_limit(p)
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="log progress (-v) or details (-vv) to stderr")
    return p


def _run_in_text(grid, snapshots):
    """The run-in, as a memory refusal names it."""
    nx, ny = grid.shape
    pixels = "" if nx == ny else f" ({nx} x {ny} pixels)"
    return (f"a run-in at n = {grid.n}{pixels}"
            + (f" with {snapshots} snapshots" if snapshots else ""))


def _options(settings, args):
    """The run options: the scene's ``[transient]``, overridden by the flags."""
    overrides = {name: getattr(args, name) for name in _OPTION_FLAGS
                 if getattr(args, name) is not None}
    return dataclasses.replace(settings.options, **overrides)


def _settings(options, contact_rtol):
    """The run settings of a part of the run, as recorded in ``settings_history``."""
    values = dataclasses.asdict(options)
    values["snapshots"] = list(values["snapshots"])
    values["contact_rtol"] = contact_rtol
    return values


def _inputs(scene, problem):
    """Root attributes and datasets that identify the run's inputs.

    The outline goes into the run file with the result (its group
    ``outline``; ``radius`` for a disk), from ``problem.outline``.
    """
    attrs = {"scene": scene.text, "scene_path": str(scene.source_path or ""),
             "n": problem.n, "normal_force": scene.normal_force,
             "E_star": scene.E_star, "exponent": scene.exponent,
             "wear_coefficients": problem.wear_coefficients}
    return attrs, {"phase": problem.labels}


def _same_outline(a, b):
    """Whether two outlines are the same face (masks compared pixel by pixel)."""
    if a is None or b is None or a.kind != b.kind:
        return False
    if a.kind == "mask":
        return (a.pixel_size == b.pixel_size and a.mask.shape == b.mask.shape
                and bool(np.array_equal(a.mask, b.mask)))
    return a.parameters() == b.parameters()


def _check_same_inputs(path, attrs, arrays, stored_attrs, stored_arrays, stored, h0, outline):
    """Refuse to resume a run of another problem (face, grid, load, phases, wear law, start)."""
    if not _same_outline(stored.outline, outline):
        was = "an unknown face" if stored.outline is None else stored.outline.describe()
        raise ValueError(f"{str(path)!r} was run on {was}, the scene has the "
                         f"{outline.describe()}; use --force to start over")
    for key in ("n", "normal_force", "E_star", "exponent"):
        if stored_attrs.get(key) != attrs[key]:
            raise ValueError(f"{str(path)!r} was run with {key} = "
                             f"{shorten(stored_attrs.get(key))}, the scene has {attrs[key]!r}; "
                             f"use --force to start over")
    if not np.array_equal(np.asarray(stored_attrs.get("wear_coefficients")),
                          attrs["wear_coefficients"]):
        raise ValueError(f"{str(path)!r} was run with other wear coefficients "
                         f"({shorten(stored_attrs.get('wear_coefficients'))}); use --force")
    if not np.array_equal(stored_arrays.get("phase"), arrays["phase"]):
        raise ValueError(f"{str(path)!r} was run with another phase map; use --force")
    face_mask = arrays["phase"] >= 0
    if not np.array_equal(stored.initial_height[face_mask], h0[face_mask]):
        raise ValueError(f"{str(path)!r} was run from another initial face; use --force")


def _at(steps, distance_s_star):
    return f"step {steps}, s = {distance_s_star:.6g} s*"


@contextlib.contextmanager
def _interrupt_held():
    """Hold Ctrl-C (SIGINT) back until the block is done; it arrives right after.

    A handler of its own notes the signal during the block and the
    interrupt is raised when the block ends.  (Blocking the signal with a
    thread's signal mask instead lets the kernel hand it to another thread
    of the process, a transform or BLAS worker, where it can be lost.)
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if held:
        raise KeyboardInterrupt


class _RunFile:
    """The run file being written: checkpoints, backup, settings history, what is saved.

    Parameters
    ----------
    path : pathlib.Path
    attrs, arrays : dict
        The inputs stored with every checkpoint (:func:`_inputs`).
    settings : dict
        The settings of this part of the run (:func:`_settings`).
    requested : transient.runin.RunOptions
        The options as asked for (stored in the attribute ``options``).
    """

    def __init__(self, path, attrs, arrays, settings, requested):
        self.path = path
        self.attrs = dict(attrs)
        self.arrays = arrays
        self.requested = requested
        self.history = []
        self.missing = []
        self.settings = settings
        # Whether ``path`` holds a checkpoint of this run (then it becomes the backup).
        self.ours = False
        self.saved = None  # (steps, distance in s*) of the checkpoint on disk

    def start(self):
        """A new run: one part, from step 0."""
        self.history = [self._part(0, 0.0, [])]

    def resume(self, stored, stored_attrs):
        """Continue ``stored`` (a verified :class:`RunResult` read from :attr:`path`).

        Returns
        -------
        notes : list of str
            Changed settings and missing snapshots, for stderr.
        snapshots : tuple of float
            Snapshot distances (s*) for the run: the stored ones, then the
            requested ones still ahead.
        """
        s_star = stored.run_in_distance
        here = stored.distance / s_star
        self.ours = True
        self.saved = (stored.steps, here)
        try:
            self.history = json.loads(stored_attrs.get("settings_history", "[]"))
        except (TypeError, ValueError):
            self.history = []
        missing = stored_attrs.get("snapshots_missing")
        self.missing = [] if missing is None else [float(v) for v in np.atleast_1d(missing)]
        notes = []
        if not self.history:
            self.history = [{"from_step": 0, "to_step": stored.steps, "from_distance": 0.0,
                             "to_distance": stored.distance, "status": stored.status,
                             "settings": None, "snapshots_missing": []}]
            notes.append(f"{str(self.path)!r} does not record the settings of its first "
                         f"{stored.steps} steps")
        previous = self.history[-1].get("settings")
        if previous is not None:
            changes = [f"{key} {shorten(previous.get(key), 40)} -> {shorten(value, 40)}"
                       for key, value in self.settings.items() if previous.get(key) != value]
            if changes:
                notes.append(f"resuming {str(self.path)!r} at {_at(stored.steps, here)} with "
                             f"changed settings: {'; '.join(changes)} (each part of the run is "
                             f"recorded with its settings in the attribute settings_history)")
        # Requested snapshots behind the run: stored already, or missing for good.
        stored_d = stored.snapshot_distance.tolist()
        passed = [r for r in self.requested.snapshots
                  if r * s_star <= stored.distance * (1 + 1e-12)]
        ahead = [r for r in self.requested.snapshots if r not in passed]
        gone = [r for r in passed
                if not any(abs(d - r * s_star) <= 1e-9 * max(d, r * s_star) + 1e-12 * s_star
                           for d in stored_d)]
        new_missing = [r * s_star for r in gone if r * s_star not in self.missing]
        if new_missing:
            self.missing += new_missing
            notes.append(f"snapshots at {', '.join(f'{r:g}' for r in gone)} s* were passed "
                         f"before this resume (at s = {here:.6g} s*) and are not in the file "
                         f"(listed in the attribute snapshots_missing)")
        self.history.append(self._part(stored.steps, stored.distance,
                                       [d / s_star for d in new_missing]))
        return notes, tuple(d / s_star for d in stored_d) + tuple(ahead)

    def _part(self, steps, distance, missing):
        return {"from_step": steps, "to_step": steps, "from_distance": distance,
                "to_distance": distance, "status": "running", "settings": self.settings,
                "snapshots_missing": missing}

    def write(self, result, comparison=None, extra_attrs=None):
        """Write a checkpoint or the final run; the file it replaces becomes the backup."""
        from .output import backup_path, write_run

        self.history[-1].update(to_step=result.steps, to_distance=result.distance,
                                status=result.status)
        attrs = dict(self.attrs, **(extra_attrs or {}))
        attrs.update({
            "options": repr(self.requested),
            "settings_history": json.dumps(self.history),
            "settings_history_units": "from_distance, to_distance: m; settings: distances "
                                      "in s*, as in [transient]",
            "snapshots_missing": np.asarray(self.missing, dtype=float),
            "snapshots_missing_units": "m"})
        with _interrupt_held():  # what saved_text() says must be what is on disk
            write_run(self.path, result, attrs=attrs, arrays=self.arrays,
                      comparison=comparison, backup=self.ours)
            if not self.ours:
                # A backup beside a new run belongs to the run this one replaced.
                backup_path(self.path).unlink(missing_ok=True)
            self.ours = True
            self.saved = (result.steps, result.distance / result.run_in_distance)

    def saved_text(self):
        """What can be continued, for a message."""
        if self.saved is None:
            return "nothing was saved (no checkpoint had been written)"
        return (f"the checkpoint in {str(self.path)!r} ({_at(*self.saved)}) can be continued "
                f"with --resume")


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


def _check_outputs(args):
    """Refuse what the output paths cannot be, before any work; create missing directories."""
    from .output import backup_path, lock_path

    out = args.output
    check_distinct([("the scene", args.scene), ("-o", out),
                    ("the run file's backup", backup_path(out)),
                    ("the run file's lock", lock_path(out)), ("--plot", args.plot)])
    # Existence is checked again under the run's lock.
    prepare_output(out, force=True)
    if args.plot is not None:
        # The figure of a resumed run is drawn anew from its file.
        prepare_output(args.plot, force=args.force or args.resume, what="--plot")


def _read_resume(out):
    """The run stored in ``out``, verified; a damaged file is refused naming its backup."""
    from .output import DamagedRunFileError, backup_path, read_run

    try:
        return read_run(out)
    except DamagedRunFileError as err:
        backup = backup_path(out)
        try:
            prev = read_run(backup)[0] if backup.exists() else None
        except ValueError:
            prev = None
        if prev is None:
            hint = "no intact previous checkpoint is left; start over with --force"
        else:
            hint = (f"the previous checkpoint {str(backup)!r} "
                    f"({_at(prev.steps, prev.distance / prev.run_in_distance)}) is intact: "
                    f"rename it to {str(out)!r} and --resume")
        raise ValueError(f"{err}; {hint}") from None


def _first_solve_failed(err, job):
    """The message of a run whose initial contact solve fails, naming the likely cause."""
    face = job.initial_height[job.problem.face_mask]
    relief = float(np.ptp(face)) if np.all(np.isfinite(face)) else math.inf
    relief_f = relief / job.problem.depth_scale
    rtol = job.settings.contact_rtol
    if not relief_f < 1e6:
        cause = (f"the [initial_face] (kind {job.initial.kind!r}) has a relief of {relief:.3g} m "
                 f"= {relief_f:.3g} f*")
    elif rtol < 1e-13:
        cause = f"[transient] contact_rtol = {rtol:g} is below what round-off allows"
    else:
        cause = (f"check [transient] contact_rtol = {rtol:g} and the [initial_face] (kind "
                 f"{job.initial.kind!r}, relief {relief_f:.3g} f*)")
    return f"the first contact solve failed: {cause} ({err})"


def _report(result, comparison):
    """The summary printed after the run."""
    lines = [f"{result.status}: {result.message}",
             f"scheme {result.scheme}: {result.steps} steps ({result.rejected} rejected, "
             f"{result.failures} failed), {result.solves} contact solves, "
             f"{result.iterations} solver iterations, {result.wall_time:.3g} s"]
    if result.outline is not None:
        nx, ny = result.shape
        lines.append(f"face: {result.outline.describe()}, n = {max(nx, ny)} ({nx} x {ny} "
                     f"pixels)")
    if result.reference_slope_error > 0:
        ref = f"{result.reference_slope:.6g} +- {result.reference_slope_error:.2g}"
    else:
        ref = f"{result.reference_slope:.6g}"
    source = result.reference_slope_source or "unknown"
    lines += [f"grad_f0 = {ref} ({source}): the unit of the normalised rms slopes",
              f"scales: f* = {result.depth_scale:.4g} m, s* = {result.run_in_distance:.4g} m, "
              f"fastest relaxation h/(k_max E*) = {result.fast_distance:.4g} m"]
    if comparison is not None:
        lines += ["agreement with the steady face (eq. 9):", comparison.summary()]
    return lines


@dataclasses.dataclass
class _Job:
    """A run-in ready to start or continue, under the run file's lock."""

    scene: object
    settings: object
    initial: object
    problem: object
    initial_height: np.ndarray
    options: object
    resume: object
    run_file: _RunFile
    companion_grid: int | None = None  # --spatial-error: the companion run's grid


def _prepare(args, lock, scene, settings, initial, options):
    """Check the run file under its lock, build the problem, read what is resumed."""
    from .output import backup_path, remove_temporaries
    from .problem import WearProblem

    out = args.output
    if lock.previous_pid is not None:
        note(f"took over the lock of {str(out)!r} left by process {lock.previous_pid}, which "
              f"has ended")
    for tmp in remove_temporaries(out):
        logger.info("removed %s, left by a killed writer", tmp)
    if out.exists() and not (args.resume or args.force):
        raise ValueError(f"{str(out)!r} exists; use --resume to continue it or --force to "
                         f"start over")
    if not out.exists() and backup_path(out).exists() and not args.force:
        raise ValueError(f"{str(out)!r} does not exist but its backup "
                         f"{str(backup_path(out))!r} does: rename it to {str(out)!r} to "
                         f"continue from it, or use --force to start over")
    problem = WearProblem.from_scene(scene)
    h0 = initial.height(problem.grid)
    attrs, arrays = _inputs(scene, problem)
    run_file = _RunFile(out, attrs, arrays, _settings(options, settings.contact_rtol), options)
    resume = None
    if args.resume and out.exists():
        resume, stored_attrs, stored_arrays = _read_resume(out)
        _check_same_inputs(out, attrs, arrays, stored_attrs, stored_arrays, resume, h0,
                           problem.outline)
        if "sha256" not in stored_attrs:
            note(f"{str(out)!r} carries no checksums; resumed without verification")
        if resume.status == "steady":
            note(f"{str(out)!r} holds a finished run; nothing to continue")
        else:
            notes, snapshots = run_file.resume(resume, stored_attrs)
            for text in notes:
                note(text)
            options = dataclasses.replace(options, snapshots=snapshots)
            check_memory(run_in_memory(problem.shape, len(snapshots)),
                         _run_in_text(problem.grid, len(snapshots)), args.memory_limit)
    else:
        if args.resume:
            note(f"{str(out)!r} does not exist; starting a new run")
        run_file.start()
    grid = _companion_grid(scene, initial, problem.n) if args.spatial_error else None
    return _Job(scene, settings, initial, problem, h0, options, resume, run_file,
                companion_grid=grid)


def _companion_grid(scene, initial, n):
    """The grid of ``--spatial-error``'s companion run; refused before the run if none exists."""
    from .spatial_error import companion_grid

    m = companion_grid(scene.geometry, n, scene.outline)  # ValueError names the minimum grid
    try:
        initial.height(m, scene.outline)
    except ValueError as err:
        raise ValueError(f"--spatial-error needs the initial face on the companion grid "
                         f"n = {m}: {err}") from None
    return m


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    from .output import RunLock
    from .scene import load_transient_scene

    out = args.output
    scene, settings, initial = load_transient_scene(args.scene)
    options = _options(settings, args)
    _check_outputs(args)
    grid = scene.grid()  # load_scene has checked n against the outline
    check_memory(run_in_memory(grid.shape, len(options.snapshots)),
                 _run_in_text(grid, len(options.snapshots)), args.memory_limit)
    scene.phase_labels()  # names a phase without a face pixel before the run

    with RunLock(out) as lock:
        try:
            job = _prepare(args, lock, scene, settings, initial, options)
        except KeyboardInterrupt:
            raise CommandError("interrupted before the run started; nothing was written",
                               EXIT_INTERRUPTED) from None
        try:
            result, comparison = _run(job)
        except KeyboardInterrupt:
            raise CommandError(f"interrupted; {job.run_file.saved_text()}",
                               EXIT_INTERRUPTED) from None
        except OSError as err:
            raise CommandError(f"{describe_os_error(err)}; {job.run_file.saved_text()}",
                               EXIT_FAILED) from None
        except _StepFailureAtStart as err:
            raise CommandError(_first_solve_failed(err.__cause__, job),
                               EXIT_BAD_INPUT) from None
        print("\n".join(_report(result, comparison)))
        status = EXIT_OK if result.success else EXIT_FAILED
        at = _at(result.steps, result.distance / result.run_in_distance)
        stop = f"run {result.status} at {at}: {result.message}; continue with --resume"
        del job, result, comparison  # the figure is drawn from the file
        if args.plot is not None:
            _plot(out, args.plot)
    if status != EXIT_OK:
        print(f"error: {stop}", file=sys.stderr)
    return status


class _StepFailureAtStart(Exception):
    """The initial contact solve of a new run failed (its ``__cause__`` says how)."""


def _run(job):
    """Run (or continue), checkpointing; compare and write the result; return both."""
    from .comparison import compare_with_steady
    from .problem import StepFailure
    from .runin import run_in

    problem, resume = job.problem, job.resume
    finished = resume is not None and resume.status == "steady"
    bar = _Progress(0 if resume is None else resume.steps)
    try:
        result = run_in(problem, job.initial_height, job.options, resume=resume, on_step=bar,
                        on_checkpoint=None if finished else job.run_file.write)
    except StepFailure as err:  # every later failure is retried inside the run
        raise _StepFailureAtStart() from err
    finally:
        bar.close()
    comparison = None
    if result.success:
        comparison = compare_with_steady(result, problem.solve_steady(), problem)
        if job.companion_grid is not None and not finished:
            result = _companion(job, result)
    if not finished:
        extra = None if comparison is None else {"steady_rms_slope": comparison.steady_rms_slope}
        job.run_file.write(result, comparison, extra)
    return result, comparison


def _companion(job, result):
    """The run on about half the grid beside it: the history's spatial error bar."""
    from .spatial_error import spatial_error

    bar = _Progress(0)
    try:
        companion = spatial_error(job.scene, job.initial, job.options, result,
                                  grid=job.companion_grid, on_step=bar)
    finally:
        bar.close()
    result = companion.attach(result)
    error = result.history["rms_slope_spatial_error"] / result.reference_slope
    print(f"spatial error (companion run on n = {companion.grid}, {companion.run.wall_time:.3g}"
          f" s): largest {np.nanmax(error):.3g} grad_f0, at the end {error[-1]:.3g} grad_f0")
    return result


def _plot(out, png):
    """Draw the run file's figure; the run is saved whatever happens here."""
    from .plotting import plot_run  # deferred: matplotlib is slow to import

    try:
        plot_run(out, png)
    except OSError as err:
        raise CommandError(f"cannot draw the figure: {describe_os_error(err)}; the run is "
                           f"saved in {str(out)!r}", EXIT_FAILED) from None
    except KeyboardInterrupt:
        raise CommandError(f"interrupted while drawing the figure; the run is saved in "
                           f"{str(out)!r}", EXIT_INTERRUPTED) from None
    print(f"figure: {png}")


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
        (resumable) or an operating-system error, 2 bad input, 130
        interrupted.
    """
    args = build_parser().parse_args(argv)
    # The summary and the error line say how a run ended: library warnings (a failed
    # contact solve, retried) show with -v.
    configure_logging(args.verbose)
    # Large work arrays are allocated at every step: keep them in the heap.
    keep_freed_memory()
    return run_command(run, args, verbose=args.verbose)


if __name__ == "__main__":
    sys.exit(main())
