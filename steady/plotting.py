"""Figure of a steady result: phase map beside the limiting worn face (paper Figure 3).

Reads the HDF5 file written by :func:`steady.output.write_result`, so a
figure can be redrawn without solving again.  Uses matplotlib's Agg canvas
directly (no pyplot, no global backend state).
"""

from __future__ import annotations

import logging
import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from .output import read_result

__all__ = ["plot_file", "result_figure"]

logger = logging.getLogger(__name__)

# Light matrix, dark inclusions, as in the paper's Fig. 3a; more phases get
# further distinct colours.
_PHASE_COLOURS = ["#bdbdbd", "#252525", "#d95f02", "#1b9e77", "#7570b3", "#e7298a",
                  "#66a61e", "#e6ab02"]


def result_figure(stored):
    """Two-panel figure of a stored steady result.

    Parameters
    ----------
    stored : StoredResult
        From :func:`steady.output.read_result`.

    Returns
    -------
    matplotlib.figure.Figure
        Left: phase map; right: limiting face ``f_inf`` in micrometres.
        Axes in mm.
    """
    res = stored.result
    nx, ny = res.shape
    hx_mm, hy_mm = 0.5 * nx * res.pixel_size * 1e3, 0.5 * ny * res.pixel_size * 1e3
    extent = (-hx_mm, hx_mm, -hy_mm, hy_mm)
    n_phases = res.n_phases
    colours = [_PHASE_COLOURS[i % len(_PHASE_COLOURS)] for i in range(n_phases)]
    cmap = ListedColormap(colours).with_extremes(bad="white")
    norm = BoundaryNorm(np.arange(n_phases + 1) - 0.5, n_phases)
    phase = np.ma.masked_less(res.labels, 0)

    # Wide faces side by side; tall ones too, at a height that keeps them legible.
    fig = Figure(figsize=(10.5, 4.6 if nx >= ny else min(9.0, 3.2 + 1.6 * ny / nx)),
                 layout="constrained")
    FigureCanvasAgg(fig)
    ax_phase, ax_face = fig.subplots(1, 2)
    # Arrays are indexed [x, y]; imshow wants [row = y, column = x].
    im = ax_phase.imshow(phase.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                         interpolation="nearest")
    cb = fig.colorbar(im, ax=ax_phase, ticks=np.arange(n_phases), shrink=0.85)
    cb.set_ticklabels([f"phase {i}\nk = {k:.3g} 1/Pa\narea {100 * rho:.1f} %"
                       for i, (k, rho) in enumerate(zip(res.wear_coefficients,
                                                        res.fill_factors, strict=True))])
    ax_phase.set_title("phase map")

    face_um = res.face * 1e6
    im = ax_face.imshow(face_um.T, origin="lower", extent=extent, cmap="viridis",
                        interpolation="nearest")
    cb = fig.colorbar(im, ax=ax_face, shrink=0.85)
    cb.set_label(r"limiting face $f_\infty$ (µm)")
    error = (f" ± {res.rms_slope_error / res.reference_slope:.1g}"
             if np.isfinite(res.rms_slope_error) else "")
    ax_face.set_title(f"rms slope {res.rms_slope:.4g} = ({res.normalised_rms_slope:.4g}{error}) "
                      r"$\nabla f_\infty^0$")
    for ax in (ax_phase, ax_face):
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_aspect("equal")
    fig.suptitle(f"{res.outline.describe()}, F = {res.normal_force:.3g} N, "
                 f"E* = {res.E_star / 1e6:.3g} MPa, n = {res.n}")
    return fig


def plot_file(result_path, png_path, *, force=False, dpi=120):
    """Draw the figure of an HDF5 result into a PNG file.

    Parameters
    ----------
    result_path : str or path-like
        File written by :func:`steady.output.write_result`.
    png_path : str or path-like
        Output image; missing parent directories are created.
    force : bool, optional
        Overwrite an existing image (default False).
    dpi : int, optional

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        Unreadable result file, or ``png_path`` exists and ``force`` is
        False.
    """
    return save_png(result_figure(read_result(result_path)), png_path, force=force, dpi=dpi)


def save_png(fig, png_path, *, force=False, dpi=120):
    """Write a figure to a PNG file, creating missing parent directories.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    png_path : str or path-like
    force : bool, optional
        Overwrite an existing image (default False).
    dpi : int, optional

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
