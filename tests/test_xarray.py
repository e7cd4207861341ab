"""The files in other tools: each kind opens in xarray (h5netcdf) as labelled arrays in SI units.

Result files (``runin-steady``), run files (``runin-transient``) and fit files (``runin-fit``):
the CF attribute ``Conventions``; CF ``units`` that udunits parses and a ``long_name`` on every
variable, the scalar results 0-d variables (no ``*_units`` attribute), the values per phase
along ``phase_name``; coordinates ``x`` and ``y`` in m as dimension scales, the fields stored
(y, x) so that xarray draws x across; the run history along its distance; no dimension of
length 0; every group a node of ``xarray.open_datatree``; and the problem's inputs in a run
file written from Python.
"""

import pathlib
import re
import shutil

import h5py
import numpy as np
import pytest
import xarray as xr
from conftest import E_STAR, FORCE, GEOMETRIES, K1, RADIUS, run_cli, scene_text

import steady.cli.fit as fit_cli
import steady.cli.solve as steady_cli
import transient.cli.runin as transient_cli
from steady import MeasuredFace, fit_face, solve, write_fit
from steady.outline import Circle
from steady.output import read_result, write_result
from steady.problem import FacePhases, Problem
from steady.safe_files import DIMENSION_SCALE_ATTRIBUTES, attributes_digest, dataset_digest
from steady.wear import PowerLaw
from transient import output as run_output
from transient.output import read_run, write_run
from transient.problem import WearProblem
from transient.result import HISTORY_UNITS
from transient.runin import RunOptions, run_in

NAMES = ("epoxy", "bronze filler")
#: A run file of layout 4 (tests/test_file_layouts.py) and its scene: an ellipse, nx != ny.
DATA = pathlib.Path(__file__).parent / "data"
LAYOUT_4 = DATA / "run_layout4.h5"
N = 24

#: A udunits unit as this project writes it: "1", or SI symbols with integer powers
#: ("Pa-1", "m2"), separated by spaces.
UDUNITS = re.compile(r"^(1|(m|Pa|N|s)(-?[0-9]+)?( (m|Pa|N|s)(-?[0-9]+)?)*)$")


