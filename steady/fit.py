"""Wear ratios from a measured worn face: the inverse problem of equations 7 and 9.

The steady face is linear in the phase pressures,
``f_inf = sum_i p_i K chi_i`` (eq. 9), and in the steady state
``k_i p_i^m = C`` (eq. 3, 7), so the wear ratios follow from the pressures:
``k_i / k_ref = (p_ref / p_i)^m``.  A measured height map ``z`` of a worn
face is fitted by linear least squares,

    z(x, y) = sum_i p_i F_i(x - s_x, y - s_y) + c_0 + c_1 (x - s_x) + c_2 (y - s_y),

with ``F_i = K chi_i`` the face under unit pressure on phase ``i``
(:class:`FaceModel`, the per-phase faces of :class:`steady.basis.PhaseBasis`),
a free offset ``c_0`` and tilt ``(c_1, c_2)``, and ``s`` the position of the
face's centre (the origin of its outline, :mod:`steady.outline`) in the map
(zero, given, or searched).  The face may have any outline: a disk, a
rectangle, an ellipse, an annulus or a pixel mask.  The pressures are free:
the load ``sum_i A_i p_i = F_N`` is not imposed, so the ratios do not depend
on ``E*`` or ``F_N``, which only scale the relief; the fitted load
``sum_i A_i p_i`` over ``F_N`` (:attr:`FitResult.load_scale`) is reported as
a consistency figure (1 when the scene's ``E*`` and ``F_N`` explain the
relief's amplitude).

Confidence intervals come from the least-squares covariance with the
residual treated as a stationary, spatially correlated field: its
autocovariance is estimated from the residual map itself and enters the
sandwich covariance ``(X^T X)^-1 X^T Sigma X (X^T X)^-1``; the effective
number of independent samples sets the degrees of freedom of the t
quantile.  Ratio intervals are Fieller's intervals for ``p_ref / p_i``
(exact for a ratio of two normal estimates, unbounded when the denominator
is not distinguished from zero), raised to the power ``m``.  See
``docs/model.md``, "Wear ratios from a measured face".

Units: the fit runs on the heights over a power of two near the largest
one (:class:`_HeightUnit`), exactly, and scales its results back: the same
bits as a fit in metres where that neither overflows nor underflows, the
same ratios for heights in any unit, and a refusal naming the heights'
range when a result (the pressures' covariance, in Pa^2, first) cannot be
a floating-point number in SI units.

Distance to the rim (``rim_margin``, and the part of the face that every
trial shift of the search sees): closed forms for the disk, the rectangle
and the annulus; for other outlines (ellipse, mask) the Euclidean distance
transform of the face on the model grid, interpolated linearly, which is
within about half a model pixel of the true distance
(:meth:`FaceModel.rim_distance`).

Command line (``runin-fit``, or ``python -m steady.cli.fit``; :mod:`steady.cli.fit`)::

    runin-fit SCENE.toml MEASURED -o FIT.h5 [--pixel-size DX [DY]] [--height-scale S]
              [--plot FIT.png] [--shift] [--max-shift M] [--rim-margin M] [--n N]
              [--reference-phase I] [--confidence C] [--force] [-v]
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy import fft, ndimage, optimize, signal, special

from .halfspace import HalfSpace
from .labels import extend_off_face
from .measured_face import MeasuredFace
from .problem import Problem, default_phase_names
from .scene import problem_of
from .schema import Key

__all__ = ["DEFAULT_MIN_PHASE_PIXELS", "FaceBasis", "FaceModel", "FitResult", "fit_face",
           "fit_scene"]

logger = logging.getLogger(__name__)

#: A phase must cover at least this many fitted pixels to be determined.
DEFAULT_MIN_PHASE_PIXELS = 10

#: A phase face whose part independent of the other columns (sine of its
#: angle to their span) is below this is not determined by the data.
_COLLINEAR_TOL = 1e-6

#: Default search radius of the lateral shift, in units of the outline's scale
#: ``L`` (the radius of a disk, else the larger half side of the bounding box).
_DEFAULT_MAX_SHIFT = 0.05

#: Pixels of the model grid computed beyond the face's bounding box on every
#: side, so that the cubic splines of the per-phase faces see ``K chi_i`` (not
#: an extrapolation) out to the box's edge: the spline prefilter's boundary
#: error decays by ``2 - sqrt(3) = 0.27`` per pixel, to 5e-3 at the box.
_MODEL_PAD = 4

#: Pixels on which the grid stage of the shift search runs (at most).
_SEARCH_PIXELS = 8000

#: Fewest measured pixels across the narrowest part of the fitted face.
_MIN_PIXELS_ACROSS = 8


#: The fit's ``rim_margin`` (and ``runin-fit --rim-margin``): a length >= 0, in the range
#: of every scale of a problem (:data:`steady.schema.SCALE_RANGE`) unless 0.
RIM_MARGIN = Key("rim_margin", "number", unit="m", low=0.0, low_open=False)
#: The fit's ``max_shift`` (and ``runin-fit --max-shift``), as ``rim_margin``.
MAX_SHIFT = Key("max_shift", "number", unit="m", low=0.0, low_open=False)


@dataclasses.dataclass(frozen=True, eq=False)
class FitResult:
    """Wear ratios that best explain a measured worn face.

    Attributes
    ----------
    ratios : ndarray, shape (P,)
        ``k_i / k_ref = (p_ref / p_i)^m``; 1 for the reference phase, NaN
        where a fitted pressure is not positive.
    ratio_intervals : ndarray, shape (P, 2)
        Confidence interval of each ratio at level ``confidence`` (Fieller);
        the upper end is ``inf`` when phase ``i``'s pressure is not
        distinguished from zero (the face gives only a lower bound), the
        lower end 0 when the reference's is not.
    phase_pressures : ndarray, shape (P,), Pa
        Fitted steady pressure of each phase, at the scene's ``E*``.
    phase_pressure_errors : ndarray, shape (P,), Pa
        Their standard errors.
    pressure_covariance : ndarray, shape (P, P), Pa^2
    offset : float, m
        Fitted height of the plane at the face's centre.
    tilt : tuple of float, dimensionless
        ``(dz/dx, dz/dy)`` of the fitted plane.
    shift : tuple of float, m
        Position of the face's centre (the origin of its outline) from the
        map's centre (given or found).
    residual_rms : float, m
        Rms of measured minus fitted over the fitted pixels.
    relief : float, m
        Max minus min of the fitted face without its plane, over the fitted
        pixels: the scale the residual compares with.
    samples : int
        Pixels in the fit.
    effective_samples : float
        Independent samples: ``samples`` over the residual's correlation
        area in pixels (equal to ``samples`` for white noise).
    correlation_length : float, m
        Radius at which the residual's radially averaged autocorrelation
        falls to ``1/e`` (below one pixel for white noise).
    degrees_of_freedom : float
        ``effective_samples - (P + 3)``: of the t quantile of the intervals.
    load_scale : float
        ``sum_i A_i p_i / F_N`` (areas of the model's face): 1 when the
        scene's load and modulus explain the relief's amplitude.
    load_scale_interval : tuple of float
    implied_normal_force : float, N
        ``sum_i A_i p_i``: the load that explains the relief at the scene's ``E*``.
    implied_E_star : float, Pa
        ``E* / load_scale``: the modulus that explains it at the scene's load.
    confidence : float
    reference_phase : int
    exponent : float
        ``m`` of the wear law.
    normal_force : float, N
    E_star : float, Pa
    outline : outline object
        The face's outline (:mod:`steady.outline`).
    n : int
        Pixels along the longer side of the model grid (across the diameter
        of a disk).
    success : bool
        All fitted phase pressures are positive, every ratio is bounded
        (its interval is not ``[0, inf]``) and every figure is finite.
    message : str
        Why the fit failed, and notes (unbounded intervals, a shift at the
        search limit, a residual correlated over the whole window).
    measured : MeasuredFace
    fitted : ndarray, shape (nx, ny), m
        Fitted face with its plane on the measured grid; NaN off the face.
    residual : ndarray, shape (nx, ny), m
        Measured minus fitted on the fitted pixels; NaN elsewhere.
    fit_mask : ndarray of bool, shape (nx, ny)
        The fitted pixels: finite, on the face and farther than
        ``rim_margin`` (plus the shift search radius) from its rim.
    phase : ndarray, shape (nx, ny), int
        Phase at each measured pixel, -1 off the face.
    scene_ratios : ndarray, shape (P,), or None
        The ratios of the scene's wear coefficients, for comparison (not
        used by the fit).
    """

    ratios: np.ndarray
    ratio_intervals: np.ndarray
    phase_pressures: np.ndarray
    phase_pressure_errors: np.ndarray
    pressure_covariance: np.ndarray
    offset: float
    tilt: tuple
    shift: tuple
    residual_rms: float
    relief: float
    samples: int
    effective_samples: float
    correlation_length: float
    degrees_of_freedom: float
    load_scale: float
    load_scale_interval: tuple
    implied_normal_force: float
    implied_E_star: float
    confidence: float
    reference_phase: int
    exponent: float
    normal_force: float
    E_star: float
    outline: object
    n: int
    success: bool
    message: str
    measured: MeasuredFace
    fitted: np.ndarray
    residual: np.ndarray
    fit_mask: np.ndarray
    phase: np.ndarray
    scene_ratios: np.ndarray | None = None

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return self.phase_pressures.shape[0]

    def summary_lines(self, names=None):
        """Short human-readable summary, a list of lines.

        Parameters
        ----------
        names : sequence of str, optional
            A name for each phase (a scene's ``[phases] names``); default
            ``("phase 0", "phase 1", ...)``.
        """
        names = default_phase_names(self.n_phases) if names is None else tuple(names)
        ref = self.reference_phase
        level = f"{100 * self.confidence:g} %"
        lines = [f"wear ratios k_i/k_{ref} ({level} intervals; k_{ref} of {names[ref]})"]
        width = max(15, *(len(name) + 1 for name in names))
        for i in range(self.n_phases):
            if i == ref:
                continue
            lo, hi = self.ratio_intervals[i]
            upper = "inf" if not math.isfinite(hi) else f"{hi:.4g}"
            scene = ("" if self.scene_ratios is None
                     else f"   (scene: {self.scene_ratios[i]:.4g})")
            lines.append(f"  {names[i]:<{width}}{self.ratios[i]:.4g}  [{lo:.4g}, {upper}]{scene}")
        pressures = ", ".join(f"{name} {p:.4g} +- {e:.2g}" for name, p, e in
                              zip(names, self.phase_pressures, self.phase_pressure_errors,
                                  strict=True))
        lo, hi = self.load_scale_interval
        lines += [
            f"phase pressures  {pressures} Pa",
            f"residual rms     {self.residual_rms:.4g} m  (relief {self.relief:.4g} m)",
            f"samples          {self.samples} pixels, {self.effective_samples:.4g} effective "
            f"(correlation length {self.correlation_length:.3g} m)",
            f"load scale       {self.load_scale:.4g}  [{lo:.4g}, {hi:.4g}]  (implied load "
            f"{self.implied_normal_force:.4g} N at E* = {self.E_star:.4g} Pa, or E* = "
            f"{self.implied_E_star:.4g} Pa at {self.normal_force:.4g} N)",
            f"offset, tilt     {self.offset:.4g} m, ({self.tilt[0]:.3g}, {self.tilt[1]:.3g})",
            f"shift            ({self.shift[0]:.4g}, {self.shift[1]:.4g}) m",
            f"face             {self.outline.describe()}, model grid n = {self.n}",
        ]
        if self.message:
            lines.append(("note             " if self.success else "fit failed       ")
                         + self.message)
        return lines


def _fieller(a, b, vaa, vbb, vab, t):
    """Confidence interval of ``a / b`` on ``(0, inf)`` (Fieller's theorem).

    The set ``{r : (a - r b)^2 <= t^2 (vaa - 2 r vab + r^2 vbb)}``,
    intersected with the positive reals; its hull when that is two pieces.
    The set does not change when ``a, b`` are scaled by ``c`` and the
    variances by ``c^2``: they are, by a power of two near their size (exact),
    so that the discriminant, of degree 4 in them, neither overflows nor
    underflows.
    """
    size = max(abs(a), abs(b), math.sqrt(max(vaa, 0.0)), math.sqrt(max(vbb, 0.0)))
    if 0 < size < math.inf:
        e = -math.frexp(size)[1]
        a, b = math.ldexp(a, e), math.ldexp(b, e)
        vaa, vbb, vab = math.ldexp(vaa, 2 * e), math.ldexp(vbb, 2 * e), math.ldexp(vab, 2 * e)
    qa = b * b - t * t * vbb
    qb = a * b - t * t * vab
    qc = a * a - t * t * vaa
    disc = qb * qb - qa * qc
    if qa > 0:
        root = math.sqrt(max(disc, 0.0))
        lo, hi = (qb - root) / qa, (qb + root) / qa
        return max(lo, 0.0), hi if hi > 0 else 0.0
    # Denominator not distinguished from zero: the set is unbounded.
    if disc <= 0 or qa == 0:
        return 0.0, math.inf
    root = math.sqrt(disc)
    lo, hi = sorted(((qb - root) / qa, (qb + root) / qa))
    if lo > 0:
        return 0.0, math.inf
    return max(hi, 0.0), math.inf


def _ring_profile(values, radius, step):
    """Mean of ``values`` over rings of width ``step`` (ring 0 the centre alone)."""
    ring = np.floor(radius / step + 0.5).astype(int)
    count = np.bincount(ring.ravel())
    total = np.bincount(ring.ravel(), weights=values.ravel())
    return np.divide(total, count, out=np.full(count.shape, np.nan), where=count > 0), ring


class _Covariance:
    """Autocovariance of a residual map, corrected for the fit, and the sandwich meat.

    The noise is treated as a stationary field with autocovariance ``C(l)``
    at lag ``l``.  The estimate from the residual,
    ``C_hat(l) = mean of e(r) e(r + l)`` over the pairs of fitted pixels
    (zero-padded FFTs), is biased low: the fit absorbs the part of the noise
    that resembles its columns, so ``E[e e^T] = M Sigma M`` with
    ``M = I - X (X^T X)^-1 X^T``.  The expected bias is linear in ``C`` and
    costs a few FFTs (the pair sums of ``H Sigma``, ``Sigma H`` and
    ``H Sigma H``); ``C = C_hat + bias(C)`` is solved by fixed-point
    iteration.  ``C`` is summed over a window: the lags out to the first
    ring where the radial average of the corrected ``C`` is not positive
    (beyond it the estimate is noise), at most ``max_radius``.

    Attributes
    ----------
    meat : ndarray, shape (k, k)
        ``X^T Sigma X`` for the columns given.
    correlation_area : float
        ``sum_l C(l) / C(0)`` over the window, pixels (at least 1).
    length : float, m
        Radius where the ring average of ``C / C(0)`` falls to ``1/e``.
    window_limited : bool
        The corrected ``C`` stays positive out to ``max_radius``.
    """

    def __init__(self, residual, mask, pixel, max_radius, columns, *, max_iterations=50,
                 rtol=1e-4):
        nx, ny = mask.shape
        dx, dy = pixel
        self._mask = mask
        self._columns = columns
        self._shape = (fft.next_fast_len(2 * nx, real=True),
                       fft.next_fast_len(2 * ny, real=True))
        lx_max = min(nx - 1, max(1, int(math.ceil(max_radius / dx))))
        ly_max = min(ny - 1, max(1, int(math.ceil(max_radius / dy))))
        lx = np.arange(-lx_max, lx_max + 1)
        ly = np.arange(-ly_max, ly_max + 1)
        self._index = np.ix_(lx % self._shape[0], ly % self._shape[1])
        self._centre = (lx_max, ly_max)
        self._radius = np.hypot(lx[:, None] * dx, ly[None, :] * dy)
        self._step = min(dx, dy)
        self._max_radius = max_radius
        e_q = self._rfft(np.where(mask, residual, 0.0))
        m_q = self._rfft(mask.astype(float))
        pairs = np.rint(self._lags(m_q.conj() * m_q))
        self._pairs = np.where(pairs > 0.5, pairs, np.inf)
        c_hat = self._lags(e_q.conj() * e_q) / self._pairs
        self.iterations, self.converged, self.window_limited = 0, True, False
        if not c_hat[self._centre] > 0:  # an exact fit: no noise to speak of
            c = np.zeros_like(c_hat)
        else:
            self._g = np.linalg.pinv(columns.T @ columns)
            self._columns_q = [self._rfft(self._image(col)) for col in columns.T]
            c = self._windowed(c_hat)
            self.converged = False
            for self.iterations in range(1, max_iterations + 1):  # noqa: B007
                updated = self._windowed(c_hat + self._bias(c))
                change = abs(updated.sum() - c.sum()) / abs(updated.sum())
                c = updated
                if change < rtol:
                    self.converged = True
                    break
        self.kernel = c
        self.meat = self._columns.T @ self._apply(c)
        self.meat = 0.5 * (self.meat + self.meat.T)
        c0 = c[self._centre]
        self.correlation_area = max(float(c.sum() / c0), 1.0) if c0 > 0 else 1.0
        self.length = self._length(c) if c0 > 0 else 0.0

    def _windowed(self, c):
        """``c`` inside the window (rings before the first non-positive one), zero outside."""
        rho, ring = _ring_profile(c / c[self._centre], self._radius, self._step)
        non_positive = np.flatnonzero(~(rho[1:] > 0)) + 1
        self.window_limited = non_positive.size == 0
        stop = int(non_positive[0]) if non_positive.size else rho.size
        return np.where((ring < stop) & (self._radius <= self._max_radius), c, 0.0)

    def _length(self, c):
        """Radius where the ring average of ``c / c(0)`` falls to ``1/e``, m."""
        rho, _ = _ring_profile(c / c[self._centre], self._radius, self._step)
        rho = np.nan_to_num(rho)
        level = math.exp(-1.0)
        below = np.flatnonzero(rho[1:] < level)
        if below.size == 0:
            return (rho.size - 1) * self._step
        j = int(below[0]) + 1
        return self._step * (j - 1 + (rho[j - 1] - level) / (rho[j - 1] - rho[j]))

    def _rfft(self, image):
        return fft.rfft2(image, self._shape)

    def _lags(self, spectrum):
        return fft.irfft2(spectrum, self._shape)[self._index]

    def _image(self, values):
        image = np.zeros(self._mask.shape)
        image[self._mask] = values
        return image

    def _apply(self, c):
        """``Sigma X`` on the fitted pixels for the kernel ``c``, shape (N, k)."""
        # Only the window's bounding box, centred, enters the convolution.
        ix, iy = np.nonzero(c)
        cx, cy = self._centre
        rx = int(np.max(np.abs(ix - cx))) if ix.size else 0
        ry = int(np.max(np.abs(iy - cy))) if iy.size else 0
        kernel = c[cx - rx:cx + rx + 1, cy - ry:cy + ry + 1]
        # C is even in the lag, so convolution and correlation agree.
        return np.column_stack([signal.fftconvolve(self._image(col), kernel,
                                                   mode="same")[self._mask]
                                for col in self._columns.T])

    def _bias(self, c):
        """``C - E[C_hat]`` at every lag for the noise autocovariance ``c``."""
        sigma_x = self._apply(c)
        meat = self._columns.T @ sigma_x
        g = self._g
        y = sigma_x @ g                                        # Sigma X G
        z = self._columns @ (g @ (0.5 * (meat + meat.T)) @ g)  # X G B G
        h_sigma = np.zeros(self._columns_q[0].shape, dtype=complex)
        h_sigma_h = np.zeros_like(h_sigma)
        for a, x_q in enumerate(self._columns_q):
            h_sigma += x_q.conj() * self._rfft(self._image(y[:, a]))
            h_sigma_h += self._rfft(self._image(z[:, a])).conj() * x_q
        # Pair sums over (r, r + l) of H Sigma, Sigma H (the same at -l) and H Sigma H.
        s1 = self._lags(h_sigma)
        s2 = self._lags(h_sigma_h)
        return (s1 + s1[::-1, ::-1] - s2) / self._pairs


class FaceBasis:
    """Per-phase faces of a phase map, sampled anywhere on the face: the fit's operator.

    The faces ``F_i = K chi_i`` under unit pressure on each phase (m/Pa)
    are computed once on the model grid (the outline's
    :class:`~steady.outline.FaceGrid`), then sampled at the measured pixels
    by cubic-spline interpolation (the faces are continuous; only their
    slope is log-singular at phase boundaries and at the rim).  The basis
    also says which measured pixels lie on the face, how far from its rim,
    and whether a measured map covers it.

    Parameters
    ----------
    phases : steady.problem.FacePhases
        The phase map on the face's grid (the model grid).
    E_star : float, Pa

    Attributes
    ----------
    outline : outline object
    grid : steady.outline.FaceGrid
        The model grid; ``n`` pixels along the longer side, pixel ``h``.
    faces : ndarray, shape (P, nx, ny), m/Pa
        ``F_i = K chi_i`` on the model grid (read-only).
    areas : ndarray, shape (P,), m^2
        Face area of each phase (pixel counts times ``h^2``).
    inradius : float, m
        The largest distance from a face pixel centre of the model grid to
        the rim (:meth:`rim_distance`): the rim margin and the shift search
        radius together must stay below it.

    Raises
    ------
    ValueError
        A periodic cell (``outline.periodic``): the fit places a measured face
        by its rim.

    Notes
    -----
    Cost: ``P`` half-space products on the grid of ``(nx + 8) x (ny + 8)``
    pixels (the faces are computed four pixels beyond the bounding box, so
    that the splines interpolate ``K chi_i`` up to the box's edge).
    """

    def __init__(self, phases, E_star):
        grid = phases.grid
        if grid.outline.periodic:
            # The fit places a measured face by its rim and samples faces beyond the box.
            raise ValueError(f"the wear-ratio fit needs a face with a rim; the "
                             f"{grid.outline.describe()} is a periodic cell")
        labels = phases.labels
        self.outline = grid.outline
        self.E_star = E_star
        self.grid = grid
        self.n = grid.n
        self.h = grid.h
        self.n_phases = phases.n_phases
        self.counts = phases.counts
        self.labels = labels
        self.areas = self.counts * self.h**2
        pad = _MODEL_PAD
        padded = np.pad(labels, pad, constant_values=-1)
        hs = HalfSpace(padded.shape, self.h, self.E_star)
        faces_padded = np.array([hs.displacement((padded == i).astype(float))
                                 for i in range(self.n_phases)])
        faces = faces_padded[:, pad:-pad, pad:-pad].copy()
        faces.flags.writeable = False
        #: ``F_i = K chi_i`` on the model grid, shape (P, nx, ny), m/Pa.
        self.faces = faces
        self._splines = [ndimage.spline_filter(f, order=3, mode="nearest")
                         for f in faces_padded]
        self._origin = np.array([grid.x[0], grid.y[0]]) - pad * self.h
        self._filled = extend_off_face(labels, grid.mask)
        self._transform = None
        inside = grid.mask
        X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
        # Rim distance at the model's face pixel centres, m (for the fitted part's box).
        self._pixel_rim_distance = np.where(inside, self.rim_distance(X, Y), -np.inf)
        self.inradius = float(self._pixel_rim_distance.max())

    @property
    def shape(self):
        """``(nx, ny)`` of the model grid."""
        return self.grid.shape

    def _index(self, x, y):
        """Fractional indices of points in the padded model grid, shape (2, N)."""
        return np.array([(np.asarray(x, dtype=float) - self._origin[0]) / self.h,
                         (np.asarray(y, dtype=float) - self._origin[1]) / self.h])

    def faces_at(self, x, y):
        """Per-phase faces at points (cubic-spline interpolation).

        Parameters
        ----------
        x, y : ndarray, shape (N,), m
            Coordinates from the face's centre.

        Returns
        -------
        ndarray, shape (P, N), m/Pa
        """
        coords = self._index(x, y)
        return np.array([ndimage.map_coordinates(s, coords, order=3, mode="nearest",
                                                 prefilter=False) for s in self._splines])

    def phases_at(self, x, y):
        """Phase at points: the nearest model face pixel's, -1 off the face of the outline.

        Parameters
        ----------
        x, y : ndarray, shape (N,), m
            Coordinates from the face's centre.

        Returns
        -------
        ndarray, shape (N,), int
        """
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        nx, ny = self.shape
        i = np.clip(np.rint((x - self.grid.x[0]) / self.h).astype(int), 0, nx - 1)
        j = np.clip(np.rint((y - self.grid.y[0]) / self.h).astype(int), 0, ny - 1)
        return np.where(self.outline.contains(x, y), self._filled[i, j], -1)

    def rim_distance(self, x, y, *, closed_form=True):
        """Distance from points of the face to the outline's rim.

        The outline's closed form where it has one
        (:meth:`~steady.outline.Circle.exact_rim_distance`: the disk, the
        rectangle, the annulus); for other outlines the Euclidean distance
        transform of the face on the model grid (centre to centre, less half
        a pixel, signed: negative off the face), interpolated linearly:
        within about ``h / 2`` of the true distance.

        Parameters
        ----------
        x, y : ndarray, m
            Coordinates from the face's centre.
        closed_form : bool, optional
            Use the outline's closed form where it has one (default True);
            False: the distance transform whatever the outline.

        Returns
        -------
        ndarray, m
            Meaningful on the face (positive there, up to the transform's
            error near the rim).
        """
        if closed_form:
            exact = self.outline.exact_rim_distance(np.asarray(x, dtype=float),
                                                    np.asarray(y, dtype=float))
            if exact is not None:
                return exact
        if self._transform is None:
            # Padded like the faces: off-face pixels around the box, so that a
            # face touching the box's edge has its rim there.
            inside = np.pad(self.grid.mask, _MODEL_PAD, constant_values=False)
            d_in = ndimage.distance_transform_edt(inside)
            d_out = ndimage.distance_transform_edt(~inside)
            self._transform = self.h * np.where(inside, d_in - 0.5, 0.5 - d_out)
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        coords = self._index(x.ravel(), y.ravel())
        return ndimage.map_coordinates(self._transform, coords, order=1,
                                       mode="nearest").reshape(x.shape)

    def fitted_region(self, x, y, erosion=0.0):
        """Points of the face at least ``erosion`` from its rim (strictly inside for 0).

        Parameters
        ----------
        x, y : ndarray, m
            Coordinates from the face's centre.
        erosion : float, m, optional
            Rim margin, plus the shift search radius when a shift is searched.

        Returns
        -------
        ndarray of bool
        """
        inside = np.asarray(self.outline.contains(x, y), dtype=bool)
        if erosion > 0 and inside.any():
            x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
            inside[inside] = self.rim_distance(x[inside], y[inside]) > erosion
        return inside

    def region_box(self, erosion=0.0):
        """Bounding box of the face less ``erosion`` at the rim, from the face's centre.

        The model's face pixels farther than ``erosion`` from the rim, each
        with its square, clipped to the outline's bounding box shrunk by
        ``erosion``: the face's own box for ``erosion = 0`` (exactly, for
        outlines whose rim lies on pixel edges along the box).

        Returns
        -------
        lower, upper : ndarray, shape (2,), m
            ``(x, y)`` of the box's corners.
        """
        keep = (self.grid.mask if erosion <= 0
                else self._pixel_rim_distance > erosion)
        i, j = np.nonzero(keep)
        half = 0.5 * self.h
        box = np.array(self.outline.half_extent) - erosion
        lower = np.maximum([self.grid.x[i.min()] - half, self.grid.y[j.min()] - half], -box)
        upper = np.minimum([self.grid.x[i.max()] + half, self.grid.y[j.max()] + half], box)
        return lower, upper

    def design(self, x, y, shift):
        """Design columns ``F_0 .. F_{P-1}, 1, x - s_x, y - s_y`` at points, shape (N, P + 3).

        Parameters
        ----------
        x, y : ndarray, shape (N,), m
            Coordinates from the map's centre.
        shift : (float, float), m
            The face's centre in the map.
        """
        u, v = x - shift[0], y - shift[1]
        return np.column_stack([*self.faces_at(u, v), np.ones_like(u), u, v])

    def fitted_pixels(self, measured, start, rim_margin, erosion, partial):
        """The measured pixels' coordinates ``X, Y`` (m), the fitted ones and the covariance window.

        Parameters
        ----------
        measured : steady.measured_face.MeasuredFace
        start : ndarray, shape (2,), m
            The face's centre in the map.
        rim_margin, erosion : float, m
            The rim margin; it plus the shift search radius.
        partial : bool
            Whether the part fitted is less than the face (for messages).

        Returns
        -------
        X, Y : ndarray, shape of the map, m
        mask : ndarray of bool
            The fitted pixels.
        window : float, m
            The radius of the residual's covariance window.

        Raises
        ------
        ValueError
            The erosion leaves nothing to fit, the map does not cover the
            face, or its pixels are too coarse for it.
        """
        reach = self.inradius - erosion
        if reach <= 0:
            raise ValueError(f"nothing left to fit: the rim margin {rim_margin:.4g} m "
                             f"(and the shift search radius) cover the "
                             f"{self.outline.describe()}, no point of which is farther than "
                             f"{self.inradius:.4g} m from its rim")
        self._check_coverage(measured, start, erosion, partial)
        dx, dy = measured.pixel_size
        if 2 * reach < _MIN_PIXELS_ACROSS * max(dx, dy):
            raise ValueError(f"measured map {measured.source}: pixels of {max(dx, dy):.4g} m "
                             f"give fewer than {_MIN_PIXELS_ACROSS} pixels across the "
                             f"narrowest part of the fitted face, {2 * reach:.4g} m wide")
        xs, ys = measured.coordinates()
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        region = self.fitted_region(X - start[0], Y - start[1], erosion)
        mask = np.isfinite(measured.heights) & region
        # The covariance window: half the radius of the disk of the fitted
        # part's area (half the fitted radius for a disk; the inradius would
        # cut the correlation of a narrow face, a ring or a long rectangle).
        window = 0.5 * math.sqrt(region.sum() * dx * dy / math.pi)
        return X, Y, mask, window

    def _check_coverage(self, measured, start, erosion, partial):
        """Raise ``ValueError`` naming both sizes unless the map covers the part to fit.

        The part to fit, the face less ``erosion`` at the rim about ``start``,
        must lie within the map's extent (to half a measured pixel).
        """
        lower, upper = self.region_box(erosion)
        lower, upper = lower + start, upper + start
        half = 0.5 * np.array(measured.extent)
        slack = 0.5 * np.array(measured.pixel_size) * (1 + 1e-9)
        if np.all(lower >= -half - slack) and np.all(upper <= half + slack):
            return
        (nx, ny), (dx, dy) = measured.shape, measured.pixel_size
        face_lower, face_upper = self.region_box(0.0)
        width, length = (face_upper - face_lower) * 1e3
        extra = ""
        if partial or np.any(start):
            w, h = (upper - lower) * 1e3
            extra = (f"; the part fitted (after the rim margin and the shift search), "
                     f"{w:.4g} x {h:.4g} mm, spans x {lower[0] * 1e3:.4g} to "
                     f"{upper[0] * 1e3:.4g} mm and y {lower[1] * 1e3:.4g} to "
                     f"{upper[1] * 1e3:.4g} mm from the map's centre")
        raise ValueError(
            f"measured map {measured.source} of {nx} x {ny} pixels of {dx * 1e3:.4g} x "
            f"{dy * 1e3:.4g} mm ({2 * half[0] * 1e3:.4g} x {2 * half[1] * 1e3:.4g} mm) "
            f"cannot cover the {self.outline.describe()} of {width:.4g} x {length:.4g} mm"
            f"{extra}; check the pixel size, or crop the map to the face with its centre at "
            f"the map's centre")

    def maps(self, measured, X, Y, start, beta):
        """The fitted face (NaN off the face) and the phase map on the measured pixels.

        Parameters
        ----------
        measured : steady.measured_face.MeasuredFace
        X, Y : ndarray, shape of the map, m
        start : ndarray, shape (2,), m
        beta : ndarray, shape (P + 3,)
            Coefficients of :meth:`design`'s columns.

        Returns
        -------
        fitted : ndarray, shape of the map, units of ``beta`` times m/Pa
        phase : ndarray, shape of the map, int
        """
        on_face = self.outline.contains(X - start[0], Y - start[1])
        fitted = np.full(measured.shape, np.nan)
        fitted[on_face] = self.design(X[on_face], Y[on_face], start) @ beta
        phase = np.full(measured.shape, -1, dtype=np.int64)
        phase[on_face] = self.phases_at(X[on_face] - start[0], Y[on_face] - start[1])
        return fitted, phase


def _least_squares(columns, z):
    """Coefficients of ``z ~ columns @ beta``, the columns scaled to unit rms, and the scales."""
    scale = np.sqrt(np.mean(columns**2, axis=0))
    scaled = columns / scale
    coef = np.linalg.lstsq(scaled, z, rcond=None)[0]
    return coef / scale, scaled, scale


def _check_determined(columns, phases, n_phases, min_pixels):
    """Raise ``ValueError`` naming a phase the fitted pixels cannot determine."""
    counts = np.bincount(phases[phases >= 0], minlength=n_phases)
    n_fit = phases.size
    for i, c in enumerate(counts):
        if c < min_pixels:
            raise ValueError(f"phase {i} covers {c} of the {n_fit} fitted pixels (at least "
                             f"{min_pixels} needed): its wear coefficient is not determined "
                             f"(masked by NaN holes or the rim margin?)")
    scaled = columns / np.sqrt(np.mean(columns**2, axis=0))
    for i in range(n_phases):
        others = np.delete(scaled, i, axis=1)
        coef = np.linalg.lstsq(others, scaled[:, i], rcond=None)[0]
        independent = np.linalg.norm(scaled[:, i] - others @ coef) / math.sqrt(n_fit)
        if independent < _COLLINEAR_TOL:
            raise ValueError(f"phase {i}: its face is a combination of the other phases' "
                             f"faces and the plane on the fitted pixels (independent part "
                             f"{independent:.1e}); its wear coefficient is not determined")


def _search_shift(basis, x, y, z, start, max_shift):
    """Shift minimising the residual: a grid of model-pixel steps, then Nelder-Mead.

    The grid runs on at most ``_SEARCH_PIXELS`` of the fitted pixels
    (every ``s``-th), the refinement on all of them.  Returns the shift
    and whether it lies at the search limit.
    """
    def rss(offset, x, y, z):
        if np.hypot(*offset) > max_shift * (1 + 1e-9):
            return math.inf
        columns = basis.design(x, y, start + offset)
        beta = _least_squares(columns, z)[0]
        r = z - columns @ beta
        return float(r @ r)

    step = min(basis.h, max_shift)
    if step == 0.0:
        return start, False
    m = int(math.ceil(max_shift / step - 1e-9))
    grid = [np.array([i * step, j * step]) for i in range(-m, m + 1)
            for j in range(-m, m + 1) if math.hypot(i, j) * step <= max_shift * (1 + 1e-9)]
    stride = max(1, z.size // _SEARCH_PIXELS)
    sample = (x[::stride], y[::stride], z[::stride])
    best = grid[int(np.argmin([rss(g, *sample) for g in grid]))]
    reference = max(rss(best, x, y, z), np.finfo(float).tiny)
    simplex = np.array([best, best + [0.5 * step, 0.0], best + [0.0, 0.5 * step]])
    found = optimize.minimize(lambda o: rss(o, x, y, z) / reference, best,
                              method="Nelder-Mead",
                              options={"initial_simplex": simplex, "xatol": 1e-2 * basis.h,
                                       "fatol": 1e-9, "maxiter": 200})
    offset = found.x if found.fun <= 1.0 else best
    at_limit = np.hypot(*offset) > max_shift - 0.5 * step
    logger.info("shift search: %d grid points on %d pixels, %d refinement steps, offset "
                "(%.3g, %.3g) m", len(grid), sample[2].size, found.nit, *offset)
    return start + offset, bool(at_limit)


@dataclasses.dataclass(frozen=True)
class _Solution:
    """The least-squares solution on the fitted pixels, in the units of the normalised heights.

    ``beta`` the coefficients of the design columns (pressures, offset,
    tilt), ``columns`` the design matrix at the fitted pixels, ``residual``
    the residual there and ``residual_map`` on the whole map (NaN off the
    fitted pixels), ``stats`` the residual's statistics, ``start`` the face's
    centre in the map and ``at_limit`` whether the shift search stopped at
    its limit.
    """

    beta: np.ndarray
    columns: np.ndarray
    residual: np.ndarray
    residual_map: np.ndarray
    stats: object
    start: np.ndarray
    at_limit: bool


class FaceModel(FaceBasis):
    """The wear-ratio fit of a phase map: its :class:`FaceBasis` and the least-squares fit.

    The measured heights are fitted by the per-phase faces, sampled at the
    measured pixels, with a free offset and tilt (:meth:`fit`).

    Parameters
    ----------
    problem : steady.problem.Problem
        The phase map on the face's grid (the model grid), ``E*``, the
        normal force (it only enters the consistency figure
        :attr:`FitResult.load_scale`) and the wear law, a power law
        ``k_i p^m``: its exponent relates ratios and pressures,
        ``k_i / k_ref = (p_ref / p_i)^m``; its coefficients are reported
        beside the fit (:attr:`FitResult.scene_ratios`), not used by it.

    Notes
    -----
    Build one model and call :meth:`fit` for many measured faces: the
    per-phase faces are computed once (:class:`FaceBasis`).

    Examples
    --------
    A rectangular face of aspect 1:3 with a Voronoi map; the measured face
    is the forward model's with ``k_1 / k_0 = 3``, on the model's pixels:

    >>> import numpy as np
    >>> from steady import FacePhases, MeasuredFace, Problem, Voronoi
    >>> from steady.outline import Rectangle
    >>> grid = Rectangle(4e-3, 12e-3).grid(48)
    >>> phases = FacePhases(grid, Voronoi(64, (0.6, 0.4), 2029).labels(grid), 2)
    >>> model = FaceModel(Problem(phases, [1e-13, 1e-13], 10.0, 1.3e6))
    >>> model.grid.shape, model.faces.shape
    ((16, 48), (2, 16, 48))
    >>> face = np.tensordot([3e4, 1e4], model.faces, axes=1)     # p_0 / p_1 = k_1 / k_0 = 3
    >>> fit = model.fit(MeasuredFace(face, grid.h))
    >>> print(f"k1/k0 = {fit.ratios[1]:.6f}, {fit.samples} pixels")
    k1/k0 = 3.000000, 768 pixels
    """

    def __init__(self, problem):
        if not isinstance(problem, Problem):
            raise ValueError(f"FaceModel takes a steady.problem.Problem, got "
                             f"{type(problem).__name__}")
        factor = problem.wear.factor
        if factor is None or factor.exponent is None:
            # Its model relates ratios and pressures through k_i p_i^m = C.
            raise ValueError(f"the fit supports the power law k p^m, not the "
                             f"{problem.wear.describe()}")
        if problem.sliding is not None:
            # Its model is a pressure constant on each phase: a face of K chi_i per phase.
            raise ValueError(f"the fit assumes a uniform sliding speed (pressure constant on "
                             f"each phase), not the sliding {problem.sliding.describe()}")
        if problem.counterbody.layered:
            # Its faces are the half-space's (padded past the face to fit the rim).
            raise ValueError(f"the fit assumes a half-space counter-body, not a "
                             f"{problem.counterbody.describe()}")
        super().__init__(problem.phases, problem.E_star)
        self.problem = problem
        self.normal_force = problem.normal_force
        self.exponent = factor.exponent
        self.wear_coefficients = np.asarray(factor.coefficients, dtype=float)

    @classmethod
    def from_scene(cls, scene, *, n=None):
        """The model of a :class:`steady.scene.Scene` on its grid of ``n`` (default ``scene.n``).

        The phase map is rasterised on ``scene.grid(n)``
        (:meth:`steady.scene.Scene.phase_labels`, which names a phase with no
        pixel on the face).
        """
        return cls(problem_of(scene, n=n))

    def fit(self, measured, *, shift=(0.0, 0.0), search_shift=False, max_shift=None,
            rim_margin=0.0, reference_phase=0, confidence=0.95,
            min_phase_pixels=DEFAULT_MIN_PHASE_PIXELS):
        """Fit the wear ratios to a measured face; see :func:`fit_face`."""
        start, rim_margin, max_shift, confidence, ref = self._fit_options(
            measured, shift, max_shift, rim_margin, reference_phase, confidence)
        # Every trial shift within max_shift of the start sees the same pixels:
        # those at least rim_margin + max_shift from the rim at the start.
        erosion = rim_margin + (max_shift if search_shift else 0.0)
        X, Y, mask, window = self.fitted_pixels(measured, start, rim_margin, erosion,
                                                rim_margin or search_shift)
        x, y, heights = X[mask], Y[mask], measured.heights[mask]
        # The fit is linear in the heights: it runs on the heights over a power of two
        # near their largest magnitude (exact, no rounding), so that the squares it forms
        # (least squares, the residual's covariance, Fieller's quadratic) neither overflow
        # nor underflow whatever the heights' unit; the results are scaled back exactly
        # (to the same bits as a fit in metres, where that does not overflow).
        units = _HeightUnit(heights)
        z = units.normalise(heights)
        _check_determined(self.design(x, y, start), self.phases_at(x - start[0], y - start[1]),
                          self.n_phases, min_phase_pixels)
        at_limit = False
        if search_shift:
            start, at_limit = _search_shift(self, x, y, z, start, max_shift)
            _check_determined(self.design(x, y, start),
                              self.phases_at(x - start[0], y - start[1]), self.n_phases,
                              min_phase_pixels)
        columns = self.design(x, y, start)
        beta, scaled, scale = _least_squares(columns, z)
        residual = z - columns @ beta
        residual_map = np.full(measured.shape, np.nan)
        residual_map[mask] = residual
        stats = _ResidualStatistics(residual_map, mask, measured.pixel_size, window, scaled,
                                    scale, self.n_phases + 3, confidence)
        solution = _Solution(beta, columns, residual, residual_map, stats, start, at_limit)
        return self._result(measured, X, Y, mask, solution, units, ref, confidence, max_shift)

    def _result(self, measured, X, Y, mask, solution, units, ref, confidence, max_shift):
        """The :class:`FitResult` of a solution: ratios, intervals, figures, back in SI units."""
        beta, columns, stats, start = (solution.beta, solution.columns, solution.stats,
                                       solution.start)
        P, m = self.n_phases, self.exponent
        p, v = beta[:P], stats.covariance[:P, :P]
        # Ratios and their intervals do not depend on the heights' unit.
        ratios, intervals, notes = _ratios(p, v, ref, m, stats.t)
        load = float(self.areas @ p)
        load_sd = math.sqrt(max(float(self.areas @ v @ self.areas), 0.0))
        fitted, phase = self.maps(measured, X, Y, start, beta)
        # Back to metres and pascals.
        beta = units.restore(beta, 1, "fitted pressures")
        covariance = units.restore(v, 2, "covariance of the pressures")
        errors = units.restore(np.sqrt(np.maximum(np.diag(v), 0.0)), 1,
                               "standard errors of the pressures")
        residual_rms = units.restore(math.sqrt(np.mean(solution.residual**2)), 1,
                                     "residual rms")
        relief = units.restore(float(np.ptp(columns[:, :P] @ p)), 1, "relief")
        load_interval = tuple(units.restore(load + sign * stats.t * load_sd, 1, "load scale")
                              for sign in (-1, 1))
        load = units.restore(load, 1, "load scale")
        fitted = units.restore(fitted, 1, "fitted face")
        residual_map = units.restore(solution.residual_map, 1, "residual")
        units.check(measured)
        p = beta[:P]
        load_scale = load / self.normal_force
        load_scale_interval = (load_interval[0] / self.normal_force,
                               load_interval[1] / self.normal_force)
        with np.errstate(over="ignore", divide="ignore"):
            implied_E_star = self.E_star / load_scale if load_scale > 0 else math.nan
        failures = _failures(p)
        failures += _not_finite(ratios, intervals, p, ref, {
            "standard errors of the pressures": errors,
            "residual rms": residual_rms,
            "load scale": load_scale,
            "load scale interval": load_scale_interval,
            "implied E*": implied_E_star if load_scale > 0 else 0.0,
            "offset and tilt": beta[P:],
            "effective samples": stats.effective_samples,
        })
        if solution.at_limit:
            notes.append(f"the shift lies at the search limit {max_shift:.4g} m")
        notes += stats.notes()
        logger.info("fit: %d pixels (%.0f effective), residual rms %.3g m, ratios %s",
                    stats.samples, stats.effective_samples, residual_rms, ratios.tolist())
        return FitResult(
            ratios=ratios, ratio_intervals=intervals, phase_pressures=p,
            phase_pressure_errors=errors, pressure_covariance=covariance,
            offset=float(beta[P]), tilt=(float(beta[P + 1]), float(beta[P + 2])),
            shift=(float(start[0]), float(start[1])), residual_rms=residual_rms,
            relief=relief, samples=stats.samples,
            effective_samples=float(stats.effective_samples),
            correlation_length=float(stats.correlation.length),
            degrees_of_freedom=float(stats.dof), load_scale=load_scale,
            load_scale_interval=load_scale_interval, implied_normal_force=load,
            implied_E_star=implied_E_star, confidence=confidence, reference_phase=ref,
            exponent=m, normal_force=self.normal_force, E_star=self.E_star,
            outline=self.outline, n=self.n, success=not failures,
            message="; ".join(failures + notes), measured=measured, fitted=fitted,
            residual=residual_map, fit_mask=mask, phase=phase,
            scene_ratios=self.wear_coefficients / self.wear_coefficients[ref],
        )

    def _fit_options(self, measured, shift, max_shift, rim_margin, reference_phase,
                     confidence):
        """The fit's options checked: ``(start, rim_margin, max_shift, confidence, reference)``."""
        if not isinstance(measured, MeasuredFace):
            raise ValueError(f"measured must be a MeasuredFace, got {type(measured).__name__}")
        start = np.asarray(shift, dtype=float)
        if start.shape != (2,) or not np.all(np.isfinite(start)):
            raise ValueError(f"shift must be two finite lengths (m), got {shift!r}")
        rim_margin = RIM_MARGIN.parse(rim_margin, "")
        max_shift = (_DEFAULT_MAX_SHIFT * self.outline.scale if max_shift is None
                     else MAX_SHIFT.parse(max_shift, ""))
        confidence = float(confidence)
        if not 0 < confidence < 1:
            raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
        if (isinstance(reference_phase, bool)
                or not isinstance(reference_phase, (int, np.integer))
                or not 0 <= reference_phase < self.n_phases):
            raise ValueError(f"reference_phase must be a phase index 0..{self.n_phases - 1}, "
                             f"got {reference_phase!r}")
        return start, rim_margin, max_shift, confidence, int(reference_phase)


class _ResidualStatistics:
    """The fit's residual as a correlated field: its covariance, effective samples and ``t``.

    Parameters
    ----------
    residual_map : ndarray, shape of the measured map, m
        The residual on the fitted pixels, NaN elsewhere.
    mask : ndarray of bool
        The fitted pixels.
    pixel_size : (float, float), m
    window : float, m
        Radius of the covariance estimate.
    scaled : ndarray, shape (N, K)
        The design matrix with its columns scaled (:func:`_least_squares`).
    scale : ndarray, shape (K,)
        The column scales.
    unknowns : int
        ``K``, the fitted parameters.
    confidence : float
        Level of the intervals.
    """

    def __init__(self, residual_map, mask, pixel_size, window, scaled, scale, unknowns,
                 confidence):
        self.window = window
        self.correlation = _Covariance(residual_map, mask, pixel_size, window, scaled)
        self.samples = int(mask.sum())
        self.effective_samples = self.samples / self.correlation.correlation_area
        self.dof = max(self.effective_samples - unknowns, 1.0)
        bread = np.linalg.pinv(scaled.T @ scaled)
        covariance = bread @ self.correlation.meat @ bread
        covariance /= np.outer(scale, scale)
        #: Covariance of the fitted parameters (pressures, offset, tilt).
        self.covariance = covariance
        #: Student's ``t`` of the intervals.
        self.t = float(special.stdtrit(self.dof, 0.5 + 0.5 * confidence))

    def notes(self):
        """What the user should know about the intervals' reliability."""
        notes = []
        if not self.correlation.converged:
            notes.append(f"the estimate of the residual's correlation did not settle in "
                         f"{self.correlation.iterations} iterations: the intervals are "
                         f"approximate")
        if self.correlation.window_limited:
            notes.append("the residual stays correlated out to the covariance window "
                         f"({self.window:.3g} m): the intervals may be too narrow")
        return notes


class _HeightUnit:
    """The fit's working unit of height: a power of two near the largest measured height.

    Dividing by a power of two is exact, and so is multiplying back: a fit
    in this unit gives the bits of a fit in metres wherever the latter
    neither overflows nor underflows, and stays finite for any finite
    heights.  :meth:`restore` notes what cannot be represented in metres and
    pascals; :meth:`check` refuses the map then.

    Parameters
    ----------
    heights : ndarray, m
        The fitted heights (finite).
    """

    def __init__(self, heights):
        largest = float(np.max(np.abs(heights), initial=0.0))
        #: ``heights / 2**exponent`` lies within (-1, 1).
        self.exponent = int(np.frexp(largest)[1]) if largest > 0 else 0
        self.range = ((float(np.min(heights)), float(np.max(heights))) if heights.size
                      else (math.nan, math.nan))
        self.lost = []

    def normalise(self, heights):
        """Heights in the working unit."""
        return np.ldexp(heights, -self.exponent)

    def restore(self, value, power, name):
        """A result of the fit (of degree ``power`` in the heights) back in SI units.

        Notes ``name`` when it overflows (to infinity) or its largest
        magnitude underflows (below the smallest normal number).
        """
        value = np.asarray(value, dtype=float)
        with np.errstate(over="ignore", under="ignore"):
            out = np.ldexp(value, power * self.exponent)
        finite = np.isfinite(value)
        if np.any(np.isinf(out) & finite):
            self.lost.append(f"{name} beyond {np.finfo(float).max:.3g}")
        elif (np.max(np.abs(value[finite]), initial=0.0) > 0
              and np.max(np.abs(out[finite]), initial=0.0) < np.finfo(float).tiny):
            self.lost.append(f"{name} below {np.finfo(float).tiny:.3g}")
        return out if out.ndim else float(out)

    def check(self, measured):
        """Refuse the map when a result could not be represented (:meth:`restore`).

        Raises
        ------
        ValueError
            Naming the map, the heights' range and what left the range of
            floating-point numbers.
        """
        if self.lost:
            lo, hi = self.range
            raise ValueError(f"measured map {measured.source}: heights from {lo:.3g} to "
                             f"{hi:.3g} m are out of the range the fit can report in metres "
                             f"and pascals ({self.lost[0]}); check the heights' unit "
                             f"(height scale)")


def _not_finite(ratios, intervals, p, ref, figures):
    """Why the fit's figures make no answer: what is not finite, and ratios it leaves open.

    Parameters
    ----------
    ratios, intervals, p, ref
        As :func:`_ratios` and the pressures (Pa); a ratio of a pressure
        that is not positive is left to :func:`_failures`.
    figures : dict of str to float or array
        Further figures that must be finite.

    Returns
    -------
    list of str
    """
    reasons = []
    for i, ratio in enumerate(ratios):
        if i == ref:
            continue
        lo, hi = intervals[i]
        if p[ref] > 0 and p[i] > 0 and not math.isfinite(ratio):
            reasons.append(f"k{i}/k{ref} = {ratio} is not finite")
        if math.isnan(lo) or math.isnan(hi) or math.isinf(lo):
            reasons.append(f"the interval of k{i}/k{ref}, [{lo:.4g}, {hi:.4g}], is not finite")
        elif lo == 0.0 and math.isinf(hi):
            reasons.append(f"k{i}/k{ref} is not determined by the map: its interval is "
                           f"[0, inf] (phase {i}'s pressure is not told from zero against "
                           f"the noise)")
    for name, value in figures.items():
        if not np.all(np.isfinite(value)):
            reasons.append(f"the {name} {np.round(value, 6).tolist()} is not finite")
    return reasons


def _ratios(p, v, ref, m, t):
    """Ratios ``(p_ref / p_i)^m`` with Fieller intervals, and notes on one-sided ones."""
    P = len(p)
    notes = []
    ratios = np.full(P, np.nan)
    intervals = np.full((P, 2), np.nan)
    for i in range(P):
        if i == ref:
            ratios[i], intervals[i] = 1.0, (1.0, 1.0)
            continue
        if p[ref] > 0 and p[i] > 0:
            ratios[i] = (p[ref] / p[i]) ** m
        lo, hi = _fieller(p[ref], p[i], v[ref, ref], v[i, i], v[ref, i], t)
        intervals[i] = (lo**m, hi**m)
        if lo == 0.0 and math.isinf(hi):
            continue  # no bound at all: a failure (_not_finite), not a note
        if math.isinf(hi):
            notes.append(f"k{i}/k{ref} is bounded only from below: phase {i}'s pressure is "
                         f"not distinguished from zero")
        elif lo == 0.0:
            notes.append(f"k{i}/k{ref} is bounded only from above: phase {ref}'s pressure "
                         f"is not distinguished from zero")
    return ratios, intervals, notes


def _failures(p):
    """Why fitted pressures ``p`` (Pa) make no wear law: those that are not positive."""
    failures = [f"phase {i}: fitted pressure {p[i]:.4g} Pa is not positive"
                for i in range(len(p)) if not p[i] > 0]
    if failures and np.all(p < 0):
        failures.append("is the height map upside down? The fit expects the face's "
                        "elevation, larger = protruding")
    return failures


def fit_face(measured, problem, **options):
    """Wear ratios that best explain a measured worn face (inverse of eq. 7, 9).

    Least squares over the phase pressures, a height offset and a tilt
    (and, with ``search_shift``, a lateral shift of the phase map); the
    ratios ``k_i / k_ref = (p_ref / p_i)^m`` with confidence intervals from
    the covariance of a spatially correlated residual.

    Parameters
    ----------
    measured : MeasuredFace
        Height map (m, larger = protruding, NaN where missing) with its
        pixel size; its centre is the face's centre (the origin of the
        outline) unless ``shift`` says otherwise.  It must cover the face's
        bounding box.
    problem : steady.problem.Problem
        The phase map on the model grid, ``E*`` (it scales the relief only:
        the ratios do not depend on it), the normal force (it enters only
        the consistency figure ``load_scale``) and the power law whose
        exponent relates ratios and pressures (see :class:`FaceModel`).
    **options
        Keywords of the fit:

        - ``shift`` : (float, float), m -- position of the face's centre
          from the map's centre (default ``(0, 0)``); the start of a search;
        - ``search_shift`` : bool -- search the shift that minimises the
          residual within ``max_shift`` of ``shift`` (default False);
        - ``max_shift`` : float, m -- search radius (default ``0.05 L``,
          ``L`` the outline's scale: the radius of a disk, else the larger
          half side of the bounding box); the fitted part of the face
          shrinks by it at the rim so that every shift sees the same pixels;
        - ``rim_margin`` : float, m -- leave out the points within this
          distance of the face's rim (default 0; see
          :meth:`FaceModel.rim_distance`);
        - ``reference_phase`` : int -- the phase the ratios refer to
          (default 0);
        - ``confidence`` : float -- level of the intervals (default 0.95);
        - ``min_phase_pixels`` : int -- fewest fitted pixels of a phase
          (default :data:`DEFAULT_MIN_PHASE_PIXELS`).

    Returns
    -------
    FitResult
        ``success`` is False (with the reason in ``message``) when a
        fitted phase pressure is not positive, a ratio's interval is
        ``[0, inf]`` (the map does not determine it) or a figure is not
        finite.  Ratios and intervals do not depend on the heights' unit.

    Raises
    ------
    ValueError
        The map cannot cover the face (names both sizes), the rim margin
        leaves nothing to fit, bad options, heights so large or small
        that a result cannot be represented in metres and pascals (names
        their range), or
        the fit is not determined: a phase covers too few fitted pixels, or
        its face is a combination of the other columns (names the phase).

    See Also
    --------
    FaceModel : build once, fit many faces.
    fit_scene : the same from a scene file.

    Examples
    --------
    A synthetic measured face from the forward model (eq. 7, 9) with
    ``k_1 / k_0 = 3``, a tilt, an offset, noise of 1 % of the relief and the
    face's outside as NaN (masked):

    >>> import numpy as np
    >>> from steady import Circle, FacePhases, MeasuredFace, Problem, Voronoi, fit_face, solve
    >>> n, E_star, force = 48, 1.3e6, 10.0
    >>> grid = Circle(4e-3).grid(n)
    >>> phases = FacePhases(grid, Voronoi(64, (0.6, 0.4), seed=2029).labels(grid), 2)
    >>> problem = Problem(phases, [1e-13, 3e-13], force, E_star)
    >>> truth = solve(problem)
    >>> relief = np.nanmax(truth.face) - np.nanmin(truth.face)
    >>> noise = np.random.default_rng(8191).standard_normal((n, n))
    >>> heights = truth.face + 2e-5 + 1e-3 * grid.x[:, None] + 0.01 * relief * noise
    >>> fit = fit_face(MeasuredFace(heights, grid.h), problem)
    >>> lo, hi = fit.ratio_intervals[1]
    >>> print(f"k1/k0 = {fit.ratios[1]:.3f} in [{lo:.3f}, {hi:.3f}], tilt {fit.tilt[0]:.4f}")
    k1/k0 = 3.008 in [2.986, 3.030], tilt 0.0012
    >>> print(f"load scale {fit.load_scale:.3f}, success {fit.success}")
    load scale 1.000, success True
    """
    return FaceModel(problem).fit(measured, **options)


def fit_scene(scene, measured, *, n=None, **options):
    """Fit the wear ratios of a scene's phase map to a measured face.

    Parameters
    ----------
    scene : Scene
        Phase map, outline, ``E*``, load and exponent (its wear
        coefficients are reported beside the fit, not used).
    measured : MeasuredFace
    n : int, optional
        Model grid, pixels along the longer side of the face's bounding box
        (default ``scene.n``).
    **options
        As :func:`fit_face`.

    Returns
    -------
    FitResult
    """
    return FaceModel.from_scene(scene, n=n).fit(measured, **options)
