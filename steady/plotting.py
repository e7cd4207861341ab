"""Figure of a steady result: phase map beside the limiting worn face (paper Figure 3).

Each ``plot_*`` function takes a result file (written by
:func:`steady.output.write_result`), a :class:`steady.output.StoredResult`
or a :class:`steady.solution.SteadyResult`, draws into the axes given as
``ax=`` (or a new figure) and returns the :class:`~matplotlib.figure.Figure`;
:func:`plot_file` writes the two-panel figure of a file into a PNG (the
``--plot`` of ``runin-steady``); :func:`segmentation_figure` draws the
segmentation of a micrograph phase map over its image, with the grey-level
histogram (the ``--segmentation`` of ``runin-steady``).  Uses matplotlib's
Agg canvas directly (no pyplot, no global backend state), unless the caller
uses pyplot: then they are pyplot's, which ``plt.show()`` shows
(:func:`new_figure`).

One convention for every map here and in :mod:`transient.plotting`: arrays
are indexed ``[x, y]``, x runs along the horizontal axis and y up
(:func:`draw_map`), lengths in mm from the centre of the grid's box.  The
face is drawn as relief: its height about its least-squares plane (or its
mean) over the face, in micrometres; pressures in Pa, kPa, MPa or GPa,
whichever suits their size.  Figures are sized for print (a column is
:data:`COLUMN_WIDTH` inches wide, a page :data:`PAGE_WIDTH`) with fonts of
:data:`FONT_SIZES` points.
"""

from __future__ import annotations

import logging
import os
import pathlib
import sys

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.transforms import offset_copy

from .micrograph import Micrograph
from .output import read_result
from .problem import default_phase_names
from .relief import PlaneFit
from .text import shorten

__all__ = ["COLUMN_WIDTH", "FONT_SIZES", "PAGE_WIDTH", "colour_bar", "default_removal",
           "draw_map", "figure_and_axes",
           "grid_extent", "map_height", "new_figure", "phase_colours", "plot_face", "plot_file",
           "plot_phases", "pressure_scale", "pressure_unit", "relief", "result_figure",
           "root_figure", "save_figure", "save_new", "segmentation_figure", "set_fonts"]

logger = logging.getLogger(__name__)

#: Width of a journal column and of a page, inches.
COLUMN_WIDTH = 3.5
PAGE_WIDTH = 7.2

#: Font sizes in points, at the figure's printed size.
FONT_SIZES = {"label": 10, "tick": 9, "legend": 8.5, "title": 10}

# Light matrix, dark inclusions, as in the paper's Fig. 3a; more phases get
# further distinct colours.
_PHASE_COLOURS = ["#bdbdbd", "#252525", "#d95f02", "#1b9e77", "#7570b3", "#e7298a",
                  "#66a61e", "#e6ab02"]

_RELIEF = {"plane": "about the best-fit plane", "mean": "about the mean"}


def new_figure(width, height):
    """A figure of ``width`` x ``height`` inches, constrained layout.

    Where the caller uses pyplot (it is imported), the figure is pyplot's:
    ``plt.show()`` shows it and a notebook or a sphinx-gallery page keeps it.
    Elsewhere (the commands, which never import pyplot) it is a figure on
    an Agg canvas, with no global state and no display.
    """
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        return pyplot.figure(figsize=(width, height), layout="constrained")
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def root_figure(ax):
    """The figure that holds ``ax``, through any subfigures (matplotlib 3.7 and later)."""
    # Axes.figure is the innermost (sub)figure; a (sub)figure's own .figure is the root.
    return ax.figure.figure


def figure_and_axes(ax, size):
    """``(figure, axes)``: those of ``ax``, or a new figure of ``size`` inches with one axes.

    Parameters
    ----------
    ax : matplotlib.axes.Axes or None
        The caller's axes.
    size : (float, float), inches
        Width and height of the new figure.

    Returns
    -------
    matplotlib.figure.Figure, matplotlib.axes.Axes
    """
    if ax is not None:
        return root_figure(ax), ax
    fig = new_figure(*size)
    return fig, fig.add_subplot()


