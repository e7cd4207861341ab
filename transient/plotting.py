"""Figures of a run: the rms slope's history, the worn face as relief and its pressure.

Each ``plot_*`` function takes a run file (written by
:func:`transient.output.write_run`) or a :class:`transient.result.RunResult`,
draws into the axes given as ``ax=`` (or a new figure) and returns the
:class:`~matplotlib.figure.Figure`::

    from transient.plotting import plot_history
    plot_history("run.h5", units="m").savefig("history.png")

:func:`run_figure` puts them together, and :func:`plot_run` writes that
figure into a PNG (the ``--plot`` of ``runin-transient``).  Distances are
in metres with ``s*`` on a secondary axis (or the other way round), the
face is relief about its plane in micrometres, pressures in kPa or MPa,
lengths in mm; every map follows :func:`steady.plotting.draw_map` (x
horizontal, y up), as the steady figures do.  Uses matplotlib's Agg
canvas directly (no pyplot, no global backend state), or pyplot's where the
caller uses pyplot (:func:`steady.plotting.new_figure`).
:func:`draw_rms_slope_history` draws the history panel for other figures
too (``studies/runin_history.py``).
"""

from __future__ import annotations

import dataclasses
import math
import os

import h5py
import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.patches import Patch
from matplotlib.ticker import NullLocator
from matplotlib.transforms import offset_copy

from steady.output import read_values
from steady.plotting import (
    COLUMN_WIDTH,
    FONT_SIZES,
    PAGE_WIDTH,
    colour_bar,
    default_removal,
    draw_map,
    figure_and_axes,
    map_height,
    new_figure,
    phase_colours,
    pressure_scale,
    relief,
    root_figure,
    save_new,
    set_fonts,
)

from .output import read_run
from .result import rms_slope_uncertainty

__all__ = ["RUN_IN_WITHIN", "add_distance_axis", "distance_scale", "draw_rms_slope_history",
           "extent", "format_metres", "plot_face", "plot_history", "plot_pressure", "plot_run",
           "run_figure", "run_in_distance_of"]

#: The tolerance of the run-in distance marked on the history: the distance
#: after which the run stays within 1 % of the steady state.
RUN_IN_WITHIN = 0.01

# Histories whose last step jumped to "infinity" when the steady state was
# reached: points beyond this many s* are not drawn.
_JUMP = 1e6


def _error_band(history, reference):
    """Half-width of the error band: :func:`transient.result.rms_slope_uncertainty`."""
    return rms_slope_uncertainty(history) / reference


def _check_units(units):
    if units not in ("m", "s*"):
        raise ValueError(f"units must be 'm' or 's*', got {units!r}")


def _distance_ticks(left, right):
    """Powers of ten between ``10 left`` and ``right``: every decade, every other when many."""
    low, high = math.floor(math.log10(10 * left)), math.ceil(math.log10(right))
    step = 1 if high - low <= 6 else 2
    ticks = [10.0 ** k for k in range(low - low % step, high + 1, step)]
    return [t for t in ticks if 10 * left < t <= right * (1 + 1e-12)]


