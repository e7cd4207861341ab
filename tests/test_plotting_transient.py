"""Figures of runs: distance axes in metres and s*, relief, pressure units, orientation."""

import dataclasses

import h5py
import numpy as np
import pytest
from conftest import GEOMETRIES, K1, problem
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from steady.outline import Rectangle
from steady.plotting import relief, result_figure
from steady.solution import solve
from transient import initial_face
from transient.comparison import compare_with_steady
from transient.output import read_run, write_run
from transient.plotting import (
    add_distance_axis,
    distance_scale,
    format_metres,
    plot_face,
    plot_history,
    plot_pressure,
    plot_run,
    run_figure,
    run_in_distance_of,
)
from transient.problem import WearProblem
from transient.runin import RunOptions, run_in

#: A block twice as wide along x as along y.
WIDE = Rectangle(8e-3, 4e-3)


@pytest.fixture(scope="module")
def wide_problem():
    return WearProblem(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32, outline=WIDE))


@pytest.fixture(scope="module")
def steady(wide_problem):
    return solve(wide_problem.problem)


@pytest.fixture(scope="module")
def run_file(tmp_path_factory, wide_problem, steady):
    result = run_in(wide_problem, initial_face.flat(wide_problem.grid),
                    RunOptions(tol=1e-2, snapshots_s_star=(0.1,)))
    path = tmp_path_factory.mktemp("run") / "run.h5"
    write_run(path, result, comparison=compare_with_steady(result, steady, wide_problem))
    return path


@pytest.fixture(scope="module")
def result(run_file):
    return read_run(run_file)[0]


def _steps(result):
    """Distances of the steps after s = 0, m, and their mask (a final jump to 1e8 s* left out)."""
    d = np.asarray(result.history["distance"])
    pos = (d > 0) & (d < 1e6 * distance_scale(result))
    return d, pos


def _drawn(ax):
    """The image of a map panel as an array indexed [x, y] (NaN where masked)."""
    return np.ma.filled(np.ma.masked_invalid(ax.images[0].get_array()), np.nan).T


# -- the distance axes ----------------------------------------------------------------------

@pytest.mark.parametrize(("units", "to_secondary"), [("m", 1 / 250.0), ("s*", 250.0)])
def test_secondary_axis_converts_with_s_star(units, to_secondary):
    """With s* = 250 m, 1 km is 4 s* and 10 s* is 2.5 km."""
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_xlim(1e-2, 1e4)
    top = add_distance_axis(ax, 250.0, units)
    fig.canvas.draw()
    assert top.get_xlim() == pytest.approx((1e-2 * to_secondary, 1e4 * to_secondary),
                                           rel=1e-12)
    assert "s* = 250 m" in top.get_xlabel(), top.get_xlabel()
    with pytest.raises(ValueError, match="units must be 'm' or 's\\*', got 'km'"):
        add_distance_axis(ax, 250.0, "km")


def test_history_against_distance_in_metres(run_file, result):
    fig = plot_history(run_file, units="m")
    ax = fig.axes[0]
    d, pos = _steps(result)
    line = ax.lines[0]
    np.testing.assert_array_equal(line.get_xdata(), d[pos], err_msg="distance in m")
    np.testing.assert_allclose(line.get_ydata(),
                               result.history["rms_slope"][pos] / result.reference_slope,
                               rtol=1e-15)
    assert ax.get_xlabel() == "sliding distance (m)"
    assert ax.get_ylabel() == r"rms slope / $\nabla f^0_\infty$"
    assert ax.get_xticklabels()[0].get_text() == "0", "s = 0 at the left edge"
    top = ax.child_axes[0]
    s_star = distance_scale(result)
    assert format_metres(s_star) in top.get_xlabel(), "s* printed on the figure"
    fig.canvas.draw()
    assert top.get_xlim() == pytest.approx(np.array(ax.get_xlim()) / s_star, rel=1e-12)
    asymptote = [line for line in ax.lines if line.get_label().startswith("steady face")]
    assert len(asymptote) == 1, [line.get_label() for line in ax.lines]
    with h5py.File(run_file, "r") as f:
        stored = f["comparison/steady_rms_slope"][()] / result.reference_slope
    assert asymptote[0].get_ydata()[0] == pytest.approx(stored, rel=1e-12), "steady value"