def named_problem(n=N, exponent=1.0):
    """Two named phases (the gallery's Voronoi map) on the disk of :data:`RADIUS`."""
    grid = Circle(RADIUS).grid(n)
    labels = GEOMETRIES["voronoi"].labels(grid)
    return Problem(FacePhases(grid, labels, 2, NAMES),
                   PowerLaw([K1, 10 * K1], exponent=exponent), FORCE, E_STAR)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A result file, a run file and a fit file of :func:`named_problem`, written from Python."""
    where = tmp_path_factory.mktemp("files")
    problem = named_problem()
    steady = solve(problem)
    result_path = write_result(where / "result.h5", steady, phase_names=NAMES)
    run = run_in(WearProblem(problem), np.zeros(problem.shape), RunOptions(snapshots_s_star=(0.5,)))
    run_path = where / "run.h5"
    write_run(run_path, run)
    fit = fit_face(MeasuredFace(steady.face, problem.grid.h), problem)
    fit_path = write_fit(where / "fit.h5", fit, phase_names=NAMES)
    return {"result": result_path, "run": run_path, "fit": fit_path, "problem": problem,
            "run_result": run}


def units_of(path):
    """Every ``units`` of a dataset in a file, ``{where: unit}``; None: no long_name or *_units."""
    found = {}

    def visit(name, obj):
        for key, value in obj.attrs.items():
            if key == "units":
                found[f"/{name} @{key}"] = value.decode() if isinstance(value, bytes) else value
            elif key.endswith("_units"):  # a quantity as an attribute pair: not CF
                found[f"/{name} @{key}"] = None
        if isinstance(obj, h5py.Dataset) and "long_name" not in obj.attrs:
            found[f"/{name} @long_name"] = None

    with h5py.File(path, "r") as f:
        visit("", f)
        f.visititems(visit)
    return found


@pytest.mark.parametrize("kind", ["result", "run", "fit"])
def test_every_unit_is_a_udunits_string_and_every_dataset_has_a_long_name(files, kind):
    units = units_of(files[kind])
    missing = [where for where, unit in units.items() if unit is None]
    assert not missing, f"{kind} file: datasets without long_name, or *_units: {missing}"
    bad = {where: unit for where, unit in units.items() if not UDUNITS.match(str(unit))}
    assert not bad, f"{kind} file: units that udunits does not parse: {bad}"
    assert len(units) > 20, f"{kind} file: only {len(units)} units found"


def test_result_file_opens_as_labelled_arrays(files):
    problem = files["problem"]
    with xr.open_dataset(files["result"], engine="h5netcdf") as ds:
        assert ds.attrs["Conventions"] == "CF-1.10", ds.attrs
        for name in ("phase", "pressure", "face", "slope"):
            assert ds[name].dims == ("y", "x"), f"{name} dims {ds[name].dims}"
        assert ds["x"].attrs["units"] == "m" and ds["y"].attrs["units"] == "m", "coords in m"
        assert np.array_equal(ds["x"].values, problem.grid.x), "x: the grid's pixel centres"
        assert np.array_equal(ds["y"].values, problem.grid.y), "y: the grid's pixel centres"
        assert tuple(ds["phase_name"].values.tolist()) == NAMES, f"{ds['phase_name'].values}"
        assert ds["pressure"].attrs["units"] == "Pa", "pressure in Pa"
        # Labelled selection: the pixel at the face's centre is on the face.
        centre = ds["pressure"].sel(x=0.0, y=0.0, method="nearest")
        assert float(centre) > 0, f"pressure at the centre {float(centre)}"
        assert ds["wear_coefficients"].attrs["units"] == "Pa-1", "Archard's k in Pa-1"
        for name in ("wear_coefficients", "fill_factors", "phase_pressures"):
            assert ds[name].dims == ("phase_name",), f"{name}: {ds[name].dims}"
        for name in ("rms_slope", "rms_slope_ref", "mean_pressure", "normal_force", "n"):
            assert ds[name].dims == () and ds[name].attrs["long_name"], f"{name}: {ds[name]}"
        assert ds["normal_force"].attrs["units"] == "N" and float(ds["normal_force"]) == FORCE
    assert read_result(files["result"]).phase_names == NAMES, "names read back"


def test_run_file_opens_as_labelled_arrays(files):
    run = files["run_result"]
    with xr.open_dataset(files["run"], engine="h5netcdf") as ds:
        for name in ("worn_depth", "face", "pressure"):
            assert ds[name].dims == ("y", "x"), f"{name}: dims {ds[name].dims}"
        assert np.array_equal(ds["face"].values, run.face.T, equal_nan=True), "face stored (y, x)"
        assert ds["x"].attrs["units"] == "m", "x in m"
        assert tuple(ds["phase_name"].values.tolist()) == NAMES, "phase names as a coordinate"
        assert ds["distance_scale"].attrs["units"] == "m", "s* in m"
        assert float(ds["distance_scale"]) == run.distance_scale, "s*, a 0-d variable"
    with xr.open_dataset(files["run"], engine="h5netcdf", group="history") as hist:
        assert hist["distance"].attrs["units"] == "m", "distance in m"
        assert np.array_equal(hist["distance"].values, run.history["distance"]), "distance"
        for name in HISTORY_UNITS:
            if name != "distance" and len(run.history[name]) == len(run.history["distance"]):
                assert hist[name].dims == ("distance",), f"history/{name} dims {hist[name].dims}"
            elif name != "distance":  # a spatial error no companion run filled: not written
                assert name not in hist, f"history/{name} written with {len(run.history[name])}"
        assert float(hist["distance_scale"]) == run.distance_scale, "s* beside the history"
    with xr.open_dataset(files["run"], engine="h5netcdf", group="snapshots") as snaps:
        assert snaps["recession"].dims == ("distance", "y", "x"), f"{snaps['recession'].dims}"
        assert np.array_equal(snaps["distance"].values, run.snapshot_distance), "snapshots"


def test_fit_file_opens_as_labelled_arrays(files):
    with xr.open_dataset(files["fit"], engine="h5netcdf") as ds:
        for name in ("measured", "fitted", "residual", "fit_mask", "phase"):
            assert ds[name].dims == ("y", "x"), f"{name} dims {ds[name].dims}"
        assert ds["x"].attrs["units"] == "m", "x in m"
        assert ds["pressure_covariance"].attrs["units"] == "Pa2", "covariance in Pa2"
        assert ds["pressure_covariance"].dims == ("phase_name", "other_phase_name"), \
            ds["pressure_covariance"].dims
        assert ds["ratios"].dims == ("phase_name",) and ds["tilt"].dims == ("component",), \
            (ds["ratios"].dims, ds["tilt"].dims)
        assert tuple(ds["phase_name"].values.tolist()) == NAMES, "phase names"


def test_run_file_written_from_python_carries_the_inputs(files):
    """No attrs, no arrays: the load, modulus, wear law, phase map and names are stored."""
    problem = files["problem"]
    back, attrs, arrays = read_run(files["run"])
    assert attrs["normal_force"] == FORCE and attrs["E_star"] == E_STAR, "load and modulus"
    assert np.array_equal(attrs["wear_coefficients"], [K1, 10 * K1]), "wear coefficients"
    assert attrs["exponent"] == 1.0, "wear law"
    with h5py.File(files["run"], "r") as f:
        units = {name: f[name].attrs["units"]
                 for name in ("normal_force", "E_star", "wear_coefficients", "exponent")}
    assert units == {"normal_force": "N", "E_star": "Pa", "wear_coefficients": "Pa-1",
                     "exponent": "1"}, units
    assert "Archard" in attrs["wear_law"], f"wear law {attrs['wear_law']!r}"
    assert np.array_equal(arrays["phase"], problem.labels), "phase map"
    assert [v.decode() for v in arrays["phase_name"]] == list(NAMES), "phase names"
    assert back.outline == problem.outline, "outline"


def test_power_law_coefficients_carry_their_unit():
    """``dw/ds = k p^m``: k in Pa-m; udunits has no fractional powers."""
    assert run_output.problem_inputs(named_problem(exponent=2.0))[0]["wear_coefficients"][1] \
        == "Pa-2", "k of m = 2 in Pa-2"
    assert run_output.problem_inputs(named_problem(exponent=1.5))[0]["wear_coefficients"][1] \
        == "Pa^-1.5", "k of m = 1.5"


def _as_version_2(source, target):
    """The run file ``source``, of layout 4, rewritten in the layout of version 2, with checksums.

    No coordinates, phase names or dimension scales; every other dataset and
    attribute as written (so the digests are this module's, over the same values).
    """
    digest, attrs_digest = dataset_digest, attributes_digest
    with h5py.File(source, "r") as src, h5py.File(target, "w") as dst:
        def copy(name, obj):
            if isinstance(obj, h5py.Group):
                dst.require_group(name)
                return
            if name in ("x", "y", "phase_name") or name.startswith("outline/mask_"):
                return
            data = obj[()]
            ds = dst.create_dataset(name, data=data)
            keep = {k: v for k, v in obj.attrs.items()
                    if k not in DIMENSION_SCALE_ATTRIBUTES and k != "sha256"}
            ds.attrs.update(keep)
            ds.attrs["sha256"] = digest(data, keep)

        src.visititems(copy)
        for name in ["", *[n for n in dst if isinstance(dst[n], h5py.Group)]]:
            group, origin = (dst, src) if not name else (dst[name], src[name])
            keep = {k: v for k, v in origin.attrs.items() if k != "sha256"}
            if not name:
                keep["format_version"] = 2
            group.attrs.update(keep)
            group.attrs["sha256"] = attrs_digest(keep)


def test_version_2_run_files_are_read(tmp_path):
    old = tmp_path / "old.h5"
    _as_version_2(LAYOUT_4, old)
    back, attrs, arrays = read_run(old)
    run, _, _ = read_run(LAYOUT_4)
    assert attrs["format_version"] == 2, "the file is of version 2"
    assert back.steps == run.steps and np.array_equal(back.pressure, run.pressure), \
        "a version 2 file reads as written"
    assert "x" not in arrays and "phase_name" not in arrays, f"arrays {sorted(arrays)}"


def test_run_file_checksums_still_catch_a_flipped_value(files, tmp_path):
    """The dimension scales are left out of the digests, their values are not."""
    path = tmp_path / "run.h5"
    path.write_bytes(files["run"].read_bytes())
    with h5py.File(path, "r+") as f:
        x = f["x"][()]
        x[0] = -x[0] * 2
        f["x"][...] = x
    with pytest.raises(run_output.DamagedRunFileError, match="dataset 'x' does not match"):
        read_run(path)


def test_files_the_commands_write_open_as_labelled_arrays(tmp_path, capsys):
    """runin-steady, runin-transient and runin-fit: the same scheme, with the scene's names."""
    names = '[phases]\nnames = ["matrix", "hard phase"]\n'
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text("runin").replace("[phases]\n", names))
    outputs = {"result": tmp_path / "result.h5", "run": tmp_path / "run.h5",
               "fit": tmp_path / "fit.h5"}
    status, _, err = run_cli(steady_cli, [scene, "-o", outputs["result"], "--no-slope-error"],
                             capsys)
    assert status == 0, err
    status, _, err = run_cli(transient_cli, [scene, "-o", outputs["run"]], capsys)
    assert status == 0, err
    with h5py.File(outputs["result"], "r") as f:
        # Stored (y, x); a measured map is indexed [i, j], i along x, as the library's fields.
        face, h = f["face"][()].T, float(f["pixel_size"][()])
    np.save(tmp_path / "measured.npy", face)
    status, _, err = run_cli(fit_cli, [scene, tmp_path / "measured.npy", "--pixel-size", h,
                                       "-o", outputs["fit"]], capsys)
    assert status == 0, err
    for kind, path in outputs.items():
        units = units_of(path)
        bad = {where: unit for where, unit in units.items()
               if unit is None or not UDUNITS.match(str(unit))}
        assert not bad, f"{kind} file: bad units or no long_name: {bad}"
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            assert ds["phase"].dims == ("y", "x"), f"{kind}: phase dims {ds['phase'].dims}"
            assert ds["phase_name"].values.tolist() == ["matrix", "hard phase"], \
                f"{kind}: phase names {ds['phase_name'].values}"


