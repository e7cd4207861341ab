"""The discretised wear problem of a run-in: one grid, one phase map, one load, fixed.

:class:`WearProblem` is what a run-in solves (docs/model.md, "Wear and time
integration"): the half-space operator, the phase map and the wear law's
field of every pixel, the load (and its programme), the natural scales of
the run-in, the steady state it tends to and the hooks of the integration
variable (the face recession, or across interfaces its wear work).  It holds
no state of a run: the contact solves, their counters, the warm start, the
force of the current distance and the section the face has worn down to
belong to the run's :class:`transient.solver.StageSolver`.
:func:`transient.scene.wear_problem_of` is the one way from a scene file to a
problem; every caller (command line, studies, tests) goes through it or
through the constructor, which takes a phase map, never a per-pixel
coefficient field built by hand.
"""

from __future__ import annotations

import functools

import numpy as np

from steady.normalisation import reference_slope
from steady.problem import Problem, check_scale, input_names
from steady.scene import SLIDING_SPEED
from steady.solution import solve

from .depth import WorkDepth

__all__ = ["PEAK_RATE_LIMIT", "WearProblem", "check_run_in_scales"]

#: Largest wear rate ``g(p)`` (m/m) a run may meet at a pixel that carries the
#: whole load, ``p = F_N / h^2``: the rate, its slope and their products with
#: distances and coefficients are computed at every step, and must not
#: overflow (about 1e308) on the way.
PEAK_RATE_LIMIT = 1e200


def check_run_in_scales(problem, names=None, force=None):
    """Refuse a run-in whose scales leave :data:`steady.problem.SCALE_RANGE`, naming the inputs.

    Beyond the problem's own (:func:`steady.problem.check_scales`, checked
    when it was built), a run-in has its distances: the run-in distance
    ``s* = L / (k_min' E*)`` and the fastest relaxation distance
    ``h / (k_max' E*)`` (``k'`` the law's rate constant at the pixel mean
    pressure, ``k m pbar^(m-1)`` for the power law; messages name it in the
    law's terms, :attr:`steady.wear.WearLaw.rate_constant_words`), both in
    range; and the wear rate of a pixel that carries the whole load,
    ``g(F_N / h^2)`` of the fastest phase, below :data:`PEAK_RATE_LIMIT` (a
    large exponent overflows ``p^m`` at the rim's pressures long before at
    ``pbar``).  Computed as the run computes them: an overflow is ``inf``,
    an underflow 0.

    Parameters
    ----------
    problem : steady.problem.Problem
    names : mapping, optional
        How the message names each input (default
        :func:`steady.problem.input_names`; a scene's keys).
    force : float, optional, N
        The force (default the problem's): each force of a load programme
        is a load the run meets.

    Raises
    ------
    ValueError
        The first scale out of range, with its inputs.
    """
    F, E = problem.normal_force if force is None else float(force), problem.E_star
    names = (input_names(problem.outline, F, E, problem.n, problem.wear) if names is None
             else names)
    h = problem.grid.h
    wear = problem.wear
    phases = wear.wear_field(np.arange(wear.n_phases))
    mean = F / (float(problem.face_mask.sum()) * h * h)
    with np.errstate(all="ignore"):
        # In numpy's floats: an underflow to 0 divides to inf rather than raising.
        constants = np.asarray(wear.rate_constant(phases, np.float64(mean)), dtype=float)
        slow, fast = np.float64(constants.min()), np.float64(constants.max())
        peak = float(np.max(wear.rate(np.full(wear.n_phases, F / (h * h)), phases)))
        s_star = float(problem.outline.scale / (slow * E))
        fastest = float(h / (fast * E))
    inputs = ("wear", "normal_force", "outline", "E_star")
    slope = f"(g' = {wear.rate_constant_words})"
    check_scale(s_star, f"the run-in distance s* = L / (g' E*) of the slowest phase {slope}",
                "m", inputs, names)
    check_scale(fastest, f"the fastest relaxation distance h / (g' E*) {slope}", "m",
                (*inputs, "n"), names)
    if not peak < PEAK_RATE_LIMIT:  # NaN is not
        given = " and ".join(names[key] for key in ("wear", "normal_force", "outline", "n"))
        raise ValueError(f"{given}: the wear rate of a pixel carrying the whole load, "
                         f"g(F_N / h^2) of the fastest phase, is {peak:.3g}, above "
                         f"{PEAK_RATE_LIMIT:g}: the run's rates would overflow (a smaller "
                         f"exponent, or a coarser grid)")



