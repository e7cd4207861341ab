"""The command ``runin-transient``: run-in of the punch described by a scene file.

Usage (``runin-transient`` once installed, or ``python -m transient``)::

    runin-transient SCENE.toml -o RUN.h5 [--resume | --force] [--plot RUN.png]
                    [--scheme NAME] [--tol T] [--spread-tol T] [--shape-tol T]
                    [--jump-spread T] [--max-distance S] [--max-steps N]
                    [--checkpoint-interval SEC] [--memory-limit GIB] [-v]

Starts from the scene's initial face (``[initial_face]``, flat by default),
wears it until the wear rates equalise (``[transient]`` options, overridden
by the flags), compares the final face with the closed-form steady face
(eq. 9, with ``runin-steady``'s error bar: :func:`steady.solution.solve_scene`),
prints the agreement, the end of the dynamics and the run-in distances
within 1 % and 0.1 % (:mod:`transient.run_in_distance`; as times too with
``[load] sliding_speed``) and stores everything in ``RUN.h5``.  The
face may have any outline of the scene's ``[punch]`` (:mod:`steady.outline`);
the summary names it and the reference slope ``grad_f0`` the rms slopes are
normalised by (the homogeneous face's: eq. 12 for a disk), with its source.  A
progress bar is drawn when stderr is a terminal; elsewhere ``-v`` logs one line per step
(at a bounded rate, :mod:`transient.cli.progress`).

Before the run starts everything that can be checked is: the scene, the
output paths (missing directories are created; a directory, a device, an
unwritable place or ``--plot`` naming the run file are refused), the
memory the grid and the snapshots need (:func:`transient.memory.run_in_memory`) and the
run file's lock: one writer at a time (:class:`steady.safe_files.RunLock`),
a second one is refused at once.

The run file is checkpointed atomically right after the first step and
then every ``checkpoint_interval`` seconds (further apart on fine grids,
so that checkpoints take at most 5 % of the run); the file it replaces is kept as
``RUN.h5.prev``.  Every checkpoint carries checksums, verified by
``--resume``; a damaged file is refused, naming the previous checkpoint if
it is intact.  ``--resume`` continues a killed, stopped or failed run with
the scene's (and the flags') current settings: the inputs that define the
problem (face, grid, load, phases and the phases below the face, wear law,
sliding kinematics, initial face) must be unchanged (the phase names and
the sliding speed may change),
the run settings (scheme, tolerances, limits, snapshots) may change, since
the stored state (face, pressure, previous face and rate, next step) is
what every scheme continues from.  Each part of the run is recorded with
its settings in the root attribute ``settings_history`` (JSON, one entry
per part: steps, distances, status, settings); snapshots requested at
distances the run had already passed are listed in ``snapshots_missing``
and on stderr.  ``--force`` starts over.  ``--resume`` on a finished run
that lacks its grid error runs the companions and stores it (unless
``--no-grid-error``); one that holds it is left untouched.

After the run, the scene runs again on about ``3 n / 4`` and ``n / 2``
(the companions, about 0.8 of the run's cost): the largest difference of
the history from theirs is its grid error, part of the run-in distance's
``+-`` (``--no-grid-error`` skips them; the summary then says the ``+-``
lacks it).  A scene whose map has no coarser grid, or whose initial face
exists only on its own grid, runs without them (a note on stderr says
why).

Exit status: 0 steady state or ``end_depth`` reached; 1 run stopped or failed (resumable),
an operating-system error (the message names the last checkpoint), a
companion run that failed or a figure that could not
be drawn (the run is saved); 2 bad input (``error: ...`` on stderr, nothing
written), including a run whose first contact solve fails, an unsupported
``--plot`` suffix and a run file another run is writing or that is damaged;
130 interrupted (the message says whether a checkpoint can be continued).
The scene file opens every message about its ``[initial_face]``.

A flag that overrides a :class:`transient.options.RunOptions` field comes
from the field's declaration (``flag``).  One that adds a computation
after the run reads what it needs from the ``_Job`` (scene, initial face,
problem, options) in ``_run``, stores its figures
through the ``extra_quantities`` of ``RunFile.write`` and prints them in
``_report``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import pathlib
import sys

import numpy as np

from steady.cli.common import (
    EXIT_BAD_INPUT,
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
from steady.memory import check_memory, keep_freed_memory
from steady.safe_files import OutputAppearedError

from ..memory import run_in_memory
from ..options import add_option_flags, options_from_flags
from .progress import Progress
from .run_file import (
    RunFile,
    at_text,
    check_same_inputs,
    read_resume,
    run_inputs,
    stored_columns_digest,
)

__all__ = ["build_parser", "main"]

logger = logging.getLogger(__name__)

def build_parser():
    """The argument parser of ``runin-transient`` (``python -m transient``)."""
    p = ArgumentParser(prog=program_name("python -m transient"),
                       description="Run-in wear of a multi-phase punch on an elastic "
                                   "half-space, from its initial face to the steady state.",
                       epilog=EXIT_STATUS_EPILOG)
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
    p.add_argument("--plot", type=pathlib.Path, metavar="FIGURE",
                   help="draw the history and the final face into this figure, .png, .pdf or "
                        ".svg (from RUN.h5; an existing figure is replaced with --resume or "
                        "--force)")
    from ..stepping import SCHEMES

    add_option_flags(p, choices={"scheme": sorted(SCHEMES)})
    p.add_argument("--no-grid-error", action="store_true",
                   help="skip the companion runs on about 3n/4 and n/2 that give the history's "
                        "grid error (about 0.8 of the run's cost); the run-in distance's +- "
                        "then lacks it")
    add_grid_flag(p)
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


def _check_outputs(args):
    """Refuse what the output paths cannot be, before any work; create missing directories."""
    from steady.safe_files import backup_path, lock_path

    out = args.output
    check_distinct([("the scene", args.scene), ("-o", out),
                    ("the run file's backup", backup_path(out)),
                    ("the run file's lock", lock_path(out)), ("--plot", args.plot)])
    if args.plot is not None:
        check_figure_path(args.plot)
    # Existence is checked again under the run's lock.
    prepare_output(out, force=True)
    if args.plot is not None:
        # The figure of a resumed run is drawn anew from its file.
        prepare_output(args.plot, force=args.force or args.resume, what="--plot")


def _first_solve_failed(err, job, scene_path):
    """The message of a run whose initial contact solve fails, naming the likely cause."""
    face = job.initial_recession[job.problem.face_mask]
    relief = float(np.ptp(face)) if np.all(np.isfinite(face)) else math.inf
    relief_f = relief / job.problem.depth_scale
    rtol = job.options.contact_rtol
    if not relief_f < 1e6:
        cause = (f"the [initial_face] (kind {job.initial.kind!r}) has a relief of {relief:.3g} m "
                 f"= {relief_f:.3g} f*")
    elif rtol < 1e-13:
        cause = f"[transient] contact_rtol = {rtol:g} is below what round-off allows"
    else:
        cause = (f"check [transient] contact_rtol = {rtol:g} and the [initial_face] (kind "
                 f"{job.initial.kind!r}, relief {relief_f:.3g} f*)")
    return f"{scene_path}: the first contact solve failed: {cause} ({err})"


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
              f"scales: f* = {result.depth_scale:.4g} m, distance scale s* = "
              f"{result.distance_scale:.4g} m, fastest relaxation h/(k_max E*) = "
              f"{result.fast_distance:.4g} m"]
    lines += _distance_lines(result)
    lines += _end_lines(result)
    if comparison is not None:
        lines += ["agreement with the steady face (eq. 9):", comparison.summary()]
    return lines


def _distance_lines(result):
    """The run-in distances within 1 % and 0.1 % and the real end of the run."""
    from ..run_in_distance import TOLERANCES

    s_end = float(result.history["distance"][-1])
    end = f"{s_end:.4g} m = {s_end / result.distance_scale:.4g} s*"
    if result.sliding_speed is not None:
        end += f" = {s_end / result.sliding_speed:.4g} s at {result.sliding_speed:g} m/s"
    jumps = result.steps - (len(result.history["distance"]) - 1)
    then = ", then the jump to the steady state" if jumps > 0 else ""
    lines = [f"end of the dynamics: s = {end} ({len(result.history['distance']) - 1} steps"
             f"{then})"]
    try:
        lines += [result.run_in_distance(x).summary() for x in TOLERANCES]
    except ValueError as err:
        lines.append(f"run-in distance: {err}")
    return lines + [_slope_line(result)]


def _slope_line(result):
    """The history's last rms slope with its bar and the bar's parts."""
    h = result.history
    bar = float(result.rms_slope_uncertainty[-1])
    parts = f"estimator {float(h['rms_slope_error'][-1]):.2g}"
    spatial = np.asarray(h.get("rms_slope_spatial_error", ()), dtype=float)
    if spatial.shape == np.shape(h["distance"]):
        parts += f", grid {spatial[-1]:.2g}"
    else:
        parts += "; without the grid's error: no companion runs"
    return (f"rms slope at the end of the dynamics: {float(h['rms_slope'][-1]):.6g} +- "
            f"{bar:.2g} ({parts})")


def _end_lines(result):
    """Why a depth run ended, its worn depth there and its coating's distances.

    Printed for a run whose phase map changes with depth, and for any run
    that ended at its depth or distance; nothing for another columnar run.
    """
    if result.columns is None and result.status not in ("depth", "distance"):
        return []
    s_end = float(result.history["distance"][-1])
    at = f"s = {s_end:.4g} m = {s_end / result.distance_scale:.4g} s*"
    why = {"steady": f"the steady state (every face pixel below its last interface), {at}",
           "depth": f"the end depth, mean worn depth reached at {at}",
           "distance": f"the end distance, {at}"}.get(result.status,
                                                        f"{result.status} at {at}")
    lines = [f"run ended at {why}; mean worn depth at the end {result.mean_worn_depth:.4g} m"]
    if result.columns is not None and "coating_overshoot" in result.history:
        lines += [result.coating_worn_through.summary(), result.coating_gone.summary()]
    return lines


@dataclasses.dataclass
class _Job:
    """A run-in ready to start or continue, under the run file's lock."""

    scene: object
    initial: object
    problem: object
    initial_recession: np.ndarray
    options: object
    resume: object
    run_file: RunFile
    companion_grids: tuple = ()  # the companion runs' grids; empty: none
    no_companions: str | None = None  # why there are none, if the scene has none
    # A finished run with nothing to add: not written again.
    finished: bool = False
    # Why a companion run failed (the run is written without its grid error).
    companion_failure: str | None = None
    # What the companion runs found, for the summary.
    companion_line: str | None = None
    verbose: int = 0  # -v: progress lines outside a terminal


