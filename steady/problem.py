"""The problem definition: a phase map on a face's grid, a wear law, a load, a modulus.

Every solver of the project takes its problem from here, checked once:

- :class:`FacePhases` -- the phase map rasterised on the grid of a face
  outline (:class:`steady.outline.FaceGrid`): the label of every pixel,
  with the number of phases the map declares (not guessed from the
  labels), every phase present on the face;
- :class:`Problem` -- those phases, a wear law (:mod:`steady.wear`), the
  normal force and the counter-body's modulus ``E*``.

The steady solve (:func:`steady.solution.solve`), the run-in
(:class:`transient.problem.WearProblem`) and the fit of wear ratios
(:class:`steady.fit.FaceModel`) take a :class:`Problem`; the sweep basis
(:class:`steady.basis.PhaseBasis`), which varies the wear law and the load,
takes :class:`FacePhases`.  :meth:`Problem.from_scene` is the one way from
a scene file (:mod:`steady.scene`) to a problem.

Examples
--------
>>> from steady.outline import Circle
>>> from steady.phases import Voronoi
>>> grid = Circle(4e-3).grid(64)
>>> problem = Problem(FacePhases(grid, Voronoi(100, (0.5, 0.5), 2024).labels(grid), 2),
...                   [1e-13, 1e-12], 10.0, 1.3e6)
>>> problem.n_phases, problem.shape, round(problem.pixel_area * 1e12, 3)
(2, (64, 64), 15625.0)
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .halfspace import HalfSpace
from .labels import validate_labels
from .outline import FaceGrid
from .text import shorten
from .wear import as_wear_law

__all__ = ["FacePhases", "Problem"]


def _positive(value, name, unit):
    """A positive finite float; ``ValueError`` naming ``name`` and the value."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be a positive finite number ({unit}), got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive finite number ({unit}), got "
                         f"{shorten(value)}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number ({unit}), got "
                         f"{shorten(value)}")
    return v


@dataclasses.dataclass(frozen=True, eq=False)
class FacePhases:
    """A phase map on the grid of a face outline, checked.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
        The face's grid (its outline, ``n``, pixel size).
    labels : array_like of int, shape ``grid.shape``
        Phase index ``0..P-1`` of every face pixel (``grid.mask``), ``-1``
        off the face.
    n_phases : int
        ``P``, the phases the map declares; every one must have a pixel on
        the face.

    Attributes
    ----------
    counts : ndarray of int, shape (P,)
        Face pixels of each phase.

    Raises
    ------
    ValueError
        Labels of another shape, not integers, a pixel off the face not
        ``-1``, a face pixel outside ``0..P-1``, or a phase without a pixel
        on the face (the message names it and the pixel counts).
    """

    grid: FaceGrid
    labels: np.ndarray
    n_phases: int

    def __post_init__(self):
        """Check the labels against the grid and the declared phases; store them read-only."""
        if not isinstance(self.grid, FaceGrid):
            raise ValueError(f"grid must be a FaceGrid (outline.grid(n)), got "
                             f"{type(self.grid).__name__}")
        labels = np.asarray(self.labels)
        if labels.shape != self.grid.shape:
            raise ValueError(f"labels must have shape {self.grid.shape} to match the grid of the "
                             f"{self.grid.outline.describe()} at n = {self.grid.n}, got "
                             f"{labels.shape}")
        if isinstance(self.n_phases, (bool, np.bool_)) or int(self.n_phases) != self.n_phases:
            raise ValueError(f"n_phases must be an integer, got {self.n_phases!r}")
        counts = validate_labels(labels, int(self.n_phases), face_mask=self.grid.mask)
        labels = np.array(labels, copy=True)
        labels.flags.writeable = False
        counts.flags.writeable = False
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "n_phases", int(self.n_phases))
        object.__setattr__(self, "counts", counts)

    @property
    def outline(self):
        """The face's outline."""
        return self.grid.outline

    @property
    def face_mask(self):
        """Face pixels, shape (nx, ny), read-only."""
        return self.grid.mask

    @property
    def fill_factors(self):
        """Area fractions of the phases (pixel counts, eq. 13), shape (P,)."""
        return self.counts / self.counts.sum()

    @property
    def face_area(self):
        """Face pixels times ``h^2``, m^2."""
        return float(self.counts.sum()) * self.grid.pixel_area


