"""The README's quick start, first steps and Python examples run as written, in an empty directory.

The reference material lives in docs/ (scene keys, commands, the library, files); the README
keeps what a new user runs first, and each of its commands and examples is run here.
"""

import importlib
import pathlib
import re
import shlex

import h5py
import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def example(heading):
    """The first Python block of the README after ``heading``."""
    assert heading in README, f"README lacks the heading {heading!r}"
    match = re.search(r"```python\n(.*?)```", README.split(heading, 1)[1], re.S)
    assert match is not None, f"no Python example after {heading!r}"
    return match.group(1)


def run(code, where, monkeypatch):
    """Run an example in ``where`` (an empty directory); return its namespace."""
    monkeypatch.chdir(where)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    return namespace


def test_steady_library_example(tmp_path, monkeypatch):
    ns = run(example("### A steady face"), tmp_path, monkeypatch)
    assert ns["result"].n == 128 and ns["result"].n_phases == 2, f"result {ns['result']}"


def test_run_in_library_example(tmp_path, monkeypatch):
    ns = run(example("### A run-in"), tmp_path, monkeypatch)
    result, stored = ns["result"], ns["stored"]
    assert result.success, f"run ended {result.status}: {result.message}"
    assert ns["comparison"].face_error < 1e-6, f"face error {ns['comparison'].face_error}"
    assert stored.steps == result.steps and ns["attrs"]["format_version"] == 5, \
        f"run file: {stored.steps} steps, attributes {ns['attrs']}"
    assert (tmp_path / "out" / "run.png").stat().st_size > 10_000, "figure not drawn"


def quick_start():
    """The two lines of the quick start, each split into its commands."""
    block = re.search(r"## Quick start\n\n```bash\n(.*?)```", README, re.S)
    assert block is not None, "no bash block in the quick start"
    lines = block.group(1).splitlines()
    assert len(lines) == 2, f"the quick start has {len(lines)} lines: {lines}"
    return [[shlex.split(c) for c in line.split(" && ")] for line in lines]


def run_commands(commands, capsys):
    """Run installed commands (``[project.scripts]``) in-process, in the current directory."""
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    for name, *argv in commands:
        assert name in scripts, f"{name!r} is not a command of this package"
        module, function = scripts[name].split(":")
        status = getattr(importlib.import_module(module), function)(argv)
        assert status == 0, f"{name} {argv}: exit {status}, {capsys.readouterr().err}"


def test_quick_start_tests_with_the_test_extra_and_without_slow_tests():
    """The second line installs an extra that exists and runs the default (fast) suite."""
    install, test = quick_start()[1]
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    extra = re.fullmatch(r"\.\[(\w+)\]", install[-1])
    assert install[:-1] == ["pip", "install", "-e"] and extra is not None, install
    assert extra.group(1) in pyproject["project"]["optional-dependencies"], install
    assert test == ["python", "-m", "pytest"], test
    addopts = pyproject["tool"]["pytest"]["ini_options"]["addopts"]
    assert "-m 'not slow'" in addopts and "python -m pytest -m slow" in README, \
        f"the README says slow tests are left out by default; addopts = {addopts!r}"


@pytest.mark.slow
def test_first_steps_commands_run_in_an_empty_directory(tmp_path, monkeypatch, capsys):
    """The commands of "A steady face", as written."""
    block = re.search(r"### A steady face\n.*?```bash\n(.*?)```", README, re.S)
    assert block is not None, "no commands under 'A steady face'"
    monkeypatch.chdir(tmp_path)
    run_commands([shlex.split(line) for line in block.group(1).splitlines()], capsys)
    with h5py.File(tmp_path / "steady.h5", "r") as f:
        assert f.attrs["format"] == "runin.steady", f"result file {dict(f.attrs)}"
    assert (tmp_path / "steady.png").stat().st_size > 10_000, "figure not drawn"


@pytest.mark.slow
def test_quick_start_runs_twice_in_an_empty_directory(tmp_path, monkeypatch, capsys):
    """The installed commands of the quick start, run as written, and again over their files."""
    install, *commands = quick_start()[0]
    assert install == ["pip", "install", "."], f"the quick start installs with {install}"
    assert [c[0] for c in commands] == ["runin-examples", "runin-transient"], commands
    monkeypatch.chdir(tmp_path)
    for _ in ("first", "second"):
        run_commands(commands, capsys)
    with h5py.File(tmp_path / "run.h5", "r") as f:
        assert f.attrs["format"] == "runin.transient", f"run file {dict(f.attrs)}"
    assert (tmp_path / "run.png").stat().st_size > 10_000, "figure not drawn"
    assert sorted(p.name for p in (tmp_path / "example").iterdir()) == \
        ["voronoi_transient.toml"], "the example copy"
    # What a new user reads next: the run-in distance in metres from the summary, the run file
    # as labelled arrays, the history in metres in one call.
    summary = capsys.readouterr().out
    line = re.search(r"run-in distance within 1 %: s = (\S+) \+- (\S+) m = (\S+) ", summary)
    assert line is not None, f"no run-in distance in metres in the summary:\n{summary}"
    distance, error, in_s_star = (float(v) for v in line.groups())
    with h5py.File(tmp_path / "run.h5", "r") as f:
        scale = f["distance_scale"][()]
    assert abs(distance / scale - in_s_star) <= 0.0011 * in_s_star, (distance, scale, in_s_star)
    assert 0 < error < distance
    xarray = pytest.importorskip("xarray")
    with xarray.open_dataset(tmp_path / "run.h5", engine="h5netcdf") as ds:
        assert ds["x"].attrs["units"] == "m" and ds["worn_depth"].dims == ("y", "x"), ds
    with xarray.open_dataset(tmp_path / "run.h5", engine="h5netcdf", group="history") as ds:
        assert ds["distance"].attrs["units"] == "m"
        assert float(ds["distance"][-1]) > distance, "the history ends before the run-in"
    from transient.plotting import plot_history
    fig = plot_history(tmp_path / "run.h5", units="m")
    assert fig.axes[0].get_xlabel() == "sliding distance (m)"
