"""Figure of a run file: the friction proxy's history beside the final face and pressure.

Reads the HDF5 file written by :func:`transient.output.write_run`, so a
figure can be redrawn without running again.  Uses matplotlib's Agg
canvas directly (no pyplot, no global backend state).
:func:`draw_rms_slope_history` draws the history panel for other figures
too (``studies/runin_history.py``).
"""

from __future__ import annotations

import pathlib

import h5py
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .output import read_run

__all__ = ["draw_rms_slope_history", "extent", "plot_run", "run_figure"]


def _error_band(history, reference):
    """Half-width of the error band: the per-step bar, or the companion run's if larger."""
    error = np.asarray(history.get("rms_slope_error", np.zeros_like(history["distance"])),
                       dtype=float)
    spatial = np.asarray(history.get("rms_slope_spatial_error", ()), dtype=float)
    if spatial.shape == error.shape:
        error = np.fmax(error, spatial)
    return error / reference


def draw_rms_slope_history(ax, history, distance_scale, reference_slope, *, steady=None,
                           color="C0", label="continuum estimate",
                           plain_label="plain pixel value"):
    """The rms slope against the sliding distance, with its error band.

    The distance axis is logarithmic; the value at ``s = 0`` (the initial
    face's own) is drawn at the left edge, labelled ``0``, and joined to the
    first step by a dotted line: the history jumps there (docs/model.md,
    "The run-in history").

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    history : mapping of str to ndarray
        ``distance`` (m), ``rms_slope`` and, when present,
        ``rms_slope_error``, ``rms_slope_spatial_error``, ``rms_slope_plain``
        (:data:`transient.runin.HISTORY_UNITS`).
    distance_scale : float, m
        ``s*``, the unit of the distance axis.
    reference_slope : float
        ``grad_f0``, the unit of the slope axis.
    steady : (float, float), optional
        The steady face's rms slope and its error bar (dimensional), drawn
        as the asymptote.
    color : str, optional
    label : str, optional
    plain_label : str or None, optional
        Legend of the plain pixel value, drawn faintly when the history has
        it (``"_nolegend_"`` to leave it out of the legend, None not to draw
        it).

    Returns
    -------
    float
        The position of the ``s = 0`` point on the axis, in ``s*``.
    """
    s = np.asarray(history["distance"], dtype=float) / distance_scale
    y = np.asarray(history["rms_slope"], dtype=float) / reference_slope
    err = _error_band(history, reference_slope)
    pos = s > 0
    # The last step of a run that reached the steady state is a jump of ~1e8 s*.
    finite_end = s[pos][s[pos] < 1e6] if np.any(pos) else np.array([1.0])
    right = max(100.0, 3 * float(finite_end.max()) if finite_end.size else 100.0)
    left = float(s[pos].min()) / 4 if np.any(pos) else 1e-6
    shown = pos & (s <= right)
    ax.fill_between(s[shown], (y - err)[shown], (y + err)[shown], color=color, alpha=0.25,
                    lw=0)
    ax.semilogx(s[shown], y[shown], "-", color=color, lw=1.2, label=label)
    if plain_label is not None and "rms_slope_plain" in history:
        ax.semilogx(s[shown], np.asarray(history["rms_slope_plain"])[shown] / reference_slope,
                    "-", color=color, lw=0.8, alpha=0.35, label=plain_label)
    if np.any(s == 0) and np.any(pos):
        y0 = float(y[s == 0][0])
        first = int(np.flatnonzero(pos)[0])
        ax.plot([left], [y0], "o", color=color, ms=5, mfc="white", zorder=3)
        ax.plot([left, s[first]], [y0, y[first]], ":", color=color, lw=0.9)
    if steady is not None:
        value, error = (v / reference_slope for v in steady)
        if np.isfinite(error):
            ax.axhspan(value - error, value + error, color="k", alpha=0.08, lw=0)
        ax.axhline(value, color="k", ls="--", lw=0.8,
                   label=f"steady face {value:.4f} $\\pm$ {error:.2g}")
    ax.set_xlim(left / 1.5, right)
    # Powers of ten, every other decade, clear of the "0" at the left edge.
    ticks = [t for t in 10.0 ** np.arange(-12, 13, 2) if 10 * left < t <= right]
    ax.set_xticks([left] + ticks)
    ax.set_xticklabels(["0"] + [f"$10^{{{int(np.log10(t))}}}$" for t in ticks])
    ax.set_xlabel("sliding distance / s*  (s = 0 at the left edge)")
    ax.set_ylabel("rms slope / grad_f0")
    return left


def _comparison(run_path):
    """Attributes of the run file's ``comparison`` group, or an empty dict."""
    with h5py.File(run_path, "r") as f:
        return dict(f["comparison"].attrs) if "comparison" in f else {}


