"""Memory: what a computation needs, what the machine has, and the allocator's setting.

:func:`steady_memory` estimates the peak memory of a steady solve from the
arrays it allocates (:func:`halfspace_memory`, :func:`product_memory`,
:func:`slope_estimator_memory` count its parts), :func:`fit_memory` that of
a wear-ratio fit (:mod:`steady.fit`); :func:`check_memory`
compares an estimate with the memory available (:func:`available_memory`)
or with a given limit and refuses a computation that does not fit.
:func:`keep_freed_memory` sets the C allocator of the process to keep freed
large blocks (for the commands, which allocate grid-sized arrays at every
step).
"""

from __future__ import annotations

import ctypes
import math
import os
import platform
import sys

import scipy.fft

from .text import format_bytes

__all__ = [
    "available_memory",
    "check_memory",
    "fit_memory",
    "halfspace_memory",
    "keep_freed_memory",
    "product_memory",
    "slope_estimator_memory",
    "steady_memory",
]

_GIB = 2 ** 30
_FLOAT = 8  # bytes of a float64
#: Allocator overhead and short-lived copies the inventories below do not list.
_MARGIN = 1.25
#: Allocations that do not grow with the grid (FFT plans, HDF5 buffers), bytes.
_BASE = 16 * 2 ** 20


def available_memory():
    """Memory available to a new computation, bytes, or None if unknown.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux: free memory plus the
    caches the kernel can drop), else the free physical pages of
    :func:`os.sysconf`.
    """
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def check_memory(needed, what, limit_gib=None):
    """Refuse a computation whose memory estimate exceeds what may be used.

    Parameters
    ----------
    needed : int
        Estimated peak, bytes (e.g. :func:`steady_memory`).
    what : str
        The computation, for the message (``"a steady solve at n = 4096"``).
    limit_gib : float, optional
        ``--memory-limit``, GiB (``inf``: no check).  Default: the
        available memory (:func:`available_memory`); no check if unknown.

    Raises
    ------
    ValueError
        ``needed`` exceeds the limit; the message gives both numbers and
        names ``--memory-limit``.
    """
    if limit_gib is None:
        limit = available_memory()
        if limit is None:
            return
        source = "are available"
    elif math.isinf(limit_gib):
        return
    else:
        limit = limit_gib * _GIB
        source = "may be used (--memory-limit)"
    if needed > limit:
        raise ValueError(f"{what} needs about {format_bytes(needed)} of memory; "
                         f"{format_bytes(limit)} {source} (a larger --memory-limit GIB "
                         f"overrides this check)")


def keep_freed_memory():
    """Let the C allocator keep large freed blocks for reuse (glibc only; the command lines).

    glibc maps every block above its mmap threshold (32 MiB at most) afresh
    and unmaps it when freed, and trims its heap whenever twice the
    threshold is free at its top: an array of a large grid allocated once per iteration
    (an FFT spectrum, a product) is then faulted in page by page every time.
    Other threads than the main one allocate from arenas of their own, heaps
    of 64 MiB that are unmapped when emptied and that map any larger block
    afresh whatever the settings: the history's figures, computed on a
    thread of their own, faulted their arrays in afresh at every step of a
    run at n = 2048 (docs/benchmarks.md, "Run-in memory").  This sets
    ``M_MMAP_MAX = 0`` (blocks come from the heap), a trim threshold of
    2 GiB (freed memory stays for the next array) and
    ``M_ARENA_MAX = 1`` (every thread allocates from the main heap).  The
    peak memory is that of the largest set of arrays alive at once, as
    before; freed memory is returned at exit.  Process-wide, so called by
    the command lines only, not on import, before they start threads.
    Elsewhere (another C library) it does nothing.

    Returns
    -------
    bool
        True if the allocator took the settings.
    """
    if not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc":
        return False
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return False
    m_trim_threshold, m_mmap_max, m_arena_max = -1, -4, -8  # <malloc.h>
    return (bool(libc.mallopt(m_mmap_max, 0)) and bool(libc.mallopt(m_trim_threshold, 2**31 - 1))
            and bool(libc.mallopt(m_arena_max, 1)))


