"""Time integrators for the run-in wear of a punch on an elastic half-space.

The discretised run-in is the system (PHYSICS.md, "Wear" and "Contact")

    dw/ds = k p^m,        p = P(w),

where ``w`` (m, shape (n, n)) is the height of the punch face above its lowest
point -- worn depth plus initial shape, larger = recessed --, ``k`` the wear
coefficient of each pixel's phase (1/Pa), ``m`` the wear exponent and
``P(w)`` the pressure of the unilateral contact under the prescribed normal
force.  ``P`` is not a smooth function of ``w``: the pressure is the
multiplier of a complementarity problem, so the system is a differential
complementarity system.  While the contact set does not change it is an
index-1 DAE (the pressure is the algebraic variable), linear for ``m = 1``;
its eigenvalues span ``k E*/a`` (the run-in) to ``k_max E*/h`` (one pixel),
so it is stiff, and stiffer with refinement and with the wear ratio.

Schemes
-------
Every scheme is registered by name (:data:`SCHEMES`, :func:`get_scheme`):

``explicit_euler``
    ``w+ = w + ds k P(w)^m``: one unshifted contact solve per step; stable
    only for ``ds < 2 lambda_min(K) / max(k m p^(m-1))`` (about
    ``1.16 h / (k_max E*)`` for ``m = 1``, see :meth:`WearProblem.stable_step`).
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

Stiffly accurate schemes (all three implicit ones) end a step with the
pressure of the new face, ``p+ = P(w+)``, so the differential variable
keeps its classical order on the index-1 DAE; where the contact set
changes during a step the solution is only Lipschitz in ``s`` and every
scheme drops to first order locally.

Power-law wear (``m != 1``) is treated in every implicit stage by Newton's
method on ``w = w0 + c k P(w)^m``: ``k p^m`` is linearised about the last
pressure iterate ``p0``, ``k p^m ~ k p0^m + k m p0^(m-1) (p - p0)``, which is
again a shifted contact problem with ``shift = c k m p0^(m-1)`` and height
``w0 + c k (1 - m) p0^m``.  The iteration stops when the pressure changes by
less than ``newton_rtol`` (relative to the mean pressure); measured: about
three solves per stage for ``m = 2`` and ``m = 0.5`` (Voronoi face, n = 32,
``k_2/k_1 = 10``), each warm-started from the last.  For ``m < 1``
the derivative is unbounded at ``p = 0``; ``p0`` is floored at
``pressure_floor`` times the mean pressure in the linearisation only.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from .contact import solve_contact

__all__ = [
    "BDF2",
    "ExplicitEuler",
    "ImplicitEuler",
    "SCHEMES",
    "SDIRK2",
    "Scheme",
    "StepFailure",
    "StepState",
    "Trial",
    "WearProblem",
    "get_scheme",
    "register_scheme",
]

logger = logging.getLogger(__name__)

# Lower bound of the eigenvalues of the pixel influence matrix, in units of
# h / E*: the minimum of the symbol of the zero-padded circulant (which
# bounds every principal submatrix from below).  Used only when the
# half-space does not expose its spectrum.
_MIN_SYMBOL = 0.5806


class StepFailure(RuntimeError):
    """A step could not be completed (contact solver failed, non-finite values,
    Newton iteration did not converge); the caller retries with a smaller step."""


class WearProblem:
    """The discretised wear system ``dw/ds = k P(w)^m`` on one grid.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
        Elastic half-space operator of the grid (n pixels, pixel size h).
    wear : ndarray, shape (n, n), 1/Pa
        Wear coefficient ``k`` of each pixel's phase; ignored off the face.
    face : ndarray of bool, shape (n, n)
        Pixels of the punch face.
    normal_force : float, N
        Prescribed normal force ``F_N``.
    radius : float, m
        Punch radius ``a`` (sets the natural scales).
    exponent : float, optional
        Wear exponent ``m`` (default 1, Archard).
    contact_rtol : float, optional
        Relative tolerance of every contact solve (default 1e-10).
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
    solves : int
        Contact solves done so far (counter, for work accounting).
    iterations : int
        Contact-solver iterations done so far.
    """

    def __init__(self, halfspace, wear, face, normal_force, radius, *, exponent=1.0,
                 contact_rtol=1e-10, contact_maxiter=None, newton_rtol=1e-9,
                 newton_maxiter=30, pressure_floor=1e-6):
        n = halfspace.n
        face = np.asarray(face, dtype=bool)
        wear = np.asarray(wear, dtype=float)
        if face.shape != (n, n) or wear.shape != (n, n):
            raise ValueError(f"face and wear must have shape {(n, n)}, got {face.shape} "
                             f"and {wear.shape}")
        if not face.any():
            raise ValueError("face has no pixel")
        kf = wear[face]
        if not (np.all(np.isfinite(kf)) and np.all(kf > 0)):
            raise ValueError(f"wear coefficients must be positive and finite on the face, "
                             f"got range [{kf.min()!r}, {kf.max()!r}] 1/Pa")
        if not (np.isfinite(normal_force) and normal_force > 0):
            raise ValueError(f"normal_force must be positive, got {normal_force!r} N")
        if not (np.isfinite(radius) and radius > 0):
            raise ValueError(f"radius must be positive, got {radius!r} m")
        if not (np.isfinite(exponent) and exponent > 0):
            raise ValueError(f"wear exponent must be positive, got {exponent!r}")
        self.halfspace = halfspace
        self.n = n
        self.face = face
        self.wear = np.where(face, wear, 0.0)
        self.normal_force = float(normal_force)
        self.radius = float(radius)
        self.exponent = float(exponent)
        self.contact_rtol = float(contact_rtol)
        self.contact_maxiter = contact_maxiter
        self.newton_rtol = float(newton_rtol)
        self.newton_maxiter = int(newton_maxiter)
        self.pressure_floor = float(pressure_floor)
        self.area = float(face.sum()) * halfspace.h ** 2
        self.solves = 0
        self.iterations = 0

    # -- natural scales (PHYSICS.md) ------------------------------------
    @property
    def mean_pressure(self):
        """``pbar = F_N / A`` over the face, Pa."""
        return self.normal_force / self.area

    @property
    def depth_scale(self):
        """``f* = pbar a / E*``, m."""
        return self.mean_pressure * self.radius / self.halfspace.E_star

    @property
    def run_in_distance(self):
        """``s* = a / (k_min E*)``, m: the slow (run-in) sliding distance.

        For ``m != 1`` the rate constant is ``k m pbar^(m-1)``.
        """
        return self.radius / (self._rate_constant(self.wear[self.face].min())
                              * self.halfspace.E_star)

    @property
    def fast_distance(self):
        """``h / (k_max E*)``, m: the fastest (one-pixel) relaxation distance."""
        return self.halfspace.h / (self._rate_constant(self.wear[self.face].max())
                                   * self.halfspace.E_star)

    def _rate_constant(self, k):
        m = self.exponent
        return k * m * self.mean_pressure ** (m - 1.0)

    def steady_pressure(self):
        """Closed-form steady pressure ``k_i p_i^m = C`` under the load (eq. 7), Pa, shape (n, n).

        The limit of an implicit Euler step as ``ds -> infinity``: the warm
        start of a jump.
        """
        k = self.wear[self.face]
        p = np.zeros((self.n, self.n))
        p[self.face] = (k / k.min()) ** (-1.0 / self.exponent)
        return p * (self.normal_force / (p.sum() * self.halfspace.h ** 2))

    # -- the right-hand side -------------------------------------------
    def rate(self, pressure):
        """Wear rate ``k p^m``, m/m (dimensionless), shape (n, n); zero off the face."""
        p = np.maximum(pressure, 0.0)
        if self.exponent == 1.0:
            return self.wear * p
        return self.wear * p ** self.exponent

    def stable_step(self, pressure):
        """Largest stable explicit-Euler step at ``pressure``, m.

        ``2 / lambda_max`` with ``lambda_max <= max(k m p^(m-1)) / lambda_min(K)``;
        ``lambda_min(K)`` is bounded below by the minimum of the zero-padded
        circulant's symbol, which bounds every principal submatrix (any contact
        set) from below.
        """
        spectrum = getattr(self.halfspace, "influence_symbol", None)
        if spectrum is not None:
            lam_min = float(np.min(spectrum))
        else:
            lam_min = _MIN_SYMBOL * self.halfspace.h / self.halfspace.E_star
        m = self.exponent
        if m == 1.0:
            slope = float(self.wear[self.face].max())
        else:
            p = np.maximum(pressure[self.face], self.pressure_floor * self.mean_pressure)
            slope = float(np.max(self.wear[self.face] * m * p ** (m - 1.0)))
        return 2.0 * lam_min / slope

    # -- contact solves ------------------------------------------------
    def contact(self, height, *, shift=None, x0=None):
        """One contact solve, counted; raises :class:`StepFailure` on failure.

        Parameters
        ----------
        height : ndarray, shape (n, n), m
        shift : ndarray, shape (n, n), m/Pa, optional
        x0 : ndarray, shape (n, n), Pa, optional
            Warm start.

        Returns
        -------
        transient.contact.ContactResult
        """
        if not np.all(np.isfinite(height[self.face])):
            raise StepFailure("non-finite face height")
        res = solve_contact(self.halfspace, self.face, height, self.normal_force,
                            shift=shift, x0=x0, rtol=self.contact_rtol,
                            maxiter=self.contact_maxiter)
        self.solves += 1
        self.iterations += int(res.nit)
        if not res.success:
            raise StepFailure(f"contact solve failed: {res.message} "
                              f"(nit={res.nit}, residual={res.residual:.3g})")
        if not (np.all(np.isfinite(res.pressure)) and np.isfinite(res.approach)):
            raise StepFailure("contact solve returned non-finite pressure")
        return res

    def _rebuild(self, height, c, res):
        """Face and approach of an implicit stage ``w = height + c k P(w)^m``.

        On the contact the face is rebuilt as ``d - K p`` with ``K p`` recomputed
        from the pressure (one FFT product) and ``d`` the mean of
        ``height + c k p^m + K p`` there: the solver's residual, which scales
        with the shifted operator and so with ``c``, is projected out of the
        shape (it would reach ``rtol * ds / s*`` of ``f*`` after a jump), while
        the rigid part keeps the exact mean of the update.
        """
        p = res.pressure
        contact = self.face & (p > 0)
        w = height + c * self.rate(p)
        if not contact.any():
            return w, res
        kp = self.halfspace.displacement(p)
        d = float(np.mean((w + kp)[contact]))
        w = np.where(contact, d - kp, w)
        return w, dataclasses.replace(res, approach=d)

    def implicit(self, height, c, x0):
        """Solve ``w = height + c k P(w)^m`` for ``w``.

        Parameters
        ----------
        height : ndarray, shape (n, n), m
        c : float, m
            Sliding distance multiplying the implicit rate (``ds``, ``gamma ds``...).
        x0 : ndarray, shape (n, n), Pa
            Pressure guess (warm start and first linearisation point).

        Returns
        -------
        w : ndarray, shape (n, n), m
        result : ContactResult
            The contact of the face ``w`` (its pressure is ``P(w)``).
        """
        if self.exponent == 1.0:
            shift = c * self.wear
            res = self.contact(height, shift=shift, x0=x0)
            return self._rebuild(height, c, res)
        m = self.exponent
        pbar = self.mean_pressure
        p0 = np.asarray(x0, dtype=float)
        for it in range(self.newton_maxiter):
            # Off the face the wear coefficient is 0; 1 keeps p^(m-1) finite there.
            floor = self.pressure_floor * pbar if m < 1.0 else 0.0
            pl = np.where(self.face, np.maximum(p0, floor), 1.0)
            shift = c * self.wear * m * pl ** (m - 1.0)
            h_lin = height + c * self.wear * (1.0 - m) * pl ** m
            res = self.contact(h_lin, shift=shift, x0=p0)
            change = float(np.max(np.abs(res.pressure - p0))) / pbar
            p0 = res.pressure
            if change <= self.newton_rtol:
                return self._rebuild(height, c, res)
        raise StepFailure(f"power-law Newton iteration did not converge in "
                          f"{self.newton_maxiter} iterations (last change {change:.3g} pbar)")


@dataclasses.dataclass(frozen=True)
class StepState:
    """An accepted point of the run-in, everything a scheme needs to step on.

    Attributes
    ----------
    height : ndarray, shape (n, n), m
        Face height ``w`` (worn depth + initial shape, up to a constant).
    pressure : ndarray, shape (n, n), Pa
        ``P(w)``, the contact pressure of that face.
    approach : float, m
        Rigid approach of that contact (same constant as ``height``).
    previous_height : ndarray, shape (n, n), m, or None
        Face at the previous accepted point (multistep schemes, shape-change test).
    previous_rate : ndarray, shape (n, n), or None
        ``k p^m`` there.
    previous_step : float, m, or None
        The step that led from there to here.
    """

    height: np.ndarray
    pressure: np.ndarray
    approach: float
    previous_height: np.ndarray | None = None
    previous_rate: np.ndarray | None = None
    previous_step: float | None = None


@dataclasses.dataclass(frozen=True)
class Trial:
    """Outcome of one attempted step.

    Attributes
    ----------
    height : ndarray, shape (n, n), m
        New face ``w+``.
    pressure : ndarray, shape (n, n), Pa
        ``P(w+)``.
    approach : float, m
    contact_fraction : float
    error : ndarray, shape (n, n), m
        Local error estimate of ``w+``.
    """

    height: np.ndarray
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
    solves_per_step : int
        Contact solves per step (m = 1).
    max_growth : float
        Largest step ratio the scheme tolerates.
    explicit : bool
    """

    name = ""
    order = 1
    error_order = 1
    solves_per_step = 1
    max_growth = 5.0
    explicit = False

    def step(self, problem, state, ds):
        """Attempt one step of length ``ds`` (m) from ``state``; return a :class:`Trial`."""
        raise NotImplementedError

    def __repr__(self):
        return f"<{type(self).__name__} {self.name!r}, order {self.order}>"


