"""Load-controlled contact solver against closed forms and a dense direct solve."""

import logging

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
from conftest import benchmark

from steady import reference
from steady.halfspace import HalfSpace
from steady.outline import Circle
from transient import initial_face
from transient.contact import ContactResult, solve_contact, solve_trusted_contact
from transient.preconditioners import PRECONDITIONERS

# The paper's epoxy cylinder (Fig. 6): a = 4 mm, F = 10 N, E* = 1.3 MPa.
RADIUS = 4e-3
E_STAR = 1.3e6
FORCE = 10.0
# Tilt at which a (non-rotating) tilted flat punch starts to lift off:
# the rim coefficient F / (2 pi a) - 2 E* theta a / pi of the pressure vanishes.
CRITICAL_TILT = FORCE / (4 * RADIUS**2 * E_STAR)


def grid(n):
    """The grid of the ``n x n`` pixels over the punch."""
    return Circle(RADIUS).grid(n)


def setup(n, E_star=E_STAR):
    g = grid(n)
    hs = HalfSpace(n, g.h, E_star)
    return hs, g.mask


def effective_radius(face, hs):
    """Radius of the disk with the pixelated face's area."""
    return np.sqrt(face.sum() * hs.h**2 / np.pi)


def load(res, hs):
    return res.pressure.sum() * hs.h**2


# -- kernels -------------------------------------------------------------------

@pytest.mark.parametrize("n", [20, 21])
def test_preconditioner_kernels_match_the_half_space(n):
    hs, _ = setup(n)
    p = np.random.default_rng(31337).random((n, n))
    u = hs.displacement(p)
    symbol = hs.influence_symbol
    assert symbol.min() > 0, "the circulant embedding must be positive definite"
    via_symbol = hs.inverse(hs.forward(p) * symbol)
    assert np.allclose(via_symbol, u, rtol=0, atol=1e-13 * np.abs(u).max()), (
        "influence_symbol must reproduce HalfSpace.displacement")
    unit = np.zeros((n, n))
    unit[0, 0] = 1.0
    assert np.allclose(hs.influence_quadrant[:n, :n], hs.displacement(unit), rtol=1e-12,
                       atol=0), "influence_quadrant must be the response to a unit pixel pressure"
    # The aliased symbol is the spectrum of the 2n-circulant kernel folded to n x n.
    i = np.arange(2 * n)
    fold = np.minimum(i, 2 * n - i)
    circulant = hs.influence_quadrant[fold][:, fold]
    folded = circulant.reshape(2, n, 2, n).sum(axis=(0, 2))
    expected = np.fft.rfft2(folded).real
    aliased = hs.aliased_symbol
    assert np.allclose(aliased, expected, rtol=0, atol=1e-12 * expected.max()), (
        "aliased_symbol must be the spectrum of the n-periodic folded kernel")
    assert aliased.min() > 0, "the aliased symbol must be positive"


# -- flat punch ------------------------------------------------------------

FLAT_SIZES = (31, 32, 63, 64, 127, 128)


@pytest.fixture(scope="module")
def flat_results():
    out = {}
    for n in FLAT_SIZES:
        hs, face = setup(n)
        out[n] = (hs, face, solve_contact(hs, face, initial_face.flat(grid(n)), FORCE))
    return out


