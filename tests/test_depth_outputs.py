"""What a run whose phase map changes with depth records and reports.

A three-phase Voronoi punch whose phases 0 and 1 wear alike: columns that swap
the labels 0 and 1 at a depth below the surface change the phase fractions but
not the wear coefficients, so the run's dynamics are the columnar run's and its
history must equal it; the new columns (worn depth, phase fractions, interface
crossings, the quasi-steady rms slope) are checked against the snapshots. A
hand-built two-layer column (a coating of varying thickness) gives the coating
distances; the run file stores all of it with units and reads it back, and a
columnar run's file gains nothing.
"""

import dataclasses

import h5py
import numpy as np
import pytest
from conftest import E_STAR, FORCE, GEOMETRIES, K1, RADIUS, with_columns

import transient.cli.runin as transient_cli
from steady.depth import DepthColumns
from steady.outline import Circle
from steady.problem import FacePhases, Problem
from steady.wear import PowerLaw
from transient.history import Coating, crossings
from transient.output import read_run, write_run
from transient.problem import WearProblem
from transient.result import COATING_HISTORY_UNITS, DEPTH_HISTORY_UNITS, HISTORY_UNITS
from transient.run_in_distance import coating_distance
from transient.runin import RunOptions, run_in

N = 31
NAMES = ("matrix", "matrix twin", "filler")
SNAPSHOTS = (0.003, 0.01, 0.03, 0.1)


def three_phases(n=N):
    """The gallery's Voronoi map with its phase 0 split in two halves of equal wear."""
    grid = Circle(RADIUS).grid(n)
    labels = GEOMETRIES["voronoi"].labels(grid)
    x = grid.x[:, None] + 0.0 * grid.y[None, :]
    split = np.where(labels == 1, 2, np.where(x < 0, 0, 1))
    return Problem(FacePhases(grid, np.where(grid.mask, split, -1), 3, NAMES),
                   PowerLaw([K1, K1, 10 * K1]), FORCE, E_STAR)


def run(problem, columns=None):
    """A run-in to the steady state, with snapshots, of ``problem`` given ``columns``."""
    wear = WearProblem(with_columns(problem, columns))
    return run_in(wear, np.zeros(problem.shape), RunOptions(tol=1e-3, snapshots_s_star=SNAPSHOTS))


@pytest.fixture(scope="module")
def columnar():
    """The columnar run of :func:`three_phases`."""
    return run(three_phases())


@pytest.fixture(scope="module")
def swapped(columnar):
    """The same punch whose labels 0 and 1 swap at a depth the run passes at its middle."""
    problem = three_phases()
    labels = problem.labels
    worn = columnar.snapshot_recession[2] - columnar.initial_recession
    depth = float(np.median(worn[problem.face_mask]))
    below = np.where(labels == 0, 1, np.where(labels == 1, 0, labels))
    interfaces = np.where(problem.face_mask, depth, np.inf)[None]
    columns = DepthColumns(interfaces, np.stack([labels, below]), 3)
    return run(problem, columns), columns, depth


@pytest.fixture(scope="module")
def coated(columnar):
    """A coating of phase 1, thinner towards -x, over the three-phase map."""
    problem = three_phases()
    grid = problem.grid
    worn = columnar.snapshot_recession[1] - columnar.initial_recession
    t0 = float(np.median(worn[problem.face_mask]))
    thickness = t0 * (1.0 + 0.5 * grid.x[:, None] / RADIUS) + 0.0 * grid.y[None, :]
    face = problem.face_mask
    below = np.where(problem.labels == 1, 0, problem.labels)  # phase 1 only in the coating
    columns = DepthColumns(np.where(face, thickness, np.inf)[None],
                           np.stack([np.where(face, 1, -1), below]), 3)
    return run(problem, columns), columns, thickness


