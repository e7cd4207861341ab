"""The friction proxy along the run-in: the worn face's rms slope, its error bar, its rms height.

The run loop (:mod:`transient.runin`) records at every accepted step what a
:class:`FaceEstimator` measures of the face (docs/model.md, "The run-in
history"):

``rms_slope``
    The continuum rms slope of the worn face ``f = d - w`` over the face.
    In contact ``f = K p`` up to a constant, so its mean-square slope is that
    of the half-space surface under the run's pressure, which the
    energy-corrected estimator of :mod:`steady.rms_slope` gives (the same as
    the steady module's ``rms_slope``).  Off the contact (partial contact)
    the pixel quadrature of ``|grad f|^2 - |grad K p|^2``, ``f`` by finite
    differences (it is smooth there), is added.  At ``s = 0`` the value is
    the initial face's own (:func:`face_statistics`: exact for a flat or a
    tilted face).
``rms_slope_error``
    Its estimated discretisation error: the uncertainty of the rim-layer
    correction (below) and the estimator's error on the run's own phase map
    (:func:`steady.rms_slope.estimate_map_rms_slope`, relative, carried along
    the history), added in quadrature.  Never NaN: where the map's error
    cannot be estimated it is infinite, which the comparison with the
    steady face reports as "no error bar".
``rms_height``
    Rms of ``f`` over the face after removing its least-squares plane
    (:mod:`steady.relief`).

The rim layer
-------------
A flat face starts with the ``(a^2 - r^2)^(-1/2)`` rim pressure.  For any
``s > 0`` the wear has flattened it in a layer of width ``l = k E* s``
along the rim, with slopes of order ``K / (E* l^(1/2))`` (``K`` the rim's
stress intensity): a mean-square slope per unit rim length of order
``K^2 / E*^2``, whatever ``l``.  (Another initial face in contact at the
rim has the same singularity with another ``K``: each rim pixel's excess
below is weighted by the square of its initial pressure over the flat
punch's.)  The continuum history therefore jumps at
``s = 0`` from the flat face's 0 to about ``0.848 grad_f0``
(:mod:`transient.axisymmetric`).  Where ``l`` is not much wider than a
pixel, the corrected estimator over-estimates the mean-square slope by an
amount that depends only on the resolution ``rho = l / h``:
:func:`rim_layer_excess`, fitted to the homogeneous cylinder's run-in on
n = 64 ... 512 against the axisymmetric reference.  For Archard's law
(``m = 1``) the excess of every rim pixel (its own phase's ``rho``) is
subtracted, and :data:`RIM_LAYER_SCATTER` of it enters the error bar; for
``m != 1`` nothing is subtracted and the whole excess is the error bar.

Faces of other outlines (:mod:`steady.outline`) get the same correction in
units of their own ``grad_f0`` (the homogeneous face's rms slope,
:func:`steady.normalisation.reference_slope`).  The fit was made on the
disk; the edges of a flat rectangle or annulus carry the same inverse
square-root singularity, a rectangle's corners a stronger one (the corner
pixel's pressure grows as ``h^-0.69`` under refinement, an edge's as
``h^-0.49``), which the fit does not know.  Measured on homogeneous faces
from flat, n = 48, 96, 192, at ``s = 1e-4 .. 3 s*``: the corrected values
of a 1:2 rectangle on consecutive grids differ by up to 0.014 ``grad_f0``
(a 1:2 annulus 0.009, the disk 0.010), within the sum of their error bars
(``tests/test_transient_outlines.py``).

Interior phase boundaries wear into steps that are smoothed over a layer of
width ``k E* s`` of the faster phase; while that layer is narrower than a
few pixels (``s`` below about ten fastest relaxation distances
``h / (k_max E*)``) the estimate is low.  The per-step error bar does not
include this; the companion run on a coarser grid
(:mod:`transient.spatial_error`) measures part of it.
"""

from __future__ import annotations

import dataclasses
import math
import weakref

import numpy as np

from steady.problem import FacePhases
from steady.relief import PlaneFit, rms_height
from steady.rms_slope import estimate_map_rms_slope, estimate_rms_slope, slope_energy_of

