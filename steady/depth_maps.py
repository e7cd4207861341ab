"""Phase maps that change with depth: voxel stacks, spheres in a matrix, layers over a map.

The 3-d kinds of ``[phases] map`` (registered in :data:`steady.phases.PHASE_MAPS`)
and the layers of a scene's ``[depth]`` section.  Each has, like a 2-d kind,
``n_phases``, ``labels(grid)`` -- here the section at depth 0, the initial
surface -- ``min_grid`` and ``check_grid``, and besides
``columns(grid) -> steady.depth.DepthColumns``: below each face pixel, the
depths (m) where the phase changes and the phase of each segment.  The
depth ``w`` is measured from the initial surface downwards; the last segment
of a pixel goes on for ever (what lies below the geometry is columnar).

- :class:`Voxels` (``kind = "voxels"``): a stack of 2-d maps, slice ``k``
  covering the depths ``[k d, (k + 1) d)`` with ``d = voxel_depth``; below
  the last slice the last slice continues.
- :class:`Spheres` (``kind = "spheres"``): random non-overlapping spheres
  (phase 1) in a matrix (phase 0), placed by random sequential addition in a
  box periodic in x, y and z, so that the packing has no walls and every
  plane section is a fair sample of it: the expected area fraction of the
  particles in a section equals their volume fraction (stereology, Delesse's
  principle).  The field extends from above the initial surface (spheres
  are cut by it) down to ``depth``; below it the matrix continues.
- :class:`DepthLayers` (``[depth] kind = "layers"``): layers from the
  surface down, each homogeneous or a 2-d or 3-d map of its own, over the
  scene's ``[phases] map`` (the substrate).

:func:`columns_from_segments` turns raw segments (interfaces that may be
repeated, at or above the surface, or between equal phases) into the
minimal :class:`~steady.depth.DepthColumns`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import pathlib

import numpy as np

from .array_files import INTEGERS, npy_header
from .depth import DepthColumns
from .labels import extend_off_face
from .outline import MIN_SIDE_PIXELS, UNIT_DISK, FaceGrid, as_grid
from .phases import (
    PHASE_MAPS,
    PhaseMap,
    check_refinement,
    check_resolution,
    face_words,
    grid_outline,
    scale_units_note,
)
from .schema import Key

__all__ = ["MAX_SPHERES", "MAX_VOLUME_FRACTION", "DepthLayers", "Spheres", "Voxels",
           "columns_from_segments", "columns_of"]

#: Largest particle volume fraction (random sequential addition of equal spheres jams near 0.38
#: in 3-d; placing becomes slow before; a larger target is refused when placing fails).
MAX_VOLUME_FRACTION = 0.5

#: Most spheres in the placement box (placing is a Python loop).
MAX_SPHERES = 100_000

#: Random positions tried for one sphere before the packing is declared not reachable.
_MAX_TRIES = 20_000

#: Most phases of a voxel stack (the largest index on the face, plus one).
MAX_VOXEL_PHASES = 64


def columns_from_segments(interfaces, phases, n_phases):
    """The minimal :class:`~steady.depth.DepthColumns` of raw segments.

    Parameters
    ----------
    interfaces : ndarray, shape (S, nx, ny), m
        Depths of the segment boundaries below each pixel, non-decreasing
        along the first axis; they may be ``<= 0`` (above the surface),
        repeated (a segment of zero length) or ``+inf`` (padding).
    phases : ndarray of int, shape (S + 1, nx, ny)
        Phase of each segment, ``-1`` off the face; a padded segment
        repeats the pixel's last phase.
    n_phases : int

    Returns
    -------
    DepthColumns
        The phase at depth 0 first; an interface kept only where the phase
        changes, below the surface, at most one per depth.
    """
    z = np.asarray(interfaces, dtype=float)
    phases = np.asarray(phases)
    S = z.shape[0]
    face = phases[0] >= 0
    # Phase above and below each interface: the first and the last of a group of equal depths.
    first = np.zeros(z.shape, dtype=np.int64)
    for j in range(1, S):
        first[j] = np.where(z[j] == z[j - 1], first[j - 1], j)
    last = np.zeros(z.shape, dtype=bool)
    if S:
        last[-1] = True
        last[:-1] = z[1:] != z[:-1]
    above = np.take_along_axis(phases, first, axis=0) if S else phases[:0]
    below = phases[1:]
    keep = last & np.isfinite(z) & (z > 0.0) & (above != below) & face[None]
    surface = np.take_along_axis(phases, np.sum(z <= 0.0, axis=0)[None], axis=0)[0]
    n_keep = keep.sum(axis=0)
    S_new = int(n_keep.max(initial=0))
    order = np.argsort(~keep, axis=0, kind="stable")[:S_new]
    kept = np.take_along_axis(keep, order, axis=0)
    out_z = np.where(kept, np.take_along_axis(z, order, axis=0), np.inf)
    tail = phases[-1][None]
    out_p = np.concatenate([surface[None], np.where(
        kept, np.take_along_axis(below, order, axis=0), tail)])
    out_p = np.where(face[None], out_p, -1)
    return DepthColumns(out_z, out_p, n_phases)


def columns_of(geometry, grid):
    """The columns of any phase geometry on ``grid``: a 3-d kind's own, else columnar."""
    if hasattr(geometry, "columns"):
        return geometry.columns(grid)
    return DepthColumns.from_labels(geometry.labels(grid), geometry.n_phases)


