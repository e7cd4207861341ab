"""Shift-aware Fourier preconditioner and the Galerkin warm start of implicit stages.

The implicit stages of the run-in solve ``(K + ds diag(k)) p = d - w`` with a
shift that differs from phase to phase.  The stitched Fourier preconditioner
(:class:`transient.preconditioners.FourierPreconditioner`) is checked against
dense spectra of the preconditioned operator, and the warm start
(:class:`transient.warm_start.WarmStart`) against the linearity of the
full-contact problem.
"""

import numpy as np
import pytest
import scipy.linalg
from conftest import FORCE, GEOMETRIES, halfspace, wear_problem

from transient.contact import solve_contact
from transient.preconditioners import (
    FourierPreconditioner,
    JacobiPreconditioner,
    ScaledShift,
    make_preconditioner,
    shift_levels,
)
from transient.runin import RunOptions, run_in
from transient.warm_start import WarmStart


def two_phase_shift(labels, hs, magnitude, ratio=0.1):
    """Shift of a stage: ``magnitude K_00`` on phase 1, ``ratio`` times that on phase 0."""
    face = labels >= 0
    return np.where(face, hs.self_influence * magnitude * np.where(labels == 1, 1.0, ratio), 0.0)


def dense(operator, face):
    """Matrix of a linear map of (n, n) fields, restricted to the face pixels."""
    n = face.shape[0]
    idx = np.flatnonzero(face)
    out = np.empty((idx.size, idx.size))
    for j, i in enumerate(idx):
        e = np.zeros(n * n)
        e[i] = 1.0
        out[:, j] = operator(e.reshape(n, n)).ravel()[idx]
    return out


def preconditioned_condition(matrix, precondition, face):
    """Condition number of ``P A`` on the zero-mean subspace (the load constraint).

    ``precondition``: a preconditioner, or its dense matrix on the face.
    """
    basis = scipy.linalg.null_space(np.ones((1, int(face.sum()))))
    p = precondition
    if callable(precondition):
        p = dense(lambda r: precondition(r, face), face)
    factor = np.linalg.cholesky(basis.T @ (0.5 * (p + p.T)) @ basis)
    ev = np.linalg.eigvalsh(factor.T @ (basis.T @ matrix @ basis) @ factor)
    return ev[-1] / ev[0]


# -- the levels of a shift -------------------------------------------------------

def test_phase_wise_shift_gives_one_level_per_phase():
    n = 32
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    face = labels >= 0
    shift = two_phase_shift(labels, hs, 3.0)
    levels, weights = shift_levels(shift, face, hs.self_influence)
    assert levels == sorted({float(v) for v in shift[face]}), f"levels {levels}"
    for level, phi in zip(levels, weights, strict=True):
        assert np.array_equal(phi[face] == 1.0, shift[face] == level), \
            "a phase-wise shift must be split by indicators"
    assert np.array_equal(sum(weights)[face], np.ones(face.sum())), "weights must sum to one"


def test_phase_wise_shift_without_face_mask_counts_every_pixel():
    # face_mask=None means "all pixels": the same levels as an all-true mask.
    n = 32
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    shift = two_phase_shift(labels, hs, 3.0)
    levels, weights = shift_levels(shift, None, hs.self_influence)
    expected, expected_weights = shift_levels(shift, np.ones((n, n), bool), hs.self_influence)
    assert levels == expected == sorted({float(v) for v in shift.ravel()}), f"levels {levels}"
    for phi, expected_phi in zip(weights, expected_weights, strict=True):
        assert np.array_equal(phi, expected_phi), "weights must not depend on the default mask"
    r = np.random.default_rng(3).standard_normal((n, n))
    face = np.ones((n, n), bool)
    assert np.array_equal(FourierPreconditioner(hs, shift)(r, face),
                          FourierPreconditioner(hs, shift, face_mask=face)(r, face))


