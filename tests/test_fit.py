"""Wear ratios from a measured face: round trips through the forward model (eq. 7, 9).

Synthetic measured faces are the steady face of known wear coefficients
(:func:`steady.solution.solve`) plus an offset, a tilt, noise (white, or
correlated by a Gaussian filter) and NaN holes; the fit must recover the
ratios within its stated intervals, and the intervals must cover the truth
at their nominal rate.  The fit is linear, so the coverage does not depend
on the noise level; its width scales with it.  The paper's disk first, then
the other outlines of :mod:`steady.outline` (a 1:3 rectangle, an annulus, an
ellipse and the shipped aggregate chip's pixel mask).
"""

import pathlib
import re
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import E_STAR, FORCE, GEOMETRIES, K1, OUTLINES, RADIUS, problem
from scipy import ndimage

from steady import (
    FaceModel,
    HalfSpace,
    MeasuredFace,
    PowerLaw,
    Voronoi,
    fit_face,
    fit_scene,
    load_scene,
    pressure_field,
    read_fit,
    read_measured,
    solve,
    write_fit,
)
from steady.cli.fit import main
from steady.fit_files import fit_figure, plot_fit
from steady.outline import Circle, MaskOutline, Rectangle

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: Two phases: the gallery's Voronoi map (64 seeds, 30 % of phase 1), k_1/k_0 = 3.
TWO = (GEOMETRIES["voronoi"], (1.0, 3.0))
#: Three phases, 64 seeds; phase 2 wears half as fast as phase 0.
THREE = (Voronoi(64, (0.5, 0.3, 0.2), 3301), (1.0, 3.0, 0.5))


def pixel_size(n):
    """Pixel size of the n x n grid over the disk of :data:`RADIUS`, m."""
    return Circle(RADIUS).grid(n).h


def fit_problem(labels, outline=RADIUS, *, exponent=1.0):
    """The fit's model: ``labels`` on the outline's grid, E*, F_N and the power law of ``exponent``.

    Only the law's exponent enters the fit; its coefficients (all :data:`K1`
    here) are reported beside it as ``scene_ratios``.
    """
    wear = PowerLaw([K1] * (int(np.max(labels)) + 1), exponent=exponent)
    return problem(labels, wear, outline=outline)


def steady_face(geometry, ratios, n, *, E_star=E_STAR, exponent=1.0):
    """The forward model: steady face (m, NaN off the face), labels and relief."""
    wear = PowerLaw([K1 * r for r in ratios], exponent=exponent)
    model = problem(geometry, wear, n=n, E_star=E_star)
    result = solve(model)
    return result.face, model.labels, float(np.nanmax(result.face) - np.nanmin(result.face))


def plane(n, offset=2e-5, tilt=(1e-3, -4e-4)):
    """Offset plus tilt on the n x n grid, m."""
    x = (np.arange(n) - 0.5 * (n - 1)) * pixel_size(n)
    return offset + tilt[0] * x[:, None] + tilt[1] * x[None, :]


def noise(rng, shape, correlation=0.0):
    """Unit-variance noise of ``shape`` (``n``: n x n), smoothed over ``correlation`` pixels."""
    nx, ny = (shape, shape) if np.ndim(shape) == 0 else shape
    pad = int(4 * correlation) + 1
    w = rng.standard_normal((nx + 2 * pad, ny + 2 * pad))
    if correlation > 0:
        w = ndimage.gaussian_filter(w, correlation)
        delta = np.zeros((2 * pad + 1, 2 * pad + 1))
        delta[pad, pad] = 1.0
        w /= np.sqrt(np.sum(ndimage.gaussian_filter(delta, correlation) ** 2))
    return w[pad:pad + nx, pad:pad + ny]


