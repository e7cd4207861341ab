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
pressure by a hundredth of the last wear-rate spread.  Far from the steady
state that is several orders above ``contact_rtol`` and the warm start
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

import concurrent.futures
import dataclasses
import logging
import math
import time
import types

import numpy as np

from .control import (
    DEPTH_SLACK,
    DIVERGENCE_RELIEF,
    StepController,
    StopTests,
    checkpoint_due,
    contact_tolerance,
)
from .diagnostics import masked_gradient, shape_rms, wear_rate_spread
from .history import DepthRecorder, FaceEstimator
from .options import RunOptions
from .problem import StepFailure, WarmStart
from .stepping import StepState, get_scheme

__all__ = ["COATING_HISTORY_UNITS", "DEPTH_HISTORY_UNITS", "HISTORY_UNITS",
           "PROGRAMME_HISTORY_UNITS", "RunResult", "RunState", "run_in"]

logger = logging.getLogger(__name__)

# History datasets filled by transient.history.FaceEstimator.figures.
_FACE_FIGURES = ("rms_slope", "rms_slope_error", "rms_slope_source", "rms_slope_plain",
                 "rim_layer_pixels", "rms_height", "normalised_rms_slope",
                 "normalised_rms_height")

#: History datasets and their units (docs/model.md, "The run-in history").
HISTORY_UNITS = {
    "distance": "m",
    "step": "m",
    "rms_slope": "1 (continuum rms slope of the worn face over the face, estimated)",
    "normalised_rms_slope": "1 (rms_slope / grad_f0)",
    "rms_slope_error": "1 (estimated discretisation error of rms_slope)",
    "rms_slope_source": "code (0: the initial face's own slope; 1: corrected estimate, full "
                        "contact; 2: the same plus differences off the contact)",
    "rms_slope_plain": "1 (plain pixel rms of the exact-kernel slope of K p, gap differences "
                       "off the contact)",
    "rms_slope_spatial_error": "1 (|S_n - S_m| from the same run on a coarser grid m; empty "
                               "unless transient.spatial_error filled it)",
    "rim_layer_pixels": "1 (width k E* s of the slowest-wearing rim phase's worn layer, in "
                        "pixels)",
    "rms_height": "m (rms of the face about its least-squares plane)",
    "normalised_rms_height": "1 (rms_height / (grad_f0 L), L the outline's scale: a for a "
                             "disk)",
    "spread": "1 ((max - min) / mean of k p^m over the contact)",
    "shape_rate": "1 (rms shape change / f* per s*)",
    "peak_pressure": "Pa",
    "contact_fraction": "1",
    "approach": "m",
    "worn_volume": "m^3",
    "solves": "1",
    "face_deviation": "1 (rms over the face of the face minus the steady face f_inf, their "
                      "least-squares constant removed, / relief max - min of f_inf)",
    "face_deviation_step_error": "1 (rms over the face of the step's local error estimate, "
                                 "its mean removed, / relief of f_inf; 0 at s = 0)",
    "rms_slope_step_error": "1 (rms slope of the step's local error estimate; 0 at s = 0)",
    "rim_worn_depth": "m (worn depth, mean over the rim pixels of the face)",
    "face_deviation_spatial_error": "1 (|D_n - D_m| of face_deviation from the same run on a "
                                    "coarser grid m; empty unless transient.spatial_error "
                                    "filled it)",
    "rms_slope_deviation_spatial_error": "1 (the same of rms_slope / steady_rms_slope - 1, each "
                                         "run's own steady value; empty unless "
                                         "transient.spatial_error filled it)",
}

#: History datasets of a run under a ``[load] programme`` only, and their units.
PROGRAMME_HISTORY_UNITS = {"force": "N (normal force of the load programme at the point)"}

#: History datasets of a run whose phase map changes with depth only (the problem has
#: ``columns``), and their units; ``phase_fraction`` has shape (K, P).
DEPTH_HISTORY_UNITS = {
    "worn_depth_mean": "m (worn depth below the initial surface, mean over the face)",
    "worn_depth_rim": "m (worn depth below the initial surface, mean over the rim pixels)",
    "worn_depth_max": "m (worn depth below the initial surface, largest over the face)",
    "phase_fraction": "1 (area fraction of each phase in the section at the worn depth, along "
                      "phase_name)",
    "crossings": "1 (face pixels that crossed an interface in the step to this point)",
    "quasi_steady_rms_slope": "1 (rms slope of the steady face of the current section, eq. 9, "
                              "by the estimator of rms_slope with the rim layer fully worn)",
    "normalised_quasi_steady_rms_slope": "1 (quasi_steady_rms_slope / grad_f0)",
}

#: History datasets of a depth run under a coating (a layer of one phase over the whole face,
#: :class:`transient.history.Coating`), and their units.
COATING_HISTORY_UNITS = {
    "coating_overshoot": "m (largest depth worn past the coating over the face: positive once "
                         "it is worn through somewhere)",
    "coating_contact_remaining": "m (largest coating thickness left under a contact pixel: "
                                 "negative once the coating is gone from the contact)",
}

# History datasets that files written before them lack (read as NaN when resumed).
_LATER_HISTORY = ("face_deviation", "face_deviation_step_error", "rms_slope_step_error",
                  "rim_worn_depth")


