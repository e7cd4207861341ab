"""Faults around the run file: write errors, interrupts, concurrent writers, damaged files.

Every fault ends in one line ``error: ...`` on stderr that says what is
saved, the documented exit status, no traceback, and no finished run or
checkpoint thrown away.  In-process where a fault can be injected
(``main(argv)`` with a patched function); in a subprocess for the real
signals (SIGINT, SIGKILL), concurrent writers and a real write error
(``RLIMIT_FSIZE``).
"""

import errno
import json
import os
import pathlib
import signal
import stat
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest
from conftest import one_error_line, run_cli

import steady.cli.solve as steady_cli
import transient.__main__ as cli
from steady.output import read_result
from steady.safe_files import RunLock, backup_path, lock_path
from transient.output import read_run
from transient.solver import StageSolver


@pytest.fixture
def scene(scene_file):
    """The gallery's run-in scene (n = 32, tol 1e-3, snapshots at 0.1 and 1 s*)."""
    return scene_file("runin")




def leftovers(directory):
    """Temporary and lock files left in a directory."""
    return sorted(p.name for p in pathlib.Path(directory).iterdir()
                  if p.name.endswith((".tmp", ".lock")))


def flip_bit(path, offset, bit=0x10):
    data = bytearray(path.read_bytes())
    data[offset] ^= bit
    path.write_bytes(bytes(data))


# -- the file system ---------------------------------------------------------
def test_new_directories_and_same_permissions(tmp_path, scene, capsys):
    """Missing directories are created; result, run file, backup and figure honour the umask."""
    old = os.umask(0o027)
    try:
        status, _, err = run_cli(cli, [scene, "-o", tmp_path / "runs" / "run.h5", "--plot",
                                  tmp_path / "figures" / "run.png"], capsys)
        assert status == 0, f"exit {status}: {err}"
        status, _, err = run_cli(steady_cli, [scene, "-o", tmp_path / "steady" / "result.h5",
                                              "--no-slope-error"], capsys)
        assert status == 0, f"exit {status}: {err}"
    finally:
        os.umask(old)
    # The backup of a finished run is gone (tests/test_writers.py checks a stopped run's).
    for path in (tmp_path / "runs" / "run.h5",
                 tmp_path / "figures" / "run.png", tmp_path / "steady" / "result.h5"):
        mode = stat.S_IMODE(path.stat().st_mode)
        assert mode == 0o640, f"{path.name}: mode {oct(mode)}, expected 0o640 (umask 027)"
    assert leftovers(tmp_path / "runs") == [], f"left: {leftovers(tmp_path / 'runs')}"


