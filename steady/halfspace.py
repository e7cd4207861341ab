"""Elastic half-space operator on a rectangular grid of square pixels (paper equation 8).

The surface displacement of an elastic half-space under a pressure that is
constant on each square pixel of side ``h`` is an aperiodic convolution of the
pixel pressures with the exact pixel influence coefficient (Love's closed form
of the integral of ``1/r`` over a rectangle; Johnson, *Contact Mechanics*,
sec. 3.9).  The surface gradient is the convolution with the exact
derivative of the same integral.  On an ``nx x ny`` grid both convolutions
are done by zero padding to ``2nx x 2ny`` and real FFTs (DC-FFT; Liu, Wang &
Liu, Wear 243, 2000, doi:10.1016/S0043-1648(00)00427-0).

Fourier-space arrays carry the suffix ``_q``.  The influence kernel is even
in both axes, so its spectrum is real; the derivative kernels are odd in
one axis, so their spectra are purely imaginary.  Only the real (resp.
imaginary) parts are stored.

The inverse transform keeps only the ``nx`` rows of the grid after its
column pass, and the padded input and the product's spectrum live in work
buffers allocated once, so that one product costs less than a plain padded
FFT pair.  The buffers make an instance unsafe to share between threads.
The product's transforms write into those buffers (``numpy.fft``'s ``out``,
NumPy 2; :mod:`scipy.fft` has none and returns fresh arrays of the padded
spectrum's size, which cost a copy and, at n = 1024, 17 MB of fresh pages per
transform), their lines shared among the ``workers`` threads.
"""

from __future__ import annotations

import concurrent.futures
import copy
import functools
import logging
import os
import threading

import numpy as np
import scipy.fft

from .schema import Key

__all__ = ["HalfSpace", "grid_shape", "pixel_integral", "pixel_integral_gradient"]

logger = logging.getLogger(__name__)

# The operator's inputs; their scale range is a problem's to check.
_PIXEL = Key("h", "number", unit="m", low=0.0, doc="pixel size")
_E_STAR = Key("E_star", "number", unit="Pa", low=0.0, doc="effective modulus")

# Whether numpy.fft writes into a given array (NumPy 2); else the product's
# transforms are scipy.fft's, into fresh arrays.
_FFT_OUT = np.lib.NumpyVersion(np.__version__) >= "2.0.0"
# Arrays of fewer elements are transformed on the calling thread alone.
_THREADED_SIZE = 1 << 16
# Grids of at least this many rows take the padded product's column transforms as two
# transforms of half the length (:meth:`HalfSpace._split_product`): faster there, not on
# smaller grids (docs/benchmarks.md, "Contact solve on run-in problems").
_SPLIT_ROWS = 2048
_POOL_LOCK = threading.Lock()
_POOL = []
# A forked child has none of the parent's pool threads: it makes its own.
os.register_at_fork(after_in_child=_POOL.clear)


def _thread_count(workers):
    """Threads meant by ``workers`` (:mod:`scipy.fft`'s convention: -1 is every core)."""
    cores = os.cpu_count() or 1
    return max(1, cores + 1 + workers if workers < 0 else workers)


def _pool():
    """The process's thread pool for the transforms' lines, made on first use."""
    with _POOL_LOCK:
        if not _POOL:
            _POOL.append(concurrent.futures.ThreadPoolExecutor(
                max(1, (os.cpu_count() or 1) - 1), thread_name_prefix="halfspace-fft"))
        return _POOL[0]


