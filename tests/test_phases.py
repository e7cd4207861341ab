"""Phase geometries: rasterisation at any n, fill factors, validation."""

import math

import numpy as np
import pytest
from conftest import scene_text

from steady.array_files import LABELS, read_npy
from steady.labels import realised_fill_factors, validate_labels
from steady.outline import Circle, as_grid
from steady.phases import ArrayMap, Homogeneous, Rods, Voronoi, load_phase_map
from steady.scene import parse_scene

FIVE_RODS = Rods(((0.0, 0.0), (0.6, 0.0), (0.0, 0.6), (-0.6, 0.0), (0.0, -0.6)), (0.25,) * 5)


@pytest.mark.parametrize("n", [8, 33, 64])
def test_homogeneous_labels_follow_face_mask(n):
    labels = Homogeneous().labels(n)
    on_face = as_grid(n).mask
    assert labels.shape == (n, n), f"shape {labels.shape}"
    assert np.all(labels[on_face] == 0), "face pixels must be phase 0"
    assert np.all(labels[~on_face] == -1), "pixels off the face must be -1"


@pytest.mark.parametrize("n", [81, 128])
def test_voronoi_is_deterministic_and_matches_seed_counts(n):
    geo = Voronoi(400, (0.3, 0.7), 2718)
    again = Voronoi(400, [0.3, 0.7], 2718)
    assert np.array_equal(geo.labels(n), again.labels(n)), "same parameters, same map"
    counts = np.bincount(geo.seed_phases, minlength=2)
    assert counts.tolist() == [120, 280], f"seed labels {counts} do not match round(rho N)"
    other = Voronoi(400, (0.3, 0.7), 2719).labels(n)
    assert not np.array_equal(geo.labels(n), other), "another seed must give another map"


def test_voronoi_realised_fill_factors_scatter_around_targets():
    # Area fractions of 1600 random cells scatter by ~ 1 / sqrt(1600) ~ 0.025
    # around the seed fractions; measured |error| 0.004..0.02 over seeds 3101..3105.
    for seed in range(3101, 3106):
        rho = realised_fill_factors(Voronoi(1600, (0.5, 0.5), seed).labels(160), 2)
        assert abs(rho[1] - 0.5) < 0.05, f"seed {seed}: rho_2 = {rho[1]}"
        assert math.isclose(rho.sum(), 1.0, rel_tol=1e-12), f"fill factors sum {rho.sum()}"


def test_voronoi_three_phases_rasterised_at_several_n_is_the_same_geometry():
    geo = Voronoi(100, (0.2, 0.3, 0.5), 5077)
    coarse, fine = geo.labels(40), geo.labels(160)
    assert geo.n_phases == 3, f"n_phases {geo.n_phases}"
    # Cell edges move by up to a coarse pixel between the two grids, so the
    # area fractions agree to O(h / cell size); measured max difference 0.0023.
    r_c, r_f = realised_fill_factors(coarse, 3), realised_fill_factors(fine, 3)
    assert np.allclose(r_c, r_f, atol=0.03), f"fill factors {r_c} at n=40 vs {r_f} at n=160"


def test_rods_labels_and_fill_factor():
    n = 200
    labels = FIVE_RODS.labels(n)
    rho = realised_fill_factors(labels, 2)
    exact = 5 * 0.25**2  # area fraction of five rods of radius a/4
    # Pixelated disks: area error ~ perimeter * h / area; measured 0.0008 at n=200.
    assert abs(rho[1] - exact) < 0.005, f"rod fill factor {rho[1]} vs {exact}"
    c = n // 2
    assert labels[c, c] == 1, "centre pixel lies in the central rod"


def test_rods_custom_phases():
    geo = Rods(((0.0, 0.0), (0.5, 0.0)), (0.2, 0.2), matrix_phase=2, rod_phases=(0, 1))
    rho = realised_fill_factors(geo.labels(64), geo.n_phases)
    assert geo.n_phases == 3, f"n_phases {geo.n_phases}"
    assert rho[2] > rho[0], f"matrix must hold most of the face: {rho}"


@pytest.mark.parametrize("k", [1, 2, 3])
def test_array_map_replication(k):
    n0 = 20
    base = Voronoi(25, (0.4, 0.6), 9151).labels(n0)
    geo = ArrayMap(base)
    fine = geo.labels(k * n0)
    on_face = as_grid(k * n0).mask
    assert np.all(fine[~on_face] == -1), "off-face pixels must be -1"
    assert np.all(fine[on_face] >= 0), "every face pixel of the refined grid must be labelled"
    coarse_mask = as_grid(n0).mask
    replicated = np.kron(base, np.ones((k, k), dtype=int))
    both = on_face & np.kron(coarse_mask, np.ones((k, k), dtype=bool))
    assert np.array_equal(fine[both], replicated[both]), "replication must keep the labels"


