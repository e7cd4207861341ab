"""What the commands check before the work, and what they say when something goes wrong after it.

- an unsupported ``--plot`` suffix is refused before any work (nothing written);
- ``--resume --spatial-error`` on a finished run computes the spatial error it lacks;
- messages: a null byte in an argument names the argument; the lock of a live process is not
  taken over (and "which has ended" is said only of a process that has); one wording for a
  refusal to overwrite; every ``[initial_face]`` error starts with the scene file;
- the exit-status table (0 done, 1 resumable or an OS error, 2 bad input or refused with
  nothing written, 130 interrupted) holds on the paths fixed here and every ``--help`` states it.

In-process (``main(argv)``, faults injected with monkeypatch) except where a real process is
needed.
"""

import os
import re
import signal
import subprocess
import sys

import h5py
import numpy as np
import pytest
from conftest import one_error_line, run_cli

import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.cli.common import EXIT_STATUS_EPILOG
from steady.cli.entry import launch
from steady.safe_files import lock_path
from transient.output import read_run


@pytest.fixture
def steady_scene(scene_file):
    return scene_file("steady", filename="steady.toml")


@pytest.fixture
def runin_scene(scene_file):
    return scene_file("runin", filename="runin.toml", transient={"tol": 1e-3})


# -- --plot: the suffix before any work ------------------------------------------------------
@pytest.mark.parametrize("name", ["figure.txt", "figure", "figure.pdf"])
def test_steady_refuses_a_plot_suffix_before_the_solve(tmp_path, steady_scene, capsys, name):
    out = tmp_path / "r.h5"
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", out, "--plot", tmp_path / name],
                             capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith("error: --plot ") and "expected the suffix .png" in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["steady.toml"], \
        f"nothing may be written: {sorted(p.name for p in tmp_path.iterdir())}"


@pytest.mark.parametrize("name", ["figure.txt", "figure"])
def test_runin_refuses_a_plot_suffix_before_the_run(tmp_path, runin_scene, capsys, name):
    out = tmp_path / "run.h5"
    status, stdout, err = run_cli(transient_cli, [runin_scene, "-o", out, "--plot",
                                                  tmp_path / name], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith("error: --plot ") and "expected the suffix .png" in line, line
    assert stdout == "", f"no run may start: {stdout!r}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runin.toml"], \
        f"nothing may be written: {sorted(p.name for p in tmp_path.iterdir())}"


def test_an_upper_case_png_suffix_is_a_png(tmp_path, steady_scene, capsys):
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", tmp_path / "r.h5", "--plot",
                                          tmp_path / "r.PNG", "--no-slope-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert (tmp_path / "r.PNG").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "a PNG image"


# -- --resume --spatial-error on a finished run ----------------------------------------------
def spatial_error_of(path):
    with h5py.File(path) as f:
        return f["history/rms_slope_spatial_error"][()], f["history/distance"][()]


