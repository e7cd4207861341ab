"""Face outlines: grids, masks, areas, scene files, and phase maps on them."""

import math
import re

import numpy as np
import pytest
from conftest import OUTLINES, RADIUS, scene_text

from steady.array_files import read_face_mask
from steady.memory import fit_memory, steady_memory
from steady.outline import (
    MAX_GRID_SIZE,
    UNIT_DISK,
    Annulus,
    Circle,
    Ellipse,
    FaceGrid,
    MaskOutline,
    Rectangle,
    as_grid,
    as_outline,
    outline_from_table,
)
from steady.phases import ArrayMap, Homogeneous, Rods, Voronoi
from steady.problem import FacePhases, Problem
from steady.scene import parse_scene
from steady.solution import solve
from transient.memory import run_in_memory


@pytest.mark.parametrize("n", [31, 64])
def test_circle_grid_is_the_disk_grid(n):
    grid = Circle(RADIUS).grid(n)
    assert grid.shape == (n, n), f"shape {grid.shape}"
    # Pixel centres strictly inside the disk, tested exactly in integers:
    # (2i + 1 - n)^2 + (2j + 1 - n)^2 < n^2; the same mask for every radius.
    c = 2 * np.arange(n) + 1 - n
    disk = c[:, None] ** 2 + c[None, :] ** 2 < n * n
    assert np.array_equal(grid.mask, disk), "the circle's mask is the exact disk test"
    assert np.array_equal(UNIT_DISK.grid(n).mask, disk), "the unit disk's mask too"
    assert np.array_equal(as_grid(n).mask, disk), "and that of a bare n"
    # Centres -a + (i + 1/2) h, h = 2a / n, bit for bit.
    centres = -RADIUS + (np.arange(n) + 0.5) * (2.0 * RADIUS / n)
    unit = -1.0 + (np.arange(n) + 0.5) * (2.0 / n)
    assert np.array_equal(grid.x, centres), "pixel centres bit for bit"
    assert np.array_equal(grid.unit_y, unit), "unit centres bit for bit"
    assert np.array_equal(UNIT_DISK.grid(n).x, unit), "the unit disk's centres are the units"
    assert grid.h == 2 * RADIUS / n, f"pixel size {grid.h}"


def test_integer_grids_keep_their_labels():
    """A geometry rasterised on the disk's FaceGrid gives the labels of ``labels(n)``."""
    rods = Rods(((0.0, 0.0),), (0.5 * RADIUS,))         # on the disk of RADIUS
    for geometry, unit in ((Voronoi(64, (0.7, 0.3), 2029),) * 2,
                           (rods, Rods(((0.0, 0.0),), (0.5,)))):
        for n in (32, 45):
            old = unit.labels(n)
            new = geometry.labels(Circle(RADIUS).grid(n))
            assert np.array_equal(old, new), f"{geometry}: labels changed at n = {n}"


@pytest.mark.parametrize("n, shape", [(96, (32, 96)), (100, (33, 100)), (65, (22, 65))])
def test_rectangle_grid(n, shape):
    rect = OUTLINES["rectangle"]          # 1:3, long side along y
    grid = rect.grid(n)
    assert grid.shape == shape, f"n = {n}: shape {grid.shape}, expected {shape}"
    assert grid.mask.all(), "every pixel of a rectangle's grid is a face pixel"
    # The grid is centred: pixel centres symmetric about 0 to round-off.
    assert np.allclose(grid.x, -grid.x[::-1], atol=1e-15 * RADIUS), "x centred"
    assert np.allclose(grid.y, -grid.y[::-1], atol=1e-15 * RADIUS), "y centred"
    # Its realised width differs from the true one by less than a pixel.
    assert abs(shape[0] * grid.h - rect.width) <= 0.5 * grid.h + 1e-15, "width within h/2"


@pytest.mark.parametrize("name", ["annulus", "ellipse"])
def test_pixel_area_converges_to_the_exact_area(name):
    """The staircase's area error stays a small part of (rim length) x h at every grid.

    Counting pixel centres inside a curved outline errs by at most the rim's
    pixels; their errors partly cancel, irregularly in n (a lattice-point
    problem).  Measured at n = 31..1000: at most 0.053 P h / A.
    """
    outline = OUTLINES[name]
    if name == "annulus":
        rim = 2 * math.pi * (outline.inner_radius + outline.outer_radius)
    else:  # Ramanujan's perimeter of an ellipse (relative error below 1e-5 here)
        a, b = outline.half_extent
        rim = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))
    for n in (31, 64, 100, 255, 256, 512, 1000):
        grid = outline.grid(n)
        error = abs(grid.face_area / outline.area - 1)
        bound = 0.1 * rim * grid.h / outline.area
        assert error <= bound, f"{name}, n = {n}: area error {error:.2e} above {bound:.2e}"