def test_flat_punch_approach_converges_first_order(flat_results):
    errors = []
    for n in FLAT_SIZES:
        hs, face, res = flat_results[n]
        assert res.success, f"n={n}: {res.message}"
        assert abs(load(res, hs) / FORCE - 1) < 1e-13, f"n={n}: load {load(res, hs)} N"
        assert res.contact_fraction == 1.0, f"n={n}: flat punch lifts off {res.contact_fraction}"
        # Against the disk of the same area as the pixelated face, the
        # approach error is a clean O(h): measured 7.8e-3, 7.6e-3, 3.8e-3,
        # 3.6e-3, 1.8e-3, 1.8e-3 for n = 31 ... 128 (the nominal radius adds
        # an area error that fluctuates with n).
        exact = reference.flat_punch_approach(FORCE, effective_radius(face, hs), E_STAR)
        errors.append(abs(res.approach / exact - 1))
        nominal = reference.flat_punch_approach(FORCE, RADIUS, E_STAR)
        assert abs(res.approach / nominal - 1) < 1.5e-2, (
            f"n={n}: approach {res.approach} m vs F/(2aE*) = {nominal} m")
    order = -np.polyfit(np.log(FLAT_SIZES), np.log(errors), 1)[0]
    assert 0.9 < order < 1.1, f"approach error order {order:.3f}, errors {errors}"
    assert errors[-1] < 2.5e-3, f"approach error at n=128: {errors[-1]:.3e} (measured 1.8e-3)"


def test_flat_punch_pressure_is_boussinesq_away_from_the_rim(flat_results):
    errors = []
    for n in FLAT_SIZES:
        hs, face, res = flat_results[n]
        r, _ = grid(n).polar()
        exact = reference.flat_punch_pressure(r, effective_radius(face, hs), FORCE)
        inner = face & (r < 0.5 * RADIUS)
        rms = np.sqrt(np.mean((res.pressure[inner] - exact[inner]) ** 2))
        errors.append(rms / reference.disk_mean_pressure(FORCE, RADIUS))
    # Measured 8.8e-3 (n=31) down to 2.1e-3 (n=128), first order.
    order = -np.polyfit(np.log(FLAT_SIZES), np.log(errors), 1)[0]
    assert 0.9 < order < 1.1, f"inner pressure error order {order:.3f}, errors {errors}"
    assert errors[-1] < 3e-3, f"inner rms pressure error at n=128: {errors[-1]:.3e}"


def test_flat_punch_rim_carries_the_peak(flat_results):
    hs, face, res = flat_results[128]
    r, _ = grid(128).polar()
    assert r[np.unravel_index(np.argmax(res.pressure), r.shape)] > 0.97 * RADIUS, (
        "the edge singularity must put the peak pressure on the rim")


def test_fourier_iterations_do_not_grow_with_the_grid(flat_results):
    nits = [flat_results[n][2].nit for n in FLAT_SIZES]
    # Measured 8 to 10 for n = 31 ... 128, 12 at 512, 14 at 1024; plain
    # Polonsky-Keer needs 18 to 35 here.
    assert max(nits) <= 12, f"iterations {nits}"


# -- Hertz -------------------------------------------------------------------

HERTZ_FORCE = 0.3  # N: with R = 80 mm, c = 0.6 a, inside the rim, and c/R = 0.03


@pytest.mark.parametrize("n", [127, 128])
def test_crowned_face_is_hertz(n):
    hs, face = setup(n)
    sphere = 4 * E_STAR * (0.6 * RADIUS) ** 3 / (3 * HERTZ_FORCE)
    c, p_max, approach = reference.hertz(HERTZ_FORCE, sphere, E_STAR)
    res = solve_contact(hs, face, initial_face.crowned(grid(n), sphere), HERTZ_FORCE)
    assert res.success, res.message
    assert abs(load(res, hs) / HERTZ_FORCE - 1) < 1e-13, f"load {load(res, hs)} N"
    r, _ = grid(n).polar()
    contact = res.pressure > 0
    assert r[contact].max() < 0.7 * RADIUS, "contact must stay inside the rim"
    radius = np.sqrt(contact.sum() * hs.h**2 / np.pi)
    # Measured at n = 127, 128: contact radius +3.1e-3, +3.0e-3 (one pixel
    # row is h/c = 1.3e-2); peak +1.2e-4, -5.4e-5; approach +3.8e-5
    # (the exact sphere's r^4/(8R^3) against Hertz's paraboloid: ~6e-5).
    assert abs(radius / c - 1) < 6e-3, f"contact radius {radius} m vs Hertz {c} m"
    assert abs(res.pressure.max() / p_max - 1) < 1e-3, (
        f"peak pressure {res.pressure.max()} Pa vs Hertz {p_max} Pa")
    assert abs(res.approach / approach - 1) < 2e-4, (
        f"approach {res.approach} m vs Hertz {approach} m")


