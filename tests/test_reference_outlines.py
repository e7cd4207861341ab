"""Closed forms of other face outlines: rectangle, disk at any r, annulus, rms-slope factors.

The homogeneous face of an outline is the displacement under a uniform
pressure on it (steady.reference); its rms slope is ``S pbar / E*``.
"""

import math

import numpy as np
import pytest
from scipy import integrate, special

from steady import reference
from steady.halfspace import HalfSpace

E_STAR = 1.3e6   # Pa
PRESSURE = 2.5e4  # Pa

#: Rms-slope factors, pinned (tanh-sinh quadrature, confirmed below by the
#: whole-plane identity and by nested adaptive quadrature to a few 1e-14).
SQUARE = 1.264064510708848
ASPECT_2 = 1.251084360516164
ASPECT_3 = 1.235270727397658
ANNULI = {0.25: 1.254346088861461, 0.5: 1.217400850059011, 0.75: 1.179159380168287}
STRIP = 2 / math.sqrt(3)  # infinite strip: (2 / (pi E*)) ln|(x + c)/(x - c)| has rms pi / sqrt(3)


def _rel(got, want):
    return np.max(np.abs(got - want)) / np.max(np.abs(want))


# -- rectangle: Love's closed form --------------------------------------------

@pytest.mark.parametrize("shape", [(16, 48), (33, 20), (7, 7)])
def test_rectangle_is_a_uniformly_loaded_grid(shape):
    """A uniform pressure on a whole nx x ny grid is a uniform rectangle: same face, same slopes."""
    nx, ny = shape
    h = 1e-4
    halfspace = HalfSpace(shape, h, E_STAR)
    load = np.full(shape, PRESSURE)
    x = (np.arange(nx) + 0.5 - nx / 2) * h
    y = (np.arange(ny) + 0.5 - ny / 2) * h
    args = (x[:, None], y[None, :], nx * h / 2, ny * h / 2, PRESSURE, E_STAR)
    u = reference.rectangle_face(*args)
    gx, gy = reference.rectangle_face_gradient(*args)
    assert u.shape == shape and gx.shape == shape, f"{shape}: broadcast shape {u.shape}"
    # Measured differences: <= 6e-16 (face), 8e-16 (slopes) of the largest value, corner pixels
    # included; FFT round-off.
    err = _rel(halfspace.displacement(load), u)
    assert err < 1e-14, f"{shape}: face differs from the half-space operator by {err:.1e}"
    hx, hy = halfspace.gradient(load)
    for name, got, want in (("du/dx", hx, gx), ("du/dy", hy, gy)):
        err = _rel(got, want)
        assert err < 1e-14, f"{shape}: {name} differs from the half-space operator by {err:.1e}"
        corners = got[[0, 0, -1, -1], [0, -1, 0, -1]] - want[[0, 0, -1, -1], [0, -1, 0, -1]]
        assert np.max(np.abs(corners)) < 1e-14 * np.max(np.abs(want)), \
            f"{shape}: {name} at the corner pixels differs by {np.max(np.abs(corners)):.1e}"


def test_rectangle_centre_and_far_field():
    a, b = 1e-3, 3e-3
    scale = PRESSURE / (math.pi * E_STAR)
    centre = reference.rectangle_face(0.0, 0.0, a, b, PRESSURE, E_STAR)
    want = scale * 4 * (a * math.asinh(b / a) + b * math.asinh(a / b))
    assert centre == pytest.approx(want, rel=1e-15), "centre value 4 (a asinh(b/a) + b asinh(a/b))"
    square = reference.rectangle_face(0.0, 0.0, a, a, PRESSURE, E_STAR)
    assert square == pytest.approx(8 * a * math.asinh(1.0) * scale, rel=1e-15), \
        "centre of a square: the pixel self-influence 4 h asinh(1) with h = 2a"
    # Far away the rectangle is a point force 4 a b p: u = 4 a b p / (pi E* r), to O((b/r)^2)
    # (quadrupole).  Round-off grows like eps r / a (measured 2e-10 at r = 3e6 a; the plain
    # corner sum would lose eps (r/a)^2 ~ 1e-3 there).
    for r in (1e2 * b, 1e4 * b, 1e6 * b):
        for angle in (0.0, 0.7, math.pi / 2):
            x, y = r * math.cos(angle), r * math.sin(angle)
            got = reference.rectangle_face(x, y, a, b, PRESSURE, E_STAR)
            point = 4 * a * b * scale / r
            assert abs(got / point - 1) < 2 * (b / r) ** 2 + 1e-15 * r / a, \
                f"far field at r = {r:g} m, angle {angle}: {got / point - 1:.2e}"