def draw_rms_slope_history(ax, history, distance_scale, reference_slope, *, steady=None,
                           color="C0", label="continuum estimate",
                           plain_label="plain pixel value", units="s*"):
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
        (:data:`transient.result.HISTORY_UNITS`).
    distance_scale : float, m
        ``s*``, the distance scale of the run.
    reference_slope : float
        The unit of the slope axis: ``grad_f0`` for the normalised rms
        slope, 1 for the rms slope itself.
    steady : (float, float), optional
        The steady face's rms slope and its error bar (dimensional), drawn
        as the asymptote.
    color : str, optional
    label : str, optional
    plain_label : str or None, optional
        Legend of the plain pixel value, drawn faintly when the history has
        it (``"_nolegend_"`` to leave it out of the legend, None not to draw
        it).
    units : {"s*", "m"}, optional
        Distance axis in ``s*`` (default) or in metres.

    Returns
    -------
    float
        The position of the ``s = 0`` point on the axis, in ``units``.
    """
    _check_units(units)
    scale = 1.0 if units == "s*" else float(distance_scale)
    s = np.asarray(history["distance"], dtype=float) / distance_scale
    y = np.asarray(history["rms_slope"], dtype=float) / reference_slope
    err = _error_band(history, reference_slope)
    pos = s > 0
    finite_end = s[pos & (s < _JUMP)]
    # The axis ends with the data (a little beyond its last point).
    right = 1.25 * float(finite_end.max()) if finite_end.size else 1.0
    left = float(s[pos].min()) / 4 if np.any(pos) else 1e-6
    shown = pos & (s <= right)
    x = s * scale
    ax.fill_between(x[shown], (y - err)[shown], (y + err)[shown], color=color, alpha=0.25,
                    lw=0)
    ax.semilogx(x[shown], y[shown], "-", color=color, lw=1.4, label=label)
    if plain_label is not None and "rms_slope_plain" in history:
        ax.semilogx(x[shown], np.asarray(history["rms_slope_plain"])[shown] / reference_slope,
                    "-", color=color, lw=0.9, alpha=0.35, label=plain_label)
    if np.any(s == 0) and np.any(pos):
        y0 = float(y[s == 0][0])
        first = int(np.flatnonzero(pos)[0])
        ax.plot([left * scale], [y0], "o", color=color, ms=5, mfc="white", zorder=3)
        ax.plot([left * scale, x[first]], [y0, y[first]], ":", color=color, lw=0.9)
    if steady is not None:
        value, error = (v / reference_slope for v in steady)
        if np.isfinite(error):
            ax.axhspan(value - error, value + error, color="k", alpha=0.08, lw=0)
        shown_error = f" $\\pm$ {error:.2g}" if np.isfinite(error) else ""
        ax.axhline(value, color="k", ls="--", lw=0.8,
                   label=f"steady face {value:.4g}{shown_error}")
    left, right = left * scale, right * scale
    ax.set_xlim(left / 1.5, right)
    ticks = _distance_ticks(left, right)
    ax.set_xticks([left] + ticks)
    ax.set_xticklabels(["0"] + [f"$10^{{{round(math.log10(t))}}}$" for t in ticks])
    ax.xaxis.set_minor_locator(NullLocator())
    if units == "s*":
        ax.set_xlabel("sliding distance / s*  (s = 0 at the left edge)")
    else:
        ax.set_xlabel("sliding distance (m)")
    ax.set_ylabel("rms slope / grad_f0" if reference_slope != 1 else "rms slope (rad)")
    return left


def format_metres(value):
    r"""A length in metres as text (mathtext), a power of ten when large or small.

    Examples
    --------
    >>> print(format_metres(46153.8), "|", format_metres(1234.5), "|", format_metres(0.25))
    4.62$\times 10^{4}$ m | 1230 m | 0.25 m
    """
    if 100 <= abs(value) < 1e4:  # three significant figures without an exponent
        return f"{float(f'{value:.3g}'):.0f} m"
    if value == 0 or 1e-3 <= abs(value) < 1e4:
        return f"{value:.3g} m"
    exponent = math.floor(math.log10(abs(value)))
    mantissa = value / 10.0 ** exponent
    if round(mantissa, 2) >= 10:
        mantissa, exponent = mantissa / 10, exponent + 1
    return f"{mantissa:.3g}$\\times 10^{{{exponent}}}$ m"


def add_distance_axis(ax, distance_scale, units="m"):
    """A secondary distance axis on top: ``s*`` over an axis in metres, or the reverse.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes whose x axis is the sliding distance in ``units``.
    distance_scale : float, m
        ``s*``; its value is printed in the secondary axis' label.
    units : {"m", "s*"}, optional
        The unit of ``ax``'s x axis (default ``"m"``).

    Returns
    -------
    matplotlib.axes.Axes
        The secondary axis (``ax.secondary_xaxis``).
    """
    _check_units(units)
    s_star = float(distance_scale)
    if units == "m":
        functions = (lambda s: s / s_star, lambda u: u * s_star)
        label = f"sliding distance / s*  (s* = {format_metres(s_star)})"
    else:
        functions = (lambda u: u * s_star, lambda s: s / s_star)
        label = f"sliding distance (m)  (s* = {format_metres(s_star)})"
    top = ax.secondary_xaxis("top", functions=functions)
    top.set_xlabel(label)
    set_fonts(top)
    return top


@dataclasses.dataclass(frozen=True)
class _Run:
    """A run's result with what its file adds (each empty when absent).

    The root attributes, the ``comparison`` group's attributes and the
    ``run_in_distance`` group's datasets.
    """

    result: object
    attrs: dict
    comparison: dict
    run_in: dict
    phase_names: tuple = ()
    labels: object = None

    @property
    def distance_scale(self):
        """``s*``, m."""
        return distance_scale(self.result)


def _groups(run_path):
    """The run file's ``comparison`` figures and ``run_in_distance`` datasets, or empty."""
    with h5py.File(run_path, "r") as f:
        # Its variables, or its attributes in a file of a layout before 5.
        comparison = read_values(f["comparison"]) if "comparison" in f else {}
        group = f.get("run_in_distance")
        run_in = ({name: ds[()] for name, ds in group.items() if isinstance(ds, h5py.Dataset)}
                  if isinstance(group, h5py.Group) else {})
    return comparison, run_in