@pytest.mark.parametrize("pattern_kind", ["two phases", "one phase", "many values"])
def test_scaled_shift_builds_what_auto_builds(pattern_kind):
    """``ScaledShift(k).preconditioner(c, c k)`` is ``"auto"``'s for ``c k``, bit for bit.

    The factors span every choice: one level (a spread below 1 % of the
    symbol's floor), the phase levels, and Jacobi (a shift ten times the
    largest eigenvalue of ``K``).
    """
    n = 32
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    face = labels >= 0
    rng = np.random.default_rng(17)
    pattern = {"two phases": np.where(labels == 1, 1.0, 0.01),
               "one phase": np.ones((n, n)),
               "many values": 10 ** rng.uniform(-2.0, 0.0, (n, n))}[pattern_kind]
    pattern = np.where(face, pattern, 0.0)
    floor = float(hs.aliased_symbol.min())
    top = float(hs.influence_symbol.max())
    r = np.where(face, rng.standard_normal((n, n)), 0.0)
    scaled = ScaledShift(hs, face, pattern)
    kinds = set()
    for c in (1e-4 * floor, floor, 30 * top, 1e4 * top):
        shift = c * pattern
        ours, auto = scaled.preconditioner(c, shift), make_preconditioner("auto", hs, face, shift)
        assert type(ours) is type(auto), f"c = {c:.3g}: {type(ours)} against {type(auto)}"
        assert getattr(ours, "levels", None) == getattr(auto, "levels", None), f"c = {c:.3g}"
        assert np.array_equal(ours(r, face), auto(r, face)), f"c = {c:.3g}: results differ"
        kinds.add((type(ours).__name__, len(getattr(ours, "levels", []))))
    expected = {"two phases": {("FourierPreconditioner", 1), ("FourierPreconditioner", 2),
                               ("JacobiPreconditioner", 0)},
                "one phase": {("FourierPreconditioner", 1), ("JacobiPreconditioner", 0)},
                "many values": {("FourierPreconditioner", 1), ("FourierPreconditioner", 4),
                                ("JacobiPreconditioner", 0)}}[pattern_kind]
    assert kinds == expected, f"choices made: {sorted(kinds)}"


def test_continuous_shift_is_interpolated_between_nodes():
    n = 24
    hs = halfspace(n)
    rng = np.random.default_rng(6113)
    shift = hs.self_influence * 10 ** rng.uniform(-2.0, 2.0, (n, n))
    levels, weights = shift_levels(shift, None, hs.self_influence, max_levels=4)
    assert len(levels) == 4, f"{len(levels)} levels, expected the 4 allowed"
    assert levels[0] == pytest.approx(shift.min(), rel=1e-12) and \
        levels[-1] == pytest.approx(shift.max(), rel=1e-12), "nodes must span the shift"
    stacked = np.array(weights)
    assert stacked.min() >= 0.0, "interpolation weights must be non-negative"
    assert np.allclose(stacked.sum(axis=0), 1.0, rtol=0, atol=1e-14), "weights must sum to one"
    assert np.count_nonzero(stacked > 0, axis=0).max() <= 2, \
        "each pixel interpolates between two neighbouring nodes"


@pytest.mark.parametrize("n", [24, 25])
def test_single_precision_of_interpolated_levels_is_the_double_one_to_round_off(n):
    # The residual is converted to single precision once and then weighted per level
    # (interpolation weights are not exact in float32, unlike a phase's indicator): the
    # result stays that of the double-precision preconditioner to float32 round-off.
    # Measured at n = 24, 25: 1.8e-7, 1.9e-7 of its largest value (float32 eps 1.2e-7).
    hs = halfspace(n)
    rng = np.random.default_rng(6113)
    shift = hs.self_influence * 10 ** rng.uniform(-2.0, 2.0, (n, n))
    pc = FourierPreconditioner(hs, shift)
    assert len(pc.levels) == 4, pc.levels
    active = np.ones((n, n), bool)
    residual = rng.standard_normal((n, n))
    single, double = pc(residual, active), pc.accurate(residual, active)
    error = np.abs(single - double).max() / np.abs(double).max()
    assert error < 1e-6, f"single-precision levels off by {error:.2e}"


