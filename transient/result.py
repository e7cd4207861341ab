"""The result of a run-in: its state, history and snapshots, and the units of its history.

:func:`transient.runin.run_in` returns a :class:`RunResult` (a checkpoint is
a ``"running"`` one); its :class:`RunState` is everything a resumed run
needs beyond the distance, counters, history and snapshots.  The history's
datasets and their units are declared here (:data:`HISTORY_UNITS` and the
datasets of runs under a load programme or across interfaces), for the run
that fills them and the files that store them (:mod:`transient.output`).
"""

from __future__ import annotations

import dataclasses
import math
import types

import numpy as np

from steady.topography import to_topography

from .run_in_distance import coating_distance, run_in_distance

__all__ = ["COATING_HISTORY_UNITS", "DEPTH_HISTORY_UNITS", "HISTORY_UNITS",
           "PROGRAMME_HISTORY_UNITS", "RunResult", "RunState", "rms_slope_uncertainty"]

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
    "rms_slope_spatial_error": "1 (max |S_n - S_m| from the same run on coarser grids m; empty "
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
                      "least-squares constant removed, / rms of f_inf, its mean removed)",
    "face_deviation_step_error": "1 (rms over the face of the step's local error estimate, "
                                 "its mean removed, / rms of f_inf; 0 at s = 0)",
    "rms_slope_step_error": "1 (rms slope of the step's local error estimate; 0 at s = 0)",
    "rim_worn_depth": "m (worn depth, mean over the rim pixels of the face)",
    "companion_deviation_low": "1 (least over the companion runs on coarser grids of their "
                               "deviation from their own steady state, max(d_S, d_f); empty "
                               "unless transient.spatial_error filled it)",
    "companion_deviation_high": "1 (the same, greatest; empty unless transient.spatial_error "
                                "filled it)",
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
    recession : ndarray, shape (nx, ny), m
        Face recession (worn depth + initial shape) minus ``offset``.
    offset : float, m
        Constant removed from ``recession`` (the rigid part of the wear).
    pressure : ndarray, shape (nx, ny), Pa
        Contact pressure of the face.
    approach : float, m
        Rigid approach, in the frame of ``recession``.
    initial_recession : ndarray, shape (nx, ny), m
        The face the run started from.
    previous_recession : ndarray, shape (nx, ny), m, or None
        ``recession`` at the previous accepted point, in the frame of the
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
        next implicit stages (:class:`transient.warm_start.WarmStart`);
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

    recession: np.ndarray
    offset: float
    pressure: np.ndarray
    approach: float
    initial_recession: np.ndarray
    previous_recession: np.ndarray | None = None
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
    :attr:`state`; :attr:`recession`, :attr:`offset`, :attr:`pressure`,
    :attr:`approach` and :attr:`initial_recession` read them from there.

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
    snapshot_recession : ndarray, shape (k, nx, ny), m
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
    snapshot_recession: np.ndarray
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
    # A run file of layout 4 or earlier: its face_deviation is relative to the steady face's
    # max - min, not its rms (a run continued from it converts it).
    face_deviation_per_relief: bool = False

    def run_in_distance(self, within=0.01, *, sliding_speed=None):
        """The sliding distance after which the run stays within ``within`` of the steady state.

        Both the friction proxy (the history's ``rms_slope`` against
        :attr:`steady_rms_slope`) and the face (``face_deviation``: the rms
        of the face minus the steady face over that of the steady face)
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
        >>> from steady import examples
        >>> from transient import RunOptions, run_in
        >>> from transient.scene import load_transient_scene, wear_problem_of
        >>> scene, _, initial = load_transient_scene(examples.path("voronoi_transient"))
        >>> problem = wear_problem_of(scene, n=40)
        >>> result = run_in(problem, initial.recession(problem.grid), RunOptions(tol=1e-3))
        >>> one, tenth = result.run_in_distance(0.01), result.run_in_distance(0.001)
        >>> one.reached and tenth.reached and one.distance_m < tenth.distance_m
        True
        """
        return run_in_distance(self, within, sliding_speed=sliding_speed)

    @property
    def rms_slope_uncertainty(self):
        """The history's rms slope error bar, ndarray, shape (K,), 1 (slope).

        :func:`rms_slope_uncertainty` of :attr:`history`: the estimator's
        bar, the step's error and, when the companion runs filled it, the
        grid's, in quadrature.
        """
        return rms_slope_uncertainty(self.history)

    @property
    def coating_worn_through(self):
        """Where the coating was first worn through anywhere (first pixel past its interface).

        A :class:`transient.run_in_distance.CoatingDistance` (m and ``s*``),
        NaN with the reason without a coating or before it happened.
        """
        return coating_distance(self, "worn_through")

    @property
    def coating_gone(self):
        """Where the coating was gone from the contact (no contact pixel left in its phase).

        A :class:`transient.run_in_distance.CoatingDistance`, as
        :attr:`coating_worn_through`.
        """
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
        worn = np.nan_to_num(self.snapshot_recession - self.initial_recession[None], nan=0.0)
        return np.stack([self.columns.phase_at(w) for w in worn]) if len(worn) else \
            np.empty((0, *self.shape), dtype=self.columns.phases.dtype)

    @property
    def recession(self):
        """Face recession (worn depth + initial shape) minus :attr:`offset`, m, shape (nx, ny)."""
        return self.state.recession

    @property
    def offset(self):
        """Constant removed from :attr:`recession` (the rigid part of the wear), m."""
        return self.state.offset

    @property
    def pressure(self):
        """Contact pressure of the face, Pa, shape (nx, ny)."""
        return self.state.pressure

    @property
    def approach(self):
        """Rigid approach in the frame of :attr:`recession`, m."""
        return self.state.approach

    @property
    def initial_recession(self):
        """The face the run started from, m, shape (nx, ny); NaN off the face."""
        return self.state.initial_recession

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
        return self.recession.shape

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
        return self.recession + self.offset - self.initial_recession

    @property
    def face(self):
        """Face elevation ``d - w`` in the convention of the steady face ``f_inf = K p``, m.

        Equals ``K p`` on the contact; defined up to a constant; NaN off the face.
        """
        return self.approach - self.recession

    def topography(self, snapshot=None):
        """The worn face as a ``SurfaceTopography.Topography`` (the optional extra ``surface``).

        Heights in m (elevation, the sign of :attr:`face`, up to a
        constant), undefined off the face, physical size ``(nx h, ny h)``
        (:func:`steady.topography.to_topography`): power spectra,
        autocorrelation and scale-dependent slopes of the worn face from
        that library.

        Parameters
        ----------
        snapshot : int, optional
            Index of a stored snapshot (:attr:`snapshot_distance`; negative
            from the last); default the final face, :attr:`face`.  A
            snapshot's face is ``-snapshot_recession[snapshot]``.

        Returns
        -------
        SurfaceTopography.Topography

        Raises
        ------
        ValueError
            ``snapshot`` out of range, or the pixel size unknown (a run read
            from a file written without its outline).
        ModuleNotFoundError
            SurfaceTopography is not installed.
        """
        if self.outline is None:
            raise ValueError("the run's pixel size is unknown: its file does not record the "
                             "face's outline")
        if snapshot is None:
            return to_topography(self.face, self.pixel_size)
        count = len(self.snapshot_distance)
        if isinstance(snapshot, bool) or not isinstance(snapshot, (int, np.integer)) \
                or not -count <= snapshot < count:
            raise ValueError(f"snapshot must be an index of one of the run's {count} "
                             f"snapshots, got {snapshot!r}")
        return to_topography(-np.asarray(self.snapshot_recession[snapshot], dtype=float),
                             self.pixel_size)


def rms_slope_uncertainty(history):
    """Error bar of a history's ``rms_slope``, shape (K,): its parts in quadrature.

    The parts are ``rms_slope_error`` (the estimator's: rim layer and phase
    map), ``rms_slope_step_error`` (the step's local error) and
    ``rms_slope_spatial_error`` (the grid's, from the companion runs of
    :mod:`transient.spatial_error`; absent or empty without them).  An
    infinite part (no estimate possible) makes the bar infinite.

    Parameters
    ----------
    history : mapping of str to array_like
        A run's history (:attr:`RunResult.history`, a run file's group).

    Returns
    -------
    ndarray, shape (K,)
    """
    n = len(history["distance"])
    total = np.zeros(n)
    for name in ("rms_slope_error", "rms_slope_step_error", "rms_slope_spatial_error"):
        part = np.asarray(history.get(name, ()), dtype=float)
        if part.shape == (n,):
            total += np.nan_to_num(part, nan=0.0, posinf=np.inf) ** 2
    return np.sqrt(total)