def test_rectangle_gradient_is_the_derivative():
    """Central differences of the face at random points inside and outside."""
    a, b = 1e-3, 2.5e-3
    rng = np.random.default_rng(2718)
    x = rng.uniform(-3 * a, 3 * a, 200)
    y = rng.uniform(-3 * b, 3 * b, 200)
    # Keep 2 % of a away from the edge lines, where the slope is log-singular.
    ok = (np.abs(np.abs(x) - a) > 0.02 * a) & (np.abs(np.abs(y) - b) > 0.02 * a)
    x, y = x[ok], y[ok]
    step = 1e-6 * a
    face = reference.rectangle_face
    fx = (face(x + step, y, a, b, PRESSURE, E_STAR)
          - face(x - step, y, a, b, PRESSURE, E_STAR)) / (2 * step)
    fy = (face(x, y + step, a, b, PRESSURE, E_STAR)
          - face(x, y - step, a, b, PRESSURE, E_STAR)) / (2 * step)
    gx, gy = reference.rectangle_face_gradient(x, y, a, b, PRESSURE, E_STAR)
    # Measured: 4.4e-10 of p / E* (step^2 truncation and round-off over 2 step).
    unit = PRESSURE / E_STAR
    for name, got, want in (("du/dx", gx, fx), ("du/dy", gy, fy)):
        err = np.max(np.abs(got - want)) / unit
        assert err < 5e-9, f"{name} against central differences: {err:.1e} p/E*"


def test_rectangle_on_edges_and_corners():
    a, b = 1e-3, 2e-3
    args = (a, b, PRESSURE, E_STAR)
    on = [(a, 0.3 * b), (-a, -0.9 * b), (0.4 * a, b), (-0.2 * a, -b),
          (a, b), (-a, b), (a, -b), (-a, -b)]
    x, y = np.array(on).T
    # The face is continuous: on the boundary it is the limit from both sides.
    u = reference.rectangle_face(x, y, *args)
    assert np.all(np.isfinite(u)), f"face on the boundary not finite: {u}"
    for sx, sy in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1)):
        near = reference.rectangle_face(x + sx * 1e-12 * a, y + sy * 1e-12 * a, *args)
        # The slope is ~ ln(1e-12): a step of 1e-12 a moves u by ~1e-11 (measured 9e-12).
        assert _rel(near, u) < 1e-10, f"face jumps at the boundary (step {sx, sy})"
    gx, gy = reference.rectangle_face_gradient(x, y, *args)
    assert not np.any(np.isnan(gx) | np.isnan(gy)), "NaN slope on the boundary"
    # Normal component infinite, u falling outwards; tangential finite; both at corners.
    assert gx[0] == -np.inf and gx[1] == np.inf, f"du/dx on x = +-a: {gx[:2]}"
    assert np.all(np.isfinite(gy[:2])), f"du/dy along x = +-a: {gy[:2]}"
    assert gy[2] == -np.inf and gy[3] == np.inf, f"du/dy on y = +-b: {gy[2:4]}"
    assert np.all(np.isfinite(gx[2:4])), f"du/dx along y = +-b: {gx[2:4]}"
    assert np.all(np.isinf(gx[4:]) & np.isinf(gy[4:])), f"corners: {gx[4:]}, {gy[4:]}"
    assert np.all(np.sign(gx[4:]) == -np.sign(x[4:])), "corners: u falls outwards"
    # On the edges' extensions outside the rectangle the slope is finite and continuous.
    x, y = np.array([a, a, -a, 0.5 * a]), np.array([1.5 * b, -4 * b, 2 * b, 3 * b])
    g = np.array(reference.rectangle_face_gradient(x, y, *args))
    g_near = np.array(reference.rectangle_face_gradient(x * (1 + 1e-9), y, *args))
    assert np.all(np.isfinite(g)), f"slope on the edges' extensions: {g}"
    # Measured 5e-10 relative (the slope's own variation over 1e-9 a).
    assert _rel(g_near, g) < 1e-8, "slope jumps across an edge's extension"


