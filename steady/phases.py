"""Phase maps of the punch face that can be rasterised at any grid size.

A phase geometry is a continuous description of which phase sits where on
the face, in units of the face's scale ``L`` (:mod:`steady.outline`: the
punch radius ``a`` of a disk, else the larger half side of the face's
bounding box), centred on the face's centre.  Every geometry has

- ``n_phases`` : the number of phases ``P``;
- ``labels(grid)`` : an ``(nx, ny)`` integer array with the phase index
  ``0..P-1`` at every face pixel of ``grid`` (a
  :class:`steady.outline.FaceGrid`) and ``-1`` off the face; an integer
  ``n`` stands for the ``n x n`` grid of the unit disk
  (:func:`steady.grid.face_mask`);
- ``min_grid(outline=None)`` : the smallest ``n`` (pixels along the longer
  side) at which the geometry is resolved on that outline (default: a disk);
- ``check_grid(grid)`` : raises :class:`ValueError` (naming ``n`` and the
  minimum) if ``labels(grid)`` would refuse the grid.

Because the geometry is continuous, the same object can be rasterised at
several ``n`` (for instance to estimate the discretisation error of the
rms slope).  :class:`ArrayMap` is the exception: it is given as pixels and
can only be refined by integer factors.

Resolution rules (``labels`` refuses coarser grids):

- every geometry: ``n >= 8``;
- :class:`Voronoi`: at least 2 pixels per mean seed spacing.  ``N`` seeds
  in the bounding box ``[-bx, bx] x [-by, by]`` (units of ``L``; the square
  ``[-1, 1]^2`` of a disk) are ``sqrt(4 bx by / N)`` apart on average and a
  pixel is ``2 / n`` wide, so ``n >= ceil(2 sqrt(N / (bx by)))``;
- :class:`Rods`: at least 3 pixels per radius of the smallest rod,
  ``n >= ceil(6 / r_min)`` (``r_min`` in units of ``L``);
- :class:`ArrayMap`: ``n`` must be a multiple of the map's size along its
  longer side;
- :class:`~steady.inclusions.Inclusions` (random circular inclusions, in
  :mod:`steady.inclusions`, exported here): at least 3 pixels per mean
  radius, ``n >= ceil(6 / r)``.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import pathlib
import stat

import numpy as np
from scipy import ndimage, spatial

from .grid import face_mask as disk_face_mask
from .outline import Circle, FaceGrid
from .text import format_bytes

__all__ = [
    "ArrayMap",
    "Homogeneous",
    "Inclusions",
    "MIN_GRID",
    "Rods",
    "Voronoi",
    "extend_off_face",
    "face_grid",
    "load_phase_map",
    "npy_header",
    "read_face_mask",
    "read_npy",
    "realised_fill_factors",
    "validate_labels",
]

logger = logging.getLogger(__name__)

#: Smallest grid accepted by any geometry, pixels across the diameter.
MIN_GRID = 8

#: Tolerance on the sum of the fill factors.
_FILL_SUM_TOL = 1e-9


def _check_grid(n, minimum, what):
    """Raise ``ValueError`` unless ``n`` is an integer ``>= minimum``.

    ``n`` may be a :class:`~steady.outline.FaceGrid` (its ``n`` is checked).
    """
    if isinstance(n, FaceGrid):
        n = n.n
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"grid size n must be an integer, got {n!r}")
    if n < minimum:
        raise ValueError(f"grid too coarse for {what}: n = {n}, the minimum is n = {minimum}")
    return int(n)


#: The outline of grids given by their size alone: the unit disk.
_UNIT_DISK = Circle(1.0)


def face_grid(grid):
    """The :class:`~steady.outline.FaceGrid` a geometry rasterises on.

    Parameters
    ----------
    grid : FaceGrid or int
        A grid, or ``n`` for the ``n x n`` grid of the unit disk (the
        cylindrical punch in units of its radius).

    Returns
    -------
    FaceGrid
    """
    if isinstance(grid, FaceGrid):
        return grid
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)):
        raise ValueError(f"grid size n must be an integer, got {grid!r}")
    return FaceGrid(_UNIT_DISK, int(grid))


def _outline_of(grid):
    """The outline of a grid argument (the unit disk for an integer)."""
    return grid.outline if isinstance(grid, FaceGrid) else _UNIT_DISK


def validate_labels(labels, n_phases, *, face_mask=None):
    """Check a rasterised phase map and count the pixels of each phase.

    Parameters
    ----------
    labels : ndarray, shape (nx, ny), int
        Phase index on the face, ``-1`` off the face.
    n_phases : int
        Number of phases ``P``.
    face_mask : ndarray of bool, shape (nx, ny), optional
        The face's pixels (e.g. :attr:`steady.outline.FaceGrid.mask`), to
        check the labels against; default: the pixels with ``labels >= 0``.

    Returns
    -------
    ndarray, shape (P,), int
        Face pixels of each phase.

    Raises
    ------
    ValueError
        If the array is not 2-d, the face pixels do not carry labels
        ``0..P-1``, a pixel off the face is not ``-1``, there is no face
        pixel, or a phase has no pixel.
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"phase labels must be a 2-d array, got shape {labels.shape}")
    if not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"phase labels must be integers, got dtype {labels.dtype}")
    n_phases = int(n_phases)
    if n_phases < 1:
        raise ValueError(f"n_phases must be at least 1, got {n_phases}")
    mask = labels >= 0 if face_mask is None else np.asarray(face_mask)
    if mask.shape != labels.shape:
        raise ValueError(f"face mask of shape {mask.shape} for labels of shape {labels.shape}")
    if not mask.any():
        raise ValueError("the phase map has no face pixel")
    face_labels = labels[mask]
    low, high = int(face_labels.min()), int(face_labels.max())
    if low < 0:
        raise ValueError(f"phase label {low} found on the face; face pixels need labels "
                         f"0..{n_phases - 1}")
    if high >= n_phases:
        raise ValueError(f"unknown phase label {high} on the face: there are {n_phases} phases "
                         f"(labels 0..{n_phases - 1})")
    if np.any(labels[~mask] != -1):
        raise ValueError("pixels off the face must carry the label -1")
    if n_phases > face_labels.size:
        # Counting would allocate one entry per label: refuse before.
        raise ValueError(f"{n_phases} phases (labels 0..{n_phases - 1}) cannot all have a pixel "
                         f"on a face of {face_labels.size} pixels")
    counts = np.bincount(face_labels, minlength=n_phases)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        shown = (f"pixel counts per phase: {counts.tolist()}" if n_phases <= 16
                 else f"{empty.size} of the {n_phases} phases have none")
        raise ValueError(f"phase {int(empty[0])} has no pixel on the face ({shown})")
    return counts


