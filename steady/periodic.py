"""Elastic half-space operator on a periodic cell of square pixels.

The face covers a cell ``nx h x ny h`` that repeats in both directions.  The
surface displacement of the half-space under a pressure constant on each
pixel of the cell is a circular convolution of the pixel pressures: one
plain real FFT pair of the cell, no zero padding.

Symbol
------
A pressure constant on the pixels has the continuum spectrum
``P(Q) = P_d(q) s(Q_x) s(Q_y)`` at every alias ``Q = q + 2 pi (m, l) / h``
of a grid wavenumber ``q``, with ``s(Q) = sin(Q h / 2) / (Q h / 2)`` the
pixel's form factor; the displacement ``2 P(Q) c(|Q|) / (E* |Q|)``
(Johnson, *Contact Mechanics*, sec. 3.9 in Fourier form; ``c`` the
optional compliance factor, 1 for the half-space), sampled at the pixel
centres, aliases back to ``q``.  The discrete symbol is therefore::

    S(q) = sum over (m, l) of 2 c(|Q|) / (E* |Q|) s(Q_x) s(Q_y),

and ``u = irfft2(S rfft2(p))`` is the continuum displacement at the pixel
centres, exactly.  The series converges slowly (its terms fall as
``|Q|^-3`` with alternating signs).  For ``c = 1`` it is summed by an
Ewald-type split: ``1 / |Q| = (2 / sqrt(pi)) int_0^inf exp(-t^2 |Q|^2) dt``
makes each ``t`` separable in ``x`` and ``y``; each axis' alias sum of
``s(Q) exp(-t^2 Q^2)`` is taken in Fourier space for ``t >= 0.3 h`` and,
by Poisson's formula, as the pixel box smoothed by a Gaussian in real space
for smaller ``t`` (both sides to ``exp(-42)``); below ``t0 = 0.03 h`` the
integrand is 1 to within ``erfc(8)``, and above, Gauss-Legendre panels in
``log t`` integrate it.  The result matches a brute-force alias sum
extrapolated in its cut-off to 4e-14 of the symbol's largest value, the
brute sum's own error (``tests/test_periodic.py``).  The surface gradient's
symbol (``i Q_x`` times the terms) is summed the same way (to 6e-10 of its
largest value, again the brute sum's error).  With a compliance factor the
correction ``c - 1``, which must tend to zero at large ``|Q|`` (a layer's
does exponentially), is summed directly over rings of aliases until two
rings each add less than ``1e-13`` of the symbol's largest value.

The mean
--------
A periodic load's mean displacement is unbounded on a half-space: only its
differences are defined, and the mean pressure is set by the load.  The
operator fixes the arbitrary mean as ``S_0`` times the mean pressure, ``S_0``
the symbol's largest value (the cell's longest wave, about
``max(W, L) / (pi E*)``): the displacement of a cell then has the elastic
scale of a punch of the cell's size, which the contact solver's stopping rule
measures its residual against, and the operator is positive definite.  Only
differences of the displacement mean anything; figures and statistics of a
cell remove its mean.
"""

from __future__ import annotations

import copy
import functools
import math

import numpy as np
import scipy.fft
import scipy.special

from .halfspace import _E_STAR, _PIXEL, grid_shape

__all__ = ["PeriodicHalfSpace"]

# Each axis' alias sum is taken in Fourier space from this t / h up, in real space below;
# both sides keep terms down to exp(-_GAUSS_CUT^2).
_SWITCH = 0.3
_GAUSS_CUT = 6.5
# Below t0 = _T0 h the integrand is 1 (0 for the gradient) to within erfc(_T0^-1 / 4).
_T0 = 0.03
# Gauss-Legendre nodes per unit of log t, and the panels' extent beyond the longest period.
_NODES_PER_PANEL = 16
_TAIL = 1.5
# A compliance correction's ring of aliases smaller than this share of the symbol ends its sum;
# 64 rings reach |Q| = 128 pi / h, where a layer's correction exp(-2 |Q| H) is below 1e-13 for
# any thickness H above h / 25.
_RING_TOL = 1e-13
_MAX_RINGS = 64


