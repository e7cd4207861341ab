"""The run-in: wear a punch face from its initial shape to the steady state.

:func:`run_in` integrates ``dw/ds = k P(w)^m`` (see :mod:`transient.stepping`)
from the initial face with a registered scheme, with adaptive steps from
the scheme's error estimate, until the wear rates equalise; it records a
history, takes snapshots and hands resumable checkpoints to a callback.
:func:`compare_with_steady` measures the agreement of the final face with
the closed-form steady face (eq. 9, :func:`steady.solution.solve`).
:func:`write_run` / :func:`read_run` store a run in HDF5.

Step control
------------
The local error estimate of a step is measured on the *shape*: its mean
over the face is removed (the rigid offset is irrelevant and integrated
exactly) and its rms over the face is compared with ``tol * f*``
(``f* = pbar a / E*``, PHYSICS.md "Natural scales").  Accepted steps grow
by at most the scheme's ``max_growth``; rejected or failed steps shrink.
Steps land exactly on the snapshot distances.  Explicit Euler is further
limited to 0.9 times its stability limit.

Steady state
------------
The run stops when both

- the spread of the wear rate over the contact, ``(max - min) / mean`` of
  ``k p^m`` over the pixels with ``p > 0`` (or over the whole face when
  some pixel is out of contact: then the spread is 1), is below
  ``spread_tol``, and
- the rms change of the shape per run-in distance ``s* = a / (k_min E*)``,
  in units of ``f*``, is below ``shape_tol``.

Jump to the steady state
------------------------
As ``ds -> infinity`` the implicit Euler step ``(K + ds k) p = d - w``
gives ``k p -> C``: the steady pressure (eq. 7) with an error of order
``s* / ds``.  Once the spread is below ``jump_spread`` and no snapshot is
pending, the run takes implicit Euler steps of ``jump_step`` s* (default
``1e8``) until the criteria hold; a single such step is normally enough.
The face after an implicit stage is rebuilt from its pressure,
``w = d - K p`` on the contact (the displacement the contact solver
returns minus the shift), so that the solver's residual, which scales with
the shifted operator, does not enter the face.

Reproducibility
---------------
A run's future depends only on the state stored in a checkpoint (face,
pressure, previous face and rate, next step, counters); a resumed run
repeats the uninterrupted one bit for bit on the same machine and
library versions.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import pathlib
import time
import types

import numpy as np

from steady import reference

from .stepping import StepFailure, StepState, get_scheme

__all__ = [
    "FORMAT",
    "HISTORY_UNITS",
    "RunOptions",
    "RunResult",
    "SteadyComparison",
    "VERSION",
    "compare_with_steady",
    "face_rms_slope",
    "read_run",
    "run_in",
    "wear_rate_spread",
    "write_run",
]

logger = logging.getLogger(__name__)

#: ``format`` attribute of a run file.
FORMAT = "runin.transient"
#: Layout version of a run file.
VERSION = 1

#: History datasets and their units.
HISTORY_UNITS = {
    "distance": "m",
    "step": "m",
    "rms_slope": "1",
    "normalised_rms_slope": "1 (rms_slope / grad_f0)",
    "rms_slope_fd": "1 (finite differences of the worn face)",
    "spread": "1 ((max - min) / mean of k p^m over the contact)",
    "shape_rate": "1 (rms shape change / f* per s*)",
    "peak_pressure": "Pa",
    "contact_fraction": "1",
    "approach": "m",
    "worn_volume": "m^3",
    "solves": "1",
}

_STATUSES = ("running", "steady", "stopped", "failed")


@dataclasses.dataclass(frozen=True)
class RunOptions:
    """Options of :func:`run_in`; distances in units of ``s* = a / (k_min E*)``.

    Attributes
    ----------
    scheme : str
        Registered integrator (default ``"sdirk2"``).
    tol : float
        Local error per step, rms over the face of the shape error in units of
        ``f*`` (default 1e-5).
    step : float or None
        Fixed step in s* (no adaptivity, no jump); default None (adaptive).
    initial_step : float or None
        First adaptive step in s*; default ``0.01 * sqrt(tol) * h/a``
        (the fast scale, where the flat punch's edge relaxes).
    spread_tol : float
        Steady when the wear-rate spread is below this (default 1e-6) ...
    shape_tol : float
        ... and the shape changes by less than this many ``f*`` per s*
        (default 1e-6).
    jump_spread : float
        Jump to the steady state once the spread is below this
        (default 1e-3; 0 disables, ``inf`` jumps at once).
    jump_step : float
        Length of a jump, in s* (default 1e8).
    max_distance : float
        Stop (resumable, status ``"stopped"``) beyond this distance in s*
        (default 1e12).
    max_steps : int
        Stop after this many accepted steps (default 100000).
    snapshots : tuple of float
        Distances in s* at which the face and the pressure are stored; steps
        land on them exactly.
    max_failures : int
        Consecutive failed attempts before the run stops (default 20).
    checkpoint_interval : float
        Wall-clock seconds between checkpoints (default 10; 0 = every step).
    """

    scheme: str = "sdirk2"
    tol: float = 1e-5
    step: float | None = None
    initial_step: float | None = None
    spread_tol: float = 1e-6
    shape_tol: float = 1e-6
    jump_spread: float = 1e-3
    jump_step: float = 1e8
    max_distance: float = 1e12
    max_steps: int = 100000
    snapshots: tuple = ()
    max_failures: int = 20
    checkpoint_interval: float = 10.0

    def __post_init__(self):
        get_scheme(self.scheme)
        for name in ("tol", "spread_tol", "shape_tol", "jump_step", "max_distance"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0 and not math.isnan(value)):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        for name in ("step", "initial_step"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive distance in s*, got {value!r}")
        if not (self.jump_spread >= 0):
            raise ValueError(f"jump_spread must be >= 0, got {self.jump_spread!r}")
        if int(self.max_steps) != self.max_steps or self.max_steps < 1:
            raise ValueError(f"max_steps must be a positive integer, got {self.max_steps!r}")
        if int(self.max_failures) != self.max_failures or self.max_failures < 1:
            raise ValueError(f"max_failures must be a positive integer, got "
                             f"{self.max_failures!r}")
        if not (self.checkpoint_interval >= 0):
            raise ValueError(f"checkpoint_interval must be >= 0 s, got "
                             f"{self.checkpoint_interval!r}")
        snaps = tuple(float(s) for s in self.snapshots)
        if any(not (math.isfinite(s) and s >= 0) for s in snaps):
            raise ValueError(f"snapshots must be non-negative distances in s*, got {snaps!r}")
        object.__setattr__(self, "snapshots", tuple(sorted(set(snaps))))


@dataclasses.dataclass(frozen=True, eq=False)
class RunResult:
    """A run-in, finished or in progress (a checkpoint is a ``"running"`` result).

    Attributes
    ----------
    status : str
        ``"running"``, ``"steady"`` (converged), ``"stopped"`` (limit reached)
        or ``"failed"`` (a step could not be completed).
    message : str
    scheme : str
    distance : float, m
        Sliding distance reached.
    steps, rejected, failures : int
        Accepted steps, rejected steps (error too large), failed attempts.
    solves, iterations : int
        Contact solves and contact-solver iterations.
    wall_time : float, s
    height : ndarray, shape (n, n), m
        Face height (worn depth + initial shape) minus ``offset``.
    offset : float, m
        Constant removed from ``height`` (the rigid part of the wear).
    pressure : ndarray, shape (n, n), Pa
        Contact pressure of the face.
    approach : float, m
        Rigid approach, in the frame of ``height``.
    initial_height : ndarray, shape (n, n), m
    previous_height, previous_rate : ndarray, shape (n, n), or None
        State of the previous accepted point (for resuming).
    previous_step, next_step : float or None, m
    history : mapping of str to ndarray, shape (steps + 1,)
        See :data:`HISTORY_UNITS`.
    snapshot_distance : ndarray, shape (k,), m
    snapshot_height : ndarray, shape (k, n, n), m
        ``worn depth + initial shape`` at the snapshots (NaN off the face).
    snapshot_pressure : ndarray, shape (k, n, n), Pa
    depth_scale, run_in_distance, fast_distance, mean_pressure,
    reference_slope : float
        ``f*`` (m), ``s*`` (m), ``h / (k_max E*)`` (m), ``F / A`` (Pa),
        ``grad_f0`` (eq. 12).
    """

    status: str
    message: str
    scheme: str
    distance: float
    steps: int
    rejected: int
    failures: int
    solves: int
    iterations: int
    wall_time: float
    height: np.ndarray
    offset: float
    pressure: np.ndarray
    approach: float
    initial_height: np.ndarray
    previous_height: np.ndarray | None
    previous_rate: np.ndarray | None
    previous_step: float | None
    next_step: float | None
    history: types.MappingProxyType
    snapshot_distance: np.ndarray
    snapshot_height: np.ndarray
    snapshot_pressure: np.ndarray
    depth_scale: float
    run_in_distance: float
    fast_distance: float
    mean_pressure: float
    reference_slope: float

    @property
    def success(self):
        """Whether the run reached the steady state."""
        return self.status == "steady"

    @property
    def face(self):
        """Pixels of the punch face, shape (n, n), bool."""
        return np.isfinite(self.worn_depth)

    @property
    def worn_depth(self):
        """Depth worn off since the start, m, shape (n, n); NaN off the face."""
        return self.height + self.offset - self.initial_height

    @property
    def face_height(self):
        """Face height ``d - w`` in the convention of the steady face ``f_inf = K p``, m.

        Equals ``K p`` on the contact; defined up to a constant; NaN off the face.
        """
        return self.approach - self.height


def _rms_face(field, face):
    v = field[face]
    return float(np.sqrt(np.mean(v * v)))


def _shape_rms(field, face):
    v = field[face]
    v = v - v.mean()
    return float(np.sqrt(np.mean(v * v)))


def _masked_gradient(field, mask, h):
    """Finite-difference gradient using only pixels in ``mask`` (central where possible)."""
    out = []
    for axis in (0, 1):
        f = np.where(mask, field, 0.0)
        fp = np.roll(f, -1, axis)
        fm = np.roll(f, 1, axis)
        mp = np.roll(mask, -1, axis)
        mm = np.roll(mask, 1, axis)
        idx = np.arange(mask.shape[axis])
        edge_p = (idx == mask.shape[axis] - 1)
        edge_m = (idx == 0)
        shape = [1, 1]
        shape[axis] = -1
        mp = mp & ~edge_p.reshape(shape)
        mm = mm & ~edge_m.reshape(shape)
        g = np.where(mp & mm, (fp - fm) / (2 * h),
                     np.where(mp, (fp - f) / h, np.where(mm, (f - fm) / h, 0.0)))
        out.append(np.where(mask, g, 0.0))
    return out


def face_rms_slope(halfspace, face, height, pressure, approach):
    """Rms slope of the worn face over the face pixels, dimensionless.

    On the contact the face is ``d - w = K p``, whose gradient is the exact
    kernel derivative convolved with the pressure (the definition of
    :func:`steady.solution.solve`, so that the final value compares with
    it); the gap ``w - (d - K p)`` off the contact adds its finite-difference
    gradient.

    This is the slope of the half-space surface under the pixel pressure.
    For the flat punch at ``s = 0`` it is not zero but about 0.6 ``grad_f0``
    (measured 0.589, 0.596, 0.598, 0.600 at n = 32, 64, 128, 256): the
    pixel pressure of the edge singularity, ``~ (a/h)^(1/2)``, makes ``K p``
    ripple between the pixel centres of the rim, whose share of the face
    falls like ``h/a``, so the rms does not vanish under refinement.  The
    run-in removes it with the singularity.  The history also records
    ``rms_slope_fd``, finite differences of the worn face itself (zero for
    a flat face).

    Parameters
    ----------
    halfspace : HalfSpace
    face : ndarray of bool, shape (n, n)
    height : ndarray, shape (n, n), m
    pressure : ndarray, shape (n, n), Pa
        Contact pressure of ``height``.
    approach : float, m

    Returns
    -------
    float
    """
    pressure_q = halfspace.forward(pressure)
    gx, gy = halfspace.gradient(pressure, pressure_q=pressure_q)
    contact = pressure > 0
    if np.any(face & ~contact):
        kp = halfspace.displacement_q(pressure_q)
        gap = np.where(face, height - (approach - kp), 0.0)
        gap = np.where(contact, 0.0, np.maximum(gap, 0.0))
        dx, dy = _masked_gradient(gap, face, halfspace.h)
        gx = gx - dx
        gy = gy - dy
    s2 = gx * gx + gy * gy
    return float(np.sqrt(np.mean(s2[face])))


def wear_rate_spread(problem, pressure):
    """Spread of the wear rate, the steady-state test (eq. 3).

    Parameters
    ----------
    problem : transient.stepping.WearProblem
    pressure : ndarray, shape (n, n), Pa

    Returns
    -------
    float
        ``(max - min) / mean`` of ``k p^m`` over the face; 1 when some face
        pixel is out of contact (its rate is 0).
    """
    face = problem.face
    if np.any(pressure[face] <= 0):
        return 1.0
    r = problem.rate(pressure)[face]
    return float((r.max() - r.min()) / r.mean())


class _Run:
    """Mutable state of a run in progress."""

    def __init__(self, problem, options):
        self.problem = problem
        self.options = options
        self.scheme = get_scheme(options.scheme)
        self.s_star = problem.run_in_distance
        self.f_star = problem.depth_scale
        hs = problem.halfspace
        self.grad_f0 = reference.reference_slope(
            reference.mean_pressure(problem.normal_force, problem.radius), hs.E_star)
        self.history = {name: [] for name in HISTORY_UNITS}
        self.snap_d, self.snap_h, self.snap_p = [], [], []

    # -- recording -----------------------------------------------------
    def record(self, step, shape_rate):
        p = self.problem
        hist = self.history
        rms = face_rms_slope(p.halfspace, p.face, self.height, self.pressure, self.approach)
        hist["distance"].append(self.s)
        hist["step"].append(step)
        hist["rms_slope"].append(rms)
        hist["normalised_rms_slope"].append(rms / self.grad_f0)
        gx, gy = _masked_gradient(self.height, p.face, p.halfspace.h)
        hist["rms_slope_fd"].append(float(np.sqrt(np.mean((gx * gx + gy * gy)[p.face]))))
        hist["spread"].append(wear_rate_spread(p, self.pressure))
        hist["shape_rate"].append(shape_rate)
        hist["peak_pressure"].append(float(self.pressure.max()))
        hist["contact_fraction"].append(float(np.mean(self.pressure[p.face] > 0)))
        hist["approach"].append(self.approach + self.offset)
        worn = self.height + self.offset - self.initial_height
        hist["worn_volume"].append(float(np.sum(worn[p.face])) * p.halfspace.h ** 2)
        hist["solves"].append(p.solves)

    def snapshot(self):
        face = self.problem.face
        self.snap_d.append(self.s)
        self.snap_h.append(np.where(face, self.height + self.offset, np.nan))
        self.snap_p.append(self.pressure.copy())

    def result(self, status, message):
        n = self.problem.n
        k = len(self.snap_d)
        face = self.problem.face
        return RunResult(
            status=status, message=message, scheme=self.scheme.name, distance=self.s,
            steps=self.steps, rejected=self.rejected, failures=self.failures,
            solves=self.problem.solves, iterations=self.problem.iterations,
            wall_time=self.wall_time + (time.monotonic() - self.t0),
            height=np.where(face, self.height, np.nan), offset=self.offset,
            pressure=self.pressure.copy(), approach=self.approach,
            initial_height=np.where(face, self.initial_height, np.nan),
            previous_height=None if self.prev_height is None else self.prev_height.copy(),
            previous_rate=None if self.prev_rate is None else self.prev_rate.copy(),
            previous_step=self.prev_step, next_step=self.next_step,
            history=types.MappingProxyType({k_: np.array(v, dtype=float if k_ != "solves"
                                                         else np.int64)
                                            for k_, v in self.history.items()}),
            snapshot_distance=np.array(self.snap_d, dtype=float),
            snapshot_height=np.array(self.snap_h).reshape(k, n, n),
            snapshot_pressure=np.array(self.snap_p).reshape(k, n, n),
            depth_scale=self.f_star, run_in_distance=self.s_star,
            fast_distance=self.problem.fast_distance,
            mean_pressure=self.problem.mean_pressure, reference_slope=self.grad_f0)

    # -- set-up --------------------------------------------------------
    def start(self, initial_height):
        p = self.problem
        face = p.face
        h0 = np.where(face, np.asarray(initial_height, dtype=float), 0.0)
        if h0.shape != (p.n, p.n):
            raise ValueError(f"initial_height must have shape {(p.n, p.n)}, got {h0.shape}")
        if not np.all(np.isfinite(h0[face])):
            raise ValueError("initial_height must be finite on the face")
        self.initial_height = h0
        self.offset = float(h0[face].mean())
        self.height = np.where(face, h0 - self.offset, 0.0)
        res = p.contact(self.height)
        self.pressure = res.pressure
        self.approach = float(res.approach)
        self.s = 0.0
        self.steps = self.rejected = self.failures = 0
        self.wall_time = 0.0
        self.prev_height = self.prev_rate = None
        self.prev_step = None
        o = self.options
        if o.step is not None:
            self.next_step = o.step * self.s_star
        elif o.initial_step is not None:
            self.next_step = o.initial_step * self.s_star
        else:
            self.next_step = 0.01 * math.sqrt(o.tol) * p.halfspace.h / p.radius * self.s_star
        self.record(0.0, math.inf)
        self.snap_index = 0
        self._take_due_snapshots()

    def restore(self, saved):
        p = self.problem
        face = p.face
        if saved.height.shape != (p.n, p.n):
            raise ValueError(f"checkpoint grid {saved.height.shape} does not match the "
                             f"problem's {(p.n, p.n)}")

        def clean(a):
            return None if a is None else np.where(face, a, 0.0)

        self.initial_height = clean(saved.initial_height)
        self.height = clean(saved.height)
        self.offset = float(saved.offset)
        self.pressure = np.array(saved.pressure, dtype=float)
        self.approach = float(saved.approach)
        self.prev_height = clean(saved.previous_height)
        self.prev_rate = clean(saved.previous_rate)
        self.prev_step = saved.previous_step
        self.next_step = saved.next_step
        self.s = float(saved.distance)
        self.steps, self.rejected, self.failures = saved.steps, saved.rejected, saved.failures
        p.solves, p.iterations = saved.solves, saved.iterations
        self.wall_time = saved.wall_time
        self.history = {k: list(v.tolist()) for k, v in saved.history.items()}
        self.snap_d = list(saved.snapshot_distance.tolist())
        self.snap_h = list(saved.snapshot_height)
        self.snap_p = list(saved.snapshot_pressure)
        self.snap_index = len(self.snap_d)

    def _take_due_snapshots(self):
        snaps = self.options.snapshots
        while (self.snap_index < len(snaps)
               and snaps[self.snap_index] * self.s_star <= self.s * (1 + 1e-12)):
            self.snapshot()
            self.snap_index += 1

    # -- stepping ------------------------------------------------------
    def pending_target(self):
        snaps = self.options.snapshots
        if self.snap_index < len(snaps):
            return snaps[self.snap_index] * self.s_star
        return None

    def loop(self, on_step, on_checkpoint):
        o, p, scheme = self.options, self.problem, self.scheme
        face = p.face
        tol_abs = o.tol * self.f_star
        last_ckpt = time.monotonic()
        consecutive = 0
        jumps = 0
        fixed = o.step is not None
        while True:
            spread = self.history["spread"][-1]
            shape_rate = self.history["shape_rate"][-1]
            if spread < o.spread_tol and shape_rate < o.shape_tol:
                return "steady", (f"steady state at s = {self.s:.6g} m "
                                  f"({self.s / self.s_star:.6g} s*): wear-rate spread "
                                  f"{spread:.3g}, shape change {shape_rate:.3g} f*/s*")
            if self.s >= o.max_distance * self.s_star * (1 - 1e-12):
                return "stopped", (f"reached max_distance {o.max_distance:.6g} s* before the "
                                   f"steady state (spread {spread:.3g}); resume with a "
                                   f"larger max_distance")
            if self.steps >= o.max_steps:
                return "stopped", (f"reached max_steps {o.max_steps} before the steady state "
                                   f"(s = {self.s / self.s_star:.6g} s*, spread "
                                   f"{spread:.3g}); resume with a larger max_steps")
            target = self.pending_target()
            jump = (not fixed and target is None and spread < o.jump_spread)
            if jump:
                jumps += 1
                if jumps > 5:
                    return "stopped", (f"the wear-rate spread stagnates at {spread:.3g} above "
                                       f"spread_tol {o.spread_tol:.3g} after {jumps - 1} "
                                       f"jumps: loosen spread_tol or tighten the contact "
                                       f"tolerance")
                ds = o.jump_step * self.s_star
                step_scheme = get_scheme("implicit_euler")
            else:
                ds = self.next_step
                step_scheme = scheme
                if scheme.explicit:
                    limit = 0.9 * p.stable_step(self.pressure)
                    if fixed and ds > limit / 0.9:
                        raise ValueError(
                            f"fixed step {ds / self.s_star:.6g} s* exceeds the explicit Euler "
                            f"stability limit {limit / 0.9 / self.s_star:.6g} s*")
                    ds = min(ds, limit)
            remaining = o.max_distance * self.s_star - self.s
            ds = min(ds, remaining)
            if target is not None:
                if target - self.s <= ds * (1 + 1e-9):
                    ds = target - self.s
            # A jump starts from the closed-form steady pressure, its limit.
            state = StepState(self.height, p.steady_pressure() if jump else self.pressure,
                              self.approach, self.prev_height, self.prev_rate, self.prev_step)
            try:
                trial = step_scheme.step(p, state, ds)
                err = _shape_rms(trial.error, face) / tol_abs
                if not (math.isfinite(err) and np.all(np.isfinite(trial.height[face]))):
                    raise StepFailure("non-finite face or error estimate")
                if _shape_rms(trial.height, face) > 1e6 * self.f_star:
                    raise StepFailure("face relief above 1e6 f*: divergence")
            except StepFailure as exc:
                self.failures += 1
                consecutive += 1
                logger.info("step of %.3g s* failed (%s); retrying smaller", ds / self.s_star,
                            exc)
                if consecutive >= o.max_failures or fixed:
                    return "failed", (f"step of {ds / self.s_star:.3g} s* at s = "
                                      f"{self.s / self.s_star:.6g} s* failed {consecutive} "
                                      f"times: {exc}")
                self.next_step = 0.25 * ds
                continue
            consecutive = 0
            q = step_scheme.error_order
            if not fixed and not jump and err > 1.0:
                self.rejected += 1
                self.next_step = ds * max(0.1, 0.9 * err ** (-1.0 / (q + 1)))
                logger.debug("rejected %.3g s* (err %.3g)", ds / self.s_star, err)
                continue
            # Accept.
            new_height = np.where(face, trial.height, 0.0)
            c = float(new_height[face].mean())
            new_height = np.where(face, new_height - c, 0.0)
            change = _shape_rms(new_height - self.height, face)
            shape_rate = change / self.f_star / (ds / self.s_star)
            self.prev_height = np.where(face, self.height - c, 0.0)
            self.prev_rate = p.rate(self.pressure)
            self.prev_step = ds
            self.height = new_height
            self.offset += c
            self.pressure = trial.pressure
            self.approach = trial.approach - c
            self.s += ds
            self.steps += 1
            if fixed:
                self.next_step = o.step * self.s_star
            elif not jump:
                growth = min(scheme.max_growth,
                             0.9 * err ** (-1.0 / (q + 1)) if err > 0 else scheme.max_growth)
                self.next_step = ds * max(0.2, growth)
            self.record(ds, shape_rate)
            self._take_due_snapshots()
            if on_step is not None:
                on_step(self)
            if on_checkpoint is not None and \
                    time.monotonic() - last_ckpt >= o.checkpoint_interval:
                on_checkpoint(self.result("running", "in progress"))
                last_ckpt = time.monotonic()


def run_in(problem, initial_height, options=None, *, resume=None, on_step=None,
           on_checkpoint=None):
    """Wear the face from ``initial_height`` until the wear rates equalise.

    Parameters
    ----------
    problem : transient.stepping.WearProblem
    initial_height : ndarray, shape (n, n), m
        Initial face (larger = recessed); see :mod:`transient.initial_face`.
    options : RunOptions, optional
    resume : RunResult, optional
        A checkpoint (or a stopped run) to continue from; ``initial_height``
        is then taken from it.
    on_step : callable, optional
        ``on_step(run)`` after each accepted step, with attributes ``s``,
        ``s_star``, ``steps`` and ``history`` (for progress displays).
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
    """
    options = RunOptions() if options is None else options
    run = _Run(problem, options)
    run.t0 = time.monotonic()
    if resume is None:
        run.start(initial_height)
    else:
        run.restore(resume)
    if resume is not None and resume.status == "steady":
        return run.result("steady", resume.message)
    status, message = run.loop(on_step, on_checkpoint)
    log = logger.info if status == "steady" else logger.warning
    log("%s: %s", status, message)
    return run.result(status, message)


@dataclasses.dataclass(frozen=True)
class SteadyComparison:
    """Agreement of a run's final face with the closed-form steady face (eq. 9).

    Attributes
    ----------
    face_error : float
        ``max |(d - w) + c - f_inf| / relief(f_inf)`` over the face, ``c`` the
        best (minimax) constant, relief = max - min of ``f_inf``.
    face_rms_error : float
        Rms of the same difference with the least-squares constant, / relief.
    rms_slope, steady_rms_slope : float
        Plain pixel rms slopes of the run's face and of ``f_inf`` (exact kernel
        gradient at the pixel centres of the face).
    rms_slope_error : float
        ``rms_slope / steady_rms_slope - 1``.
    phase_pressures, steady_phase_pressures : ndarray, shape (P,), Pa
        Mean pressure on each phase, run and eq. 7.
    phase_pressure_error : float
        ``max_i |p_i / p_i,steady - 1|``.
    """

    face_error: float
    face_rms_error: float
    rms_slope: float
    steady_rms_slope: float
    rms_slope_error: float
    phase_pressures: np.ndarray
    steady_phase_pressures: np.ndarray
    phase_pressure_error: float

    def summary(self):
        """One line per figure, for the terminal."""
        pp = ", ".join(f"{a:.6g}/{b:.6g}" for a, b in
                       zip(self.phase_pressures, self.steady_phase_pressures))
        return (f"face shape error (max, / steady relief): {self.face_error:.3e}\n"
                f"face shape error (rms, / steady relief): {self.face_rms_error:.3e}\n"
                f"rms slope: {self.rms_slope:.6g} vs steady {self.steady_rms_slope:.6g} "
                f"(relative {self.rms_slope_error:+.3e})\n"
                f"phase pressures (run/steady, Pa): {pp} "
                f"(max relative {self.phase_pressure_error:.3e})")


def compare_with_steady(result, steady, halfspace, labels):
    """Compare a run's face with the steady face.

    Parameters
    ----------
    result : RunResult
    steady : steady.solution.SteadyResult
        For the same grid, phases, wear coefficients, force and exponent.
    halfspace : HalfSpace
    labels : ndarray, shape (n, n), int
        Phase of each pixel, -1 off the face.

    Returns
    -------
    SteadyComparison
    """
    face = labels >= 0
    fin = steady.face[face]
    ft = result.face_height[face]
    diff = ft - fin
    relief = float(fin.max() - fin.min())
    mid = 0.5 * (diff.max() + diff.min())
    face_error = float(np.max(np.abs(diff - mid)) / relief)
    face_rms = float(np.sqrt(np.mean((diff - diff.mean()) ** 2)) / relief)
    rms = face_rms_slope(halfspace, face, np.where(face, result.height, 0.0),
                         result.pressure, result.approach)
    # The plain pixel rms slope: the definition the run measures (the steady
    # module may also carry a corrected continuum estimate in ``rms_slope``).
    steady_rms = float(getattr(steady, "rms_slope_plain", math.nan))
    if not math.isfinite(steady_rms):
        steady_rms = float(steady.rms_slope)
    n_phases = len(steady.phase_pressures)
    pp = np.array([result.pressure[labels == i].mean() for i in range(n_phases)])
    return SteadyComparison(
        face_error=face_error, face_rms_error=face_rms, rms_slope=rms,
        steady_rms_slope=steady_rms,
        rms_slope_error=rms / steady_rms - 1.0,
        phase_pressures=pp, steady_phase_pressures=np.asarray(steady.phase_pressures),
        phase_pressure_error=float(np.max(np.abs(pp / steady.phase_pressures - 1.0))))


# -- HDF5 -------------------------------------------------------------------

_SCALARS = ("status", "message", "scheme", "distance", "steps", "rejected", "failures",
            "solves", "iterations", "wall_time", "offset", "approach", "depth_scale",
            "run_in_distance", "fast_distance", "mean_pressure", "reference_slope")
_OPTIONAL_SCALARS = ("previous_step", "next_step")


def write_run(path, result, *, attrs=None, arrays=None, comparison=None):
    """Write a run (or checkpoint) atomically: a temporary file, then ``os.replace``.

    Parameters
    ----------
    path : str or path-like
    result : RunResult
    attrs : mapping, optional
        Extra root attributes (scene text, parameters).
    arrays : mapping of str to ndarray, optional
        Extra root datasets (e.g. ``phase``).
    comparison : SteadyComparison, optional
        Stored in the group ``comparison``.
    """
    import h5py

    path = pathlib.Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["version"] = VERSION
        for name in _SCALARS:
            f.attrs[name] = getattr(result, name)
        for name in _OPTIONAL_SCALARS:
            value = getattr(result, name)
            f.attrs[name] = np.nan if value is None else value
        for name, value in (attrs or {}).items():
            f.attrs[name] = value
        units = {"worn_depth": "m", "pressure": "Pa", "height": "m",
                 "initial_height": "m"}
        f.create_dataset("worn_depth", data=result.worn_depth).attrs["units"] = "m"
        f.create_dataset("pressure", data=result.pressure).attrs["units"] = "Pa"
        for name, value in (arrays or {}).items():
            f.create_dataset(name, data=value)
        st = f.create_group("state")
        st.attrs["description"] = "everything a resumed run needs (face up to offset)"
        for name in ("height", "initial_height"):
            st.create_dataset(name, data=getattr(result, name)).attrs["units"] = units[name]
        for name, unit in (("previous_height", "m"), ("previous_rate", "1")):
            value = getattr(result, name)
            if value is not None:
                st.create_dataset(name, data=value).attrs["units"] = unit
        hist = f.create_group("history")
        for name, value in result.history.items():
            hist.create_dataset(name, data=value).attrs["units"] = HISTORY_UNITS[name]
        snaps = f.create_group("snapshots")
        snaps.create_dataset("distance", data=result.snapshot_distance).attrs["units"] = "m"
        snaps.create_dataset("height", data=result.snapshot_height,
                             compression="gzip").attrs["units"] = "m"
        snaps.create_dataset("pressure", data=result.snapshot_pressure,
                             compression="gzip").attrs["units"] = "Pa"
        if comparison is not None:
            g = f.create_group("comparison")
            for fld in dataclasses.fields(comparison):
                value = getattr(comparison, fld.name)
                if isinstance(value, np.ndarray):
                    g.create_dataset(fld.name, data=value).attrs["units"] = "Pa"
                else:
                    g.attrs[fld.name] = value
        f.flush()
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)


def read_run(path):
    """Read a run file written by :func:`write_run`.

    Returns
    -------
    result : RunResult
    attrs : dict
        All root attributes.
    arrays : dict
        Root datasets other than ``worn_depth`` and ``pressure``.

    Raises
    ------
    ValueError
        Not a run file, or an unknown layout version.
    """
    import h5py

    path = pathlib.Path(path)
    try:
        f = h5py.File(path, "r")
    except OSError as err:
        raise ValueError(f"cannot read run file {str(path)!r}: {err}") from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{str(path)!r} is not a run file (format "
                             f"{f.attrs.get('format')!r}, expected {FORMAT!r})")
        if int(f.attrs.get("version", -1)) != VERSION:
            raise ValueError(f"{str(path)!r} has layout version {f.attrs.get('version')!r}, "
                             f"expected {VERSION}")
        attrs = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
        st = f["state"]
        opt = {}
        for name in _OPTIONAL_SCALARS:
            v = float(attrs[name])
            opt[name] = None if math.isnan(v) else v
        kw = {name: attrs[name] for name in _SCALARS}
        for name in ("steps", "rejected", "failures", "solves", "iterations"):
            kw[name] = int(kw[name])
        for name in ("status", "message", "scheme"):
            kw[name] = str(kw[name])
        result = RunResult(
            **kw, **opt,
            height=st["height"][()], initial_height=st["initial_height"][()],
            pressure=f["pressure"][()],
            previous_height=st["previous_height"][()] if "previous_height" in st else None,
            previous_rate=st["previous_rate"][()] if "previous_rate" in st else None,
            history=types.MappingProxyType({k: v[()] for k, v in f["history"].items()}),
            snapshot_distance=f["snapshots/distance"][()],
            snapshot_height=f["snapshots/height"][()],
            snapshot_pressure=f["snapshots/pressure"][()])
        arrays = {k: f[k][()] for k in f if isinstance(f[k], h5py.Dataset)
                  and k not in ("worn_depth", "pressure")}
    return result, attrs, arrays
