"""The discretised wear problem of a run-in: one grid, one phase map, one load.

:class:`WearProblem` holds everything a time integrator needs to advance
``dw/ds = k P(w)^m`` (docs/model.md, "Wear and time integration"): the
half-space operator, the phase map and the wear coefficient of every pixel,
the load, the natural scales of the run-in and the contact solves (plain,
and shifted for implicit stages).  :meth:`WearProblem.from_scene` is the one
way from a scene file to a problem; every caller (command line, studies,
tests) goes through it or through the constructor, which takes a phase
map, never a per-pixel coefficient field built by hand.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from steady.normalisation import reference_slope
from steady.problem import Problem, check_scale, input_names
from steady.solution import solve

from .contact import solve_trusted_contact
from .depth import WorkDepth
from .preconditioners import ScaledShift

__all__ = ["PEAK_RATE_LIMIT", "WarmStart", "StepFailure", "WearProblem", "check_run_in_scales"]

#: Largest wear rate ``g(p)`` (m/m) a run may meet at a pixel that carries the
#: whole load, ``p = F_N / h^2``: the rate, its slope and their products with
#: distances and coefficients are computed at every step, and must not
#: overflow (about 1e308) on the way.
PEAK_RATE_LIMIT = 1e200


# Eigenvalues of the predictor's Gram matrix below this fraction of the
# largest are dropped (the pressures of a run are nearly collinear).
_GRAM_CUTOFF = 1e-12


class StepFailure(RuntimeError):
    """A step could not be completed; the caller retries with a smaller step.

    Raised when the contact solver fails, values turn non-finite or the
    power-law Newton iteration does not converge.
    """


def check_run_in_scales(problem, names=None):
    """Refuse a run-in whose scales leave :data:`steady.problem.SCALE_RANGE`, naming the inputs.

    Beyond the problem's own (:func:`steady.problem.check_scales`, checked
    when it was built), a run-in has its distances: the run-in distance
    ``s* = L / (k_min' E*)`` and the fastest relaxation distance
    ``h / (k_max' E*)`` (``k'`` the law's rate constant at the pixel mean
    pressure, ``k m pbar^(m-1)``), both in range; and the wear rate of a
    pixel that carries the whole load, ``g(F_N / h^2)`` of the fastest
    phase, below :data:`PEAK_RATE_LIMIT` (a large exponent overflows
    ``p^m`` at the rim's pressures long before at ``pbar``).  Computed as
    the run computes them: an overflow is ``inf``, an underflow 0.

    Parameters
    ----------
    problem : steady.problem.Problem
    names : mapping, optional
        How the message names each input (default
        :func:`steady.problem.input_names`; a scene's keys).

    Raises
    ------
    ValueError
        The first scale out of range, with its inputs.
    """
    F, E = problem.normal_force, problem.E_star
    names = (input_names(problem.outline, F, E, problem.n, problem.wear) if names is None
             else names)
    h = problem.grid.h
    wear = problem.wear
    phases = wear.coefficient_field(np.arange(wear.n_phases))
    mean = F / (float(problem.face_mask.sum()) * h * h)
    with np.errstate(all="ignore"):
        # In numpy's floats: an underflow to 0 divides to inf rather than raising.
        constants = np.asarray(wear.rate_constant(phases, np.float64(mean)), dtype=float)
        slow, fast = np.float64(constants.min()), np.float64(constants.max())
        peak = float(np.max(wear.rate(np.full(wear.n_phases, F / (h * h)), phases)))
        s_star = float(problem.outline.scale / (slow * E))
        fastest = float(h / (fast * E))
    inputs = ("wear", "normal_force", "outline", "E_star")
    check_scale(s_star, "the run-in distance s* = L / (k m pbar^(m-1) E*) of the slowest "
                "phase", "m", inputs, names)
    check_scale(fastest, "the fastest relaxation distance h / (k m pbar^(m-1) E*)", "m",
                (*inputs, "n"), names)
    if not peak < PEAK_RATE_LIMIT:  # NaN is not
        given = " and ".join(names[key] for key in ("wear", "normal_force", "outline", "n"))
        raise ValueError(f"{given}: the wear rate of a pixel carrying the whole load, "
                         f"g(F_N / h^2) of the fastest phase, is {peak:.3g}, above "
                         f"{PEAK_RATE_LIMIT:g}: the run's rates would overflow (a smaller "
                         f"exponent, or a coarser grid)")


class WearProblem:
    """The discretised wear system ``dw/ds = k P(w)^m`` on one grid.

    Parameters
    ----------
    problem : steady.problem.Problem
        The phase map on the face's grid, the wear law, the load and ``E*``
        (checked there); its half-space operator is the one of the run.
    contact_rtol : float, optional
        Relative tolerance of every contact solve (default 1e-10);
        :func:`transient.runin.run_in` sets it to its options'
        ``contact_rtol``.
    contact_maxiter : int, optional
        Iteration cap of every contact solve (default: the solver's).
    newton_rtol : float, optional
        Stop the power-law Newton iteration when the pressure changes by less
        than this times the mean pressure (default 1e-9).  Unused for m = 1.
    newton_maxiter : int, optional
        Newton iteration cap (default 30).
    pressure_floor : float, optional
        Floor of the linearisation pressure for ``m < 1``, in units of the mean
        pressure (default 1e-6).

    Attributes
    ----------
    problem : steady.problem.Problem
    wear : wear law
        The problem's (:mod:`steady.wear`): the rate, its linearisation and
        the steady pressures all come from it.
    outline : outline object
        The face's outline.
    grid : steady.outline.FaceGrid
        Its grid: ``shape``, ``n``, ``h``, pixel centres.
    shape : (int, int)
        ``(nx, ny)``.
    n : int
        Pixels along the longer side of the grid (across the diameter of a
        disk).
    scale : float, m
        ``L``, the outline's length scale (the radius of a disk).
    face_mask : ndarray of bool, shape (nx, ny)
        Pixels of the punch face (``labels >= 0``).
    coefficient_field : ndarray, shape (nx, ny), 1/Pa
        The wear law's coefficient of each pixel, zero off the face.
    solves : int
        Contact solves done so far (counter, for work accounting).
    iterations : int
        Contact-solver iterations done so far.
    columns : steady.depth.DepthColumns or None
        The phases below the face (``problem.phases.columns``); None for a
        columnar problem.  With interfaces the wear law must be a power law.
    work_depth : transient.depth.WorkDepth or None
        Its wear-work map, None unless ``columns`` has an interface: the run
        then integrates the wear work (docs/model.md, "Wear across
        interfaces") and ``coefficient_field`` is that of the current
        section (:meth:`at_depth`).
    stage_solves, most_stage_solves : int
        Newton iterations (contact solves) of the stages across interfaces:
        their sum and the most in one stage.

    Examples
    --------
    >>> from steady import Circle, FacePhases, Problem, Voronoi
    >>> grid = Circle(4e-3).grid(32)
    >>> phases = FacePhases(grid, Voronoi(64, (0.7, 0.3), seed=2029).labels(grid), 2)
    >>> problem = WearProblem(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6))
    >>> problem.n_phases, float(problem.coefficient_field[problem.face_mask].min())
    (2, 1e-13)
    """

    def __init__(self, problem, *, contact_rtol=1e-10, contact_maxiter=None, newton_rtol=1e-9,
                 newton_maxiter=30, pressure_floor=1e-6):
        if not isinstance(problem, Problem):
            raise ValueError(f"WearProblem takes a steady.problem.Problem, got "
                             f"{type(problem).__name__}")
        check_run_in_scales(problem)
        grid = problem.grid
        self.problem = problem
        self.wear = problem.wear
        self.halfspace = problem.halfspace
        self.outline = grid.outline
        self.grid = grid
        self.shape = grid.shape
        self.n = grid.n
        self.labels = problem.labels
        self.counts = problem.phases.counts
        self.face_mask = problem.face_mask
        self.coefficient_field = problem.coefficient_field()
        self.normal_force = problem.normal_force
        #: N, the force of the contact solves: ``normal_force`` unless a load programme's run
        #: sets the force of its current distance (:attr:`load_programme`).
        self.applied_force = self.normal_force
        #: The scene's ``[load] programme`` (a :class:`steady.load_programme.LoadProgramme`;
        #: None: constant load); ``normal_force`` is then its last force.
        self.load_programme = None
        self.contact_rtol = float(contact_rtol)
        self.contact_maxiter = contact_maxiter
        self.newton_rtol = float(newton_rtol)
        self.newton_maxiter = int(newton_maxiter)
        self.pressure_floor = float(pressure_floor)
        self.area = float(self.face_mask.sum()) * self.halfspace.h ** 2
        self.solves = 0
        self.iterations = 0
        # (x0, K x0) of the warm start implicit() predicted, for the next solve.
        self._predicted = None
        self._reference = None
        self._stage_shift = None  # the levels of the linear law's stage shifts c k
        #: m/s, the scene's ``[load] sliding_speed`` (None: not given); only for reporting times.
        self.sliding_speed = None
        #: The scene's phase geometry (None: built from a label map), for the error bar of the
        #: rms slope from the geometry's own grid ladder, as ``runin-steady`` gives it.
        self.geometry = None
        self.columns = problem.phases.columns
        self.work_depth = None
        self.stage_solves = self.most_stage_solves = 0
        if self.columns is not None:
            self._check_columns(problem)
            if not self.columns.columnar:
                factor = problem.speed_ratio if problem.sliding is not None else None
                self.work_depth = WorkDepth(self.columns, self.wear.factor.coefficients, factor)

    def _check_columns(self, problem):
        """Refuse a wear law the run across interfaces does not take (the phases checked them)."""
        if self.wear.factor is None:
            # The run integrates the wear work g(p) and maps it to depth through k of each layer.
            raise ValueError(f"depth-varying phases need a wear law k_i g(p) (the power law), "
                             f"not the {self.wear.describe()}")

    @classmethod
    def from_scene(cls, scene, *, n=None, problem=None, **options):
        """The wear problem of a scene file, the one factory every caller uses.

        Parameters
        ----------
        scene : steady.scene.Scene
            As read by :func:`steady.scene.load_scene` or
            :func:`transient.scene.load_transient_scene`.  (A run's contact
            tolerance is its option ``contact_rtol``, which
            :func:`transient.runin.run_in` applies.)
        n : int, optional
            Grid size; default ``scene.n``.  The phase geometry is rasterised
            at this size.
        problem : steady.problem.Problem, optional
            ``Problem.from_scene(scene, n=n)``, if the caller has built it
            (a command that checks the scene's map before the run): the map
            is then not rasterised again.
        **options
            Keyword arguments of the constructor (``contact_rtol``,
            ``contact_maxiter``, ``newton_rtol``, ...), overriding the scene.

        Returns
        -------
        WearProblem
            On the grid ``scene.grid(n)`` of the scene's outline.

        Raises
        ------
        ValueError
            A grid too coarse for the outline or the phase geometry (the
            message names ``n`` and the minimum), a phase without a pixel
            on the face at this grid, or a scale out of range
            (:func:`check_run_in_scales`, naming the scene's keys).

        Examples
        --------
        >>> from transient.scene import load_transient_scene
        >>> scene, options, initial = load_transient_scene(
        ...     "steady/examples/voronoi_transient.toml")
        >>> problem = WearProblem.from_scene(scene, n=40)
        >>> problem.n, problem.n_phases
        (40, 2)
        """
        if problem is None:
            problem = Problem.from_scene(scene, n=n)
        programme = getattr(scene, "load_programme", None)
        try:
            if programme is None:
                check_run_in_scales(problem, scene.input_names())
            for force in () if programme is None else (programme.initial_force,
                                                         *programme.forces):
                # Each force of a programme is a load the run meets.
                names = scene.input_names()
                if force != scene.normal_force:
                    names["normal_force"] = f"[load] programme force {force!r}"
                check_run_in_scales(dataclasses.replace(problem, normal_force=force), names)
        except ValueError as err:
            where = "" if scene.source_path is None else f"{scene.source_path}: "
            raise ValueError(f"{where}{err}") from None
        wear_problem = cls(problem, **options)
        wear_problem.sliding_speed = scene.sliding_speed
        wear_problem.load_programme = programme
        wear_problem.geometry = scene.geometry
        return wear_problem

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return self.problem.n_phases

    @property
    def scale(self):
        """``L``, the outline's length scale, m (the radius ``a`` of a disk)."""
        return self.outline.scale

    @property
    def reference(self):
        """The outline's reference slope under the load (a ``ReferenceSlope``).

        From :func:`steady.normalisation.reference_slope`: ``value`` is
        ``grad_f0`` (``4 pbar / (pi E*)`` for a disk, eq. 12; the homogeneous
        face's rms slope for other outlines), with its ``error``,
        ``mean_pressure`` ``F_N / A`` (``A`` the outline's exact area) and
        ``source`` in words.  Computed once.
        """
        if self._reference is None:
            self._reference = reference_slope(self.outline, self.normal_force,
                                              self.halfspace.E_star)
        return self._reference

    @property
    def reference_slope(self):
        """``grad_f0``, the normalisation of rms slopes (see :attr:`reference`)."""
        return self.reference.value

    # -- natural scales (docs/model.md, "Natural scales") -----------------
    @property
    def pixel_mean_pressure(self):
        """``F_N`` over the pixel area of the face, Pa: the mean of any admissible pressure."""
        return self.normal_force / self.area

    @property
    def depth_scale(self):
        """``f* = pbar L / E*``, m (``pbar`` the pixel mean pressure, ``L`` the scale)."""
        return self.pixel_mean_pressure * self.scale / self.halfspace.E_star

    @property
    def distance_scale(self):
        """``s* = L / (k_min E*)``, m: the slow (run-in) sliding distance (``L = a``, a disk).

        For ``m != 1`` the rate constant is ``k m pbar^(m-1)``.
        """
        return self.scale / (self._rate_constants().min() * self.halfspace.E_star)

    @property
    def fast_distance(self):
        """``h / (k_max E*)``, m: the fastest (one-pixel) relaxation distance."""
        return self.halfspace.h / (self._rate_constants().max() * self.halfspace.E_star)

    def _rate_constants(self):
        """The law's rate constant of each phase at the pixel mean pressure, 1/Pa, shape (P,)."""
        phases = self.wear.coefficient_field(np.arange(self.n_phases))
        return np.asarray(self.wear.rate_constant(phases, self.pixel_mean_pressure), dtype=float)

    def steady_pressure(self):
        """Closed-form steady pressure ``k_i p_i^m = C`` under the load (eq. 7), Pa, shape (nx, ny).

        The limit of an implicit Euler step as ``ds -> infinity``: the warm
        start of a jump.  Across interfaces, of the section below every
        interface (where a run jumps): ``p`` proportional to ``k^(-1/m)``
        pixel by pixel, carrying the load.
        """
        if self.work_depth is not None:
            k = self.work_depth.slope(self.columns.segment_at(self.columns.bottom))
            factor = self.wear.factor
            if factor.exponent is None:
                return factor.pixel_pressures(np.where(self.face_mask, k, 0.0),
                                              self.normal_force, self.halfspace.h ** 2)
            # g = p^m: p proportional to k^(-1/m), carrying the load.
            p = np.where(self.face_mask, np.where(self.face_mask, k, 1.0)
                         ** (-1.0 / factor.exponent), 0.0)
            return p * (self.normal_force / (float(p.sum()) * self.halfspace.h ** 2))
        if self.problem.sliding is not None:  # pixel-wise, k_i v p^m / v_ref = C
            return self.problem.steady_pressure()
        p_phase = self.wear.phase_pressures(self.counts, self.normal_force,
                                            self.halfspace.h ** 2)
        return np.append(p_phase, 0.0)[self.labels]

    def solve_steady(self, *, face_only=False):
        """The closed-form steady state of this problem (eq. 7, 9), for comparison.

        Across interfaces, of the section below every interface
        (``problem.section(columns.bottom)``, where the phase map provides
        sections).

        Parameters
        ----------
        face_only : bool, optional
            Skip the rms slope estimate (:func:`steady.solution.solve`'s
            ``face_only``; default False).

        Returns
        -------
        steady.solution.SteadyResult
            With the corrected rms slope and the error bar of this map
            resampled (:func:`steady.rms_slope.estimate_map_rms_slope`),
            unless ``face_only``.
        """
        if self.work_depth is not None:
            return solve(self.problem.section(self.columns.bottom), face_only=face_only)
        return solve(self.problem, face_only=face_only)

    # -- the right-hand side -------------------------------------------
    def rate(self, pressure):
        """Wear rate of the law, m/m (dimensionless), shape (nx, ny); zero off the face."""
        return self.wear.rate(pressure, self.coefficient_field)

    # -- the integration variable (docs/model.md, "Wear across interfaces") --
    # A columnar problem integrates the height itself, and every hook below is
    # the identity; across interfaces the run integrates the wear work R.
    @staticmethod
    def worn_depth(height, offset, initial_height):
        """Worn depth of a run state, ``height + offset - initial_height``, m, shape (nx, ny)."""
        return height + offset - initial_height

    def variable(self, height, origin):
        """The integration variable of the face ``height`` (m): the height, or its wear work.

        ``origin`` (m, shape (nx, ny)) is the height of zero worn depth,
        ``initial_height - offset``; unused for a columnar problem.
        """
        if self.work_depth is None:
            return height
        return self.work_depth.work(np.where(self.face_mask, height - origin, 0.0))

    def face(self, variable, origin):
        """The face height (m) of an integration variable; see :meth:`variable`."""
        if self.work_depth is None:
            return variable
        return origin + self.work_depth.depth(variable)

    def variable_rate(self, pressure):
        """Rate of the integration variable: ``k p^m`` (m/m), or ``p^m`` for the wear work."""
        if self.work_depth is None:
            return self.rate(pressure)
        return np.where(self.face_mask, self.wear.factor.rate(pressure), 0.0)

    def depth_error(self, error, variable):
        """An error of the integration variable in metres: times the local ``k`` at ``variable``."""
        if self.work_depth is None:
            return error
        work = self.work_depth
        return error * work.slope(work.segment(variable))

    def at_depth(self, worn_depth):
        """Set :attr:`coefficient_field` to the section at ``worn_depth`` (m); its segments.

        Returns
        -------
        ndarray of int, shape (nx, ny)
            The segment of every pixel (:meth:`steady.depth.DepthColumns.segment_at`);
            None for a columnar problem, whose field never changes.
        """
        if self.work_depth is None:
            return None
        segments = self.columns.segment_at(np.where(self.face_mask, worn_depth, 0.0))
        self.coefficient_field = self.work_depth.slope(segments)
        self._stage_shift = None
        return segments

    @functools.cached_property
    def compliance_floor(self):
        """Lower bound of the eigenvalues of ``K`` on any contact set, m/Pa.

        The minimum of the zero-padded circulant's symbol, which bounds every
        principal submatrix of ``K`` from below: a displacement residual
        ``r`` moves the pressure by at most ``|r| / compliance_floor``.
        """
        return float(np.min(self.halfspace.influence_symbol))

    def stable_step(self, pressure):
        """Largest stable explicit-Euler step at ``pressure``, m.

        ``2 / lambda_max`` with ``lambda_max <= max(k m p^(m-1)) / lambda_min(K)``;
        ``lambda_min(K)`` is bounded below by the minimum of the zero-padded
        circulant's symbol, which bounds every principal submatrix (any contact
        set) from below.
        """
        slope = self.wear.largest_rate_slope(pressure[self.face_mask],
                                             self.coefficient_field[self.face_mask],
                                             self.pressure_floor * self.pixel_mean_pressure)
        return 2.0 * self.compliance_floor / slope

    # -- contact solves ------------------------------------------------
    def contact(self, height, *, shift=None, x0=None, x0_displacement=None, atol=0.0,
                preconditioner="auto"):
        """One contact solve, counted; raises :class:`StepFailure` on failure.

        Parameters
        ----------
        height : ndarray, shape (nx, ny), m
        shift : ndarray, shape (nx, ny), m/Pa, optional
        x0 : ndarray, shape (nx, ny), Pa, optional
            Warm start.
        x0_displacement : ndarray, shape (nx, ny), m, optional
            ``K x0``, if known (see :func:`transient.contact.solve_contact`);
            default: the one :meth:`implicit` predicted along with ``x0``.
        atol : float, m, optional
            Absolute tolerance of the solve beside ``contact_rtol`` (default
            0: ``contact_rtol`` alone; see
            :func:`transient.control.contact_tolerance`).
        preconditioner : str or callable, optional
            As :func:`transient.contact.solve_contact` takes it (default
            ``"auto"``).

        Returns
        -------
        transient.contact.ContactResult
        """
        if not np.all(np.isfinite(height[self.face_mask])):
            raise StepFailure("non-finite face height")
        predicted, self._predicted = self._predicted, None
        if x0_displacement is None and predicted is not None and predicted[0] is x0:
            x0_displacement = predicted[1]
        res = solve_trusted_contact(self.halfspace, self.face_mask, height, self.applied_force,
                                    shift=shift, x0=x0, x0_displacement=x0_displacement,
                                    rtol=self.contact_rtol, atol=atol,
                                    maxiter=self.contact_maxiter, preconditioner=preconditioner)
        self.solves += 1
        self.iterations += int(res.nit)
        if not res.success:
            raise StepFailure(f"contact solve failed: {res.message} "
                              f"(nit={res.nit}, residual={res.residual:.3g})")
        if not (np.all(np.isfinite(res.pressure)) and np.isfinite(res.approach)):
            raise StepFailure("contact solve returned non-finite pressure")
        return res

    def _rebuild(self, height, c, res, coefficients=None):
        """Face and contact of an implicit stage ``w = height + c k P(w)^m``.

        On the contact the face is rebuilt as ``d - K p``, with the solver's
        own ``K p`` (kept apart from the shift's part, so exact to the
        round-off of ``K p`` whatever the shift) and ``d`` the mean of
        ``height + c k p^m + K p`` there: the solver's residual, which scales
        with the shifted operator and so with ``c``, is projected out of the
        shape (it would reach ``rtol * ds / s*`` of ``f*`` after a jump),
        while the rigid part keeps the exact mean of the update.
        """
        p = res.pressure
        contact = self.face_mask & (p > 0)
        if coefficients is None:
            w = height + c * self.rate(p)
        else:
            w = height + c * self.wear.rate(p, coefficients)
        kp = res.elastic_displacement
        if not contact.any():
            return w, res
        d = float(np.mean((w + kp)[contact]))
        w = np.where(contact, d - kp, w)
        return w, dataclasses.replace(res, approach=d)

    def _linearisation(self, height, c, p0):
        """Shift and height of the contact problem linearised about ``p0`` (a nonlinear law)."""
        return self.wear.linearisation(height, c, p0, self.coefficient_field, self.face_mask,
                                       self.pressure_floor * self.pixel_mean_pressure)

    def implicit(self, height, c, x0, *, history=None, atol=0.0, origin=None):
        """Solve ``w = height + c k P(w)^m`` for ``w``.

        Across interfaces (:attr:`work_depth`) ``height`` and ``w`` are wear
        works and the stage is ``R = height + c P(origin + D(R))^m``
        (:meth:`_implicit_work`).

        Parameters
        ----------
        height : ndarray, shape (nx, ny), m
        c : float, m
            Sliding distance multiplying the implicit rate (``ds``, ``gamma ds``...).
        x0 : ndarray, shape (nx, ny), Pa
            Pressure guess (warm start and first linearisation point), used
            when ``history`` holds no pressure.
        history : WarmStart, optional
            Recent pressures of the run: the warm start is their Galerkin
            combination (:meth:`WarmStart.predict`), and the stage's
            pressure joins them.
        atol : float, m, optional
            Absolute tolerance of the contact solve (default 0; see
            :meth:`contact`).  Each solve of a power-law Newton iteration
            takes it too: its test compares successive pressures to
            ``newton_rtol``, so the caller keeps it 0 there.
        origin : ndarray, shape (nx, ny), m, optional
            The height of zero worn depth (:meth:`variable`); needed across
            interfaces only.

        Returns
        -------
        w : ndarray, shape (nx, ny), m
        result : ContactResult
            The contact of the face ``w`` (its pressure is ``P(w)``).

        """
        if self.work_depth is not None:
            return self._implicit_work(height, c, x0, history, atol, origin)
        if self.wear.linear:
            shift = c * self.coefficient_field
            if history is not None and len(history):
                x0, kx0 = history.predict(height, shift_scale=c)
                self._predicted = (x0, kx0)
            if self._stage_shift is None:
                self._stage_shift = ScaledShift(self.halfspace, self.face_mask,
                                                self.coefficient_field)
            res = self.contact(height, shift=shift, x0=x0, atol=atol,
                               preconditioner=self._stage_shift.preconditioner(c, shift))
        else:
            pbar = self.pixel_mean_pressure
            p0 = np.asarray(x0, dtype=float)
            if history is not None and len(history):
                # The stage linearised about the newest pressure predicts the
                # first linearisation point.
                shift, h_lin = self._linearisation(height, c, history.newest())
                p0, kx0 = history.predict(h_lin, shift)
                self._predicted = (p0, kx0)
            for _ in range(self.newton_maxiter):
                shift, h_lin = self._linearisation(height, c, p0)
                res = self.contact(h_lin, shift=shift, x0=p0, atol=atol)
                change = float(np.max(np.abs(res.pressure - p0))) / pbar
                p0 = res.pressure
                if change <= self.newton_rtol:
                    break
            else:
                raise StepFailure(f"power-law Newton iteration did not converge in "
                                  f"{self.newton_maxiter} iterations (last change "
                                  f"{change:.3g} pbar)")
        w, res = self._rebuild(height, c, res)
        if history is not None:
            history.push(res.pressure, res.elastic_displacement)
        return w, res


    def _implicit_work(self, known, c, x0, history, atol, origin):
        """The stage ``R = known + c P(origin + D(R))^m`` in the wear work, by Newton's method.

        ``D`` is linearised about the iterate, the line of its segment
        (slope ``k``), and ``p^m`` about the last pressure: each iteration
        is the shifted contact problem of a columnar stage with the
        coefficients ``k`` of the iterate's segments.  Semismooth Newton on
        the piecewise-linear ``D``: it ends once no pixel changes segment
        (then the linearisation is exact for ``m = 1``) and, for ``m != 1``,
        the pressure changes by less than ``newton_rtol``; at most
        ``newton_maxiter`` iterations, else :class:`StepFailure`.
        """
        work, face = self.work_depth, self.face_mask
        floor = self.pressure_floor * self.pixel_mean_pressure
        p0 = history.newest() if history is not None and len(history) else np.asarray(x0, float)
        guess = known + c * self.variable_rate(p0)
        segments = work.segment(guess)
        start = p0
        for iteration in range(1, self.newton_maxiter + 1):
            k = work.slope(segments)
            # origin + D(R_i) + k (R - R_i) with R = known + c p^m:
            base = origin + work.depth(guess, segments) + k * (known - guess)
            shift, h_lin = self.wear.linearisation(base, c, p0, k, face, floor)
            if iteration == 1 and history is not None and len(history):
                # The solver computes K x0 itself: the combination's own, with
                # the large weights of the pressures of a wear-through, carries
                # their round-off, which the solve returned in its K p and the
                # next combination amplified, to per cent of K x0 and wrong
                # stage pressures (tests/test_depth_run.py).
                start, _ = history.predict(h_lin, shift)
                if not self.wear.linear:
                    p0 = start
                    shift, h_lin = self.wear.linearisation(base, c, p0, k, face, floor)
            res = self.contact(h_lin, shift=shift, x0=start, atol=atol)
            change = float(np.max(np.abs(res.pressure - p0))) / self.pixel_mean_pressure
            p0 = start = res.pressure
            guess = known + c * self.variable_rate(p0)
            moved = work.segment(guess)
            changing = int(np.count_nonzero(moved != segments))
            segments = moved
            if changing == 0 and (self.wear.linear or change <= self.newton_rtol):
                break
        else:
            raise StepFailure(f"Newton iteration across interfaces did not converge in "
                              f"{self.newton_maxiter} iterations ({changing} pixels changing "
                              f"segment, last change {change:.3g} pbar)")
        self.stage_solves += iteration
        self.most_stage_solves = max(self.most_stage_solves, iteration)
        w, res = self._rebuild(base, c, res, k)
        if history is not None:
            history.push(res.pressure, res.elastic_displacement)
        return work.work(np.where(face, w - origin, 0.0)), res


#: Columns of the history a block: the warm start forms its differences and
#: sums their products a block at a time, so that the differences of a block
#: (a few rows of it, 512 KiB each) are summed while still in cache.
_BLOCK = 1 << 16


def _blocks(size):
    """Slices of ``range(size)`` of :data:`_BLOCK` columns, in order."""
    return [slice(start, min(start + _BLOCK, size)) for start in range(0, size, _BLOCK)]


def _dot(a, b):
    """``<a, b>`` for two rows (einsum: a threaded BLAS call can be erratic on a loaded machine)."""
    return float(np.einsum("j,j->", a, b))


class WarmStart:
    """The last few contact pressures of a run: the warm start of its implicit stages.

    Holds up to ``size`` pressures ``v_j`` (newest first), each with its
    elastic displacement ``K v_j`` (the solver's own, which it returns with
    the pressure).  :meth:`predict` returns the combination
    ``x = sum_j alpha_j v_j`` with ``sum_j alpha_j = 1`` (so ``x`` carries
    the load) that minimises the energy of the next contact problem,

        E(x) = x^T (K + diag(shift)) x / 2 + x^T h,

    over that affine span: the Galerkin projection of its solution, at
    least as close in the operator's norm as any single pressure or any
    polynomial extrapolation of them in the sliding distance.  Both the
    pressures and the displacements are state (a checkpoint stores them,
    :meth:`pressures`, :meth:`displacements`): the solver's ``K v_j`` carry
    the round-off of its updates, so that a resumed run needs them as they
    were to repeat the run bit for bit.

    Parameters
    ----------
    problem : WearProblem
    size : int, optional
        Pressures kept (default 6).
    pressures : ndarray, shape (k, nx, ny), Pa, optional
        Initial content, newest first (a checkpoint's).
    displacements : ndarray, shape (k, nx, ny), m, optional
        ``K`` times each of ``pressures`` (default: computed by FFT).
    """

    def __init__(self, problem, size=6, pressures=None, displacements=None):
        if int(size) != size or size < 1:
            raise ValueError(f"size must be a positive integer, got {size!r}")
        self.problem = problem
        self.size = int(size)
        # The pressures [0] and their displacements [1] in rows of one array,
        # a ring: ``_order`` lists the rows held, newest first, and a push
        # writes over the oldest instead of moving the others.  Every sum runs
        # over the rows in that order, so that where they lie changes no
        # number.  :meth:`pressures` and :meth:`displacements` put them in
        # order and hand them out without a copy: the next push after that
        # writes a new array.
        self._stack = None
        self._order = []
        self._shared = False
        # Differences of consecutive pressures d_i = v_i - v_(i+1) and their
        # products, newest first (i = 0 .. len - 2): they span the same affine
        # set as the differences from the newest, but stay the same when a
        # pressure is added, and so do their Gram matrices, which are kept:
        # <d_i, K d_j> (exact K symmetric: computed once per pair) and
        # <d_i, k d_j> with the wear coefficients k (filled when first asked).
        # The differences themselves are not kept but formed when needed, a
        # block of pixels at a time (a subtraction, bit for bit the same each
        # time): kept, they would double the memory of the history.
        self._gram = np.zeros((self.size - 1, self.size - 1))
        self._gram_k = np.full((self.size - 1, self.size - 1), np.nan)
        if pressures is not None:
            pressures = np.asarray(pressures, dtype=float)
            if displacements is None:
                displacements = [None] * len(pressures)
            elif np.shape(displacements) != pressures.shape:
                raise ValueError(f"displacements must have the shape of the pressures "
                                 f"{pressures.shape}, got {np.shape(displacements)}")
            for p, kp in zip(pressures[::-1], displacements[::-1], strict=True):
                self.push(p, kp)

    def __len__(self):
        """Number of pressures held."""
        return len(self._order)

    @property
    def _values(self):
        """The pressures held, newest first: a list of views, shape (nx ny,)."""
        return [self._stack[0, slot] for slot in self._order]

    @property
    def _products(self):
        """Their displacements, newest first: a list of views, shape (nx ny,)."""
        return [self._stack[1, slot] for slot in self._order]

    def push(self, pressure, displacement=None):
        """Add a pressure (Pa, shape (nx, ny)) and its ``K p`` (m; computed if None)."""
        pressure = np.where(self.problem.face_mask, pressure, 0.0)
        if displacement is None:
            displacement = self.problem.halfspace.displacement(pressure)
        value = pressure.ravel()
        product = np.asarray(displacement, dtype=float).ravel()  # copied into the stack
        if self._stack is None:
            self._stack = np.empty((2, self.size, value.size))
        if len(self) and self.size > 1:
            k = min(len(self), self.size - 1)  # differences held after this one
            for gram in (self._gram, self._gram_k):
                gram[1:k, 1:k] = gram[:k - 1, :k - 1].copy()
            self._gram[0, :k] = self._gram[:k, 0] = self._new_gram_row(value, product, k)
            self._gram_k[0, :k] = self._gram_k[:k, 0] = np.nan
        kept = self._order[:self.size - 1]
        if self._shared:  # the rows handed out stay as they are
            old, self._stack, self._shared = self._stack, np.empty_like(self._stack), False
            for slot in kept:
                self._stack[:, slot] = old[:, slot]
            del old
        slot = min(set(range(self.size)) - set(kept))  # the oldest's, or a free one
        self._stack[0, slot], self._stack[1, slot] = value, product
        self._order = [slot, *kept]

    def newest(self):
        """The newest pressure, Pa, shape (nx, ny)."""
        return self._stack[0, self._order[0]].reshape(self.problem.shape).copy()

    def pressures(self):
        """The pressures held, newest first, Pa, shape (k, nx, ny) (read-only, not a copy)."""
        return self._handed_out(0)

    def displacements(self):
        """Their elastic displacements ``K p``, newest first, m, shape (k, nx, ny) (read-only)."""
        return self._handed_out(1)

    def _handed_out(self, which):
        """Pressures (0) or displacements (1), read-only, which later pushes leave as they are."""
        if self._stack is None:
            return np.empty((0, *self.problem.shape))
        self._in_order()
        self._shared = True
        out = self._stack[which, :len(self)].reshape(-1, *self.problem.shape)
        out.flags.writeable = False
        return out

    def _in_order(self):
        """Move the rows held to the first ones, newest first (in place, one row spare)."""
        moves = {target: source for target, source in enumerate(self._order) if target != source}
        if not moves:
            return
        spare = np.empty(self._stack.shape[2])
        for which in (0, 1):
            stack, pending = self._stack[which], dict(moves)
            while pending:
                sources = set(pending.values())
                target = next((t for t in pending if t not in sources), None)
                if target is None:  # a cycle: its first row to the spare
                    target = next(iter(pending))
                    spare[:] = stack[target]
                    pending = {t: (-1 if s == target else s) for t, s in pending.items()}
                    continue
                source = pending.pop(target)
                stack[target] = spare if source == -1 else stack[source]
        self._order = list(range(len(self)))

    def _new_gram_row(self, value, product, k):
        """``<d_0, K d_j>`` (j < k), ``d_0`` the difference that pushing ``value`` adds.

        One product per pair, newest with older, each summed block by block
        (:func:`_blocks`) from differences formed exactly: the same numbers
        whatever the order of the pushes and predictions that led here.
        """
        values, products = self._values, self._products
        row = np.zeros(k)
        d = np.empty(min(_BLOCK, value.size))
        kd = np.empty((k, d.size))
        for block in _blocks(value.size):
            m = block.stop - block.start
            np.subtract(value[block], values[0][block], out=d[:m])
            np.subtract(product[block], products[0][block], out=kd[0, :m])
            for j in range(1, k):  # K d_j of the older ones, j their index after this push
                np.subtract(products[j - 1][block], products[j][block], out=kd[j, :m])
            for j in range(k):
                row[j] += _dot(d[:m], kd[j, :m])
        return row

    def _stage_products(self, height, weight, scale, k, pairs):
        """The sums :meth:`predict` needs, in one pass over the pressures, block by block.

        Parameters
        ----------
        height : ndarray, shape (nx ny,), m
        weight : ndarray, shape (nx ny,), m/Pa, or None
            The shift (zero off the face) divided by ``scale``.
        scale : float
        k : int
            Differences held.
        pairs : list of (int, int)
            The ``(i, j)`` of the products ``<d_i, diag(weight) d_j>`` wanted.

        Returns
        -------
        gradient : ndarray, shape (k,)
            ``<d_i, g>``, ``g = K v_0 + scale weight v_0 + height`` less its
            mean over the face (the load's multiplier, summed first from its
            three terms: it is most of ``g``, which is nearly uniform on the
            contact, and taken off after the products it would cancel in them).
        weighted : ndarray, shape (len(pairs),)
            ``<d_i, diag(weight) d_j>`` for the pairs: each from the
            differences formed exactly and summed over the blocks in order, a
            pair's number does not depend on the other pairs asked for.

        The differences are formed in each block (the differences of sums
        ``<v_i, g> - <v_(i+1), g>`` would lose as many digits as consecutive
        pressures share).
        """
        values, products = self._values, self._products
        face = self.problem.face_mask.ravel()
        mean = float(np.add.reduce(products[0], where=face) + np.add.reduce(height, where=face))
        if weight is not None:
            mean += scale * _dot(weight, values[0])  # the pressures vanish off the face
        mean /= np.count_nonzero(face)
        rows = sorted({i for i, _ in pairs})
        gradient, weighted = np.zeros(k), np.zeros(len(pairs))
        g = np.empty(min(_BLOCK, height.size))
        d = np.empty((k, g.size))
        w = np.empty((len(rows), g.size))
        for block in _blocks(height.size):
            m = block.stop - block.start
            gb = g[:m]
            if weight is None:
                np.add(products[0][block], height[block], out=gb)
            else:
                np.multiply(weight[block], scale, out=gb)
                gb *= values[0][block]
                gb += products[0][block]
                gb += height[block]
            gb -= mean
            for i in range(k):
                np.subtract(values[i][block], values[i + 1][block], out=d[i, :m])
            for i in range(k):
                gradient[i] += _dot(d[i, :m], gb)
            for r, i in enumerate(rows):
                np.multiply(weight[block], d[i, :m], out=w[r, :m])
            for p, (i, j) in enumerate(pairs):
                weighted[p] += _dot(w[rows.index(i), :m], d[j, :m])
        return gradient, weighted

    def predict(self, height, shift=None, *, shift_scale=None):
        """Warm start of the contact problem ``(K + diag(shift)) p = d - height``.

        Parameters
        ----------
        height : ndarray, shape (nx, ny), m
        shift : ndarray, shape (nx, ny), m/Pa, optional
        shift_scale : float, m, optional
            The shift is ``shift_scale`` times the wear coefficients
            (:attr:`WearProblem.coefficient_field`), the linear wear law's
            stage: the Gram matrix of that part is then kept from one call to
            the next instead of summed again.  Not with ``shift``.

        Returns
        -------
        pressure : ndarray, shape (nx, ny), Pa
            The energy-minimising combination of the pressures held (see the
            class docstring); negative values are left to the solver, which
            drops them.
        displacement : ndarray, shape (nx, ny), m
            ``K`` times it on the whole grid (the same combination of the
            stored products).
        """
        if shift is not None and shift_scale is not None:
            raise ValueError("give the shift either as an array or as shift_scale, not both")
        shape = self.problem.shape
        k = len(self) - 1
        beta = None
        if k:
            # x = v0 + D^T beta keeps the load, with the consecutive differences
            # D (a small Gram matrix free of cancellation); the pressures
            # vanish off the face, so the sums run over the face.
            everything = [(i, j) for i in range(k) for j in range(i, k)]
            if shift_scale is not None:  # the kept Gram matrix, its missing entries
                weight, scale, gram_k = (self.problem.coefficient_field.ravel(), shift_scale,
                                         self._gram_k)
                pairs = [(i, j) for i, j in everything if np.isnan(gram_k[i, j])]
            elif shift is not None:
                weight, scale, gram_k = (np.where(self.problem.face_mask, shift, 0.0).ravel(),
                                         1.0, np.empty((k, k)))
                pairs = everything
            else:
                weight, scale, pairs = None, 1.0, []
            rhs, sums = self._stage_products(np.ravel(height), weight, scale, k, pairs)
            gram = self._gram[:k, :k].copy()
            if weight is not None:
                for (i, j), value in zip(pairs, sums, strict=True):
                    gram_k[i, j] = gram_k[j, i] = value
                gram += scale * gram_k[:k, :k]
            w, q = np.linalg.eigh(0.5 * (gram + gram.T))
            keep = w > _GRAM_CUTOFF * max(float(w[-1]), 0.0)
            if keep.any():
                beta = -(q[:, keep] @ ((q[:, keep].T @ rhs) / w[keep]))
        if beta is None:
            return self.newest(), self._products[0].reshape(shape).copy()
        return self._combination(beta, self._values), self._combination(beta, self._products)

    def _combination(self, beta, rows):
        """``v_0 + sum_i beta_i (v_i - v_(i+1)) = sum_j alpha_j v_j`` of ``rows``, newest first.

        Summed row by row in that order, a block at a time.
        """
        k = len(beta)
        alpha = np.zeros(k + 1)
        alpha[0] = 1.0
        alpha[:k] += beta
        alpha[1:] -= beta
        out = np.empty(rows[0].size)
        term = np.empty(min(_BLOCK, out.size))
        for block in _blocks(out.size):
            part, t = out[block], term[:block.stop - block.start]
            np.multiply(rows[0][block], alpha[0], out=part)
            for a, row in zip(alpha[1:], rows[1:k + 1], strict=True):
                part += np.multiply(row[block], a, out=t)
        return out.reshape(self.problem.shape)
