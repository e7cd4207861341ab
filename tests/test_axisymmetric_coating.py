"""The coated axisymmetric reference: its limits, conservation, order and physical behaviour."""

import math

import numpy as np
import pytest

from transient.axisymmetric import (
    AxisymmetricRunIn,
    CoatedAxisymmetricRunIn,
    coated_reference_history,
)

RINGS = 40
DISTANCES = (0.01, 0.1, 1.0)


@pytest.fixture(scope="module")
def coating():
    """A tenth of ``pbar a / E*`` of coating on a substrate wearing ten times faster."""
    return CoatedAxisymmetricRunIn(RINGS, thickness=0.1, substrate_coefficient=10.0)


def assert_same_run(state, other, tol, what):
    """Same pressure, same face up to a constant, same rms slope."""
    pressure = np.max(np.abs(state.pressure / other.pressure - 1))
    face = np.ptp(state.face - other.face) / np.ptp(other.face)
    slope = abs(state.rms_slope / other.rms_slope - 1)
    assert max(pressure, face, slope) < tol, \
        f"{what} at s = {state.distance}: pressure {pressure:.1e}, face {face:.1e}, " \
        f"rms slope {slope:.1e} apart"


@pytest.mark.parametrize("distance", DISTANCES)
def test_thick_coating_is_the_homogeneous_coating(distance):
    """Thick coating, t -> infinity: the coating's run.

    No ring crosses; measured 6e-10 apart at s = s* (rounding), bound 1e-8.
    """
    thick = CoatedAxisymmetricRunIn(RINGS, thickness=1e6, substrate_coefficient=10.0)
    state = thick.state(distance)
    assert state.rings_through == 0, "no ring wears through a thick coating"
    assert_same_run(state, AxisymmetricRunIn(RINGS).state(distance), 1e-8, "thick coating")


@pytest.mark.parametrize("distance", DISTANCES)
def test_thin_coating_is_the_substrate(distance):
    """Thin coating, t -> 0: the substrate's run.

    Measured 8.8e-9 apart at s = s* with t = 1e-7, bound 5e-8.
    """
    thin = CoatedAxisymmetricRunIn(RINGS, thickness=1e-7, substrate_coefficient=10.0)
    state = thin.state(distance)
    assert state.rings_through == RINGS, "a thin coating is gone from the whole face"
    substrate = AxisymmetricRunIn(RINGS, wear_coefficient=10.0).state(distance)
    assert_same_run(state, substrate, 5e-8, "thin coating")


@pytest.mark.parametrize("distance", DISTANCES)
def test_equal_coefficients_are_homogeneous(distance):
    """k_c = k_s: crossings change nothing; measured 6e-10 apart, bound 1e-8."""
    same = CoatedAxisymmetricRunIn(RINGS, thickness=0.1, substrate_coefficient=1.0)
    state = same.state(distance)
    assert_same_run(state, AxisymmetricRunIn(RINGS).state(distance), 1e-8, "k_c = k_s")


@pytest.mark.parametrize("distance", (0.005, 0.05, 0.3, 2.0))
def test_load_and_wear_volume_are_conserved(coating, distance):
    """The load is carried; the worn volume is Archard's of the wear work pbar s.

    A ring's depth is ``k_c R`` before it crosses and ``k_s R - t (k_s/k_c - 1)``
    after (``R`` its wear work), so the mean depth is ``k_c pbar s`` before the
    first crossing and ``k_s pbar s - t (k_s/k_c - 1)`` after the last.
    """
    state = coating.state(distance)
    load = float(coating.areas @ state.pressure)
    assert load == pytest.approx(coating.normal_force, rel=1e-12), f"load {load}"
    first, last = coating.wear_through_distances()
    pbar, t = coating.mean_pressure, coating.thickness
    k_c, k_s = coating.wear_coefficient, coating.substrate_coefficient
    if distance < first:
        expected = k_c * pbar * distance
    elif distance > last:
        expected = k_s * pbar * distance - t * (k_s / k_c - 1)
    else:
        expected = None
    if expected is not None:
        assert state.mean_worn_depth == pytest.approx(expected, rel=1e-10), \
            f"mean worn depth {state.mean_worn_depth} vs {expected}"


@pytest.mark.parametrize("ratio", (10.0, 0.1))
def test_rim_wears_through_first(ratio):
    """The rim crosses first, then the rings one after another towards the centre."""
    run = CoatedAxisymmetricRunIn(RINGS, thickness=0.1, substrate_coefficient=ratio)
    first, last = run.wear_through_distances()
    assert first == run.crossings[-1] and last == run.crossings[0], \
        f"first crossing at ring {np.argmin(run.crossings)}, last at {np.argmax(run.crossings)}"
    assert np.all(np.diff(run.crossings) <= 0), "rings do not cross from the rim inwards"
    assert run.state(0.5 * (first + last)).rings_through not in (0, RINGS), \
        "half-way between the crossings the coating is partly gone"


def test_crossing_distance_between_rings(coating):
    """At the ring centres the crossings; in between, between its neighbours'."""
    coating.wear_through_distances()
    at_centres = coating.crossing_distance(coating.centres)
    assert np.array_equal(at_centres, coating.crossings), "crossings at the ring centres"
    mid = coating.crossing_distance(0.5 * (coating.centres[1:] + coating.centres[:-1]))
    assert np.all((mid <= coating.crossings[:-1]) & (mid >= coating.crossings[1:])), \
        "interpolated crossings out of order"
    with pytest.raises(ValueError, match="radius must lie in"):
        coating.crossing_distance(1.5)