def test_nearly_uniform_shift_is_one_level():
    hs = halfspace(16)
    shift = np.full((16, 16), 2 * hs.self_influence)
    shift[3, 4] *= 1.001
    levels, weights = shift_levels(shift, None, hs.self_influence)
    assert weights is None and levels == [shift.min()], f"levels {levels}"


# -- the preconditioned spectrum -----------------------------------------------

@pytest.mark.parametrize("n, magnitude", [(16, 0.1), (17, 1.0), (16, 10.0), (17, 100.0)])
def test_stitched_fourier_bounds_the_two_phase_spectrum(n, magnitude):
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    face = labels >= 0
    shift = two_phase_shift(labels, hs, magnitude)
    k = dense(hs.displacement, face)
    a = 0.5 * (k + k.T) + np.diag(shift[face])
    stitched = FourierPreconditioner(hs, shift, face_mask=face, precision="double")
    p = dense(lambda r: stitched(r, face), face)
    assert np.abs(p - p.T).max() < 1e-13 * np.abs(p).max(), "preconditioner not symmetric"
    # Single-precision transforms (the default) perturb it by their round-off:
    # measured 0.6 .. 1.5e-7 of its largest entry (float32 eps 1.2e-7) in these cases.
    default = dense(lambda r: FourierPreconditioner(hs, shift, face_mask=face)(r, face), face)
    error = np.abs(default - p).max() / np.abs(p).max()
    assert error < 1e-6, f"single-precision transforms off by {error:.2e}"
    assert np.linalg.eigvalsh(0.5 * (p + p.T))[0] > 0, "preconditioner not positive definite"
    cond = preconditioned_condition(a, p, face)
    single = preconditioned_condition(
        a, FourierPreconditioner(hs, np.full((n, n), shift[face].min())), face)
    jacobi = preconditioned_condition(a, JacobiPreconditioner(hs, shift), face)
    # Measured 1.91 .. 2.83 for these four cases (one level, the smaller
    # shift: 2.86 .. 9.93; Jacobi 2.74 .. 9.65); 2.0 .. 3.1 at n = 20, 21.
    assert cond < 3.2, f"stitched condition number {cond:.2f}"
    assert cond <= single * (1 + 1e-9), f"stitched {cond:.2f} worse than one level {single:.2f}"
    assert cond < jacobi, f"stitched {cond:.2f} not better than Jacobi {jacobi:.2f}"


@pytest.mark.parametrize("magnitude", [0.3, 30.0])
def test_stitched_fourier_solves_the_shifted_problem(magnitude):
    # Same answer as the unpreconditioned iteration, in fewer iterations than Jacobi.
    n = 41
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    shift = two_phase_shift(labels, hs, magnitude, ratio=0.01)
    face = labels >= 0
    height = np.zeros((n, n))
    plain = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11, preconditioner="none")
    res = {name: solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11,
                               preconditioner=name) for name in ("fourier", "jacobi")}
    diff = np.abs(res["fourier"].pressure - plain.pressure).max() / plain.pressure.max()
    assert diff < 1e-8, f"fourier differs from the plain iteration by {diff:.2e}"
    assert res["fourier"].nit < res["jacobi"].nit, \
        f"fourier {res['fourier'].nit} iterations, jacobi {res['jacobi'].nit}"


