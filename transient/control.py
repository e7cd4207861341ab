"""Step control and stop tests of the run loop (docs/model.md, "Wear and time integration").

The run loop (:class:`transient.runin` ``_Run.loop``) asks two objects what
to do: a :class:`StepController` proposes the length of the next attempt
(adaptive from the scheme's error estimate, or fixed), says whether an
attempt is rejected and how to go on after an accepted, rejected or failed
one; :class:`StopTests` says when the run is over (steady state, distance
or step limits, stagnating jumps, repeated failures) and when to jump to
the steady state.  Neither holds any of the run's state: the loop hands
them the figures they judge, and the counts they test (jumps, failures in
a row) stay with the run.  The numbers that steer them are named
below.
"""

from __future__ import annotations

import math

__all__ = [
    "CHECKPOINT_SHARE",
    "CROSSING_CUT",
    "CROSSING_MARGIN",
    "DEPTH_ROUNDING",
    "DEPTH_SLACK",
    "DIVERGENCE_RELIEF",
    "EXPLICIT_SAFETY",
    "FAILURE_FACTOR",
    "INITIAL_STEP_FACTOR",
    "LANDING_SLACK",
    "MAX_JUMPS",
    "MIN_ACCEPT_FACTOR",
    "MIN_REJECT_FACTOR",
    "SAFETY",
    "SOLVE_ERROR_SHARE",
    "SOLVE_SPREAD_SHARE",
    "STEP_ROUNDING",
    "StepController",
    "StopTests",
    "checkpoint_due",
    "contact_tolerance",
    "depth_resolution",
]

#: Fraction of the step the error estimate calls optimal that is proposed.
SAFETY = 0.9
#: A rejected step is retried at least this fraction of its length.
MIN_REJECT_FACTOR = 0.1
#: The step after an accepted one is at least this fraction of it.
MIN_ACCEPT_FACTOR = 0.2
#: A failed attempt (solver failure, non-finite values) is retried at this fraction.
FAILURE_FACTOR = 0.25
#: Explicit Euler steps stay below this fraction of their stability limit.
EXPLICIT_SAFETY = 0.9
#: First adaptive step, ``INITIAL_STEP_FACTOR sqrt(tol) (h / L) s*``: the fast
#: scale on which the flat punch's edge relaxes (``L`` the outline's scale).
INITIAL_STEP_FACTOR = 0.01
#: Across interfaces a step that the current rates say pixels cross in is cut to end
#: this fraction past the last of those crossings (docs/model.md, "Wear across
#: interfaces") ...
CROSSING_MARGIN = 0.02
#: ... but to no less than this fraction of its length.
CROSSING_CUT = 0.5
#: A face relief (shape rms) above this many ``f*`` is a divergence.
DIVERGENCE_RELIEF = 1e6
#: Jumps to the steady state tried before the run stops as stagnating.
MAX_JUMPS = 5
#: A step is stretched by up to this fraction to land on a snapshot.
LANDING_SLACK = 1e-9
#: Relative slack of the distance limit (round-off of the summed steps).
_DISTANCE_SLACK = 1e-12
#: Relative slack of ``end_depth``: a run that lands within it has reached it.
DEPTH_SLACK = 1e-9
#: Rounding units (of the face's largest value) within which the mean worn depth is
#: resolved, and ``end_depth`` reached: a step's face is a difference of numbers of the
#: size of the rigid approach, and its mean moves by about a unit at every step
#: whatever the step's length (see :func:`depth_resolution`).
DEPTH_ROUNDING = 16
#: Rounding units of the sliding distance (or, near its start, of the fastest
#: relaxation distance) below which a step is too short to move the run on.
STEP_ROUNDING = 16
#: Most of a run's wall time its checkpoints may take (see :func:`checkpoint_due`).
CHECKPOINT_SHARE = 0.05
#: Share of a step's error tolerance ``tol f*`` left to its contact solves.
SOLVE_ERROR_SHARE = 1e-3
#: Share of the last wear-rate spread that a solve may move the pressure by.
SOLVE_SPREAD_SHARE = 1e-2


