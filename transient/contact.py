"""Unilateral normal contact of the punch face on the elastic half-space, load control.

The face can carry pressure on the pixels of ``face_mask``; its recession field
``h(x)`` (m, larger = recessed, farther from the counter-body) holds the
worn depth plus the initial shape.  Under the normal force ``F`` the
pressure ``p`` and the rigid approach ``d`` solve the linear
complementarity problem

    u = (K + diag(shift)) p,    g = u + h - d >= 0,    p >= 0,    p g = 0,
    sum(p) h_pix^2 = F,

on the face (``p = 0`` off it), with ``K`` the half-space influence
operator (paper eq. 8).  ``shift = ds * k`` turns the problem into one
implicit Euler step of the Archard wear law,
``w_{n+1} = w_n + ds k p_{n+1}`` with ``h = w_n``.

The solver is the constrained conjugate gradient of Polonsky & Keer
(Wear 231 (1999) 206-219, doi:10.1016/S0043-1648(99)00113-1), with three
changes:

- a preconditioner: by default the inverse Fourier symbol of the operator
  (``~ E* |q| / 2``), aliased to the ``nx x ny`` grid and restricted to the
  active set (after Vollebregt, J. Comput. Phys. 257 (2014) 333-351,
  doi:10.1016/j.jcp.2013.10.005), with one symbol per level of a
  non-uniform shift, stitched by the shift map.  The iteration count then
  hardly grows with the grid, while that of plain Polonsky-Keer does
  (figures in docs/benchmarks.md, "Contact solver");
- the elastic displacement ``K p`` is updated with the conjugate
  direction's product (one padded FFT pair per iteration for the
  operator), the change from the few pixels that enter or leave the active
  set is summed directly, and it is recomputed by FFT only when many do or
  every 50 iterations.  It is kept apart from the shift's part
  ``shift * p`` (exact from ``p``), so that its round-off stays that of
  ``K p`` however large the shift, and the caller gets ``K p`` without a
  further product;
- pixels that penetrate enter the active set with the pressure of the
  current step length (Polonsky & Keer's rule, made unit-consistent for a
  preconditioned direction and capped by the pressure ``-g / A_ii`` that
  closes the gap alone).
"""

from __future__ import annotations

import dataclasses
import logging
import numbers

import numpy as np
import scipy.linalg

from .preconditioners import PRECONDITIONERS, make_preconditioner

__all__ = ["NORMS", "ContactResult", "solve_contact"]

logger = logging.getLogger(__name__)

# Pixels entering or leaving the active set up to this count have their
# displacement change summed directly (one nx x ny gather each, a few per cent
# of an FFT pair); more trigger a full FFT recomputation.
_DIRECT_UPDATE_PIXELS = 8
# Incremental displacement updates between full recomputations; each adds
# a round-off of order eps |K p|, so the drift stays far below any tolerance.
_REFRESH = 50
# Bound of the round-off one iteration adds to every entry of the incrementally
# updated displacement K p, in units of eps max|K p|: the update v -= tau K t,
# the direct column sums of a set change and the load rescaling each round
# once (by at most eps |K p|), with a factor 2 for the growth of |K p|
# between full recomputations.
_ROUNDING_PER_ITERATION = 8.0
# Solves that must reduce the first residual by more than this factor take the
# preconditioner in double precision (FourierPreconditioner.accurate): the round-off of
# single-precision transforms puts error into every eigencomponent at about 1e-7 of the
# residual, which costs a cold flat-punch solve to rtol = 1e-10 more iterations; a run-in's
# warm-started solves start a few tolerances away and lose none (docs/benchmarks.md,
# "Contact solve on run-in problems").
_SINGLE_REDUCTION = 1e-4
# Elements per call of the BLAS axpy behind :func:`_axpy`: OpenBLAS runs a call of at most
# 10000 on the calling thread; one over a whole large array runs threaded, slower than in
# blocks and than numpy's two passes (docs/benchmarks.md, "Contact solve on run-in problems").
_AXPY_BLOCK = 8192
_daxpy = scipy.linalg.blas.get_blas_funcs("axpy", dtype=np.float64)


@dataclasses.dataclass(frozen=True)
class ContactResult:
    """Solution of one load-controlled contact problem.

    Attributes
    ----------
    pressure : ndarray, shape (nx, ny), Pa
        Contact pressure, non-negative, zero off the face.
    approach : float, m
        Rigid approach ``d``: ``u = d - h`` where ``p > 0``.
    displacement : ndarray, shape (nx, ny), m
        ``(K + diag(shift)) p`` on the whole grid, consistent with
        ``pressure`` to round-off (updated with each step and recomputed
        by FFT at least every 50 iterations).
    elastic_displacement : ndarray, shape (nx, ny), m
        ``K p``, the half-space's part of ``displacement`` (the same
        without ``shift * p``), on the whole grid, with the round-off of
        ``K p`` alone.
    contact_fraction : float
        Pixels with ``p > 0`` over face pixels.
    nit : int
        Conjugate gradient iterations.
    residual : float, m
        Final gap violation over the face, in the norm of the stopping rule
        (rms or max, see :func:`solve_contact`).
    residual_history : ndarray, shape (nit + 1,), m
        Residual before each iteration and at the end.
    success : bool
        Whether the stopping rule was met.
    message : str
        What happened, in words.
    """

    pressure: np.ndarray
    approach: float
    displacement: np.ndarray
    elastic_displacement: np.ndarray
    contact_fraction: float
    nit: int
    residual: float
    residual_history: np.ndarray
    success: bool
    message: str