@pytest.mark.parametrize("magnitude", [0.3, 30.0])
def test_single_precision_transforms_converge_as_double(magnitude):
    # Single-precision transforms inside the double-precision iteration, all the
    # way (a callable without the double-precision ``accurate`` method): the same
    # iterations (measured 16 and 18) and the same answer to the solver's
    # tolerance (measured 4e-12 and 2e-12 of the peak) on the hard two-phase case
    # (shift ratio 1:0.01) from a cold start.
    n = 41
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    shift = two_phase_shift(labels, hs, magnitude, ratio=0.01)
    face = labels >= 0
    height = np.zeros((n, n))
    single = FourierPreconditioner(hs, shift, face_mask=face)
    double = FourierPreconditioner(hs, shift, face_mask=face, precision="double")
    res = {name: solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11,
                               preconditioner=pc)
           for name, pc in (("single", lambda r, active: single(r, active)), ("double", double))}
    single, double = res["single"], res["double"]
    assert single.success and double.success, (single.message, double.message)
    assert single.nit <= double.nit + 1, f"single {single.nit} iterations, double {double.nit}"
    diff = np.abs(single.pressure - double.pressure).max() / double.pressure.max()
    assert diff < 1e-10, f"single-precision transforms change the pressure by {diff:.2e}"


@pytest.mark.parametrize("n", [48, 49])
def test_tight_cold_solve_takes_double_precision_transforms(n):
    # Their round-off would cost the flat punch at rtol = 1e-10 from a cold start
    # more iterations (measured 11 against 10 on this disk at n = 48 and 49; 14
    # against 10 on a 1:2 rectangle, mirror asymmetry 1e-9 against 1e-12 of the
    # peak): a solve that must reduce its first residual more than 1e4-fold takes
    # the preconditioner's double-precision method.
    hs = halfspace(n)
    face = GEOMETRIES["homogeneous"].labels(n) >= 0
    height = np.zeros((n, n))
    double = FourierPreconditioner(hs, None, precision="double")
    default = solve_contact(hs, face, height, FORCE, rtol=1e-10)
    reference = solve_contact(hs, face, height, FORCE, rtol=1e-10, preconditioner=double)
    assert default.nit == reference.nit, f"{default.nit} iterations, {reference.nit} in double"
    assert np.array_equal(default.pressure, reference.pressure), "not the double-precision path"


# -- the warm start ------------------------------------------------------------

def test_galerkin_warm_start_is_exact_on_the_span():
    # In full contact the stage problem is linear in the height: the solution for
    # a combination of two heights is the same combination of their pressures,
    # which the prediction must find (extrapolation included).
    n = 48
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    hs, face = problem.halfspace, problem.face_mask
    shift = 0.05 * problem.distance_scale * problem.wear_field
    r, _ = np.meshgrid(np.arange(n) - n / 2, np.arange(n) - n / 2, indexing="ij")
    heights = [np.zeros((n, n)), 2e-4 * (r / n) ** 2]   # m, a third of f*
    solves = [solve_contact(hs, face, h, FORCE, shift=shift, rtol=1e-12) for h in heights]
    assert all(s.contact_fraction == 1.0 for s in solves), "the test needs full contact"
    history = WarmStart(problem)
    for s in solves:
        history.push(s.pressure)
    for theta in (0.3, 1.7):
        height = (1 - theta) * heights[0] + theta * heights[1]
        exact = (1 - theta) * solves[0].pressure + theta * solves[1].pressure
        guess, displacement = history.predict(height, shift)
        err = np.abs(guess - exact).max() / exact.max()
        # The two pressures differ by 6.6 % of the peak; the prediction is off by
        # 9e-15 .. 4e-14 of it (measured), the solves' round-off.
        assert err < 1e-11, f"theta {theta}: prediction off by {err:.2e} of the peak"
        assert np.allclose(displacement, hs.displacement(guess), rtol=0,
                           atol=1e-12 * np.abs(displacement).max()), "K x0 of the prediction"
        warm = solve_contact(hs, face, height, FORCE, shift=shift, x0=guess,
                             x0_displacement=displacement, rtol=1e-10)
        assert warm.success and warm.nit == 0, f"theta {theta}: {warm.nit} iterations"