# -- tilted face ---------------------------------------------------------------

@pytest.mark.parametrize("n", [127, 128])
def test_tilted_face_in_full_contact_has_the_rigid_punch_moment(n):
    hs, face = setup(n)
    tilt = 0.5 * CRITICAL_TILT
    res = solve_contact(hs, face, initial_face.tilted(grid(n), tilt), FORCE)
    assert res.success and res.contact_fraction == 1.0, res.message
    r, theta = grid(n).polar()
    centroid = np.sum(res.pressure * r * np.cos(theta)) * hs.h**2 / FORCE
    # A flat punch forced to a tilt theta carries M = 4/3 E* a^3 theta
    # (Johnson, Contact Mechanics, sec. 3.8); the face recedes towards +x.
    a_eff = effective_radius(face, hs)
    expected = -4 / 3 * E_STAR * a_eff**3 * np.tan(tilt) / FORCE
    # Measured with a_eff: -1.1e-2 (n=63, 64), -5.5e-3 (n=127, 128), -2.7e-3
    # (n=255, 256): first order, three times the approach error.
    assert abs(centroid / expected - 1) < 8e-3, f"centroid {centroid} m vs {expected} m"
    flat_approach = reference.flat_punch_approach(FORCE, a_eff, E_STAR)
    approach = flat_approach + np.tan(tilt) * RADIUS  # the field is zero at x = -a
    # Measured +1.8e-3 of the flat approach at n = 127, 128 (as for the flat punch).
    assert abs(res.approach - approach) < 3e-3 * flat_approach, (
        f"approach {res.approach} m vs {approach} m")


@pytest.mark.parametrize("n", [64, 65])
def test_tilted_face_lifts_off_on_the_recessed_side(n):
    hs, face = setup(n)
    height = initial_face.tilted(grid(n), 2 * CRITICAL_TILT)
    cold = solve_contact(hs, face, height, FORCE, rtol=1e-10)
    assert cold.success, cold.message
    assert 0.3 < cold.contact_fraction < 0.95, f"contact fraction {cold.contact_fraction}"
    assert abs(load(cold, hs) / FORCE - 1) < 1e-13, "load must be met to round-off"
    # Lift-off region: along every row of constant y, once lifted stays lifted
    # towards +x (the recessed side).
    contact = cold.pressure > 0
    for j in range(n):
        column = contact[face[:, j], j]
        if column.any():
            last = np.nonzero(column)[0].max()
            assert column[: last + 1].all(), f"row y={j}: contact not contiguous from -x"
    r, theta = grid(n).polar()
    centroid = np.sum(cold.pressure * r * np.cos(theta)) * hs.h**2 / FORCE
    # Past the critical tilt the centroid moves beyond the full-contact
    # value at lift-off, -a/3 (measured -0.547 a).
    assert -0.8 * RADIUS < centroid < -RADIUS / 3, f"centroid {centroid / RADIUS} a"
    # Gap closed under pressure, open (to the tolerance) elsewhere.
    gap = cold.displacement + height - cold.approach
    scale = cold.approach
    assert np.abs(gap[contact]).max() < 1e-8 * scale, "gap must close where p > 0"
    assert gap[face & ~contact].min() > -1e-8 * scale, "no interpenetration"
    # Same answer from a warm start (a rougher, uniform one and a near one).
    for x0 in (face * 1.0, np.roll(cold.pressure, 1, axis=1)):
        warm = solve_contact(hs, face, height, FORCE, x0=x0, rtol=1e-10)
        assert warm.success, warm.message
        diff = np.abs(warm.pressure - cold.pressure).max() / cold.pressure.max()
        assert diff < 1e-6, f"warm start differs by {diff:.2e} of the peak pressure"
        assert abs(warm.approach / cold.approach - 1) < 1e-9, "approach from warm start"


