"""The run-in across interfaces: wear coefficients at the current worn depth.

The run integrates the wear work ``R = int p^m ds`` and the worn depth is
``D(R)`` (transient.depth; docs/model.md, "Wear across interfaces").
Checked here: columns that repeat the face's map at every depth (or a
layer of the substrate's own phase) give the columnar run; a hard coating
on a soft substrate conserves the load, wears monotonically, wears through
at the rim first, with bounded Newton iterations and every pixel crossing
once; the error still follows the tolerance across the first crossings;
``end_depth`` ends a run on its depth, a tiny one within the depth the run
resolves; no step too short to move the run on is taken; an interrupted run
resumes bit for bit; bad columns and a bad end_depth are refused.
"""

import numpy as np
import pytest
from conftest import FORCE, K1, problem, wear_problem, with_columns

from steady.depth import DepthColumns
from steady.phases import Homogeneous
from steady.problem import FacePhases, Problem
from steady.wear import PowerLaw, ThresholdLaw
from transient.control import (
    CROSSING_CUT,
    CROSSING_MARGIN,
    DEPTH_SLACK,
    SOLVE_ERROR_SHARE,
    StepController,
    StopTests,
)
from transient.depth import WorkDepth
from transient.options import RunOptions
from transient.output import read_run, write_run
from transient.problem import WearProblem
from transient.result import HISTORY_UNITS
from transient.runin import run_in
from transient.solver import STAGE_SHARE_FACTOR


def repeated(wear, depths):
    """Columns that repeat ``wear``'s phase map below interfaces at ``depths`` (m)."""
    face = wear.face_mask
    interfaces = np.stack([np.where(face, d, np.inf) for d in depths])
    phases = np.stack([np.where(face, wear.labels, -1)] * (len(depths) + 1))
    return DepthColumns(interfaces, phases, wear.n_phases)


