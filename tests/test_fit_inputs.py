"""``runin-fit`` against bad inputs and faults: refused, never garbage or a traceback.

Each class of bad input or fault that concerns the fit: outputs that name an input,
heights that are not real or out of range, a fit whose figures are not
finite, unreadable measured maps (empty, a directory, a foreign format --
never the advice to unpickle), failures reported on stderr, the memory
estimate and ``--memory-limit``, the ``--plot`` suffix checked before any
work.  The command runs in-process (:func:`steady.cli.fit.main`) unless its
start-up matters.
"""

import json
import pathlib
import pickle
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import GEOMETRIES, K1, problem

from steady import FaceModel, MeasuredFace, PowerLaw, load_scene, read_measured, solve
from steady.array_files import PNG_SIGNATURE
from steady.cli.fit import main
from steady.memory import fit_memory
from steady.outline import Circle
from steady.text import format_bytes

N = 40
#: Pixel size of the n = 40 grid over the disk of radius 4 mm, m.
PIXEL = 2e-4


@pytest.fixture
def case(tmp_path, scene_file):
    """A scene and its steady face as a measured map (m), in ``tmp_path``."""
    scene_path = scene_file("steady", n=N)
    scene = load_scene(scene_path)
    truth = solve(problem(scene.geometry, [1e-9, 4e-9], n=N))
    np.save(tmp_path / "face.npy", truth.face)
    return scene_path, tmp_path / "face.npy", truth.face


def run(capsys, *args):
    """Exit status, stdout and stderr of ``runin-fit`` in-process."""
    try:
        status = main([str(a) for a in args])
    except SystemExit as done:  # argument errors exit from the parser
        status = done.code
    out, err = capsys.readouterr()
    return status, out, err


def one_error_line(err):
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), f"not one error line: {err!r}"
    assert "Traceback" not in err and "unexpected" not in err, err
    return lines[0]


# -- outputs that name an input -------------------------------------------------------------
@pytest.mark.parametrize("target, named", [
    ("-o measured", "-o and the measured map"),
    ("-o scene", "-o and the scene"),
    ("--plot measured", "--plot and the measured map"),
    ("--plot scene", "--plot and the scene"),
])
def test_outputs_never_replace_an_input(case, capsys, target, named):
    """``-o`` or ``--plot`` naming the scene or the measured map: refused even with --force."""
    scene_path, face_path, _ = case
    option, which = target.split()
    victim = face_path if which == "measured" else scene_path
    before = victim.read_bytes()
    out_h5 = face_path.parent / "fit.h5"
    args = [scene_path, face_path, "--pixel-size", PIXEL, "--force"]
    args += ["-o", victim] if option == "-o" else ["-o", out_h5, "--plot", victim]
    status, _, err = run(capsys, *args)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert named in line and "name the same file" in line, line
    assert victim.read_bytes() == before, f"{which} was overwritten"
    assert not out_h5.exists(), "nothing written"


# -- heights that are not real or out of range ----------------------------------------------
def test_complex_heights_are_refused(case, capsys):
    scene_path, face_path, face = case
    np.save(face_path, face * (1 + 0.5j))
    status, _, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL,
                         "-o", face_path.parent / "fit.h5")
    line = one_error_line(err)
    assert status == 2 and "holds complex numbers (complex128)" in line, f"{status}: {line}"
    assert "face.npy" in line, line
    with pytest.raises(ValueError, match="holds complex numbers"):
        MeasuredFace(face * (1 + 0.5j), PIXEL)
    with pytest.raises(ValueError, match="holds booleans"):
        MeasuredFace(np.isfinite(face), PIXEL)


@pytest.fixture(scope="module")
def noisy():
    """A fit model and a measured face with 2 % noise (seed 7919), k_1/k_0 = 3."""
    truth = solve(problem(GEOMETRIES["voronoi"], PowerLaw([K1, 3 * K1]), n=N))
    relief = np.nanmax(truth.face) - np.nanmin(truth.face)
    heights = truth.face + 0.02 * relief * np.random.default_rng(7919).standard_normal(
        truth.face.shape)
    model = FaceModel(problem(truth.labels, PowerLaw([K1, K1]), n=N))
    return model, heights, Circle(4e-3).grid(N).h