def test_annulus_mask_and_resolution():
    ring = Annulus(2e-3, 4e-3)
    grid = ring.grid(64)
    r = np.hypot(grid.x[:, None], grid.y[None, :])
    assert np.array_equal(grid.mask, (r < 4e-3) & (r > 2e-3) & as_grid(64).mask), "ring mask"
    thin = Annulus(3.6e-3, 4e-3)            # ring 0.1 of the outer radius
    assert thin.min_grid() == 60, f"three pixels across the ring: {thin.min_grid()}"
    with pytest.raises(ValueError, match="grid too coarse for the annulus face.*n = 40, the "
                                         "minimum is n = 60"):
        thin.grid(40)
    with pytest.raises(ValueError, match="inner_radius must be smaller than outer_radius"):
        Annulus(4e-3, 4e-3)


def test_outline_areas_and_extents():
    cases = {
        "circle": (math.pi * RADIUS**2, (RADIUS, RADIUS)),
        "rectangle": (4 * RADIUS**2 / 3, (RADIUS / 3, RADIUS)),
        "annulus": (0.75 * math.pi * RADIUS**2, (RADIUS, RADIUS)),
        "ellipse": (0.5 * math.pi * RADIUS**2, (RADIUS, 0.5 * RADIUS)),
    }
    for name, (area, extent) in cases.items():
        outline = OUTLINES[name]
        assert math.isclose(outline.area, area, rel_tol=1e-14), f"{name}: area {outline.area}"
        assert np.allclose(outline.half_extent, extent, rtol=1e-14), f"{name}: extent"
        assert outline.scale == max(extent), f"{name}: scale {outline.scale}"


def test_mask_outline_refines_by_whole_factors():
    mask = np.zeros((12, 6), dtype=bool)
    mask[2:10, 1:5] = True
    mask[2:5, 1:3] = False                  # an L shape
    outline = MaskOutline(mask, 0.5e-3)
    assert math.isclose(outline.area, mask.sum() * 0.25e-6, rel_tol=1e-14), "area"
    grid = outline.grid(36)
    assert grid.shape == (36, 18), f"shape {grid.shape}"
    assert grid.mask.sum() == 9 * mask.sum(), "each mask pixel becomes 3 x 3 grid pixels"
    assert math.isclose(grid.face_area, outline.area, rel_tol=1e-13), "the face area is exact"
    assert np.array_equal(outline.contains(grid.x[:, None], grid.y[None, :]), grid.mask), \
        "contains() at the pixel centres is the refined mask"
    with pytest.raises(ValueError, match="must be a multiple of 12"):
        outline.grid(30)
    with pytest.raises(ValueError, match="has no face pixel"):
        MaskOutline(np.zeros((4, 4), dtype=bool), 1e-3)


def test_encloses_disk():
    rect = Rectangle(2e-3, 6e-3)
    assert rect.encloses_disk((0.0, 2e-3), 1e-3), "touching both long sides"
    assert not rect.encloses_disk((0.5e-3, 0.0), 0.6e-3), "crosses a long side"
    ring = Annulus(2e-3, 4e-3)
    assert ring.encloses_disk((3e-3, 0.0), 1e-3), "fills the ring's width"
    assert not ring.encloses_disk((2.5e-3, 0.0), 1e-3), "reaches into the hole"
    ellipse = Ellipse(4e-3, 2e-3)
    # Analytic: the circle of radius r at (c, 0) touches the ellipse x^2/a^2 + y^2/b^2 = 1
    # from inside when r^2 = b^2 (1 - c^2 / (a^2 - b^2)) for |c| < (a^2 - b^2) / a.
    c = 1e-3
    r = 2e-3 * math.sqrt(1 - c**2 / (16e-6 - 4e-6))
    assert ellipse.encloses_disk((c, 0.0), 0.999 * r), "just inside"
    assert not ellipse.encloses_disk((c, 0.0), 1.001 * r), "just outside"


