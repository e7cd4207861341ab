"""Half-space operator: exact pixel kernels and aperiodic FFT products."""

import numpy as np
import pytest
from scipy import integrate

from steady import reference
from steady.halfspace import HalfSpace, pixel_integral, pixel_integral_gradient
from steady.outline import UNIT_DISK


def _direct(p, h, E_star):
    """Dense O(nx^2 ny^2) sums of the exact pixel kernels."""
    nx, ny = p.shape
    cx, cy = np.arange(nx) * h, np.arange(ny) * h
    u = np.zeros((nx, ny))
    gx = np.zeros((nx, ny))
    gy = np.zeros((nx, ny))
    for i in range(nx):
        for j in range(ny):
            u += p[i, j] * pixel_integral(cx - cx[i], cy - cy[j], h)
            gx += p[i, j] * pixel_integral_gradient(cx - cx[i], cy - cy[j], h)
            gy += p[i, j] * pixel_integral_gradient(cy - cy[j], cx - cx[i], h).T
    s = 1 / (np.pi * E_star)
    return s * u, s * gx, s * gy


@pytest.mark.parametrize("point", [(0.3, 0.1), (1.7, -0.4), (-5.0, 3.0)])
def test_pixel_integral_against_quadrature(point):
    x, y = point
    want = integrate.dblquad(lambda yy, xx: 1 / np.hypot(x - xx, y - yy), -0.5, 0.5, -0.5, 0.5,
                             epsabs=1e-13)[0]
    got = pixel_integral(np.array([x]), np.array([y]), 1.0)[0, 0]
    assert got == pytest.approx(want, rel=1e-11), f"pixel integral at {point}"


def test_pixel_integral_at_the_centre():
    """Closed form at the centre of a square of side h: 4 h asinh(1)."""
    got = pixel_integral(np.array([0.0]), np.array([0.0]), 2.0)[0, 0]
    assert got == pytest.approx(8 * np.arcsinh(1.0), rel=1e-15), "centre value"


@pytest.mark.parametrize("point", [(0.3, 0.1), (1.7, -0.4), (-5.0, 3.0)])
def test_pixel_gradient_is_the_derivative(point):
    x, y = point
    eps = 1e-5
    fd = (pixel_integral(np.array([x + eps]), np.array([y]), 1.0)
          - pixel_integral(np.array([x - eps]), np.array([y]), 1.0))[0, 0] / (2 * eps)
    got = pixel_integral_gradient(np.array([x]), np.array([y]), 1.0)[0, 0]
    # Central differences: error ~ eps^2 f''' / 6, below 1e-8 here.
    assert got == pytest.approx(fd, abs=1e-8), f"gradient at {point}"


@pytest.mark.parametrize("n", [7, 8, 13, (7, 12), (12, 5), (2, 9)])
def test_products_match_dense_sums(n):
    """FFT products equal the dense sums to round-off (no wrap-around), square or not."""
    rng = np.random.default_rng(2718)
    hs = HalfSpace(n, 0.1, 2.0)
    p = rng.random(hs.shape)
    u, gx, gy = _direct(p, 0.1, 2.0)
    got_u = hs.displacement(p)
    got_gx, got_gy = hs.gradient(p)
    for name, a, b in (("u", got_u, u), ("gx", got_gx, gx), ("gy", got_gy, gy)):
        err = np.max(np.abs(a - b)) / np.max(np.abs(b))
        assert err < 1e-13, f"n={n}: {name} differs from the dense sum by {err:.1e}"


def test_product_reuse_does_not_alias():
    """Work buffers are reused: earlier results must stay intact."""
    rng = np.random.default_rng(3141)
    hs = HalfSpace(16, 1.0, 1.0)
    a, b = rng.random((16, 16)), rng.random((16, 16))
    ua = hs.displacement(a)
    keep = ua.copy()
    hs.displacement(b)
    hs.gradient(b)
    assert np.array_equal(ua, keep), "a later product overwrote an earlier result"


def test_threads_change_no_product():
    """Threads split the transforms, not the sums: the same numbers with one or two."""
    p = np.random.default_rng(5273).random((96, 80))
    one, two = (HalfSpace((96, 80), 1.0, 1.0, workers=w) for w in (1, 2))
    assert np.array_equal(one.displacement(p), two.displacement(p)), \
        "threads changed the product"


@pytest.mark.parametrize("n", [63, 64])
def test_uniform_disk_against_eq10(n):
    """Uniform pressure on the face: displacement vs eq. 10, error O(h)."""
    hs = HalfSpace(n, 2.0 / n, 1.0)
    grid = UNIT_DISK.grid(n)
    face = grid.mask
    p = np.where(face, 1.0 / (face.sum() * hs.h**2) * np.pi, 0.0)
    r, _ = grid.polar()
    u = hs.displacement(p)
    exact = reference.disk_face(r, 1.0, 1.0, 1.0)
    err = np.max(np.abs(u[face] - exact[face])) / (4 / np.pi)
    # Measured 2.2e-2 (n = 64) and 2.2e-2 (n = 63): the rim staircase.
    assert err < 3e-2, f"n={n}: eq. 10 face error {err:.2e}"


