"""Wear ratios from a measured face: round trips through the forward model (eq. 7, 9).

Synthetic measured faces are the steady face of known wear coefficients
(:func:`steady.solution.solve`) plus an offset, a tilt, noise (white, or
correlated by a Gaussian filter) and NaN holes; the fit must recover the
ratios within its stated intervals, and the intervals must cover the truth
at their nominal rate.  The fit is linear, so the coverage does not depend
on the noise level; its width scales with it.
"""

import pathlib
import re
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import E_STAR, FORCE, GEOMETRIES, K1, RADIUS, halfspace
from scipy import ndimage

from steady import (
    FaceModel,
    HalfSpace,
    MeasuredFace,
    Voronoi,
    fit_face,
    fit_scene,
    load_scene,
    pixel_size,
    read_fit,
    read_measured,
    solve,
    write_fit,
)
from steady.fit import main
from steady.fit_files import plot_fit
from steady.grid import face_mask, polar

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: Two phases: the gallery's Voronoi map (64 seeds, 30 % of phase 1), k_1/k_0 = 3.
TWO = (GEOMETRIES["voronoi"], (1.0, 3.0))
#: Three phases, 64 seeds; phase 2 wears half as fast as phase 0.
THREE = (Voronoi(64, (0.5, 0.3, 0.2), 3301), (1.0, 3.0, 0.5))


def steady_face(geometry, ratios, n, *, E_star=E_STAR, exponent=1.0):
    """The forward model: steady face (m, NaN off the face), labels and relief."""
    labels = geometry.labels(n)
    k = [K1 * r for r in ratios]
    result = solve(HalfSpace(n, pixel_size(n, RADIUS), E_star), labels, k, FORCE,
                   exponent=exponent)
    return result.face, labels, float(np.nanmax(result.face) - np.nanmin(result.face))


def plane(n, offset=2e-5, tilt=(1e-3, -4e-4)):
    """Offset plus tilt on the n x n grid, m."""
    x = (np.arange(n) - 0.5 * (n - 1)) * pixel_size(n, RADIUS)
    return offset + tilt[0] * x[:, None] + tilt[1] * x[None, :]


def noise(rng, n, correlation=0.0):
    """Unit-variance noise; Gaussian-filtered with ``correlation`` pixels if positive."""
    pad = int(4 * correlation) + 1
    w = rng.standard_normal((n + 2 * pad, n + 2 * pad))
    if correlation > 0:
        w = ndimage.gaussian_filter(w, correlation)
        delta = np.zeros((2 * pad + 1, 2 * pad + 1))
        delta[pad, pad] = 1.0
        w /= np.sqrt(np.sum(ndimage.gaussian_filter(delta, correlation) ** 2))
    return w[pad:pad + n, pad:pad + n]


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
    fit = fit_face(MeasuredFace(face + plane(n), pixel_size(n, RADIUS)), labels, RADIUS, E_STAR,
                   FORCE)
    assert fit.success, fit.message
    assert np.allclose(fit.ratios, ratios, rtol=1e-9), f"ratios {fit.ratios}"
    assert fit.offset == pytest.approx(2e-5, rel=1e-8), f"offset {fit.offset}"
    assert np.allclose(fit.tilt, (1e-3, -4e-4), rtol=1e-8), f"tilt {fit.tilt}"
    assert fit.load_scale == pytest.approx(1.0, rel=1e-9), "sum A_i p_i = F_N (eq. 5)"
    assert fit.samples == face_mask(n).sum(), "every face pixel is fitted"