def _trial(problem, height, res, error):
    return Trial(height=height, pressure=res.pressure, approach=float(res.approach),
                 contact_fraction=float(res.contact_fraction), error=error)


class ExplicitEuler(Scheme):
    """Forward Euler, ``w+ = w + ds k P(w)^m``; refuses steps beyond the stability limit."""

    name = "explicit_euler"
    order = 1
    error_order = 1
    explicit = True

    def step(self, problem, state, ds):
        limit = problem.stable_step(state.pressure)
        if ds > limit * (1.0 + 1e-12):
            raise ValueError(f"explicit Euler step {ds!r} m exceeds its stability limit "
                             f"{limit:.6g} m (2 lambda_min(K) / max k m p^(m-1))")
        f0 = problem.rate(state.pressure)
        height = state.height + ds * f0
        res = problem.contact(height, x0=state.pressure)
        error = 0.5 * ds * (problem.rate(res.pressure) - f0)
        return _trial(problem, height, res, error)


class ImplicitEuler(Scheme):
    """Backward Euler: the step is the contact problem with ``K + ds diag(k)``."""

    name = "implicit_euler"
    order = 1
    error_order = 1

    def step(self, problem, state, ds):
        f0 = problem.rate(state.pressure)
        height, res = problem.implicit(state.height, ds, state.pressure)
        error = 0.5 * ds * (problem.rate(res.pressure) - f0)
        return _trial(problem, height, res, error)


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

    def step(self, problem, state, ds):
        f0 = problem.rate(state.pressure)
        if state.previous_height is None:
            return ImplicitEuler().step(problem, state, ds)
        omega = ds / state.previous_step
        base = ((1 + omega) ** 2 * state.height
                - omega ** 2 * state.previous_height) / (1 + 2 * omega)
        beta = (1 + omega) / (1 + 2 * omega)
        height, res = problem.implicit(base, beta * ds, state.pressure)
        predictor = state.height + ds * ((1 + 0.5 * omega) * f0
                                         - 0.5 * omega * state.previous_rate)
        error = (8.0 / 23.0) * (height - predictor)
        return _trial(problem, height, res, error)