class _Operator:
    """``K`` (the half-space part of ``A = K + diag(shift)``), by FFT or by a few columns."""

    def __init__(self, halfspace, shift):
        self.halfspace = halfspace
        self.shift = shift
        self.diagonal = halfspace.self_influence + (0.0 if shift is None else shift)
        self._aranges = tuple(np.arange(m) for m in halfspace.shape)
        self.products = 0

    def __call__(self, p, *, contiguous=True):
        """``K p`` by one padded FFT product.

        ``contiguous=False`` returns the product as the half-space leaves it, a strided view
        of its inverse transform's rows, without the copy into an array of its own (for the
        conjugate direction's product, which is read twice and dropped).
        """
        self.products += 1
        u = self.halfspace.displacement(p)
        return np.ascontiguousarray(u) if contiguous else u

    def columns(self, ii, jj, values):
        """``K`` applied to a pressure that is ``values`` on pixels ``(ii, jj)``, else 0."""
        q = self.halfspace.influence_quadrant
        ax, ay = self._aranges
        u = np.zeros(self.halfspace.shape)
        for i, j, v in zip(ii, jj, values, strict=True):
            u += v * q[np.abs(ax - i)][:, np.abs(ay - j)]
        return u


def _initial_pressure(recession, on_face, force, halfspace):
    """Cold start: Hertz-like pressure on the pixels a rigid estimate puts in contact.

    For a sphere, the contact region ``dh < d / 2`` (``dh = h - min h``)
    has the radius ``c`` with ``d = 3 F / (4 E* c)`` (Hertz), and
    ``p ~ sqrt(d / 2 - dh)``.  The same construction on the sorted recessions
    of any face gives a start of the right extent; for a flat face it is
    uniform.  Unnormalised.
    """
    dh_face = recession[on_face] - recession[on_face].min()
    if not dh_face.any():
        return on_face.astype(float)
    dh = np.sort(dh_face)
    count = np.arange(1, dh.size + 1)
    c = np.sqrt(count * halfspace.h**2 / np.pi)
    half_approach = 0.375 * force / (halfspace.E_star * c)
    # First set size whose half-approach does not reach the next pixel's recession.
    k = min(int(np.argmax(half_approach <= np.append(dh[1:], np.inf))), dh.size - 1)
    level = max(float(half_approach[k]), float(dh[k]))
    excess = np.where(on_face, level - (recession - recession[on_face].min()), 0.0)
    if np.all(excess[on_face] >= 0.5 * level):
        return on_face.astype(float)
    return np.sqrt(np.maximum(excess, 0.0))