def _prepare(args, lock, scene, initial, options, checked):
    """Check the run file under its lock, build the problem, read what is resumed.

    ``checked`` is the scene's steady problem, built (its map rasterised and
    checked) before the lock was taken.
    """
    from steady.safe_files import backup_path, remove_temporaries

    from ..scene import wear_problem_of

    out = args.output
    if lock.previous_pid is not None:  # RunLock refuses the lock of a process still running
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
    problem = wear_problem_of(scene, problem=checked)
    try:
        h0 = initial.recession(problem.grid)
    except ValueError as err:  # "[initial_face]: ...": the scene file first, as when loading
        raise ValueError(f"{args.scene}: {err}") from None
    attrs, quantities, arrays = run_inputs(scene, problem)
    run_file = RunFile(out, attrs, quantities, arrays, options.settings(), options)
    resume, finished = None, False
    if args.resume and out.exists():
        resume, stored_attrs, stored_arrays = read_resume(out)
        check_same_inputs(out, quantities, arrays, stored_attrs, stored_arrays, resume, h0,
                           problem, scene.wear)
        if "sha256" not in stored_attrs:
            note(f"{str(out)!r} carries no checksums; resumed without verification")
        if stored_columns_digest(stored_attrs, resume) is None:
            note(f"{str(out)!r} does not record the phases below its face; resumed on the "
                 f"scene's without comparing them")
        finished = resume.status == "steady" and not _lacks_grid_error(args, resume)
        if finished:
            note(f"{str(out)!r} holds a finished run; nothing to continue")
        else:
            if resume.status == "steady":
                note(f"{str(out)!r} holds a finished run without its grid error: "
                     f"running the companion runs and storing it")
            notes, snapshots = run_file.resume(resume, stored_attrs)
            for text in notes:
                note(text)
            options = dataclasses.replace(options, snapshot_distances=snapshots,
                                          snapshots_s_star=())
            check_memory(run_in_memory(problem.shape, len(snapshots),
                                       periodic=problem.outline.periodic),
                         _run_in_text(problem.grid, len(snapshots)), args.memory_limit)
    else:
        if args.resume:
            note(f"{str(out)!r} does not exist; starting a new run")
        run_file.start()
    grids, why_none = ((), None) if args.no_grid_error or finished else _companion_grids(
        args.scene, scene, initial, problem.n)
    return _Job(scene, initial, problem, h0, options, resume, run_file,
                companion_grids=grids, no_companions=why_none, finished=finished,
                verbose=args.verbose)