def test_array_map_ignores_labels_off_face():
    base = Homogeneous().labels(16)
    base[0, 0] = 7  # corner pixel, off the face
    geo = ArrayMap(base)
    assert geo.n_phases == 1, f"an off-face label must be ignored, n_phases {geo.n_phases}"
    assert geo.labels(16)[0, 0] == -1, "off-face pixel must read -1"


def test_load_npy_and_png(tmp_path):
    import matplotlib.image

    labels = Rods(((0.0, 0.0),), (0.5,)).labels(32)
    np.save(tmp_path / "m.npy", labels)
    from_npy = load_phase_map(tmp_path / "m.npy")
    assert np.array_equal(from_npy.labels(32), labels), ".npy map must round-trip"
    # Grey PNG: rod dark (0.2), matrix light (0.8), off face white.
    grey = np.where(labels == 1, 0.2, np.where(labels == 0, 0.8, 1.0))
    matplotlib.image.imsave(tmp_path / "m.png", np.repeat(grey[..., None], 3, axis=2))
    from_png = load_phase_map(tmp_path / "m.png")
    # Phases numbered by increasing grey: dark rod -> 0, light matrix -> 1.
    expected = np.where(labels == 1, 0, np.where(labels == 0, 1, -1))
    assert np.array_equal(from_png.labels(32), expected), ".png map must number by grey level"


@pytest.mark.parametrize("fill, fragment", [
    ((0.5, 0.6), "sum to 1"),
    ((1.2, -0.2), "(0, 1)"),
    ((0.0, 1.0), "(0, 1)"),
    ((1.0,), "at least two"),
])
def test_bad_fill_factors(fill, fragment):
    with pytest.raises(ValueError, match=None) as err:
        Voronoi(100, fill, 2024)
    assert fragment in str(err.value), f"message {err.value!r} lacks {fragment!r}"
    assert str(list(fill)[0]) in str(err.value), f"message {err.value!r} must name the values"


@pytest.mark.parametrize("n_seeds, seed, fragment", [
    (0, 2024, "n_seeds must be an integer >= 1, got 0"),
    (100.0, 2024, "n_seeds must be an integer >= 1, got 100.0"),
    (100, -1, "seed must be an integer >= 0, got -1"),
    (100, True, "seed must be an integer >= 0, got True"),
])
def test_bad_seeds(n_seeds, seed, fragment):
    with pytest.raises(ValueError) as err:
        Voronoi(n_seeds, (0.5, 0.5), seed)
    assert fragment in str(err.value), f"message {err.value!r} lacks {fragment!r}"


def test_too_few_seeds_for_a_phase():
    with pytest.raises(ValueError, match="phase 1 would get no seed"):
        Voronoi(10, (0.99, 0.01), 2024)


@pytest.mark.parametrize("geo, n, minimum", [
    (Voronoi(1600, (0.5, 0.5), 2024), 79, 80),
    (Voronoi(1601, (0.5, 0.5), 2024), 80, 81),
    (FIVE_RODS, 23, 24),
    (Homogeneous(), 7, 8),
])
def test_grid_too_coarse(geo, n, minimum):
    with pytest.raises(ValueError, match=f"n = {n}, the minimum is n = {minimum}"):
        geo.labels(n)
    assert geo.labels(minimum).shape == (minimum, minimum), "the minimum itself is accepted"


def test_array_map_needs_multiple_of_its_size():
    geo = ArrayMap(Homogeneous().labels(16))
    with pytest.raises(ValueError, match="n = 24 is not a multiple of the size 16"):
        geo.labels(24)
    with pytest.raises(ValueError, match="n = 8, the minimum is n = 16"):
        geo.labels(8)


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(centres=((0.0, 0.0), (0.3, 0.0)), radii=(0.2, 0.2)), "rods 0 and 1 overlap"),
    (dict(centres=((0.0, 0.0),), radii=(-0.1,)),
     "rod radii must be an array of numbers each > 0 (m), got [-0.1]"),
    (dict(centres=((0.0, math.nan),), radii=(0.1,)),
     "rod centres must be an array of [x, y] pairs (m), got [[0.0, nan]]"),
    (dict(centres=((0.0, 0.0),), radii=(0.1,), matrix_phase=-1),
     "matrix_phase must be an integer >= 0, got -1"),
    (dict(centres=((0.0, 0.0),), radii=(0.1,), rod_phases=(1.0,)),
     "rod_phases must be an array of integers each >= 0, got [1.0]"),
    (dict(centres=((0.0, 0.0),), radii=(0.2,), rod_phases=(2,)), "phase 1 is used by neither"),
    (dict(centres=(), radii=()), "at least one rod"),
    (dict(centres=0.0, radii=(0.1,)), "rods need sequences of centres [x, y]"),
])
def test_bad_rods(kwargs, fragment):
    with pytest.raises(ValueError) as err:
        Rods(**kwargs)
    assert fragment in str(err.value), f"message {err.value!r} lacks {fragment!r}"


