"""Error bars of the rms slope are never NaN; where none can be estimated, no claim is made.

A phase of a single pixel vanishes when its map is resampled on every coarser
grid, which left the estimator's ladder one grid long and the run-in's error
bar NaN at every step but the first; the comparison with the steady face then
reported identical values as "OUTSIDE the error bars".  The estimator refines
the map instead (as the steady module refines a pixel map at its own size),
and a bar that cannot be estimated at all is infinite ("no error bar").
"""

import math

import h5py
import numpy as np
import pytest
from conftest import scene_text

import transient.__main__ as transient_cli
from steady.outline import Circle
from steady.problem import FacePhases, Problem
from steady.rms_slope import SlopeEnergy, estimate_map_rms_slope
from steady.wear import pressure_field
from transient.comparison import SteadyComparison
from transient.history import FaceEstimator
from transient.problem import WearProblem
from transient.solver import StageSolver

N = 32
K = (1e-13, 1e-12)


def single_pixel_labels(n=N):
    """A disk's grid of phase 0 with one pixel of phase 1 near the centre."""
    grid = Circle(4e-3).grid(n)
    labels = np.where(grid.mask, 0, -1)
    labels[n // 2, n // 2 - 3] = 1
    return grid, labels


def test_a_single_pixel_phase_gets_a_finite_error_from_the_refined_map():
    grid, labels = single_pixel_labels()
    estimate = estimate_map_rms_slope(labels, K, 10.0, grid.outline, 1.3e6)
    assert estimate.grids == (N, 2 * N), f"ladder {estimate.grids}: the map is refined"
    assert math.isfinite(estimate.error) and estimate.error > 0, f"error {estimate.error}"
    pressure, _, _ = pressure_field(labels, K, 10.0, grid.pixel_area)
    own = SlopeEnergy(grid.shape, grid.h, 1.3e6)(pressure, grid.mask).rms_slope
    assert estimate.rms_slope == pytest.approx(own, rel=1e-12), \
        f"value {estimate.rms_slope} is not the map's own grid's {own}"
    assert estimate.error == pytest.approx(2 * abs(estimate.values[1] - estimate.values[0]),
                                           rel=1e-12), "first-order error of the value on n"


def test_the_history_of_a_single_pixel_phase_has_no_nan_error_bar(tmp_path, capsys):
    _, labels = single_pixel_labels()
    np.save(tmp_path / "single.npy", labels)
    (tmp_path / "s.toml").write_text(scene_text("runin", map="file", path="single.npy"))
    status = transient_cli.main([str(tmp_path / "s.toml"), "-o", str(tmp_path / "run.h5")])
    out, err = capsys.readouterr()
    assert status == 0, f"exit {status}: {err!r}"
    with h5py.File(tmp_path / "run.h5") as f:
        errors = f["history/rms_slope_error"][()]
        compared = dict(f["comparison"].attrs)
    assert not np.isnan(errors).any(), \
        f"NaN error bars at {int(np.isnan(errors).sum())} of {errors.size} steps"
    assert np.all(errors[1:] > 0), f"error bars {errors}"
    assert compared["rms_slope_agrees"], f"the run and the steady face disagree: {compared}"
    line = next(ln for ln in out.splitlines() if ln.startswith("rms slope: "))
    assert "within the error bars" in line and "nan" not in line, line


def _comparison(run_bar, steady_bar, agrees):
    return SteadyComparison(
        face_error=1e-9, face_rms_error=1e-9, rms_slope=0.19, rms_slope_uncertainty=run_bar,
        steady_rms_slope=0.2, steady_rms_slope_uncertainty=steady_bar, rms_slope_error=-0.05,
        rms_slope_agrees=agrees, rms_slope_plain=0.18, steady_rms_slope_plain=0.18,
        rms_height=1e-4, steady_rms_height=1e-4, phase_pressures=np.array([1.0, 2.0]),
        steady_phase_pressures=np.array([1.0, 2.0]), phase_pressure_error=0.0)


@pytest.mark.parametrize("run_bar, steady_bar, missing", [
    (math.inf, 0.001, "the run's"),
    (0.001, math.nan, "the steady"),
    (math.nan, math.inf, "the run's and the steady"),
])
def test_a_comparison_without_error_bar_says_so(run_bar, steady_bar, missing):
    summary = _comparison(run_bar, steady_bar, True).summary()
    assert "OUTSIDE" not in summary and "within" not in summary, summary
    assert (f"no error bar: {missing} discretisation error could not be estimated, "
            f"not compared") in summary, summary
    assert not _comparison(run_bar, steady_bar, True).rms_slope_compared, "compared"
    assert "OUTSIDE the error bars" in _comparison(0.001, 0.001, False).summary(), \
        "finite bars that do not overlap are a disagreement"


def test_an_unestimated_map_error_is_infinite_not_nan():
    grid, labels = single_pixel_labels()
    problem = WearProblem(Problem(FacePhases(grid, labels, 2), K, 10.0, 1.3e6))
    estimator = FaceEstimator(problem, np.zeros(grid.shape))
    assert math.isfinite(estimator.map_error), f"map error {estimator.map_error}"
    estimator.map_error = math.inf
    res = StageSolver(problem).contact(np.zeros(grid.shape))
    for pressure in (res.pressure, np.zeros(grid.shape)):  # the latter: a zero slope
        fig = estimator.figures(1.0, np.zeros(grid.shape), pressure, res.approach)
        assert fig["rms_slope_error"] == math.inf, f"error bar {fig['rms_slope_error']}"