@dataclasses.dataclass(frozen=True, eq=False)
class RunState:
    """What the future of a run depends on beyond its distance, counters, history and snapshots.

    A :class:`RunResult` holds it as :attr:`RunResult.state`; ``run_in(...,
    resume=result)`` continues from it, and :func:`transient.output.write_run`
    stores it (the group ``state`` and root attributes).  Arrays are on the
    problem's grid, shape ``(nx, ny)``; off the face they are NaN in a
    result (a resumed run reads only the face's pixels).

    Attributes
    ----------
    height : ndarray, shape (nx, ny), m
        Face height (worn depth + initial shape) minus ``offset``.
    offset : float, m
        Constant removed from ``height`` (the rigid part of the wear).
    pressure : ndarray, shape (nx, ny), Pa
        Contact pressure of the face.
    approach : float, m
        Rigid approach, in the frame of ``height``.
    initial_height : ndarray, shape (nx, ny), m
        The face the run started from.
    previous_height : ndarray, shape (nx, ny), m, or None
        ``height`` at the previous accepted point, in the frame of the
        current ``offset`` (BDF2's second point); None before the first step.
    previous_rate : ndarray, shape (nx, ny), 1, or None
        Rate of the integration variable at the previous accepted point,
        the wear rate ``k p^m`` (``p^m``, Pa^m, across interfaces, where
        the run integrates the wear work); None before the first step.
    previous_step : float or None, m
        Length of the last accepted step; None before the first.
    next_step : float or None, m
        Length the step controller proposes for the next attempt.
    pressure_history : ndarray, shape (k, nx, ny), Pa, or None
        The last contact pressures, newest first: the warm start of the
        next implicit stages (:class:`transient.problem.WarmStart`);
        None before the first attempt, and in a steady result (a run that
        reached the steady state takes no further step).
    pressure_history_displacement : ndarray, shape (k, nx, ny), m, or None
        Their elastic displacements ``K p`` as the run holds them (the
        solver's own, which a resumed run needs to repeat the run bit for
        bit).
    jumps : int
        Jumps to the steady state attempted so far (failed ones too); after
        :data:`transient.control.MAX_JUMPS` the run stops as stagnating.
    """

    height: np.ndarray
    offset: float
    pressure: np.ndarray
    approach: float
    initial_height: np.ndarray
    previous_height: np.ndarray | None = None
    previous_rate: np.ndarray | None = None
    previous_step: float | None = None
    next_step: float | None = None
    pressure_history: np.ndarray | None = None
    pressure_history_displacement: np.ndarray | None = None
    jumps: int = 0