def test_two_files_written_alike_compare_identical(files, tmp_path):
    """studies/compare_outputs.py compares dimension scales by the names they refer to."""
    import importlib
    import pathlib
    import sys

    studies = pathlib.Path(__file__).resolve().parent.parent / "studies"
    sys.path.insert(0, str(studies))
    try:
        compare = importlib.import_module("compare_outputs")
    finally:
        sys.path.remove(str(studies))
    stored = read_result(files["result"])
    again = write_result(tmp_path / "again.h5", stored.result, phase_names=stored.phase_names)
    assert compare.compare_files(files["result"], again, ()) == [], "a rewrite is identical"
    other = write_result(tmp_path / "other.h5", stored.result, phase_names=("a", "b"))
    assert compare.compare_files(files["result"], other, ()) == ["/phase_name: dataset differs"]


@pytest.fixture(scope="module")
def ellipse_files(tmp_path_factory):
    """The result and the run file the commands write of the ellipse of :data:`LAYOUT_4`'s scene.

    An ellipse 8 mm along x and 5 mm along y: 24 pixels along x, 15 along y, so that a
    field drawn the wrong way round shows.
    """
    where = tmp_path_factory.mktemp("ellipse")
    scene = where / "scene.toml"
    shutil.copy(DATA / "run_layout4.toml", scene)
    paths = {"result": where / "result.h5", "run": where / "run.h5"}
    assert steady_cli.main([str(scene), "-o", str(paths["result"]), "--no-slope-error"]) == 0
    assert transient_cli.main([str(scene), "-o", str(paths["run"])]) == 0
    return paths


