"""Ctrl-C (SIGINT) at any moment of a command, start-up included: one line, exit 130.

Each command runs as ``python -m ...`` and as its console script (the wrapper pip writes for
the ``[project.scripts]`` entry of ``pyproject.toml``).  The moments are counted from the start
of the heavy imports (the first import of numpy, which a ``sitecustomize`` module on the
child's path reports through a pipe); the imports (numpy, scipy, h5py, the library) take up to
a second, then the work follows.  What runs before, the interpreter's own start-up (``site``
and its ``.pth`` files) and a few milliseconds of light imports, is Python's.
"""

import os
import pathlib
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from conftest import scene_text

from steady.scene import load_scene
from steady.solution import solve_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: The modules of the commands, as ``python -m`` runs them.
MODULES = {"runin-steady": "steady", "runin-transient": "transient",
           "runin-fit": "steady.cli.fit", "runin-design": "steady.cli.design"}

#: Commands that load no heavy module at all (nothing to interrupt in the imports).
LIGHT_COMMANDS = {"runin-examples": "steady.cli.examples"}

#: Seconds after the heavy imports start: in them (up to ~0.8 s), then in the work.
MOMENTS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.8, 1.2)

#: Reports, through the pipe named by the environment, when numpy starts to be imported.
SITECUSTOMIZE = """\
import os
import sys

_fd = os.environ.pop("RUNIN_TEST_READY_FD", None)


class _HeavyImports:
    @staticmethod
    def find_spec(name, path=None, target=None):
        global _fd
        if name == "numpy" and _fd is not None:
            os.write(int(_fd), b"r")
            os.close(int(_fd))
            _fd = None
        return None


if _fd is not None:
    sys.meta_path.insert(0, _HeavyImports)
"""