def test_history_equals_the_columnar_run(columnar, swapped):
    """Equal wear coefficients in every segment: the dynamics and the history are the same."""
    result, _, _ = swapped
    assert result.status == columnar.status == "steady"
    # The swapped run integrates the wear work across its interface: the same dynamics, to
    # the contact solves' share of the step tolerance.  Measured: at most 4.0e-5 of each
    # figure's largest value (the step error estimates; the worn volume 8.6e-6).  ``solves``
    # counts the stages' Newton iterations too.
    assert len(result.history["distance"]) == len(columnar.history["distance"])
    for name in set(HISTORY_UNITS) - {"solves"}:
        a = np.asarray(columnar.history[name], dtype=float)
        b = np.asarray(result.history[name], dtype=float)
        finite = np.abs(a[np.isfinite(a)])
        scale = finite.max(initial=0.0)
        np.testing.assert_allclose(b, a, rtol=0.0, atol=1e-4 * scale, equal_nan=True,
                                   err_msg=f"history {name} differs from the columnar run's")
    assert set(columnar.history) == set(HISTORY_UNITS), "a columnar run records only its own"
    assert set(DEPTH_HISTORY_UNITS) <= set(result.history), "the depth columns are recorded"
    assert not set(COATING_HISTORY_UNITS) & set(result.history), "no coating, no coating marks"


def test_worn_depth_columns(swapped):
    """Mean worn depth from the worn volume, rim worn depth as the history's, max at least mean."""
    result, _, _ = swapped
    h = result.history
    area = np.count_nonzero(result.face_mask) * result.pixel_size ** 2
    np.testing.assert_allclose(h["worn_depth_mean"], np.asarray(h["worn_volume"]) / area,
                               rtol=1e-12, atol=1e-25, err_msg="mean worn depth")
    np.testing.assert_array_equal(h["worn_depth_rim"], h["rim_worn_depth"],
                                  err_msg="rim worn depth")
    assert np.all(h["worn_depth_max"] >= h["worn_depth_mean"]), "max below mean"
    assert h["worn_depth_max"][0] == 0.0, "nothing worn at s = 0"


def test_phase_fractions_and_crossings(swapped):
    """Fractions sum to 1 and swap where the pixels cross; crossings add up to the pixels past."""
    result, columns, depth = swapped
    h = result.history
    fractions = np.asarray(h["phase_fraction"])
    assert fractions.shape == (len(h["distance"]), 3), f"shape {fractions.shape}"
    np.testing.assert_allclose(fractions.sum(axis=1), 1.0, rtol=0, atol=1e-15,
                               err_msg="fractions do not sum to 1")
    np.testing.assert_array_equal(fractions[0], columns.fractions(0.0), err_msg="at s = 0")
    np.testing.assert_array_equal(fractions[:, 2], fractions[0, 2],
                                  err_msg="the filler is the filler in both segments")
    distance = np.asarray(h["distance"])
    total = np.cumsum(h["crossings"])
    sections = result.snapshot_sections
    passed = []
    for j, s in enumerate(result.snapshot_distance):
        i = int(np.flatnonzero(distance == s)[0])
        worn = result.snapshot_recession[j] - result.initial_recession
        past = int(np.count_nonzero(worn[result.face_mask] >= depth))
        passed.append(past)
        assert total[i] == past, f"snapshot {j}: {total[i]} crossings, {past} pixels past"
        counts = np.bincount(sections[j][result.face_mask], minlength=3)
        np.testing.assert_allclose(fractions[i], counts / counts.sum(), rtol=0, atol=1e-15,
                                   err_msg=f"fractions at snapshot {j}")
        np.testing.assert_array_equal(sections[j], columns.phase_at(np.nan_to_num(worn)),
                                      err_msg=f"section at snapshot {j}")
    face = int(np.count_nonzero(result.face_mask))
    assert 0 < passed[0] < passed[2] < passed[-1] <= face, f"pixels past the interface {passed}"
    assert fractions[-1, 0] != fractions[0, 0], "the fractions did not change"


def test_crossings_helper():
    """A pixel crossing two interfaces counts once; off the face nothing counts."""
    interfaces = np.array([[[1.0, 1.0], [1.0, np.inf]], [[2.0, 2.0], [2.0, np.inf]]])
    phases = np.array([[[0, 0], [0, -1]], [[1, 1], [1, -1]], [[0, 0], [0, -1]]])
    columns = DepthColumns(interfaces, phases, 2)
    before = np.array([[0.5, 0.5], [1.5, 0.0]])
    after = np.array([[2.5, 0.9], [1.9, 9.0]])
    assert crossings(columns, before, after) == 1, "one pixel changed segment"
    assert crossings(columns, after, after) == 0, "no step, no crossing"