from .contact import solve_contact
from .diagnostics import face_rms_slope, masked_gradient

__all__ = [
    "RIM_LAYER_FIT",
    "RIM_LAYER_SCATTER",
    "SOURCE_CONTACT",
    "SOURCE_INITIAL",
    "SOURCE_PARTIAL_CONTACT",
    "FaceStatistics",
    "FaceEstimator",
    "face_statistics",
    "rim_layer_excess",
]

#: ``(G0, b, c)`` of the rim-layer excess ``G0 / (1 + b rho + c rho^2)``,
#: grad_f0^2: a least-squares fit (in the logarithm) to the excess of the
#: corrected estimator's mean-square slope over the axisymmetric reference,
#: homogeneous cylinder from flat, n = 64, 128, 256, 512,
#: ``s = 1e-3 .. 0.03 s*`` (16 points, rho = 0.03 .. 7.7; residuals within
#: 8 %).  Its large-rho end, ``G0 / c rho^2 = 0.132 / rho^2``, is the
#: second-order quadrature error of a resolved layer.  The 33 points of
#: ``studies/runin_convergence.py`` refit to (0.368, 0.609, 2.75).
RIM_LAYER_FIT = (0.371, 0.627, 2.81)

#: Relative uncertainty of :func:`rim_layer_excess` carried into the error bar:
#: its residuals on the 33 points of ``studies/runin_convergence.py`` are within
#: 12 % for rho <= 4 (beyond, the excess is below 0.5 % of the mean square).
RIM_LAYER_SCATTER = 0.15

#: ``rms_slope_source``: the initial face's own value (``s = 0``).
SOURCE_INITIAL = 0
#: ``rms_slope_source``: corrected estimate, the face in full contact.
SOURCE_CONTACT = 1
#: ``rms_slope_source``: corrected estimate plus differences off the contact.
SOURCE_PARTIAL_CONTACT = 2


def rim_layer_excess(rho):
    """Excess of the corrected mean-square slope from an unresolved rim layer.

    Parameters
    ----------
    rho : array_like
        Width ``k E* s / h`` of the worn rim layer in pixels (``k`` the
        rim phase's rate constant, ``s`` the distance slid).

    Returns
    -------
    ndarray
        ``G0 / (1 + b rho + c rho^2)`` (:data:`RIM_LAYER_FIT`), in units of
        ``grad_f0^2``, for the flat punch's rim stress intensity.

    Examples
    --------
    >>> print(f"{rim_layer_excess(0.0):.3f} {rim_layer_excess(10.0):.5f}")
    0.371 0.00128
    """
    g0, b, c = RIM_LAYER_FIT
    rho = np.asarray(rho, dtype=float)
    return g0 / (1.0 + b * rho + c * rho * rho)


@dataclasses.dataclass(frozen=True)
class FaceStatistics:
    """Rms slope and rms height of a smooth face from its pixel recessions.

    Attributes
    ----------
    rms_slope : float
        Rms over the face pixels of the finite-difference slope.
    rms_slope_error : float
        ``|S_h - S_2h|``, the same on every other pixel with differences
        over ``2h``: zero for a plane, whose differences are exact.
    rms_height : float, m
        Rms of the recession about its least-squares plane
        (:func:`steady.relief.rms_height`).
    """

    rms_slope: float
    rms_slope_error: float
    rms_height: float


def _difference_rms_slope(face, face_mask, h, *, periodic=False, stride=1):
    gx, gy = masked_gradient(np.where(face_mask, face, 0.0), face_mask, h, periodic=periodic,
                             stride=stride)
    return float(np.sqrt(np.mean((gx * gx + gy * gy)[face_mask])))