def _axis_sums(q, t, h, derivative):
    """``sum_m s(Q_m) exp(-t^2 Q_m^2)`` (times ``Q_m`` with ``derivative``), shape (K, len(q)).

    ``Q_m = q + 2 pi m / h``.  Fourier side for ``t >= _SWITCH h``; else the
    Poisson dual, the pixel box convolved with the Gaussian of
    ``exp(-t^2 Q^2)`` sampled at the pixel offsets.
    """
    out = np.empty((t.size, q.size))
    fourier = t >= _SWITCH * h
    if fourier.any():
        tf = t[fourier][:, None, None]
        m_max = math.ceil(_GAUSS_CUT * h / (2 * np.pi * float(tf.min())) + 1)
        Q = q[None, None, :] + 2 * np.pi * np.arange(-m_max, m_max + 1)[None, :, None] / h
        terms = np.sinc(Q * h / (2 * np.pi)) * np.exp(-(tf * Q) ** 2)
        if derivative:
            terms *= Q
        out[fourier] = terms.sum(axis=1)
    real = ~fourier
    if real.any():
        tr = t[real][:, None, None]
        j = np.arange(1, math.ceil(2 * _GAUSS_CUT * float(tr.max()) / h + 1.5))[None, :, None]
        lo, hi = (j - 0.5) * h / (2 * tr), (j + 0.5) * h / (2 * tr)
        if derivative:
            # -h sum_j f'(jh) sin(q j h), f = box / h convolved with the Gaussian; f' odd.
            fprime = (np.exp(-hi**2) - np.exp(-lo**2)) / (2 * h * math.sqrt(math.pi) * tr)
            out[real] = -2 * h * np.sum(fprime * np.sin(q[None, None, :] * j * h), axis=1)
        else:
            a0 = scipy.special.erf(h / (4 * t[real]))[:, None]
            aj = 0.5 * (scipy.special.erfc(lo) - scipy.special.erfc(hi))
            out[real] = a0 + 2 * np.sum(aj * np.cos(q[None, None, :] * j * h), axis=1)
    return out


def _log_t_nodes(h, longest):
    """Gauss-Legendre nodes and weights in ``t`` over ``[t0, t_max]``, panels of unit ``log t``.

    ``t_max`` puts ``exp(-t^2 q^2)`` below ``exp(-(_GAUSS_CUT + _TAIL)^2)`` for the
    smallest non-zero wavenumber ``2 pi / longest``.
    """
    s0 = math.log(_T0 * h)
    s1 = math.log((_GAUSS_CUT + _TAIL) * longest / (2 * np.pi))
    panels = max(1, math.ceil(s1 - s0))
    x, w = np.polynomial.legendre.leggauss(_NODES_PER_PANEL)
    edges = np.linspace(s0, s1, panels + 1)
    half = 0.5 * (edges[1:] - edges[:-1])
    s = ((edges[:-1] + half)[:, None] + half[:, None] * x[None, :]).ravel()
    weights = (half[:, None] * w[None, :]).ravel()
    t = np.exp(s)
    return t, weights * t  # dt = t ds


def _wavenumbers(shape, h):
    """``qx`` (full, ``fftfreq``) and ``qy`` (half, ``rfftfreq``), rad/m."""
    nx, ny = shape
    return (2 * np.pi * np.fft.fftfreq(nx, d=h), 2 * np.pi * np.fft.rfftfreq(ny, d=h))


def _halfspace_sums(shape, h):
    """Ewald-type sums ``int A_x A_y dt`` and ``int B_x A_y dt``, ``int A_x B_y dt``.

    Returns the three arrays of shape ``(nx, ny // 2 + 1)`` in units where the symbol
    is ``4 / (sqrt(pi) E*)`` times the first (plus ``t0``) and the gradient's
    imaginary parts the same factor times the others.
    """
    qx, qy = _wavenumbers(shape, h)
    t, w = _log_t_nodes(h, max(shape) * h)
    ax, ay = _axis_sums(qx, t, h, False), _axis_sums(qy, t, h, False)
    bx, by = _axis_sums(qx, t, h, True), _axis_sums(qy, t, h, True)
    wa = ax * w[:, None]
    return _T0 * h + wa.T @ ay, (bx * w[:, None]).T @ ay, wa.T @ by