def coating(n, thickness, ratio=10.0, exponent=1.0, **options):
    """A flat disk with a hard coating (phase 1, ``k = K1``) over a soft substrate (phase 0).

    ``thickness`` is in units of ``f*``; the centre pixel is phase 0 at the
    surface too (every phase has a face pixel there), over phase 0.
    """
    base = problem(Homogeneous(), PowerLaw([K1]), n=n)
    face = base.face_mask
    labels = np.where(face, 1, -1)
    labels[n // 2, n // 2] = 0
    wear = PowerLaw([ratio * K1, K1], exponent=exponent)
    phases = Problem(FacePhases(base.grid, labels, 2), wear, base.normal_force, base.E_star)
    f_star = WearProblem(phases).depth_scale
    columns = DepthColumns(np.where(face, thickness * f_star, np.inf)[None],
                           np.stack([labels, np.where(face, 0, -1)]), 2)
    return WearProblem(with_columns(phases, columns), **options)


# -- the wear-work map ------------------------------------------------------------
def test_work_depth_is_the_inverse_of_the_work_of_a_depth():
    rng = np.random.default_rng(3917)
    interfaces = np.sort(rng.uniform(1e-7, 1e-5, (3, 5, 4)), axis=0)
    interfaces[2, 0, 0] = np.inf  # a pixel with two interfaces only
    phases = rng.integers(0, 3, (4, 5, 4))
    phases[3, 0, 0] = phases[2, 0, 0]
    columns = DepthColumns(interfaces, phases, 3)
    work = WorkDepth(columns, (1e-13, 4e-13, 2e-12))
    depth = rng.uniform(0.0, 2e-5, (5, 4))
    back = work.depth(work.work(depth))
    assert np.allclose(back, depth, rtol=1e-14, atol=0), \
        f"D(R(d)) - d up to {np.max(np.abs(back - depth)):.3g} m"
    # dD/dR is the coefficient of the phase at that depth.
    k = np.asarray((1e-13, 4e-13, 2e-12))[columns.phase_at(depth)]
    slope = work.slope(work.segment(work.work(depth)))
    assert np.allclose(slope, k, rtol=1e-15), "slope of D is not the local coefficient"


# -- the columnar limit ------------------------------------------------------------
@pytest.mark.parametrize("geometry, ratios, exponent, depths", [
    ("voronoi", (1.0, 10.0), 2.0, (0.05, 0.2, 0.6)),
    ("homogeneous", (1.0,), 1.0, (0.1,)),
])
def test_columns_that_repeat_the_map_give_the_columnar_run(geometry, ratios, exponent, depths):
    columnar = wear_problem(geometry, ratios, n=24, exponent=exponent)
    f_star = columnar.depth_scale
    layered = wear_problem(geometry, ratios, n=24, exponent=exponent,
                           columns=repeated(columnar, [d * f_star for d in depths]))
    assert layered.work_depth is not None, "the repeated columns have interfaces"
    options = RunOptions(tol=1e-4, distance_limit=0.3 * columnar.distance_scale)
    a = run_in(columnar, np.zeros(columnar.shape), options)
    b = run_in(layered, np.zeros(layered.shape), options)
    face = columnar.face_mask
    assert (a.steps, a.distance) == (b.steps, b.distance), \
        f"steps {a.steps} / {b.steps}, distance {a.distance} / {b.distance}"
    assert np.max(b.worn_depth[face]) > max(depths) * f_star, "no interface crossed"
    error = np.max(np.abs(a.worn_depth - b.worn_depth)[face]) / f_star
    # The power law solves every stage to contact_rtol (measured 4e-14 f*); Archard's
    # leaves a step's solves SOLVE_ERROR_SHARE x STAGE_SHARE_FACTOR tol f* in the largest
    # violation (measured 3.3e-8 f* over 10 steps).
    bound = 1e-12 if exponent != 1.0 else 10 * SOLVE_ERROR_SHARE * STAGE_SHARE_FACTOR * options.tol
    assert error < bound, f"worn depth differs by {error:.3g} f* (bound {bound:.3g})"
    pressure = np.max(np.abs(a.pressure - b.pressure)) / a.pressure.max()
    assert pressure < 100 * bound, f"pressure differs by {pressure:.3g} of its peak"


# -- a coating --------------------------------------------------------------------
@pytest.mark.parametrize("n, scheme, exponent, most", [
    (16, "esdirk3", 1.0, 4), (17, "bdf2", 1.0, 4),
    # Measured: 6 Newton iterations in a stage at most (about 15 s).
    pytest.param(16, "esdirk3", 2.0, 8, marks=pytest.mark.slow)])
def test_coating_wears_through_rim_first_with_bounded_newton(n, scheme, exponent, most):
    problem_ = coating(n, 0.3, exponent=exponent)
    face = problem_.face_mask
    h2 = problem_.halfspace.h ** 2
    points, stage_solves = [], []

    def on_step(run):
        points.append((run.s, float(run.pressure[face].sum()) * h2, run.worn_depth()[face],
                       run.crossings, run.segments.copy()))
        stage_solves.append(run.solver.most_stage_solves)

    options = RunOptions(tol=1e-4, scheme=scheme)
    result = run_in(problem_, np.zeros(problem_.shape), options, on_step=on_step)
    assert result.status == "steady", result.message
    assert result.failures == 0, f"{result.failures} failed attempts"
    load = max(abs(force / FORCE - 1.0) for _, force, *_ in points)
    assert load < 1e-13, f"load off by {load:.3g}"
    depths = np.array([d for _, _, d, *_ in points])
    assert np.all(np.isfinite(depths)), "non-finite worn depth"
    # Worn depth never decreases by more than the step tolerance (the schemes' stage
    # weights may be negative where a pixel leaves the contact; measured -6e-8 f*).
    rise = np.min(np.diff(depths, axis=0)) / problem_.depth_scale
    assert rise > -options.tol, f"worn depth fell by {-rise:.3g} f* in a step"
    # Every pixel crosses its one interface once, and the run is below all of them.
    crossings = sum(c for *_, c, _ in points)
    assert crossings == face.sum(), f"{crossings} crossings for {face.sum()} pixels"
    assert problem_.columns.columnar_below(result.worn_depth), "steady above an interface"
    # The steady state is the substrate's (homogeneous): the uniform pressure (measured 0).
    uniform = FORCE / (face.sum() * h2)
    steady = np.max(np.abs(result.pressure[face] / uniform - 1.0))
    assert steady < 1e-9, f"final pressure off the substrate's steady one by {steady:.3g}"
    assert np.allclose(problem_.steady_pressure()[face], uniform, rtol=1e-14), \
        "steady_pressure is not the substrate's"
    # Newton ends in a few iterations per stage, through the wear-through (measured: 3
    # for m = 1).
    assert max(stage_solves) <= most, f"{max(stage_solves)} Newton iterations in one stage"
    # The rim (the flat punch's pressure singularity) wears through first.
    s = np.array([p[0] for p in points])
    segments = np.array([p[4] for p in points])
    through = np.where(segments.any(axis=0), s[np.argmax(segments, axis=0)], np.inf)
    rim = face & ~np.pad(face, 1)[2:, 1:-1] | face & ~np.pad(face, 1)[:-2, 1:-1] \
        | face & ~np.pad(face, 1)[1:-1, 2:] | face & ~np.pad(face, 1)[1:-1, :-2]
    inner = face.copy()
    inner[n // 2, n // 2] = False  # soft at the surface
    inner &= np.hypot(*np.meshgrid(*(np.arange(m) - (m - 1) / 2 for m in face.shape),
                                   indexing="ij")) < n / 8
    assert through[rim].max() < through[inner].min(), \
        (f"rim through by {through[rim].max() / result.distance_scale:.3g} s*, centre from "
         f"{through[inner].min() / result.distance_scale:.3g} s*")


def test_recent_pressures_keep_their_true_displacements_across_interfaces():
    # The warm start of every stage is a combination of the run's recent pressures and of
    # their K p as the solver returned them.  Through the wear-through those weights are
    # large, and a solve started from the combination's own K x0 returned it with its
    # round-off, which the next combination amplified: measured on the coating of
    # coating_transient (n = 32), K x0 off by 49 % of it and stage pressures by 0.36 pbar,
    # which made the error estimate reject steps for nothing.  Started from its true
    # K x0, every solve stays exact: measured 1e-15 of K p here (3 % before).
    problem_ = coating(24, 0.3)
    face = problem_.face_mask
    worst = []

    def on_step(run):
        warm = run.solver.warm_start
        for p, kp in zip(warm.pressures(), warm.displacements(), strict=True):
            exact = problem_.halfspace.displacement(p)
            worst.append(np.max(np.abs(kp - exact)[face]) / np.max(np.abs(exact[face])))

    result = run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-5),
                    on_step=on_step)
    assert result.status == "steady", result.message
    assert max(worst) < 1e-12, f"stored K p off by {max(worst):.3g} of it"