def set_fonts(*axes):
    """Set the label, tick and title sizes of :data:`FONT_SIZES` on each axes (colour bars too)."""
    for ax in axes:
        ax.tick_params(which="both", labelsize=FONT_SIZES["tick"])
        ax.xaxis.label.set_size(FONT_SIZES["label"])
        ax.yaxis.label.set_size(FONT_SIZES["label"])
        ax.title.set_size(FONT_SIZES["title"])
        legend = ax.get_legend()
        if legend is not None:
            for text in legend.get_texts():
                text.set_fontsize(FONT_SIZES["legend"])


def phase_colours(n_phases):
    """One colour per phase, phase 0 first (light matrix, dark inclusions)."""
    return [_PHASE_COLOURS[i % len(_PHASE_COLOURS)] for i in range(int(n_phases))]


def grid_extent(shape, pixel_size):
    """``imshow`` extent of a grid in mm: its box ``[x0, x1, y0, y1]`` centred on the origin.

    Parameters
    ----------
    shape : (int, int)
        ``(nx, ny)``.
    pixel_size : float, m

    Returns
    -------
    list of float, mm
    """
    nx, ny = shape
    h_mm = 1e3 * float(pixel_size)
    return [-0.5 * nx * h_mm, 0.5 * nx * h_mm, -0.5 * ny * h_mm, 0.5 * ny * h_mm]


def draw_map(ax, field, extent, *, unit="mm", **imshow):
    """Draw a field indexed ``[x, y]`` with x along the horizontal axis and y up.

    The one convention of every map of :mod:`steady.plotting` and
    :mod:`transient.plotting`: ``imshow`` shows ``field.T`` (rows are y)
    with ``origin="lower"``, so that ``field[i, j]`` is drawn at
    ``(x_i, y_j)``, and a face wider along x than along y is drawn wider
    than tall.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    field : ndarray or masked array, shape (nx, ny)
        Masked entries and NaN are drawn in the colour map's "bad" colour.
    extent : sequence of 4 float
        ``[x0, x1, y0, y1]`` of the grid's box (:func:`grid_extent`).
    unit : str, optional
        Unit of the extent, for the axis labels (default ``"mm"``).
    **imshow
        Passed to ``imshow`` (``cmap``, ``norm``, ``vmin``, ...).

    Returns
    -------
    matplotlib.image.AxesImage
    """
    image = ax.imshow(np.asanyarray(field).T, origin="lower", extent=tuple(extent),
                      interpolation="nearest", **imshow)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_aspect("equal")
    return image


def colour_bar(image, label):
    """A colour bar beside a map: on the right, or below a map more than 1.5 times wider than tall.

    Parameters
    ----------
    image : matplotlib.image.AxesImage
        From :func:`draw_map`.
    label : str

    Returns
    -------
    matplotlib.colorbar.Colorbar
        Its axes' fonts set (:func:`set_fonts`).
    """
    x0, x1, y0, y1 = image.get_extent()
    wide = abs(x1 - x0) > 1.5 * abs(y1 - y0)
    bar = image.axes.figure.colorbar(image, ax=image.axes, location="bottom" if wide else "right",
                       shrink=0.9, aspect=30)
    bar.set_label(label)
    set_fonts(bar.ax)
    return bar


def default_removal(outline, remove=None):
    """What a face's relief removes: ``remove`` if given, else by the outline.

    A periodic cell's face has an arbitrary mean and no tilt to level:
    ``"mean"``; any other face (or an unknown outline): ``"plane"``.

    Parameters
    ----------
    outline : outline object or None
    remove : {"plane", "mean"} or None, optional

    Returns
    -------
    str
    """
    if remove is not None:
        return remove
    return "mean" if getattr(outline, "periodic", False) else "plane"


