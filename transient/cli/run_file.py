"""The run file of ``runin-transient``: inputs, checkpoints, backup, resume, settings history.

A run writes its file at a time under the run file's lock
(:class:`steady.safe_files.RunLock`).  :class:`RunFile` writes every
checkpoint atomically with the run's inputs (:func:`run_inputs`); the file
it replaces is kept as ``RUN.h5.prev`` while the run goes on, and removed
once the run has ended steady and its final file reads back intact.  A
checkpoint replaces only the run's own previous checkpoint, or the file
that was there when the run started (``--resume``, ``--force``): a file
another writer put at the run's path meanwhile is refused
(:class:`steady.safe_files.OutputAppearedError`), not replaced.  A resumed
run continues only the run of the same problem (:func:`check_same_inputs`:
face, grid, load, phases and the phases below the face, wear law, sliding
kinematics, initial face), from a file whose
checksums hold (:func:`read_resume`, which names the previous checkpoint
when the file is damaged); its settings may change, and each part of the
run is recorded with its settings in the root attribute
``settings_history``.  Ctrl-C is held back while a checkpoint is written
(:func:`interrupt_held`), so that what :meth:`RunFile.saved_text` says is
what is on disk.
"""

from __future__ import annotations

import contextlib
import errno
import json
import signal
import threading

import numpy as np

from steady.outline import describe_change
from steady.safe_files import backup_path, file_identity
from steady.sliding import Translation, sliding_from_file
from steady.text import shorten
from steady.wear import same_wear_law, wear_law_from_file

from .. import output

__all__ = ["RunFile", "at_text", "check_same_columns", "check_same_inputs", "interrupt_held",
           "read_resume", "run_inputs", "stored_columns_digest"]


def run_inputs(scene, problem):
    """What identifies the run's inputs in its file: attributes, quantities and fields.

    The outline goes into the run file with the result (its group
    ``outline``; ``radius`` for a disk), from ``problem.outline``; the wear
    law with the problem (:func:`transient.output.problem_inputs`); a load
    programme with the history (its group's ``load_breakpoints``,
    ``load_forces``, ``load_initial_force``).

    Returns
    -------
    attrs : dict of str to str
        ``scene`` (its text) and ``scene_path``.
    quantities : dict of str to (value, str, str)
        ``n``, and the scene's ``normal_force`` (N, before a load
        programme's first step) and ``E_star`` (Pa), with units and long
        names (:func:`transient.output.write_run`).
    arrays : dict of str to ndarray
        ``phase``, the phase map.
    """
    attrs = {"scene": scene.text, "scene_path": str(scene.source_path or "")}
    quantities = {
        "n": (problem.n, "1", "pixels of the grid along the face's longer side"),
        "normal_force": (scene.normal_force, "N", "the scene's normal force F_N (before a "
                                                  "load programme's first step)"),
        "E_star": (scene.E_star, "Pa", "effective modulus E* of the counter-body")}
    return attrs, quantities, {"phase": problem.labels}


def _check_same_counterbody(path, stored_attrs, counterbody):
    """Refuse a run file of another counter-body: a half-space, or a layer of other numbers."""
    stored = tuple(None if stored_attrs.get(key) is None else float(stored_attrs[key])
                   for key in ("thickness", "poisson"))
    if stored != (counterbody.thickness, counterbody.poisson):
        was = ("a half-space" if stored[0] is None
               else f"a layer of thickness {stored[0]!r} m, poisson {stored[1]!r}")
        now = ("a half-space" if not counterbody.layered
               else f"a layer of thickness {counterbody.thickness!r} m, poisson "
                    f"{counterbody.poisson!r}")
        raise ValueError(f"{str(path)!r} was run on {was} ([counterbody]), the scene has "
                         f"{now}; use --force to start over")


