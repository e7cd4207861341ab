"""Files of earlier layouts read, and their runs resume, with the values they were written with.

tests/data holds files of one scene (run_layout4.toml: an ellipse, so that nx != ny, two named
phases, a non-linear wear law, a load programme, a snapshot) written by the code of earlier
layouts: a run stopped after five steps (run layout 4), its steady result (result layout 2)
and the fit of a noisy copy of its steady face (fit layout 2).  Each reads back as the file
the present code writes of the same scene, value for value, and the run resumes bit for bit
to the uninterrupted run.
"""

import dataclasses
import pathlib
import shutil

import h5py
import numpy as np
from conftest import run_cli

import steady.cli.fit as fit_cli
import steady.cli.solve as steady_cli
from steady.fit_files import read_fit
from steady.output import read_result
from transient.cli import runin as transient_cli
from transient.output import read_run

DATA = pathlib.Path(__file__).parent / "data"
SCENE = DATA / "run_layout4.toml"


def _version(path):
    with h5py.File(path, "r") as f:
        return int(f.attrs["format_version"])


def _same(a, b, what):
    """Assert two stored values equal: arrays by dtype kind, shape and value (NaN equal)."""
    if isinstance(a, (np.ndarray, np.generic, float, int)) and not isinstance(a, bool):
        a, b = np.asarray(a), np.asarray(b)
        assert a.shape == b.shape, f"{what}: shape {a.shape} != {b.shape}"
        assert a.dtype.kind == b.dtype.kind, f"{what}: dtype {a.dtype} != {b.dtype}"
        same = (np.array_equal(a, b, equal_nan=True) if a.dtype.kind in "fc"
                else np.array_equal(a, b))
        assert same, f"{what}: {a!r} != {b!r}"
    else:
        assert a == b, f"{what}: {a!r} != {b!r}"


def test_a_layout_2_result_file_reads_as_the_present_layout(tmp_path, capsys):
    old_path = DATA / "result_layout2.h5"
    new_path = tmp_path / "result.h5"
    scene = tmp_path / SCENE.name
    shutil.copy(SCENE, scene)
    status, _, err = run_cli(steady_cli, [scene, "-o", new_path], capsys)
    assert status == 0, err
    assert _version(old_path) == 2, "the fixture is a layout-2 result file"
    old, new = read_result(old_path), read_result(new_path)
    for field in dataclasses.fields(old.result):
        _same(getattr(old.result, field.name), getattr(new.result, field.name),
              f"result.{field.name}")
    assert old.result.face.shape == (24, 15), f"indexed [x, y]: {old.result.face.shape}"
    assert old.phase_names == new.phase_names == ("matrix", "filler"), old.phase_names
    assert old.scene_text == new.scene_text == SCENE.read_text(), "the scene's text"


def test_a_layout_2_fit_file_reads_as_the_present_layout(tmp_path, capsys):
    old_path = DATA / "fit_layout2.h5"
    old = read_fit(old_path)
    assert old.version == 2, f"the fixture is a layout-2 fit file, not {old.version}"
    scene = tmp_path / SCENE.name
    shutil.copy(SCENE, scene)
    measured = tmp_path / "fit_layout2_measured.npy"
    shutil.copy(DATA / measured.name, measured)
    status, _, err = run_cli(fit_cli, [scene, measured, "--pixel-size",
                                       repr(float(old.attrs["pixel_size"][0])),
                                       "-o", tmp_path / "fit.h5"], capsys)
    assert status == 0, err
    new = read_fit(tmp_path / "fit.h5")
    assert set(old.attrs) == set(new.attrs), sorted(set(old.attrs) ^ set(new.attrs))
    for name in old.attrs:
        if name != "measured_source":  # the path given on the command line
            _same(old.attrs[name], new.attrs[name], f"attrs[{name!r}]")
    assert set(old.arrays) == set(new.arrays), sorted(set(old.arrays) ^ set(new.arrays))
    for name in old.arrays:
        _same(old.arrays[name], new.arrays[name], f"arrays[{name!r}]")
    assert old.arrays["measured"].shape == (24, 15), old.arrays["measured"].shape
    assert old.outline == new.outline, f"{old.outline} != {new.outline}"
    assert old.phase_names == new.phase_names == ("matrix", "filler"), old.phase_names
    assert old.scene_text == new.scene_text, "the scene's text"


def test_a_layout_4_run_file_reads_as_written_and_resumes_to_the_uninterrupted_run(
        tmp_path, capsys):
    scene = tmp_path / SCENE.name
    shutil.copy(SCENE, scene)
    old = tmp_path / "run.h5"
    shutil.copy(DATA / "run_layout4.h5", old)
    with h5py.File(old, "r") as f:
        assert f.attrs["format_version"] == 4, "a layout-4 file"
        stored = {name: f[name][()] for name in ("state/recession", "state/pressure_history",
                                                  "snapshots/recession", "pressure")}
        offset, steps = float(f.attrs["offset"]), int(f.attrs["steps"])
    back, attrs, arrays = read_run(old)
    assert back.steps == steps == 5 and back.offset == offset, (back.steps, back.offset)
    _same(back.recession, stored["state/recession"], "state/recession")
    _same(back.state.pressure_history, stored["state/pressure_history"], "pressure_history")
    _same(back.snapshot_recession, stored["snapshots/recession"], "snapshots/recession")
    _same(back.pressure, stored["pressure"], "pressure")
    assert back.pressure.shape == (24, 15), f"indexed [x, y]: {back.pressure.shape}"
    assert back.load_programme is not None, "the load programme is read"

    assert transient_cli.main([str(scene), "-o", str(old), "--resume"]) == 0, \
        capsys.readouterr().err
    straight = tmp_path / "straight.h5"
    assert transient_cli.main([str(scene), "-o", str(straight)]) == 0, capsys.readouterr().err
    resumed, _, _ = read_run(old)
    uninterrupted, _, _ = read_run(straight)
    assert resumed.status == uninterrupted.status == "steady", resumed.message
    for name in ("steps", "distance", "offset", "approach", "solves", "iterations"):
        _same(getattr(resumed, name), getattr(uninterrupted, name), name)
    for name in ("recession", "pressure", "snapshot_distance", "snapshot_recession",
                 "snapshot_pressure"):
        _same(getattr(resumed, name), getattr(uninterrupted, name), name)
    assert resumed.history.keys() == uninterrupted.history.keys(), "history datasets"
    for name, values in uninterrupted.history.items():
        if name in ("face_deviation", "face_deviation_step_error"):
            # Layout 4 held them relative to the steady relief: converted on resuming, to
            # rounding (one product).
            assert np.allclose(resumed.history[name], values, rtol=4e-16, atol=0), name
            continue
        _same(resumed.history[name], values, f"history/{name}")