def relief(face, face_mask, pixel_size, *, remove="plane"):
    """The face's height about its least-squares plane or its mean over the face.

    Parameters
    ----------
    face : ndarray, shape (nx, ny), m
        Heights at the pixel centres (values off the face are ignored).
    face_mask : ndarray of bool, shape (nx, ny)
    pixel_size : float, m
        Pixel side (any positive length when only the mean is removed).
    remove : {"plane", "mean"}, optional
        Remove the least-squares plane ``c0 + c1 x + c2 y`` (default; the
        relief of :func:`steady.relief.rms_height`) or only the mean.

    Returns
    -------
    ndarray, shape (nx, ny), m
        Zero mean over the face; NaN off it.

    Raises
    ------
    ValueError
        ``remove`` is neither ``"plane"`` nor ``"mean"``.

    Examples
    --------
    >>> import numpy as np
    >>> mask = np.ones((4, 3), dtype=bool)
    >>> tilted = 2.0 + np.arange(4.0)[:, None] + np.zeros(3)
    >>> print(np.abs(relief(tilted, mask, 1.0)).max() < 1e-12)
    True
    >>> relief(tilted, mask, 1.0, remove="mean")[:, 0]
    array([-1.5, -0.5,  0.5,  1.5])
    """
    if remove not in _RELIEF:
        raise ValueError(f"remove must be 'plane' or 'mean', got {remove!r}")
    face_mask = np.asarray(face_mask, dtype=bool)
    face = np.asarray(face, dtype=float)
    out = np.full(face.shape, np.nan)
    if not face_mask.any():
        return out
    if remove == "plane":
        out[face_mask] = PlaneFit(face_mask, pixel_size).residual(face)
    else:
        values = face[face_mask]
        out[face_mask] = values - values.mean()
    return out


def pressure_unit(values):
    """The unit that suits pressures of this size: ``(factor, unit)``, Pa per unit.

    Parameters
    ----------
    values : array_like, Pa
        NaN ignored.

    Returns
    -------
    factor : float
        ``1``, ``1e3``, ``1e6`` or ``1e9``.
    unit : str
        ``"Pa"``, ``"kPa"``, ``"MPa"`` or ``"GPa"``: the largest unit in
        which the largest magnitude is at least 1.

    Examples
    --------
    >>> pressure_unit([2.0e5, 3.5e5])
    (1000.0, 'kPa')
    """
    values = np.abs(np.asarray(values, dtype=float))
    top = float(np.nanmax(values)) if np.any(np.isfinite(values)) else 0.0
    for factor, unit in ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa")):
        if top >= factor:
            return factor, unit
    return 1.0, "Pa"


#: Pa per unit of the pressure units a figure can be asked for.
PRESSURE_UNITS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}


def pressure_scale(values, units="auto"):
    """``(factor, unit)`` of pressures drawn in ``units``: one of :data:`PRESSURE_UNITS` or auto.

    Parameters
    ----------
    values : array_like, Pa
        The pressures (for ``"auto"``).
    units : str, optional
        ``"auto"`` (default): the unit that suits their size
        (:func:`pressure_unit`); else a key of :data:`PRESSURE_UNITS`.

    Returns
    -------
    factor : float
        Pa per unit.
    unit : str

    Raises
    ------
    ValueError
        Another ``units``.

    Examples
    --------
    >>> pressure_scale([2.0e5], "auto"), pressure_scale([2.0e5], "Pa")
    ((1000.0, 'kPa'), (1.0, 'Pa'))
    """
    if units == "auto":
        return pressure_unit(values)
    if units not in PRESSURE_UNITS:
        raise ValueError(f"pressure units must be 'auto' or one of {', '.join(PRESSURE_UNITS)}, "
                         f"got {units!r}")
    return PRESSURE_UNITS[units], units


def _steady(source):
    """``(SteadyResult, phase names)`` of a file, a StoredResult or a SteadyResult.

    The names: those the file stores (:attr:`steady.output.StoredResult.phase_names`),
    else the result's own, else ``"phase 0"``, ...
    """
    if isinstance(source, (str, os.PathLike)):
        source = read_result(source)
    if hasattr(source, "result") and hasattr(source, "scene_text"):
        source, names = source.result, tuple(getattr(source, "phase_names", ()) or ())
    elif hasattr(source, "labels") and hasattr(source, "face"):
        names = tuple(getattr(source, "phase_names", ()) or ())
    else:
        raise ValueError(f"expected a steady result file, StoredResult or SteadyResult, got "
                         f"{type(source).__name__}")
    if len(names) != source.n_phases:
        names = default_phase_names(source.n_phases)
    return source, tuple(str(name) for name in names)