def test_warm_start_from_the_solution_converges_at_once():
    n = 48
    hs, face = setup(n)
    height = initial_face.tilted(grid(n), 2 * CRITICAL_TILT, azimuth=0.7)
    cold = solve_contact(hs, face, height, FORCE)
    warm = solve_contact(hs, face, height, FORCE, x0=cold.pressure)
    assert warm.success and warm.nit <= 1, f"warm start took {warm.nit} iterations"


@pytest.mark.parametrize("n", [40, 41])
def test_known_displacement_of_the_warm_start_saves_a_product(n, monkeypatch):
    hs, face = setup(n)
    rng = np.random.default_rng(4409)
    shift = hs.self_influence * np.where(rng.random((n, n)) < 0.3, 2.0, 0.2)
    height = initial_face.crowned(grid(n), 0.2)
    cold = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11)
    # A warm start near the solution, non-negative, zero off the face.
    x0 = np.where(face, cold.pressure * (1 + 0.01 * rng.random((n, n))), 0.0)
    products = []
    real = hs.displacement
    monkeypatch.setattr(hs, "displacement", lambda p: products.append(1) or real(p))
    plain = solve_contact(hs, face, height, FORCE, shift=shift, x0=x0, rtol=1e-11)
    calls = len(products)
    known = solve_contact(hs, face, height, FORCE, shift=shift, x0=x0,
                          x0_displacement=real(x0), rtol=1e-11)
    assert len(products) - calls == calls - 1, \
        f"{len(products) - calls} products with K x0 given, {calls} without"
    for res in (plain, known):
        assert res.success, res.message
        diff = np.abs(res.pressure - cold.pressure).max() / cold.pressure.max()
        assert diff < 1e-8, f"warm start differs by {diff:.2e} of the peak pressure"
        assert np.allclose(res.displacement, real(res.pressure) + shift * res.pressure, rtol=0,
                           atol=1e-12 * np.abs(res.displacement).max()), \
            "displacement must be (K + diag shift) p on the whole grid"
    # A warm start the solver has to change (negative values) ignores it.
    bad = np.where(face, x0 - 0.5 * x0.mean(), 0.0)
    res = solve_contact(hs, face, height, FORCE, shift=shift, x0=bad,
                        x0_displacement=real(bad), rtol=1e-11)
    diff = np.abs(res.pressure - cold.pressure).max() / cold.pressure.max()
    assert res.success and diff < 1e-8, \
        f"a clipped warm start must not use the displacement of the unclipped one ({diff:.2e})"


@pytest.mark.parametrize("n", [40, 41])
def test_trusted_entry_is_the_checked_solver_bit_for_bit(n):
    # The run-in loop's entry skips the checks, not any of the work: on valid
    # arguments (a shifted stage, warm start and its displacement) it returns
    # exactly what the checked entry returns.
    hs, face = setup(n)
    rng = np.random.default_rng(6133)
    shift = np.where(face, hs.self_influence * np.where(rng.random((n, n)) < 0.3, 5.0, 0.5),
                     0.0)
    height = initial_face.crowned(grid(n), 0.3)
    cold = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11)
    x0 = np.where(face, cold.pressure * (1 + 0.02 * rng.random((n, n))), 0.0)
    kw = dict(shift=shift, x0=x0, x0_displacement=hs.displacement(x0), rtol=1e-11)
    checked = solve_contact(hs, face, height, FORCE, **kw)
    trusted = solve_trusted_contact(hs, face, height, FORCE, **kw)
    assert checked.success and checked.nit > 0, checked.message
    for field in ("pressure", "displacement", "elastic_displacement", "residual_history"):
        assert np.array_equal(getattr(trusted, field), getattr(checked, field)), \
            f"trusted entry differs in {field}"
    assert (trusted.approach, trusted.nit, trusted.message) == \
        (checked.approach, checked.nit, checked.message), "trusted entry differs"


# -- diagonal shift against a dense direct solve ------------------------------

