"""A coated flat punch worn on the square grid against its axisymmetric reference.

A homogeneous coating (thickness ``t``, ``k_c``) on a homogeneous substrate
(``k_s``) of a flat disk punch stays axisymmetric while it wears, so the 2-d
run across the interface (transient.runin, docs/model.md "Wear across
interfaces") must follow :class:`transient.axisymmetric.CoatedAxisymmetricRunIn`
(docs/model.md, "The coated reference") up to the grid's error.  The scene
is the shipped ``coating_transient.toml`` with ``t = 0.5 pbar a / E*`` and
``k_s / k_c = 4``, the reference on 80 graded rings.  Checked: (a) every
pixel wears through at the reference's ``crossing_distance`` of its radius,
(b) the mean worn depth follows the exact identity of the worn volume,
(c) after the coating is gone the rms slope and the face's deviation from
eq. 10 match the reference within the grid's error bars, (d) the face decays
to the substrate's steady state at the reference's rate.  The grid's error is
measured between n = 64 and 128 (n = 128 is marked slow); (c) and (d) are
followed further down at a tighter tolerance (marked slow).
"""

import dataclasses
import math

import numpy as np
import pytest

from transient.axisymmetric import CoatedAxisymmetricRunIn
from transient.options import RunOptions
from transient.run_in_distance import WearThroughMap
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of

EXAMPLE = "steady/examples/coating_transient.toml"
#: Coating thickness over ``pbar a / E*`` (pbar = F / (pi a^2)) and ``k_s / k_c``.
THICKNESS, RATIO = 0.5, 4.0
RINGS = 80
TOL = 1e-4
#: The tighter tolerance of the slow checks that follow the face further down.
FINE_TOL = 1e-5


def coated_scene():
    """The example scene with the coating ``THICKNESS`` thick over a substrate ``RATIO`` softer."""
    scene, _, _ = load_transient_scene(EXAMPLE)
    k_c = scene.wear.coefficients[1]
    a, E_star = scene.outline.scale, scene.E_star
    f_star = scene.normal_force / (math.pi * a * E_star)
    return dataclasses.replace(
        scene, wear=dataclasses.replace(scene.wear, coefficients=(RATIO * k_c, k_c)),
        depth=dataclasses.replace(scene.depth, thicknesses=(THICKNESS * f_star,)))


def make_reference():
    """The reference in the scene's own units (m, Pa, 1/Pa)."""
    scene = coated_scene()
    k_c = scene.wear.coefficients[1]
    return CoatedAxisymmetricRunIn(
        RINGS, thickness=scene.depth.thicknesses[0], substrate_coefficient=RATIO * k_c,
        radius=scene.outline.scale, E_star=scene.E_star, normal_force=scene.normal_force,
        wear_coefficient=k_c)


@dataclasses.dataclass
class CoatedRun:
    """A 2-d run and the distance (m) at which each face pixel wore through (NaN off it)."""

    result: object
    problem: object
    crossing: np.ndarray
    radius: np.ndarray


@pytest.fixture(scope="module")
def reference():
    """The reference, built once."""
    return make_reference()


@pytest.fixture(scope="module")
def runs():
    """The 2-d runs by grid size (and tolerance), each run once."""
    done = {}

    def get(n, tol=TOL):
        if (n, tol) not in done:
            done[n, tol] = coated_run(n, tol)
        return done[n, tol]

    return get


def coated_run(n, tol=TOL):
    """Run the coated scene on ``n`` pixels to its steady state, recording the wear-through.

    A pixel's wear-through lies in the accepted step in which its worn depth
    passed the thickness, linearly interpolated within the step.
    """
    scene = coated_scene()
    problem = wear_problem_of(scene, n=n)
    face, t = problem.face_mask, scene.depth.thicknesses[0]
    crossing = WearThroughMap(face, t)
    result = run_in(problem, np.zeros(problem.shape), RunOptions(tol=tol), on_step=crossing)
    assert result.status == "steady", result.message
    return CoatedRun(result, problem, crossing.distance, problem.grid.radii)


def _history(run, name):
    return np.asarray(run.result.history[name], dtype=float)


def _crossing_errors(run, reference):
    """Each face pixel's wear-through distance minus the reference's at its radius, in s*_c."""
    face = run.problem.face_mask
    expected = reference.crossing_distance(run.radius[face])
    return (run.crossing[face] - expected) / reference.distance_scale