def holes(n, seed):
    """Three round NaN holes of 3 pixels radius at random places."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    out = np.zeros((n, n), dtype=bool)
    for ci, cj in rng.integers(n // 4, 3 * n // 4, size=(3, 2)):
        out |= np.hypot(i - ci, j - cj) < 3
    return out


def in_interval(fit, ratios):
    lo, hi = fit.ratio_intervals.T
    return (lo <= np.asarray(ratios)) & (np.asarray(ratios) <= hi)


@pytest.mark.parametrize("n", [47, 48])
@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
def test_exact_face_is_recovered(case, n):
    """No noise: pressures, ratios, offset and tilt to round-off; the load scale is 1."""
    geometry, ratios = case
    face, labels, _ = steady_face(geometry, ratios, n)
    fit = fit_face(MeasuredFace(face + plane(n), pixel_size(n)), fit_problem(labels))
    assert fit.success, fit.message
    assert np.allclose(fit.ratios, ratios, rtol=1e-9), f"ratios {fit.ratios}"
    assert fit.offset == pytest.approx(2e-5, rel=1e-8), f"offset {fit.offset}"
    assert np.allclose(fit.tilt, (1e-3, -4e-4), rtol=1e-8), f"tilt {fit.tilt}"
    assert fit.load_scale == pytest.approx(1.0, rel=1e-9), "sum A_i p_i = F_N (eq. 5)"
    assert fit.samples == Circle(RADIUS).grid(n).mask.sum(), "every face pixel is fitted"


def test_summary_lists_the_phases_by_name():
    geometry, ratios = THREE
    face, labels, _ = steady_face(geometry, ratios, 48)
    fit = fit_face(MeasuredFace(face, pixel_size(48)), fit_problem(labels))
    named = fit.summary_lines(("matrix", "grains", "fibres"))
    assert named[0] == "wear ratios k_i/k_0 (95 % intervals; k_0 of matrix)", named[0]
    assert named[1].startswith("  grains         ") and named[2].startswith("  fibres  "), named
    assert named[3].startswith("phase pressures  matrix ") and ", fibres " in named[3], named[3]
    assert fit.summary_lines()[1].startswith("  phase 1        "), "the default names"


@pytest.mark.parametrize("exponent", [0.5, 2.0])
def test_power_law_ratios(exponent):
    """k_i p_i^m = C: the ratios are (p_0 / p_i)^m, whatever m."""
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n, exponent=exponent)
    fit = fit_face(MeasuredFace(face, pixel_size(n)), fit_problem(labels, exponent=exponent))
    assert fit.ratios[1] == pytest.approx(3.0, rel=1e-9), f"m = {exponent}: {fit.ratios}"
    expected = 3.0 ** (-1 / exponent)
    p = fit.phase_pressures
    assert p[1] / p[0] == pytest.approx(expected, rel=1e-9), "p_i ~ k_i^(-1/m) (eq. 7)"


@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
def test_round_trip_with_noise_tilt_offset_and_holes(case):
    """Noise of 1 % and 10 % of the relief, tilt, offset, NaN holes: truth within the intervals.

    Twenty realisations at each level (seeds 6101..6120, the same at both):
    the 95 % intervals may miss a few times (at most 4 of 20 per ratio: a
    1.6 % chance at the nominal rate).  The fit is linear, so ten times the
    noise gives exactly ten times the standard errors of the pressures.
    """
    geometry, ratios = case
    n = 41
    face, labels, relief = steady_face(geometry, ratios, n)
    gaps = holes(n, 6007)
    model = FaceModel(fit_problem(labels))
    errors = {}
    for level in (0.01, 0.1):
        misses = np.zeros(len(ratios), dtype=int)
        errors[level] = []
        for seed in range(6101, 6121):
            heights = face + plane(n) + level * relief * noise(np.random.default_rng(seed), n)
            heights[gaps] = np.nan
            fit = model.fit(MeasuredFace(heights, pixel_size(n)))
            assert fit.success, f"noise {level}, seed {seed}: {fit.message}"
            assert fit.samples == np.sum(Circle(RADIUS).grid(n).mask & ~gaps), \
                "holes are left out, not fatal"
            misses += ~in_interval(fit, ratios)
            errors[level].append(fit.phase_pressure_errors)
        assert np.all(misses <= 4), f"noise {level}: intervals missed {misses} times of 20"
    assert np.allclose(errors[0.1], 10 * np.array(errors[0.01]), rtol=1e-6), \
        "standard errors proportional to the noise"


@pytest.mark.parametrize("correlation", [0.0, 1.5], ids=["white", "correlated"])
def test_coverage_is_nominal(correlation):
    """The 95 % intervals contain the truth about 95 % of the time (120 realisations).

    Three phases at n = 32, noise of 10 % of the relief, white or smoothed
    by a Gaussian of 1.5 pixels (about 30 effective samples of 800 pixels).
    At 120 trials the binomial standard error is 2 %; the slow test measures
    the rate at 1000 trials.
    """
    geometry, ratios = THREE
    n = 32
    face, labels, relief = steady_face(geometry, ratios, n)
    model = FaceModel(fit_problem(labels))
    rng = np.random.default_rng(7411 if correlation else 7417)
    hits = np.zeros(len(ratios))
    trials = 120
    for _ in range(trials):
        heights = face + plane(n) + 0.1 * relief * noise(rng, n, correlation)
        hits += in_interval(model.fit(MeasuredFace(heights, pixel_size(n))), ratios)
    rate = hits[1:] / trials
    assert np.all((rate >= 0.89) & (rate <= 1.0)), f"coverage {rate} (nominal 0.95)"


@pytest.mark.slow
@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize("correlation", [0.0, 2.0], ids=["white", "correlated"])
def test_coverage_measured(case, correlation):
    """Coverage of the 95 % intervals over 1000 realisations (n = 40, 10 % noise).

    Measured (seeds 9059 white, 9049 correlated over 2 pixels): two phases 0.963
    (white) and 0.949 (correlated); three phases 0.951 / 0.961 (white) and
    0.965 / 0.948 (correlated); the load scale 0.950 .. 0.962.  The binomial
    standard error is 0.7 %.
    """
    geometry, ratios = case
    n = 40
    face, labels, relief = steady_face(geometry, ratios, n)
    model = FaceModel(fit_problem(labels))
    rng = np.random.default_rng(9049 if correlation else 9059)
    hits = np.zeros(len(ratios))
    load_hits = 0
    trials = 1000
    for _ in range(trials):
        heights = face + plane(n) + 0.1 * relief * noise(rng, n, correlation)
        fit = model.fit(MeasuredFace(heights, pixel_size(n)))
        hits += in_interval(fit, ratios)
        load_hits += fit.load_scale_interval[0] <= 1 <= fit.load_scale_interval[1]
    rate = hits[1:] / trials
    print(f"coverage {rate}, load scale {load_hits / trials}")
    assert np.all(np.abs(rate - 0.95) < 0.025), f"coverage {rate} (nominal 0.95)"
    assert abs(load_hits / trials - 0.95) < 0.025, f"load scale coverage {load_hits / trials}"


def test_other_grid_and_modulus():
    """A face measured on a finer grid with twice the scene's E*: ratios within the intervals.

    Model at n = 48, measurement at n = 96 (pixels half as large): the model's
    discretisation error (0.7 % of the relief) is a correlated residual and
    widens the intervals to cover it.  E* only scales the relief: the load
    scale is 1/2 and the implied modulus twice the scene's.
    """
    face, _, relief = steady_face(TWO[0], TWO[1], 96, E_star=2 * E_STAR)
    heights = face + 0.01 * relief * noise(np.random.default_rng(5807), 96)
    fit = fit_face(MeasuredFace(heights, pixel_size(96)), fit_problem(TWO[0].labels(48)))
    assert in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert abs(fit.ratios[1] / 3 - 1) < 0.02, f"ratio {fit.ratios[1]}"
    assert fit.load_scale == pytest.approx(0.5, rel=0.01), f"load scale {fit.load_scale}"
    assert fit.implied_E_star == pytest.approx(2 * E_STAR, rel=0.01), "implied E*"
    assert fit.effective_samples < 0.1 * fit.samples, "the model error is a correlated residual"


def test_shift_is_found():
    """The face sits 3 pixels right and 2 down of the map's centre: the search finds it."""
    n, pad = 48, 6
    face, labels, relief = steady_face(TWO[0], TWO[1], n)
    h = pixel_size(n)
    heights = np.full((n + 2 * pad, n + 2 * pad), np.nan)
    heights[pad + 3:pad + 3 + n, pad - 2:pad - 2 + n] = (
        face + plane(n) + 0.01 * relief * noise(np.random.default_rng(4421), n))
    measured = MeasuredFace(heights, h)
    fit = fit_face(measured, fit_problem(labels), search_shift=True, max_shift=5 * h)
    assert np.allclose(fit.shift, (3 * h, -2 * h), atol=0.05 * h), \
        f"shift {np.divide(fit.shift, h)} pixels"
    assert in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert fit.residual_rms < 0.015 * relief, f"residual {fit.residual_rms / relief} of relief"
    unshifted = fit_face(measured, fit_problem(labels), rim_margin=5 * h)
    assert unshifted.residual_rms > 3 * fit.residual_rms, "a misplaced map fits worse"