def _phase_names(res, known, names):
    """``names`` checked (one per phase), or the names ``known`` from the result."""
    if names is None:
        return known
    names = tuple(str(name) for name in names)
    if len(names) != res.n_phases:
        raise ValueError(f"names has {len(names)} entries, expected one per phase "
                         f"({res.n_phases})")
    return names


def map_height(shape, width):
    """Height in inches of a map panel ``width`` inches wide for a grid of ``shape``.

    Room for the map at its aspect (within 0.9 to 7 inches), its axis
    labels and title, and a colour bar below a wide map (:func:`colour_bar`).

    Parameters
    ----------
    shape : (int, int)
        ``(nx, ny)`` of the grid.
    width : float, inches

    Returns
    -------
    float, inches
    """
    nx, ny = shape
    below = 0.8 if nx > 1.5 * ny else 0.0
    return float(np.clip(0.75 * width * ny / nx, 0.9, 7.0)) + 0.8 + below


def plot_phases(source, *, ax=None, names=None, details=True):
    """The phase map, with the phase names in the legend.

    Parameters
    ----------
    source : str, path-like, StoredResult or SteadyResult
        A result file of :func:`steady.output.write_result`, or a result.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure a column wide).
    names : sequence of str, optional
        One name per phase, phase 0 first (default: the names the file
        stores, else the result's own, else ``"phase 0"``, ...).
    details : bool, optional
        Add each phase's wear coefficient, area fraction and steady
        pressure (eq. 7) to its legend entry (default True).

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn into; axes in mm, x horizontal, y up.
    """
    res, known = _steady(source)
    names = _phase_names(res, known, names)
    fig, ax = figure_and_axes(ax, (COLUMN_WIDTH, map_height(res.shape, COLUMN_WIDTH) + 0.6))
    colours = phase_colours(res.n_phases)
    cmap = ListedColormap(colours).with_extremes(bad="white")
    norm = BoundaryNorm(np.arange(res.n_phases + 1) - 0.5, res.n_phases)
    draw_map(ax, np.ma.masked_less(res.labels, 0), grid_extent(res.shape, res.pixel_size),
             cmap=cmap, norm=norm)
    labels = list(names)
    if details:
        factor, unit = pressure_unit(res.phase_pressures)
        law = None if res.wear is None else res.wear.factor
        # A law k_i g(p) has a coefficient per phase; m is in its unit when g = p^m.
        m = None if law is None else law.exponent
        k_unit = "" if m is None else " 1/Pa" if m == 1 else f" Pa$^{{-{m:g}}}$"
        k = [""] * res.n_phases if law is None else [
            f"k = {v:.3g}{k_unit}, " for v in law.coefficients]
        labels = [f"{name}: {k_i}{100 * rho:.1f} %, p = {p / factor:.3g} {unit}"
                  for name, k_i, rho, p in zip(names, k, res.fill_factors, res.phase_pressures,
                                               strict=True)]
    handles = [Patch(facecolor=c, edgecolor="0.4", lw=0.5, label=label)
               for c, label in zip(colours, labels, strict=True)]
    # Below the axes, clear of the x tick labels and label whatever the axes' height.
    below = offset_copy(ax.transAxes, fig=fig, y=-3.6 * FONT_SIZES["label"], units="points")
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
              bbox_transform=below, frameon=False, fontsize=FONT_SIZES["legend"])
    set_fonts(ax)
    return fig