def _check_field(name, value, shape):
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def solve_contact(halfspace, face_mask, recession, normal_force, *, shift=None, x0=None,
                  x0_displacement=None, rtol=1e-8, atol=0.0, norm="rms", maxiter=None,
                  preconditioner="auto", callback=None):
    r"""Contact pressure and rigid approach of the face under a normal force.

    Solves the complementarity problem of the module docstring by a
    preconditioned constrained conjugate gradient (Polonsky & Keer 1999).

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
        The elastic half-space operator on the ``nx x ny`` grid.
    face_mask : ndarray of bool, shape (nx, ny)
        Pixels of the face, which can carry pressure; at least one.
    recession : ndarray, shape (nx, ny), m
        Height of the face, larger = farther from the counter-body (worn
        depth plus initial shape).  Must be finite on the face; values off
        the face are ignored.  Only differences matter.
    normal_force : float, N
        Total normal force, finite and non-negative.
    shift : ndarray, shape (nx, ny), m/Pa, optional
        Non-negative diagonal added to the operator: ``K + diag(shift)``
        (an implicit Euler wear step uses ``shift = ds * k``).  Default: none.
    x0 : ndarray, shape (nx, ny), Pa, optional
        Warm start.  Negative values and values off the face are dropped
        and the rest is scaled to the load.  Default (or an ``x0`` that is
        zero on the face): uniform on a flat face, else a Hertz-like
        pressure on the region a rigid estimate puts in contact.
    x0_displacement : ndarray, shape (nx, ny), m, optional
        ``K x0`` (the half-space's displacement, without the shift), when
        the caller knows it: it saves the first operator product.  Used
        only if ``x0`` is zero off the face and non-negative on it (else
        the product is computed).
    rtol, atol : float, optional
        Relative (dimensionless, default 1e-8) and absolute (m, default 0)
        tolerances of the stopping rule below.
    norm : {"rms", "max"}, optional
        The norm over the face pixels in which the stopping rule measures the
        violation of the contact conditions (default ``"rms"``; see Notes).
    maxiter : int, optional
        Maximum number of iterations (default ``max(200, 10 max(nx, ny))``).
    preconditioner : str or callable, optional
        One of ``"auto"``, ``"fourier"``, ``"fourier-padded"``, ``"jacobi"``, ``"none"``.
        ``"auto"`` (default) is ``"fourier"``, the inverse Fourier symbol of ``K + shift``
        aliased to the ``nx x ny`` grid (one unpadded FFT pair per iteration, cheaper than a
        padded one: in single precision for a solve that starts within ``1e4`` tolerances,
        as a warm-started one does, else in double; ``"fourier-padded"`` applies it on the
        padded grid); a non-uniform shift is split into levels, one symbol and one FFT pair each,
        stitched by the shift map (:class:`transient.preconditioners.FourierPreconditioner`).
        Where the shift is at least ten times the largest eigenvalue of ``K`` on every face
        pixel the operator is diagonal to within 10 % and ``"auto"`` takes ``"jacobi"``
        (free).  Or a preconditioner already built for this face and shift, called as
        ``z = preconditioner(residual, active)`` (a pressure, Pa, zero off ``active``, from a
        gap residual, m): a caller that solves many problems of one shift pattern builds them
        with :class:`transient.preconditioners.ScaledShift`.
    callback : callable, optional
        Called as ``callback(pressure)`` after each iteration with the
        current pressure (read-only view; copy it to keep it).

    Returns
    -------
    ContactResult

    Raises
    ------
    ValueError
        On a wrong shape, a non-finite recession on the face, a negative or
        non-finite force, a negative or non-finite shift, an empty face,
        bad tolerances, an unknown norm or an unknown preconditioner.

    Notes
    -----
    Stopping rule.  With ``d`` the mean of ``u + h`` over the active set ``I = {p > 0}`` and
    the gap ``g = u + h - d``, the residual is the rms, over the face pixels, of the violation
    of the contact conditions::

        residual = sqrt( (sum_I g^2 + sum_{face \ I} min(g, 0)^2) / N_face )

    (gap left open under pressure, or interpenetration where there is none), in metres.  The
    iteration stops when ``residual <= max(rtol * U, atol)`` with ``U`` the rms displacement
    over the active set, the elastic scale of the problem (for the flat punch
    ``U = F / (2 a E*)``).  So ``rtol`` is the relative residual of the contact equation
    ``u = d - h`` on the contact area.  With ``norm="max"`` the residual is the largest
    violation over the face pixels instead of the rms: the rms of a violation left on a few
    pixels (the corners of a rectangle, where the pressure is singular) is that violation
    times the square root of their share of the face, so the rms rule lets it reach
    ``sqrt(N_face / n_pixels)`` times its tolerance there; the max rule bounds it on every
    pixel.  ``p >= 0`` holds exactly and the load is met to
    round-off at every iteration.  The returned ``approach`` is ``d``.  The displacement
    behind the residual is updated with each step, which rounds each of its entries by at
    most a few ``eps max|u|``; when the accumulated bound could reach a thousandth of the
    tolerance, it is recomputed by FFT and the rule checked again.

    Examples
    --------
    The flat punch: in full contact, with the rigid approach
    ``F / (2 a E*)`` of the continuum punch up to the staircase of the rim.

    >>> import numpy as np
    >>> from steady import Circle, HalfSpace, reference
    >>> n, a, E_star, force = 64, 4e-3, 1.3e6, 10.0
    >>> grid = Circle(a).grid(n)
    >>> halfspace = HalfSpace(grid.shape, grid.h, E_star)
    >>> res = solve_contact(halfspace, grid.mask, np.zeros((n, n)), force)
    >>> res.success, res.contact_fraction
    (True, 1.0)
    >>> print(f"load {res.pressure.sum() * halfspace.h**2:.9f} N")
    load 10.000000000 N
    >>> print(f"{res.approach / reference.flat_punch_approach(force, a, E_star):.3f}")
    1.002
    """
    on_face, n_face, recession, force, shift, x0, maxiter = _checked_inputs(
        halfspace, face_mask, recession, normal_force, shift, x0, rtol, atol, norm, maxiter,
        preconditioner)
    return _solve(halfspace, on_face, n_face, recession, force, shift, x0, x0_displacement,
                  rtol, atol, norm, maxiter, preconditioner, callback)