def test_faster_phase_is_only_bounded_below():
    """Phase 1 wears 10^4 times faster: its pressure is not told from zero, the ratio is a bound."""
    n = 40
    face, labels, relief = steady_face(TWO[0], (1.0, 1e4), n)
    heights = face + 0.1 * relief * noise(np.random.default_rng(6653), n)
    fit = fit_face(MeasuredFace(heights, pixel_size(n)), fit_problem(labels))
    lo, hi = fit.ratio_intervals[1]
    assert np.isinf(hi) and 1 < lo < 1e4, f"interval {lo, hi}"
    assert "bounded only from below" in fit.message, fit.message


def test_upside_down_map_fails_with_a_reason():
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n)
    fit = fit_face(MeasuredFace(-face, pixel_size(n)), fit_problem(labels))
    assert not fit.success, "negative pressures are not a success"
    assert "not positive" in fit.message and "upside down" in fit.message, fit.message


def test_errors_name_the_problem():
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n)
    h = pixel_size(n)
    with pytest.raises(ValueError,
                       match=r"36 x 36 pixels .* cannot cover the circle face \(radius 4 mm\) "
                             r"of 8 x 8 mm"):
        fit_face(MeasuredFace(face[2:-2, 2:-2], h), fit_problem(labels))
    with pytest.raises(ValueError, match=r"cannot cover the circle face"):
        fit_face(MeasuredFace(face, 0.9 * h), fit_problem(labels))
    absent = np.where(labels == 1, np.nan, face)
    with pytest.raises(ValueError, match=r"phase 1 covers 0 of the \d+ fitted pixels"):
        fit_face(MeasuredFace(absent, h), fit_problem(labels))
    with pytest.raises(ValueError, match="reference_phase must be a phase index 0..1"):
        fit_face(MeasuredFace(face, h), fit_problem(labels), reference_phase=2)
    with pytest.raises(ValueError, match="confidence must lie in"):
        fit_face(MeasuredFace(face, h), fit_problem(labels), confidence=95)
    with pytest.raises(ValueError, match=r"rim_margin must be a number >= 0 \(m\), got -0.0001"):
        fit_face(MeasuredFace(face, h), fit_problem(labels), rim_margin=-1e-4)
    with pytest.raises(ValueError, match="nothing left to fit"):
        fit_face(MeasuredFace(face, h), fit_problem(labels), rim_margin=RADIUS)
    with pytest.raises(ValueError, match="2-d array"):
        MeasuredFace(face[0], h)
    with pytest.raises(ValueError, match="no finite height"):
        MeasuredFace(np.full((4, 4), np.nan), h)
    with pytest.raises(ValueError, match=r"measured map array pixel_size must be a number > 0 "
                                         r"\(m\), got -"):
        MeasuredFace(face, -h)
    with pytest.raises(ValueError, match=r"measured map array pixel_size must be one or two "
                                         r"lengths \(m\), got \(1, 2, 3\)"):
        MeasuredFace(face, (1, 2, 3))


def test_collinear_phase_is_undetermined():
    """A ring at the rim seen from a small central disk: not determined.

    There the ring's face is a smooth radial bowl, a combination of the inner
    phase's face and the plane to 1e-7.
    """
    n = 200
    grid = Circle(RADIUS).grid(n)
    r, _ = grid.polar()
    labels = np.where(r < 0.5 * RADIUS, 0, 1)
    labels[~grid.mask] = -1
    model = FaceModel(fit_problem(labels))
    face = np.tensordot([2e5, 1e5], model.faces, axes=1)
    with pytest.raises(ValueError, match=r"phase 1: its face is a combination of the other"):
        model.fit(MeasuredFace(face, pixel_size(n)), rim_margin=0.93 * RADIUS,
                  min_phase_pixels=0)


def test_readers(tmp_path):
    heights = np.arange(12.0).reshape(3, 4)
    heights[1, 2] = np.nan
    np.save(tmp_path / "m.npy", heights)
    np.savetxt(tmp_path / "m.txt", heights)
    np.savetxt(tmp_path / "m.csv", heights, delimiter=",")
    for name in ("m.npy", "m.txt", "m.csv"):
        face = read_measured(tmp_path / name, pixel_size=(1e-4, 2e-4), height_scale=1e-6)
        assert np.allclose(face.heights, heights * 1e-6, equal_nan=True), name
        assert face.pixel_size == (1e-4, 2e-4) and face.extent == pytest.approx((3e-4, 8e-4))
    with pytest.raises(ValueError, match=r"pixel size of .*m.npy.* is unknown"):
        read_measured(tmp_path / "m.npy")
    with pytest.raises(FileNotFoundError, match="nope.npy' does not exist"):
        read_measured(tmp_path / "nope.npy", pixel_size=1e-4)
    with pytest.raises(ValueError, match=r"height_scale must be a number > 0 \(m per file unit\), "
                                         r"got 0"):
        read_measured(tmp_path / "m.npy", pixel_size=1e-4, height_scale=0)


def test_profilometer_file_without_surface_topography(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)
    (tmp_path / "m.x3p").write_bytes(b"PK")
    with pytest.raises(ValueError, match=r"pip install 'runin\[surface\]'"):
        read_measured(tmp_path / "m.x3p")


def test_profilometer_file_through_surface_topography(tmp_path):
    """An x3p file (ISO 25178-72) written by SurfaceTopography: heights and pixel size in m."""
    st = pytest.importorskip("SurfaceTopography")
    heights = np.random.default_rng(2203).standard_normal((12, 10))
    masked = np.ma.masked_array(heights, mask=np.zeros_like(heights, dtype=bool))
    masked.mask[3, 4] = True
    st.Topography(masked, physical_sizes=(1.2, 1.0), unit="mm").to_x3p(tmp_path / "m.x3p")
    face = read_measured(tmp_path / "m.x3p")
    assert face.shape == (12, 10) and np.allclose(face.pixel_size, (1e-4, 1e-4)), face
    assert np.isnan(face.heights[3, 4]) and np.isnan(face.heights).sum() == 1, "undefined pixel"
    ok = ~np.isnan(face.heights)
    assert np.allclose(face.heights[ok], 1e-3 * heights[ok]), "heights converted to m"
    with pytest.raises(ValueError, match="given, but"):
        read_measured(tmp_path / "m.x3p", pixel_size=2e-4)


