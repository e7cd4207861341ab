"""DepthColumns: the phase below each pixel as a function of the worn depth."""

import numpy as np
import pytest

from steady.depth import DepthColumns


def _two_layer(shape=(3, 4), t=2e-6):
    """A coating (phase 1) of thickness ``t`` over a substrate (phase 0), pixel (0, 0) off."""
    z = np.full((1,) + shape, t)
    phases = np.stack([np.ones(shape, int), np.zeros(shape, int)])
    phases[:, 0, 0] = -1
    return DepthColumns(z, phases, 2)


def _ragged():
    """Pixels with 0, 1 and 2 interfaces (``+inf`` padding), three phases."""
    z = np.array([[[1.0, 2.0, np.inf]], [[np.inf, 3.0, np.inf]]])
    phases = np.array([[[0, 1, 2]], [[1, 0, 2]], [[1, 2, 2]]])
    return DepthColumns(z, phases, 3)


def test_a_depth_at_an_interface_is_in_the_segment_below():
    c = _two_layer()
    assert c.phase_at(2e-6 - 1e-12)[1, 1] == 1
    assert c.phase_at(2e-6)[1, 1] == 0
    assert c.phase_at(0.0)[0, 0] == -1


def test_ragged_columns_follow_each_pixel_own_interfaces():
    c = _ragged()
    depth = np.array([[0.5, 2.5, 7.0]])
    assert c.phase_at(depth).tolist() == [[0, 0, 2]]
    assert c.segment_at(depth).tolist() == [[0, 1, 0]]
    assert c.next_interface(depth).tolist() == [[1.0, 3.0, np.inf]]
    assert c.bottom.tolist() == [[1.0, 3.0, 0.0]]
    # Below its last interface a column keeps its last phase for ever.
    assert c.phase_at(1e9).tolist() == [[1, 2, 2]]
    assert c.columnar_below(np.array([[1.0, 3.0, 0.0]]))
    assert not c.columnar_below(np.array([[1.0, 2.9, 0.0]]))


def test_section_fractions_sum_to_one_and_count_face_pixels():
    c = _two_layer()
    assert c.fractions(0.0).tolist() == [0.0, 1.0]
    depth = np.zeros(c.shape)
    depth[2, :] = 5e-6  # one row of 4 worn through, of the 11 face pixels
    assert c.fractions(depth) == pytest.approx([4 / 11, 7 / 11], abs=0)


def test_a_columnar_map_has_no_interface():
    labels = np.array([[0, 1], [-1, 0]])
    c = DepthColumns.from_labels(labels, 2)
    assert c.columnar and c.n_interfaces == 0
    assert np.array_equal(c.phase_at(1.0), labels)
    assert np.all(np.isinf(c.next_interface(0.0)))
    assert not _two_layer().columnar


def test_columns_are_read_only_copies():
    z = np.full((1, 2, 2), 1.0)
    phases = np.stack([np.ones((2, 2), int), np.zeros((2, 2), int)])
    c = DepthColumns(z, phases, 2)
    z[:] = 5.0
    assert np.all(c.interfaces == 1.0)
    with pytest.raises(ValueError):
        c.interfaces[0, 0, 0] = 2.0


@pytest.mark.parametrize("change, message", [
    (lambda z, p: (z * -1.0, p, 3), "depth not positive below pixel (0, 0)"),
    (lambda z, p: (np.where(np.isinf(z), np.nan, z), p, 3), "depth NaN below pixel (0, 2)"),
    (lambda z, p: (z[::-1], p, 3), "not ascending below pixel (0, 0)"),
    (lambda z, p: (z, p, 2), "phase 2 at pixel (0, 2) is outside 0..1"),
    (lambda z, p: (z[:1], p, 3), "phases must have shape (S + 1, nx, ny) = (2, 1, 3)"),
    (lambda z, p: (z, p.astype(float), 3), "phases must be integers"),
    (lambda z, p: (z, np.where(np.arange(3)[:, None, None] == 1, -1, p), 3),
     "the face changes with depth at pixel (0, 0) (segment 1)"),
    (lambda z, p: (z, np.full_like(p, -1), 3), "no face pixel"),
    (lambda z, p: (z, np.minimum(p, 1), 3), "phase 2 occurs nowhere"),
    (lambda z, p: (z[0], p, 3), "interfaces must have shape (S, nx, ny)"),
])
def test_bad_columns_are_refused_naming_the_value(change, message):
    z = np.array([[[1.0, 2.0, np.inf]], [[np.inf, 3.0, np.inf]]])
    phases = np.array([[[0, 1, 2]], [[1, 0, 2]], [[1, 2, 2]]])
    with pytest.raises(ValueError) as err:
        DepthColumns(*change(z, phases))
    assert message in str(err.value)
