"""Figures of steady results: relief, orientation, units, phase names, drawing into axes.

The map convention (x along the horizontal axis, y up) is checked on the
rendered pixels, not on the arguments given to ``imshow``.
"""

import numpy as np
import pytest
from conftest import GEOMETRIES, problem
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from steady.outline import Circle, Rectangle
from steady.output import read_result, write_result
from steady.plotting import (
    draw_map,
    grid_extent,
    plot_face,
    plot_file,
    plot_phases,
    pressure_unit,
    relief,
    result_figure,
)
from steady.scene import load_scene
from steady.solution import solve, solve_scene

#: A block twice as wide along x as along y.
WIDE = Rectangle(8e-3, 4e-3)


@pytest.fixture(scope="module")
def wide_result():
    return solve(problem(GEOMETRIES["voronoi"], [1e-13, 1e-12], n=40, outline=WIDE))


def _axes_box(fig, ax):
    """Width and height of an axes in display pixels, after drawing."""
    fig.canvas.draw()
    box = ax.get_window_extent()
    return box.width, box.height


# -- relief -----------------------------------------------------------------------------

@pytest.mark.parametrize("n", [31, 32])
@pytest.mark.parametrize("remove", ["plane", "mean"])
def test_relief_has_zero_mean_on_the_face(n, remove):
    res = solve(problem(GEOMETRIES["voronoi"], [1e-13, 1e-12], n=n))
    mask = res.labels >= 0
    r = relief(res.face, mask, res.pixel_size, remove=remove)
    spread = np.ptp(r[mask])
    assert np.all(np.isnan(r[~mask])), "NaN off the face"
    assert abs(r[mask].mean()) < 1e-13 * spread, f"mean {r[mask].mean():.3g} m"
    # The relief differs from the face by a constant (mean) or a plane.
    nx, ny = mask.shape
    x = np.arange(nx)[:, None] + np.zeros(ny)
    y = np.zeros(nx)[:, None] + np.arange(ny)
    design = np.column_stack([np.ones(mask.sum()), x[mask], y[mask]])
    removed = res.face[mask] - r[mask]
    coef, *_ = np.linalg.lstsq(design, removed, rcond=None)
    assert np.abs(design @ coef - removed).max() < 1e-12 * spread, "a plane was removed"
    if remove == "plane":
        # What is left is orthogonal to x and y: no tilt remains.
        for coordinate in (x[mask], y[mask]):
            tilt = np.dot(r[mask], coordinate - coordinate.mean())
            assert abs(tilt) < 1e-10 * spread * np.abs(coordinate).sum(), "tilt left"
    else:
        assert np.ptp(removed) < 1e-15, "only a constant removed"


def test_relief_of_a_tilted_plane_is_zero():
    grid = Circle(4e-3).grid(24)
    plane = 3e-6 + 1e-3 * grid.x[:, None] - 2e-3 * grid.y[None, :]
    r = relief(plane, grid.mask, grid.h)
    assert np.nanmax(np.abs(r)) < 1e-18, f"left {np.nanmax(np.abs(r)):.3g} m"


def test_relief_rejects_an_unknown_choice():
    with pytest.raises(ValueError, match=r"remove must be 'plane' or 'mean', got 'tilt'"):
        relief(np.zeros((4, 4)), np.ones((4, 4), bool), 1.0, remove="tilt")


# -- one orientation for every map ----------------------------------------------------------

