"""Closed-form limiting worn face of a multi-phase punch (paper equations 7, 9, 15).

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
(:func:`steady.reference.disk_normalised_rms_slope`).  A face of another outline
(:mod:`steady.outline`) is normalised the same way by its own homogeneous
face: ``pbar = F_N / A`` and ``grad_f0`` that face's rms slope
(:mod:`steady.normalisation`), with lengths in units of the outline's
scale ``L``.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math

import numpy as np

from .counterbody import Counterbody
from .normalisation import reference_slope
from .problem import Problem
from .relief import rms_height
from .rms_slope import estimate_map_rms_slope, estimate_rms_slope, slope_energy_of
from .scene import problem_of
from .topography import isotropic_psd, to_topography
from .validity import check_rms_slope

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
        Steady pressure, constant on each phase, zero off the face; under
        non-uniform sliding (:mod:`steady.sliding`) the pixel-wise closed
        form ``k_i v(x) p^m / v_ref = C``.
    phase_pressures : ndarray, shape (P,), Pa
        Pressure on each phase (eq. 7); under non-uniform sliding the mean
        over each phase.
    face : ndarray, shape (nx, ny), m
        Limiting face ``f_inf = K p`` (eq. 9) at the pixel centres; NaN
        off the face.
    slope : ndarray, shape (nx, ny), dimensionless
        Magnitude of the gradient of ``f_inf``; NaN off the face.
    rms_slope : float, dimensionless
        The rms slope over the face: the energy-corrected estimate of
        :mod:`steady.rms_slope`, whose error bar is ``rms_slope_error``;
        NaN when not estimated (``face_only``).  Never the plain pixel
        value, which is ``rms_slope_plain``.
    reference_slope : float, dimensionless
        ``grad_f0``, the rms slope of the homogeneous face of the same
        outline under the same load: ``4 pbar / (pi E*)`` for a disk (eq.
        12); see :mod:`steady.normalisation`.
    fill_factors : ndarray, shape (P,)
        Realised area fractions of the phases (pixel counts, eq. 13).
    wear : steady.wear.WearLaw or None
        The wear law of the phases (:mod:`steady.wear`); None for a result
        read from a file whose law is not registered here.
    normal_force : float, N
    E_star : float, Pa
    outline : outline object
        The face's outline (:mod:`steady.outline`).
    rms_slope_plain : float, dimensionless
        Root mean square of ``slope`` over the face pixels (plain pixel
        quadrature: first order, low by up to tens of per cent on fine
        grains); always set.
    rms_slope_error : float, dimensionless
        Estimated discretisation error of ``rms_slope``; infinite where no
        bound could be estimated, NaN when ``rms_slope`` is not estimated.
    rms_height : float, m
        Rms of ``face`` over the face pixels about its least-squares plane
        (:func:`steady.relief.rms_height`; the asymptote of the run-in's
        ``rms_height``); NaN when not computed.
    reference_slope_error : float, dimensionless
        Uncertainty of ``reference_slope`` (0 for a closed form).
    reference_slope_source : str
        Where ``reference_slope`` comes from, in words.
    thickness, poisson : float or None
        The counter-body's layer (m, and its Poisson's ratio); None: a
        half-space (:class:`steady.counterbody.Counterbody`).
    """

    labels: np.ndarray
    pressure: np.ndarray
    phase_pressures: np.ndarray
    face: np.ndarray
    slope: np.ndarray
    rms_slope: float
    reference_slope: float
    fill_factors: np.ndarray
    wear: object
    normal_force: float
    E_star: float
    outline: object
    rms_slope_plain: float = math.nan
    rms_slope_error: float = math.nan
    rms_height: float = math.nan
    reference_slope_error: float = 0.0
    reference_slope_source: str = ""
    thickness: float | None = None
    poisson: float | None = None

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
        """``pbar = F_N / A``, ``A`` the outline's exact area (``pi a^2`` for a disk), Pa."""
        return self.normal_force / self.outline.area

    @property
    def normalised_rms_slope(self):
        """``rms_slope / grad_f0`` (eq. 15), dimensionless."""
        return self.rms_slope / self.reference_slope

    @property
    def normalised_rms_slope_plain(self):
        """``rms_slope_plain / grad_f0``, dimensionless: the plain pixel value, normalised."""
        return self.rms_slope_plain / self.reference_slope

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

    @functools.cached_property
    def face_psd(self):
        """Radially averaged power spectral density ``C^iso(q)`` of :attr:`face`.

        A :class:`steady.topography.PowerSpectrum`: the wavevector (m^-1) and
        the density (m^4) of :func:`steady.topography.isotropic_psd`, the face
        about its least-squares plane under SurfaceTopography's radial Hann
        window (docs/model.md, "The face's power spectrum").  Computed on
        first use; SurfaceTopography is not needed.
        """
        return isotropic_psd(self.face, self.pixel_size)

    def topography(self):
        """:attr:`face` as a ``SurfaceTopography.Topography`` (the optional extra ``surface``).

        Heights in m, undefined off the face, physical size ``(nx h, ny h)``
        (:func:`steady.topography.to_topography`): power spectra,
        autocorrelation and scale-dependent slopes of the steady face from
        that library.

        Returns
        -------
        SurfaceTopography.Topography

        Raises
        ------
        ModuleNotFoundError
            SurfaceTopography is not installed.
        """
        return to_topography(self.face, self.pixel_size)


