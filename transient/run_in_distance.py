"""The run-in distance: how far the face slides before it stays within a tolerance of steady.

The history of a run (:class:`transient.result.RunResult`) records, at
every accepted step, two relative deviations from the steady state
(docs/model.md, "The run-in distance"):

- the friction proxy's, ``d_S = |S(s) - S_inf| / S_inf``: the history's
  ``rms_slope`` against the rms slope of the closed-form steady face by the
  same estimator (:attr:`~transient.result.RunResult.steady_rms_slope`);
- the face's, ``d_f = rms(f(s) - f_inf - c) / rms(f_inf - c_inf)``: the
  history's ``face_deviation`` (``c``, ``c_inf`` the least-squares
  constants: the rigid offset is not part of the shape; 1 from a flat
  face).

The run is *within x* at a point where ``max(d_S, d_f) <= x``; the run-in
distance ``s_x`` is where it enters that band for the last time: after the
last recorded point outside the band the deviation is interpolated to
``x``, with ``log(deviation)`` linear in ``s`` between the two recorded
points (exact for the exponential approach of the slowest relaxation mode,
which governs the end of a run-in).

Its uncertainty has two parts.  The run's own, from the errors it
estimates at every point: the step's local error (``rms_slope_step_error``,
``face_deviation_step_error``: time integration) times
:data:`STEP_ERROR_FACTOR`, and the part of the slope estimator's error bar
that the steady value does not share (the rim layer; the map's share is
common to both and cancels in ``d_S``).  The band is widened and narrowed
by them: the first crossing of the narrowed band and the last of the
widened one bound ``s_x``.  And the grid's, when the companion runs of
:mod:`transient.spatial_error` gave it (``runin-transient`` runs them
unless ``--no-grid-error``): the same run on coarser grids ``m``, each
against its own grid's steady state, enters the band at ``s_x^(m)``; the
history holds the least and greatest of their deviations
(``companion_deviation_low``, ``companion_deviation_high``), whose entries
are the least and greatest ``s_x^(m)``, and the grid's part is the larger
distance from ``s_x`` to them.  The two parts add in quadrature on each
side (``low_m``, ``high_m``); the uncertainty is the larger side.  Without
the companions the grid's part is left out (:attr:`RunInDistance.spatial`
is False).  The bar's calibration against finer grids, tighter tolerances
and the axisymmetric reference is in ``docs/benchmarks.md``, "Calibrated
error bar".
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from steady.scene import SLIDING_SPEED

__all__ = ["COATING_EVENTS", "STEP_ERROR_FACTOR", "TOLERANCES", "CoatingDistance",
           "RunInDistance", "WearThroughMap", "coating_distance", "deviations", "distance_table",
           "entry", "run_in_distance"]

#: The tolerances a run file and the summary of ``runin-transient`` give the run-in distance for.
TOLERANCES = (0.01, 0.001)

#: What the step's local error estimate is multiplied by in the run-in distance's bar.  A
#: local estimate does not hold what the earlier steps' errors left in the face: against
#: runs at a hundredth of the tolerance, the distance's step error was 1.0 to 2.7 times the
#: bar of the local estimates alone on the shipped run-in scenes (docs/benchmarks.md,
#: "Calibrated error bar").
STEP_ERROR_FACTOR = 3.0


@dataclasses.dataclass(frozen=True)
class RunInDistance:
    """The run-in distance of a run within one tolerance.

    Attributes
    ----------
    within : float
        The relative tolerance ``x`` (0.01: 1 %).
    reached : bool
        Whether the run's last recorded point is within ``x``.  When False
        the distances and depths are NaN (and :attr:`message` says why).
    distance_m : float, m
        ``s_x``: the sliding distance after which the friction proxy and
        the face stay within ``x`` of the steady state.
    distance_s_star : float
        The same in units of the distance scale ``s*``.
    uncertainty_m : float, m
        Its uncertainty from the step and grid errors (module notes);
        infinite when the widened band is not entered before the run's end.
    low_m, high_m : float, m
        The bounds it comes from (``high_m`` infinite as above).
    mean_worn_depth_m, rim_worn_depth_m : float, m
        Depth worn off at ``s_x``, mean over the face and over its rim
        pixels (linear in ``s`` between recorded points).
    time_s, time_uncertainty_s : float, s
        ``s_x`` and its uncertainty over the sliding speed; NaN without one
        (as in the run file).
    end_m : float, m
        The last recorded distance of the run (the end of its dynamics).
    distance_scale : float, m
        ``s*``.
    spatial : bool
        Whether the companion run's spatial errors are in the uncertainty.
    message : str
        Why it was not reached ("" when reached).
    """

    within: float
    reached: bool
    distance_m: float
    distance_s_star: float
    uncertainty_m: float
    low_m: float
    high_m: float
    mean_worn_depth_m: float
    rim_worn_depth_m: float
    time_s: float
    time_uncertainty_s: float
    end_m: float
    distance_scale: float
    spatial: bool = False
    message: str = ""

    @property
    def uncertainty_s_star(self):
        """:attr:`uncertainty_m` in units of ``s*``."""
        return self.uncertainty_m / self.distance_scale

    def summary(self):
        """One line for the terminal."""
        pct = f"{100 * self.within:g} %"
        if not self.reached:
            return f"run-in distance within {pct}: not reached ({self.message})"
        line = (f"run-in distance within {pct}: s = {self.distance_m:.5g} +- "
                f"{self.uncertainty_m:.2g} m = {self.distance_s_star:.4g} +- "
                f"{self.uncertainty_s_star:.2g} s*; worn depth there {self.mean_worn_depth_m:.4g} m"
                f" (mean)")
        # A face without a rim (a periodic cell) has no rim depth.
        if math.isfinite(self.rim_worn_depth_m):
            line += f", {self.rim_worn_depth_m:.4g} m (rim)"
        if math.isfinite(self.time_s):
            line += f"; time {self.time_s:.5g} +- {self.time_uncertainty_s:.2g} s"
        return line + ("" if self.spatial else " (+- without the grid's error: no companion "
                                               "runs)")


def deviations(result):
    """Relative deviations from the steady state at the recorded points, and their errors.

    Parameters
    ----------
    result : transient.result.RunResult

    Returns
    -------
    deviation, low, high : ndarray, shape (K,)
        ``max(d_S, d_f)`` at each recorded point (module notes), and its
        bounds from the errors ``e_S``, ``e_f`` of each:
        ``max(d_S - e_S, d_f - e_f, 0)`` and ``max(d_S + e_S, d_f + e_f)``.

    Raises
    ------
    ValueError
        The result lacks the steady rms slope or the face deviation (a run
        file written before they were recorded).
    """
    h = result.history
    steady, steady_error = result.steady_rms_slope, result.steady_rms_slope_error
    if not math.isfinite(steady) or steady <= 0 or "face_deviation" not in h:
        raise ValueError("the run lacks the steady rms slope or the face deviation history "
                         "(written before they were recorded): no run-in distance")
    face = np.asarray(h["face_deviation"], dtype=float)
    if not np.all(np.isfinite(face[1:])):
        raise ValueError("the run's face deviation history is incomplete (resumed from a run "
                         "file written before it was recorded): no run-in distance")
    slope = np.asarray(h["rms_slope"], dtype=float)
    d_slope = np.abs(slope / steady - 1.0)
    # The estimator's error bar is hypot(rim layer, map error * S); the steady value's is
    # the map's share alone (no rim layer at s = inf), which d_S does not see.
    bar = np.asarray(h["rms_slope_error"], dtype=float)
    map_share = (steady_error / steady) * slope if math.isfinite(steady_error) else 0.0
    rim = np.sqrt(np.maximum(bar ** 2 - map_share ** 2, 0.0))
    parts = [rim / steady, STEP_ERROR_FACTOR * _dataset(h, "rms_slope_step_error") / steady]
    # An infinite error bar (no estimate possible) stays infinite: no bound.
    e_slope = np.sqrt(sum(np.nan_to_num(p, nan=0.0, posinf=np.inf) ** 2 for p in parts))
    e_face = STEP_ERROR_FACTOR * np.nan_to_num(_dataset(h, "face_deviation_step_error"),
                                               nan=0.0, posinf=np.inf)
    # At s = 0 the slope is the initial face's own, exact, value.
    e_slope[0], e_face[0] = 0.0, 0.0
    deviation = np.maximum(d_slope, face)
    low = np.maximum(np.maximum(d_slope - e_slope, 0.0), np.maximum(face - e_face, 0.0))
    high = np.maximum(d_slope + e_slope, face + e_face)
    return deviation, low, high


def _dataset(history, name, fill=0.0):
    """A history dataset as floats; ``fill`` when absent (or empty: no companion runs)."""
    n = len(history["distance"])
    value = np.asarray(history.get(name, ()), dtype=float)
    return value if value.shape == (n,) else np.full(n, fill)


def entry(distance, deviation, within):
    """Distance (m) after which ``deviation`` stays at or below ``within``; None if it ends above.

    Parameters
    ----------
    distance : ndarray, shape (K,), m
        Increasing recorded distances.
    deviation : ndarray, shape (K,)
    within : float

    Returns
    -------
    float or None
        ``distance[0]`` if every point is within; else between the last
        point above ``within`` and the next, ``log(deviation)`` linear in
        the distance (linear in the deviation where the next point is 0).
    """
    outside = np.flatnonzero(deviation > within)
    if outside.size == 0:
        return float(distance[0])
    i = int(outside[-1])
    if i + 1 >= distance.size:
        return None
    d0, d1 = float(deviation[i]), float(deviation[i + 1])
    if d1 > 0:
        t = math.log(d0 / within) / math.log(d0 / d1)
    else:
        t = (d0 - within) / d0
    return float(distance[i] + t * (distance[i + 1] - distance[i]))


def run_in_distance(result, within=0.01, *, sliding_speed=None):
    """The run-in distance of ``result`` within ``within`` (module notes).

    Parameters
    ----------
    result : transient.result.RunResult
    within : float, optional
        Relative tolerance in (0, 1); default 0.01.
    sliding_speed : float, optional, m/s
        Default ``result.sliding_speed``; gives the time.  A speed in the
        range of every scale (:data:`steady.scene.SLIDING_SPEED`).

    Returns
    -------
    RunInDistance

    Raises
    ------
    ValueError
        ``within`` or ``sliding_speed`` out of range, or a result without
        the figures it needs (:func:`deviations`).
    """
    within = float(within)
    if not 0.0 < within < 1.0:
        raise ValueError(f"within must lie in (0, 1), got {within!r}")
    # The result's speed was checked where it entered (the problem's).
    speed = (result.sliding_speed if sliding_speed is None
             else SLIDING_SPEED.parse(sliding_speed, ""))
    h = result.history
    s = np.asarray(h["distance"], dtype=float)
    s_star = result.distance_scale
    unsteady = _without_steady_state(result)
    if unsteady:
        nan = math.nan
        return RunInDistance(
            within=within, reached=False, distance_m=nan, distance_s_star=nan,
            uncertainty_m=nan, low_m=nan, high_m=nan, mean_worn_depth_m=nan,
            rim_worn_depth_m=nan, time_s=nan, time_uncertainty_s=nan, end_m=float(s[-1]),
            distance_scale=float(s_star), message=unsteady)
    deviation, low, high = deviations(result)
    nan = math.nan
    companions = [_dataset(h, name, fill=math.nan) for name in (
        "companion_deviation_low", "companion_deviation_high")]
    spatial = all(np.all(np.isfinite(c)) for c in companions)
    common = dict(within=within, end_m=float(s[-1]), distance_scale=float(s_star),
                  spatial=bool(spatial))
    found = entry(s, deviation, within)
    if found is None:
        if result.status == "steady":
            status = ("; the jump to the steady state skipped the rest: lower jump_spread to "
                      "follow it")
        else:
            status = f"; the run {result.status}"
        return RunInDistance(
            reached=False, distance_m=nan, distance_s_star=nan, uncertainty_m=nan, low_m=nan,
            high_m=nan, mean_worn_depth_m=nan, rim_worn_depth_m=nan, time_s=nan,
            time_uncertainty_s=nan,
            message=(f"the dynamics end at s = {s[-1]:.4g} m = {s[-1] / s_star:.4g} s*, "
                     f"{100 * deviation[-1]:.3g} % from the steady state{status}"), **common)
    lo = entry(s, low, within)
    hi = entry(s, high, within)
    lo = found if lo is None else min(lo, found)
    hi = math.inf if hi is None else max(hi, found)
    if spatial:
        # The companions' own entries into the band: the earliest and the latest.
        early = entry(s, companions[0], within)
        late = entry(s, companions[1], within)
        early = found if early is None else min(early, found)
        late = math.inf if late is None else max(late, found)
        lo = found - math.hypot(found - lo, found - early)
        hi = found + math.hypot(hi - found, late - found)
    uncertainty = max(found - lo, hi - found)
    area = float(np.count_nonzero(result.face_mask)) * result.pixel_size ** 2
    mean_depth = float(np.interp(found, s, np.asarray(h["worn_volume"], dtype=float))) / area
    rim = _dataset(h, "rim_worn_depth")
    rim_depth = float(np.interp(found, s, rim)) if np.all(np.isfinite(rim)) else nan
    return RunInDistance(
        reached=True, distance_m=found, distance_s_star=float(found / s_star),
        uncertainty_m=uncertainty, low_m=lo, high_m=hi, mean_worn_depth_m=mean_depth,
        rim_worn_depth_m=rim_depth, time_s=nan if speed is None else found / speed,
        time_uncertainty_s=nan if speed is None else uncertainty / speed, **common)


def _without_steady_state(result):
    """Why a depth run that ended without a steady state has no run-in distance, or "".

    A run whose phase map changes with depth (``result.columns``) and that
    ended at its ``end_depth`` or ``max_distance`` (status ``"depth"`` or
    ``"distance"``) approached no steady state: the one of the initial
    section is not its limit.  A columnar run's status does not matter here.
    """
    columns = getattr(result, "columns", None)
    if columns is None or columns.columnar or result.status not in ("depth", "distance"):
        return ""
    s = float(np.asarray(result.history["distance"], dtype=float)[-1])
    end = "depth" if result.status == "depth" else "distance"
    return (f"the run ended at its {end} (s = {s:.4g} m = {s / result.distance_scale:.4g} s*) "
            f"before its section was columnar: no steady state to approach")


#: The coating events :func:`coating_distance` finds, and what each one is.
COATING_EVENTS = {
    "worn_through": "the coating is first worn through anywhere (a pixel past its first "
                    "interface)",
    "gone": "the coating is gone from the contact (no contact pixel left in the coating phase)",
}

# The history dataset whose sign change marks each event, and the sign after it.
_COATING_MARKS = {"worn_through": ("coating_overshoot", 1.0),
                  "gone": ("coating_contact_remaining", -1.0)}


@dataclasses.dataclass(frozen=True)
class CoatingDistance:
    """Where a coating event happened along a run (:data:`COATING_EVENTS`).

    Attributes
    ----------
    event : str
        ``"worn_through"`` or ``"gone"``.
    distance_m : float, m
        Sliding distance of the event, interpolated between the recorded
        points (NaN when not reached).
    distance_s_star : float
        The same in units of ``s*``.
    reason : str
        Why it is NaN ("" when reached).
    """

    event: str
    distance_m: float
    distance_s_star: float
    reason: str = ""

    @property
    def reached(self):
        """Whether the event happened within the run."""
        return math.isfinite(self.distance_m)

    def summary(self):
        """One line for the terminal."""
        what = {"worn_through": "coating worn through", "gone": "coating gone from the contact"}
        if not self.reached:
            return f"{what[self.event]}: not reached ({self.reason})"
        return (f"{what[self.event]} at s = {self.distance_m:.5g} m = "
                f"{self.distance_s_star:.4g} s*")


def coating_distance(result, event):
    """Distance at which a coating event happened in ``result``, from its history.

    The event marks are the history's ``coating_overshoot`` (the largest
    depth worn past the coating: the coating is worn through once it is
    ``>= 0``, a depth at an interface being in the segment below) and
    ``coating_contact_remaining`` (the largest coating thickness left under
    a contact pixel: gone once ``<= 0``).  The distance is the first
    recorded point where the mark has changed sign, interpolated linearly
    in the mark between it and the point before.

    Parameters
    ----------
    result : transient.result.RunResult
    event : str
        A key of :data:`COATING_EVENTS`.

    Returns
    -------
    CoatingDistance
        NaN distances with the reason when the run has no coating or the
        event did not happen before the run's end.

    Raises
    ------
    ValueError
        An unknown ``event``.
    """
    if event not in COATING_EVENTS:
        raise ValueError(f"coating event must be one of {', '.join(COATING_EVENTS)}, "
                         f"got {event!r}")
    name, sign = _COATING_MARKS[event]
    h = result.history
    s_star = result.distance_scale

    def missing(reason):
        return CoatingDistance(event, math.nan, math.nan, reason)

    if name not in h:
        return missing("the run has no coating: its surface section is not one layer of one "
                       "phase over the whole face")
    s = np.asarray(h["distance"], dtype=float)
    mark = sign * np.asarray(h[name], dtype=float)
    past = np.flatnonzero(mark >= 0.0)
    if past.size == 0:
        return missing(f"not by the end of the run at s = {s[-1]:.4g} m = "
                       f"{s[-1] / s_star:.4g} s*")
    i = int(past[0])
    found = float(s[i])
    before = mark[i - 1] if i > 0 else math.nan
    if math.isfinite(before) and before < 0.0:
        t = -before / (mark[i] - before)
        found = float(s[i - 1] + t * (s[i] - s[i - 1]))
    return CoatingDistance(event, found, found / s_star)


def distance_table(result, tolerances=TOLERANCES):
    """The run-in distances of ``result`` as the run file's group ``run_in_distance`` holds them.

    Parameters
    ----------
    result : transient.result.RunResult
    tolerances : sequence of float, optional
        Default :data:`TOLERANCES`.

    Returns
    -------
    dict
        ``name -> (values, units, long_name)``, each ``values`` of shape
        ``(len(tolerances),)`` (NaN where not reached; ``time`` NaN without
        a sliding speed); empty when the result lacks the figures
        (:func:`deviations`).
    """
    try:
        found = [run_in_distance(result, x) for x in tolerances]
    except ValueError:
        return {}

    def column(name):
        return np.array([getattr(d, name) for d in found], dtype=float)

    return {
        "within": (np.array(tolerances, dtype=float), "1",
                   "relative tolerance of the deviation from the steady state"),
        "reached": (column("reached"), "1",
                    "1 where the run ends within the tolerance, else 0"),
        "distance": (column("distance_m"), "m",
                     "sliding distance after which the rms slope and the face stay within the "
                     "tolerance of the steady state"),
        "distance_s_star": (column("distance_s_star"), "1",
                            "the same distance over the distance scale s*"),
        "uncertainty": (column("uncertainty_m"), "m",
                        "uncertainty of the distance from the step and grid errors"),
        "low": (column("low_m"), "m", "lower bound of the distance"),
        "high": (column("high_m"), "m", "upper bound of the distance (inf: not resolved)"),
        "mean_worn_depth": (column("mean_worn_depth_m"), "m",
                            "depth worn off at that distance, mean over the face"),
        "rim_worn_depth": (column("rim_worn_depth_m"), "m",
                           "depth worn off at that distance, mean over the rim pixels"),
        "time": (column("time_s"), "s", "that distance over the sliding speed (NaN: none)"),
        "time_uncertainty": (column("time_uncertainty_s"), "s",
                             "uncertainty of the time (NaN: no sliding speed)"),
    }


class WearThroughMap:
    """The sliding distance at which each face pixel's worn depth first reaches a depth.

    An ``on_step`` callback of :func:`transient.runin.run_in`: after every
    accepted step it marks the pixels whose worn depth passed ``depth``
    during the step, at the distance interpolated linearly within it.  With
    a coating's thickness it maps where and when the coating wears through.

    Parameters
    ----------
    face_mask : ndarray of bool, shape (nx, ny)
    depth : float or ndarray, shape (nx, ny), m
        The depth below the initial surface to reach (e.g. a coating's
        thickness).

    Attributes
    ----------
    distance : ndarray, shape (nx, ny), m
        Sliding distance at which each pixel reached ``depth``; NaN off the
        face and where it has not (yet).
    """

    def __init__(self, face_mask, depth):
        self.face_mask = np.asarray(face_mask, dtype=bool)
        self.depth = np.broadcast_to(np.asarray(depth, dtype=float), self.face_mask.shape)
        self.distance = np.full(self.face_mask.shape, np.nan)
        self._last = (0.0, np.zeros(self.face_mask.shape))

    def __call__(self, run):
        """Mark the pixels that reached the depth in the step that ended at ``run.s``."""
        worn = run.worn_depth()
        s0, w0 = self._last
        new = self.face_mask & np.isnan(self.distance) & (worn >= self.depth)
        if new.any():
            before = w0[new]
            self.distance[new] = s0 + ((self.depth[new] - before) / (worn[new] - before)
                                       * (run.s - s0))
        self._last = (run.s, worn.copy())