def halfspace_memory(n, *, gradient=False, periodic=False):
    """Bytes held by the operator of grid ``n``: the padded half-space's or a periodic cell's.

    Parameters
    ----------
    n : int
        Pixels across the grid.
    gradient : bool, optional
        Include the two gradient spectra, built on the first slope
        (default False).
    periodic : bool, optional
        The grid is a periodic cell's (the outline's ``periodic``), whose
        operator is :class:`steady.periodic.PeriodicHalfSpace`, with no
        padding (default False: :class:`steady.halfspace.HalfSpace`).

    Returns
    -------
    int
        The padded operator: the influence spectrum (real, ``2n x (n+1)``),
        the zero-padded buffer (``2n x 2n``), the complex work buffer
        (``2n x (n+1)``), the corner lattice and influence quadrant
        (``(n+2)^2`` each), and with ``gradient`` the two gradient spectra
        (real, ``2n x (n+1)`` each): 96 bytes per pixel, 128 with the
        gradient.  A cell's: the symbol and the two gradient spectra, built
        with it whatever ``gradient`` (real, ``n x (n/2+1)`` each), and the
        influence quadrant a preconditioner may ask for (``(n+1)^2``): 20
        bytes per pixel.
    """
    if periodic:
        return 3 * n * (n // 2 + 1) * _FLOAT + (n + 1) ** 2 * _FLOAT
    spectrum = 2 * n * (n + 1) * _FLOAT
    total = spectrum + (2 * n) ** 2 * _FLOAT + 2 * spectrum + 2 * (n + 2) ** 2 * _FLOAT
    if gradient:
        total += 2 * spectrum
    return total


def product_memory(n, *, periodic=False):
    """Bytes of the short-lived transforms of one half-space product of grid ``n``.

    The padded operator's: the padded spectrum of the pressure and ``i``
    times it for the gradient (complex ``2n x (n+1)`` each), the column
    pass of the inverse (complex ``2n x (n+1)``; only ``n`` rows are kept
    but the whole array stays alive) and the row pass (real ``n x 2n``):
    112 bytes per pixel.  A periodic cell's (``periodic``, one plain FFT
    pair): the spectrum of the pressure, ``i`` times it and one product
    (complex ``n x (n/2+1)`` each) and the displacement and the gradient's
    two components (real ``n x n`` each): 48 bytes per pixel.
    """
    if periodic:
        return 3 * n * (n // 2 + 1) * 2 * _FLOAT + 3 * n * n * _FLOAT
    spectrum = 2 * n * (n + 1) * 2 * _FLOAT
    return 3 * spectrum + n * 2 * n * _FLOAT


def slope_estimator_memory(n, *, periodic=False):
    """Bytes of the energy-corrected slope estimator of grid ``n``: kept, and while applied.

    On a periodic cell (``periodic``) the estimator is
    :class:`steady.rms_slope.PeriodicSlopeEnergy`, Parseval's sum on the
    cell's own spectra: it keeps the slope weight (real ``n x (n/2+1)``, 4
    bytes per pixel) and, applied, holds the field, its spectrum, the
    weighted spectrum and its conjugate, the gradient's two components and
    the jumps between neighbours, each concatenated: about 100 bytes per
    pixel.  Otherwise :class:`steady.rms_slope.SlopeEnergy` convolves on a fine box of FFT
    size ``S`` (about ``2.2 n``) and a coarse one of size ``S_c`` (about
    ``1.2 n``), the same arithmetic as its constructor with the default
    margin ``max(8, n // 16)``, coarsening 8 and far radius 8.

    Returns
    -------
    kept : int
        Two gradient spectra on the fine box and five on the coarse one
        (the gradient's and the three second derivatives' that carry the
        blocks' first moments), single-precision complex ``S x (S/2+1)``:
        ``8 S^2 + 20 S_c^2`` bytes, about 65 per pixel.
    applied : int
        The transforms of one application on the fine box (source
        spectrum, product, column and row passes): ``32 S^2`` bytes, about
        150 per pixel.
    """
    if periodic:
        return 4 * n * (n // 2 + 1), 100 * n * n
    c = 8
    margin = c * -(-max(8, n // 16) // c)
    fine = c * -(-(n + 2 * margin) // c)
    nc = fine // c
    extra = max(1, math.ceil((8.0 * n / 2 - fine / 2) / c))
    coarse_out = nc + 2 * extra
    size = scipy.fft.next_fast_len(n + fine - 1, real=True)
    coarse = scipy.fft.next_fast_len(nc + coarse_out - 1, real=True)
    return 8 * size ** 2 + 20 * coarse ** 2, 32 * size ** 2


def steady_memory(n, *, slope_error=True, periodic=False):
    """Estimated peak memory of a steady solve at grid ``n``, bytes.

    Counted from the arrays :func:`steady.solution.solve_scene` allocates,
    in two stages of which the larger is the peak:

    - throughout, the solution: labels, pressure, face, slope and the two
      gradient components (the face and the components are views of
      ``n x 2n`` arrays): 64 bytes per pixel;
    - the face: the half-space operator with its gradient spectra
      (:func:`halfspace_memory`, 128 bytes per pixel; a periodic cell's, 20)
      and the transforms of the products (:func:`product_memory`, 112
      bytes per pixel; a cell's, 48); the operator is freed with them
      (unless the problem holds one);
    - with ``slope_error`` (the default of the command), then: the
      pressure and face mask of the finest grid of the ladder (17 bytes per
      pixel) and the slope estimator of :mod:`steady.rms_slope`, kept and
      applied (:func:`slope_estimator_memory`, about 210 bytes per pixel;
      a cell's, about 104).

    The sum is multiplied by 1.25 (allocator overhead, short-lived copies
    not listed) and 16 MiB are added for what does not grow with ``n``.
    The estimate is an upper bound of the measured peak within a factor of
    2 (``tests/test_memory.py``; the measured ratios are in
    docs/benchmarks.md, "Memory estimates").

    Parameters
    ----------
    n : int or (int, int)
        Pixels across a square grid, or ``(nx, ny)``: a rectangular grid
        is counted as the square of the same number of pixels (the arrays
        scale with ``nx ny``; the margins of the slope estimator, a few per
        cent, with the sides).
    slope_error : bool, optional
        Whether the corrected rms slope and its error bar are computed
        (default True).
    periodic : bool, optional
        The grid is a periodic cell's (the outline's ``periodic``): its
        operator and slope estimator, with no padding (default False).

    Returns
    -------
    int

    Examples
    --------
    >>> print(format_bytes(steady_memory(1024)), format_bytes(steady_memory(12000)))
    396 MiB 51 GiB
    >>> print(format_bytes(steady_memory(1024, periodic=True)))
    245 MiB
    """
    n = int(n) if not isinstance(n, (tuple, list)) else math.ceil(math.sqrt(n[0] * n[1]))
    peak = (halfspace_memory(n, gradient=True, periodic=periodic)
            + product_memory(n, periodic=periodic))
    if slope_error:
        peak = max(peak, 17 * n * n + sum(slope_estimator_memory(n, periodic=periodic)))
    return int(_MARGIN * (8 * n * n * _FLOAT + peak)) + _BASE


def fit_memory(model_shape, n_phases, measured_shape):
    """Estimated peak memory of a wear-ratio fit (:mod:`steady.fit`, ``runin-fit``), bytes.

    Counted from the arrays :class:`steady.fit.FaceModel` and its
    :meth:`~steady.fit.FaceModel.fit` allocate, with ``P`` phases, ``K = P +
    3`` columns of the design matrix, ``M`` pixels of the model grid padded by
    four on every side and ``N`` measured pixels (every one taken as fitted):

    - the model while its faces are computed: the padded labels, the
      half-space operator of the padded grid (:func:`halfspace_memory`, 96
      bytes per pixel), one product's transforms and its unit pressure
      (about 90), and the ``P`` padded faces twice (list and array): ``(200 +
      16 P) M`` bytes;
    - the model kept during the fit: the padded spline coefficients, the
      faces, the phase map extended off the face, the rim distance, the
      coordinate grids: ``(16 P + 64) M`` bytes;
    - the fit: the map, its coordinates and masks, the fitted values and
      the design matrix with its scaled copy and the least-squares copies
      (``64 + 32 K`` bytes per measured pixel); the residual's covariance
      on a zero-padded box of about ``4.4 N`` pixels: the spectra of the
      residual and of the fitted-pixel mask, of the ``K`` columns and of the
      two pair sums (complex, about 38 bytes per measured pixel each) and
      the transforms of one convolution (about 110): ``(260 + 38 K) N``
      bytes, with ``16 K N`` more for the covariance applied to the columns.

    The sum is multiplied by 1.25 (allocator overhead, short-lived copies
    not listed) and 16 MiB are added for what does not grow with the grids,
    as :func:`steady_memory`.  ``tests/test_fit_inputs.py`` measures it
    against the peak of a run.

    Parameters
    ----------
    model_shape : (int, int)
        Pixels of the model grid (the scene's grid at ``--n``).
    n_phases : int
    measured_shape : (int, int)
        Pixels of the measured map.

    Returns
    -------
    int

    Examples
    --------
    >>> print(format_bytes(fit_memory((256, 256), 2, (256, 256))))
    82.9 MiB
    """
    P = int(n_phases)
    K = P + 3
    padded = (int(model_shape[0]) + 8) * (int(model_shape[1]) + 8)
    measured = int(measured_shape[0]) * int(measured_shape[1])
    build = (200 + 16 * P) * padded
    kept = (16 * P + 64) * padded
    fit = (64 + 32 * K) * measured + (260 + 38 * K) * measured + 16 * K * measured
    return int(_MARGIN * max(build, kept + fit)) + _BASE