def plot_face(source, *, ax=None, remove=None, units="um", cmap="viridis"):
    """The limiting face ``f_inf`` as relief about its mean plane.

    Parameters
    ----------
    source : str, path-like, StoredResult or SteadyResult
        A result file of :func:`steady.output.write_result`, or a result.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure a column wide).
    remove : {"plane", "mean"}, optional
        Draw the height about the face's least-squares plane or about its
        mean (:func:`relief`); the colour bar says which.  Default
        (:func:`default_removal`): the mean on a periodic cell, else the plane.
    units : {"um", "normalised"}, optional
        Heights in micrometres (default) or in ``grad_f0 L`` (eq. 15 over
        ``L``; ``L`` the outline's scale, the radius of a disk).
    cmap : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn into; axes in mm, x horizontal, y up, with a
        colour bar.
    """
    res, _ = _steady(source)
    if units not in ("um", "normalised"):
        raise ValueError(f"units must be 'um' or 'normalised', got {units!r}")
    fig, ax = figure_and_axes(ax, (COLUMN_WIDTH, map_height(res.shape, COLUMN_WIDTH)))
    remove = default_removal(res.outline, remove)
    height = relief(res.face, res.labels >= 0, res.pixel_size, remove=remove)
    if units == "um":
        field, unit = height * 1e6, "µm"
    else:
        field, unit = height / (res.reference_slope * res.scale), r"$\nabla f^0_\infty L$"
    image = draw_map(ax, field, grid_extent(res.shape, res.pixel_size), cmap=cmap)
    colour_bar(image, f"height {_RELIEF[remove]} ({unit})")
    set_fonts(ax)
    return fig


def result_figure(stored, *, axes=None, remove=None, names=None):
    """Two-panel figure of a steady result: phase map beside the face's relief.

    Parameters
    ----------
    stored : str, path-like, StoredResult or SteadyResult
        From :func:`steady.output.read_result`, or a result file.
    axes : sequence of 2 matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure a page wide).
    remove : {"plane", "mean"}, optional
        What the face panel removes from ``f_inf`` (:func:`plot_face`; default
        :func:`default_removal`).
    names : sequence of str, optional
        Phase names (:func:`plot_phases`).

    Returns
    -------
    matplotlib.figure.Figure
        Left: phase map with the phase names; right: the limiting face
        ``f_inf`` about its plane in micrometres, titled with its rms
        slope; a new figure is titled with the outline, load, modulus and
        grid.  Axes in mm, x horizontal, y up.

    Examples
    --------
    A block twice as long along x as along y is drawn wider than tall:

    >>> from steady import FacePhases, Problem, Rectangle, Voronoi, solve
    >>> grid = Rectangle(8e-3, 4e-3).grid(48)
    >>> phases = FacePhases(grid, Voronoi(40, (0.5, 0.5), seed=2024).labels(grid), 2)
    >>> result = solve(Problem(phases, [1e-13, 1e-12], 4.0, 1.3e6))
    >>> fig = result_figure(result)
    >>> [ax.get_xlabel() for ax in fig.axes[:2]]
    ['x (mm)', 'x (mm)']
    >>> fig.axes[1].images[0].get_extent()
    [-4.0, 4.0, -2.0, 2.0]
    """
    res, known = _steady(stored)
    own = axes is None
    if own:
        fig = new_figure(PAGE_WIDTH, map_height(res.shape, 0.5 * PAGE_WIDTH) + 0.9)
        axes = fig.subplots(1, 2)
    else:
        fig = root_figure(axes[0])
    ax_phase, ax_face = axes
    plot_phases(res, ax=ax_phase, names=_phase_names(res, known, names))
    plot_face(res, ax=ax_face, remove=remove)
    ax_phase.set_title("phase map")
    error = (f" ± {res.rms_slope_error / res.reference_slope:.1g}"
             if np.isfinite(res.rms_slope_error) else "")
    if np.isfinite(res.rms_slope):
        ax_face.set_title(f"limiting face, rms slope {res.rms_slope:.3g}\n"
                          f"= ({res.normalised_rms_slope:.4g}{error}) " r"$\nabla f^0_\infty$")
    else:  # the face alone (--no-slope-error): the plain pixel value, named so
        ax_face.set_title(f"limiting face, plain pixel rms slope {res.rms_slope_plain:.3g}\n"
                          f"(no corrected estimate computed)")
    if own:  # a title of the inputs on a figure of ours, not on the caller's
        fig.suptitle(f"{res.outline.describe()}, F = {res.normal_force:.3g} N, "
                     f"E* = {res.E_star / 1e6:.3g} MPa, n = {res.n}",
                     fontsize=FONT_SIZES["title"])
    set_fonts(ax_phase, ax_face)
    return fig