def test_outline_from_table_and_errors():
    assert outline_from_table({"radius": 0.004}) == Circle(0.004)
    assert outline_from_table({"shape": "ellipse", "semi_axis_x": 1.0,
                               "semi_axis_y": 2.0}) == Ellipse(1.0, 2.0)
    bad = [
        ({"shape": "square", "side": 1.0}, "[punch] shape must be one of"),
        ({"shape": "rectangle", "width": 1.0}, "missing key 'length' in [punch]"),
        ({"shape": "rectangle", "width": 1.0, "length": 2.0, "radius": 1.0},
         "unknown key 'radius' in [punch] (shape 'rectangle'"),
        ({"shape": "rectangle", "width": -1.0, "length": 2.0},
         "[punch] width must be a number > 0 (m), got -1.0"),
        ({"shape": "annulus", "inner_radius": 2.0, "outer_radius": 1.0},
         "inner_radius must be smaller than outer_radius"),
        ({"shape": "mask", "path": "nowhere.npy", "pixel_size": 1e-3}, "does not exist"),
    ]
    for table, fragment in bad:
        with pytest.raises(ValueError) as err:
            outline_from_table(table, base_dir="/nonexistent")
        assert fragment in str(err.value), f"{table}: {err.value!r} lacks {fragment!r}"
    assert as_outline(0.004) == Circle(0.004), "a number is a disk's radius"
    with pytest.raises(ValueError, match=r"radius must be a number > 0 \(m\), got -1.0"):
        as_outline(-1.0)


def test_scene_files_with_outlines(tmp_path):
    punch = {"shape": "rectangle", "width": 0.004, "length": 0.012}
    text = scene_text("steady", n=96, punch=punch)
    scene = parse_scene(text, tmp_path)
    assert scene.outline == Rectangle(0.004, 0.012), "outline parsed"
    assert "radius" not in scene.outline.parameters(), "a rectangle has no radius"
    labels = scene.phase_labels()
    assert labels.shape == (32, 96), f"labels of shape {labels.shape}"
    counts = np.bincount(labels.ravel() + 1)
    assert counts[0] == 0 and counts[1:].sum() == 32 * 96, "the whole grid is the face"
    # Rods must fit the face, not only the disk around it.
    with pytest.raises(ValueError, match=r"rod 0 .* does not lie inside the face \(rectangle"):
        parse_scene(scene_text("steady", n=96, punch=punch, map="rods",
                               centres=[[0.0015, 0.0]], radii=[0.001]), tmp_path)
    # A grid too coarse for the outline's short side names both.
    with pytest.raises(ValueError, match=r"\[grid\] n: grid too coarse for the rectangle face"
                                         r".*n = 12, the minimum is n = 24"):
        parse_scene(scene_text("steady", n=12, punch=punch, map="homogeneous"), tmp_path)


def test_voronoi_seeds_fill_the_bounding_box():
    """Seeds are uniform in the face's box: the cells have the same size on every outline."""
    geometry = Voronoi(1200, (0.5, 0.5), 2718)
    rect = Rectangle(4e-3, 12e-3)
    points, phases = geometry.seeds(rect)
    assert np.all(np.abs(points[:, 0]) <= 2e-3) and np.all(np.abs(points[:, 1]) <= 6e-3), \
        "seeds inside the rectangle's box (m)"
    assert np.bincount(phases).tolist() == [600, 600], "seed counts of the fill factors"
    assert geometry.min_grid(rect) == 120, "two pixels per mean seed spacing"
    labels = geometry.labels(rect.grid(120))
    fill = np.bincount(labels.ravel()) / labels.size
    # 1200 cells: the realised fill factor scatters by about 1/sqrt(1200) = 0.03.
    assert abs(fill[1] - 0.5) < 0.06, f"realised fill factor {fill}"
    # The disk's seeds are unchanged by the generalisation.
    square, _ = geometry.seeds()
    expected = np.random.default_rng(2718).uniform(-1.0, 1.0, size=(1200, 2))
    assert np.array_equal(square, expected), "the disk's seeds bit for bit"