@pytest.mark.parametrize("factor", [1e100, 1e-100, 1e150, 1e-155, 2.0 ** 400, 2.0 ** -400])
def test_ratios_do_not_depend_on_the_heights_unit(noisy, factor):
    """Scaling the heights scales the pressures: ratios and intervals stay.

    Within the range where the pressures' covariance (Pa^2) is a
    floating-point number (here about 1e-157 to 1e151); a power of two
    gives the same bits, as the fit runs in a unit that is one.
    """
    model, heights, h = noisy
    base = model.fit(MeasuredFace(heights, h))
    fit = model.fit(MeasuredFace(heights * factor, h))
    assert fit.success, fit.message
    assert np.allclose(fit.ratios, base.ratios, rtol=1e-12), f"{fit.ratios} {base.ratios}"
    assert np.allclose(fit.ratio_intervals, base.ratio_intervals, rtol=1e-9), \
        f"{fit.ratio_intervals} vs {base.ratio_intervals}"
    assert np.allclose(fit.phase_pressures, factor * base.phase_pressures, rtol=1e-9), \
        "pressures scale with the heights"
    assert np.allclose(fit.pressure_covariance, factor**2 * base.pressure_covariance,
                       rtol=1e-9), "covariance scales with their square"
    assert fit.load_scale == pytest.approx(factor * base.load_scale, rel=1e-9), "load scale"
    if np.log2(factor) == int(np.log2(factor)):
        assert np.array_equal(fit.ratio_intervals, base.ratio_intervals), "same bits"
        assert np.array_equal(fit.pressure_covariance,
                              np.ldexp(base.pressure_covariance, 2 * int(np.log2(factor)))), \
            "same bits, scaled"


@pytest.mark.parametrize("factor, side", [(1e300, "beyond"), (1e-300, "below")])
def test_heights_out_of_range_are_refused(case, capsys, factor, side):
    """Heights of 1e296 m or 1e-304 m: no finite covariance in Pa^2; refused, the range named."""
    scene_path, face_path, face = case
    np.save(face_path, face * factor)
    out_h5 = face_path.parent / "fit.h5"
    status, out, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert "'" + str(face_path) + "'" in line and "heights from" in line, line
    assert f"covariance of the pressures {side}" in line and "height scale" in line, line
    assert not out_h5.exists() and not out, "nothing written, no summary"


def test_height_scale_overflow_is_refused(case):
    _, face_path, face = case
    np.save(face_path, face * 1e300)
    with pytest.raises(ValueError, match=r"times the height scale 1e\+20 m exceed"):
        read_measured(face_path, pixel_size=PIXEL, height_scale=1e20)


def test_a_fit_that_is_not_finite_is_a_failure(noisy, monkeypatch):
    """An interval that comes out NaN (here forced) fails the fit with the reason."""
    import steady.fit

    model, heights, h = noisy
    monkeypatch.setattr(steady.fit, "_fieller", lambda *args: (np.nan, np.inf))
    fit = model.fit(MeasuredFace(heights, h))
    assert not fit.success, "a NaN interval is not a success"
    assert "the interval of k1/k0, [nan, inf], is not finite" in fit.message, fit.message


def test_pure_noise_determines_nothing(noisy):
    """Noise without a face: the ratio's interval is [0, inf], a failed fit, not a note."""
    model, heights, h = noisy
    noise = np.random.default_rng(6278).standard_normal(heights.shape)
    fit = model.fit(MeasuredFace(noise, h))
    lo, hi = fit.ratio_intervals[1]
    assert lo == 0 and np.isinf(hi), f"interval {lo, hi}"
    assert np.all(fit.phase_pressures > 0), "positive pressures: only the interval fails it"
    assert not fit.success and "k1/k0 is not determined by the map" in fit.message, fit.message


# -- unreadable measured maps ---------------------------------------------------------------
def _hdf5(path):
    with h5py.File(path, "w") as f:
        f["heights"] = np.zeros((4, 4))


def _bad_file(kind, path):
    """Make ``path`` a bad measured map of ``kind``."""
    if kind == "missing":
        return
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "directory":
        path.mkdir()
    elif kind == "hdf5":
        _hdf5(path)
    elif kind == "pickle":
        path.write_bytes(pickle.dumps(np.zeros((4, 4))))
    elif kind == "not utf-8":
        path.write_bytes(b"1 2\n\xff\xfe 3\n")
    elif kind == "comments only":
        path.write_text("# heights in um\n\n")
    elif kind == "truncated":
        np.save(path, np.zeros((40, 40)))
        path.write_bytes(path.read_bytes()[:300])
    elif kind == "1-d":
        np.save(path, np.zeros(0))
    elif kind == "png signature":
        path.write_bytes(PNG_SIGNATURE)