def test_quasi_steady_slope_is_the_steady_one(swapped):
    """Every section wears like the surface: its steady face is the run's steady face."""
    result, _, _ = swapped
    quasi = np.asarray(result.history["quasi_steady_rms_slope"])
    np.testing.assert_allclose(quasi, result.steady_rms_slope, rtol=1e-12, atol=0.0,
                               err_msg="quasi-steady rms slope")
    np.testing.assert_allclose(result.history["normalised_quasi_steady_rms_slope"],
                               quasi / result.reference_slope, rtol=1e-15, atol=0.0)


def test_coating_distances(coated):
    """The events lie where the marks change sign, which the snapshots' worn depths give."""
    result, columns, thickness = coated
    coating = Coating.of(columns)
    assert coating.phase == 1, "the coating's phase"
    h = result.history
    distance = np.asarray(h["distance"])
    face = result.face_mask
    for j, s in enumerate(result.snapshot_distance):
        i = int(np.flatnonzero(distance == s)[0])
        worn = (result.snapshot_recession[j] - result.initial_recession)[face]
        assert h["coating_overshoot"][i] == np.max(worn - thickness[face]), f"snapshot {j}"
        contact = result.snapshot_pressure[j][face] > 0
        assert h["coating_contact_remaining"][i] == np.max((thickness[face] - worn)[contact])
    for event, name, sign in (("worn_through", "coating_overshoot", 1.0),
                              ("gone", "coating_contact_remaining", -1.0)):
        found = coating_distance(result, event)
        assert found.reached, f"{event}: {found.reason}"
        i = int(np.searchsorted(distance, found.distance_m))
        mark = sign * np.asarray(h[name])
        assert 0 < i and mark[i - 1] < 0 <= mark[i], f"{event} at {found.distance_m}"
        assert np.all(mark[:i] < 0), f"{event}: an earlier sign change"
        at = np.interp(found.distance_m, distance[i - 1:i + 1], mark[i - 1:i + 1])
        assert abs(at) <= 1e-12 * np.max(np.abs(mark)), f"{event}: mark {at} there"
        np.testing.assert_allclose(found.distance_s_star,
                                   found.distance_m / result.distance_scale, rtol=1e-15)
    assert result.coating_worn_through.distance_m < result.coating_gone.distance_m, \
        "gone from the contact before it is worn through"


def test_coating_distance_interpolates_a_hand_made_history(coated):
    """Marks -2, -1, 1, 3 at s = 0, 1, 2, 3 m: worn through at 1.5 m; gone never."""
    result = coated[0]
    history = {"distance": np.array([0.0, 1.0, 2.0, 3.0]),
               "coating_overshoot": np.array([-2.0, -1.0, 1.0, 3.0]),
               "coating_contact_remaining": np.array([3.0, 2.0, 1.0, np.nan])}
    made = dataclasses.replace(result, history=history)
    through = made.coating_worn_through
    assert through.distance_m == 1.5, through
    assert through.distance_s_star == 1.5 / result.distance_scale
    gone = made.coating_gone
    assert np.isnan(gone.distance_m) and np.isnan(gone.distance_s_star)
    assert gone.reason == "not by the end of the run at s = 3 m = " \
                          f"{3 / result.distance_scale:.4g} s*", gone.reason
    with pytest.raises(ValueError, match="coating event must be one of .*got 'peeled'"):
        coating_distance(made, "peeled")


def test_no_coating(swapped, columnar):
    """Columns that do not start with one layer, and a columnar run: NaN with the reason."""
    for result in (swapped[0], columnar):
        found = result.coating_worn_through
        assert not found.reached and "no coating" in found.reason, found


def test_run_in_distance_without_steady_state(swapped, columnar):
    """A depth run ended at its depth or distance has no run-in distance; a columnar one does."""
    for status in ("depth", "distance"):
        ended = dataclasses.replace(swapped[0], status=status)
        found = ended.run_in_distance(0.01)
        assert not found.reached and np.isnan(found.distance_m)
        assert f"ended at its {status}" in found.message, found.message
        assert "no steady state to approach" in found.message, found.message
    assert swapped[0].run_in_distance(0.01).reached, "steady: the usual criterion"
    stopped = dataclasses.replace(columnar, status="distance")
    assert stopped.run_in_distance(0.01) == columnar.run_in_distance(0.01)


