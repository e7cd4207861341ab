"""Each input is checked once, where it enters: counted over whole commands.

A scene's keys check their own values (the schema); the scales that follow from them are checked
once each as the scene is read, the phase map's once as it enters a problem (``FacePhases``), the
run-in's distances once per force of the load programme as the run's problem is built.  The
counts below come from the functions that do the checking, wrapped for the duration of a command.
"""

import collections

import numpy as np
import pytest
from conftest import run_cli, scene_text

import steady.cli.solve as steady_cli
import steady.labels
import steady.problem
import steady.rms_slope
import transient.__main__ as transient_cli
import transient.problem

#: The run-in scene of the gallery under a load programme: 10 N, then 20 N and 5 N.
PROGRAMME = "programme = [[1000.0, 20.0], [2000.0, 5.0]]\n"


@pytest.fixture()
def counted(monkeypatch):
    """Every scale checked (by what it is and its value) and every phase map validated."""
    scales, maps = collections.Counter(), collections.Counter()
    real_scale, real_labels = steady.problem.check_scale, steady.labels.validate_labels

    def check_scale(value, what, unit, inputs, names):
        # A scale of a law linear in p has the same value under every force: the inputs, as
        # the message names them, tell the checks apart.
        given = tuple(names[key] for key in inputs)
        scales[(what or inputs[0], unit, float(value), given)] += 1
        return real_scale(value, what, unit, inputs, names)

    def validate_labels(labels, n_phases, **kw):
        maps[(np.shape(labels), np.asarray(labels).tobytes())] += 1
        return real_labels(labels, n_phases, **kw)

    for module in (steady.problem, steady.scene, transient.problem):
        monkeypatch.setattr(module, "check_scale", check_scale, raising=False)
    for module in (steady.problem, steady.rms_slope, steady.wear):
        monkeypatch.setattr(module, "validate_labels", validate_labels, raising=False)
    return scales, maps


def _scene(tmp_path, programme=True):
    text = scene_text("runin", transient={"tol": 1e-3})
    if programme:
        text = text.replace("normal_force = 10.0\n", "normal_force = 10.0\n" + PROGRAMME)
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


def _repeated(counter):
    return {key: count for key, count in counter.items() if count > 1}


@pytest.mark.parametrize("programme", [False, True])
def test_a_run_in_checks_each_scale_and_map_once(tmp_path, capsys, counted, programme):
    scales, maps = counted
    # The companion runs on coarser grids are problems of their own (their pixel's scales
    # differ): left out here.
    status, _, err = run_cli(transient_cli, [_scene(tmp_path, programme), "-o",
                                             tmp_path / "run.h5", "--no-grid-error"], capsys)
    assert status == 0, err
    assert not _repeated(scales), f"scales checked more than once: {_repeated(scales)}"
    checked = {what for what, *_ in scales}
    for what in ("the mean pressure pbar = F_N / A", "the pixel h = 2 L / n",
                 "the steady pressure of phase 1 (eq. 7)",
                 "the fastest relaxation distance h / (g' E*) (g' = dg/dp at pbar = k m "
                 "pbar^(m-1))"):
        assert what in checked, f"{what!r} was not checked at all: {sorted(checked)}"
    # One mean pressure per force the run meets: 10 N, and 20 N and 5 N under the programme.
    means = sorted(v for what, _, v, _ in scales if what == "the mean pressure pbar = F_N / A")
    forces = (5.0, 10.0, 20.0) if programme else (10.0,)
    assert np.allclose(means, [f / (np.pi * 0.004 ** 2) for f in forces], rtol=1e-12), means
    finest = {key: count for key, count in maps.items() if key[0] == (32, 32)}
    assert list(finest.values()) == [1], f"the run's phase map validated {finest} times"


def test_the_steady_command_checks_each_scale_once(tmp_path, capsys, counted):
    scales, maps = counted
    status, _, err = run_cli(steady_cli, [_scene(tmp_path), "-o", tmp_path / "s.h5"], capsys)
    assert status == 0, err
    assert not _repeated(scales), f"scales checked more than once: {_repeated(scales)}"
    finest = [count for key, count in maps.items() if key[0] == (32, 32)]
    assert finest == [1], f"the phase map validated {finest} times"


def test_a_problem_built_in_python_checks_its_inputs(counted):
    scales, _ = counted
    from steady import Circle, FacePhases, Problem, Voronoi

    grid = Circle(4e-3).grid(32)
    labels = Voronoi(64, (0.7, 0.3), seed=2029).labels(grid)
    Problem(FacePhases(grid, labels, 2), [1e-13, 1e-12], 10.0, 1.3e6)
    checked = {what for what, *_ in scales}
    assert {"normal_force", "E_star", "radius"} <= checked, sorted(checked)
    assert not _repeated(scales), _repeated(scales)
    with pytest.raises(ValueError, match=r"normal_force must be a number > 0 \(N\), got -1"):
        Problem(FacePhases(grid, labels, 2), [1e-13, 1e-12], -1, 1.3e6)
