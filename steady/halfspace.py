"""Elastic half-space operator on a square pixel grid (paper eq. 8).

The surface displacement of an elastic half-space under a pressure that is
constant on each square pixel of side ``h`` is an aperiodic convolution of the
pixel pressures with the exact pixel influence coefficient (Love's closed form
of the integral of ``1/r`` over a rectangle; Johnson, *Contact Mechanics*,
sec. 3.9).  The surface gradient is the convolution with the exact
derivative of the same integral.  Both convolutions are done by zero padding
to ``2n x 2n`` and real FFTs (DC-FFT; Liu, Wang & Liu, Wear 243, 2000,
doi:10.1016/S0043-1648(00)00427-0).

Fourier-space arrays carry the suffix ``_q``.  The influence kernel is even
in both axes, so its spectrum is real; the derivative kernels are odd in
one axis, so their spectra are purely imaginary.  Only the real (resp.
imaginary) parts are stored.

The inverse transform keeps only the ``n`` rows of the face after its
column pass, and the padded input and the product's spectrum live in work
buffers allocated once, so that one product costs less than a plain padded
FFT pair.  The buffers make an instance unsafe to share between threads.
"""

from __future__ import annotations

import functools
import logging

import numpy as np
import scipy.fft

__all__ = ["HalfSpace", "pixel_integral", "pixel_integral_gradient"]

logger = logging.getLogger(__name__)


def _corner_sum(values):
    """Second mixed difference over the corners of each pixel.

    ``values[i, j]`` is an antiderivative sampled at the corner
    ``((i - 1/2) h, (j - 1/2) h)``; the result at ``(i, j)`` is
    ``F(i+1, j+1) - F(i, j+1) - F(i+1, j) + F(i, j)``.
    """
    return values[1:, 1:] - values[:-1, 1:] - values[1:, :-1] + values[:-1, :-1]


def pixel_integral(offsets_x, offsets_y, h):
    """Integral of ``1/r`` over a square pixel, seen from a point.

    Parameters
    ----------
    offsets_x, offsets_y : ndarray, shape (m,), m
        Offsets of the observation points from the pixel centre along each
        axis; they form an ``m x m`` grid (``indexing='ij'``).  Offsets
        must not lie on the pixel's edges (``|offset| == h/2``).
    h : float, m
        Side of the pixel.

    Returns
    -------
    ndarray, shape (m, m), m
        ``integral over the pixel of 1/|x - x'| dA'``.  Multiply by
        ``1 / (pi E*)`` for the displacement per unit pressure (eq. 8).

    Notes
    -----
    With ``X = x - x'`` and ``Y = y - y'``, an antiderivative of ``1/R`` is
    ``G = X ln(Y + R) + Y ln(X + R)``.  The terms ``X ln|X|`` and
    ``Y ln|Y|`` cancel in the corner sum, which leaves the form
    ``X asinh(Y/|X|) + Y asinh(X/|Y|)``, free of cancellation for ``X``
    or ``Y`` of either sign.
    """
    return _pixel_corner_sum(np.asarray(offsets_x, float), np.asarray(offsets_y, float), h,
                             _antiderivative)


def pixel_integral_gradient(offsets_x, offsets_y, h):
    """x-derivative of :func:`pixel_integral` with respect to the observation point.

    Parameters
    ----------
    offsets_x, offsets_y : ndarray, shape (m,), m
        As in :func:`pixel_integral`.
    h : float, m
        Side of the pixel.

    Returns
    -------
    ndarray, shape (m, m), dimensionless
        ``d/dx integral over the pixel of 1/|x - x'| dA'``.  The
        y-derivative is the transpose of this function with the offsets
        swapped.

    Notes
    -----
    ``dG/dX = ln(Y + R) + 1``; in the corner sum the constant and the
    ``ln|X|`` parts cancel, leaving ``asinh(Y/|X|)``.  The result is
    log-singular on the pixel's edges ``|x| = h/2``.
    """
    return _pixel_corner_sum(np.asarray(offsets_x, float), np.asarray(offsets_y, float), h,
                             _antiderivative_dx)