def _transform(name, a, out, axis, workers, **kwargs):
    """``numpy.fft.<name>(a, axis=axis, out=out, **kwargs)`` on ``workers`` threads.

    The lines along ``axis`` are independent: each thread takes a block of
    them (a slice of the other axis of the 2-d arrays ``a`` and ``out``).
    ``out`` may be ``a`` for a complex transform (in place).  Without
    NumPy 2's ``out``, :mod:`scipy.fft`'s transform is copied into ``out``.
    """
    if not _FFT_OUT:
        out[...] = getattr(scipy.fft, name)(a, axis=axis, workers=workers, **kwargs)
        return out
    function = getattr(np.fft, name)
    threads = _thread_count(workers) if a.size >= _THREADED_SIZE else 1
    other = 1 - axis
    edges = np.linspace(0, a.shape[other], threads + 1).astype(int)
    if threads == 1:
        return function(a, axis=axis, out=out, **kwargs)

    def block(i):
        part = (slice(None),) * other + (slice(edges[i], edges[i + 1]),)
        function(a[part], axis=axis, out=out[part], **kwargs)

    futures = [_pool().submit(block, i) for i in range(1, threads)]
    block(0)
    for future in futures:
        future.result()
    return out


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


def _corner_asinh(shape, h):
    """Corner coordinates and ``asinh`` lattices of an ``nx x ny`` grid.

    Corners sit at ``(i - 1/2) h`` for ``i = 0..nx+1`` along x and
    ``j = 0..ny+1`` along y; none is zero, so no case needs special
    treatment.  Returns ``(cx, cy, asinh(Y/|X|), asinh(X/|Y|))``, the two
    lattices of shape ``(nx + 2, ny + 2)``.  The same arrays yield the
    influence kernel and both derivative kernels; on a square grid the
    second lattice is the transpose of the first.
    """
    nx, ny = shape
    corners = (np.arange(max(nx, ny) + 2) - 0.5) * h
    lattice = np.arcsinh(corners[None, :] / np.abs(corners[:, None]))
    cx, cy = corners[: nx + 2], corners[: ny + 2]
    return cx, cy, lattice[: nx + 2, : ny + 2], lattice.T[: nx + 2, : ny + 2]


def _influence_quadrant(cx, cy, asinh_yx, asinh_xy):
    """Pixel integral of ``1/r`` at offsets ``0..nx`` by ``0..ny`` pixels, from the corners."""
    return _corner_sum(cx[:, None] * asinh_yx + cy[None, :] * asinh_xy)


def grid_shape(shape):
    """``(nx, ny)`` of a grid given as ``(nx, ny)`` or one ``n`` (square), checked.

    Raises
    ------
    ValueError
        If a size is not an integer of at least 2.
    """
    given = shape
    shape = (shape, shape) if np.ndim(shape) == 0 else tuple(shape)
    if len(shape) != 2:
        raise ValueError(f"grid shape must be n or (nx, ny), got {given!r}")
    out = []
    for v in shape:
        if isinstance(v, (bool, np.bool_)) or int(v) != v or int(v) < 2:
            raise ValueError(f"grid sizes must be integers of at least 2, got {given!r}")
        out.append(int(v))
    return tuple(out)