def check_same_inputs(path, quantities, arrays, stored_attrs, stored_arrays, stored, h0,
                      problem, wear):
    """Refuse to resume a run of another problem; the message names what differs, both values.

    Everything that defines the problem is compared: the face, the grid,
    the load and its programme, ``E*`` and the counter-body's layer, the
    phase map and the phases below the face (:func:`check_same_columns`),
    the wear law (``wear``, the scene's, against the file's:
    :func:`steady.wear.same_wear_law`), the sliding kinematics and the
    initial face.  The phase names are labels and may change.

    Parameters
    ----------
    path : pathlib.Path
        The run file.
    quantities, arrays : dict
        The scene's inputs as :func:`run_inputs` gives them.
    stored_attrs, stored_arrays : mapping
        The file's root attributes and quantities, and its datasets.
    stored : transient.result.RunResult
        The run the file holds.
    h0 : ndarray, shape (nx, ny), m
        The scene's initial face.
    problem : transient.problem.WearProblem
        The scene's problem.
    wear : wear law
        The scene's law.
    """
    outline = problem.outline
    if stored.outline is None or stored.outline != outline:
        change = (f"an unknown face, the scene has the {outline.describe()}"
                  if stored.outline is None else describe_change(stored.outline, outline))
        raise ValueError(f"{str(path)!r} was run on {change}; use --force to start over")
    for key in ("n", "normal_force", "E_star"):
        if stored_attrs.get(key) != quantities[key][0]:
            raise ValueError(f"{str(path)!r} was run with {key} = "
                             f"{shorten(stored_attrs.get(key))}, the scene has "
                             f"{shorten(quantities[key][0])}; use --force to start over")
    _check_same_counterbody(path, stored_attrs, problem.problem.counterbody)
    try:
        stored_wear = wear_law_from_file(stored_attrs)
    except ValueError:
        stored_wear = None
    if not same_wear_law(stored_wear, wear):
        was = ("an unknown wear law" if stored_wear is None
               else f"another wear law ({stored_wear.scene_words()})")
        raise ValueError(f"{str(path)!r} was run with {was}; the scene has "
                         f"{wear.scene_words()}; use --force to start over")
    try:
        stored_sliding = sliding_from_file(stored_attrs)
    except ValueError:
        stored_sliding = None
    sliding = problem.problem.sliding or Translation()
    if stored_sliding != sliding:
        was = ("an unknown sliding kinematics" if stored_sliding is None
               else f"[sliding] {stored_sliding.describe()}")
        raise ValueError(f"{str(path)!r} was run under {was}; the scene has [sliding] "
                         f"{sliding.describe()}; use --force to start over")
    stored_programme, programme = stored.load_programme, problem.load_programme
    if (stored_programme is None) != (programme is None) or (
            programme is not None and stored_programme.pairs != programme.pairs):
        def shown(programme):
            return "none" if programme is None else shorten([list(p) for p in programme.pairs])
        raise ValueError(f"{str(path)!r} was run with another [load] programme "
                         f"({shown(stored_programme)}), the scene has {shown(programme)}; "
                         f"use --force to start over")
    if not np.array_equal(stored_arrays.get("phase"), arrays["phase"]):
        raise ValueError(f"{str(path)!r} was run with another phase map; use --force")
    check_same_columns(path, stored_attrs, stored, problem.columns)
    face_mask = arrays["phase"] >= 0
    if not np.array_equal(stored.initial_recession[face_mask], h0[face_mask]):
        raise ValueError(f"{str(path)!r} was run from another initial face; use --force")


#: A root attribute every file of a run with columns holds, checkpoint or not, since
#: depth runs were written (:func:`transient.output.write_run`).
_DEPTH_RUN_MARK = "coating_worn_through_distance"


def stored_columns_digest(stored_attrs, stored):
    """The digest of the columns a run file's run had: "" for none, None when not recorded.

    A checkpoint holds ``columns_sha256``, a final file the columns
    themselves; a depth run written before either was recorded is known
    only as one (None).
    """
    digest = stored_attrs.get("columns_sha256")
    if digest is not None:
        return digest.decode() if isinstance(digest, bytes) else str(digest)
    if stored.columns is not None:
        return stored.columns.digest
    return None if _DEPTH_RUN_MARK in stored_attrs else ""