def test_run_file_layout(tmp_path, coated):
    """Depth datasets with units and scales; read back, the same columns and distances."""
    result, columns, _ = coated
    path = tmp_path / "run.h5"
    write_run(path, result)
    with h5py.File(path, "r") as f:
        fraction = f["history/phase_fraction"]
        assert fraction.shape == (len(result.history["distance"]), 3)
        assert fraction.attrs["units"] == "1"
        assert [d.label or d[0].name for d in fraction.dims] == \
            ["/history/distance", "/phase_name"], [d[0].name for d in fraction.dims]
        for name in ("worn_depth_mean", "worn_depth_rim", "worn_depth_max",
                     "coating_overshoot", "coating_contact_remaining"):
            assert f[f"history/{name}"].attrs["units"] == "m", name
        assert f["history/crossings"].attrs["units"] == "1"
        section = f["snapshots/section"]
        # Stored (distance, y, x): the library's [k, i, j] with the last two swapped.
        assert section.dtype == np.int8
        assert section.shape == np.swapaxes(result.snapshot_recession, 1, 2).shape
        assert "phase map of the section" in section.attrs["long_name"] or \
            "section" in section.attrs["long_name"]
        np.testing.assert_array_equal(section[()], np.swapaxes(result.snapshot_sections, 1, 2))
        assert f["columns/interfaces"].attrs["units"] == "m"
        assert f["columns/n_phases"][()] == 3
        for event, found in (("worn_through", result.coating_worn_through),
                             ("gone", result.coating_gone)):
            distance = f[f"coating_{event}_distance"]
            assert distance.shape == () and distance[()] == found.distance_m
            assert distance.attrs["units"] == "m"
            assert f[f"coating_{event}_distance_s_star"].attrs["units"] == "1"
            assert f.attrs[f"coating_{event}_reason"] == ""
    read, attrs, _ = read_run(path)
    np.testing.assert_array_equal(read.columns.interfaces, columns.interfaces)
    np.testing.assert_array_equal(read.columns.phases, columns.phases)
    np.testing.assert_array_equal(read.history["phase_fraction"], result.history["phase_fraction"])
    assert read.coating_gone == result.coating_gone
    np.testing.assert_array_equal(read.snapshot_sections, result.snapshot_sections)


def test_xarray_opens_the_depth_datasets(tmp_path, coated):
    """The history's fractions are labelled by distance and phase name; sections by x, y."""
    xr = pytest.importorskip("xarray")
    path = tmp_path / "run.h5"
    write_run(path, coated[0])
    with xr.open_dataset(path, engine="h5netcdf", group="history") as hist:
        assert hist["phase_fraction"].dims == ("distance", "phase_name")
        assert hist["phase_fraction"].attrs["units"] == "1"
    with xr.open_dataset(path, engine="h5netcdf", group="snapshots") as snaps:
        assert snaps["section"].dims == ("distance", "y", "x")


def test_columnar_run_file_unchanged(tmp_path, columnar):
    """A columnar run's file has no depth dataset, group or attribute."""
    path = tmp_path / "run.h5"
    write_run(path, columnar)
    with h5py.File(path, "r") as f:
        # The history's own (but the spatial errors no companion run filled) and s*.
        assert set(f["history"]) - {"distance_scale"} <= set(HISTORY_UNITS), set(f["history"])
        assert not set(f["history"]) & set(DEPTH_HISTORY_UNITS), set(f["history"])
        assert "columns" not in f and "section" not in f["snapshots"]
        assert not [a for a in (*f.attrs, *f) if a.startswith("coating_")]
    assert read_run(path)[0].columns is None


def test_summary_lines(coated, swapped, columnar):
    """Why the run ended and its mean worn depth; the coating's distances when it has one."""
    result = coated[0]
    lines = transient_cli._end_lines(result)
    assert lines[0].startswith("run ended at the steady state"), lines
    assert f"mean worn depth at the end {result.mean_worn_depth:.4g} m" in lines[0]
    assert lines[1].startswith("coating worn through at s = "), lines
    assert lines[2].startswith("coating gone from the contact at s = "), lines
    assert len(transient_cli._end_lines(swapped[0])) == 1
    depth = transient_cli._end_lines(dataclasses.replace(swapped[0], status="depth"))
    assert depth[0].startswith("run ended at the end depth"), depth
    assert transient_cli._end_lines(columnar) == []


