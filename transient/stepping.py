"""Time integrators for the run-in wear of a punch on an elastic half-space.

The discretised run-in is the system (docs/model.md, "Wear and time integration")

    dw/ds = k p^m,        p = P(w),

where ``w`` (m, shape (nx, ny)) is the recession of the punch face -- worn depth
plus initial shape, larger = recessed, defined up to a constant (the run
keeps its face mean in a separate offset) --, ``k`` the wear coefficient of
each pixel's phase (1/Pa for ``m = 1``, Pa^-m in general), ``m`` the wear
exponent and
``P(w)`` the pressure of the unilateral contact under the prescribed normal
force.  ``P`` is not a smooth function of ``w``: the pressure is the
multiplier of a complementarity problem, so the system is a differential
complementarity system.  While the contact set does not change it is an
index-1 DAE (the pressure is the algebraic variable), linear for ``m = 1``;
its eigenvalues span ``k E*/a`` (the run-in) to ``k_max E*/h`` (one pixel),
so it is stiff, and stiffer with refinement and with the wear ratio.

Schemes
-------
Every scheme is registered by name with the class decorator
:func:`register_scheme` (:data:`SCHEMES`, :func:`get_scheme`); it steps a
:class:`transient.problem.WearProblem` through the run's stage solver
(:class:`transient.solver.StageSolver`), which solves its contact problems:

``explicit_euler``
    ``w+ = w + ds k P(w)^m``: one unshifted contact solve per step; stable
    only for ``ds < 2 lambda_min(K) / max(k m p^(m-1))`` (about
    ``1.16 h / (k_max E*)`` for ``m = 1``, see
    :meth:`transient.solver.StageSolver.stable_step`).
    A step beyond that limit is refused.
``implicit_euler``
    ``w+ = w + ds k P(w+)^m``: the step *is* a contact problem with the
    operator ``K + ds diag(k)`` (one shifted solve for ``m = 1``).  L-stable,
    first order.  As ``ds -> infinity`` its pressure tends to the steady
    pressure ``k p^m = C`` (eq. 3-7): one huge step lands on the steady state.
``bdf2``
    Variable-step BDF2: one shifted solve per step, second order, L-stable
    at constant step (zero-stable for step ratios below ``1 + sqrt 2``, so
    the growth per step is capped at 2.4).
``sdirk2``
    Alexander's two-stage, stiffly accurate, L-stable SDIRK
    (``gamma = 1 - 1/sqrt 2``): two shifted solves per step, second order,
    with an embedded first-order estimate.
``esdirk3``
    Kennedy & Carpenter's ESDIRK3(2)4L[2]SA: three shifted solves per
    step, third order, L-stable, with an embedded second-order estimate.
``esdirk4``
    Their ESDIRK4(3)6L[2]SA: five shifted solves per step, fourth order,
    L-stable, with an embedded third-order estimate.

Stiffly accurate schemes (every implicit one) end a step with the
pressure of the new face, ``p+ = P(w+)``, so the differential variable
keeps its classical order on the index-1 DAE; where the contact set
changes during a step the solution is only Lipschitz in ``s`` and every
scheme drops to first order locally.

Across interfaces (phases that change with depth below the face) the
schemes integrate the wear work ``R`` of the face instead of its recession,
``dR/ds = P(w)^m`` with ``w = w0 + D(R)`` (docs/model.md, "Wear across
interfaces"), through the problem's hooks
:meth:`~transient.problem.WearProblem.variable`, ``face`` and
``depth_error`` and the solver's ``variable_rate``, which are the identity
(the wear rate) for a columnar problem; the state's ``origin`` is the
recession of zero worn depth.

Power-law wear (``m != 1``) is treated in every implicit stage by Newton's
method on ``w = w0 + c k P(w)^m``: ``k p^m`` is linearised about the last
pressure iterate ``p0``, ``k p^m ~ k p0^m + k m p0^(m-1) (p - p0)``, which is
again a shifted contact problem with ``shift = c k m p0^(m-1)`` and recession
``w0 + c k (1 - m) p0^m``.  The iteration stops when the pressure changes by
less than ``newton_rtol`` (relative to the mean pressure), each solve
warm-started from the last (solves per stage: docs/benchmarks.md, "Run-in
stepping").  For ``m < 1``
the derivative is unbounded at ``p = 0``; ``p0`` is floored at
``pressure_floor`` times the mean pressure in the linearisation only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from steady.registry import Registry

__all__ = [
    "BDF2",
    "ESDIRK3",
    "ESDIRK4",
    "ExplicitEuler",
    "ImplicitEuler",
    "SCHEMES",
    "SDIRK2",
    "Scheme",
    "StepState",
    "Trial",
    "get_scheme",
    "register_scheme",
]

SCHEMES = Registry("scheme", entry_point_group="runin.schemes")
"""Registered integrators by name, instances of :class:`Scheme` (see :func:`register_scheme`)."""


def register_scheme(cls):
    """Class decorator: register an instance of a :class:`Scheme` under its ``name``."""
    if not cls.name:
        raise ValueError(f"scheme {cls.__name__} has no name")
    SCHEMES.register(cls.name, cls())
    return cls


def get_scheme(name):
    """The registered scheme called ``name``: ``SCHEMES[name]``.

    Raises
    ------
    ValueError
        If no scheme has that name (the message lists the registered ones).
    """
    return SCHEMES[name]


@dataclasses.dataclass(frozen=True)
class StepState:
    """An accepted point of the run-in, everything a scheme needs to step on.

    Attributes
    ----------
    recession : ndarray, shape (nx, ny), m
        Face recession ``w`` (worn depth + initial shape, up to a constant).
    pressure : ndarray, shape (nx, ny), Pa
        ``P(w)``, the contact pressure of that face.
    approach : float, m
        Rigid approach of that contact (same constant as ``recession``).
    previous_recession : ndarray, shape (nx, ny), m, or None
        Face at the previous accepted point (multistep schemes, shape-change test).
    previous_rate : ndarray, shape (nx, ny), or None
        ``k p^m`` there.
    previous_step : float, m, or None
        The step that led from there to here.
    warm : bool
        Whether every implicit stage starts from the solver's warm start of
        the recent pressures and adds its own to them
        (:meth:`transient.solver.StageSolver.implicit`; default True);
        False: each stage starts from the pressure before it (a jump to the
        steady state).
    contact_atol : float, m
        Absolute tolerance of the step's contact solves (their ``atol``, see
        :func:`transient.contact.solve_contact`; the solver's
        ``contact_rtol`` holds beside it): what the step's error control and
        the wear-rate spread leave to the solves
        (:func:`transient.control.contact_tolerance`).  Default 0: every
        solve to ``contact_rtol``.
    origin : ndarray, shape (nx, ny), m, or None
        Height of zero worn depth (``initial_recession - offset``), in the frame
        of ``recession`` and ``previous_recession``: across interfaces the scheme
        integrates the wear work of the face
        (:meth:`transient.problem.WearProblem.variable`); None: columnar.
    """

    recession: np.ndarray
    pressure: np.ndarray
    approach: float
    previous_recession: np.ndarray | None = None
    previous_rate: np.ndarray | None = None
    previous_step: float | None = None
    warm: bool = True
    contact_atol: float = 0.0
    origin: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class Trial:
    """Outcome of one attempted step.

    Attributes
    ----------
    recession : ndarray, shape (nx, ny), m
        New face ``w+``.
    pressure : ndarray, shape (nx, ny), Pa
        ``P(w+)``.
    approach : float, m
    contact_fraction : float
    error : ndarray, shape (nx, ny), m
        Local error estimate of ``w+``.
    """

    recession: np.ndarray
    pressure: np.ndarray
    approach: float
    contact_fraction: float
    error: np.ndarray


class Scheme:
    """Base class of a registered time integrator.

    Attributes
    ----------
    name : str
    order : int
        Classical order of the solution.
    error_order : int
        The error estimate scales as ``ds^(error_order + 1)``.
    max_growth : float
        Largest step ratio the scheme tolerates.
    explicit : bool
    """

    name = ""
    order = 1
    error_order = 1
    max_growth = 5.0
    explicit = False

    def step(self, solver, state, ds):
        """Attempt one step of length ``ds`` from ``state``.

        Parameters
        ----------
        solver : transient.solver.StageSolver
            The run's contact solves on its problem (``solver.problem``).
        state : StepState
            The accepted point to step from.
        ds : float, m
            Sliding distance of the step, positive.

        Returns
        -------
        Trial
            The new face, its contact and the local error estimate.

        Raises
        ------
        transient.solver.StepFailure
            A contact solve failed or a value turned non-finite; the caller
            retries with a smaller step.
        """
        raise NotImplementedError

    def __repr__(self):
        """``<ClassName 'name', order k>``."""
        return f"<{type(self).__name__} {self.name!r}, order {self.order}>"


def _trial(solver, state, variable, res, error):
    """The trial of a step that ended at ``variable`` with local error ``error`` of it."""
    problem = solver.problem
    return Trial(recession=problem.face(variable, state.origin), pressure=res.pressure,
                 approach=float(res.approach), contact_fraction=float(res.contact_fraction),
                 error=problem.depth_error(error, variable))


def _implicit(solver, state, base, c, x0):
    """One implicit stage ``y = base + c f(y)`` of a step from ``state``: ``(y, contact)``."""
    return solver.implicit(base, c, x0, warm=state.warm, atol=state.contact_atol,
                           origin=state.origin)


def _variable(solver, state, recession):
    """The integration variable of the face ``recession`` (m) in the frame of ``state``."""
    return solver.problem.variable(recession, state.origin)


@register_scheme
class ExplicitEuler(Scheme):
    """Forward Euler, ``w+ = w + ds k P(w)^m``; refuses steps beyond the stability limit."""

    name = "explicit_euler"
    order = 1
    error_order = 1
    explicit = True

    def step(self, solver, state, ds):
        """One forward Euler step (see :meth:`Scheme.step`).

        The error estimate is ``ds/2`` times the change of the rate over the
        step.  A step beyond :meth:`~transient.solver.StageSolver.stable_step`
        raises ``ValueError``.
        """
        limit = solver.stable_step(state.pressure)
        if ds > limit * (1.0 + 1e-12):
            raise ValueError(f"explicit Euler step {ds!r} m exceeds its stability limit "
                             f"{limit:.6g} m (2 lambda_min(K) / max k m p^(m-1))")
        f0 = solver.variable_rate(state.pressure)
        y = _variable(solver, state, state.recession) + ds * f0
        res = solver.contact(solver.problem.face(y, state.origin), x0=state.pressure,
                             atol=state.contact_atol)
        error = 0.5 * ds * (solver.variable_rate(res.pressure) - f0)
        return _trial(solver, state, y, res, error)


@register_scheme
class ImplicitEuler(Scheme):
    """Backward Euler: the step is the contact problem with ``K + ds diag(k)``."""

    name = "implicit_euler"
    order = 1
    error_order = 1

    def step(self, solver, state, ds):
        """One backward Euler step, a shifted contact solve (see :meth:`Scheme.step`).

        The error estimate is ``ds/2`` times the change of the rate over the step.
        """
        f0 = solver.variable_rate(state.pressure)
        y, res = _implicit(solver, state, _variable(solver, state, state.recession), ds,
                           state.pressure)
        error = 0.5 * ds * (solver.variable_rate(res.pressure) - f0)
        return _trial(solver, state, y, res, error)


@register_scheme
class BDF2(Scheme):
    """Variable-step BDF2 (first step implicit Euler).

    With ``omega = ds / ds_prev``::

        w+ = ((1 + omega)^2 w - omega^2 w_prev) / (1 + 2 omega)
             + ds (1 + omega) / (1 + 2 omega) k P(w+)^m

    The local error is estimated by comparison with the second-order
    Adams-Bashforth predictor, ``err ~ C (w+ - w_AB2)`` with the
    constant-step ratio ``C = (2/9) / (2/9 + 5/12) = 8/23``.
    """

    name = "bdf2"
    order = 2
    error_order = 2
    max_growth = 2.4

    def step(self, solver, state, ds):
        """One BDF2 step, or implicit Euler without a previous point (see :meth:`Scheme.step`)."""
        f0 = solver.variable_rate(state.pressure)
        if state.previous_recession is None:
            return SCHEMES["implicit_euler"].step(solver, state, ds)
        omega = ds / state.previous_step
        y0 = _variable(solver, state, state.recession)
        base = ((1 + omega) ** 2 * y0
                - omega ** 2 * _variable(solver, state, state.previous_recession)
                ) / (1 + 2 * omega)
        beta = (1 + omega) / (1 + 2 * omega)
        y, res = _implicit(solver, state, base, beta * ds, state.pressure)
        predictor = y0 + ds * ((1 + 0.5 * omega) * f0 - 0.5 * omega * state.previous_rate)
        error = (8.0 / 23.0) * (y - predictor)
        return _trial(solver, state, y, res, error)


@register_scheme
class SDIRK2(Scheme):
    """Alexander's L-stable, stiffly accurate two-stage SDIRK, ``gamma = 1 - 1/sqrt 2``.

    Stages ``W1 = w + gamma ds f(W1)``, ``w+ = W2 = w + ds((1 - gamma) f(W1) +
    gamma f(W2))``, each a shifted contact solve (shift ``gamma ds k``).
    Embedded first-order solution ``w + ds f(W1)``: ``err = gamma ds (f(W2) - f(W1))``.
    """

    name = "sdirk2"
    order = 2
    error_order = 1
    gamma = 1.0 - 1.0 / math.sqrt(2.0)

    def step(self, solver, state, ds):
        """One SDIRK2 step, two shifted contact solves (see :meth:`Scheme.step`)."""
        g = self.gamma
        y0 = _variable(solver, state, state.recession)
        _, res1 = _implicit(solver, state, y0, g * ds, state.pressure)
        f1 = solver.variable_rate(res1.pressure)
        base = y0 + (1 - g) * ds * f1
        y, res2 = _implicit(solver, state, base, g * ds, res1.pressure)
        error = g * ds * (solver.variable_rate(res2.pressure) - f1)
        return _trial(solver, state, y, res2, error)


def _esdirk3_tableau():
    """Kennedy & Carpenter's ESDIRK3(2)4L[2]SA: ``gamma``, ``A`` (4 x 4), ``b``, ``b_hat``.

    ``gamma`` is the root of ``6 g^3 - 18 g^2 + 9 g - 1`` that makes the
    method L-stable; ``c = (0, 2 gamma, 3/5, 1)``; the last row of ``A`` is
    ``b`` (stiffly accurate); ``b_hat`` is the embedded second-order method
    (A-stable, ``R(inf) = 0.218``).  Appl. Numer. Math. 44 (2003) 139-181,
    doi:10.1016/S0168-9274(02)00138-1, table of ARK3(2)4L[2]SA.
    """
    g = 0.43586652150845899941601945
    c3 = 0.6
    a = np.zeros((4, 4))
    a[1, :2] = g
    a[2, 1] = c3 * (c3 - 2 * g) / (4 * g)
    a[2, 0] = c3 - a[2, 1] - g
    a[2, 2] = g
    b3 = (1 - 6 * g + 6 * g * g) / (3 * c3 * (c3 - 2 * g))
    b2 = (-2 + 3 * c3 + 6 * g * (1 - c3)) / (12 * g * (c3 - 2 * g))
    a[3] = (1 - b2 - b3 - g, b2, b3, g)
    b_hat = np.array([926040629867 / 8503851176844, -19534562426408 / 21341649249991,
                      17036650473653 / 13401246206802, 4543788980243 / 8490594148910])
    return g, a, a[3].copy(), b_hat


class _ESDIRK(Scheme):
    """An explicit-first-stage, stiffly accurate DIRK written as its table.

    Subclasses set ``gamma``, ``a`` (s x s, lower triangular, ``a[0] = 0``,
    ``a[i, i] = gamma`` for ``i >= 1``, last row ``b``), ``b`` and ``b_hat``.
    The first stage is the rate of the accepted point, so a step costs
    ``s - 1`` shifted contact solves, all with the shift ``gamma ds k``::

        W_i = w + ds sum_{j<i} a_ij f(W_j) + gamma ds f(W_i),   i = 1 .. s-1,
        w+ = W_(s-1).

    Each stage starts from the pressure of the one before.  The embedded
    weights ``b_hat`` give the error estimate ``ds sum_i (b_i - b_hat_i)
    f(W_i)``, of order ``ds^(error_order + 1)``.
    """

    gamma = a = b = b_hat = None

    def step(self, solver, state, ds):
        """One step, ``s - 1`` shifted contact solves (see :meth:`Scheme.step`)."""
        stages = len(self.b)
        rates = [solver.variable_rate(state.pressure)]
        y0 = _variable(solver, state, state.recession)
        x0 = state.pressure
        for i in range(1, stages):
            base = y0 + ds * sum(self.a[i, j] * rates[j] for j in range(i))
            y, res = _implicit(solver, state, base, self.gamma * ds, x0)
            rates.append(solver.variable_rate(res.pressure))
            x0 = res.pressure
        weights = self.b - self.b_hat
        error = ds * sum(weights[j] * rates[j] for j in range(stages))
        return _trial(solver, state, y, res, error)


@register_scheme
class ESDIRK3(_ESDIRK):
    """Kennedy & Carpenter's ESDIRK3(2)4L[2]SA: third order, L-stable, stiffly accurate.

    Four stages with ``c = (0, 2 gamma, 3/5, 1)``, ``gamma = 0.4358665``; the
    first is explicit and is the rate of the accepted point, so a step costs
    three shifted contact solves, all with the same shift ``gamma ds k``
    (:class:`_ESDIRK`).  Stage order 2.  The embedded second-order weights
    ``b_hat`` give an error estimate of order ``ds^3``.
    """

    name = "esdirk3"
    order = 3
    error_order = 2
    gamma, a, b, b_hat = _esdirk3_tableau()


def _esdirk4_tableau():
    """Kennedy & Carpenter's ESDIRK4(3)6L[2]SA: ``gamma``, ``A`` (6 x 6), ``b``, ``b_hat``.

    The implicit part of their ARK4(3)6L[2]SA: ``gamma = 1/4``,
    ``c = (0, 1/2, 83/250, 31/50, 17/20, 1)``, stiffly accurate (the last
    row of ``A`` is ``b``), L-stable, stage order 2; ``b_hat`` is the
    embedded third-order method.  Appl. Numer. Math. 44 (2003) 139-181,
    doi:10.1016/S0168-9274(02)00138-1, table of ARK4(3)6L[2]SA.
    """
    g = 0.25
    a = np.zeros((6, 6))
    a[1, 0] = g
    a[2, :2] = (8611 / 62500, -1743 / 31250)
    a[3, :3] = (5012029 / 34652500, -654441 / 2922500, 174375 / 388108)
    a[4, :4] = (15267082809 / 155376265600, -71443401 / 120774400,
                730878875 / 902184768, 2285395 / 8070912)
    a[5, :5] = (82889 / 524892, 0.0, 15625 / 83664, 69875 / 102672, -2260 / 8211)
    for i in range(1, 6):
        a[i, i] = g
    b_hat = np.array([4586570599 / 29645900160, 0.0, 178811875 / 945068544,
                      814220225 / 1159782912, -3700637 / 11593932, 61727 / 225920])
    return g, a, a[5].copy(), b_hat


@register_scheme
class ESDIRK4(_ESDIRK):
    """Kennedy & Carpenter's ESDIRK4(3)6L[2]SA: fourth order, L-stable, stiffly accurate.

    Six stages with ``c = (0, 1/2, 83/250, 31/50, 17/20, 1)``,
    ``gamma = 1/4``: five shifted contact solves a step, all with the shift
    ``ds k / 4`` (:class:`_ESDIRK`).  Stage order 2.  The embedded
    third-order weights ``b_hat`` give an error estimate of order ``ds^4``.
    """

    name = "esdirk4"
    order = 4
    error_order = 3
    gamma, a, b, b_hat = _esdirk4_tableau()