def test_rectangle_symmetries():
    a, b = 1e-3, 3e-3
    rng = np.random.default_rng(1618)
    x, y = rng.uniform(-2 * b, 2 * b, (2, 50))
    u = reference.rectangle_face(x, y, a, b, PRESSURE, E_STAR)
    gx, gy = reference.rectangle_face_gradient(x, y, a, b, PRESSURE, E_STAR)
    ut = reference.rectangle_face(y, x, b, a, PRESSURE, E_STAR)
    gxt, gyt = reference.rectangle_face_gradient(y, x, b, a, PRESSURE, E_STAR)
    assert _rel(ut, u) < 1e-15, "face not symmetric under transposition"
    assert _rel(gyt, gx) < 1e-15 and _rel(gxt, gy) < 1e-15, "slopes not transposed"
    gxm, gym = reference.rectangle_face_gradient(-x, y, a, b, PRESSURE, E_STAR)
    assert np.array_equal(gxm, -gx) and np.array_equal(gym, gy), "du/dx not odd in x"
    # Scale: lengths times 10 multiply u by 10 and leave the slope unchanged.
    u10 = reference.rectangle_face(10 * x, 10 * y, 10 * a, 10 * b, PRESSURE, E_STAR)
    g10 = reference.rectangle_face_gradient(10 * x, 10 * y, 10 * a, 10 * b, PRESSURE, E_STAR)[0]
    assert _rel(u10, 10 * u) < 1e-14 and _rel(g10, gx) < 1e-14, "not scale-invariant"


# -- disk at any r ------------------------------------------------------------

def test_disk_face_continuity_centre_far_field():
    a = 2e-3
    unit = PRESSURE * a / E_STAR
    centre = reference.disk_face(0.0, a, PRESSURE, E_STAR)
    assert centre == pytest.approx(2 * unit, rel=1e-15), "centre value 2 p a / E*"
    rim = reference.disk_face(a, a, PRESSURE, E_STAR)
    assert rim == pytest.approx(4 / math.pi * unit, rel=1e-15), "rim value 4 p a / (pi E*)"
    for side in (1 - 1e-12, 1 + 1e-12):
        near = reference.disk_face(side * a, a, PRESSURE, E_STAR)
        # Slope ~ ln: a step of 1e-12 a moves u by ~3e-11 of p a / E*.
        assert abs(near - rim) < 1e-10 * unit, f"face jumps at the rim ({side}): {near - rim:.1e}"
    # Far field F / (pi E* r) (1 + a^2 / (8 r^2) + O(r^-4)), without cancellation to r = 1e8 a.
    force = math.pi * a**2 * PRESSURE
    r = a * np.array([10.0, 1e2, 1e4, 1e8])
    got = reference.disk_face(r, a, PRESSURE, E_STAR)
    want = force / (math.pi * E_STAR * r) * (1 + a**2 / (8 * r**2))
    err = np.abs(got / want - 1)
    assert np.all(err < np.maximum((a / r) ** 4, 1e-14)), f"far field: {err}"
    slope = reference.disk_face_slope(r, a, PRESSURE, E_STAR)
    want = -force / (math.pi * E_STAR * r**2) * (1 + 3 * a**2 / (8 * r**2))
    err = np.abs(slope / want - 1)
    assert np.all(err < np.maximum((a / r) ** 4, 1e-14)), f"far-field slope: {err}"


