"""HDF5 result files: round trip, units, refusal to overwrite, validation on read."""

import h5py
import numpy as np
import pytest

from steady.output import FORMAT, FORMAT_VERSION, read_result, write_result
from steady.scene import parse_scene
from steady.solution import solve_scene

SCENE = """\
[punch]
radius = 0.004
[load]
normal_force = 10.0
[counterbody]
E_star = 1.3e6
[grid]
n = 33
[wear]
coefficients = [1.0e-9, 3.0e-9]
[phases]
map = { kind = "voronoi", n_seeds = 64, fill_factors = [0.5, 0.5], seed = 5501 }
"""


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    scene = parse_scene(SCENE, tmp_path_factory.mktemp("scene"))
    return scene, solve_scene(scene)


def test_round_trip(tmp_path, solved):
    scene, res = solved
    path = write_result(tmp_path / "sub" / "r.h5", res, scene)
    stored = read_result(path)
    assert stored.scene_text == SCENE, "scene text must be stored verbatim"
    for name in ("labels", "pressure", "face", "slope", "phase_pressures", "fill_factors",
                 "wear_coefficients"):
        assert np.array_equal(getattr(stored.result, name), getattr(res, name),
                              equal_nan=True), f"{name} changed in the round trip"
    assert stored.result.rms_slope == res.rms_slope, "rms slope changed"
    assert stored.result.reference_slope == res.reference_slope, "grad_f0 changed"
    with h5py.File(path) as f:
        assert f.attrs["format"] == FORMAT and f.attrs["format_version"] == FORMAT_VERSION, \
            "format attributes"
        units = {name: f[name].attrs["units"] for name in ("phase", "pressure", "face", "slope")}
        assert units == {"phase": "1", "pressure": "Pa", "face": "m", "slope": "1"}, f"{units}"
        assert f.attrs["rms_slope_ref_units"] == "1", "attribute units"
        assert f["phase"].dtype.kind == "i", f"phase dtype {f['phase'].dtype}"


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
    with pytest.raises(ValueError, match="missing.h5' does not exist"):
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