def solve(problem, *, geometry=None, face_only=False):
    """Limiting worn face of a multi-phase punch (eq. 7, 9) and its rms slope with an error bar.

    Parameters
    ----------
    problem : steady.problem.Problem
        The phase map on the face's grid, the wear law, the load and ``E*``.
    geometry : phase geometry, optional
        The continuous geometry (:mod:`steady.phases`; a scene's
        ``scene.geometry``) whose rasterisation at ``problem.n`` is the
        problem's phase map.  The error bar then compares the geometry
        rasterised at ``n/2`` and ``n/4``
        (:func:`steady.rms_slope.estimate_rms_slope`); without it, the map
        itself resampled (:func:`steady.rms_slope.estimate_map_rms_slope`).
    face_only : bool, optional
        Skip the rms slope estimate, for callers that want the face alone:
        ``rms_slope`` and ``rms_slope_error`` are then NaN (default False).

    Returns
    -------
    SteadyResult
        ``rms_slope`` is the energy-corrected estimate
        (:mod:`steady.rms_slope`) with its error bar ``rms_slope_error``;
        the plain pixel value is ``rms_slope_plain``.

    Raises
    ------
    ValueError
        A ``geometry`` that does not rasterise to the problem's map, or a
        non-finite result.

    Notes
    -----
    One forward transform of the pressure feeds the three products (face
    and two slope components), so the face costs one forward and three
    inverse transforms; the corrected rms slope and its error bar add the
    slope energy (:class:`steady.rms_slope.SlopeEnergy`) on ``n``, ``n/2``
    and ``n/4``, several times that.

    Examples
    --------
    A biphasic Voronoi punch whose phase 1 wears ten times faster: by eq. 7
    its pressure is ten times lower.

    >>> from steady import Circle, FacePhases, Problem, Voronoi, solve
    >>> grid = Circle(4e-3).grid(64)
    >>> phases = FacePhases(grid, Voronoi(100, (0.5, 0.5), seed=2024).labels(grid), 2)
    >>> result = solve(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6))
    >>> print(f"{result.phase_pressures[0] / result.phase_pressures[1]:.6f}")
    10.000000
    >>> result.face.shape, result.n_phases
    ((64, 64), 2)
    >>> print(f"{result.normalised_rms_slope:.3f} "
    ...       f"+- {result.rms_slope_error / result.reference_slope:.3f} grad_f0, "
    ...       f"plain pixel value {result.normalised_rms_slope_plain:.3f}")
    1.489 +- 0.004 grad_f0, plain pixel value 1.326
    """
    if not isinstance(problem, Problem):
        raise ValueError(f"solve takes a steady.problem.Problem, got {type(problem).__name__}")
    if problem.phases.columns is not None:
        geometry = None  # the section is the map; a 3-d geometry's labels are the surface's
        _log_section(problem)
    if geometry is not None and not face_only:
        labels = geometry.labels(problem.grid)
        if not np.array_equal(labels, problem.labels):
            raise ValueError(f"the geometry {type(geometry).__name__} rasterised at n = "
                             f"{problem.n} is not the problem's phase map "
                             f"({int(np.sum(labels != problem.labels))} pixels differ)")
    return _solve(problem, geometry, face_only)