def test_history_in_s_star_and_absolute_slope(result):
    fig = plot_history(result, units="s*", normalised=False)
    ax = fig.axes[0]
    d, pos = _steps(result)
    np.testing.assert_allclose(ax.lines[0].get_xdata(), d[pos] / distance_scale(result),
                               rtol=1e-15)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), result.history["rms_slope"][pos])
    assert ax.get_ylabel() == "rms slope (rad)"
    assert ax.child_axes[0].get_xlabel().startswith("sliding distance (m)")


def test_history_panels_and_given_axes(result):
    fig = plot_history(result, quantities=("rms_slope", "rms_height", "convergence"),
                       normalised=False)
    assert [a.get_ylabel() for a in fig.axes] == ["rms slope (rad)", "rms height (µm)",
                                                  "convergence measure"]
    np.testing.assert_allclose(fig.axes[1].lines[0].get_ydata(),
                               result.history["rms_height"][_steps(result)[1]] * 1e6, rtol=1e-15)
    mine = Figure()
    a, b = mine.subplots(1, 2)
    assert plot_history(result, quantities=("rms_slope", "rms_height"), ax=(a, b)) is mine
    assert a.lines and b.lines
    with pytest.raises(ValueError, match="1 axes given for 2 quantities"):
        plot_history(result, quantities=("rms_slope", "rms_height"), ax=a)
    with pytest.raises(ValueError, match="unknown quantity 'slope'"):
        plot_history(result, quantities=("slope",))
    with pytest.raises(ValueError, match="units must be 'm' or 's\\*', got 'mm'"):
        plot_history(result, units="mm")


def test_run_in_distance_is_marked_from_the_file_table(result):
    """The run file's ``run_in_distance`` table: the 1 % row, if the run reached it."""
    table = {"within": np.array([0.01, 0.001]), "reached": np.array([1.0, 0.0]),
             "distance": np.array([1234.5, np.nan])}
    assert run_in_distance_of(result, table=table) == 1234.5
    assert run_in_distance_of(result, 0.001, table=table) is None, "not reached"
    assert run_in_distance_of(result, 0.1, table=table) is None, "no such row"
    ax = run_figure(result, run_in=table).axes[0]
    marks = [line for line in ax.lines if line.get_label().startswith("run-in distance")]
    assert len(marks) == 1 and list(marks[0].get_xdata()) == [1234.5, 1234.5]
    assert marks[0].get_label() == "run-in distance (1 %) 1230 m"
    in_s_star = run_figure(result, run_in=table, units="s*").axes[0]
    mark = [line for line in in_s_star.lines if line.get_label().startswith("run-in")][0]
    assert mark.get_xdata()[0] == pytest.approx(1234.5 / distance_scale(result), rel=1e-15)


def test_run_in_distance_without_a_table_comes_from_the_result(result):
    method = getattr(result, "run_in_distance", None)
    if not callable(method):
        assert run_in_distance_of(result) is None, "nothing recorded: no mark"
        return
    found = method(0.01)
    assert run_in_distance_of(result) == (found.distance_m if found.reached else None)


# -- the face and its pressure ------------------------------------------------------------

def test_face_is_relief_with_zero_mean(result):
    fig = plot_face(result)
    drawn = _drawn(fig.axes[0])
    mask = result.face_mask
    expected = relief(result.face, mask, result.pixel_size) * 1e6
    np.testing.assert_allclose(drawn[mask], expected[mask], rtol=1e-12)
    assert abs(drawn[mask].mean()) < 1e-9 * np.ptp(drawn[mask]), "zero mean on the face"
    assert np.all(np.isnan(drawn[~mask]))
    assert fig.axes[1].get_xlabel() == "height about the best-fit plane (µm)", "bar below"
    snapshot = _drawn(plot_face(result, snapshot=0, remove="mean", units="normalised").axes[0])
    assert abs(np.nanmean(snapshot)) < 1e-9 * np.nanmax(np.abs(snapshot))
    with pytest.raises(ValueError, match="snapshot 5 out of range: the run has 1"):
        plot_face(result, snapshot=5)