def _run(source):
    """The :class:`_Run` of a run file or a RunResult."""
    if isinstance(source, _Run):
        return source
    if isinstance(source, (str, os.PathLike)):
        result, attrs, arrays = read_run(source)
        names = tuple(n.decode() if isinstance(n, bytes) else str(n)
                      for n in np.atleast_1d(arrays.get("phase_name", ())))
        return _Run(result, dict(attrs), *_groups(source), phase_names=names,
                    labels=arrays.get("phase"))
    if hasattr(source, "history") and hasattr(source, "depth_scale"):
        problem = getattr(source, "problem", None)
        return _Run(source, {}, {}, {}, labels=None if problem is None else problem.labels)
    raise ValueError(f"expected a run file or a RunResult, got {type(source).__name__}")


def distance_scale(result):
    """``s* = L / (k_min E*)`` of a run, m (``distance_scale``, formerly ``run_in_distance``)."""
    scale = getattr(result, "distance_scale", None)
    return float(result.run_in_distance if scale is None else scale)


def _steady_slope(attrs, comparison):
    """The steady face's rms slope and its error bar (NaN if unknown), or None."""
    if "steady_rms_slope" in comparison:
        return (float(comparison["steady_rms_slope"]),
                float(comparison.get("steady_rms_slope_uncertainty", np.nan)))
    if "steady_rms_slope" in attrs:
        return float(attrs["steady_rms_slope"]), np.nan
    return None


def run_in_distance_of(source, within=RUN_IN_WITHIN, *, table=None):
    """The run-in distance within ``within`` of the steady state, m, or None.

    From the run file's group ``run_in_distance`` (datasets ``within``,
    ``reached``, ``distance``), else from the result's
    ``run_in_distance(within)`` method where it has one; None when neither
    gives a distance the run reached.

    Parameters
    ----------
    source : str, path-like or RunResult
    within : float, optional
        Relative tolerance (default :data:`RUN_IN_WITHIN`, 1 %).
    table : mapping of str to ndarray, optional
        The group's datasets, in place of the file's.

    Returns
    -------
    float or None, m
    """
    run = _run(source)
    table = run.run_in if table is None else table
    if {"within", "distance"} <= table.keys():
        tolerances = np.atleast_1d(np.asarray(table["within"], dtype=float))
        distances = np.atleast_1d(np.asarray(table["distance"], dtype=float))
        reached = np.atleast_1d(np.asarray(table.get("reached", np.ones_like(distances)),
                                           dtype=float))
        match = np.flatnonzero(np.isclose(tolerances, within, rtol=1e-9, atol=0.0))
        if match.size and reached[match[0]] > 0 and np.isfinite(distances[match[0]]):
            return float(distances[match[0]])
        return None
    method = getattr(run.result, "run_in_distance", None)
    if callable(method):
        try:
            found = method(within)
        except ValueError:
            return None
        if found.reached and math.isfinite(found.distance_m):
            return float(found.distance_m)
    return None


