"""A face as a SurfaceTopography topography, and its isotropic power spectral density.

The package SurfaceTopography (the optional extra ``surface``, ``pip
install 'runin[surface]'``) analyses height maps: power spectra,
autocorrelation, scale-dependent slopes and curvatures, for measured and
computed faces alike.  :func:`to_topography` turns a face of this project
(the steady face, a run's worn face or one of its snapshots) into a
``SurfaceTopography.Topography``: its heights in m, its physical size
``(nx h, ny h)`` in m, and the pixels off the face as undefined data (a
masked array).  The axes are the project's: ``heights[i, j]`` lies at
``x = i h``, ``y = j h`` from the first pixel's centre, axis 0 along x,
and ``physical_sizes`` is ``(L_x, L_y)`` in that order.

:func:`isotropic_psd` is the radially averaged power spectral density
``C^iso(q)`` of a face, without SurfaceTopography: the same numbers, to
rounding, as its ``power_spectrum_from_area()`` (version 1.27, default
arguments) of the face detrended by its least-squares plane, with the
pixels off the face set to zero (``topography.detrend("height")
.fill_undefined_data(0.0)``; the library refuses a spectrum of undefined
data).  Its definition, its window and its bins are in docs/model.md,
"The face's power spectrum".
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import scipy.fft

from .measured_face import check_pixel_size
from .relief import PlaneFit

__all__ = ["PowerSpectrum", "isotropic_psd", "to_topography"]

#: Bin edges per decade of the wavevector, and how far (decades) the outer edges reach
#: beyond the smallest and the largest wavevector: SurfaceTopography's defaults.
_EDGES_PER_DECADE = 10
_EDGE_MARGIN = 0.01


@dataclasses.dataclass(frozen=True, eq=False)
class PowerSpectrum:
    """The radially averaged power spectral density ``C^iso(q)`` of a face.

    Attributes
    ----------
    wavevector : ndarray, shape (K,), m^-1
        ``q = 2 pi / wavelength``: the mean ``|q|`` of the Fourier
        wavevectors in each bin, increasing.
    density : ndarray, shape (K,), m^4
        Mean of ``C(q) = |h_q|^2 / (L_x L_y)`` over the bin, ``h_q`` the
        Fourier transform of the windowed face (docs/model.md, "The face's
        power spectrum").
    """

    wavevector: np.ndarray
    density: np.ndarray


def _checked_face(face, pixel_size):
    """``(face, face mask, (dx, dy))`` of a face array, NaN off the face; ValueError if bad."""
    face = np.asarray(face, dtype=float)
    if face.ndim != 2:
        raise ValueError(f"a face must be a 2-d array of heights (m), got shape {face.shape}")
    mask = np.isfinite(face)
    if np.count_nonzero(mask) < 3:
        raise ValueError(f"a face needs at least 3 pixels with a height, got "
                         f"{np.count_nonzero(mask)} of {face.size}")
    return face, mask, check_pixel_size(pixel_size, "face")


def to_topography(face, pixel_size):
    """The face as a ``SurfaceTopography.Topography`` in metres, undefined off the face.

    Parameters
    ----------
    face : ndarray, shape (nx, ny), m
        Heights at the pixel centres, indexed ``[i, j]`` with ``i`` along
        x; NaN off the face.
    pixel_size : float or (float, float), m
        The pixels' side, or ``(dx, dy)``.

    Returns
    -------
    SurfaceTopography.Topography
        Heights a masked array (masked off the face; a face without
        NaN is not masked), ``physical_sizes = (nx dx, ny dy)``, unit
        ``"m"``, not periodic.  A copy: changing it leaves ``face`` as it is.

    Raises
    ------
    ModuleNotFoundError
        SurfaceTopography is not installed (the message says how to install it).
    ValueError
        ``face`` not 2-d or with fewer than 3 heights, or ``pixel_size``
        not a length > 0.

    Examples
    --------
    A tilted plane on a 5 x 3 grid of 1 mm pixels, one pixel off the face:

    >>> import numpy as np
    >>> face = 0.01 * np.arange(5.0)[:, None] * 1e-3 + np.zeros(3)
    >>> face[0, 0] = np.nan
    >>> topography = to_topography(face, 1e-3)
    >>> topography.physical_sizes, topography.unit, bool(topography.has_undefined_data)
    ((0.005, 0.003), 'm', True)
    >>> print(f"{topography.rms_gradient():.4f}")
    0.0100
    """
    face, mask, (dx, dy) = _checked_face(face, pixel_size)
    try:
        with warnings.catch_warnings():
            # NuMPI, under SurfaceTopography, warns on import that it runs without
            # mpi4py, serially: the way this project uses it.
            warnings.filterwarnings("ignore", "Could not import mpi4py", ImportWarning)
            from SurfaceTopography import Topography
    except ImportError:
        raise ModuleNotFoundError("a face as a topography needs SurfaceTopography: install "
                                  "the optional extra with pip install 'runin[surface]'",
                                  name="SurfaceTopography") from None
    heights = np.ma.masked_array(face, mask=~mask) if not mask.all() else face.copy()
    nx, ny = face.shape
    return Topography(heights, physical_sizes=(nx * dx, ny * dy), unit="m", periodic=False)


def _radial_hann(shape, size):
    """SurfaceTopography's radial Hann window on a grid, scaled to a mean square of 1.

    ``(1 + cos(pi r / r_max)) / 2`` within ``r_max = min(L_x, L_y) / 2`` of the
    pixel ``(nx // 2, ny // 2)``, zero beyond (``FFTTricks.get_window_2D``).
    """
    (nx, ny), (sx, sy) = shape, size
    r = np.hypot((sx * (np.arange(nx) - nx // 2) / nx)[:, None],
                 (sy * (np.arange(ny) - ny // 2) / ny)[None, :])
    r_max = 0.5 * min(sx, sy)
    window = np.where(r > r_max, 0.0, 0.5 + 0.5 * np.cos(np.pi * r / r_max))
    return window * np.sqrt(nx * ny / np.sum(window * window))


def _log_bin_edges(q_min, q_max):
    """SurfaceTopography's logarithmic bin edges from ``q_min`` to ``q_max`` (``make_grid``)."""
    lo, hi = math.log10(q_min), math.log10(q_max)
    count = int(math.ceil((hi - lo + 1) * _EDGES_PER_DECADE))
    return 10.0 ** np.linspace(lo - _EDGE_MARGIN, hi + _EDGE_MARGIN, count)


def isotropic_psd(face, pixel_size):
    """The radially averaged power spectral density ``C^iso(q)`` of a face.

    The face minus its least-squares plane over the face pixels, zero off
    the face, times SurfaceTopography's radial Hann window; then
    ``C(q) = |dx dy sum h e^(-i q.x)|^2 / (L_x L_y)`` averaged over the
    wavevectors in logarithmic bins (10 edges per decade) from
    ``2 pi / max(L_x, L_y)`` to the Nyquist wavevector ``pi / max(dx, dy)``;
    empty bins are left out.  SurfaceTopography's ``power_spectrum_from_area``
    (version 1.27, default arguments) of that face gives the same numbers to
    rounding; docs/model.md, "The face's power spectrum", says why these
    choices.

    Parameters
    ----------
    face : ndarray, shape (nx, ny), m
        Heights at the pixel centres, indexed ``[i, j]`` with ``i`` along
        x; NaN off the face.
    pixel_size : float or (float, float), m
        The pixels' side, or ``(dx, dy)``.

    Returns
    -------
    PowerSpectrum

    Raises
    ------
    ValueError
        ``face`` not 2-d or with fewer than 3 heights, or ``pixel_size``
        not a length > 0.

    Examples
    --------
    A cosine of wavelength 1 mm on a 16 mm square: the spectrum peaks in the
    bin of ``q = 2 pi / 1 mm`` (whose mean wavevector is a little off it).

    >>> import numpy as np
    >>> x = (np.arange(128) + 0.5) * 0.125e-3
    >>> face = 1e-6 * np.cos(2 * np.pi * x / 1e-3)[:, None] + np.zeros(128)
    >>> spectrum = isotropic_psd(face, 0.125e-3)
    >>> peak = spectrum.wavevector[np.argmax(spectrum.density)]
    >>> print(f"peak at a wavelength of {2 * np.pi / peak * 1e3:.1f} mm")
    peak at a wavelength of 1.0 mm
    """
    face, mask, (dx, dy) = _checked_face(face, pixel_size)
    nx, ny = face.shape
    sx, sy = nx * dx, ny * dy
    heights = np.zeros(face.shape)
    # The plane's residual does not depend on the scale of x and y: unit pixels fit it.
    heights[mask] = PlaneFit(mask, 1.0).residual(face)
    heights *= _radial_hann(face.shape, (sx, sy))
    # The half spectrum of real heights: a column other than q_y = 0 (and the Nyquist
    # column of an even ny) stands for its complex conjugate too, and counts twice.
    power = np.abs(dx * dy * scipy.fft.rfft2(heights)) ** 2 / (sx * sy)
    ky = np.arange(power.shape[1])
    weight = np.where((ky == 0) | (2 * ky == ny), 1.0, 2.0)[None, :] * np.ones((nx, 1))
    kx = np.arange(nx)
    kx = np.where(kx > nx // 2, nx - kx, kx)
    q = np.hypot((2 * np.pi / sx * kx)[:, None], (2 * np.pi / sy * ky)[None, :])
    edges = _log_bin_edges(min(2 * np.pi / sx, 2 * np.pi / sy),
                           np.pi * min(nx / sx, ny / sy))
    # Bin k holds edges[k - 1] < q <= edges[k]; bins 0 and len(edges) lie outside.
    index = np.searchsorted(edges, q.ravel())
    counts, q_sums, c_sums = (np.bincount(index, weights=w, minlength=len(edges) + 1)[1:-1]
                              for w in (weight.ravel(), (weight * q).ravel(),
                                        (weight * power).ravel()))
    full = counts > 0
    return PowerSpectrum(wavevector=q_sums[full] / counts[full],
                         density=c_sums[full] / counts[full])