def test_a_step_ends_just_past_the_last_crossing_in_it():
    controller = StepController(RunOptions(), 1.0)
    assert controller.before_crossing(1.0, -np.inf) == 1.0, "cut without a crossing"
    assert controller.before_crossing(1.0, 1.0) == 1.0, "cut with the crossing at its end"
    assert controller.before_crossing(1.0, 0.7) == 0.7 * (1 + CROSSING_MARGIN), \
        "not just past the crossing"
    assert controller.before_crossing(1.0, 0.99) == 1.0, "stretched past its length"
    assert controller.before_crossing(1.0, 0.1) == CROSSING_CUT, "cut below CROSSING_CUT"
    fixed = StepController(RunOptions(fixed_step=1e-3), 1.0)
    assert fixed.before_crossing(1.0, 0.7) == 1.0, "a fixed step was cut"


def test_the_last_crossing_is_where_the_rates_take_the_pixels():
    # On the coating every coated pixel's wear work runs at p (m = 1) towards the
    # coating's thickness over its k: it crosses in (R_1 - R) / p.  The centre pixel,
    # soft above and below, has no kink to cross.
    problem_ = coating(16, 0.3)
    face = problem_.face_mask
    k = problem_.work_depth.slopes[0]
    thickness = 0.3 * problem_.depth_scale
    coated = face & (problem_.columns.phases[0] == 1)
    seen = []

    def on_step(run):
        depth, p = run.worn_depth()[coated], run.pressure[coated]
        expected = np.sort((thickness - depth) / k[coated] / p)
        seen.append((expected, [run.last_crossing(d) for d in
                                (np.inf, expected[0] * (1 + 1e-9), expected[0] * (1 - 1e-9))]))

    run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-4, max_steps=1),
           on_step=on_step)
    expected, (every, first, none) = seen[0]
    assert every == pytest.approx(expected[-1], rel=1e-12), f"{every} m, not {expected[-1]} m"
    assert first == pytest.approx(expected[0], rel=1e-12), f"{first} m, not {expected[0]} m"
    assert none == -np.inf, f"a crossing at {none} m before the first"


@pytest.mark.slow
def test_error_follows_the_tolerance_across_the_first_crossings():
    # Up to s = 0.17 s* twenty rim pixels wear through (n = 16).  Measured slope of the
    # largest worn-depth error against tol (reference tol 1e-8): 0.70 across them, 0.69
    # before any (s = 0.1 s*): ESDIRK3's tolerance proportionality is kept.
    tols = np.array([1e-3, 1e-4, 1e-5, 1e-6, 1e-7])
    depths = []
    for tol in (*tols, 1e-8):
        problem_ = coating(16, 0.3)
        result = run_in(problem_, np.zeros(problem_.shape),
                        RunOptions(tol=tol, distance_limit=0.17 * problem_.distance_scale))
        face = problem_.face_mask
        depths.append(result.worn_depth[face] / problem_.depth_scale)
    crossed = int(problem_.columns.segment_at(np.where(face, result.worn_depth, 0.0)).sum())
    assert crossed >= 10, f"only {crossed} pixels crossed"
    errors = [np.max(np.abs(d - depths[-1])) for d in depths[:-1]]
    slope = np.polyfit(np.log(tols), np.log(errors), 1)[0]
    assert 0.55 < slope < 0.85, f"error ~ tol^{slope:.2f} across interfaces"


