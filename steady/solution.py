"""Closed-form limiting worn face of a multi-phase punch (paper eq. 7, 9, 15).

In the steady state every point of the face wears at the same rate.  With a
local wear law ``dw/ds = k_i p^m`` on phase ``i`` that means
``k_i p_i^m = C``: the pressure is constant on each phase,

    p_i = F_N k_i^(-1/m) / sum_j A_j k_j^(-1/m)

(eq. 7 for Archard's law ``m = 1``), and the limiting face is the
half-space displacement under that pressure, ``f_inf = K p`` (eq. 9).  The
face is defined up to a constant (the rigid offset keeps growing); it is
reported as ``K p`` itself.

Normalisation (eq. 12, 15): with ``pbar = F_N / (pi a^2)`` and
``grad_f0 = 4 pbar / (pi E*)``, the normalised face
``f_inf / (grad_f0 a)`` and the normalised rms slope ``rms / grad_f0`` depend
only on the phase geometry, the wear ratios and the exponent.  For a
homogeneous cylinder the normalised face is ``E(r/a)`` (eq. 10) and the
normalised rms slope tends to 1 under refinement
(:func:`steady.reference.cylinder_rms_slope`).  A face of another outline
(:mod:`steady.outline`) is normalised the same way by its own homogeneous
face: ``pbar = F_N / A`` and ``grad_f0`` that face's rms slope
(:mod:`steady.normalisation`), with lengths in units of the outline's
scale ``L``.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from .accuracy import estimate_rms_slope
from .halfspace import HalfSpace
from .normalisation import reference_slope
from .outline import Circle
from .pressures import pressure_field
from .relief import rms_height

__all__ = ["SteadyResult", "solve", "solve_scene"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True, eq=False)
class SteadyResult:
    """Limiting worn state of a multi-phase punch.

    Attributes
    ----------
    labels : ndarray, shape (nx, ny), int
        Phase index on the face, -1 off it.
    pressure : ndarray, shape (nx, ny), Pa
        Steady pressure, constant on each phase, zero off the face.
    phase_pressures : ndarray, shape (P,), Pa
        Pressure on each phase (eq. 7).
    face : ndarray, shape (nx, ny), m
        Limiting face ``f_inf = K p`` (eq. 9) at the pixel centres; NaN
        off the face.
    slope : ndarray, shape (nx, ny), dimensionless
        Magnitude of the gradient of ``f_inf``; NaN off the face.
    rms_slope : float, dimensionless
        Best estimate of the rms slope over the face: the energy-corrected
        value of :mod:`steady.accuracy` where ``rms_slope_error`` is set,
        else ``rms_slope_plain``.
    reference_slope : float, dimensionless
        ``grad_f0``, the rms slope of the homogeneous face of the same
        outline under the same load: ``4 pbar / (pi E*)`` for a disk (eq.
        12); see :mod:`steady.normalisation`.
    fill_factors : ndarray, shape (P,)
        Realised area fractions of the phases (pixel counts, eq. 13).
    wear_coefficients : ndarray, shape (P,), 1/Pa
        ``k_i`` of each phase.
    exponent : float
        Pressure exponent ``m`` of the wear law.
    normal_force : float, N
    radius : float or None, m
        Punch radius ``a`` of a circular face; None for other outlines.
    E_star : float, Pa
    rms_slope_plain : float, dimensionless
        Root mean square of ``slope`` over the face pixels (plain pixel
        quadrature: first order, low by up to tens of per cent on fine
        grains).
    rms_slope_error : float, dimensionless
        Estimated discretisation error of ``rms_slope``; NaN when not
        estimated (:func:`solve` alone does not).
    rms_height : float, m
        Rms of ``face`` over the face pixels about its least-squares plane
        (:func:`steady.relief.rms_height`; the asymptote of the run-in's
        ``rms_height``); NaN when not computed.
    outline : outline object
        The face's outline (:mod:`steady.outline`); default the disk of
        ``radius``.
    reference_slope_error : float, dimensionless
        Uncertainty of ``reference_slope`` (0 for a closed form).
    reference_slope_source : str
        Where ``reference_slope`` comes from, in words.
    """

    labels: np.ndarray
    pressure: np.ndarray
    phase_pressures: np.ndarray
    face: np.ndarray
    slope: np.ndarray
    rms_slope: float
    reference_slope: float
    fill_factors: np.ndarray
    wear_coefficients: np.ndarray
    exponent: float
    normal_force: float
    radius: float
    E_star: float
    rms_slope_plain: float = math.nan
    rms_slope_error: float = math.nan
    rms_height: float = math.nan
    outline: object = None
    reference_slope_error: float = 0.0
    reference_slope_source: str = ""

    def __post_init__(self):
        """Complete ``outline`` from ``radius`` (a disk)."""
        if self.outline is None:
            object.__setattr__(self, "outline", Circle(self.radius))

    @property
    def n(self):
        """Pixels along the longer side of the grid (across the diameter of a disk)."""
        return max(self.labels.shape)

    @property
    def shape(self):
        """``(nx, ny)`` of the grid."""
        return self.labels.shape

    @property
    def scale(self):
        """The outline's length scale ``L`` (the radius of a disk), m."""
        return self.outline.scale

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return self.phase_pressures.shape[0]

    @property
    def pixel_size(self):
        """Pixel side ``h = 2L/n``, m."""
        return 2.0 * self.scale / self.n

    @property
    def mean_pressure(self):
        """``pbar = F_N / A`` (``pi a^2`` for a disk), Pa."""
        if isinstance(self.outline, Circle):
            return self.normal_force / (math.pi * self.outline.radius**2)
        return self.normal_force / self.outline.area

    @property
    def normalised_rms_slope(self):
        """``rms_slope / grad_f0`` (eq. 15), dimensionless."""
        return self.rms_slope / self.reference_slope

    @property
    def normalised_rms_height(self):
        """``rms_height / (grad_f0 L)``, dimensionless (0.15499 for eq. 10)."""
        return self.rms_height / (self.reference_slope * self.scale)

    @property
    def normalised_face(self):
        """``f_inf / (grad_f0 L)``, shape (nx, ny), dimensionless; NaN off the face.

        Eq. 15 divided by ``a``; equals ``E(r/a)`` for a homogeneous
        cylinder (eq. 10).
        """
        return self.face / (self.reference_slope * self.scale)