@pytest.mark.parametrize("name, kind, fragment", [
    ("m.npy", "missing", "does not exist"),
    ("m.npy", "empty", "is empty (0 bytes)"),
    ("m.npy", "directory", "is a directory, not a file"),
    ("m.npy", "hdf5", "is an HDF5 file, not a .npy array"),
    ("m.npy", "pickle", "is pickled Python data, not a .npy array"),
    ("m.npy", "truncated", "is truncated"),
    ("m.npy", "1-d", "must be a 2-d array, got shape (0,)"),
    ("m.txt", "empty", "is empty (0 bytes)"),
    ("m.txt", "directory", "is a directory, not a file"),
    ("m.csv", "hdf5", "is an HDF5 file, not a text grid"),
    ("m.txt", "not utf-8", "is not a text grid: byte 0xff at offset 4 is not UTF-8 text"),
    ("m.dat", "comments only", "holds no numbers"),
    ("m.x3p", "empty", "is empty (0 bytes)"),
    ("m.x3p", "directory", "is a directory, not a file"),
    # Not handed to SurfaceTopography, whose reader of headerless grids would take 8 bytes
    # for 2 x 2 heights.
    ("m.png", "png signature", "is a PNG image, not a height map"),
    ("m.dat", "png signature", "is a PNG image, not a text grid"),
])
def test_unreadable_maps_are_one_line(case, capsys, name, kind, fragment):
    """One line naming the file and what is wrong, exit 2; never advice to unpickle."""
    scene_path, face_path, _ = case
    path = face_path.parent / name
    _bad_file(kind, path)
    status, out, err = run(capsys, scene_path, path, "--pixel-size", PIXEL,
                           "-o", face_path.parent / "fit.h5")
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert f"measured map '{path}' {fragment}" in line, f"{line!r} lacks {fragment!r}"
    assert "allow_pickle" not in line and "pickle.load" not in line, line
    assert not (face_path.parent / "fit.h5").exists() and not out, "nothing written"


@pytest.mark.parametrize("which, fragment", [
    ("scene", "cannot read scene file '{loop}'"),
    ("measured", "cannot read measured map '{loop}'"),
    ("-o", "output '{loop}'"),
    ("--plot", "--plot '{loop}'"),
])
def test_a_loop_of_symbolic_links_is_bad_input(case, capsys, which, fragment):
    """A link to itself as any path: one line naming it, exit 2, nothing written."""
    scene_path, face_path, _ = case
    loop = face_path.parent / ("loop.png" if which == "--plot" else "loop")
    loop.symlink_to(loop.name)
    out_h5 = face_path.parent / "fit.h5"
    paths = {"scene": scene_path, "measured": face_path, "-o": out_h5, "--plot": None}
    paths[which] = loop
    args = [paths["scene"], paths["measured"], "-o", paths["-o"], "--pixel-size", PIXEL]
    status, out, err = run(capsys, *args, *(["--plot", loop] if which == "--plot" else []))
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    expected = f"{fragment.format(loop=loop)}: Too many levels of symbolic links"
    assert expected in line, f"{line!r} lacks {expected!r}"
    assert not out_h5.exists() and not out, "nothing written"


@pytest.mark.parametrize("flag", ["--rim-margin", "--max-shift", "--height-scale",
                                  "--pixel-size", "--confidence"])
def test_a_negative_number_in_exponent_form_reaches_its_check(case, capsys, flag):
    """``-1e-4`` is the flag's value (refused as negative), not a missing argument."""
    scene_path, face_path, _ = case
    args = [scene_path, face_path, "-o", face_path.parent / "fit.h5", "--shift"]
    args += [flag, "-1e-4"] + (["--pixel-size", PIXEL] if flag != "--pixel-size" else [])
    status, _, err = run(capsys, *args)
    line = one_error_line(err)
    # As typed where the flag checks it, as the fit read it where the fit does.
    assert status == 2 and ("-0.0001" in line or "got '-1e-4'" in line), \
        f"exit {status}: {line}"
    assert "expected one argument" not in line and "expected at least" not in line, line


def test_ragged_text_grid_gets_no_numpy_advice(tmp_path):
    (tmp_path / "m.txt").write_text("1 2 3\n4 5\n")
    with pytest.raises(ValueError, match="number of columns changed") as err:
        read_measured(tmp_path / "m.txt", pixel_size=PIXEL)
    assert "usecols" not in str(err.value), err.value


# -- failures on stderr, help, memory -------------------------------------------------------
@pytest.mark.parametrize("kind", ["constant", "noise"])
def test_failed_fit_ends_with_an_error_line(case, capsys, kind):
    """A failed fit: summary on stdout, file written, one ``error:`` line on stderr, exit 1."""
    scene_path, face_path, face = case
    if kind == "constant":
        heights = np.where(np.isfinite(face), 1e-5, np.nan)
    else:
        heights = 1e-5 * np.random.default_rng(5113).standard_normal(face.shape)
    np.save(face_path, heights)
    out_h5 = face_path.parent / "fit.h5"
    status, out, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert line.startswith("error: the fit failed: ") and f"'{out_h5}'" in line, line
    assert "fit failed" in out and "wear ratios" in out, f"summary on stdout: {out}"
    assert out_h5.exists(), "the failed fit's file is written"


