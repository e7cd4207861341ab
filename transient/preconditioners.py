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
  embedding of ``K`` (``~ E* |q| / 2`` at low wavenumber), on the padded
  ``2n x 2n`` grid or aliased to the ``n x n`` grid (cheaper), plus a
  diagonal share for a non-uniform shift.
- :class:`JacobiPreconditioner`: ``1 / diag(A)``.  Free; exact in the
  limit ``shift >> self-influence``.
- :class:`AMGPreconditioner`: one smoothed-aggregation V-cycle (pyamg) on
  a sparse surrogate of ``A`` (the influence kernel truncated to a few
  pixels, plus the shift).  Kept for comparison; needs the optional extra
  ``runin[amg]``.

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

import logging

import numpy as np
import scipy.fft
import scipy.sparse

__all__ = [
    "AMGPreconditioner",
    "FourierPreconditioner",
    "JacobiPreconditioner",
    "PRECONDITIONERS",
    "make_preconditioner",
    "register_preconditioner",
]

logger = logging.getLogger(__name__)

#: Preconditioner factories by name, ``factory(halfspace, face_mask, shift)``
#: (see :func:`register_preconditioner`); ``"none"`` maps to None.
PRECONDITIONERS = {"none": None}

# A non-uniform shift at least this many self-influences K_00 on every face
# pixel makes the operator nearly diagonal: "auto" then takes Jacobi, which
# needs about as many iterations as the Fourier blend and costs nothing
# (docs/benchmarks.md, "Contact solver").
_DIAGONAL_DOMINANCE = 3.0


def register_preconditioner(name):
    """Register a preconditioner factory under ``name`` (a decorator).

    The factory is called as ``factory(halfspace, face_mask, shift)`` with
    ``shift`` an ``(n, n)`` array in m/Pa or None, and returns a callable
    ``z = precondition(residual, active)``.
    """
    def decorate(factory):
        PRECONDITIONERS[name] = factory
        return factory
    return decorate


def make_preconditioner(name, halfspace, face_mask, shift):
    """The preconditioner ``name`` for one contact problem, or None for ``"none"``.

    Raises
    ------
    ValueError
        If no preconditioner has that name.
    """
    try:
        factory = PRECONDITIONERS[name]
    except KeyError:
        raise ValueError(f"preconditioner must be one of {sorted(PRECONDITIONERS)}, "
                         f"got {name!r}") from None
    return None if factory is None else factory(halfspace, face_mask, shift)


class JacobiPreconditioner:
    """Diagonal preconditioner ``z = r / (K_00 + shift)``.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    shift : ndarray, shape (n, n), m/Pa, or None
    """

    def __init__(self, halfspace, shift=None):
        self.diagonal = halfspace.self_influence + (0.0 if shift is None else shift)

    def __call__(self, residual, active):
        """Apply to a residual (m), zero off the active set; returns Pa."""
        return residual / self.diagonal


class FourierPreconditioner:
    """Inverse symbol of the influence operator, shift-aware.

    ``padded=True``: the exact inverse of the ``2n x 2n`` circulant
    embedding ``C`` of ``K`` (one padded FFT pair per application).
    ``padded=False`` (default): the inverse of its ``n``-periodic
    aliasing, whose symbol is ``C``'s at the even wavenumbers (so it is
    positive too); one unpadded FFT pair, about a third of the cost, for a
    few more iterations (docs/benchmarks.md).

    For a uniform shift ``s`` the symbol is that of ``K + s I``.  For a
    non-uniform shift the preconditioner is ``W C_s^-1 W + (I - W^2) D^-1``
    with ``C_s`` the circulant of ``K + min(shift) I``,
    ``D = diag(K_00 + shift)`` and ``W^2 = (K_00 + min shift) / (K_00 + shift)``:
    where the shift is small the Fourier part acts, where it dominates the
    (then nearly exact) diagonal part takes over.  Both terms are symmetric
    positive (semi-)definite, so the sum is too.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    shift : ndarray, shape (n, n), m/Pa, or None
    face_mask : ndarray of bool, shape (n, n), optional
        Pixels over which the shift's range is taken (default: all).
    padded : bool, optional
        Apply on the zero-padded ``2n x 2n`` grid (default False).
    """

    def __init__(self, halfspace, shift=None, *, face_mask=None, padded=False):
        self.halfspace = halfspace
        self.padded = bool(padded)
        k00 = halfspace.self_influence
        self.weight = None
        self.diagonal = None
        s_ref = 0.0
        if shift is not None:
            s_face = shift if face_mask is None else shift[face_mask]
            s_ref = float(s_face.min())
            if float(s_face.max()) > s_ref * (1 + 1e-12):
                self.weight = np.sqrt((k00 + s_ref) / (k00 + shift))
                self.diagonal = (1.0 - self.weight**2) / (k00 + shift)
        symbol = halfspace.influence_symbol if self.padded else halfspace.aliased_symbol
        self.inverse_symbol = 1.0 / symbol if s_ref == 0 else 1.0 / (symbol + s_ref)

    def _apply(self, field):
        hs = self.halfspace
        if self.padded:
            return hs.inverse(hs.forward(field) * self.inverse_symbol)
        n = hs.n
        spectrum = scipy.fft.rfft2(field, workers=hs.workers)
        spectrum *= self.inverse_symbol
        return scipy.fft.irfft2(spectrum, s=(n, n), workers=hs.workers)

    def __call__(self, residual, active):
        """Apply to a residual (m), zero off the active set; returns Pa."""
        if self.weight is None:
            z = self._apply(residual)
        else:
            z = self.weight * self._apply(self.weight * residual)
            z += self.diagonal * residual
        z *= active
        return z


