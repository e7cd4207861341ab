"""What the commands check before the work, and what they say when something goes wrong after it.

- an unsupported ``--plot`` suffix is refused before any work (nothing written);
- ``--resume`` on a finished run computes the grid error it lacks (``--no-grid-error`` skips it);
- messages: a null byte in an argument names the argument; the lock of a live process is not
  taken over (and "which has ended" is said only of a process that has); one wording for a
  refusal to overwrite; every ``[initial_face]`` error starts with the scene file;
- the exit-status table (0 done, 1 resumable or an OS error, 2 bad input or refused with
  nothing written, 130 interrupted) holds on the paths fixed here and every ``--help`` states it.

In-process (``main(argv)``, faults injected with monkeypatch) except where a real process is
needed.
"""

import importlib
import os
import pathlib
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
@pytest.mark.parametrize("name", ["figure.txt", "figure", "figure.jpg"])
def test_steady_refuses_a_plot_suffix_before_the_solve(tmp_path, steady_scene, capsys, name):
    out = tmp_path / "r.h5"
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", out, "--plot", tmp_path / name],
                             capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith("error: --plot ") and "expected the suffix .png, .pdf or .svg" in line, \
        line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["steady.toml"], \
        f"nothing may be written: {sorted(p.name for p in tmp_path.iterdir())}"


@pytest.mark.parametrize("name", ["figure.txt", "figure"])
def test_runin_refuses_a_plot_suffix_before_the_run(tmp_path, runin_scene, capsys, name):
    out = tmp_path / "run.h5"
    status, stdout, err = run_cli(transient_cli, [runin_scene, "-o", out, "--plot",
                                                  tmp_path / name], capsys)
    line = one_error_line(err)
    assert status == 2, f"exit {status}: {err}"
    assert line.startswith("error: --plot ") and "expected the suffix .png, .pdf or .svg" in line, \
        line
    assert stdout == "", f"no run may start: {stdout!r}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runin.toml"], \
        f"nothing may be written: {sorted(p.name for p in tmp_path.iterdir())}"