def face_statistics(face, face_mask, h, *, periodic=False):
    """Rms slope (finite differences) and rms height of a smooth face over the face pixels.

    For the initial faces of :mod:`transient.initial_face`: exact for a
    flat or tilted face (differences of a plane are exact, its residual
    plane is zero); second order in ``h`` inside a smooth face, with the
    staircase rim's first-order share.

    Parameters
    ----------
    face : ndarray, shape (nx, ny), m
        Heights at the pixel centres (either sign convention).
    face_mask : ndarray of bool, shape (nx, ny)
    h : float, m
    periodic : bool, optional
        Whether the face is a periodic cell's (the outline's ``periodic``,
        default False): its differences then wrap around the cell's edges,
        ``S_2h`` is taken over ``2h`` at every pixel (every other pixel would
        not tile a side of an odd number of pixels, and would depend on
        where the cell's origin lies), and the rms height is about the mean
        (a periodic face has no tilt to level) instead of the least-squares
        plane.

    Returns
    -------
    FaceStatistics

    Examples
    --------
    >>> from steady.outline import Circle
    >>> from transient.initial_face import tilted
    >>> grid = Circle(4e-3).grid(33)
    >>> stats = face_statistics(tilted(grid, 0.01), grid.mask, grid.h)
    >>> print(f"{stats.rms_slope:.6f} {stats.rms_slope_error:.1e} {stats.rms_height:.1e}")
    0.010000 0.0e+00 0.0e+00
    """
    face = np.asarray(face, dtype=float)
    slope = _difference_rms_slope(face, face_mask, h, periodic=periodic)
    if periodic:
        coarse = _difference_rms_slope(face, face_mask, h, periodic=True, stride=2)
    else:
        coarse = _difference_rms_slope(face[::2, ::2], face_mask[::2, ::2], 2 * h)
    # A plane's differences are exact on both: round-off is not an error.
    error = abs(slope - coarse)
    if error <= 1e-12 * max(slope, coarse):
        error = 0.0
    return FaceStatistics(rms_slope=slope, rms_slope_error=error,
                          rms_height=rms_height(face, face_mask, h, plane=not periodic))


# The estimator of each live problem (FaceEstimator.of), with its initial face.
_ESTIMATORS = weakref.WeakKeyDictionary()