def test_disk_inside_is_the_cylinder():
    """Inside the disk: eq. 10 and its derivative, written out with Legendre's integrals."""
    a = 2e-3
    r = np.linspace(0.0, a, 41)
    face = reference.disk_face(r, a, PRESSURE, E_STAR)
    unit = reference.disk_reference_slope(PRESSURE, E_STAR)  # 4 p / (pi E*)
    cylinder = 4 * PRESSURE * a / (np.pi * E_STAR) * special.ellipe((r / a) ** 2)
    assert np.array_equal(face, cylinder), "disk_face inside differs from eq. 10"
    k = r[1:-1] / a
    slope = reference.disk_face_slope(r[1:-1], a, PRESSURE, E_STAR)
    want = unit * (special.ellipe(k**2) - special.ellipk(k**2)) / k
    # Carlson's R_D against E - K: measured 4e-15 of the reference slope.
    err = np.max(np.abs(slope - want)) / unit
    assert err < 1e-13, f"disk_face_slope inside differs from (E - K) / k by {err:.1e}"
    assert reference.disk_face_slope(0.0, a, PRESSURE, E_STAR) == 0.0, "zero on the axis"
    assert reference.disk_face_slope(a, a, PRESSURE, E_STAR) == -np.inf, "rim slope is -inf"


@pytest.mark.parametrize("rho", [0.1, 0.55, 0.97, 1.03, 1.6, 7.0])
def test_disk_slope_is_the_derivative(rho):
    a = 2e-3
    r, step = rho * a, 1e-6 * a
    fd = (reference.disk_face(r + step, a, PRESSURE, E_STAR)
          - reference.disk_face(r - step, a, PRESSURE, E_STAR)) / (2 * step)
    got = reference.disk_face_slope(r, a, PRESSURE, E_STAR)
    # Measured below 2.5e-10 of 4 p / (pi E*) (round-off over 2 step; truncation
    # ~ step^2 / |r - a|^2 near the rim).
    unit = reference.disk_reference_slope(PRESSURE, E_STAR)
    assert abs(got - fd) < 2e-9 * unit, f"r = {rho} a: slope {got:.6e}, differences {fd:.6e}"


# -- annulus ------------------------------------------------------------------

def _chord(r, radius, phi):
    """Length of a ray inside the disk ``radius``.

    The ray starts at distance ``r`` from the centre, at angle ``phi`` from
    the outward radial direction.
    """
    disc = radius**2 - (r * math.sin(phi)) ** 2
    if r < radius:
        return -r * math.cos(phi) + math.sqrt(disc)
    return 2 * math.sqrt(disc) if disc > 0 and math.cos(phi) < 0 else 0.0


def _direct_annulus(r, inner, outer):
    """Eq. 8 in polar coordinates about the point: u = p / (pi E*) int chord length d phi."""
    points = [math.pi - math.asin(R / r) for R in (inner, outer) if r > R]
    value, _ = integrate.quad(lambda phi: _chord(r, outer, phi) - _chord(r, inner, phi),
                              0.0, math.pi, points=points or None, epsabs=1e-14, epsrel=1e-13,
                              limit=200)
    return 2 * PRESSURE / (math.pi * E_STAR) * value


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.5, 0.72, 1.0, 1.6, 4.0])
def test_annulus_against_direct_integral(rho):
    inner, outer = 1e-3, 2e-3
    r = rho * outer
    got = reference.annulus_face(r, inner, outer, PRESSURE, E_STAR)
    want = _direct_annulus(r, inner, outer)
    # Measured below 1.2e-15 relative (quadrature to 1e-13).
    assert got == pytest.approx(want, rel=1e-12), f"annulus face at r = {rho} a"
    centre = 2 * PRESSURE * (outer - inner) / E_STAR
    if rho == 0.0:
        assert got == pytest.approx(centre, rel=1e-15), "centre value 2 p (a - c) / E*"


def test_annulus_slope_and_rims():
    inner, outer = 1e-3, 2e-3
    r = np.array([0.0, 0.4, 1.0, 1.7, 2.0, 3.0]) * 1e-3
    s = reference.annulus_face_slope(r, inner, outer, PRESSURE, E_STAR)
    assert s[0] == 0 and s[2] == np.inf and s[4] == -np.inf, f"centre and rims: {s}"
    assert s[1] > 0 and s[3] < 0 and s[5] < 0, f"signs (rising in the hole, falling out): {s}"
    want = (reference.disk_face_slope(r, outer, PRESSURE, E_STAR)
            - reference.disk_face_slope(r, inner, PRESSURE, E_STAR))
    assert np.array_equal(s, want), "annulus slope is not the difference of the disks'"


