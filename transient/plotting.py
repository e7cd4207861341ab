"""Figure of a run file: the history beside the final face and pressure.

Reads the HDF5 file written by :func:`transient.output.write_run`, so a
figure can be redrawn without running again.  Uses matplotlib's Agg
canvas directly (no pyplot, no global backend state).
"""

from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .output import read_run

__all__ = ["plot_run", "run_figure"]


def run_figure(result, attrs):
    """Four-panel figure of a stored run.

    Parameters
    ----------
    result : transient.runin.RunResult
    attrs : mapping
        Root attributes of the run file (``radius``, ``steady_rms_slope``).

    Returns
    -------
    matplotlib.figure.Figure
        Top: rms slope and the convergence measures against the sliding
        distance; bottom: final face (in ``f*``) and pressure (in the mean
        pressure), axes in mm.
    """
    h = result.history
    s = h["distance"] / result.run_in_distance
    fig = Figure(figsize=(10, 8))
    FigureCanvasAgg(fig)
    ax = fig.subplots(2, 2)
    pos = s > 0
    a = ax[0, 0]
    a.semilogx(s[pos], h["normalised_rms_slope"][pos], ".-", label="K p, exact kernel")
    if "rms_slope_fd" in h:
        a.semilogx(s[pos], h["rms_slope_fd"][pos] / result.reference_slope, "--",
                   label="worn face, finite differences")
    if "steady_rms_slope" in attrs:
        a.axhline(attrs["steady_rms_slope"] / result.reference_slope, color="k", ls=":",
                  label="steady (eq. 9)")
    a.legend(fontsize=8)
    a.set_xlabel("sliding distance / s*")
    a.set_ylabel("rms slope / grad_f0")
    a.set_title(f"{result.scheme}: {result.steps} steps, {result.solves} contact solves")
    a = ax[0, 1]
    a.loglog(s[pos], np.maximum(h["spread"][pos], 1e-17), ".-", label="wear-rate spread")
    sr = h["shape_rate"][pos]
    a.loglog(s[pos], np.maximum(sr, 1e-17), ".-", label="shape change (f* per s*)")
    a.set_xlabel("sliding distance / s*")
    a.legend()
    a.set_title(f"status: {result.status}")
    n = result.height.shape[0]
    radius = float(attrs.get("radius", 1.0))
    ext = [-radius * 1e3, radius * 1e3, -radius * 1e3, radius * 1e3]
    face = result.face - np.nanmin(result.face)
    # Arrays are indexed [x, y]; imshow wants [row = y, column = x].
    im = ax[1, 0].imshow((face / result.depth_scale).T, origin="lower", extent=ext)
    fig.colorbar(im, ax=ax[1, 0], label="face height / f*")
    ax[1, 0].set_title(f"final face (n = {n})")
    pr = np.where(result.face_mask, result.pressure / result.pixel_mean_pressure, np.nan)
    im = ax[1, 1].imshow(pr.T, origin="lower", extent=ext)
    fig.colorbar(im, ax=ax[1, 1], label="pressure / pbar")
    ax[1, 1].set_title("final pressure")
    for a in ax[1]:
        a.set_xlabel("x (mm)")
        a.set_ylabel("y (mm)")
    fig.tight_layout()
    return fig


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
    run_figure(result, attrs).savefig(png_path, dpi=110)
    return png_path
