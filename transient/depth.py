"""Wear across interfaces: the worn depth as a function of the wear work, pixel by pixel.

Below a face pixel the wear coefficient is that of the phase at the current
worn depth, ``k(d)`` (:class:`steady.depth.DepthColumns`), so
``dd/ds = k(d) p^m`` has a right-hand side that jumps at every interface.
The run integrates the *wear work* ``R = int p^m ds`` instead (Pa m for
``m = 1``), whose rate ``p^m`` is continuous in the face; the worn depth is
``d = D(R)``, the inverse of

    R(d) = int_0^d dz / k(z),

continuous, increasing and piecewise linear in ``R`` with slope ``k`` of the
segment it is in (docs/model.md, "Wear across interfaces").  Segment ``j``
of a pixel starts at depth ``z_j`` (``z_0 = 0``) and at work
``R_j = sum_{i<j} (z_(i+1) - z_i) / k_i``; the last segment goes on for ever.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WorkDepth"]


class WorkDepth:
    """The map ``R -> d`` from wear work to worn depth below every face pixel, and its inverse.

    Parameters
    ----------
    columns : steady.depth.DepthColumns
        The phases below the face.
    coefficients : array_like, shape (P,)
        The power law's coefficient of each phase, Pa^-m (1/Pa for ``m = 1``).
    factor : ndarray, shape (nx, ny), optional
        Multiplies every coefficient of a pixel (the speed ratio
        ``v / v_ref`` of non-uniform sliding); default 1.

    Attributes
    ----------
    columns : steady.depth.DepthColumns
    slopes : ndarray, shape (S + 1, nx, ny)
        ``k`` of every segment (``dd/dR``), 0 off the face.
    starts : ndarray, shape (S + 1, nx, ny), m
        Depth at which each segment starts (``inf`` for padding).
    works : ndarray, shape (S + 1, nx, ny)
        Wear work at which each segment starts (``inf`` for padding).

    Examples
    --------
    A coating 1 um thick with ``k = 1e-13 /Pa`` over a substrate with
    ``k = 1e-12 /Pa``: ``R = 1e7 Pa m`` wears the coating through.

    >>> from steady.depth import DepthColumns
    >>> columns = DepthColumns(np.full((1, 1, 1), 1e-6), np.array([[[1]], [[0]]]), 2)
    >>> work = WorkDepth(columns, (1e-12, 1e-13))
    >>> [float(work.depth(np.full((1, 1), r))[0, 0]) for r in (5e6, 1e7, 2e7)]
    [5e-07, 1e-06, 1.1e-05]
    """

    def __init__(self, columns, coefficients, factor=None):
        self.columns = columns
        face = columns.face_mask
        k = np.asarray(coefficients, dtype=float)[np.maximum(columns.phases, 0)]
        if factor is not None:
            k = k * np.asarray(factor, dtype=float)[None]
        self.slopes = np.where(face[None], k, 0.0)
        shape = (1,) + columns.shape
        self.starts = np.concatenate([np.zeros(shape), columns.interfaces])
        with np.errstate(invalid="ignore", divide="ignore"):
            thickness = np.diff(self.starts, axis=0)  # inf - inf = nan in the padding
            layer_work = np.where(np.isfinite(thickness) & face[None],
                                  thickness / np.where(face[None], k[:-1], 1.0), np.inf)
        self.works = np.concatenate([np.zeros(shape), np.cumsum(layer_work, axis=0)])
        # Off the face every pixel stays in segment 0 at zero work.
        self.works[1:, ~face] = np.inf
        self.starts[1:, ~face] = np.inf
        self._inverse = np.where(face[None], 1.0 / np.where(face[None], k, 1.0), 0.0)

    def segment(self, work):
        """Index of the segment of each pixel at wear work ``work``, shape (nx, ny)."""
        return np.sum(self.works[1:] <= work, axis=0)

    def slope(self, segment):
        """``k`` (``dd/dR``) of each pixel's ``segment``, shape (nx, ny), 0 off the face."""
        return np.take_along_axis(self.slopes, segment[None], axis=0)[0]

    def depth(self, work, segment=None):
        """Worn depth ``D(R)`` (m) at wear work ``work`` (shape (nx, ny)).

        With ``segment`` the map is that segment's line (its linearisation).
        """
        j = self.segment(work) if segment is None else segment
        start = np.take_along_axis(self.starts, j[None], axis=0)[0]
        origin = np.take_along_axis(self.works, j[None], axis=0)[0]
        return start + self.slope(j) * (work - origin)

    def remaining(self, work):
        """Wear work (shape (nx, ny)) left before each pixel reaches its next kink.

        A kink is an interface where the coefficient changes (one between
        layers of equal ``k`` is none); ``inf`` past a pixel's last one and
        off the face.
        """
        j = self.segment(work)
        k = self.slope(j)
        left = np.full(work.shape, np.inf)
        for i in range(1, self.works.shape[0]):
            kink = (i > j) & (self.slopes[i] != k) & np.isinf(left)
            left = np.where(kink, self.works[i] - work, left)
        return left

    def work(self, depth):
        """Wear work ``R(d)`` at worn depth ``depth`` (m, shape (nx, ny)); 0 off the face."""
        j = self.columns.segment_at(depth)
        start = np.take_along_axis(self.starts, j[None], axis=0)[0]
        origin = np.take_along_axis(self.works, j[None], axis=0)[0]
        inverse = np.take_along_axis(self._inverse, j[None], axis=0)[0]
        return np.where(self.columns.face_mask, origin + (depth - start) * inverse, 0.0)