def _lacks_grid_error(args, stored):
    """Whether the companions are asked for and a finished stored run lacks their error."""
    from ..spatial_error import DATASET

    error = np.asarray(stored.history.get(DATASET, ()), dtype=float)
    return not args.no_grid_error and error.shape != np.shape(stored.history["distance"])


def _companion_grids(scene_path, scene, initial, n):
    """The companion runs' grids and None; or none and why (noted once the run is done)."""
    from ..spatial_error import companion_grids

    try:
        grids = companion_grids(scene.geometry, n, scene.outline)  # names the minimum grid
        for m in grids:
            initial.recession(scene.grid(m))
    except ValueError as err:  # "[initial_face]: ...": the scene file first
        return (), f"{scene_path}: no grid error (no companion runs): {err}"
    return grids, None


def run(args):
    """Do the work for parsed arguments; return the exit status."""
    from steady.safe_files import RunLock
    from steady.scene import problem_of

    from ..scene import load_transient_scene

    out = args.output
    not_started = "interrupted before the run started; nothing was written"
    try:
        scene, options, initial = read_input(load_transient_scene, args.scene, n=args.n)
        options = options_from_flags(options, args)
        _check_outputs(args)
        grid = scene.grid()  # load_scene has checked n against the outline
        snapshots = len(options.snapshot_distances) + len(options.snapshots_s_star)
        check_memory(run_in_memory(grid.shape, snapshots, periodic=grid.outline.periodic),
                     _run_in_text(grid, snapshots), args.memory_limit)
        # Names a phase without a face pixel, or a scale out of range, before the run; the
        # run's problem takes its map (rasterised once).
        checked = problem_of(scene)
    except KeyboardInterrupt:
        raise CommandError(not_started, EXIT_INTERRUPTED) from None

    with RunLock(out) as lock:
        try:
            job = _prepare(args, lock, scene, initial, options, checked)
        except KeyboardInterrupt:
            raise CommandError(not_started, EXIT_INTERRUPTED) from None
        try:
            result, comparison = _run(job)
        except KeyboardInterrupt:
            raise CommandError(f"interrupted; {job.run_file.saved_text()}",
                               EXIT_INTERRUPTED) from None
        except OSError as err:
            raise CommandError(f"{describe_os_error(err)}; {job.run_file.saved_text()}",
                               EXIT_FAILED) from None
        except _StepFailureAtStart as err:
            raise CommandError(_first_solve_failed(err.__cause__, job, args.scene),
                               EXIT_BAD_INPUT) from None
        except OutputAppearedError as err:  # the file is another writer's: not ours to resume
            raise CommandError(str(err), EXIT_BAD_INPUT) from None
        except ValueError as err:  # once the run has started: not "nothing written"
            saved = job.run_file.saved is not None
            raise CommandError(f"{err}; {job.run_file.saved_text()}",
                               EXIT_FAILED if saved else EXIT_BAD_INPUT) from None
        print("\n".join(_report(result, comparison)))
        if job.companion_line is not None:
            print(job.companion_line)
        status = EXIT_OK if result.finished else EXIT_FAILED
        at = at_text(result.steps, result.distance, result.distance_scale)
        stop = f"run {result.status} at {at}: {result.message}; continue with --resume"
        if job.companion_failure is not None:
            status = EXIT_FAILED
            stop = (f"{job.companion_failure}; the run is saved in {str(out)!r} without its "
                    f"grid error: --resume computes it")
        del job, result, comparison  # the figure is drawn from the file
        if args.plot is not None:
            _plot(out, args.plot, may_replace=args.force or args.resume)
    if status != EXIT_OK:
        print(f"error: {stop}", file=sys.stderr)
    return status