def dense_lcp(hs, face, height, force, shift):
    """Exact solution by a dense NNLS on the face pixels and a root find on d."""
    n = hs.shape[0]
    ii, jj = np.nonzero(face)
    m = ii.size
    columns = np.empty((m, m))
    for k in range(m):
        e = np.zeros((n, n))
        e[ii[k], jj[k]] = 1.0
        columns[:, k] = hs.displacement(e)[ii, jj]
    A = 0.5 * (columns + columns.T) + np.diag(shift[ii, jj])
    L = scipy.linalg.cholesky(A, lower=True)
    h = height[ii, jj]

    def pressure(d):
        # min 1/2 p^T A p + (h - d)^T p, p >= 0, as a non-negative least squares.
        rhs = scipy.linalg.solve_triangular(L, d - h, lower=True)
        return scipy.optimize.nnls(L.T, rhs, maxiter=50 * m)[0]

    def excess(d):
        return pressure(d).sum() * hs.h**2 - force

    hi = h.min() + 1e-9
    while excess(hi) < 0:
        hi = h.min() + 2 * (hi - h.min())
    d = scipy.optimize.brentq(excess, h.min(), hi, xtol=1e-16, rtol=1e-15)
    # Polish on the active set: A_SS p_S = d - h_S with sum(p_S) h^2 = F.
    active = pressure(d) > 0
    A_ss = A[np.ix_(active, active)]
    x1 = np.linalg.solve(A_ss, np.ones(active.sum()))
    xh = np.linalg.solve(A_ss, h[active])
    d = (force / hs.h**2 + xh.sum()) / x1.sum()
    p = np.zeros((n, n))
    p[ii[active], jj[active]] = d * x1 - xh
    return p, d


@pytest.mark.parametrize("n", [12, 13])
@pytest.mark.parametrize("magnitude", [0.3, 30.0, 3e4])
def test_shifted_operator_matches_dense_direct_solve(n, magnitude):
    hs, face = setup(n)
    rng = np.random.default_rng(20260521 + n)
    # Two phases with wear ratios 1e-2 apart, shift in units of the self-influence.
    phase = rng.random((n, n)) < 0.4
    shift = hs.self_influence * magnitude * np.where(phase, 1.0, 1e-2)
    height = initial_face.tilted(grid(n), 3 * CRITICAL_TILT, azimuth=0.3)
    expected_p, expected_d = dense_lcp(hs, face, height, FORCE, shift)
    res = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-12)
    assert res.success, res.message
    peak = expected_p.max()
    diff = np.abs(res.pressure - expected_p).max() / peak
    # Both solve the same discrete problem; measured <= 4.4e-12 of the peak
    # pressure and <= 1.6e-13 in the approach at rtol = 1e-12.
    assert diff < 1e-10, f"pressure differs from the dense solve by {diff:.2e} of the peak"
    assert abs(res.approach - expected_d) < 1e-11 * abs(expected_d), (
        f"approach {res.approach} m vs dense {expected_d} m")
    assert np.array_equal(res.pressure > 0, expected_p > 0), "contact sets differ"
    assert np.allclose(res.displacement, hs.displacement(res.pressure) + shift * res.pressure,
                       rtol=0, atol=1e-12 * np.abs(res.displacement).max()), (
        "displacement must be (K + diag shift) p")


def test_big_shift_is_nearly_diagonal():
    n = 40
    hs, face = setup(n)
    shift = np.full((n, n), 1e6 * n * hs.self_influence)
    height = initial_face.tilted(grid(n), 1e-3)
    res = solve_contact(hs, face, height, FORCE, shift=shift)
    assert res.success and res.nit <= 3, f"{res.nit} iterations: {res.message}"
    # Winkler foundation: p = (d - h) / s where positive.
    winkler = np.where(face, np.maximum(res.approach - height, 0.0) / shift, 0.0)
    diff = np.abs(res.pressure - winkler).max() / winkler.max()
    assert diff < 1e-5, f"pressure differs from the Winkler limit by {diff:.2e}"


