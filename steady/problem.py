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
takes :class:`FacePhases`.  :func:`steady.scene.problem_of` is the one way from
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

from .counterbody import Counterbody
from .depth import DepthColumns
from .labels import validate_labels
from .outline import FaceGrid
from .schema import SCALE_RANGE as _SCALE_RANGE
from .schema import Key
from .text import shorten
from .wear import as_wear_law

__all__ = ["SCALE_RANGE", "FacePhases", "Problem", "check_input_scales", "check_load_scales",
           "check_phase_names", "check_phase_scales", "check_pixel_scale", "check_rate_scales",
           "check_scale", "check_scales", "default_phase_names", "input_names"]

#: The range of every scale of a problem, in SI units (m, N, Pa, 1/Pa, 1): the
#: lengths of the face and its pixel, the force, the modulus, the mean and phase
#: pressures, the slope and depth scales, the wear rate and the rate constants
#: (and a run-in's distances, :mod:`transient.problem`).  Physical problems lie
#: far inside it; within it, products of up to ten scales -- the slope energies
#: square pressures, areas and moduli together -- stay within double precision
#: (about 1e+-308), while beyond it a problem ends in overflow, underflow to 0
#: or NaN.  A scale outside it is refused up front, naming its inputs (the
#: scene's keys declare it too: :data:`steady.schema.SCALE_RANGE`).
SCALE_RANGE = _SCALE_RANGE


#: The force and the modulus of a problem built in Python: positive finite numbers in
#: :data:`SCALE_RANGE`, as the scene's keys of the same name.
_FORCE = Key("normal_force", "number", unit="N", low=0.0)
_MODULUS = Key("E_star", "number", unit="Pa", low=0.0)


def input_names(outline, normal_force, E_star, n=None, wear=None):
    """How messages name a problem's inputs in Python: ``name -> text``.

    The keys are ``"outline"``, one per length of the outline (its
    ``parameters()`` in m), ``"normal_force"``, ``"E_star"``, ``"n"`` and
    ``"wear"``; :meth:`steady.scene.Scene.input_names` gives the same keys
    the words of a scene file (``"[load] normal_force = 10.0"``).
    """
    lengths = {name: value for name, (value, unit) in outline.parameters().items()
               if unit == "m"}
    names = {name: f"{type(outline).__name__} {name} = {value!r}"
             for name, value in lengths.items()}
    names["outline"] = (f"{type(outline).__name__}("
                        + ", ".join(f"{k}={v!r}" for k, v in lengths.items()) + ")")
    names.update(normal_force=f"normal_force = {normal_force!r}", E_star=f"E_star = {E_star!r}",
                 n=f"n = {shorten(n)}", wear=getattr(wear, "describe", lambda: repr(wear))())
    return names


def default_phase_names(n_phases):
    """``("phase 0", "phase 1", ...)``: the names of phases a scene does not name."""
    return tuple(f"phase {i}" for i in range(int(n_phases)))


def check_phase_names(names, n_phases):
    """The phase names as a tuple of str: one per phase, non-empty, distinct, one line each.

    Raises
    ------
    ValueError
        Another count than ``n_phases``, a name that is not a non-empty
        string, a line break or a repeated name; the message names it.
    """
    if isinstance(names, str):
        raise ValueError(f"phase names must be a sequence of strings, one per phase, got "
                         f"{shorten(names)}")
    names = tuple(names)
    if len(names) != n_phases:
        raise ValueError(f"{len(names)} phase name(s) given for {n_phases} phase(s): "
                         f"{shorten(list(names))}")
    seen = set()
    for i, name in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"the name of phase {i} must be a non-empty string, got "
                             f"{shorten(name)}")
        if any(c in name for c in "\n\r\0"):
            raise ValueError(f"the name of phase {i} must be one line, got {shorten(name)}")
        if name in seen:
            raise ValueError(f"phase names must be distinct: {name!r} is given twice")
        seen.add(name)
    return names


def _shown(value):
    """A scale's value for messages: 3 digits, ``inf``, ``0``, ``nan``."""
    return f"{value:.3g}" if math.isfinite(value) and value != 0 else str(value)


