"""Micrographs as phase maps (``steady.micrograph``): segmentation, placement, scenes, output.

Images made for the purpose come from ``studies/make_micrograph.py``
(Voronoi grains of known phases, blur, noise); the true threshold between
two phases is taken as the midpoint of their grey levels, and the errors
are given in units of the gap between the levels.
"""

import importlib
import importlib.util
import pathlib
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import benchmark, scene_text
from PIL import Image
from scipy import ndimage

from steady.micrograph import Micrograph, Segmentation, load_micrograph, read_grey, segment
from steady.output import write_result
from steady.scene import load_scene
from steady.solution import solve_scene

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENES = ROOT / "steady" / "examples"
RADIUS = 4e-3  # m, the gallery's punch

#: Seeds of the synthetic images (twenty images per case, under a second).
SEEDS = tuple(range(3001, 3021))

#: Synthetic cases: image parameters, segmentation options and tolerances.
#: Measured over SEEDS (120 x 160 pixels, 60 grains) with
#: ``pytest tests/test_micrograph.py -k recovered -s``, which prints the
#: maxima; each tolerance is about twice the measured maximum.
#: - "clean": no blur, noise 5 % of full scale.  The histogram has two well
#:   separated modes, so the Otsu threshold lands near the midpoint: max
#:   error 0.012 gap (the 256-bin histogram resolves 0.009 gap); fill factors
#:   within 1.3e-3; 0.20 % of pixels misclassified (the noise tail beyond
#:   half the gap, Phi(-3) = 0.13 %, plus boundary pixels).
#: - "blurred": blur 1.5 px, noise 8 %, smoothed with sigma 1 px, specks
#:   under 20 px removed.  Blurred boundaries fill the histogram between the
#:   modes and the classes are unequal (70/30), which pulls the Otsu threshold
#:   towards the smaller class by up to 0.053 gap; fill factors within 8.4e-3;
#:   1.6 % misclassified (a threshold off the midpoint shifts every blurred
#:   boundary by a fraction of a pixel).
#: - "three": three phases, no blur, noise 5 %, specks under 20 px removed:
#:   thresholds within 0.014 gap, fill factors within 1.6e-4, 0.021 %
#:   misclassified.  (With blur, a boundary between the darkest and the
#:   brightest phase passes through the middle grey level and shows as a thin
#:   band of the middle phase, a few % of the area: see docs/model.md.)
CASES = {
    "clean": dict(image=dict(fill_factor=0.3, levels=(0.35, 0.65), blur=0.0, noise=0.05),
                  options=dict(), threshold=0.025, fill=3e-3, wrong=5e-3),
    "blurred": dict(image=dict(fill_factor=0.3, levels=(0.35, 0.65), blur=1.5, noise=0.08),
                    options=dict(smoothing=1.0, min_speck=20), threshold=0.1, fill=0.017,
                    wrong=0.03),
    "three": dict(image=dict(fill_factor=(0.3, 0.2), levels=(0.2, 0.5, 0.8), blur=0.0,
                             noise=0.05),
                  options=dict(min_speck=20), threshold=0.03, fill=4e-4, wrong=5e-4),
}


@pytest.fixture(scope="module")
def make_micrograph():
    """The study script that makes synthetic micrographs (and the shipped image)."""
    sys.path.insert(0, str(ROOT / "studies"))
    try:
        yield importlib.import_module("make_micrograph")
    finally:
        sys.path.remove(str(ROOT / "studies"))


@pytest.fixture
def skimage():
    return pytest.importorskip("skimage")


def recovery(make_micrograph, case, seeds):
    """Largest threshold error (units of the gap), fill-factor error and misclassified share."""
    spec = CASES[case]
    levels = np.asarray(spec["image"]["levels"])
    midpoints, gap = 0.5 * (levels[1:] + levels[:-1]), levels[1] - levels[0]
    errors = []
    for seed in seeds:
        grey, truth = make_micrograph.make_grains(rows=120, cols=160, n_grains=60, seed=seed,
                                                  **spec["image"])
        seg = segment(grey, len(levels), **spec["options"])
        true_fill = np.bincount(truth.ravel(), minlength=len(levels)) / truth.size
        errors.append((np.max(np.abs(np.asarray(seg.thresholds) - midpoints)) / gap,
                       np.max(np.abs(np.asarray(seg.fill_factors) - true_fill)),
                       np.mean(seg.labels != truth)))
    return np.max(errors, axis=0)


@pytest.mark.parametrize("case", sorted(CASES))
def test_synthetic_phases_are_recovered(skimage, make_micrograph, case):
    threshold, fill, wrong = recovery(make_micrograph, case, SEEDS)
    print(f"{case}: max threshold error {threshold:.4f} gap, max fill-factor error {fill:.2e}, "
          f"max misclassified {wrong:.4%}")
    spec = CASES[case]
    assert threshold < spec["threshold"], f"{case}: threshold off by {threshold:.4f} gap"
    assert fill < spec["fill"], f"{case}: fill factors off by {fill:.2e}"
    assert wrong < spec["wrong"], f"{case}: {wrong:.2%} of the pixels misclassified"


def test_smoothing_and_speck_removal_reduce_misclassification(skimage, make_micrograph):
    grey, truth = make_micrograph.make_grains(rows=120, cols=160, n_grains=60, seed=3007,
                                              fill_factor=0.3, levels=(0.35, 0.65), blur=1.5,
                                              noise=0.08)
    wrong = {}
    for options in ({}, {"min_speck": 20}, {"smoothing": 1.0}):
        seg = segment(grey, 2, **options)
        wrong[tuple(options)] = np.mean(seg.labels != truth)
    # Noise of 8 % against a gap of 30 % scatters ~5 % of the pixels across the
    # threshold as isolated specks: removing them or smoothing first fixes most.
    assert wrong[("min_speck",)] < 0.5 * wrong[()], f"misclassified shares {wrong}"
    assert wrong[("smoothing",)] < 0.5 * wrong[()], f"misclassified shares {wrong}"