def solve_trusted_contact(halfspace, face_mask, recession, normal_force, *, shift=None, x0=None,
                          x0_displacement=None, rtol=1e-8, atol=0.0, norm="rms",
                          maxiter=None, preconditioner="auto"):
    """:func:`solve_contact` on arguments its caller guarantees, without their checks.

    The run-in loop's entry: it solves many problems whose arguments it has
    built itself, and the checks of :func:`solve_contact` (several passes
    over the grid's arrays) cost a few per cent of a solve.  The caller
    guarantees what those checks would establish: arrays of the grid's shape
    (float), ``face_mask`` boolean with at least one pixel, ``recession`` and
    ``x0`` finite on the face, ``normal_force`` finite and non-negative,
    ``shift`` (m/Pa) finite, non-negative and zero off the face, tolerances,
    ``norm`` and ``maxiter`` valid, ``preconditioner`` a registered name or a callable.
    On such arguments the result is that of :func:`solve_contact`, bit for
    bit; on others it is undefined.

    Parameters and returns as :func:`solve_contact` (without ``callback``).
    """
    on_face = face_mask
    if maxiter is None:
        maxiter = max(200, 10 * max(halfspace.shape))
    return _solve(halfspace, on_face, int(np.count_nonzero(on_face)), recession,
                  float(normal_force), shift, x0, x0_displacement, rtol, atol, norm,
                  int(maxiter), preconditioner, None)


def _solve(halfspace, on_face, n_face, recession, force, shift, x0, x0_displacement, rtol, atol,
           norm, maxiter, preconditioner, callback):
    """The iteration of :func:`solve_contact` on checked arguments."""
    operator = _Operator(halfspace, shift)
    h_face = np.where(on_face, recession, 0.0)
    if force == 0.0:
        return _zero_load_result(h_face, on_face)
    if not callable(preconditioner):
        preconditioner = make_preconditioner(preconditioner, halfspace, on_face, shift)
    problem = _Problem(operator, on_face.astype(float), n_face, h_face, force, halfspace.h**2,
                       preconditioner)
    state = _State(*_start(problem, on_face, x0, x0_displacement))
    return _iterate(problem, state, rtol, atol, norm == "max", maxiter, callback)


# -- input checks ------------------------------------------------------------------------------

def _checked_inputs(halfspace, face_mask, recession, normal_force, shift, x0, rtol, atol, norm,
                    maxiter, preconditioner):
    """The arguments of :func:`solve_contact`, checked (see its Raises) and converted.

    Returns
    -------
    on_face : ndarray of bool, shape (nx, ny)
    n_face : int
        Face pixels, at least one.
    recession : ndarray, shape (nx, ny), m
    force : float, N
    shift : ndarray, shape (nx, ny), m/Pa, or None
        Zero off the face; None if zero everywhere.
    x0 : ndarray, shape (nx, ny), Pa, or None
    maxiter : int
    """
    shape = tuple(halfspace.shape)
    on_face, n_face = _checked_face(face_mask, shape)
    recession = _check_field("recession", recession, shape)
    if not np.all(np.isfinite(recession[on_face])):
        bad = int((~np.isfinite(recession[on_face])).sum())
        raise ValueError(f"recession must be finite on the face, got {bad} non-finite values")
    if not isinstance(normal_force, numbers.Real) and np.ndim(normal_force) != 0:
        raise ValueError(f"normal_force must be a scalar in N, got {normal_force!r}")
    force = float(normal_force)
    if not (np.isfinite(force) and force >= 0):
        raise ValueError(f"normal_force must be finite and non-negative, got {normal_force!r} N")
    if shift is not None:
        shift = _checked_shift(shift, on_face, shape)
    if x0 is not None:
        x0 = _check_field("x0", x0, shape)
        if not np.all(np.isfinite(x0[on_face])):
            raise ValueError("x0 must be finite on the face")
    maxiter = _checked_controls(rtol, atol, norm, maxiter, preconditioner, shape)
    return on_face, n_face, recession, force, shift, x0, maxiter


def _checked_face(face_mask, shape):
    """The face as a boolean array of the grid's ``shape``, and its pixel count (at least 1)."""
    on_face = np.asarray(face_mask)
    if on_face.shape != shape:
        raise ValueError(f"face_mask must have shape {shape}, got {on_face.shape}")
    if on_face.dtype != bool:
        raise ValueError(f"face_mask must be a boolean mask, got dtype {on_face.dtype}")
    n_face = int(on_face.sum())
    if n_face == 0:
        raise ValueError("face has no pixel: nothing can carry the load")
    return on_face, n_face


def _checked_shift(shift, on_face, shape):
    """The shift (m/Pa), finite and non-negative on the face, zero off it; None if all zero."""
    shift = _check_field("shift", shift, shape)
    s_face = shift[on_face]
    if not np.all(np.isfinite(s_face)):
        raise ValueError("shift must be finite on the face")
    if s_face.min() < 0:
        raise ValueError(f"shift must be non-negative, got min {s_face.min()!r} m/Pa")
    shift = np.where(on_face, shift, 0.0)
    return shift if shift.any() else None