@pytest.mark.parametrize("exponent", [0.5, 2.0])
def test_power_law_ratios(exponent):
    """k_i p_i^m = C: the ratios are (p_0 / p_i)^m, whatever m."""
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n, exponent=exponent)
    fit = fit_face(MeasuredFace(face, pixel_size(n, RADIUS)), labels, RADIUS, E_STAR, FORCE,
                   exponent=exponent)
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
    model = FaceModel(labels, RADIUS, E_STAR, FORCE)
    errors = {}
    for level in (0.01, 0.1):
        misses = np.zeros(len(ratios), dtype=int)
        errors[level] = []
        for seed in range(6101, 6121):
            heights = face + plane(n) + level * relief * noise(np.random.default_rng(seed), n)
            heights[gaps] = np.nan
            fit = model.fit(MeasuredFace(heights, pixel_size(n, RADIUS)))
            assert fit.success, f"noise {level}, seed {seed}: {fit.message}"
            assert fit.samples == np.sum(face_mask(n) & ~gaps), "holes are left out, not fatal"
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
    model = FaceModel(labels, RADIUS, E_STAR, FORCE)
    rng = np.random.default_rng(7411 if correlation else 7417)
    hits = np.zeros(len(ratios))
    trials = 120
    for _ in range(trials):
        heights = face + plane(n) + 0.1 * relief * noise(rng, n, correlation)
        hits += in_interval(model.fit(MeasuredFace(heights, pixel_size(n, RADIUS))), ratios)
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
    model = FaceModel(labels, RADIUS, E_STAR, FORCE)
    rng = np.random.default_rng(9049 if correlation else 9059)
    hits = np.zeros(len(ratios))
    load_hits = 0
    trials = 1000
    for _ in range(trials):
        heights = face + plane(n) + 0.1 * relief * noise(rng, n, correlation)
        fit = model.fit(MeasuredFace(heights, pixel_size(n, RADIUS)))
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
    fit = fit_face(MeasuredFace(heights, pixel_size(96, RADIUS)), TWO[0].labels(48), RADIUS,
                   E_STAR, FORCE)
    assert in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert abs(fit.ratios[1] / 3 - 1) < 0.02, f"ratio {fit.ratios[1]}"
    assert fit.load_scale == pytest.approx(0.5, rel=0.01), f"load scale {fit.load_scale}"
    assert fit.implied_E_star == pytest.approx(2 * E_STAR, rel=0.01), "implied E*"
    assert fit.effective_samples < 0.1 * fit.samples, "the model error is a correlated residual"


def test_shift_is_found():
    """The face sits 3 pixels right and 2 down of the map's centre: the search finds it."""
    n, pad = 48, 6
    face, labels, relief = steady_face(TWO[0], TWO[1], n)
    h = pixel_size(n, RADIUS)
    heights = np.full((n + 2 * pad, n + 2 * pad), np.nan)
    heights[pad + 3:pad + 3 + n, pad - 2:pad - 2 + n] = (
        face + plane(n) + 0.01 * relief * noise(np.random.default_rng(4421), n))
    measured = MeasuredFace(heights, h)
    fit = fit_face(measured, labels, RADIUS, E_STAR, FORCE, search_shift=True, max_shift=5 * h)
    assert np.allclose(fit.shift, (3 * h, -2 * h), atol=0.05 * h), \
        f"shift {np.divide(fit.shift, h)} pixels"
    assert in_interval(fit, TWO[1]).all(), f"{fit.ratios} {fit.ratio_intervals}"
    assert fit.residual_rms < 0.015 * relief, f"residual {fit.residual_rms / relief} of relief"
    unshifted = fit_face(measured, labels, RADIUS, E_STAR, FORCE, rim_margin=5 * h)
    assert unshifted.residual_rms > 3 * fit.residual_rms, "a misplaced map fits worse"


def test_faster_phase_is_only_bounded_below():
    """Phase 1 wears 10^4 times faster: its pressure is not told from zero, the ratio is a bound."""
    n = 40
    face, labels, relief = steady_face(TWO[0], (1.0, 1e4), n)
    heights = face + 0.1 * relief * noise(np.random.default_rng(6653), n)
    fit = fit_face(MeasuredFace(heights, pixel_size(n, RADIUS)), labels, RADIUS, E_STAR, FORCE)
    lo, hi = fit.ratio_intervals[1]
    assert np.isinf(hi) and 1 < lo < 1e4, f"interval {lo, hi}"
    assert "bounded only from below" in fit.message, fit.message


def test_upside_down_map_fails_with_a_reason():
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n)
    fit = fit_face(MeasuredFace(-face, pixel_size(n, RADIUS)), labels, RADIUS, E_STAR, FORCE)
    assert not fit.success, "negative pressures are not a success"
    assert "not positive" in fit.message and "upside down" in fit.message, fit.message


def test_errors_name_the_problem():
    n = 40
    face, labels, _ = steady_face(TWO[0], TWO[1], n)
    h = pixel_size(n, RADIUS)
    with pytest.raises(ValueError, match=r"36 x 36 pixels .* cannot cover the face of diameter 8"):
        fit_face(MeasuredFace(face[2:-2, 2:-2], h), labels, RADIUS, E_STAR, FORCE)
    with pytest.raises(ValueError, match=r"cannot cover the face"):
        fit_face(MeasuredFace(face, 0.9 * h), labels, RADIUS, E_STAR, FORCE)
    absent = np.where(labels == 1, np.nan, face)
    with pytest.raises(ValueError, match=r"phase 1 covers 0 of the \d+ fitted pixels"):
        fit_face(MeasuredFace(absent, h), labels, RADIUS, E_STAR, FORCE)
    with pytest.raises(ValueError, match="reference_phase must be a phase index 0..1"):
        fit_face(MeasuredFace(face, h), labels, RADIUS, E_STAR, FORCE, reference_phase=2)
    with pytest.raises(ValueError, match="confidence must lie in"):
        fit_face(MeasuredFace(face, h), labels, RADIUS, E_STAR, FORCE, confidence=95)
    with pytest.raises(ValueError, match="rim_margin must be a non-negative"):
        fit_face(MeasuredFace(face, h), labels, RADIUS, E_STAR, FORCE, rim_margin=-1e-4)
    with pytest.raises(ValueError, match="nothing left to fit"):
        fit_face(MeasuredFace(face, h), labels, RADIUS, E_STAR, FORCE, rim_margin=RADIUS)
    with pytest.raises(ValueError, match="2-d array"):
        MeasuredFace(face[0], h)
    with pytest.raises(ValueError, match="no finite height"):
        MeasuredFace(np.full((4, 4), np.nan), h)
    with pytest.raises(ValueError, match="pixel size of array must be one or two positive"):
        MeasuredFace(face, -h)


