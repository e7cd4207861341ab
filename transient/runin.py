"""The run-in: wear a punch face from its initial shape to the steady state.

:func:`run_in` integrates ``dw/ds = k P(w)^m`` (the schemes of
:mod:`transient.stepping` on a :class:`transient.problem.WearProblem`) from
the initial face, with adaptive steps from the scheme's error estimate,
until the wear rates equalise; it records a history
(:mod:`transient.diagnostics`), takes snapshots and hands resumable
checkpoints to a callback.  Step lengths and stop tests come from
:mod:`transient.control`; the comparison with the steady face lives in
:mod:`transient.comparison`, the run file in :mod:`transient.output`.

Step control
------------
The local error estimate of a step is measured on the *shape*: its mean
over the face is removed (the rigid offset is irrelevant and integrated
exactly) and its rms over the face is compared with ``tol * f*``
(``f* = pbar L / E*``, ``L`` the face outline's scale: the radius ``a`` of
a disk; docs/model.md "Natural scales").  Accepted steps grow
by at most the scheme's ``max_growth``; rejected or failed steps shrink.
Steps land exactly on the snapshot distances.  Explicit Euler is further
limited to a fraction of its stability limit.

Steady state
------------
The run stops when both

- the spread of the wear rate over the contact, ``(max - min) / mean`` of
  ``k p^m`` over the pixels with ``p > 0`` (or over the whole face when
  some pixel is out of contact: then the spread is 1), is below
  ``spread_tol``, and
- the rms change of the shape per run-in distance ``s* = L / (k_min E*)``,
  in units of ``f*``, is below ``shape_tol``.

Jump to the steady state
------------------------
As ``ds -> infinity`` the implicit Euler step ``(K + ds k) p = d - w``
gives ``k p -> C``: the steady pressure (eq. 7) with an error of order
``s* / ds``.  Once the spread is below ``jump_spread`` and no snapshot is
pending, the run takes implicit Euler steps of ``jump_step`` s* (default
``1e8``) until the criteria hold; a single such step is normally enough.
The face after an implicit stage is rebuilt from its pressure,
``w = d - K p`` on the contact (with the solver's own ``K p``), so
that the solver's residual, which scales with the shifted operator, does
not enter the face.  A jump's state is the steady face at no particular
distance: it stays out of the history, the distance and the rigid wear, so
that the history ends where the dynamics end.

Contact tolerance
-----------------
The contact solves of a regular step stop at the absolute residual
:func:`transient.control.contact_tolerance` leaves them, or at
``contact_rtol`` times the displacement, whichever is larger: a thousandth
of the step's error tolerance ``tol f*``, and no more than moves the
pressure by a hundredth of the last wear-rate spread; the stage solver
takes it ``transient.solver.STAGE_SHARE_FACTOR`` times in the largest
violation over the face (``transient.solver.STAGE_NORM``).  Far from the
steady state that is several orders above ``contact_rtol`` and the warm start
often meets it as it stands; near it the spread's share takes over, so the
pressures the spread test sees are exact to its precision.  Jumps,
fixed steps (no error control to leave a share) and power-law steps
solve to ``contact_rtol``.

Reproducibility
---------------
A run's future depends only on what a checkpoint stores: its
:class:`RunState` (face, pressure, previous face and rate, next step, the
warm start's recent pressures, the jumps taken) and the distance, counters
and history of the :class:`RunResult` holding it; a resumed run repeats
the uninterrupted one bit for bit on the same machine and library
versions.
"""

from __future__ import annotations

import logging
import math
import time
import types

import numpy as np

from .control import (
    DIVERGENCE_RELIEF,
    StepController,
    StopTests,
    checkpoint_due,
    contact_tolerance,
    depth_resolution,
)
from .diagnostics import shape_rms, wear_rate_spread
from .history import FaceEstimator
from .options import RunOptions
from .recording import RunRecord, frozen
from .result import RunResult, RunState
from .solver import StageSolver, StepFailure
from .stepping import StepState, get_scheme

__all__ = ["run_in"]

logger = logging.getLogger(__name__)


