"""Cross sections, ring averages and differential profiles."""

import numpy as np
import pytest
from conftest import problem

from steady import reference
from steady.outline import Circle
from steady.phases import Homogeneous, Rods
from steady.profiles import cross_section, differential_profile, ring_average
from steady.solution import solve

RADIUS = 0.01  # m


def _face(n, geometry, k):
    return solve(problem(geometry, k, n=n, outline=RADIUS, force=35.0, E_star=1.3e6))


@pytest.mark.parametrize("n", [63, 64])
def test_cross_section_of_a_linear_field_is_exact(n):
    grid = Circle(RADIUS).grid(n)
    r, theta = grid.polar()
    x = r * np.cos(theta)
    field = np.where(grid.mask, 3.0 * x + 1.0, np.nan)
    d, v = cross_section(field, RADIUS, (-0.005, -0.002), (0.006, 0.003), 41)
    xs = np.linspace(-0.005, 0.006, 41)
    assert np.allclose(d[-1], np.hypot(0.011, 0.005), rtol=1e-14), f"length {d[-1]}"
    assert np.allclose(v, 3.0 * xs + 1.0, rtol=1e-12, atol=1e-14), "bilinear is exact on a plane"


def test_cross_section_nan_off_face_and_defined_to_rim():
    n = 64
    field = np.where(Circle(RADIUS).grid(n).mask, 1.0, np.nan)
    d, v = cross_section(field, RADIUS, (-1.2 * RADIUS, 0.0), (1.2 * RADIUS, 0.0), 241)
    x = np.linspace(-1.2, 1.2, 241)
    assert np.all(np.isnan(v[np.abs(x) > 1.0 + 1e-12])), "NaN beyond the rim"
    assert np.all(v[np.abs(x) <= 1.0] == 1.0), "values up to the rim, from face pixels only"


def test_ring_average_and_differential_profile_of_homogeneous_face():
    n = 128
    res = _face(n, Homogeneous(), [1e-13])
    r_ring, mean = ring_average(res.face, RADIUS, n // 2)
    exact = reference.disk_face(r_ring, RADIUS, res.mean_pressure, 1.3e6)
    relief = np.nanmax(res.face) - np.nanmin(res.face)
    # Rings one pixel wide average eq. 10 to within the grid error of the
    # face (measured at most 0.30 % of the relief).
    assert np.nanmax(np.abs(mean - exact)) < 0.01 * relief, "ring average vs eq. 10"
    _, diff = differential_profile(res.face, RADIUS, (-RADIUS, 0.0), (RADIUS, 0.0), 201)
    inner = np.abs(np.linspace(-1, 1, 201)) < 0.95
    # Axisymmetric face: the differential profile vanishes up to pixelation;
    # measured max 0.17 % of the relief inside r < 0.95 a.
    assert np.nanmax(np.abs(diff[inner])) < 0.01 * relief, \
        f"differential profile {np.nanmax(np.abs(diff[inner]))} vs relief {relief}"


def test_differential_profile_shows_hard_rod():
    n = 128
    # Hard central rod (low k): it carries more pressure and stands proud.
    res = _face(n, Rods(((0.0, 0.0), (0.6 * RADIUS, 0.0)), (0.25 * RADIUS,) * 2),
                [1.7e-13, 1.0e-13])
    _, diff = differential_profile(res.face, RADIUS, (-RADIUS, 0.0), (RADIUS, 0.0), 201)
    x = np.linspace(-1, 1, 201)
    over_rod = diff[np.abs(x - 0.6) < 0.1].mean()
    opposite = diff[np.abs(x + 0.6) < 0.1].mean()
    assert over_rod > 0 > opposite, f"rod at x=0.6a must stand proud: {over_rod}, {opposite}"


def test_bad_arguments():
    field = np.zeros((16, 16))
    with pytest.raises(ValueError, match="n_points must be an integer >= 2, got 1"):
        cross_section(field, RADIUS, (0, 0), (0.001, 0), 1)
    with pytest.raises(ValueError, match="n_bins must be an integer >= 1, got 0"):
        ring_average(field, RADIUS, 0)
    with pytest.raises(ValueError, match=r"radius must be a number > 0 \(m\), got -1.0"):
        ring_average(field, -1.0, 4)
    with pytest.raises(ValueError, match=r"field of shape \(16, 17\) is not on a grid of the "
                                         r"circle face"):
        ring_average(np.zeros((16, 17)), RADIUS, 4)
    with pytest.raises(ValueError, match=r"grid too coarse for the circle face .*: n = 5"):
        ring_average(np.zeros((4, 5)), RADIUS, 4)