class HalfSpace:
    """Aperiodic elastic half-space operator on an ``nx x ny`` pixel grid.

    Build once per grid and modulus; the influence spectra are computed at
    construction (displacement) or on first use (gradient) and cached, so
    each product afterwards costs about one zero-padded FFT pair.

    Parameters
    ----------
    shape : int or (int, int)
        Pixels along each axis: ``(nx, ny)`` (x along axis 0, y along axis
        1), or one ``n`` for a square ``n x n`` grid (a face's grid:
        ``HalfSpace(grid.shape, grid.h, E_star)``).
    h : float, m
        Pixel side (pixels are square).
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)`` of the half-space.
    workers : int, optional
        Threads of the transforms, as :mod:`scipy.fft` counts them (-1, the
        default: all cores, at every size: docs/benchmarks.md, "Contact solve
        on run-in problems"); the product's transforms share their lines among
        them from 65536 elements up.

    Notes
    -----
    Arrays are indexed ``[i, j]`` with ``i`` along x (axis 0) and ``j``
    along y (axis 1); fields have the shape :attr:`shape`.  The displacement is ``u = K p`` with
    ``K(x) = 1/(pi E*) * integral over a pixel of 1/r``; it is positive
    into the half-space.

    Examples
    --------
    A uniform pressure ``p`` on the face: at the centre of a loaded disk the
    displacement is ``2 p a / E*``, here up to the staircase of the rim.

    >>> import numpy as np
    >>> from steady.outline import Circle
    >>> n, a, E_star, p = 64, 4e-3, 1.3e6, 1e4
    >>> grid = Circle(a).grid(n)
    >>> halfspace = HalfSpace(grid.shape, grid.h, E_star)
    >>> u = halfspace.displacement(np.where(grid.mask, p, 0.0))
    >>> u.shape
    (64, 64)
    >>> print(f"{u[n // 2, n // 2] / (2 * p * a / E_star):.3f}")
    1.002
    """

    def __init__(self, shape, h, E_star, *, workers=-1):
        self.shape = grid_shape(shape)
        nx, ny = self.shape
        self.h = _PIXEL.parse(h, "pixel size", scale=False)
        self.E_star = _E_STAR.parse(E_star, "", scale=False)
        self.workers = workers
        self._corners = _corner_asinh(self.shape, self.h)
        self._influence_q = self._even_spectrum(self.influence_quadrant)
        self._influence_q.flags.writeable = False
        self._gradient_q = None
        # Work buffers, reused by every product: the zero padding of the rows
        # is written once, and the padded spectrum of a product needs no
        # fresh allocation (at n = 1024 it is 34 MB, which the allocator
        # would map and fault in page by page at every call).
        self._rows = np.zeros((nx, 2 * ny))
        self._work = np.empty((2 * nx, ny + 1), dtype=complex)
        # exp(-i pi j / nx): the odd wavenumbers' shift of the split column transforms.
        self._twiddle = np.exp(-1j * np.pi * np.arange(nx) / nx)[:, None]

    def with_own_buffers(self, *, workers=None):
        """The same operator, sharing its spectra (read-only), with work buffers of its own.

        Products write into the work buffers: two threads need one operator
        each, and this one costs the buffers (about 48 bytes per pixel), not
        the spectra.

        Parameters
        ----------
        workers : int, optional
            ``scipy.fft`` workers of the new operator (default: this one's).

        Returns
        -------
        HalfSpace
        """
        own = copy.copy(self)
        own._rows, own._work = np.zeros_like(self._rows), np.empty_like(self._work)
        if workers is not None:
            own.workers = workers
        return own

    # -- spectra -------------------------------------------------------
    # The circulant 2nx x 2ny embeddings of the kernels are even (influence)
    # or odd in one axis (derivatives), so their spectra follow from the
    # (nx+1) x (ny+1) quadrant by type-I cosine and sine transforms, without
    # building the embedding.  The entries at offset nx (ny) never reach the
    # grid (offsets there span -(nx-1)..nx-1); the transforms take them as the
    # even extension's value, or as zero for an odd extension.
    def _even_spectrum(self, quadrant):
        """Real spectrum (2nx, ny + 1) of a kernel even in both axes."""
        nx, w = self.shape[0], self.workers
        c = scipy.fft.dct(scipy.fft.dct(quadrant, type=1, axis=0, workers=w),
                          type=1, axis=1, workers=w)
        return np.concatenate([c, c[nx - 1:0:-1]], axis=0)

    def _odd_x_spectrum(self, quadrant):
        """Imaginary part (2nx, ny + 1) of the spectrum of a kernel odd in x, even in y.

        ``X_k = -2i sum_j x_j sin(pi j k / nx)``: minus i times a type-I sine
        transform of the interior rows; ``X_{2nx-k} = -X_k``.
        """
        (nx, ny), w = self.shape, self.workers
        c = scipy.fft.dct(quadrant[1:nx], type=1, axis=1, workers=w)
        s = scipy.fft.dst(c, type=1, axis=0, workers=w)
        out = np.empty((2 * nx, ny + 1))
        out[0] = out[nx] = 0.0
        out[1:nx] = -s
        out[nx + 1:] = s[::-1]
        return out

    def _odd_y_spectrum(self, quadrant):
        """Imaginary part (2nx, ny + 1) of the spectrum of a kernel even in x, odd in y."""
        (nx, ny), w = self.shape, self.workers
        c = scipy.fft.dct(quadrant[:, 1:ny], type=1, axis=0, workers=w)
        s = scipy.fft.dst(c, type=1, axis=1, workers=w)
        out = np.empty((2 * nx, ny + 1))
        out[:, 0] = out[:, ny] = 0.0
        out[: nx + 1, 1:ny] = -s
        out[nx + 1:, 1:ny] = -s[nx - 1:0:-1]
        return out

    def _gradient_quadrants(self):
        """The x- and y-derivative kernels at offsets ``0..nx`` by ``0..ny`` pixels, 1/Pa."""
        _, _, asinh_yx, asinh_xy = self._corners
        scale = 1.0 / (np.pi * self.E_star)
        # d/dx: corner sum of asinh(Y/|X|); d/dy: of asinh(X/|Y|).
        return _corner_sum(asinh_yx) * scale, _corner_sum(asinh_xy) * scale

    def _ensure_gradient(self):
        if self._gradient_q is None:
            gx, gy = self._gradient_quadrants()
            # Both spectra are purely imaginary; their imaginary parts are kept.
            self._gradient_q = (self._odd_x_spectrum(gx), self._odd_y_spectrum(gy))
            for a in self._gradient_q:
                a.flags.writeable = False
            logger.debug("gradient spectra built for a %d x %d grid", *self.shape)
        return self._gradient_q

    # -- transforms ----------------------------------------------------
    def forward(self, field_r):
        """Spectrum of a grid field zero-padded to ``2nx x 2ny``.

        Parameters
        ----------
        field_r : ndarray, shape (nx, ny)

        Returns
        -------
        ndarray, shape (2nx, ny + 1), complex
        """
        return self._padded_spectrum(field_r, np.empty((2 * self.shape[0], self.shape[1] + 1),
                                                       dtype=complex))

    def _padded_spectrum(self, field_r, out):
        """:meth:`forward` into ``out`` (shape (2nx, ny + 1), complex), which it returns.

        The row transforms run on the grid's ``nx`` rows only (the padding
        rows are zero, and so are their transforms), then the column
        transforms in place: a quarter fewer operations than a transform of
        the whole padded array.
        """
        field_r = np.asarray(field_r)
        if field_r.shape != self.shape:
            raise ValueError(f"field must have shape {self.shape}, got {field_r.shape}")
        nx, ny = self.shape
        self._rows[:, :ny] = field_r
        _transform("rfft", self._rows, out[:nx], 1, self.workers)
        out[nx:] = 0.0
        return _transform("fft", out, out, 0, self.workers)

    def inverse(self, spectrum_q, *, overwrite=False):
        """Real field on the grid from a padded half spectrum.

        Parameters
        ----------
        spectrum_q : ndarray, shape (2nx, ny + 1), complex
        overwrite : bool, optional
            The spectrum may be destroyed (default False).

        Returns
        -------
        ndarray, shape (nx, ny)
        """
        nx, ny = self.shape
        if not overwrite:
            spectrum_q = spectrum_q.copy()
        # Only the grid's nx rows are kept after the column transform.
        cols = _transform("ifft", spectrum_q, spectrum_q, 0, self.workers)[:nx]
        field = _transform("irfft", cols, np.empty((nx, 2 * ny)), 1, self.workers, n=2 * ny)
        return field[:, :ny]

    def _product(self, pressure_q, kernel_q):
        """Field on the face of ``kernel_q * pressure_q``, through the work buffer."""
        np.multiply(pressure_q, kernel_q, out=self._work)
        return self.inverse(self._work, overwrite=True)

    # -- operators -----------------------------------------------------
    def displacement(self, pressure_r):
        """Surface displacement under a pixel-wise constant pressure (eq. 8).

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa

        Returns
        -------
        ndarray, shape (nx, ny), m
        """
        if self.shape[0] >= _SPLIT_ROWS:
            return self._split_product(pressure_r)
        return self._product(self._padded_spectrum(pressure_r, self._work), self._influence_q)

    def _split_product(self, pressure_r):
        """:meth:`displacement` with column transforms of length ``nx``, not ``2 nx``.

        The padded column transform of a column zero on its last ``nx``
        entries is, at its even wavenumbers, the length-``nx`` transform of
        the column and, at its odd ones, that of the column times
        ``exp(-i pi j / nx)``; of the inverse only the grid's ``nx`` rows are
        kept, the even wavenumbers' inverse plus ``exp(i pi j / nx)`` times the
        odd ones'.  The two halves live in the work buffer; no zero padding is
        written.  The same product to round-off.
        """
        pressure_r = np.asarray(pressure_r)
        if pressure_r.shape != self.shape:
            raise ValueError(f"field must have shape {self.shape}, got {pressure_r.shape}")
        (nx, ny), w = self.shape, self.workers
        even, odd = self._work.reshape(2, nx, ny + 1)
        # The inverse's 1/(2 nx) over the half-length transforms' 1/nx, exact in binary.
        np.multiply(pressure_r, 0.5, out=self._rows[:, :ny])
        _transform("rfft", self._rows, even, 1, w)
        np.multiply(even, self._twiddle, out=odd)
        for half, kernel in ((even, self._influence_q[0::2]), (odd, self._influence_q[1::2])):
            _transform("fft", half, half, 0, w)
            half *= kernel
            _transform("ifft", half, half, 0, w)
        odd *= self._twiddle.conj()
        even += odd
        field = _transform("irfft", even, np.empty((nx, 2 * ny)), 1, w, n=2 * ny)
        return field[:, :ny]

    def displacement_q(self, pressure_q):
        """Displacement from an already transformed pressure (see :meth:`forward`)."""
        return self._product(pressure_q, self._influence_q)

    def gradient(self, pressure_r, *, pressure_q=None):
        """Surface gradient ``(du/dx, du/dy)`` at the pixel centres.

        Exact derivative of the pixel integral convolved with the pressure;
        no finite differences.

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa
        pressure_q : ndarray, shape (2nx, ny + 1), optional
            The pressure's spectrum, if already computed.

        Returns
        -------
        gx, gy : ndarray, shape (nx, ny), dimensionless
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
        """Influence coefficients at pixel offsets ``0..nx`` by ``0..ny``, m/Pa.

        Displacement at offset ``(i, j)`` pixels from a pixel under unit
        pressure; the kernel is even in both axes.  Shape ``(nx + 1, ny + 1)``,
        computed once, read-only.
        """
        quadrant = _influence_quadrant(*self._corners) / (np.pi * self.E_star)
        quadrant.flags.writeable = False
        return quadrant

    @functools.cached_property
    def aliased_symbol(self):
        """Symbol of the ``(nx, ny)``-periodic aliasing of the influence kernel, m/Pa.

        The padded symbol at the even wavenumbers (positive, like it); shape
        ``(nx, ny // 2 + 1)``, the spectrum layout of an unpadded ``rfft2``.
        Computed once, read-only.  The Fourier preconditioner of the contact
        solver inverts it.
        """
        symbol = np.ascontiguousarray(self._influence_q[::2, ::2])
        symbol.flags.writeable = False
        return symbol

    @property
    def influence_symbol(self):
        """Real spectrum of the padded ``2nx x 2ny`` influence kernel, m/Pa.

        ``inverse(forward(p) * influence_symbol)`` is :meth:`displacement`;
        shape ``(2nx, ny + 1)``, read-only.
        """
        return self._influence_q

    @functools.cached_property
    def compliance_floor(self):
        """Lower bound of the eigenvalues of ``K`` on any contact set, m/Pa.

        The minimum of the zero-padded circulant's symbol, which bounds every
        principal submatrix of ``K`` from below.
        """
        return float(np.min(self._influence_q))

    @property
    def self_influence(self):
        """Displacement of a pixel per unit pressure on itself, m/Pa."""
        return 4 * self.h * np.arcsinh(1.0) / (np.pi * self.E_star)