def test_file_round_trip_and_figure(tmp_path):
    n = 41
    face, labels, relief = steady_face(THREE[0], THREE[1], n)
    heights = face + plane(n) + 0.05 * relief * noise(np.random.default_rng(3907), n)
    fit = fit_face(MeasuredFace(heights, pixel_size(n), source="synthetic"),
                   fit_problem(labels))
    path = write_fit(tmp_path / "fit.h5", fit)
    stored = read_fit(path)
    assert np.array_equal(stored.attrs["ratios"], fit.ratios), "ratios stored"
    assert np.array_equal(stored.attrs["ratio_upper"], fit.ratio_intervals[:, 1]), "intervals"
    assert np.array_equal(stored.arrays["residual"], fit.residual, equal_nan=True), "residual"
    assert stored.attrs["success"] and stored.attrs["measured_source"] == "synthetic"
    with h5py.File(path) as f:
        assert f.attrs["format"] == "runin.fit" and f.attrs["format_version"] == 3, "layout"
        assert f["outline"].attrs["kind"] == "circle", "the outline is recorded"
        assert f["outline/radius"][()] == RADIUS and f["radius"][()] == RADIUS, "radius"
        assert f["phase_pressures"].attrs["units"] == "Pa" and f["fitted"].attrs["units"] == "m"
        assert np.array_equal(f["residual"][()], fit.residual.T, equal_nan=True), "stored (y, x)"
    with pytest.raises(ValueError, match="exists"):
        write_fit(path, fit)
    png = plot_fit(path, tmp_path / "fit.png")
    assert png.stat().st_size > 20_000, "figure drawn"


def test_fit_scene_uses_the_scene(scene_file):
    scene = load_scene(scene_file("steady", n=40))
    truth = solve(problem(scene.geometry, scene.wear, n=40, force=scene.normal_force))
    fit = fit_scene(scene, MeasuredFace(truth.face, pixel_size(40)))
    assert np.allclose(fit.ratios, fit.scene_ratios, rtol=1e-9), "ratios of the scene"
    assert fit.scene_ratios[1] == pytest.approx(10.0), "scene ratios reported"


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "steady.cli.fit", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_command_line(tmp_path, scene_file, capsys):
    scene_path = scene_file("steady", n=40)
    scene = load_scene(scene_path)
    truth = solve(problem(scene.geometry, [1e-9, 4e-9], n=40))
    np.save(tmp_path / "face.npy", truth.face * 1e6)       # micrometres
    args = [str(scene_path), str(tmp_path / "face.npy"), "--pixel-size", "2e-4",
            "--height-scale", "1e-6", "-o", str(tmp_path / "fit.h5")]
    assert main(args + ["--plot", str(tmp_path / "fit.png")]) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    assert re.search(r"phase 1\s+4\s+\[4, 4\]\s+\(scene: 10\)", out), out
    assert (tmp_path / "fit.png").stat().st_size > 20_000, "figure drawn"
    assert main(args) == 2 and "exists (use --force" in capsys.readouterr().err
    np.save(tmp_path / "face.npy", -truth.face)
    assert main(args[:4] + args[6:] + ["--force"]) == 1, "negative pressures: exit 1"
    assert "upside down" in capsys.readouterr().out


@pytest.mark.parametrize("extra, fragment", [
    ([], "pixel size of"),
    (["--pixel-size", "1e-4"], "cannot cover the circle face"),
    (["--pixel-size", "2e-4", "--reference-phase", "3"], "reference_phase"),
    (["--pixel-size", "2e-4", "--confidence", "1.5"], "confidence must lie in"),
])
def test_command_line_errors(tmp_path, scene_file, capsys, extra, fragment):
    scene_path = scene_file("steady", n=40)
    np.save(tmp_path / "face.npy", np.zeros((40, 40)))
    status = main([str(scene_path), str(tmp_path / "face.npy"), "-o", str(tmp_path / "fit.h5"),
                   *extra])
    err = capsys.readouterr().err
    assert status == 2, f"exit {status}: {err}"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert fragment in lines[0], f"{lines[0]!r} lacks {fragment!r}"
    assert not (tmp_path / "fit.h5").exists(), "no output after an error"


def test_module_runs_as_a_command(tmp_path, scene_file):
    """``python -m steady.cli.fit``: bad input is one line on stderr, exit 2, no traceback."""
    scene_path = scene_file("steady", n=40)
    np.save(tmp_path / "face.npy", np.zeros((30, 30)))
    proc = run_cli(scene_path, "face.npy", "--pixel-size", "2e-4", "-o", "fit.h5", cwd=tmp_path)
    assert proc.returncode == 2, f"exit {proc.returncode}: {proc.stderr}"
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: measured map"), \
        proc.stderr
    assert "30 x 30 pixels" in proc.stderr and "circle face (radius 4 mm) of 8 x 8 mm" \
        in proc.stderr, proc.stderr


def test_docs_example(tmp_path, monkeypatch):
    """The fit's example in docs/library.md runs as written, in an empty directory."""
    page = (ROOT / "docs" / "library.md").read_text()
    section = page.split("## Wear ratios from a measured face", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(code, "docs/library.md", "exec"), namespace)
    fit = namespace["fit"]
    assert fit.success and fit.ratio_intervals[1, 0] <= 1.7 <= fit.ratio_intervals[1, 1], fit


# Other outlines (steady.outline): the gallery's 1:3 rectangle (2.67 x 8 mm, the long side
# along y), annulus (radii 2 and 4 mm) and ellipse, and the shipped aggregate chip's mask.

#: The shipped aggregate chip: a mask face of 96 x 72 pixels of 0.125 mm (12 x 9 mm box).
CHIP = ROOT / "steady" / "examples" / "aggregate_chip.toml"


def chip_outline():
    return load_scene(CHIP).outline


def outline_face(outline, geometry, ratios, n, *, E_star=E_STAR):
    """The forward model on an outline's grid: face (m, NaN off it), labels, relief, grid.

    Eq. 7 (:func:`steady.pressures.pressure_field`) and eq. 9 (the half-space
    product on the grid of the bounding box): :func:`steady.solution.solve`
    without its normalisation, which for an ellipse or a mask costs an
    estimate on a fine grid that the fit does not use
    (:func:`test_forward_model_is_the_solver`).
    """
    grid = outline.grid(n)
    labels = geometry.labels(grid)
    pressure, _, _ = pressure_field(labels, [K1 * r for r in ratios], FORCE, grid.h**2,
                                    face_mask=grid.mask)
    face = HalfSpace(grid.shape, grid.h, E_star).displacement(pressure)
    face[~grid.mask] = np.nan
    return face, labels, float(np.nanmax(face) - np.nanmin(face)), grid


def grid_plane(grid, offset=2e-5, tilt=(1e-3, -4e-4)):
    """Offset plus tilt on an outline's grid, m."""
    return offset + tilt[0] * grid.x[:, None] + tilt[1] * grid.y[None, :]