def _failing_fsync(monkeypatch, fail_at):
    """Make the ``fail_at``-th fsync of a regular file fail with ENOSPC (a full disk)."""
    real = os.fsync
    calls = {"n": 0}

    def fsync(fd):
        if stat.S_ISREG(os.fstat(fd).st_mode):
            calls["n"] += 1
            if calls["n"] == fail_at:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def test_write_error_names_the_last_checkpoint(tmp_path, scene, capsys, monkeypatch):
    out = tmp_path / "run.h5"
    _failing_fsync(monkeypatch, fail_at=4)  # the fourth checkpoint
    status, _, err = run_cli(cli, [scene, "-o", out, "--checkpoint-interval", "0"], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert f"cannot write {str(out)!r}: No space left on device" in line, line
    assert f"the checkpoint in {str(out)!r} (step 3, s = " in line and "--resume" in line, line
    saved = read_run(out)[0]
    assert saved.steps == 3 and saved.status == "running", f"{saved.steps} {saved.status}"
    assert leftovers(tmp_path) == [], f"left: {leftovers(tmp_path)}"


def test_write_error_before_any_checkpoint(tmp_path, scene, capsys, monkeypatch):
    _failing_fsync(monkeypatch, fail_at=1)
    status, _, err = run_cli(cli, [scene, "-o", tmp_path / "run.h5"], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert "No space left on device; nothing was saved" in line, line
    assert not (tmp_path / "run.h5").exists() and leftovers(tmp_path) == [], \
        f"files left: {sorted(p.name for p in tmp_path.iterdir())}"


def test_a_real_write_error(tmp_path, scene):
    """A file-size limit makes the kernel refuse the write (EFBIG): one line, exit 1."""
    def limit():
        import resource

        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    out = tmp_path / "run.h5"
    proc = subprocess.run([sys.executable, "-m", "transient", str(scene), "-o", str(out)],
                          capture_output=True, text=True, timeout=120, preexec_fn=limit)
    line = one_error_line(proc.stderr)
    assert proc.returncode == 1, f"exit {proc.returncode}: {proc.stderr}"
    assert f"cannot write {str(out)!r}: File too large; nothing was saved" in line, line
    assert leftovers(tmp_path) == [] and not out.exists(), \
        f"files left: {sorted(p.name for p in tmp_path.iterdir())}"


def test_plot_failure_keeps_the_run(tmp_path, scene, capsys, monkeypatch):
    import transient.plotting

    def fail(run_path, png_path):
        raise PermissionError(errno.EACCES, "Permission denied", str(png_path))

    monkeypatch.setattr(transient.plotting, "plot_run", fail)
    out = tmp_path / "run.h5"
    status, _, err = run_cli(cli, [scene, "-o", out, "--plot", tmp_path / "run.png"], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert "cannot draw the figure" in line and f"the run is saved in {str(out)!r}" in line, line
    assert read_run(out)[0].status == "steady", "the finished run must be kept"


def test_leftover_temporary_files_are_removed(tmp_path, scene, capsys):
    stray = tmp_path / ".run.h5.k1ll3d.tmp"
    stray.write_bytes(b"half a file of a killed writer")
    status, _, err = run_cli(cli, [scene, "-o", tmp_path / "run.h5"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert not stray.exists(), "the killed writer's temporary file is still there"


def test_first_checkpoint_follows_the_first_step(tmp_path, scene, capsys, monkeypatch):
    import transient.output

    steps = []
    real = transient.output.write_run

    def record(path, result, **kw):
        steps.append(result.steps)
        return real(path, result, **kw)

    monkeypatch.setattr(transient.output, "write_run", record)
    status, _, err = run_cli(cli, [scene, "-o", tmp_path / "run.h5"], capsys)  # interval 10 s
    assert status == 0, f"exit {status}: {err}"
    assert steps[0] == 1, f"first checkpoint at step {steps[0]}, expected 1 (all: {steps})"


# -- interrupts ----------------------------------------------------------------
def _interrupt_at_solve(monkeypatch, k):
    real = StageSolver.contact
    calls = {"n": 0}

    def contact(self, *args, **kw):
        calls["n"] += 1
        if calls["n"] == k:
            raise KeyboardInterrupt
        return real(self, *args, **kw)

    monkeypatch.setattr(StageSolver, "contact", contact)


def test_interrupt_before_the_first_checkpoint(tmp_path, scene, capsys, monkeypatch):
    _interrupt_at_solve(monkeypatch, 1)
    status, _, err = run_cli(cli, [scene, "-o", tmp_path / "run.h5"], capsys)
    line = one_error_line(err)
    assert status == 130, f"exit {status}: {err}"
    assert line == "error: interrupted; nothing was saved (no checkpoint had been written)", line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"], "nothing written"


def test_interrupt_after_checkpoints_then_resume(tmp_path, scene, capsys, monkeypatch):
    out = tmp_path / "run.h5"
    _interrupt_at_solve(monkeypatch, 12)
    status, _, err = run_cli(cli, [scene, "-o", out, "--checkpoint-interval", "0"], capsys)
    line = one_error_line(err)
    saved = read_run(out)[0]
    assert status == 130, f"exit {status}: {err}"
    assert f"interrupted; the checkpoint in {str(out)!r} (step {saved.steps}, s = " in line \
        and line.endswith("can be continued with --resume"), line
    assert saved.steps > 0 and not lock_path(out).exists(), "checkpoint kept, lock released"
    with h5py.File(out) as f:  # rewritten at every checkpoint: stored plain
        assert [f[f"snapshots/{name}"].compression for name in ("recession", "pressure")] \
            == [None, None], "a checkpoint's snapshots are not compressed"
    monkeypatch.undo()
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume", "--checkpoint-interval", "0"],
                             capsys)
    assert status == 0 and err == "", f"exit {status}: {err!r}"
    assert read_run(out)[0].status == "steady", "the resumed run must finish"
    with h5py.File(out) as f:
        filters = [(f[f"snapshots/{name}"].compression, f[f"snapshots/{name}"].shuffle)
                   for name in ("recession", "pressure")]
        assert filters == [("gzip", True)] * 2, f"a finished run's snapshot filters: {filters}"


def test_steady_interrupt(tmp_path, capsys, monkeypatch, scene_file):
    def interrupted(*args, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(steady_cli, "solve_scene", interrupted)
    status, _, err = run_cli(steady_cli, [scene_file("steady"), "-o", tmp_path / "r.h5"],
                             capsys)
    assert status == 130, f"exit {status}: {err}"
    assert one_error_line(err) == "error: interrupted; nothing was written", err
    assert not (tmp_path / "r.h5").exists(), "no result after an interrupt"


def test_sigint(tmp_path, write_slow_scene):
    """Ctrl-C (SIGINT) in the middle of a run: exit 130, one line naming the checkpoint."""
    out = tmp_path / "run.h5"
    child = subprocess.Popen([sys.executable, "-m", "transient", str(write_slow_scene()),
                              "-o", str(out), "--checkpoint-interval", "0"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _wait_for(lambda: out.exists(), child)
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    line = one_error_line(err)
    assert child.returncode == 130, f"exit {child.returncode}: {err}"
    assert f"interrupted; the checkpoint in {str(out)!r} (step " in line, line
    assert read_run(out)[0].status == "running", "a readable checkpoint"
    assert leftovers(tmp_path) == [], f"left: {leftovers(tmp_path)}"


@pytest.fixture
def write_slow_scene(scene_file):
    """A run of a thousand steps or more (n = 64, SDIRK2, tol 1e-6): long enough to interrupt."""
    def write():
        return scene_file("runin", filename="slow.toml", n=64,
                          transient={"scheme": "sdirk2", "tol": 1e-6,
                                     "snapshots_s_star": (0.1, 1.0)})
    return write


def _wait_for(condition, child, timeout=60):
    deadline = time.monotonic() + timeout
    while not condition():
        assert child.poll() is None, f"the run ended (status {child.returncode}) too early"
        assert time.monotonic() < deadline, "timed out waiting for the run"
        time.sleep(0.02)


# -- concurrent writers ------------------------------------------------------------
def test_second_writer_is_refused(tmp_path, scene, capsys):
    out = tmp_path / "run.h5"
    out.write_bytes(b"another run's checkpoint")
    with RunLock(out):
        for flag in ("--force", "--resume"):
            status, _, err = run_cli(cli, [scene, "-o", out, flag], capsys)
            line = one_error_line(err)
            assert status == 2, f"{flag}: exit {status}: {err}"
            assert line == f"error: another run is writing {str(out)!r} (pid {os.getpid()})", \
                line
    assert out.read_bytes() == b"another run's checkpoint", "the other run's file was touched"


def test_concurrent_writers(tmp_path, write_slow_scene):
    """Two real processes: the second is refused at once, naming the first's pid."""
    scene = write_slow_scene()
    out = tmp_path / "run.h5"
    first = subprocess.Popen([sys.executable, "-m", "transient", str(scene), "-o", str(out)],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait_for(lambda: out.exists(), first)  # running, and checkpointed once
        proc = subprocess.run([sys.executable, "-m", "transient", str(scene), "-o", str(out),
                               "--resume"], capture_output=True, text=True, timeout=60)
        line = one_error_line(proc.stderr)
        assert proc.returncode == 2, f"exit {proc.returncode}: {proc.stderr}"
        assert line == f"error: another run is writing {str(out)!r} (pid {first.pid})", line
        assert first.poll() is None, "the first run must go on"
        assert read_run(out)[0].status == "running", "the first run's checkpoint is intact"
    finally:
        first.kill()
        first.wait()


def test_a_dead_writer_lock_is_taken_over(tmp_path, scene, capsys):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, timeout=60)
    pid = int(dead.stdout)
    out = tmp_path / "run.h5"
    lock_path(out).write_text(f"{pid}\n")  # left by a killed run
    status, _, err = run_cli(cli, [scene, "-o", out], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert err == (f"note: took over the lock of {str(out)!r} left by process {pid}, which has "
                   f"ended\n"), f"stderr {err!r}"
    assert not lock_path(out).exists(), "the lock is released at the end"


# -- damaged run files ----------------------------------------------------------------
@pytest.fixture
def stopped_run(tmp_path, scene, capsys):
    """A run stopped after 3 steps, checkpointed after each (so a backup exists)."""
    out = tmp_path / "run.h5"
    status, _, err = run_cli(cli, [scene, "-o", out, "--max-steps", "3", "--checkpoint-interval",
                              "0"], capsys)
    assert status == 1 and backup_path(out).exists(), f"exit {status}: {err}"
    return scene, out


def _offset(path, name):
    with h5py.File(path, "r") as f:
        return f[name].id.get_offset()


def _damage_state(path):
    flip_bit(path, _offset(path, "state/recession") + 8 * (16 * 32 + 16) + 3)


def _damage_scalar(path):
    import struct

    with h5py.File(path, "r") as f:
        distance = f["distance"][()]
    data = path.read_bytes()
    flip_bit(path, data.index(struct.pack("<d", distance)), 0x01)


def _damage_attribute(path):
    flip_bit(path, path.read_bytes().index(b"RunOptions("), 0x01)


def _truncate(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _garbage(path):
    path.write_bytes(np.random.default_rng(4049).bytes(4096))


@pytest.mark.parametrize("damage, fragment", [
    (_damage_state, "dataset 'state/recession' does not match its checksum"),
    (_damage_scalar, "dataset 'distance' does not match its checksum"),
    (_damage_attribute, "the root attributes do not match their checksum"),
    (_truncate, "cannot be opened (Unable to synchronously open file (truncated file"),
    (lambda p: p.write_bytes(b""), "the file is empty (0 bytes)"),
    (_garbage, "no HDF5 signature"),
])
def test_damaged_run_file_is_refused(stopped_run, capsys, damage, fragment):
    scene, out = stopped_run
    damage(out)
    damaged = out.read_bytes()
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume"], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith(f"error: run file {str(out)!r} is damaged: {fragment}"), line
    assert line.endswith(f"the previous checkpoint {str(backup_path(out))!r} (step 3, s = "
                         f"18.852 m = 0.000612691 s*) is intact: rename it to {str(out)!r} and "
                         f"--resume"), \
        line
    assert out.read_bytes() == damaged, "the damaged file must be left as it is"
    backup_path(out).replace(out)  # what the message says to do
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume"], capsys)
    assert status == 0, f"resuming from the backup: exit {status}: {err}"


def test_damaged_run_file_without_backup(stopped_run, capsys):
    scene, out = stopped_run
    backup_path(out).unlink()
    _damage_state(out)
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume"], capsys)
    line = one_error_line(err)
    assert status == 2 and line.endswith("no intact previous checkpoint is left; start over "
                                         "with --force"), line


def test_other_file_as_run_file(tmp_path, scene, capsys, scene_file):
    out = tmp_path / "result.h5"
    assert run_cli(steady_cli, [scene_file("steady", filename="st.toml"), "-o", out,
                                "--no-slope-error"], capsys)[0] == 0, "steady result"
    before = out.read_bytes()
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume"], capsys)
    line = one_error_line(err)
    assert status == 2 and f"{str(out)!r} is not a run file (format 'runin.steady'" in line, line
    assert out.read_bytes() == before and read_result(out).result.n == 40, "file untouched"


# -- what a resume continues with ----------------------------------------------------------
def test_resume_with_another_scheme_is_recorded(stopped_run, capsys):
    scene, out = stopped_run
    status, _, err = run_cli(cli, [scene, "-o", out, "--resume", "--scheme", "bdf2"], capsys)
    assert status == 0, f"exit {status}: {err}"
    notes = err.splitlines()
    assert len(notes) == 1 and notes[0].startswith(
        f"note: resuming {str(out)!r} at step 3, s = 18.852 m = 0.000612691 s* with changed "
        f"settings: "
        f"scheme 'esdirk3' -> 'bdf2'; max_steps 3 -> 100000; checkpoint_interval 0.0 -> "
        f"10.0"), f"stderr {err!r}"
    result, attrs, _ = read_run(out)
    parts = json.loads(attrs["settings_history"])
    assert [p["settings"]["scheme"] for p in parts] == ["esdirk3", "bdf2"], parts
    assert [(p["from_step"], p["to_step"]) for p in parts] == [(0, 3), (3, result.steps)], parts
    assert [p["status"] for p in parts] == ["stopped", "steady"], parts
    assert parts[1]["from_distance"] == parts[0]["to_distance"], "parts must join"
    assert attrs["scheme"] == "bdf2", "the root scheme is that of the last part"


def test_passed_snapshots_are_reported_missing(tmp_path, scene_file, capsys):
    s_star = 0.004 / (1.0e-13 * 1.3e6)  # the "runin" scene's: L / (k_min E*)
    first = scene_file("runin", filename="a.toml",
                       transient={"tol": 1e-3, "snapshots_s_star": (1.0,)})
    out = tmp_path / "run.h5"
    status, _, err = run_cli(cli, [first, "-o", out, "--distance-limit", f"{0.5 * s_star!r}"],
                             capsys)
    assert status == 1, f"exit {status}: {err}"
    more = scene_file("runin", filename="b.toml",
                      transient={"tol": 1e-3, "snapshots_s_star": (0.1, 1.0)})
    status, _, err = run_cli(cli, [more, "-o", out, "--resume"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert (f"note: snapshots at {0.1 * s_star:.6g} m were passed before this resume (at s = "
            f"{0.5 * s_star:.6g} m)") in err and \
        "are not in the file (listed in the attribute snapshots_missing)" in err, err
    result, attrs, _ = read_run(out)
    assert result.distance_scale == s_star, "the scene's s*"
    assert np.allclose(attrs["snapshots_missing"], [0.1 * s_star], rtol=1e-12), \
        f"snapshots_missing {attrs['snapshots_missing']}"
    assert np.allclose(result.snapshot_distance, [s_star], rtol=1e-12), \
        f"stored snapshots {result.snapshot_distance / s_star} s*"
    parts = json.loads(attrs["settings_history"])
    assert parts[-1]["snapshots_missing"] == [pytest.approx(0.1 * s_star)], parts[-1]


def test_resume_of_a_finished_run_leaves_it_untouched(tmp_path, scene, capsys):
    out = tmp_path / "run.h5"
    assert run_cli(cli, [scene, "-o", out], capsys)[0] == 0, "first run"
    files = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    status, stdout, err = run_cli(cli, [scene, "-o", out, "--resume", "--scheme", "bdf2"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert err == f"note: {str(out)!r} holds a finished run; nothing to continue\n", err
    assert "agreement with the steady face" in stdout, stdout
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == files, "files changed"


def test_a_lone_backup_is_not_dropped(stopped_run, capsys):
    """Without its run file, a backup is what is left of a run: refused, unless --force."""
    scene, out = stopped_run
    out.unlink()
    backup = backup_path(out).read_bytes()
    for flag in ([], ["--resume"]):
        status, _, err = run_cli(cli, [scene, "-o", out, *flag], capsys)
        line = one_error_line(err)
        assert status == 2, f"{flag}: exit {status}: {err}"
        assert line == (f"error: {str(out)!r} does not exist but its backup "
                        f"{str(backup_path(out))!r} does: rename it to {str(out)!r} to continue "
                        f"from it, or use --force to start over"), line
    assert backup_path(out).read_bytes() == backup and not out.exists(), "nothing touched"
