"""The contact tolerance of a run's regular steps (transient.control.contact_tolerance).

The solves of a regular step stop at a residual the step's error control
and the wear-rate spread leave them.  Checked here: the two bounds behind
it (a residual ``r`` moves a stage's face by at most ``r`` and its pressure
by at most ``r / lambda``), and that a run with it keeps the history of a
run that solves everything to ``contact_rtol``.  Measured on the Voronoi
map at n = 64, ``k_2/k_1 = 10``, ``tol = 1e-4``: the same 29 steps and 86
solves, 153 solver iterations against 453, snapshot faces within 1.1e-6
``f*`` of each other (the bound, solves x share x ``STAGE_SHARE_FACTOR`` x
tol, is 2.6e-4), the history's rms slope within 5.8e-6 (relative), the
final faces equal.  Then the stopping rule in the largest violation over
the face: it bounds the corner pixels of a rectangle that the rms leaves,
and so keeps the steps of a rectangle's run-in at the loose share.
"""

import math

import numpy as np
import pytest
from conftest import K1, wear_problem
from conftest import problem as face_problem

import transient.control as control
import transient.solver as solver
from steady.outline import Rectangle
from steady.phases import Homogeneous
from transient.contact import solve_contact
from transient.control import SOLVE_ERROR_SHARE, SOLVE_SPREAD_SHARE, contact_tolerance
from transient.diagnostics import shape_rms, wear_rate_spread
from transient.problem import WearProblem
from transient.runin import RunOptions, run_in


def test_tolerance_is_the_smaller_share():
    tol, f_star, lam, pbar = 1e-4, 2e-3, 3e-10, 2e5
    step_share = SOLVE_ERROR_SHARE * tol * f_star
    assert contact_tolerance(tol, f_star, 1.0, lam, pbar) == pytest.approx(
        min(step_share, SOLVE_SPREAD_SHARE * lam * pbar), rel=1e-15)
    # Near the steady state the spread's share takes over and tightens with it.
    small = contact_tolerance(tol, f_star, 1e-7, lam, pbar)
    assert small == pytest.approx(SOLVE_SPREAD_SHARE * 1e-7 * lam * pbar, rel=1e-15)
    assert small < step_share
    assert contact_tolerance(tol, f_star, 0.0, lam, pbar) == 0.0
    # A spread that could not be measured counts as 1 (pixels out of contact).
    assert contact_tolerance(tol, f_star, math.nan, lam, pbar) == contact_tolerance(
        tol, f_star, 1.0, lam, pbar)


@pytest.mark.parametrize("c_over_s_star", [1e-3, 0.3])
def test_a_residual_moves_face_and_pressure_within_the_bounds(c_over_s_star):
    n = 64
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    hs, face = problem.halfspace, problem.face_mask
    rng = np.random.default_rng(7)
    height = np.where(face, 0.05 * problem.depth_scale * rng.standard_normal((n, n)), 0.0)
    c = c_over_s_star * problem.distance_scale
    shift = c * problem.wear_field
    lam = problem.compliance_floor
    # A loose tolerance, about what a regular step leaves its solves.
    atol = 1e-7 * problem.depth_scale
    tight = solve_contact(hs, face, height, problem.normal_force, shift=shift, rtol=1e-13)
    loose = solve_contact(hs, face, height, problem.normal_force, shift=shift, rtol=1e-13,
                          atol=atol, x0=np.where(face, problem.pixel_mean_pressure, 0.0))
    assert tight.success and loose.success
    assert loose.nit < tight.nit
    assert loose.residual <= atol
    dp = loose.pressure - tight.pressure
    rms_dp = float(np.sqrt(np.mean(dp[face] ** 2)))
    assert rms_dp <= loose.residual / lam, \
        f"pressure moved {rms_dp:.3g} Pa, bound {loose.residual / lam:.3g} Pa"
    # The stage's increment c k p (the face's change), without its mean.
    d_increment = shape_rms(np.where(face, shift * dp, 0.0), face)
    assert d_increment <= loose.residual, \
        f"increment moved {d_increment:.3g} m, residual {loose.residual:.3g} m"


