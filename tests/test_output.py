"""HDF5 files: the atomic writer and the steady result files.

Result files: round trip, units, refusal to overwrite, validation on read.
"""

import os
import stat

import h5py
import numpy as np
import pytest
from conftest import scene_text

from steady.output import FORMAT, FORMAT_VERSION, read_result, write_result
from steady.safe_files import atomic_h5
from steady.scene import parse_scene
from steady.solution import solve_scene

#: The gallery's steady scene on an odd grid (n = 33).
SCENE = scene_text("steady_odd")


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    scene = parse_scene(SCENE, tmp_path_factory.mktemp("scene"))
    return scene, solve_scene(scene)


def test_round_trip(tmp_path, solved):
    scene, res = solved
    path = write_result(tmp_path / "sub" / "r.h5", res, scene)
    stored = read_result(path)
    assert stored.scene_text == SCENE, "scene text must be stored verbatim"
    for name in ("labels", "pressure", "face", "slope", "phase_pressures", "fill_factors"):
        assert np.array_equal(getattr(stored.result, name), getattr(res, name),
                              equal_nan=True), f"{name} changed in the round trip"
    assert stored.result.wear == res.wear, f"wear law {stored.result.wear} != {res.wear}"
    assert stored.result.rms_slope == res.rms_slope, "rms slope changed"
    assert stored.result.reference_slope == res.reference_slope, "grad_f0 changed"
    with h5py.File(path) as f:
        assert f.attrs["format"] == FORMAT and f.attrs["format_version"] == FORMAT_VERSION, \
            "format attributes"
        units = {name: f[name].attrs["units"] for name in ("phase", "pressure", "face", "slope")}
        assert units == {"phase": "1", "pressure": "Pa", "face": "m", "slope": "1"}, f"{units}"
        assert f["rms_slope_ref"].shape == () and f["rms_slope_ref"].attrs["units"] == "1", \
            "a scalar result: a 0-d variable with its unit"
        assert not [name for name in f.attrs if name.endswith("_units")], dict(f.attrs)
        assert f["phase"].dtype.kind == "i", f"phase dtype {f['phase'].dtype}"
        assert f["face"].shape == res.face.shape[::-1], "fields stored (y, x)"
        assert np.array_equal(f["face"][()], res.face.T, equal_nan=True), "the face transposed"


def test_no_overwrite_without_force(tmp_path, solved):
    scene, res = solved
    path = tmp_path / "r.h5"
    path.write_bytes(b"keep me")
    with pytest.raises(ValueError, match="exists"):
        write_result(path, res, scene)
    assert path.read_bytes() == b"keep me", "existing file must be untouched"
    write_result(path, res, scene, force=True)
    assert read_result(path).result.n == 33, "force overwrites"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5"], "no temporary file left"


