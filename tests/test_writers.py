"""Writers of one output at once, and the backup of a finished run.

Every writer -- the steady result, the run file, the fit file, sweep and
study files -- publishes its file so that a file another process wrote
after the writer's check is never replaced without ``--force``: the
writer is refused (exit status 2, one line, nothing written, no temporary
file left).  The other writer is simulated in-process, at the moment that
matters: after the command's check and before its file is published.

A run that ends steady removes its backup ``RUN.h5.prev`` once its final
file reads back intact; a stopped, failed or interrupted run keeps it.
"""

import os
import pathlib
import stat
import sys

import h5py
import numpy as np
import pytest
from conftest import one_error_line, run_cli, temporaries

import steady.cli.fit as fit_cli
import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
import transient.output
from steady.output import read_result
from steady.safe_files import (
    OutputAppearedError,
    OutputExistsError,
    atomic_h5,
    backup_path,
    file_identity,
    lock_path,
)
from steady.sweep import SweepFile
from transient.output import DamagedRunFileError, read_run

STUDIES = pathlib.Path(__file__).resolve().parent.parent / "studies"

#: What the other writer leaves at the output.
OTHER = b"the other writer's finished result"





def appeared(path):
    """The refusal of a writer whose output another process wrote meanwhile."""
    return (f"error: output {str(path)!r} appeared meanwhile (another process wrote it); "
            f"nothing was written (use --force to overwrite)")


def replaced(path):
    """The refusal of a writer whose file another process replaced meanwhile."""
    return (f"error: output {str(path)!r} was replaced meanwhile by another process; "
            f"nothing was written (use --force to overwrite)")


# -- the atomic writer ------------------------------------------------------------------
def test_a_file_that_appears_during_the_write_is_not_replaced(tmp_path):
    path = tmp_path / "x.h5"
    with pytest.raises(OutputAppearedError, match="appeared meanwhile.*use --force"):
        with atomic_h5(path, format="runin.test", version=1) as f:
            f["values"] = np.arange(3.0)
            path.write_bytes(OTHER)  # another writer publishes first
    assert path.read_bytes() == OTHER, "the other writer's file was replaced"
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"
    with atomic_h5(path, format="runin.test", version=2, force=True) as f:
        f["values"] = np.arange(3.0)
    with h5py.File(path, "r") as f:
        assert f.attrs["format_version"] == 2, "force replaces whatever is there"


def test_replaces_names_the_one_file_a_writer_may_replace(tmp_path):
    path = tmp_path / "x.h5"
    first = atomic_h5(path, format="runin.test", version=1)
    with first as f:
        f["values"] = np.arange(2.0)
    assert first.identity == file_identity(path), "identity of the file written"
    second = atomic_h5(path, format="runin.test", version=2, replaces=first.identity)
    with second as f:  # its own previous file: replaced
        f["values"] = np.arange(2.0)
    assert second.identity == file_identity(path) != first.identity, "the new file in place"
    other = tmp_path / "other"
    other.write_bytes(OTHER)
    with pytest.raises(OutputAppearedError, match="was replaced meanwhile"):
        with atomic_h5(path, format="runin.test", version=3, replaces=second.identity) as f:
            os.replace(other, path)  # another writer's file in its place
    assert path.read_bytes() == OTHER and temporaries(tmp_path) == [], "refused, untouched"
    with pytest.raises(OutputExistsError, match=r"x.h5' exists \(use --force to overwrite\)"):
        with atomic_h5(path, format="runin.test", version=3):
            pytest.fail("the block must not run for an existing file")


def test_temporary_files_of_dead_writers_are_removed(tmp_path):
    """A writer killed while writing leaves its temporary file; the next writer removes it."""
    import socket
    import subprocess

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, timeout=60)
    pid = int(dead.stdout)
    host = socket.gethostname()
    stale = tmp_path / f".x.h5.{host}.{pid}.k1ll3d.tmp"
    live = tmp_path / f".x.h5.{host}.{os.getppid()}.l1v3.tmp"  # a live process's
    foreign = tmp_path / ".x.h5.n0p1d.tmp"  # whose writer cannot be told
    for p in (stale, live, foreign):
        p.write_bytes(b"half a file")
    with atomic_h5(tmp_path / "x.h5", format="runin.test", version=1) as f:
        f["values"] = np.arange(2.0)
    assert not stale.exists(), "the dead writer's temporary file is still there"
    assert live.exists() and foreign.exists(), "a live writer's file must be left alone"



