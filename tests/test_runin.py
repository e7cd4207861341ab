"""The run-in against the closed-form steady state, hard cases, checkpoints and failures.

Convergence tests: run from the initial face until the wear rates equalise,
then compare with :func:`steady.solution.solve` (eq. 7, 9).  Required: face
shape (best constant removed) within 1e-3 of the steady relief, rms slope
within 0.5 %, per-phase pressures within 1e-3.  Measured at n = 32: face
6e-9 .. 3e-8 (the final jump's error, of order s*/ds = 1e-8), rms slope and
pressures to round-off; the bounds are the required ones.  The history's
last rms slope (the continuum estimate, :mod:`transient.history`) also
meets the steady module's corrected value on the twice finer grid within
the two error bars.
"""

import dataclasses
import math
import pathlib
import shutil

import numpy as np
import pytest
from conftest import CRITICAL_TILT, E_STAR, FORCE, GEOMETRIES, K1, RADIUS, RODS, wear_problem

from steady.outline import Circle
from steady.phases import Voronoi
from steady.rms_slope import estimate_rms_slope
from transient import initial_face
from transient.comparison import compare_with_steady
from transient.control import MAX_JUMPS
from transient.output import read_run, write_run
from transient.result import HISTORY_UNITS
from transient.runin import RunOptions, run_in
from transient.solver import StageSolver, StepFailure

FAST = RunOptions(tol=1e-3)
VORONOI = GEOMETRIES["voronoi"]


def run_and_compare(geometry, ratios, n, *, initial=None, exponent=1.0, options=FAST):
    problem = wear_problem(geometry, ratios, n, exponent=exponent)
    h0 = np.zeros((n, n)) if initial is None else initial(problem.grid)
    result = run_in(problem, h0, options)
    assert result.status == "steady", result.message
    return result, compare_with_steady(result, problem.solve_steady(), problem)


def assert_agrees(result, cmp, what):
    assert cmp.face_error < 1e-3, f"{what}: face error {cmp.face_error:.3g} of the relief"
    assert abs(cmp.rms_slope_error) < 5e-3, f"{what}: rms slope error {cmp.rms_slope_error:.3g}"
    assert cmp.phase_pressure_error < 1e-3, \
        f"{what}: phase pressure error {cmp.phase_pressure_error:.3g}"
    for name, values in result.history.items():
        assert np.all(np.isfinite(values[1:])), f"{what}: non-finite {name} history"


