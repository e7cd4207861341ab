"""What a run-in records as it goes: its history, point by point, and its snapshots.

:class:`RunRecord` belongs to the run's loop (:func:`transient.runin.run_in`):
at every accepted point the loop hands it the point, and it appends the
history's figures (:data:`transient.result.HISTORY_UNITS`): those of the
contact at once, those of the face's rms slope and recession
(:class:`transient.history.FaceEstimator`) on a worker thread while the
run goes on -- they do not steer it -- and, across interfaces, the depth
figures (:class:`transient.history.DepthRecorder`).  It also stores the
face and the pressure at the requested snapshot distances and holds the
closed-form steady face the history measures the run against.
"""

from __future__ import annotations

import concurrent.futures
import math

import numpy as np

from .diagnostics import masked_gradient, shape_rms, wear_rate_spread
from .history import DepthRecorder
from .result import _LATER_HISTORY, HISTORY_UNITS, PROGRAMME_HISTORY_UNITS

__all__ = ["RunRecord"]

# History datasets filled by transient.history.FaceEstimator.figures.
_FACE_FIGURES = ("rms_slope", "rms_slope_error", "rms_slope_source", "rms_slope_plain",
                 "rim_layer_pixels", "rms_height", "normalised_rms_slope",
                 "normalised_rms_height")


def frozen(array):
    """``array``, made read-only: a result shares it with the run and later results."""
    array.flags.writeable = False
    return array


def _depth_figures(estimator, depth, worn, distance, recession, face_state):
    """The face's figures and the rms slope of the section's quasi-steady face (history thread).

    ``depth`` is ``(recorder, labels)`` of :meth:`RunRecord._record_depth`.
    """
    rim_layers, pressure, approach = face_state
    figures = estimator.figures(distance, recession, pressure, approach, rim_layers=rim_layers)
    recorder, labels = depth
    figures["quasi_steady_rms_slope"] = recorder.quasi_steady(worn, labels)
    return figures