def realised_fill_factors(labels, n_phases):
    """Fraction of the face pixels held by each phase (eq. 13).

    Parameters
    ----------
    labels : ndarray, shape (n, n), int
        Phase index on the face, ``-1`` off the face.
    n_phases : int

    Returns
    -------
    ndarray, shape (P,)
        Pixel-count fractions; they sum to 1.

    Raises
    ------
    ValueError
        As :func:`validate_labels`.
    """
    counts = validate_labels(labels, n_phases)
    return counts / counts.sum()


def extend_off_face(values, face_mask=None):
    """Copy of a face field with every pixel off the face set to its nearest face pixel.

    Parameters
    ----------
    values : ndarray, shape (nx, ny)
        Field on the pixel grid; values off the face are not used.
    face_mask : ndarray of bool, shape (nx, ny), optional
        The face's pixels; default: the disk of :func:`steady.grid.face_mask`
        (``values`` square).

    Returns
    -------
    ndarray, shape (nx, ny)
        Same dtype; equal to ``values`` on the face.
    """
    values = np.asarray(values)
    on_face = disk_face_mask(values.shape[0]) if face_mask is None else face_mask
    _, (ii, jj) = ndimage.distance_transform_edt(~on_face, return_indices=True)
    return values[ii, jj]


@dataclasses.dataclass(frozen=True)
class Homogeneous:
    """A single-phase face."""

    @property
    def n_phases(self):
        """Number of phases (1)."""
        return 1

    def min_grid(self, outline=None):
        """Smallest accepted grid, :data:`MIN_GRID` (the outline sets its own)."""
        return MIN_GRID

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return _check_grid(grid, self.min_grid(), "a homogeneous face")

    def labels(self, grid):
        """Phase 0 on the face, -1 off it; shape of the grid."""
        self.check_grid(grid)
        return np.where(face_grid(grid).mask, 0, -1)