def check_scale(value, what, unit, inputs, names):
    """``ValueError`` unless ``value`` lies in :data:`SCALE_RANGE`.

    Parameters
    ----------
    value : float
    what : str or None
        The scale in words with its formula (``"the mean pressure pbar =
        F_N / A"``); None for an input itself, named by ``names[inputs[0]]``.
    unit : str
    inputs : sequence of str
        The keys of ``names`` the scale comes from.
    names : mapping
        How the message names each input (:func:`input_names`).
    """
    low, high = SCALE_RANGE
    if low <= value <= high:  # NaN is not
        return
    span = f"outside [{low:g}, {high:g}] {unit}, the range of every scale of a problem (SI units)"
    if what is None:  # an input itself
        raise ValueError(f"{names[inputs[0]]} {unit} is {span}")
    given = " and ".join(names[key] for key in inputs)
    raise ValueError(f"{given}: {what} = {_shown(value)} {unit} is {span}")


def check_input_scales(outline, normal_force, E_star, names):
    """The inputs themselves in range: the outline's lengths, the force and the modulus.

    A scene's keys declare their range (:data:`steady.schema.SCALE_RANGE`)
    and are checked as they are read: this is for inputs given in Python.
    """
    for name, (value, unit) in outline.parameters().items():
        if unit == "m":
            check_scale(float(value), None, "m", (name,), names)
    check_scale(float(normal_force), None, "N", ("normal_force",), names)
    check_scale(float(E_star), None, "Pa", ("E_star",), names)


def check_load_scales(outline, normal_force, E_star, names, n=None):
    """The scales of a load on the face: ``pbar = F_N / A``, ``grad_f0``, ``f*``; the pixel.

    ``grad_f0 = 4 pbar / (pi E*)`` is the disk's, the scale of every
    outline's; ``f* = pbar L / E*``.  With ``n``, first the pixel
    ``h = 2 L / n``.
    """
    F, E, L = float(normal_force), float(E_star), outline.scale
    if n is not None:
        check_pixel_scale(outline, n, names)
    pbar = F / outline.area
    check_scale(pbar, "the mean pressure pbar = F_N / A", "Pa", ("normal_force", "outline"),
                names)
    check_scale(4.0 * pbar / (math.pi * E), "the reference slope grad_f0 = 4 pbar / (pi E*)",
                "1", ("normal_force", "outline", "E_star"), names)
    check_scale(pbar * L / E, "the depth scale f* = pbar L / E*", "m",
                ("normal_force", "outline", "E_star"), names)


def check_pixel_scale(outline, n, names):
    """The pixel ``h = 2 L / n`` of the grid of ``n`` pixels along the longer side, m."""
    check_scale(2.0 * outline.scale / n, "the pixel h = 2 L / n", "m", ("outline", "n"), names)


def check_rate_scales(wear, outline, normal_force, names):
    """The wear law's rate constant of every phase at ``pbar``, 1/Pa.

    :meth:`steady.wear.WearLaw.rate_constant`, named in the law's terms
    (``dg/dp at pbar = k m pbar^(m-1)`` for the power law): with ``E*`` and
    a length it sets the natural sliding distances.
    """
    pbar = float(normal_force) / outline.area
    k = np.asarray(wear.wear_field(np.arange(wear.n_phases)), dtype=float)
    with np.errstate(all="ignore"):
        rate_constants = np.asarray(wear.rate_constant(k, np.float64(pbar)), dtype=float)
    for i, kappa in enumerate(np.atleast_1d(rate_constants)):
        check_scale(float(kappa), f"the rate constant of phase {i}, {wear.rate_constant_words}",
                    "1/Pa", ("wear", "normal_force", "outline"), names)