def _checked_controls(rtol, atol, norm, maxiter, preconditioner, shape):
    """Checks the tolerances, the norm and the preconditioner; the iteration limit, as int."""
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(tol) and tol >= 0):
            raise ValueError(f"{name} must be finite and non-negative, got {tol!r}")
    if rtol == 0 and atol == 0:
        raise ValueError("rtol and atol cannot both be zero")
    if norm not in NORMS:
        raise ValueError(f"norm must be one of {NORMS}, got {norm!r}")
    if maxiter is None:
        maxiter = max(200, 10 * max(shape))
    if int(maxiter) != maxiter or maxiter < 1:
        raise ValueError(f"maxiter must be a positive integer, got {maxiter!r}")
    if not callable(preconditioner) and preconditioner not in PRECONDITIONERS:
        raise ValueError(f"preconditioner must be one of {sorted(PRECONDITIONERS)} or a "
                         f"callable, got {preconditioner!r}")
    return int(maxiter)


# -- set-up ------------------------------------------------------------------------------------

def _zero_load_result(h_face, on_face):
    """The result under no load: no pressure, the face touching at its lowest pixel."""
    zero = np.zeros(h_face.shape)
    return ContactResult(zero, float(h_face[on_face].min()), zero.copy(), zero.copy(), 0.0,
                         0, 0.0, np.zeros(1), True, "zero load: no pressure")


@dataclasses.dataclass(frozen=True)
class _Problem:
    """One checked contact problem under load, as the iteration reads it (never changed).

    Attributes
    ----------
    operator : _Operator
        ``K``, with the shift (m/Pa, or None) and the diagonal of ``K + diag(shift)``.
    face : ndarray, shape (nx, ny)
        1.0 on the face pixels, 0.0 off them.
    n_face : int
        Face pixels.
    recession : ndarray, shape (nx, ny), m
        ``h`` on the face, 0 off it.
    force : float, N
        Normal force, positive.
    area : float, m^2
        Pixel area.
    precondition : callable or None
        ``z = precondition(r, active)``, a pressure (Pa) from a gap residual (m);
        None for plain Polonsky-Keer.
    """

    operator: _Operator
    face: np.ndarray
    n_face: int
    recession: np.ndarray
    force: float
    area: float
    precondition: object


def _start(problem, on_face, x0, x0_displacement):
    """The first iterate: a pressure carrying the load, and its displacement ``K p``.

    The warm start ``x0`` if it carries load, else :func:`_initial_pressure`;
    ``K p`` from ``x0_displacement`` when that is ``K`` of the same pressure.

    Parameters
    ----------
    problem : _Problem
    on_face : ndarray of bool, shape (nx, ny)
    x0 : ndarray, shape (nx, ny), Pa, or None
    x0_displacement : ndarray, shape (nx, ny), m, or None
        As in :func:`solve_contact`.

    Returns
    -------
    p : ndarray, shape (nx, ny), Pa
    v : ndarray, shape (nx, ny), m
    """
    operator = problem.operator
    shape = tuple(operator.halfspace.shape)
    p = np.zeros(shape)
    if x0 is not None:
        # One pass and a minimum where the warm start is non-negative, as a run's is.
        p = np.where(on_face, x0, 0.0)
        if p.min() < 0:
            np.maximum(p, 0.0, out=p)
    if p.sum() <= 0:
        p = _initial_pressure(problem.recession, on_face, problem.force, operator.halfspace)
        x0_displacement = None
    c = problem.force / (problem.area * p.sum())
    # (compared before the scaling: the same test as ``c p == c x0`` without its product)
    known = x0_displacement is not None and np.array_equal(p, x0)
    p *= c
    if known:
        v = c * _check_field("x0_displacement", x0_displacement, shape)
    else:
        v = operator(p)
    return p, v


# -- the iteration -----------------------------------------------------------------------------

_CONVERGED, _RECOMPUTE, _ITERATE = "converged", "recompute", "iterate"
#: The norms of the stopping rule (:func:`solve_contact`, Notes).
NORMS = ("rms", "max")


class _State:
    """The state the iteration carries from one step to the next (arrays updated in place).

    Attributes
    ----------
    p : ndarray, shape (nx, ny), Pa
        Pressure, non-negative, carrying the load.
    v : ndarray, shape (nx, ny), m
        ``K p``, updated with each step.
    v_max : float, m
        ``max |v|`` at the start or at its last recomputation by FFT, the scale of its
        round-off.
    since_full : int
        Incremental updates of ``v`` since then.
    verified : bool
        Whether ``v`` was recomputed for the stopping rule after the last step (a residual
        within the tolerance is then final).
    t : ndarray, shape (nx, ny)
        Conjugate direction: a pressure (Pa), or a gap (m) without a preconditioner.
    gz_old : float
        ``r . z`` of the previous direction.
    restart : bool
        Whether the next direction is the preconditioned residual alone (a pixel entered).
    set_changed : bool
        Whether the active set changed at the last step.
    """

    __slots__ = ("p", "v", "v_max", "since_full", "verified", "t", "gz_old", "restart",
                 "set_changed")

    def __init__(self, p, v):
        self.p = p
        self.v = v
        self.v_max = _largest_magnitude(v)
        self.since_full = 0
        self.verified = False
        self.t = np.zeros(p.shape)
        self.gz_old = 1.0
        self.restart = True
        self.set_changed = True

    def recompute_displacement(self, operator):
        """``v = K p`` afresh by FFT, dropping the round-off of the incremental updates."""
        self.v = operator(self.p)
        self.v_max = _largest_magnitude(self.v)
        self.since_full = 0