def _as_fill_factors(fill_factors):
    try:
        values = tuple(float(v) for v in fill_factors)
    except (TypeError, ValueError):
        raise ValueError(f"fill factors must be a sequence of numbers, got "
                         f"{fill_factors!r}") from None
    if len(values) < 2:
        raise ValueError(f"fill factors need at least two phases, got {list(values)}")
    bad = [v for v in values if not (np.isfinite(v) and 0.0 < v < 1.0)]
    if bad:
        raise ValueError(f"fill factors must each lie in (0, 1), got {list(values)}")
    if abs(math.fsum(values) - 1.0) > _FILL_SUM_TOL:
        raise ValueError(f"fill factors must sum to 1, got {list(values)} "
                         f"(sum {math.fsum(values)!r})")
    return values


def _apportion(fractions, total):
    """Integers proportional to ``fractions`` summing to ``total``.

    Largest-remainder rounding: each count is ``floor`` or ``ceil`` of
    ``fraction * total``, which is as close to the fill factors as whole
    seeds allow.
    """
    exact = np.asarray(fractions) * total
    counts = np.floor(exact).astype(int)
    remainder = total - counts.sum()
    # Stable sort: ties go to the lower phase index, reproducibly.
    order = np.argsort(-(exact - counts), kind="stable")
    counts[order[:remainder]] += 1
    return counts