def _alias_rings(shape, h, term):
    """``sum over aliases (m, l) of term(Qx, Qy)``, by rings ``max(|m|, |l|) = r``.

    Stops after two rings that each add less than ``_RING_TOL`` of the sum's
    largest value.

    Raises
    ------
    ValueError
        The rings still add more after ``_MAX_RINGS`` (a compliance factor that
        does not tend to 1).
    """
    qx, qy = _wavenumbers(shape, h)
    qx, qy = qx[:, None, None], qy[None, :, None]
    total = term(qx, qy)[..., 0]
    quiet = 0
    for r in range(1, _MAX_RINGS + 1):
        # The ring's aliases (m, l), max(|m|, |l|) = r, along a last axis.
        side = np.arange(-r, r + 1)
        m = np.concatenate([side, side, np.full(2 * r - 1, -r), np.full(2 * r - 1, r)])
        n_ = np.concatenate([np.full(2 * r + 1, -r), np.full(2 * r + 1, r), side[1:-1],
                             side[1:-1]])
        ring = term(qx + 2 * np.pi * m / h, qy + 2 * np.pi * n_ / h).sum(axis=-1)
        total += ring
        scale = max(float(np.max(np.abs(total))), np.finfo(float).tiny)
        quiet = quiet + 1 if float(np.max(np.abs(ring))) < _RING_TOL * scale else 0
        if quiet == 2:
            return total
    raise ValueError(f"the compliance factor's alias sum does not converge in {_MAX_RINGS} "
                     f"rings: the factor must tend to 1 at large wavenumbers")