def _stack_columns(stack, tops, n_phases):
    """Columns of a stack of 2-d maps: slice ``k`` from ``tops[k]`` (m) down, ``tops[0] = 0``."""
    stack = np.asarray(stack)
    z = np.broadcast_to(np.asarray(tops[1:], dtype=float)[:, None, None],
                        (len(tops) - 1,) + stack.shape[1:])
    return columns_from_segments(z, stack, n_phases)


_VOXEL_DEPTH = Key("voxel_depth", "number", unit="m", low=0.0, required=True,
                   doc="depth of one slice; below the last slice the last slice continues "
                       "(columnar)")


@PHASE_MAPS.register("voxels", (
    Key("file", "path", required=True,
        doc=".npy of integer phase indices, shape (nx, ny, nz): nz slices from the surface "
            "down, each a map of the face's grid at n or a divisor of it; 0..P-1 on the face"),
    _VOXEL_DEPTH),
    doc="a voxel stack: slice k covers the depths [k d, (k + 1) d), the last one for ever")
@dataclasses.dataclass(frozen=True, eq=False)
class Voxels(PhaseMap):
    """A stack of phase maps from the surface down (a tomography volume).

    Parameters
    ----------
    voxels : ndarray of int, shape (mx, my, nz)
        Phase index of each voxel: ``mx x my`` the grid of ``outline`` with
        ``n0 = max(mx, my)`` pixels along its longer side (as
        :class:`~steady.phases.ArrayMap`), ``nz`` slices from the surface
        down.  On the face ``0..P-1`` with every phase somewhere in the
        stack; off the face any value.
    voxel_depth : float, m
        Depth of one slice, at most the scale ``L`` of ``outline`` (a
        slice deeper than half the face is wide is not a voxel of it).
    source : str, optional
        Where the stack came from (for messages).
    outline : outline object, optional
        The face (default: the unit disk, radius 1 m).

    Notes
    -----
    Slice ``k`` covers the depths ``[k d, (k + 1) d)``; below the last one,
    at ``nz d``, the last slice continues for ever: the material is columnar
    there.  ``labels(grid)`` is slice 0; grids of ``n = k n0`` replicate the
    voxels ``k x k`` (as :class:`~steady.phases.ArrayMap`).
    """

    voxels: np.ndarray
    voxel_depth: float
    source: str = "array"
    outline: object = None

    def __post_init__(self):
        """Check the voxels; store them read-only, off the face filled by the nearest face pixel."""
        a = np.asarray(self.voxels)
        outline = UNIT_DISK if self.outline is None else self.outline
        what = f"voxel map {self.source}"
        if a.ndim != 3:
            raise ValueError(f"{what} must be a 3-d array (nx, ny, nz), got shape {a.shape}")
        if not np.issubdtype(a.dtype, np.integer):
            raise ValueError(f"{what} must hold integers, got dtype {a.dtype}")
        if min(a.shape) == 0:
            raise ValueError(f"{what} is empty: an array of shape {a.shape}")
        d = _VOXEL_DEPTH.parse(self.voxel_depth, "", scale=False)  # its range: against L below
        L = outline.scale
        if d > L:
            raise ValueError(f"{what}: voxel_depth {d:.6g} m is deeper than the face scale L = "
                             f"{L:.6g} m of the {outline.describe()}, at most L is accepted"
                             f"{scale_units_note(L, voxel_depth=d)}")
        n0 = max(a.shape[:2])
        check_resolution(n0, MIN_SIDE_PIXELS, what)
        grid = FaceGrid(outline, n0)
        if a.shape[:2] != grid.shape:
            raise ValueError(f"{what} has {a.shape[0]} x {a.shape[1]} pixels per slice; the grid "
                             f"of the {outline.describe()} with {n0} pixels along its longer "
                             f"side has {grid.shape[0]} x {grid.shape[1]}")
        face = grid.mask
        on_face = a[face]
        low, high = int(on_face.min()), int(on_face.max())
        if low < 0:
            i, j, k = (int(v[0]) for v in np.nonzero(face[:, :, None] & (a < 0)))
            raise ValueError(f"{what}: phase {int(a[i, j, k])} at voxel ({i}, {j}, {k}) on the "
                             f"face is out of range: face voxels need phases 0..P-1")
        if high >= MAX_VOXEL_PHASES:
            i, j, k = (int(v[0]) for v in np.nonzero(face[:, :, None] & (a == high)))
            raise ValueError(f"{what}: phase {high} at voxel ({i}, {j}, {k}) is out of range "
                             f"0..{MAX_VOXEL_PHASES - 1}")
        n_phases = high + 1
        absent = np.flatnonzero(np.bincount(on_face.ravel(), minlength=n_phases) == 0)
        if absent.size:
            raise ValueError(f"{what}: phase {int(absent[0])} occurs in no face voxel (phases "
                             f"0..{high} are used)")
        filled = np.stack([extend_off_face(a[:, :, k].astype(np.int64), face)
                           for k in range(a.shape[2])])
        filled.flags.writeable = False
        object.__setattr__(self, "voxels", filled)  # (nz, mx, my)
        object.__setattr__(self, "voxel_depth", d)
        object.__setattr__(self, "_n_phases", n_phases)

    @classmethod
    def from_values(cls, values, context):
        """From the checked keys: the file read through :func:`steady.array_files.npy_header`."""
        return cls(load_voxels(values["file"], max_side=context.n), values["voxel_depth"],
                   repr(str(values["file"])), context.outline)

    @property
    def n_phases(self):
        """Number of phases: one more than the largest index on the face."""
        return self._n_phases

    @property
    def size(self):
        """Pixels ``n0`` along the longer side of a slice."""
        return max(self.voxels.shape[1:])

    @property
    def n_slices(self):
        """``nz``."""
        return self.voxels.shape[0]

    def min_grid(self, outline=None):
        """The stack's own size ``n0``."""
        return self.size

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` unless a multiple of the stack's size ``n0``."""
        mx, my = self.voxels.shape[1:]
        return check_refinement(grid, (mx, my), f"voxel map {self.source} of {mx} x {my} pixels")

    def _slices(self, grid):
        """The slices on ``grid``, shape (nz, nx, ny), -1 off the face."""
        n = self.check_grid(grid)
        grid = as_grid(grid)
        k = n // self.size
        fine = self.voxels if k == 1 else self.voxels.repeat(k, axis=1).repeat(k, axis=2)
        return np.where(grid.mask[None], fine, -1)

    def labels(self, grid):
        """Slice 0, the surface section, on a grid of ``n = k n0``; -1 off the face."""
        n = self.check_grid(grid)
        grid = as_grid(grid)
        k = n // self.size
        top = self.voxels[0] if k == 1 else np.kron(self.voxels[0], np.ones((k, k), np.int64))
        return np.where(grid.mask, top, -1)

    def columns(self, grid):
        """The columns on ``grid``: an interface where a pixel's phase changes between slices, m."""
        tops = self.voxel_depth * np.arange(self.n_slices)
        return _stack_columns(self._slices(grid), tops, self.n_phases)


def load_voxels(path, *, max_side=None):
    """A voxel stack (nx, ny, nz) of integers from a ``.npy`` file, its header checked first.

    ``max_side``: refuse slices larger than the grid's ``n`` before reading the data.
    """
    path = pathlib.Path(path)
    what = "voxel map"
    if path.suffix.lower() != ".npy":
        raise ValueError(f"{what} {str(path)!r} must be a .npy file, got suffix "
                         f"{path.suffix!r}")
    shape, _ = npy_header(path, what=what, holds=INTEGERS)
    if len(shape) != 3:
        raise ValueError(f"{what} {str(path)!r} must be a 3-d array (nx, ny, nz), got shape "
                         f"{shape}")
    if max_side is not None and max(shape[:2]) > max_side:
        raise ValueError(f"{what} {str(path)!r} has {shape[0]} x {shape[1]} pixels per slice, "
                         f"more than the grid's n = {max_side} (n must be a multiple of it)")
    return np.load(path, allow_pickle=False)


# The keys of a scene's map, and the checks of the same parameters given in Python.
_SPHERE_KEYS = (
    Key("radius", "number", unit="m", low=0.0, required=True, doc="mean sphere radius"),
    Key("volume_fraction", "number", unit="1", low=0.0, high=MAX_VOLUME_FRACTION,
        high_open=False, required=True, doc="volume fraction of the spheres"),
    Key("seed", "integer", low=0, low_open=False, required=True,
        doc="seed of the random generator"),
    Key("depth", "number", unit="m", low=0.0, required=True,
        doc="the particle field extends from above the surface down to this depth; below it "
            "the matrix continues"),
    Key("spread", "number", unit="1", low=0.0, low_open=False, high=1.0,
        doc="relative half-width of the radii, uniform in [r (1 - s), r (1 + s)] (default 0)"),
    Key("matrix_phase", "integer", low=0, low_open=False, default=0,
        doc="phase of the matrix (default 0)"),
    Key("particle_phase", "integer", low=0, low_open=False, default=1,
        doc="phase of the spheres (default 1)"))


@PHASE_MAPS.register("spheres", _SPHERE_KEYS,
                     doc="random non-overlapping spheres (phase 1) in a matrix (phase 0), down "
                         "to a depth")
@dataclasses.dataclass(frozen=True)
class Spheres(PhaseMap):
    """Random non-overlapping spheres in a matrix, from above the surface down to ``depth``.

    Parameters
    ----------
    radius : float, m
        Mean sphere radius; the largest (``radius (1 + spread)``) at most
        half the face scale ``L`` (checked when the spheres meet a face,
        :meth:`check_outline`).
    volume_fraction : float
        Volume fraction of the spheres in the field, in ``(0, 0.5]``.
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    depth : float, m
        Depth of the particle field's bottom: below it the matrix
        continues; a sphere reaching below it is cut there.
    spread : float, optional
        Radii uniform in ``[radius (1 - spread), radius (1 + spread)]``,
        ``0 <= spread < 1`` (default 0: one size).
    matrix_phase, particle_phase : int, optional
        Default 0 and 1; distinct.

    Notes
    -----
    Placement by random sequential addition, largest sphere first, each at
    a uniformly random centre that overlaps no sphere placed before
    (touching allowed), in the box ``[-B, B)^2 x [-r_max, depth + r_max)``
    with ``B = L + r_max``, periodic along all three axes: no walls, so
    the packing is homogeneous and the field starts above the surface; the
    box's spheres and their periodic images are cut to the depths
    ``[0, depth]``.  The placement is drawn in units of ``L``, so that the
    same parameters on a face twice as large give the same packing scaled.
    Random sequential addition of equal spheres jams near a volume fraction
    of 0.38; a target it cannot reach is refused.  A pixel is in a sphere
    at depth ``w`` when ``rho^2 + (w - z_c)^2 < r^2``: its column meets the
    sphere over ``z_c -+ sqrt(r^2 - rho^2)``.

    Examples
    --------
    Spheres of 0.4 mm down to 2 mm below a disk of 4 mm:

    >>> from steady.outline import Circle
    >>> spheres = Spheres(0.4e-3, 0.3, 2031, 2e-3)
    >>> spheres.min_grid(Circle(4e-3))
    40
    >>> spheres.labels(Circle(4e-3).grid(40)).shape
    (40, 40)
    """

    radius: float
    volume_fraction: float
    seed: int
    depth: float
    spread: float = 0.0
    matrix_phase: int = 0
    particle_phase: int = 1

    def __post_init__(self):
        """Check the parameters."""
        # The scale range of the lengths is a problem's to check.
        for key in _SPHERE_KEYS:
            object.__setattr__(self, key.name, key.parse(getattr(self, key.name), "sphere",
                                                         scale=False))
        if self.matrix_phase == self.particle_phase:
            raise ValueError(f"matrix_phase = {self.matrix_phase} and particle_phase = "
                             f"{self.particle_phase} must be distinct")
        if max(self.matrix_phase, self.particle_phase) > 1:
            raise ValueError(f"matrix_phase = {self.matrix_phase} and particle_phase = "
                             f"{self.particle_phase}: the two phases must be 0 and 1")

    @classmethod
    def from_values(cls, values, context):
        """From the checked keys (m), checked against the scene's face."""
        spheres = cls(values["radius"], values["volume_fraction"], values["seed"],
                      values["depth"], values.get("spread", 0.0), values["matrix_phase"],
                      values["particle_phase"])
        spheres.check_outline(context.outline)
        return spheres

    @property
    def n_phases(self):
        """2."""
        return 2

    @property
    def max_radius(self):
        """Largest radius, m."""
        return self.radius * (1.0 + self.spread)

    def _scaled(self, outline):
        """The :class:`_SpherePacking` of the face of ``outline``: lengths over its scale."""
        L = outline.scale
        return self._packing(self.radius / L, self.depth / L, L)

    @functools.lru_cache(maxsize=4)  # noqa: B019 -- frozen, hashable; a few faces at most
    def _packing(self, radius, depth, scale):
        return _SpherePacking(radius, self.volume_fraction, self.seed, depth, self.spread, scale)

    def check_outline(self, outline):
        """``ValueError`` unless the spheres fit the face of ``outline``.

        The largest radius at most ``L / 2``; at most :data:`MAX_SPHERES`
        spheres in the placement box.
        """
        packing = self._scaled(outline)
        L = outline.scale
        if packing.max_radius > 0.5:
            note = scale_units_note(L, radius=self.radius) if self.max_radius <= 0.5 else ""
            raise ValueError(f"sphere radius {self.max_radius:.6g} m is larger than 0.5 L = "
                             f"{0.5 * L:.6g} m, half the scale of the face "
                             f"({outline.describe()}){note}")
        count = packing.expected_count()
        if count > MAX_SPHERES:
            raise ValueError(f"about {count:.0f} spheres of radius {self.radius:.6g} m to a "
                             f"depth of {self.depth:.6g} m under the face ({outline.describe()}), "
                             f"more than {MAX_SPHERES}")

    def spheres(self, outline=None):
        """Centres (N, 3) and radii (N,), m, placed for the face of ``outline``.

        In the periodic box ``[-B, B)^2 x [-r_max, depth + r_max)``; the
        default face is the unit disk (1 m).

        Raises
        ------
        ValueError
            The spheres do not fit the face (:meth:`check_outline`), or the
            volume fraction cannot be reached by random sequential addition.
        """
        outline = UNIT_DISK if outline is None else outline
        self.check_outline(outline)
        centres, radii = self._scaled(outline).spheres
        centres, radii = centres * outline.scale, radii * outline.scale
        centres.flags.writeable = False
        radii.flags.writeable = False
        return centres, radii

    def realised_volume_fraction(self, outline=None):
        """Volume of the placed spheres over the placement box's volume (default face 1 m)."""
        outline = UNIT_DISK if outline is None else outline
        self.check_outline(outline)
        return self._scaled(outline).realised_volume_fraction()

    def min_grid(self, outline=None):
        """``ceil(4 L / radius)``: the mean radius at least two pixels ``2 L / n``.

        ``L`` is the scale of ``outline`` (default: the unit disk, 1 m).
        """
        radius = self._scaled(UNIT_DISK if outline is None else outline).radius
        return max(MIN_SIDE_PIXELS, math.ceil(4.0 / radius - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` naming the radius, pixel (m) and ``n`` if too coarse."""
        outline = grid_outline(grid)
        low = self.min_grid(outline)
        n = check_resolution(grid, MIN_SIDE_PIXELS, f"spheres of radius {self.radius:.6g} m")
        if n < low:
            raise ValueError(f"grid too coarse for spheres of radius {self.radius:.6g} m on "
                             f"{face_words(grid)}: the radius is under two pixels at n = {n} "
                             f"(pixel {2.0 * outline.scale / n:.6g} m), the minimum is n = {low}")
        return n

    def labels(self, grid):
        """The surface section (depth 0): the particle phase inside a sphere, else the matrix."""
        return self.columns(grid).phase_at(0.0)

    def columns(self, grid):
        """The columns on ``grid``, m: where each pixel's column enters and leaves a sphere."""
        self.check_outline(grid_outline(grid))  # first: it names lengths meant in units of L
        self.check_grid(grid)
        grid = as_grid(grid)
        return self._scaled(grid.outline).columns(grid, self.matrix_phase, self.particle_phase)


