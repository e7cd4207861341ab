"""The warm start of a run's implicit stages: the last few contact pressures, combined.

A run solves one contact problem per implicit stage; consecutive stages are
close, and the Galerkin combination of the last few pressures
(:class:`WarmStart`) starts each solve within a few iterations of its end.
It belongs to the stage solver (:class:`transient.solver.StageSolver`),
which pushes every stage's pressure and asks for the next start; a
checkpoint stores its pressures and their displacements.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WarmStart"]

# Eigenvalues of the predictor's Gram matrix below this fraction of the
# largest are dropped (the pressures of a run are nearly collinear).
_GRAM_CUTOFF = 1e-12


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
    problem : transient.problem.WearProblem
        The run's problem: its grid, face, operator and (for the linear law's
        stage, ``shift_scale``) its coefficient field.
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

    def _stage_products(self, recession, weight, scale, k, pairs):
        """The sums :meth:`predict` needs, in one pass over the pressures, block by block.

        Parameters
        ----------
        recession : ndarray, shape (nx ny,), m
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
            ``<d_i, g>``, ``g = K v_0 + scale weight v_0 + recession`` less its
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
        mean = float(np.add.reduce(products[0], where=face) + np.add.reduce(recession, where=face))
        if weight is not None:
            mean += scale * _dot(weight, values[0])  # the pressures vanish off the face
        mean /= np.count_nonzero(face)
        rows = sorted({i for i, _ in pairs})
        gradient, weighted = np.zeros(k), np.zeros(len(pairs))
        g = np.empty(min(_BLOCK, recession.size))
        d = np.empty((k, g.size))
        w = np.empty((len(rows), g.size))
        for block in _blocks(recession.size):
            m = block.stop - block.start
            gb = g[:m]
            if weight is None:
                np.add(products[0][block], recession[block], out=gb)
            else:
                np.multiply(weight[block], scale, out=gb)
                gb *= values[0][block]
                gb += products[0][block]
                gb += recession[block]
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

    def predict(self, recession, shift=None, *, shift_scale=None):
        """Warm start of the contact problem ``(K + diag(shift)) p = d - recession``.

        Parameters
        ----------
        recession : ndarray, shape (nx, ny), m
        shift : ndarray, shape (nx, ny), m/Pa, optional
        shift_scale : float, m, optional
            The shift is ``shift_scale`` times the wear coefficients
            (:attr:`transient.problem.WearProblem.wear_field`), the linear wear law's
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
                weight, scale, gram_k = (self.problem.wear_field.ravel(), shift_scale,
                                         self._gram_k)
                pairs = [(i, j) for i, j in everything if np.isnan(gram_k[i, j])]
            elif shift is not None:
                weight, scale, gram_k = (np.where(self.problem.face_mask, shift, 0.0).ravel(),
                                         1.0, np.empty((k, k)))
                pairs = everything
            else:
                weight, scale, pairs = None, 1.0, []
            rhs, sums = self._stage_products(np.ravel(recession), weight, scale, k, pairs)
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