# Measured at tol 1e-4, in s*_c (the front sweeps the face over 0.44 s*_c): largest
# |error| 0.0184 (n = 64), 0.0076 (128); rms 0.0029, 0.00105 (first order in h or
# better).  Bounds: the measured errors with a margin of 1.3 to 1.4.
CROSSING_BOUNDS = {64: (0.025, 0.004), 128: (0.010, 0.0015)}


@pytest.mark.parametrize("n", [64, pytest.param(128, marks=pytest.mark.slow)])
def test_every_pixel_wears_through_where_the_reference_does(runs, reference, n):
    run = runs(n)
    face = run.problem.face_mask
    assert not np.isnan(run.crossing[face]).any(), "a face pixel never wore through"
    radius, crossing = run.radius[face], run.crossing[face]
    h = run.problem.grid.h
    assert radius[np.argmin(crossing)] > reference.radius - 1.5 * h, "the rim is not first"
    assert radius[np.argmax(crossing)] < 1.5 * h, "the centre is not last"
    error = _crossing_errors(run, reference)
    largest, rms = np.max(np.abs(error)), np.sqrt(np.mean(error ** 2))
    bound_max, bound_rms = CROSSING_BOUNDS[n]
    assert largest < bound_max, f"n = {n}: a pixel wears through {largest:.3g} s*_c off"
    assert rms < bound_rms, f"n = {n}: rms wear-through error {rms:.3g} s*_c"


@pytest.mark.slow
def test_the_wear_through_converges_with_the_grid(runs, reference):
    coarse, fine = (np.sqrt(np.mean(_crossing_errors(runs(n), reference) ** 2))
                    for n in (64, 128))
    # Measured ratio 0.36: first order in h, or better; bound 0.55 (1.5 times it).
    assert fine < 0.55 * coarse, f"rms error {coarse:.3g} (n = 64) -> {fine:.3g} (n = 128)"


def test_mean_worn_depth_follows_the_worn_volume(runs, reference):
    """``k_c pbar s`` before the first crossing, ``k_s pbar s - t (k_s/k_c - 1)`` after the last.

    ``pbar`` is the run's: the force over the face's pixels.  Before any
    crossing the identity is exact (measured 2.3e-16 f*); after the last the
    contact solves leave 2.4e-7 f* at tol 1e-4 (bound 1e-6).
    """
    run = runs(64)
    result, scene = run.result, coated_scene()
    s, worn = _history(run, "distance"), _history(run, "worn_depth_mean")
    k_s, k_c = scene.wear.coefficients
    t, pbar = scene.depth.thicknesses[0], result.pixel_mean_pressure
    f_star = result.depth_scale
    crossing = run.crossing[run.problem.face_mask]
    before, after = s <= crossing.min(), s >= crossing.max()
    assert before.sum() > 5 and after.sum() > 5, f"{before.sum()} / {after.sum()} points"
    error = np.abs(worn[before] - k_c * pbar * s[before]) / f_star
    assert error.max() < 1e-13, f"before the first crossing: {error.max():.3g} f* off"
    error = np.abs(worn[after] - (k_s * pbar * s[after] - t * (k_s / k_c - 1))) / f_star
    assert error.max() < 1e-6, f"after the last crossing: {error.max():.3g} f* off"


def _after_the_coating(run, reference):
    """History points after the reference's last crossing: distance, slope, deviation, and refs."""
    _, last = reference.wear_through_distances()
    s = _history(run, "distance")
    keep = s >= last
    states = [reference.state(d) for d in s[keep]]
    slope = np.array([st.rms_slope for st in states]) / reference.reference_slope
    deviation = np.array([st.face_deviation for st in states])
    return (s[keep], _history(run, "normalised_rms_slope")[keep],
            _history(run, "rms_slope_error")[keep] / run.result.reference_slope,
            _history(run, "face_deviation")[keep], slope, deviation)


# Above this face deviation the history's decay is the grid's, not the step's.  At
# tol 1e-4 the steps grow to several e-foldings of the substrate (0.12 s*_c): n = 64
# keeps D / D_ref - 1 at the grid's 0.044 down to D = 1e-2, then 0.030 at 4.3e-3,
# 0.002 at 1.4e-3, -0.11 at 2.4e-4 (a step of 0.33 s*_c) and -0.94 at 1e-6.  At
# tol 1e-5 (2.7 times the steps) it keeps 0.036-0.046 down to D = 6.5e-4, then 0.019
# at 2.4e-4 and -0.04 at 5.6e-5: FINE_RESOLVED.
# (Deviations relative to the relief of eq. 10 there; relative to its rms, as now, they are
# 1 / 0.2717 = 3.68 times larger: the windows below are the same faces.)
RESOLVED = 1.1e-2
FINE_RESOLVED = 1.1e-3
#: Above this the face has not yet settled into the substrate's slowest mode.
SETTLED = 0.11