class FaceEstimator:
    """What the history records of the worn face at every step (see module notes).

    Built once per run: the corrected estimator of the grid, the rim pixels
    and their rate constants, the initial face's own figures and the
    estimator's error on the run's phase map.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    initial_recession : ndarray, shape (nx, ny), m
        Initial face (larger = recessed), as given to
        :func:`transient.runin.run_in`.
    precision : {"single", "double"}, optional
        Precision of the transforms of :meth:`figures`' corrected estimate
        (:class:`steady.rms_slope.SlopeEnergy`, default "single": half the
        time; over the shipped Voronoi run-in at n = 1024 the history's rms
        slope moved by at most 2.9e-7 of itself, 1.9e-4 of its error bar).
        The map's error and :attr:`energy` are double precision either way.
    contact_rtol : float, optional
        Relative tolerance of the contact solves that weigh the rim layer of
        a face that is not flat (default 1e-10; a run passes its options').

    Attributes
    ----------
    energy : steady.rms_slope.SlopeEnergy
        The corrected estimator of the grid, double precision (the map's
        ladder, the steady comparison's).
    reference_slope : float
        ``grad_f0``, the rms slope of the outline's homogeneous face
        (``4 pbar / (pi E*)``, ``pbar = F / (pi a^2)`` for a disk, eq. 12;
        :attr:`transient.problem.WearProblem.reference`).
    initial : FaceStatistics
        Of the initial face (:func:`face_statistics`).
    map_error : float
        Relative error of the corrected estimator on the run's phase map at
        the steady state: with the scene's phase geometry
        (``problem.geometry``) the ladder of the geometry rasterised on
        coarser grids (:func:`steady.rms_slope.estimate_rms_slope`, the
        error bar of ``runin-steady``); for a bare label map the ladder of
        the map resampled (:func:`steady.rms_slope.estimate_map_rms_slope`:
        from coarser grids, or from the map refined where a phase vanishes
        on every coarser one), which also measures the resampling's half
        pixel and is larger; infinite where no error can be estimated,
        and then the history's ``rms_slope_error`` is infinite too (no
        bound: never NaN).
    geometry_estimate : steady.rms_slope.SlopeEstimate or None
        The ladder of the scene's phase geometry behind ``map_error``
        (under uniform sliding), which :func:`steady.solution.solve_scene`
        may take instead of computing it again; None for a bare label map.

    Examples
    --------
    >>> import numpy as np
    >>> from transient.problem import WearProblem
    >>> from steady import examples
    >>> from transient.scene import load_transient_scene, wear_problem_of
    >>> scene, _, _ = load_transient_scene(examples.path("voronoi_transient"))
    >>> problem = wear_problem_of(scene, n=40)
    >>> estimator = FaceEstimator(problem, np.zeros((40, 40)))
    >>> from transient.solver import StageSolver
    >>> res = StageSolver(problem).contact(np.zeros((40, 40)))
    >>> fig = estimator.figures(0.0, np.zeros((40, 40)), res.pressure, res.approach)
    >>> fig["rms_slope"], fig["rms_slope_error"], fig["rms_height"]
    (0.0, 0.0, 0.0)
    """

    @classmethod
    def of(cls, problem, initial_recession, **options):
        """The estimator of ``problem`` from ``initial_recession``, built once and then reused.

        The run (:func:`transient.runin.run_in`) and the comparison of its
        end with the steady face (:func:`transient.comparison.compare_with_steady`)
        share it: on a 1024^2 grid building one takes over a second.  Kept
        while the problem lives, for the last initial face asked for (the
        ``options`` of the constructor apply when it is built).  Not to be
        applied from two threads at once.
        """
        h0 = np.where(problem.face_mask, np.asarray(initial_recession, dtype=float), 0.0)
        kept = _ESTIMATORS.get(problem)
        if kept is not None and np.array_equal(kept[0], h0):
            return kept[1]
        estimator = cls(problem, h0, **options)
        _ESTIMATORS[problem] = (h0, estimator)
        return estimator

    def __init__(self, problem, initial_recession, *, precision="single", contact_rtol=1e-10):
        hs = problem.halfspace
        self.problem = problem
        self.contact_rtol = float(contact_rtol)
        self.face_mask = problem.face_mask
        self.h = hs.h
        self.energy = slope_energy_of(problem.grid, hs.E_star, operator=hs)
        # The map's ladder and the steady comparison keep the double-precision
        # estimator; the figures of every step share its spectra.
        self._step_energy = self.energy.in_precision(precision)
        self._own_halfspace = None
        self._threaded = False
        self._plane = PlaneFit(self.face_mask, hs.h, plane=not problem.outline.periodic)
        self.reference_slope = problem.reference_slope
        h0 = np.where(self.face_mask, np.asarray(initial_recession, dtype=float), 0.0)
        self.initial = face_statistics(-h0, self.face_mask, hs.h,
                                       periodic=problem.outline.periodic)
        padded = np.pad(self.face_mask, 1)
        interior = (padded[2:, 1:-1] & padded[:-2, 1:-1] & padded[1:-1, 2:]
                    & padded[1:-1, :-2])
        # A periodic cell has no rim: no worn layer to correct, none in the error bar.
        self.rim = self.face_mask & ~interior & (not problem.outline.periodic)
        rate = problem.wear.rate_constant(problem.wear_field[self.rim],
                                          problem.pixel_mean_pressure)
        # Layer width per unit sliding distance, in pixels.
        self._rim_growth = rate * hs.E_star / hs.h
        self._rim_weight = self._rim_weights(h0)
        geometry = problem.geometry
        self.geometry_estimate = None
        if geometry is not None and problem.columns is None:
            # The ladder of the geometry rasterised on coarser grids, as the steady
            # command's error bar (steady.solution.solve_scene): one bar for one value.
            estimate = self.geometry_estimate = estimate_rms_slope(
                geometry, problem.wear, problem.normal_force, problem.outline, hs.E_star,
                problem.n, labels=problem.labels, energy=self.energy)
            self.map_error = _relative_error(estimate)
        else:
            self.map_error = _sections_map_error(problem.problem, hs.E_star, self.energy)

    def _rim_weights(self, h0):
        """Squared rim stress intensity of each rim pixel relative to the flat punch's.

        1 for a flat face.  Otherwise the ratio of the initial contact
        pressure to the flat punch's on each rim pixel, squared: 0 where the
        rim is out of contact at ``s = 0`` (no layer is worn there from the
        start; if the contact reaches it later, the layer that forms there is
        neither corrected nor in the per-step error bar).
        """
        f_star = self.problem.depth_scale
        if np.ptp(h0[self.face_mask]) <= 1e-12 * f_star:
            return np.ones(int(self.rim.sum()))
        p = self.problem
        flat = solve_contact(p.halfspace, self.face_mask, np.zeros_like(h0), p.normal_force,
                             rtol=self.contact_rtol).pressure[self.rim]
        start = solve_contact(p.halfspace, self.face_mask, h0, p.normal_force,
                              rtol=self.contact_rtol).pressure[self.rim]
        return (start / flat) ** 2

    @property
    def workers(self):
        """Threads of its transforms (:mod:`scipy.fft`'s ``workers``); may be reset.

        :func:`transient.runin.run_in` sets 1 while the figures run on their
        own thread beside the solver's transforms, so that the two do not
        ask for more threads than the machine has cores.
        """
        return self.energy.workers

    @workers.setter
    def workers(self, value):
        self.energy.workers = value
        if self._own_halfspace is not None:
            self._own_halfspace.workers = value

    @property
    def threaded(self):
        """Whether :meth:`figures` runs beside the contact solves, on another thread.

        Then it uses a half-space operator of its own, whose work buffers
        the run's solver does not share (built on first use: a run in full
        contact never needs it); else the problem's (default False).
        Setting it False frees the estimator's own.
        """
        return self._threaded

    @threaded.setter
    def threaded(self, value):
        self._threaded = bool(value)
        if not self._threaded:
            self._own_halfspace = None

    def _halfspace(self):
        """The half-space operator :meth:`figures` applies (see :attr:`threaded`)."""
        if not self._threaded:
            return self.problem.halfspace
        if self._own_halfspace is None:
            # The problem's operator with work buffers of its own: the spectra
            # (read-only) are shared, the buffers every product writes are not.
            self._own_halfspace = self.problem.halfspace.with_own_buffers(workers=self.workers)
        return self._own_halfspace

    def rim_layer_pixels(self, distance):
        """Width ``k E* s / h`` of the slowest-wearing rim phase's worn layer, pixels.

        0 on a face without a rim (a periodic cell).
        """
        if not self._rim_growth.size:
            return 0.0
        return float(np.min(self._rim_growth)) * distance

    def figures(self, distance, recession, pressure, approach, *, rim_layers=None):
        """The history's figures of the face at one point of the run.

        Parameters
        ----------
        distance : float, m
            Sliding distance; at 0 the slope figures are the initial face's.
        recession : ndarray, shape (nx, ny), m
            Face recession (larger = recessed), any constant offset.
        pressure : ndarray, shape (nx, ny), Pa
            Contact pressure of ``recession``.
        approach : float, m
            Rigid approach in the frame of ``recession``.
        rim_layers : sequence of (float, float), optional
            Under a load programme, one rim layer per rise of the force: the
            distance (m) slid since the rise and its weight ``(dF / F_N)^2``
            (the rise's share of the rim stress intensity, squared); default
            one layer of ``distance`` and weight 1.

        Returns
        -------
        dict
            ``rms_slope``, ``rms_slope_error``, ``rms_slope_source``,
            ``rms_slope_plain``, ``rim_layer_pixels`` and ``rms_height`` (m).
        """
        face_mask = self.face_mask
        hs = self._halfspace()
        recession = np.where(face_mask, recession, 0.0)
        face = np.where(face_mask, approach - recession, 0.0)
        pressure = np.where(face_mask, pressure, 0.0)
        integrals = self._step_energy(pressure, face_mask)
        off = face_mask & ~(pressure > 0)
        # In partial contact the plain value and the correction off the contact
        # share the exact-kernel gradient of K p; in full contact the plain
        # value is the estimator's own face sum.
        # A cell's integrals are the layer's own (its operator's modes); a finite
        # face's estimator corrects the half-space's kernel, and takes the layer's change.
        periodic = self.problem.problem.outline.periodic
        layered = self.problem.problem.counterbody.layered and not periodic
        gradient = hs.gradient(pressure) if off.any() or layered else None
        plain = (face_rms_slope(hs, face_mask, recession, pressure, approach, gradient=gradient,
                                periodic=periodic)
                 if off.any() or layered
                 else math.sqrt(integrals.face_sum / integrals.face_area))
        out = {"rms_slope_plain": plain, "rim_layer_pixels": self.rim_layer_pixels(distance),
               "rms_height": self._plane(face)}
        if distance == 0:
            out.update(rms_slope=self.initial.rms_slope,
                       rms_slope_error=self.initial.rms_slope_error,
                       rms_slope_source=SOURCE_INITIAL)
            return out
        energy = float(integrals.corrected)
        if layered:
            # The estimator corrects the half-space's kernel; the layer's smooth
            # correction changes the energy by its pixel sum (steady.solution, on a layer).
            gx, gy = gradient
            energy += (float(np.sum((gx * gx + gy * gy)[face_mask])) * self.h ** 2
                       - float(integrals.face_sum))
        source = SOURCE_CONTACT
        if off.any():
            gx, gy = gradient
            fx, fy = masked_gradient(face, face_mask, self.h, periodic=periodic)
            energy += float(np.sum((fx * fx + fy * fy - gx * gx - gy * gy)[off])) * self.h ** 2
            source = SOURCE_PARTIAL_CONTACT
        mean_square = energy / integrals.face_area
        if rim_layers is None:
            layers = rim_layer_excess(self._rim_growth * distance)
        else:
            layers = sum(w * rim_layer_excess(self._rim_growth * d) for d, w in rim_layers)
        excess = (self.reference_slope ** 2 * float(np.mean(self._rim_weight * layers))
                  if self._rim_weight.size else 0.0)
        if self.problem.wear.linear:
            slope = math.sqrt(max(mean_square - excess, 0.0))
            spread = RIM_LAYER_SCATTER * excess
            rim_error = max(abs(math.sqrt(max(mean_square - excess + sign * spread, 0.0)) - slope)
                            for sign in (-1.0, 1.0))
        else:
            slope = math.sqrt(max(mean_square, 0.0))
            rim_error = slope - math.sqrt(max(mean_square - excess, 0.0))
        # An infinite map error is no bound, also on a zero slope (inf * 0 is NaN).
        map_part = self.map_error * slope if math.isfinite(self.map_error) else math.inf
        out.update(rms_slope=slope, rms_slope_error=math.hypot(rim_error, map_part),
                   rms_slope_source=source)
        return out