#: What pip writes for a console script ``name = "module:function"``.
CONSOLE_SCRIPT = """\
import re
import sys
from {module} import {function}
if __name__ == '__main__':
    sys.argv[0] = re.sub(r'(-script\\.pyw|\\.exe)?$', '', sys.argv[0])
    sys.exit({function}())
"""


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A directory with the inputs of the four commands, and their arguments."""
    where = tmp_path_factory.mktemp("interrupts")
    (where / "site").mkdir()
    (where / "site" / "sitecustomize.py").write_text(SITECUSTOMIZE)
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    for name, target in scripts.items():
        module, function = target.split(":")
        (where / name).write_text(CONSOLE_SCRIPT.format(module=module, function=function))
    # Long enough that the later moments land in the work, not after it.
    (where / "steady.toml").write_text(scene_text("steady", n=384))
    (where / "runin.toml").write_text(scene_text("runin", n=160))
    (where / "fit.toml").write_text(scene_text("steady", n=96))
    fitted = solve_scene(load_scene(where / "fit.toml"), slope_error=False)
    np.save(where / "face.npy", fitted.face)
    args = {
        "runin-steady": ["steady.toml", "-o", "out/steady.h5"],
        "runin-transient": ["runin.toml", "-o", "out/run.h5"],
        "runin-fit": ["fit.toml", "face.npy", "--pixel-size", repr(fitted.pixel_size),
                      "--n", "384", "-o", "out/fit.h5"],
        "runin-design": ["--pbar-over-estar", "0.08", "--wear-ratio", "1e-2",
                         "--fill-factor", "0.2"],
    }
    return where, args


def interrupt(where, argv, delay):
    """Run ``argv`` in ``where``, SIGINT ``delay`` s after numpy starts loading; the process."""
    read, write = os.pipe()
    env = dict(os.environ, RUNIN_TEST_READY_FD=str(write), MPLBACKEND="Agg",
               PYTHONPATH=os.pathsep.join([str(where / "site"), str(ROOT)]))
    proc = subprocess.Popen(argv, cwd=where, env=env, pass_fds=(write,), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    os.close(write)
    try:
        ready, _, _ = select.select([read], [], [], 60)
        assert ready and os.read(read, 1) == b"r", f"{argv} never imported numpy"
    finally:
        os.close(read)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    proc.stdout_text, proc.stderr_text = proc.communicate(timeout=120)
    return proc


def assert_interrupted(proc, what):
    """Exit 130 and one ``error: interrupted`` line; or, if it ended first, exit 0."""
    err = proc.stderr_text
    assert "Traceback" not in err, f"{what}: traceback on stderr: {err!r}"
    if proc.returncode == 0:  # finished before the signal came
        return
    assert proc.returncode == 130, f"{what}: exit {proc.returncode}, stderr {err!r}"
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and errors[0].startswith("error: interrupted"), \
        f"{what}: expected one 'error: interrupted' line, got {err!r}"
    assert err.splitlines()[-1] == errors[0], f"{what}: the error line is not the last: {err!r}"


def command_line(work, command, form, tag="run"):
    """``python -m`` or the console script; outputs named by ``tag`` (``out/NAME-TAG.h5``)."""
    where, args = work
    argv = [arg.replace(".h5", f"-{tag}.h5") for arg in args[command]]
    if form == "module":
        return [sys.executable, "-m", MODULES[command], *argv]
    return [sys.executable, str(where / command), *argv]


@pytest.mark.parametrize("command", sorted(MODULES))
@pytest.mark.parametrize("form", ["module", "console script"])
def test_ctrl_c_during_the_imports_is_one_line(work, command, form):
    """0.1 s after numpy starts loading every command is still importing."""
    proc = interrupt(work[0], command_line(work, command, form, "imports"), 0.1)
    assert_interrupted(proc, f"{command} ({form}) at 0.1 s")
    assert proc.returncode == 130, f"{command} ({form}) finished before 0.1 s?"
    assert "nothing was written" in proc.stderr_text, \
        f"{command} ({form}): interrupted in the imports: {proc.stderr_text!r}"


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(MODULES))
@pytest.mark.parametrize("form", ["module", "console script"])
def test_ctrl_c_at_any_moment_is_one_line(work, command, form):
    for delay in MOMENTS:
        proc = interrupt(work[0], command_line(work, command, form, f"{form[0]}{delay}"),
                         delay)
        assert_interrupted(proc, f"{command} ({form}) at {delay} s")
    leftovers = [p.name for p in (work[0] / "out").glob("*") if ".tmp" in p.name] \
        if (work[0] / "out").exists() else []
    assert not leftovers, f"{command}: temporary files left: {leftovers}"


def test_entry_points_import_nothing_heavy():
    """The console scripts' modules and ``python -m``'s packages load no heavy module."""
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    modules = sorted({target.split(":")[0] for target in scripts.values()})
    code = ("import sys\n"
            f"for name in {modules!r}: __import__(name)\n"
            "print(' '.join(sorted(sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    loaded = set(proc.stdout.split())
    light = {"steady", "steady.lazy", "steady.cli", "steady.cli.entry", "transient",
             "transient.__main__"}
    heavy = sorted(name for name in loaded
                   if name.split(".")[0] in ("numpy", "scipy", "h5py", "matplotlib")
                   or (name.split(".")[0] in ("steady", "transient") and name not in light))
    assert not heavy, f"the entry points {modules} import {heavy}"


def test_console_scripts_name_light_entry_points():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert sorted(scripts) == sorted({**MODULES, **LIGHT_COMMANDS}), \
        f"commands {sorted(scripts)}"
    for name, target in scripts.items():
        assert target.split(":")[0] in ("steady.cli.entry", "transient.__main__"), \
            f"{name} enters through {target}, which imports the command's heavy modules"


def test_exit_status_constant_matches_common():
    from steady.cli import common, entry

    assert entry._EXIT_INTERRUPTED == common.EXIT_INTERRUPTED == 128 + signal.SIGINT, \
        "the entry's interrupted status is the commands' 130"
