"""Preconditioners for the constrained conjugate gradient contact solver.

Each preconditioner approximates the inverse of the contact operator
``A = K + diag(shift)`` (``K`` the half-space influence operator of
:class:`steady.halfspace.HalfSpace`, m/Pa) and is applied to a gap
residual (m) on the current active set; it returns a pressure-like
direction (Pa) supported on that set.  Restricting a symmetric positive
definite approximation of ``A^-1`` to the active set keeps it symmetric
positive definite there, which is all the projected conjugate gradient
needs.

- :class:`FourierPreconditioner`: the inverse symbol of the circulant
  embedding of ``K + s`` (``~ E* |q| / 2`` at low wavenumber), on the
  padded ``2nx x 2ny`` grid or aliased to the ``nx x ny`` grid (cheaper); for
  a non-uniform shift one symbol per level of the shift, stitched by the
  shift map (:func:`shift_levels`).
- :class:`JacobiPreconditioner`: ``1 / diag(A)``.  Free; exact in the
  limit ``shift >> self-influence``.

Every preconditioner is registered by name (:data:`PRECONDITIONERS`,
:func:`register_preconditioner`); :func:`make_preconditioner` builds one
for a contact problem, and ``"auto"`` chooses among the others.

References
----------
E. A. H. Vollebregt, "A new solver for the elastic normal contact problem
using conjugate gradients, deflation, and an FFT-based preconditioner",
J. Comput. Phys. 257 (2014) 333-351, doi:10.1016/j.jcp.2013.10.005.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from steady.registry import Registry

__all__ = [
    "FourierPreconditioner",
    "JacobiPreconditioner",
    "PRECONDITIONERS",
    "ScaledShift",
    "make_preconditioner",
    "register_preconditioner",
    "shift_levels",
]

#: Preconditioner factories by name, ``factory(halfspace, face_mask, shift)``
#: (see :func:`register_preconditioner`); ``"none"`` maps to None.
PRECONDITIONERS = Registry("preconditioner", entry_point_group="runin.preconditioners")
PRECONDITIONERS.register("none", None)

# A shift at least this many times the largest eigenvalue of K on every face
# pixel makes the operator diagonal to within 10 %: "auto" then takes Jacobi,
# which costs nothing and needs no more iterations than the Fourier
# preconditioner there (docs/benchmarks.md, "Contact solver").
_DIAGONAL_DOMINANCE = 10.0
# Most levels of the stitched Fourier preconditioner for a non-uniform shift
# (one FFT pair each); more distinct values are interpolated between nodes.
_MAX_LEVELS = 4
# Floating-point types of the unpadded Fourier preconditioner's transforms.  Single
# precision halves their cost; the outer iteration stays in double (docs/benchmarks.md,
# "Contact solve on run-in problems").
_PRECISIONS = {"single": np.dtype(np.float32), "double": np.dtype(np.float64)}
# Relative spread of the shift (in units of the smallest eigenvalue plus the
# smallest shift) below which it is treated as uniform.
_UNIFORM_SPREAD = 1e-2


def _one_level(s_min, s_max, scale):
    """Whether a shift between ``s_min`` and ``s_max`` (m/Pa) is one level.

    A spread below ``_UNIFORM_SPREAD`` of the smallest ``scale + shift``
    (``scale`` the symbol's minimum) changes the operator's eigenvalues by
    less than that fraction: one level, the minimum, is as good.
    """
    return s_max - s_min <= _UNIFORM_SPREAD * (scale + s_min)


def _diagonal_floor(halfspace):
    """Least shift (m/Pa) on every face pixel for which ``"auto"`` takes Jacobi.

    ``_DIAGONAL_DOMINANCE`` times the largest eigenvalue of ``K``, bounded by
    the largest value of the padded symbol.
    """
    return _DIAGONAL_DOMINANCE * float(halfspace.influence_symbol.max())


def _symbol(halfspace, padded):
    """The Fourier symbol a :class:`FourierPreconditioner` inverts."""
    return halfspace.influence_symbol if padded else halfspace.aliased_symbol


def register_preconditioner(name):
    """Register a preconditioner factory under ``name`` (a decorator).

    The factory is called as ``factory(halfspace, face_mask, shift)`` with
    ``shift`` an array of the grid's shape ``(nx, ny)`` in m/Pa or None, and
    returns a callable
    ``z = precondition(residual, active)``.
    """
    return PRECONDITIONERS.register(name)


def make_preconditioner(name, halfspace, face_mask, shift):
    """The preconditioner ``name`` for one contact problem, or None for ``"none"``.

    Raises
    ------
    ValueError
        If no preconditioner has that name (the message lists the registered ones).
    """
    factory = PRECONDITIONERS[name]
    return None if factory is None else factory(halfspace, face_mask, shift)


class JacobiPreconditioner:
    """Diagonal preconditioner ``z = r / (K_00 + shift)``.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    shift : ndarray, shape (nx, ny), m/Pa, or None
    """

    def __init__(self, halfspace, shift=None):
        self.diagonal = halfspace.self_influence + (0.0 if shift is None else shift)

    def __call__(self, residual, active):
        """Apply to a residual (m), zero off the active set; returns Pa."""
        return residual / self.diagonal


class FourierPreconditioner:
    """Inverse symbol of the influence operator, shift-aware.

    ``padded=True``: the inverse of the ``2nx x 2ny`` circulant embedding
    ``C`` of ``K`` (one padded FFT pair per level and application).
    ``padded=False`` (default): the inverse of its ``(nx, ny)``-periodic
    aliasing, whose symbol is ``C``'s at the even wavenumbers (so it is
    positive too); one unpadded FFT pair per level, about a third of the
    cost, for a few more iterations (docs/benchmarks.md).

    For a uniform shift ``s`` the preconditioner is ``(C + s I)^-1``.  A
    non-uniform shift is sorted into levels ``sigma_j`` (its distinct
    values on the face, at most ``max_levels`` of them; otherwise nodes
    spaced evenly in ``log(lambda + s)``, ``lambda`` the smallest value of
    the symbol) with weights ``phi_j(x) >= 0``, ``sum_j phi_j = 1`` (the
    indicator of each value, or linear interpolation in ``log(lambda + s)``
    between neighbouring nodes), and the preconditioner is

        M = B B^T,    B = sum_j diag(phi_j) (C + sigma_j I)^(-1/2):

    a Fourier multiplier per level, stitched by the shift map.  For a
    pattern finer than the scale on which ``K`` equals the local shift it
    is ``1 / (K + s(x))`` pixel by pixel; for a smooth pattern it is
    ``C^-1``, whatever the shift.  ``M`` is symmetric positive definite.
    One unpadded (padded) FFT pair per level and application.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    shift : ndarray, shape (nx, ny), m/Pa, or None
    face_mask : ndarray of bool, shape (nx, ny), optional
        Pixels over which the shift's levels are taken (default: all).
    padded : bool, optional
        Apply on the zero-padded ``2nx x 2ny`` grid (default False).
    max_levels : int, optional
        Most levels of a non-uniform shift (default 4).
    precision : {"single", "double"}, optional
        Floating-point precision of the unpadded transforms (default
        ``"single"``: about half the cost, and an approximate inverse needs
        no more while the residual is to fall by a few orders; :meth:`accurate`
        applies it in double precision).  The padded form always uses the
        half-space's double-precision transforms.  The result is double
        precision either way.
    """

    def __init__(self, halfspace, shift=None, *, face_mask=None, padded=False,
                 max_levels=_MAX_LEVELS, precision="single"):
        scale = float(_symbol(halfspace, padded).min())
        levels, weights = shift_levels(shift, face_mask, scale, max_levels)
        self._set_levels(halfspace, levels, weights, padded, precision)

    @classmethod
    def from_levels(cls, halfspace, levels, weights, *, padded=False, precision="single"):
        """The preconditioner of given levels and weights, as :func:`shift_levels` returns.

        For callers that know the levels of their shift without a pass over
        it (:class:`ScaledShift`).  ``weights`` are used as they are (not
        copied).
        """
        self = cls.__new__(cls)
        self._set_levels(halfspace, [float(s) for s in levels], weights, padded, precision)
        return self

    def _set_levels(self, halfspace, levels, weights, padded, precision):
        if precision not in _PRECISIONS:
            raise ValueError(f"precision must be one of {sorted(_PRECISIONS)}, "
                             f"got {precision!r}")
        self.halfspace = halfspace
        self.padded = bool(padded)
        self.levels = levels
        self.weights = weights
        # The padded transforms are the half-space's own, in double precision.
        self.dtype = np.dtype(float) if self.padded else _PRECISIONS[precision]
        self._plans = {}
        self._plan(self.dtype)

    def _plan(self, dtype):
        """Multipliers, weights and work buffers of the transforms in ``dtype``, built once.

        The multipliers are ``1 / (C + sigma)`` for one level, ``(C + sigma_j)^(-1/2)``
        for several.  The weighted residual and each level's spectrum go through work
        buffers: fresh arrays of this size cost as much as a transform.
        """
        plan = self._plans.get(dtype)
        if plan is None:
            symbol = _symbol(self.halfspace, self.padded)
            if self.weights is None:
                multipliers, weights = [_multiplier(symbol, self.levels[0], dtype, False)], None
            else:
                multipliers = [_multiplier(symbol, s, dtype, True) for s in self.levels]
                weights = [phi if phi.dtype == dtype else phi.astype(dtype)
                           for phi in self.weights]
            plan = self._plans[dtype] = dict(
                multipliers=multipliers, weights=weights,
                field=np.empty(self.halfspace.shape, dtype),
                weighted=None if weights is None else np.empty(self.halfspace.shape, dtype),
                spectrum=None)
        return plan

    # scipy.fft's transforms, which return fresh arrays: numpy.fft's into work buffers took
    # more CPU time here in single precision (docs/benchmarks.md, "Contact solve on run-in
    # problems").
    def _forward(self, field):
        hs = self.halfspace
        if self.padded:
            return hs.forward(field)
        return scipy.fft.rfft2(field, workers=hs.workers)

    def _inverse(self, spectrum):
        hs = self.halfspace
        if self.padded:
            return hs.inverse(spectrum, overwrite=True)
        return scipy.fft.irfft2(spectrum, s=hs.shape, workers=hs.workers, overwrite_x=True)

    def __call__(self, residual, active):
        """Apply to a residual (m), zero off the active set; returns Pa (float64)."""
        return self._apply(residual, active, self.dtype)

    def accurate(self, residual, active):
        """:meth:`__call__` with double-precision transforms whatever the precision.

        For a solve that must reduce its residual by many orders, where the
        round-off of single-precision transforms costs iterations
        (:func:`transient.contact.solve_contact` takes it for a reduction of
        more than ``1e4``).  Built on first use.
        """
        return self._apply(residual, active, np.dtype(float))

    def unrestricted(self, residual, *, accurate=False):
        """The preconditioned residual before its restriction to the active set.

        :meth:`__call__` (``accurate=True``: :meth:`accurate`) is this times the
        active set's indicator, in double precision; a caller that multiplies by
        that indicator anyway saves the pass.

        Parameters
        ----------
        residual : ndarray, shape (nx, ny), m
            Zero off the active set.
        accurate : bool, optional
            Double-precision transforms whatever the precision (default False).

        Returns
        -------
        ndarray, shape (nx, ny), Pa
            A fresh array in the transforms' precision (float32 for ``"single"``).
        """
        return self._transform(residual, np.dtype(float) if accurate else self.dtype)

    def _apply(self, residual, active, dtype):
        z = self._transform(residual, dtype)
        return np.multiply(z, active, out=np.empty(residual.shape))

    def _transform(self, residual, dtype):
        """The preconditioned residual, unrestricted, in ``dtype`` (a fresh array)."""
        plan = self._plan(dtype)
        field = plan["field"]
        field[...] = residual
        if plan["weights"] is None:
            spectrum = self._forward(field)
            spectrum *= plan["multipliers"][0]
            return self._inverse(spectrum)
        # B^T r: one transform per level, summed in Fourier space (the residual converted to
        # the transforms' type once: a product of mixed types converts in buffers, which at
        # n = 1024 in single precision took 1.0 ms against 0.45 + 0.30 ms) ...
        total = None
        for phi, root in zip(plan["weights"], plan["multipliers"], strict=True):
            spectrum = self._forward(np.multiply(phi, field, out=plan["weighted"]))
            spectrum *= root
            total = spectrum if total is None else total.__iadd__(spectrum)
        # ... then B: one inverse transform per level.
        if plan["spectrum"] is None:
            plan["spectrum"] = np.empty_like(total)
        z = None
        for phi, root in zip(plan["weights"], plan["multipliers"], strict=True):
            part = self._inverse(np.multiply(total, root, out=plan["spectrum"]))
            part *= phi
            z = part if z is None else z.__iadd__(part)
        return z


def _multiplier(symbol, level, dtype, root):
    """``1 / (symbol + level)``, or its square root (``root``), in ``dtype``.

    In double precision, rounded once into ``dtype``: the same values as
    ``(1 / sqrt(symbol + level)).astype(dtype)`` through one temporary instead of
    three fresh arrays (a stage builds its multipliers anew; docs/benchmarks.md,
    "Contact solve on run-in problems").
    """
    shifted = symbol + level
    if root:
        np.sqrt(shifted, out=shifted)
    return np.divide(1.0, shifted, out=np.empty(symbol.shape, dtype))


def shift_levels(shift, face_mask, scale, max_levels=_MAX_LEVELS):
    """Levels and weights of a diagonal shift for the stitched Fourier preconditioner.

    Parameters
    ----------
    shift : ndarray, shape (nx, ny), m/Pa, or None
    face_mask : ndarray of bool, shape (nx, ny), or None
        Pixels whose shift counts (default: all).
    scale : float, m/Pa
        Smallest eigenvalue scale of the operator (the symbol's minimum):
        shifts differing by much less than ``scale + shift`` are one level.
    max_levels : int, optional
        Most levels (default 4).

    Returns
    -------
    levels : list of float, m/Pa
        ``sigma_j``, increasing; one value for a uniform shift.
    weights : list of ndarray, shape (nx, ny), or None
        ``phi_j``, non-negative, summing to one on every pixel; None for a
        uniform shift.
    """
    if shift is None:
        return [0.0], None
    values = np.ravel(shift) if face_mask is None else shift[face_mask]
    s_min, s_max = float(values.min()), float(values.max())
    if _one_level(s_min, s_max, scale):
        return [s_min], None
    distinct = _few_distinct(values, max_levels)
    if distinct is not None:
        levels = [float(v) for v in distinct]
        weights = [(shift == v).astype(float) for v in distinct]
        return levels, weights
    # Linear interpolation in log(scale + s) between evenly spaced nodes.
    t = np.log(scale + np.clip(shift, s_min, s_max))
    nodes = np.linspace(np.log(scale + s_min), np.log(scale + s_max), max_levels)
    position = np.clip((t - nodes[0]) / (nodes[1] - nodes[0]), 0.0, max_levels - 1.0)
    levels = [float(np.exp(v) - scale) for v in nodes]
    weights = [np.clip(1.0 - np.abs(position - j), 0.0, None) for j in range(max_levels)]
    return levels, weights


class ScaledShift:
    """The ``"auto"`` preconditioner of ``K + c diag(k)`` for any ``c > 0``, ``k`` fixed.

    A run's linear-law stages shift the operator by ``c k``, the wear
    coefficients times a stage's step: the same pattern at every stage.
    Its extremes and, for a few distinct values (a phase-wise ``k``), its
    levels and their indicator weights are found once here; each stage's
    preconditioner then costs its symbols only.  It is the one
    :func:`make_preconditioner` builds for ``"auto"`` and the shift
    ``c k`` (the same choice of Jacobi, one level or the levels of ``k``);
    a pattern of more than ``max_levels`` values, whose weights depend on
    ``c``, is built afresh each time.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    face_mask : ndarray of bool, shape (nx, ny)
    pattern : ndarray, shape (nx, ny)
        ``k``, non-negative and finite on the face (its unit times ``c``'s
        is m/Pa).
    """

    def __init__(self, halfspace, face_mask, pattern):
        self.halfspace = halfspace
        self.face_mask = face_mask
        values = pattern[face_mask]
        self.low, self.high = float(values.min()), float(values.max())
        distinct = _few_distinct(values, _MAX_LEVELS)
        self.values = None if distinct is None else [float(v) for v in distinct]
        # (in the precision of the default transforms, so that no stage converts them)
        self.weights = (None if distinct is None or len(distinct) == 1
                        else [(pattern == v).astype(_PRECISIONS["single"]) for v in distinct])
        self._diagonal = _diagonal_floor(halfspace)
        self._scale = float(_symbol(halfspace, False).min())

    def preconditioner(self, c, shift):
        """The preconditioner of ``K + diag(shift)`` with ``shift = c * pattern``.

        Parameters
        ----------
        c : float
            Positive factor.
        shift : ndarray, shape (nx, ny), m/Pa
            ``c * pattern`` (the caller's array, used by Jacobi and by a
            pattern of many values).
        """
        hs = self.halfspace
        low, high = c * self.low, c * self.high
        if low >= self._diagonal:
            return JacobiPreconditioner(hs, shift)
        if _one_level(low, high, self._scale):
            return FourierPreconditioner.from_levels(hs, [low], None)
        if self.weights is None:
            return FourierPreconditioner(hs, shift, face_mask=self.face_mask)
        return FourierPreconditioner.from_levels(hs, [c * v for v in self.values], self.weights)


def _few_distinct(values, limit):
    """The sorted distinct values of an array if there are at most ``limit``, else None.

    One pass over the array per value found, cheaper than a sort for the few
    levels of a phase-wise shift.
    """
    found = []
    rest = values
    while rest.size:
        if len(found) == limit:
            return None
        found.append(rest[0])
        rest = rest[rest != rest[0]]
    return sorted(found)


@register_preconditioner("jacobi")
def _jacobi(halfspace, face_mask, shift):
    return JacobiPreconditioner(halfspace, shift)


@register_preconditioner("fourier")
def _fourier(halfspace, face_mask, shift):
    return FourierPreconditioner(halfspace, shift, face_mask=face_mask)


@register_preconditioner("fourier-padded")
def _fourier_padded(halfspace, face_mask, shift):
    return FourierPreconditioner(halfspace, shift, face_mask=face_mask, padded=True)


@register_preconditioner("auto")
def _auto(halfspace, face_mask, shift):
    """Fourier (stitched by the shift's levels), unless the shift makes the operator diagonal.

    A shift of at least ``_DIAGONAL_DOMINANCE`` times the largest eigenvalue
    of ``K`` (:func:`_diagonal_floor`) on every face pixel leaves
    ``K + diag(shift)`` within 10 % of its diagonal: Jacobi, which costs
    nothing, is then as good.
    """
    if shift is not None and shift[face_mask].min() >= _diagonal_floor(halfspace):
        return _jacobi(halfspace, face_mask, shift)
    return _fourier(halfspace, face_mask, shift)