def test_forward_model_is_the_solver():
    """The helper's face is the solver's on the rectangle, to round-off."""
    outline = OUTLINES["rectangle"]
    face, labels, _, grid = outline_face(outline, *TWO, 48)
    result = solve(problem(labels, [K1, 3 * K1], outline=outline))
    assert np.allclose(face, result.face, rtol=1e-12, atol=0, equal_nan=True), \
        "pressure_field + HalfSpace is solve's face"


@pytest.mark.parametrize("n", [41, 48])
@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize("name", ["rectangle", "annulus", "ellipse"])
def test_exact_face_on_outlines(name, case, n):
    """No noise: ratios, offset and tilt to round-off; load scale 1; every face pixel fitted."""
    geometry, ratios = case
    outline = OUTLINES[name]
    face, labels, _, grid = outline_face(outline, geometry, ratios, n)
    fit = fit_face(MeasuredFace(face + grid_plane(grid), grid.h), fit_problem(labels, outline))
    assert fit.success, fit.message
    assert np.allclose(fit.ratios, ratios, rtol=1e-9), f"{name}: ratios {fit.ratios}"
    assert fit.offset == pytest.approx(2e-5, rel=1e-8), f"{name}: offset {fit.offset}"
    assert np.allclose(fit.tilt, (1e-3, -4e-4), rtol=1e-8), f"{name}: tilt {fit.tilt}"
    assert fit.load_scale == pytest.approx(1.0, rel=1e-9), "sum A_i p_i = F_N (eq. 5)"
    assert fit.samples == grid.mask.sum(), f"{name}: every face pixel is fitted"
    assert fit.outline == outline and not isinstance(fit.outline, Circle), \
        "the result carries the outline, not a disk's radius"
    assert np.array_equal(fit.phase, labels), f"{name}: phases on the measured grid"
    assert np.array_equal(np.isfinite(fit.fitted), grid.mask), "fitted face on the face only"


#: Largest relative error of each ratio over the 20 seeds 6101..6120 at n = 48
#: (rectangle, 16 x 48 pixels) and 41 (annulus), noise 1 % and 10 % of the relief
#: (measured; the bounds asserted are 1.25 times these).  The median half-width of
#: the 95 % intervals, for comparison: 1.2 % and 13 % (rectangle, two phases),
#: 3.6 % / 0.6 % and 36 % / 6.4 % (rectangle, three), 1.1 % and 11 % (annulus, two),
#: 2.4 % / 0.45 % and 28 % / 4.5 % (annulus, three).
ROUND_TRIP_ERRORS = {
    ("rectangle", "two"): {0.01: (0.0105,), 0.1: (0.113,)},
    ("rectangle", "three"): {0.01: (0.0295, 0.0072), 0.1: (0.415, 0.069)},
    ("annulus", "two"): {0.01: (0.0139,), 0.1: (0.163,)},
    ("annulus", "three"): {0.01: (0.0347, 0.0039), 0.1: (0.523, 0.038)},
}


@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize("name, n", [("rectangle", 48), ("annulus", 41)],
                         ids=["rectangle", "annulus"])
def test_round_trip_on_outlines(name, n, case):
    """Noise of 1 % and 10 % of the relief, tilt and offset: the truth within the intervals.

    Twenty realisations at each level (seeds 6101..6120, the same at both):
    the 95 % intervals may miss a few times (at most 4 of 20 per ratio: a
    1.6 % chance at the nominal rate; measured: at most 1 on the rectangle, 2
    on the annulus).  The largest relative error of each ratio stays within
    1.25 times the measured one (:data:`ROUND_TRIP_ERRORS`: 1.0 to 1.4 % and
    11 to 16 % for k_1/k_0 = 3 with two phases; 3 to 3.5 % and 42 to 52 % for
    that ratio with three phases, where phase 1 carries a third of phase 0's
    pressure and phase 2 twice it; 0.4 to 0.7 % and 4 to 7 % for k_2/k_0 =
    0.5).  Ten times the noise gives ten times the pressures' errors.
    """
    geometry, ratios = case
    outline = OUTLINES[name]
    face, labels, relief, grid = outline_face(outline, geometry, ratios, n)
    model = FaceModel(fit_problem(labels, outline))
    key = (name, "two" if len(ratios) == 2 else "three")
    errors = {}
    for level in (0.01, 0.1):
        misses = np.zeros(len(ratios), dtype=int)
        worst = np.zeros(len(ratios))
        errors[level] = []
        for seed in range(6101, 6121):
            heights = face + grid_plane(grid) + level * relief * noise(
                np.random.default_rng(seed), grid.shape)
            fit = model.fit(MeasuredFace(heights, grid.h))
            assert fit.success, f"{name}, noise {level}, seed {seed}: {fit.message}"
            misses += ~in_interval(fit, ratios)
            worst = np.maximum(worst, np.abs(fit.ratios / ratios - 1))
            errors[level].append(fit.phase_pressure_errors)
        assert np.all(misses <= 4), f"{key}, noise {level}: intervals missed {misses} of 20"
        bound = 1.25 * np.array(ROUND_TRIP_ERRORS[key][level])
        assert np.all(worst[1:] <= bound), \
            f"{key}, noise {level}: largest relative errors {worst[1:]} (bounds {bound})"
    assert np.allclose(errors[0.1], 10 * np.array(errors[0.01]), rtol=1e-6), \
        "standard errors proportional to the noise"


def exact_mask_rim_distance(outline, x, y):
    """Distance (m) from points of a mask face to its rim: to the nearest square off the face."""
    lx, ly = outline.half_extent
    size = outline.pixel_size
    i, j = np.nonzero(~outline.mask)
    cx, cy = (i + 0.5) * size - lx, (j + 0.5) * size - ly
    out = np.minimum.reduce([x + lx, lx - x, y + ly, ly - y])   # the mask's own box
    for s in range(0, x.size, 500):
        ax = np.maximum(np.abs(x[s:s + 500, None] - cx) - 0.5 * size, 0.0)
        ay = np.maximum(np.abs(y[s:s + 500, None] - cy) - 0.5 * size, 0.0)
        out[s:s + 500] = np.minimum(out[s:s + 500], np.hypot(ax, ay).min(axis=1))
    return out