def _positive_finite(value, name, unit):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive finite number ({unit}), "
                         f"got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number ({unit}), got {value!r}")
    return v


def _wear_coefficients(wear_coefficients, n_phases):
    k = np.atleast_1d(np.asarray(wear_coefficients, dtype=float))
    if k.ndim != 1 or k.size != n_phases:
        raise ValueError(f"need one wear coefficient per phase ({n_phases}), got "
                         f"{np.asarray(wear_coefficients).tolist()}")
    if not np.all(np.isfinite(k) & (k > 0)):
        raise ValueError(f"wear coefficients must be positive and finite (1/Pa), got "
                         f"{k.tolist()}")
    return k


def solve(halfspace, labels, wear_coefficients, normal_force, *, exponent=1.0, outline=None):
    """Limiting worn face of a multi-phase punch (eq. 7, 9).

    Parameters
    ----------
    halfspace : HalfSpace
        Operator of the grid over the face's bounding box; carries its
        shape ``(nx, ny)``, the pixel size ``h`` and ``E*``.
    labels : ndarray, shape (nx, ny), int
        Phase index ``0..P-1`` on the face, -1 off it (the face is where
        ``labels >= 0``); every phase present.
    wear_coefficients : array_like, shape (P,), 1/Pa
        ``k_i = k_wear,i / sigma_0,i``, positive and finite.
    normal_force : float, N
        ``F_N``, positive and finite.
    exponent : float, optional
        Pressure exponent ``m`` of the local wear law ``dw/ds = k p^m``
        (default 1, Archard).  Positive and finite.
    outline : outline object, optional
        The face's outline (:mod:`steady.outline`), for the normalisation;
        default: the disk of radius ``a = n h / 2`` on a square grid.

    Returns
    -------
    SteadyResult

    Raises
    ------
    ValueError
        Bad input (named in the message), or a non-finite result.

    Notes
    -----
    One forward transform of the pressure feeds the three products (face
    and two slope components), so a solve costs one forward and three
    inverse transforms.

    Examples
    --------
    A biphasic Voronoi punch whose phase 1 wears ten times faster: by eq. 7
    its pressure is ten times lower.

    >>> from steady import HalfSpace, Voronoi, pixel_size, solve
    >>> n, a = 64, 4e-3
    >>> labels = Voronoi(100, (0.5, 0.5), seed=2024).labels(n)
    >>> result = solve(HalfSpace(n, pixel_size(n, a), 1.3e6), labels, [1e-13, 1e-12], 10.0)
    >>> print(f"{result.phase_pressures[0] / result.phase_pressures[1]:.6f}")
    10.000000
    >>> result.face.shape, result.n_phases
    ((64, 64), 2)
    >>> print(f"rms slope {result.rms_slope:.4f} = {result.normalised_rms_slope:.4f} grad_f0")
    rms slope 0.2583 = 1.3259 grad_f0
    """
    if not isinstance(halfspace, HalfSpace):
        raise ValueError(f"halfspace must be a HalfSpace, got {type(halfspace).__name__}")
    labels = np.asarray(labels)
    shape = tuple(halfspace.shape)
    if labels.shape != shape:
        raise ValueError(f"labels must have shape {shape} to match the half-space grid, "
                         f"got {labels.shape}")
    normal_force = _positive_finite(normal_force, "normal_force", "N")
    exponent = _positive_finite(exponent, "exponent", "dimensionless")
    if not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"labels must be integers, got dtype {labels.dtype}")
    n_phases = int(labels.max()) + 1
    k = _wear_coefficients(wear_coefficients, n_phases)
    on_face = labels >= 0
    h = halfspace.h
    if outline is None:
        if shape[0] != shape[1]:
            raise ValueError(f"a {shape[0]} x {shape[1]} grid needs its outline (the default "
                             f"is a disk on a square grid)")
        outline = Circle(0.5 * shape[0] * h)
    pressure, p_phase, counts = pressure_field(labels, k, normal_force, h * h,
                                               exponent=exponent, face_mask=on_face)

    pressure_q = halfspace.forward(pressure)
    face = halfspace.displacement_q(pressure_q)
    gx, gy = halfspace.gradient(pressure, pressure_q=pressure_q)
    slope2 = gx * gx
    slope2 += gy * gy
    rms = math.sqrt(np.sum(slope2, where=on_face) / counts.sum())
    height = rms_height(face, on_face, h)
    off = ~on_face
    face[off] = np.nan
    slope = np.sqrt(slope2, out=slope2)
    slope[off] = np.nan
    if not math.isfinite(rms):
        raise ValueError(f"steady solve produced a non-finite rms slope ({rms}); "
                         f"phase pressures {p_phase.tolist()} Pa")
    ref = reference_slope(outline, normal_force, halfspace.E_star)
    grad_f0 = ref.value
    logger.debug("steady %s P=%d rms slope %.6g (%.6g grad_f0)", shape, n_phases, rms,
                 rms / grad_f0)
    return SteadyResult(
        labels=labels,
        pressure=pressure,
        phase_pressures=p_phase,
        face=face,
        slope=slope,
        rms_slope=rms,
        reference_slope=grad_f0,
        fill_factors=counts / counts.sum(),
        wear_coefficients=k,
        exponent=exponent,
        normal_force=normal_force,
        radius=outline.radius if isinstance(outline, Circle) else None,
        E_star=halfspace.E_star,
        rms_slope_plain=rms,
        rms_height=height,
        outline=outline,
        reference_slope_error=ref.error,
        reference_slope_source=ref.source,
    )