def _initial_face(problem, initial_recession):
    """``initial_recession`` (m) checked, on the problem's grid, zero off the face."""
    face_mask = problem.face_mask
    h0 = np.where(face_mask, np.asarray(initial_recession, dtype=float), 0.0)
    if h0.shape != problem.shape:
        raise ValueError(f"initial_recession must have shape {problem.shape}, got {h0.shape}")
    if not np.all(np.isfinite(h0[face_mask])):
        raise ValueError("initial_recession must be finite on the face")
    return h0


class _Run:
    """A run in progress: its state, and the loop that advances it.

    The constructor sets every attribute, from the initial face (a new run:
    the first contact solve) or from the result it resumes:

    - fixed: ``problem`` (never changed), ``options``, ``scheme``,
      ``s_star``, ``f_star``, ``controller`` and ``stop``
      (:mod:`transient.control`), ``reference``, ``grad_f0``, ``programme``;
    - ``solver`` (:class:`transient.solver.StageSolver`: the contact solves,
      their counters, the warm start, the force and the section) and
      ``record`` (:class:`transient.recording.RunRecord`: the history, the
      snapshots, the steady face);
    - the state a checkpoint stores (:class:`transient.result.RunState`,
      arrays zero off the face), advanced by :meth:`accept`:
      ``initial_recession``, ``recession``, ``offset``, ``pressure``, ``approach``,
      ``prev_recession``, ``prev_rate``, ``prev_step``, ``next_step``,
      ``jumps`` and the solver's warm start;
    - the progress: ``s`` (m), ``steps``, ``rejected``, ``failures``,
      ``wall_time`` (s, before this call), ``t0`` (monotonic clock at its
      start) and ``latest`` (the current point's spread and shape change,
      which the stop tests judge);
    - across interfaces, following from the state: ``segments`` (of every
      pixel), ``crossings`` (face pixels whose segment the last step
      changed) and ``depth_landing`` (the distance a retry aims at after a
      trial went past ``end_depth``, or None).

    ``on_step`` callbacks read ``s``, ``s_star``, ``steps``, ``history`` and
    ``latest``.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    options : RunOptions
    initial_recession : ndarray, shape (nx, ny), m, or None
        The initial face of a new run (ignored when resuming).
    resume : RunResult or None
        The result to continue from.
    """

    def __init__(self, problem, options, initial_recession, resume):
        self.t0 = time.monotonic()
        self.problem = problem
        self.options = options
        self.scheme = get_scheme(options.scheme)
        self.s_star = problem.distance_scale
        self.f_star = problem.depth_scale
        self.controller = StepController(options, self.s_star)
        self.stop = StopTests(options, self.s_star)
        self.reference = problem.reference
        self.grad_f0 = self.reference.value
        face_mask = problem.face_mask
        self.programme = problem.load_programme
        # The run's contact solves stop at its options' tolerance (the floor of a step's).
        self.solver = solver = StageSolver(problem, contact_rtol=options.contact_rtol)
        if self.programme is not None:
            solver.force = self.programme.force_at(
                0.0 if resume is None else float(resume.distance))
        if resume is None:
            h0 = _initial_face(problem, initial_recession)
            estimator = FaceEstimator.of(problem, h0, contact_rtol=options.contact_rtol)
            state = self._first_state(h0)
        else:
            state = resume.state
            if state.recession.shape != problem.shape:
                raise ValueError(f"checkpoint grid {state.recession.shape} does not match the "
                                 f"problem's {problem.shape}")
            estimator = FaceEstimator.of(problem, np.where(face_mask, state.initial_recession, 0.0),
                                         contact_rtol=options.contact_rtol)
            solver.solves, solver.iterations = resume.solves, resume.iterations
        self.record = RunRecord(problem, estimator, options.snapshots(self.s_star),
                                self.grad_f0, resume)

        def clean(a):
            return None if a is None else np.where(face_mask, a, 0.0)

        self.initial_recession = clean(state.initial_recession)
        self.recession = clean(state.recession)
        self.offset = float(state.offset)
        self.pressure = np.array(state.pressure, dtype=float)
        self.approach = float(state.approach)
        self.prev_recession = clean(state.previous_recession)
        self.prev_rate = clean(state.previous_rate)
        self.prev_step = state.previous_step
        self.next_step = state.next_step
        solver.restore_warm_start(state.pressure_history, state.pressure_history_displacement)
        self.jumps = int(state.jumps)
        # Across interfaces: the segment of every pixel at the current point (the section
        # whose coefficients the solver holds), and the pixels that changed segment over
        # the last accepted step (``crossings``, for the history).
        self.segments = solver.at_depth(self.worn_depth())
        self.crossings = 0
        # Distance of the next attempt after one that went past end_depth (None: none).
        self.depth_landing = None
        if resume is None:
            self.stop.check_end_depth(self.depth_resolution())
            self.s, self.steps, self.rejected, self.failures = 0.0, 0, 0, 0
            self.wall_time = 0.0
        else:
            self.s = float(resume.distance)
            self.steps, self.rejected = resume.steps, resume.rejected
            self.failures = resume.failures
            self.wall_time = resume.wall_time
        if resume is None or self.controller.fixed:
            self.controller.check_first_step(self.next_step if resume is None
                                             else options.fixed_step, self.min_step(), self.s)
        # (spread, shape_rate) of the current point, which the stop tests judge: the last
        # history point's, or the figures of the state a jump reached (not in the history).
        self.latest = None
        if resume is not None:
            history = self.history
            self.latest = (history["spread"][-1], history["shape_rate"][-1])
            if (self.jumps and self.prev_step is not None
                    and self.prev_step != history["step"][-1]):
                self.latest = self._jump_point()  # the last accepted step was a jump

    @property
    def history(self):
        """The history so far (:attr:`transient.recording.RunRecord.history`), lists."""
        return self.record.history

    def worn_depth(self):
        """Worn depth at the current point, m, shape (nx, ny) (:meth:`WearProblem.worn_depth`)."""
        return self.problem.worn_depth(self.recession, self.offset, self.initial_recession)

    def mean_depth(self):
        """Mean worn depth over the face, m (None unless the run ends at a depth)."""
        if self.options.end_depth is None:
            return None
        return float(self.worn_depth()[self.problem.face_mask].mean())

    def min_step(self):
        """The shortest step that moves the run on, m.

        :meth:`transient.control.StepController.min_step` at the current
        distance.
        """
        return self.controller.min_step(self.s, self.problem.fast_distance)

    def depth_resolution(self):
        """The mean worn depth the run resolves at its current point, m.

        :func:`transient.control.depth_resolution` of the largest of the
        rigid approach, the face's recession with its offset and the
        initial face.
        """
        face_mask = self.problem.face_mask
        size = max(abs(self.approach),
                   float(np.max(np.abs(self.recession[face_mask]))) + abs(self.offset),
                   float(np.max(np.abs(self.initial_recession[face_mask]))))
        return depth_resolution(size)

    def depth_aim(self):
        """Distance (m) the next step aims at to land on ``end_depth``, or None.

        After a trial that went past it, the landing that trial gave;
        otherwise where the mean worn depth reaches it at the current rate
        (:meth:`transient.control.StopTests.depth_target`).
        """
        depth = self.mean_depth()
        if depth is None:
            return None
        if self.depth_landing is not None:
            return self.depth_landing
        p = self.problem
        rate = float(self.solver.rate(self.pressure)[p.face_mask].mean())
        return self.stop.depth_target(self.s, depth, rate)

    def below_interfaces(self):
        """Whether the phases no longer change below the face (always, for a columnar run)."""
        p = self.problem
        return p.work_depth is None or p.columns.columnar_below(self.worn_depth())

    def _first_state(self, h0):
        """The state at ``s = 0`` from the checked initial face ``h0`` (m): first contact solve."""
        p = self.problem
        face_mask = p.face_mask
        offset = float(h0[face_mask].mean())
        recession = np.where(face_mask, h0 - offset, 0.0)
        res = self.solver.contact(recession)
        return RunState(recession=recession, offset=offset, pressure=res.pressure,
                        approach=float(res.approach), initial_recession=h0,
                        next_step=self.controller.first_step(p.halfspace.h, p.scale))

    def _jump_point(self):
        """``(spread, shape_rate)`` of the state a jump reached, from the state alone.

        Computed the same way after the jump and from a checkpoint taken
        after it, so that a resumed run judges the same figures.
        """
        face_mask = self.problem.face_mask
        change = shape_rms(self.recession - self.prev_recession, face_mask)
        return (wear_rate_spread(self.solver.rate, self.pressure, face_mask),
                change / self.f_star / (self.prev_step / self.s_star))

    def begin(self):
        """Record the starting point of a new run: history at ``s = 0``, snapshots due there."""
        self.latest = self.record.record(self, 0.0, math.inf)
        self.record.take_due_snapshots(self.s, self.recession + self.offset, self.pressure)

    # -- the load programme ----------------------------------------------------
    def pending_target(self):
        """Distance of the next snapshot or load breakpoint (m), or None."""
        targets = [t for t in (self.next_breakpoint(), self.record.next_snapshot())
                   if t is not None]
        return min(targets) if targets else None

    def next_breakpoint(self):
        """Distance of the load programme's next breakpoint (m), or None."""
        return None if self.programme is None else self.programme.next_breakpoint(self.s)

    def rim_layers(self, *, before_change=False):
        """The rim layers of a load programme's run, for the history's estimator; None without.

        Each rise of the force adds the flat punch's pressure under the
        increase, singular at the rim, whose worn layer grows from the rise
        on: one ``(distance since the rise (m), (dF / F_N)^2)`` per rise
        (:meth:`transient.history.FaceEstimator.figures`).  A step down
        lifts the rim off and adds none.  With ``before_change`` a
        breakpoint at the current distance is not yet applied.
        """
        if self.programme is None:
            return None
        return self.programme.rim_layers(self.s, before=before_change)

    def change_load(self):
        """Apply the load programme's force at the current distance, if it changed.

        The face is continuous across a step of the load, its pressure is
        not (:meth:`transient.solver.StageSolver.change_force`); BDF2's
        previous point, which belongs to the old load, is dropped.  Returns
        ``(rim layers, pressure, approach)`` before the change, from which
        the history measures the face, or None when the force did not change.
        """
        force = self.programme.force_at(self.s)
        if force == self.solver.force:
            return None
        before = (self.rim_layers(before_change=True), self.pressure, self.approach)
        logger.info("load %.6g N -> %.6g N at s = %.6g m", self.solver.force, force, self.s)
        res = self.solver.change_force(force, self.recession, self.pressure)
        self.pressure = res.pressure
        self.approach = float(res.approach)
        self.prev_recession = self.prev_rate = self.prev_step = None
        return before

    def plan(self, jump, target):
        """Scheme and length (m) of the next attempt.

        A regular step lands on ``target`` or on the distance where the
        mean worn depth reaches ``end_depth`` (:meth:`depth_aim`),
        whichever comes first; across interfaces it ends just past the
        first crossing ahead
        (:meth:`transient.control.StepController.before_crossing`).  No
        step is shorter than :meth:`min_step` unless it lands on a target;
        the loop ends the run rather than retry one.
        """
        p = self.problem
        if jump:
            return get_scheme("implicit_euler"), self.options.jump_step_s_star * self.s_star
        # After a step cut short to land on a target, the next grows from it: not below
        # the shortest step that moves the run on.
        ds = max(self.next_step, self.min_step())
        if self.scheme.explicit:
            ds = self.controller.explicit_limit(ds, self.solver.stable_step(self.pressure))
        if p.work_depth is not None:
            ds = self.controller.before_crossing(ds, self.last_crossing(ds))
        at_depth = self.depth_aim()
        if at_depth is not None:
            target = at_depth if target is None else min(target, at_depth)
        return self.scheme, self.controller.land(ds, self.s, target, self.stop.end())

    def last_crossing(self, ds):
        """Distance (m) in which the last face pixel to reach a kink within ``ds`` reaches it.

        At the current rates; ``-inf`` when no pixel reaches one within
        ``ds`` (m).
        """
        p = self.problem
        work = p.variable(self.recession, self.initial_recession - self.offset)
        rate = self.solver.variable_rate(self.pressure)[p.face_mask]
        left = p.work_depth.remaining(work)[p.face_mask]
        moving = rate > 0
        distance = left[moving] / rate[moving]
        return float(np.max(distance[distance < ds], initial=-np.inf))

    def attempt(self, scheme, ds, jump):
        """One trial step and its scaled error; raises :class:`StepFailure`."""
        p, solver = self.problem, self.solver
        face_mask = p.face_mask
        solver.start_warm(self.pressure)
        # A jump starts from the closed-form steady pressure, its limit; every
        # other stage from the Galerkin combination of the recent pressures,
        # and solves to what the step's error and the spread need.
        atol = 0.0
        if not (jump or self.controller.fixed) and p.wear.linear:
            atol = contact_tolerance(self.options.tol, self.f_star, self.latest[0],
                                     p.compliance_floor, solver.force / p.area)
        origin = None
        if p.work_depth is not None:
            origin = self.initial_recession - self.offset
        state = StepState(self.recession, p.steady_pressure() if jump else self.pressure,
                          self.approach, self.prev_recession, self.prev_rate, self.prev_step,
                          warm=not jump, contact_atol=atol, origin=origin)
        trial = scheme.step(solver, state, ds)
        err = shape_rms(trial.error, face_mask) / (self.options.tol * self.f_star)
        if not (math.isfinite(err) and np.all(np.isfinite(trial.recession[face_mask]))):
            raise StepFailure("non-finite face or error estimate")
        if shape_rms(trial.recession, face_mask) > DIVERGENCE_RELIEF * self.f_star:
            raise StepFailure(f"face relief above {DIVERGENCE_RELIEF:g} f*: divergence")
        return trial, err

    def past_end_depth(self, trial, ds):
        """Where to land instead of a trial that went past ``end_depth`` (m), or None."""
        if self.options.end_depth is None:
            return None
        after = self.problem.worn_depth(trial.recession, self.offset, self.initial_recession)
        return self.stop.depth_landing(self.s, ds, self.mean_depth(),
                                       float(after[self.problem.face_mask].mean()),
                                       self.depth_resolution())

    def accept(self, trial, ds, jump=False):
        """Move to the trial point; the rigid part of the wear goes into ``offset``.

        A jump's state is the steady face at no particular distance: it
        advances neither the distance nor the rigid wear, and stays out of
        the history (its figures go to ``latest``).  Across interfaces the
        recession is not re-centred (``offset`` stays): the worn depth, which
        sets the phases, is then the recession minus one fixed origin, free of
        the round-off a moving offset would add at every step; a jump there
        (below every interface) drops its least increment.
        """
        p = self.problem
        face_mask = p.face_mask
        new_recession = np.where(face_mask, trial.recession, 0.0)
        c = 0.0
        if p.work_depth is None:
            c = float(new_recession[face_mask].mean())
        elif jump:
            # The jump's wear less its least increment: no pixel rises above the
            # depth it had reached (below every interface).
            c = float(np.min((new_recession - self.recession)[face_mask]))
        if c:
            new_recession = np.where(face_mask, new_recession - c, 0.0)
        change = shape_rms(new_recession - self.recession, face_mask)
        shape_rate = change / self.f_star / (ds / self.s_star)
        self.prev_recession = np.where(face_mask, self.recession - c, 0.0)
        self.prev_rate = self.solver.variable_rate(self.pressure)
        self.prev_step = ds
        self.recession = new_recession
        self.pressure = trial.pressure
        self.approach = trial.approach - c
        self.steps += 1
        if p.work_depth is not None:
            segments = self.solver.at_depth(self.worn_depth())
            self.crossings = int(np.count_nonzero((segments != self.segments) & face_mask))
            self.segments = segments
        if jump:
            self.latest = self._jump_point()
            return
        self.offset += c
        self.s += ds
        face_state = None
        if self.programme is not None:
            self.s = self.programme.snap(self.s)
            face_state = self.change_load()
        self.latest = self.record.record(self, ds, shape_rate, trial.error, face_state)
        self.record.take_due_snapshots(self.s, self.recession + self.offset, self.pressure)

    def loop(self, on_step, on_checkpoint):
        """Step until a stop test says the run is over; return ``(status, message)``.

        Each pass: the stop tests, the choice of a jump (counted: the stop
        tests end a run whose jumps stagnate) or a regular step (landing on
        the next snapshot), one attempt, then accept it, reject it (error
        above tolerance: retry shorter) or count a failure (retry at a
        fraction, until the stop tests give up).
        """
        o = self.options
        controller, stop = self.controller, self.stop
        fixed = controller.fixed
        last_checkpoint = None  # the first checkpoint follows the first accepted step
        checkpoint_cost = 0.0
        consecutive = 0
        while True:
            spread, shape_rate = self.latest
            columnar = self.below_interfaces()
            depth = self.mean_depth()
            ended = stop.check(spread, shape_rate, self.s, self.steps,
                               held=self.next_breakpoint() is not None, depth=depth,
                               depth_resolution=0.0 if depth is None else self.depth_resolution(),
                               columnar=columnar)
            if ended is not None:
                return ended
            target = self.pending_target()
            jump = stop.jump_due(spread, target, fixed, columnar)
            if jump:
                ended = stop.stagnation(self.jumps, spread)
                if ended is not None:
                    return ended
                self.jumps += 1
            scheme, ds = self.plan(jump, target)
            # A step below min_step moves the run on only to land on a snapshot or a
            # breakpoint, and no shorter retry would.
            min_step = self.min_step()
            if not (jump or ds >= min_step or (target is not None and ds == target - self.s)):
                return stop.short_step(ds, min_step, self.s, at_depth=self.depth_aim(),
                                       depth=self.mean_depth())
            try:
                trial, err = self.attempt(scheme, ds, jump)
            except StepFailure as exc:
                self.failures += 1
                consecutive += 1
                logger.info("step of %.3g s* failed (%s); retrying smaller",
                            ds / self.s_star, exc)
                ended = stop.give_up(consecutive, fixed, ds, self.s, exc)
                if ended is not None:
                    return ended
                self.next_step = controller.after_failure(ds)
                continue
            consecutive = 0
            landing = None if jump else self.past_end_depth(trial, ds)
            if landing is not None:
                self.rejected += 1
                self.depth_landing = landing
                logger.debug("past end_depth: landing at %.6g s*", landing / self.s_star)
                continue
            if controller.rejects(err, jump):
                if ds <= min_step:  # its retry would be no shorter
                    return stop.short_step(ds, min_step, self.s)
                self.rejected += 1
                self.next_step = controller.after_reject(ds, err, scheme)
                logger.debug("rejected %.3g s* (err %.3g)", ds / self.s_star, err)
                continue
            if not jump:
                self.next_step = controller.after_accept(ds, err, scheme)
            self.depth_landing = None
            self.accept(trial, ds, jump)
            if on_step is not None:
                on_step(self)
            if on_checkpoint is not None and (
                    last_checkpoint is None
                    or checkpoint_due(time.monotonic() - last_checkpoint,
                                      o.checkpoint_interval, checkpoint_cost)):
                started = time.monotonic()
                on_checkpoint(_result_of(self, "running", "in progress"))
                last_checkpoint = time.monotonic()
                checkpoint_cost = last_checkpoint - started