def _distance(run, units):
    """Positive distances before any final jump, in ``units``, and their mask."""
    s = np.asarray(run.result.history["distance"], dtype=float) / run.distance_scale
    pos = (s > 0) & (s < _JUMP)
    return s * (1.0 if units == "s*" else run.distance_scale), pos


def _draw_slope(ax, run, units, normalised):
    result = run.result
    g0 = result.reference_slope if normalised else 1.0
    draw_rms_slope_history(ax, result.history, run.distance_scale, g0,
                           steady=_steady_slope(run.attrs, run.comparison), units=units)
    quasi = result.history.get("quasi_steady_rms_slope")
    if quasi is not None:
        x, pos = _distance(run, units)
        # plot, not semilogx: the axis is logarithmic already, and its ticks are set
        ax.plot(x[pos], np.asarray(quasi, dtype=float)[pos] / g0, "-", color="C3", lw=1.0,
                drawstyle="steps-post", label="quasi-steady face of the section")
    ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$" if normalised else "rms slope (rad)")
    mark = run_in_distance_of(run)
    if mark is not None:
        x = mark / run.distance_scale if units == "s*" else mark
        ax.axvline(x, color="0.3", ls=":", lw=1.0,
                   label=f"run-in distance ({100 * RUN_IN_WITHIN:g} %) {format_metres(mark)}")


def _draw_height(ax, run, units, normalised):
    result, comparison = run.result, run.comparison
    h = result.history
    x, pos = _distance(run, units)
    scale = result.outline.scale if result.outline is not None else math.nan
    if normalised:
        y, unit = np.asarray(h["normalised_rms_height"]), r" / $(\nabla f^0_\infty L)$"
        reference = result.reference_slope * scale
    else:
        y, unit = np.asarray(h["rms_height"]) * 1e6, " (µm)"
        reference = 1e-6
    ax.semilogx(x[pos], y[pos], "-", color="C2", lw=1.4, label="worn face")
    if "steady_rms_height" in comparison and np.isfinite(reference):
        ax.axhline(comparison["steady_rms_height"] / reference, color="k", ls="--", lw=0.8,
                   label="steady face")
    ax.set_ylabel(f"rms height{unit}")
    ax.set_xlabel("sliding distance (m)" if units == "m" else "sliding distance / s*")


def _draw_convergence(ax, run, units, normalised):
    del normalised  # the measures are relative already
    h = run.result.history
    x, pos = _distance(run, units)
    ax.loglog(x[pos], np.maximum(h["spread"][pos], 1e-17), ".-", ms=2,
              label="wear-rate spread")
    ax.loglog(x[pos], np.maximum(h["shape_rate"][pos], 1e-17), ".-", ms=2,
              label="shape change (f* per s*)")
    ax.set_ylabel("convergence measure")
    ax.set_xlabel("sliding distance (m)" if units == "m" else "sliding distance / s*")


def _phase_names(run, n_phases):
    """The run's phase names: its file's, its problem's, or ``phase i``."""
    names = run.phase_names
    problem = getattr(run.result, "problem", None)
    if len(names) != n_phases and problem is not None:
        names = tuple(problem.phase_names)
    if len(names) != n_phases:
        names = tuple(f"phase {i}" for i in range(n_phases))
    return names