def test_annulus_halfspace_converges():
    """The n x n pixel annulus converges to the closed form, first order (staircase rims)."""
    inner, outer = 1e-3, 2e-3
    sizes = np.array([24, 35, 48, 71, 96, 143, 192])
    errors = []
    for n in sizes:
        h = 2 * outer / n
        x = (np.arange(n) + 0.5) * h - outer
        r = np.hypot(x[:, None], x[None, :])
        load = np.where((r > inner) & (r < outer), PRESSURE, 0.0)
        u = HalfSpace(n, h, E_STAR).displacement(load)
        want = reference.annulus_face(r, inner, outer, PRESSURE, E_STAR)
        errors.append(np.max(np.abs(u - want)) / (PRESSURE * outer / E_STAR))
    order = -np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    # Measured: order 1.08, largest error 0.0067 p a / E* at n = 192 (first order: the
    # staircase misplaces the rims by O(h); the fit scatters by ~0.2 with the rasterisation).
    assert 0.8 < order < 1.4, f"observed order {order:.2f}, errors {errors}"
    assert errors[-1] < 0.01, f"error at n = {sizes[-1]}: {errors[-1]:.1e} p a / E*"


# -- rms-slope factors --------------------------------------------------------

def _tanh_sinh(level):
    """Tanh-sinh rule on [0, 1]: nodes and weights."""
    step = 2.0**-level
    tau = np.arange(-np.ceil(3.5 / step), np.ceil(3.5 / step) + 1) * step
    u = 0.5 * np.pi * np.sinh(tau)
    return special.expit(2 * u), step * 0.25 * np.pi * np.cosh(tau) / np.cosh(u) ** 2


def _exp_sinh(level):
    """Exp-sinh rule on (0, inf): log-singular at 0, algebraic decay at infinity."""
    step = 2.0**-level
    tau = np.arange(np.floor(-4.5 / step), np.ceil(3.2 / step) + 1) * step
    x = np.exp(0.5 * np.pi * np.sinh(tau))
    return x, step * 0.5 * np.pi * np.cosh(tau) * x


def _exterior_energy(a, b, level=5):
    """Integral of |grad u|^2 outside the rectangle (unit pressure and modulus).

    The quadrant's exterior is (a, inf) x (0, b), (0, a) x (b, inf) and
    (a, inf) x (b, inf): exp-sinh along the unbounded sides, which reaches
    the far field (|grad u|^2 ~ r^-4) without a cut-off, tanh-sinh along the
    bounded ones.  Nodes closer to an edge than the spacing of doubles land
    on it, where the slope is infinite; they are dropped (their share is
    ~1e-14).
    """
    t, w = _tanh_sinh(level)
    s, v = _exp_sinh(level)

    def part(x, wx, y, wy):
        gx, gy = reference.rectangle_face_gradient(x[:, None], y[None, :], a, b, 1.0, 1.0)
        f = gx**2 + gy**2
        return wx @ np.where(np.isfinite(f), f, 0.0) @ wy

    inside_x, inside_y = (a * t, a * w), (b * t, b * w)
    outside_x, outside_y = (a + a * s, a * v), (b + b * s, b * v)
    return 4 * (part(*outside_x, *inside_y) + part(*inside_x, *outside_y)
                + part(*outside_x, *outside_y))


@pytest.mark.parametrize("sides", [(1.0, 1.0), (1.0, 3.0), (0.3, 0.1), (2.0, 1.0)])
def test_rectangle_factor_by_the_whole_plane_identity(sides):
    """Whole-plane identity: interior (S^2 A) plus exterior = 4 p^2 A / E*^2."""
    a, b = sides
    area = 4 * a * b
    factor = reference.rectangle_rms_slope(a, b)
    total = factor**2 * area + _exterior_energy(a, b)
    # Measured defect: 2e-14.
    assert total / (4 * area) == pytest.approx(1.0, abs=1e-12), \
        f"{sides}: interior + exterior = {total / (4 * area):.15f} of 4 p^2 A / E*^2"