def _solve(problem, geometry, face_only, estimate=None):
    """:func:`solve` of a problem whose map is ``geometry``'s at ``problem.n`` (or None).

    ``estimate``: the ladder of ``geometry`` (:func:`estimate_rms_slope`), if
    the caller has it; used only with ``geometry``.
    """
    result = _limiting_face(problem)
    if face_only:
        return dataclasses.replace(result, rms_slope=math.nan)
    if geometry is None:
        labels, wear = problem.present_phases()
        estimate = estimate_map_rms_slope(labels, wear, problem.normal_force,
                                          problem.outline, problem.E_star,
                                          sliding=problem.sliding)
    elif estimate is None:
        estimate = estimate_rms_slope(geometry, problem.wear, problem.normal_force,
                                      problem.outline, problem.E_star, problem.n,
                                      sliding=problem.sliding, labels=problem.labels)
    logger.debug("steady %s rms slope %.6g +- %.2g (grids %s), plain %.6g", problem.shape,
                 estimate.rms_slope, estimate.error, estimate.grids, result.rms_slope_plain)
    rms_slope, error = estimate.rms_slope, estimate.error
    if problem.counterbody.layered and problem.outline.periodic:
        # A cell's integrals on its own operator are the layer's, exactly; the
        # ladder's error (the map's rasterisation) stays the bar.
        energy = slope_energy_of(problem.grid, problem.E_star, operator=problem.halfspace)
        rms_slope = float(energy(result.pressure, problem.face_mask).rms_slope)
    elif problem.counterbody.layered:
        rms_slope = _layer_rms_slope(problem, result, rms_slope)
        # The half-space's correction holds where the layer's kernel is 1/r, within
        # about its thickness of a phase boundary: on layers of a few pixels the rest of
        # the gap to the plain value is an error (docs/model.md, measured there).
        share = min(1.0, 2.0 * problem.grid.h / problem.counterbody.thickness)
        error = error + abs(rms_slope - result.rms_slope_plain) * share
    return dataclasses.replace(result, rms_slope=rms_slope, rms_slope_error=error)


def _layer_rms_slope(problem, result, halfspace_rms_slope):
    """The corrected rms slope on a layer: the half-space's plus the layer's change.

    The estimators correct the half-space's ``1/r`` kernel, whose pixel error
    dominates near phase boundaries, where the layer's kernel is ``1/r`` too;
    the layer's correction is smooth, and its change of the mean square
    slope is taken at the pixels: ``rms^2 = rms_hs^2 + plain^2 - plain_hs^2``
    (docs/model.md, "Counter-body of finite thickness").
    """
    halfspace = Counterbody(problem.E_star).operator(problem.grid)  # the half-space's
    gx, gy = halfspace.gradient(result.pressure)
    on_face = problem.face_mask
    plain_hs2 = np.sum(gx * gx + gy * gy, where=on_face) / np.count_nonzero(on_face)
    square = halfspace_rms_slope ** 2 + result.rms_slope_plain ** 2 - plain_hs2
    return math.sqrt(max(square, 0.0))


def _log_section(problem):
    """Say which section of a depth-varying problem is solved: its quasi-steady face."""
    if not problem.phases.depth_varying:
        return
    depth = problem.phases.depth
    where = (f"the section at depth {depth:.6g} m" if np.ndim(depth) == 0 and depth > 0
             else "the surface section" if np.ndim(depth) == 0
             else "the section at the given depth map")
    logger.info("the phase map changes with depth: solving the quasi-steady face of %s", where)