def _drawn_extent(face):
    """The widths (m) across and up of ``face.plot()``, drawn on a figure without pyplot."""
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    face.plot(ax=ax)
    return np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim())


@pytest.mark.parametrize("kind", ["result", "run"])
def test_files_open_as_a_datatree_with_x_across(ellipse_files, kind):
    path = ellipse_files[kind]
    if kind == "result":
        face = read_result(path).result.face
    else:
        face = read_run(path)[0].face
    nx, ny = face.shape
    assert (nx, ny) == (24, 15), f"the ellipse's grid {face.shape}"
    tree = xr.open_datatree(path, engine="h5netcdf")
    try:
        ds = tree.to_dataset()
        assert ds.attrs["Conventions"] == "CF-1.10", ds.attrs
        assert ds["face"].dims == ("y", "x") and ds["face"].shape == (ny, nx), ds["face"]
        # Labelled access gives the library's [i, j] (i along x) pixel for pixel.
        i, j = 17, 4
        assert np.array_equal(ds["face"].isel(x=i, y=j).values, face[i, j], equal_nan=True)
        assert np.array_equal(ds["face"].values, face.T, equal_nan=True), "face stored (y, x)"
        h = float(ds["x"][1] - ds["x"][0])
        across, up = _drawn_extent(ds["face"])
        assert (across, up) == (pytest.approx(nx * h), pytest.approx(ny * h)), \
            f"ds.face.plot() draws {across} m across and {up} m up: {nx * h} x {ny * h} expected"
        empty = {f"{node.path}:{dim}" for node in tree.subtree
                 for dim, size in node.to_dataset().sizes.items() if size == 0}
        assert not empty, f"dimensions of length 0: {sorted(empty)}"
        for node in tree.subtree:
            for name, var in node.to_dataset(inherit=False).variables.items():
                assert var.attrs.get("long_name"), f"{node.path}/{name} has no long_name"
                if var.dtype.kind == "f" and "code" not in var.attrs["long_name"]:
                    assert var.attrs.get("units"), f"{node.path}/{name} has no units"
        for name, unit in {"normal_force": "N", "E_star": "Pa", "n": "1"}.items():
            assert ds[name].dims == () and ds[name].attrs["units"] == unit, ds[name]
        assert ds["wear_coefficients"].dims == ("phase_name",), ds["wear_coefficients"]
        assert ds["phase_name"].values.tolist() == ["matrix", "filler"], ds["phase_name"]
        if kind == "run":
            assert tree["snapshots"]["recession"].dims == ("distance", "y", "x")
            assert tree["history"]["load_forces"].dims == ("load_breakpoints",)
            assert float(tree["history"]["load_breakpoints"][0]) == 20.0
            assert tree["history"]["distance"].attrs["units"] == "m"
    finally:
        tree.close()