def test_array_map_on_a_rectangle():
    rect = Rectangle(2e-3, 6e-3)
    base = np.zeros((8, 24), dtype=int)
    base[:, 12:] = 1
    geometry = ArrayMap(base, outline=rect)
    labels = geometry.labels(rect.grid(48))
    assert labels.shape == (16, 48) and np.array_equal(labels[::2, ::2], base), \
        "pixel replication by 2"
    with pytest.raises(ValueError, match="has 24 x 8 pixels; the grid of the rectangle face"):
        ArrayMap(base.T.copy(), outline=rect)
    with pytest.raises(ValueError, match="not a multiple of the size 24"):
        geometry.labels(rect.grid(36))


def test_rectangle_steady_face_transposes():
    """Rectangle(w, l) and Rectangle(l, w) give transposed faces (a symmetry, to round-off)."""
    n, E_star, force = 48, 1.3e6, 10.0
    faces = []
    for outline in (Rectangle(2e-3, 6e-3), Rectangle(6e-3, 2e-3)):
        grid = outline.grid(n)
        labels = Homogeneous().labels(grid)
        res = solve(Problem(FacePhases(grid, labels, 1), [1e-13], force, E_star))
        faces.append(res)
    a, b = faces
    assert np.allclose(a.face, b.face.T, rtol=1e-12, atol=0), "faces transpose"
    assert math.isclose(a.reference_slope, b.reference_slope, rel_tol=1e-12), "same reference"
    assert math.isclose(a.rms_slope_plain, b.rms_slope_plain, rel_tol=1e-12), "same slope"
    assert math.isclose(a.mean_pressure, force / 12e-6, rel_tol=1e-14), "pbar = F / area"
    # Load conservation on the face.
    assert math.isclose(float(a.pressure.sum()) * (2e-3 / 16) ** 2, force, rel_tol=1e-13), \
        "the pressure carries the load"


def test_read_face_mask(tmp_path):
    from PIL import Image

    mask = np.zeros((10, 6), dtype=bool)
    mask[2:8, 1:5] = True
    np.save(tmp_path / "b.npy", mask)
    np.save(tmp_path / "i.npy", np.where(mask, 3, -1))
    assert np.array_equal(read_face_mask(tmp_path / "b.npy"), mask), "boolean .npy"
    assert np.array_equal(read_face_mask(tmp_path / "i.npy"), mask), "-1 off the face"
    rgba = np.zeros((10, 6, 4), dtype=np.uint8)
    rgba[..., 3] = np.where(mask, 255, 0)
    Image.fromarray(rgba).save(tmp_path / "a.png")
    assert np.array_equal(read_face_mask(tmp_path / "a.png"), mask), "opaque pixels of a PNG"
    Image.fromarray(rgba[..., 0]).save(tmp_path / "grey.png")
    with pytest.raises(ValueError, match="has no alpha channel"):
        read_face_mask(tmp_path / "grey.png")
    np.save(tmp_path / "f.npy", mask.astype(float))
    with pytest.raises(ValueError, match="must hold booleans"):
        read_face_mask(tmp_path / "f.npy")


def test_face_grid_refuses_an_empty_face():
    with pytest.raises(ValueError, match="grid size n must be an integer"):
        FaceGrid(Circle(1.0), 8.5)


@pytest.mark.parametrize("outline", [Circle(1.0), Rectangle(1.0, 3.0), Ellipse(1.0, 0.5)],
                         ids=["circle", "rectangle", "ellipse"])
def test_a_grid_beyond_the_address_space_is_refused(outline):
    """Up to MAX_GRID_SIZE a grid has a memory estimate; beyond, it is refused."""
    # An integer beyond 64 bits is shown in short: its 31 digits tell nothing.
    for n, shown in ((MAX_GRID_SIZE + 1, str(MAX_GRID_SIZE + 1)),
                     (np.int64(2**63 - 1), "9223372036854775807"), (10**30, "1e+30")):
        with pytest.raises(ValueError, match=rf"grid size n = {re.escape(shown)} is larger than "
                                             rf"{MAX_GRID_SIZE}: an n x n grid of 8-byte"):
            FaceGrid(outline, n)
    shape = FaceGrid(outline, MAX_GRID_SIZE).shape  # no array: the shape alone
    for estimate in (steady_memory(shape), run_in_memory(shape, 10),
                     fit_memory(shape, 2, (1000, 1000))):
        assert estimate > 8 * shape[0] * shape[1], f"estimate {estimate} of a {shape} grid"
