"""Per-phase fields of one phase map, for sweeps over wear coefficients.

The steady pressure is constant on each phase (eq. 7), so the limiting face
is a linear combination of the faces of the phase indicators,
``f_inf = sum_i p_i K chi_i`` (eq. 9), and the mean-square slope is a
quadratic form in the phase pressures.  A :class:`PhaseBasis` transforms
each phase once; afterwards the face, the rms slope (plain and
energy-corrected, :mod:`steady.rms_slope`) and the phase pressures for any
number of wear-coefficient sets cost no transform at all.  This is what
makes maps over the wear ratio (paper Fig. 4b, 5b) cheap.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .counterbody import Counterbody
from .normalisation import reference_slope
from .pressures import phase_pressures
from .problem import FacePhases
from .rms_slope import slope_energy_of

__all__ = ["PhaseBasis", "SweepSlopes"]


@dataclasses.dataclass(frozen=True, eq=False)
class SweepSlopes:
    """Rms slopes for a set of wear-coefficient rows.

    Attributes
    ----------
    rms_slope : ndarray, shape (K,), dimensionless
        Energy-corrected rms slope.
    rms_slope_plain : ndarray, shape (K,), dimensionless
        Plain pixel rms slope.
    reference_slope : float, dimensionless
        ``grad_f0``, the homogeneous face's rms slope (``4 pbar / (pi E*)``
        for a disk; :mod:`steady.normalisation`).
    phase_pressures : ndarray, shape (K, P), Pa
    """

    rms_slope: np.ndarray
    rms_slope_plain: np.ndarray
    reference_slope: float
    phase_pressures: np.ndarray

    @property
    def normalised(self):
        """``rms_slope / grad_f0`` (eq. 15), shape (K,)."""
        return self.rms_slope / self.reference_slope


class PhaseBasis:
    """Faces and slope quadratic forms of the phase indicators of one map.

    Parameters
    ----------
    phases : steady.problem.FacePhases
        The phase map on the face's grid (checked there).
    E_star : float, Pa
    faces : bool, optional
        Also keep the per-phase faces ``K chi_i`` (``P`` arrays of
        ``nx x ny``) for :meth:`face`; default True.

    The wear coefficients and the load are arguments of the queries: a
    sweep varies them over one basis.

    Notes
    -----
    Cost: for ``P`` phases, ``P`` transforms of the face and the
    energy-corrected slope integrals (:meth:`steady.rms_slope.SlopeEnergy.gram`).

    Examples
    --------
    >>> from steady import FacePhases, Voronoi
    >>> from steady.outline import UNIT_DISK
    >>> grid = UNIT_DISK.grid(64)
    >>> basis = PhaseBasis(FacePhases(grid, Voronoi(100, (0.5, 0.5), 2024).labels(grid), 2), 1.0)
    >>> basis.rms_slopes([[1.0, 1.0], [1.0, 10.0]], 3.0).normalised.shape
    (2,)
    """

    def __init__(self, phases, E_star, *, faces=True):
        if not isinstance(phases, FacePhases):
            raise ValueError(f"phases must be a steady.problem.FacePhases, got "
                             f"{type(phases).__name__}")
        grid = phases.grid
        labels = phases.labels
        self.phases = phases
        self.outline = grid.outline
        self.n_phases = phases.n_phases
        self.counts = phases.counts
        self.labels = labels
        self.E_star = float(E_star)
        self.h = grid.h
        indicators = [(labels == i).astype(float) for i in range(self.n_phases)]
        self._gram = slope_energy_of(grid, self.E_star).gram(indicators, labels >= 0)
        self._faces = None
        if faces:
            hs = Counterbody(self.E_star).operator(grid)
            self._faces = np.array([hs.displacement(chi) for chi in indicators])

    @property
    def fill_factors(self):
        """Realised area fractions of the phases, shape (P,)."""
        return self.counts / self.counts.sum()

    def phase_pressures(self, wear_coefficients, normal_force, *, exponent=1.0):
        """Steady phase pressures (eq. 7) for one or many coefficient rows.

        Parameters
        ----------
        wear_coefficients : array_like, shape (P,) or (K, P), 1/Pa
        normal_force : float, N
        exponent : float, optional

        Returns
        -------
        ndarray, shape (P,) or (K, P), Pa
        """
        k = np.asarray(wear_coefficients, dtype=float)
        if k.ndim not in (1, 2) or k.shape[-1] != self.n_phases:
            raise ValueError(f"need {self.n_phases} wear coefficients per row, got "
                             f"shape {k.shape}")
        return phase_pressures(self.counts, k, normal_force, self.h**2, exponent=exponent)

    def rms_slopes(self, wear_coefficients, normal_force, *, exponent=1.0):
        """Rms slopes for many wear-coefficient rows.

        Parameters
        ----------
        wear_coefficients : array_like, shape (K, P), 1/Pa
        normal_force : float, N
        exponent : float, optional

        Returns
        -------
        SweepSlopes
        """
        p = np.atleast_2d(self.phase_pressures(wear_coefficients, normal_force,
                                               exponent=exponent))
        integrals = self._gram.integrals(p)
        g0 = reference_slope(self.outline, normal_force, self.E_star).value
        return SweepSlopes(rms_slope=np.atleast_1d(integrals.rms_slope),
                           rms_slope_plain=np.atleast_1d(integrals.rms_slope_plain),
                           reference_slope=g0, phase_pressures=p)

    def face(self, wear_coefficients, normal_force, *, exponent=1.0):
        """Limiting face ``f_inf`` (eq. 9), shape (nx, ny), m; NaN off the face."""
        if self._faces is None:
            raise ValueError("this basis was built with faces=False")
        p = self.phase_pressures(wear_coefficients, normal_force, exponent=exponent)
        f = np.tensordot(p, self._faces, axes=1)
        f[self.labels < 0] = np.nan
        return f