_LIMITED_WRITE = """
import resource, signal, sys
import numpy as np
from steady.safe_files import atomic_h5
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))
try:
    with atomic_h5(sys.argv[1], format="runin.test", version=1) as f:
        f["values"] = np.arange({count}, dtype=float)
        f["values"].attrs["units"] = "m"
        f.create_group("group").attrs["name"] = "after the array"
except OSError as err:
    print(err)
"""


@pytest.mark.parametrize("count", [2, 90_000, 99_000, 99_500, 99_900, 100_000, 400_000])
def test_a_refused_write_is_an_error_and_never_a_truncated_file(tmp_path, count):
    """A file-size limit of 800,000 bytes: files below and around it, written or refused whole.

    The kernel refuses the write that passes the limit (EFBIG), wherever HDF5
    makes it: the array's data, or the metadata it writes when the file is
    closed (``count`` near 100,000 floats).
    """
    import subprocess

    path = tmp_path / "x.h5"
    proc = subprocess.run([sys.executable, "-c", _LIMITED_WRITE.format(limit=800_000,
                                                                       count=count),
                           str(path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr[-2000:]
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"
    if proc.stdout:
        assert proc.stdout.strip() == f"[Errno 27] cannot write {str(path)!r}: File too large", \
            proc.stdout
        assert not path.exists(), "a refused write left a file"
        assert count >= 99_000, f"{count} floats (8 bytes each) were refused under the limit"
        return
    with h5py.File(path, "r") as f:
        assert np.array_equal(f["values"][...], np.arange(count, dtype=float)), "values"
        assert f["group"].attrs["name"] == "after the array", "metadata written at the close"

# -- runin-steady and runin-fit ------------------------------------------------------
def _write_other_after(monkeypatch, module, name, out):
    """Make ``module.name`` write the other writer's file at ``out`` once it is done."""
    real = getattr(module, name)

    def work(*args, **kwargs):
        result = real(*args, **kwargs)
        out.write_bytes(OTHER)
        return result

    monkeypatch.setattr(module, name, work)


# The other writer publishes after the solve (before this one starts writing)
# or while this one writes its file (after the check of atomic_h5).
STEADY_MOMENTS = {"after the solve": ("steady.cli.solve", "solve_scene"),
                  "while writing": ("steady.output", "_write")}
FIT_MOMENTS = {"after the fit": ("steady.cli.fit", "fit_scene"),
               "while writing": ("steady.fit_files", "write_outline")}


@pytest.mark.parametrize("moment", STEADY_MOMENTS)
def test_steady_result_written_meanwhile_is_kept(tmp_path, scene_file, capsys, monkeypatch,
                                                 moment):
    scene = scene_file("steady")
    out = tmp_path / "result.h5"
    module, name = STEADY_MOMENTS[moment]
    _write_other_after(monkeypatch, sys.modules[module], name, out)
    status, stdout, err = run_cli(steady_cli, [scene, "-o", out, "--no-slope-error"], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line == appeared(out), line
    assert out.read_bytes() == OTHER, "the other writer's result was replaced"
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"
    out.unlink()
    status, _, err = run_cli(steady_cli, [scene, "-o", out, "--no-slope-error", "--force"],
                             capsys)
    assert status == 0, f"--force: exit {status}: {err}"
    assert read_result(out).result.n == 40, "--force replaces the file written meanwhile"


@pytest.mark.parametrize("moment", FIT_MOMENTS)
def test_fit_written_meanwhile_is_kept(tmp_path, scene_file, capsys, monkeypatch, moment):
    from steady.fit_files import read_fit
    from steady.scene import load_scene
    from steady.solution import solve_scene

    scene = scene_file("steady")
    np.save(tmp_path / "face.npy", solve_scene(load_scene(scene), face_only=True).face)
    out = tmp_path / "fit.h5"
    args = [scene, tmp_path / "face.npy", "--pixel-size", "2e-4", "-o", out]
    module, name = FIT_MOMENTS[moment]
    _write_other_after(monkeypatch, sys.modules[module], name, out)
    status, _, err = run_cli(fit_cli, args, capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line == appeared(out), line
    assert out.read_bytes() == OTHER, "the other writer's fit was replaced"
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"
    out.unlink()
    status, _, err = run_cli(fit_cli, args + ["--force"], capsys)
    assert status == 0, f"--force: exit {status}: {err}"
    assert read_fit(out).attrs["n"] == 40, "--force replaces the file written meanwhile"


# -- the run file --------------------------------------------------------------------
@pytest.fixture
def scene(scene_file):
    """The gallery's run-in scene (n = 32, tol 1e-3, snapshots at 0.1 and 1 s*)."""
    return scene_file("runin")


def _other_writer_at(monkeypatch, out, call, how):
    """Before the ``call``-th write of the run file, another process writes ``out``."""
    real = transient.output.write_run
    calls = {"n": 0}

    def write_run(path, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == call:
            how(out)
        return real(path, *args, **kwargs)

    monkeypatch.setattr(transient.output, "write_run", write_run)


def test_run_file_written_before_the_first_checkpoint_is_kept(tmp_path, scene, capsys,
                                                               monkeypatch):
    """The lock keeps other runs out; a file another command writes there is refused too."""
    out = tmp_path / "run.h5"
    _other_writer_at(monkeypatch, out, 1, lambda p: p.write_bytes(OTHER))
    status, _, err = run_cli(transient_cli, [scene, "-o", out], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line == appeared(out), line
    assert out.read_bytes() == OTHER, "the other writer's file was replaced"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5", "scene.toml"], \
        f"left behind: {sorted(p.name for p in tmp_path.iterdir())}"


def test_run_file_replaced_between_checkpoints_is_kept(tmp_path, scene, capsys, monkeypatch):
    out = tmp_path / "run.h5"

    def replace(path):  # e.g. another command with --force
        (tmp_path / "other").write_bytes(OTHER)
        os.replace(tmp_path / "other", path)

    _other_writer_at(monkeypatch, out, 3, replace)
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--checkpoint-interval", "0"],
                             capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line == replaced(out), line
    assert out.read_bytes() == OTHER, "the other writer's file was replaced"
    assert read_run(backup_path(out))[0].steps == 1, "the run's checkpoint before is kept"
    assert temporaries(tmp_path) == [] and not lock_path(out).exists(), \
        f"left behind: {sorted(p.name for p in tmp_path.iterdir())}"


def test_run_replaces_the_file_it_started_from(tmp_path, scene, capsys):
    """--force and --resume replace the file there at the start, then their own checkpoints."""
    out = tmp_path / "run.h5"
    out.write_bytes(OTHER)
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--force", "--max-steps", "3",
                                             "--checkpoint-interval", "0"], capsys)
    assert status == 1 and read_run(out)[0].steps == 3, f"--force: exit {status}: {err}"
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--resume",
                                             "--checkpoint-interval", "0"], capsys)
    assert status == 0 and read_run(out)[0].status == "steady", f"--resume: exit {status}: {err}"


# -- the backup of a finished run -------------------------------------------------------
def test_finished_run_drops_its_backup(tmp_path, scene, capsys):
    out = tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--checkpoint-interval", "0"],
                             capsys)
    assert status == 0, f"exit {status}: {err}"
    assert read_run(out)[0].status == "steady", "the finished run is in place"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5", "scene.toml"], \
        f"files beside the finished run: {sorted(p.name for p in tmp_path.iterdir())}"


def test_stopped_run_keeps_its_backup_until_it_ends(tmp_path, scene, capsys):
    """A stopped run keeps its backup (with the umask's permissions); resumed to the end, not."""
    out = tmp_path / "run.h5"
    old = os.umask(0o027)
    try:
        status, _, err = run_cli(transient_cli, [scene, "-o", out, "--max-steps", "3",
                                                 "--checkpoint-interval", "0"], capsys)
    finally:
        os.umask(old)
    assert status == 1, f"exit {status}: {err}"
    kept = read_run(backup_path(out))[0]
    assert (kept.steps, kept.status) == (3, "running"), "the last checkpoint is kept"
    mode = stat.S_IMODE(backup_path(out).stat().st_mode)
    assert mode == 0o640, f"backup mode {oct(mode)}, expected 0o640 (umask 027)"
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--resume"], capsys)
    assert status == 0, f"resume: exit {status}: {err}"
    assert not backup_path(out).exists(), "the backup outlives the finished run"


def test_interrupted_run_keeps_its_backup(tmp_path, scene, capsys, monkeypatch):
    out = tmp_path / "run.h5"
    real = transient.output.write_run
    calls = {"n": 0}

    def write_run(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(transient.output, "write_run", write_run)
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--checkpoint-interval", "0"],
                             capsys)
    assert status == 130, f"exit {status}: {err}"
    assert read_run(backup_path(out))[0].steps == 2, "the checkpoint before the last is kept"


def test_final_file_that_does_not_read_back_keeps_the_backup(tmp_path, scene, capsys,
                                                             monkeypatch):
    out = tmp_path / "run.h5"

    def damaged(path):
        raise DamagedRunFileError(path, "dataset 'pressure' does not match its checksum")

    monkeypatch.setattr(transient.output, "verify_run", damaged, raising=False)
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--checkpoint-interval", "0"],
                             capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert "the finished run does not read back as written" in line, line
    assert f"the previous checkpoint {str(backup_path(out))!r} (step " in line, line
    assert line.endswith(f"is kept: rename it to {str(out)!r} and --resume"), line
    assert read_run(backup_path(out))[0].status == "running", "the backup is kept"


def test_verify_run_names_the_damage(tmp_path, scene, capsys):
    out = tmp_path / "run.h5"
    assert run_cli(transient_cli, [scene, "-o", out], capsys)[0] == 0, "the run"
    transient.output.verify_run(out)  # intact: no exception
    with h5py.File(out, "r+") as f:
        f["history/distance"][0] += 1.0
    with pytest.raises(DamagedRunFileError, match="dataset 'history/distance' does not match"):
        transient.output.verify_run(out)


# -- sweep and study files ----------------------------------------------------------------
def test_a_sweep_created_meanwhile_is_joined_not_truncated(tmp_path, monkeypatch):
    path = tmp_path / "sweep.h5"
    first = SweepFile(path, {"n": 16})
    first.write({"x": 1}, {"y": 2.0})
    # The second sweep checked before the first created the file.
    real = pathlib.Path.exists
    monkeypatch.setattr(pathlib.Path, "exists",
                        lambda self: False if self == path else real(self))
    second = SweepFile(path, {"n": 16})
    monkeypatch.undo()
    assert second.keys() == {'{"x":1}'}, "the first sweep's point was lost"
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"


@pytest.fixture
def study_io():
    sys.path.insert(0, str(STUDIES))
    try:
        import study_io

        yield study_io
    finally:
        sys.path.remove(str(STUDIES))


def _study(study_io, out, *flags, other=None):
    """Run a tiny study on ``out``; ``other(out)`` acts while it computes."""
    def compute(path, params):
        if other is not None:
            other(path)
        study_io.write_study(path, "tiny", params, {"x": (np.arange(3.0), "1")})

    def plot(path, png):
        study_io.read_study(path, "tiny")

    return study_io.run_study("tiny", "A tiny study.", compute, plot, {"a": 1}, {"a": 2},
                              ["-o", str(out), "--png", str(out.with_suffix(".png")), *flags])


def test_study_file_written_meanwhile_is_kept(tmp_path, study_io, capsys):
    out = tmp_path / "tiny.h5"
    assert _study(study_io, out) == 0, "a new study file"
    assert _study(study_io, out) == 0, "an earlier run's file is replaced"
    status = _study(study_io, out, other=lambda p: p.write_bytes(OTHER))
    err = capsys.readouterr().err
    assert status == 2, f"exit {status}: {err}"
    assert err.strip() == replaced(out), err
    assert out.read_bytes() == OTHER, "the other process's file was replaced"
    out.unlink()
    status = _study(study_io, out, other=lambda p: p.write_bytes(OTHER))
    err = capsys.readouterr().err
    assert status == 2 and err.strip() == appeared(out), f"exit {status}: {err}"
    assert out.read_bytes() == OTHER, "the other process's file was replaced"
    assert _study(study_io, out, "--force", other=lambda p: p.write_bytes(OTHER)) == 0, \
        "--force replaces it"
    assert study_io.read_study(out, "tiny")[1]["params"] == {"a": 1}, "the study's file"
    assert temporaries(tmp_path) == [], f"left behind: {temporaries(tmp_path)}"