def _antiderivative(X, Y):
    ax = np.abs(X)
    ay = np.abs(Y)
    with np.errstate(divide="ignore", invalid="ignore"):
        gx = np.where(ax > 0, X * np.arcsinh(Y / np.where(ax > 0, ax, 1.0)), 0.0)
        gy = np.where(ay > 0, Y * np.arcsinh(X / np.where(ay > 0, ay, 1.0)), 0.0)
    return gx + gy


def _antiderivative_dx(X, Y):
    ax = np.abs(X)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.arcsinh(Y / ax)


def _pixel_corner_sum(ox, oy, h, antiderivative):
    """Corner sum of ``antiderivative`` for every pair of offsets (ox, oy)."""
    # Each point needs the four corners (ox +- h/2, oy +- h/2).
    Xm, Xp = ox - h / 2, ox + h / 2
    Ym, Yp = oy - h / 2, oy + h / 2
    F = antiderivative
    return (F(Xp[:, None], Yp[None, :]) - F(Xm[:, None], Yp[None, :])
            - F(Xp[:, None], Ym[None, :]) + F(Xm[:, None], Ym[None, :]))


def _corner_asinh(n, h):
    """``asinh(Y/|X|)`` on the ``(n + 2)^2`` lattice of pixel corners.

    Corners sit at ``(i - 1/2) h`` for ``i = 0..n+1``; none is zero, so no
    case needs special treatment.  The same array yields the influence
    kernel and the x-derivative kernel.
    """
    corners = (np.arange(n + 2) - 0.5) * h
    return corners, np.arcsinh(corners[None, :] / np.abs(corners[:, None]))


def _influence_quadrant(corners, asinh):
    """Pixel integral of ``1/r`` at offsets ``0..n`` pixels, from the corner lattice."""
    g = corners[:, None] * asinh  # X asinh(Y/|X|); the other half is its transpose
    g += g.T
    return _corner_sum(g)