class WearProblem:
    """The discretised wear system ``dw/ds = g(P(w))`` on one grid: data, not a solver.

    Parameters
    ----------
    problem : steady.problem.Problem
        The phase map on the face's grid, the wear law, the load and ``E*``
        (checked there); its half-space operator is the one of the run.
        Under a load programme its force is the programme's last.
    load_programme : steady.load_programme.LoadProgramme, optional
        The scene's ``[load] programme`` (default None: a constant load).
    sliding_speed : float, optional, m/s
        The scene's ``[load] sliding_speed`` (default None); only for
        reporting distances as times.  Checked through the scene's key
        (:data:`steady.scene.SLIDING_SPEED`): a speed in the range of every
        scale.
    geometry : phase geometry, optional
        The scene's phase geometry (default None: a bare label map), for
        the error bar of the rms slope from the geometry's own grid ladder,
        as ``runin-steady`` gives it.
    names : mapping, optional
        How messages name the inputs (:func:`steady.problem.input_names`;
        :meth:`from_scene` gives the scene's keys).

    Attributes
    ----------
    problem : steady.problem.Problem
    wear : steady.wear.WearLaw
        The problem's law: the rate, its linearisation and the steady
        pressures all come from it.
    outline : outline object
        The face's outline.
    grid : steady.outline.FaceGrid
        Its grid: ``shape``, ``n``, ``h``, pixel centres.
    shape : (int, int)
        ``(nx, ny)``.
    n : int
        Pixels along the longer side of the grid (across the diameter of a
        disk).
    face_mask : ndarray of bool, shape (nx, ny)
        Pixels of the punch face (``labels >= 0``).
    wear_field : ndarray, shape (nx, ny)
        The wear law's field of each pixel at the initial surface
        (:meth:`steady.problem.Problem.wear_field`), zero off the face.
    normal_force : float, N
        The problem's force (a programme's last).
    columns : steady.depth.DepthColumns or None
        The phases below the face (``problem.phases.columns``); None for a
        columnar problem.  With interfaces the law must factorise,
        ``k_i g(p)`` (:attr:`steady.wear.WearLaw.factor`).
    work_depth : transient.depth.WorkDepth or None
        Its wear-work map, None unless ``columns`` has an interface: the run
        then integrates the wear work (docs/model.md, "Wear across
        interfaces").

    Raises
    ------
    ValueError
        A scale of the run out of range (:func:`check_run_in_scales`, for
        each force of the programme), a sliding speed that is not a speed
        in range, or a law that does not factorise across interfaces.

    Examples
    --------
    >>> from steady import Circle, FacePhases, Problem, Voronoi
    >>> grid = Circle(4e-3).grid(32)
    >>> phases = FacePhases(grid, Voronoi(64, (0.7, 0.3), seed=2029).labels(grid), 2)
    >>> problem = WearProblem(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6))
    >>> problem.n_phases, float(problem.wear_field[problem.face_mask].min())
    (2, 1e-13)
    """

    def __init__(self, problem, *, load_programme=None, sliding_speed=None, geometry=None,
                 names=None):
        if not isinstance(problem, Problem):
            raise ValueError(f"WearProblem takes a steady.problem.Problem, got "
                             f"{type(problem).__name__}")
        if sliding_speed is not None:
            sliding_speed = SLIDING_SPEED.parse(sliding_speed, "")
        forces = (None,) if load_programme is None else (load_programme.initial_force,
                                                         *load_programme.forces)
        for force in forces:
            given = names
            if names is not None and force is not None and force != load_programme.initial_force:
                given = dict(names, normal_force=f"[load] programme force {force!r}")
            check_run_in_scales(problem, given, force)
        grid = problem.grid
        columns = problem.phases.columns
        work_depth = None
        if columns is not None:
            if problem.wear.factor is None:
                # The run integrates the wear work g(p) and maps it to depth through k.
                raise ValueError(f"depth-varying phases need a wear law k_i g(p) (the power "
                                 f"law), not the {problem.wear.describe()}")
            if not columns.columnar:
                factor = problem.speed_ratio if problem.sliding is not None else None
                work_depth = WorkDepth(columns, problem.wear.factor.coefficients, factor)
        fields = dict(
            problem=problem, wear=problem.wear, halfspace=problem.halfspace,
            outline=grid.outline, grid=grid, shape=grid.shape, n=grid.n,
            labels=problem.labels, counts=problem.phases.counts, face_mask=problem.face_mask,
            wear_field=problem.wear_field(), normal_force=problem.normal_force,
            load_programme=load_programme, sliding_speed=sliding_speed, geometry=geometry,
            area=float(problem.face_mask.sum()) * problem.halfspace.h ** 2, columns=columns,
            work_depth=work_depth)
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def __setattr__(self, name, value):
        """Refuse: a problem is fixed (a run's state belongs to its solver)."""
        raise AttributeError(f"a WearProblem is fixed: cannot set {name!r} (the state of a run "
                             f"belongs to its transient.solver.StageSolver)")

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return self.problem.n_phases

    @property
    def scale(self):
        """``L``, the outline's length scale, m (the radius ``a`` of a disk)."""
        return self.outline.scale

    @functools.cached_property
    def reference(self):
        """The outline's reference slope under the load (a ``ReferenceSlope``).

        From :func:`steady.normalisation.reference_slope`: ``value`` is
        ``grad_f0`` (``4 pbar / (pi E*)`` for a disk, eq. 12; the homogeneous
        face's rms slope for other outlines), with its ``error``,
        ``mean_pressure`` ``F_N / A`` (``A`` the outline's exact area) and
        ``source`` in words.  Computed once.
        """
        return reference_slope(self.outline, self.normal_force, self.halfspace.E_star)

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
        """``f* = pbar L / E*``, m (``pbar`` the pixel mean pressure, ``L`` the scale).

        On a layer its own displacement scale, ``f*`` times the factor of the
        wave ``1 / L`` (:meth:`steady.counterbody.Counterbody.displacement_scale`).
        """
        return self.problem.counterbody.displacement_scale(self.pixel_mean_pressure, self.scale)

    @property
    def distance_scale(self):
        """``s* = L / (k_min E*)``, m: the slow (run-in) sliding distance (``L = a``, a disk).

        ``k`` is the law's rate constant (:meth:`steady.wear.WearLaw.rate_constant`:
        ``g'(pbar) = k m pbar^(m-1)`` for the power law).
        """
        return self.scale / (self._rate_constants().min() * self.halfspace.E_star)

    @property
    def fast_distance(self):
        """``h / (k_max E*)``, m: the fastest (one-pixel) relaxation distance."""
        return self.halfspace.h / (self._rate_constants().max() * self.halfspace.E_star)

    def _rate_constants(self):
        """The law's rate constant of each phase at the pixel mean pressure, 1/Pa, shape (P,)."""
        phases = self.wear.wear_field(np.arange(self.n_phases))
        return np.asarray(self.wear.rate_constant(phases, self.pixel_mean_pressure), dtype=float)

    @functools.cached_property
    def compliance_floor(self):
        """Lower bound of the eigenvalues of ``K`` on any contact set, m/Pa.

        The operator's own bound (``compliance_floor``: the minimum of the
        zero-padded circulant's symbol of :class:`steady.halfspace.HalfSpace`, of
        the cell's symbol of :class:`steady.periodic.PeriodicHalfSpace`), which
        bounds every principal submatrix of ``K`` from below: a displacement
        residual ``r`` moves the pressure by at most ``|r| / compliance_floor``.
        """
        return self.halfspace.compliance_floor

    # -- the steady state --------------------------------------------------
    def steady_pressure(self):
        """Closed-form steady pressure ``g_i(p_i) = C`` under the load (eq. 7), Pa, shape (nx, ny).

        The limit of an implicit Euler step as ``ds -> infinity``: the warm
        start of a jump.  Across interfaces, of the section below every
        interface (where a run jumps), pixel by pixel, carrying the load.
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
        if self.problem.sliding is not None:  # pixel-wise, k_i v g(p) / v_ref = C
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

    # -- the right-hand side ---------------------------------------------
    def rate(self, pressure, field=None):
        """Wear rate of the law, m/m, shape (nx, ny); zero off the face.

        ``field`` is the law's per-pixel field (default
        :attr:`wear_field`, the initial surface's; a run's solver
        passes the section it has worn down to).
        """
        return self.wear.rate(pressure, self.wear_field if field is None else field)

    # -- the integration variable (docs/model.md, "Wear across interfaces") --
    # A columnar problem integrates the recession itself, and every hook below is
    # the identity; across interfaces the run integrates the wear work R.
    @staticmethod
    def worn_depth(recession, offset, initial_recession):
        """Worn depth of a run state, ``recession + offset - initial_recession``, m."""
        return recession + offset - initial_recession

    def variable(self, recession, origin):
        """The integration variable of the face ``recession`` (m): the recession, or its wear work.

        ``origin`` (m, shape (nx, ny)) is the recession of zero worn depth,
        ``initial_recession - offset``; unused for a columnar problem.
        """
        if self.work_depth is None:
            return recession
        return self.work_depth.work(np.where(self.face_mask, recession - origin, 0.0))

    def face(self, variable, origin):
        """The face recession (m) of an integration variable; see :meth:`variable`."""
        if self.work_depth is None:
            return variable
        return origin + self.work_depth.depth(variable)

    def work_rate(self, pressure):
        """Rate of the wear work across interfaces: ``g(p)`` of a unit ``k``, 0 off the face."""
        return np.where(self.face_mask, self.wear.factor.rate(pressure), 0.0)

    def depth_error(self, error, variable):
        """An error of the integration variable in metres: times the local ``k`` at ``variable``."""
        if self.work_depth is None:
            return error
        work = self.work_depth
        return error * work.slope(work.segment(variable))

    def section_field(self, worn_depth):
        """The segments and the law's field of the section at ``worn_depth`` (m).

        Returns
        -------
        segments : ndarray of int, shape (nx, ny), or None
            The segment of every pixel
            (:meth:`steady.depth.DepthColumns.segment_at`); None for a
            problem without interfaces, whose field is
            :attr:`wear_field` at every depth.
        field : ndarray, shape (nx, ny), or None
            ``k`` of every pixel's segment (times the speed ratio).
        """
        if self.work_depth is None:
            return None, None
        segments = self.columns.segment_at(np.where(self.face_mask, worn_depth, 0.0))
        return segments, self.work_depth.slope(segments)