def test_history_figure_panels(tmp_path, coated, columnar):
    """A depth run's figure has the depth panel and the quasi-steady slope; a columnar one not."""
    from transient.plotting import plot_history, run_figure

    result = coated[0]
    fig = run_figure(result)
    titles = [ax.get_title() for ax in fig.axes]
    assert "worn depth and the section" in titles, titles
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert "quasi-steady face of the section" in labels, labels
    legend = [t.get_text() for ax in fig.axes if ax.get_legend() is not None
              for t in ax.get_legend().get_texts()]
    for name in NAMES:
        assert f"{name} (fraction)" in legend, legend
    assert "coating worn through" in legend and "coating gone from the contact" in legend
    assert "worn depth and the section" not in [ax.get_title()
                                                for ax in run_figure(columnar).axes]
    with pytest.raises(ValueError, match="no depth history"):
        plot_history(columnar, quantities="depth")


def test_resumed_depth_run_repeats_the_history(tmp_path, swapped):
    """Stopped after 6 steps, written, read and resumed: the same depth history bit for bit."""
    whole, columns, _ = swapped
    problem = three_phases()
    wear = WearProblem(with_columns(problem, columns))
    options = RunOptions(tol=1e-3, snapshots_s_star=SNAPSHOTS)
    first = run_in(wear, np.zeros(problem.shape), dataclasses.replace(options, max_steps=6))
    assert first.status != "steady", first.status
    write_run(tmp_path / "run.h5", first)
    stored = read_run(tmp_path / "run.h5")[0]
    wear = WearProblem(with_columns(problem, stored.columns))
    resumed = run_in(wear, None, options, resume=stored)
    assert resumed.status == "steady"
    for name in (*DEPTH_HISTORY_UNITS, "distance", "rms_slope"):
        np.testing.assert_array_equal(resumed.history[name], whole.history[name],
                                      err_msg=f"resumed {name}")


def test_quasi_steady_slope_of_a_changed_section(swapped):
    """Where the section wears otherwise, its slope is the steady slope of that phase map."""
    import math

    from steady.solution import solve
    from transient.history import FaceEstimator

    _, columns, _ = swapped
    problem = three_phases()
    unequal = dataclasses.replace(problem, wear=PowerLaw([K1, 3 * K1, 10 * K1]))
    result = run(unequal, columns)
    h = result.history
    fractions = np.asarray(h["phase_fraction"])
    final = columns.phases[1]
    assert np.array_equal(fractions[-1], columns.fractions(np.inf)), "not all past at the end"
    quasi = np.asarray(h["quasi_steady_rms_slope"])
    for index, labels, what in ((-1, final, "bottom"), (0, problem.labels, "surface")):
        section = dataclasses.replace(unequal,
                                      phases=FacePhases(problem.grid, labels, 3, NAMES))
        steady = solve(section, face_only=True)
        face = section.face_mask
        expected = FaceEstimator(WearProblem(section), np.zeros(problem.shape)).figures(
            math.inf, np.where(face, -steady.face, 0.0), np.where(face, steady.pressure, 0.0),
            0.0)["rms_slope"]
        np.testing.assert_allclose(quasi[index], expected, rtol=1e-12,
                                   err_msg=f"{what} section")
    # The run's steady state is the one of the section below every interface.
    np.testing.assert_allclose(quasi[-1], result.steady_rms_slope, rtol=1e-12,
                               err_msg="the steady state is the bottom section's")
    assert abs(quasi[-1] / quasi[0] - 1) > 0.01, "the sections' steady slopes do not differ"


def test_checkpoint_without_columns(tmp_path, coated):
    """A checkpoint keeps the coating distances and the sections, not the columns."""
    result = dataclasses.replace(coated[0], status="running")
    path = tmp_path / "checkpoint.h5"
    write_run(path, result)
    with h5py.File(path, "r") as f:
        assert "columns" not in f, "a checkpoint stores no columns"
        assert f["coating_gone_distance"][()] == result.coating_gone.distance_m
        np.testing.assert_array_equal(f["snapshots/section"][()],
                                      np.swapaxes(result.snapshot_sections, 1, 2))
    assert read_run(path)[0].columns is None