def _state_of(run):
    """The state at the run's current point as a :class:`RunState` (NaN off the face).

    The arrays that are the run's own are read-only views, not copies: the
    run replaces them at every step and never writes into them.
    """
    face_mask = run.problem.face_mask
    warm = run.solver.warm_start

    def shared(a):
        return None if a is None else frozen(a.view())

    return RunState(
        recession=np.where(face_mask, run.recession, np.nan), offset=run.offset,
        pressure=shared(run.pressure), approach=run.approach,
        initial_recession=np.where(face_mask, run.initial_recession, np.nan),
        previous_recession=shared(run.prev_recession), previous_rate=shared(run.prev_rate),
        previous_step=run.prev_step, next_step=run.next_step,
        pressure_history=None if warm is None else warm.pressures(),
        pressure_history_displacement=None if warm is None else warm.displacements(),
        jumps=run.jumps)


def _result_of(run, status, message):
    """The run so far as a :class:`RunResult`, once the history's figures are in."""
    record, problem = run.record, run.problem
    record.collect()
    return RunResult(
        status=status, message=message, scheme=run.scheme.name, distance=run.s,
        steps=run.steps, rejected=run.rejected, failures=run.failures,
        solves=run.solver.solves, iterations=run.solver.iterations,
        wall_time=run.wall_time + (time.monotonic() - run.t0),
        history=types.MappingProxyType({k_: np.array(v, dtype=float if k_ != "solves"
                                                     else np.int64)
                                        for k_, v in record.history.items()}),
        snapshot_distance=np.array(record.snap_d, dtype=float),
        snapshot_recession=record.snap_h, snapshot_pressure=record.snap_p,
        depth_scale=run.f_star, distance_scale=run.s_star,
        fast_distance=problem.fast_distance, pixel_mean_pressure=problem.pixel_mean_pressure,
        reference_slope=run.grad_f0, state=_state_of(run), outline=problem.outline,
        reference_slope_error=run.reference.error, reference_slope_source=run.reference.source,
        problem=problem.problem, steady_rms_slope=record.steady_slope[0],
        steady_rms_slope_error=record.steady_slope[1], sliding_speed=problem.sliding_speed,
        load_programme=run.programme, columns=problem.columns)