@dataclasses.dataclass(frozen=True)
class Voronoi:
    """Voronoi cells of random seeds, each seed labelled with a phase.

    Parameters
    ----------
    n_seeds : int
        Seeds, uniform in the face's bounding box (units of ``L``: the
        square ``[-1, 1]^2`` around a disk).  The paper uses ``20^2, 40^2,
        80^2, 160^2``.
    fill_factors : sequence of float, shape (P,)
        Target share of the seeds of each phase, each in (0, 1), summing
        to 1.  Exactly ``round(rho_i N)`` seeds (largest remainder) get
        phase ``i``, in random order; the realised area fractions on the
        face scatter around the targets (see :func:`realised_fill_factors`).
    seed : int
        Seed of :func:`numpy.random.default_rng`; the geometry is a pure
        function of the three parameters.

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
        if (isinstance(self.n_seeds, bool) or not isinstance(self.n_seeds, (int, np.integer))
                or self.n_seeds < 1):
            raise ValueError(f"n_seeds must be a positive integer, got {self.n_seeds!r}")
        if (isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer))
                or self.seed < 0):
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")
        fill = _as_fill_factors(self.fill_factors)
        counts = _apportion(fill, int(self.n_seeds))
        if np.any(counts == 0):
            raise ValueError(
                f"{self.n_seeds} seeds are too few for fill factors {list(fill)}: phase "
                f"{int(np.flatnonzero(counts == 0)[0])} would get no seed")
        object.__setattr__(self, "n_seeds", int(self.n_seeds))
        object.__setattr__(self, "seed", int(self.seed))
        object.__setattr__(self, "fill_factors", fill)

    @property
    def n_phases(self):
        """Number of phases, ``len(fill_factors)``."""
        return len(self.fill_factors)

    @functools.lru_cache(maxsize=4)  # noqa: B019 -- frozen, hashable; a few boxes at most
    def seeds(self, box=(1.0, 1.0)):
        """Seed points, their phases and their k-d tree in a bounding box.

        Parameters
        ----------
        box : (float, float), optional
            Half sides ``(bx, by)`` of the box, units of ``L`` (default the
            square ``[-1, 1]^2`` around a disk).

        Returns
        -------
        points : ndarray, shape (n_seeds, 2), read-only
        phases : ndarray, shape (n_seeds,), read-only
        tree : scipy.spatial.cKDTree
        """
        bx, by = (float(b) for b in box)
        rng = np.random.default_rng(self.seed)
        if (bx, by) == (1.0, 1.0):
            points = rng.uniform(-1.0, 1.0, size=(self.n_seeds, 2))
        else:
            points = rng.uniform((-bx, -by), (bx, by), size=(self.n_seeds, 2))
        counts = _apportion(self.fill_factors, self.n_seeds)
        phases = rng.permutation(np.repeat(np.arange(self.n_phases), counts))
        points.flags.writeable = False
        phases.flags.writeable = False
        return points, phases, spatial.cKDTree(points)

    @property
    def seed_phases(self):
        """Phase of each seed, shape (n_seeds,) (read-only)."""
        return self.seeds()[1]

    def min_grid(self, outline=None):
        """``max(8, ceil(2 sqrt(n_seeds / (bx by))))``: two pixels per mean seed spacing.

        ``(bx, by)`` is the outline's bounding box in units of its scale
        (``(1, 1)`` for a disk, the default).
        """
        bx, by = (1.0, 1.0) if outline is None else outline.aspect
        return max(MIN_GRID, math.ceil(2.0 * math.sqrt(self.n_seeds / (bx * by)) - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return _check_grid(grid, self.min_grid(_outline_of(grid)),
                           f"{self.n_seeds} Voronoi seeds")

    def labels(self, grid):
        """Nearest-seed phase at every face pixel, -1 off it; shape of the grid.

        The seeds are uniform in the face's bounding box.
        """
        self.check_grid(grid)
        grid = face_grid(grid)
        _, phases, tree = self.seeds(grid.outline.aspect)
        i, j = np.nonzero(grid.mask)
        _, nearest = tree.query(np.column_stack([grid.unit_x[i], grid.unit_y[j]]))
        out = np.full(grid.shape, -1, dtype=np.int64)
        out[i, j] = phases[nearest]
        return out


@dataclasses.dataclass(frozen=True)
class Rods:
    """Circular rods of one phase in a matrix of another (paper Fig. 7-8).

    Parameters
    ----------
    centres : sequence of (float, float)
        Rod centres, units of the face's scale ``L`` (the radius ``a`` of a
        disk).
    radii : sequence of float
        Rod radii, units of ``L``, one per rod.
    matrix_phase : int, optional
        Phase of the face outside the rods (default 0).
    rod_phases : sequence of int, optional
        Phase of each rod (default: 1 for every rod).

    Notes
    -----
    Rods must lie inside the face (for a disk ``|c| + r <= 1``; checked
    when they are rasterised, :meth:`check_outline`) and must not overlap
    (touching is allowed).  Every phase ``0..P-1``, with
    ``P = 1 + max(matrix_phase, rod_phases)``, must be used.  A pixel
    belongs to a rod when its centre lies strictly inside the rod.
    """

    centres: tuple
    radii: tuple
    matrix_phase: int = 0
    rod_phases: tuple | None = None

    def __post_init__(self):
        """Check the rods; store centres and radii as tuples of floats, phases as ints."""
        try:
            centres = tuple((float(c[0]), float(c[1])) for c in self.centres)
            bad_len = [c for c in self.centres if len(c) != 2]
        except (TypeError, ValueError, IndexError):
            raise ValueError(f"rod centres must be pairs of numbers, got "
                             f"{self.centres!r}") from None
        if bad_len:
            raise ValueError(f"rod centres must be pairs of numbers, got {self.centres!r}")
        try:
            radii = tuple(float(r) for r in self.radii)
        except (TypeError, ValueError):
            raise ValueError(f"rod radii must be numbers, got {self.radii!r}") from None
        if not centres:
            raise ValueError("at least one rod is needed")
        if len(radii) != len(centres):
            raise ValueError(f"{len(centres)} rod centres but {len(radii)} radii")
        for r in radii:
            if not (np.isfinite(r) and r > 0):
                raise ValueError(f"rod radii must be positive and finite, got {list(radii)}")
        for c in centres:
            if not all(np.isfinite(c)):
                raise ValueError(f"rod centres must be finite, got {list(centres)}")
        rod_phases = (1,) * len(centres) if self.rod_phases is None else self.rod_phases
        phases = (self.matrix_phase, *rod_phases)
        if any(isinstance(p, bool) or not isinstance(p, (int, np.integer)) or p < 0
               for p in phases):
            raise ValueError(f"matrix_phase and rod_phases must be non-negative integers, got "
                             f"{self.matrix_phase!r} and {self.rod_phases!r}")
        rod_phases = tuple(int(p) for p in rod_phases)
        if len(rod_phases) != len(centres):
            raise ValueError(f"{len(centres)} rods but {len(rod_phases)} rod phases")
        for k, ((cx, cy), r) in enumerate(zip(centres, radii, strict=True)):
            # Every face lies in [-1, 1]^2 (units of its scale); the face
            # itself is checked when the rods meet it (check_outline).
            if max(abs(cx), abs(cy)) + r > 1.0 + 1e-12:
                raise ValueError(f"rod {k} (centre ({cx}, {cy}), radius {r}, units of the face "
                                 f"scale) does not lie inside the face's bounding square")
        for k in range(len(centres)):
            for m in range(k + 1, len(centres)):
                d = math.dist(centres[k], centres[m])
                if d < radii[k] + radii[m] - 1e-12:
                    raise ValueError(f"rods {k} and {m} overlap: centres {d:.6g} apart, radii "
                                     f"{radii[k]} and {radii[m]} (units of the punch radius)")
        used = set(phases)
        missing = sorted(set(range(max(used) + 1)) - used)
        if missing:
            raise ValueError(f"phase {missing[0]} is used by neither the matrix nor a rod "
                             f"(matrix_phase={self.matrix_phase}, rod_phases={list(rod_phases)})")
        object.__setattr__(self, "centres", centres)
        object.__setattr__(self, "radii", radii)
        object.__setattr__(self, "matrix_phase", int(self.matrix_phase))
        object.__setattr__(self, "rod_phases", rod_phases)

    @property
    def n_phases(self):
        """Number of phases, ``1 + max(matrix_phase, rod_phases)``."""
        return 1 + max(self.matrix_phase, *self.rod_phases)

    def min_grid(self, outline=None):
        """``max(8, ceil(6 / r_min))``: three pixels per radius of the smallest rod."""
        return max(MIN_GRID, math.ceil(6.0 / min(self.radii) - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return _check_grid(grid, self.min_grid(), f"rods of radius {min(self.radii)} L")

    def check_outline(self, outline):
        """``ValueError`` naming the first rod that does not lie inside the face of ``outline``."""
        L = outline.scale
        for k, ((cx, cy), r) in enumerate(zip(self.centres, self.radii, strict=True)):
            if not outline.encloses_disk((cx * L, cy * L), r * L):
                raise ValueError(f"rod {k} (centre ({cx}, {cy}), radius {r}, units of the face "
                                 f"scale {L:.6g} m) does not lie inside the face "
                                 f"({outline.describe()})")

    def labels(self, grid):
        """Rod phase inside each rod, matrix phase elsewhere on the face; shape of the grid."""
        self.check_grid(grid)
        grid = face_grid(grid)
        self.check_outline(grid.outline)
        x, y = grid.unit_x, grid.unit_y
        out = np.where(grid.mask, self.matrix_phase, -1)
        for (cx, cy), r, phase in zip(self.centres, self.radii, self.rod_phases, strict=True):
            inside = (x[:, None] - cx) ** 2 + (y[None, :] - cy) ** 2 < r * r
            out[inside] = phase
        return out


@dataclasses.dataclass(frozen=True, eq=False)
class ArrayMap:
    """A phase map given as pixels.

    Parameters
    ----------
    labels : ndarray, shape (mx, my), int
        Phase index at each pixel of the grid of ``outline`` with
        ``n0 = max(mx, my)`` pixels along its longer side (for a disk the
        ``n0 x n0`` grid over ``[-a, a]^2``).  On the face the labels must
        be ``0..P-1`` with every phase present; off the face any value is
        ignored (``-1`` is customary).
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
        outline = _UNIT_DISK if self.outline is None else self.outline
        if a.ndim != 2 or (self.outline is None and a.shape[0] != a.shape[1]):
            raise ValueError(f"phase map {self.source} must be a square 2-d array, "
                             f"got shape {a.shape}")
        if not (a.dtype == bool or np.issubdtype(a.dtype, np.integer)):
            raise ValueError(f"phase map {self.source} must hold integers, got dtype {a.dtype}")
        a = a.astype(np.int64)
        n0 = max(a.shape)
        _check_grid(n0, MIN_GRID, f"phase map {self.source}")
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
        n0 = self.size
        mx, my = self.labels_array.shape
        n = _check_grid(grid, n0, f"phase map {self.source} of {mx} x {my} pixels")
        if n % n0:
            raise ValueError(f"grid size n = {n} is not a multiple of the size {n0} of phase "
                             f"map {self.source}")
        if isinstance(grid, FaceGrid):
            k = n // n0
            if grid.shape != (k * mx, k * my):
                raise ValueError(f"phase map {self.source} of {mx} x {my} pixels does not fit "
                                 f"the {grid.shape[0]} x {grid.shape[1]} grid of the "
                                 f"{grid.outline.describe()}")
        return n

    def labels(self, grid):
        """Labels on a grid of ``n = k n0`` pixels along the longer side."""
        n = self.check_grid(grid)
        grid = face_grid(grid)
        k = n // self.size
        fine = self.labels_array if k == 1 else np.kron(self.labels_array,
                                                        np.ones((k, k), dtype=np.int64))
        return np.where(grid.mask, fine, -1)