def _draw_depth(ax, run, units, normalised):
    """Worn depth (mean, rim, largest; µm, logarithmic) and, right, the section's fractions."""
    del normalised  # depths in µm, fractions in 1
    result = run.result
    h = result.history
    if "phase_fraction" not in h:
        raise ValueError("the run has no depth history (its phase map does not change with "
                         "depth): no depth panel")
    x, pos = _distance(run, units)
    for name, style, label in (("worn_depth_mean", "-", "mean worn depth"),
                               ("worn_depth_rim", "--", "rim"),
                               ("worn_depth_max", ":", "largest")):
        depth = np.asarray(h[name], dtype=float)[pos] * 1e6
        ax.loglog(x[pos], np.where(depth > 0, depth, np.nan), style, color="k", lw=1.2,
                  label=label)
    mean = np.asarray(h["worn_depth_mean"], dtype=float)[pos] * 1e6
    low = float(np.min(mean[mean > 0], initial=math.inf))
    high = float(np.max(np.asarray(h["worn_depth_max"], dtype=float)[pos] * 1e6, initial=0.0))
    if math.isfinite(low) and high > low:  # the depths in the lower part, under the legend
        ax.set_ylim(low / 2, high * (2 * high / low) ** 0.7)
    ax.set_ylabel("worn depth (µm)")
    scale = 1.0 if units == "m" else 1.0 / run.distance_scale
    for found, ls in ((result.coating_worn_through, "-."), (result.coating_gone, (0, (1, 3)))):
        if found.reached and found.distance_m > 0:
            ax.axvline(found.distance_m * scale, color="0.4", ls=ls, lw=1.0,
                       label=found.summary().split(" at s")[0])
    fractions = np.atleast_2d(np.asarray(h["phase_fraction"], dtype=float))
    right = ax.twinx()
    colours = phase_colours(fractions.shape[1])  # each phase in its colour of the maps
    for i, name in enumerate(_phase_names(run, fractions.shape[1])):
        right.semilogx(x[pos], fractions[pos, i], "-", color=colours[i], lw=1.2,
                       drawstyle="steps-post", label=f"{name} (fraction)")
    # Fractions in the lower part, the legend of both axes above them (drawn on top).
    right.set_ylim(-0.02, 1.7)
    right.set_yticks([0.0, 0.25, 0.5, 0.75, 1.0])
    right.set_ylabel("phase fraction of the section")
    handles, labels = ax.get_legend_handles_labels()
    more = right.get_legend_handles_labels()
    right.legend(handles + more[0], labels + more[1], loc="upper left", ncol=2,
                 fontsize=FONT_SIZES["legend"])
    set_fonts(right)
    ax.set_xlabel("sliding distance (m)" if units == "m" else "sliding distance / s*")


#: The panels of :func:`plot_history` by quantity: ``draw(ax, run, units, normalised)``.
_PANELS = {"rms_slope": _draw_slope, "rms_height": _draw_height,
           "convergence": _draw_convergence, "depth": _draw_depth}


def plot_history(source, *, units="m", normalised=True, quantities=("rms_slope",), ax=None,
                 secondary=True, legend=True):
    r"""The rms slope (and other measures) against the sliding distance.

    Parameters
    ----------
    source : str, path-like or RunResult
        A run file of :func:`transient.output.write_run`, or a result.
    units : {"m", "s*"}, optional
        The distance axis in metres (default) or in ``s*``; the other on a
        secondary axis on top, with the value of ``s*`` in its label.
    normalised : bool, optional
        Rms slope in ``grad_f0`` and rms height in ``grad_f0 L`` (default),
        else the rms slope itself and the rms height in micrometres.
    quantities : sequence of str, optional
        Panels, one each, top to bottom: ``"rms_slope"`` (with its error
        band, the plain pixel value, the steady face's value and the run-in
        distance when the file has them), ``"rms_height"`` (about the best
        plane), ``"convergence"`` (the stop test's measures), ``"depth"``
        (a depth run's worn depth and its section's phase fractions).
    ax : matplotlib.axes.Axes or sequence of them, optional
        Axes to draw into, one per quantity (default: a new figure a
        column wide).
    secondary : bool, optional
        Add the secondary distance axis (default True).
    legend : bool, optional

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        Unknown ``units`` or quantity, or not as many axes as quantities.

    Examples
    --------
    >>> from steady import Circle, FacePhases, Problem, Voronoi
    >>> from transient import initial_face
    >>> from transient.problem import WearProblem
    >>> from transient.runin import RunOptions, run_in
    >>> grid = Circle(4e-3).grid(24)
    >>> phases = FacePhases(grid, Voronoi(16, (0.5, 0.5), seed=2024).labels(grid), 2)
    >>> problem = WearProblem(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6))
    >>> result = run_in(problem, initial_face.flat(problem.grid), RunOptions(tol=1e-2))
    >>> fig = plot_history(result, units="m")
    >>> print(fig.axes[0].get_xlabel(), "|", fig.axes[0].child_axes[0].get_xlabel())
    sliding distance (m) | sliding distance / s*  (s* = 3.08$\times 10^{4}$ m)
    """
    _check_units(units)
    quantities = (quantities,) if isinstance(quantities, str) else tuple(quantities)
    unknown = [q for q in quantities if q not in _PANELS]
    if unknown or not quantities:
        raise ValueError(f"unknown quantity {unknown[0] if unknown else quantities!r}: "
                         f"expected some of {', '.join(_PANELS)}")
    run = _run(source)
    if ax is None:
        fig = new_figure(COLUMN_WIDTH, 0.4 + 2.6 * len(quantities))
        axes = list(np.atleast_1d(fig.subplots(len(quantities), 1, sharex=True)))
    else:
        axes = [ax] if hasattr(ax, "plot") else list(ax)
        if len(axes) != len(quantities):
            raise ValueError(f"{len(axes)} axes given for {len(quantities)} quantities")
        fig = root_figure(axes[0])
    for a, quantity in zip(axes, quantities, strict=True):
        _PANELS[quantity](a, run, units, normalised)
        if legend and quantity != "depth":  # the depth panel's legend covers both its axes
            a.legend(loc="best", fontsize=FONT_SIZES["legend"])
        set_fonts(a)
    if ax is None:
        for a in axes[:-1]:
            a.set_xlabel("")
    if secondary:
        add_distance_axis(axes[0], run.distance_scale, units)
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