def test_mask_outline_round_trip():
    """The shipped aggregate chip's face (a pixel mask): ratio within its interval, rim margin.

    Model at n = 96 (one pixel per mask pixel, 3420 face pixels), the gallery's
    Voronoi map with k_1/k_0 = 3, noise of 1 % of the relief, tilt, offset.  A
    rim margin of 0.3 mm comes from the distance transform (a mask has no
    closed form): at the pixel centres it is within 0.21 h of the exact
    distance to the nearest square off the face (measured: (sqrt 2 - 1) h / 2,
    a diagonal neighbour), so every pixel kept lies more than 0.3 mm - 0.21 h
    from the rim and every face pixel left out within 0.3 mm + 0.21 h.
    Measured: 2879 pixels kept, the same count as the exact distances give;
    k1/k0 = 3.004 [2.984, 3.025].
    """
    outline = chip_outline()
    assert isinstance(outline, MaskOutline), outline
    face, labels, relief, grid = outline_face(outline, *TWO, 96)
    heights = face + grid_plane(grid) + 0.01 * relief * noise(np.random.default_rng(5413),
                                                              grid.shape)
    margin = 3e-4
    fit = fit_face(MeasuredFace(heights, grid.h), fit_problem(labels, outline),
                   rim_margin=margin)
    assert fit.success and in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert abs(fit.ratios[1] / 3 - 1) < 0.01, f"ratio {fit.ratios[1]} (1 % noise)"
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    exact = exact_mask_rim_distance(outline, X[grid.mask], Y[grid.mask])
    kept = fit.fit_mask[grid.mask]
    tolerance = 0.21 * grid.h
    assert np.all(exact[kept] > margin - tolerance), "a pixel kept lies within the margin"
    assert np.all(exact[~kept] <= margin + tolerance), "a pixel left out lies beyond the margin"
    assert abs(int(kept.sum()) - int(np.sum(exact > margin))) <= 10, \
        f"{kept.sum()} pixels kept, {np.sum(exact > margin)} by the exact distance"
    assert np.array_equal(fit.phase >= 0, grid.mask), "phase -1 exactly off the mask's face"


def test_rim_margin_on_rectangle():
    """Points within the margin of the rectangle's sides are left out, and counted.

    Model and measurement on the 16 x 48 grid of the 1:3 rectangle (pixel h):
    pixel centres lie (j + 1/2) h from a side, so a margin of 2.2 h leaves
    out two rows on every side, (16 - 4) x (48 - 4) = 528 pixels kept; on a
    map twice as fine, four rows of its pixels, (32 - 8) x (96 - 8) = 2112.
    The closed form and the distance transform agree to round-off at the
    model's pixel centres, where the rectangle's sides are pixel edges.
    """
    outline = OUTLINES["rectangle"]
    face, labels, _, grid = outline_face(outline, *TWO, 48)
    h = grid.h
    model = FaceModel(fit_problem(labels, outline))
    fit = model.fit(MeasuredFace(face, h), rim_margin=2.2 * h)
    assert fit.samples == 12 * 44, f"{fit.samples} pixels kept, 528 expected"
    expected = np.zeros(grid.shape, dtype=bool)
    expected[2:-2, 2:-2] = True
    assert np.array_equal(fit.fit_mask, expected), "the pixels within 2.2 h of a side are out"
    assert np.allclose(fit.ratios, TWO[1], rtol=1e-9), "exact face, exact ratios"
    fine = outline_face(outline, *TWO, 96)[0]
    fit = model.fit(MeasuredFace(fine, 0.5 * h), rim_margin=2.2 * h)
    assert fit.samples == 24 * 88, f"{fit.samples} fine pixels kept, 2112 expected"
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    assert np.allclose(model.rim_distance(X, Y, closed_form=False), model.rim_distance(X, Y),
                       rtol=0, atol=1e-12 * h), "distance transform = closed form at centres"


@pytest.mark.parametrize("name, n", [("circle", 40), ("annulus", 41), ("rectangle", 40)])
def test_distance_transform_against_closed_forms(name, n):
    """The distance transform of outlines without a closed form, tried where there is one.

    Measured (the disk at n = 40 and 96, the annulus at n = 40, 41 and 96):
    within 0.49 h of the exact distance at the face's pixel centres, and
    within 1.05 h at random points of the face (interpolated between the
    centres, across the pixel staircase of the rim).  The bounds asserted:
    0.5 h and 1.1 h.
    """
    outline = OUTLINES[name]
    grid = outline.grid(n)
    model = FaceModel(fit_problem(GEOMETRIES["voronoi"].labels(grid), outline))
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    x, y = X[grid.mask], Y[grid.mask]
    error = np.abs(model.rim_distance(x, y, closed_form=False) - model.rim_distance(x, y))
    assert error.max() < 0.5 * grid.h, f"{name}: {error.max() / grid.h:.3f} h at centres"
    rng = np.random.default_rng(7723)
    lx, ly = outline.half_extent
    x, y = rng.uniform(-lx, lx, 20000), rng.uniform(-ly, ly, 20000)
    inside = outline.contains(x, y)
    x, y = x[inside], y[inside]
    error = np.abs(model.rim_distance(x, y, closed_form=False) - model.rim_distance(x, y))
    assert error.max() < 1.1 * grid.h, f"{name}: {error.max() / grid.h:.3f} h between centres"


def test_phases_off_the_outline():
    """``phases_at`` is -1 off the face of the outline: the annulus's hole, beyond its sides."""
    annulus = FaceModel(fit_problem(TWO[0].labels(OUTLINES["annulus"].grid(41)),
                                    OUTLINES["annulus"]))
    x = np.array([0.0, 1.9e-3, 3e-3, 0.0, 4.1e-3])
    y = np.array([0.0, 0.0, 0.0, -3e-3, 0.0])
    phases = annulus.phases_at(x, y)
    assert np.all(phases[[0, 1, 4]] == -1), f"the hole and the outside: {phases}"
    assert np.all(phases[[2, 3]] >= 0), f"on the ring: {phases}"
    rectangle = FaceModel(fit_problem(TWO[0].labels(OUTLINES["rectangle"].grid(48)),
                                      OUTLINES["rectangle"]))
    phases = rectangle.phases_at(np.array([1.4e-3, 1.2e-3, 0.0]), np.array([0.0, 3.9e-3, 4.1e-3]))
    assert phases[0] == -1 and phases[1] >= 0 and phases[2] == -1, \
        f"beyond the half width 1.33 mm, inside, beyond the half length 4 mm: {phases}"