def _input_file(path, what):
    """Size in bytes of an input file; ``ValueError`` unless it is a readable regular file."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise ValueError(f"{what} {str(path)!r} does not exist") from None
    except OSError as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {err.strerror or err}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} {str(path)!r} is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{what} {str(path)!r} is not a regular file (a device or a pipe?)")
    if st.st_size == 0:
        raise ValueError(f"{what} {str(path)!r} is empty (0 bytes)")
    return st.st_size


def npy_header(path, *, what="file", shape=None, max_side=None, square=True):
    """Shape and dtype of a ``.npy`` file, read from its header without loading the data.

    Parameters
    ----------
    path : str or path-like
    what : str, optional
        How messages name the file (e.g. ``"phase map"``).
    shape : tuple of int, optional
        Refuse any other shape.
    max_side : int, optional
        Refuse anything but a square 2-d array of at most
        ``max_side x max_side`` values.
    square : bool, optional
        With ``max_side``: whether the array must be square (default True);
        if not, any 2-d array whose longer side is at most ``max_side``.

    Returns
    -------
    shape : tuple of int
    dtype : numpy.dtype

    Raises
    ------
    ValueError
        Missing file, a directory or device, an empty file, no ``.npy``
        header, a damaged header, an array of Python objects, a shape
        refused by ``shape`` or ``max_side``, or fewer data bytes than the
        header announces (a truncated file, or a header that claims a huge
        array).
    """
    import numpy.lib.format as npy_format

    path = pathlib.Path(path)
    size = _input_file(path, what)
    try:
        with open(path, "rb") as f:
            if f.read(6) != npy_format.MAGIC_PREFIX:
                magic = False
            else:
                magic = True
                f.seek(0)
                version = npy_format.read_magic(f)
                read = (npy_format.read_array_header_1_0 if version == (1, 0)
                        else npy_format.read_array_header_2_0)
                found, _, dtype = read(f)
                offset = f.tell()
    except OSError as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {err.strerror or err}") from None
    except Exception as err:  # noqa: BLE001 -- numpy parses the header with Python's tokenizer
        raise ValueError(f"{what} {str(path)!r} has a damaged .npy header: "
                         f"{str(err)[:200]}") from None
    if not magic:
        raise ValueError(f"{what} {str(path)!r} is not a .npy file (no NumPy header)")
    found = tuple(found)
    if dtype.hasobject:
        raise ValueError(f"{what} {str(path)!r} holds Python objects, not numbers")
    if shape is not None and found != tuple(shape):
        raise ValueError(f"{what} {str(path)!r} holds an array of shape {found}; "
                         f"{tuple(shape)} is needed")
    if max_side is not None:
        if len(found) != 2 or (square and found[0] != found[1]):
            kind = "square 2-d" if square else "2-d"
            raise ValueError(f"{what} {str(path)!r} must be a {kind} array, got shape "
                             f"{found}")
        if max(found) > max_side:
            raise ValueError(f"{what} {str(path)!r} has {found[0]} x {found[1]} pixels, more "
                             f"than the grid's n = {max_side} (n must be a multiple of the "
                             f"map's size)")
    needed = math.prod(found) * dtype.itemsize
    if size - offset < needed:
        dims = " x ".join(str(d) for d in found) or "scalar"
        raise ValueError(f"{what} {str(path)!r} is truncated: its header announces {dims} "
                         f"values of {dtype} ({format_bytes(needed)}), the file holds "
                         f"{size - offset} bytes of data")
    return found, dtype


def read_npy(path, *, what="file", max_side=None, shape=None, square=True):
    """Read a 2-d array (square by default) from a ``.npy`` file, checking the file first.

    Parameters
    ----------
    path : str or path-like
    what : str, optional
        How messages name the file (e.g. ``"phase map"``).
    max_side : int, optional
        Refuse arrays larger than ``max_side x max_side`` (before loading).
    shape : tuple of int, optional
        Refuse any other shape (before loading).
    square : bool, optional
        Refuse arrays that are not square (default True).

    Returns
    -------
    ndarray, shape (m, m), or (mx, my) if not ``square``

    Raises
    ------
    ValueError
        As :func:`npy_header`, or not square 2-d.  Never ``EOFError`` or
        ``MemoryError``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "empty.npy"
    >>> _ = path.write_bytes(b"")
    >>> try:
    ...     read_npy(path, what="phase map")
    ... except ValueError as err:
    ...     print(str(err).replace(str(path), "empty.npy"))
    phase map 'empty.npy' is empty (0 bytes)
    """
    path = pathlib.Path(path)
    found, dtype = npy_header(path, what=what, shape=shape, square=square,
                              max_side=math.inf if max_side is None else max_side)
    try:
        return np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError) as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None
    except MemoryError:
        raise ValueError(f"{what} {str(path)!r} ({found[0]} x {found[1]} values of {dtype}) "
                         f"does not fit in memory") from None


def load_phase_map(path, *, max_phases=16, max_size=None, outline=None):
    """Read a phase map from a ``.npy`` or ``.png`` file.

    Parameters
    ----------
    path : str or path-like
        ``.npy``: a 2-d integer array, phase index per pixel (any value off
        the face, e.g. -1).  ``.png``: an image; each distinct grey level
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
    suffix = path.suffix.lower()
    if suffix not in (".npy", ".png"):
        _input_file(path, what)
        raise ValueError(f"{what} {str(path)!r} must be a .npy or .png file")
    square = outline is None or outline.aspect == (1.0, 1.0)
    if suffix == ".npy":
        a = read_npy(path, what=what, max_side=max_size, square=square)
    else:
        a = _png_labels(path, max_phases, max_size, outline)
    return ArrayMap(a, source=repr(str(path)), outline=outline)