def test_far_field_is_a_point_load():
    """Far from a loaded pixel u -> F / (pi E* r)."""
    n = 64
    p = np.zeros((n, n))
    p[0, 0] = 1.0
    hs = HalfSpace(n, 1.0, 3.0)
    u = hs.displacement(p)
    r = 60.0
    want = 1.0 / (np.pi * 3.0 * r)
    # Quadrupole correction ~ h^2 / (24 r^2) relative.
    assert u[60, 0] == pytest.approx(want, rel=1e-4), "far field of one pixel"


@pytest.mark.parametrize("bad", [dict(n=1), dict(n=(8, 1)), dict(n=(8, 2.5)), dict(n=(2, 3, 4)),
                                 dict(h=0.0), dict(h=np.nan), dict(E_star=-1.0)])
def test_bad_arguments(bad):
    args = dict(n=8, h=1.0, E_star=1.0) | bad
    with pytest.raises(ValueError, match="must"):
        HalfSpace(args["n"], args["h"], args["E_star"])


def test_wrong_shape():
    with pytest.raises(ValueError, match="shape"):
        HalfSpace(8, 1.0, 1.0).displacement(np.zeros((8, 9)))
    with pytest.raises(ValueError, match=r"shape \(8, 9\)"):
        HalfSpace((8, 9), 1.0, 1.0).displacement(np.zeros((9, 8)))


def test_a_grid_is_its_shape():
    assert HalfSpace((8, 12), 1.0, 1.0).shape == (8, 12), "shape of a rectangular grid"
    assert HalfSpace(8, 1.0, 1.0).shape == (8, 8), "one n: a square grid"
    assert not hasattr(HalfSpace(8, 1.0, 1.0), "n"), "n means the longer side of a face's grid"


def test_transposed_grid_transposes_the_products():
    """Swapping the axes of the grid and of the pressure swaps the gradient components."""
    rng = np.random.default_rng(1618)
    p = rng.random((9, 14))
    a, b = HalfSpace((9, 14), 0.3, 1.0), HalfSpace((14, 9), 0.3, 1.0)
    gx, gy = a.gradient(p)
    gx_t, gy_t = b.gradient(p.T)
    assert np.allclose(a.displacement(p), b.displacement(p.T).T, rtol=1e-14, atol=0), "u"
    assert np.allclose(gx, gy_t.T, rtol=1e-13, atol=1e-16), "d/dx is d/dy of the transpose"
    assert np.allclose(gy, gx_t.T, rtol=1e-13, atol=1e-16), "d/dy is d/dx of the transpose"
    assert np.array_equal(a.aliased_symbol.shape, (9, 8)), "aliased symbol layout"


def test_operator_with_own_buffers_shares_spectra_and_gives_the_same_products():
    """Two threads' operators: spectra shared (read-only), buffers apart, products bitwise equal."""
    hs = HalfSpace((24, 17), 0.1, 2.0)
    own = hs.with_own_buffers(workers=1)
    assert own._influence_q is hs._influence_q and not own._influence_q.flags.writeable
    assert own._work is not hs._work and own._rows is not hs._rows and own.workers == 1
    p = np.random.default_rng(3).random((24, 17))
    assert np.array_equal(own.displacement(p), hs.displacement(p))


@pytest.mark.parametrize("shape", [(40, 54), (257, 300)])
def test_threaded_transforms_are_those_of_one_thread(shape):
    # Each thread transforms a block of whole lines, so the split changes no bit; at
    # (257, 300) the padded arrays are large enough to be split, into unequal blocks.
    p = np.random.default_rng(2713).random(shape)
    one, two = HalfSpace(shape, 1e-5, 1e6, workers=1), HalfSpace(shape, 1e-5, 1e6, workers=2)
    assert np.array_equal(one.displacement(p), two.displacement(p)), "displacement"
    for a, b in zip(one.gradient(p), two.gradient(p), strict=True):
        assert np.array_equal(a, b), "gradient"


@pytest.mark.parametrize("n", [7, 8, 13, (7, 12), (12, 5), (2, 9)])
def test_split_column_product_matches_dense_sums(n, monkeypatch):
    """The product with half-length column transforms (large grids) equals the dense sums."""
    from steady import halfspace

    monkeypatch.setattr(halfspace, "_SPLIT_ROWS", 2)
    rng = np.random.default_rng(2741)
    hs = HalfSpace(n, 0.1, 2.0)
    p = rng.random(hs.shape)
    u = _direct(p, 0.1, 2.0)[0]
    first = hs.displacement(p)
    err = np.max(np.abs(first - u)) / np.max(np.abs(u))
    assert err < 1e-13, f"n={n}: split product differs from the dense sum by {err:.1e}"
    hs.displacement(rng.random(hs.shape))
    assert np.array_equal(first, hs.displacement(p)), "work buffers leak between products"


def _child_product(n, queue):
    queue.put(HalfSpace(n, 1e-5, 1e6, workers=2).displacement(np.ones((n, n))))


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # fork of a threaded process
def test_threaded_product_in_a_forked_child():
    # The parent's transform threads do not survive a fork: the child makes its own
    # (without them, its first split transform would wait for ever).
    import multiprocessing

    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork on this platform")
    n = 260  # padded arrays above the size that is split among threads
    want = HalfSpace(n, 1e-5, 1e6, workers=2).displacement(np.ones((n, n)))
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_child_product, args=(n, queue), daemon=True)
    child.start()
    got = queue.get(timeout=60)
    child.join(timeout=60)
    assert np.array_equal(got, want), "the child's product differs"