def _relative_error(estimate):
    """The relative error bar of a :class:`steady.rms_slope.SlopeEstimate`.

    Infinite without a bound; 0 for a flat face known exactly (a homogeneous
    periodic cell: zero slope, zero error), whose slope has nothing to rasterise.
    """
    if not math.isfinite(estimate.error):
        return math.inf
    if estimate.rms_slope > 0:
        return estimate.error / estimate.rms_slope
    return 0.0 if estimate.error == 0 else math.inf


def _sections_map_error(problem, E_star, energy):
    """Relative map error of a depth-varying map: its surface's, and its first mixed section's.

    The surface section's map (the phases on the face) is the ladder's first
    value.  A surface of one phase (a coating, a homogeneous top layer) has
    no phase boundary to rasterise, and its error says nothing of those the
    run wears down to: the first plane section from the top with two phases
    or more is estimated too, and the larger relative error kept.
    """
    def estimate(section):
        labels, wear = section.present_phases()
        return _relative_error(estimate_map_rms_slope(
            labels, wear, section.normal_force, section.outline, E_star, energy=energy))

    error = estimate(problem)
    columns, face = problem.phases.columns, problem.face_mask
    if columns is None or np.count_nonzero(problem.phases.counts) > 1:
        return error
    depths = columns.interfaces[:, face]
    for depth in np.unique(depths[np.isfinite(depths)]):
        # (a depth at an interface is in the segment below it)
        section = problem.section(float(depth))
        if np.count_nonzero(section.phases.counts) > 1:
            return max(error, estimate(section))
    return error


