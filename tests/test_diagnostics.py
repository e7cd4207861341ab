"""The face's finite-difference gradient (transient.diagnostics.masked_gradient)."""

import numpy as np

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