CASES = {
    "homogeneous": (GEOMETRIES["homogeneous"], (1.0,), None),
    "voronoi_0.3_k10": (VORONOI, (1.0, 10.0), None),
    "voronoi_0.3_k0.01": (VORONOI, (1.0, 1e-2), None),
    "rods": (RODS, (1.0, 1.7), None),
    "tilted": (VORONOI, (1.0, 10.0),
               lambda grid: initial_face.tilted(grid, 3 * CRITICAL_TILT)),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_run_in_reaches_the_steady_face(case):
    """Face, pressures and the history's last rms slope against the steady state.

    The last rms slope (n = 32) against the steady module's corrected value on
    n = 64: measured differences 0.11 % (rods) to 0.55 % (homogeneous) of the
    value, summed error bars 1.9 % to 4.2 %.
    """
    geometry, ratios, initial = CASES[case]
    n = 32
    result, cmp = run_and_compare(geometry, ratios, n, initial=initial)
    assert_agrees(result, cmp, case)
    if case == "tilted":
        cf = result.history["contact_fraction"]
        assert cf[0] < 0.8, f"tilted start should be in partial contact, got {cf[0]:.3f}"
        assert cf[-1] == 1.0, "steady state is in full contact"
    steady = estimate_rms_slope(geometry, [K1 * r for r in ratios], FORCE, RADIUS, E_STAR, 2 * n)
    end, bar = result.history["rms_slope"][-1], result.history["rms_slope_error"][-1]
    assert abs(end - steady.rms_slope) <= bar + steady.error, \
        f"{case}: run ends at {end:.5f} +- {bar:.5f}, steady (n = {2 * n}) " \
        f"{steady.rms_slope:.5f} +- {steady.error:.5f}"
    assert cmp.rms_slope_agrees, cmp.summary()
    # The history ends where the dynamics end, the wear-rate spread below jump_spread
    # (1e-3): measured 0.3e-4 .. 1.4e-4 from the steady face's rms height.
    assert result.history["rms_height"][-1] == pytest.approx(
        cmp.steady_rms_height, rel=RunOptions().jump_spread), \
        f"{case}: the history's last rms height is not near the steady face's"
    assert cmp.rms_height == pytest.approx(cmp.steady_rms_height, rel=1e-6), \
        f"{case}: the final face's rms height is not the steady face's"


def test_homogeneous_run_in_history_is_physical():
    result, cmp = run_and_compare("homogeneous", (1.0,), 33)
    h = result.history
    # The flat punch's edge singularity at s = 0: the rim pixels carry the
    # largest pressure, which the run-in removes.
    assert h["peak_pressure"][0] > 3 * result.pixel_mean_pressure, "no edge concentration at s = 0"
    assert result.pressure.max() == pytest.approx(result.pixel_mean_pressure, rel=1e-6), \
        "steady pressure of a homogeneous punch is uniform"
    # The history ends where the dynamics end, the spread below jump_spread (measured 2e-4).
    assert h["peak_pressure"][-1] == pytest.approx(result.pixel_mean_pressure,
                                                   rel=RunOptions().jump_spread), \
        "pressure at the end of the dynamics is not near uniform"
    # The first steps are on the fast (pixel) scale; the jump to the steady state is
    # taken (an accepted step) but not recorded: no step of the history is huge.
    assert h["step"][1] < 10 * result.fast_distance, "first step too large for the edge layer"
    assert result.steps > len(h["distance"]) - 1, "no jump to the steady state"
    assert h["step"][1:].max() < 10 * result.distance_scale, "a jump is in the history"
    assert result.distance == h["distance"][-1], "the run does not end at its last history point"
    assert np.all(np.diff(h["worn_volume"]) > 0), "worn volume must grow"
    # Volume balance: d(volume)/ds = sum k p h^2 = k F for a homogeneous punch.
    assert h["worn_volume"][-1] == pytest.approx(K1 * FORCE * result.distance, rel=1e-9), \
        "worn volume breaks the balance k F s"
    assert h["normalised_rms_slope"][0] < h["normalised_rms_slope"][-1], \
        "rms slope should grow during run-in"
    assert_agrees(result, cmp, "homogeneous n=33")


@pytest.mark.parametrize("exponent", [0.5, 2.0])
def test_power_law_wear_reaches_its_steady_face(exponent):
    result, cmp = run_and_compare(VORONOI, (1.0, 10.0), 32,
                                  exponent=exponent)
    assert_agrees(result, cmp, f"m={exponent}")


HARD = {
    "k1e3_fill0.05": ((0.95, 0.05), 1e3),
    "k1e-3_fill0.95": ((0.05, 0.95), 1e-3),
    "k1e-3_fill0.05": ((0.95, 0.05), 1e-3),
    "k1e3_fill0.95": ((0.05, 0.95), 1e3),
}


@pytest.mark.parametrize("case", sorted(HARD))
def test_hard_wear_ratios_and_fill_factors(case):
    fill, ratio = HARD[case]
    result, cmp = run_and_compare(Voronoi(64, fill, 2029), (1.0, ratio), 32)
    assert_agrees(result, cmp, case)


@pytest.mark.parametrize("ratio", [1e-6, 1e6])
def test_extreme_wear_ratios(ratio):
    result, cmp = run_and_compare(VORONOI, (1.0, ratio), 32)
    assert_agrees(result, cmp, f"ratio {ratio:g}")


def test_direct_jump_reaches_steady_state_in_few_solves():
    # jump_spread = inf: implicit Euler with ds = 1e8 s* from the flat face.
    options = RunOptions(jump_spread=math.inf)
    result, cmp = run_and_compare(VORONOI, (1.0, 1e3), 48,
                                  options=options)
    assert result.solves <= 3, f"{result.solves} contact solves"
    assert cmp.face_error < 1e-6, f"face error {cmp.face_error:.3g}"


@pytest.mark.parametrize("n", [32, 65])
def test_odd_and_even_grids(n):
    result, cmp = run_and_compare(RODS, (1.0, 1.7), n)
    assert_agrees(result, cmp, f"n={n}")


@pytest.mark.slow
@pytest.mark.parametrize("n", [256, 1024])
def test_fine_grids_jump_to_steady(n):
    # Fine grids are the stiff case (fastest relaxation h / (k_max E*)); the
    # implicit jump does not care.
    options = RunOptions(jump_spread=math.inf)
    result, cmp = run_and_compare(GEOMETRIES["voronoi_fine"], (1.0, 1e3), n,
                                  options=options)
    assert_agrees(result, cmp, f"n={n}")


@pytest.mark.slow
def test_full_run_in_at_n_128():
    result, cmp = run_and_compare(Voronoi(100, (0.7, 0.3), 2029), (1.0, 10.0), 128)
    assert_agrees(result, cmp, "n=128")


# -- checkpoints, resume, failures ------------------------------------------------

def _same_result(a, b, converted=()):
    """Bitwise the same run; ``converted`` histories to rounding (multiplied on reading)."""
    assert a.status == b.status and a.steps == b.steps, (a.status, a.steps, b.status, b.steps)
    assert np.array_equal(a.recession, b.recession, equal_nan=True), "face differs"
    assert np.array_equal(a.pressure, b.pressure), "pressure differs"
    assert a.offset == b.offset and a.distance == b.distance, "offset or distance differs"
    for name in HISTORY_UNITS:
        if name in converted:
            assert np.allclose(a.history[name], b.history[name], rtol=4e-16, atol=0), \
                f"history {name} differs beyond rounding"
        else:
            assert np.array_equal(a.history[name], b.history[name]), f"history {name} differs"


def test_resume_from_any_checkpoint_is_bitwise_identical(tmp_path):
    problem = wear_problem(VORONOI, (1.0, 10.0), 32)
    options = RunOptions(tol=1e-3, checkpoint_interval=0.0, snapshots_s_star=(0.01, 0.5))
    checkpoints = []
    full = run_in(problem, np.zeros((32, 32)), options, on_checkpoint=checkpoints.append)
    assert full.status == "steady", full.message
    assert len(checkpoints) == full.steps, "checkpoint_interval = 0 checkpoints every step"
    for index in (0, len(checkpoints) // 2, len(checkpoints) - 2):
        path = tmp_path / f"ckpt{index}.h5"
        write_run(path, checkpoints[index])
        saved, _, _ = read_run(path)
        fresh = wear_problem(VORONOI, (1.0, 10.0), 32)
        resumed = run_in(fresh, None, options, resume=saved)
        _same_result(full, resumed)
        assert np.array_equal(full.snapshot_recession, resumed.snapshot_recession,
                              equal_nan=True), \
            f"snapshots differ after resuming from checkpoint {index}"


def test_stagnating_jumps_stop_at_the_same_point_after_a_resume(tmp_path):
    # Jumps of 0.01 s* (implicit Euler steps far too short to reach the
    # steady state, which the spread approaches over several s*) leave the
    # spread far above spread_tol: the run stops as stagnating after
    # MAX_JUMPS of them.  Resumed from a checkpoint written between its
    # jumps, it must stop where the uninterrupted run does: the jump count
    # is part of the state a checkpoint carries.
    options = RunOptions(tol=1e-3, jump_spread=math.inf, jump_step_s_star=0.01,
                         checkpoint_interval=0.0)
    problem = wear_problem(RODS, (1.0, 1.7), 32)
    checkpoints = []
    full = run_in(problem, np.zeros((32, 32)), options, on_checkpoint=checkpoints.append)
    assert full.status == "stopped" and "stagnates" in full.message, \
        f"expected a stop for stagnating jumps, got {full.status}: {full.message}"
    assert full.steps == MAX_JUMPS, f"{full.steps} jumps taken, expected {MAX_JUMPS}"
    path = tmp_path / "between_jumps.h5"
    write_run(path, checkpoints[1])  # after two jumps
    saved, _, _ = read_run(path)
    resumed = run_in(wear_problem(RODS, (1.0, 1.7), 32), None, options, resume=saved)
    assert resumed.message == full.message, \
        f"resumed run ended '{resumed.message}', uninterrupted '{full.message}'"
    _same_result(full, resumed)
    # Continued as it is, the stagnated run takes no further jump.
    again = run_in(wear_problem(RODS, (1.0, 1.7), 32), None, options, resume=full)
    assert again.message == full.message, f"continued stagnated run ended '{again.message}'"
    _same_result(full, again)


def test_run_file_without_jump_count_reads_as_none_taken(tmp_path):
    # Run files written before the jump count was stored lack the attribute;
    # they were written by runs that had not stopped as stagnating, and are
    # continued as if no jump had been taken.
    import h5py

    stopped = run_in(wear_problem(RODS, (1.0, 1.7), 32), np.zeros((32, 32)),
                     RunOptions(tol=1e-3, max_steps=3))
    path = tmp_path / "old.h5"
    write_run(path, stopped)
    with h5py.File(path, "a") as f:
        del f["jumps"]
        del f.attrs["sha256"]  # an unverified older file
    back, _, _ = read_run(path)
    assert back.state.jumps == 0, f"jump count {back.state.jumps} read from a file without one"
    _same_result(stopped, back)


def test_run_file_round_trip(tmp_path):
    result, cmp = run_and_compare(RODS, (1.0, 1.7), 32,
                                  options=RunOptions(tol=1e-3, snapshots_s_star=(0.0, 0.1, 1.0)))
    path = tmp_path / "run.h5"
    write_run(path, result, arrays={"phase": RODS.labels(Circle(RADIUS).grid(32))},
              comparison=cmp)
    back, attrs, arrays = read_run(path)
    _same_result(result, back)
    assert attrs["format"] == "runin.transient" and attrs["format_version"] == 5, \
        f"layout {attrs['format']!r} version {attrs['format_version']!r}, expected " \
        "'runin.transient' version 5"
    assert back.snapshot_distance.tolist() == pytest.approx(
        [0.0, 0.1 * result.distance_scale, result.distance_scale], rel=1e-12), \
        "snapshots not at the requested distances"
    assert back.snapshot_recession.shape == (3, 32, 32), \
        "expected back.snapshot_recession.shape == (3, 32, 32)"
    assert "phase" in arrays, "expected 'phase' in arrays"
    import h5py

    with h5py.File(path) as f:
        assert f["worn_depth"].attrs["units"] == "m", \
            "expected f['worn_depth'].attrs['units'] == 'm'"
        assert f["pressure"].attrs["units"] == "Pa", \
            "expected f['pressure'].attrs['units'] == 'Pa'"
        assert f["history/distance"].attrs["units"] == "m", \
            "expected f['history/distance'].attrs['units'] == 'm'"
        assert f["comparison/face_error"][()] == cmp.face_error, \
            "expected f['comparison/face_error'][()] == cmp.face_error"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5"], \
        f"temporary file left behind: {sorted(p.name for p in tmp_path.iterdir())}"


def test_read_run_rejects_other_files(tmp_path):
    import h5py

    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "something else"
    with pytest.raises(ValueError, match="not a run file"):
        read_run(path)


def test_failed_steps_are_retried_smaller(monkeypatch):
    problem = wear_problem(RODS, (1.0, 1.7), 32)
    real = StageSolver.contact
    calls = {"n": 0}

    def flaky(solver, height, **kw):
        calls["n"] += 1
        if calls["n"] in (5, 6, 7):
            raise StepFailure("injected failure")
        return real(solver, height, **kw)

    monkeypatch.setattr(StageSolver, "contact", flaky)
    result = run_in(problem, np.zeros((32, 32)), FAST)
    assert result.status == "steady", result.message
    assert result.failures == 3, f"{result.failures} failures recorded"


def test_persistent_failure_stops_with_a_resumable_state(monkeypatch):
    problem = wear_problem(RODS, (1.0, 1.7), 32)
    real = StageSolver.contact
    calls = {"n": 0}

    def broken(solver, height, **kw):
        calls["n"] += 1
        if calls["n"] > 10:
            raise StepFailure("solver gave up")
        return real(solver, height, **kw)

    monkeypatch.setattr(StageSolver, "contact", broken)
    result = run_in(problem, np.zeros((32, 32)), dataclasses.replace(FAST, max_failures=4))
    assert result.status == "failed", "a persistent failure must stop the run"
    assert "failed 4 times" in result.message and "solver gave up" in result.message, \
        "expected 'failed 4 times' in result.message and 'solver gave up' in result.message"
    assert np.all(np.isfinite(result.pressure)), "failed run returned non-finite pressure"
    monkeypatch.setattr(StageSolver, "contact", real)
    resumed = run_in(problem, None, FAST, resume=result)
    assert resumed.status == "steady", resumed.message


def test_stopped_run_resumes_to_steady():
    problem = wear_problem(RODS, (1.0, 1.7), 32)
    stopped = run_in(problem, np.zeros((32, 32)), dataclasses.replace(FAST, max_steps=5))
    assert stopped.status == "stopped" and "max_steps" in stopped.message, \
        "expected stopped.status == 'stopped' and 'max_steps' in stopped.message"
    done = run_in(problem, None, FAST, resume=stopped)
    assert done.status == "steady", done.message
    straight = run_in(wear_problem(RODS, (1.0, 1.7), 32), np.zeros((32, 32)), FAST)
    _same_result(straight, done)


@pytest.mark.parametrize("field,value,match", [
    ("tol", 0.0, r"tol must be a number in \(2.22045e-16, 1\] \(f\*\), got 0.0"),
    ("spread_tol", -1.0, r"spread_tol must be a number > 0 \(1\), got -1.0"),
    ("max_steps", 0, r"max_steps must be an integer >= 1, got 0"),
    ("snapshot_distances", (-1.0,),
     r"snapshot_distances must be an array of numbers each >= 0 \(m\)"),
    ("snapshots_s_star", (-1.0,),
     r"snapshots_s_star must be an array of numbers each >= 0 \(s\*\)"),
    ("fixed_step", math.inf, r"fixed_step must be a number > 0 \(m\), got inf"),
    ("distance_limit", -1.0, r"distance_limit must be a number > 0 \(m\), got -1.0"),
])
def test_bad_options_are_named(field, value, match):
    with pytest.raises(ValueError, match=match):
        RunOptions(**{field: value})


# -- files of the earlier layout ----------------------------------------------------------
LAYOUT3 = pathlib.Path(__file__).parent / "data"


def test_a_layout_3_run_file_reads_and_resumes_to_the_uninterrupted_run(tmp_path, capsys,
                                                                        monkeypatch):
    # tests/data/run_layout3.h5: the scene tests/data/run_layout3.toml stopped after five
    # steps by the code of layout 3, whose face's recession is the dataset "height".
    import h5py

    import transient.solver
    from transient.cli import runin as cli

    # That code's stage solves stopped on the rms violation at the share itself: both runs
    # take its rule, so that the uninterrupted one repeats the stored steps.
    monkeypatch.setattr(transient.solver, "STAGE_NORM", "rms")
    monkeypatch.setattr(transient.solver, "STAGE_SHARE_FACTOR", 1.0)

    scene = tmp_path / "scene.toml"
    shutil.copy(LAYOUT3 / "run_layout3.toml", scene)
    old = tmp_path / "run.h5"
    shutil.copy(LAYOUT3 / "run_layout3.h5", old)
    with h5py.File(old) as f:
        assert f.attrs["format_version"] == 3 and "height" in f["state"], "a layout-3 file"
        stored_height = f["state/height"][()]
    back, _, _ = read_run(old)
    assert back.steps == 5 and np.array_equal(back.recession, stored_height, equal_nan=True), \
        "the recession read from the dataset height"
    assert cli.main([str(scene), "-o", str(old), "--resume"]) == 0, capsys.readouterr().err
    straight = tmp_path / "straight.h5"
    assert cli.main([str(scene), "-o", str(straight)]) == 0, capsys.readouterr().err
    resumed, _, _ = read_run(old)
    uninterrupted, attrs, _ = read_run(straight)
    # The old file's deviations were relative to the steady relief: converted on resuming.
    _same_result(uninterrupted, resumed,
                 converted=("face_deviation", "face_deviation_step_error"))
    with h5py.File(old) as f:
        assert f.attrs["format_version"] == 5 and "recession" in f["state"], \
            "a resumed file is written in the new layout"
