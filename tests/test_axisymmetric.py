"""The axisymmetric run-in reference against the flat punch, eq. 10 and its own refinement."""

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.special

from steady import reference
from transient.axisymmetric import AxisymmetricRunIn, reference_history


@pytest.fixture(scope="module")
def model():
    return AxisymmetricRunIn(rings=200)


def eq10_rms_height():
    """Rms of E(r/a) about its mean over the unit disk (normalised eq. 10 face)."""
    def disk_mean(f):
        return 2 * scipy.integrate.quad(lambda k: f(k) * k, 0, 1, epsabs=0, epsrel=1e-12)[0]

    mean = disk_mean(lambda k: scipy.special.ellipe(k * k))
    return math.sqrt(disk_mean(lambda k: (scipy.special.ellipe(k * k) - mean) ** 2))


def test_flat_punch_at_s0(model):
    """At s = 0 the rigid flat punch, approach F/(2 a E*), pressure F/(2 pi a sqrt(a^2 - r^2)).

    Measured with 200 rings: approach within 5.2e-8, ring pressures within
    3.7e-5 of the closed form inside r < 0.9 a (collocation at the ring
    centres of a piecewise-constant pressure); bounds 20 times that.
    """
    state = model.state(0.0)
    approach = reference.flat_punch_approach(model.normal_force, model.radius, model.E_star)
    assert state.approach == pytest.approx(approach, rel=1e-6), \
        f"approach {state.approach} vs F/(2aE*) = {approach}"
    inner = model.centres < 0.9 * model.radius
    exact = reference.flat_punch_pressure(model.centres[inner], model.radius, model.normal_force)
    err = np.max(np.abs(state.pressure[inner] / exact - 1))
    assert err < 1e-3, f"flat-punch pressure off by {err:.2e} inside 0.9 a"
    assert state.rms_slope == 0.0 and state.rms_height < 1e-12, \
        "the flat face has no slope and no relief"


def test_steady_state_is_eq10(model):
    """For s >> s* the face tends to eq. 10, rms slope grad_f0, rms height 0.15499 grad_f0 a.

    Measured with 200 rings at s = 30 s*: face within 2.4e-9 of the relief,
    rms slope 0.999979, rms height within 1.1e-5, pressure uniform to 3e-8.
    """
    state = model.state(30 * model.distance_scale)
    pbar = model.mean_pressure
    exact = reference.disk_face(model.centres, model.radius, pbar, model.E_star)
    diff = state.face - exact
    relief = exact.max() - exact.min()
    assert np.ptp(diff) / relief < 1e-7, f"steady face off eq. 10 by {np.ptp(diff) / relief:.2e}"
    assert state.rms_slope / model.reference_slope == pytest.approx(1.0, abs=1e-4), \
        f"steady rms slope {state.rms_slope / model.reference_slope}"
    height = state.rms_height / (model.reference_slope * model.radius)
    assert height == pytest.approx(eq10_rms_height(), rel=1e-4), \
        f"steady rms height {height} vs eq. 10 {eq10_rms_height()}"
    assert np.all(np.abs(state.pressure / pbar - 1) < 1e-6), "steady pressure is uniform"


def test_exact_in_distance_against_a_matrix_exponential(model):
    """The eigen-decomposition route agrees with expm of the affine generator."""
    n = model.rings
    generator = np.zeros((n + 1, n + 1))
    generator[:n, :n] = -model.wear_coefficient * model._b
    generator[:n, n] = model.wear_coefficient * model._c
    s = 0.05 * model.distance_scale
    w = scipy.linalg.expm(generator * s)[:n, n]
    shape = w - model.recession(s)
    # Measured: 1.5e-9 of the relief (the scaling and squaring of a stiff generator).
    assert np.ptp(shape) < 1e-8 * np.ptp(w), \
        f"heights differ by {np.ptp(shape):.2e} beyond a constant (relief {np.ptp(w):.2e})"


def test_history_jumps_at_s0_and_rises_to_one(model):
    """Flat face: rms slope 0 at s = 0, about 0.848 grad_f0 just after, then rising to 1."""
    s = np.array([0.0, 1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]) * model.distance_scale
    slopes = np.array([model.state(d).rms_slope for d in s]) / model.reference_slope
    assert slopes[0] == 0.0, "the flat face's slope is 0"
    assert 0.84 < slopes[1] < 0.86, f"rms slope just after s = 0: {slopes[1]:.4f}"
    assert np.all(np.diff(slopes[1:]) > 0), f"history not increasing: {slopes}"
    assert slopes[-1] == pytest.approx(1.0, abs=5e-4), f"s = 10 s*: {slopes[-1]}"


def test_ring_refinement_is_second_order():
    """Richardson's assumption: differences fall by about 4 per doubling of the rings.

    Measured at s = 1e-3 s* (beta = 4): differences 7.8e-3 and 2.1e-3 of the
    rms slope for N = 40 -> 80 -> 160, order 1.92 (1.95 for 75 -> 150 -> 300).
    """
    counts = (40, 80, 160)
    values = [AxisymmetricRunIn(c).state(1e-3).rms_slope for c in counts]
    order = math.log2(abs(values[1] - values[0]) / abs(values[2] - values[1]))
    assert 1.6 < order < 2.5, f"observed order {order:.2f} of the ring refinement"


def test_reference_history_extrapolates():
    ref = reference_history([0.0, 0.01, 1.0], rings=300)
    assert ref.rms_slope[0] == 0.0, "s = 0 is the flat face"
    # The 1200-ring extrapolated values (docs/benchmarks.md): 0.854770, 0.982926;
    # with 300 rings 0.854770 and 0.982926, error estimates 5e-5 and 1e-5.
    assert ref.rms_slope[1:] == pytest.approx([0.854770, 0.982926], abs=2e-5), ref.rms_slope
    assert np.all(ref.rms_slope_error[1:] < 1e-4), ref.rms_slope_error


@pytest.mark.parametrize("build, fragment", [
    (lambda: AxisymmetricRunIn(rings=2), "rings must be an integer >= 4, got 2"),
    (lambda: AxisymmetricRunIn(rings=20, grading=0.5),
     "grading must be a number >= 1 (1), got 0.5"),
    (lambda: AxisymmetricRunIn(rings=20, radius=-1.0), "radius must be a number > 0 (m), got -1.0"),
    (lambda: AxisymmetricRunIn(rings=20, E_star=math.inf),
     "E_star must be a number > 0 (Pa), got inf"),
    (lambda: AxisymmetricRunIn(rings=20, normal_force=0.0),
     "normal_force must be a number > 0 (N), got 0.0"),
    (lambda: AxisymmetricRunIn(rings=20, wear_coefficient=math.nan),
     "wear_coefficient must be a number > 0 (1/Pa), got nan"),
    (lambda: AxisymmetricRunIn(rings=20).state(-1.0),
     "distance must be a number >= 0 (m), got -1.0"),
    (lambda: reference_history([0.0, -1.0], rings=20),
     "distances_s_star must be an array of numbers each >= 0 (s*), got [0.0, -1.0]"),
    (lambda: reference_history([[0.0], [1.0, 2.0]], rings=20),
     "distances_s_star must be an array of numbers each >= 0 (s*), got [[0.0], [1.0, 2.0]]"),
])
def test_bad_input_is_named(build, fragment):
    with pytest.raises(ValueError) as err:
        build()
    assert fragment in str(err.value), f"{err.value!r} lacks {fragment!r}"
