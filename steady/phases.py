"""Phase maps of the punch face that can be rasterised at any grid size.

A phase geometry is a continuous description of which phase sits where on
the face, centred on the face's centre, its lengths in m (as in scene
files).  It is rasterised in units of the face's scale ``L``
(:mod:`steady.outline`: the punch radius ``a`` of a disk, else the larger
half side of the face's bounding box): a length ``x`` becomes ``x / L``,
the one division, so that a geometry and the scene file that describes it
give the same pixels.  Every geometry has

- ``n_phases`` : the number of phases ``P``;
- ``labels(grid)`` : an ``(nx, ny)`` integer array with the phase index
  ``0..P-1`` at every face pixel of ``grid`` (a
  :class:`steady.outline.FaceGrid`) and ``-1`` off the face; an integer
  ``n`` stands for the ``n x n`` grid of the unit disk, of radius 1 m
  (:func:`steady.outline.as_grid`);
- ``min_grid(outline=None)`` : the smallest ``n`` (pixels along the longer
  side) at which the geometry is resolved on that outline (default: the
  unit disk);
- ``check_grid(grid)`` : raises :class:`ValueError` (naming ``n`` and the
  minimum) if ``labels(grid)`` would refuse the grid.

Because the geometry is continuous, the same object can be rasterised at
several ``n`` (for instance to estimate the discretisation error of the
rms slope).  :class:`ArrayMap` is the exception: it is given as pixels and
can only be refined by integer factors.

Resolution rules (``labels`` refuses coarser grids):

- every geometry: ``n >= 8``;
- :class:`Voronoi`: at least 2 pixels per mean seed spacing.  ``N`` seeds
  in the bounding box ``[-bx L, bx L] x [-by L, by L]`` (``bx = by = 1``
  for a disk) are ``L sqrt(4 bx by / N)`` apart on average and a pixel is
  ``2 L / n`` wide, so ``n >= ceil(2 sqrt(N / (bx by)))``;
- :class:`Rods`: at least 3 pixels per radius of the smallest rod,
  ``n >= ceil(6 L / r_min)``;
- :class:`ArrayMap`: ``n`` must be a multiple of the map's size along its
  longer side;
- :class:`~steady.inclusions.Inclusions` (random circular inclusions, in
  :mod:`steady.inclusions`): at least 3 pixels per mean radius,
  ``n >= ceil(6 L / r)``.

A length that fits the face only when read in units of ``L`` (a script
written when geometries took lengths in units of ``L``) is refused, and
the message gives what it meant in m (:func:`scale_units_note`).

Every kind subclasses :class:`PhaseMap`, the written contract above, and is
registered in :data:`PHASE_MAPS` with its ``[phases] map`` keys
(:class:`steady.schema.KindRegistry`): besides the kinds here,
``inclusions`` (:mod:`steady.inclusions`), ``micrograph``
(:mod:`steady.micrograph`) and the kinds that change with depth below the
surface, ``voxels`` and ``spheres`` (:mod:`steady.depth_maps`: their
``labels`` are the surface section, ``columns(grid)`` the rest).  Label
checks and fill factors are in :mod:`steady.labels`, the readers of map
files in :mod:`steady.array_files`.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import pathlib

import numpy as np
from scipy import spatial

from .array_files import LABELS, array_suffix, read_npy, read_png
from .labels import apportion, check_fill_factors, extend_off_face, validate_labels
from .outline import MIN_SIDE_PIXELS, UNIT_DISK, FaceGrid, as_grid, grid_size, grid_size_text
from .schema import Key, KindRegistry
from .text import shorten

__all__ = [
    "PHASE_MAPS",
    "ArrayMap",
    "Homogeneous",
    "PhaseMap",
    "Rods",
    "Voronoi",
    "check_refinement",
    "check_resolution",
    "face_words",
    "grid_outline",
    "load_phase_map",
    "scale_units_note",
]

logger = logging.getLogger(__name__)

class PhaseMap:
    """The contract of a phase-map kind: what every ``[phases] map`` kind provides.

    A kind is a frozen dataclass that subclasses this class and is
    registered in :data:`PHASE_MAPS` with its keys.  It provides

    - ``n_phases``: the number of phases ``P``;
    - ``labels(grid)``: the phase index ``0..P-1`` of every face pixel of
      ``grid`` (a :class:`steady.outline.FaceGrid`), ``-1`` off the face;
    - ``min_grid(outline=None)`` and ``check_grid(grid)``: the smallest
      ``n`` that resolves it, and the refusal of a coarser grid;
    - the classmethod ``from_values(values, context)``: the kind built from
      its checked keys (:class:`steady.schema.Context`).

    and answers, with the defaults here for a kind that has nothing to say,

    - :meth:`declared_phases`: the number of phases its keys declare, known
      before it is built (a scene compares it with the wear law's before a
      map does its work: a segmentation, a file read);
    - :meth:`file_record`: what a result file records of it;
    - :meth:`segmented_image`: the segmentation of the image it was made from;
    - :meth:`empty_phase_words`: why a phase can have no pixel on a grid.

    Callers ask these, never which kind a map is.
    """

    @classmethod
    def declared_phases(cls, values):
        """The number of phases the checked keys ``values`` declare (default None: unknown).

        None for a kind whose phases are known only once it is built (the
        labels of a file); it is then compared with the wear law's after.

        Parameters
        ----------
        values : dict
            The kind's checked ``[phases] map`` keys (as ``from_values`` takes them).

        Returns
        -------
        int or None
        """
        return None

    def empty_phase_words(self, phase, n):
        """Why ``phase`` has no pixel on the face at ``n``, for the refusal (default: none).

        Parameters
        ----------
        phase : int
        n : int
            Pixels along the longer side of the grid.
        """
        return f"phase {phase} has no pixel on the face at n = {n}"

    def file_record(self):
        """Groups of attributes a result file records of this map (default: none).

        Returns
        -------
        dict of str to dict
            ``{group name: {attribute: value}}``; a quantity ``x`` has its
            udunits unit in the attribute ``x_units``.
        """
        return {}

    def segmented_image(self):
        """The segmentation of the grey-level image this map was made from, or None (default).

        Returns
        -------
        steady.micrograph.Segmentation or None
            What ``runin-steady --segmentation`` draws and the summary
            reports (:func:`steady.plotting.segmentation_figure`).
        """
        return None


#: Registered phase-map kinds (``[phases] map kind``), each with its keys: subclasses of
#: :class:`PhaseMap`.  The kinds of the modules named register when the registry is first
#: read, those of other packages through the entry points ``runin.phase_maps``.
PHASE_MAPS = KindRegistry("phase map", "kind", base=PhaseMap,
                          modules=("steady.inclusions", "steady.micrograph", "steady.depth_maps"),
                          entry_point_group="runin.phase_maps")


def check_resolution(grid, minimum, what):
    """``n`` of a grid as an int; ``ValueError`` naming ``n`` and ``minimum`` if it is coarser.

    Parameters
    ----------
    grid : FaceGrid or int
        A grid, or its ``n`` (pixels along the longer side).
    minimum : int
        The geometry's smallest ``n``.
    what : str
        The geometry, for the message (``"1600 Voronoi seeds"``).
    """
    n = grid.n if isinstance(grid, FaceGrid) else grid_size(grid)
    if n < minimum:
        raise ValueError(f"grid too coarse for {what}: n = {n}, the minimum is n = "
                         f"{grid_size_text(minimum)}")
    return n


def check_refinement(grid, shape, what, name=None):
    """``n`` of a grid that refines a pixel map of ``shape`` by an integer factor, as an int.

    ``what`` names the map in messages (``name``, default ``what``, in the
    one about the multiple); ``ValueError`` for a grid coarser than the map,
    a size that is not a multiple of the map's longer side, or a grid of
    another shape than the map's refined one.
    """
    n0 = max(shape)
    n = check_resolution(grid, n0, what)
    if n % n0:
        raise ValueError(f"grid size n = {n} is not a multiple of the size {n0} of "
                         f"{what if name is None else name}")
    k = n // n0
    if isinstance(grid, FaceGrid) and grid.shape != (k * shape[0], k * shape[1]):
        raise ValueError(f"{what} does not fit the {grid.shape[0]} x {grid.shape[1]} grid of "
                         f"the {grid.outline.describe()}")
    return n


def grid_outline(grid):
    """The outline a grid covers: its own, or for a bare ``n`` the unit disk (radius 1 m)."""
    return grid.outline if isinstance(grid, FaceGrid) else UNIT_DISK


def face_words(grid):
    """The face of ``grid`` in words, for messages; a bare ``n`` says where it rasterises."""
    if isinstance(grid, FaceGrid):
        return f"the {grid.outline.describe()}"
    return ("the unit disk of a bare n (radius 1 m: lengths are in m, rasterise on "
            "outline.grid(n) for a face of another size)")


def _in_scale_units(value, scale):
    """``"0.6 L = 0.0024 m"``: a number read in units of the face scale ``scale`` (m)."""
    if isinstance(value, tuple):
        return (f"({', '.join(f'{v:.6g}' for v in value)}) L = "
                f"({', '.join(f'{v * scale:.6g}' for v in value)}) m")
    return f"{value:.6g} L = {value * scale:.6g} m"


def scale_units_note(scale, **lengths):
    """The end of a refusal of lengths that look given in units of the face scale ``L``.

    Phase geometries take lengths in m.  A script written for lengths in
    units of ``L`` gives numbers near 1, which do not fit a face of a few
    mm; its refusal says what those numbers meant in m, so that the script
    is converted, never silently re-read.

    Parameters
    ----------
    scale : float, m
        ``L`` of the face.
    **lengths : float or tuple of float
        The lengths as given (the numbers of the script), by name.

    Returns
    -------
    str
        ``"; lengths are in m (...)"``, to append to the message.

    Examples
    --------
    >>> note = scale_units_note(4e-3, centre=(0.6, 0.0), radius=0.25)
    >>> print(note[:62])
    ; lengths are in m, not in units of the face scale L = 0.004 m
    >>> print(note[63:])
    (in those units centre (0.6, 0) L = (0.0024, 0) m, radius 0.25 L = 0.001 m)
    """
    meant = ", ".join(f"{name} {_in_scale_units(value, scale)}"
                      for name, value in lengths.items())
    return (f"; lengths are in m, not in units of the face scale L = {scale:.6g} m (in those "
            f"units {meant})")


@PHASE_MAPS.register("homogeneous", doc="one phase")
@dataclasses.dataclass(frozen=True)
class Homogeneous(PhaseMap):
    """A single-phase face."""

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys (none)."""
        return cls()

    @classmethod
    def declared_phases(cls, values):
        """One phase."""
        return 1

    @property
    def n_phases(self):
        """Number of phases (1)."""
        return 1

    def min_grid(self, outline=None):
        """Smallest accepted grid, :data:`MIN_SIDE_PIXELS` (the outline sets its own)."""
        return MIN_SIDE_PIXELS

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return check_resolution(grid, self.min_grid(), "a homogeneous face")

    def labels(self, grid):
        """Phase 0 on the face, -1 off it; shape of the grid."""
        self.check_grid(grid)
        return np.where(as_grid(grid).mask, 0, -1)