def plot_face(source, *, ax=None, remove=None, units="um", snapshot=None, cmap="viridis"):
    """The worn face as relief about its plane (or mean), the final one or a snapshot.

    Parameters
    ----------
    source : str, path-like or RunResult
        A run file of :func:`transient.output.write_run`, or a result.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure a column wide).
    remove : {"plane", "mean"}, optional
        Draw the height about the face's least-squares plane or about its
        mean (:func:`steady.plotting.relief`); the colour bar says which.
        Default (:func:`steady.plotting.default_removal`): the mean on a
        periodic cell, else the plane.
    units : {"um", "normalised"}, optional
        Heights in micrometres (default) or in ``f*``, the run's depth
        scale.
    snapshot : int, optional
        Index of a stored snapshot (:attr:`RunResult.snapshot_distance`),
        whose distance titles the axes; default the final face.
    cmap : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Axes in mm (in pixels when the run's outline is unknown), x
        horizontal, y up, as in :mod:`steady.plotting`.
    """
    if units not in ("um", "normalised"):
        raise ValueError(f"units must be 'um' or 'normalised', got {units!r}")
    run = _run(source)
    result = run.result
    fig, ax = figure_and_axes(ax, (COLUMN_WIDTH, map_height(result.shape, COLUMN_WIDTH)))
    outline = _outline(result, run.attrs)
    ext, unit = extent(result.shape, outline)
    h = 2.0 * outline.scale / max(result.shape) if outline is not None else 1.0
    if snapshot is None:
        face = result.face
    else:
        count = len(result.snapshot_distance)
        if not -count <= snapshot < count:
            raise ValueError(f"snapshot {snapshot} out of range: the run has {count}")
        face = -np.asarray(result.snapshot_recession[snapshot], dtype=float)
        s = float(result.snapshot_distance[snapshot])
        ax.set_title(f"face at s = {format_metres(s)} ({s / result.distance_scale:.3g} s*)")
    mask = result.face_mask & np.isfinite(face)
    remove = default_removal(outline, remove)
    height = relief(face, mask, h, remove=remove)
    field, scale = ((height * 1e6, "µm") if units == "um"
                    else (height / result.depth_scale, "f*"))
    image = draw_map(ax, field, ext, unit=unit, cmap=cmap)
    about = "the best-fit plane" if remove == "plane" else "the mean"
    colour_bar(image, f"height about {about} ({scale})")
    set_fonts(ax)
    return fig


