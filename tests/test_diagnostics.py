"""The face's finite-difference gradient (transient.diagnostics.masked_gradient)."""

import numpy as np
import pytest

from transient.diagnostics import masked_gradient


def _disk(n):
    i = np.arange(n) - (n - 1) / 2
    return i[:, None] ** 2 + i[None, :] ** 2 <= (n / 2) ** 2


def test_linear_field_is_differentiated_exactly_on_the_face():
    n, h = 33, 0.25
    face = _disk(n)
    face[0, :] = False
    face[5, 16] = False  # a hole: its neighbours take one-sided differences
    x = h * np.arange(n)
    field = 3.0 * x[:, None] - 2.0 * x[None, :]
    field[~face] = np.nan  # never read off the face
    gx, gy = masked_gradient(field, face, h)
    # Every face pixel has a face neighbour along each axis here.
    assert np.allclose(gx[face], 3.0, rtol=0, atol=1e-12)
    assert np.allclose(gy[face], -2.0, rtol=0, atol=1e-12)
    assert not gx[~face].any() and not gy[~face].any()


def test_quadratic_field_central_inside_one_sided_at_the_edge():
    n, h = 9, 0.5
    face = np.zeros((n, n), bool)
    face[2:7, 3] = True  # a column of five pixels: no neighbour along axis 1
    x = h * np.arange(n)
    field = np.broadcast_to((x ** 2)[:, None], (n, n)).copy()
    gx, gy = masked_gradient(field, face, h)
    column = gx[2:7, 3]
    # Central differences are exact for a quadratic: 2 x; one-sided ones are off by h.
    assert np.allclose(column[1:-1], 2 * x[3:6], rtol=0, atol=1e-12)
    assert np.isclose(column[0], 2 * x[2] + h) and np.isclose(column[-1], 2 * x[6] - h)
    assert not gy.any()


def test_isolated_pixel_has_zero_gradient():
    face = np.zeros((5, 5), bool)
    face[2, 2] = True
    gx, gy = masked_gradient(np.full((5, 5), 7.0), face, 1.0)
    assert not gx.any() and not gy.any()


# A face that repeats with a cell of nx x ny pixels: cosines of whole periods over each side.
_WAVES = ((1.0, 1, 0, 0.3), (0.5, 2, 3, 1.1), (0.25, 0, 1, -0.7))  # (amplitude, kx, ky, phase)


def _periodic_face(nx, ny, h):
    """The cosines on the cell's pixels, and the gradient of each after central differences."""
    x = h * np.arange(nx)[:, None]
    y = h * np.arange(ny)[None, :]
    face = np.zeros((nx, ny))
    exact = [np.zeros((nx, ny)), np.zeros((nx, ny))]
    central = [np.zeros((nx, ny)), np.zeros((nx, ny))]
    for amplitude, kx, ky, phase in _WAVES:
        qx, qy = 2 * np.pi * kx / (nx * h), 2 * np.pi * ky / (ny * h)
        arg = qx * x + qy * y + phase
        face += amplitude * np.cos(arg)
        for axis, q in enumerate((qx, qy)):
            derivative = -amplitude * q * np.sin(arg)
            exact[axis] += derivative
            # A central difference of cos(q x) is its derivative times sin(q h) / (q h).
            central[axis] += derivative * np.sinc(q * h / np.pi)
    return face, exact, central


@pytest.mark.parametrize("shape", [(24, 16), (25, 19)])
def test_periodic_face_central_differences_across_the_edges(shape):
    """On a cell every pixel, the edges' too, takes central differences by wrap-around.

    Each cosine's difference is its derivative times ``sin(qh) / (qh)``, to round-off
    (measured 3e-15 of the largest slope); the plain rms slope is the same wherever the cell's
    origin lies (np.roll of the face; measured 2e-16 relative), where the differences of a
    finite face, one-sided at the grid's edges, move with it.
    """
    nx, ny = shape
    h = 1.0 / nx
    face, _, central = _periodic_face(nx, ny, h)
    cell = np.ones(shape, bool)
    gx, gy = masked_gradient(face, cell, h, periodic=True)
    scale = max(np.abs(central[0]).max(), np.abs(central[1]).max())
    for axis, g in enumerate((gx, gy)):
        error = np.abs(g - central[axis]).max() / scale
        assert error < 1e-13, f"axis {axis}: central differences off by {error:.1e}"

    def rms(field, periodic):
        gx, gy = masked_gradient(field, cell, h, periodic=periodic)
        return np.sqrt(np.mean(gx * gx + gy * gy))

    reference = rms(face, True)
    for shift in [(1, 0), (0, 5), (7, 3), (nx // 2, ny - 1)]:
        rolled = rms(np.roll(face, shift, axis=(0, 1)), True)
        assert rolled == pytest.approx(reference, rel=1e-13, abs=0), f"roll {shift}"
    # The same face with one-sided differences at the edges (a finite face's): measured
    # 0.9 % to 1.8 % above, and 1e-3 apart between two origins.
    one_sided = [rms(np.roll(face, s, axis=(0, 1)), False) / reference - 1
                 for s in [(0, 0), (7, 3)]]
    assert min(one_sided) > 5e-3 and abs(one_sided[0] - one_sided[1]) > 5e-4, one_sided


def test_periodic_differences_converge_at_second_order():
    """Against the analytic derivative, the error falls as ``h^2``: order from a log-log fit.

    Measured order 1.99 over nx = 32 .. 256 (the sinc's ``(q h)^2 / 6`` and its next term).
    """
    sizes = np.array([32, 64, 128, 256])
    errors = []
    for nx in sizes:
        h = 1.0 / nx
        face, exact, _ = _periodic_face(nx, nx // 2 * 3 // 2, h)
        gx, gy = masked_gradient(face, np.ones(face.shape, bool), h, periodic=True)
        errors.append(max(np.abs(gx - exact[0]).max(), np.abs(gy - exact[1]).max()))
    order = -np.polyfit(np.log(sizes), np.log(errors), 1)[0]
    assert order == pytest.approx(2.0, abs=0.02), f"order {order:.3f}, errors {errors}"


def test_stride_takes_differences_over_wider_steps():
    """``stride = 2``: the central differences of a quadratic over ``2h`` on each side."""
    n, h = 12, 0.5
    x = h * np.arange(n)
    field = np.broadcast_to((x ** 2)[:, None], (n, 4)).copy()
    face = np.ones((n, 4), bool)
    gx, gy = masked_gradient(field, face, h, stride=2)
    assert np.allclose(gx[2:-2, :], 2 * x[2:-2, None], rtol=0, atol=1e-12), "central over 4h"
    # One-sided over 2h at the two pixels of each end: off by 2h.
    assert np.allclose(gx[:2, 0], 2 * x[:2] + 2 * h) and np.allclose(gx[-2:, 0], 2 * x[-2:] - 2 * h)
    assert not gy.any()