@pytest.mark.parametrize("name", sorted(PRECONDITIONERS))
def test_every_preconditioner_gives_the_same_answer(name):
    n = 33
    hs, face = setup(n)
    rng = np.random.default_rng(9173)
    shift = hs.self_influence * rng.uniform(0.0, 5.0, (n, n))
    height = initial_face.crowned(grid(n), 0.05)
    reference_res = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11,
                                  preconditioner="none")
    res = solve_contact(hs, face, height, FORCE, shift=shift, rtol=1e-11, preconditioner=name)
    assert res.success, f"{name}: {res.message}"
    diff = np.abs(res.pressure - reference_res.pressure).max() / reference_res.pressure.max()
    assert diff < 1e-8, f"{name} differs from the plain iteration by {diff:.2e}"


# -- result contract --------------------------------------------------------------

def test_result_reports_the_stopping_rule():
    n = 50
    hs, face = setup(n)
    height = initial_face.tilted(grid(n), 2 * CRITICAL_TILT)
    seen = []
    res = solve_contact(hs, face, height, FORCE, rtol=1e-9, callback=seen.append)
    assert isinstance(res, ContactResult)
    assert len(seen) == res.nit and res.residual_history.size == res.nit + 1, (
        "one callback per iteration, one residual before each and at the end")
    assert res.residual == res.residual_history[-1], "final residual is the last in history"
    contact = res.pressure > 0
    gap = np.where(face, res.displacement + height - res.approach, 0.0)
    violation = np.where(contact, gap, np.minimum(gap, 0.0))
    rms = np.sqrt(np.sum(violation**2) / face.sum())
    assert np.isclose(rms, res.residual, rtol=1e-6, atol=0), "residual is the rms violation"
    scale = np.sqrt(np.mean(res.displacement[contact] ** 2))
    assert res.residual <= 1e-9 * scale, "stopping rule: residual <= rtol * rms displacement"
    assert res.pressure.min() >= 0 and not res.pressure[~face].any(), "p >= 0, zero off face"
    assert res.contact_fraction == contact.sum() / face.sum(), "contact fraction"
    with pytest.raises(dataclass_error()):
        res.nit = 0


def dataclass_error():
    import dataclasses
    return dataclasses.FrozenInstanceError


def test_no_convergence_is_reported_not_hidden(caplog):
    n = 64
    hs, face = setup(n)
    with caplog.at_level(logging.WARNING, logger="transient.contact"):
        res = solve_contact(hs, face, np.zeros((n, n)), FORCE, maxiter=2,
                            preconditioner="none")
    assert not res.success and "no convergence" in res.message, res.message
    assert res.nit == 2, f"nit {res.nit}"
    assert any("no convergence" in rec.getMessage() for rec in caplog.records), (
        "failure must be logged")
    assert abs(load(res, hs) / FORCE - 1) < 1e-13, "load met even on failure"


def test_zero_force_gives_zero_pressure():
    n = 16
    hs, face = setup(n)
    height = initial_face.tilted(grid(n), 0.01)
    res = solve_contact(hs, face, height, 0.0)
    assert res.success and not res.pressure.any(), "no load, no pressure"
    assert res.approach == height[face].min(), "the face just touches"