def test_read_rejects_bad_files(tmp_path, solved):
    scene, res = solved
    with pytest.raises(FileNotFoundError, match="missing.h5' does not exist"):
        read_result(tmp_path / "missing.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with pytest.raises(ValueError, match="text.h5' is not an HDF5 file"):
        read_result(tmp_path / "text.h5")
    good = write_result(tmp_path / "good.h5", res, scene)
    data = good.read_bytes()
    (tmp_path / "cut.h5").write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match="cut.h5"):
        read_result(tmp_path / "cut.h5")
    with h5py.File(tmp_path / "foreign.h5", "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(ValueError, match="foreign.h5' is not a runin.steady file"):
        read_result(tmp_path / "foreign.h5")
    with h5py.File(good, "a") as f:
        f.attrs["format_version"] = 99
    with pytest.raises(ValueError, match="good.h5' has format_version 99"):
        read_result(good)
    other = write_result(tmp_path / "partial.h5", res, scene)
    with h5py.File(other, "a") as f:
        del f["slope"]
    with pytest.raises(ValueError, match="partial.h5' lacks 'slope'"):
        read_result(other)


def test_atomic_h5_writes_format_attributes_and_parents(tmp_path):
    path = tmp_path / "a" / "b" / "x.h5"
    with atomic_h5(path, format="runin.test", version=3) as f:
        f["values"] = np.arange(4.0)
        assert not path.exists(), "the target appears only when the block completes"
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == "runin.test", f"format {f.attrs['format']!r}"
        assert f.attrs["format_version"] == 3, f"format_version {f.attrs['format_version']!r}"
        assert "version" not in f.attrs, "one name for the version attribute"
        assert np.array_equal(f["values"][()], np.arange(4.0)), "dataset written"
    assert os.listdir(path.parent) == ["x.h5"], "no temporary file left"


@pytest.mark.parametrize("interrupt", [RuntimeError("disk on fire"), KeyboardInterrupt()])
def test_atomic_h5_removes_the_temporary_file_on_error(tmp_path, interrupt):
    """Any exception, KeyboardInterrupt included: no temporary file, the old file untouched."""
    path = tmp_path / "x.h5"
    path.write_bytes(b"previous run")
    with pytest.raises(type(interrupt)):
        with atomic_h5(path, format="runin.test", version=1, force=True) as f:
            f["values"] = np.arange(3.0)
            raise interrupt
    assert path.read_bytes() == b"previous run", "existing file must be untouched"
    assert os.listdir(tmp_path) == ["x.h5"], f"left behind: {os.listdir(tmp_path)}"
    new = tmp_path / "new.h5"
    with pytest.raises(type(interrupt)):
        with atomic_h5(new, format="runin.test", version=1):
            raise interrupt
    assert sorted(os.listdir(tmp_path)) == ["x.h5"], f"left behind: {os.listdir(tmp_path)}"


def test_atomic_h5_backup_already_linked_to_the_file(tmp_path):
    """A backup that is already a hard link of the file: no temporary file left.

    A writer killed between keeping the backup and renaming its new file
    leaves them so; renaming a third link over the backup does nothing.
    """
    path, backup = tmp_path / "x.h5", tmp_path / "x.h5.prev"
    with atomic_h5(path, format="runin.test", version=1) as f:
        f["values"] = np.arange(2.0)
    os.link(path, backup)
    with atomic_h5(path, format="runin.test", version=2, force=True, backup=backup) as f:
        f["values"] = np.arange(3.0)
    assert sorted(os.listdir(tmp_path)) == ["x.h5", "x.h5.prev"], \
        f"left behind: {sorted(os.listdir(tmp_path))}"
    with h5py.File(path, "r") as new, h5py.File(backup, "r") as old:
        assert (new.attrs["format_version"], old.attrs["format_version"]) == (2, 1), \
            "the new file in place, the old one kept as the backup"


def test_atomic_h5_refuses_existing_files_and_directories(tmp_path):
    path = tmp_path / "x.h5"
    path.write_bytes(b"keep me")
    with pytest.raises(ValueError, match="x.h5' exists"):
        with atomic_h5(path, format="runin.test", version=1):
            pytest.fail("the block must not run for an existing file")
    assert path.read_bytes() == b"keep me", "existing file must be untouched"
    (tmp_path / "d.h5").mkdir()
    for force in (False, True):
        with pytest.raises(ValueError, match="d.h5' is a directory"):
            with atomic_h5(tmp_path / "d.h5", format="runin.test", version=1, force=force):
                pytest.fail("the block must not run for a directory")
    assert sorted(os.listdir(tmp_path)) == ["d.h5", "x.h5"], "nothing created"


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_atomic_h5_permissions_honour_the_umask(tmp_path, umask):
    """Like a file created with open(): 0o666 less the umask (not mkstemp's 0o600)."""
    previous = os.umask(umask)
    try:
        with atomic_h5(tmp_path / "x.h5", format="runin.test", version=1) as f:
            f["values"] = np.arange(2.0)
        with open(tmp_path / "plain", "w"):
            pass
    finally:
        os.umask(previous)
    mode = stat.S_IMODE((tmp_path / "x.h5").stat().st_mode)
    plain = stat.S_IMODE((tmp_path / "plain").stat().st_mode)
    assert mode == 0o666 & ~umask == plain, \
        f"umask {umask:o}: mode {mode:o}, a plain file gets {plain:o}"


def test_rms_height_round_trips_and_is_optional_on_read(tmp_path, solved):
    """The steady face's rms height (m) is stored with its unit; older files read as NaN."""
    scene, res = solved
    assert np.isfinite(res.rms_height) and res.rms_height > 0, f"rms height {res.rms_height}"
    path = write_result(tmp_path / "r.h5", res, scene)
    back = read_result(path).result
    assert back.rms_height == res.rms_height, "rms height round trip"
    with h5py.File(path, "r+") as f:
        assert f["rms_height"].attrs["units"] == "m", "unit of the rms height"
        del f["rms_height"]
    assert np.isnan(read_result(path).result.rms_height), "a file without it reads NaN"


def test_phase_names_come_from_the_scene_and_are_checked(tmp_path, solved):
    """``[phases] names`` reach the file's ``phase_name``; a file without it reads the defaults."""
    scene, res = solved
    named = parse_scene(SCENE.replace("[phases]\n", '[phases]\nnames = ["resin", "filler"]\n'),
                        tmp_path)
    path = write_result(tmp_path / "named.h5", res, named)
    assert read_result(path).phase_names == ("resin", "filler"), "names of the scene"
    with h5py.File(path, "r") as f:
        assert f["phase_name"].attrs["long_name"] == "name of the phase, phase 0 first"
        assert "units" not in f["phase_name"].attrs, "text has no unit"
    assert read_result(write_result(tmp_path / "plain.h5", res, scene)).phase_names == \
        ("phase 0", "phase 1"), "the default names"
    with pytest.raises(ValueError, match="1 phase name"):
        write_result(tmp_path / "bad.h5", res, scene, phase_names=["resin"])
    assert not (tmp_path / "bad.h5").exists(), "nothing written for bad names"
    with h5py.File(path, "r+") as f:
        del f["phase_name"]  # a file written before the names (its scales dangle: unread)
    assert read_result(path).phase_names == ("phase 0", "phase 1"), "older file: defaults"


def test_datasets_carry_cf_units_long_names_and_coordinates(tmp_path, solved):
    scene, res = solved
    path = write_result(tmp_path / "r.h5", res, scene)
    grid = res.outline.grid(res.n)
    with h5py.File(path, "r") as f:
        for name in ("phase", "pressure", "face", "slope"):
            ds = f[name]
            assert ds.attrs["long_name"], f"{name} has no long_name"
            assert [d.label or d[0].name for d in ds.dims] == ["/y", "/x"], \
                f"{name}: dimension scales {[d.keys() for d in ds.dims]}"
        assert np.array_equal(f["x"][()], grid.x) and np.array_equal(f["y"][()], grid.y), \
            "x, y: the pixel centres (m)"
        assert f["x"].attrs["units"] == "m" and f["y"].attrs["units"] == "m", "coordinates in m"
        assert f["outline/area"].attrs["units"] == "m2", "area in m2"
        assert f["wear_coefficients"].attrs["units"] == "Pa-1", "Archard's k in Pa-1"
        assert [d[0].name for d in f["wear_coefficients"].dims] == ["/phase_name"], \
            "one coefficient per phase, along phase_name"
        assert f.attrs["wear_law"] == "Archard's law dw/ds = k p, k = [1e-09, 3e-09] 1/Pa", \
            f"wear law {f.attrs['wear_law']!r}"