def test_help_states_the_exit_statuses():
    proc = subprocess.run([sys.executable, "-m", "steady.cli.fit", "--help"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    text = " ".join(proc.stdout.split())
    assert "exit status: 0 done; 1" in text and "a fit failed (its file is written" in text, text
    assert "2 bad input or refused, nothing written; 130 interrupted" in text, text
    assert "--memory-limit GIB" in text, "the option the memory advice names"


def test_memory_limit_refuses_a_fit_before_it_starts(case, capsys):
    scene_path, face_path, _ = case
    out_h5 = face_path.parent / "fit.h5"
    status, _, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5,
                         "--n", 100000)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert "a fit at n = 100000 of a 40 x 40 map needs about" in line, line
    assert "--memory-limit" in line, line
    status, _, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5,
                         "--memory-limit", "0.001")
    assert status == 2 and "1.02 MiB may be used (--memory-limit)" in one_error_line(err), err
    assert not out_h5.exists(), "nothing written"
    status, _, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5,
                         "--memory-limit", "inf")
    assert status == 0 and out_h5.exists(), err


def test_fit_memory_grows_with_both_grids():
    """Doubling the model grid, or the measured map, about quadruples the estimate."""
    def grown(model, measured):
        return fit_memory(model, 2, measured) - 16 * 2**20

    model = grown((2048, 2048), (64, 64)) / grown((1024, 1024), (64, 64))
    measured = grown((64, 64), (2048, 2048)) / grown((64, 64), (1024, 1024))
    assert 3.6 < model < 4.4 and 3.6 < measured < 4.4, f"ratios {model:.2f}, {measured:.2f}"
    assert fit_memory((64, 64), 5, (512, 512)) > fit_memory((64, 64), 2, (512, 512)), \
        "more phases, more columns"


_MEASURE = """
import json, pathlib, sys, tempfile
import numpy as np
sys.path.insert(0, {tests!r})
from conftest import scene_text
from steady.cli.fit import main
import steady.fit_files, steady.plotting  # imported before the baseline
def peak():
    for line in pathlib.Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
n, m = {n}, {m}
d = pathlib.Path(tempfile.mkdtemp())
(d / "s.toml").write_text(scene_text("steady", n=n))
h = 8e-3 / m
x = (np.arange(m) - 0.5 * (m - 1)) * h
rng = np.random.default_rng(3769)
np.save(d / "m.npy", 1e-5 * np.exp(-(x[:, None] ** 2 + x[None, :] ** 2) / 8e-6)
        + 1e-7 * rng.standard_normal((m, m)))
before = peak()
status = main([str(d / "s.toml"), str(d / "m.npy"), "--pixel-size", str(h), "-o",
               str(d / "f.h5"), "--plot", str(d / "f.png"), "--memory-limit", "inf"])
print(json.dumps([status, peak() - before]))
"""


@pytest.mark.slow
@pytest.mark.skipif(not pathlib.Path("/proc/self/status").exists(), reason="needs /proc")
@pytest.mark.parametrize("n, m", [(256, 256), (64, 1024), (1024, 64)])
def test_fit_memory_bounds_the_measured_peak(n, m):
    """The estimate over the peak of a run (with its figure) lies in [1, 2].

    Measured: 1.78 (n = 256, 256 x 256 map), 1.58 (n = 64, 1024 x 1024),
    1.58 (n = 1024, 64 x 64).
    """
    tests = str(pathlib.Path(__file__).resolve().parent)
    proc = subprocess.run([sys.executable, "-c", _MEASURE.format(tests=tests, n=n, m=m)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    status, measured = json.loads(proc.stdout.strip().splitlines()[-1])
    estimate = fit_memory((n, n), 2, (m, m))
    assert status in (0, 1), f"exit {status}"
    assert 1.0 <= estimate / measured <= 2.0, \
        f"n = {n}, {m} x {m} map: estimate {format_bytes(estimate)}, measured " \
        f"{format_bytes(measured)} (ratio {estimate / measured:.2f})"


# -- the --plot suffix, before any work ------------------------------------------------------
@pytest.mark.parametrize("name", ["fit.txt", "fit", "fit.jpg"])
def test_plot_suffix_is_checked_before_any_work(case, capsys, name):
    scene_path, face_path, _ = case
    out_h5 = face_path.parent / "fit.h5"
    status, out, err = run(capsys, scene_path, face_path, "--pixel-size", PIXEL, "-o", out_h5,
                           "--plot", face_path.parent / name)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith(f"error: --plot '{face_path.parent / name}': expected the suffix "
                           f".png, .pdf or .svg"), line
    assert not out_h5.exists() and not out, "refused before the fit: nothing written"