class SDIRK2(Scheme):
    """Alexander's L-stable, stiffly accurate two-stage SDIRK, ``gamma = 1 - 1/sqrt 2``.

    Stages ``W1 = w + gamma ds f(W1)``, ``w+ = W2 = w + ds((1 - gamma) f(W1) +
    gamma f(W2))``, each a shifted contact solve (shift ``gamma ds k``).
    Embedded first-order solution ``w + ds f(W1)``: ``err = gamma ds (f(W2) - f(W1))``.
    """

    name = "sdirk2"
    order = 2
    error_order = 1
    solves_per_step = 2
    gamma = 1.0 - 1.0 / math.sqrt(2.0)

    def step(self, problem, state, ds):
        g = self.gamma
        _, res1 = problem.implicit(state.height, g * ds, state.pressure)
        f1 = problem.rate(res1.pressure)
        base = state.height + (1 - g) * ds * f1
        height, res2 = problem.implicit(base, g * ds, res1.pressure)
        error = g * ds * (problem.rate(res2.pressure) - f1)
        return _trial(problem, height, res2, error)


SCHEMES = {}
"""Registered integrators by name (see :func:`register_scheme`)."""


def register_scheme(scheme):
    """Register a :class:`Scheme` instance under ``scheme.name``; returns it."""
    if not scheme.name:
        raise ValueError(f"scheme {scheme!r} has no name")
    SCHEMES[scheme.name] = scheme
    return scheme


def get_scheme(name):
    """The registered scheme called ``name``.

    Raises
    ------
    ValueError
        If no scheme has that name.
    """
    try:
        return SCHEMES[name]
    except KeyError:
        raise ValueError(f"unknown scheme {name!r}; expected one of "
                         f"{sorted(SCHEMES)}") from None


for _scheme in (ExplicitEuler(), ImplicitEuler(), BDF2(), SDIRK2()):
    register_scheme(_scheme)
del _scheme