def plot_pressure(source, *, ax=None, units="auto", cmap="magma"):
    """The final contact pressure on the face.

    A pressure constant on each phase (the steady state's, eq. 7) is drawn
    with one colour per phase, the colours of the phase maps, and the
    phases' pressures in the legend; any other with the colour map.

    Parameters
    ----------
    source : str, path-like or RunResult
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure a column wide).
    units : {"auto", "Pa", "kPa", "MPa", "GPa", "normalised"}, optional
        ``"auto"`` (default): Pa, kPa, MPa or GPa, whichever suits the
        pressure's size (:func:`steady.plotting.pressure_unit`); a unit
        named: that unit; ``"normalised"``: in the mean pressure over the
        face's pixels.
    cmap : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Axes in mm (pixels when the outline is unknown), x horizontal, y up.
    """
    if units != "normalised":
        pressure_scale((), units)  # refused before the file is read
    run = _run(source)
    result = run.result
    fig, ax = figure_and_axes(ax, (COLUMN_WIDTH, map_height(result.shape, COLUMN_WIDTH)))
    ext, unit = extent(result.shape, _outline(result, run.attrs))
    pressure = np.where(result.face_mask, result.pressure, np.nan)
    if units == "normalised":
        factor, label = result.pixel_mean_pressure, "mean pressure"
    else:
        factor, label = pressure_scale(pressure, units)
    phases = _phase_wise(run, pressure)
    if phases is None:
        image = draw_map(ax, pressure / factor, ext, unit=unit, cmap=cmap)
        colour_bar(image, f"pressure ({label})")
    else:  # constant on each phase (the steady state): one colour per phase, as the maps
        labels, values = phases
        names = _phase_names(run, len(values))
        colours = phase_colours(len(values))
        draw_map(ax, np.ma.masked_less(labels, 0), ext, unit=unit,
                 cmap=ListedColormap(colours).with_extremes(bad="white"),
                 norm=BoundaryNorm(np.arange(len(values) + 1) - 0.5, len(values)))
        handles = [Patch(facecolor=c, edgecolor="0.4", lw=0.5,
                         label=f"{name}: p = {value / factor:.4g} {label}")
                   for c, name, value in zip(colours, names, values, strict=True)
                   if np.isfinite(value)]
        # Below the axes, clear of the x label (as the steady figure's phase legend).
        below = offset_copy(ax.transAxes, fig=fig, y=-3.6 * FONT_SIZES["label"], units="points")
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                  bbox_transform=below, frameon=False, fontsize=FONT_SIZES["legend"],
                  ncol=1)
    set_fonts(ax)
    return fig


def _phase_wise(run, pressure):
    """``(labels, phase pressures)`` when the pressure is constant on each phase, else None.

    Constant to 1e-6 of itself, the steady state's wear-rate spread (eq. 7,
    after a jump to within ``s* / jump`` of it); a phase without a pixel
    has NaN.
    """
    labels = run.labels
    if labels is None or np.shape(labels) != pressure.shape:
        return None
    labels = np.asarray(labels)
    values = []
    for i in range(int(labels.max()) + 1):
        p = pressure[labels == i]
        if p.size and not (np.all(p > 0) and np.ptp(p) <= 1e-6 * p.max()):
            return None
        values.append(float(p.mean()) if p.size else math.nan)
    return labels, values