@dataclasses.dataclass(frozen=True, eq=False)
class Problem:
    """A multi-phase punch on an elastic half-space: what every solver takes.

    Parameters
    ----------
    phases : FacePhases
        The phase map on the face's grid.
    wear : wear law or sequence of float
        The local wear law of the phases (:mod:`steady.wear`), with as many
        phases as ``phases``; a sequence of coefficients ``k_i`` (1/Pa)
        stands for Archard's law.
    normal_force : float, N
        ``F_N``, positive and finite.
    E_star : float, Pa
        Effective modulus ``E / (1 - nu^2)`` of the counter-body, positive
        and finite.

    Raises
    ------
    ValueError
        A wear law for another number of phases, a force or modulus that is
        not positive and finite; the message names the value.
    """

    phases: FacePhases
    wear: object
    normal_force: float
    E_star: float

    def __post_init__(self):
        """Check the law against the phases, the force and the modulus."""
        if not isinstance(self.phases, FacePhases):
            raise ValueError(f"phases must be a FacePhases, got {type(self.phases).__name__}")
        wear = as_wear_law(self.wear)
        if wear.n_phases != self.phases.n_phases:
            raise ValueError(f"the wear law is for {wear.n_phases} phase(s) "
                             f"({wear.describe()}), the phase map has "
                             f"{self.phases.n_phases}")
        object.__setattr__(self, "wear", wear)
        object.__setattr__(self, "normal_force",
                           _positive(self.normal_force, "normal_force", "N"))
        object.__setattr__(self, "E_star", _positive(self.E_star, "E_star", "Pa"))

    @classmethod
    def from_scene(cls, scene, *, n=None):
        """The problem of a scene file (:class:`steady.scene.Scene`), the one factory.

        Parameters
        ----------
        scene : steady.scene.Scene
        n : int, optional
            Grid size, pixels along the longer side; default ``scene.n``.
            The phase geometry is rasterised at this size.

        Raises
        ------
        ValueError
            A grid too coarse for the outline or the geometry, or a phase
            without a pixel on the face at this grid (named, with what to
            change).
        """
        grid = scene.grid(n)
        phases = FacePhases(grid, scene.phase_labels(grid), scene.geometry.n_phases)
        return cls(phases, scene.wear, scene.normal_force, scene.E_star)

    # -- the grid --------------------------------------------------------
    @property
    def grid(self):
        """The face's :class:`~steady.outline.FaceGrid`."""
        return self.phases.grid

    @property
    def outline(self):
        """The face's outline (:mod:`steady.outline`)."""
        return self.phases.grid.outline

    @property
    def shape(self):
        """``(nx, ny)``."""
        return self.phases.grid.shape

    @property
    def n(self):
        """Pixels along the longer side of the grid."""
        return self.phases.grid.n

    @property
    def pixel_area(self):
        """``h^2``, m^2."""
        return self.phases.grid.pixel_area

    @property
    def labels(self):
        """Phase index of every pixel, -1 off the face, shape (nx, ny), read-only."""
        return self.phases.labels

    @property
    def face_mask(self):
        """Face pixels, shape (nx, ny), read-only."""
        return self.phases.grid.mask

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return self.phases.n_phases

    # -- derived ---------------------------------------------------------
    @functools.cached_property
    def halfspace(self):
        """The elastic half-space operator of the grid (built on first use, then kept)."""
        return HalfSpace(self.shape, self.grid.h, self.E_star)

    @property
    def mean_pressure(self):
        """``pbar = F_N / A``, ``A`` the outline's exact area (``pi a^2`` for a disk), Pa."""
        return self.normal_force / self.outline.area

    def phase_pressures(self):
        """Steady pressure of each phase (eq. 7, the wear law's), Pa, shape (P,)."""
        return self.wear.phase_pressures(self.phases.counts, self.normal_force,
                                         self.pixel_area)

    def steady_pressure(self):
        """Steady pressure of every pixel, Pa, shape (nx, ny); zero off the face."""
        # Label -1 (off the face) picks the trailing zero.
        return np.append(self.phase_pressures(), 0.0)[self.labels]

    def coefficient_field(self):
        """The wear law's coefficient of every pixel, zero off the face, shape (nx, ny)."""
        return self.wear.coefficient_field(self.labels)
