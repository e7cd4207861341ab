"""Accurate rms slope of a worn face, with an estimate of its discretisation error.

The surface gradient of the face is log-singular at the rim and along every
phase boundary.  The plain pixel estimate (mean of ``|grad f|^2`` at the
pixel centres of the face) converges only about first order, with an error
proportional to the boundary length per pixel, so that at a fixed grid it
depends on the grain size.  This module removes most of that error.

Method
------
For any pressure ``p`` on the plane, Parseval's theorem and the half-space
symbol ``u_q = 2 p_q / (E* |q|)`` give the exact identity

    integral over the plane of |grad u|^2 dA = (4 / E*^2) integral of p^2 dA,

whose right-hand side is exact on the grid.  Hence the mean-square slope on
the face is the total minus the *exterior* integral, and the exterior field
is smooth everywhere except next to the rim: the log singularities along
internal phase boundaries drop out.  The exterior integral is computed by
pixel quadrature on a fine box around the face, on a coarse box
(block-summed sources) out to ``far_radius`` radii, and analytically
(monopole about the load centroid) beyond.

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
validation against fine-grid references.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import scipy.fft

from .grid import pixel_size
from .halfspace import pixel_integral_gradient

__all__ = ["SlopeEnergy", "SlopeEstimate", "SlopeIntegrals", "edge_jumps", "estimate_rms_slope",
           "monopole_tail"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class SlopeIntegrals:
    """Integrals of ``|grad f|^2`` for one pressure field on one grid.

    Attributes
    ----------
    face_area : float, m^2
        Pixel count of the face times ``h^2``.
    total : float, m^2
        ``(4 / E*^2) sum p^2 h^2``: the exact integral over the plane.
    face : float, m^2
        Plain pixel quadrature over the face.
    exterior : float, m^2
        Pixel quadrature over the exterior plus the analytic far tail.
    rim_share : float
        Fraction of the squared pressure jumps that sits on the rim.
    """

    face_area: float
    total: float
    face: float
    exterior: float
    rim_share: float

    @property
    def defect(self):
        """Quadrature defect ``T - I - X``, m^2 (zero for an exact quadrature)."""
        return self.total - self.face - self.exterior

    @property
    def corrected(self):
        """Corrected integral over the face, m^2."""
        return self.total - self.exterior - 0.5 * self.rim_share * self.defect

    @property
    def rms_slope(self):
        """Corrected rms slope over the face, dimensionless."""
        return float(np.sqrt(max(self.corrected, 0.0) / self.face_area))

    @property
    def rms_slope_plain(self):
        """Plain pixel rms slope over the face, dimensionless."""
        return float(np.sqrt(self.face / self.face_area))


def edge_jumps(pressure_r, face):
    """Squared pressure jumps summed over pixel edges.

    Parameters
    ----------
    pressure_r : ndarray, shape (n, n), Pa
    face : ndarray of bool, shape (n, n)

    Returns
    -------
    interior : float, Pa^2
        Over edges between two face pixels.
    rim : float, Pa^2
        Over edges between a face pixel and a pixel off the face
        (including the grid's border).
    """
    p = np.where(face, pressure_r, 0.0)
    f = np.pad(face, 1)
    p = np.pad(p, 1)
    interior = rim = 0.0
    for axis in (0, 1):
        a = np.moveaxis(p, axis, 0)
        m = np.moveaxis(f, axis, 0)
        jump = (a[1:] - a[:-1]) ** 2
        interior += float(jump[m[1:] & m[:-1]].sum())
        rim += float(jump[m[1:] ^ m[:-1]].sum())
    return interior, rim


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
    cx, cy = centroid
    x0, x1, y0, y1 = box
    # (distance to the side, the side's tangential extent on either side of the foot)
    sides = [(x1 - cx, cy - y0, y1 - cy), (cx - x0, cy - y0, y1 - cy),
             (y1 - cy, cx - x0, x1 - cx), (cy - y0, cx - x0, x1 - cx)]
    integral = 0.0
    for d, lo, hi in sides:
        for t in (lo, hi):
            phi = np.arctan2(t, d)
            integral += (phi / 2 + np.sin(2 * phi) / 4) / (2 * d * d)
    return (force / (np.pi * E_star)) ** 2 * integral


class _BoxGradient:
    """``|grad u|^2`` on an output box from sources on a (coarser) pixel grid.

    Sources occupy pixel indices ``[0, ns)`` on both axes with spacing
    ``H``; outputs are the pixel centres ``[lo, lo + m)`` of the same
    lattice.  Aperiodic linear convolution by FFT of the smallest fast size.
    """

    def __init__(self, ns, lo, m, H, E_star, workers):
        self.ns, self.lo, self.m, self.workers = ns, lo, m, workers
        size = scipy.fft.next_fast_len(ns + m - 1, real=True)
        self.size = size
        offsets = np.arange(lo - ns + 1, lo + m)
        dx = pixel_integral_gradient(offsets * H, offsets * H, H) / (np.pi * E_star)
        index = np.mod(offsets, size)
        kernel = np.zeros((size, size))
        kernel[np.ix_(index, index)] = dx
        self.gx_q = scipy.fft.rfft2(kernel, workers=workers)
        kernel[np.ix_(index, index)] = dx.T
        self.gy_q = scipy.fft.rfft2(kernel, workers=workers)
        self.rows = np.mod(np.arange(lo, lo + m), size)

    def __call__(self, sources):
        s = (self.size, self.size)
        sq = scipy.fft.rfft2(sources, s=s, workers=self.workers)
        out = np.zeros((self.m, self.m))
        for kq in (self.gx_q, self.gy_q):
            g = scipy.fft.irfft2(sq * kq, s=s, workers=self.workers)
            g = g[np.ix_(self.rows, self.rows)]
            out += g * g
        return out


class SlopeEnergy:
    """Energy-corrected quadrature of the slope on one grid (see module notes).

    Build once per grid; kernel spectra are cached.

    Parameters
    ----------
    n : int
        Pixels across the grid of the face.
    h : float, m
        Pixel size.
    E_star : float, Pa
    margin : int, optional
        Fine pixels kept around the grid (default ``max(8, n // 16)``);
        they carry the rim's exterior at the grid's own resolution.
    coarsening : int, optional
        Ratio of coarse to fine pixel size (default 4).
    far_radius : float, optional
        Half-width of the coarse box in units of the grid's half-width
        (default 8); beyond it the monopole tail is analytic.
    workers : int, optional
        Threads for :mod:`scipy.fft`.
    """

    def __init__(self, n, h, E_star, *, margin=None, coarsening=4, far_radius=8.0,
                 workers=-1):
        self.n, self.h, self.E_star = int(n), float(h), float(E_star)
        c = int(coarsening)
        margin = max(8, self.n // 16) if margin is None else int(margin)
        # The fine box must tile into coarse pixels: round its size up.
        margin = c * -(-margin // c)
        fine = self.n + 2 * margin
        fine = c * -(-fine // c)
        self.c, self.margin, self.fine = c, margin, fine
        self._fine = _BoxGradient(self.n, -margin, fine, self.h, self.E_star, workers)
        # Coarse sources are the fine box block-summed; outputs span far_radius.
        nc = fine // c
        half = far_radius * self.n / 2  # in fine pixels, from the grid centre
        extra = max(1, int(np.ceil((half - fine / 2) / c)))
        self._coarse = _BoxGradient(nc, -extra, nc + 2 * extra, c * self.h, self.E_star, workers)
        self._coarse_inner = slice(extra, extra + nc)
        self._coarse_extra = extra

    def __call__(self, pressure_r, face):
        """Integrals of ``|grad f|^2`` for a pressure on the face.

        Parameters
        ----------
        pressure_r : ndarray, shape (n, n), Pa
            Zero off the face.
        face : ndarray of bool, shape (n, n)

        Returns
        -------
        SlopeIntegrals
        """
        n, h, m = self.n, self.h, self.margin
        p = np.where(face, pressure_r, 0.0)
        area = h * h
        g2 = self._fine(p)
        on_face = np.zeros(g2.shape, dtype=bool)
        on_face[m:m + n, m:m + n] = face
        face_sum = float(g2[on_face].sum()) * area
        exterior = float(g2[~on_face].sum()) * area

        boxed = np.zeros((self.fine, self.fine))
        boxed[m:m + n, m:m + n] = p
        c = self.c
        coarse_p = boxed.reshape(self.fine // c, c, self.fine // c, c).mean(axis=(1, 3))
        g2c = self._coarse(coarse_p)
        g2c[self._coarse_inner, self._coarse_inner] = 0.0
        exterior += float(g2c.sum()) * (c * h) ** 2

        force = float(p.sum()) * area
        x = (np.arange(n) - (n - 1) / 2) * h
        centroid = (float(x @ p.sum(axis=1)) * area / force, float(x @ p.sum(axis=0)) * area / force)
        lo = (-n / 2 - m - self._coarse_extra * c) * h
        hi = lo + (self.fine + 2 * self._coarse_extra * c) * h
        exterior += monopole_tail(force, centroid, (lo, hi, lo, hi), self.E_star)

        total = 4.0 / self.E_star**2 * float(np.sum(p * p)) * area
        interior_jumps, rim_jumps = edge_jumps(p, face)
        jumps = interior_jumps + rim_jumps
        rim_share = rim_jumps / jumps if jumps > 0 else 1.0
        return SlopeIntegrals(face_area=float(face.sum()) * area, total=total, face=face_sum,
                              exterior=exterior, rim_share=rim_share)


@dataclasses.dataclass(frozen=True)
class SlopeEstimate:
    """Rms slope of a limiting face with its estimated discretisation error.

    Attributes
    ----------
    rms_slope : float, dimensionless
        Energy-corrected rms slope on the finest grid in ``grids``.
    error : float, dimensionless
        Estimated absolute discretisation error of ``rms_slope``.
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

    @property
    def relative_error(self):
        """``error / rms_slope``."""
        return self.error / self.rms_slope


def _ladder(geometry, n):
    """Grids for the estimate: ``n/4, n/2, n`` where the geometry allows, else ``n, 2n``."""
    coarse = []
    for d in (4, 2):
        if n % d == 0:
            try:
                geometry.check_grid(n // d)
            except ValueError:
                continue
            coarse.append(n // d)
    if coarse:
        return coarse + [n]
    return [n, 2 * n]


def estimate_rms_slope(geometry, wear_coefficients, normal_force, radius, E_star, n, *,
                       exponent=1.0):
    """Energy-corrected rms slope of the limiting face, with an error estimate.

    Parameters
    ----------
    geometry : phase geometry
        An object of :mod:`steady.phases` (``labels(n)``, ``check_grid(n)``).
    wear_coefficients : array_like, shape (P,), 1/Pa
    normal_force : float, N
    radius : float, m
    E_star : float, Pa
    n : int
        Grid of the estimate.
    exponent : float, optional
        Pressure exponent ``m`` of the wear law (default 1).

    Returns
    -------
    SlopeEstimate
        The value on grid ``n`` with the error
        ``max(|S_n - S_n/2|, |S_n/2 - S_n/4| / 2)`` from the same geometry
        rasterised at ``n/2`` and ``n/4``.  Where the geometry admits no
        coarser grid (a pixel map at its own size, or ``n`` near the
        coarsest grid the geometry accepts) the value comes from ``2n``
        and the error is ``|S_2n - S_n|``.
    """
    from .solution import phase_pressures  # solution imports this module's users

    grids = _ladder(geometry, int(n))
    values = []
    plain = None
    for m in grids:
        labels = geometry.labels(m)
        face = labels >= 0
        n_phases = int(labels.max()) + 1
        counts = np.bincount(labels[face], minlength=n_phases)
        h = pixel_size(m, radius)
        p = phase_pressures(counts, wear_coefficients, normal_force, h * h, exponent=exponent)
        pressure = np.where(face, np.append(p, 0.0)[labels], 0.0)
        integrals = SlopeEnergy(m, h, E_star)(pressure, face)
        values.append(integrals.rms_slope)
        plain = integrals.rms_slope_plain
        logger.debug("n=%d rms slope corrected %.8g plain %.8g", m, values[-1], plain)
    if len(values) >= 3:
        error = max(abs(values[-1] - values[-2]), abs(values[-2] - values[-3]) / 2)
    else:
        error = abs(values[-1] - values[0])
    return SlopeEstimate(rms_slope=values[-1], error=float(error), rms_slope_plain=plain,
                         grids=tuple(grids), values=tuple(values))