class _StepFailureAtStart(Exception):
    """The initial contact solve of a new run failed (its ``__cause__`` says how)."""


def _run(job):
    """Run (or continue), checkpointing; compare and write the result; return both."""
    from ..comparison import compare_with_steady, steady_of_run
    from ..runin import run_in
    from ..solver import StepFailure

    problem, resume = job.problem, job.resume
    finished = job.finished  # a finished run lacking its spatial error is not: it gets it
    bar = Progress(0 if resume is None else resume.steps, log=job.verbose)
    try:
        result = run_in(problem, job.initial_recession, job.options, resume=resume, on_step=bar,
                        on_checkpoint=None if finished else job.run_file.write)
    except StepFailure as err:  # every later failure is retried inside the run
        raise _StepFailureAtStart() from err
    finally:
        bar.close()
    comparison = None
    if result.success:
        # The steady result of runin-steady (solve_scene), its error bar included, on the
        # run's own map, operator and ladder: none of them computed a second time.
        initial = np.where(problem.face_mask, result.initial_recession, 0.0)
        comparison = compare_with_steady(result, steady_of_run(job.scene, problem, initial),
                                         problem)
        if job.companion_grids and not finished:
            result = _companion(job, result)
        elif job.no_companions is not None:
            note(job.no_companions)
    if not finished:
        # The steady face's rms slope: the steady result's, with its error bar, once compared.
        extra = None if comparison is None else {"steady_rms_slope": (
            comparison.steady_rms_slope, "1", "rms slope of the steady face f_inf")}
        job.run_file.write(result, comparison, extra)
    return result, comparison