def test_collinear_phase_is_undetermined():
    """A ring at the rim seen from a small central disk: not determined.

    There the ring's face is a smooth radial bowl, a combination of the inner
    phase's face and the plane to 1e-7.
    """
    n = 200
    r, _ = polar(n, RADIUS)
    labels = np.where(r < 0.5 * RADIUS, 0, 1)
    labels[~face_mask(n)] = -1
    model = FaceModel(labels, RADIUS, E_STAR, FORCE)
    face = np.tensordot([2e5, 1e5], model.faces, axes=1)
    with pytest.raises(ValueError, match=r"phase 1: its face is a combination of the other"):
        model.fit(MeasuredFace(face, pixel_size(n, RADIUS)), rim_margin=0.93 * RADIUS,
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
    with pytest.raises(ValueError, match="does not exist"):
        read_measured(tmp_path / "nope.npy", pixel_size=1e-4)
    with pytest.raises(ValueError, match="height scale must be a positive"):
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
    fit = fit_face(MeasuredFace(heights, pixel_size(n, RADIUS), source="synthetic"), labels,
                   RADIUS, E_STAR, FORCE)
    path = write_fit(tmp_path / "fit.h5", fit)
    stored = read_fit(path)
    assert np.array_equal(stored.attrs["ratios"], fit.ratios), "ratios stored"
    assert np.array_equal(stored.attrs["ratio_upper"], fit.ratio_intervals[:, 1]), "intervals"
    assert np.array_equal(stored.arrays["residual"], fit.residual, equal_nan=True), "residual"
    assert stored.attrs["success"] and stored.attrs["measured_source"] == "synthetic"
    with h5py.File(path) as f:
        assert f.attrs["format"] == "runin.fit" and f.attrs["format_version"] == 1, "layout"
        assert f.attrs["phase_pressures_units"] == "Pa" and f["fitted"].attrs["units"] == "m"
    with pytest.raises(ValueError, match="exists"):
        write_fit(path, fit)
    png = plot_fit(path, tmp_path / "fit.png")
    assert png.stat().st_size > 20_000, "figure drawn"


def test_fit_scene_uses_the_scene(scene_file):
    scene = load_scene(scene_file("steady", n=40))
    truth = solve(halfspace(40), scene.geometry.labels(40), scene.wear_coefficients,
                  scene.normal_force)
    fit = fit_scene(scene, MeasuredFace(truth.face, pixel_size(40, RADIUS)))
    assert np.allclose(fit.ratios, fit.scene_ratios, rtol=1e-9), "ratios of the scene"
    assert fit.scene_ratios[1] == pytest.approx(10.0), "scene ratios reported"


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "steady.fit", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_command_line(tmp_path, scene_file, capsys):
    scene_path = scene_file("steady", n=40)
    scene = load_scene(scene_path)
    truth = solve(halfspace(40), scene.geometry.labels(40), [1e-9, 4e-9], FORCE)
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
    (["--pixel-size", "1e-4"], "cannot cover the face"),
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
    """``python -m steady.fit``: bad input is one line on stderr, exit 2, no traceback."""
    scene_path = scene_file("steady", n=40)
    np.save(tmp_path / "face.npy", np.zeros((30, 30)))
    proc = run_cli(scene_path, "face.npy", "--pixel-size", "2e-4", "-o", "fit.h5", cwd=tmp_path)
    assert proc.returncode == 2, f"exit {proc.returncode}: {proc.stderr}"
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: measured map"), \
        proc.stderr
    assert "30 x 30 pixels" in proc.stderr and "diameter 8 mm" in proc.stderr, proc.stderr


def test_readme_example(tmp_path, monkeypatch):
    """The README's example of this section runs as written."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Wear ratios from a measured face", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    (tmp_path / "studies").symlink_to(ROOT / "studies")
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    fit = namespace["fit"]
    assert fit.success and fit.ratio_intervals[1, 0] <= 1.7 <= fit.ratio_intervals[1, 1], fit