@pytest.mark.parametrize("ratio", (10.0, 1000.0))
def test_softer_substrate_unloads_the_rim_but_keeps_contact(ratio):
    """Through at steady state (t = 3): the rim's pressure falls towards pbar k_c / k_s, not 0.

    Measured at the crossings: lowest ring pressure 0.1009 pbar (ratio 10),
    0.00101 pbar (ratio 1000).
    """
    run = CoatedAxisymmetricRunIn(RINGS, thickness=3.0, substrate_coefficient=ratio)
    first, last = run.wear_through_distances()
    low = run.minimum_crossing_pressure
    assert 0.9 / ratio < low < 1.2 / ratio, f"lowest pressure {low} pbar at the crossings"
    mid = run.state(0.5 * (first + last))
    assert mid.pressure[-1] < mid.pressure[0], "the worn-through rim carries less than the centre"


def test_approach_to_the_substrate_steady_state(coating):
    """After the last crossing the face tends to eq. 10 at the slowest mode of -k_s B.

    Measured rate over 2 to 4 decay distances: 1.00027 of the slowest mode's
    (faster modes not quite gone), bound 2e-3.
    """
    _, last = coating.wear_through_distances()
    decay = coating.substrate_decay_distance
    s1, s2 = last + 2 * decay, last + 4 * decay
    d1, d2 = coating.state(s1).face_deviation, coating.state(s2).face_deviation
    rate = math.log(d1 / d2) / (s2 - s1)
    assert rate * decay == pytest.approx(1.0, rel=2e-3), \
        f"deviation decays at {rate * decay:.3f} of the slowest substrate mode"
    final = coating.state(last + 40 * decay)
    assert final.rms_slope / coating.reference_slope == pytest.approx(
        AxisymmetricRunIn(RINGS).state(30.0).rms_slope / coating.reference_slope, abs=1e-9), \
        "the steady rms slope is the homogeneous one"


def test_ring_refinement_is_second_order():
    """Crossing distances and the rms slope after the last crossing: order 2 in 1/N.

    Measured (t = 0.1, k_s/k_c = 10, N = 20, 40, 80, 160): orders 1.89, 1.99
    (first), 2.05, 2.05 (last), 2.03, 2.01 (rms slope at 0.2 s*).
    """
    rows = []
    for count in (20, 40, 80):
        run = CoatedAxisymmetricRunIn(count, thickness=0.1, substrate_coefficient=10.0)
        rows.append([*run.wear_through_distances(), run.state(0.2).rms_slope])
    rows = np.array(rows)
    order = np.log2(np.abs(rows[1] - rows[0]) / np.abs(rows[2] - rows[1]))
    assert np.all((order > 1.7) & (order < 2.4)), f"observed orders {order}"


def test_reference_history_error_bars():
    """Extrapolated away from the front, the difference on it; the flat face at s = 0."""
    ref = coated_reference_history([0.0, 0.05, 0.2], thickness_f_star=0.1, ratio=10.0, rings=40)
    assert ref.rms_slope[0] == 0.0 and ref.mean_worn_depth[0] == 0.0, "s = 0 is the flat face"
    assert ref.first_through < 0.05 < ref.last_through < 0.2, \
        f"crossings {ref.first_through}, {ref.last_through}"
    # Measured, 80 rings: 1.2612 at 0.05 s* (on the front), 1.02072 at 0.2 s*.
    assert ref.rms_slope[1] == pytest.approx(1.2612, abs=ref.rms_slope_error[1]), ref.rms_slope
    assert ref.rms_slope[2] == pytest.approx(1.02072, abs=2 * ref.rms_slope_error[2]), \
        ref.rms_slope
    assert ref.mean_worn_depth[2] == pytest.approx(1.1, rel=1e-10), "wear volume after the front"


def test_bad_input_is_named():
    with pytest.raises(ValueError, match=r"thickness must be a number > 0 \(m\), got 0.0"):
        CoatedAxisymmetricRunIn(20, thickness=0.0, substrate_coefficient=1.0)
    with pytest.raises(ValueError, match=r"substrate_coefficient must be a number > 0 \(1/Pa\), "
                                         r"got nan"):
        CoatedAxisymmetricRunIn(20, thickness=1.0, substrate_coefficient=float("nan"))
    with pytest.raises(ValueError, match="distance must be"):
        CoatedAxisymmetricRunIn(20, thickness=1.0, substrate_coefficient=2.0).state(-1.0)
    with pytest.raises(ValueError, match=r"distances_s_star must be an array of numbers each "
                                         r">= 0 \(s\*\), got \[-0.1\]"):
        coated_reference_history([-0.1], thickness_f_star=0.1, ratio=10.0, rings=20)


@pytest.mark.slow
def test_reference_history_160_rings():
    """The figures docs/model.md quotes (t = 0.1, k_s/k_c = 10, 160 rings); 56 s on 2 cores."""
    ref = coated_reference_history([1e-3, 0.05, 0.2, 0.5], thickness_f_star=0.1, ratio=10.0,
                                   rings=160)
    assert ref.first_through == pytest.approx(0.009839, abs=1e-6), ref.first_through
    assert ref.last_through == pytest.approx(0.14561, abs=1e-5), ref.last_through
    assert ref.first_through_error < 5e-6 and ref.last_through_error < 2e-5, \
        (ref.first_through_error, ref.last_through_error)
    assert ref.rms_slope == pytest.approx([0.84909, 1.27774, 1.02085, 1.00004], abs=2e-5), \
        ref.rms_slope
    assert ref.rms_slope_error[1] == pytest.approx(0.017, abs=1e-3), "front: |S_N - S_N/2|"
    assert ref.substrate_decay_distance * ref.ratio == pytest.approx(0.4853, abs=1e-4), \
        ref.substrate_decay_distance