def check_same_columns(path, stored_attrs, stored, columns):
    """Refuse to resume a run on other phases below the face (``[depth]``, a 3-d map).

    ``columns`` (:class:`steady.depth.DepthColumns` or None) are the
    scene's; a depth run whose file does not record its columns is resumed
    on the scene's (the caller notes it).
    """
    digest = stored_columns_digest(stored_attrs, stored)
    scene = ("phases that do not change with depth (no [depth], a 2-d map)" if columns is None
             else f"phases that change with depth ([depth] or a 3-d map: "
                  f"{columns.describe()})")
    if digest is None:
        if columns is None:
            raise ValueError(f"{str(path)!r} was run on phases that change with depth; the "
                             f"scene has {scene}; use --force to start over")
        return
    if digest == ("" if columns is None else columns.digest):
        return
    if not digest:
        was = "phases that do not change with depth"
    elif stored.columns is not None:
        was = f"other phases below the face ({stored.columns.describe()})"
    else:
        was = "other phases below the face (its checkpoint's columns_sha256 differs)"
    raise ValueError(f"{str(path)!r} was run on {was}; the scene has {scene}; use --force to "
                     f"start over")


def at_text(steps, distance, distance_scale):
    """Where a run is, for messages: ``step 12, s = 1538.5 m = 0.05 s*``."""
    return f"step {steps}, s = {distance:.6g} m = {distance / distance_scale:.6g} s*"


@contextlib.contextmanager
def interrupt_held():
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