def test_specks_below_the_size_take_the_surrounding_phase(skimage):
    image = np.zeros((60, 80))
    image[:, 40:] = 1.0
    corners = [(5, 5), (5, 20), (30, 8), (45, 20), (20, 25)]
    for side, (r, c) in zip((1, 2, 3, 4, 5), corners, strict=True):
        image[r:r + side, c:c + side] = 1.0                          # bright in the dark half
        image[r:r + side, 45 + c // 2:45 + c // 2 + side] = 0.0      # dark in the bright half
    seg = segment(image, 2, min_speck=9)
    # Sizes 1 and 4 are under 9 pixels (two in each half); 9, 16, 25 stay.
    assert seg.specks == 4 and seg.speck_pixels == 2 * (1 + 4), \
        f"{seg.specks} specks, {seg.speck_pixels} pixels relabelled"
    assert seg.labels[5, 5] == 0 and seg.labels[5, 20] == 0, "bright specks kept"
    assert seg.labels[30, 8] == 1 and seg.labels[45, 20] == 1, "patches of 9 and 16 px kept"
    for phase in (0, 1):
        patches, count = ndimage.label(seg.labels == phase)
        smallest = np.bincount(patches.ravel())[1:].min()
        assert smallest >= 9, f"phase {phase} keeps a patch of {smallest} pixels"
    counts = np.bincount(seg.labels.ravel())
    assert seg.fill_factors == tuple(counts / counts.sum()), "fill factors after removal"


@pytest.mark.parametrize("name, n_phases", [("coins", 2), ("coins", 3), ("camera", 3)])
def test_sample_images_give_ordered_phases(skimage, name, n_phases):
    from skimage import data
    from skimage.filters import threshold_multiotsu

    image = getattr(data, name)()
    seg = segment(image, n_phases)
    thresholds = np.asarray(seg.thresholds)
    # As documented: 256 bins over the grey range (scikit-image bins an integer
    # image by its integer levels instead, which moves a threshold by < 1 level).
    expected = threshold_multiotsu(image.astype(float), classes=n_phases, nbins=256)
    assert np.array_equal(thresholds, expected), \
        f"{name}: thresholds {seg.thresholds}, scikit-image's {expected}"
    assert np.allclose(thresholds, threshold_multiotsu(image, classes=n_phases), atol=1), \
        f"{name}: thresholds {seg.thresholds} far from scikit-image's on integer levels"
    assert len(thresholds) == n_phases - 1 and np.all(np.diff(thresholds) > 0), \
        f"{name}: thresholds {seg.thresholds} not increasing"
    assert abs(sum(seg.fill_factors) - 1) < 1e-12 and min(seg.fill_factors) > 0.01, \
        f"{name}: fill factors {seg.fill_factors}"
    means = [image[seg.labels == p].mean() for p in range(n_phases)]
    assert np.all(np.diff(means) > 0), f"{name}: mean grey of the phases {means} not increasing"
    for p in range(n_phases):
        inside = image[seg.labels == p]
        low = thresholds[p - 1] if p else -np.inf
        high = thresholds[p] if p < n_phases - 1 else np.inf
        assert inside.min() >= low and inside.max() < high, f"{name}: phase {p} out of its band"


def test_segmentation_needs_the_extra(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "skimage", None)
    monkeypatch.setitem(sys.modules, "skimage.filters", None)
    with pytest.raises(ValueError, match=r"pip install 'runin\[micrograph\]'"):
        segment(np.eye(10), 2)
    path = tmp_path / "grey.npy"
    np.save(path, np.eye(10))
    with pytest.raises(ValueError, match=r"scikit-image.*runin\[micrograph\]"):
        load_micrograph(path, RADIUS, 2)


def test_command_line_names_the_missing_extra(monkeypatch, tmp_path, capsys):
    import steady.cli.solve

    np.save(tmp_path / "grey.npy", np.eye(16))
    (tmp_path / "s.toml").write_text(micrograph_scene('path = "grey.npy", n_phases = 2'))
    monkeypatch.setitem(sys.modules, "skimage", None)
    monkeypatch.setitem(sys.modules, "skimage.filters", None)
    status = steady.cli.solve.main([str(tmp_path / "s.toml"), "-o", str(tmp_path / "r.h5")])
    err = capsys.readouterr().err
    assert status == 2, f"exit {status}: {err!r}"
    assert err.startswith("error:") and err.count("\n") == 1, f"stderr {err!r}"
    assert "runin[micrograph]" in err and "Traceback" not in err, f"stderr {err!r}"


# -- placement on the face: exact pixel bookkeeping ----------------------------------------

def segmentation(labels):
    """A Segmentation of given labels (no image: placement needs only the labels)."""
    labels = np.asarray(labels)
    counts = np.bincount(labels.ravel())
    return Segmentation(labels, (0.5,) * (len(counts) - 1), tuple(counts / labels.size), 0.0,
                        0, 0, 0)


@pytest.mark.parametrize("n0, k", [(8, 1), (8, 3), (9, 2), (12, 4)])
def test_default_pixel_size_replicates_pixels(n0, k):
    rng = np.random.default_rng(4133 + n0)
    labels = rng.integers(0, 3, size=(n0, n0))
    labels[0, :3] = (0, 1, 2)
    geometry = Micrograph(segmentation(labels), RADIUS)
    assert geometry.pixel_size == 2 * RADIUS / n0, f"pixel size {geometry.pixel_size}"
    # Columns run along x, rows along -y: grid [i, j] = image[n0 - 1 - j, i].
    expected = np.kron(labels[::-1, :].T, np.ones((k, k), dtype=int))
    got = geometry.labels(k * n0)
    face = got >= 0
    assert np.array_equal(got[face], expected[face]), f"n0 = {n0}, k = {k}: pixels moved"


def test_crop_picks_the_centred_pixels_and_the_offset_shifts_them():
    # Image 10 x 12 pixels of a / 4: 3 a wide, 2.5 a tall; grid n = 8 has the
    # same pixel, so grid pixel (i, j) sits on image pixel (8 - j, i + 2) when centred.
    p = RADIUS / 4
    geometry = Micrograph(segmentation(np.zeros((10, 12), dtype=int) + np.eye(10, 12,
                                                                             dtype=int)),
                          RADIUS, p)
    rows, cols = geometry.image_indices(8)
    assert np.array_equal(cols, np.arange(8) + 2), f"columns {cols}"
    assert np.array_equal(rows, 8 - np.arange(8)), f"rows {rows}"
    shifted = Micrograph(geometry.segmentation, RADIUS, p, offset=(-2 * p, p))
    rows, cols = shifted.image_indices(8)
    assert np.array_equal(cols, np.arange(8)), f"columns with offset {cols}"
    assert np.array_equal(rows, 7 - np.arange(8)), f"rows with offset {rows}"


def test_tile_repeats_the_image():
    # Image 4 x 6 pixels of a / 4 (1.5 a x a) tiled over the face: grid pixel i
    # (x = -a + (i + 1/2) a / 4) lies i - 1/2 pixels right of the image's left
    # edge (-0.75 a), grid pixel j lies 5.5 - j pixels below its top edge (0.5 a).
    p = RADIUS / 4
    geometry = Micrograph(segmentation(np.arange(24).reshape(4, 6) % 2), RADIUS, p,
                          cover="tile")
    rows, cols = geometry.image_indices(8)
    assert np.array_equal(cols, (np.arange(8) - 1) % 6), f"columns {cols}"
    assert np.array_equal(rows, (5 - np.arange(8)) % 4), f"rows {rows}"
    # At n = 16 (pixel a / 8) the periods are 12 grid pixels along x, 8 along y.
    labels = geometry.labels(16)
    face = (labels[:4, :] >= 0) & (labels[12:, :] >= 0)
    assert np.array_equal(labels[:4, :][face], labels[12:, :][face]), "x period"
    face = (labels[:, :8] >= 0) & (labels[:, 8:] >= 0)
    assert np.array_equal(labels[:, :8][face], labels[:, 8:][face]), "y period"


def test_a_crop_that_cannot_cover_the_face_names_the_sizes():
    seg = segmentation(np.eye(100, 120, dtype=int))
    with pytest.raises(ValueError, match=r"covers 6 mm x 5 mm \(120 x 100 pixels of 5e-05 m\) "
                                         r"but the face needs 8 mm x 8 mm.*tile"):
        Micrograph(seg, RADIUS, 5e-5)
    Micrograph(seg, RADIUS, 5e-5, cover="tile")  # tiling covers any face
    with pytest.raises(ValueError, match=r"pixel_size must be a number > 0 \(m\), got -5e-05"):
        Micrograph(seg, RADIUS, -5e-5, cover="tile")
    Micrograph(seg, RADIUS, 8e-5)                 # 9.6 mm x 8 mm: exactly enough
    Micrograph(seg, RADIUS, 8e-5, offset=(8e-4, 0.0))  # 0.8 mm of spare width
    with pytest.raises(ValueError, match=r"offset \(0 mm, 0.1 mm\)"):
        Micrograph(seg, RADIUS, 8e-5, offset=(0.0, 1e-4))
    with pytest.raises(ValueError, match="without a pixel_size it must be square"):
        Micrograph(seg, RADIUS)


# -- scene files ------------------------------------------------------------------------

def micrograph_scene(keys, **overrides):
    """The gallery's steady scene (two phases) with a micrograph map of ``keys``."""
    text = scene_text("steady", map="homogeneous", **overrides)
    return text.replace('map = { kind = "homogeneous" }', f'map = {{ kind = "micrograph", '
                                                          f'{keys} }}')


@pytest.fixture
def grains_png(make_micrograph, tmp_path):
    """A small synthetic micrograph as a PNG: 200 x 160 pixels, two phases."""
    grey, truth = make_micrograph.make_grains(rows=160, cols=200, n_grains=80, seed=3011,
                                              fill_factor=0.3, levels=(0.35, 0.65), blur=1.5,
                                              noise=0.05)
    make_micrograph.write_png(tmp_path / "grains.png", grey)
    return tmp_path / "grains.png", truth


def test_scene_builds_a_micrograph_map(skimage, grains_png, caplog):
    path, truth = grains_png
    (path.parent / "s.toml").write_text(micrograph_scene(
        'path = "grains.png", n_phases = 2, smoothing = 1, min_speck = 20, '
        'pixel_size = 5e-5, offset = [5e-4, 0.0]', n=40))
    with caplog.at_level("INFO", logger="steady.micrograph"):
        scene = load_scene(path.parent / "s.toml")
    geometry = scene.geometry
    assert isinstance(geometry, Micrograph) and scene.n_phases == 2, f"{geometry}"
    assert "thresholds" in caplog.text and "image fill factors" in caplog.text, caplog.text
    true_fill = np.bincount(truth.ravel()) / truth.size
    assert np.max(np.abs(np.asarray(geometry.segmentation.fill_factors) - true_fill)) < 0.01, \
        f"image fill factors {geometry.segmentation.fill_factors} vs true {true_fill}"
    labels = scene.phase_labels()
    assert np.allclose(geometry.face_fill_factors(40), np.bincount(labels[labels >= 0]) /
                       np.count_nonzero(labels >= 0)), "face fill factors"
    assert geometry.extent == pytest.approx((0.01, 0.008)), f"extent {geometry.extent}"


@pytest.mark.parametrize("keys, fragment", [
    ('path = "grains.png"', "missing key 'n_phases'"),
    ('path = "grains.png", n_phases = 2, sigma = 1.0',
     "unknown key 'sigma' in [phases] map (kind 'micrograph') (allowed: cover, crop, "
     "fill_holes, fill_phases, kind, min_speck, n_phases, offset, path, pixel_size, smoothing, "
     "thresholds)"),
    ('path = "grains.png", n_phases = 1', "[phases] map n_phases must be an integer >= 2, got 1"),
    ('path = "grains.png", n_phases = 2.0', "[phases] map n_phases must be an integer >= 2, "
                                             "got 2.0"),
    ('path = "grains.png", n_phases = 2, smoothing = -1.0', "[phases] map smoothing must be a "
                                                           "number >= 0 (pixels), got -1.0"),
    ('path = "grains.png", n_phases = 2, smoothing = true', "smoothing must be"),
    ('path = "grains.png", n_phases = 2, min_speck = 2.5', "min_speck must be an integer >= 0 "
                                                          "(pixels), got 2.5"),
    ('path = "grains.png", n_phases = 2, pixel_size = 0', "[phases] map pixel_size must be a "
                                                         "number > 0 (m), got 0"),
    ('path = "grains.png", n_phases = 2, pixel_size = 5e-5, cover = "stretch"',
     "[phases] map cover must be one of 'crop', 'tile', got 'stretch'"),
    ('path = "grains.png", n_phases = 2, pixel_size = 5e-5, offset = [1e-4]',
     "[phases] map offset must be an [x, y] pair (m), got [0.0001]"),
    ('path = "grains.png", n_phases = 2', "it must be square"),
    ('path = "grains.png", n_phases = 2, pixel_size = 2e-5', "covers 4 mm x 3.2 mm"),
    ('path = "missing.png", n_phases = 2', "micrograph"),
    ('path = "s.toml", n_phases = 2', "must be a .png or .npy file"),
    ('path = "", n_phases = 2', "[phases] map path must be a file name, got ''"),
])
def test_bad_micrograph_keys_are_one_line_errors(skimage, grains_png, keys, fragment):
    path, _ = grains_png
    scene = path.parent / "s.toml"
    scene.write_text(micrograph_scene(keys))
    with pytest.raises(ValueError) as err:
        load_scene(scene)
    message = str(err.value)
    assert fragment in message, f"{keys}: {message!r} lacks {fragment!r}"
    assert "\n" not in message and message.startswith(str(scene)), f"{keys}: {message!r}"


def test_too_many_phases_for_the_grey_levels(skimage, tmp_path):
    np.save(tmp_path / "two.npy", np.eye(16))
    with pytest.raises(ValueError, match="2 distinct grey levels, fewer than the 3 phases"):
        load_micrograph(tmp_path / "two.npy", RADIUS, 3)


def test_otsu_beyond_its_limit_asks_for_thresholds_before_the_image_is_read(tmp_path):
    # 6 phases: C(256, 5) = 8.8e9 sets of thresholds, minutes (docs/benchmarks.md).
    with pytest.raises(ValueError) as err:
        load_micrograph(tmp_path / "absent.npy", RADIUS, 6)
    assert ("n_phases = 6 by Otsu's thresholds would search C(256, 5) = 8.8e+09 sets" in
            str(err.value) and "(at most 5 phases): give thresholds = [...], 5 increasing grey "
            "levels" in str(err.value)), str(err.value)
    # 5 phases are searched: the image is then looked for.
    with pytest.raises(ValueError, match="absent.npy' does not exist"):
        load_micrograph(tmp_path / "absent.npy", RADIUS, 5)
    image = np.random.default_rng(3517).random((32, 32))
    with pytest.raises(ValueError, match="n_phases = 7 by Otsu's thresholds"):
        segment(image, 7)
    given = segment(image, 7, thresholds=np.linspace(0.1, 0.9, 6))
    assert given.n_phases == 7 and given.method == "manual", given.summary()


def test_bench_otsu_smoke(skimage, capsys):
    bench = benchmark("bench_otsu")
    rows = bench.main(["--size", "16", "--phases", "2", "3", "--repeat", "1"])
    assert [(row["phases"], row["sets"]) for row in rows] == [(2, 256), (3, 32640)], rows
    assert all(row["wall"] > 0 for row in rows), rows
    assert "6 phases, refused" in capsys.readouterr().out


def test_colour_png_is_read_as_luminance(tmp_path):
    rgb = np.zeros((10, 12, 3), dtype=np.uint8)
    rgb[..., 0], rgb[..., 1], rgb[..., 2] = 255, 0, 0
    Image.fromarray(rgb).save(tmp_path / "red.png")
    grey = read_grey(tmp_path / "red.png")
    assert grey.shape == (10, 12) and np.allclose(grey, 0.2125), f"grey {grey[0, 0]}"


def test_command_line_reports_and_records_the_segmentation(skimage, grains_png):
    path, _ = grains_png
    (path.parent / "s.toml").write_text(micrograph_scene(
        'path = "grains.png", n_phases = 2, smoothing = 1.0, pixel_size = 5e-5, '
        'cover = "tile"', n=40, radius=6e-3))
    proc = subprocess.run([sys.executable, "-m", "steady", "s.toml", "-o", "r.h5",
                           "--no-slope-error"], cwd=path.parent, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert "segmentation     2 phases, thresholds" in proc.stdout, proc.stdout
    scene = load_scene(path.parent / "s.toml")
    seg = scene.geometry.segmentation
    with h5py.File(path.parent / "r.h5") as f:
        group = f["micrograph"]
        assert np.allclose(group.attrs["thresholds"], seg.thresholds), "thresholds stored"
        assert np.allclose(group.attrs["image_fill_factors"], seg.fill_factors), "fill stored"
        assert group.attrs["cover"] == "tile" and group.attrs["pixel_size"] == 5e-5, \
            f"placement stored: {dict(group.attrs)}"
        assert group.attrs["threshold_method"] == "otsu" and group.attrs["holes"] == 0, \
            f"segmentation stored: {dict(group.attrs)}"
        assert np.array_equal(group.attrs["crop"], [[0, 160], [0, 200]]), "the whole image"
        assert group.attrs["fill_phases"].size == 0, "no phase filled"
        assert np.allclose(f["fill_factors"][()], scene.geometry.face_fill_factors(40)), \
            "the face's fill factors are the result's"


def test_results_of_other_maps_have_no_micrograph_group(tmp_path):
    (tmp_path / "s.toml").write_text(scene_text("steady", n=16, map="homogeneous",
                                                coefficients=(1e-9,)))
    scene = load_scene(tmp_path / "s.toml")
    write_result(tmp_path / "r.h5", solve_scene(scene, face_only=True), scene)
    with h5py.File(tmp_path / "r.h5") as f:
        assert "micrograph" not in f, "a micrograph group without a micrograph"


# -- the shipped example -------------------------------------------------------------------

def test_shipped_image_is_what_the_script_makes(make_micrograph):
    grey, _ = make_micrograph.make_grains(**make_micrograph.PARAMS)
    shipped = np.asarray(Image.open(SCENES / "micrograph_example.png"))
    assert np.array_equal(shipped, np.rint(grey * 255).astype(np.uint8)), \
        "steady/examples/micrograph_example.png differs from make_micrograph.py's image"
    assert (SCENES / "micrograph_example.png").stat().st_size < 300_000, "image too large"


def test_shipped_scene_builds_its_phase_map(skimage, make_micrograph):
    scene = load_scene(SCENES / "micrograph_steady.toml")
    assert isinstance(scene.geometry, Micrograph) and scene.n_phases == 2, f"{scene.geometry}"
    assert scene.ignored_sections == ("initial_face", "transient"), scene.ignored_sections
    _, truth = make_micrograph.make_grains(**make_micrograph.PARAMS)
    true_fill = np.bincount(truth.ravel()) / truth.size
    seg = scene.geometry.segmentation
    # Measured: 0.6930 / 0.3070 against the truth 0.6958 / 0.3042; 0.9 % misclassified.
    assert np.max(np.abs(np.asarray(seg.fill_factors) - true_fill)) < 0.005, \
        f"image fill factors {seg.fill_factors} vs true {true_fill}"
    assert np.mean(seg.labels != truth) < 0.015, "misclassified pixels"
    labels = scene.phase_labels()
    face = np.bincount(labels[labels >= 0]) / np.count_nonzero(labels >= 0)
    # The face (8 mm) is a window of the 12 x 9 mm image: measured 0.721 / 0.279.
    assert abs(face[1] - 0.279) < 0.005, f"face fill factors {face}"


def test_shipped_scene_runs_in(skimage, tmp_path):  # about 2 s
    proc = subprocess.run([sys.executable, "-m", "transient",
                           str(SCENES / "micrograph_steady.toml"), "-o", str(tmp_path / "t.h5")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert "within the error bars" in proc.stdout, proc.stdout


# -- a secondary-electron image: crop, given thresholds, hole filling -------------------------

#: Seeds of the particle images (about 0.1 s each with its segmentations).
PARTICLE_SEEDS = tuple(range(3101, 3113))

#: The threshold given for the particle images: at the foot of the rims' peak in the histogram
#: of the smoothed grey levels (matrix peak at 0.5, rims' peak near 0.67; see the figure of
#: ``segmentation_figure``).  Measured over PARTICLE_SEEDS: 0.60 overestimates the area fraction
#: by 0.011 on average (boundaries move outwards by a fraction of a pixel), 0.62 by -0.001.
PARTICLE_THRESHOLD = 0.62

#: Segmentation options for the particle images besides the crop.
PARTICLE_OPTIONS = dict(smoothing=1.0, min_speck=10)


def particle_crop(make_micrograph):
    """The rows above the data bar, every column: ``[[0, rows - bar], [0, cols]]``."""
    params = make_micrograph.PARTICLES
    return [[0, params["rows"] - params["bar_rows"]], [0, params["cols"]]]


@pytest.fixture(scope="module")
def particle_errors(make_micrograph):
    """Per seed: the particles' true area fraction above the bar and four segmentations' errors.

    Columns: truth; Otsu's threshold on the whole image and on the crop; the area-fraction
    error of Otsu on the whole image (phase 1 in the rows above the bar), of Otsu on the crop,
    of Otsu on the crop with holes filled, of the given threshold with holes filled; and the
    share of misclassified pixels of the last.
    """
    pytest.importorskip("skimage")
    crop = particle_crop(make_micrograph)
    above = slice(*crop[0])
    rows = []
    for seed in PARTICLE_SEEDS:
        grey, truth = make_micrograph.make_particles(**{**make_micrograph.PARTICLES,
                                                        "seed": seed})
        truth = truth[above]
        whole = segment(grey, 2)
        otsu = segment(grey, 2, crop=crop)
        otsu_filled = segment(grey, 2, crop=crop, fill_holes=True, **PARTICLE_OPTIONS)
        given = segment(grey, 2, crop=crop, thresholds=[PARTICLE_THRESHOLD], fill_holes=True,
                        **PARTICLE_OPTIONS)
        true_fill = truth.mean()
        rows.append((true_fill, whole.thresholds[0], otsu.thresholds[0],
                     whole.labels[above].mean() - true_fill,
                     otsu.fill_factors[1] - true_fill, otsu_filled.fill_factors[1] - true_fill,
                     given.fill_factors[1] - true_fill, np.mean(given.labels != truth)))
    return np.array(rows)


def test_particles_are_recovered_by_crop_threshold_and_hole_filling(particle_errors):
    # Measured over PARTICLE_SEEDS (true area fractions 0.12 to 0.15): area-fraction error
    # -0.0065 to +0.0034, misclassified pixels 0.95 % to 2.0 % (the blurred boundaries and
    # the particles cut by the image's edge, whose open cores stay matrix).
    error, wrong = particle_errors[:, 6], particle_errors[:, 7]
    print(f"given threshold + holes: area-fraction error {error.min():+.4f} to "
          f"{error.max():+.4f}, misclassified up to {wrong.max():.2%}")
    assert np.max(np.abs(error)) < 0.013, f"area-fraction errors {error}"
    assert np.max(wrong) < 0.04, f"misclassified shares {wrong}"


def test_otsu_fails_on_the_particles(particle_errors):
    whole_t, crop_t = particle_errors[:, 1], particle_errors[:, 2]
    whole, otsu, otsu_filled = particle_errors[:, 3], particle_errors[:, 4], particle_errors[:, 5]
    print(f"Otsu: whole image threshold {whole_t.max():.4f}, error {whole.min():+.4f}; crop "
          f"threshold {crop_t.min():.4f}-{crop_t.max():.4f}, error {otsu.min():+.4f} to "
          f"{otsu.max():+.4f}; with holes filled {otsu_filled.min():+.4f} to "
          f"{otsu_filled.max():+.4f}")
    # With the data bar, Otsu splits its black from everything else (measured 0.0059): the
    # whole field becomes "particle".  Leaving the bar out changes the threshold to one
    # within the rims (0.580 to 0.586), which finds the rims, not the cores (the area
    # fraction 0.008 to 0.026 low), and whose holes filled give boundaries too far out
    # (0.024 to 0.035 high).
    assert np.all(whole_t < 0.05) and np.all(crop_t > 0.55), \
        f"Otsu's thresholds: whole image {whole_t}, cropped {crop_t}"
    assert np.all(whole > 0.8), f"Otsu on the whole image: area-fraction errors {whole}"
    assert np.all(otsu < -0.004) and np.mean(otsu) < -0.015, \
        f"Otsu on the crop: area-fraction errors {otsu}"
    assert np.all(otsu_filled > 0.012), f"Otsu with holes filled: errors {otsu_filled}"


def test_crop_is_the_segmentation_of_the_cropped_pixels(skimage, make_micrograph):
    grey, _ = make_micrograph.make_particles(**make_micrograph.PARTICLES)
    seg = segment(grey, 2, crop=[[10, 250], [30, 330]], smoothing=1.0)
    alone = segment(grey[10:250, 30:330], 2, smoothing=1.0)
    assert seg.shape == (240, 300) and seg.crop == ((10, 250), (30, 330)), \
        f"shape {seg.shape}, crop {seg.crop}"
    assert seg.thresholds == alone.thresholds, f"{seg.thresholds} vs {alone.thresholds}"
    assert np.array_equal(seg.labels, alone.labels), "labels of the crop"
    assert np.array_equal(seg.image, grey[10:250, 30:330]), "the image kept is the crop"


def test_crop_sets_the_placement(tmp_path):
    image = np.zeros((40, 50))
    image[:30, 20:] = 1.0
    np.save(tmp_path / "grey.npy", image)
    # Rows 0..29, columns 10..39: a 30 x 30 square, so it spans the 2 mm face by default.
    geometry = load_micrograph(tmp_path / "grey.npy", 1e-3, 2, thresholds=[0.5],
                               crop=[[0, 30], [10, 40]])
    assert geometry.pixel_size == pytest.approx(2e-3 / 30), f"pixel {geometry.pixel_size}"
    assert geometry.segmentation.fill_factors == (1 / 3, 2 / 3), \
        f"fill factors {geometry.segmentation.fill_factors}"
    # Columns 10..19 (phase 0) lie left of x = -1/3 mm, columns 20..39 (phase 1) right of it.
    labels = geometry.labels(30)
    assert np.all(labels[:10][labels[:10] >= 0] == 0), "phase 0 left of the boundary"
    assert np.all(labels[10:][labels[10:] >= 0] == 1), "phase 1 right of the boundary"
    with pytest.raises(ValueError, match="must be square"):
        load_micrograph(tmp_path / "grey.npy", 1e-3, 2, thresholds=[0.5],
                        crop=[[0, 30], [0, 40]])


def ring(shape=(30, 30), outer=(5, 25), inner=(10, 20), levels=(0.5, 1.0, 0.0)):
    """A square ring of grey ``levels[1]`` around a core ``levels[2]`` on ``levels[0]``."""
    image = np.full(shape, levels[0])
    image[outer[0]:outer[1], outer[0]:outer[1]] = levels[1]
    image[inner[0]:inner[1], inner[0]:inner[1]] = levels[2]
    return image


def test_hole_filling_fills_enclosed_cores_only(skimage):
    image = ring()
    image[0:5, 0:5], image[0:2, 0:2] = 1.0, 0.0           # a rim cut open by the corner
    seg = segment(image, 2, thresholds=[0.75], fill_holes=True)
    assert seg.labels[10:20, 10:20].min() == 1 and seg.holes == 1 and seg.hole_pixels == 100, \
        f"core: {seg.holes} holes, {seg.hole_pixels} pixels"
    assert np.all(seg.labels[0:2, 0:2] == 0), "a core open to the image's edge stays"
    assert seg.fill_factors[1] == (400 + 21) / 900, f"fill factors {seg.fill_factors}"
    plain = segment(image, 2, thresholds=[0.75])
    assert plain.holes == 0 and plain.fill_factors[1] == (300 + 21) / 900, \
        f"without fill_holes: {plain.fill_factors}"
    # A one-pixel gap in the rim (sharing a side with both) opens the core: not a hole.
    image[12, 5:10] = 0.0
    assert segment(image, 2, thresholds=[0.75], fill_holes=True).holes == 0, "gap in the rim"
    # A rim of diagonal steps (a diamond of pixels touching at corners) closes the core:
    # cores are connected through sides only.
    r, c = np.mgrid[0:15, 0:15]
    image = np.where(np.abs(r - 7) + np.abs(c - 7) == 4, 1.0, 0.5)
    seg = segment(image, 2, thresholds=[0.75], fill_holes=True)
    assert seg.holes == 1 and seg.hole_pixels == 1 + 3 + 5 + 7 + 5 + 3 + 1, \
        f"{seg.holes} holes, {seg.hole_pixels} pixels behind a diagonal rim"


def test_hole_filling_with_three_phases(skimage):
    # Phases: 0 dark (0.0), 1 middle (0.5), 2 bright (1.0).  A bright ring (2) around a dark
    # core (0) in a middle matrix (1); a middle ring (1) around a dark core (0) in a bright
    # field (2); a bright particle (2) inside the middle matrix.
    image = np.full((40, 80), 0.5)
    image[5:25, 5:25], image[10:20, 10:20] = 1.0, 0.0
    image[30:36, 30:36] = 1.0
    image[:, 40:] = 1.0
    image[5:25, 45:65], image[10:20, 50:60] = 0.5, 0.0
    image[34:, :10] = 0.0                                        # dark, open to the edge
    thresholds = [0.25, 0.75]
    seg = segment(image, 3, thresholds=thresholds, fill_holes=True)
    assert seg.fill_phases == (1, 2), f"fill phases {seg.fill_phases}"
    assert np.all(seg.labels[10:20, 10:20] == 2), "dark core in a bright rim -> 2"
    assert np.all(seg.labels[30:36, 30:36] == 2), "a brighter particle is not a hole"
    # From the brightest down: the field (2) encloses the middle ring and its core, darker
    # phases only, so they become 2 -- unless only phase 1's holes are filled.
    assert np.all(seg.labels[5:25, 45:65] == 2), "the middle ring inside the bright field"
    assert np.all(seg.labels[34:, :10] == 0) and seg.fill_factors[0] == 60 / 3200, \
        f"a dark patch open to the edge stays: {seg.fill_factors}"
    only = segment(image, 3, thresholds=thresholds, fill_holes=True, fill_phases=[1])
    assert np.all(only.labels[10:20, 10:20] == 0), "phase 2's holes left with fill_phases [1]"
    assert np.all(only.labels[10:20, 50:60] == 1), "phase 1's core filled"
    assert only.holes == 1 and only.hole_pixels == 100, f"{only.holes}, {only.hole_pixels}"


def test_given_thresholds_need_no_scikit_image(monkeypatch):
    monkeypatch.setitem(sys.modules, "skimage", None)
    monkeypatch.setitem(sys.modules, "skimage.filters", None)
    seg = segment(ring(), 2, thresholds=[0.75], fill_holes=True)
    assert seg.method == "manual" and seg.thresholds == (0.75,), f"{seg.summary()}"
    assert "thresholds 0.75 (manual)" in seg.summary() and "1 holes (100 pixels) filled " \
        "in phase 1" in seg.summary(), seg.summary()


@pytest.mark.parametrize("options, fragment", [
    (dict(thresholds=[0.2, 0.6]), "thresholds = [0.2, 0.6] must hold n_phases - 1 = 1 grey "
                                  "level, got 2"),
    (dict(thresholds=[0.6, 0.2], n_phases=3), "thresholds = [0.6, 0.2] must increase"),
    (dict(thresholds=[0.4, 0.4], n_phases=3), "thresholds = [0.4, 0.4] must increase"),
    (dict(thresholds=["a"]), "thresholds = ['a'] must be a list of finite grey levels"),
    (dict(thresholds=[float("nan")]), "thresholds = [nan] must be a list"),
    (dict(thresholds=0.5), "thresholds = 0.5 must be a list"),
    (dict(thresholds=[1.5]), "thresholds = [1.5]: 1.5 lies outside the grey range (0, 1] of "
                             "the image"),
    (dict(thresholds=[0.0]), "thresholds = [0.0]: 0 lies outside the grey range (0, 1]"),
    (dict(thresholds=[0.2], crop=[[0, 8], [0, 30]]),
     "0.2 lies outside the grey range (0.5, 1] of the cropped image"),
    (dict(crop=[[0, 10]]), "crop = [[0, 10]] must be [[row0, row1], [col0, col1]]"),
    (dict(crop=[[0, 10.5], [0, 10]]), "crop = [[0, 10.5], [0, 10]] must be"),
    (dict(crop=[[10, 0], [0, 10]]), "crop = [[10, 0], [0, 10]] must be"),
    (dict(crop=[[-2, 10], [0, 10]]), "crop = [[-2, 10], [0, 10]] must be"),
    (dict(crop=[[0, 1], [0, 10]]), "at least 2 pixels each way"),
    (dict(crop=[[0, 31], [0, 10]]), "crop = [[0, 31], [0, 10]] reaches beyond the image of 30 "
                                    "rows x 30 columns"),
    (dict(crop="top"), "crop = 'top' must be"),
    (dict(fill_holes=1), "fill_holes must be true or false, got 1"),
    (dict(fill_phases=[1]), "fill_phases = [1] needs fill_holes = true"),
    (dict(fill_holes=True, fill_phases=[0]), "fill_phases = [0] must list distinct phases 1 "
                                             "to 1"),
    (dict(fill_holes=True, fill_phases=[1, 1], n_phases=3), "fill_phases = [1, 1] must list"),
    (dict(fill_holes=True, fill_phases=[3], n_phases=3), "fill_phases = [3] must list distinct "
                                                          "phases 1 to 2"),
    (dict(n_phases=1), "n_phases must be an integer >= 2, got 1"),
    (dict(smoothing=-1.0), "smoothing must be a number >= 0 (pixels), got -1.0"),
    (dict(smoothing=float("inf")), "smoothing must be a number >= 0 (pixels), got inf"),
    (dict(min_speck=2.5), "min_speck must be an integer >= 0 (pixels), got 2.5"),
])
def test_bad_segmentation_options_are_named(skimage, options, fragment):
    options = {"n_phases": 2, **options}
    with pytest.raises(ValueError) as err:
        segment(ring(), options.pop("n_phases"), **options)
    assert fragment in str(err.value), f"{options}: {str(err.value)!r} lacks {fragment!r}"


@pytest.fixture
def particles_png(make_micrograph, tmp_path):
    """The particle image (400 x 300 pixels, data bar from row 260) as a PNG."""
    grey, truth = make_micrograph.make_particles(**make_micrograph.PARTICLES)
    make_micrograph.write_png(tmp_path / "particles.png", grey)
    return tmp_path / "particles.png", truth


PARTICLE_KEYS = ('path = "particles.png", n_phases = 2, crop = [[0, 260], [0, 400]], '
                 'thresholds = [0.62], fill_holes = true, smoothing = 1.0, min_speck = 10, '
                 'pixel_size = 2.5e-5')


def test_scene_with_crop_thresholds_and_holes(particles_png):
    path, truth = particles_png
    (path.parent / "s.toml").write_text(micrograph_scene(PARTICLE_KEYS, n=48, radius=3e-3))
    geometry = load_scene(path.parent / "s.toml").geometry
    seg = geometry.segmentation
    assert seg.crop == ((0, 260), (0, 400)) and seg.method == "manual", seg.summary()
    assert seg.fill_phases == (1,) and seg.holes > 50, seg.summary()
    assert geometry.extent == pytest.approx((0.01, 0.0065)), f"extent {geometry.extent}"
    # The PNG's 8-bit grey levels move the area fraction by 1e-4 from the float image's.
    error = seg.fill_factors[1] - truth[:260].mean()
    assert abs(error) < 0.013, f"area fraction {seg.fill_factors[1]} vs {truth[:260].mean()}"


@pytest.mark.parametrize("keys, fragment", [
    ('thresholds = [0.62, 0.7]', "[phases] map: thresholds = [0.62, 0.7] must hold n_phases - 1"),
    ('thresholds = [1.2]', "thresholds = [1.2]: 1.2 lies outside the grey range"),
    ('thresholds = 0.62', "[phases] map thresholds must be an array of numbers (grey level), "
                          "got 0.62"),
    ('crop = [[0, 260], [0, 500]]', "crop = [[0, 260], [0, 500]] reaches beyond the image of "
                                    "300 rows x 400 columns"),
    ('crop = [[0, 260.5], [0, 400]]', "crop = [[0.0, 260.5], [0.0, 400.0]] must be"),
    ('crop = [[0, -260], [0, 400]]', "[phases] map crop must be an array of [x, y] pairs each "
                                     ">= 0 (pixels)"),
    ('fill_holes = "yes"', "[phases] map fill_holes must be true or false, got 'yes'"),
    ('fill_phases = [1]', "fill_phases = [1] needs fill_holes = true"),
    ('fill_holes = true, fill_phases = [2]', "fill_phases = [2] must list distinct phases 1 to 1"),
    ('crop = [[0, 260], [0, 260]], pixel_size = 1e-5', "covers 2.6 mm x 2.6 mm"),
])
def test_bad_crop_threshold_and_hole_keys_are_one_line_errors(skimage, particles_png, keys,
                                                              fragment):
    path, _ = particles_png
    scene = path.parent / "s.toml"
    scene.write_text(micrograph_scene(f'path = "particles.png", n_phases = 2, '
                                      f'pixel_size = 2.5e-5, {keys}'.replace(
                                          "pixel_size = 2.5e-5, crop = [[0, 260], [0, 260]], "
                                          "pixel_size = 1e-5", "crop = [[0, 260], [0, 260]], "
                                                               "pixel_size = 1e-5"),
                                      radius=3e-3))
    with pytest.raises(ValueError) as err:
        load_scene(scene)
    message = str(err.value)
    assert fragment in message, f"{keys}: {message!r} lacks {fragment!r}"
    assert "\n" not in message and message.startswith(str(scene)), f"{keys}: {message!r}"


# -- the segmentation figure ---------------------------------------------------------------

def test_segmentation_figure_draws_image_phases_face_and_histogram(skimage, particles_png):
    from matplotlib.figure import Figure
    from matplotlib.image import AxesImage

    from steady.plotting import segmentation_figure

    path, _ = particles_png
    geometry = load_micrograph(path, 3e-3, 2, crop=[[0, 260], [0, 400]], thresholds=[0.62],
                               fill_holes=True, smoothing=1.0, min_speck=10, pixel_size=2.5e-5)
    fig = segmentation_figure(geometry, names=["ferrite", "cementite"])
    assert isinstance(fig, Figure) and len(fig.axes) == 2, f"{fig.axes}"
    image_ax, hist_ax = fig.axes
    images = [a for a in image_ax.get_children() if isinstance(a, AxesImage)]
    assert len(images) == 2, f"{len(images)} images: the grey image and the phases over it"
    grey, overlay = images
    assert grey.get_array().shape == (260, 400), f"image {grey.get_array().shape}"
    assert np.array_equal(overlay.get_array()[..., 3] > 0, geometry.segmentation.labels == 1), \
        "phase 1 coloured, phase 0 clear"
    # Extent in mm, face coordinates: 10 mm x 6.5 mm around the face's centre.
    assert grey.get_extent() == pytest.approx([-5.0, 5.0, -3.25, 3.25]), grey.get_extent()
    face = image_ax.collections[0].get_paths()[0].vertices
    assert np.allclose(np.hypot(*face.T), 3.0, atol=0.02), "the face's outline, radius 3 mm"
    assert image_ax.get_title() == "2 phases, threshold 0.62 (manual)", image_ax.get_title()
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[0].startswith("ferrite: 85.") and legend[2] == "face", legend
    lines = [line for line in hist_ax.get_lines() if line.get_linestyle() == "--"]
    assert [line.get_xdata()[0] for line in lines] == [0.62], "the threshold marked"
    heights = sum(p.get_height() for p in hist_ax.patches if p.get_height() >= 1)
    assert heights == 260 * 400, f"histogram holds {heights} pixels"
    assert "holes filled" in fig.get_suptitle() and "rows 0:260" in fig.get_suptitle(), \
        fig.get_suptitle()


def test_segmentation_figure_takes_axes_and_refuses_bad_ones(skimage):
    from matplotlib.figure import Figure

    from steady.plotting import segmentation_figure

    geometry = Micrograph(segment(ring(), 2, thresholds=[0.75], fill_holes=True), 1e-3,
                          cover="tile", pixel_size=2e-5)
    fig = Figure()
    ax = fig.subplots()
    assert segmentation_figure(geometry, ax=ax) is fig and len(fig.axes) == 1, "one panel"
    # Tiled: the face's 2 mm box, 100 image pixels of 20 um, drawn over the 0.6 mm image.
    assert ax.images[0].get_array().shape == (100, 100), ax.images[0].get_array().shape
    pair = Figure().subplots(1, 2)
    assert len(segmentation_figure(geometry, ax=pair).axes) == 2, "two panels"
    with pytest.raises(ValueError, match="ax must be a matplotlib Axes or a pair of them, got 3"):
        segmentation_figure(geometry, ax=3)
    with pytest.raises(ValueError, match=r"names must name the 2 phases, got \['a'\]"):
        segmentation_figure(geometry, names=["a"])
    with pytest.raises(ValueError, match="keeps no image"):
        segmentation_figure(Micrograph(segmentation(np.eye(8, dtype=int)), 1e-3))


def test_command_line_draws_the_segmentation_alone(skimage, particles_png, monkeypatch, capsys):
    import steady.cli.solve

    path, _ = particles_png
    (path.parent / "s.toml").write_text(micrograph_scene(PARTICLE_KEYS, n=48, radius=3e-3))
    monkeypatch.chdir(path.parent)
    status = steady.cli.solve.main(["s.toml", "--segmentation", "seg.png"])
    out, err = capsys.readouterr()
    assert status == 0, f"exit {status}: {err}"
    assert "thresholds 0.62 (manual), crop rows 0:260, columns 0:400" in out, out
    assert out.endswith("segmentation PNG seg.png\n"), out
    written = sorted(p.name for p in path.parent.iterdir())
    assert written == ["particles.png", "s.toml", "seg.png"], f"files {written}"
    assert Image.open(path.parent / "seg.png").format == "PNG", "a PNG"
    status = steady.cli.solve.main(["s.toml", "--segmentation", "seg.png"])
    err = capsys.readouterr().err
    assert status == 2 and "'seg.png' exists" in err, f"exit {status}: {err!r}"


@pytest.mark.parametrize("argv, fragment", [
    (["--segmentation", "seg.jpg"], "seg.jpg': expected the suffix .png, .pdf or .svg"),
    (["--segmentation", "s.toml"], "--segmentation"),
    (["--plot", "p.png", "--segmentation", "seg.png"], "required: -o/--output"),
    ([], "required: -o/--output"),
])
def test_command_line_refuses_bad_segmentation_requests(skimage, particles_png, capsys, argv,
                                                        fragment):
    import steady.cli.solve

    path, _ = particles_png
    (path.parent / "s.toml").write_text(micrograph_scene(PARTICLE_KEYS, n=48, radius=3e-3))
    try:
        status = steady.cli.solve.main([str(path.parent / "s.toml"), *[
            str(path.parent / a) if a.endswith((".png", ".pdf", ".toml")) else a for a in argv]])
    except SystemExit as exit_:
        status = exit_.code
    err = capsys.readouterr().err
    assert status == 2 and fragment in err and err.count("\n") == 1, f"exit {status}: {err!r}"
    assert sorted(p.name for p in path.parent.iterdir()) == ["particles.png", "s.toml"], \
        "nothing written"


def test_command_line_refuses_segmentation_of_another_map(tmp_path, capsys):
    import steady.cli.solve

    (tmp_path / "s.toml").write_text(scene_text("steady", n=16, map="homogeneous",
                                                coefficients=(1e-9,)))
    status = steady.cli.solve.main([str(tmp_path / "s.toml"), "--segmentation",
                                    str(tmp_path / "seg.png")])
    err = capsys.readouterr().err
    assert status == 2 and "--segmentation needs a phase map of kind \"micrograph\", the " \
        "scene's is 'homogeneous'" in err, f"exit {status}: {err!r}"
    assert not (tmp_path / "seg.png").exists(), "nothing written"


def test_script_writes_the_particle_image(make_micrograph, tmp_path, capsys):
    assert make_micrograph.main(["--particles", "-o", str(tmp_path / "p.png")]) == 0, "exit"
    grey, truth = make_micrograph.make_particles(**make_micrograph.PARTICLES)
    written = np.asarray(Image.open(tmp_path / "p.png"))
    assert np.array_equal(written, np.rint(grey * 255).astype(np.uint8)), "the image written"
    bar = written[make_micrograph.PARTICLES["rows"] - make_micrograph.PARTICLES["bar_rows"]:]
    assert np.isin(bar, (0, 255)).all(), "the data bar is black and white"
    fill = truth[:260].mean()
    assert f"{1 - fill:.4f}, {fill:.4f} (above the 40-row data bar)" in capsys.readouterr().out, \
        "true fill factors printed"