def check_phase_scales(wear, counts, normal_force, pixel_area, names):
    """The steady phase pressures (eq. 7) and the steady wear rate ``g_i(p_i)`` of a phase map.

    ``k^(-1/m)`` of extreme ratios underflows: the pressures of the phases
    with ``counts`` face pixels each (of area ``pixel_area``, m^2), and
    their common wear rate, must be numbers in range.
    """
    k = np.asarray(wear.wear_field(np.arange(wear.n_phases)), dtype=float)
    with np.errstate(all="ignore"):
        pressures = np.asarray(wear.phase_pressures(counts, float(normal_force), pixel_area),
                               dtype=float)
        rates = np.asarray(wear.rate(pressures, k), dtype=float)
    for i, p in enumerate(pressures):
        check_scale(float(p), f"the steady pressure of phase {i} (eq. 7)", "Pa",
                    ("wear", "normal_force", "outline"), names)
    for i, rate in enumerate(rates):
        check_scale(float(rate), f"the steady wear rate of phase {i}, g_i(p_i)", "1",
                    ("wear", "normal_force", "outline"), names)


def check_scales(outline, normal_force, E_star, *, n=None, wear=None, counts=None,
                 names=None):
    """Refuse a problem whose scales leave :data:`SCALE_RANGE`, naming the inputs of each.

    Checked in order (each only when its inputs are given): the lengths of
    the outline, the normal force and the modulus themselves
    (:func:`check_input_scales`); the pixel ``h = 2 L / n``, the mean
    pressure, the reference slope and the depth scale
    (:func:`check_load_scales`); the wear law's rate constants
    (:func:`check_rate_scales`); with the pixel ``counts`` of the phases,
    the steady phase pressures and wear rate (:func:`check_phase_scales`).
    Every value is computed as the solvers compute it, in double precision:
    an overflow is ``inf``, an underflow 0, and both are out of range.  A
    scene checks each once as it is read (:func:`steady.scene.parse_scene`).

    Parameters
    ----------
    outline : outline object
    normal_force : float, N
    E_star : float, Pa
    n : int, optional
        Grid size, pixels along the longer side.
    wear : wear law, optional
    counts : array_like of int, shape (P,), optional
        Face pixels of each phase (needs ``n`` and ``wear``).
    names : mapping, optional
        How the message names each input (:func:`input_names`, the
        default, or a scene's keys).

    Raises
    ------
    ValueError
        The first scale out of range: its formula, value and unit, the
        range, and the inputs it comes from.
    """
    normal_force, E_star = float(normal_force), float(E_star)
    names = input_names(outline, normal_force, E_star, n, wear) if names is None else names
    check_input_scales(outline, normal_force, E_star, names)
    check_load_scales(outline, normal_force, E_star, names, n)
    if wear is None:
        return
    wear = as_wear_law(wear)
    check_rate_scales(wear, outline, normal_force, names)
    if counts is not None and n is not None:
        h = 2.0 * outline.scale / n
        check_phase_scales(wear, counts, normal_force, h * h, names)


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
    names : sequence of str, optional
        A name for each phase (``[phases] names``), used in summaries,
        figures and files; default ``("phase 0", "phase 1", ...)``.  Phases
        are numbered from 0 everywhere.
    columns : steady.depth.DepthColumns, optional
        The phase below every face pixel as a function of depth, for a map
        that changes with depth (default None: columnar, the paper's punch).
        With columns, ``labels`` is their section at ``depth`` and every
        phase must occur somewhere in the columns, not necessarily in the
        section: a phase may have no pixel (a zero area, ``counts`` 0).
    depth : float or array_like, shape (nx, ny), m, optional
        The depth below the initial surface of the section ``labels`` is
        (default 0: the surface); only with ``columns``.

    Attributes
    ----------
    counts : ndarray of int, shape (P,)
        Face pixels of each phase.

    Raises
    ------
    ValueError
        Labels of another shape, not integers, a pixel off the face not
        ``-1``, a face pixel outside ``0..P-1``, or a phase without a pixel
        on the face (the message names it and the pixel counts); with
        columns, columns of another grid, face or phase count, or labels
        that are not their section at ``depth`` (the message names a pixel).
    """

    grid: FaceGrid
    labels: np.ndarray
    n_phases: int
    names: tuple | None = None
    columns: DepthColumns | None = None
    depth: object = 0.0

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
        if self.columns is None:
            counts = validate_labels(labels, int(self.n_phases), face_mask=self.grid.mask)
        else:
            counts = self._section_counts(labels)
        labels = np.array(labels, copy=True)
        labels.flags.writeable = False
        counts.flags.writeable = False
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "n_phases", int(self.n_phases))
        object.__setattr__(self, "counts", counts)
        object.__setattr__(self, "names", default_phase_names(self.n_phases)
                           if self.names is None
                           else check_phase_names(self.names, self.n_phases))

    def _section_counts(self, labels):
        """Check ``labels`` as the section of ``columns`` at ``depth``; the pixels of each phase."""
        columns, grid = self.columns, self.grid
        if not isinstance(columns, DepthColumns):
            raise ValueError(f"columns must be a steady.depth.DepthColumns, got "
                             f"{type(columns).__name__}")
        if columns.shape != grid.shape or not np.array_equal(columns.face_mask, grid.mask):
            raise ValueError(f"the columns ({columns.shape[0]} x {columns.shape[1]} pixels) are "
                             f"not on the face of the {grid.outline.describe()} at n = {grid.n}")
        if columns.n_phases != int(self.n_phases):
            raise ValueError(f"the columns have {columns.n_phases} phase(s), n_phases is "
                             f"{self.n_phases}")
        depth = np.asarray(self.depth, dtype=float)
        if depth.ndim and depth.shape != grid.shape:
            raise ValueError(f"depth must be a number or have shape {grid.shape}, got "
                             f"{depth.shape}")
        if not np.all(np.isfinite(depth[grid.mask] if depth.ndim else depth)) or np.any(
                (depth[grid.mask] if depth.ndim else depth) < 0):
            raise ValueError("depth must be finite and >= 0 (m below the initial surface)")
        if not np.issubdtype(labels.dtype, np.integer):
            raise ValueError(f"phase labels must be integers, got dtype {labels.dtype}")
        section = columns.phase_at(depth)
        differ = np.argwhere(section != labels)
        if differ.size:
            i, j = (int(v) for v in differ[0])
            raise ValueError(f"labels are not the columns' section at the given depth: pixel "
                             f"({i}, {j}) has label {int(labels[i, j])}, the section phase "
                             f"{int(section[i, j])} ({len(differ)} pixels differ)")
        depth = np.array(depth, copy=True)
        depth.flags.writeable = False
        object.__setattr__(self, "depth", float(depth) if depth.ndim == 0 else depth)
        return np.bincount(labels[grid.mask], minlength=columns.n_phases)

    @property
    def outline(self):
        """The face's outline."""
        return self.grid.outline

    @property
    def face_mask(self):
        """Face pixels, shape (nx, ny), read-only."""
        return self.grid.mask

    @property
    def depth_varying(self):
        """Whether the phase map changes with depth below some face pixel."""
        return self.columns is not None and not self.columns.columnar

    def section(self, depth):
        """The phases of the section at ``depth`` (m, scalar or (nx, ny)) of the columns."""
        if self.columns is None:
            raise ValueError("a columnar phase map has the same section at every depth: "
                             "it has no columns")
        depth = np.broadcast_to(np.asarray(depth, dtype=float), self.grid.shape) \
            if np.ndim(depth) else float(depth)
        return FacePhases(self.grid, self.columns.phase_at(depth), self.n_phases, self.names,
                          self.columns, depth)

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
    """A multi-phase punch on an elastic half-space or layer: what every solver takes.

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
    sliding : sliding kinematics, optional
        The local sliding speed (:mod:`steady.sliding`, ``[sliding]``);
        default None, a translation (the paper's uniform speed), which a
        :class:`~steady.sliding.Translation` also becomes.  Another kind
        multiplies the coefficient field by ``v / v_ref``
        (:meth:`wear_field`) and makes the steady pressure vary
        within each phase (:meth:`steady_pressure`); it needs a wear law with
        a factorisation ``k_i g(p)`` (:attr:`steady.wear.WearLaw.factor`).
    thickness : float, m, optional, keyword
        The counter-body is a layer of this thickness on a rigid flat
        (:class:`steady.counterbody.Counterbody`); default None, a half-space.
    poisson : float, optional, keyword
        The layer's Poisson's ratio in ``[0, 0.5]``, with ``thickness`` only.
    checked : bool, optional, keyword
        The outline, the force, the modulus and the law and the scales that
        follow from them were checked where they entered (a scene file,
        :meth:`from_scene`; the problem a :meth:`section` comes from): only
        those of the phase map are checked here (default False: all).
    names : mapping, optional, keyword
        How messages name the inputs (default :func:`input_names`; a
        scene's keys).

    Raises
    ------
    ValueError
        A wear law for another number of phases, a force or modulus that is
        not positive and finite, a scale of the problem outside
        :data:`SCALE_RANGE` (:func:`check_scales`), or kinematics whose axis
        lies on the face or with another law than the power law; the message
        names the value.
    """

    phases: FacePhases
    wear: object
    normal_force: float
    E_star: float
    sliding: object = None
    thickness: float | None = dataclasses.field(default=None, kw_only=True)
    poisson: float | None = dataclasses.field(default=None, kw_only=True)
    checked: dataclasses.InitVar[bool] = dataclasses.field(default=False, kw_only=True)
    names: dataclasses.InitVar[object] = dataclasses.field(default=None, kw_only=True)

    def __post_init__(self, checked, names):
        """Check the law against the phases, the force and the modulus."""
        if not isinstance(self.phases, FacePhases):
            raise ValueError(f"phases must be a FacePhases, got {type(self.phases).__name__}")
        wear = as_wear_law(self.wear)
        if wear.n_phases != self.phases.n_phases:
            raise ValueError(f"the wear law is for {wear.n_phases} phase(s) "
                             f"({wear.describe()}), the phase map has "
                             f"{self.phases.n_phases}")
        object.__setattr__(self, "wear", wear)
        if not checked:  # their range is checked below, named in the caller's words
            object.__setattr__(self, "normal_force",
                               _FORCE.parse(self.normal_force, "", scale=False))
            object.__setattr__(self, "E_star", _MODULUS.parse(self.E_star, "", scale=False))
        names = (input_names(self.outline, self.normal_force, self.E_star, self.n, wear)
                 if names is None else names)
        if not checked:
            check_scales(self.outline, self.normal_force, self.E_star, n=self.n, wear=wear,
                         names=names)
        check_phase_scales(wear, self.phases.counts, self.normal_force, self.pixel_area, names)
        if self.thickness is not None or self.poisson is not None:
            layer = self.counterbody  # checks the layer where it enters
            object.__setattr__(self, "thickness", layer.thickness)
            object.__setattr__(self, "poisson", layer.poisson)
        if self.sliding is not None:
            self._check_sliding(wear)

    def _check_sliding(self, wear):
        """Check non-uniform kinematics against the face and the law; a translation is None."""
        sliding = self.sliding
        if not hasattr(sliding, "speed_ratio") or not hasattr(sliding, "uniform"):
            raise ValueError(f"sliding must be a kind of steady.sliding.SLIDING, got "
                             f"{type(sliding).__name__}")
        if sliding.uniform:
            object.__setattr__(self, "sliding", None)
            return
        if self.outline.periodic:
            raise ValueError(f"sliding {sliding.describe()} on the {self.outline.describe()}: "
                             f"a periodic cell slides in translation only (a sliding speed that "
                             f"varies across the plane does not repeat with the cell)")
        sliding.check_outline(self.outline, "sliding")
        if wear.factor is None:
            raise ValueError(f"sliding {sliding.describe()} needs a wear law k_i g(p) whose "
                             f"coefficients the sliding speed multiplies (the power law k p^m), "
                             f"not the {wear.describe()}")
        pressure = self.steady_pressure()[self.face_mask]
        names = input_names(self.outline, self.normal_force, self.E_star, self.n, wear)
        for p, what in ((pressure.max(), "largest"), (pressure.min(), "smallest")):
            check_scale(float(p), f"the {what} steady pixel pressure under the sliding "
                        f"{sliding.describe()}", "Pa", ("wear", "normal_force", "outline"),
                        names)

    def section(self, depth):
        """The problem of the section at ``depth``: the quasi-steady problem there.

        Parameters
        ----------
        depth : float or array_like, shape (nx, ny), m
            Worn depth below the initial surface, ``>= 0``; a number is a
            plane section.

        Returns
        -------
        Problem
            Labels ``columns.phase_at(depth)``, the same columns, law, load,
            modulus and kinematics.  ``steady.solve(problem.section(w))`` is
            the quasi-steady face of the section: the limiting face the
            punch would reach if the phase map no longer changed below ``w``.
            A phase without a pixel in the section carries no load.

        Raises
        ------
        ValueError
            A columnar problem (no columns), or a depth that is negative,
            not finite or of another shape.
        """
        return dataclasses.replace(self, phases=self.phases.section(depth), checked=True)

    def present_phases(self):
        """The labels and the wear law of the phases with a face pixel, renumbered from 0.

        A section of a depth-varying map may lack a phase; the estimators
        of the rms slope take only phases that are on the face.  A map with
        every phase returns its own labels and law.
        """
        counts = self.phases.counts
        if np.all(counts > 0):
            return self.labels, self.wear
        present = np.flatnonzero(counts > 0)
        renumber = np.full(self.n_phases + 1, -1)
        renumber[present] = np.arange(present.size)
        return renumber[self.labels], self.wear.restrict(present)

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

    @property
    def phase_names(self):
        """A name for each phase, phase 0 first (:attr:`FacePhases.names`)."""
        return self.phases.names

    # -- derived ---------------------------------------------------------
    @functools.cached_property
    def counterbody(self):
        """The counter-body (:class:`steady.counterbody.Counterbody`): modulus and layer."""
        return Counterbody(self.E_star, self.thickness, self.poisson)

    @functools.cached_property
    def halfspace(self):
        """The counter-body's elastic operator of the grid (built on first use, then kept).

        :meth:`steady.counterbody.Counterbody.operator`: the half-space's, or
        the layer's with the same interface.
        """
        return self.counterbody.operator(self.grid)

    @property
    def mean_pressure(self):
        """``pbar = F_N / A``, ``A`` the outline's exact area (``pi a^2`` for a disk), Pa."""
        return self.normal_force / self.outline.area

    @functools.cached_property
    def speed_ratio(self):
        """``v / v_ref`` at every pixel centre, shape (nx, ny), read-only; None: a translation."""
        if self.sliding is None:
            return None
        ratio = self.sliding.speed_ratio(self.grid)
        ratio.flags.writeable = False
        return ratio

    def phase_pressures(self):
        """Steady pressure of each phase (eq. 7, the wear law's), Pa, shape (P,).

        Under non-uniform sliding (:attr:`sliding`) the pressure varies within
        a phase: this is then each phase's mean, its load over its area (NaN
        for a phase without a pixel in a section).  Without it a phase
        without a pixel gets the pressure it would carry at the common wear
        rate: it carries no load.
        """
        if self.sliding is not None:
            load = np.bincount(self.labels[self.face_mask],
                               weights=self.steady_pressure()[self.face_mask],
                               minlength=self.n_phases)
            counts = self.phases.counts
            return np.where(counts > 0, load / np.maximum(counts, 1), np.nan)
        return self.wear.phase_pressures(self.phases.counts, self.normal_force,
                                         self.pixel_area)

    def steady_pressure(self):
        """Steady pressure of every pixel, Pa, shape (nx, ny); zero off the face.

        Constant on each phase (eq. 7); under non-uniform sliding the pixel-wise
        closed form ``k_i v(x) p^m / v_ref = C``
        (:meth:`steady.wear.Factorisation.pixel_pressures`).
        """
        if self.sliding is not None:
            return self.wear.factor.pixel_pressures(self.wear_field(), self.normal_force,
                                                    self.pixel_area)
        # Label -1 (off the face) picks the trailing zero.
        return np.append(self.phase_pressures(), 0.0)[self.labels]

    def wear_field(self):
        """The wear law's coefficient of every pixel, zero off the face, shape (nx, ny).

        Under non-uniform sliding, times the speed ratio ``v / v_ref``
        (:attr:`speed_ratio`): the law's rate ``k p^m`` of this field is the
        wear per unit sliding distance of the reference point.
        """
        if self.sliding is not None:
            return self.wear.wear_field(self.labels) * self.speed_ratio
        return self.wear.wear_field(self.labels)