@pytest.mark.parametrize("change, match", [
    (dict(normal_force=-1.0), "normal_force"),
    (dict(normal_force=np.nan), "normal_force"),
    (dict(normal_force=np.inf), "normal_force"),
    (dict(recession=np.full((9, 9), np.nan)), "recession"),
    (dict(recession=np.zeros((8, 9))), "recession"),
    (dict(face_mask=np.ones((9, 8), bool)), "face_mask"),
    (dict(face_mask=np.ones((9, 9))), "face_mask"),
    (dict(face_mask=np.zeros((9, 9), bool)), "face has no pixel"),
    (dict(shift=-np.ones((9, 9))), "shift"),
    (dict(shift=np.ones((3, 3))), "shift"),
    (dict(shift=np.full((9, 9), np.inf)), "shift"),
    (dict(x0=np.ones((2, 2))), "x0"),
    (dict(rtol=-1.0), "rtol"),
    (dict(atol=np.nan), "atol"),
    (dict(rtol=0.0, atol=0.0), "rtol"),
    (dict(maxiter=0), "maxiter"),
    (dict(maxiter=2.5), "maxiter"),
    (dict(preconditioner="multigrid"), "preconditioner"),
    (dict(norm="l1"), "norm"),
])
def test_bad_input_raises(change, match):
    n = 9
    hs, face = setup(n)
    args = dict(halfspace=hs, face_mask=face, recession=np.zeros((n, n)), normal_force=1.0)
    args.update(change)
    kwargs = {k: args.pop(k) for k in list(args) if k not in
              ("halfspace", "face_mask", "recession", "normal_force")}
    with pytest.raises(ValueError, match=match):
        solve_contact(args["halfspace"], args["face_mask"], args["recession"],
                      args["normal_force"], **kwargs)


# -- large grids ---------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("n", [1023, 1024])
def test_flat_punch_on_a_fine_grid(n):
    hs, face = setup(n)
    res = solve_contact(hs, face, np.zeros((n, n)), FORCE)
    # Measured 14 iterations at n = 1023 and 1024.
    assert res.success and res.nit <= 17, f"{res.nit} iterations: {res.message}"
    exact = reference.flat_punch_approach(FORCE, effective_radius(face, hs), E_STAR)
    # O(h) continuation of the measured 1.8e-3 at n = 128: ~2.3e-4 at n = 1024.
    assert abs(res.approach / exact - 1) < 4e-4, f"approach error {res.approach / exact - 1}"


@pytest.mark.slow
def test_crowned_face_on_a_fine_grid():
    n = 512
    hs, face = setup(n)
    sphere = 4 * E_STAR * (0.6 * RADIUS) ** 3 / (3 * HERTZ_FORCE)
    c, p_max, approach = reference.hertz(HERTZ_FORCE, sphere, E_STAR)
    res = solve_contact(hs, face, initial_face.crowned(grid(n), sphere), HERTZ_FORCE)
    assert res.success, res.message
    radius = np.sqrt((res.pressure > 0).sum() * hs.h**2 / np.pi)
    # Measured +7.9e-4 (contact radius) and +7.2e-5 (peak) at n = 512.
    assert abs(radius / c - 1) < 2e-3, f"contact radius {radius} vs {c}"
    assert abs(res.pressure.max() / p_max - 1) < 3e-4, "peak pressure"


def test_benchmark_script_smoke(tmp_path):
    bench = benchmark("bench_contact")
    out = tmp_path / "bench.h5"
    peer_rows, pc_rows = bench.main(["--sizes", "24", "--pc-sizes", "25", "--repeat", "1",
                                     "--out", str(out), "--skip-peers"])
    assert out.exists(), "the benchmark writes its HDF5 file"
    for row in peer_rows:
        assert row["runin"]["nit"] > 0, f"{row['case']}: no run met the accuracy"
    assert {row["scene"] for row in pc_rows} >= {"flat", "crowned"}, "preconditioner scenes"
    for row in pc_rows:
        assert row["auto"]["nit"] > 0, f"{row['scene']}: auto did not meet the accuracy"