# -- depth-varying microstructure ---------------------------------------------
def crossings(columns, before, after):
    """Face pixels whose segment changed between two worn depths: interfaces crossed.

    Parameters
    ----------
    columns : steady.depth.DepthColumns
    before, after : ndarray, shape (nx, ny), m
        Worn depth below the initial surface at the start and at the end of
        a step (any value off the face).

    Returns
    -------
    int
        Pixels of the face whose segment index (:meth:`DepthColumns.segment_at`)
        differs between the two depths: a pixel that crosses two interfaces
        in one step counts once.

    Examples
    --------
    >>> import numpy as np
    >>> from steady.depth import DepthColumns
    >>> columns = DepthColumns(np.full((1, 2, 2), 1e-6), np.stack(
    ...     [np.ones((2, 2), int), np.zeros((2, 2), int)]), 2)
    >>> crossings(columns, np.zeros((2, 2)), np.array([[0.0, 5e-7], [1e-6, 2e-6]]))
    2
    """
    face = columns.face_mask
    changed = columns.segment_at(np.where(face, before, 0.0)) != columns.segment_at(
        np.where(face, after, 0.0))
    return int(np.count_nonzero(changed & face))


@dataclasses.dataclass(frozen=True)
class Coating:
    """A layer of one phase over the whole face, on something else.

    Attributes
    ----------
    phase : int
        The coating's phase: that of every face pixel's first segment.
    thickness : ndarray, shape (nx, ny), m
        Depth of each face pixel's first interface (0 off the face).
    """

    phase: int
    thickness: np.ndarray

    @classmethod
    def of(cls, columns):
        """The coating of ``columns``, or None when its surface is not one.

        A coating: every face pixel has an interface, its first segment is
        one phase and the segment below it another (at every pixel).
        """
        if columns is None or columns.n_interfaces == 0:
            return None
        face = columns.face_mask
        top = columns.phases[0][face]
        if not (np.all(np.isfinite(columns.interfaces[0][face])) and np.all(top == top[0])
                and np.all(columns.phases[1][face] != top[0])):
            return None
        return cls(int(top[0]), np.where(face, columns.interfaces[0], 0.0))

    def overshoot(self, worn, face_mask):
        """Largest depth worn past the coating, m: positive once worn through anywhere."""
        return float(np.max((worn - self.thickness)[face_mask]))

    def contact_remaining(self, worn, pressure, face_mask):
        """Largest coating left under a contact pixel, m: negative once gone from the contact.

        ``max`` over the pixels in contact (``p > 0``) of the coating's
        thickness minus the worn depth; NaN without a contact pixel.
        """
        contact = face_mask & (pressure > 0)
        if not contact.any():
            return math.nan
        return float(np.max((self.thickness - worn)[contact]))