class AMGPreconditioner:
    """One smoothed-aggregation V-cycle on a sparse surrogate of the operator.

    The surrogate keeps the influence kernel within ``radius`` pixels
    (plus the shift on the diagonal) on the face pixels; the hierarchy is
    built once for the face and the V-cycle is restricted to the active
    set, which keeps it symmetric positive definite there.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    face_mask : ndarray of bool, shape (n, n)
    shift : ndarray, shape (n, n), m/Pa, or None
    radius : int, optional
        Truncation radius of the kernel, pixels (default 2).
    """

    def __init__(self, halfspace, face_mask, shift=None, *, radius=2):
        try:
            import pyamg  # optional dependency, imported on use
        except ImportError:
            raise ValueError("the 'amg' preconditioner needs pyamg: install the optional "
                             "extra with pip install 'runin[amg]'") from None

        n = halfspace.n
        radius = int(radius)
        quadrant = halfspace.influence_quadrant[: radius + 1, : radius + 1]
        index = -np.ones((n, n), dtype=np.int64)
        ii, jj = np.nonzero(face_mask)
        index[ii, jj] = np.arange(ii.size)
        rows, cols, vals = [], [], []
        for di in range(-radius, radius + 1):
            for dj in range(-radius, radius + 1):
                if di * di + dj * dj > radius * radius:
                    continue
                i2, j2 = ii + di, jj + dj
                ok = (i2 >= 0) & (i2 < n) & (j2 >= 0) & (j2 < n)
                ok[ok] &= face_mask[i2[ok], j2[ok]]
                rows.append(index[ii[ok], jj[ok]])
                cols.append(index[i2[ok], j2[ok]])
                vals.append(np.full(ok.sum(), quadrant[abs(di), abs(dj)]))
        rows, cols, vals = map(np.concatenate, (rows, cols, vals))
        diag = np.zeros(ii.size)
        if shift is not None:
            diag = shift[ii, jj]
        matrix = scipy.sparse.csr_matrix(
            (np.concatenate([vals, diag]), (np.concatenate([rows, np.arange(ii.size)]),
                                            np.concatenate([cols, np.arange(ii.size)]))),
            shape=(ii.size, ii.size))
        # Scale to O(1) entries so that pyamg's strength thresholds are meaningful.
        self._scale = float(quadrant[0, 0])
        self._solver = pyamg.smoothed_aggregation_solver(matrix / self._scale,
                                                         symmetry="symmetric")
        self._index = (ii, jj)
        self._shape = (n, n)
        logger.debug("AMG hierarchy: %d levels for %d face pixels",
                     len(self._solver.levels), ii.size)

    def __call__(self, residual, active):
        """Apply to a residual (m) on the active set; returns Pa."""
        ii, jj = self._index
        r = np.where(active, residual, 0.0)[ii, jj]
        x = self._solver.solve(r, x0=np.zeros_like(r), maxiter=1, cycle="V", tol=1e-300)
        z = np.zeros(self._shape)
        z[ii, jj] = x / self._scale
        return np.where(active, z, 0.0)


@register_preconditioner("jacobi")
def _jacobi(halfspace, face_mask, shift):
    return JacobiPreconditioner(halfspace, shift)


@register_preconditioner("fourier")
def _fourier(halfspace, face_mask, shift):
    return FourierPreconditioner(halfspace, shift, face_mask=face_mask)


@register_preconditioner("fourier-padded")
def _fourier_padded(halfspace, face_mask, shift):
    return FourierPreconditioner(halfspace, shift, face_mask=face_mask, padded=True)


@register_preconditioner("amg")
def _amg(halfspace, face_mask, shift):
    return AMGPreconditioner(halfspace, face_mask, shift)


@register_preconditioner("auto")
def _auto(halfspace, face_mask, shift):
    """Fourier, unless a non-uniform shift makes the operator nearly diagonal (Jacobi).

    A uniform shift keeps the Fourier symbol exact; a non-uniform one of at
    least ``_DIAGONAL_DOMINANCE`` self-influences everywhere on the face
    leaves little for the Fourier part to do.
    """
    if shift is not None:
        s_face = shift[face_mask]
        if (s_face.max() > s_face.min()
                and s_face.min() >= _DIAGONAL_DOMINANCE * halfspace.self_influence):
            return _jacobi(halfspace, face_mask, shift)
    return _fourier(halfspace, face_mask, shift)