def plot_file(result_path, png_path, *, force=False, dpi=200):
    """Draw the figure of an HDF5 result (:func:`result_figure`) into a PNG file.

    Parameters
    ----------
    result_path : str or path-like
        File written by :func:`steady.output.write_result`.
    png_path : str or path-like
        Output image; missing parent directories are created.
    force : bool, optional
        Overwrite an existing image (default False).
    dpi : int, optional
        Resolution (default 200 dots per inch of the printed size).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        Unreadable result file, or ``png_path`` exists and ``force`` is
        False.
    """
    return save_new(result_figure(read_result(result_path)), png_path, force=force, dpi=dpi)


def save_new(fig, path, **options):
    """:func:`save_figure` of a figure a ``plot_*`` function made for it, then released.

    A figure made for a file only is closed once written, where it is
    pyplot's (:func:`new_figure`): it is not left open for ``plt.show()``.
    """
    try:
        return save_figure(fig, path, **options)
    finally:
        pyplot = sys.modules.get("matplotlib.pyplot")
        if pyplot is not None:
            pyplot.close(fig)


def save_figure(fig, png_path, *, force=False, dpi=200):
    """Write a figure to a file, creating missing parent directories.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    png_path : str or path-like
        The file; its suffix gives the format (``.png``, or ``.pdf`` and
        ``.svg`` for vector figures).
    force : bool, optional
        Overwrite an existing image (default False).
    dpi : int, optional
        Resolution (default 200).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``png_path`` exists and ``force`` is False.
    """
    png_path = pathlib.Path(png_path)
    if png_path.exists() and not force:
        raise ValueError(f"output {str(png_path)!r} exists (pass force=True to overwrite)")
    png_path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png_path, dpi=dpi)
    logger.info("figure written to %s", png_path)
    return png_path


# -- the segmentation of a micrograph -------------------------------------------------
#: Translucent colours of phases 1, 2, ... over the image (phase 0 is left
#: clear, so the image shows through), and of phase 0 in the histogram.
_OVERLAY_COLOURS = ("#e6194b", "#4363d8", "#3cb44b", "#f58231", "#911eb4", "#42d4f4",
                    "#f032e6", "#bfef45")
_PHASE0_COLOUR = "#808080"
_OVERLAY_ALPHA = 0.4

#: Largest side, pixels, of the view of a tiled micrograph over the face; a
#: cropped image with a longer side is drawn one pixel in every few.
_TILE_VIEW = 1200
_IMAGE_VIEW = 2048


def _phase_colour(phase):
    return _PHASE0_COLOUR if phase == 0 else _OVERLAY_COLOURS[(phase - 1)
                                                              % len(_OVERLAY_COLOURS)]