class DepthRecorder:
    """What the history records of a depth-varying run beyond the columnar figures.

    Built once per run for a problem with columns
    (:class:`steady.depth.DepthColumns`); :meth:`figures` measures the worn
    depth, the section and the interfaces crossed at every recorded point
    (docs/files.md, the history of a depth run), :meth:`quasi_steady` the
    rms slope of the current section's steady face.

    A new section's quasi-steady slope is one slope estimate on the
    section's steady face; a section repeats until a pixel crosses an
    interface and is then read from a cache (the cost of depth runs:
    docs/benchmarks.md, "Runs across interfaces").

    Parameters
    ----------
    problem : transient.problem.WearProblem
    columns : steady.depth.DepthColumns
    estimator : FaceEstimator
        The run's (the quasi-steady face is measured by the same estimator
        as the worn face, at the rim layer fully worn).
    rim : ndarray of bool, shape (nx, ny)
        The rim pixels whose mean worn depth is ``worn_depth_rim``.
    """

    def __init__(self, problem, columns, estimator, rim):
        self.problem = problem
        self.columns = columns
        self.estimator = estimator
        self.rim = rim
        self.face_mask = problem.face_mask
        self.coating = Coating.of(columns)
        self._segment = None
        self._section = None  # (labels bytes, rms slope): sections repeat between crossings

    def figures(self, worn, pressure, previous=None, crossed=None):
        """The depth figures of one recorded point, and the step's interface crossings.

        Parameters
        ----------
        worn : ndarray, shape (nx, ny), m
            Worn depth below the initial surface.
        pressure : ndarray, shape (nx, ny), Pa
        previous : ndarray, shape (nx, ny), m, optional
            Worn depth at the previous point, when the recorder did not see
            it (the first point after a resume); at the run's first point
            nothing has been crossed.
        crossed : int, optional
            The step's crossings as the stepping counted them; default
            those between the previous point's segments and these
            (:func:`crossings`).

        Returns
        -------
        figures : dict
            ``worn_depth_mean``, ``worn_depth_rim``, ``worn_depth_max`` (m),
            ``phase_fraction`` (P,), ``crossings`` and, for a coating,
            ``coating_overshoot`` and ``coating_contact_remaining`` (m).
        labels : ndarray of int, shape (nx, ny)
            The section's phase map.
        """
        face = self.face_mask
        columns = self.columns
        worn = np.where(face, worn, 0.0)
        segment = columns.segment_at(worn)
        if self._segment is None and previous is not None:
            self._segment = columns.segment_at(np.where(face, previous, 0.0))
        if crossed is None:
            crossed = 0 if self._segment is None else int(np.count_nonzero(
                (segment != self._segment) & face))
        self._segment = segment
        labels = np.take_along_axis(columns.phases, segment[None], axis=0)[0]
        counts = np.bincount(labels[face], minlength=columns.n_phases)
        out = {"worn_depth_mean": float(worn[face].mean()),
               # NaN on a face without a rim (a periodic cell).
               "worn_depth_rim": float(worn[self.rim].mean()) if self.rim.any() else math.nan,
               "worn_depth_max": float(worn[face].max()),
               "phase_fraction": counts / counts.sum(), "crossings": crossed}
        if self.coating is not None:
            out["coating_overshoot"] = self.coating.overshoot(worn, face)
            out["coating_contact_remaining"] = self.coating.contact_remaining(
                worn, pressure, face)
        return out, labels

    def section_problem(self, worn, labels):
        """The steady problem of the section at the worn depth ``worn`` (m), phase map ``labels``.

        The run's steady problem with the phases of the section (the run's
        columns at ``worn``): the quasi-steady problem, as
        :meth:`steady.problem.Problem.section` gives it.
        """
        base = self.problem.problem
        phases = FacePhases(base.grid, labels, base.n_phases, base.phase_names,
                            self.problem.columns, worn)
        return dataclasses.replace(base, phases=phases)

    def quasi_steady(self, worn, labels):
        """Rms slope of the steady face of the section ``labels`` (eq. 7, 9): the quasi-steady face.

        ``worn`` (m, shape (nx, ny)) is the worn depth whose section
        ``labels`` is.  Measured by the run's estimator as the steady face
        of the run (:class:`FaceEstimator`, distance infinite); kept for the last
        section, which repeats until a pixel crosses an interface.  NaN
        where the steady side refuses the section.  Runs on the history's
        thread (the estimator's half-space operator).
        """
        key = labels.tobytes()
        if self._section is not None and self._section[0] == key:
            return self._section[1]
        from steady.solution import solve

        try:
            section = self.section_problem(worn, labels)
        except ValueError:  # a section the steady side does not take (a phase absent)
            value = math.nan
        else:
            # The estimator's own operator (this runs beside the contact solves, whose
            # operator's buffers it must not share); the section's face is one product.
            section.__dict__["halfspace"] = self.estimator._halfspace()
            steady = solve(section, face_only=True)
            face_mask = self.face_mask
            value = float(self.estimator.figures(
                math.inf, np.where(face_mask, -steady.face, 0.0),
                np.where(face_mask, steady.pressure, 0.0), 0.0)["rms_slope"])
        self._section = (key, value)
        return value