class RunRecord:
    """The history and the snapshots of a run, and the steady face it is measured against.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    estimator : transient.history.FaceEstimator
        The run's estimator of the face's figures (its initial face's).
    snapshots : sequence of float, m
        Distances at which the face and the pressure are stored, sorted.
    grad_f0 : float
        The reference slope the history normalises by.
    resume : transient.result.RunResult, optional
        The result whose history and snapshots go on.

    Attributes
    ----------
    history : dict of str to list
        One list per dataset of the history.
    snap_d : list of float, m
    snap_h, snap_p : ndarray, shape (k, nx, ny), m and Pa
        The snapshots' distances, faces (worn depth + initial shape, NaN
        off the face) and pressures: read-only arrays, replaced by a new one
        at each snapshot (every result shares them, none copies them).
    snap_index : int
        The next requested snapshot.
    steady_face : ndarray, shape (nx, ny), m
        The closed-form steady face ``f_inf`` (eq. 9), zero off the face.
    steady_shape_rms : float, m
        Its rms over the face, its mean removed: what ``face_deviation``
        is relative to (1 for a flat face).  An integral of the face, it
        converges under refinement as the deviation does; the face's
        ``max - min``, a single pixel's value at the rim, does not.
    steady_slope : (float, float)
        The estimator's rms slope of ``f_inf`` and its error bar, the rim
        layer fully worn (distance infinite).
    """

    def __init__(self, problem, estimator, snapshots, grad_f0, resume=None):
        self.problem = problem
        self.estimator = estimator
        self.snapshots = tuple(snapshots)
        self.grad_f0 = grad_f0
        face_mask = problem.face_mask
        # The face and its pressure only: the rms slope of f_inf is the estimator's below
        # (the steady solve's own estimate, a ladder of coarser maps, would go unused).
        steady = problem.solve_steady(face_only=True)
        self.steady_face = np.where(face_mask, steady.face, 0.0)
        self.steady_shape_rms = shape_rms(steady.face, face_mask)
        # A flat steady face (a homogeneous cell), to round-off: no relief to compare with.
        self._flat = self.steady_shape_rms <= 1e-12 * float(np.max(np.abs(
            steady.face[face_mask])))
        figures = estimator.figures(math.inf, -self.steady_face,
                                    np.where(face_mask, steady.pressure, 0.0), 0.0)
        self.steady_slope = (float(figures["rms_slope"]), float(figures["rms_slope_error"]))
        if resume is None:
            self.history = {name: [] for name in HISTORY_UNITS}
            if problem.load_programme is not None:
                self.history.update({name: [] for name in PROGRAMME_HISTORY_UNITS})
            self.snap_d = []
            self.snap_h = self.snap_p = frozen(np.empty((0, *problem.shape)))
        else:
            self.history = {k: list(v.tolist()) for k, v in resume.history.items()}
            if resume.face_deviation_per_relief:
                # A file of an earlier layout: its deviations were relative to the relief.
                to_rms = float(np.ptp(steady.face[face_mask])) / self.steady_shape_rms
                for name in ("face_deviation", "face_deviation_step_error"):
                    if name in self.history:
                        self.history[name] = [v * to_rms for v in self.history[name]]
            for name in _LATER_HISTORY:
                self.history.setdefault(name, [math.nan] * len(self.history["distance"]))
            self.snap_d = list(resume.snapshot_distance.tolist())
            self.snap_h = frozen(np.array(resume.snapshot_recession, dtype=float))
            self.snap_p = frozen(np.array(resume.snapshot_pressure, dtype=float))
        self.snap_index = len(self.snap_d)
        self._depth = None  # the depth figures' recorder, built at the first point recorded
        self._worker = None
        self._estimator_workers = None
        self._pending = []

    # -- the history -------------------------------------------------------
    def record(self, run, step, shape_rate, error=None, face_state=None):
        """Append the current point of ``run`` to the history; its ``(spread, shape_rate)``.

        ``run`` is the loop (:func:`transient.runin.run_in`'s): its distance,
        face, offset, pressure, approach, previous face, crossings, solver
        and rim layers.  ``error`` is the accepted step's local error
        estimate (m, shape (nx, ny)); None at ``s = 0``.  ``face_state`` is
        ``(rim layers, pressure, approach)`` of the face's figures when they
        are not the current ones: at a step of the load, the face
        (continuous) is measured from its contact before the step, whose
        rim layer the estimator knows.
        """
        if face_state is None:
            face_state = (run.rim_layers(), run.pressure, run.approach)
        p = self.problem
        face_mask = p.face_mask
        hist = self.history
        # The face's figures are computed on a worker thread while the run goes on
        # (they do not steer it); :meth:`collect` waits for them.
        if self._worker is None:
            self._worker = concurrent.futures.ThreadPoolExecutor(
                max_workers=1, thread_name_prefix="runin-history")
            # One thread for the figures' transforms: the solver's use the cores.
            self._estimator_workers, self.estimator.workers = self.estimator.workers, 1
            self.estimator.threaded = True
        index = len(hist["distance"])
        worn = run.recession + run.offset - run.initial_recession
        depth = self._record_depth(run, worn, index)
        # Not copied: the run replaces its face and pressure, never writes into them.
        if depth is None:
            self._pending.append((index, self._worker.submit(
                self.estimator.figures, run.s, run.recession, face_state[1], face_state[2],
                rim_layers=face_state[0])))
        else:
            self._pending.append((index, self._worker.submit(
                _depth_figures, self.estimator, depth, worn, run.s, run.recession,
                face_state)))
        hist["distance"].append(run.s)
        hist["step"].append(step)
        for name in _FACE_FIGURES:
            hist[name].append(math.nan)
        hist["spread"].append(wear_rate_spread(run.solver.rate, run.pressure, face_mask))
        hist["shape_rate"].append(shape_rate)
        hist["peak_pressure"].append(float(run.pressure.max()))
        hist["contact_fraction"].append(float(np.mean(run.pressure[face_mask] > 0)))
        hist["approach"].append(run.approach + run.offset)
        hist["worn_volume"].append(float(np.sum(worn[face_mask])) * p.halfspace.h ** 2)
        hist["solves"].append(run.solver.solves)
        rim = self.estimator.rim
        # A periodic cell has no rim: NaN, no depth.
        hist["rim_worn_depth"].append(float(worn[rim].mean()) if rim.any() else math.nan)
        diff = (run.approach - run.recession - self.steady_face)[face_mask]
        hist["face_deviation"].append(
            self._per_steady_shape(float(np.sqrt(np.mean((diff - diff.mean()) ** 2)))))
        step_error = slope_error = 0.0
        if error is not None:
            step_error = self._per_steady_shape(shape_rms(error, face_mask))
            gx, gy = masked_gradient(np.where(face_mask, error, 0.0), face_mask, p.halfspace.h,
                                     periodic=p.outline.periodic)
            slope_error = float(np.sqrt(np.mean((gx * gx + gy * gy)[face_mask])))
        hist["face_deviation_step_error"].append(step_error)
        hist["rms_slope_step_error"].append(slope_error)
        if "force" in hist:
            hist["force"].append(run.solver.force)
        self.collect(wait=False)
        return hist["spread"][-1], shape_rate

    def _per_steady_shape(self, deviation):
        """A shape deviation (m) over the steady face's rms shape; NaN if that face is flat.

        The steady face of a homogeneous periodic cell is flat: no relief to compare with.
        """
        return math.nan if self._flat else deviation / self.steady_shape_rms

    def _record_depth(self, run, worn, index):
        """Append the depth figures of a run with columns; returns the section's map, or None.

        The recorder (:class:`transient.history.DepthRecorder`) is built at
        the first point recorded; after a resume it takes the crossings of
        the first step from the previous face.  A columnar problem records
        nothing here.  The quasi-steady figures are filled by
        :meth:`collect`.
        """
        columns = self.problem.columns
        if columns is None:
            return None
        recorder = self._depth
        if recorder is None:
            recorder = self._depth = DepthRecorder(self.problem, columns, self.estimator,
                                                   self.estimator.rim)
        previous = (None if run.prev_recession is None or index == 0
                    else run.prev_recession + run.offset - run.initial_recession)
        # The stepping counted the last step's crossings (none before the first step).
        figures, labels = recorder.figures(worn, run.pressure, previous,
                                           crossed=run.crossings if index else None)
        figures.update(quasi_steady_rms_slope=math.nan,
                       normalised_quasi_steady_rms_slope=math.nan)
        hist = self.history
        for name, value in figures.items():
            if name not in hist:  # a file written before them: NaN before the resume
                hist[name] = [np.full_like(np.asarray(value, dtype=float), np.nan).tolist()
                              for _ in range(index)]
            hist[name].append(value.tolist() if isinstance(value, np.ndarray) else value)
        return recorder, labels

    def collect(self, wait=True):
        """Put the face's figures into the history, waiting for those still being computed.

        With ``wait`` False only those already computed (for progress displays).
        """
        hist = self.history
        if wait:
            pending, self._pending = self._pending, []
        else:
            done = [item[1].done() for item in self._pending]
            pending = [item for item, ok in zip(self._pending, done, strict=True) if ok]
            self._pending = [item for item, ok in zip(self._pending, done, strict=True)
                             if not ok]
        for index, future in pending:
            figures = future.result()
            for name in _FACE_FIGURES:
                if name in figures:
                    hist[name][index] = figures[name]
            hist["normalised_rms_slope"][index] = figures["rms_slope"] / self.grad_f0
            hist["normalised_rms_height"][index] = figures["rms_height"] / (
                self.grad_f0 * self.problem.scale)
            if "quasi_steady_rms_slope" in figures:
                value = figures["quasi_steady_rms_slope"]
                hist["quasi_steady_rms_slope"][index] = value
                hist["normalised_quasi_steady_rms_slope"][index] = value / self.grad_f0

    def close(self):
        """Stop the worker thread (figures not collected are dropped)."""
        if self._worker is not None:
            self._worker.shutdown(wait=True, cancel_futures=True)
            self._worker = None
            self.estimator.workers = self._estimator_workers
            self.estimator.threaded = False  # frees its half-space before the comparison
        self._pending = []

    # -- the snapshots -----------------------------------------------------
    def next_snapshot(self):
        """Distance of the next requested snapshot (m), or None."""
        return self.snapshots[self.snap_index] if self.snap_index < len(self.snapshots) \
            else None

    def take_due_snapshots(self, s, recession, pressure):
        """Store the face (``recession``, worn depth + initial shape) and pressure at ``s`` (m).

        Once for every requested snapshot at or before ``s``.
        """
        face_mask = self.problem.face_mask
        while (self.snap_index < len(self.snapshots)
               and self.snapshots[self.snap_index] <= s * (1 + 1e-12)):
            self.snap_d.append(s)
            self.snap_h = frozen(np.concatenate(
                [self.snap_h, np.where(face_mask, recession, np.nan)[None]]))
            self.snap_p = frozen(np.concatenate([self.snap_p, pressure[None]]))
            self.snap_index += 1