def checkpoint_due(elapsed, interval, last_cost):
    """Whether a checkpoint is due, ``elapsed`` s after the last one, which took ``last_cost`` s.

    Due once ``interval`` seconds have passed (the run's
    ``checkpoint_interval``; 0: after every step) and, unless the interval
    is 0, the run has worked long enough since that writing checkpoints
    takes at most ``CHECKPOINT_SHARE`` of its time: on a fine grid, whose
    checkpoints take a second or more, they come further apart than
    ``interval``.
    """
    if interval == 0:
        return True
    return elapsed >= max(interval, last_cost * (1.0 - CHECKPOINT_SHARE) / CHECKPOINT_SHARE)


def depth_resolution(face_size):
    """The mean worn depth (m) a run resolves on a face whose values reach ``face_size`` (m).

    ``DEPTH_ROUNDING`` rounding units of ``face_size`` (the largest of the
    rigid approach, the recession with its offset and the initial face):
    the face of a step is computed as a difference of numbers that large,
    and the mean worn depth moves by about a unit at every step, however
    short.  ``end_depth`` is reached within it (:meth:`StopTests.depth_reached`).

    Examples
    --------
    >>> f"{depth_resolution(1e-3):.3g}"
    '3.47e-18'
    """
    return DEPTH_ROUNDING * math.ulp(face_size)


def contact_tolerance(tol, depth_scale, spread, compliance_floor, mean_pressure):
    """Absolute tolerance (m) of the contact solves of one regular step.

    A solve that stops at a residual ``r`` (m, rms over the face) moves the
    stage's face by at most ``r`` (the stage's increment is ``c k p`` with
    ``(K + c k) dp = r``, and ``c k (K + c k)^-1`` has norm below 1) and its
    pressure by at most ``r / lambda`` (``lambda`` the compliance floor,
    :attr:`transient.problem.WearProblem.compliance_floor`).  The tolerance
    is the smaller of ``SOLVE_ERROR_SHARE`` of the step's error tolerance
    ``tol f*`` and the residual that moves the pressure by
    ``SOLVE_SPREAD_SHARE`` of the last wear-rate spread: far from the steady
    state it sits far above ``contact_rtol`` times the displacement, and it
    tightens as the spread falls, so the spread test sees pressures that are
    exact to its own precision.  Jumps, fixed steps and power-law steps
    keep 0 (``contact_rtol`` alone).  The stage solver applies it
    ``transient.solver.STAGE_SHARE_FACTOR`` times in the largest violation
    over the face (``transient.solver.STAGE_NORM``), not the rms: the rms
    does not see a few singular pixels (docs/benchmarks.md, "Stopping rule
    of the stage solves").

    Parameters
    ----------
    tol : float
        The run's step tolerance (relative to ``f*``).
    depth_scale : float, m
        ``f*``.
    spread : float
        Last recorded wear-rate spread (``(max - min) / mean``, 1 with
        pixels out of contact).
    compliance_floor : float, m/Pa
    mean_pressure : float, Pa
        The face's mean pressure.

    Returns
    -------
    float, m
    """
    if not math.isfinite(spread):
        spread = 1.0
    return min(SOLVE_ERROR_SHARE * tol * depth_scale,
               SOLVE_SPREAD_SHARE * spread * compliance_floor * mean_pressure)


