"""The stage solver of a run-in: every contact solve of a run, and the state they carry.

A :class:`transient.problem.WearProblem` is what is solved: the grid, the
phases, the wear law, the load and the scales, fixed.  :class:`StageSolver`
solves it: the contact problems of the integrators' steps (plain, and
shifted for implicit stages, :meth:`StageSolver.implicit`), the Newton
iteration of a nonlinear law or across interfaces, and what these carry
from one solve to the next -- the solver's tolerances, the warm start
(:class:`transient.warm_start.WarmStart`), the preconditioner of the linear
law's stages, the counters, the force of a load programme at the current
distance (:attr:`StageSolver.force`) and the coefficients of the section the
face has worn down to (:attr:`StageSolver.wear_field`).  The run
(:func:`transient.runin.run_in`) owns one; the integrators
(:mod:`transient.stepping`) step through it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .contact import solve_trusted_contact
from .preconditioners import ScaledShift
from .warm_start import WarmStart

__all__ = ["STAGE_NORM", "STAGE_SHARE_FACTOR", "StageSolver", "StepFailure"]

#: The norm in which a stage solve with an absolute tolerance measures its residual
#: (:func:`transient.contact.solve_contact`, ``norm``), and the factor on that tolerance
#: (:func:`transient.control.contact_tolerance`, a share of the step's ``tol f*``) it
#: takes.  The rms over the face lets the violation at a rectangle's corner pixels reach
#: ``sqrt(N_face / 4)`` times its tolerance, which a looser share turns into rejected
#: steps; the largest violation bounds every pixel (docs/benchmarks.md, "Stopping rule of
#: the stage solves").
STAGE_NORM = "max"
#: The factor on the share of :func:`transient.control.contact_tolerance` (see ``STAGE_NORM``).
STAGE_SHARE_FACTOR = 30.0


class StepFailure(RuntimeError):
    """A step could not be completed; the caller retries with a smaller step.

    Raised when the contact solver fails, values turn non-finite or a
    Newton iteration does not converge.
    """


class StageSolver:
    """The contact solves of a run on one :class:`transient.problem.WearProblem`.

    Parameters
    ----------
    problem : transient.problem.WearProblem
    contact_rtol : float, optional
        Relative tolerance of every contact solve (default 1e-10);
        :func:`transient.runin.run_in` takes its options' ``contact_rtol``.
    contact_maxiter : int, optional
        Iteration cap of every contact solve (default: the solver's).
    newton_rtol : float, optional
        Stop a Newton iteration (a nonlinear law, or across interfaces)
        when the pressure changes by less than this times the mean pressure
        (default 1e-9).
    newton_maxiter : int, optional
        Newton iteration cap (default 30).
    pressure_floor : float, optional
        Floor of the linearisation pressure where ``g'`` is infinite at 0
        (``m < 1``), in units of the mean pressure (default 1e-6).

    Attributes
    ----------
    problem : transient.problem.WearProblem
    force : float, N
        The force of the solves: the problem's ``normal_force`` unless a
        load programme's run sets the force of its current distance.
    wear_field : ndarray, shape (nx, ny)
        The wear law's field of every pixel (:meth:`at_depth`): the
        problem's, or across interfaces that of the section the face has
        worn down to.
    stage_norm : str
        ``STAGE_NORM`` when the solver was built.
    stage_share_factor : float
        ``STAGE_SHARE_FACTOR`` when the solver was built.
    solves, iterations : int
        Contact solves and contact-solver iterations done so far.
    stage_solves, most_stage_solves : int
        Newton iterations (contact solves) of the stages across interfaces:
        their sum and the most in one stage.
    warm_start : transient.warm_start.WarmStart or None
        The recent pressures of the run, the start of every implicit stage
        that asks for it (:meth:`start_warm`, :meth:`drop_warm_start`).

    Examples
    --------
    >>> import numpy as np
    >>> from steady import Circle, FacePhases, Problem, Voronoi
    >>> from transient.problem import WearProblem
    >>> grid = Circle(4e-3).grid(32)
    >>> phases = FacePhases(grid, Voronoi(64, (0.7, 0.3), seed=2029).labels(grid), 2)
    >>> solver = StageSolver(WearProblem(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6)))
    >>> res = solver.contact(np.zeros(grid.shape))
    >>> round(float(res.pressure.sum()) * grid.pixel_area, 9), solver.solves
    (10.0, 1)
    """

    def __init__(self, problem, *, contact_rtol=1e-10, contact_maxiter=None, newton_rtol=1e-9,
                 newton_maxiter=30, pressure_floor=1e-6):
        self.problem = problem
        self.contact_rtol = float(contact_rtol)
        self.contact_maxiter = contact_maxiter
        self.newton_rtol = float(newton_rtol)
        self.newton_maxiter = int(newton_maxiter)
        self.pressure_floor = float(pressure_floor)
        self.stage_norm, self.stage_share_factor = STAGE_NORM, float(STAGE_SHARE_FACTOR)
        self.force = problem.normal_force
        self.wear_field = problem.wear_field
        self.solves = self.iterations = 0
        self.stage_solves = self.most_stage_solves = 0
        self.warm_start = None
        # (x0, K x0) of the warm start implicit() predicted, for the next solve.
        self._predicted = None
        self._stage_shift = None  # the levels of the linear law's stage shifts c k

    # -- the state the solves carry --------------------------------------------
    def at_depth(self, worn_depth):
        """Take the coefficients of the section at ``worn_depth`` (m); return its segments.

        Returns
        -------
        ndarray of int, shape (nx, ny), or None
            The segment of every pixel
            (:meth:`steady.depth.DepthColumns.segment_at`); None for a
            problem without interfaces, whose field never changes.
        """
        segments, field = self.problem.section_field(worn_depth)
        if segments is not None:
            self.wear_field = field
            self._stage_shift = None
        return segments

    def start_warm(self, pressure):
        """Start the warm start from ``pressure`` (Pa) unless it holds pressures already."""
        if self.warm_start is None:
            self.warm_start = WarmStart(self.problem, pressures=pressure[None])

    def restore_warm_start(self, pressures, displacements):
        """The warm start of a checkpoint: its pressures and their ``K p``, newest first."""
        self.warm_start = (None if pressures is None else
                           WarmStart(self.problem, pressures=pressures,
                                     displacements=displacements))

    def change_force(self, force, recession, pressure):
        """Take the force ``force`` (N) for the next solves: the contact of ``recession`` under it.

        Solved from ``pressure`` (the old load's, which the solver scales
        to the new one); the warm start, whose pressures carry the old load,
        is dropped and restarts as at the start of a run.
        """
        self.force = force
        res = self.contact(recession, x0=pressure)
        self.drop_warm_start()
        return res

    def drop_warm_start(self):
        """Forget the recent pressures (a step of the load, the end of a run)."""
        self.warm_start = None

    # -- the right-hand side ---------------------------------------------------
    @property
    def mean_pressure(self):
        """The force over the face's pixel area, Pa: the mean of any admissible pressure."""
        return self.problem.pixel_mean_pressure

    def rate(self, pressure):
        """Wear rate of the law at the current section, m/m, shape (nx, ny); zero off the face."""
        return self.problem.rate(pressure, self.wear_field)

    def variable_rate(self, pressure):
        """Rate of the integration variable (:meth:`transient.problem.WearProblem.variable`).

        The wear rate ``g(p)`` (m/m) of the current section; across
        interfaces the rate of the wear work, ``g(p)`` of a unit coefficient.
        """
        if self.problem.work_depth is None:
            return self.rate(pressure)
        return self.problem.work_rate(pressure)

    def stable_step(self, pressure):
        """Largest stable explicit-Euler step at ``pressure``, m.

        ``2 / lambda_max`` with ``lambda_max <= max(g'(p)) / lambda_min(K)``;
        ``lambda_min(K)`` is bounded below by the minimum of the zero-padded
        circulant's symbol, which bounds every principal submatrix (any contact
        set) from below.
        """
        face = self.problem.face_mask
        slope = self.problem.wear.largest_rate_slope(
            pressure[face], self.wear_field[face],
            self.pressure_floor * self.problem.pixel_mean_pressure)
        return 2.0 * self.problem.compliance_floor / slope

    # -- contact solves ----------------------------------------------------------
    def contact(self, recession, *, shift=None, x0=None, x0_displacement=None, atol=0.0,
                preconditioner="auto"):
        """One contact solve under :attr:`force`, counted; :class:`StepFailure` on failure.

        Parameters
        ----------
        recession : ndarray, shape (nx, ny), m
        shift : ndarray, shape (nx, ny), m/Pa, optional
        x0 : ndarray, shape (nx, ny), Pa, optional
            Warm start.
        x0_displacement : ndarray, shape (nx, ny), m, optional
            ``K x0``, if known (see :func:`transient.contact.solve_contact`);
            default: the one :meth:`implicit` predicted along with ``x0``.
        atol : float, m, optional
            Absolute tolerance of the solve beside ``contact_rtol`` (default
            0: ``contact_rtol`` alone; see
            :func:`transient.control.contact_tolerance`).  A positive one is
            taken times ``STAGE_SHARE_FACTOR`` in the norm ``STAGE_NORM``.
        preconditioner : str or callable, optional
            As :func:`transient.contact.solve_contact` takes it (default
            ``"auto"``).

        Returns
        -------
        transient.contact.ContactResult
        """
        problem = self.problem
        if not np.all(np.isfinite(recession[problem.face_mask])):
            raise StepFailure("non-finite face recession")
        predicted, self._predicted = self._predicted, None
        if x0_displacement is None and predicted is not None and predicted[0] is x0:
            x0_displacement = predicted[1]
        norm = "rms"
        if atol > 0:
            atol, norm = atol * self.stage_share_factor, self.stage_norm
        res = solve_trusted_contact(problem.halfspace, problem.face_mask, recession, self.force,
                                    shift=shift, x0=x0, x0_displacement=x0_displacement,
                                    rtol=self.contact_rtol, atol=atol, norm=norm,
                                    maxiter=self.contact_maxiter, preconditioner=preconditioner)
        self.solves += 1
        self.iterations += int(res.nit)
        if not res.success:
            raise StepFailure(f"contact solve failed: {res.message} "
                              f"(nit={res.nit}, residual={res.residual:.3g})")
        if not (np.all(np.isfinite(res.pressure)) and np.isfinite(res.approach)):
            raise StepFailure("contact solve returned non-finite pressure")
        return res

    def _rebuild(self, recession, c, res, coefficients=None):
        """Face and contact of an implicit stage ``w = recession + c g(P(w))``.

        On the contact the face is rebuilt as ``d - K p``, with the solver's
        own ``K p`` (kept apart from the shift's part, so exact to the
        round-off of ``K p`` whatever the shift) and ``d`` the mean of
        ``recession + c g(p) + K p`` there: the solver's residual, which scales
        with the shifted operator and so with ``c``, is projected out of the
        shape (it would reach ``rtol * ds / s*`` of ``f*`` after a jump),
        while the rigid part keeps the exact mean of the update.
        """
        p = res.pressure
        contact = self.problem.face_mask & (p > 0)
        if coefficients is None:
            w = recession + c * self.rate(p)
        else:
            w = recession + c * self.problem.wear.rate(p, coefficients)
        kp = res.elastic_displacement
        if not contact.any():
            return w, res
        d = float(np.mean((w + kp)[contact]))
        w = np.where(contact, d - kp, w)
        return w, dataclasses.replace(res, approach=d)

    def _linearisation(self, recession, c, p0, field=None):
        """Shift and recession of the stage linearised about ``p0`` (the law's linearisation)."""
        problem = self.problem
        return problem.wear.linearisation(
            recession, c, p0, self.wear_field if field is None else field,
            problem.face_mask, self.pressure_floor * problem.pixel_mean_pressure)

    def implicit(self, recession, c, x0, *, warm=True, atol=0.0, origin=None):
        """Solve the implicit stage ``w = recession + c g(P(w))`` for ``w``.

        Across interfaces (:attr:`transient.problem.WearProblem.work_depth`)
        ``recession`` and ``w`` are wear works and the stage is
        ``R = recession + c g(P(origin + D(R)))`` (:meth:`_implicit_work`).

        Parameters
        ----------
        recession : ndarray, shape (nx, ny), m
        c : float, m
            Sliding distance multiplying the implicit rate (``ds``, ``gamma ds``...).
        x0 : ndarray, shape (nx, ny), Pa
            Pressure guess (start and first linearisation point), used when
            the warm start is not asked for or holds no pressure.
        warm : bool, optional
            Start from the Galerkin combination of the recent pressures
            (:meth:`transient.warm_start.WarmStart.predict`), and add the
            stage's pressure to them (default True; a jump to the steady
            state starts from its own guess).
        atol : float, m, optional
            Absolute tolerance of the contact solve (default 0; see
            :meth:`contact`).  Each solve of a Newton iteration takes it too:
            its test compares successive pressures to ``newton_rtol``, so the
            caller keeps it 0 there.
        origin : ndarray, shape (nx, ny), m, optional
            The recession of zero worn depth
            (:meth:`transient.problem.WearProblem.variable`); needed across
            interfaces only.

        Returns
        -------
        w : ndarray, shape (nx, ny), m
        result : ContactResult
            The contact of the face ``w`` (its pressure is ``P(w)``).
        """
        history = self.warm_start if warm else None
        if self.problem.work_depth is not None:
            return self._implicit_work(recession, c, x0, history, atol, origin)
        if self.problem.wear.linear:
            res = self._linear_stage(recession, c, x0, history, atol)
        else:
            res = self._newton_stage(recession, c, x0, history, atol)
        w, res = self._rebuild(recession, c, res)
        if history is not None:
            history.push(res.pressure, res.elastic_displacement)
        return w, res

    def _linear_stage(self, recession, c, x0, history, atol):
        """The stage of the linear law: one solve with the shift ``c k``."""
        field = self.wear_field
        shift = c * field
        if history is not None and len(history):
            x0, kx0 = history.predict(recession, shift_scale=c)
            self._predicted = (x0, kx0)
        if self._stage_shift is None:
            self._stage_shift = ScaledShift(self.problem.halfspace, self.problem.face_mask,
                                            field)
        return self.contact(recession, shift=shift, x0=x0, atol=atol,
                            preconditioner=self._stage_shift.preconditioner(c, shift))

    def _newton_stage(self, recession, c, x0, history, atol):
        """The stage of a nonlinear law: Newton's method, a shifted solve per iteration."""
        pbar = self.problem.pixel_mean_pressure
        p0 = np.asarray(x0, dtype=float)
        if history is not None and len(history):
            # The stage linearised about the newest pressure predicts the
            # first linearisation point.
            shift, h_lin = self._linearisation(recession, c, history.newest())
            p0, kx0 = history.predict(h_lin, shift)
            self._predicted = (p0, kx0)
        for _ in range(self.newton_maxiter):
            shift, h_lin = self._linearisation(recession, c, p0)
            res = self.contact(h_lin, shift=shift, x0=p0, atol=atol)
            change = float(np.max(np.abs(res.pressure - p0))) / pbar
            p0 = res.pressure
            if change <= self.newton_rtol:
                return res
        raise StepFailure(f"Newton iteration of the wear law did not converge in "
                          f"{self.newton_maxiter} iterations (last change {change:.3g} pbar)")

    def _implicit_work(self, known, c, x0, history, atol, origin):
        """The stage ``R = known + c g(P(origin + D(R)))`` in the wear work, by Newton's method.

        ``D`` is linearised about the iterate, the line of its segment
        (slope ``k``), and ``g`` about the last pressure: each iteration
        is the shifted contact problem of a columnar stage with the
        coefficients ``k`` of the iterate's segments, the first iterate's
        those that the warm start's predicted pressure reaches (so that a
        crossing it foresees costs no second solve).  Semismooth Newton on
        the piecewise-linear ``D``: it ends once no pixel changes segment
        (then the linearisation is exact for the linear law) and, for
        another law, the pressure changes by less than ``newton_rtol``; at
        most ``newton_maxiter`` iterations, else :class:`StepFailure`.
        """
        problem = self.problem
        work, wear = problem.work_depth, problem.wear
        p0 = history.newest() if history is not None and len(history) else np.asarray(x0, float)
        guess = known + c * self.variable_rate(p0)
        segments = work.segment(guess)
        start = p0
        for iteration in range(1, self.newton_maxiter + 1):
            k = work.slope(segments)
            # origin + D(R_i) + k (R - R_i) with R = known + c g(p):
            base = origin + work.depth(guess, segments) + k * (known - guess)
            shift, h_lin = self._linearisation(base, c, p0, k)
            if iteration == 1 and history is not None and len(history):
                # The solver computes K x0 itself: the combination's own, with
                # the large weights of the pressures of a wear-through, carries
                # their round-off, which the solve returned in its K p and the
                # next combination amplified, to per cent of K x0 and wrong
                # stage pressures (tests/test_depth_run.py).
                start, _ = history.predict(h_lin, shift)
                # The segments the predicted pressure reaches: the stage's crossings
                # seen before its first solve rather than after it, which would
                # cost a second one (docs/benchmarks.md, "Runs across interfaces").
                ahead = known + c * self.variable_rate(np.maximum(start, 0.0))
                predicted = work.segment(ahead)
                if np.any(predicted != segments):
                    segments, guess = predicted, ahead
                    k = work.slope(segments)
                    base = origin + work.depth(guess, segments) + k * (known - guess)
                    shift, h_lin = self._linearisation(base, c, p0, k)
                    start, _ = history.predict(h_lin, shift)
                if not wear.linear:
                    p0 = start
                    shift, h_lin = self._linearisation(base, c, p0, k)
            res = self.contact(h_lin, shift=shift, x0=start, atol=atol)
            change = float(np.max(np.abs(res.pressure - p0))) / problem.pixel_mean_pressure
            p0 = start = res.pressure
            guess = known + c * self.variable_rate(p0)
            moved = work.segment(guess)
            changing = int(np.count_nonzero(moved != segments))
            segments = moved
            if changing == 0 and (wear.linear or change <= self.newton_rtol):
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
        return work.work(np.where(problem.face_mask, w - origin, 0.0)), res