def test_rods_outside_the_face_are_refused_on_rasterising():
    rods = Rods(((0.9, 0.0),), (0.2,))
    with pytest.raises(ValueError, match=r"rod 0 \(centre \(0.9, 0\) m, radius 0.2 m\) does "
                                         r"not lie inside the face \(circle face \(radius "
                                         r"1000 mm\)\)$"):
        rods.labels(32)


def test_rods_in_metres_give_the_labels_of_the_scene_file():
    """Rods of 1 mm on a disk of 5 mm, built in m, are the scene file's rods, pixel for pixel."""
    centres, radii = [(0.0, 0.0), (2.5e-3, 0.0), (-1.5e-3, 2.5e-3)], [1e-3, 1e-3, 0.8e-3]
    text = scene_text("parser", map="rods", radius=5e-3, n=96, centres=centres, radii=radii)
    scene = parse_scene(text, ".")
    rods = Rods(centres=centres, radii=radii)
    assert scene.geometry == rods, scene.geometry
    labels = rods.labels(Circle(5e-3).grid(96))
    assert np.array_equal(labels, scene.phase_labels()), "labels differ from the scene's"
    # On the unit disk (a bare n), the rods divided by L = 5 mm give the same pixels.
    unit = Rods([(x / 5e-3, y / 5e-3) for x, y in centres], [r / 5e-3 for r in radii])
    assert np.array_equal(labels, unit.labels(96)), "the same rods scaled to the unit disk"
    assert rods.min_grid(Circle(5e-3)) == 38 and unit.min_grid() == 38, \
        "three pixels per radius of the smallest rod: 6 / 0.16"


def test_rods_too_small_for_the_grid_are_named_in_metres():
    rods = Rods(centres=[(0.0, 0.0), (2.5e-3, 0.0)], radii=[1e-3, 1e-3])
    with pytest.raises(ValueError, match=r"grid too coarse for rods of radius 0.001 m \(3 pixels "
                                         r"per radius\) on the circle face \(radius 5 mm\): "
                                         r"n = 24, the minimum is n = 30"):
        rods.labels(Circle(5e-3).grid(24))
    # A bare n is the unit disk, 1 m: the message says so.
    with pytest.raises(ValueError, match=r"rods of radius 0.001 m .* on the unit disk of a bare n "
                                         r"\(radius 1 m: lengths are in m.*the minimum is "
                                         r"n = 6000"):
        rods.labels(96)


def test_rods_in_units_of_the_face_scale_are_refused_with_their_meaning():
    """A script written for lengths in units of L is refused, never re-read as metres."""
    old = Rods(((0.0, 0.0), (0.6, 0.0)), (0.25, 0.25))
    with pytest.raises(ValueError, match=r"rod 0 \(centre \(0, 0\) m, radius 0.25 m\) does not "
                                         r"lie inside the face .*lengths are in m, not in units "
                                         r"of the face scale L = 0.004 m \(in those units centre "
                                         r"\(0, 0\) L = \(0, 0\) m, radius 0.25 L = 0.001 m\)"):
        old.labels(Circle(4e-3).grid(64))
    centre = Rods(((0.6, 0.0),), (0.01,))
    with pytest.raises(ValueError, match=r"centre \(0.6, 0\) L = \(0.0024, 0\) m"):
        centre.labels(Circle(4e-3).grid(64))
    # The scene reader says the same, for the key in the file.
    text = scene_text("parser", map="rods", centres=[(0.6, 0.0)], radii=[0.01])
    with pytest.raises(ValueError, match=r"\[phases\] map: rod 0 .*\(0.6, 0\) L = \(0.0024, 0\) m"):
        parse_scene(text, ".")


def test_labels_validation():
    labels = Rods(((0.0, 0.0),), (0.5,)).labels(32)
    with pytest.raises(ValueError, match="unknown phase label 1"):
        validate_labels(labels, 1)
    with pytest.raises(ValueError, match="phase 2 has no pixel"):
        validate_labels(labels, 3)
    with pytest.raises(ValueError, match="n_phases must be an integer >= 1, got 0"):
        validate_labels(labels, 0)
    inside = labels.copy()
    inside[16, 16] = -1
    with pytest.raises(ValueError, match="label -1 found on the face"):
        validate_labels(inside, 2, face_mask=as_grid(32).mask)
    # Without a mask the face is where the labels say: the hole is off it.
    assert validate_labels(inside, 2).sum() == (labels >= 0).sum() - 1, \
        "without a mask the labels define the face"
    counts = validate_labels(labels, 2, face_mask=as_grid(32).mask)
    assert counts.tolist() == np.bincount(labels[labels >= 0]).tolist(), \
        f"counts with the caller's mask: {counts}"
    with pytest.raises(ValueError, match="phase map array: phase label -1 found on the face"):
        ArrayMap(inside)
    gap = np.where(labels == 1, 2, labels)
    with pytest.raises(ValueError, match="phase 1 has no pixel"):
        ArrayMap(gap)