class StepController:
    """Lengths of the steps: elementary error-per-step control, or fixed steps.

    Parameters
    ----------
    options : transient.options.RunOptions
    s_star : float, m
        Run-in distance ``s*``.
    """

    def __init__(self, options, s_star):
        self.options = options
        self.s_star = s_star
        self.fixed = options.fixed_step is not None

    def first_step(self, h, scale):
        """Length of the first attempt, m (``h`` the pixel size, ``scale`` L, a disk's radius)."""
        o = self.options
        if o.fixed_step is not None:
            return o.fixed_step
        if o.first_step is not None:
            return o.first_step
        return INITIAL_STEP_FACTOR * math.sqrt(o.tol) * h / scale * self.s_star

    def explicit_limit(self, ds, stable_step):
        """Clip an explicit step to ``EXPLICIT_SAFETY`` times its stability limit (m).

        Raises
        ------
        ValueError
            A fixed step beyond the stability limit itself.
        """
        limit = EXPLICIT_SAFETY * stable_step
        if self.fixed and ds > limit / EXPLICIT_SAFETY:
            raise ValueError(
                f"fixed step {ds:.6g} m ({ds / self.s_star:.6g} s*) exceeds the explicit "
                f"Euler stability limit {limit / EXPLICIT_SAFETY:.6g} m "
                f"({limit / EXPLICIT_SAFETY / self.s_star:.6g} s*)")
        return min(ds, limit)

    @staticmethod
    def min_step(s, fast_distance):
        """The shortest step (m) that moves the run on from ``s`` (m).

        ``STEP_ROUNDING`` rounding units of the sliding distance, or near
        its start of the fastest relaxation distance ``fast_distance`` (m),
        on which the shortest dynamics of the run happen: a shorter step
        leaves the distance as it is, or resolves nothing.
        """
        return STEP_ROUNDING * math.ulp(max(s, fast_distance))

    def check_first_step(self, ds, min_step, distance=0.0):
        """Refuse a run whose first step ``ds`` (m) from ``distance`` (m) is below ``min_step``.

        Named by the option that set it: ``fixed_step``, ``first_step``, or
        ``tol`` through the default first step.

        Raises
        ------
        ValueError
            ``ds`` at or below ``min_step`` (:meth:`min_step`).
        """
        if ds > min_step:
            return
        o = self.options
        if o.fixed_step is not None:
            given = f"fixed_step = {o.fixed_step:g} m"
        elif o.first_step is not None and distance == 0.0:
            given = f"first_step = {o.first_step:g} m"
        else:
            given = (f"tol = {o.tol:g} gives a first step 0.01 sqrt(tol) (h/L) s* of "
                     f"{ds:.3g} m, which")
        raise ValueError(f"{given} is below the shortest step that moves the run on from "
                         f"s = {distance:g} m, {min_step:.3g} m ({STEP_ROUNDING} rounding units "
                         f"of the sliding distance or of the fastest relaxation distance)")

    @staticmethod
    def land(ds, s, target, end):
        """Shorten (or stretch by at most ``LANDING_SLACK``) ``ds`` to land on ``target``.

        ``end`` is the distance limit; every argument in m.
        """
        ds = min(ds, end - s)
        if target is not None and target - s <= ds * (1 + LANDING_SLACK):
            ds = target - s
        return ds

    def after_accept(self, ds, err, scheme):
        """Next step after an accepted one of length ``ds`` with scaled error ``err``."""
        if self.fixed:
            return self.options.fixed_step
        q = scheme.error_order
        growth = min(scheme.max_growth,
                     SAFETY * err ** (-1.0 / (q + 1)) if err > 0 else scheme.max_growth)
        return ds * max(MIN_ACCEPT_FACTOR, growth)

    def before_crossing(self, ds, crossing):
        """Cut ``ds`` (m) to end just past the last crossing within it, ``crossing`` m ahead.

        A crossing within a step puts a kink of the wear rate in it, whose
        error the estimate of the step before did not foresee; one near the
        step's end costs little, one near its middle most.  A step that the
        current rates say pixels cross in ends ``CROSSING_MARGIN`` past the
        last of them (``-inf``: none), but is cut to no less than
        ``CROSSING_CUT`` of its length: dense crossings leave it as it is.
        Fixed steps are not cut.
        """
        if self.fixed or not 0.0 <= crossing < ds:
            return ds
        return min(ds, max(crossing * (1.0 + CROSSING_MARGIN), CROSSING_CUT * ds))

    def rejects(self, err, jump):
        """Whether an attempt of scaled error ``err`` is rejected (never a jump or a fixed step)."""
        return not self.fixed and not jump and err > 1.0

    @staticmethod
    def after_reject(ds, err, scheme):
        """Retry length after a step rejected with scaled error ``err > 1``."""
        q = scheme.error_order
        return ds * max(MIN_REJECT_FACTOR, SAFETY * err ** (-1.0 / (q + 1)))

    @staticmethod
    def after_failure(ds):
        """Retry length after a failed attempt."""
        return FAILURE_FACTOR * ds