def run_figure(result, attrs, comparison=None):
    """Five-panel figure of a stored run.

    Parameters
    ----------
    result : transient.runin.RunResult
    attrs : mapping
        Root attributes of the run file (``steady_rms_slope``; ``radius``
        when the result carries no outline).
    comparison : mapping, optional
        The run file's ``comparison`` attributes
        (:class:`transient.comparison.SteadyComparison`): the steady face's
        rms slope and rms height with their error bars.

    Returns
    -------
    matplotlib.figure.Figure
        Top: the rms slope (converged estimate with its error band, the
        plain pixel value faint, the steady value as the asymptote), the rms
        height, and the convergence measures against the sliding distance;
        bottom: final face (in ``f*``) and pressure (in the mean pressure),
        axes in mm (in pixels when the run's outline is unknown); a face
        longer along y than along x is drawn lying, y horizontal.
    """
    comparison = comparison or {}
    h = result.history
    g0 = result.reference_slope
    fig = Figure(figsize=(15, 8.5))
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(2, 6)
    ax_slope = fig.add_subplot(grid[0, 0:2])
    ax_height = fig.add_subplot(grid[0, 2:4])
    ax_conv = fig.add_subplot(grid[0, 4:6])
    ax_face = fig.add_subplot(grid[1, 0:3])
    ax_pressure = fig.add_subplot(grid[1, 3:6])
    steady = None
    if "steady_rms_slope" in comparison:
        steady = (comparison["steady_rms_slope"],
                  comparison.get("steady_rms_slope_uncertainty", np.nan))
    elif "steady_rms_slope" in attrs:
        steady = (attrs["steady_rms_slope"], np.nan)
    draw_rms_slope_history(ax_slope, h, result.distance_scale, g0, steady=steady)
    ax_slope.legend(fontsize=8, loc="best")
    ax_slope.set_title(f"{result.scheme}: {result.steps} steps, {result.solves} contact solves",
                       fontsize=10)
    s = h["distance"] / result.distance_scale
    pos = (s > 0) & (s < 1e6)
    outline = _outline(result, attrs)
    scale = np.nan if outline is None else outline.scale
    length = "a" if outline is None or outline.kind == "circle" else "L"
    if "normalised_rms_height" in h:
        ax_height.semilogx(s[pos], h["normalised_rms_height"][pos], "-", color="C2",
                           label="worn face")
        if "steady_rms_height" in comparison:
            ax_height.axhline(comparison["steady_rms_height"] / (g0 * scale), color="k",
                              ls="--", lw=0.8, label="steady face")
        ax_height.legend(fontsize=8, loc="lower right")
    ax_height.set_xlabel("sliding distance / s*")
    ax_height.set_ylabel(f"rms height / (grad_f0 {length}), best plane removed")
    a = ax_conv
    a.loglog(s[pos], np.maximum(h["spread"][pos], 1e-17), ".-", ms=2, label="wear-rate spread")
    a.loglog(s[pos], np.maximum(h["shape_rate"][pos], 1e-17), ".-", ms=2,
             label="shape change (f* per s*)")
    a.set_xlabel("sliding distance / s*")
    a.legend(fontsize=8)
    a.set_title(f"status: {result.status}", fontsize=10)
    nx, ny = result.height.shape
    ext, unit = extent(result.height.shape, outline)
    # Arrays are indexed [x, y]; imshow wants [row, column]: x along the
    # horizontal axis, unless the face is taller than wide (ny > nx), which
    # is drawn lying down, its long side y horizontal, to fill the panel.
    lying = ny > nx
    if lying:
        ext = ext[2:] + ext[:2]

    def show(ax, field):
        return ax.imshow(field if lying else field.T, origin="lower", extent=ext)

    # A wide image gets a colour bar of its own height (the default spans the axes).
    ratio = (ext[3] - ext[2]) / (ext[1] - ext[0])
    bar = {"fraction": 0.046 * ratio, "pad": 0.04} if ratio < 0.9 else {}

    face = result.face - np.nanmin(result.face)
    im = show(ax_face, face / result.depth_scale)
    fig.colorbar(im, ax=ax_face, label="face height / f*", **bar)
    grid = f"n = {nx}" if nx == ny else f"n = {max(nx, ny)}, {nx} x {ny} pixels"
    described = "" if outline is None else f"{outline.describe()}, "
    ax_face.set_title(f"final face ({described}{grid})", fontsize=10)
    pr = np.where(result.face_mask, result.pressure / result.pixel_mean_pressure, np.nan)
    im = show(ax_pressure, pr)
    fig.colorbar(im, ax=ax_pressure, label="pressure / pbar", **bar)
    ax_pressure.set_title("final pressure", fontsize=10)
    for a in (ax_face, ax_pressure):
        a.set_xlabel(f"{'y' if lying else 'x'} ({unit})")
        a.set_ylabel(f"{'x' if lying else 'y'} ({unit})")
    fig.tight_layout()
    return fig


def _outline(result, attrs):
    """The run's outline: the result's, else the disk of the file's ``radius``, else None."""
    if result.outline is not None:
        return result.outline
    radius = attrs.get("radius")
    if isinstance(radius, (int, float, np.number)) and np.isfinite(radius) and radius > 0:
        from steady.outline import Circle

        return Circle(float(radius))
    return None


def extent(shape, outline):
    """``imshow`` extent of a grid and its unit: the bounding box in mm, else pixels.

    Parameters
    ----------
    shape : (int, int)
        ``(nx, ny)`` of the grid.
    outline : outline object or None
        The grid's outline (:mod:`steady.outline`), which sets the pixel
        size ``h = 2 L / n`` (``n`` the longer side); None: pixel units.

    Returns
    -------
    extent : list of float
        ``[x0, x1, y0, y1]``: the grid's box centred on the origin.
    unit : str
        ``"mm"`` or ``"pixels"``.
    """
    nx, ny = shape
    if outline is None:
        return [-0.5 * nx, 0.5 * nx, -0.5 * ny, 0.5 * ny], "pixels"
    h_mm = 2e3 * outline.scale / max(nx, ny)
    return [-0.5 * nx * h_mm, 0.5 * nx * h_mm, -0.5 * ny * h_mm, 0.5 * ny * h_mm], "mm"


def plot_run(run_path, png_path):
    """Draw a run file into a PNG.

    Parameters
    ----------
    run_path : str or path-like
        HDF5 file of ``python -m transient``.
    png_path : str or path-like

    Returns
    -------
    pathlib.Path
        The PNG written.
    """
    result, attrs, _ = read_run(run_path)
    png_path = pathlib.Path(png_path)
    run_figure(result, attrs, _comparison(run_path)).savefig(png_path, dpi=100)
    return png_path