class PeriodicHalfSpace:
    """Elastic half-space operator on an ``nx x ny`` periodic cell of square pixels.

    The same interface as :class:`steady.halfspace.HalfSpace`; the product is
    one plain FFT pair of the cell and the symbol integrates each pixel
    exactly (module docstring), so that a pressure constant on the pixels
    gives the continuum displacement at their centres.

    Parameters
    ----------
    shape : int or (int, int)
        Pixels of the cell along x and y (``(nx, ny)``), or one ``n``.
    h : float, m
        Pixel side.
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)``.
    compliance_factor : callable, optional
        ``c(|q|)``: the multiplier of each Fourier mode's compliance, called with
        an array of wavenumbers (rad/m, positive) and returning an array of the
        same shape; it must tend to 1 at large wavenumbers.  Default: 1 (the
        half-space).
    workers : int, optional
        Threads of the transforms, as :mod:`scipy.fft` counts them (default -1:
        all cores).

    Notes
    -----
    Fields have the shape :attr:`shape`; spectra the ``rfft2`` layout
    ``(nx, ny // 2 + 1)``.  The displacement (positive into the half-space) has
    the arbitrary mean ``S_0 pbar`` (module docstring).  The operator holds no
    work buffers: instances may be shared between threads.

    Examples
    --------
    Two phases in stripes along y: the displacement is the square wave's Fourier series
    (``tests/test_periodic.py``), here its first mode against ``2 P_1 / (E* q)``.

    >>> import numpy as np
    >>> n, h, E_star, dp = 32, 1e-4, 1e6, 1e3
    >>> p = np.zeros((n, n))
    >>> p[: n // 2] = dp
    >>> u = PeriodicHalfSpace(n, h, E_star).displacement(p)
    >>> q = 2 * np.pi / (n * h)
    >>> first = abs(np.fft.rfft(u[:, 0])[1]) * 2 / n
    >>> print(f"{first / (2 * (2 * dp / np.pi) / (E_star * q)):.4f}")
    1.0001
    """

    def __init__(self, shape, h, E_star, *, compliance_factor=None, workers=-1):
        self.shape = grid_shape(shape)
        self.h = _PIXEL.parse(h, "pixel size", scale=False)
        self.E_star = _E_STAR.parse(E_star, "", scale=False)
        if compliance_factor is not None and not callable(compliance_factor):
            raise ValueError(f"compliance_factor must be a callable of |q| (rad/m), got "
                             f"{compliance_factor!r}")
        self.compliance_factor = compliance_factor
        self.workers = workers
        symbol, gx, gy = self._spectra()
        for a in (symbol, gx, gy):
            a.flags.writeable = False
        self._influence_q = symbol
        self._gradient_q = (gx, gy)

    def _spectra(self):
        """The displacement symbol and the gradient's imaginary parts, m/Pa and 1/Pa."""
        unit = 4.0 / (math.sqrt(math.pi) * self.E_star)
        base, gx, gy = (unit * a for a in _halfspace_sums(self.shape, self.h))
        if self.compliance_factor is not None:
            base += self._correction(lambda Q: 1.0)
            gx += self._correction(lambda Q: Q[0])
            gy += self._correction(lambda Q: Q[1])
        nx, ny = self.shape
        gx[0, 0] = gy[0, 0] = 0.0
        # The arbitrary mean: the longest wave's compliance (module docstring).
        base[0, 0] = 0.0
        base[0, 0] = base.max()
        # An odd kernel's Nyquist modes vanish (the aliases +-pi/h cancel).
        if nx % 2 == 0:
            gx[nx // 2] = 0.0
        if ny % 2 == 0:
            gy[:, -1] = 0.0
        return base, gx, gy

    def _correction(self, weight):
        """``sum over aliases of 2 (c(|Q|) - 1) / (E* |Q|) s s`` times ``weight((Qx, Qy))``."""
        h, factor = self.h, self.compliance_factor

        def term(qx, qy):
            Q = np.hypot(qx, qy)
            safe = np.where(Q > 0, Q, 1.0)
            c = np.asarray(factor(safe), dtype=float)
            form = np.sinc(qx * h / (2 * np.pi)) * np.sinc(qy * h / (2 * np.pi))
            value = np.where(Q > 0, 2.0 * (c - 1.0) / (self.E_star * safe) * form, 0.0)
            return value * np.broadcast_to(weight((qx, qy)), value.shape)

        return _alias_rings(self.shape, h, term)

    def with_own_buffers(self, *, workers=None):
        """The same operator (it holds no work buffers), with its own ``workers``.

        Parameters
        ----------
        workers : int, optional
            ``scipy.fft`` workers of the new operator (default: this one's).

        Returns
        -------
        PeriodicHalfSpace
        """
        own = copy.copy(self)
        if workers is not None:
            own.workers = workers
        return own

    # -- transforms ----------------------------------------------------
    def forward(self, field_r):
        """Spectrum of a cell field, ``rfft2``.

        Parameters
        ----------
        field_r : ndarray, shape (nx, ny)

        Returns
        -------
        ndarray, shape (nx, ny // 2 + 1), complex
        """
        field_r = np.asarray(field_r)
        if field_r.shape != self.shape:
            raise ValueError(f"field must have shape {self.shape}, got {field_r.shape}")
        return scipy.fft.rfft2(field_r, workers=self.workers)

    def inverse(self, spectrum_q, *, overwrite=False):
        """Real cell field from a half spectrum, ``irfft2``.

        Parameters
        ----------
        spectrum_q : ndarray, shape (nx, ny // 2 + 1), complex
        overwrite : bool, optional
            The spectrum may be destroyed (default False).

        Returns
        -------
        ndarray, shape (nx, ny)
        """
        return scipy.fft.irfft2(spectrum_q, s=self.shape, workers=self.workers,
                                overwrite_x=overwrite)

    # -- operators -----------------------------------------------------
    def displacement(self, pressure_r):
        """Surface displacement at the pixel centres (its mean arbitrary: ``S_0 pbar``).

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa

        Returns
        -------
        ndarray, shape (nx, ny), m
        """
        return self.displacement_q(self.forward(pressure_r))

    def displacement_q(self, pressure_q):
        """Displacement from an already transformed pressure (see :meth:`forward`)."""
        return self.inverse(pressure_q * self._influence_q, overwrite=True)

    def gradient(self, pressure_r, *, pressure_q=None):
        """Surface gradient ``(du/dx, du/dy)`` at the pixel centres, exactly.

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa
        pressure_q : ndarray, shape (nx, ny // 2 + 1), optional
            The pressure's spectrum, if already computed.

        Returns
        -------
        gx, gy : ndarray, shape (nx, ny), dimensionless
        """
        if pressure_q is None:
            pressure_q = self.forward(pressure_r)
        i_pressure_q = pressure_q * 1j
        return tuple(self.inverse(i_pressure_q * g, overwrite=True) for g in self._gradient_q)

    def mean_square_slope(self, pressure_r):
        """Mean over the cell of the continuum face's ``|grad u|^2``, exactly.

        Parseval on the continuum pressure (constant on pixels):
        ``(4 / E*^2) sum_q |P_d(q)|^2 W(q) / N^2`` with ``W`` the alias sum of
        ``c^2 s^2 s^2`` (1 for the half-space, whose value is then
        ``(2 / E*)^2`` times the pressure's variance).  No discretisation error:
        the log singularities of the gradient at pressure steps are integrated.

        Parameters
        ----------
        pressure_r : ndarray, shape (nx, ny), Pa

        Returns
        -------
        float, dimensionless
        """
        pressure_r = np.asarray(pressure_r, dtype=float)
        if self.compliance_factor is None:
            return float(4.0 / self.E_star**2 * np.var(pressure_r))
        power = np.abs(self.forward(pressure_r)) ** 2
        ny = self.shape[1]
        # Columns other than 0 and Nyquist stand for two of the full spectrum.
        twice = np.full(power.shape[1], 2.0)
        twice[0] = 1.0
        if ny % 2 == 0:
            twice[-1] = 1.0
        weight = self.slope_weight
        return float(4.0 / self.E_star**2 * np.sum(power * weight * twice)
                     / (self.shape[0] * ny) ** 2)

    @functools.cached_property
    def slope_weight(self):
        """``W(q)``, the alias sum of ``c(|Q|)^2 s(Qx)^2 s(Qy)^2``; 0 at ``q = 0``, read-only.

        1 elsewhere for the half-space (``sum_m sinc^2(x + m) = 1``).  Shape
        ``(nx, ny // 2 + 1)``.
        """
        h, factor = self.h, self.compliance_factor
        if factor is None:
            weight = np.ones(self._influence_q.shape)
            weight[0, 0] = 0.0
            weight.flags.writeable = False
            return weight

        def term(qx, qy):
            Q = np.hypot(qx, qy)
            c = np.asarray(factor(np.where(Q > 0, Q, 1.0)), dtype=float)
            form = (np.sinc(qx * h / (2 * np.pi)) * np.sinc(qy * h / (2 * np.pi))) ** 2
            return np.where(Q > 0, (c * c - 1.0) * form, 0.0)

        weight = 1.0 + _alias_rings(self.shape, h, term)
        weight[0, 0] = 0.0
        weight.flags.writeable = False
        return weight

    # -- what the contact solver and its preconditioners read -------------
    @property
    def influence_symbol(self):
        """The operator's symbol, m/Pa, shape (nx, ny // 2 + 1), read-only; positive.

        ``inverse(forward(p) * influence_symbol)`` is :meth:`displacement`; at
        ``q = 0`` the arbitrary ``S_0`` (module docstring).
        """
        return self._influence_q

    @property
    def aliased_symbol(self):
        """The symbol a Fourier preconditioner inverts: :attr:`influence_symbol` (no padding)."""
        return self._influence_q

    @functools.cached_property
    def compliance_floor(self):
        """Smallest eigenvalue of the operator, m/Pa: the symbol's minimum.

        It bounds every principal submatrix (any contact set) from below.
        """
        return float(self._influence_q.min())

    @functools.cached_property
    def influence_quadrant(self):
        """Periodic influence coefficients at offsets ``0..nx`` by ``0..ny`` pixels, m/Pa.

        The kernel of :meth:`displacement`, even in
        both axes; the entries at offset ``nx`` (``ny``) repeat offset 0, so that
        an offset ``|i - i'|`` of two cell pixels indexes it directly.  Shape
        ``(nx + 1, ny + 1)``, read-only.
        """
        kernel = scipy.fft.irfft2(self._influence_q, s=self.shape, workers=self.workers)
        quadrant = np.pad(kernel, ((0, 1), (0, 1)), mode="wrap")
        quadrant.flags.writeable = False
        return quadrant

    @property
    def self_influence(self):
        """Displacement of a pixel per unit pressure on itself, m/Pa."""
        return float(self.influence_quadrant[0, 0])