def _nested_quad_factor(beta):
    """S by nested adaptive quadrature (QUADPACK) over a quadrant.

    Half sides 1 and beta; the slope from the plain corner sums of asinh.
    """
    def asinh_ratio(X, Y):
        return math.asinh(Y / abs(X))

    def energy(y, x):
        gx = (asinh_ratio(x + 1, y + beta) - asinh_ratio(x - 1, y + beta)
              - asinh_ratio(x + 1, y - beta) + asinh_ratio(x - 1, y - beta))
        gy = (asinh_ratio(y + beta, x + 1) - asinh_ratio(y - beta, x + 1)
              - asinh_ratio(y + beta, x - 1) + asinh_ratio(y - beta, x - 1))
        return gx * gx + gy * gy

    def column(x):
        return integrate.quad(energy, 0.0, beta, args=(x,), epsabs=1e-14, epsrel=1e-13,
                              limit=200)[0]

    value, _ = integrate.quad(column, 0.0, 1.0, epsabs=1e-13, epsrel=1e-12, limit=200)
    return math.sqrt(value / (math.pi**2 * beta))


@pytest.mark.parametrize("beta, want", [(1.0, SQUARE), (3.0, ASPECT_3)])
def test_rectangle_factor_by_adaptive_quadrature(beta, want):
    got = reference.rectangle_rms_slope(1.0, beta)
    assert got == pytest.approx(want, rel=1e-14), f"1:{beta} factor {got!r}, pinned {want!r}"
    # Measured: 2e-14 (square), 1e-14 (1:3).
    assert got == pytest.approx(_nested_quad_factor(beta), rel=1e-12), \
        f"1:{beta} factor against nested adaptive quadrature"


def test_rectangle_factor_symmetry_scale_and_strip_limit():
    assert reference.rectangle_rms_slope(2.0) == pytest.approx(ASPECT_2, rel=1e-14), "1:2 factor"
    pairs = [(2e-3, 6e-3), (6e-3, 2e-3), (1.0, 3.0), (3.0, 1.0), (1 / 3, 1.0), (3.0,)]
    values = [reference.rectangle_rms_slope(*p) for p in pairs]
    assert all(v == values[0] for v in values), f"not symmetric or scale-invariant: {values}"
    # Long rectangles tend to the infinite strip, 2 / sqrt(3), from above: ends add ~ln(L)/L.
    aspects = [10.0, 1e2, 1e3, 1e4]
    factors = np.array([reference.rectangle_rms_slope(beta) for beta in aspects])
    assert np.all(np.diff(factors) < 0) and np.all(factors > STRIP), f"not monotone: {factors}"
    # Measured: (S - 2/sqrt(3)) beta = 0.35, 0.42, 0.43, 0.43.
    excess = (factors - STRIP) * np.array(aspects)
    assert np.all((excess > 0.3) & (excess < 0.5)), f"(S - strip) * aspect: {excess}"
    assert reference.rectangle_rms_slope(1.0) < reference.disk_rms_slope(), \
        "the square is rougher than the disk"


def test_annulus_factor():
    for ratio, want in ANNULI.items():
        got = reference.annulus_rms_slope(ratio)
        assert got == pytest.approx(want, rel=1e-14), f"ratio {ratio}: {got!r}, pinned {want!r}"

        # Adaptive quadrature of the E, K form of the slope.
        def slope(r, ratio=ratio):
            k, q = r * r, (ratio / r) ** 2
            return ((special.ellipe(k) - special.ellipk(k)) / r
                    - (special.ellipe(q) - special.ellipk(q)))

        value, _ = integrate.quad(lambda r: slope(r) ** 2 * r, ratio, 1.0, epsabs=1e-15,
                                  epsrel=1e-13, limit=200)
        quad = math.sqrt(32 / (math.pi**2 * (1 - ratio**2)) * value)
        # Measured: 1.4e-14 at most.
        assert got == pytest.approx(quad, rel=1e-12), f"ratio {ratio} against adaptive quadrature"
    assert reference.annulus_rms_slope(0.0) == pytest.approx(4 / math.pi, rel=1e-15), \
        "ratio 0 is the disk"
    # A small hole lowers S by O(ratio^2): measured 0.337 ratio^2 at 1e-2, 1e-3, 1e-4.
    for ratio in (1e-2, 1e-3, 1e-4):
        got = reference.annulus_rms_slope(ratio)
        assert 0 < 1 - got / (4 / math.pi) < 0.5 * ratio**2, f"ratio {ratio}: {got!r}"
    quadrature = reference.disk_normalised_rms_slope()
    assert reference.disk_rms_slope() == pytest.approx(4 / math.pi * quadrature, rel=1e-14), \
        "disk factor against eq. 12"
    # A thin ring is a strip bent round: S -> 2 / sqrt(3) (measured 5e-8 above at 0.9999).
    thin = reference.annulus_rms_slope(0.9999)
    assert 0 < thin - STRIP < 1e-6, f"thin ring {thin!r} against the strip {STRIP!r}"