class RunFile:
    """The run file being written: checkpoints, backup, settings history, what is saved.

    Parameters
    ----------
    path : pathlib.Path
    attrs, quantities, arrays : dict
        The inputs stored with every checkpoint (:func:`run_inputs`).
    settings : dict
        The settings of this part of the run (:meth:`RunOptions.settings`).
    requested : transient.options.RunOptions
        The options as asked for (stored in the attribute ``options``).
    """

    def __init__(self, path, attrs, quantities, arrays, settings, requested):
        self.path = path
        self.attrs = dict(attrs)
        self.quantities = dict(quantities)
        self.arrays = arrays
        self.requested = requested
        self.history = []
        self.missing = []
        self.settings = settings
        # Whether ``path`` holds a checkpoint of this run (then it becomes the backup).
        self.ours = False
        self.saved = None  # (steps, distance (m), s* (m)) of the checkpoint on disk
        # The file at ``path`` the next write may replace (None: none); see atomic_h5.
        self.replaces = None
        self._kept = None  # what saved_text() says when the final file failed its check

    def start(self):
        """A new run: one part, from step 0.

        Called under the run's lock, once ``path`` has been checked: the
        file it names now (one ``--force`` replaces) is the one the first
        checkpoint may replace; a file another writer puts there later is
        refused.
        """
        self.history = [self._part(0, 0.0, [])]
        self.replaces = file_identity(self.path)

    def resume(self, stored, stored_attrs):
        """Continue ``stored`` (a verified :class:`RunResult` read from :attr:`path`).

        Returns
        -------
        notes : list of str
            Changed settings and missing snapshots, for stderr.
        snapshots : tuple of float
            Snapshot distances (m) for the run: the stored ones, then the
            requested ones still ahead.
        """
        s_star = stored.distance_scale
        self.ours = True
        self.replaces = file_identity(self.path)
        self.saved = (stored.steps, stored.distance, s_star)
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
                notes.append(f"resuming {str(self.path)!r} at {at_text(*self.saved)} with "
                             f"changed settings: {'; '.join(changes)} (each part of the run is "
                             f"recorded with its settings in the attribute settings_history)")
        # Requested snapshots behind the run: stored already, or missing for good.
        stored_d = stored.snapshot_distance.tolist()
        requested = self.requested.snapshots(s_star)
        passed = [r for r in requested if r <= stored.distance * (1 + 1e-12)]
        ahead = [r for r in requested if r not in passed]
        gone = [r for r in passed
                if not any(abs(d - r) <= 1e-9 * max(d, r) + 1e-12 * s_star for d in stored_d)]
        new_missing = [r for r in gone if r not in self.missing]
        if new_missing:
            self.missing += new_missing
            notes.append(f"snapshots at {', '.join(f'{r:.6g}' for r in gone)} m were passed "
                         f"before this resume (at s = {stored.distance:.6g} m) and are not in "
                         f"the file (listed in the attribute snapshots_missing)")
        self.history.append(self._part(stored.steps, stored.distance, new_missing))
        return notes, tuple(stored_d) + tuple(ahead)

    def _part(self, steps, distance, missing):
        return {"from_step": steps, "to_step": steps, "from_distance": distance,
                "to_distance": distance, "status": "running", "settings": self.settings,
                "snapshots_missing": missing}

    def write(self, result, comparison=None, extra_quantities=None):
        """Write a checkpoint or the final run; the file it replaces becomes the backup.

        The backup of a run that ends steady is removed once the final file
        reads back with every checksum; it is kept after a stop or a failure.

        Raises
        ------
        steady.safe_files.OutputAppearedError
            (a ``ValueError``) Another writer put a file at ``path`` since
            the run's previous write (or its start): nothing is written.
        OSError
            The file cannot be written, or the final file does not read back
            (its backup is kept).
        """
        self.history[-1].update(to_step=result.steps, to_distance=result.distance,
                                status=result.status)
        attrs = dict(self.attrs, **{
            "options": repr(self.requested),
            # JSON (docs/files.md): from_distance, to_distance in m, settings in s*.
            "settings_history": json.dumps(self.history)})
        quantities = dict(self.quantities, **(extra_quantities or {}))
        if self.missing:  # no empty variable: a run that missed none has none
            quantities["snapshots_missing"] = (
                np.asarray(self.missing, dtype=float), "m",
                "requested snapshot distances passed before a resume (not in the file)")
        with interrupt_held():  # what saved_text() says must be what is on disk
            self.replaces = output.write_run(
                self.path, result, attrs=attrs, quantities=quantities, arrays=self.arrays,
                comparison=comparison, backup=self.ours, force=False, replaces=self.replaces,
                checked=True)
            if not self.ours:
                # A backup beside a new run belongs to the run this one replaced.
                backup_path(self.path).unlink(missing_ok=True)
            self.ours = True
            previous, self.saved = self.saved, (result.steps, result.distance,
                                                result.distance_scale)
            if result.finished:
                self._drop_backup(previous)

    def _drop_backup(self, previous):
        """Remove the backup of a finished run once its final file reads back intact."""
        backup = backup_path(self.path)
        try:
            output.verify_run(self.path)
        except output.DamagedRunFileError as err:
            if previous is not None and backup.exists():
                self._kept = (f"the previous checkpoint {str(backup)!r} ({at_text(*previous)}) "
                              f"is kept: rename it to {str(self.path)!r} and --resume")
            else:
                self._kept = "no intact checkpoint is left; start over with --force"
            raise OSError(errno.EIO, f"the finished run does not read back as written: "
                                     f"{err}") from None
        # Another writer's file in its place (with --force) leaves the backup as the run's.
        if file_identity(self.path) == self.replaces:
            backup.unlink(missing_ok=True)

    def saved_text(self):
        """What can be continued, for a message."""
        if self._kept is not None:
            return self._kept
        if self.saved is None:
            return "nothing was saved (no checkpoint had been written)"
        return (f"the checkpoint in {str(self.path)!r} ({at_text(*self.saved)}) can be continued "
                f"with --resume")


def read_resume(out):
    """The run stored in ``out``, verified; a damaged file is refused naming its backup."""
    try:
        return output.read_run(out)
    except output.DamagedRunFileError as err:
        backup = backup_path(out)
        try:
            prev = output.read_run(backup)[0] if backup.exists() else None
        except ValueError:
            prev = None
        if prev is None:
            hint = "no intact previous checkpoint is left; start over with --force"
        else:
            hint = (f"the previous checkpoint {str(backup)!r} "
                    f"({at_text(prev.steps, prev.distance, prev.distance_scale)}) is intact: "
                    f"rename it to {str(out)!r} and --resume")
        raise ValueError(f"{err}; {hint}") from None