class _ActiveSet:
    """The active set ``I = {p > 0}`` in the forms the steps use.

    Attributes
    ----------
    mask : ndarray of bool, shape (nx, ny)
    weight : ndarray, shape (nx, ny)
        ``mask`` as 1.0 / 0.0.
    count : float
        Pixels in the set.
    off : ndarray, shape (nx, ny), or None
        1.0 on the face pixels out of the set, else 0.0; None when the set is the whole face.
    full : bool
        Whether the set is the whole face.
    """

    __slots__ = ("mask", "weight", "count", "off", "full")

    def __init__(self, p, face, n_face):
        self.mask = p > 0
        self.weight = self.mask.astype(float)
        self.count = float(np.count_nonzero(self.mask))
        self.full = self.count == n_face
        self.off = None if self.full else face - self.weight


def _iterate(problem, state, rtol, atol, peak, maxiter, callback):
    """The constrained conjugate gradient from the first iterate; the result.

    Each iteration: the active set, if it changed (:class:`_ActiveSet`); the
    approach, gap and residual (:func:`_gap`, :func:`_residual`, :func:`_tolerance`);
    the stopping rule (:func:`_stopping_rule`); the conjugate direction
    (:func:`_update_direction`) and the step along it (:func:`_curvature`,
    :func:`_take_step`); the pixels leaving and entering the set
    (:func:`_update_active_set`) and the pressure scaled back to the load
    (:func:`_rescale_to_load`).

    Parameters
    ----------
    problem : _Problem
    state : _State
        The first iterate, advanced in place.
    rtol, atol, maxiter, callback
        As in :func:`solve_contact`, checked.
    peak : bool
        Whether the rule measures the largest violation (``norm="max"``) rather than the rms.

    Returns
    -------
    ContactResult
    """
    u, g, r, penetration, work = (np.empty(state.p.shape) for _ in range(5))
    history = []
    success = False
    message = ""
    it = 0
    while True:
        if state.set_changed:
            active = _ActiveSet(state.p, problem.face, problem.n_face)
        d, u_now = _gap(problem, state, active, u, g, r)
        tolerance = _tolerance(u_now, active, rtol, atol)
        residual = _residual(g, r, active, problem.n_face, penetration, peak)
        if not np.isfinite(residual):
            message = f"non-finite residual at iteration {it}"
            history.append(residual)
            break
        verdict = _stopping_rule(residual, tolerance, state)
        if verdict == _RECOMPUTE:
            state.recompute_displacement(problem.operator)
            state.verified = True
            continue
        history.append(residual)
        if verdict == _CONVERGED:
            success = True
            message = (f"converged in {it} iterations: residual {residual:.3e} m "
                       f"<= {tolerance:.3e} m")
            break
        state.verified = False
        if it >= maxiter:
            message = (f"no convergence in {maxiter} iterations: residual {residual:.3e} m "
                       f"> {tolerance:.3e} m")
            break
        it += 1
        rt = _update_direction(problem, state, r, active, work,
                               accurate=tolerance < _SINGLE_REDUCTION * history[0])
        q = problem.operator(state.t, contiguous=False)
        tq = _curvature(problem, state.t, q)
        if not tq > 0:
            message = f"breakdown at iteration {it}: non-positive curvature {tq!r}"
            break
        tau = rt / tq
        _take_step(state, q, tau, work)
        if (_update_active_set(problem, state, active, g, r, penetration, tau)
                and not _rescale_to_load(problem, state)):
            message = f"all pressure lost at iteration {it}"
            break
        if callback is not None:
            view = state.p.view()
            view.flags.writeable = False
            callback(view)
    return _result(problem, state, d, it, residual, history, success, message)


def _gap(problem, state, active, u, g, r):
    """The rigid approach ``d`` (m), the mean of ``u + h`` over the active set, and ``u``.

    Fills the work arrays (m, shape (nx, ny)) the gap ``g = u + h - d`` (meaningful on the
    face) and its restriction ``r`` to the active set, and ``u = (K + diag(shift)) p`` unless
    there is no shift (``u`` is then ``state.v``, returned as it is, not copied).
    """
    shift = problem.operator.shift
    if shift is None:
        u = state.v
    else:
        np.multiply(shift, state.p, out=u)
        u += state.v
    np.add(u, problem.recession, out=g)
    d = _dot(g, active.weight) / active.count
    g -= d
    np.multiply(g, active.weight, out=r)
    return d, u


