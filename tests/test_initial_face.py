"""Initial recession fields of the punch face."""

import numpy as np
import pytest

from steady.outline import Circle, PeriodicCell
from transient import initial_face

RADIUS = 4e-3


def grid(n, radius=RADIUS):
    """The ``n x n`` grid over the disk of ``radius``."""
    return Circle(radius).grid(n)


@pytest.mark.parametrize("n", [15, 16])
def test_flat_is_zero(n):
    h = initial_face.flat(grid(n))
    assert h.shape == (n, n) and not h.any(), "a flat face has zero height"


@pytest.mark.parametrize("n", [15, 16])
@pytest.mark.parametrize("azimuth", [0.0, 0.9, -2.5])
def test_tilted_is_a_plane_receding_towards_the_azimuth(n, azimuth):
    angle = 0.02
    h = initial_face.tilted(grid(n), angle, azimuth)
    x = grid(n).x
    X, Y = np.meshgrid(x, x, indexing="ij")
    # Least-squares plane through the field: slope tan(angle) along the azimuth.
    design = np.column_stack([X.ravel(), Y.ravel(), np.ones(n * n)])
    gx, gy, c = np.linalg.lstsq(design, h.ravel(), rcond=None)[0]
    assert np.isclose(np.hypot(gx, gy), np.tan(angle), rtol=1e-12), "slope magnitude"
    assert np.isclose(np.arctan2(gy, gx), np.arctan2(np.sin(azimuth), np.cos(azimuth)),
                      atol=1e-12), "slope direction"
    assert np.isclose(c, np.tan(angle) * RADIUS, rtol=1e-12), "zero at the lowest rim point"
    face = grid(n).mask
    assert h[face].min() >= 0, "pixel centres lie inside the disk: heights non-negative"
    assert h[face].max() <= 2 * RADIUS * np.tan(angle), "at most 2 a tan(angle)"


@pytest.mark.parametrize("n", [15, 16])
def test_crowned_is_a_sphere_close_to_its_paraboloid(n):
    sphere = 0.08
    h = initial_face.crowned(grid(n), sphere)
    x = grid(n).x
    r2 = x[:, None] ** 2 + x[None, :] ** 2
    face = grid(n).mask
    assert np.allclose((sphere - h[face]) ** 2 + r2[face], sphere**2, rtol=1e-12, atol=0), (
        "points on the sphere")
    # Exact sphere vs paraboloid: r^4 / (8 R^3) at most.
    paraboloid = r2 / (2 * sphere)
    assert np.all(np.abs(h - paraboloid)[face] <= RADIUS**4 / (8 * sphere**3) * 1.01), (
        "sphere within r^4/(8R^3) of its paraboloid")
    assert h[face].min() >= 0, "heights non-negative"


def test_from_array_and_file_round_trip(tmp_path):
    n = 11
    rng = np.random.default_rng(61023)
    values = rng.normal(scale=1e-6, size=(n, n))
    values[0, 0] = np.nan  # off the face: ignored
    h = initial_face.from_array(values, grid(n))
    assert h is not values and np.array_equal(h, values, equal_nan=True), "a float copy"
    path = tmp_path / "face.npy"
    np.save(path, values)
    assert np.array_equal(initial_face.from_file(grid(n), path), values, equal_nan=True), "file"


@pytest.mark.parametrize("call, match", [
    (lambda: initial_face.flat(grid(1)), "n = 1,"),
    (lambda: initial_face.flat(grid(8, -1.0)), "radius"),
    (lambda: initial_face.flat(grid(8.5)), "grid size n .* 8.5"),
    (lambda: initial_face.flat(8), "grid"),
    (lambda: initial_face.tilted(grid(8), np.pi / 2), "angle"),
    (lambda: initial_face.tilted(grid(8), -0.1), "angle"),
    (lambda: initial_face.tilted(grid(8), 0.1, np.nan), "azimuth"),
    (lambda: initial_face.crowned(grid(8), 0.5 * RADIUS), "sphere_radius"),
    (lambda: initial_face.crowned(grid(8), np.inf), "sphere_radius"),
    (lambda: initial_face.from_array(np.zeros((8, 7)), grid(8)), "shape"),
    (lambda: initial_face.from_array(np.full((8, 8), np.inf), grid(8)), "finite"),
])
def test_bad_input_raises(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_from_file_needs_npy(tmp_path):
    path = tmp_path / "face.txt"
    path.write_text("0")
    with pytest.raises(ValueError, match="npy"):
        initial_face.from_file(grid(8), path)


@pytest.mark.parametrize("values, found", [
    (np.zeros((8, 8)) * (1 + 1e-6j), r"holds complex numbers \(complex128\)"),
    (np.ones((8, 8), dtype=bool), r"holds booleans \(bool\)"),
])
def test_a_face_of_complex_numbers_or_booleans_is_refused(tmp_path, values, found):
    # float() of a complex array keeps its real part, of a boolean one makes 0 and 1 m.
    with pytest.raises(ValueError, match=f"recession field {found}; it must hold real numbers"):
        initial_face.from_array(values, grid(8))
    np.save(tmp_path / "h.npy", values)
    with pytest.raises(ValueError, match=f"initial face file .*h.npy' {found}; it must hold "
                                         f"real numbers"):
        initial_face.from_file(grid(8), tmp_path / "h.npy")


@pytest.mark.parametrize("kind, parameters", [("tilted", {"angle": 1e-3}),
                                              ("crowned", {"sphere_radius": 0.05})])
def test_a_face_that_does_not_repeat_is_refused_on_a_periodic_cell(kind, parameters):
    """A tilt or a crown would jump at the cell's edges: refused, by kind and by function."""
    grid = PeriodicCell(8e-3, 4e-3).grid(32)
    expected = f"initial face kind '{kind}' on \\[punch\\] shape = \"periodic\""
    with pytest.raises(ValueError, match=expected):
        initial_face.initial_recession(kind, grid, **parameters)
    with pytest.raises(ValueError, match=expected):
        getattr(initial_face, kind)(grid, **parameters)
    with pytest.raises(ValueError, match="a periodic cell takes kind 'file' or 'flat'"):
        initial_face.check_outline(kind, grid.outline)
    assert initial_face.initial_recession(kind, Circle(4e-3).grid(32), **parameters).any()


def test_flat_and_a_file_are_taken_on_a_periodic_cell(tmp_path):
    """A flat face repeats; a file's field (a measured patch) is taken as it stands."""
    grid = PeriodicCell(8e-3, 4e-3).grid(32)
    assert not initial_face.initial_recession("flat", grid).any()
    field = np.random.default_rng(3301).random(grid.shape) * 1e-6
    np.save(tmp_path / "patch.npy", field)
    read = initial_face.initial_recession("file", grid, path=tmp_path / "patch.npy")
    assert np.array_equal(read, field), "the file's field as it stands"
    assert np.array_equal(initial_face.from_array(field, grid), field)