@dataclasses.dataclass(frozen=True)
class _SpherePacking:
    """Spheres placed in units of the face scale ``L``: the numbers of the rasteriser.

    ``radius`` and ``depth`` over ``L``; ``scale`` (``L``, m) turns the
    columns into m and words the messages.
    """

    radius: float
    volume_fraction: float
    seed: int
    depth: float
    spread: float
    scale: float

    @property
    def max_radius(self):
        """Largest radius, units of ``L``."""
        return self.radius * (1.0 + self.spread)

    def _box(self):
        """Half side ``B`` and the depth range ``(z0, z1)`` of the periodic placement box."""
        r = self.max_radius
        return 1.0 + r, (-r, self.depth + r)

    def expected_count(self):
        """Spheres expected in the placement box."""
        B, (z0, z1) = self._box()
        s = self.spread
        mean_cube = self.radius ** 3 * (1.0 + s * s)  # <r^3> of the uniform radii
        return self.volume_fraction * 4.0 * B * B * (z1 - z0) / (4.0 / 3.0 * math.pi * mean_cube)

    @functools.cached_property
    def spheres(self):
        """Centres (N, 3) and radii (N,) in units of ``L`` placed in the periodic box.

        Raises
        ------
        ValueError
            The volume fraction places no sphere, or cannot be reached by
            random sequential addition.
        """
        rng = np.random.default_rng(self.seed)
        B, (z0, z1) = self._box()
        period = np.array([2 * B, 2 * B, z1 - z0])
        low = np.array([-B, -B, z0])
        target = self.volume_fraction * float(np.prod(period))
        radii = []
        volume = 0.0
        while volume < target:
            r = self.radius * (1.0 + self.spread * rng.uniform(-1.0, 1.0))
            radii.append(r)
            volume += 4.0 / 3.0 * math.pi * r ** 3
        # The last sphere overshoots by less than its volume: drop it if that is closer.
        if volume - target > 2.0 / 3.0 * math.pi * radii[-1] ** 3:
            radii.pop()
        if not radii:
            raise self._empty(volume, period)
        radii = np.sort(np.array(radii))[::-1]
        centres = _place(radii, low, period, rng, self._stalled)
        centres.flags.writeable = False
        radii.flags.writeable = False
        return centres, radii

    def _empty(self, sphere, period):
        """The error of a volume fraction below half a sphere in the placement box."""
        least = 0.5 * sphere / float(np.prod(period))
        return ValueError(f"sphere volume_fraction = {self.volume_fraction:g} places no sphere "
                          f"of radius {self.radius * self.scale:.6g} m: the particle phase "
                          f"would have no voxel (the box around the face holds half a sphere "
                          f"from volume_fraction = {least:.3g})")

    def _stalled(self, radii, placed, period):
        """The error of a packing that random sequential addition cannot reach."""
        reached = float(np.sum(4.0 / 3.0 * math.pi * radii[:placed] ** 3) / np.prod(period))
        return ValueError(f"sphere volume_fraction = {self.volume_fraction:g} is not reachable "
                          f"by random sequential addition: placing stalled at {reached:.3f} "
                          f"(radius {self.radius * self.scale:.6g} m, spread {self.spread:g})")

    def realised_volume_fraction(self):
        """Volume of the placed spheres over the placement box's volume."""
        _, radii = self.spheres
        B, (z0, z1) = self._box()
        return float(np.sum(4.0 / 3.0 * math.pi * radii ** 3) / (4.0 * B * B * (z1 - z0)))

    def _intervals(self, grid):
        """Every (pixel, top, bottom) where a column meets a sphere, units of ``L``."""
        centres, radii = self.spheres
        B, (z0, z1) = self._box()
        period = np.array([2 * B, 2 * B, z1 - z0])
        x, y = grid.unit_x, grid.unit_y
        pix, tops, bottoms = [], [], []
        shifts = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)])
        images = (centres[:, None, :] + shifts * period).reshape(-1, 3)
        r_images = np.repeat(radii, len(shifts))
        z = images[:, 2]
        seen = ((z + r_images > 0.0) & (z - r_images < self.depth)
                & np.all(np.abs(images[:, :2]) <= 1 + r_images[:, None], axis=1))
        for (px, py, pz), r in zip(images[seen], r_images[seen], strict=True):
            i = np.flatnonzero(np.abs(x - px) < r)
            j = np.flatnonzero(np.abs(y - py) < r)
            if not (i.size and j.size):
                continue
            rho2 = (x[i, None] - px) ** 2 + (y[None, j] - py) ** 2
            ii, jj = np.nonzero(rho2 < r * r)
            half = np.sqrt(r * r - rho2[ii, jj])
            pix.append(i[ii] * grid.shape[1] + j[jj])
            tops.append(np.maximum(pz - half, 0.0))
            bottoms.append(np.minimum(pz + half, self.depth))
        if not pix:
            return np.zeros(0, int), np.zeros(0), np.zeros(0)
        return np.concatenate(pix), np.concatenate(tops), np.concatenate(bottoms)

    def columns(self, grid, matrix_phase, particle_phase):
        """The columns on ``grid`` (of the face of scale ``scale``), m."""
        pix, tops, bottoms = self._intervals(grid)
        mask = grid.mask.ravel()
        keep = mask[pix] & (bottoms > tops)
        pix, tops, bottoms = pix[keep], tops[keep], bottoms[keep]
        order = np.lexsort((tops, pix))
        pix, tops, bottoms = pix[order], tops[order], bottoms[order]
        npix = mask.size
        starts = np.searchsorted(pix, np.arange(npix))
        rank = np.arange(pix.size) - starts[pix]
        S = 2 * (int(rank.max()) + 1 if rank.size else 0)
        z = np.full((S, npix), np.inf)
        phases = np.full((S + 1, npix), matrix_phase, dtype=np.int64)
        z[2 * rank, pix] = tops
        z[2 * rank + 1, pix] = bottoms
        phases[2 * rank + 1, pix] = particle_phase
        phases[:, ~mask] = -1
        L = grid.outline.scale
        shape = (S,) + grid.shape
        return columns_from_segments(z.reshape(shape) * L, phases.reshape((S + 1,) + grid.shape),
                                     2)


