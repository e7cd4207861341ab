"""Profiles of a face: straight cross sections, ring averages, differential profiles.

The differential profile of the paper (Fig. 7b, 8b) is a cross section minus
the average of the face over the ring of the same radius: it removes the
macroscopic curvature (eq. 10) and leaves the effect of the phases.

Fields are ``(nx, ny)`` arrays on the grid of a face outline
(:class:`steady.outline.FaceGrid`, axis 0 along x), NaN off the face; the
outline is an outline object or a number, the radius of a disk (m).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .labels import extend_off_face
from .outline import FaceGrid, as_outline
from .schema import Key

__all__ = ["cross_section", "differential_profile", "ring_average"]

#: Samples along a cross section, and rings of a ring average.
_N_POINTS = Key("n_points", "integer", low=2, low_open=False)
_N_BINS = Key("n_bins", "integer", low=1, low_open=False)


def _grid_of(field, outline):
    """The field as floats and the outline's grid it lies on, checked."""
    field = np.asarray(field, dtype=float)
    if field.ndim != 2:
        raise ValueError(f"field must be a 2-d array, got shape {field.shape}")
    outline = as_outline(outline)
    grid = FaceGrid(outline, max(field.shape))
    if grid.shape != field.shape:
        raise ValueError(f"field of shape {field.shape} is not on a grid of the "
                         f"{outline.describe()} (n = {grid.n} gives {grid.shape})")
    return field, grid


def cross_section(field, outline, start, end, n_points):
    """Sample a face along a straight line by bilinear interpolation.

    Parameters
    ----------
    field : ndarray, shape (nx, ny)
        Values at the pixel centres (e.g. ``SteadyResult.face``, m); values
        off the face are not used.
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is the radius ``a`` of a
        disk, m.
    start, end : (float, float), m
        End points ``(x, y)`` of the line.
    n_points : int
        Samples, at least 2, evenly spaced from ``start`` to ``end``.

    Returns
    -------
    distance : ndarray, shape (n_points,), m
        Distance of each sample from ``start``.
    values : ndarray, shape (n_points,)
        Interpolated values; NaN at samples off the face (outside the
        outline; a sample on the rim is on the face).

    Notes
    -----
    Near the rim the bilinear stencil reaches pixels off the face; those
    take the value of the nearest face pixel, so that the profile extends
    to the rim.
    """
    field, grid = _grid_of(field, outline)
    distance, points = _line(start, end, n_points)
    filled = extend_off_face(field, grid.mask)
    half = np.array([grid.x.size, grid.y.size]) / grid.n * grid.outline.scale
    index = (points + half[:, None]) / grid.h - 0.5  # fractional pixel index along each axis
    values = ndimage.map_coordinates(filled, index, order=1, mode="nearest")
    values[~grid.outline.covers(points[0], points[1])] = np.nan
    return distance, values


def _line(start, end, n_points):
    """Distance from ``start`` (n_points,) and points (2, n_points) of a sampled line, m."""
    n_points = _N_POINTS.parse(n_points, "")
    start = np.asarray(start, dtype=float)
    end = np.asarray(end, dtype=float)
    if start.shape != (2,) or end.shape != (2,):
        raise ValueError(f"start and end must be (x, y) pairs in m, got {start!r} and {end!r}")
    t = np.linspace(0.0, 1.0, n_points)
    points = start[:, None] + (end - start)[:, None] * t[None, :]
    return t * np.linalg.norm(end - start), points


def ring_average(field, outline, n_bins):
    """Average of a face over rings of equal radius about its centre.

    Parameters
    ----------
    field : ndarray, shape (nx, ny)
        Values at the pixel centres; only face pixels are used.
    outline : outline object or float
        The face; a number is the radius of a disk, m.
    n_bins : int
        Rings of equal width ``R / n_bins`` from 0 to the face's
        circumradius ``R`` (``a`` for a disk).  About ``n/2`` (one pixel
        per ring) is a sensible choice.

    Returns
    -------
    r : ndarray, shape (n_bins,), m
        Mid radius of each ring.
    mean : ndarray, shape (n_bins,)
        Average over the face pixels whose centre lies in the ring; NaN for
        a ring that holds no pixel centre.
    """
    field, grid = _grid_of(field, outline)
    n_bins = _N_BINS.parse(n_bins, "")
    radius = grid.outline.circumradius()
    on_face = grid.mask
    ring = np.minimum((grid.radii[on_face] / radius * n_bins).astype(int), n_bins - 1)
    sums = np.bincount(ring, weights=field[on_face], minlength=n_bins)
    counts = np.bincount(ring, minlength=n_bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    return (np.arange(n_bins) + 0.5) * radius / n_bins, mean


def differential_profile(field, outline, start, end, n_points, *, n_bins=None):
    """Cross section minus the ring average at each sample's radius (Fig. 7b, 8b).

    Parameters
    ----------
    field, outline, start, end, n_points
        As in :func:`cross_section`.
    n_bins : int, optional
        Rings for :func:`ring_average`; default ``n // 2`` (one pixel wide
        on a disk).

    Returns
    -------
    distance : ndarray, shape (n_points,), m
    values : ndarray, shape (n_points,)
        NaN off the face.  Zero, up to interpolation, for an axisymmetric
        face.
    """
    field, grid = _grid_of(field, outline)
    n_bins = max(grid.n // 2, 1) if n_bins is None else n_bins
    distance, values = cross_section(field, grid.outline, start, end, n_points)
    r_ring, mean = ring_average(field, grid.outline, n_bins)
    ok = np.isfinite(mean)
    _, points = _line(start, end, n_points)
    r = np.hypot(points[0], points[1])
    return distance, values - np.interp(r, r_ring[ok], mean[ok])