def test_a_ragged_multilayer_crosses_thousands_of_interfaces_without_failure():
    # Six interfaces of random depth below every pixel, phases alternating from the
    # Voronoi surface down (k ratio 10), n = 32: measured 3496 crossings in 136 steps,
    # 14 rejected, none failed, at most 3 Newton iterations in a stage (the columnar
    # run to the same distance takes 18 steps).
    columnar = wear_problem("voronoi", (1.0, 10.0), 32)
    f_star, face = columnar.depth_scale, columnar.face_mask
    rng = np.random.default_rng(8821)
    interfaces = np.cumsum(rng.uniform(0.05, 0.3, (6, 32, 32)), axis=0) * f_star
    phases = (columnar.labels[None] + np.arange(7)[:, None, None]) % 2
    columns = DepthColumns(np.where(face, interfaces, np.inf), np.where(face, phases, -1), 2)
    problem_ = wear_problem("voronoi", (1.0, 10.0), 32, columns=columns)
    end = 0.8 * float(np.median(interfaces[-1][face]))
    crossings, stage_solves = [], []

    def on_step(run):
        crossings.append(run.crossings)
        stage_solves.append(run.solver.most_stage_solves)

    result = run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-4, end_depth=end),
                    on_step=on_step)
    assert result.status == "depth" and result.failures == 0, \
        f"{result.status} with {result.failures} failures: {result.message}"
    # A pixel that crosses two interfaces in one step counts once.
    advanced = int(columns.segment_at(np.where(face, result.worn_depth, 0.0))[face].sum())
    assert 1000 < sum(crossings) <= advanced, f"{sum(crossings)} crossings, {advanced} made"
    assert max(stage_solves) <= 4, f"{max(stage_solves)} Newton iterations in one stage"


# -- ends and resumes ---------------------------------------------------------------
def test_end_depth_lands_on_the_mean_worn_depth():
    problem_ = coating(16, 0.3)
    end = 0.5 * problem_.depth_scale
    result = run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-4, end_depth=end))
    assert result.status == "depth", result.message
    mean = float(result.worn_depth[problem_.face_mask].mean())
    assert abs(mean / end - 1.0) < 10 * DEPTH_SLACK, f"mean worn depth {mean / end} end_depth"


def test_end_depth_ends_a_columnar_run_too():
    problem_ = wear_problem("voronoi", (1.0, 10.0), 24)
    end = 0.2 * problem_.depth_scale
    result = run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-4, end_depth=end))
    assert result.status == "depth", result.message
    mean = float(result.worn_depth[problem_.face_mask].mean())
    assert abs(mean / end - 1.0) < 10 * DEPTH_SLACK, f"mean worn depth {mean / end} end_depth"


@pytest.mark.parametrize("make", [lambda: coating(16, 0.3),
                                  lambda: wear_problem("voronoi", (1.0, 10.0), 24)],
                         ids=["coating", "columnar"])
@pytest.mark.parametrize("scheme", ["esdirk3", "bdf2"])
def test_a_tiny_end_depth_ends_within_the_depth_the_run_resolves(make, scheme):
    # 1e-12 f* (about 1e-15 m): the mean worn depth moves by a rounding unit of the
    # approach at every step, more than a landing step adds to it.
    problem_ = make()
    end = 1e-12 * problem_.depth_scale
    result = run_in(problem_, np.zeros(problem_.shape),
                    RunOptions(scheme=scheme, tol=1e-4, end_depth=end, max_steps=50))
    assert result.status == "depth" and result.steps <= 3, \
        f"{result.status} after {result.steps} steps: {result.message}"
    mean = float(result.worn_depth[problem_.face_mask].mean())
    # The run resolves 16 rounding units of the approach, about 2.5 f* here.
    assert abs(mean - end) <= 16 * np.spacing(2.5 * problem_.depth_scale), \
        f"mean worn depth {mean:.6g} m, end_depth {end:.6g} m"