def run_figure(result, attrs=None, comparison=None, run_in=None, *, units="m",
               normalised=True):
    """Summary figure of a run: histories above, final face and pressure below.

    Parameters
    ----------
    result : transient.result.RunResult or str or path-like
        A result, or a run file (then ``attrs``, ``comparison`` and
        ``run_in`` are read from it).
    attrs : mapping, optional
        Root attributes of the run file (``steady_rms_slope``; ``radius``
        when the result carries no outline).
    comparison : mapping, optional
        The run file's ``comparison`` attributes
        (:class:`transient.comparison.SteadyComparison`): the steady face's
        rms slope and rms height with their error bars.
    run_in : mapping, optional
        The run file's ``run_in_distance`` datasets (``within``,
        ``reached``, ``distance``): the run-in distance marked on the
        history (:func:`run_in_distance_of`).
    units : {"m", "s*"}, optional
        Distance axes in metres (default, ``s*`` on a secondary axis) or
        in ``s*``.
    normalised : bool, optional
        Rms slope and height in ``grad_f0`` and ``grad_f0 L`` (default).

    Returns
    -------
    matplotlib.figure.Figure
        A page wide.  Top: the rms slope (continuum estimate with its
        error band, plain pixel value faint, the steady face's value as
        the asymptote; for a depth run the quasi-steady face's of the
        current section); middle: rms height and the convergence measures,
        and for a depth run the worn depth and the section's phase
        fractions (the coating's distances marked); bottom: the final face
        as relief about its plane (µm) and the final pressure (kPa or
        MPa), axes in mm (pixels when the outline is unknown), x
        horizontal and y up.
    """
    if isinstance(result, (str, os.PathLike)):
        source = _run(result)
    else:
        source = _Run(result, dict(attrs or {}), dict(comparison or {}), dict(run_in or {}))
    result, attrs = source.result, source.attrs
    maps = map_height(result.shape, 0.5 * PAGE_WIDTH)
    depth = "phase_fraction" in result.history
    rows = (2.6, 2.3) + ((2.3,) if depth else ()) + (maps,)
    fig = new_figure(PAGE_WIDTH, sum(rows) + 0.5)
    grid = fig.add_gridspec(len(rows), 2, height_ratios=rows)
    ax_slope = fig.add_subplot(grid[0, :])
    ax_height = fig.add_subplot(grid[1, 0])
    ax_conv = fig.add_subplot(grid[1, 1], sharex=ax_height)
    ax_face = fig.add_subplot(grid[-1, 0])
    ax_pressure = fig.add_subplot(grid[-1, 1], sharex=ax_face, sharey=ax_face)
    plot_history(source, units=units, normalised=normalised, ax=ax_slope)
    if depth:
        ax_depth = fig.add_subplot(grid[2, :])
        plot_history(source, units=units, ax=ax_depth, quantities="depth", secondary=False)
        ax_depth.set_title("worn depth and the section")
    has_height = "rms_height" in result.history and "normalised_rms_height" in result.history
    if has_height:
        plot_history(source, units=units, normalised=normalised, ax=ax_height,
                     quantities="rms_height", secondary=False)
    else:
        ax_height.set_axis_off()
    plot_history(source, units=units, ax=ax_conv, quantities="convergence", secondary=False)
    plot_face(source, ax=ax_face)
    plot_pressure(source, ax=ax_pressure)
    nx, ny = result.shape
    grid_text = f"n = {nx}" if nx == ny else f"{nx} x {ny} pixels"
    outline = _outline(result, attrs)
    described = "" if outline is None else f"{outline.describe()}, "
    fig.suptitle(f"{described}{grid_text}: {result.status}", fontsize=FONT_SIZES["title"])
    for ax, title in ((ax_height, "rms height"), (ax_conv, "convergence"),
                      (ax_face, "final face"), (ax_pressure, "final pressure")):
        ax.set_title(title)
    set_fonts(ax_slope, ax_height, ax_conv, ax_face, ax_pressure)
    return fig


def plot_run(run_path, png_path, *, force=True, dpi=200, units="m"):
    """Draw a run file's :func:`run_figure` into a PNG.

    Parameters
    ----------
    run_path : str or path-like
        HDF5 file of ``runin-transient``.
    png_path : str or path-like
        Output image; missing parent directories are created.
    force : bool, optional
        Replace an existing image (default True: the command checks before
        the run whether it may).
    dpi : int, optional
        Resolution (default 200).
    units : {"m", "s*"}, optional
        Distance axes (:func:`run_figure`).

    Returns
    -------
    pathlib.Path
        The PNG written.

    Raises
    ------
    ValueError
        Unreadable run file, or ``png_path`` exists and ``force`` is False.
    """
    return save_new(run_figure(run_path, units=units), png_path, force=force, dpi=dpi)