def test_resume_computes_the_spatial_error_a_finished_run_lacks(tmp_path, scene_file, capsys):
    scene = scene_file("runin", filename="s.toml", n=48, transient={"tol": 1e-3})
    out = tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [scene, "-o", out], capsys)
    assert status == 0, f"first run: exit {status}: {err}"
    before, _, _ = read_run(out)
    with h5py.File(out) as f:  # absent: not computed
        assert "rms_slope_spatial_error" not in f["history"], "a run without --spatial-error"

    status, stdout, err = run_cli(transient_cli, [scene, "-o", out, "--resume",
                                                  "--spatial-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert "nothing to continue" not in err, f"the spatial error was asked for: {err!r}"
    assert "companion run on n = 24" in stdout, stdout
    error, distance = spatial_error_of(out)
    assert error.shape == distance.shape, f"error shape {error.shape}, history {distance.shape}"
    assert np.all(np.isfinite(error)) and error[1:].max() > 0, f"error {error}"
    after, _, _ = read_run(out)
    assert after.status == "steady" and after.steps == before.steps, \
        f"the run itself is unchanged: {after.status} after {after.steps} steps"
    assert np.array_equal(after.worn_depth, before.worn_depth, equal_nan=True), \
        "the worn face is unchanged"

    # Now it holds what was asked: nothing to do, nothing touched.
    files = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--resume", "--spatial-error"],
                             capsys)
    assert status == 0, f"exit {status}: {err}"
    assert err == f"note: {str(out)!r} holds a finished run; nothing to continue\n", err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == files, "files changed"


# -- messages: a null byte names its argument ------------------------------------------------
@pytest.mark.parametrize("command, argv, name", [
    ("steady.cli.solve", ["S", "-o", "a\0b.h5"], "-o/--output"),
    ("steady.cli.solve", ["S", "-o", "r.h5", "--plot", "a\0b.png"], "--plot"),
    ("steady.cli.solve", ["a\0b.toml", "-o", "r.h5"], "scene"),
    ("transient.cli.runin", ["R", "-o", "a\0b.h5"], "-o/--output"),
    ("transient.cli.runin", ["R", "-o", "run.h5", "--plot", "a\0b.png"], "--plot"),
    ("transient.cli.runin", ["a\0b.toml", "-o", "run.h5"], "scene"),
    ("steady.cli.fit", ["S", "m\0.npy", "-o", "f.h5"], "measured"),
    ("steady.cli.fit", ["S", "m.npy", "-o", "f\0.h5"], "-o/--output"),
    ("steady.cli.design", ["--pbar-over-estar", "0.08", "--wear-ratio", "0.01",
                           "--fill-factor", "0.2", "--table", "t\0.h5"], "--table"),
])
def test_a_null_byte_names_its_argument(tmp_path, steady_scene, runin_scene, capsys,
                                        monkeypatch, command, argv, name):
    monkeypatch.chdir(tmp_path)
    argv = [{"S": str(steady_scene), "R": str(runin_scene)}.get(a, a) for a in argv]
    try:
        status = launch(command, argv)
    except SystemExit as done:
        status = done.code
    err = capsys.readouterr().err
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith(f"error: argument {name}: ") and "null byte" in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runin.toml", "steady.toml"], \
        "nothing written"


# -- messages: the lock of a live process, of a dead one -------------------------------------
def test_the_lock_of_a_live_process_is_not_taken_over(tmp_path, runin_scene, capsys):
    """A lock file naming a running process that does not hold the lock: refused, untouched."""
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        out = tmp_path / "run.h5"
        lock_path(out).write_text(f"{live.pid}\n")  # a lock file copied from elsewhere, say
        status, stdout, err = run_cli(transient_cli, [runin_scene, "-o", out], capsys)
        line = one_error_line(err)
        assert status == 2, f"exit {status}: {err}"
        assert "ended" not in err and f"process {live.pid}, which is running" in line, line
        assert "remove the lock file" in line, f"the way out is named: {line}"
        assert lock_path(out).read_text() == f"{live.pid}\n", "the lock file is untouched"
        assert not out.exists() and stdout == "", "nothing run, nothing written"
    finally:
        live.kill()
        live.wait()


def test_the_lock_of_an_ended_unreaped_process_is_taken_over(tmp_path, runin_scene, capsys):
    """A killed writer its parent has not reaped yet (a zombie) has ended: its lock is free."""
    dead = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        os.kill(dead.pid, signal.SIGKILL)
        os.waitid(os.P_PID, dead.pid, os.WEXITED | os.WNOWAIT)  # dead, not reaped
        out = tmp_path / "run.h5"
        lock_path(out).write_text(f"{dead.pid}\n")
        status, _, err = run_cli(transient_cli, [runin_scene, "-o", out], capsys)
        assert status == 0, f"exit {status}: {err}"
        assert err == (f"note: took over the lock of {str(out)!r} left by process {dead.pid}, "
                       f"which has ended\n"), f"stderr {err!r}"
    finally:
        dead.wait()


# -- messages: one wording for a refusal to overwrite ----------------------------------------
def test_the_library_says_force_true(tmp_path, steady_scene, capsys):
    from steady.plotting import plot_file

    out = tmp_path / "r.h5"
    assert run_cli(steady_cli, [steady_scene, "-o", out, "--no-slope-error"], capsys)[0] == 0
    (tmp_path / "r.png").write_bytes(b"precious")
    with pytest.raises(ValueError, match=re.escape("exists (pass force=True to overwrite)")):
        plot_file(out, tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes() == b"precious", "figure untouched"


def test_steady_plot_that_appears_during_the_solve(tmp_path, steady_scene, capsys, monkeypatch):
    """Not replaced; the command's wording; exit 1, since the result is written."""
    png = tmp_path / "r.png"
    solve = steady_cli.solve_scene

    def solve_while_someone_writes_the_figure(*args, **kwargs):
        png.write_bytes(b"precious")
        return solve(*args, **kwargs)

    monkeypatch.setattr(steady_cli, "solve_scene", solve_while_someone_writes_the_figure)
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", tmp_path / "r.h5", "--plot", png,
                                          "--no-slope-error"], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert "(use --force to overwrite)" in line and "use force " not in line, line
    assert f"the result is saved in {str(tmp_path / 'r.h5')!r}" in line, line
    assert png.read_bytes() == b"precious", "the figure that appeared is not replaced"


def test_runin_plot_that_appears_during_the_run(tmp_path, runin_scene, capsys, monkeypatch):
    import transient.cli.runin as runin

    png = tmp_path / "run.png"
    run = runin._run

    def run_while_someone_writes_the_figure(job):
        png.write_bytes(b"precious")
        return run(job)

    monkeypatch.setattr(runin, "_run", run_while_someone_writes_the_figure)
    out = tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [runin_scene, "-o", out, "--plot", png], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert "(use --force to overwrite)" in line and f"saved in {str(out)!r}" in line, line
    assert png.read_bytes() == b"precious", "the figure that appeared is not replaced"
    assert read_run(out)[0].status == "steady", "the run is saved"


# -- messages: [initial_face] errors start with the scene file -------------------------------
def test_initial_face_errors_start_with_the_scene_file(tmp_path, scene_file, capsys):
    np.save(tmp_path / "h16.npy", np.zeros((16, 16)))
    np.save(tmp_path / "h32.npy", np.zeros((32, 32)))
    cases = {
        # Read at load time (its header), its shape checked on the grid.
        "wrong shape": (scene_file("runin", filename="a.toml", initial_face={
            "kind": "file", "path": "h16.npy"}), [], "holds an array of shape (16, 16)"),
        # Right for the grid, not for --spatial-error's companion grid.
        "companion grid": (scene_file("runin", filename="b.toml", initial_face={
            "kind": "file", "path": "h32.npy"}), ["--spatial-error"],
            "companion grid n = 16: [initial_face]"),
        # Read at load time.
        "unknown key": (scene_file("runin", filename="c.toml", initial_face={
            "kind": "crowned", "height": 1e-3}), [], "[initial_face]"),
    }
    for what, (scene, extra, fragment) in cases.items():
        out = tmp_path / f"{scene.stem}.h5"
        status, _, err = run_cli(transient_cli, [scene, "-o", out, *extra], capsys)
        line = one_error_line(err)
        assert status == 2, f"{what}: exit {status}: {err}"
        assert line.startswith(f"error: {scene}: "), f"{what}: no scene file first: {line}"
        assert fragment in line, f"{what}: {line!r} lacks {fragment!r}"
        assert not out.exists(), f"{what}: nothing written"


def test_a_failed_first_solve_names_the_scene_file(tmp_path, scene_file, capsys):
    scene = scene_file("runin", transient={"contact_rtol": 1e-300})
    status, _, err = run_cli(transient_cli, [scene, "-o", tmp_path / "run.h5"], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith(f"error: {scene}: the first contact solve failed: "), line


# -- the exit-status table -------------------------------------------------------------------
@pytest.mark.parametrize("module", [
    "steady.cli.solve", "transient.cli.runin", "steady.cli.design", "steady.cli.fit"])
def test_every_help_states_the_exit_statuses(module, capsys):
    with pytest.raises(SystemExit) as done:
        launch(module, ["--help"])
    assert done.value.code == 0, f"--help exit {done.value.code}"
    text = " ".join(capsys.readouterr().out.split())
    assert EXIT_STATUS_EPILOG in text, f"{module} --help lacks the exit statuses: {text[-400:]}"
    for status, meaning in (("0", "done"), ("1", "a run stopped or failed"),
                            ("2", "bad input or refused, nothing written"),
                            ("130", "interrupted")):
        assert f"{status} {meaning}" in EXIT_STATUS_EPILOG, f"the table lacks {status} {meaning}"


def test_a_failed_companion_run_keeps_the_finished_run(tmp_path, scene_file, capsys,
                                                       monkeypatch):
    """Exit 1 naming the file, not 2 ("nothing written"): the finished run is written."""
    import transient.spatial_error

    def fails(*args, **kwargs):
        raise ValueError("the companion's phase map changed")

    monkeypatch.setattr(transient.spatial_error, "spatial_error", fails)
    scene = scene_file("runin", n=48, transient={"tol": 1e-3})
    out = tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--spatial-error"], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert line.startswith(f"error: {scene}: --spatial-error: the companion run on n = 24 "
                           f"failed: "), line
    assert "--resume --spatial-error computes it" in line, line
    assert read_run(out)[0].status == "steady", "the finished run is written"


@pytest.mark.parametrize("command", ["steady", "transient"])
def test_ctrl_c_before_the_work_says_nothing_was_written(tmp_path, steady_scene, runin_scene,
                                                         capsys, monkeypatch, command):
    import transient.scene

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    if command == "steady":
        monkeypatch.setattr(steady_cli, "load_scene", interrupted)
        module, scene = steady_cli, steady_scene
    else:
        monkeypatch.setattr(transient.scene, "load_transient_scene", interrupted)
        module, scene = transient_cli, runin_scene
    status, _, err = run_cli(module, [scene, "-o", tmp_path / "out.h5"], capsys)
    line = one_error_line(err)
    assert status == 130, f"exit {status}: {err}"
    assert "nothing was written" in line, line