def test_an_end_depth_the_run_cannot_resolve_is_refused():
    problem_ = wear_problem("voronoi", (1.0, 10.0), 24)
    end = 1e-17 * problem_.depth_scale
    with pytest.raises(ValueError, match=r"end_depth = \S+ m is below the mean worn depth this "
                                         r"run resolves, \S+ m .* give a larger end_depth"):
        run_in(problem_, np.zeros(problem_.shape), RunOptions(end_depth=end, max_steps=50))


@pytest.mark.parametrize("options, named", [
    (dict(first_step=1e-30), "first_step = 1e-30 m is below"),
    (dict(fixed_step=1e-30), "fixed_step = 1e-30 m is below"),
])
def test_a_first_step_too_short_to_move_the_run_on_is_refused(options, named):
    problem_ = wear_problem("voronoi", (1.0, 10.0), 24)
    with pytest.raises(ValueError, match=named + r" the shortest step that moves the run on"):
        run_in(problem_, np.zeros(problem_.shape), RunOptions(max_steps=50, **options))


def test_a_step_that_cannot_move_the_run_on_ends_it():
    options = RunOptions(end_depth=1e-9)
    stop = StopTests(options, 1.0)
    min_step = StepController.min_step(100.0, 1e-3)
    assert min_step == 16 * np.spacing(100.0), f"min_step {min_step} at s = 100 m"
    assert StepController.min_step(0.0, 1e-3) == 16 * np.spacing(1e-3), "min_step at s = 0"
    status, message = stop.short_step(0.0, min_step, 100.0, at_depth=100.0 + min_step / 2,
                                      depth=0.99e-9)
    assert status == "depth" and "as closely as the sliding distance resolves" in message, \
        message
    status, message = stop.short_step(min_step / 4, min_step, 100.0)
    assert status == "failed" and "does not fall with the step" in message, message


def test_an_interrupted_coating_run_resumes_bit_for_bit(tmp_path):
    options = RunOptions(tol=1e-4, checkpoint_interval=0.0)
    checkpoints = []
    full = run_in(coating(16, 0.3), np.zeros((16, 16)), options,
                  on_checkpoint=checkpoints.append)
    assert full.status == "steady", full.message
    # Mid-way through the wear-through, and the last regular step.
    for index in (len(checkpoints) // 3, len(checkpoints) // 2, len(checkpoints) - 2):
        path = tmp_path / f"checkpoint{index}.h5"
        write_run(path, checkpoints[index])
        saved, _, _ = read_run(path)
        resumed = run_in(coating(16, 0.3), None, options, resume=saved)
        assert (resumed.status, resumed.steps) == (full.status, full.steps), \
            f"resumed from {index}: {resumed.status} after {resumed.steps} steps"
        assert np.array_equal(full.recession, resumed.recession, equal_nan=True), \
            f"face differs after resuming from checkpoint {index}"
        assert np.array_equal(full.pressure, resumed.pressure), "pressure differs"
        for name in HISTORY_UNITS:
            assert np.array_equal(full.history[name], resumed.history[name], equal_nan=True), \
                f"history {name} differs after resuming from checkpoint {index}"


# -- refusals ------------------------------------------------------------------------
def test_bad_columns_are_refused_naming_the_fault():
    columnar = wear_problem("voronoi", (1.0, 10.0), 24)
    columns = repeated(columnar, [1e-6])
    with pytest.raises(ValueError, match=r"the columns \(24 x 24 pixels\) are not on the face "
                                         r"of the circle face \(radius 4 mm\) at n = 32"):
        fine = wear_problem("voronoi", (1.0, 10.0), 32).problem
        FacePhases(fine.grid, fine.labels, 2, columns=columns)
    phases = np.array(columns.phases)
    face = columnar.face_mask
    phases[0][face] = 1 - phases[0][face]
    flipped = DepthColumns(columns.interfaces, phases, 2)
    with pytest.raises(ValueError, match="labels are not the columns' section at the given "
                                         r"depth: pixel \(\d+, \d+\)"):
        FacePhases(columnar.problem.grid, columnar.labels, 2, columns=flipped)
    threshold = Problem(columnar.problem.phases, ThresholdLaw([K1, 10 * K1], [0.0, 0.0]),
                        FORCE, columnar.problem.E_star)
    with pytest.raises(ValueError, match=r"need a wear law k_i g\(p\).* not the threshold law"):
        WearProblem(with_columns(threshold, columns))


def test_end_depth_must_be_positive():
    with pytest.raises(ValueError, match=r"end_depth must be a number > 0 \(m\), got 0.0"):
        RunOptions(end_depth=0.0)