def _limiting_face(problem):
    """The fields of the steady state (eq. 7, 9) and the plain pixel rms slope."""
    # The problem's operator if it has one; else one that is freed on return,
    # before the slope estimator's arrays are allocated (steady.memory.steady_memory).
    halfspace = problem.__dict__.get("halfspace")
    if halfspace is None:
        halfspace = problem.counterbody.operator(problem.grid)
    on_face = problem.face_mask
    counts = problem.phases.counts
    p_phase = problem.phase_pressures()
    pressure = problem.steady_pressure()

    pressure_q = halfspace.forward(pressure)
    face = halfspace.displacement_q(pressure_q)
    gx, gy = halfspace.gradient(pressure, pressure_q=pressure_q)
    slope2 = gx * gx
    slope2 += gy * gy
    plain = math.sqrt(np.sum(slope2, where=on_face) / counts.sum())
    # A periodic face has no tilt to level: its mean alone is arbitrary.
    height = rms_height(face, on_face, halfspace.h, plane=not problem.outline.periodic)
    off = ~on_face
    face[off] = np.nan
    slope = np.sqrt(slope2, out=slope2)
    slope[off] = np.nan
    if not math.isfinite(plain):
        raise ValueError(f"steady solve produced a non-finite rms slope ({plain}); "
                         f"phase pressures {p_phase.tolist()} Pa")
    ref = reference_slope(problem.outline, problem.normal_force, problem.E_star)
    return SteadyResult(
        labels=np.array(problem.labels),
        pressure=pressure,
        phase_pressures=p_phase,
        face=face,
        slope=slope,
        rms_slope=math.nan,
        reference_slope=ref.value,
        fill_factors=counts / counts.sum(),
        wear=problem.wear,
        normal_force=problem.normal_force,
        E_star=problem.E_star,
        outline=problem.outline,
        rms_slope_plain=plain,
        rms_height=height,
        reference_slope_error=ref.error,
        reference_slope_source=ref.source,
        thickness=problem.thickness,
        poisson=problem.poisson,
    )


def solve_scene(scene, *, n=None, face_only=False, problem=None, estimate=None):
    """Solve the steady state of a :class:`steady.scene.Scene`: :func:`solve` of its problem.

    Parameters
    ----------
    scene : Scene
    n : int, optional
        Grid size, pixels along the longer side; default ``scene.n``.  The
        geometry is rasterised at this size, and at ``n/2`` and ``n/4`` for
        the error bar of the rms slope.
    face_only : bool, optional
        Skip the rms slope estimate (``rms_slope`` and its error NaN),
        default False.
    problem : steady.problem.Problem, optional
        ``problem_of(scene, n=n)``, if the caller has built it (a
        command that checks the scene's map before the solve): the map is
        then not rasterised again.  Default: built here.
    estimate : steady.rms_slope.SlopeEstimate, optional
        ``estimate_rms_slope(scene.geometry, problem.wear,
        problem.normal_force, problem.outline, problem.E_star, n,
        sliding=problem.sliding)``, if the caller has computed it: the
        ladder (the bulk of the cost) is then not computed again.  Not
        checked; ignored for a depth-varying scene (its map has no
        geometry ladder).  Default: computed here.

    Returns
    -------
    SteadyResult

    Raises
    ------
    ValueError
        A ``problem`` whose grid is not the scene's at ``n``.

    Warns
    -----
    steady.validity.ValidityWarning
        The face's rms slope (the plain pixel value with ``face_only``)
        beyond :data:`steady.validity.SLOPE_LIMIT`: the scene lies outside
        the range of the linear half-space.

    Examples
    --------
    The homogeneous epoxy cylinder of the paper's Fig. 6 on a coarse grid:
    the corrected rms slope is ``grad_f0`` (eq. 10, 12) within its error
    bar, the plain pixel value 3.5 % low.

    >>> from steady import examples, load_scene, solve_scene
    >>> scene = load_scene(examples.path("epoxy_cylinder"))
    >>> result = solve_scene(scene, n=64)
    >>> print(f"{result.normalised_rms_slope:.3f} "
    ...       f"+- {result.rms_slope_error / result.reference_slope:.3f} grad_f0, "
    ...       f"plain {result.normalised_rms_slope_plain:.3f}")
    0.997 +- 0.012 grad_f0, plain 0.965
    """
    # The problem's map is the geometry's at n by construction: no need to check it.
    if problem is None:
        problem = problem_of(scene, n=n)
    elif problem.shape != scene.grid(n).shape:
        raise ValueError(f"the problem's grid {problem.shape[0]} x {problem.shape[1]} is not "
                         f"the scene's at n = {scene.n if n is None else n}")
    geometry = scene.geometry
    if problem.phases.columns is not None:
        geometry = None  # a depth-varying scene: the section is the map
        _log_section(problem)
    result = _solve(problem, geometry, face_only, estimate)
    where = "the scene" if scene.source_path is None else str(scene.source_path)
    check_rms_slope(result.rms_slope if math.isfinite(result.rms_slope)
                    else result.rms_slope_plain, f"the steady face of {where}")
    return result