def run_in(problem, initial_recession, options=None, *, resume=None, on_step=None,
           on_checkpoint=None):
    """Wear the face from ``initial_recession`` until the wear rates equalise.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    initial_recession : ndarray, shape (nx, ny), m
        Initial face (larger = recessed) on the problem's grid; see
        :mod:`transient.initial_face`.
    options : RunOptions, optional
    resume : RunResult, optional
        A checkpoint (or a stopped run) to continue from: its
        :attr:`RunResult.state`, distance, counters, history and snapshots;
        ``initial_recession`` is then taken from it.
    on_step : callable, optional
        ``on_step(run)`` after each accepted step, with attributes ``s``,
        ``s_star``, ``steps``, ``history``, ``latest`` (``(spread,
        shape_rate)`` of the current point, a jump's too) and ``options``
        (for progress displays).
    on_checkpoint : callable, optional
        ``on_checkpoint(result)`` with a ``"running"`` :class:`RunResult`
        every ``options.checkpoint_interval`` seconds.

    Returns
    -------
    RunResult
        ``status`` says how the run ended; a failed or stopped run can be
        resumed.  A step that fails is retried smaller; the run never returns
        non-finite values.

    Raises
    ------
    ValueError
        Bad options or inputs, or a fixed explicit step beyond the stability
        limit.

    Examples
    --------
    A biphasic Voronoi punch worn from flat to the steady state, with a
    loose step tolerance; the final face is the closed-form one (eq. 9).

    >>> from steady import examples
    >>> from transient import RunOptions, compare_with_steady, run_in
    >>> from transient.scene import load_transient_scene, wear_problem_of
    >>> scene, settings, initial = load_transient_scene(examples.path("voronoi_transient"))
    >>> problem = wear_problem_of(scene, n=40)
    >>> result = run_in(problem, initial.recession(problem.grid),
    ...                 RunOptions(tol=1e-2))
    >>> result.status
    'steady'
    >>> slope = result.history["normalised_rms_slope"]
    >>> print(f"rms slope {slope[0]:.3f} -> {slope[1]:.3f} -> {slope[-1]:.3f} grad_f0")
    rms slope 0.000 -> 0.86 -> 1.35 grad_f0
    >>> comparison = compare_with_steady(result, problem.solve_steady(), problem)
    >>> bool(comparison.face_error < 1e-6)
    True
    """
    options = RunOptions() if options is None else options
    run = _Run(problem, options, initial_recession, resume)
    try:
        if resume is None:
            run.begin()
        elif resume.status == "steady":
            return _result_of(run, "steady", resume.message)
        status, message = run.loop(on_step, on_checkpoint)
        log = logger.info if status in ("steady", "depth") else logger.warning
        log("%s: %s", status, message)
        if status == "steady":
            run.solver.drop_warm_start()  # freed before the result is built: not state any more
        return _result_of(run, status, message)
    finally:
        run.record.close()
