"""Command line ``python -m steady``: good runs, refusals, error reporting."""

import pathlib
import platform
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import scene_text

SCENES = pathlib.Path(__file__).resolve().parent.parent / "steady" / "examples"

#: The gallery's steady scene: two phases, 100 Voronoi seeds, n = 40.
SCENE = scene_text("steady")


def run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "steady", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def assert_bad_input(proc, fragment):
    assert proc.returncode == 2, f"exit {proc.returncode}, stderr {proc.stderr!r}"
    assert proc.stderr.startswith("error:"), f"stderr {proc.stderr!r}"
    assert "Traceback" not in proc.stderr, f"traceback in {proc.stderr!r}"
    assert fragment in proc.stderr, f"stderr {proc.stderr!r} lacks {fragment!r}"


def test_good_run_writes_result_and_figure(tmp_path):
    (tmp_path / "s.toml").write_text(SCENE)
    proc = run("s.toml", "-o", "out/r.h5", "--plot", "out/r.png", cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert "rms / grad_f0" in proc.stdout, f"summary {proc.stdout!r}"
    assert (tmp_path / "out" / "r.png").stat().st_size > 10_000, "figure not written"
    with h5py.File(tmp_path / "out" / "r.h5") as f:
        for name in ("phase", "pressure", "face", "slope"):
            assert "units" in f[name].attrs, f"dataset {name} lacks units"
        assert f["scene"][()].decode() == SCENE, "scene text stored"
        assert f["rms_slope"][()] > 0, "rms slope stored"

    # A second run must not overwrite without --force.
    before = (tmp_path / "out" / "r.h5").read_bytes()
    proc = run("s.toml", "-o", "out/r.h5", cwd=tmp_path)
    assert_bad_input(proc, "exists (use --force to overwrite)")
    assert (tmp_path / "out" / "r.h5").read_bytes() == before, "file must be untouched"
    proc = run("s.toml", "-o", "out/r.h5", "--force", cwd=tmp_path)
    assert proc.returncode == 0, f"--force run failed: {proc.stderr}"


@pytest.mark.parametrize("old, new, fragment", [
    ("normal_force = 10.0", "normal_force = -10.0",
     "[load] normal_force must be a number > 0 (N), got -10.0"),
    ("n = 40", "n = 12", "grid too coarse"),
    ("[grid]", "[grdi]", "unknown section [grdi]"),
    ("n = 40", "n = = 40", "malformed TOML"),
])
def test_bad_scene(tmp_path, old, new, fragment):
    assert old in SCENE, f"test setup: {old!r} not in the gallery scene"
    (tmp_path / "s.toml").write_text(SCENE.replace(old, new))
    proc = run("s.toml", "-o", "r.h5", cwd=tmp_path)
    assert_bad_input(proc, fragment)
    assert not (tmp_path / "r.h5").exists(), "no output after an error"


def test_missing_scene_and_bad_arguments(tmp_path):
    assert_bad_input(run("nope.toml", "-o", "r.h5", cwd=tmp_path), "does not exist")
    assert_bad_input(run("nope.toml", cwd=tmp_path), "-o/--output")


def test_usage_names_the_command_as_typed(tmp_path):
    proc = run("--help", cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert proc.stdout.startswith("usage: python -m steady "), f"usage {proc.stdout[:80]!r}"


def test_run_in_scene_is_accepted_with_a_note(tmp_path):
    """The sections of the run-in are skipped with one note line; unknown ones stay errors."""
    text = scene_text("steady", transient={"tol": 1e-4},
                      initial_face={"kind": "tilted", "angle": 0.3})
    (tmp_path / "s.toml").write_text(text)
    proc = run("s.toml", "-o", "r.h5", cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr}"
    assert proc.stderr == "note: ignoring run-in sections [initial_face], [transient]\n", \
        f"stderr {proc.stderr!r}"
    with h5py.File(tmp_path / "r.h5") as f:
        assert f["scene"][()].decode() == text, "the whole scene text is stored"
    (tmp_path / "u.toml").write_text(scene_text("steady", extra="[transient_settings]\ntol = 1e-4"))
    assert_bad_input(run("u.toml", "-o", "u.h5", cwd=tmp_path),
                     "unknown section [transient_settings]")
    (tmp_path / "plain.toml").write_text(SCENE)
    proc = run("plain.toml", "-o", "p.h5", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stderr == "", \
        f"no note without run-in sections: {proc.stderr!r}"
    with h5py.File(tmp_path / "r.h5") as f, h5py.File(tmp_path / "p.h5") as g:
        assert np.array_equal(f["face"][()], g["face"][()], equal_nan=True), \
            "the run-in sections must not change the steady face"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["epoxy_cylinder", "voronoi_biphasic", "rods_steel_in_brass",
                                  "rods_brass_in_steel", "checkerboard"])
def test_shipped_scenes_run(tmp_path, name):
    scene = SCENES / f"{name}.toml"
    proc = run(scene, "-o", tmp_path / "r.h5", "--plot", tmp_path / "r.png", cwd=tmp_path)
    assert proc.returncode == 0, f"{name}: exit {proc.returncode}: {proc.stderr}"
    assert (tmp_path / "r.png").stat().st_size > 10_000, f"{name}: figure not written"
    with h5py.File(tmp_path / "r.h5") as f:
        rms, error, plain = (f[k][()] for k in ("rms_slope", "rms_slope_error",
                                                 "rms_slope_plain"))
        ref = f["rms_slope_ref"][()]
    ratio = rms / ref
    # Corrected rms / grad_f0 at n = 256: 1.00015, 1.6129, 1.0023, 1.1434, 1.2645
    # (plain pixel values 0.990, 1.447, 0.986, 1.130, 1.219); error bars 0.06-0.16 %.
    assert 0.99 < ratio < 1.62, f"{name}: rms / grad_f0 = {ratio}"
    assert 0 < error < 2e-3 * rms, f"{name}: error bar {error} of {rms}"
    assert plain < rms, f"{name}: the plain pixel value {plain} should lie below {rms}"
    if name == "epoxy_cylinder":
        # Homogeneous: the continuum value is grad_f0 (eq. 10, 12).
        assert abs(ratio - 1) < 2 * error / ref + 1e-4, \
            f"homogeneous rms / grad_f0 = {ratio} +- {error}"


@pytest.mark.skipif(not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc",
                    reason="glibc's allocator only")
def test_freed_large_arrays_are_reused_without_page_faults():
    # After keep_freed_memory a freed 32 MiB array's pages serve the next one:
    # measured 0.2 page faults per array (528 with glibc's defaults on the same
    # machine).  In a child process: the setting is process-wide.
    code = """
import resource
import numpy as np
from steady.memory import keep_freed_memory
assert keep_freed_memory()
a = np.ones(2**22); del a
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(5):
    a = np.ones(2**22); a += 1.0; del a
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 5)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert float(out) < 10, f"{float(out)} page faults per freed and reallocated 32 MiB array"


@pytest.mark.skipif(not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc",
                    reason="glibc's allocator only")
def test_freed_large_arrays_are_reused_on_another_thread():
    # A thread's own arena maps a 128 MiB block afresh each time: measured 65 page
    # faults per pair of a 32 and a 128 MiB array with M_MMAP_MAX = 0 alone (593 with
    # glibc's defaults), 0.2 with every thread on the main heap.
    code = """
import resource, threading
import numpy as np
from steady.memory import keep_freed_memory
assert keep_freed_memory()
def work(out):
    a = np.ones(2**22); b = np.ones(2**24); del a, b
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(5):
        a = np.ones(2**22); a += 1.0; del a
        b = np.ones(2**24); b += 1.0; del b
    out.append((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 5)
out = []
thread = threading.Thread(target=work, args=(out,))
thread.start()
thread.join()
print(out[0])
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert float(out) < 10, f"{float(out)} page faults per freed and reallocated pair on a thread"