def _companion(job, result):
    """The runs on coarser grids beside it: the history's grid error.

    If the companion run fails, the main run is returned as it is (and
    written: it is finished) and :attr:`_Job.companion_failure` says why.
    """
    from ..solver import StepFailure
    from ..spatial_error import spatial_error

    bar = Progress(0, log=job.verbose, label="companion runs")
    try:
        # Without snapshots, which would only move their steps (and differ on resuming).
        options = dataclasses.replace(job.options, snapshot_distances=(), snapshots_s_star=())
        companions = spatial_error(job.scene, job.initial, options, result,
                                   grids=job.companion_grids, on_step=bar)
    except (ValueError, StepFailure) as err:
        grids = ", ".join(map(str, job.companion_grids))
        job.companion_failure = (f"{job.scene.source_path or 'the scene'}: the companion runs "
                                 f"on n = {grids} failed: {err}")
        return result
    finally:
        bar.close()
    result = companions.attach(result)
    error = result.history["rms_slope_spatial_error"] / result.reference_slope
    grids = ", ".join(map(str, companions.grids))
    wall = sum(run.wall_time for run in companions.runs)
    job.companion_line = (f"grid error (companion runs on n = {grids}, {wall:.3g} s): rms "
                          f"slope largest {np.nanmax(error):.3g} grad_f0, at the end "
                          f"{error[-1]:.3g} grad_f0")
    return result


def _plot(out, png, *, may_replace):
    """Draw the run file's figure; the run is saved whatever happens here.

    ``may_replace``: whether an existing figure may be replaced (``--force``,
    ``--resume``); without it one that exists now appeared during the run.
    """
    from ..plotting import plot_run  # deferred: matplotlib is slow to import

    saved = f"the run is saved in {str(out)!r}"
    if png.exists() and not may_replace:
        raise CommandError(f"--plot {str(png)!r} appeared during the run (use --force to "
                           f"overwrite); {saved}", EXIT_FAILED)
    try:
        plot_run(out, png)
    except OSError as err:
        raise CommandError(f"cannot draw the figure: {describe_os_error(err)}; {saved}",
                           EXIT_FAILED) from None
    except ValueError as err:
        raise CommandError(f"cannot draw the figure: {err}; {saved}", EXIT_FAILED) from None
    except KeyboardInterrupt:
        raise CommandError(f"interrupted while drawing the figure; the run is saved in "
                           f"{str(out)!r}", EXIT_INTERRUPTED) from None
    print(f"figure: {png}")


def main(argv=None):
    """The command ``runin-transient`` (``python -m transient``).

    Entered through :mod:`transient.__main__`, which handles Ctrl-C while
    the modules load.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 steady state or end depth reached, 1 run stopped or failed
        (resumable), an operating-system error or a failed companion run or
        figure (the run is saved), 2 bad input, 130 interrupted.
    """
    args = build_parser().parse_args(argv)
    # The summary and the error line say how a run ended: library warnings (a failed
    # contact solve, retried) show with -v.
    configure_logging(args.verbose)
    # Large work arrays are allocated at every step: keep them in the heap.
    keep_freed_memory()
    return run_command(run, args, verbose=args.verbose)