def test_shift_search_on_rectangle():
    """The face sits a pixel right and a pixel down of the map's centre: the search finds it.

    Its default radius is 0.05 L, L = 4 mm the rectangle's scale (half its
    long side): 0.2 mm, 2.4 pixels at n = 96 (h = 1/12 mm), beyond the shift's
    0.12 mm.  Every trial shift sees the same pixels, those farther than
    0.2 mm from the sides about the map's centre: (32 - 4) x (96 - 4) = 2576.
    """
    outline = OUTLINES["rectangle"]
    face, labels, relief, grid = outline_face(outline, *TWO, 96)
    h, pad = grid.h, 4
    nx, ny = grid.shape
    heights = np.full((nx + 2 * pad, ny + 2 * pad), np.nan)
    heights[pad + 1:pad + 1 + nx, pad - 1:pad - 1 + ny] = (
        face + grid_plane(grid) + 0.01 * relief * noise(np.random.default_rng(4423), grid.shape))
    fit = fit_face(MeasuredFace(heights, h), fit_problem(labels, outline), search_shift=True)
    assert np.allclose(fit.shift, (h, -h), atol=0.05 * h), \
        f"shift {np.divide(fit.shift, h)} pixels"
    assert fit.samples == 28 * 92, f"{fit.samples} pixels, 2576 expected (erosion 0.05 L)"
    assert in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert "search limit" not in fit.message, fit.message


def test_errors_on_outlines():
    """A map that does not cover the rectangle, a phase absent, nothing left of the annulus."""
    outline = OUTLINES["rectangle"]
    face, labels, _, grid = outline_face(outline, *TWO, 48)
    h = grid.h
    sizes = (r"cannot cover the rectangle face \(width 2.66667 mm, length 8 mm\) of 2.667 x "
             r"8 mm")
    with pytest.raises(ValueError, match=r"16 x 40 pixels of 0.1667 x 0.1667 mm \(2.667 x "
                                         r"6.667 mm\) " + sizes):
        fit_face(MeasuredFace(face[:, 4:-4], h), fit_problem(labels, outline))
    with pytest.raises(ValueError, match=r"48 x 16 pixels .* \(8 x 2.667 mm\) " + sizes):
        fit_face(MeasuredFace(face.T, h), fit_problem(labels, outline))   # x and y swapped
    with pytest.raises(ValueError, match=r"the part fitted .* 2 x 7.333 mm"):
        fit_face(MeasuredFace(face, h), fit_problem(labels, outline), shift=(0.0, 1e-3),
                 rim_margin=1 / 3 * 1e-3)
    absent = np.where(labels == 1, 2, labels)                     # phases 0 and 2, no 1
    with pytest.raises(ValueError, match=r"phase 1 has no pixel on the face"):
        FaceModel(fit_problem(absent, outline))
    hidden = np.where(labels == 1, np.nan, face)
    with pytest.raises(ValueError, match=r"phase 1 covers 0 of the \d+ fitted pixels"):
        fit_face(MeasuredFace(hidden, h), fit_problem(labels, outline))
    with pytest.raises(ValueError, match=r"labels must have shape \(16, 48\) to match the grid "
                                         r"of the rectangle face .* at n = 48, got \(48, 48\)"):
        FaceModel(fit_problem(TWO[0].labels(48), outline))
    ring = OUTLINES["annulus"]
    ring_face, ring_labels, _, ring_grid = outline_face(ring, *TWO, 41)
    with pytest.raises(ValueError, match=r"nothing left to fit: .* annulus face \(inner_radius "
                                         r"2 mm, outer_radius 4 mm\)"):
        fit_face(MeasuredFace(ring_face, ring_grid.h), fit_problem(ring_labels, ring),
                 rim_margin=1e-3)


@pytest.mark.parametrize("path, n", [("tread_block.toml", 120), ("annular_seal.toml", 80),
                                     ("elliptic_pad.toml", 64), ("aggregate_chip.toml", 192)])
def test_shipped_scenes(path, n):
    """Each shipped outline's scene fits its own steady face: the scene's ratios to round-off."""
    scene = load_scene(ROOT / "steady" / "examples" / path)
    ratios = np.array(scene.wear.coefficients) / K1
    face, _, _, grid = outline_face(scene.outline, scene.geometry, ratios, n,
                                    E_star=scene.E_star)
    face *= scene.normal_force / FORCE                 # outline_face loads with FORCE
    fit = fit_scene(scene, MeasuredFace(face, grid.h), n=n)
    assert fit.success, f"{path}: {fit.message}"
    assert np.allclose(fit.ratios, fit.scene_ratios, rtol=1e-8), \
        f"{path}: {fit.ratios} vs the scene's {fit.scene_ratios}"
    assert fit.load_scale == pytest.approx(1.0, rel=1e-8), f"{path}: load scale"
    assert fit.outline is scene.outline and fit.n == n, "the scene's outline and grid"


def test_command_line_on_rectangle(tmp_path, scene_file, capsys):
    """A rectangle scene through ``runin-fit``: ratio, file with its outline, figure on its box."""
    punch = {"shape": "rectangle", "width": 2 * RADIUS / 3, "length": 2 * RADIUS}
    scene_path = scene_file("steady", n=48, punch=punch)
    scene = load_scene(scene_path)
    face, _, _, grid = outline_face(scene.outline, scene.geometry, (1.0, 4.0), 48)
    np.save(tmp_path / "face.npy", face * 1e6)             # micrometres
    args = [str(scene_path), str(tmp_path / "face.npy"), "--pixel-size", repr(grid.h),
            "--height-scale", "1e-6", "-o", str(tmp_path / "fit.h5")]
    assert main(args + ["--plot", str(tmp_path / "fit.png")]) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    assert re.search(r"phase 1\s+4\s+\[4, 4\]\s+\(scene: 10\)", out), out
    assert "rectangle face (width 2.66667 mm, length 8 mm), model grid n = 48" in out, out
    stored = read_fit(tmp_path / "fit.h5")
    assert stored.outline == scene.outline and stored.version == 3, stored.outline
    assert stored.attrs["radius"] is None and stored.attrs["scale"] == RADIUS, "scale L"
    with h5py.File(tmp_path / "fit.h5") as f:
        group = f["outline"]
        assert group.attrs["kind"] == "rectangle" and group["width"].attrs["units"] == "m", \
            dict(group["width"].attrs)
        assert group["length"][()] == 2 * RADIUS and "radius" not in f, "lengths in m"
    assert (tmp_path / "fit.png").stat().st_size > 20_000, "figure drawn"
    fig = fit_figure(stored)
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 3, f"{len(fig.axes)} axes"
    for ax in panels:
        assert np.allclose(ax.get_xlim(), (-RADIUS / 3 * 1e3, RADIUS / 3 * 1e3)), ax.get_xlim()
        assert np.allclose(ax.get_ylim(), (-RADIUS * 1e3, RADIUS * 1e3)), ax.get_ylim()
        assert ax.get_aspect() == 1.0, "equal aspect"
        assert ax.get_subplotspec().get_geometry()[:2] == (1, 3), "tall: side by side"

    np.save(tmp_path / "face.npy", face[:, 2:-2] * 1e6)
    status = main(args + ["--force"])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1, err
    assert "16 x 44 pixels" in err and "(2.667 x 7.333 mm)" in err and "of 2.667 x 8 mm" in err, \
        err