@dataclasses.dataclass(frozen=True, eq=False)
class RunResult:
    """A run-in, finished or in progress (a checkpoint is a ``"running"`` result).

    The face, its pressure and everything else a resumed run needs are in
    :attr:`state`; :attr:`height`, :attr:`offset`, :attr:`pressure`,
    :attr:`approach` and :attr:`initial_height` read them from there.

    Attributes
    ----------
    status : str
        ``"running"``, ``"steady"`` (converged), ``"depth"`` (the mean worn
        depth reached ``end_depth``), ``"stopped"`` (limit reached)
        or ``"failed"`` (a step could not be completed).
    message : str
    scheme : str
    distance : float, m
        Sliding distance reached: the end of the dynamics, the last point of
        :attr:`history`.  A jump to the steady state does not advance it.
    steps, rejected, failures : int
        Accepted steps (jumps to the steady state included), rejected steps
        (error too large), failed attempts.
    solves, iterations : int
        Contact solves and contact-solver iterations.
    wall_time : float, s
    history : mapping of str to ndarray, shape (K,)
        One point at ``s = 0`` and one per accepted regular step; jumps to
        the steady state are not in it (their state is the run's final
        :attr:`state`; the steady figures are :attr:`steady_rms_slope` and
        the face's deviation from ``f_inf``, ``face_deviation``).
        See :data:`HISTORY_UNITS` and :mod:`transient.history`: ``rms_slope``
        is the continuum rms slope of the face with its ``rms_slope_error``
        (at ``s = 0`` the initial face's own value), ``rms_slope_plain`` the
        plain pixel value, ``rms_height`` the relief about the best plane;
        ``rms_slope_spatial_error`` is empty (shape (0,)) unless
        :meth:`transient.spatial_error.SpatialError.attach` filled it.
    snapshot_distance : ndarray, shape (k,), m
    snapshot_height : ndarray, shape (k, nx, ny), m
        ``worn depth + initial shape`` at the snapshots (NaN off the face).
    snapshot_pressure : ndarray, shape (k, nx, ny), Pa
    depth_scale, distance_scale, fast_distance, pixel_mean_pressure,
    reference_slope : float
        ``f*`` (m), the distance scale ``s* = L / (k_min E*)`` (m; not a
        distance the run took: see :meth:`run_in_distance`),
        ``h / (k_max E*)`` (m), ``F`` over the
        face's pixel area (Pa), ``grad_f0`` (the homogeneous face's rms
        slope: ``4 pbar / (pi E*)`` for a disk, eq. 12;
        :func:`steady.normalisation.reference_slope`).
    state : RunState
        The face, its pressure and what else the run's future depends on
        (NaN off the face).
    outline : outline object or None
        The face's outline (:mod:`steady.outline`); None when unknown (a
        run file written without it).
    reference_slope_error : float
        Uncertainty of ``reference_slope`` (0: a closed form).
    reference_slope_source : str
        Where ``reference_slope`` comes from, in words ("" when unknown).
    problem : steady.problem.Problem or None
        The problem the run solved (load, modulus, wear law, phase map and
        names), which :func:`transient.output.write_run` stores; None for a
        run read from a file.
    steady_rms_slope, steady_rms_slope_error : float
        The rms slope of the closed-form steady face ``f_inf`` (eq. 9) by the
        history's estimator (:class:`transient.history.FaceEstimator`, the
        rim layer fully worn) and its error bar: the value the history's
        ``rms_slope`` tends to.  NaN when unknown (a run file written
        without them).
    sliding_speed : float or None, m/s
        The scene's ``[load] sliding_speed`` (None: not given): turns
        distances into times.
    load_programme : steady.load_programme.LoadProgramme or None
        The scene's ``[load] programme`` (None: a constant load).  With one,
        the history holds the ``force`` of every point, steps land on its
        breakpoints and the steady state is the one under its last force.
    columns : steady.depth.DepthColumns or None
        The phase below every face pixel as a function of depth, for a
        problem whose phase map changes with depth (None: columnar).  Its
        history then holds :data:`DEPTH_HISTORY_UNITS` (and, under a
        coating, :data:`COATING_HISTORY_UNITS`).
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
    history: types.MappingProxyType
    snapshot_distance: np.ndarray
    snapshot_height: np.ndarray
    snapshot_pressure: np.ndarray
    depth_scale: float
    distance_scale: float
    fast_distance: float
    pixel_mean_pressure: float
    reference_slope: float
    state: RunState
    outline: object = None
    reference_slope_error: float = 0.0
    reference_slope_source: str = ""
    problem: object = None
    steady_rms_slope: float = math.nan
    steady_rms_slope_error: float = math.nan
    sliding_speed: float | None = None
    load_programme: object = None
    columns: object = None

    def run_in_distance(self, within=0.01, *, sliding_speed=None):
        """The sliding distance after which the run stays within ``within`` of the steady state.

        Both the friction proxy (the history's ``rms_slope`` against
        :attr:`steady_rms_slope`) and the face (``face_deviation``: the rms
        of the face minus the steady face over the steady face's relief)
        must stay within ``within``; see
        :func:`transient.run_in_distance.run_in_distance` and docs/model.md,
        "The run-in distance".

        Parameters
        ----------
        within : float, optional
            Relative tolerance, in (0, 1) (default 0.01: 1 %).
        sliding_speed : float, optional, m/s
            Gives the time too; default :attr:`sliding_speed`.

        Returns
        -------
        transient.run_in_distance.RunInDistance

        Examples
        --------
        >>> from transient import RunOptions, WearProblem, run_in
        >>> from transient.scene import load_transient_scene
        >>> scene, _, initial = load_transient_scene("steady/examples/voronoi_transient.toml")
        >>> problem = WearProblem.from_scene(scene, n=40)
        >>> result = run_in(problem, initial.height(problem.grid), RunOptions(tol=1e-3))
        >>> one, tenth = result.run_in_distance(0.01), result.run_in_distance(0.001)
        >>> one.reached and tenth.reached and one.distance_m < tenth.distance_m
        True
        """
        from .run_in_distance import run_in_distance

        return run_in_distance(self, within, sliding_speed=sliding_speed)

    @property
    def coating_worn_through(self):
        """Where the coating was first worn through anywhere (first pixel past its interface).

        A :class:`transient.run_in_distance.CoatingDistance` (m and ``s*``),
        NaN with the reason without a coating or before it happened.
        """
        from .run_in_distance import coating_distance

        return coating_distance(self, "worn_through")

    @property
    def coating_gone(self):
        """Where the coating was gone from the contact (no contact pixel left in its phase).

        A :class:`transient.run_in_distance.CoatingDistance`, as
        :attr:`coating_worn_through`.
        """
        from .run_in_distance import coating_distance

        return coating_distance(self, "gone")

    @property
    def mean_worn_depth(self):
        """Depth worn off since the start, mean over the face, m."""
        worn = self.worn_depth
        return float(np.mean(worn[np.isfinite(worn)]))

    @property
    def section(self):
        """Phase map of the section at the current worn depth, shape (nx, ny), -1 off the face.

        None for a columnar run (:attr:`columns` None).
        """
        if self.columns is None:
            return None
        return self.columns.phase_at(np.nan_to_num(self.worn_depth, nan=0.0))

    @property
    def snapshot_sections(self):
        """Phase maps of the sections at the snapshots, shape (k, nx, ny); None when columnar."""
        if self.columns is None:
            return None
        worn = np.nan_to_num(self.snapshot_height - self.initial_height[None], nan=0.0)
        return np.stack([self.columns.phase_at(w) for w in worn]) if len(worn) else \
            np.empty((0, *self.shape), dtype=self.columns.phases.dtype)

    @property
    def height(self):
        """Face height (worn depth + initial shape) minus :attr:`offset`, m, shape (nx, ny)."""
        return self.state.height

    @property
    def offset(self):
        """Constant removed from :attr:`height` (the rigid part of the wear), m."""
        return self.state.offset

    @property
    def pressure(self):
        """Contact pressure of the face, Pa, shape (nx, ny)."""
        return self.state.pressure

    @property
    def approach(self):
        """Rigid approach in the frame of :attr:`height`, m."""
        return self.state.approach

    @property
    def initial_height(self):
        """The face the run started from, m, shape (nx, ny); NaN off the face."""
        return self.state.initial_height

    @property
    def success(self):
        """Whether the run reached the steady state."""
        return self.status == "steady"

    @property
    def finished(self):
        """Whether the run ended as asked: at the steady state or at its ``end_depth``."""
        return self.status in ("steady", "depth")

    @property
    def shape(self):
        """``(nx, ny)`` of the grid."""
        return self.height.shape

    @property
    def pixel_size(self):
        """Pixel side ``h = 2 L / n``, m (``n`` the longer side); NaN without the outline."""
        if self.outline is None:
            return math.nan
        return 2.0 * self.outline.scale / max(self.shape)

    @property
    def face_mask(self):
        """Pixels of the punch face, shape (nx, ny), bool."""
        return np.isfinite(self.worn_depth)

    @property
    def worn_depth(self):
        """Depth worn off since the start, m, shape (nx, ny); NaN off the face."""
        return self.height + self.offset - self.initial_height

    @property
    def face(self):
        """Face height ``d - w`` in the convention of the steady face ``f_inf = K p``, m.

        Equals ``K p`` on the contact; defined up to a constant; NaN off the face.
        """
        return self.approach - self.height


def _initial_face(problem, initial_height):
    """``initial_height`` (m) checked, on the problem's grid, zero off the face."""
    face_mask = problem.face_mask
    h0 = np.where(face_mask, np.asarray(initial_height, dtype=float), 0.0)
    if h0.shape != problem.shape:
        raise ValueError(f"initial_height must have shape {problem.shape}, got {h0.shape}")
    if not np.all(np.isfinite(h0[face_mask])):
        raise ValueError("initial_height must be finite on the face")
    return h0


def _frozen(array):
    """``array``, made read-only: a result shares it with the run and later results."""
    array.flags.writeable = False
    return array


class _Run:
    """A run in progress: its state, and the loop that advances it.

    Every attribute is set by the constructor, from the initial face (a new
    run: the first contact solve) or from the result it resumes:

    - fixed for the run: ``problem``, ``options``, ``scheme``, ``s_star``,
      ``f_star``, ``controller`` and ``stop`` (:mod:`transient.control`),
      ``reference``, ``grad_f0``, ``estimator``;
    - the state a checkpoint stores (:class:`RunState`; arrays zero off the
      face), advanced by :meth:`accept`: ``initial_height``, ``height``,
      ``offset``, ``pressure``, ``approach``, ``prev_height``,
      ``prev_rate``, ``prev_step``, ``next_step``, ``pressures`` (the
      :class:`transient.problem.WarmStart`, None until the first
      attempt), ``jumps``;
    - the progress a :class:`RunResult` reports: ``s`` (m), ``steps``,
      ``rejected``, ``failures``, ``wall_time`` (s, spent before this call),
      ``t0`` (monotonic clock at the start of this call), ``history``
      (lists), the snapshots ``snap_d`` (a list), ``snap_h``, ``snap_p``
      (read-only arrays, shape (k, nx, ny), replaced by a new one at each
      snapshot: every result shares them, none copies them) and
      ``snap_index`` (the next requested one), ``latest`` (the current
      point's spread and shape change, which the stop tests judge);
    - across interfaces (:attr:`WearProblem.work_depth`): ``segments``, the
      segment of every pixel at the current point, ``crossings``, the face
      pixels whose segment the last accepted step changed (what the history
      records as ``crossings``; 0 for a columnar run), and
      ``depth_landing``, the distance a retry aims at after a trial went
      past ``end_depth`` (None otherwise); all three follow from the state;
    - the steady state the history measures against: ``steady_face``,
      ``steady_relief``, ``steady_slope`` (:meth:`_steady_reference`);
    - the history's worker thread: ``_worker``, ``_estimator_workers``,
      ``_pending``.

    ``on_step`` callbacks read ``s``, ``s_star``, ``steps``, ``history`` and
    ``latest`` (the current point's wear-rate spread and shape change).

    Parameters
    ----------
    problem : transient.problem.WearProblem
    options : RunOptions
    initial_height : ndarray, shape (nx, ny), m, or None
        The initial face of a new run (ignored when resuming).
    resume : RunResult or None
        The result to continue from.
    """

    def __init__(self, problem, options, initial_height, resume):
        self.t0 = time.monotonic()
        # The run's contact solves stop at its options' tolerance (the floor of a step's).
        problem.contact_rtol = float(options.contact_rtol)
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
        problem.applied_force = problem.normal_force
        if self.programme is not None:
            problem.applied_force = self.programme.force_at(
                0.0 if resume is None else float(resume.distance))
        if resume is None:
            h0 = _initial_face(problem, initial_height)
            self.estimator = FaceEstimator.of(problem, h0)
            state = self._first_state(h0)
        else:
            state = resume.state
            if state.height.shape != problem.shape:
                raise ValueError(f"checkpoint grid {state.height.shape} does not match the "
                                 f"problem's {problem.shape}")
            self.estimator = FaceEstimator.of(
                problem, np.where(face_mask, state.initial_height, 0.0))
        self._steady_reference()

        def clean(a):
            return None if a is None else np.where(face_mask, a, 0.0)

        self.initial_height = clean(state.initial_height)
        self.height = clean(state.height)
        self.offset = float(state.offset)
        self.pressure = np.array(state.pressure, dtype=float)
        self.approach = float(state.approach)
        self.prev_height = clean(state.previous_height)
        self.prev_rate = clean(state.previous_rate)
        self.prev_step = state.previous_step
        self.next_step = state.next_step
        self.pressures = None
        if state.pressure_history is not None:
            self.pressures = WarmStart(
                problem, pressures=state.pressure_history,
                displacements=state.pressure_history_displacement)
        self.jumps = int(state.jumps)
        # Across interfaces: the segment of every pixel at the current point (the section
        # whose coefficients the problem holds), and the pixels that changed segment over
        # the last accepted step (``crossings``, for the history).
        self.segments = problem.at_depth(self.worn_depth())
        self.crossings = 0
        self._depth = None  # the depth figures' recorder, built at the first point recorded
        # Distance of the next attempt after one that went past end_depth (None: none).
        self.depth_landing = None

        if resume is None:
            self.s, self.steps, self.rejected, self.failures = 0.0, 0, 0, 0
            self.wall_time = 0.0
            self.history = {name: [] for name in HISTORY_UNITS}
            if self.programme is not None:
                self.history.update({name: [] for name in PROGRAMME_HISTORY_UNITS})
            self.snap_d = []
            self.snap_h = self.snap_p = _frozen(np.empty((0, *problem.shape)))
        else:
            self.s = float(resume.distance)
            self.steps, self.rejected = resume.steps, resume.rejected
            self.failures = resume.failures
            problem.solves, problem.iterations = resume.solves, resume.iterations
            self.wall_time = resume.wall_time
            self.history = {k: list(v.tolist()) for k, v in resume.history.items()}
            for name in _LATER_HISTORY:
                self.history.setdefault(name, [math.nan] * len(self.history["distance"]))
            self.snap_d = list(resume.snapshot_distance.tolist())
            self.snap_h = _frozen(np.array(resume.snapshot_height, dtype=float))
            self.snap_p = _frozen(np.array(resume.snapshot_pressure, dtype=float))
        self.snap_index = len(self.snap_d)
        # (spread, shape_rate) of the current point, which the stop tests judge: the last
        # history point's, or the figures of the state a jump reached (not in the history).
        self.latest = None
        if resume is not None:
            self.latest = (self.history["spread"][-1], self.history["shape_rate"][-1])
            if (self.jumps and self.prev_step is not None
                    and self.prev_step != self.history["step"][-1]):
                self.latest = self._jump_point()  # the last accepted step was a jump

        self._worker = None
        self._estimator_workers = None
        self._pending = []

    def worn_depth(self):
        """Worn depth at the current point, m, shape (nx, ny) (:meth:`WearProblem.worn_depth`)."""
        return self.problem.worn_depth(self.height, self.offset, self.initial_height)

    def mean_depth(self):
        """Mean worn depth over the face, m (None unless the run ends at a depth)."""
        if self.options.end_depth is None:
            return None
        return float(self.worn_depth()[self.problem.face_mask].mean())

    def below_interfaces(self):
        """Whether the phases no longer change below the face (always, for a columnar run)."""
        p = self.problem
        return p.work_depth is None or p.columns.columnar_below(self.worn_depth())

    def _first_state(self, h0):
        """The state at ``s = 0`` from the checked initial face ``h0`` (m): first contact solve."""
        p = self.problem
        face_mask = p.face_mask
        offset = float(h0[face_mask].mean())
        height = np.where(face_mask, h0 - offset, 0.0)
        res = p.contact(height)
        return RunState(height=height, offset=offset, pressure=res.pressure,
                        approach=float(res.approach), initial_height=h0,
                        next_step=self.controller.first_step(p.halfspace.h, p.scale))

    def _steady_reference(self):
        """The closed-form steady face ``f_inf`` (eq. 9), its relief and its figures.

        Sets ``steady_face`` (m, zero off the face), ``steady_relief`` (m,
        max - min over the face) and ``steady_slope`` (the estimator's rms
        slope of ``f_inf`` and its error bar, the rim layer fully worn:
        distance infinite).
        """
        p = self.problem
        face_mask = p.face_mask
        # The face and its pressure only: the rms slope of f_inf is the estimator's below
        # (the steady solve's own estimate, a ladder of coarser maps, would go unused).
        steady = p.solve_steady(face_only=True)
        self.steady_face = np.where(face_mask, steady.face, 0.0)
        self.steady_relief = float(np.ptp(steady.face[face_mask]))
        figures = self.estimator.figures(math.inf, -self.steady_face,
                                         np.where(face_mask, steady.pressure, 0.0), 0.0)
        self.steady_slope = (float(figures["rms_slope"]), float(figures["rms_slope_error"]))

    def _jump_point(self):
        """``(spread, shape_rate)`` of the state a jump reached, from the state alone.

        Computed the same way after the jump and from a checkpoint taken
        after it, so that a resumed run judges the same figures.
        """
        p = self.problem
        change = shape_rms(self.height - self.prev_height, p.face_mask)
        return (wear_rate_spread(p, self.pressure),
                change / self.f_star / (self.prev_step / self.s_star))

    def begin(self):
        """Record the starting point of a new run: history at ``s = 0``, snapshots due there."""
        self.record(0.0, math.inf)
        self._take_due_snapshots()

    # -- recording -----------------------------------------------------
    def record(self, step, shape_rate, error=None, face_state=None):
        """Append the current point to the history (:class:`transient.history.FaceEstimator`).

        ``error`` is the accepted step's local error estimate (m, shape
        (nx, ny)); None at ``s = 0``.  ``face_state`` is ``(rim layers,
        pressure, approach)`` of the face's figures when they are not the
        current ones: at a step of the load, the face (continuous) is
        measured from its contact before the step, whose rim layer the
        estimator knows.
        """
        if face_state is None:
            face_state = (self.rim_layers(), self.pressure, self.approach)
        p = self.problem
        face_mask = p.face_mask
        hist = self.history
        # The face's figures are computed on a worker thread while the run goes on
        # (they do not steer it); :meth:`result` waits for them.
        if self._worker is None:
            self._worker = concurrent.futures.ThreadPoolExecutor(
                max_workers=1, thread_name_prefix="runin-history")
            # One thread for the figures' transforms: the solver's use the cores.
            self._estimator_workers, self.estimator.workers = self.estimator.workers, 1
            self.estimator.threaded = True
        index = len(hist["distance"])
        worn = self.height + self.offset - self.initial_height
        depth = self._record_depth(worn, index)
        # Not copied: the run replaces its face and pressure, never writes into them.
        if depth is None:
            self._pending.append((index, self._worker.submit(
                self.estimator.figures, self.s, self.height, face_state[1], face_state[2],
                rim_layers=face_state[0])))
        else:
            self._pending.append((index, self._worker.submit(
                _depth_figures, self.estimator, depth, worn, self.s, self.height,
                face_state)))
        hist["distance"].append(self.s)
        hist["step"].append(step)
        for name in _FACE_FIGURES:
            hist[name].append(math.nan)
        hist["spread"].append(wear_rate_spread(p, self.pressure))
        hist["shape_rate"].append(shape_rate)
        hist["peak_pressure"].append(float(self.pressure.max()))
        hist["contact_fraction"].append(float(np.mean(self.pressure[face_mask] > 0)))
        hist["approach"].append(self.approach + self.offset)
        hist["worn_volume"].append(float(np.sum(worn[face_mask])) * p.halfspace.h ** 2)
        hist["solves"].append(p.solves)
        hist["rim_worn_depth"].append(float(worn[self.estimator.rim].mean()))
        diff = (self.approach - self.height - self.steady_face)[face_mask]
        hist["face_deviation"].append(
            float(np.sqrt(np.mean((diff - diff.mean()) ** 2))) / self.steady_relief)
        step_error = slope_error = 0.0
        if error is not None:
            step_error = shape_rms(error, face_mask) / self.steady_relief
            gx, gy = masked_gradient(np.where(face_mask, error, 0.0), face_mask, p.halfspace.h)
            slope_error = float(np.sqrt(np.mean((gx * gx + gy * gy)[face_mask])))
        hist["face_deviation_step_error"].append(step_error)
        hist["rms_slope_step_error"].append(slope_error)
        if "force" in hist:
            hist["force"].append(p.applied_force)
        self.latest = (hist["spread"][-1], shape_rate)
        self.collect(wait=False)

    def _record_depth(self, worn, index):
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
        previous = (None if self.prev_height is None or index == 0
                    else self.prev_height + self.offset - self.initial_height)
        # The stepping counted the last step's crossings (none before the first step).
        figures, labels = recorder.figures(worn, self.pressure, previous,
                                           crossed=self.crossings if index else None)
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

    def snapshot(self):
        """Store the face and the pressure at the current distance."""
        face_mask = self.problem.face_mask
        self.snap_d.append(self.s)
        self.snap_h = _frozen(np.concatenate(
            [self.snap_h, np.where(face_mask, self.height + self.offset, np.nan)[None]]))
        self.snap_p = _frozen(np.concatenate([self.snap_p, self.pressure[None]]))

    def current_state(self):
        """The state at the current point as a :class:`RunState` (NaN off the face).

        The arrays that are the run's own are read-only views, not copies: the
        run replaces them at every step and never writes into them.
        """
        face_mask = self.problem.face_mask

        def shared(a):
            return None if a is None else _frozen(a.view())

        return RunState(
            height=np.where(face_mask, self.height, np.nan), offset=self.offset,
            pressure=shared(self.pressure), approach=self.approach,
            initial_height=np.where(face_mask, self.initial_height, np.nan),
            previous_height=shared(self.prev_height), previous_rate=shared(self.prev_rate),
            previous_step=self.prev_step, next_step=self.next_step,
            pressure_history=None if self.pressures is None else self.pressures.pressures(),
            pressure_history_displacement=(None if self.pressures is None
                                           else self.pressures.displacements()),
            jumps=self.jumps)

    def result(self, status, message):
        """The run so far as a :class:`RunResult`."""
        self.collect()
        return RunResult(
            status=status, message=message, scheme=self.scheme.name, distance=self.s,
            steps=self.steps, rejected=self.rejected, failures=self.failures,
            solves=self.problem.solves, iterations=self.problem.iterations,
            wall_time=self.wall_time + (time.monotonic() - self.t0),
            history=types.MappingProxyType({k_: np.array(v, dtype=float if k_ != "solves"
                                                         else np.int64)
                                            for k_, v in self.history.items()}),
            snapshot_distance=np.array(self.snap_d, dtype=float),
            snapshot_height=self.snap_h, snapshot_pressure=self.snap_p,
            depth_scale=self.f_star, distance_scale=self.s_star,
            fast_distance=self.problem.fast_distance,
            pixel_mean_pressure=self.problem.pixel_mean_pressure,
            reference_slope=self.grad_f0, state=self.current_state(),
            outline=self.problem.outline, reference_slope_error=self.reference.error,
            reference_slope_source=self.reference.source, problem=self.problem.problem,
            steady_rms_slope=self.steady_slope[0], steady_rms_slope_error=self.steady_slope[1],
            sliding_speed=self.problem.sliding_speed, load_programme=self.programme,
            columns=self.problem.columns)

    def _take_due_snapshots(self):
        snaps = self.options.snapshots
        while (self.snap_index < len(snaps)
               and snaps[self.snap_index] * self.s_star <= self.s * (1 + 1e-12)):
            self.snapshot()
            self.snap_index += 1

    # -- stepping ------------------------------------------------------
    def pending_target(self):
        """Distance of the next snapshot or load breakpoint (m), or None."""
        snaps = self.options.snapshots
        targets = [self.next_breakpoint()]
        if self.snap_index < len(snaps):
            targets.append(snaps[self.snap_index] * self.s_star)
        targets = [t for t in targets if t is not None]
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
        final = self.problem.normal_force
        return tuple((self.s - s_j, (rise / final) ** 2)
                     for s_j, rise in self.programme.rises(self.s, before=before_change))

    def change_load(self):
        """Apply the load programme's force at the current distance, if it changed.

        The face is continuous across a step of the load, its pressure is
        not: the contact is solved again under the new force (from the old
        pressure, which the solver scales to it), and the recent pressures
        of the warm start and BDF2's previous point, which belong to the
        old load, are dropped: both restart as at the start of a run.

        Returns
        -------
        tuple or None
            ``(rim layers, pressure, approach)`` before the change, from
            which the history measures the face (:meth:`record`); None when
            the force did not change.
        """
        p = self.problem
        force = self.programme.force_at(self.s)
        if force == p.applied_force:
            return None
        before = (self.rim_layers(before_change=True), self.pressure, self.approach)
        logger.info("load %.6g N -> %.6g N at s = %.6g m", p.applied_force, force, self.s)
        p.applied_force = force
        res = p.contact(self.height, x0=self.pressure)
        self.pressure = res.pressure
        self.approach = float(res.approach)
        self.pressures = None
        self.prev_height = self.prev_rate = self.prev_step = None
        return before

    def plan(self, jump, target):
        """Scheme and length (m) of the next attempt.

        A regular step lands on ``target`` or on the distance where the
        mean worn depth reaches ``end_depth`` at the current wear rate,
        whichever comes first; across interfaces it ends just past the
        first crossing ahead
        (:meth:`transient.control.StepController.before_crossing`).
        """
        p = self.problem
        if jump:
            return get_scheme("implicit_euler"), self.options.jump_step * self.s_star
        ds = self.next_step
        if self.scheme.explicit:
            ds = self.controller.explicit_limit(ds, p.stable_step(self.pressure))
        if p.work_depth is not None:
            ds = self.controller.before_crossing(ds, self.last_crossing(ds))
        depth = self.mean_depth()
        if depth is not None:
            rate = float(p.rate(self.pressure)[p.face_mask].mean())
            at_depth = self.depth_landing
            if at_depth is None:
                at_depth = self.stop.depth_target(self.s, depth, rate)
            if at_depth is not None:
                target = at_depth if target is None else min(target, at_depth)
        return self.scheme, self.controller.land(ds, self.s, target, self.stop.end())

    def last_crossing(self, ds):
        """Distance (m) in which the last face pixel to reach a kink within ``ds`` reaches it.

        At the current rates; ``-inf`` when no pixel reaches one within
        ``ds`` (m).
        """
        p = self.problem
        work = p.variable(self.height, self.initial_height - self.offset)
        rate = p.variable_rate(self.pressure)[p.face_mask]
        left = p.work_depth.remaining(work)[p.face_mask]
        moving = rate > 0
        distance = left[moving] / rate[moving]
        return float(np.max(distance[distance < ds], initial=-np.inf))

    def attempt(self, scheme, ds, jump):
        """One trial step and its scaled error; raises :class:`StepFailure`."""
        p = self.problem
        face_mask = p.face_mask
        if self.pressures is None:
            self.pressures = WarmStart(p, pressures=self.pressure[None])
        # A jump starts from the closed-form steady pressure, its limit; every
        # other stage from the Galerkin combination of the recent pressures,
        # and solves to what the step's error and the spread need.
        atol = 0.0
        if not (jump or self.controller.fixed) and p.wear.linear:
            atol = contact_tolerance(self.options.tol, self.f_star, self.latest[0],
                                     p.compliance_floor, p.applied_force / p.area)
        origin = None
        if p.work_depth is not None:
            origin = self.initial_height - self.offset
        state = StepState(self.height, p.steady_pressure() if jump else self.pressure,
                          self.approach, self.prev_height, self.prev_rate, self.prev_step,
                          history=None if jump else self.pressures, contact_atol=atol,
                          origin=origin)
        trial = scheme.step(p, state, ds)
        err = shape_rms(trial.error, face_mask) / (self.options.tol * self.f_star)
        if not (math.isfinite(err) and np.all(np.isfinite(trial.height[face_mask]))):
            raise StepFailure("non-finite face or error estimate")
        if shape_rms(trial.height, face_mask) > DIVERGENCE_RELIEF * self.f_star:
            raise StepFailure(f"face relief above {DIVERGENCE_RELIEF:g} f*: divergence")
        return trial, err

    def past_end_depth(self, trial, ds):
        """Where to land instead of a trial that went past ``end_depth`` (m), or None.

        The secant of the mean worn depth between the current point and the
        trial: the rate at the start misses the crossings of the step.
        """
        end = self.options.end_depth
        if end is None:
            return None
        face_mask = self.problem.face_mask
        before = self.mean_depth()
        after = float(self.problem.worn_depth(trial.height, self.offset,
                                              self.initial_height)[face_mask].mean())
        if after <= end * (1 + DEPTH_SLACK):
            return None
        return self.s + ds * (end - before) / (after - before)

    def accept(self, trial, ds, jump=False):
        """Move to the trial point; the rigid part of the wear goes into ``offset``.

        A jump's state is the steady face at no particular distance: it
        advances neither the distance nor the rigid wear, and stays out of
        the history (its figures go to ``latest``).  Across interfaces the
        height is not re-centred (``offset`` stays): the worn depth, which
        sets the phases, is then the height minus one fixed origin, free of
        the round-off a moving offset would add at every step; a jump there
        (below every interface) drops its least increment.
        """
        p = self.problem
        face_mask = p.face_mask
        new_height = np.where(face_mask, trial.height, 0.0)
        c = 0.0
        if p.work_depth is None:
            c = float(new_height[face_mask].mean())
        elif jump:
            # The jump's wear less its least increment: no pixel rises above the
            # depth it had reached (below every interface).
            c = float(np.min((new_height - self.height)[face_mask]))
        if c:
            new_height = np.where(face_mask, new_height - c, 0.0)
        change = shape_rms(new_height - self.height, face_mask)
        shape_rate = change / self.f_star / (ds / self.s_star)
        self.prev_height = np.where(face_mask, self.height - c, 0.0)
        self.prev_rate = p.variable_rate(self.pressure)
        self.prev_step = ds
        self.height = new_height
        self.pressure = trial.pressure
        self.approach = trial.approach - c
        self.steps += 1
        if p.work_depth is not None:
            segments = p.at_depth(self.worn_depth())
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
        self.record(ds, shape_rate, trial.error, face_state)
        self._take_due_snapshots()

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
            ended = stop.check(spread, shape_rate, self.s, self.steps,
                               held=self.next_breakpoint() is not None,
                               depth=self.mean_depth(), columnar=columnar)
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
                on_checkpoint(self.result("running", "in progress"))
                last_checkpoint = time.monotonic()
                checkpoint_cost = last_checkpoint - started


def _depth_figures(estimator, depth, worn, distance, height, face_state):
    """The face's figures and the rms slope of the section's quasi-steady face (history thread).

    ``depth`` is ``(recorder, labels)`` of :meth:`_Run._record_depth`.
    """
    rim_layers, pressure, approach = face_state
    figures = estimator.figures(distance, height, pressure, approach, rim_layers=rim_layers)
    recorder, labels = depth
    figures["quasi_steady_rms_slope"] = recorder.quasi_steady(worn, labels)
    return figures


def run_in(problem, initial_height, options=None, *, resume=None, on_step=None,
           on_checkpoint=None):
    """Wear the face from ``initial_height`` until the wear rates equalise.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    initial_height : ndarray, shape (nx, ny), m
        Initial face (larger = recessed) on the problem's grid; see
        :mod:`transient.initial_face`.
    options : RunOptions, optional
    resume : RunResult, optional
        A checkpoint (or a stopped run) to continue from: its
        :attr:`RunResult.state`, distance, counters, history and snapshots;
        ``initial_height`` is then taken from it.
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

    >>> from transient import RunOptions, WearProblem, compare_with_steady, run_in
    >>> from transient.scene import load_transient_scene
    >>> scene, settings, initial = load_transient_scene(
    ...     "steady/examples/voronoi_transient.toml")
    >>> problem = WearProblem.from_scene(scene, n=40)
    >>> result = run_in(problem, initial.height(problem.grid),
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
    run = _Run(problem, options, initial_height, resume)
    try:
        if resume is None:
            run.begin()
        elif resume.status == "steady":
            return run.result("steady", resume.message)
        status, message = run.loop(on_step, on_checkpoint)
        log = logger.info if status in ("steady", "depth") else logger.warning
        log("%s: %s", status, message)
        if status == "steady":
            run.pressures = None  # freed before the result is built: not state any more
        return run.result(status, message)
    finally:
        run.close()