def _micrograph_view(geometry):
    """Grey levels, labels and their extent (mm, face coordinates) as the figure shows them.

    A crop shows the whole (cropped) image, one pixel in every
    ``ceil(side / _IMAGE_VIEW)`` each way; a tiling shows the periodic
    image over the face's bounding box, sampled at most :data:`_TILE_VIEW`
    pixels a side.
    """
    seg = geometry.segmentation
    width, height = geometry.extent
    x0, y0 = geometry.offset
    if geometry.cover == "crop":
        extent = np.array([-0.5 * width - x0, 0.5 * width - x0,
                           -0.5 * height - y0, 0.5 * height - y0])
        every = -(-max(seg.shape) // _IMAGE_VIEW)
        return seg.image[::every, ::every], seg.labels[::every, ::every], extent * 1e3
    half_x, half_y = geometry.outline.half_extent
    step = max(geometry.pixel_size, 2.0 * max(half_x, half_y) / _TILE_VIEW)
    x = np.arange(-half_x + 0.5 * step, half_x, step)
    y = np.arange(half_y - 0.5 * step, -half_y, -step)
    n_rows, n_cols = seg.shape
    cols = np.floor((x + x0 + 0.5 * width) / geometry.pixel_size).astype(np.int64) % n_cols
    rows = np.floor((0.5 * height - y - y0) / geometry.pixel_size).astype(np.int64) % n_rows
    extent = np.array([x[0], x[-1], y[-1], y[0]]) + 0.5 * step * np.array([-1, 1, -1, 1])
    index = (rows[:, None], cols[None, :])
    return seg.image[index], seg.labels[index], extent * 1e3


def _draw_image(ax, geometry, names, legend):
    """The image in grey, the phases over it, the face's outline; their legend handles.

    With ``legend`` the legend goes below the axes; otherwise the caller places it.
    """
    seg = geometry.segmentation
    grey, labels, extent = _micrograph_view(geometry)
    ax.imshow(grey, cmap="gray", extent=extent, interpolation="nearest",
              vmin=float(seg.image.min()), vmax=float(seg.image.max()))
    overlay = np.zeros(labels.shape + (4,), dtype=np.uint8)
    for phase in range(1, seg.n_phases):
        rgba = (*to_rgb(_phase_colour(phase)), _OVERLAY_ALPHA)
        overlay[labels == phase] = np.rint(255 * np.asarray(rgba))
    ax.imshow(overlay, extent=extent, interpolation="nearest")
    half_x, half_y = geometry.outline.half_extent
    x = np.linspace(-1.05 * half_x, 1.05 * half_x, 601)
    y = np.linspace(-1.05 * half_y, 1.05 * half_y, 601)
    inside = geometry.outline.covers(x[None, :], y[:, None]).astype(float)
    ax.contour(x * 1e3, y * 1e3, inside, levels=[0.5], colors=["#ffd700"], linewidths=1.5)
    handles = [Patch(facecolor="none" if p == 0 else _phase_colour(p),
                     alpha=1.0 if p == 0 else _OVERLAY_ALPHA, edgecolor="black",
                     label=f"{names[p]}: {100 * seg.fill_factors[p]:.1f} % of the image")
               for p in range(seg.n_phases)]
    handles.append(Line2D([], [], color="#ffd700", linewidth=1.5, label="face"))
    if legend:
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12),
                  ncols=min(len(handles), 3), fontsize="small", frameon=False)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    thresholds = ", ".join(f"{t:.4g}" for t in seg.thresholds)
    ax.set_title(f"{seg.n_phases} phases, threshold{'s' if len(seg.thresholds) > 1 else ''} "
                 f"{thresholds} ({seg.method})")
    return handles


def _draw_histogram(ax, geometry):
    """Histogram of the grey levels thresholded, coloured by phase, the thresholds marked."""
    seg = geometry.segmentation
    counts, edges = seg.histogram()
    centres = 0.5 * (edges[1:] + edges[:-1])
    colours = [_phase_colour(p) for p in np.digitize(centres, seg.thresholds)]
    ax.bar(centres, np.maximum(counts, 0.5), width=edges[1] - edges[0], color=colours,
           log=True, linewidth=0)
    for i, t in enumerate(seg.thresholds):
        ax.axvline(t, color="black", linestyle="--", linewidth=1.0,
                   label=f"threshold {i}: {t:.4g}")
    ax.legend(fontsize="small", frameon=False)
    png = geometry.source.lower().endswith(".png")
    ax.set_xlabel("grey level" + (" (fraction of full scale)" if png else ""))
    ax.set_ylabel("pixels")
    ax.set_ylim(bottom=0.5)
    smoothed = f" (smoothed, sigma {seg.smoothing:g} px)" if seg.smoothing else ""
    ax.set_title(f"grey levels thresholded{smoothed}")