class HalfSpace:
    """Aperiodic elastic half-space operator on an ``n x n`` pixel grid.

    Build once per grid and modulus; the influence spectra are computed at
    construction (displacement) or on first use (gradient) and cached, so
    each product afterwards costs about one zero-padded FFT pair.

    Parameters
    ----------
    n : int
        Pixels along each axis of the square grid.
    h : float, m
        Pixel side.
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)`` of the half-space.
    workers : int, optional
        Threads for :mod:`scipy.fft` (default: all cores).

    Notes
    -----
    Arrays are indexed ``[i, j]`` with ``i`` along x (axis 0) and ``j``
    along y (axis 1).  The displacement is ``u = K p`` with
    ``K(x) = 1/(pi E*) * integral over a pixel of 1/r``; it is positive
    into the half-space.

    Examples
    --------
    A uniform pressure ``p`` on the face: at the centre of a loaded disk the
    displacement is ``2 p a / E*``, here up to the staircase of the rim.

    >>> import numpy as np
    >>> from steady.grid import face_mask, pixel_size
    >>> n, a, E_star, p = 64, 4e-3, 1.3e6, 1e4
    >>> halfspace = HalfSpace(n, pixel_size(n, a), E_star)
    >>> u = halfspace.displacement(np.where(face_mask(n), p, 0.0))
    >>> u.shape
    (64, 64)
    >>> print(f"{u[n // 2, n // 2] / (2 * p * a / E_star):.3f}")
    1.002
    """

    def __init__(self, n, h, E_star, *, workers=-1):
        n = int(n)
        if n < 2:
            raise ValueError(f"grid size n must be at least 2, got {n}")
        if not (np.isfinite(h) and h > 0):
            raise ValueError(f"pixel size h must be positive and finite, got {h!r} m")
        if not (np.isfinite(E_star) and E_star > 0):
            raise ValueError(f"E_star must be positive and finite, got {E_star!r} Pa")
        self.n = n
        self.h = float(h)
        self.E_star = float(E_star)
        self.workers = workers
        self._m = 2 * n  # padded size
        self._corners = _corner_asinh(n, self.h)
        self._influence_q = self._even_spectrum(self.influence_quadrant)
        self._influence_q.flags.writeable = False
        self._gradient_q = None
        # Work buffers, reused by every product: the zero padding is written
        # once, and the products need no fresh allocation.
        self._padded = np.zeros((self._m, self._m))
        self._work = np.empty((self._m, n + 1), dtype=complex)

    # -- spectra -------------------------------------------------------
    # The circulant 2n x 2n embeddings of the kernels are even (influence)
    # or odd in one axis (derivatives), so their spectra follow from the
    # (n+1) x (n+1) quadrant by type-I cosine and sine transforms, without
    # building the embedding.  The entry at offset n never reaches the face
    # (offsets there span -(n-1)..n-1); the transforms take it as the even
    # extension's value, or as zero for an odd extension.
    def _even_spectrum(self, quadrant):
        """Real spectrum (2n, n + 1) of a kernel even in both axes."""
        n, w = self.n, self.workers
        c = scipy.fft.dct(scipy.fft.dct(quadrant, type=1, axis=0, workers=w),
                          type=1, axis=1, workers=w)
        return np.concatenate([c, c[n - 1:0:-1]], axis=0)

    def _odd_x_spectrum(self, quadrant):
        """Imaginary part (2n, n + 1) of the spectrum of a kernel odd in x, even in y.

        ``X_k = -2i sum_j x_j sin(pi j k / n)``: minus i times a type-I sine
        transform of the interior rows; ``X_{2n-k} = -X_k``.
        """
        n, w = self.n, self.workers
        c = scipy.fft.dct(quadrant[1:n], type=1, axis=1, workers=w)
        s = scipy.fft.dst(c, type=1, axis=0, workers=w)
        out = np.empty((2 * n, n + 1))
        out[0] = out[n] = 0.0
        out[1:n] = -s
        out[n + 1:] = s[::-1]
        return out

    def _odd_y_spectrum(self, quadrant):
        """Imaginary part (2n, n + 1) of the spectrum of a kernel even in x, odd in y."""
        n, w = self.n, self.workers
        c = scipy.fft.dct(quadrant[:, 1:n], type=1, axis=0, workers=w)
        s = scipy.fft.dst(c, type=1, axis=1, workers=w)
        out = np.empty((2 * n, n + 1))
        out[:, 0] = out[:, n] = 0.0
        out[: n + 1, 1:n] = -s
        out[n + 1:, 1:n] = -s[n - 1:0:-1]
        return out

    def _ensure_gradient(self):
        if self._gradient_q is None:
            _, asinh = self._corners
            dx = _corner_sum(asinh) / (np.pi * self.E_star)
            # d/dy is d/dx transposed.  Both spectra are purely imaginary;
            # their imaginary parts are kept.
            self._gradient_q = (self._odd_x_spectrum(dx), self._odd_y_spectrum(dx.T))
            for a in self._gradient_q:
                a.flags.writeable = False
            logger.debug("gradient spectra built for n=%d", self.n)
        return self._gradient_q

    # -- transforms ----------------------------------------------------
    def forward(self, field_r):
        """Spectrum of a face field zero-padded to ``2n x 2n``.

        Parameters
        ----------
        field_r : ndarray, shape (n, n)

        Returns
        -------
        ndarray, shape (2n, n + 1), complex
        """
        field_r = np.asarray(field_r)
        if field_r.shape != (self.n, self.n):
            raise ValueError(
                f"field must have shape {(self.n, self.n)}, got {field_r.shape}")
        n = self.n
        self._padded[:n, :n] = field_r
        return scipy.fft.rfft2(self._padded, workers=self.workers)

    def inverse(self, spectrum_q, *, overwrite=False):
        """Real field on the face from a padded half spectrum.

        Parameters
        ----------
        spectrum_q : ndarray, shape (2n, n + 1), complex
        overwrite : bool, optional
            The spectrum may be destroyed (default False).

        Returns
        -------
        ndarray, shape (n, n)
        """
        n, m = self.n, self._m
        # Only the face's n rows are kept after the column transform.
        cols = scipy.fft.ifft(spectrum_q, axis=0, workers=self.workers,
                              overwrite_x=overwrite)[:n]
        return scipy.fft.irfft(cols, n=m, axis=1, workers=self.workers)[:, :n]

    def _product(self, pressure_q, kernel_q):
        """Field on the face of ``kernel_q * pressure_q``, through the work buffer."""
        np.multiply(pressure_q, kernel_q, out=self._work)
        return self.inverse(self._work, overwrite=True)

    # -- operators -----------------------------------------------------
    def displacement(self, pressure_r):
        """Surface displacement under a pixel-wise constant pressure (eq. 8).

        Parameters
        ----------
        pressure_r : ndarray, shape (n, n), Pa

        Returns
        -------
        ndarray, shape (n, n), m
        """
        return self._product(self.forward(pressure_r), self._influence_q)

    def displacement_q(self, pressure_q):
        """Displacement from an already transformed pressure (see :meth:`forward`)."""
        return self._product(pressure_q, self._influence_q)

    def gradient(self, pressure_r, *, pressure_q=None):
        """Surface gradient ``(du/dx, du/dy)`` at the pixel centres.

        Exact derivative of the pixel integral convolved with the pressure;
        no finite differences.

        Parameters
        ----------
        pressure_r : ndarray, shape (n, n), Pa
        pressure_q : ndarray, shape (2n, n + 1), optional
            The pressure's spectrum, if already computed.

        Returns
        -------
        gx, gy : ndarray, shape (n, n), dimensionless
        """
        gx_q, gy_q = self._ensure_gradient()
        if pressure_q is None:
            pressure_q = self.forward(pressure_r)
        # The spectra are i times real arrays: the factor i goes on the
        # pressure once for both components.
        i_pressure_q = pressure_q * 1j
        return self._product(i_pressure_q, gx_q), self._product(i_pressure_q, gy_q)

    @functools.cached_property
    def influence_quadrant(self):
        """Influence coefficients at pixel offsets ``0..n`` along each axis, m/Pa.

        Displacement at offset ``(i, j)`` pixels from a pixel under unit
        pressure; the kernel is even in both axes.  Shape ``(n + 1, n + 1)``,
        computed once, read-only.
        """
        quadrant = _influence_quadrant(*self._corners) / (np.pi * self.E_star)
        quadrant.flags.writeable = False
        return quadrant

    @functools.cached_property
    def aliased_symbol(self):
        """Symbol of the ``n``-periodic aliasing of the influence kernel, m/Pa.

        The padded symbol at the even wavenumbers (positive, like it); shape
        ``(n, n // 2 + 1)``, the spectrum layout of an unpadded ``rfft2``.
        Computed once, read-only.  The Fourier preconditioner of the contact
        solver inverts it.
        """
        symbol = np.ascontiguousarray(self._influence_q[::2, ::2])
        symbol.flags.writeable = False
        return symbol

    @property
    def influence_symbol(self):
        """Real spectrum of the padded ``2n x 2n`` influence kernel, m/Pa.

        ``inverse(forward(p) * influence_symbol)`` is :meth:`displacement`;
        shape ``(2n, n + 1)``, read-only.
        """
        return self._influence_q

    @property
    def self_influence(self):
        """Displacement of a pixel per unit pressure on itself, m/Pa."""
        return 4 * self.h * np.arcsinh(1.0) / (np.pi * self.E_star)