@pytest.mark.parametrize("marked", [(1, 4), (6, 1), (7, 4)])
def test_draw_map_puts_field_i_j_at_x_i_y_j(marked):
    """Rendered: the marked pixel's colour lies at its (x, y), x horizontal, y up."""
    nx, ny = 8, 5
    field = np.zeros((nx, ny))
    field[marked] = 1.0
    extent = grid_extent((nx, ny), 1e-3)  # 1 mm pixels
    fig = Figure(figsize=(4, 3), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw_map(ax, field, extent, cmap=ListedColormap(["#00ff00", "#ff0000"]), vmin=0, vmax=1)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    red = (rgba[..., 0] > 200) & (rgba[..., 1] < 60) & (rgba[..., 2] < 60)
    rows, columns = np.nonzero(red)
    assert rows.size > 4, "the marked pixel is drawn"
    # Display coordinates count y from the bottom of the canvas.
    centre = (columns.mean() + 0.5, rgba.shape[0] - rows.mean() - 0.5)
    x, y = ax.transData.inverted().transform(centre)
    expected = (extent[0] + marked[0] + 0.5, extent[2] + marked[1] + 0.5)
    assert (x, y) == pytest.approx(expected, abs=0.1), f"drawn at ({x:.2f}, {y:.2f}) mm"
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (mm)", "y (mm)")


def test_a_face_wider_in_x_is_drawn_wider_than_tall(wide_result):
    assert wide_result.shape == (40, 20), wide_result.shape
    fig = result_figure(wide_result)
    for ax in fig.axes[:2]:
        assert ax.images[0].get_extent() == pytest.approx([-4.0, 4.0, -2.0, 2.0]), "in mm"
        width, height = _axes_box(fig, ax)
        assert width == pytest.approx(2 * height, rel=0.02), f"{width} x {height} pixels"


@pytest.mark.parametrize(("outline", "below"), [(WIDE, True), (Circle(4e-3), False),
                                                (Rectangle(6e-3, 4e-3), False)])
def test_colour_bar_below_a_wide_map_else_beside(outline, below):
    res = solve(problem(GEOMETRIES["voronoi"], [1e-13, 1e-12], n=24, outline=outline))
    fig = plot_face(res)
    fig.canvas.draw()
    face, bar = (ax.get_window_extent() for ax in fig.axes)
    if below:
        assert bar.y1 < face.y0 and bar.width > 5 * bar.height, (face, bar)
    else:
        assert bar.x0 > face.x1 and bar.height > 5 * bar.width, (face, bar)
    assert (fig.axes[1].get_xlabel() if below else fig.axes[1].get_ylabel()) == \
        "height about the best-fit plane (µm)"


# -- units and labels -----------------------------------------------------------------------

def test_face_is_drawn_as_relief_in_micrometres(wide_result):
    fig = plot_face(wide_result)
    ax, bar = fig.axes
    drawn = np.ma.filled(ax.images[0].get_array(), np.nan).T  # back to [x, y]
    mask = wide_result.labels >= 0
    expected = relief(wide_result.face, mask, wide_result.pixel_size) * 1e6
    np.testing.assert_allclose(drawn[mask], expected[mask], rtol=1e-12,
                               err_msg="relief in µm")
    assert abs(np.mean(drawn[mask])) < 1e-9 * np.ptp(drawn[mask]), "zero mean on the face"
    # Below the map, twice as wide as tall.
    assert bar.get_xlabel() == "height about the best-fit plane (µm)"
    mean = plot_face(wide_result, remove="mean").axes[1]
    assert mean.get_xlabel() == "height about the mean (µm)"


def test_face_in_normalised_units(wide_result):
    fig = plot_face(wide_result, units="normalised")
    drawn = np.ma.filled(fig.axes[0].images[0].get_array(), np.nan).T
    mask = wide_result.labels >= 0
    unit = wide_result.reference_slope * wide_result.scale
    expected = relief(wide_result.face, mask, wide_result.pixel_size) / unit
    np.testing.assert_allclose(drawn[mask], expected[mask], rtol=1e-12)
    assert r"$\nabla f^0_\infty L$" in fig.axes[1].get_xlabel()
    with pytest.raises(ValueError, match="units must be 'um' or 'normalised', got 'mm'"):
        plot_face(wide_result, units="mm")


@pytest.mark.parametrize(("values", "expected"), [
    ([3.0, 999.0], (1.0, "Pa")), ([1e3], (1e3, "kPa")), ([2e5, np.nan], (1e3, "kPa")),
    ([-3.2e6], (1e6, "MPa")), ([1.1e9], (1e9, "GPa")), ([np.nan], (1.0, "Pa"))])
def test_pressure_unit(values, expected):
    assert pressure_unit(values) == expected


# -- phase names, axes given ------------------------------------------------------------------

def test_phase_names_of_the_scene_go_with_the_file(tmp_path, scene_file):
    path = scene_file("steady", extra='names = ["epoxy", "bronze"]')
    scene = load_scene(path)
    out = tmp_path / "r.h5"
    write_result(out, solve_scene(scene, face_only=True), scene)
    texts = [t.get_text() for t in plot_phases(out).axes[0].get_legend().get_texts()]
    assert [t.split(":")[0] for t in texts] == ["epoxy", "bronze"], texts
    assert "k = 1e-09 1/Pa" in texts[0], texts[0]
    stored = read_result(out).result
    for text, p in zip(texts, stored.phase_pressures, strict=True):
        assert text.endswith(f"p = {p / 1e3:.3g} kPa"), (text, p)
    plain = plot_phases(read_result(out), details=False, names=["a", "b"])
    assert [t.get_text() for t in plain.axes[0].get_legend().get_texts()] == ["a", "b"]
    with pytest.raises(ValueError, match="names has 1 entries, expected one per phase"):
        plot_phases(out, names=["a"])


def test_phase_names_stored_in_the_file(tmp_path, wide_result):
    out = tmp_path / "r.h5"
    write_result(out, wide_result, phase_names=["rubber", "silica"])
    ax = plot_phases(out, details=False).axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["rubber", "silica"]


def test_phases_numbered_from_zero_without_names(wide_result):
    ax = plot_phases(wide_result, details=False).axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts == ["phase 0", "phase 1"]
    disk = solve(problem(GEOMETRIES["voronoi"], [1e-13, 1e-12], n=24))
    drawn = plot_phases(disk).axes[0].images[0].get_array()
    assert (disk.labels < 0).any()
    np.testing.assert_array_equal(np.ma.getmaskarray(drawn).T, disk.labels < 0,
                                  err_msg="off the face masked (drawn white)")


def test_functions_draw_into_given_axes(wide_result):
    fig = Figure()
    FigureCanvasAgg(fig)
    left, middle, right = fig.subplots(1, 3)
    assert plot_face(wide_result, ax=left) is fig
    assert plot_phases(wide_result, ax=middle) is fig
    assert len(left.images) == 1 and len(middle.images) == 1 and not right.images
    a, b = Figure().subplots(1, 2)
    assert result_figure(wide_result, axes=(a, b)) is a.get_figure()
    assert a.get_title() == "phase map" and "rms slope" in b.get_title()
    assert a.get_figure().get_suptitle() == "", "the caller's figure keeps its title"


def test_plot_file_writes_the_figure(tmp_path, wide_result):
    out = tmp_path / "r.h5"
    write_result(out, wide_result)
    png = plot_file(out, tmp_path / "fig" / "r.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "a PNG"
    with pytest.raises(ValueError, match=r"exists \(pass force=True to overwrite\)"):
        plot_file(out, png)
    assert plot_file(out, png, force=True) == png


def test_fit_figure_draws_relief_not_the_dome(tmp_path, scene_file):
    """Measured and fitted faces about the fitted face's plane: zero mean, not the dome's height."""
    from steady import MeasuredFace, fit_scene
    from steady.fit_files import fit_figure, read_fit, write_fit

    scene = load_scene(scene_file("steady"))
    face = solve_scene(scene, face_only=True).face
    measured = MeasuredFace(face, scene.grid(scene.n).h)
    stored = read_fit(write_fit(tmp_path / "fit.h5", fit_scene(scene, measured), scene))
    fig = fit_figure(stored)
    drawn = [np.ma.filled(ax.images[0].get_array(), np.nan).T for ax in fig.axes[:2]]
    for field in drawn:
        values = field[np.isfinite(field)]
        assert abs(values.mean()) < 1e-9 * np.ptp(values), "zero mean over the face"
    np.testing.assert_allclose(drawn[0], drawn[1], atol=1e-6 * np.nanmax(np.abs(drawn[1])),
                               err_msg="an exact face is fitted exactly")
    bars = [ax.get_ylabel() for ax in fig.axes[3:]]
    assert bars == ["height about plane (µm)", "residual (µm)"], bars


def test_drawn_into_a_subfigure_returns_the_whole_figure(wide_result):
    fig = Figure()
    FigureCanvasAgg(fig)
    left, _ = fig.subfigures(1, 2)
    assert plot_face(wide_result, ax=left.add_subplot()) is fig, "the root figure"
    assert len(left.axes) == 2, "the map and its colour bar in the subfigure"
    fig.canvas.draw()