def test_run_keeps_the_history_of_tight_solves(monkeypatch):
    n = 64
    options = RunOptions(tol=1e-4, snapshots_s_star=(0.01, 0.1, 1.0))

    def run():
        problem = wear_problem("voronoi", (1.0, 10.0), n)
        return problem, run_in(problem, np.zeros((n, n)), options)

    problem, loose = run()
    monkeypatch.setattr(control, "SOLVE_ERROR_SHARE", 0.0)
    monkeypatch.setattr(control, "SOLVE_SPREAD_SHARE", 0.0)
    _, tight = run()
    assert loose.status == tight.status == "steady", (loose.message, tight.message)
    assert loose.iterations < 0.6 * tight.iterations, (loose.iterations, tight.iterations)
    face, f_star = problem.face_mask, loose.depth_scale
    # A stage solve leaves at most its absolute tolerance, in the largest violation, on the face.
    bound = loose.solves * SOLVE_ERROR_SHARE * solver.STAGE_SHARE_FACTOR * options.tol
    assert np.array_equal(loose.snapshot_distance, tight.snapshot_distance)
    for a, b, s in zip(loose.snapshot_recession, tight.snapshot_recession, loose.snapshot_distance,
                       strict=True):
        diff = shape_rms(np.where(face, a - b, 0.0), face) / f_star
        assert diff < bound, f"faces at {s / loose.distance_scale:g} s* differ by {diff:.3g} f*"
    final = shape_rms(np.where(face, loose.recession - tight.recession, 0.0), face) / f_star
    assert final < 1e-9, f"final faces differ by {final:.3g} f*"
    # The history ends with the dynamics; the final state (after the jump) is steady.
    assert wear_rate_spread(problem.rate, loose.pressure, problem.face_mask) < \
        options.spread_tol
    if loose.steps == tight.steps:
        a, b = loose.history["rms_slope"][1:], tight.history["rms_slope"][1:]
        assert np.max(np.abs(a / b - 1)) < 3e-5


def violation(halfspace, face, res):
    """Violation (m) of the contact conditions at every face pixel, from the pressure alone."""
    gap = halfspace.displacement(res.pressure) + res.displacement - res.elastic_displacement \
        - res.approach
    return np.where(face, np.where(res.pressure > 0, np.abs(gap), np.maximum(-gap, 0.0)), 0.0)


def test_max_rule_bounds_the_corner_pixel_that_the_rms_rule_leaves():
    """A rectangle's implicit stage from the flat punch's pressure, to an absolute tolerance.

    Measured (1:2 rectangle, 96 x 192 pixels, ``c = 1e-3 s*``, ``atol = 1e-4`` of the rms
    displacement): the rms rule stops after 2 iterations with a violation of 6.8 ``atol``
    at the corner pixels (the rms over the face 0.62 ``atol``: a corner pixel is 1/18432 of
    the face); the max rule after 3 with at most 0.31 ``atol`` on any pixel.
    """
    problem = WearProblem(face_problem(Homogeneous(), [K1], n=192, outline=Rectangle(4e-3, 8e-3)))
    hs, face, force = problem.halfspace, problem.face_mask, problem.normal_force
    flat = solve_contact(hs, face, np.zeros(face.shape), force, rtol=1e-12)
    shift = 1e-3 * problem.distance_scale * problem.wear_field
    atol = 1e-4 * float(np.sqrt(np.mean(flat.displacement[face] ** 2)))
    runs = {norm: solve_contact(hs, face, np.zeros(face.shape), force, shift=shift,
                                x0=flat.pressure, rtol=1e-14, atol=atol, norm=norm)
            for norm in ("rms", "max")}
    assert all(res.success for res in runs.values())
    corners = [(0, 0), (0, -1), (-1, 0), (-1, -1)]
    peak = violation(hs, face, runs["max"])
    assert runs["max"].residual <= atol and peak.max() <= atol, \
        f"max rule: largest violation {peak.max() / atol:.3g} atol"
    loose = violation(hs, face, runs["rms"])
    worst_corner = max(loose[c] for c in corners)
    assert runs["rms"].residual <= atol and worst_corner > 3 * atol, \
        f"rms rule: corner violation only {worst_corner / atol:.3g} atol"
    rms = float(np.sqrt(np.mean(loose[face] ** 2)))
    assert rms <= atol, f"rms rule: rms violation {rms / atol:.3g} atol"


@pytest.mark.parametrize("factor", [10.0, solver.STAGE_SHARE_FACTOR])
def test_rectangle_from_flat_keeps_its_steps_under_a_loose_share(monkeypatch, factor):
    """The homogeneous 1:2 rectangle from flat, 96 x 192 pixels, ``tol = 1e-4``.

    The stage solves take ``factor`` times the share of
    :func:`transient.control.contact_tolerance`, in the norm ``STAGE_NORM``.
    Measured in the largest violation: 26 steps, none rejected, 77 solves;
    154 iterations at the factor 10, 127 at 30 (the rms rule at the factor
    1: 26 steps, 157 iterations).  In the rms over the face the factor 10
    leaves the corners' singular pixels unsolved: 56 steps, 13 rejected,
    1243 iterations.
    """
    monkeypatch.setattr(solver, "STAGE_SHARE_FACTOR", factor)
    problem = WearProblem(face_problem(Homogeneous(), [K1], n=192, outline=Rectangle(4e-3, 8e-3)))
    result = run_in(problem, np.zeros(problem.shape),
                    RunOptions(tol=1e-4, snapshots_s_star=(0.01, 0.1, 1.0)))
    assert result.status == "steady", result.message
    assert result.rejected == 0 and result.steps <= 27 and result.iterations < 170, \
        (f"{result.steps} steps, {result.rejected} rejected, {result.solves} solves, "
         f"{result.iterations} iterations")