def read_face_mask(path):
    """The face of a ``.npy`` or ``.png`` file, as pixels: ``True`` on the face.

    Parameters
    ----------
    path : str or path-like
        ``.npy``: a 2-d boolean array (``True`` on the face) or integer
        array (the face is where it is not -1, e.g. a phase map).
        ``.png``: an image with an alpha channel; the face is its
        non-transparent pixels.  Rows run along x, as in phase maps.

    Returns
    -------
    ndarray of bool, shape (mx, my)

    Raises
    ------
    ValueError
        Missing, empty, truncated or unreadable file, an unsupported
        suffix or dtype, a PNG without alpha channel, no face pixel.
    """
    path = pathlib.Path(path)
    what = "face mask"
    suffix = path.suffix.lower()
    if suffix not in (".npy", ".png"):
        _input_file(path, what)
        raise ValueError(f"{what} {str(path)!r} must be a .npy or .png file")
    if suffix == ".npy":
        a = read_npy(path, what=what, square=False)
        if a.dtype == bool:
            mask = a
        elif np.issubdtype(a.dtype, np.integer):
            mask = a != -1
        else:
            raise ValueError(f"{what} {str(path)!r} must hold booleans (True on the face) or "
                             f"integers (-1 off the face), got dtype {a.dtype}")
    else:
        import matplotlib.image  # deferred: only PNG files need it

        _input_file(path, what)
        _png_size(path, what)
        try:
            img = matplotlib.image.imread(path)
        except Exception as err:  # noqa: BLE001 -- any decoder failure of a damaged image
            raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None
        if img.ndim != 3 or img.shape[2] not in (2, 4):
            raise ValueError(f"{what} {str(path)!r} has no alpha channel: the face is the "
                             f"non-transparent pixels of a PNG (or use a .npy array)")
        mask = img[..., -1] > 0
    if mask.ndim != 2 or not mask.any():
        raise ValueError(f"{what} {str(path)!r} has no face pixel")
    return np.ascontiguousarray(mask)