def _residual(g, r, active, n_face, penetration, peak=False):
    """Rms (or largest) violation (m) of the contact conditions over the face.

    See :func:`solve_contact`, Notes.

    Parameters
    ----------
    g, r : ndarray, shape (nx, ny), m
        The gap, and the gap on the active set (:func:`_gap`).
    active : _ActiveSet
    n_face : int
    penetration : ndarray, shape (nx, ny), m
        Filled with ``min(g, 0)`` on the face pixels out of the set, 0 elsewhere (where it
        is negative, pixels enter the set: :func:`_update_active_set`), unless the set is
        the whole face.
    peak : bool, optional
        The largest violation instead of the rms (default False).
    """
    if not active.full:
        np.minimum(g, 0.0, out=penetration)
        penetration *= active.off
    if peak:
        largest = _largest_magnitude(r)
        return largest if active.full else max(largest, -float(penetration.min()))
    violation = _dot(r, r)
    if not active.full:
        violation += _dot(penetration, penetration)
    return float(np.sqrt(violation / n_face))


def _tolerance(u, active, rtol, atol):
    """The stopping rule's bound (m): ``rtol`` times the rms of ``u`` (m) on the set, or atol."""
    scale = float(np.sqrt(_dot3(u, u, active.weight) / active.count))
    return max(rtol * scale, atol)


def _stopping_rule(residual, tolerance, state):
    """What to do with a residual (m) against the tolerance (m).

    ``_CONVERGED`` when it is met on a displacement whose accumulated round-off
    cannot matter; ``_RECOMPUTE`` (``K p`` by FFT, then the rule again) when it
    is met on one whose round-off might, or after ``_REFRESH`` incremental
    updates; else ``_ITERATE``.
    """
    drift = state.since_full * _ROUNDING_PER_ITERATION * np.finfo(float).eps * state.v_max
    if residual <= tolerance and (state.verified or drift < 1e-3 * tolerance):
        return _CONVERGED
    if (residual <= tolerance and not state.verified) or state.since_full >= _REFRESH:
        return _RECOMPUTE
    return _ITERATE


def _update_direction(problem, state, r, active, work, accurate=False):
    """The next conjugate direction ``state.t`` from the residual ``r`` (m, shape (nx, ny)).

    ``work`` (shape (nx, ny)) is scratch.  ``accurate``: apply the preconditioner
    in double precision (its ``accurate`` method, where it has one).  Returns ``r . t``:
    for a new direction ``t = z`` that is ``r . z``, already at hand.
    """
    precondition = problem.precondition
    if hasattr(precondition, "unrestricted"):
        # Restricted to the set and with zero mean on it (so that a step along it keeps the
        # load) in two passes over the transform's output, which is not restricted first.
        z = precondition.unrestricted(r, accurate=accurate)
        z = np.subtract(z, np.float64(_dot(z, active.weight) / active.count), dtype=float)
        z *= active.weight
    else:
        if precondition is None:
            z = r.copy()
        elif accurate and hasattr(precondition, "accurate"):
            z = precondition.accurate(r, active.mask)
        else:
            z = precondition(r, active.mask)
        # Zero mean on the active set, so that a step along it keeps the load.
        z -= np.multiply(active.weight, _dot(z, active.weight) / active.count, out=work)
    gz = _dot(r, z)
    if state.restart or state.gz_old == 0:
        state.t = z
        state.gz_old = gz
        return gz
    # t = z + beta t in one pass, into z (a fresh array).
    t = state.t = _axpy(gz / state.gz_old, state.t, z)
    if state.set_changed:
        # Pixels left the set: the old direction must neither move them nor the load.
        t *= active.weight
        t -= (_dot(t, active.weight) / active.count) * active.weight
    state.gz_old = gz
    return _dot(r, state.t)


def _curvature(problem, t, q):
    """``t . (K + diag(shift)) t`` from ``q = K t``, both of shape (nx, ny)."""
    tq = _dot(t, q)
    if problem.operator.shift is not None:
        tq += _dot3(t, t, problem.operator.shift)
    return tq


def _take_step(state, q, tau, work):
    """``p -= tau t`` and ``v -= tau q`` with ``q = K t`` (m); ``work`` is scratch.

    ``q``, a strided view of the product's buffer, takes numpy's two passes: BLAS
    axpy wants a contiguous vector.
    """
    _axpy(-tau, state.t, state.p)
    state.v -= np.multiply(q, tau, out=work)
    state.since_full += 1


