"""``python -m transient``: output file, errors, checkpoints killed with SIGKILL, resume."""

import os
import pathlib
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from steady.safe_files import backup_path
from transient.output import history_cf, read_run
from transient.result import HISTORY_UNITS

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture
def write_scene(scene_file):
    """The gallery's run-in scene with the tolerance, grid and keys a test asks for."""
    def write(*, n=32, tol=1e-3, filename="s.toml", coefficients=(1.0e-13, 1.0e-12),
              **transient):
        return scene_file("runin", filename=filename, n=n, coefficients=coefficients,
                          transient={"tol": tol, "snapshots_s_star": (0.1, 1.0), **transient})
    return write


def cli(*args, cwd, timeout=600):
    return subprocess.run([sys.executable, "-m", "transient", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout)


def test_run_writes_result_and_agreement(tmp_path, write_scene):
    scene = write_scene()
    out = tmp_path / "run.h5"
    png = tmp_path / "run.png"
    proc = cli(scene, "-o", out, "--plot", png, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == "", f"stderr not quiet off a terminal: {proc.stderr!r}"
    assert "agreement with the steady face" in proc.stdout, \
        "expected 'agreement with the steady face' in proc.stdout"
    assert "face shape error" in proc.stdout and "rms slope" in proc.stdout, \
        "expected 'face shape error' in proc.stdout and 'rms slope' in proc.stdout"
    assert png.stat().st_size > 10000, "no figure"
    with h5py.File(out) as f:
        assert f.attrs["format"] == "runin.transient" and f.attrs["format_version"] == 5, \
            f"layout {f.attrs['format']!r} version {f.attrs['format_version']!r}"
        assert f.attrs["status"] == "steady", "expected f.attrs['status'] == 'steady'"
        assert f["worn_depth"].attrs["units"] == "m", \
            "expected f['worn_depth'].attrs['units'] == 'm'"
        assert f["pressure"].attrs["units"] == "Pa", \
            "expected f['pressure'].attrs['units'] == 'Pa'"
        assert f["phase"].shape == (32, 32), "expected f['phase'].shape == (32, 32)"
        for name in HISTORY_UNITS:  # the companion runs' too: they ran (n = 24, 16)
            unit, long_name = history_cf(name)
            attrs = f[f"history/{name}"].attrs
            assert attrs.get("units") == unit and attrs["long_name"] == long_name, \
                f"history/{name}: units {attrs.get('units')!r}, expected {unit!r}"
        assert f["snapshots/recession"].shape == (2, 32, 32), \
            "expected f['snapshots/height'].shape == (2, 32, 32)"
        cmp = {name: ds[()] for name, ds in f["comparison"].items()}
        assert cmp["face_error"] < 1e-3 and abs(cmp["rms_slope_error"]) < 5e-3, \
            "expected cmp['face_error'] < 1e-3 and abs(cmp['rms_slope_error']) < 5e-3"
        assert cmp["phase_pressure_error"] < 1e-3, "expected cmp['phase_pressure_error'] < 1e-3"
        assert "[transient]" in f.attrs["scene"], "expected '[transient]' in f.attrs['scene']"


def test_existing_output_needs_force_or_resume(tmp_path, write_scene):
    scene = write_scene()
    out = tmp_path / "run.h5"
    out.write_bytes(b"precious")
    proc = cli(scene, "-o", out, cwd=tmp_path)
    assert proc.returncode == 2, "existing output must be refused with exit 2"
    assert proc.stderr.startswith("error: ") and "--force" in proc.stderr, \
        "expected proc.stderr.startswith('error: ') and '--force' in proc.stderr"
    assert "Traceback" not in proc.stderr, "traceback on a usage error"
    assert out.read_bytes() == b"precious", "existing file overwritten"
    proc = cli(scene, "-o", out, "--force", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("keys,match", [
    ({"bogus": 1}, "unknown key 'bogus'"),
    ({"scheme": "rk4"}, "unknown scheme 'rk4'"),
    ({"tol": -1.0}, "[transient] tol must be a number in (2.22045e-16, 1] (f*), got -1.0"),
])
def test_bad_transient_section(tmp_path, scene_file, keys, match):
    scene = scene_file("runin", transient=keys)
    proc = cli(scene, "-o", tmp_path / "run.h5", cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout
    assert proc.stderr.startswith("error: ") and match in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr, "traceback on a usage error"


def test_bad_initial_face_section(tmp_path, scene_file):
    scene = scene_file("runin", initial_face={"kind": "tilted", "angle": 2.0})
    proc = cli(scene, "-o", tmp_path / "run.h5", cwd=tmp_path)
    assert proc.returncode == 2 and "angle must be a number in [0, 1.5708) (rad), got 2.0" \
        in proc.stderr, proc.stderr
    assert "[initial_face]" in proc.stderr, f"section not named: {proc.stderr!r}"


def test_bad_command_line(tmp_path):
    proc = cli(tmp_path / "missing.toml", "-o", tmp_path / "run.h5", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith("error: "), \
        "expected proc.returncode == 2 and proc.stderr.startswith('error: ')"
    assert "does not exist" in proc.stderr, "expected 'does not exist' in proc.stderr"
    proc = cli(tmp_path / "missing.toml", "-o", tmp_path / "run.h5", "--tol", "-3",
               cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith("error: "), \
        "expected proc.returncode == 2 and proc.stderr.startswith('error: ')"


def test_usage_names_the_command_as_typed(tmp_path, monkeypatch):
    """``runin-transient --help`` says runin-transient, ``python -m transient`` says that."""
    from transient.cli.runin import build_parser

    monkeypatch.setattr(sys, "argv", ["/usr/local/bin/runin-transient", "--help"])
    usage = build_parser().format_usage()
    assert usage.startswith("usage: runin-transient "), f"console script usage {usage!r}"
    proc = cli("--help", cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert proc.stdout.startswith("usage: python -m transient "), f"usage {proc.stdout[:80]!r}"


def test_stopped_run_exits_1_and_resumes(tmp_path, write_scene):
    scene = write_scene()
    out = tmp_path / "run.h5"
    proc = cli(scene, "-o", out, "--max-steps", "4", cwd=tmp_path)
    assert proc.returncode == 1 and "continue with --resume" in proc.stderr, proc.stderr
    assert read_run(out)[0].status == "stopped", "expected read_run(out)[0].status == 'stopped'"
    proc = cli(scene, "-o", out, "--resume", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert read_run(out)[0].status == "steady", "expected read_run(out)[0].status == 'steady'"


def test_resume_refuses_another_scene(tmp_path, write_scene):
    scene = write_scene()
    out = tmp_path / "run.h5"
    assert cli(scene, "-o", out, "--max-steps", "2", cwd=tmp_path).returncode == 1, \
        "expected cli(scene, '-o', out, '--max-steps', '2', cwd=tmp_path).returncode == 1"
    other = write_scene(filename="o.toml", coefficients=(1.0e-13, 2.0e-12))
    proc = cli(other, "-o", out, "--resume", cwd=tmp_path)
    assert proc.returncode == 2 and "another wear law" in proc.stderr, proc.stderr


def test_sigkill_at_any_moment_then_resume_is_bitwise_identical(tmp_path, write_scene):
    # A run long enough to be killed mid-way (n = 48, SDIRK2 at tol 1e-5: ~300
    # steps), checkpointed after every step.
    scene = write_scene(n=48, tol=1e-5, scheme="sdirk2")
    reference = tmp_path / "reference.h5"
    proc = cli(scene, "-o", reference, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    ref, _, _ = read_run(reference)

    out = tmp_path / "killed.h5"
    kills = 0
    for delay_steps in (30, 90):   # of about 250 steps
        args = [sys.executable, "-m", "transient", str(scene), "-o", str(out),
                "--checkpoint-interval", "0"]
        if out.exists():
            args.append("--resume")
        child = subprocess.Popen(args, cwd=tmp_path, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 300
        steps = None
        while time.monotonic() < deadline and child.poll() is None:
            if out.exists():
                try:
                    steps = read_run(out)[0].steps
                except Exception:  # noqa: BLE001 -- any failed read: poll again
                    steps = -1
                if steps >= delay_steps:
                    break
            time.sleep(0.02)
        assert child.poll() is None, \
            f"run ended (status {child.returncode}) before it could be killed at step " \
            f"{delay_steps} (last seen {steps})"
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        kills += 1
        saved, _, _ = read_run(out)            # never left unreadable, checksums verified
        assert saved.status == "running", "a killed run's file must hold a running checkpoint"
        assert 0 < saved.steps < ref.steps, "checkpoint not taken mid-run"
        assert (tmp_path / "killed.h5.lock").read_text() == f"{child.pid}\n", \
            "a killed run leaves its lock file, holding its pid"

    proc = cli(scene, "-o", out, "--resume", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.startswith(f"note: took over the lock of {str(out)!r} left by process "), \
        f"stderr {proc.stderr!r}"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".killed")) == [], \
        "temporary files of the killed writers must be gone"
    final, _, _ = read_run(out)
    assert kills == 2, "the run was not killed twice"
    assert final.steps == ref.steps and final.status == "steady", \
        "resumed run took another path than the uninterrupted one"
    # Bitwise: the stored state determines the rest of the run.
    assert np.array_equal(final.worn_depth, ref.worn_depth, equal_nan=True), \
        "worn depth not bitwise equal to the uninterrupted run"
    assert np.array_equal(final.pressure, ref.pressure), \
        "pressure not bitwise equal to the uninterrupted run"
    for name in HISTORY_UNITS:
        assert np.array_equal(final.history[name], ref.history[name]), name


def test_resume_of_a_finished_run_is_a_no_op(tmp_path, write_scene):
    scene = write_scene()
    out = tmp_path / "run.h5"
    assert cli(scene, "-o", out, cwd=tmp_path).returncode == 0, \
        "expected cli(scene, '-o', out, cwd=tmp_path).returncode == 0"
    before = read_run(out)[0]
    proc = cli(scene, "-o", out, "--resume", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    after = read_run(out)[0]
    assert after.steps == before.steps, "expected after.steps == before.steps"
    assert np.array_equal(after.worn_depth, before.worn_depth, equal_nan=True), \
        "expected np.array_equal(after.worn_depth, before.worn_depth, equal_nan=True)"


def test_shipped_transient_scenes_parse():
    from transient.scene import load_transient_scene

    scenes = sorted((ROOT / "steady" / "examples").glob("*transient*.toml"))
    assert scenes, "no transient scene shipped"
    for path in scenes:
        scene, settings, initial = load_transient_scene(path)
        assert scene.n >= 32, path


def test_work_precision_study_smoke(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "studies" / "work_precision.py"),
                           "--quick", "--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    h5 = tmp_path / "work_precision_n40.h5"
    assert h5.exists() and (tmp_path / "work_precision_n40.png").stat().st_size > 10000, \
        "expected h5.exists() and (tmp_path / 'work_precision_n40.png').stat().st_size > 10000"
    with h5py.File(h5) as f:
        assert f.attrs["format"] == "runin.work_precision", \
            "expected f.attrs['format'] == 'runin.work_precision'"
        assert f["steady_jump"].attrs["face_error"] < 1e-6, \
            "expected f['steady_jump'].attrs['face_error'] < 1e-6"
        assert f["steady_jump"].attrs["solves"] <= 3, \
            "expected f['steady_jump'].attrs['solves'] <= 3"
        for name in ("implicit_euler_tol0.01", "bdf2_tol0.01", "sdirk2_tol0.01"):
            assert np.isfinite(f[f"runs/{name}"].attrs["history_error"]), name


def test_companion_runs_store_the_grid_error(tmp_path, write_scene):
    # The companion runs on 3n/4 and n/2 fill rms_slope_spatial_error at every recorded
    # distance: 0 at s = 0 (every run starts from the flat face's exact value, 0), and
    # max |S_n - S_m| elsewhere, which must equal the largest difference of the runs' values.
    scene = write_scene(n=48)
    out = tmp_path / "run.h5"
    proc = cli(scene, "-o", out, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "companion runs on n = 36, 24" in proc.stdout, proc.stdout
    run, _, _ = read_run(out)
    error = run.history["rms_slope_spatial_error"]
    assert error.shape == run.history["distance"].shape, f"shape {error.shape}"
    assert error[0] == 0.0, f"error at s = 0: {error[0]}"
    assert np.all(np.isfinite(error)) and np.all(error >= 0), "error must be finite, >= 0"
    assert error[1:].max() > 0, "48 -> 36, 24 companions cannot agree to round-off"
    assert "(+- without the grid's error" not in proc.stdout, proc.stdout


def test_a_map_without_a_coarser_grid_runs_without_the_grid_error(tmp_path, write_scene):
    scene = write_scene(n=16)  # the gallery's 64 seeds need n >= 16: no companion grid
    proc = cli(scene, "-o", tmp_path / "run.h5", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    assert "note: " in proc.stderr and "no grid coarser than n = 16" in proc.stderr, proc.stderr
    assert "(+- without the grid's error: no companion runs)" in proc.stdout, proc.stdout


def test_run_that_reaches_end_depth_exits_0(tmp_path):
    text = (ROOT / "steady" / "examples" / "coating_transient.toml").read_text()
    text = text.replace("n = 64", "n = 16").replace("end_depth = 1.2e-3", "end_depth = 1.0e-4")
    scene = tmp_path / "coating.toml"
    scene.write_text(text)
    out = tmp_path / "run.h5"
    proc = cli(scene, "-o", out, cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert "error" not in proc.stderr, proc.stderr
    assert proc.stdout.startswith("depth: reached end_depth 0.0001 m"), proc.stdout[:200]
    assert read_run(out)[0].status == "depth", "the run file's status is not 'depth'"
    assert not backup_path(out).exists(), "the finished run kept its previous checkpoint"


@pytest.mark.parametrize("end, status, said", [
    ("1.0e-15", 0, "depth: reached end_depth 1e-15 m"),
    ("1.0e-20", 2, "error: end_depth = 1e-20 m is below the mean worn depth this run resolves"),
])
def test_a_tiny_end_depth_ends_the_run_or_is_refused(tmp_path, end, status, said):
    text = (ROOT / "steady" / "examples" / "coating_transient.toml").read_text()
    text = text.replace("n = 64", "n = 16").replace("end_depth = 1.2e-3", f"end_depth = {end}")
    scene = tmp_path / "coating.toml"
    scene.write_text(text)
    proc = cli(scene, "-o", tmp_path / "run.h5", cwd=tmp_path, timeout=60)
    assert proc.returncode == status, f"exit {proc.returncode}: {proc.stderr}"
    assert said in (proc.stdout if status == 0 else proc.stderr), proc.stdout + proc.stderr
    assert (tmp_path / "run.h5").exists() == (status == 0), "a refused run wrote its file"