# The keys of a scene's map; a map built in Python checks its parameters through them too.
_N_SEEDS = Key("n_seeds", "integer", low=1, low_open=False, required=True,
               doc="seeds, uniform in the face's bounding box")
_SEED = Key("seed", "integer", low=0, low_open=False, required=True,
            doc="seed of the random generator")


@PHASE_MAPS.register("voronoi", (
    _N_SEEDS,
    Key("fill_factors", "numbers", unit="1", low=0.0, high=1.0, required=True,
        doc="share of the seeds of each phase, summing to 1"),
    _SEED),
    doc="Voronoi cells of random seeds; exactly round(rho_i n_seeds) seeds (largest "
        "remainder) get phase i, in random order")
@dataclasses.dataclass(frozen=True)
class Voronoi(PhaseMap):
    """Voronoi cells of random seeds, each seed labelled with a phase.

    Parameters
    ----------
    n_seeds : int
        Seeds, uniform in the face's bounding box (the square ``[-a, a]^2``
        around a disk).  The paper uses ``20^2, 40^2, 80^2, 160^2``.
    fill_factors : sequence of float, shape (P,)
        Target share of the seeds of each phase, each in (0, 1), summing
        to 1.  Exactly ``round(rho_i N)`` seeds (largest remainder) get
        phase ``i``, in random order; the realised area fractions on the
        face scatter around the targets (see :func:`realised_fill_factors`).
    seed : int
        Seed of :func:`numpy.random.default_rng`; the geometry is a pure
        function of the three parameters, and the same on faces of every
        size (the seeds are drawn in units of the face scale ``L``).

    Notes
    -----
    Cells are rasterised by the nearest seed to each pixel centre; seeds
    outside the disk still shape the cells near the rim.
    """

    n_seeds: int
    fill_factors: tuple
    seed: int

    def __post_init__(self):
        """Check the parameters; store the integers as ints, the fill factors as floats."""
        n_seeds = _N_SEEDS.parse(self.n_seeds, "")
        seed = _SEED.parse(self.seed, "")
        fill = check_fill_factors(self.fill_factors)
        counts = apportion(fill, n_seeds)
        if np.any(counts == 0):
            raise ValueError(
                f"{n_seeds} seeds are too few for fill factors {list(fill)}: phase "
                f"{int(np.flatnonzero(counts == 0)[0])} would get no seed")
        object.__setattr__(self, "n_seeds", n_seeds)
        object.__setattr__(self, "seed", seed)
        object.__setattr__(self, "fill_factors", fill)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys."""
        return cls(values["n_seeds"], values["fill_factors"], values["seed"])

    @classmethod
    def declared_phases(cls, values):
        """One phase per fill factor."""
        return len(values["fill_factors"])

    @property
    def n_phases(self):
        """Number of phases, ``len(fill_factors)``."""
        return len(self.fill_factors)

    def empty_phase_words(self, phase, n):
        """Why ``phase`` has no pixel at ``n``: its seeds lie off the face, or between pixels."""
        return (f"phase {phase} has no pixel on the face with these {self.n_seeds} seeds "
                f"(seed = {self.seed}) at n = {n}: its seeds lie off the face or their cells "
                f"fall between pixel centres; use more seeds, another seed or a finer grid")

    @functools.lru_cache(maxsize=4)  # noqa: B019 -- frozen, hashable; a few boxes at most
    def _seeds(self, box=(1.0, 1.0)):
        """Seed points, their phases and k-d tree in the box of half sides ``box``; units of ``L``.

        The seeds are drawn in units of the face scale, so that a geometry
        gives the same cells, scaled, on faces of every size.
        """
        bx, by = (float(b) for b in box)
        rng = np.random.default_rng(self.seed)
        if (bx, by) == (1.0, 1.0):
            points = rng.uniform(-1.0, 1.0, size=(self.n_seeds, 2))
        else:
            points = rng.uniform((-bx, -by), (bx, by), size=(self.n_seeds, 2))
        counts = apportion(self.fill_factors, self.n_seeds)
        phases = rng.permutation(np.repeat(np.arange(self.n_phases), counts))
        points.flags.writeable = False
        phases.flags.writeable = False
        return points, phases, spatial.cKDTree(points)

    def seeds(self, outline=None):
        """Seed points and their phases on the face of ``outline``.

        Parameters
        ----------
        outline : outline object, optional
            The face (default: the unit disk, radius 1 m).

        Returns
        -------
        points : ndarray, shape (n_seeds, 2), m, read-only
            Uniform in the outline's bounding box.
        phases : ndarray, shape (n_seeds,), read-only
        """
        outline = UNIT_DISK if outline is None else outline
        points, phases, _ = self._seeds(outline.aspect)
        points = points * outline.scale
        points.flags.writeable = False
        return points, phases

    @property
    def seed_phases(self):
        """Phase of each seed, shape (n_seeds,) (read-only)."""
        return self._seeds()[1]

    def min_grid(self, outline=None):
        """``max(8, ceil(2 sqrt(n_seeds / (bx by))))``: two pixels per mean seed spacing.

        ``(bx, by)`` is the outline's bounding box over its scale ``L``
        (``(1, 1)`` for a disk, the default).
        """
        bx, by = (1.0, 1.0) if outline is None else outline.aspect
        return max(MIN_SIDE_PIXELS, math.ceil(2.0 * math.sqrt(self.n_seeds / (bx * by)) - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return check_resolution(grid, self.min_grid(as_grid(grid).outline),
                                f"{self.n_seeds} Voronoi seeds")

    def labels(self, grid):
        """Nearest-seed phase at every face pixel, -1 off it; shape of the grid.

        The seeds are uniform in the face's bounding box.  On a periodic cell
        (an outline whose ``periodic`` is True) the tessellation repeats with
        the cell: the nearest seed among all the cell's images.
        """
        self.check_grid(grid)
        grid = as_grid(grid)
        points, phases, tree = self._seeds(grid.outline.aspect)
        i, j = np.nonzero(grid.mask)
        centres = np.column_stack([grid.unit_x[i], grid.unit_y[j]])
        if grid.outline.periodic:
            box = 2.0 * np.asarray(grid.outline.aspect)
            tree = spatial.cKDTree(np.mod(points + 0.5 * box, box), boxsize=box)
            centres = np.mod(centres + 0.5 * box, box)
        _, nearest = tree.query(centres)
        out = np.full(grid.shape, -1, dtype=np.int64)
        out[i, j] = phases[nearest]
        return out


# The keys of a scene's map; rods built in Python check their parameters through them too.
_CENTRES = Key("centres", "pairs", unit="m", required=True, doc="rod centres [x, y]")
_RADII = Key("radii", "numbers", unit="m", low=0.0, required=True, doc="rod radii")
_MATRIX_PHASE = Key("matrix_phase", "integer", low=0, low_open=False, default=0,
                    doc="phase outside the rods")
_ROD_PHASES = Key("rod_phases", "integers", low=0, low_open=False,
                  doc="phase of each rod (default 1 for every rod)")


@PHASE_MAPS.register("rods", (_CENTRES, _RADII, _MATRIX_PHASE, _ROD_PHASES),
                     doc="circular rods inside the face, not overlapping")
@dataclasses.dataclass(frozen=True)
class Rods(PhaseMap):
    """Circular rods of one phase in a matrix of another (paper Fig. 7-8).

    Parameters
    ----------
    centres : sequence of (float, float), m
        Rod centres, from the face's centre.
    radii : sequence of float, m
        Rod radii, one per rod.
    matrix_phase : int, optional
        Phase of the face outside the rods (default 0).
    rod_phases : sequence of int, optional
        Phase of each rod (default: 1 for every rod).

    Notes
    -----
    Rods must lie inside the face (checked when they meet it,
    :meth:`check_outline`: on rasterising and on reading a scene) and must
    not overlap (touching is allowed).  Every phase ``0..P-1``, with
    ``P = 1 + max(matrix_phase, rod_phases)``, must be used.  A pixel
    belongs to a rod when its centre lies strictly inside the rod.

    Examples
    --------
    Two rods of 1 mm on a disk of 5 mm:

    >>> from steady.outline import Circle
    >>> rods = Rods(centres=[(0.0, 0.0), (2.5e-3, 0.0)], radii=[1e-3, 1e-3])
    >>> rods.min_grid(Circle(5e-3))
    30
    >>> labels = rods.labels(Circle(5e-3).grid(96))
    >>> labels.shape, int(labels.max())
    ((96, 96), 1)
    """

    centres: tuple
    radii: tuple
    matrix_phase: int = 0
    rod_phases: tuple | None = None

    def __post_init__(self):
        """Check the rods; store centres and radii as tuples of floats, phases as ints."""
        try:  # a scene's arrays are lists; from Python, any sequences
            centres, radii = [list(c) for c in self.centres], list(self.radii)
            rod_phases = [1] * len(centres) if self.rod_phases is None else list(self.rod_phases)
        except TypeError:
            raise ValueError(f"rods need sequences of centres [x, y], radii and rod phases, got "
                             f"{shorten(self.centres)}, {shorten(self.radii)} and "
                             f"{shorten(self.rod_phases)}") from None
        if not centres:
            raise ValueError("at least one rod is needed")
        if len(radii) != len(centres):
            raise ValueError(f"{len(centres)} rod centres but {len(radii)} radii")
        # The scale range of the radii is a problem's to check.
        centres = _CENTRES.parse(centres, "rod")
        radii = _RADII.parse(radii, "rod", scale=False)
        matrix_phase = _MATRIX_PHASE.parse(self.matrix_phase, "")
        rod_phases = _ROD_PHASES.parse(rod_phases, "")
        phases = (matrix_phase, *rod_phases)
        if len(rod_phases) != len(centres):
            raise ValueError(f"{len(centres)} rod centres but {len(rod_phases)} rod_phases")
        for k in range(len(centres)):
            for m in range(k + 1, len(centres)):
                d = math.dist(centres[k], centres[m])
                # Touching is allowed, to round-off relative to the radii.
                if d < (radii[k] + radii[m]) * (1.0 - 1e-12):
                    raise ValueError(f"rods {k} and {m} overlap: centres {d:.6g} m apart, radii "
                                     f"{radii[k]:.6g} m and {radii[m]:.6g} m")
        used = set(phases)
        missing = sorted(set(range(max(used) + 1)) - used)
        if missing:
            raise ValueError(f"phase {missing[0]} is used by neither the matrix nor a rod "
                             f"(matrix_phase={self.matrix_phase}, rod_phases={list(rod_phases)})")
        object.__setattr__(self, "centres", centres)
        object.__setattr__(self, "radii", radii)
        object.__setattr__(self, "matrix_phase", matrix_phase)
        object.__setattr__(self, "rod_phases", rod_phases)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys (m), checked against the scene's face."""
        rods = cls(values["centres"], values["radii"], values["matrix_phase"],
                   values.get("rod_phases"))
        rods.check_outline(context.outline)
        return rods

    @classmethod
    def declared_phases(cls, values):
        """``1 + max(matrix_phase, rod_phases)``, the rods' phase 1 by default."""
        rod_phases = values.get("rod_phases", (1,) * len(values["centres"]))
        return 1 + max(values["matrix_phase"], *rod_phases)

    @property
    def n_phases(self):
        """Number of phases, ``1 + max(matrix_phase, rod_phases)``."""
        return 1 + max(self.matrix_phase, *self.rod_phases)

    def min_grid(self, outline=None):
        """``max(8, ceil(6 L / r_min))``: three pixels per radius of the smallest rod.

        ``L`` is the scale of ``outline`` (default: the unit disk, 1 m).
        """
        scale = (UNIT_DISK if outline is None else outline).scale
        # r / L as the rasteriser divides (the smallest of the quotients).
        return max(MIN_SIDE_PIXELS, math.ceil(6.0 / (min(self.radii) / scale) - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` in m if the grid is too coarse for the smallest rod."""
        return check_resolution(grid, self.min_grid(grid_outline(grid)),
                                f"rods of radius {min(self.radii):.6g} m (3 pixels per radius) "
                                f"on {face_words(grid)}")

    def check_outline(self, outline):
        """``ValueError`` naming the first rod that does not lie inside the face of ``outline``."""
        L = outline.scale
        for k, ((cx, cy), r) in enumerate(zip(self.centres, self.radii, strict=True)):
            if outline.encloses_disk((cx, cy), r):
                continue
            note = ""
            if outline.encloses_disk((cx * L, cy * L), r * L):
                note = scale_units_note(L, centre=(cx, cy), radius=r)
            raise ValueError(f"rod {k} (centre ({cx:.6g}, {cy:.6g}) m, radius {r:.6g} m) does "
                             f"not lie inside the face ({outline.describe()}){note}")

    def labels(self, grid):
        """Rod phase inside each rod, matrix phase elsewhere on the face; shape of the grid."""
        self.check_outline(grid_outline(grid))  # first: it names lengths meant in units of L
        self.check_grid(grid)
        grid = as_grid(grid)
        L = grid.outline.scale
        x, y = grid.unit_x, grid.unit_y
        out = np.where(grid.mask, self.matrix_phase, -1)
        for (cx, cy), r, phase in zip(self.centres, self.radii, self.rod_phases, strict=True):
            cx, cy, r = cx / L, cy / L, r / L
            inside = (x[:, None] - cx) ** 2 + (y[None, :] - cy) ** 2 < r * r
            out[inside] = phase
        return out


@PHASE_MAPS.register("file", (
    Key("path", "path", required=True,
        doc=".npy: phase index per pixel, 0..P-1 on the face; off the face any value, "
            "a negative one (e.g. -1) only there; .png: one phase per grey level or colour "
            "on the face, by increasing value"),),
    doc="a phase map read from a file, rows along x")
@dataclasses.dataclass(frozen=True, eq=False)
class ArrayMap(PhaseMap):
    """A phase map given as pixels.

    Parameters
    ----------
    labels : ndarray, shape (mx, my), int
        Phase index at each pixel of the grid of ``outline`` with
        ``n0 = max(mx, my)`` pixels along its longer side (for a disk the
        ``n0 x n0`` grid over ``[-a, a]^2``).  On the face the labels must
        be ``0..P-1`` with every phase present; off the face any value is
        ignored (``-1`` is customary).  The face is the outline's: a
        negative value marks a pixel off it and is refused on it (the rule
        of face masks too, :func:`steady.array_files.integer_face`).
    source : str, optional
        Where the map came from (for messages).
    outline : outline object, optional
        The face the map covers (:mod:`steady.outline`; default: a disk).
        Only its shape matters: the map is in pixels of its bounding box.

    Notes
    -----
    ``labels(grid)`` accepts grids of ``n = k n0`` pixels along the longer
    side (pixel replication).  The finer face of a curved outline reaches a
    little further out at the rim than the coarse one; those pixels take
    the label of the nearest face pixel of the coarse map.
    """

    labels_array: np.ndarray
    source: str = "array"
    outline: object = None

    def __post_init__(self):
        """Check the labels; store them read-only with the pixels off the face filled."""
        a = np.asarray(self.labels_array)
        outline = UNIT_DISK if self.outline is None else self.outline
        if a.ndim != 2 or (self.outline is None and a.shape[0] != a.shape[1]):
            raise ValueError(f"phase map {self.source} must be a square 2-d array, "
                             f"got shape {a.shape}")
        LABELS.check(a.dtype, f"phase map {self.source}")
        if a.size == 0:
            raise ValueError(f"phase map {self.source} is empty: an array of shape {a.shape}")
        a = a.astype(np.int64)
        n0 = max(a.shape)
        check_resolution(n0, MIN_SIDE_PIXELS, f"phase map {self.source}")
        try:
            grid = FaceGrid(outline, n0)
            expected = grid.shape
        except ValueError as err:
            raise ValueError(f"phase map {self.source}: {err}") from None
        if a.shape != expected:
            raise ValueError(f"phase map {self.source} has {a.shape[0]} x {a.shape[1]} pixels; "
                             f"the grid of the {outline.describe()} with {n0} pixels along "
                             f"its longer side has {expected[0]} x {expected[1]}")
        on_face = grid.mask
        negative = on_face & (a < 0)
        if negative.any():
            i, j = (int(v[0]) for v in np.nonzero(negative))
            raise ValueError(f"phase map {self.source}: phase label {int(a[i, j])} found on "
                             f"the face at pixel ({i}, {j}) ({int(negative.sum())} face "
                             f"pixel(s) negative): a negative value marks a pixel off the face, "
                             f"and the face is the {outline.describe()}'s")
        n_phases = int(a[on_face].max()) + 1
        try:
            validate_labels(np.where(on_face, a, -1), n_phases, face_mask=on_face)
        except ValueError as err:
            raise ValueError(f"phase map {self.source}: {err}") from None
        # Off-face pixels take the label of the nearest face pixel, so that
        # refined grids (whose face reaches further out) are fully labelled.
        filled = extend_off_face(a, on_face)
        filled.flags.writeable = False
        object.__setattr__(self, "labels_array", filled)
        object.__setattr__(self, "_n_phases", n_phases)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys: :func:`load_phase_map`.

        The map's size must divide the scene's ``n``: a larger one is
        refused before its data are read.
        """
        return load_phase_map(values["path"], max_size=context.n, outline=context.outline)

    @property
    def n_phases(self):
        """Number of phases: one more than the largest label on the face."""
        return self._n_phases

    @property
    def size(self):
        """Pixels ``n0`` along the map's longer side."""
        return max(self.labels_array.shape)

    def min_grid(self, outline=None):
        """The map's own size ``n0``."""
        return self.size

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` unless a multiple of the map size on the map's face."""
        mx, my = self.labels_array.shape
        return check_refinement(grid, (mx, my), f"phase map {self.source} of {mx} x {my} pixels",
                                f"phase map {self.source}")

    def labels(self, grid):
        """Labels on a grid of ``n = k n0`` pixels along the longer side."""
        n = self.check_grid(grid)
        grid = as_grid(grid)
        k = n // self.size
        fine = self.labels_array if k == 1 else np.kron(self.labels_array,
                                                        np.ones((k, k), dtype=np.int64))
        return np.where(grid.mask, fine, -1)


def load_phase_map(path, *, max_phases=16, max_size=None, outline=None):
    """Read a phase map from a ``.npy`` or ``.png`` file.

    Parameters
    ----------
    path : str or path-like
        ``.npy``: a 2-d integer array, phase index per pixel: ``0..P-1`` on
        the face, any value off it (a negative one, e.g. -1, only off it).
        ``.png``: an image; each distinct grey level
        (or colour) inside the face is one phase, numbered by increasing
        value (colours compare as ``(R, G, B)`` tuples; the alpha channel is
        ignored).  Array rows (image rows) run along x.  The map covers the
        face's bounding box: square for a disk, else of the shape of the
        outline's grid (:class:`ArrayMap`).
    max_phases : int, optional
        Refuse images with more distinct levels on the face than this
        (default 16); an anti-aliased image would otherwise give hundreds
        of phases.
    max_size : int, optional
        Refuse maps of more than ``max_size`` pixels along their longer
        side, before reading their data (a scene passes its grid size
        ``n``: the map's size must divide it).
    outline : outline object, optional
        The face the map covers (default: a disk).

    Returns
    -------
    ArrayMap

    Raises
    ------
    ValueError
        Missing file, a directory or device, an empty, truncated or
        unreadable file, an unsupported suffix, a map larger than
        ``max_size``, bad contents.
    """
    path = pathlib.Path(path)
    what = "phase map"
    suffix = array_suffix(path, what)
    square = outline is None or outline.aspect == (1.0, 1.0)
    if suffix == ".npy":
        a = read_npy(path, what=what, holds=LABELS, max_side=max_size, square=square)
    else:
        a = _png_labels(path, max_phases, max_size, outline)
    return ArrayMap(a, source=repr(str(path)), outline=outline)


def _png_labels(path, max_phases, max_size=None, outline=None):
    what = "phase map"
    square = outline is None or outline.aspect == (1.0, 1.0)

    def check_size(size):
        if square and size[0] != size[1]:
            raise ValueError(f"{what} {str(path)!r} must be square, got {size[0]} x {size[1]} "
                             f"pixels")
        if max_size is not None and max(size) > max_size:
            raise ValueError(f"{what} {str(path)!r} has {size[0]} x {size[1]} pixels, more "
                             f"than the grid's n = {max_size} (n must be a multiple of the "
                             f"map's size)")

    img = read_png(path, what, check_size)
    if img.ndim == 3:
        img = img[..., :3]  # drop alpha
    if square and img.shape[0] != img.shape[1]:
        raise ValueError(f"phase map {str(path)!r} must be square, got {img.shape[1]} x "
                         f"{img.shape[0]} pixels")
    mx, my = img.shape[:2]
    if np.issubdtype(img.dtype, np.floating):
        img = np.rint(img * 65535).astype(np.int64)  # 8- and 16-bit levels stay distinct
    else:
        img = img.astype(np.int64)
    pixels = img.reshape(mx * my, -1)
    outline = UNIT_DISK if outline is None else outline
    try:
        grid = FaceGrid(outline, max(mx, my))
        if grid.shape != (mx, my):
            raise ValueError(f"it has {mx} x {my} pixels; the grid of the "
                             f"{outline.describe()} with {max(mx, my)} pixels along its longer "
                             f"side has {grid.shape[0]} x {grid.shape[1]}")
        on_face = grid.mask.ravel()
    except ValueError as err:
        raise ValueError(f"phase map {str(path)!r}: {err}") from None
    levels, inverse = np.unique(pixels[on_face], axis=0, return_inverse=True)
    if len(levels) > max_phases:
        raise ValueError(f"phase map {str(path)!r} has {len(levels)} distinct levels on the "
                         f"face, more than max_phases={max_phases} (an anti-aliased image? "
                         f"a micrograph is segmented by the map kind \"micrograph\")")
    labels = np.full(mx * my, -1, dtype=np.int64)
    labels[on_face] = inverse.ravel()
    logger.debug("%s: %d phases from levels %s", path, len(levels), levels.tolist())
    return labels.reshape(mx, my)