def _png_size(path, what):
    """Width and height from a PNG's header.

    Raises ``ValueError`` naming the file as ``what`` if it cannot be read or
    has no PNG signature.
    """
    try:
        with open(path, "rb") as f:
            head = f.read(24)
    except OSError as err:
        raise ValueError(f"cannot read {what} {str(path)!r}: {err.strerror or err}") from None
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{what} {str(path)!r} is not a PNG image (no PNG signature)")
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def _png_labels(path, max_phases, max_size=None, outline=None):
    import matplotlib.image  # deferred: only PNG maps need it

    what = "phase map"
    _input_file(path, what)
    size = _png_size(path, what)
    square = outline is None or outline.aspect == (1.0, 1.0)
    if square and size[0] != size[1]:
        raise ValueError(f"{what} {str(path)!r} must be square, got {size[0]} x {size[1]} "
                         f"pixels")
    if max_size is not None and max(size) > max_size:
        raise ValueError(f"{what} {str(path)!r} has {size[0]} x {size[1]} pixels, more than "
                         f"the grid's n = {max_size} (n must be a multiple of the map's size)")
    try:
        img = matplotlib.image.imread(path)
    except Exception as err:  # noqa: BLE001 -- any decoder failure of a damaged image
        raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None
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
    outline = _UNIT_DISK if outline is None else outline
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


# Random circular inclusions live in their own module, which builds on the
# helpers above; imported last so that the import is not circular.
from .inclusions import Inclusions  # noqa: E402