def test_history_restored_from_its_pressures_predicts_bit_for_bit():
    # What a checkpoint stores (the pressures) determines the predictions.
    n = 33
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    rng = np.random.default_rng(7919)
    history = WarmStart(problem, size=3)
    for _ in range(5):
        history.push(np.where(problem.face_mask, 1e5 * (1 + 0.01 * rng.random((n, n))), 0.0))
    assert len(history) == 3, f"{len(history)} pressures kept, expected 3"
    again = WarmStart(problem, size=3, pressures=history.pressures())
    height = 1e-7 * rng.random((n, n))
    shift = 1e-3 * problem.distance_scale * problem.wear_field
    for a, b in zip(history.predict(height, shift), again.predict(height, shift), strict=True):
        assert np.array_equal(a, b), "restored history predicts differently"


def test_history_handed_out_stays_as_it_was():
    # A checkpoint's pressures are the history's own rows, not a copy: later
    # pushes must leave them as they were when handed out.
    n = 32
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    rng = np.random.default_rng(6067)
    history = WarmStart(problem, size=3)
    pushed = [np.where(problem.face_mask, 1e5 * (1 + rng.random((n, n))), 0.0) for _ in range(6)]
    for p in pushed[:4]:
        history.push(p)
    held, moved = history.pressures(), history.displacements()
    before = (held.copy(), moved.copy())
    assert not held.flags.writeable, "handed-out pressures must be read-only"
    for p in pushed[4:]:
        history.push(p)
    assert np.array_equal(held, before[0]) and np.array_equal(moved, before[1]), \
        "a push changed the pressures handed out before it"
    assert np.array_equal(held, np.array(pushed[3:0:-1])), "pressures held, newest first"
    assert np.array_equal(history.pressures(), np.array(pushed[5:2:-1])), \
        "pressures held after the pushes, newest first"


def _galerkin_reference(history, height, shift, face):
    """The energy minimiser over the history's affine span, from scratch.

    Differences from the newest pressure, dense Gram matrix.
    """
    v = history.pressures().reshape(len(history), -1)
    kv = history.displacements().reshape(len(history), -1)
    s = np.where(face, shift, 0.0).ravel()
    d, kd = v[1:] - v[0], kv[1:] - kv[0]
    gram = d @ (kd + s * d).T
    gradient = kv[0] + s * v[0] + height.ravel()
    beta = -np.linalg.solve(0.5 * (gram + gram.T),
                            d @ (gradient - gradient[face.ravel()].mean()))
    return (v[0] + beta @ d).reshape(face.shape)


def test_kept_gram_matrices_give_the_galerkin_combination():
    # The linear law's stage (shift_scale) reuses Gram matrices of consecutive
    # differences kept across pushes; the same shift as an array sums its part
    # afresh.  Both must give the minimiser computed from scratch (measured:
    # within 2e-11 of the pressure scale on these random histories), and a
    # history restored from its pressures (no prediction between its pushes)
    # must repeat the kept one bit for bit.
    n = 33
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    face = problem.face_mask
    rng = np.random.default_rng(104729)
    history = WarmStart(problem, size=4)
    base = np.where(face, 1e5, 0.0)
    height = 1e-7 * rng.random((n, n))
    c = 1e-3 * problem.distance_scale
    shift = c * problem.wear_field
    for step in range(7):
        history.push(base * (1 + 0.01 * step + 1e-3 * rng.random((n, n))))
        if len(history) < 2:
            continue
        exact = _galerkin_reference(history, height, shift, face)
        for kind, (guess, displacement) in (("kept", history.predict(height, shift_scale=c)),
                                            ("fresh", history.predict(height, shift))):
            err = np.abs(guess - exact).max() / 1e5
            assert err < 2e-10, f"push {step}, {kind}: off the Galerkin minimiser by {err:.2e}"
            assert np.allclose(displacement, problem.halfspace.displacement(guess), rtol=0,
                               atol=1e-12 * np.abs(displacement).max()), f"{kind}: K x0"
    again = WarmStart(problem, size=4, pressures=history.pressures(),
                            displacements=history.displacements())
    for a, b in zip(history.predict(height, shift_scale=c), again.predict(height, shift_scale=c),
                    strict=True):
        assert np.array_equal(a, b), "restored history predicts differently"
    with pytest.raises(ValueError, match="not both"):
        history.predict(height, shift, shift_scale=c)