@pytest.mark.parametrize("name, start", [("r.pdf", b"%PDF-"), ("r.SVG", b"<?xml")])
def test_a_vector_figure_for_a_paper(tmp_path, steady_scene, runin_scene, capsys, name, start):
    """``--plot`` of either command writes PDF or SVG by the suffix, a vector figure."""
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", tmp_path / "r.h5", "--plot",
                                          tmp_path / name, "--no-slope-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert (tmp_path / name).read_bytes().startswith(start), f"{name} is not {start!r}"
    figure = tmp_path / f"run{pathlib.Path(name).suffix}"
    status, _, err = run_cli(transient_cli, [runin_scene, "-o", tmp_path / "run.h5", "--plot",
                                             figure, "--no-grid-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert figure.read_bytes().startswith(start), f"{figure.name} is not {start!r}"


def test_an_upper_case_png_suffix_is_a_png(tmp_path, steady_scene, capsys):
    status, _, err = run_cli(steady_cli, [steady_scene, "-o", tmp_path / "r.h5", "--plot",
                                          tmp_path / "r.PNG", "--no-slope-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert (tmp_path / "r.PNG").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "a PNG image"


# -- --resume on a finished run without its grid error ---------------------------------------
def spatial_error_of(path):
    with h5py.File(path) as f:
        return f["history/rms_slope_spatial_error"][()], f["history/distance"][()]


def test_resume_computes_the_grid_error_a_finished_run_lacks(tmp_path, scene_file, capsys):
    scene = scene_file("runin", filename="s.toml", n=48, transient={"tol": 1e-3})
    out = tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--no-grid-error"], capsys)
    assert status == 0, f"first run: exit {status}: {err}"
    before, _, _ = read_run(out)
    with h5py.File(out) as f:  # absent: not computed
        assert "rms_slope_spatial_error" not in f["history"], "a run with --no-grid-error"
    # Asked again to skip it: the finished run is left as it is.
    files = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--resume", "--no-grid-error"],
                             capsys)
    assert status == 0 and "nothing to continue" in err, f"exit {status}: {err}"
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == files, "files changed"

    status, stdout, err = run_cli(transient_cli, [scene, "-o", out, "--resume"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert "nothing to continue" not in err, f"the grid error is asked for: {err!r}"
    assert "companion runs on n = 36, 24" in stdout, stdout
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
    status, _, err = run_cli(transient_cli, [scene, "-o", out, "--resume"], capsys)
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


# -- number flags: a negative number, in any form, is a value --------------------------------
#: Each command's module and the arguments it requires besides the flag under test.
COMMAND_ARGS = {
    "steady.cli.solve": ["s.toml", "-o", "o.h5"],
    "transient.cli.runin": ["s.toml", "-o", "o.h5"],
    "steady.cli.fit": ["s.toml", "m.npy", "-o", "f.h5"],
    "steady.cli.design": ["--pbar-over-estar", "0.1", "--wear-ratio", "0.1", "--fill-factor",
                          "0.2"],
}


def _number_flags():
    """``(module, flag)`` for every flag of every command that converts its value."""
    for name in COMMAND_ARGS:
        for action in importlib.import_module(name).build_parser()._actions:
            if action.option_strings and action.nargs != 0 and action.type not in (
                    None, pathlib.Path):
                yield name, action.option_strings[-1]


@pytest.mark.parametrize("module, flag", list(_number_flags()))
@pytest.mark.parametrize("value", ["-1e-4", "-.5E+3", "-inf"])
def test_a_negative_number_is_the_value_of_its_flag(module, flag, value, capsys):
    """``-1e-4`` or ``-inf``, which argparse would take for options, are values of number flags."""
    args = list(COMMAND_ARGS[module])
    if flag in args:  # a required flag: replaced (and its exclusive partner dropped)
        del args[args.index(flag):args.index(flag) + 2]
    elif flag == "--target-slope":
        del args[args.index("--fill-factor"):args.index("--fill-factor") + 2]
    parser = importlib.import_module(module).build_parser()
    try:
        parsed = parser.parse_args([*args, flag, value])
    except SystemExit as done:
        line = one_error_line(capsys.readouterr().err)
        assert done.code == 2, f"{module} {flag} {value}: exit {done.code}"
        assert line.startswith(f"error: argument {flag}: ") and repr(value) in line, \
            f"{module} {flag} {value}: {line!r}, not a refusal of the value"
    else:
        got = getattr(parsed, flag.lstrip("-").replace("-", "_"))
        got = got[0] if isinstance(got, list) else got
        assert got == float(value), f"{module} {flag} {value}: parsed as {got!r}"


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


def test_an_initial_face_of_one_grid_runs_without_the_grid_error(tmp_path, scene_file,
                                                                 capsys):
    """A recession file fits the run's grid only: no companions, a note naming the scene."""
    np.save(tmp_path / "h32.npy", np.zeros((32, 32)))
    scene = scene_file("runin", filename="b.toml", initial_face={"kind": "file",
                                                                  "path": "h32.npy"})
    out = tmp_path / "b.h5"
    status, stdout, err = run_cli(transient_cli, [scene, "-o", out], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert err.startswith(f"note: {scene}: no grid error (no companion runs): [initial_face]"), \
        err
    assert "(+- without the grid's error: no companion runs)" in stdout, stdout
    with h5py.File(out) as f:  # absent: not computed
        assert "rms_slope_spatial_error" not in f["history"], "no companion, no grid error"


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
    status, _, err = run_cli(transient_cli, [scene, "-o", out], capsys)
    line = one_error_line(err)
    assert status == 1, f"exit {status}: {err}"
    assert line.startswith(f"error: {scene}: the companion runs on n = 36, 24 failed: "), line
    assert "grid error: --resume computes it" in line, line
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


# -- --n: the grid from the command line -------------------------------------------------------
def test_the_grid_flag_sets_the_grid_and_the_file_records_it(tmp_path, steady_scene, runin_scene,
                                                             capsys):
    status, stdout, err = run_cli(steady_cli, [steady_scene, "-o", tmp_path / "r.h5", "--n",
                                               "40", "--no-slope-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    assert "n = 40 (40 x 40 pixels)" in stdout, stdout
    with h5py.File(tmp_path / "r.h5") as f:
        assert int(f["n"][()]) == 40 and f["face"].size == 40 * 40, dict(f.attrs)
    status, stdout, err = run_cli(transient_cli, [runin_scene, "-o", tmp_path / "run.h5",
                                                  "--n", "40", "--no-grid-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    run = read_run(tmp_path / "run.h5")[0]
    assert run.shape == (40, 40), run.shape
    # Resumed on the scene's own grid: another grid, refused naming n.
    status, _, err = run_cli(transient_cli, [runin_scene, "-o", tmp_path / "run.h5",
                                             "--resume"], capsys)
    assert status == 2 and " n " in one_error_line(err), f"exit {status}: {err}"


@pytest.mark.parametrize("value, fragment", [
    ("1", "n must be an integer >= 2, got 1"), ("4.5", "expected an integer >= 2, got '4.5'"),
    ("x", "expected an integer >= 2, got 'x'")])
def test_a_bad_grid_flag_is_refused_before_any_work(tmp_path, runin_scene, capsys, value,
                                                    fragment):
    status, stdout, err = run_cli(transient_cli, [runin_scene, "-o", tmp_path / "run.h5", "--n",
                                                  value], capsys)
    line = one_error_line(err)
    assert status == 2 and line.startswith("error: argument --n: "), f"exit {status}: {err}"
    assert fragment in line, line
    assert not (tmp_path / "run.h5").exists(), "nothing written"