@pytest.mark.slow
def test_run_in_solve_benchmark_smoke(tmp_path):
    import pathlib

    import h5py

    bench = benchmark("bench_contact_solve")
    problems = tmp_path / "problems"
    kept = bench.main(["capture", "--n", "48", "--dir", str(problems), "--stride", "2",
                       "--count", "2"])
    assert kept == 2 and len(list(problems.glob("problem_*.npz"))) == 2, "two problems kept"
    out = tmp_path / "replay.h5"
    rows = bench.main(["replay", "--dir", str(problems), "--out", str(out), "--repeat", "1"])
    assert all(row["success"] for row in rows), "every captured problem solves again"
    with h5py.File(out) as f:
        assert f["seconds"].attrs["units"] == "s" and f["nit"].shape == (2,), "replay file"
    root = pathlib.Path(__file__).parents[1]
    figures = bench.main(["compare", "--dir", str(problems), "--base", str(root), "--rounds",
                          "2", "--out", str(tmp_path / "compare.h5")])
    assert figures["iterations base"] == figures["iterations this"], "same solver, same tree"
    assert figures["approach difference"] == 0.0, "the same tree gives the same approach"
    assert figures["pressure difference"] == 0.0, "the same tree gives the same pressure"
    assert figures["iteration mismatches"] == 0, "the same tree takes the same iterations"
    figures = bench.main(["overlap", "--dir", str(problems), "--rounds", "1", "--out",
                          str(tmp_path / "overlap.h5")])
    assert figures["solve"] > 0 and figures["figures"] > 0, "solve and figures timed"
    assert figures["together"] >= figures["solve_during_figures"], "together includes the solve"
    rows = bench.main(["products", "--base", str(root), "--sizes", "16", "--rounds", "1"])
    assert len(rows) == 8 and all(row["seconds"] > 0 for row in rows), "product timings"


# -- one-pass vector updates ---------------------------------------------------

def test_axpy_updates_in_place_in_one_pass_or_two():
    from transient.contact import _AXPY_BLOCK, _axpy

    rng = np.random.default_rng(3917)
    shape = (101, 2 * _AXPY_BLOCK // 101 + 3)  # two blocks and a partial one
    x, y = rng.random(shape), rng.random(shape)
    # BLAS path (contiguous float64) and numpy's (a strided view; single precision).
    for target, source in ((y.copy(), x), (y.copy()[:, ::2], x[:, ::2]),
                           (y.astype(np.float32), x)):
        want = target + (-0.37) * source
        out = _axpy(-0.37, source, target)
        assert out is target, "axpy returns the array it updated, in place"
        assert np.abs(out - want).max() <= 2 * np.finfo(target.dtype).eps, \
            f"axpy on {target.dtype}, strides {target.strides}: more than round-off"


@pytest.mark.parametrize("n", [40, 41])
def test_one_pass_updates_keep_the_iterates_of_two_pass_ones(n, monkeypatch):
    # A cold, shifted solve whose active set shrinks from about 606 to 509 pixels over
    # its first iterations: the iterates with BLAS axpy (one rounding, fused) against
    # numpy's ``y += alpha * x`` (two roundings), the formula before it. Measured at
    # n = 40, 41: pressure iterates within 8.3e-15, 1.0e-14 of their peak, approach within
    # 2.2e-16, 3.3e-16 (relative), the same 15, 14 iterations.
    from transient import contact

    hs, face = setup(n)
    rng = np.random.default_rng(6133)
    shift = np.where(face, hs.self_influence * np.where(rng.random((n, n)) < 0.3, 5.0, 0.5),
                     0.0)
    height = initial_face.crowned(grid(n), 0.08)

    def solve():
        iterates = []
        res = solve_contact(hs, face, height, HERTZ_FORCE, shift=shift, rtol=1e-11,
                            callback=lambda p: iterates.append(p.copy()))
        return res, iterates

    fused, fused_iterates = solve()

    def two_pass(alpha, x, y):
        y += alpha * x
        return y

    monkeypatch.setattr(contact, "_axpy", two_pass)
    plain, plain_iterates = solve()
    assert fused.success and fused.nit == plain.nit, (fused.nit, plain.nit)
    counts = [np.count_nonzero(p) for p in plain_iterates]
    assert len(set(counts)) > 3, f"the active set must change: {counts}"
    for k, (a, b) in enumerate(zip(fused_iterates, plain_iterates, strict=True)):
        assert np.abs(a - b).max() <= 1e-13 * b.max(), f"iterate {k} differs beyond round-off"
    assert abs(fused.approach / plain.approach - 1) < 4e-15, "approach"
