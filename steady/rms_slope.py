"""Accurate rms slope of a worn face, with an estimate of its discretisation error.

The surface gradient of the face is log-singular at the rim and along every
phase boundary.  The plain pixel estimate (mean of ``|grad f|^2`` at the
pixel centres of the face) converges only about first order, with an error
proportional to the boundary length per pixel, so that at a fixed grid it
depends on the grain size.  This module removes most of that error.

Method
------
For any pressure ``p`` on the plane, Parseval's theorem and the half-space
symbol ``u_q = 2 p_q / (E* |q|)`` give the exact identity::

    integral over the plane of |grad u|^2 dA = (4 / E*^2) integral of p^2 dA,

whose right-hand side is exact on the grid.  Hence the mean-square slope on
the face is the total minus the *exterior* integral, and the exterior field
is smooth everywhere except next to the rim: the log singularities along
internal phase boundaries drop out.  The exterior integral is computed by
pixel quadrature on a fine box around the face, on a coarse box out to
``far_radius`` radii, and analytically beyond (monopole and second moment
about the box centre, :func:`monopole_tail`, :func:`second_moment_tail`).
The coarse box's sources are the fine pixels summed over blocks, each block
a uniform coarse pixel shifted to its centre of pressure (the block's first
moments enter through the derivatives of the pixel kernel); without the
shift a block that the rim crosses sits up to half a coarse pixel off its
load.  Where the two boxes meet (and at the coarse box's outer side) the
midpoint rule's first error term, ``(H^2 / 24)`` times the flux of the
gradient of ``|grad u|^2`` through the side (Euler-Maclaurin, ``H`` the
pixel), is added, the flux read off the fine box's outer pixels.  Both
matter where the rim runs along the fine box, as a rectangle's does: there
they would otherwise leave an error of a few 1e-3 at ``n <= 128`` that
does not shrink with the grid (docs/benchmarks.md, "Other face outlines").

The remaining error comes from the rim, where the pixel quadrature misses
about the same amount inside and outside (the log singularity of a pressure
step is symmetric).  Comparing the plain face sum ``I``, the exterior sum
``X`` and the exact total ``T`` gives the quadrature defect
``delta = T - I - X``; its rim share is apportioned by the squared pressure
jumps across pixel edges, and half of it is restored to the exterior.

The error estimate compares the corrected values on the same phase geometry
rasterised at ``n``, ``n/2`` and ``n/4``
(``max(|S_n - S_n/2|, |S_n/2 - S_n/4| / 2)``, which bounds the error of a
method of order one or higher); see ``docs/benchmarks.md`` for its
validation against fine-grid references.  A phase map known only on its
grid (no geometry to rasterise again) is resampled instead
(:func:`resample_labels`, :func:`estimate_map_rms_slope`).
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math

import numpy as np
import scipy.fft

from .counterbody import Counterbody
from .halfspace import grid_shape
from .labels import extend_off_face, validate_labels
from .outline import MIN_SIDE_PIXELS, UNIT_DISK, FaceGrid, as_outline
from .phases import Homogeneous
from .wear import as_wear_law

__all__ = ["PeriodicSlopeEnergy", "SlopeEnergy", "SlopeEstimate", "SlopeGram", "SlopeIntegrals",
           "edge_jumps", "estimate_map_rms_slope", "estimate_rms_slope", "grid_ladder",
           "ladder_error", "MIN_CHORD_PIXELS", "mean_chord", "monopole_tail", "resample_labels",
           "second_moment_tail", "slope_energy_of"]

logger = logging.getLogger(__name__)

#: Transform dtype of each :class:`SlopeEnergy` precision.
_PRECISIONS = {"double": np.float64, "single": np.float32}


@dataclasses.dataclass(frozen=True)
class SlopeIntegrals:
    """Integrals of ``|grad f|^2`` for one pressure field on one grid.

    Attributes
    ----------
    face_area : float, m^2
        Pixel count of the face times ``h^2``.
    total : float, m^2
        ``(4 / E*^2) sum p^2 h^2``: the exact integral over the plane.
    face_sum : float, m^2
        Plain pixel quadrature over the face (the face sum ``I``).
    exterior : float, m^2
        Pixel quadrature over the exterior plus the analytic far tail.
    rim_share : float
        Fraction of the squared pressure jumps that sits on the rim.
    """

    face_area: float
    total: float
    face_sum: float
    exterior: float
    rim_share: float

    @property
    def defect(self):
        """Quadrature defect ``T - I - X``, m^2 (zero for an exact quadrature)."""
        return self.total - self.face_sum - self.exterior

    @property
    def corrected(self):
        """Corrected integral over the face, m^2."""
        return self.total - self.exterior - 0.5 * self.rim_share * self.defect

    @property
    def rms_slope(self):
        """Corrected rms slope over the face, dimensionless."""
        return np.sqrt(np.maximum(self.corrected, 0.0) / self.face_area)

    @property
    def rms_slope_plain(self):
        """Plain pixel rms slope over the face, dimensionless."""
        return np.sqrt(self.face_sum / self.face_area)


def edge_jumps(pressure_r, face_mask):
    """Squared pressure jumps summed over pixel edges.

    Parameters
    ----------
    pressure_r : ndarray, shape (nx, ny), Pa
    face_mask : ndarray of bool, shape (nx, ny)
        Pixels of the face.

    Returns
    -------
    interior : float, Pa^2
        Over edges between two face pixels.
    rim : float, Pa^2
        Over edges between a face pixel and a pixel off the face
        (including the grid's border).
    """
    interior, rim = _edge_differences(np.where(face_mask, pressure_r, 0.0)[None], face_mask)
    return float(np.sum(interior**2)), float(np.sum(rim**2))


def monopole_tail(force, centroid, box, E_star):
    """Far-field integral of ``|grad u|^2`` outside a rectangle, m^2.

    The field of a total force ``F`` at distance ``r`` from its centroid is
    ``|grad u| = F / (pi E* r^2)`` to dipole order (the dipole vanishes
    about the centroid).

    Parameters
    ----------
    force : float, N
    centroid : (float, float), m
    box : (x0, x1, y0, y1), m
        The rectangle, containing the centroid.
    E_star : float, Pa

    Returns
    -------
    float
        ``(F / (pi E*))^2 * integral outside the box of r^-4 dA``, summed
        side by side over the angular sectors each side subtends
        (``int cos^2(phi) / (2 d^2) dphi``).
    """
    integral = sum((phi / 2 + np.sin(2 * phi) / 4) / (2 * d * d)
                   for d, phi in _side_sectors(centroid, box))
    return (force / (np.pi * E_star)) ** 2 * integral


def _side_sectors(centre, box):
    """``(d, phi)`` of the eight half-sides of a box seen from a point inside it.

    ``d`` is the distance to a side and ``phi`` the angle, from the foot of
    the perpendicular, that the side's part on one side of the foot
    subtends; an integral outside the box of a radial power is the sum of
    its angular antiderivative over the eight pairs.
    """
    cx, cy = centre
    x0, x1, y0, y1 = box
    # (distance to the side, the side's tangential extent on either side of the foot)
    sides = [(x1 - cx, cy - y0, y1 - cy), (cx - x0, cy - y0, y1 - cy),
             (y1 - cy, cx - x0, x1 - cx), (cy - y0, cx - x0, x1 - cx)]
    for d, lo, hi in sides:
        for t in (lo, hi):
            yield d, np.arctan2(t, d)


def second_moment_tail(force, second_moment, centre, box, E_star):
    """Next term of :func:`monopole_tail`: the load's spread about the centre, m^2.

    About a centre ``O``, the displacement of a load of total force ``F``
    and second moment ``S2 = integral p |x - O|^2 dA`` is, far away and
    averaged over directions, ``(F / r + S2 / (4 r^3)) / (pi E*)``; hence
    ``|grad u|^2 = (F^2 / r^4 + 3 F S2 / (2 r^6)) / (pi E*)^2`` plus terms
    odd in the direction (the dipole's cross term), terms in ``cos 2 phi``
    (the anisotropic quadrupole; they cancel over a square box) and terms
    of order ``r^-6`` in the dipole squared (``F^2 |c - O|^2``, ``c`` the
    centroid) and ``r^-8``.

    Parameters
    ----------
    force : float, N
    second_moment : float, N m^2
        ``S2`` about ``centre``.
    centre : (float, float), m
        ``O``, inside the box.
    box : (x0, x1, y0, y1), m
    E_star : float, Pa

    Returns
    -------
    float
        ``3 F S2 / (2 (pi E*)^2)`` times the integral outside the box of
        ``r^-6 dA`` (``int cos^4(phi) / (4 d^4) dphi`` side by side).

    Examples
    --------
    A uniform disk of radius ``a`` has ``S2 = F a^2 / 2``; outside a box of
    half side ``8 a`` the term is 0.5 % of the monopole's:

    >>> box = (-8.0, 8.0, -8.0, 8.0)
    >>> mono = monopole_tail(1.0, (0.0, 0.0), box, 1.0)
    >>> print(f"{second_moment_tail(1.0, 0.5, (0.0, 0.0), box, 1.0) / mono:.4f}")
    0.0050
    """
    integral = sum((3 * phi / 8 + np.sin(2 * phi) / 4 + np.sin(4 * phi) / 32) / (4 * d**4)
                   for d, phi in _side_sectors(centre, box))
    return 1.5 * force * second_moment / (np.pi * E_star) ** 2 * integral


def _corner_sum(ox, oy, H, antiderivative):
    """Corner sum of ``antiderivative(X, Y)`` over the pixel of side ``H``.

    ``ox``, ``oy`` are runs of consecutive integer offsets (in pixels): the
    pixels' corners form one lattice, ``(k - 1/2) H``, on which the
    antiderivative is evaluated once (a quarter of the evaluations of four
    corners per offset); no corner lies on an axis.
    """
    cx = (np.arange(ox[0], ox[-1] + 2) - 0.5) * H
    cy = (np.arange(oy[0], oy[-1] + 2) - 0.5) * H
    values = antiderivative(cx[:, None], cy[None, :])
    return values[1:, 1:] - values[:-1, 1:] - values[1:, :-1] + values[:-1, :-1]


def _asinh_yx(X, Y):
    """``asinh(Y / |X|)``: the x-derivative of the antiderivative of ``1/r`` (no ``X = 0``)."""
    return np.arcsinh(Y / np.abs(X))


def _border_weights(shape):
    """Indices and weights of the midpoint rule's end correction on a box.

    ``sum(weights * f[indices])`` is the flux of ``grad f`` into the
    box through its four sides times the pixel side: per side, the inward
    derivative at the side from the three outermost pixel rows
    (``(-2 f_1 + 3 f_2 - f_3) / H``, the quadratic through their centres)
    summed along it.  Pixels in two sides' rows carry both weights.
    """
    nx, ny = shape
    weights = np.zeros(shape)
    for k, w in enumerate((-2.0, 3.0, -1.0)):
        weights[k, :] += w
        weights[nx - 1 - k, :] += w
        weights[:, k] += w
        weights[:, ny - 1 - k] += w
    # Row and column indices, in the order of the flat ones: the box's
    # gradients are column-major, which ravel() would copy.
    indices = np.nonzero(weights)
    return indices, weights[indices]


def _wrap_into(kernel, values, x0, y0, scale):
    """``kernel[(x0 + i) % sx, (y0 + j) % sy] = scale * values[i, j]``, by blocks of slices.

    ``values`` is no larger than ``kernel`` along either axis, so its
    indices wrap at most once: four block copies instead of a fancy-indexed
    assignment (the same numbers, a fraction of the time on large grids).
    """
    spans = []
    for start, count, size in ((x0, values.shape[0], kernel.shape[0]),
                               (y0, values.shape[1], kernel.shape[1])):
        first = start % size
        head = min(count, size - first)
        spans.append(((slice(first, first + head), slice(0, head)),
                      (slice(0, count - head), slice(head, count))))
    for kx, vx in spans[0]:
        for ky, vy in spans[1]:
            np.multiply(values[vx, vy], scale, out=kernel[kx, ky])


def _stored(spectrum_q):
    """A kernel spectrum as it is kept: single precision, half the memory.

    Its rounding (6e-8 of each entry) changed the run-in history's rms
    slope by at most 5e-9 of itself, 3e-6 of its error bar (the shipped
    Voronoi scene at n = 512, docs/benchmarks.md, "Run-in memory"); the
    products with it are formed in double precision.
    """
    return spectrum_q.astype(np.complex64)


class _BoxGradient:
    """Gradient on an output box from sources on a (coarser) pixel grid.

    Sources occupy pixel indices ``[0, ns_a)`` along each axis ``a`` with
    spacing ``H``; outputs are the pixel centres ``[lo_a, lo_a + m_a)`` of
    the same lattice.  Aperiodic linear convolution by FFT of the smallest
    fast size.  With ``dipoles``, each source pixel also carries first
    moments ``(mx, my)`` (Pa m: the mean of ``p (x - x_c)`` over the pixel),
    and its load is shifted to its centre of pressure to first order
    (``-mx d/dx - my d/dy`` of the pixel's kernel).
    """

    def __init__(self, ns, lo, m, H, E_star, workers, *, dipoles=False):
        self.ns, self.lo, self.m, self.workers = tuple(ns), tuple(lo), tuple(m), workers
        size = tuple(scipy.fft.next_fast_len(a + b - 1, real=True)
                     for a, b in zip(ns, m, strict=True))
        self.size = size
        ox, oy = (np.arange(l0 - a + 1, l0 + b) for a, l0, b in zip(ns, lo, m, strict=True))
        # The spectra are kept without the factor 1 / (pi E*), applied to the
        # output, so that their single-precision rounding does not depend on E*.
        self.scale = 1.0 / (np.pi * E_star)
        kernel = np.zeros(size)
        # The gradient kernels of steady.halfspace.pixel_integral_gradient, from
        # the corner lattice; the y-kernel is the x-kernel with the axes swapped.
        gx = _corner_sum(ox, oy, H, _asinh_yx)
        _wrap_into(kernel, gx, ox[0], oy[0], 1.0)
        self.gx_q = _stored(scipy.fft.rfft2(kernel, workers=workers))
        gy = gx.T if np.array_equal(ox, oy) else _corner_sum(oy, ox, H, _asinh_yx).T
        del gx
        _wrap_into(kernel, gy, ox[0], oy[0], 1.0)
        del gy
        self.gy_q = _stored(scipy.fft.rfft2(kernel, workers=workers))
        self.dipoles = dipoles
        if dipoles:
            # Minus the derivatives of the gradient kernels with respect to the
            # observation point: d/dX asinh(Y/|X|) = -Y / (X R), d/dY of it
            # 1 / R, d/dY asinh(X/|Y|) = -X / (Y R).  No corner lies on an axis.
            hessian = [lambda X, Y: Y / (X * np.hypot(X, Y)),
                       lambda X, Y: -1.0 / np.hypot(X, Y),
                       lambda X, Y: X / (Y * np.hypot(X, Y))]
            self.hessian_q = []
            for antiderivative in hessian:
                _wrap_into(kernel, _corner_sum(ox, oy, H, antiderivative), ox[0], oy[0], 1.0)
                self.hessian_q.append(_stored(scipy.fft.rfft2(kernel, workers=workers)))
        self.rows = np.mod(np.arange(lo[0], lo[0] + m[0]), size[0])
        self.cols = np.mod(np.arange(lo[1], lo[1] + m[1]), size[1])

    def __call__(self, sources, dtype=np.float64):
        """Gradient ``(gx, gy)`` on the output box, each of shape ``m``, float64.

        ``sources`` is the pressure of the source pixels, shape ``ns``; with
        ``dipoles``, the stack ``(p, mx, my)`` of shape ``(3,) + ns``.
        ``dtype`` is that of the transforms and products (float32: single
        precision throughout, against the stored single-precision spectra).
        """
        size, w = self.size, self.workers
        sources = np.asarray(sources, dtype=dtype)
        # Row transforms of the source rows only (the padding rows' are zero),
        # then the column transforms of the zero-padded result.
        rows = scipy.fft.rfft(sources, n=size[1], axis=-1, workers=w)
        spectrum = scipy.fft.fft(rows, n=size[0], axis=-2, workers=w)
        del rows
        if self.dipoles:
            sq, mxq, myq = spectrum
            xx, xy, yy = self.hessian_q
            terms = ((self.gx_q, xx, xy), (self.gy_q, xy, yy))
        else:
            sq = spectrum
            terms = ((self.gx_q,), (self.gy_q,))
        out = []
        for kernels in terms:
            # One product at a time, summed in place: a padded spectrum fewer alive.
            product = sq * kernels[0]
            if self.dipoles:
                product += mxq * kernels[1]
                product += myq * kernels[2]
            # Column pass, then the row pass on the output rows only.
            cols = scipy.fft.ifft(product, axis=0, workers=w, overwrite_x=True)[self.rows]
            del product
            gradient = scipy.fft.irfft(cols, n=size[1], axis=1, workers=w)[:, self.cols]
            gradient = gradient.astype(np.float64, copy=False)
            gradient *= self.scale
            out.append(gradient)
        return tuple(out)


class SlopeEnergy:
    """Energy-corrected quadrature of the slope on one grid (see module notes).

    Build once per grid; kernel spectra are cached.

    Parameters
    ----------
    n : int or (int, int)
        Pixels across the grid of the face: ``n`` for an ``n x n`` grid, or
        ``(nx, ny)`` for the rectangular grid of a face's bounding box
        (:class:`steady.outline.FaceGrid`).
    h : float, m
        Pixel size.
    E_star : float, Pa
    margin : int, optional
        Fine pixels kept around the grid (default ``max(8, n // 16)``, ``n``
        the longer side; at least 3, rounded up to whole coarse pixels);
        they carry the rim's exterior at the grid's own resolution.
    coarsening : int, optional
        Ratio of coarse to fine pixel size (default 8).  Coarse pixels carry
        their blocks' first moments, and the midpoint rule's end correction
        is applied where the boxes meet (module notes), so that the result
        hardly depends on ``margin`` and ``coarsening``.
    far_radius : float, optional
        Half-width of the coarse box in units of the grid's half-width
        along its longer side (default 8; the same on both axes); beyond
        it the tail is analytic (monopole and second moment).
    workers : int, optional
        Threads for :mod:`scipy.fft`.
    precision : {"double", "single"}, optional
        Precision of the transforms and spectral products of
        :meth:`__call__` (default "double"); the squares and sums are
        formed in double precision either way.  "single" takes about half
        the time; on run-in pressures of the shipped Voronoi scene
        (n = 256 to 1024) it changed ``rms_slope`` by at most 1.7e-7 of
        itself and each integral by at most 3.4e-7 (docs/benchmarks.md,
        "The history's estimator in single precision"), far below the
        estimate's own error.  :meth:`gram` always works in double
        precision.

    Examples
    --------
    >>> from steady.outline import UNIT_DISK
    >>> from steady.reference import flat_punch_pressure
    >>> grid = UNIT_DISK.grid(64)
    >>> r, _ = grid.polar()
    >>> p = np.where(grid.mask, flat_punch_pressure(r, 1.0, 1.0), 0.0)
    >>> double = SlopeEnergy(64, grid.h, 1.0)(p, grid.mask).rms_slope
    >>> single = SlopeEnergy(64, grid.h, 1.0, precision="single")(p, grid.mask).rms_slope
    >>> bool(abs(single / double - 1) < 1e-6)
    True
    """

    def __init__(self, n, h, E_star, *, margin=None, coarsening=8, far_radius=8.0,
                 workers=-1, precision="double"):
        self.precision = precision
        self.shape = grid_shape(n)
        self.n = max(self.shape)
        self.h, self.E_star = float(h), float(E_star)
        c = int(coarsening)
        margin = max(8, self.n // 16) if margin is None else int(margin)
        # The fine box must tile into coarse pixels: round its sides up.  The
        # end correction reads the fine box's three outer rows: off the face.
        margin = c * -(-max(margin, 3) // c)
        fine = tuple(c * -(-(a + 2 * margin) // c) for a in self.shape)
        self.c, self.margin, self.fine = c, margin, fine
        self._fine = _BoxGradient(self.shape, (-margin, -margin), fine, self.h, self.E_star,
                                  workers)
        # Coarse sources are the fine box block-summed; outputs reach far_radius
        # half-widths of the longer side from the grid centre on both axes.
        nc = tuple(a // c for a in fine)
        half = far_radius * self.n / 2  # in fine pixels
        extra = tuple(max(1, int(np.ceil((half - a / 2) / c))) for a in fine)
        coarse_out = tuple(a + 2 * e for a, e in zip(nc, extra, strict=True))
        self._coarse = _BoxGradient(nc, tuple(-e for e in extra), coarse_out, c * self.h,
                                    self.E_star, workers, dipoles=True)
        self._coarse_inner = tuple(slice(e, e + a) for a, e in zip(nc, extra, strict=True))
        self._coarse_extra = extra
        # Midpoint rule's end correction, (H^2 / 24) times the flux of grad |grad u|^2
        # out of each region: where the boxes meet (read off the fine box, for the
        # coarse region and the fine one's outer pixels) and at the coarse box's
        # outer side.
        H = c * self.h
        index, weight = _border_weights(fine)
        self._fine_border = index, weight * (H * H - self.h * self.h) / 24.0
        index, weight = _border_weights(coarse_out)
        self._coarse_border = index, weight * (-H * H / 24.0)
        # Pixel offsets from the box centre (the tail's expansion point), m.
        centre, self._box = self._tail_box()
        self._offsets = tuple((np.arange(a) + 0.5 - a / 2) * self.h - o
                              for a, o in zip(self.shape, centre, strict=True))
        self._tail_centre = centre

    @property
    def precision(self):
        """Precision of the transforms of :meth:`__call__`, "double" or "single"; may be reset."""
        return self._precision

    @precision.setter
    def precision(self, value):
        if value not in _PRECISIONS:
            raise ValueError(f"precision must be one of {', '.join(map(repr, _PRECISIONS))}, "
                             f"got {value!r}")
        self._precision = value

    def in_precision(self, precision):
        """The estimator with the transforms of :meth:`__call__` in ``precision``.

        A copy that shares the kernel spectra (and :attr:`workers`) with
        this one: no transform of a kernel is repeated.
        """
        other = copy.copy(self)
        other.precision = precision
        return other

    @property
    def workers(self):
        """Threads of its transforms (:mod:`scipy.fft`'s ``workers``); may be reset."""
        return self._fine.workers

    @workers.setter
    def workers(self, value):
        self._fine.workers = self._coarse.workers = value

    def _boxed(self, field):
        """``field`` (grid shape) placed in the fine box."""
        m = self.margin
        boxed = np.zeros(self.fine)
        boxed[m:m + self.shape[0], m:m + self.shape[1]] = field
        return boxed

    def _coarse_sources(self, field):
        """The fine box in ``c x c`` blocks: mean and first moments, shape (3, fx/c, fy/c).

        The moments are the means of ``p (x - x_c)`` and ``p (y - y_c)``
        over each block (Pa m), ``(x_c, y_c)`` its centre.
        """
        c = self.c
        fx, fy = self.fine
        blocks = self._boxed(field).reshape(fx // c, c, fy // c, c)
        offsets = (np.arange(c) - (c - 1) / 2) * (self.h / (c * c))
        return np.stack([blocks.mean(axis=(1, 3)),
                         np.einsum("icjd,c->ij", blocks, offsets),
                         np.einsum("icjd,d->ij", blocks, offsets)])

    def _second_moment(self, field):
        """``sum p |x - O|^2 h^2`` about the tail's centre ``O``, N m^2."""
        ox, oy = self._offsets
        return float(ox**2 @ field.sum(axis=1) + oy**2 @ field.sum(axis=0)) * self.h**2

    def _check(self, face_mask):
        face_mask = np.asarray(face_mask, dtype=bool)
        if face_mask.shape != self.shape:
            raise ValueError(f"face_mask must have the estimator's grid shape {self.shape}, got "
                             f"{face_mask.shape}")
        return face_mask

    def __call__(self, pressure_r, face_mask):
        """Integrals of ``|grad f|^2`` for a pressure on the face.

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa
            Zero off the face.
        face_mask : ndarray of bool, shape (nx, ny)
            Pixels of the face.

        Returns
        -------
        SlopeIntegrals
            The same as ``gram([pressure_r], face_mask).integrals([1.0])``,
            computed without the Gram matrices (the run-in calls this at
            every step).
        """
        face_mask = self._check(face_mask)
        h, c = self.h, self.c
        dtype = _PRECISIONS[self.precision]
        field = np.where(face_mask, pressure_r, 0.0)
        area = h * h
        on_face = self._boxed(face_mask).astype(bool)
        gx, gy = self._fine(field, dtype)
        square = gx * gx
        square += gy * gy
        face_sum = float(np.sum(square, where=on_face)) * area
        exterior = float(np.sum(square)) * area - face_sum
        index, weight = self._fine_border
        exterior += float(weight @ square[index])
        gx, gy = self._coarse(self._coarse_sources(field), dtype)
        square = gx * gx
        square += gy * gy
        exterior += (float(np.sum(square)) - float(np.sum(square[self._coarse_inner])))\
            * (c * h) ** 2
        index, weight = self._coarse_border
        exterior += float(weight @ square[index])
        force = float(np.sum(field)) * area
        exterior += self._unit_tail() * force * force
        exterior += self._moment_tail() * force * self._second_moment(field)
        if dtype is np.float64:
            interior, rim = edge_jumps(field, face_mask)
        else:
            interior, rim = _jump_sums(field, face_mask)
        jumps = interior + rim
        return SlopeIntegrals(face_area=float(face_mask.sum()) * area,
                              total=4.0 / self.E_star**2 * float(np.sum(field * field)) * area,
                              face_sum=face_sum, exterior=exterior,
                              rim_share=rim / jumps if jumps > 0 else 1.0)

    def _tail_box(self):
        """``(centre, (x0, x1, y0, y1))`` of the coarse box, m from the grid's centre."""
        h, m, c = self.h, self.margin, self.c
        (ex, ey), (nx, ny) = self._coarse_extra, self.shape
        (fx, fy) = self.fine
        x0 = (-nx / 2 - m - ex * c) * h
        y0 = (-ny / 2 - m - ey * c) * h
        x1 = x0 + (fx + 2 * ex * c) * h
        y1 = y0 + (fy + 2 * ey * c) * h
        return ((x0 + x1) / 2, (y0 + y1) / 2), (x0, x1, y0, y1)

    def _unit_tail(self):
        """Far tail of a unit force outside the coarse box (:func:`monopole_tail`), m^2/N^2."""
        return monopole_tail(1.0, self._tail_centre, self._box, self.E_star)

    def _moment_tail(self):
        """:func:`second_moment_tail` per unit force and second moment, 1/N^2."""
        return second_moment_tail(1.0, 1.0, self._tail_centre, self._box, self.E_star)

    def gram(self, fields, face_mask):
        """Quadratic forms of the slope integrals over a set of pressure fields.

        Every integral in :class:`SlopeIntegrals` is a quadratic form of the
        pressure; for ``p = sum_i w_i fields[i]`` it is ``w^T M w``.  With
        the phase indicators as fields, a sweep over wear coefficients costs
        no transform at all.

        Parameters
        ----------
        fields : sequence of ndarray, shape (nx, ny), Pa
            Pressure fields (zero off the face).
        face_mask : ndarray of bool, shape (nx, ny)
            Pixels of the face.

        Returns
        -------
        SlopeGram
        """
        face_mask = self._check(face_mask)
        h, c = self.h, self.c
        fields = np.asarray([np.where(face_mask, f, 0.0) for f in fields])
        area = h * h
        on_face = self._boxed(face_mask).astype(bool)
        coarse_outside = np.ones(self._coarse.m, dtype=bool)
        coarse_outside[self._coarse_inner] = False

        fine_index, fine_weight = self._fine_border
        coarse_index, coarse_weight = self._coarse_border
        border_weight = np.concatenate([fine_weight, fine_weight, coarse_weight, coarse_weight])
        face_rows, ext_rows, coarse_rows, border_rows = [], [], [], []
        for f in fields:
            gx, gy = self._fine(f)
            face_rows.append(np.concatenate([gx[on_face], gy[on_face]]))
            ext_rows.append(np.concatenate([gx[~on_face], gy[~on_face]]))
            border = [gx[fine_index], gy[fine_index]]
            gx, gy = self._coarse(self._coarse_sources(f))
            coarse_rows.append(np.concatenate([gx[coarse_outside], gy[coarse_outside]]))
            border_rows.append(np.concatenate(border + [gx[coarse_index], gy[coarse_index]]))

        def gram(rows, weight=None):
            a = np.asarray(rows)
            return (a if weight is None else a * weight) @ a.T

        forces = fields.reshape(len(fields), -1).sum(axis=1) * area
        moments = np.array([self._second_moment(f) for f in fields])
        # About the box centre the monopole-dipole cross term integrates to
        # zero; what is left, dipole^2 / L^2, is below 1e-6 of the total.
        spread = np.outer(forces, moments)
        exterior = (gram(ext_rows) * area + gram(coarse_rows) * (c * h) ** 2
                    + gram(border_rows, border_weight)
                    + self._unit_tail() * np.outer(forces, forces)
                    + self._moment_tail() * 0.5 * (spread + spread.T))
        flat = fields.reshape(len(fields), -1)
        total = 4.0 / self.E_star**2 * (flat @ flat.T) * area
        interior, rim = _edge_differences(fields, face_mask)
        return SlopeGram(face_area=float(face_mask.sum()) * area, total=total,
                         face_sum=gram(face_rows) * area, exterior=exterior,
                         interior_jumps=interior @ interior.T, rim_jumps=rim @ rim.T)


class PeriodicSlopeEnergy:
    """The slope integrals of a periodic cell: exact, with no exterior and no rim.

    The continuum face of a pressure constant on the cell's pixels has the
    mean-square slope of Parseval's identity
    (:meth:`steady.periodic.PeriodicHalfSpace.mean_square_slope`, ``(2 / E*)^2``
    times the pressure's variance on the half-space): the log singularities at
    phase boundaries are integrated exactly, and a cell has no rim.  So
    ``exterior`` is 0, ``rim_share`` 0 and ``corrected`` is ``total``, the exact
    integral; ``face_sum`` is the plain pixel quadrature, for comparison.  What
    is left of the discretisation error is the phase map's rasterisation, which
    the ladder of :func:`estimate_rms_slope` measures.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
        A periodic cell's grid.
    E_star : float, Pa
    operator : steady.periodic.PeriodicHalfSpace, optional
        The cell's operator (a layer's scales its modes: the integrals are
        then the layer's); default the half-space's.
    precision : {"double", "single"}, optional
        Accepted for the interface of :class:`SlopeEnergy`; the integrals are
        always formed in double precision (they cost one transform).
    workers : int, optional
        Threads for :mod:`scipy.fft`.

    Examples
    --------
    >>> import numpy as np
    >>> from steady.outline import PeriodicCell
    >>> grid = PeriodicCell(1e-3, 1e-3).grid(16)
    >>> p = np.where(grid.x[:, None] > 0, 2.0, 1.0) * np.ones(grid.shape)
    >>> print(f"{PeriodicSlopeEnergy(grid, 1.0)(p, grid.mask).rms_slope:.6f}")
    1.000000
    """

    def __init__(self, grid, E_star, *, operator=None, precision="double", workers=-1):
        self.operator = (Counterbody(E_star).operator(grid, workers=workers) if operator is None
                         else operator)
        self.shape = tuple(grid.shape)
        self.h, self.E_star = float(grid.h), float(E_star)
        if precision not in _PRECISIONS:
            raise ValueError(f"precision must be one of {', '.join(map(repr, _PRECISIONS))}, "
                             f"got {precision!r}")
        self.precision = precision

    def in_precision(self, precision):
        """The estimator with ``precision`` (the same integrals: see the class)."""
        other = copy.copy(self)
        other.precision = precision
        return other

    @property
    def workers(self):
        """Threads of its transforms (:mod:`scipy.fft`'s ``workers``); may be reset."""
        return self.operator.workers

    @workers.setter
    def workers(self, value):
        self.operator.workers = value

    def __call__(self, pressure_r, face_mask):
        """:class:`SlopeIntegrals` of a pressure on the cell (``face_mask``: every pixel).

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa
        face_mask : ndarray of bool, shape (nx, ny)
        """
        return self.gram([pressure_r], face_mask).integrals([1.0])

    def gram(self, fields, face_mask):
        """Quadratic forms of the slope integrals over a set of pressure fields.

        As :meth:`SlopeEnergy.gram`: ``total`` from the cell's spectra (exact),
        ``face_sum`` from the pixel-centre gradients, ``exterior`` and the rim's
        jumps zero; the interior jumps across every pixel edge of the cell
        (periodically).

        Parameters
        ----------
        fields : sequence of ndarray, shape (nx, ny), Pa
        face_mask : ndarray of bool, shape (nx, ny)

        Returns
        -------
        SlopeGram
        """
        face_mask = np.asarray(face_mask, dtype=bool)
        if face_mask.shape != self.shape:
            raise ValueError(f"face_mask must have the estimator's grid shape {self.shape}, got "
                             f"{face_mask.shape}")
        hs, area = self.operator, self.h * self.h
        fields = np.asarray([np.where(face_mask, f, 0.0) for f in fields], dtype=float)
        spectra = [hs.forward(f) for f in fields]
        nx, ny = self.shape
        # Columns other than 0 and Nyquist of the half spectrum stand for two.
        twice = np.full(ny // 2 + 1, 2.0)
        twice[0] = 1.0
        if ny % 2 == 0:
            twice[-1] = 1.0
        weight = hs.slope_weight * twice
        rows = np.array([(a * weight).ravel() for a in spectra])
        cross = np.real(rows @ np.conj(np.array([a.ravel() for a in spectra])).T)
        total = 4.0 / self.E_star**2 * cross * (nx * ny * area) / (nx * ny) ** 2
        gradients = [np.concatenate([g.ravel() for g in hs.gradient(f, pressure_q=a)])
                     for f, a in zip(fields, spectra, strict=True)]
        g = np.array(gradients)
        jumps = np.array([np.concatenate([(f - np.roll(f, 1, axis=0)).ravel(),
                                          (f - np.roll(f, 1, axis=1)).ravel()]) for f in fields])
        zero = np.zeros((len(fields), len(fields)))
        return SlopeGram(face_area=float(face_mask.sum()) * area, total=total,
                         face_sum=(g @ g.T) * area, exterior=zero,
                         interior_jumps=jumps @ jumps.T, rim_jumps=zero.copy())


def slope_energy_of(grid, E_star, *, operator=None, precision="double"):
    """The slope estimator of a face's grid: the periodic cell's or the finite face's.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
    E_star : float, Pa
    operator : steady.periodic.PeriodicHalfSpace, optional
        A periodic cell's operator, if the caller has it (a layer's scales
        its modes, and the cell's integrals are then the layer's, exactly);
        default: the half-space's.  A finite face's estimator corrects the
        half-space's kernel and ignores it.
    precision : {"double", "single"}, optional

    Returns
    -------
    SlopeEnergy or PeriodicSlopeEnergy
    """
    if grid.outline.periodic:
        return PeriodicSlopeEnergy(grid, E_star, operator=operator, precision=precision)
    return SlopeEnergy(grid.shape, grid.h, E_star, precision=precision)


def _jump_sums(field, face_mask):
    """:func:`edge_jumps` of one field zero off the face, summed without gathering the edges.

    The same sums in another order (they differ in the last digits), in a
    fraction of the time: squared differences of neighbours summed under
    the edge masks.
    """
    p = np.pad(field, 1)
    f = np.pad(face_mask, 1)
    interior = rim = 0.0
    for a, b, fa, fb in ((p[1:], p[:-1], f[1:], f[:-1]),
                         (p[:, 1:], p[:, :-1], f[:, 1:], f[:, :-1])):
        square = a - b
        square *= square
        interior += float(np.sum(square, where=fa & fb))
        rim += float(np.sum(square, where=fa ^ fb))
    return interior, rim


def _edge_differences(fields, face_mask):
    """Field differences across pixel edges, split into interior and rim edges.

    Returns two arrays of shape (len(fields), edges).
    """
    f = np.pad(face_mask, 1)
    p = np.pad(fields, ((0, 0), (1, 1), (1, 1)))
    interior, rim = [], []
    for axis in (1, 2):
        a = np.moveaxis(p, axis, 1)
        mask = np.moveaxis(f, axis - 1, 0)
        diff = a[:, 1:] - a[:, :-1]
        interior.append(diff[:, mask[1:] & mask[:-1]])
        rim.append(diff[:, mask[1:] ^ mask[:-1]])
    return np.concatenate(interior, axis=1), np.concatenate(rim, axis=1)


@dataclasses.dataclass(frozen=True, eq=False)
class SlopeGram:
    """Quadratic forms (``P x P`` matrices, m^2 per Pa^2) of the slope integrals.

    See :meth:`SlopeEnergy.gram`; ``interior_jumps`` and ``rim_jumps`` are
    in Pa^2 per Pa^2 (dimensionless weights).

    Attributes
    ----------
    face_area : float, m^2
        Pixel count of the face times ``h^2``.
    total, face_sum, exterior : ndarray, shape (P, P)
        Forms of the integrals of the same names of :class:`SlopeIntegrals`.
    interior_jumps, rim_jumps : ndarray, shape (P, P)
        Forms of the squared pressure jumps over interior and rim edges
        (:func:`edge_jumps`).
    """

    face_area: float
    total: np.ndarray
    face_sum: np.ndarray
    exterior: np.ndarray
    interior_jumps: np.ndarray
    rim_jumps: np.ndarray

    def integrals(self, weights):
        """:class:`SlopeIntegrals` of ``p = sum_i weights[i] fields[i]``.

        Parameters
        ----------
        weights : array_like, shape (P,) or (K, P)
            Several rows give arrays of shape (K,) in every field.
        """
        w = np.asarray(weights, dtype=float)

        def form(matrix):
            return np.einsum("...i,ij,...j->...", w, matrix, w)

        rim = form(self.rim_jumps)
        jumps = form(self.interior_jumps) + rim
        with np.errstate(invalid="ignore", divide="ignore"):
            share = np.where(jumps > 0, rim / np.where(jumps > 0, jumps, 1.0), 1.0)
        return SlopeIntegrals(face_area=self.face_area, total=form(self.total),
                              face_sum=form(self.face_sum), exterior=form(self.exterior),
                              rim_share=share)


@dataclasses.dataclass(frozen=True)
class SlopeEstimate:
    """Rms slope of a limiting face with its estimated discretisation error.

    Attributes
    ----------
    rms_slope : float, dimensionless
        Energy-corrected rms slope on the finest grid in ``grids`` (for
        :func:`estimate_map_rms_slope`: on the map's own grid, which a
        refined grid may follow).
    error : float, dimensionless
        Estimated absolute discretisation error of ``rms_slope``; infinite
        where none could be estimated (no bound).
    rms_slope_plain : float, dimensionless
        Plain pixel rms slope on that grid, for comparison.
    grids : tuple of int
        Grid sizes solved, coarse to fine.
    values : tuple of float
        Corrected rms slope on each grid.
    """

    rms_slope: float
    error: float
    rms_slope_plain: float
    grids: tuple
    values: tuple


def _grid(outline, m):
    """The grid ``m`` of an outline (``None``: the unit disk, the grid of a bare ``m``)."""
    return FaceGrid(UNIT_DISK if outline is None else outline, m)


def _accepts(geometry, n, outline=None):
    """Whether the geometry can be rasterised at grid ``n`` on the outline."""
    try:
        geometry.check_grid(_grid(outline, n))
    except ValueError:
        return False
    return True


def _coarsest_grid(geometry, outline=None):
    """Coarsest grid the geometry accepts: a multiple of 8 where it can be, else the minimum.

    A continuous geometry accepts every grid from ``min_grid()`` on; a pixel
    map (or a mask outline) only multiples of its size, the coarsest being
    the size itself.  Returns None if the geometry accepts neither.
    """
    low = geometry.min_grid(outline)
    if outline is not None:
        low = max(low, outline.min_grid())
    for m in (8 * -(-low // 8), low):
        if _accepts(geometry, m, outline):
            return m
    return None


def grid_ladder(geometry, n, outline=None):
    """Grids for a discretisation-error estimate at grid ``n``, coarse to fine.

    ``n/4, n/2, n`` where the geometry accepts them (``check_grid``: for
    Voronoi maps two pixels per mean seed spacing; on a face outline, also
    the outline's own minimum); if neither ``n/4`` nor ``n/2`` is accepted,
    the coarsest accepted grid below ``n`` (a multiple of 8, or for a pixel
    map its own size); if there is none, ``n, 2n``.  Only resolved grids
    enter the estimate (e.g. 160^2 seeds at ``n = 512``: ``320, 512``).  A
    pixel map exists only at multiples of its size: at its own size it
    refines instead.  The geometry accepts every grid of the ladder.

    Parameters
    ----------
    geometry : phase geometry
    n : int
        Pixels along the longer side of the face's bounding box.
    outline : outline object, optional
        The face (:mod:`steady.outline`); default the unit disk, grids
        given by their size alone.

    Examples
    --------
    >>> from steady.phases import ArrayMap, Rods, Voronoi
    >>> grid_ladder(Voronoi(160**2, (0.5, 0.5), 2024), 512)
    [320, 512]
    >>> grid_ladder(ArrayMap(Rods(((0.0, 0.0),), (0.5,)).labels(20)), 100)
    [20, 100]
    """
    if isinstance(n, FaceGrid):
        n = n.n
    n = geometry.check_grid(_grid(outline, int(n)))
    grids = [n // d for d in (4, 2) if n % d == 0 and _accepts(geometry, n // d, outline)]
    if not grids:
        m = _coarsest_grid(geometry, outline)
        grids = [m] if m is not None and m < n else []
    return grids + [n] if grids else [n, 2 * n]


def ladder_error(grids, values):
    """Discretisation error of the value on the finest grid of a ladder.

    Parameters
    ----------
    grids : sequence of int, shape (G,), G >= 2
        Increasing grid sizes.
    values : array_like, shape (G, ...)
        The quantity on each grid.

    Returns
    -------
    ndarray, shape (...)
        ``max_j |S_{j+1} - S_j| * m_j / (m_{j+1} - m_j) * m_{j+1} / n``:
        the first-order error of ``S_{j+1}`` from each consecutive pair,
        carried to the finest grid ``n``.  For the ladder ``n/4, n/2, n``
        this is ``max(|S_n - S_n/2|, |S_n/2 - S_n/4| / 2)``, the estimate of
        :func:`estimate_rms_slope`.
    """
    m = np.asarray(grids, dtype=float)
    v = np.asarray(values, dtype=float)
    if m.size < 2 or v.shape[0] != m.size:
        raise ValueError(f"need values on at least two grids, one row per grid; got grids "
                         f"{list(grids)} and values of shape {v.shape}")
    n = m[-1]
    factors = m[:-1] / np.diff(m) * m[1:] / n
    diffs = np.abs(np.diff(v, axis=0))
    return np.max(diffs * factors.reshape((-1,) + (1,) * (v.ndim - 1)), axis=0)


def _steady_pressure(labels, wear, normal_force, grid, sliding, *, checked=False):
    """The steady pressure of a map on ``grid``: per phase (eq. 7), or pixel-wise under sliding.

    A map the ladder rasterised is checked here (a phase may vanish on a
    coarse grid: ``ValueError``); one that is ``checked`` (the problem's own)
    is not checked again.
    """
    counts = (np.bincount(labels[labels >= 0], minlength=wear.n_phases) if checked
              else validate_labels(labels, wear.n_phases))
    if sliding is None:
        p = wear.phase_pressures(counts, normal_force, grid.pixel_area)
        return np.append(p, 0.0)[labels]  # label -1 (off the face) picks the trailing zero
    coefficients = wear.wear_field(labels) * sliding.speed_ratio(grid)
    return wear.factor.pixel_pressures(coefficients, normal_force, grid.pixel_area)


def estimate_rms_slope(geometry, wear, normal_force, outline, E_star, n, *, sliding=None,
                       labels=None, energy=None):
    """Energy-corrected rms slope of the limiting face, with an error estimate.

    Parameters
    ----------
    geometry : phase geometry
        An object of :mod:`steady.phases` (``labels(grid)``, ``check_grid(grid)``).
    wear : wear law or array_like, shape (P,)
        The phases' wear law (:mod:`steady.wear`); coefficients ``k_i``
        (1/Pa) stand for Archard's law.
    normal_force : float, N
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is the radius (m) of a
        circular face.
    E_star : float, Pa
    n : int
        Grid of the estimate, pixels along the longer side of the face's
        bounding box.
    sliding : sliding kinematics, optional
        Non-uniform sliding (:mod:`steady.sliding`): the pressure on every
        grid of the ladder is then its pixel-wise closed form, not constant
        per phase (default None: a translation).
    labels : ndarray of int, shape of the outline's grid ``n``, optional
        ``geometry``'s map at ``n``, if the caller has it (a problem's
        ``labels``): the ladder then does not rasterise ``n`` again, a
        large share of the cost at ``n = 4096``.  Not checked.
    energy : SlopeEnergy, optional
        A :class:`SlopeEnergy` of the grid ``n`` (its shape, pixel size and
        ``E_star``), if the caller has one: used there instead of building
        another.

    Returns
    -------
    SlopeEstimate
        The value on the finest grid of :func:`grid_ladder` (``n`` unless
        the geometry admits no coarser grid: then ``2n``) with the error of
        :func:`ladder_error` (``max(|S_n - S_n/2|, |S_n/2 - S_n/4| / 2)``
        for the ladder ``n/4, n/2, n``).
    """
    outline = as_outline(outline)
    wear = as_wear_law(wear)
    grids = grid_ladder(geometry, n, outline)
    values = []
    plain = None
    for m in grids:
        grid = FaceGrid(outline, m)
        given = labels is not None and m == n and labels.shape == grid.shape
        lab = labels if given else geometry.labels(grid)
        pressure = _steady_pressure(lab, wear, normal_force, grid, sliding, checked=given)
        reuse = (energy is not None and m == n and energy.shape == grid.shape
                 and energy.h == grid.h and energy.E_star == float(E_star))
        own = energy if reuse else slope_energy_of(grid, E_star)
        integrals = own(pressure, lab >= 0)
        del lab, pressure
        values.append(float(integrals.rms_slope))
        plain = float(integrals.rms_slope_plain)
        logger.debug("n=%d rms slope corrected %.8g plain %.8g", m, values[-1], plain)
    return SlopeEstimate(rms_slope=values[-1], error=float(ladder_error(grids, values)),
                         rms_slope_plain=plain,
                         grids=tuple(grids), values=tuple(values))


def resample_labels(labels, m, outline=None):
    """A phase map on the grid ``m``, read off a map given on another grid.

    Each pixel of the new grid takes the label of the pixel of ``labels``
    that contains its centre (for ``m = n/2`` the centre is a corner of four
    pixels: the one above and to the right of it); new face pixels whose
    centre falls off the old face take the nearest old face pixel's label.
    This is the rasterisation at ``m`` of the map that ``labels`` stands for,
    up to half a pixel of ``labels``: the ladder of a map with no geometry
    behind it.

    Parameters
    ----------
    labels : ndarray of int, shape (nx, ny)
        Phase index on the face, -1 off it; the grid of ``n = max(nx, ny)``
        pixels along the longer side of the outline's bounding box.
    m : int
        New grid size along the longer side, ``>= 2``.
    outline : outline object, optional
        The face (:mod:`steady.outline`); default the unit disk (``n x n``
        grids).

    Returns
    -------
    ndarray of int, shape of the outline's grid ``m`` (``(m, m)`` for a disk)
        -1 off the face of the ``m`` grid.

    Examples
    --------
    >>> from steady.phases import Voronoi
    >>> labels = Voronoi(64, (0.5, 0.5), 2024).labels(64)
    >>> resample_labels(labels, 32).shape
    (32, 32)
    """
    labels = np.asarray(labels)
    nx, ny = labels.shape
    n = max(nx, ny)
    m = int(m)
    if m < 2:
        raise ValueError(f"grid size m must be at least 2, got {m}")
    if outline is None and nx != ny:
        raise ValueError(f"a map of {nx} x {ny} pixels needs its face outline")
    grid = _grid(outline, m)
    shape, mask = grid.shape, grid.mask
    # Centres of the new pixels in old pixels from the old grid's corner.
    index = [np.clip(np.floor((np.arange(k) + 0.5) * n / m + (old - k * n / m) / 2)
                     .astype(int), 0, old - 1) for k, old in zip(shape, (nx, ny), strict=True)]
    # Off-face pixels take the nearest face pixel's label (the map's own face).
    picked = extend_off_face(labels, labels >= 0)[np.ix_(*index)]
    return np.where(mask, picked, -1)


#: Mean phase chord, in pixels, below which a resampled map is too coarse to
#: enter the ladder of :func:`estimate_map_rms_slope`.
MIN_CHORD_PIXELS = 4.0


def mean_chord(labels):
    """Mean chord of the phase regions of a map, in pixels (infinite for one phase).

    Cauchy's formula for an isotropic map: ``pi A / (2 L)``, with ``A`` the
    face area and ``L`` the length of the boundaries between phases, the
    staircase's edge count times ``pi / 4`` (its mean excess over the true
    length).  For a 30 % Voronoi map it is about twice the seed spacing.

    Parameters
    ----------
    labels : ndarray of int, shape (nx, ny)

    Returns
    -------
    float
    """
    labels = np.asarray(labels)
    face = labels >= 0
    edges = (np.sum((labels[1:] != labels[:-1]) & face[1:] & face[:-1])
             + np.sum((labels[:, 1:] != labels[:, :-1]) & face[:, 1:] & face[:, :-1]))
    return 2.0 * float(face.sum()) / edges if edges else float("inf")


def estimate_map_rms_slope(labels, wear, normal_force, outline, E_star, *, energy=None,
                          sliding=None):
    """Corrected rms slope of the limiting face of a pixel map, with an error estimate.

    As :func:`estimate_rms_slope`, for a map that exists only on its grid:
    the ladder is the map itself and the map resampled
    (:func:`resample_labels`) at ``n // 4`` and ``n // 2``.  A coarse grid
    enters when the map's mean phase chord (:func:`mean_chord`) spans at
    least :data:`MIN_CHORD_PIXELS` of its pixels (for Voronoi maps about the
    steady module's two pixels per seed spacing), the outline accepts it
    and every phase survives the resampling; when neither does, the
    coarsest such grid below ``n`` (a multiple of 8) serves, or if there is
    none ``n // 2``, which then over-estimates the error.  Measured against
    1024^2 references of continuous geometries (docs/benchmarks.md,
    "Run-in history"), the estimate is of the size of the error or larger.

    When no coarser grid keeps every phase (a phase of a few pixels
    vanishes in the resampling: a single-pixel phase, or rods of the
    smallest radius at their minimum grid), the map is refined instead, as
    the steady module refines a pixel map at its own size
    (:func:`grid_ladder`): each pixel becomes 2 x 2 pixels of the grid
    ``2n``, and the first-order error of the value on ``n`` is
    ``2 |S_2n - S_n|`` (``S_n - S = (S_n - S_2n) * 2n / (2n - n)``).  If
    even that is impossible, ``error`` is infinite: no bound, a marker
    that callers report as "no error bar", never NaN.

    Parameters
    ----------
    labels : ndarray of int, shape (nx, ny)
        Phase index ``0..P-1`` on the face, -1 off it, on the outline's
        grid of ``n = max(nx, ny)``.
    wear : wear law or array_like, shape (P,)
        The phases' wear law (:mod:`steady.wear`); coefficients ``k_i``
        (1/Pa) stand for Archard's law.
    normal_force : float, N
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is the radius (m) of a
        circular face.
    E_star : float, Pa
    energy : SlopeEnergy, optional
        The estimator of grid ``n``, if the caller has one.
    sliding : sliding kinematics, optional
        As in :func:`estimate_rms_slope`.

    Returns
    -------
    SlopeEstimate
        Value on ``n``; ``error`` is :func:`ladder_error` of the ladder, or
        with the refined grid ``2n`` (then the last of ``grids``) the error
        of the value on ``n``; infinite if neither can be had.
    """
    labels = np.asarray(labels)
    outline = as_outline(outline)
    wear = as_wear_law(wear)
    n = max(labels.shape)
    grid = FaceGrid(outline, n)
    if labels.shape != grid.shape:
        raise ValueError(f"a map of {labels.shape[0]} x {labels.shape[1]} pixels does not fit "
                         f"the grid of the {outline.describe()} ({grid.shape[0]} x "
                         f"{grid.shape[1]} pixels at n = {n})")

    def usable(m):
        return m >= low and _accepts(Homogeneous(), m, outline)

    low = max(MIN_SIDE_PIXELS, int(np.ceil(MIN_CHORD_PIXELS * n / mean_chord(labels))))
    coarse = [m for m in (n // 4, n // 2) if usable(m)]
    if not coarse:
        m = 8 * -(-low // 8)
        # A map too fine-grained for any admitted grid: n // 2 over-estimates.
        if m < n and usable(m):
            coarse = [m]
        elif n // 2 >= MIN_SIDE_PIXELS and _accepts(Homogeneous(), n // 2, outline):
            coarse = [n // 2]
    grids, values, plain = [], [], None
    for m in coarse + [n]:
        g = grid if m == n else FaceGrid(outline, m)
        lab = labels if m == n else resample_labels(labels, m, outline)
        try:
            pressure = _steady_pressure(lab, wear, normal_force, g, sliding)
        except ValueError:
            continue  # a phase vanished on the coarse grid
        estimator = energy if (m == n and energy is not None) else slope_energy_of(g, E_star)
        integrals = estimator(pressure, lab >= 0)
        grids.append(m)
        values.append(float(integrals.rms_slope))
        plain = float(integrals.rms_slope_plain)
    if len(grids) > 1:
        return SlopeEstimate(rms_slope=values[-1], error=float(ladder_error(grids, values)),
                             rms_slope_plain=plain, grids=tuple(grids), values=tuple(values))
    # No coarser grid keeps every phase: refine, as the steady module does with
    # a pixel map at its own size, and carry the difference back to n.
    error = math.inf
    try:
        fine = FaceGrid(outline, 2 * n)
        lab = resample_labels(labels, 2 * n, outline)
        pressure = _steady_pressure(lab, wear, normal_force, fine, sliding)
    except ValueError:
        logger.debug("no grid beside n = %d keeps every phase: no error estimate", n)
    else:
        refined = float(slope_energy_of(fine, E_star)(pressure, lab >= 0).rms_slope)
        error = 2.0 * abs(refined - values[0])
        grids.append(2 * n)
        values.append(refined)
    return SlopeEstimate(rms_slope=values[0], error=error, rms_slope_plain=plain,
                         grids=tuple(grids), values=tuple(values))