def _update_active_set(problem, state, active, g, r, penetration, tau):
    """Moves the pixels leaving the active set and those entering it; whether any did.

    Pixels with negative pressure leave with zero pressure; face pixels out of the
    set that penetrate (``g < 0``) enter with :func:`_entering_pressure`.  Sets
    ``state.restart`` and ``state.set_changed`` and keeps ``state.v = K p``.

    Parameters
    ----------
    problem : _Problem
    state : _State
    active : _ActiveSet
        The set of this iteration.
    g, r : ndarray, shape (nx, ny), m
        The gap before the step, and its part on the set.
    penetration : ndarray, shape (nx, ny), m
        ``min(g, 0)`` on the face pixels out of the set, 0 elsewhere (:func:`_residual`).
    tau : float
        The step length along ``state.t``: dimensionless, or Pa/m without a preconditioner
        (``t`` then being a gap).
    """
    p = state.p
    # A minimum first (one reduction, no temporary): the masks only when pixels move.
    any_leaving = bool(p.min() < 0)
    state.restart = not active.full and bool(penetration.min() < 0)
    state.set_changed = any_leaving or state.restart
    if state.set_changed:
        leaving = p < 0
        entering = penetration < 0 if state.restart else None
        dp = np.zeros(p.shape)
        dp[leaving] = -p[leaving]
        if state.restart:
            dp[entering] = _entering_pressure(problem, state, g, r, entering, tau)
        p += dp
        p[leaving] = 0.0
        ii, jj = np.nonzero(dp)
        if ii.size <= _DIRECT_UPDATE_PIXELS:
            state.v += problem.operator.columns(ii, jj, dp[ii, jj])
        else:
            state.recompute_displacement(problem.operator)
    return state.set_changed


def _entering_pressure(problem, state, g, r, entering, tau):
    """Pressure (Pa) of the pixels ``entering`` the active set, from their gap ``g < 0`` (m)."""
    if problem.precondition is None:
        # Polonsky & Keer's rule: the steepest-descent step on those pixels.
        return -tau * g[entering]
    # The same step length, as pressure per gap on the active set, capped by the
    # pressure that closes each gap alone.
    t = state.t
    rate = abs(tau) * np.sqrt(_dot(t, t) / max(_dot(r, r), np.finfo(float).tiny))
    diagonal = np.broadcast_to(problem.operator.diagonal, g.shape)[entering]
    return -g[entering] * np.minimum(rate, 1.0 / diagonal)


def _rescale_to_load(problem, state):
    """Scales ``p`` and ``v = K p`` back to the load; False if no pressure is left."""
    total = state.p.sum()
    if not total > 0:
        return False
    c = problem.force / (problem.area * total)
    state.p *= c
    state.v *= c
    return True


def _result(problem, state, d, nit, residual, history, success, message):
    """The :class:`ContactResult` of the last iterate, logged.

    After a failure ``K p`` and the approach ``d`` (m) are recomputed from the
    pressure, whose displacement may have drifted or missed a cut-short update.
    """
    operator, p = problem.operator, state.p
    if not success:
        logger.warning("contact solver failed: %s", message)
        if np.all(np.isfinite(p)):
            state.v = operator(p)
            active = p > 0
            if active.any():
                u = state.v + (0.0 if operator.shift is None else operator.shift * p)
                d = float((u + problem.recession)[active].mean())
    else:
        logger.debug("contact solver: %s (%d operator products)", message, operator.products)
    v, shift = state.v, operator.shift
    return ContactResult(
        pressure=p,
        approach=float(d),
        displacement=v if shift is None else v + shift * p,
        elastic_displacement=v,
        contact_fraction=float(np.count_nonzero(p > 0) / problem.n_face),
        nit=nit,
        residual=residual,
        residual_history=np.asarray(history),
        success=success,
        message=message,
    )


# -- products ----------------------------------------------------------------------------------

def _axpy(alpha, x, y):
    """``y += alpha x`` in one pass over C-contiguous float arrays of one shape; ``y``.

    BLAS axpy in blocks of ``_AXPY_BLOCK`` elements, each run on the calling thread;
    numpy's two passes for arrays of another layout or type (a caller's preconditioner
    may return one).
    """
    if not (y.flags.c_contiguous and y.dtype == np.float64 and x.dtype == np.float64
            and x.flags.c_contiguous and x.shape == y.shape):
        y += alpha * x
        return y
    xf, yf = x.reshape(-1), y.reshape(-1)
    for start in range(0, yf.size, _AXPY_BLOCK):
        _daxpy(xf, yf, n=min(_AXPY_BLOCK, yf.size - start), a=alpha, offx=start, offy=start)
    return y


def _largest_magnitude(a):
    """``max |a|`` of an array, from its extremes (no temporary)."""
    return float(max(a.max(), -a.min()))


def _dot3(a, b, c):
    """Sum of the elementwise product of three arrays of the same shape (no temporary)."""
    return float(np.einsum("ij,ij,ij->", a, b, c))


def _dot(a, b):
    """Sum of the elementwise product of two arrays of the same shape.

    ``einsum`` rather than BLAS: a threaded BLAS dot product can cost more
    than an FFT pair on a loaded machine.
    """
    return float(np.einsum("ij,ij->", a, b))