def test_pressure_in_kilopascals(result):
    fig = plot_pressure(result)
    drawn = _drawn(fig.axes[0])
    mask = result.face_mask
    np.testing.assert_allclose(drawn[mask], result.pressure[mask] / 1e3, rtol=1e-15)
    assert fig.axes[1].get_xlabel() == "pressure (kPa)", "colour bar below the wide map"
    normalised = _drawn(plot_pressure(result, units="normalised").axes[0])
    assert np.mean(normalised[mask]) == pytest.approx(1.0, rel=1e-9), "mean pressure 1"


def test_pressure_in_the_unit_asked_for(result):
    """``units="Pa"`` draws pascals (it drew the automatic kPa); other names are refused."""
    mask = result.face_mask
    for units, factor in (("Pa", 1.0), ("MPa", 1e6)):
        fig = plot_pressure(result, units=units)
        np.testing.assert_allclose(_drawn(fig.axes[0])[mask], result.pressure[mask] / factor,
                                   rtol=1e-15)
        assert fig.axes[1].get_xlabel() == f"pressure ({units})"
    with pytest.raises(ValueError, match="pressure units must be 'auto' or one of Pa, kPa, MPa, "
                                         "GPa, got 'bar'"):
        plot_pressure(result, units="bar")


# -- one orientation in the steady and run-in figures ---------------------------------------

def test_steady_and_run_in_faces_drawn_the_same_way(run_file, steady):
    """A block wider along x is drawn wider than tall, x horizontal, in both."""
    run = run_figure(run_file)
    steady = result_figure(steady)
    for fig in (run, steady):
        fig.canvas.draw()
    for ax in (run.axes[3], run.axes[4], steady.axes[1]):
        assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
        assert list(ax.images[0].get_extent()) == pytest.approx([-4.0, 4.0, -2.0, 2.0])
        box = ax.get_window_extent()
        assert box.width == pytest.approx(2 * box.height, rel=0.02), (box.width, box.height)


def test_plot_run_writes_a_png(tmp_path, run_file):
    png = plot_run(run_file, tmp_path / "run.png", dpi=40)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match=r"exists \(pass force=True to overwrite\)"):
        plot_run(run_file, png, force=False)


def test_a_figure_for_a_paper(result):
    # The distance axis ends with the data; the title carries no solver counts; a snapshot
    # says where it was taken.
    fig = plot_history(result)
    last = float(result.history["distance"][-1])
    assert fig.axes[0].get_xlim()[1] <= 1.3 * last, (fig.axes[0].get_xlim(), last)
    title = run_figure(result)._suptitle.get_text()
    assert "solves" not in title and "steps" not in title, title
    face = plot_face(result, snapshot=0)
    s = float(result.snapshot_distance[0])
    assert face.axes[0].get_title().startswith("face at s = ") and \
        f"{s / result.distance_scale:.3g} s*" in face.axes[0].get_title(), face.axes[0].get_title()


def test_a_steady_pressure_is_drawn_one_colour_per_phase(run_file):
    # The final pressure of a steady run is constant on each phase (eq. 7): the phases'
    # colours of the maps, their pressures in the legend.
    result, _, arrays = read_run(run_file)
    assert result.status == "steady", result.message
    ax = plot_pressure(run_file).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    p0 = float(np.mean(result.pressure[arrays["phase"] == 0]))
    assert labels[0] == f"phase 0: p = {p0 / 1e3:.4g} kPa" and len(labels) == 2, labels
    assert len(np.unique(ax.images[0].get_array().compressed())) == 2, "one colour per phase"
    # A pressure that is not constant on its phases keeps the colour map.
    varied = result.pressure * (1 + 1e-3 * np.arange(result.pressure.size)
                                .reshape(result.pressure.shape))
    path = run_file.parent / "varied.h5"
    write_run(path, dataclasses.replace(result, state=dataclasses.replace(
        result.state, pressure=varied)), arrays={"phase": arrays["phase"]})
    early = plot_pressure(path)
    assert early.axes[0].get_legend() is None and len(early.axes) == 2, "a colour bar"
