"""Unilateral normal contact of the punch face on the elastic half-space, load control.

The face can carry pressure on the pixels of ``face_mask``; its height field
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
  hardly grows with the grid (8 to 14 for the flat punch from n = 32 to
  1024 at ``rtol = 1e-8``), where plain Polonsky-Keer needs 18 to 94;
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

from .preconditioners import PRECONDITIONERS, make_preconditioner

__all__ = ["ContactResult", "solve_contact"]

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
        Final rms gap violation over the face (see :func:`solve_contact`).
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

    def __call__(self, p):
        """``K p`` by one padded FFT product."""
        self.products += 1
        return np.ascontiguousarray(self.halfspace.displacement(p))

    def columns(self, ii, jj, values):
        """``K`` applied to a pressure that is ``values`` on pixels ``(ii, jj)``, else 0."""
        q = self.halfspace.influence_quadrant
        ax, ay = self._aranges
        u = np.zeros(self.halfspace.shape)
        for i, j, v in zip(ii, jj, values, strict=True):
            u += v * q[np.abs(ax - i)][:, np.abs(ay - j)]
        return u


def _initial_pressure(height, on_face, force, halfspace):
    """Cold start: Hertz-like pressure on the pixels a rigid estimate puts in contact.

    For a sphere, the contact region ``dh < d / 2`` (``dh = h - min h``)
    has the radius ``c`` with ``d = 3 F / (4 E* c)`` (Hertz), and
    ``p ~ sqrt(d / 2 - dh)``.  The same construction on the sorted heights
    of any face gives a start of the right extent; for a flat face it is
    uniform.  Unnormalised.
    """
    dh_face = height[on_face] - height[on_face].min()
    if not dh_face.any():
        return on_face.astype(float)
    dh = np.sort(dh_face)
    count = np.arange(1, dh.size + 1)
    c = np.sqrt(count * halfspace.h**2 / np.pi)
    half_approach = 0.375 * force / (halfspace.E_star * c)
    # First set size whose half-approach does not reach the next pixel's height.
    k = min(int(np.argmax(half_approach <= np.append(dh[1:], np.inf))), dh.size - 1)
    level = max(float(half_approach[k]), float(dh[k]))
    excess = np.where(on_face, level - (height - height[on_face].min()), 0.0)
    if np.all(excess[on_face] >= 0.5 * level):
        return on_face.astype(float)
    return np.sqrt(np.maximum(excess, 0.0))


def _check_field(name, value, shape):
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def solve_contact(halfspace, face_mask, height, normal_force, *, shift=None, x0=None,
                  x0_displacement=None, rtol=1e-8, atol=0.0, maxiter=None,
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
    height : ndarray, shape (nx, ny), m
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
    maxiter : int, optional
        Maximum number of iterations (default ``max(200, 10 max(nx, ny))``).
    preconditioner : str or callable, optional
        One of ``"auto"``, ``"fourier"``, ``"fourier-padded"``, ``"jacobi"``,
        ``"amg"``, ``"none"``.  ``"auto"`` (default) is ``"fourier"``, the inverse Fourier symbol of
        ``K + shift`` aliased to the ``nx x ny`` grid (one unpadded FFT pair
        per iteration, about a third of a padded one; ``"fourier-padded"``
        applies it on the padded grid); a non-uniform shift is split into
        levels, one symbol and one FFT pair each, stitched by the shift map
        (:class:`transient.preconditioners.FourierPreconditioner`).  Where
        the shift is at least ten times the largest eigenvalue of ``K`` on
        every face pixel the operator is diagonal to within 10 % and
        ``"auto"`` takes ``"jacobi"`` (free).  ``"amg"`` (one
        smoothed-aggregation V-cycle on a truncated kernel) needs
        :mod:`pyamg` and is slower in every case measured
        (docs/benchmarks.md).  Or a preconditioner already built for this
        face and shift, called as ``z = preconditioner(residual, active)``
        (a pressure, Pa, zero off ``active``, from a gap residual, m): a
        caller that solves many problems of one shift pattern builds them
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
        On a wrong shape, a non-finite height on the face, a negative or
        non-finite force, a negative or non-finite shift, an empty face,
        bad tolerances or an unknown preconditioner.

    Notes
    -----
    Stopping rule.  With ``d`` the mean of ``u + h`` over the active set
    ``I = {p > 0}`` and the gap ``g = u + h - d``, the residual is the rms,
    over the face pixels, of the violation of the contact conditions::

        residual = sqrt( (sum_I g^2 + sum_{face \ I} min(g, 0)^2) / N_face )

    (gap left open under pressure, or interpenetration where there is
    none), in metres.  The iteration stops when
    ``residual <= max(rtol * U, atol)`` with ``U`` the rms displacement
    over the active set, the elastic scale of the problem (for the flat
    punch ``U = F / (2 a E*)``).  So ``rtol`` is the relative residual of
    the contact equation ``u = d - h`` on the contact area.  ``p >= 0``
    holds exactly and the load is met to round-off at every iteration.
    The returned ``approach`` is ``d``.  The displacement behind the
    residual is updated with each step, which rounds each of its entries by
    at most a few ``eps max|u|``; when the accumulated bound could reach a
    thousandth of the tolerance, it is recomputed by FFT and the rule
    checked again.

    Examples
    --------
    The flat punch: in full contact, with the rigid approach
    ``F / (2 a E*)`` of the continuum punch up to the staircase of the rim.

    >>> import numpy as np
    >>> from steady import HalfSpace, face_mask, pixel_size, reference
    >>> n, a, E_star, force = 64, 4e-3, 1.3e6, 10.0
    >>> halfspace = HalfSpace(n, pixel_size(n, a), E_star)
    >>> res = solve_contact(halfspace, face_mask(n), np.zeros((n, n)), force)
    >>> res.success, res.contact_fraction
    (True, 1.0)
    >>> print(f"load {res.pressure.sum() * halfspace.h**2:.9f} N")
    load 10.000000000 N
    >>> print(f"{res.approach / reference.flat_punch_approach(force, a, E_star):.3f}")
    1.002
    """
    shape = tuple(halfspace.shape)
    on_face = np.asarray(face_mask)
    if on_face.shape != shape:
        raise ValueError(f"face_mask must have shape {shape}, got {on_face.shape}")
    if on_face.dtype != bool:
        raise ValueError(f"face_mask must be a boolean mask, got dtype {on_face.dtype}")
    n_face = int(on_face.sum())
    if n_face == 0:
        raise ValueError("face has no pixel: nothing can carry the load")
    height = _check_field("height", height, shape)
    if not np.all(np.isfinite(height[on_face])):
        bad = int((~np.isfinite(height[on_face])).sum())
        raise ValueError(f"height must be finite on the face, got {bad} non-finite values")
    if not isinstance(normal_force, numbers.Real) and np.ndim(normal_force) != 0:
        raise ValueError(f"normal_force must be a scalar in N, got {normal_force!r}")
    force = float(normal_force)
    if not (np.isfinite(force) and force >= 0):
        raise ValueError(f"normal_force must be finite and non-negative, got {normal_force!r} N")
    if shift is not None:
        shift = _check_field("shift", shift, shape)
        s_face = shift[on_face]
        if not np.all(np.isfinite(s_face)):
            raise ValueError("shift must be finite on the face")
        if s_face.min() < 0:
            raise ValueError(f"shift must be non-negative, got min {s_face.min()!r} m/Pa")
        shift = np.where(on_face, shift, 0.0)
        if not shift.any():
            shift = None
    if x0 is not None:
        x0 = _check_field("x0", x0, shape)
        if not np.all(np.isfinite(x0[on_face])):
            raise ValueError("x0 must be finite on the face")
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(tol) and tol >= 0):
            raise ValueError(f"{name} must be finite and non-negative, got {tol!r}")
    if rtol == 0 and atol == 0:
        raise ValueError("rtol and atol cannot both be zero")
    if maxiter is None:
        maxiter = max(200, 10 * max(shape))
    if int(maxiter) != maxiter or maxiter < 1:
        raise ValueError(f"maxiter must be a positive integer, got {maxiter!r}")
    maxiter = int(maxiter)
    if not callable(preconditioner) and preconditioner not in PRECONDITIONERS:
        raise ValueError(f"preconditioner must be one of {sorted(PRECONDITIONERS)} or a "
                         f"callable, got {preconditioner!r}")

    area = halfspace.h**2
    operator = _Operator(halfspace, shift)
    h_face = np.where(on_face, height, 0.0)

    if force == 0.0:
        zero = np.zeros(shape)
        return ContactResult(zero, float(h_face[on_face].min()), zero.copy(), zero.copy(), 0.0,
                             0, 0.0, np.zeros(1), True, "zero load: no pressure")

    if callable(preconditioner):
        precondition = preconditioner
    else:
        precondition = make_preconditioner(preconditioner, halfspace, on_face, shift)

    # Initial pressure: the warm start if it carries load, else a rigid estimate.
    p = np.zeros(shape)
    if x0 is not None:
        p = np.where(on_face & (x0 > 0), x0, 0.0)
    if p.sum() <= 0:
        p = _initial_pressure(h_face, on_face, force, halfspace)
        x0_displacement = None
    c = force / (area * p.sum())
    p *= c
    # v = K p, the elastic displacement; u = v + shift p is formed from it.
    if x0_displacement is not None and np.array_equal(p, c * x0):
        v = c * _check_field("x0_displacement", x0_displacement, shape)
    else:
        v = operator(p)
    v_max = float(np.abs(v).max())

    # Work arrays; the loop updates in place.
    face_f = on_face.astype(float)
    t = np.zeros(shape)
    u = np.empty(shape)
    g = np.empty(shape)
    r = np.empty(shape)
    work = np.empty(shape)
    history = []
    gz_old = 1.0
    restart = True
    set_changed = True
    verified = False
    since_full = 0
    success = False
    message = ""
    it = 0
    d = float("nan")
    residual = float("nan")
    while True:
        if set_changed:
            active = p > 0
            active_f = active.astype(float)
            n_active = float(active.sum())
            off_f = face_f - active_f
            full_contact = n_active == n_face
        if shift is None:
            u[...] = v
        else:
            np.multiply(shift, p, out=u)
            u += v
        np.add(u, h_face, out=g)
        d = _dot(g, active_f) / n_active
        g -= d                        # the gap, on the face
        np.multiply(g, active_f, out=r)
        violation = _dot(r, r)
        if not full_contact:
            open_violation = np.minimum(g, 0.0)
            open_violation *= off_f
            violation += _dot(open_violation, open_violation)
        residual = float(np.sqrt(violation / n_face))
        scale = float(np.sqrt(_dot3(u, u, active_f) / n_active))
        tolerance = max(rtol * scale, atol)
        if not np.isfinite(residual):
            message = f"non-finite residual at iteration {it}"
            history.append(residual)
            break
        drift = since_full * _ROUNDING_PER_ITERATION * np.finfo(float).eps * v_max
        if residual <= tolerance and (verified or drift < 1e-3 * tolerance):
            history.append(residual)
            success = True
            message = (f"converged in {it} iterations: residual {residual:.3e} m "
                       f"<= {tolerance:.3e} m")
            break
        if (residual <= tolerance and not verified) or since_full >= _REFRESH:
            # Recompute the incrementally updated displacement (drift).
            v = operator(p)
            v_max = float(np.abs(v).max())
            since_full = 0
            verified = True
            continue
        verified = False
        history.append(residual)
        if it >= maxiter:
            message = (f"no convergence in {maxiter} iterations: residual {residual:.3e} m "
                       f"> {tolerance:.3e} m")
            break
        it += 1

        # Preconditioned residual, projected to zero mean on the active set
        # (the load constraint).
        z = r.copy() if precondition is None else precondition(r, active)
        z -= np.multiply(active_f, _dot(z, active_f) / n_active, out=work)
        gz = _dot(r, z)
        if restart or gz_old == 0:
            t = z
        else:
            t *= gz / gz_old
            t += z
            if set_changed:
                t *= active_f
                t -= (_dot(t, active_f) / n_active) * active_f
        gz_old = gz
        q = operator(t)               # K t; A t = K t + shift t
        tq = _dot(t, q)
        if shift is not None:
            tq += _dot3(t, t, shift)
        if not tq > 0:
            message = f"breakdown at iteration {it}: non-positive curvature {tq!r}"
            break
        tau = _dot(r, t) / tq
        p -= np.multiply(t, tau, out=work)
        v -= np.multiply(q, tau, out=work)
        since_full += 1

        # Pixels leaving (negative pressure) and entering (penetrating) the set.
        leaving = p < 0
        any_leaving = bool(leaving.any())
        entering = None
        if not full_contact:
            entering = (g < 0) & (off_f > 0)
        restart = entering is not None and bool(entering.any())
        set_changed = any_leaving or restart
        if set_changed:
            dp = np.zeros(shape)
            dp[leaving] = -p[leaving]
            if restart:
                if precondition is None:
                    # Polonsky & Keer's rule: the steepest-descent step on those pixels.
                    dp[entering] = -tau * g[entering]
                else:
                    # The same step length, as pressure per gap on the active set,
                    # capped by the pressure that closes each gap alone.
                    rate = abs(tau) * np.sqrt(_dot(t, t) / max(_dot(r, r), np.finfo(float).tiny))
                    diagonal = np.broadcast_to(operator.diagonal, shape)[entering]
                    dp[entering] = -g[entering] * np.minimum(rate, 1.0 / diagonal)
            p += dp
            p[leaving] = 0.0
            ii, jj = np.nonzero(dp)
            if ii.size <= _DIRECT_UPDATE_PIXELS:
                v += operator.columns(ii, jj, dp[ii, jj])
            else:
                v = operator(p)
                v_max = float(np.abs(v).max())
                since_full = 0
            total = p.sum()
            if not total > 0:
                message = f"all pressure lost at iteration {it}"
                break
            c = force / (area * total)
            p *= c
            v *= c
        if callback is not None:
            view = p.view()
            view.flags.writeable = False
            callback(view)

    residual_history = np.asarray(history)
    if not success:
        logger.warning("contact solver failed: %s", message)
        if np.all(np.isfinite(p)):
            v = operator(p)
            active = p > 0
            if active.any():
                d = float((v + (0.0 if shift is None else shift * p) + h_face)[active].mean())
    else:
        logger.debug("contact solver: %s (%d operator products)", message, operator.products)
    return ContactResult(
        pressure=p,
        approach=float(d),
        displacement=v if shift is None else v + shift * p,
        elastic_displacement=v,
        contact_fraction=float((p > 0).sum() / n_face),
        nit=it,
        residual=residual,
        residual_history=residual_history,
        success=success,
        message=message,
    )


def _dot3(a, b, c):
    """Sum of the elementwise product of three arrays of the same shape (no temporary)."""
    return float(np.einsum("ij,ij,ij->", a, b, c))


def _dot(a, b):
    """Sum of the elementwise product of two arrays of the same shape.

    ``einsum`` rather than BLAS: a threaded BLAS dot product can cost more
    than an FFT pair on a loaded machine.
    """
    return float(np.einsum("ij,ij->", a, b))
