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
  pixels, plus the shift).  Kept for comparison; needs :mod:`pyamg`.

References
----------
E. A. H. Vollebregt, "A new solver for the elastic normal contact problem
using conjugate gradients, deflation, and an FFT-based preconditioner",
J. Comput. Phys. 257 (2014) 333-351, doi:10.1016/j.jcp.2013.10.005.
"""

from __future__ import annotations

import logging
import weakref

import numpy as np
import scipy.fft
import scipy.sparse


__all__ = [
    "AMGPreconditioner",
    "FourierPreconditioner",
    "JacobiPreconditioner",
    "influence_quadrant",
    "influence_symbol",
]

logger = logging.getLogger(__name__)


# Kernels per half-space, built on first use and dropped with the half-space.
_KERNELS = weakref.WeakKeyDictionary()


def _kernels(halfspace):
    """``(quadrant (n+1, n+1), symbol (2n, n+1))`` of a half-space, cached."""
    key = (halfspace.n, halfspace.h, halfspace.E_star)
    cached = _KERNELS.get(halfspace)
    if cached is not None and cached[0] == key:
        return cached[1], cached[2]
    quadrant = halfspace.influence_quadrant()
    quadrant.flags.writeable = False
    symbol = halfspace.influence_symbol
    _KERNELS[halfspace] = (key, quadrant, symbol)
    return quadrant, symbol


def _inverse_symbol(halfspace, padded):
    """``1 / influence_symbol`` (``padded``) or of its ``n``-periodic aliasing, cached."""
    _kernels(halfspace)
    cached = _KERNELS[halfspace]
    if len(cached) < 4:
        symbol = cached[2]
        inverse = (1.0 / symbol, 1.0 / np.ascontiguousarray(symbol[::2, ::2]))
        for array in inverse:
            array.flags.writeable = False
        cached = cached + inverse
        _KERNELS[halfspace] = cached
    return cached[3] if padded else cached[4]


def influence_quadrant(halfspace):
    """Influence coefficients at non-negative pixel offsets.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace

    Returns
    -------
    ndarray, shape (n, n), m/Pa, read-only
        Displacement at offset ``(i, j)`` pixels from a pixel loaded by a
        unit pressure; the kernel is even in both axes.  Cached per
        half-space.
    """
    n = halfspace.n
    return _kernels(halfspace)[0][:n, :n]


def influence_symbol(halfspace):
    """Real spectrum of the ``2n x 2n`` circulant embedding of the influence kernel.

    Built with the same even extension as the half-space operator, so that
    ``halfspace.inverse(halfspace.forward(p) * symbol)`` equals
    ``halfspace.displacement(p)`` to round-off.  Cached per half-space.

    Returns
    -------
    ndarray, shape (2n, n + 1), m/Pa, read-only
        Positive for the exact pixel kernel (checked at ``n`` = 32 to 1024).
    """
    return _kernels(halfspace)[1]


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
    face : ndarray of bool, shape (n, n), optional
        Pixels over which the shift's range is taken (default: all).
    padded : bool, optional
        Apply on the zero-padded ``2n x 2n`` grid (default False).
    """

    def __init__(self, halfspace, shift=None, *, face=None, padded=False):
        self.halfspace = halfspace
        self.padded = bool(padded)
        k00 = halfspace.self_influence
        self.weight = None
        self.diagonal = None
        s_ref = 0.0
        if shift is not None:
            s_face = shift if face is None else shift[face]
            s_ref = float(s_face.min())
            if float(s_face.max()) > s_ref * (1 + 1e-12):
                self.weight = np.sqrt((k00 + s_ref) / (k00 + shift))
                self.diagonal = (1.0 - self.weight**2) / (k00 + shift)
        if s_ref == 0:
            self.inverse_symbol = _inverse_symbol(halfspace, self.padded)
        else:
            symbol = influence_symbol(halfspace)
            if not self.padded:
                symbol = symbol[::2, ::2]
            self.inverse_symbol = 1.0 / (symbol + s_ref)

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
    face : ndarray of bool, shape (n, n)
    shift : ndarray, shape (n, n), m/Pa, or None
    radius : int, optional
        Truncation radius of the kernel, pixels (default 2).
    """

    def __init__(self, halfspace, face, shift=None, *, radius=2):
        import pyamg  # optional dependency, imported on use

        n = halfspace.n
        radius = int(radius)
        quadrant = influence_quadrant(halfspace)[: radius + 1, : radius + 1]
        index = -np.ones((n, n), dtype=np.int64)
        ii, jj = np.nonzero(face)
        index[ii, jj] = np.arange(ii.size)
        rows, cols, vals = [], [], []
        for di in range(-radius, radius + 1):
            for dj in range(-radius, radius + 1):
                if di * di + dj * dj > radius * radius:
                    continue
                i2, j2 = ii + di, jj + dj
                ok = (i2 >= 0) & (i2 < n) & (j2 >= 0) & (j2 < n)
                ok[ok] &= face[i2[ok], j2[ok]]
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