def test_load_errors(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        load_phase_map(tmp_path / "missing.npy")
    (tmp_path / "m.txt").write_text("0 1")
    with pytest.raises(ValueError, match=r"\.npy or \.png"):
        load_phase_map(tmp_path / "m.txt")
    np.save(tmp_path / "f.npy", np.zeros((16, 16)))
    with pytest.raises(ValueError, match="must hold integers, got dtype float64"):
        load_phase_map(tmp_path / "f.npy")
    (tmp_path / "bad.npy").write_bytes(b"not numpy")
    with pytest.raises(ValueError, match="is not a .npy file"):
        load_phase_map(tmp_path / "bad.npy")


def _npy_header_only(path, shape, descr="<i8"):
    """A .npy file whose header announces ``shape`` but which holds no data."""
    import numpy.lib.format as npy_format

    with open(path, "wb") as f:
        npy_format.write_array_header_1_0(f, {"descr": descr, "fortran_order": False,
                                             "shape": shape})


@pytest.mark.parametrize("make, fragment", [
    (lambda p: p.mkdir(), "is a directory, not a file"),
    (lambda p: p.write_bytes(b""), "is empty (0 bytes)"),
    (lambda p: _npy_header_only(p, (16, 16)),
     "is truncated: its header announces 16 x 16 values of int64 (2048 bytes), the file holds "
     "0 bytes of data"),
    (lambda p: _npy_header_only(p, (100000, 100000)), "more than the grid's n = 32"),
    (lambda p: p.write_bytes(b"\x93NUMPY\x01\x00\x10\x00{'descr': 'garbage"),
     "has a damaged .npy header"),
    (lambda p: np.save(p, np.array([None, 1], dtype=object)), "holds Python objects"),
    (lambda p: np.save(p, np.zeros((4, 4, 4), dtype=int)), "must be a square 2-d array"),
    (lambda p: np.save(p, np.zeros((64, 64), dtype=int)), "more than the grid's n = 32"),
])
def test_hostile_npy_maps_are_refused_before_loading(tmp_path, make, fragment):
    """Every damaged or oversized .npy map is a one-line ValueError, never EOFError/MemoryError."""
    path = tmp_path / "map.npy"
    make(path)
    with pytest.raises(ValueError) as info:
        load_phase_map(path, max_size=32)
    assert fragment in str(info.value), f"message {str(info.value)!r} lacks {fragment!r}"
    assert len(str(info.value)) < 300, f"message of {len(str(info.value))} characters"


def test_header_claiming_a_huge_array_is_not_loaded(tmp_path):
    _npy_header_only(tmp_path / "huge.npy", (100000, 100000))
    with pytest.raises(ValueError, match=r"header announces 100000 x 100000 values of int64 "
                                         r"\(74.5 GiB\), the file holds 0 bytes"):
        read_npy(tmp_path / "huge.npy", what="phase map", holds=LABELS)


def test_devices_are_not_phase_maps():
    with pytest.raises(ValueError, match="is not a regular file"):
        load_phase_map("/dev/null")


def test_hostile_png_maps(tmp_path):
    import matplotlib.image

    wide = tmp_path / "wide.png"
    matplotlib.image.imsave(wide, np.zeros((8, 16)), cmap="gray")
    with pytest.raises(ValueError, match="must be square, got 16 x 8 pixels"):
        load_phase_map(wide)
    big = tmp_path / "big.png"
    matplotlib.image.imsave(big, np.zeros((64, 64)), cmap="gray")
    with pytest.raises(ValueError, match="64 x 64 pixels, more than the grid's n = 32"):
        load_phase_map(big, max_size=32)
    fake = tmp_path / "fake.png"
    fake.write_bytes(b"GIF89a" + bytes(100))
    with pytest.raises(ValueError, match="is not a PNG image"):
        load_phase_map(fake)
    damaged = tmp_path / "damaged.png"
    damaged.write_bytes(big.read_bytes()[:60])
    with pytest.raises(ValueError, match="is not a readable PNG image: it is truncated after 60 "
                                         "bytes, inside a chunk"):
        load_phase_map(damaged)


def test_huge_label_is_refused_before_counting():
    """A label of 10**12 on the face would make bincount allocate terabytes."""
    labels = np.where(as_grid(8).mask, 0, -1)
    labels[4, 4] = 10 ** 12
    with pytest.raises(ValueError, match="cannot all have a pixel on a face of 52 pixels"):
        ArrayMap(labels)