def test_figure_of_a_wide_face(tmp_path):
    """A face more than twice as wide as tall: the three panels stacked, on its box."""
    outline = Rectangle(2 * RADIUS, 2 * RADIUS / 3)
    face, labels, _, grid = outline_face(outline, *TWO, 48)
    fit = fit_face(MeasuredFace(face, grid.h), fit_problem(labels, outline))
    fig = fit_figure(read_fit(write_fit(tmp_path / "fit.h5", fit)))
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert [ax.get_subplotspec().get_geometry()[:2] for ax in panels] == [(3, 1)] * 3, "stacked"
    assert np.allclose(panels[0].get_ylim(), (-RADIUS / 3 * 1e3, RADIUS / 3 * 1e3)), "box"
    width, height = fig.get_size_inches()
    assert width < 12 and height > width, f"figure {width} x {height} in"


@pytest.mark.parametrize("name", ["annulus", "mask"])
def test_fit_file_records_the_outline(tmp_path, name):
    """Kind and lengths with units; a mask's own mask."""
    outline = chip_outline() if name == "mask" else OUTLINES[name]
    face, labels, _, grid = outline_face(outline, *TWO, 96 if name == "mask" else 41)
    fit = fit_face(MeasuredFace(face, grid.h), fit_problem(labels, outline))
    stored = read_fit(write_fit(tmp_path / "fit.h5", fit))
    assert type(stored.outline) is type(outline), stored.outline
    assert stored.outline.parameters() == outline.parameters(), "lengths"
    with h5py.File(tmp_path / "fit.h5") as f:
        group = f["outline"]
        assert group.attrs["kind"] == outline.kind and group["area"].attrs["units"] == "m2"
        if name == "mask":
            assert np.array_equal(group["mask"][()], outline.mask.T), "the mask, stored (y, x)"
            assert np.array_equal(stored.outline.mask, outline.mask), "read back"
            assert group["pixel_size"].attrs["units"] == "m", dict(group["pixel_size"].attrs)
        else:
            assert group["inner_radius"][()] == outline.inner_radius, list(group)
            assert group["outer_radius"].attrs["units"] == "m", dict(group["outer_radius"].attrs)
    assert np.array_equal(stored.arrays["phase"], fit.phase), "phase map on the measured grid"


def _as_attributes(f):
    """A fit file of layout 3 turned to the layouts before, in place.

    The root quantities become attribute pairs ``x``, ``x_units``; the fields are stored
    ``(nx, ny)``, without their dimension scales.
    """
    fields = ("measured", "fitted", "residual", "fit_mask", "phase")
    scales = ("x", "y", "phase_name", "other_phase_name", "component")
    for name, ds in list(f.items()):
        if isinstance(ds, h5py.Dataset) and name not in (*fields, *scales, "scene"):
            f.attrs[name], f.attrs[f"{name}_units"] = ds[()], ds.attrs["units"]
            del f[name]
    for name in fields:
        values = f[name][()].T
        del f[name]
        f.create_dataset(name, data=values)
    for name in scales[3:]:
        del f[name]


def test_reads_version_1_files(tmp_path):
    """Files of the previous layout (disks only: a radius, no outline group) still read."""
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n)
    fit = fit_face(MeasuredFace(face, pixel_size(n)), fit_problem(labels))
    path = write_fit(tmp_path / "fit.h5", fit)
    with h5py.File(path, "r+") as f:           # as version 1 wrote it
        _as_attributes(f)
        del f["outline"]
        del f.attrs["scale"], f.attrs["scale_units"]
        f.attrs["format_version"] = 1
    stored = read_fit(path)
    assert stored.version == 1 and stored.outline == Circle(RADIUS), stored.outline
    assert stored.attrs["radius"] == RADIUS and stored.attrs["scale"] == RADIUS, "radius"
    assert np.array_equal(stored.attrs["ratios"], fit.ratios), "ratios"
    assert plot_fit(path, tmp_path / "fit.png").stat().st_size > 20_000, "figure drawn"
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = 4
    with pytest.raises(ValueError, match=r"not a runin.fit file of version 1 or 2 or 3"):
        read_fit(path)


@pytest.mark.slow
@pytest.mark.parametrize("case", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize("correlation", [0.0, 2.0], ids=["white", "correlated"])
@pytest.mark.parametrize("name", ["rectangle", "annulus"])
def test_coverage_measured_on_outlines(name, correlation, case):
    """Coverage of the 95 % intervals over 1000 realisations (n = 48, 10 % noise).

    Measured (seeds 9059 white, 9049 correlated over 2 pixels): rectangle
    (16 x 48 pixels), two phases 0.970 (white) and 0.957 (correlated); three
    phases 0.962 / 0.972 and 0.950 / 0.956; annulus (ring of 12 pixels), two
    phases 0.962 and 0.956, three phases 0.958 / 0.968 and 0.939 / 0.955; the
    load scale 0.947 .. 0.966.  With the covariance window capped at half the
    inradius instead (the ring's 3 pixels), the correlated coverage fell to
    0.90 (rectangle) and 0.83 (annulus).
    """
    geometry, ratios = case
    outline = OUTLINES[name]
    face, labels, relief, grid = outline_face(outline, geometry, ratios, 48)
    model = FaceModel(fit_problem(labels, outline))
    rng = np.random.default_rng(9049 if correlation else 9059)
    hits = np.zeros(len(ratios))
    load_hits = 0
    trials = 1000
    for _ in range(trials):
        heights = face + 0.1 * relief * noise(rng, grid.shape, correlation)
        fit = model.fit(MeasuredFace(heights, grid.h))
        hits += in_interval(fit, ratios)
        load_hits += fit.load_scale_interval[0] <= 1 <= fit.load_scale_interval[1]
    rate = hits[1:] / trials
    print(f"{name}: coverage {rate}, load scale {load_hits / trials}")
    assert np.all(np.abs(rate - 0.95) < 0.025), f"{name}: coverage {rate} (nominal 0.95)"
    assert abs(load_hits / trials - 0.95) < 0.025, f"load scale coverage {load_hits / trials}"