def test_after_the_coating_slope_and_face_match_the_reference(runs, reference):
    s, slope, slope_error, deviation, ref_slope, ref_deviation = _after_the_coating(
        runs(64), reference)
    assert len(s) > 5, f"{len(s)} points after the coating is gone"
    # Measured at n = 64: |S - S_ref| 0.0028-0.0034, 0.26-0.29 of the estimator's error bar.
    off = np.abs(slope - ref_slope) / slope_error
    assert off.max() < 0.5, f"rms slope off by {off.max():.3g} of its error bar"
    resolved = deviation > RESOLVED
    # Measured: D / D_ref - 1 = 0.009-0.019 on 8 points (0.030-0.044 while D was relative
    # to the relief, which the pixel centres miss).
    ratio = deviation[resolved] / ref_deviation[resolved] - 1
    assert np.all(np.abs(ratio) < 0.03), f"face deviation off by {ratio.max():.3g}"


@pytest.mark.slow
def test_after_the_coating_the_grid_error_bars_hold(runs, reference):
    """Within twice the n = 64 to 128 difference.

    Measured: the n = 128 error is 1.12 times the difference for the rms slope
    (0.0018 against 0.0016) and 1.02 times it for the face deviation (0.0098
    against 0.0096).
    """
    coarse, fine = runs(64), runs(128)
    s, slope, _, deviation, ref_slope, ref_deviation = _after_the_coating(fine, reference)
    later = s >= s[0] + 0.1 * reference.distance_scale  # the coarse history's points are sparse
    s_c = _history(coarse, "distance")
    slope_c = np.interp(s, s_c, _history(coarse, "normalised_rms_slope"))
    bar = 2 * np.max(np.abs(slope_c - slope)[later])
    off = np.abs(slope - ref_slope)[later]
    assert off.max() < bar, f"rms slope off by {off.max():.3g}, error bar {bar:.3g}"
    assert np.all(off < np.abs(slope_c - ref_slope)[later]), "the finer grid is not closer"
    resolved = later & (deviation > RESOLVED)
    deviation_c = np.exp(np.interp(s, s_c, np.log(_history(coarse, "face_deviation"))))
    bar = 2 * np.max(np.abs(deviation_c / deviation - 1)[resolved])
    off = np.abs(deviation / ref_deviation - 1)[resolved]
    assert off.max() < bar, f"face deviation off by {off.max():.3g}, error bar {bar:.3g}"


@pytest.mark.parametrize("n", [64, pytest.param(128, marks=pytest.mark.slow)])
def test_the_face_decays_to_the_substrate_steady_state_at_the_reference_rate(runs, reference, n):
    s, _, _, deviation, _, _ = _after_the_coating(runs(n), reference)
    window = (deviation > RESOLVED) & (deviation < SETTLED)
    assert window.sum() >= 3, f"{window.sum()} points to fit"
    slope = np.polyfit(s[window], np.log(deviation[window]), 1)[0]
    decay = -1.0 / slope / reference.substrate_decay_distance - 1
    # Measured: -0.60 % (n = 64), -0.73 % (n = 128) against 0.4853 a / (k_s E*).
    assert abs(decay) < 0.015, f"n = {n}: decay distance {decay:+.3%} off the reference's"


@pytest.mark.slow
def test_at_a_tighter_tolerance_the_face_follows_the_reference_further(runs, reference):
    """At ``FINE_TOL`` the deviation matches down to ``FINE_RESOLVED``, the rate within 0.5 %."""
    s, _, _, deviation, _, ref_deviation = _after_the_coating(runs(64, FINE_TOL), reference)
    resolved = deviation > FINE_RESOLVED
    assert resolved.sum() >= 15, f"{resolved.sum()} points above {FINE_RESOLVED}"
    # Measured (n = 64): D / D_ref - 1 = 0.006-0.021 on 20 points.
    ratio = deviation[resolved] / ref_deviation[resolved] - 1
    assert np.all(np.abs(ratio) < 0.03), f"face deviation off by {ratio.max():.3g}"
    window = resolved & (deviation < SETTLED)
    slope = np.polyfit(s[window], np.log(deviation[window]), 1)[0]
    decay = -1.0 / slope / reference.substrate_decay_distance - 1
    # Measured: -0.27 % (n = 64) over FINE_RESOLVED < D < SETTLED; -0.60 % at tol 1e-4.
    assert abs(decay) < 0.005, f"decay distance {decay:+.3%} off the reference's"