def _place(radii, low, period, rng, stalled, batch=16):
    """Random sequential addition of spheres of ``radii`` in a periodic box; centres (N, 3).

    Candidates are drawn ``batch`` at a time and the first that overlaps no
    sphere placed before is taken (the same law as one at a time); the
    overlaps are looked up in cells of side ``>= 2 r_max``.  ``stalled(radii,
    placed, period)`` is the error raised after :data:`_MAX_TRIES` misses.
    """
    shape = np.maximum((period // (2.0 * radii.max())).astype(int), 1)
    slots = 4
    cells = np.full(tuple(shape) + (slots,), -1, dtype=np.int64)
    filled = np.zeros(tuple(shape), dtype=np.int64)
    offsets = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)])
    centres = np.zeros((len(radii) + 1, 3))  # the last row: that of the empty slots (-1)
    padded = np.append(radii, 0.0)
    for i, r in enumerate(radii):
        for _ in range(-(-_MAX_TRIES // batch)):
            c = low + rng.uniform(0.0, 1.0, (batch, 3)) * period
            key = np.minimum(((c - low) / period * shape).astype(int), shape - 1)
            near = (key[:, None, :] + offsets) % shape
            idx = cells[near[..., 0], near[..., 1], near[..., 2]].reshape(batch, -1)
            d = centres[idx] - c[:, None, :]
            d -= period * np.round(d / period)
            hit = (np.einsum("kmj,kmj->km", d, d) < (padded[idx] + r) ** 2) & (idx >= 0)
            free = np.flatnonzero(~hit.any(axis=1))
            if free.size:
                break
        else:
            raise stalled(radii, i, period)
        k = tuple(key[free[0]])
        if filled[k] == cells.shape[-1]:
            cells = np.concatenate([cells, np.full(cells.shape, -1, dtype=np.int64)], axis=-1)
        centres[i] = c[free[0]]
        cells[k + (filled[k],)] = i
        filled[k] += 1
    return centres[:-1].copy()


#: A layer's thickness, as ``[[depth.layers]] thickness`` holds it.
_THICKNESS = Key("thickness", "number", unit="m", low=0.0, required=True,
                 doc="thickness of the layer")


@dataclasses.dataclass(frozen=True, eq=False)
class DepthLayers:
    """Layers from the surface down over a substrate (``[depth] kind = "layers"``).

    Parameters
    ----------
    thicknesses : sequence of float, m
        Thickness of each layer, from the surface down, each positive.
    maps : sequence of phase geometry
        The map of each layer: :class:`steady.phases.Homogeneous`-like
        (one phase, see :class:`LayerPhase`) or any ``[phases] map`` kind,
        2-d or 3-d (a 3-d map's own depth starts at the layer's top and is
        cut at its bottom).
    substrate : phase geometry
        The scene's ``[phases] map``, below the last layer.
    """

    thicknesses: tuple
    maps: tuple
    substrate: object

    def __post_init__(self):
        """Check the thicknesses."""
        thicknesses = tuple(_THICKNESS.parse(t, f"[depth] layers[{i}]", scale=False)
                            for i, t in enumerate(self.thicknesses))
        object.__setattr__(self, "thicknesses", thicknesses)
        if len(self.thicknesses) != len(self.maps) or not self.maps:
            raise ValueError("[depth] needs at least one layer, each with a thickness and a map")

    @property
    def n_phases(self):
        """One more than the largest phase of a layer or the substrate."""
        return max(g.n_phases for g in (*self.maps, self.substrate))

    def min_grid(self, outline=None):
        """The largest ``min_grid`` of the layers' maps and the substrate."""
        return max(g.min_grid(outline) for g in (*self.maps, self.substrate))

    def check_grid(self, grid):
        """``n`` as an int; every map's ``check_grid``."""
        for g in (*self.maps, self.substrate):
            n = g.check_grid(grid)
        return n

    def labels(self, grid):
        """The surface section: the top layer's."""
        return self.maps[0].labels(grid)

    def columns(self, grid):
        """The columns of the layers over the substrate's columns, m."""
        grid = as_grid(grid)
        tops = np.concatenate([[0.0], np.cumsum(self.thicknesses)])
        z, p = [], []
        for k, g in enumerate((*self.maps, self.substrate)):
            c = columns_of(g, grid) if hasattr(g, "columns") else _Section(g.labels(grid))
            z0 = tops[k]
            inner = c.interfaces + z0
            if k < len(self.maps):
                inner = np.minimum(inner, tops[k + 1])  # a 3-d layer is cut at its bottom
                z.append(inner)
                z.append(np.full((1,) + grid.shape, tops[k + 1]))
            else:
                z.append(inner)
            p.append(c.phases)
        return columns_from_segments(np.concatenate(z), np.concatenate(p), self.n_phases)


class _Section:
    """The raw segments of a 2-d map: one, with no interface (its phases not all checked)."""

    def __init__(self, labels):
        self.phases = np.asarray(labels)[None]
        self.interfaces = np.zeros((0,) + self.phases.shape[1:])


@dataclasses.dataclass(frozen=True)
class LayerPhase:
    """A homogeneous layer of one phase (``phase = i`` in ``[[depth.layers]]``)."""

    phase: int

    @property
    def n_phases(self):
        """``phase + 1``."""
        return self.phase + 1

    def min_grid(self, outline=None):
        """:data:`~steady.outline.MIN_SIDE_PIXELS`."""
        return MIN_SIDE_PIXELS

    def check_grid(self, grid):
        """``n`` as an int."""
        return check_resolution(grid, MIN_SIDE_PIXELS, "a homogeneous layer")

    def labels(self, grid):
        """``phase`` on the face, -1 off it."""
        self.check_grid(grid)
        return np.where(as_grid(grid).mask, self.phase, -1)