@pytest.mark.parametrize("ratio", [0.0, 0.5])
def test_annulus_whole_plane_identity(ratio):
    """Whole-plane identity, disk and annulus: int |du/dr|^2 2 pi r dr = 4 p^2 A / E*^2."""
    outer = 2e-3
    inner = ratio * outer

    def slope(r):
        if inner == 0:
            return reference.disk_face_slope(r, outer, PRESSURE, E_STAR)
        return reference.annulus_face_slope(r, inner, outer, PRESSURE, E_STAR)

    def density(r):
        return slope(r) ** 2 * 2 * math.pi * r

    opts = dict(epsabs=0.0, epsrel=1e-13, limit=200)
    total = sum(integrate.quad(density, lo, hi, **opts)[0]
                for lo, hi in ((0.0, inner), (inner, outer)) if hi > lo)
    # Outside: r = outer / t.
    total += integrate.quad(lambda t: density(outer / t) * outer / t**2, 0.0, 1.0, **opts)[0]
    area = math.pi * (outer**2 - inner**2)
    want = 4 * PRESSURE**2 * area / E_STAR**2
    # Measured: 1.3e-14 at most (and the factor within 7e-15).
    assert total == pytest.approx(want, rel=1e-12), f"ratio {ratio}: {total / want - 1:.1e}"
    inside = integrate.quad(density, inner, outer, **opts)[0]
    factor = math.sqrt(inside / area) * E_STAR / PRESSURE
    want = reference.annulus_rms_slope(ratio)
    assert factor == pytest.approx(want, rel=1e-12), f"ratio {ratio}: factor {factor!r}"


# -- inputs -------------------------------------------------------------------

@pytest.mark.parametrize("call, fragment", [
    (lambda: reference.rectangle_face(0.0, 0.0, 0.0, 1.0, 1.0, 1.0),
     "half_width must be a number > 0 (m), got 0.0"),
    (lambda: reference.rectangle_face_gradient(0.0, 0.0, 1.0, -1.0, 1.0, 1.0),
     "half_length must be a number > 0 (m), got -1.0"),
    (lambda: reference.rectangle_face(0.0, 0.0, 1.0, 1.0, 1.0, 0.0),
     "E_star must be a number > 0 (Pa), got 0.0"),
    (lambda: reference.rectangle_rms_slope(1.0, np.inf),
     "length must be a number > 0 (m), got inf"),
    (lambda: reference.rectangle_rms_slope(0.0), "width must be a number > 0 (m), got 0.0"),
    (lambda: reference.disk_face(-1.0, 1.0, 1.0, 1.0), "r is a distance from the centre"),
    (lambda: reference.disk_face_slope(1.0, 0.0, 1.0, 1.0),
     "radius must be a number > 0 (m), got 0.0"),
    (lambda: reference.annulus_face(1.0, 2.0, 1.0, 1.0, 1.0),
     "inner_radius must be smaller than outer_radius"),
    (lambda: reference.annulus_face_slope(1.0, 0.0, 1.0, 1.0, 1.0),
     "inner_radius must be a number > 0 (m), got 0.0"),
    (lambda: reference.annulus_rms_slope(1.0), "ratio must be a number in [0, 1) (1), got 1.0"),
    (lambda: reference.annulus_rms_slope(-0.1), "ratio must be a number in [0, 1) (1), got -0.1"),
])
def test_bad_inputs_raise(call, fragment):
    with pytest.raises(ValueError) as err:
        call()
    assert fragment in str(err.value), f"{err.value!r} lacks {fragment!r}"