def test_stage_iterations_do_not_grow_with_the_grid():
    # Early run-in (the flat punch's edge layer and the first grains), sdirk2:
    # measured 4.5 (n = 64) and 5.2 (n = 128) iterations per solve, the cold
    # first solve included (13.3 and 16.1 before the shift-aware preconditioner
    # and the Galerkin warm start).
    per_solve = {}
    for n in (64, 128):
        problem = wear_problem("voronoi_fine", (1.0, 10.0), n)
        result = run_in(problem, np.zeros((n, n)),
                        RunOptions(scheme="sdirk2", tol=1e-4,
                                   distance_limit=0.03 * problem.distance_scale,
                                   spread_tol=1e-300, shape_tol=1e-300))
        assert result.status == "stopped", result.message
        cold = result.solves - 2 * result.steps  # the initial solve
        per_solve[n] = result.iterations / result.solves
        assert cold == 1, f"{cold} solves outside the stages"
    assert max(per_solve.values()) < 7.0, f"iterations per solve {per_solve}"
    assert per_solve[128] < per_solve[64] + 1.0, f"iterations grow with n: {per_solve}"


@pytest.mark.parametrize("levels", ["one", "two", "interpolated"])
def test_unrestricted_preconditioner_restricted_is_the_preconditioner(levels):
    # The solver restricts the unrestricted output itself: on the active set it is the
    # preconditioner's value bit for bit, and it is that of a second application too
    # (the work buffers are rewritten).
    n = 37
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    face = labels >= 0
    shift = {"one": None, "two": two_phase_shift(labels, hs, 3.0),
             "interpolated": np.where(face, hs.self_influence
                                      * np.random.default_rng(2729).random((n, n)), 0.0)}[levels]
    rng = np.random.default_rng(2731)
    active = face & (rng.random((n, n)) > 0.2)
    pc = FourierPreconditioner(hs, shift, face_mask=face)
    for accurate in (False, True):
        for seed in (1, 2):
            r = np.where(active, np.random.default_rng(2731 + seed).standard_normal((n, n)), 0.0)
            want = (pc.accurate if accurate else pc)(r, active)
            got = pc.unrestricted(r, accurate=accurate)
            assert got.dtype == (np.float64 if accurate else np.float32), got.dtype
            assert np.array_equal(np.where(active, got, 0.0), want), (levels, accurate, seed)


@pytest.mark.parametrize("magnitude", [0.3, 30.0])
def test_solver_restricting_the_preconditioner_itself_takes_the_same_steps(magnitude):
    # The built-in preconditioner, restricted and centred by the solver in two passes,
    # against the same preconditioner as a plain callable (restricted by it): the same
    # iterations (16 and 17) and the same pressure (measured: bit for bit; the bound allows
    # for the order of a sum).
    n = 41
    hs = halfspace(n)
    labels = GEOMETRIES["voronoi"].labels(n)
    shift = two_phase_shift(labels, hs, magnitude, ratio=0.01)
    face = labels >= 0
    height = np.zeros((n, n))
    pc = FourierPreconditioner(hs, shift, face_mask=face)

    class Restricted:
        """``pc`` without its ``unrestricted`` method."""

        __call__, accurate = staticmethod(pc), staticmethod(pc.accurate)

    fused = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11, preconditioner=pc)
    plain = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11,
                          preconditioner=Restricted())
    assert fused.success and plain.success, (fused.message, plain.message)
    assert fused.nit == plain.nit, f"{fused.nit} iterations, {plain.nit} as a callable"
    diff = np.abs(fused.pressure - plain.pressure).max() / plain.pressure.max()
    assert diff < 1e-13, f"pressure differs by {diff:.2e}"