def solve_scene(scene, *, n=None, slope_error=True):
    """Solve the steady state of a :class:`steady.scene.Scene`.

    Parameters
    ----------
    scene : Scene
    n : int, optional
        Grid size, pixels along the longer side; default ``scene.n``.  The
        geometry is rasterised at this size.
    slope_error : bool, optional
        Replace the plain pixel rms slope by the energy-corrected one with
        its error estimate (:func:`steady.accuracy.estimate_rms_slope`,
        default True).  Costs a few solves of the same grid.

    Returns
    -------
    SteadyResult

    Examples
    --------
    The homogeneous epoxy cylinder of the paper's Fig. 6 on a coarse grid:
    the corrected rms slope is ``grad_f0`` (eq. 10, 12) within its error
    bar, the plain pixel value 3.5 % low.

    >>> from steady import load_scene, solve_scene
    >>> scene = load_scene("studies/scenes/epoxy_cylinder.toml")
    >>> result = solve_scene(scene, n=64)
    >>> print(f"{result.normalised_rms_slope:.3f} "
    ...       f"+- {result.rms_slope_error / result.reference_slope:.3f} grad_f0, "
    ...       f"plain {result.rms_slope_plain / result.reference_slope:.3f}")
    0.997 +- 0.012 grad_f0, plain 0.965
    """
    grid = scene.grid(n)
    labels = scene.geometry.labels(grid)
    halfspace = HalfSpace(grid.shape, grid.h, scene.E_star)
    result = solve(halfspace, labels, scene.wear_coefficients, scene.normal_force,
                   exponent=scene.exponent, outline=scene.outline)
    if not slope_error:
        return result
    estimate = estimate_rms_slope(scene.geometry, scene.wear_coefficients, scene.normal_force,
                                  scene.outline, scene.E_star, grid.n, exponent=scene.exponent)
    return dataclasses.replace(result, rms_slope=estimate.rms_slope,
                               rms_slope_error=estimate.error)