class StopTests:
    """When the run ends, and when it jumps to the steady state.

    The run is steady when the wear-rate spread is below ``spread_tol`` and
    the shape changes by less than ``shape_tol`` f* per s* (across
    interfaces: once the face is below every interface); it ends
    (resumable) at ``end_depth`` of mean worn depth (status ``"depth"``),
    ``distance_limit`` or ``max_steps``.  Once the spread is
    below ``jump_spread`` and no snapshot is pending it jumps; after
    ``MAX_JUMPS`` jumps without reaching the steady state it stops as
    stagnating.  ``max_failures`` failed attempts in a row (one at a fixed
    step) end it as failed.

    The tests hold no state of the run: the loop hands them the figures
    they judge (the jump count is part of the run's checkpointed state,
    :class:`transient.result.RunState`).

    Parameters
    ----------
    options : transient.options.RunOptions
    s_star : float, m
    """

    def __init__(self, options, s_star):
        self.options = options
        self.s_star = s_star

    def check(self, spread, shape_rate, distance, steps, *, held=False, depth=None,
              depth_resolution=0.0, columnar=True):
        """``(status, message)`` if the run is over at its current point, else None.

        Parameters
        ----------
        spread : float
            Last recorded wear-rate spread (``(max - min) / mean`` of
            ``k p^m``; 1 with pixels out of contact).
        shape_rate : float
            Last recorded shape change, f* per s*.
        distance : float, m
            Sliding distance reached.
        steps : int
            Accepted steps so far.
        held : bool, optional
            A breakpoint of the load programme lies ahead: not steady yet
            (default False).
        depth : float or None, optional
            Mean worn depth over the face, m, which ``end_depth`` ends.
        depth_resolution : float, optional, m
            The worn depth the run resolves (:func:`depth_resolution`;
            default 0): ``end_depth`` is reached within it.
        columnar : bool, optional
            Whether the phases no longer change below the face (default
            True); until then the run is not steady.
        """
        o, s_star = self.options, self.s_star
        if (columnar and not held and spread < o.spread_tol
                and shape_rate < o.shape_tol):
            return "steady", (f"steady state at s = {distance:.6g} m "
                              f"({distance / s_star:.6g} s*): wear-rate spread "
                              f"{spread:.3g}, shape change {shape_rate:.3g} f*/s*")
        if o.end_depth is not None and depth is not None and self.depth_reached(
                depth, depth_resolution):
            within = ("" if depth >= o.end_depth * (1 - DEPTH_SLACK) else
                      f", within the {depth_resolution:.3g} m the run resolves")
            return "depth", (f"reached end_depth {o.end_depth:.6g} m (mean worn depth "
                             f"{depth:.6g} m{within}) at s = {distance:.6g} m "
                             f"({distance / s_star:.6g} s*)")
        if distance >= o.distance_limit * (1 - _DISTANCE_SLACK):
            return "stopped", (f"reached distance_limit {o.distance_limit:.6g} m before the "
                               f"steady state (spread {spread:.3g}); resume with a "
                               f"larger distance_limit")
        if steps >= o.max_steps:
            return "stopped", (f"reached max_steps {o.max_steps} before the steady state "
                               f"(s = {distance:.6g} m = {distance / s_star:.6g} s*, spread "
                               f"{spread:.3g}); resume with a larger max_steps")
        return None

    def jump_due(self, spread, target, fixed, columnar=True):
        """Whether the next attempt is a jump.

        Parameters
        ----------
        spread : float
            Last recorded wear-rate spread.
        target : float or None, m
            Distance of the next pending snapshot (None: none pending).
        fixed : bool
            Fixed steps (never a jump).
        columnar : bool, optional
            Whether the phases no longer change below the face: only then
            is the steady state the limit of a long step (default True).
        """
        return columnar and not fixed and target is None and spread < self.options.jump_spread

    def stagnation(self, jumps, spread):
        """``(status, message)`` if ``jumps`` jumps have not reached the steady state, else None.

        Asked before a jump: after ``MAX_JUMPS`` of them the next is not taken.

        Parameters
        ----------
        jumps : int
            Jumps taken so far.
        spread : float
            Last recorded wear-rate spread.
        """
        if jumps >= MAX_JUMPS:
            return "stopped", (f"the wear-rate spread stagnates at "
                               f"{spread:.3g} above spread_tol "
                               f"{self.options.spread_tol:.3g} after {jumps} "
                               f"jumps: loosen spread_tol or tighten the contact tolerance")
        return None

    def give_up(self, consecutive, fixed, ds, distance, reason):
        """``(status, message)`` once failed attempts end the run, else None (retry smaller).

        Parameters
        ----------
        consecutive : int
            Failed attempts in a row, the last one included.
        fixed : bool
            Fixed steps: a failure cannot be retried smaller.
        ds : float, m
            Length of the failed attempt.
        distance : float, m
            Where it started.
        reason : Exception
            Why it failed (:class:`transient.solver.StepFailure`).
        """
        if consecutive >= self.options.max_failures or fixed:
            s_star = self.s_star
            return "failed", (f"step of {ds / s_star:.3g} s* at s = "
                              f"{distance / s_star:.6g} s* failed {consecutive} "
                              f"times: {reason}")
        return None

    def short_step(self, ds, min_step, distance, *, at_depth=None, depth=None):
        """``(status, message)`` of a run whose next step ``ds`` (m) is below ``min_step``.

        No shorter retry can move the run on.  Where the step was cut to
        land on ``end_depth`` (its aim ``at_depth``, m, within ``min_step``
        of ``distance``) the run has reached it as closely as the sliding
        distance resolves (status ``"depth"``, mean worn depth ``depth``,
        m); otherwise the steps have shrunk away (``"failed"``): the error
        estimate does not fall with the step.

        Parameters
        ----------
        ds, min_step, distance : float, m
            The planned step, the shortest step
            (:meth:`StepController.min_step`) and the distance reached.
        at_depth : float or None, optional, m
            The distance the step aimed at to land on ``end_depth``.
        depth : float or None, optional, m
            The mean worn depth reached.
        """
        s_star = self.s_star
        at = f"s = {distance:.6g} m ({distance / s_star:.6g} s*)"
        if at_depth is not None and at_depth - distance <= min_step:
            return "depth", (f"reached end_depth {self.options.end_depth:.6g} m as closely as "
                             f"the sliding distance resolves (mean worn depth {depth:.6g} m) "
                             f"at {at}")
        return "failed", (f"the step fell to {ds:.3g} m at {at}, below the {min_step:.3g} m "
                          f"that move the run on: the error estimate does not fall with the "
                          f"step (tol = {self.options.tol:g} below round-off?)")

    def end(self):
        """The distance limit, m."""
        return self.options.distance_limit

    def depth_reached(self, depth, resolution):
        """Whether the mean worn depth ``depth`` (m) has reached ``end_depth``.

        Within ``DEPTH_SLACK`` of it, or within the worn depth the run
        resolves, ``resolution`` (m, :func:`depth_resolution`).
        """
        end = self.options.end_depth
        return depth >= end * (1 - DEPTH_SLACK) or depth >= end - resolution

    def check_end_depth(self, resolution):
        """Refuse an ``end_depth`` within the worn depth the run resolves (m): 0 has reached it.

        Raises
        ------
        ValueError
            ``end_depth`` at or below ``resolution``, naming both.
        """
        end = self.options.end_depth
        if end is not None and end <= resolution:
            raise ValueError(f"end_depth = {end:g} m is below the mean worn depth this run "
                             f"resolves, {resolution:.3g} m ({DEPTH_ROUNDING} rounding units "
                             f"of the face's displacement): the run would end before its first "
                             f"step; give a larger end_depth")

    def depth_landing(self, distance, ds, before, after, resolution=0.0):
        """Where to land instead of a trial that went past ``end_depth``, m, or None.

        The trial of length ``ds`` (m) from ``distance`` (m) took the mean
        worn depth from ``before`` to ``after`` (m); None unless ``after``
        is past ``end_depth`` by more than ``DEPTH_SLACK`` of it and the
        worn depth the run resolves, ``resolution`` (m).  The secant of the
        mean worn depth over the trial: the rate at its start misses the
        step's crossings.
        """
        end = self.options.end_depth
        if end is None or after <= end * (1 + DEPTH_SLACK) or after <= end + resolution:
            return None
        return distance + ds * (end - before) / (after - before)

    def depth_target(self, distance, depth, rate):
        """Distance (m) at which the mean worn depth reaches ``end_depth``, or None.

        Linear from the mean worn depth ``depth`` (m) and its rate ``rate``
        (m/m) at ``distance`` (m): a landing target the steps aim at, which
        they approach as the rate settles (None without ``end_depth`` or
        a positive rate).
        """
        end = self.options.end_depth
        if end is None or not rate > 0:
            return None
        return distance + max(end - depth, 0.0) / rate