def segmentation_figure(geometry, *, ax=None, names=None):
    """The segmentation of a micrograph drawn over the image, and its histogram.

    Parameters
    ----------
    geometry : steady.micrograph.Micrograph
        A segmented micrograph placed on the face
        (:func:`steady.micrograph.load_micrograph`).
    ax : matplotlib Axes or (Axes, Axes), optional
        Where to draw: one Axes for the image alone, a pair for the image
        and the histogram.  Default: a new figure with both panels.
    names : sequence of str, optional
        Names of the phases for the legend (default ``"phase 0"``, ...).

    Returns
    -------
    matplotlib.figure.Figure
        The image panel shows the (cropped) image in grey with phases 1,
        2, ... coloured translucently over it and the face's outline (x and
        y in mm, the face's coordinates; a tiled image is shown tiled over
        the face's bounding box); its title gives the thresholds.  The
        histogram panel shows the grey levels that were thresholded (after
        the smoothing), coloured by phase, with the thresholds as dashed
        lines.

    Raises
    ------
    ValueError
        ``geometry`` is not a micrograph, its segmentation keeps
        no image, ``ax`` is neither an Axes nor a pair of them, or
        ``names`` does not name every phase.

    Examples
    --------
    >>> import numpy as np
    >>> from steady.micrograph import Micrograph, segment
    >>> image = np.full((60, 60), 0.5)
    >>> image[20:40, 20:40], image[25:35, 25:35] = 1.0, 0.0     # a rim around a dark core
    >>> seg = segment(image, 2, thresholds=[0.75], fill_holes=True)
    >>> fig = segmentation_figure(Micrograph(seg, 1e-3))        # image spans the 2 mm face
    >>> [a.get_title() for a in fig.axes]
    ['2 phases, threshold 0.75 (manual)', 'grey levels thresholded']
    """
    if not isinstance(geometry, Micrograph):
        raise ValueError(f"geometry must be a Micrograph, got {shorten(geometry)}")
    seg = geometry.segmentation
    if seg.image is None:
        raise ValueError("the segmentation keeps no image to draw (made by segment() or "
                         "load_micrograph(), it does)")
    if names is None:
        names = [f"phase {p}" for p in range(seg.n_phases)]
    elif isinstance(names, str) or len(names) != seg.n_phases:
        raise ValueError(f"names must name the {seg.n_phases} phases, got {shorten(names)}")
    if ax is None:
        fig = new_figure(11.0, 5.2)
        image_ax, hist_ax = fig.subplots(1, 2, width_ratios=(3, 2))
        fig.suptitle(_figure_title(geometry))
    elif isinstance(ax, Axes):
        image_ax, hist_ax = ax, None
    elif (isinstance(ax, (tuple, list, np.ndarray)) and np.size(ax) == 2
          and all(isinstance(a, Axes) for a in np.ravel(ax))):
        image_ax, hist_ax = np.ravel(ax)
    else:
        raise ValueError(f"ax must be a matplotlib Axes or a pair of them, got {shorten(ax)}")
    handles = _draw_image(image_ax, geometry, names, legend=ax is not None)
    if ax is None:  # the figure's own: a legend the layout makes room for
        fig.legend(handles=handles, loc="outside lower left", ncols=min(len(handles), 4),
                   fontsize="small", frameon=False)
    if hist_ax is not None:
        _draw_histogram(hist_ax, geometry)
    return image_ax.figure


def _figure_title(geometry):
    """The source, the crop, the smoothing, the holes and the placement in a line."""
    seg = geometry.segmentation
    words = [pathlib.Path(geometry.source).name]
    if seg.crop is not None:
        (r0, r1), (c0, c1) = seg.crop
        words.append(f"rows {r0}:{r1}, columns {c0}:{c1}")
    if seg.fill_phases:
        words.append(f"{seg.holes} holes filled")
    if seg.specks:
        words.append(f"{seg.specks} specks relabelled")
    words.append(f"pixel {geometry.pixel_size * 1e6:.4g} µm, cover {geometry.cover}")
    return ", ".join(words)
