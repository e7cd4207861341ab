"""Outlines of the punch face, and the pixel grid that covers each.

The punch face is a plane region centred on the origin: a disk (the paper's
cylinder), a rectangle (a tread block), an ellipse, an annulus (a seal) or
any region given as a pixel mask.  Every outline has

- ``kind`` : its name in scene files (``[punch] shape``);
- ``half_extent`` : ``(Lx, Ly)``, m, the half sides of its bounding box,
  x along axis 0;
- ``scale`` : ``L = max(Lx, Ly)``, m, the length unit of phase geometries
  (the radius ``a`` of a disk);
- ``area`` : the exact area of the region, m^2 (``pbar = F_N / area``);
- ``contains(x, y)`` : whether points (m) lie strictly inside;
- ``grid(n)`` : the :class:`FaceGrid` of ``n`` pixels along the longer
  side of the bounding box;
- ``min_grid()``, ``check_grid(n)`` : the coarsest grid that resolves it;
- ``encloses_disk(centre, radius)`` : whether a disk (m) lies in the face;
- ``parameters()`` : its defining lengths, ``name -> (value, unit)``.

Grid
----
Pixels are square, of side ``h = 2 L / n``; the bounding box is covered by
``nx x ny`` pixels centred on the origin, ``n`` along the longer side and
``round(n Ls / L)`` along the shorter one (``Ls`` its half side), so that a
rectangle whose sides are whole numbers of pixels is covered exactly.  A
pixel belongs to the face when its centre lies strictly inside the
outline; areas are pixel counts times ``h^2``.  For a disk this is the
``n x n`` grid over ``[-a, a]^2`` of :mod:`steady.grid`, pixel for pixel.

Outlines are registered by name (:func:`register_outline`,
:data:`OUTLINES`); :func:`outline_from_table` builds one from the
``[punch]`` table of a scene file.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .grid import face_mask as disk_face_mask
from .text import shorten

__all__ = [
    "OUTLINES",
    "Annulus",
    "Circle",
    "Ellipse",
    "FaceGrid",
    "MIN_SIDE_PIXELS",
    "MaskOutline",
    "Rectangle",
    "as_outline",
    "outline_from_table",
    "register_outline",
]

#: Pixels across the shorter side of the bounding box (and across the ring of
#: an annulus, in units of three) below which a grid is refused.
MIN_SIDE_PIXELS = 8

#: Registered outlines, by ``kind``.
OUTLINES = {}


def register_outline(cls):
    """Class decorator: register an outline under its ``kind``.

    The class needs ``kind`` and ``keys`` (``(required, optional)`` sets of
    the ``[punch]`` keys besides ``shape``) and a classmethod
    ``from_table(table, base_dir)``.
    """
    if cls.kind in OUTLINES:
        raise ValueError(f"outline kind {cls.kind!r} is already registered")
    OUTLINES[cls.kind] = cls
    return cls


def _length(value, name):
    """A positive finite length in m (``int`` accepted, ``bool`` and strings not)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise ValueError(f"{name} must be a number (m), got {shorten(value)}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number (m), got {shorten(value)}")
    return v


def _grid_size(n):
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"grid size n must be an integer, got {n!r}")
    return int(n)


@dataclasses.dataclass(frozen=True, eq=False)
class FaceGrid:
    """The pixel grid over one outline's bounding box.

    Parameters
    ----------
    outline : outline object
        The face's outline.
    n : int
        Pixels along the longer side of the bounding box.

    Attributes
    ----------
    shape : (int, int)
        ``(nx, ny)``, pixels along x (axis 0) and y (axis 1).
    h : float, m
        Pixel side ``2 L / n``.
    x, y : ndarray, shapes (nx,) and (ny,), m
        Pixel-centre coordinates.
    unit_x, unit_y : ndarray, m / L
        The same in units of the outline's scale ``L`` (the coordinates of
        phase geometries).
    mask : ndarray of bool, shape (nx, ny)
        Pixels whose centre lies strictly inside the outline (read-only).
    """

    outline: object
    n: int

    def __post_init__(self):
        """Check ``n`` against the outline."""
        object.__setattr__(self, "n", self.outline.check_grid(self.n))

    @functools.cached_property
    def shape(self):
        """``(nx, ny)``."""
        return self.outline.grid_shape(self.n)

    @property
    def h(self):
        """Pixel side, m."""
        return 2.0 * self.outline.scale / self.n

    @property
    def pixel_area(self):
        """``h^2``, m^2."""
        return self.h * self.h

    def _unit_axis(self, m):
        # -m/n + (i + 1/2) 2/n: for m = n the unit disk's pixel centres of
        # steady.grid.pixel_centres(n, 1.0), bit for bit.
        return -(m / self.n) + (np.arange(m) + 0.5) * (2.0 / self.n)

    def _axis(self, m):
        L, h = self.outline.scale, self.h
        return -(m / self.n) * L + (np.arange(m) + 0.5) * h

    @functools.cached_property
    def x(self):
        """Pixel centres along x, m."""
        return self._axis(self.shape[0])

    @functools.cached_property
    def y(self):
        """Pixel centres along y, m."""
        return self._axis(self.shape[1])

    @functools.cached_property
    def unit_x(self):
        """Pixel centres along x in units of the scale ``L``."""
        return self._unit_axis(self.shape[0])

    @functools.cached_property
    def unit_y(self):
        """Pixel centres along y in units of the scale ``L``."""
        return self._unit_axis(self.shape[1])

    @property
    def unit_half_extent(self):
        """Half sides of the grid's box in units of ``L``: ``(nx / n, ny / n)``."""
        nx, ny = self.shape
        return nx / self.n, ny / self.n

    @functools.cached_property
    def mask(self):
        """Face pixels, shape (nx, ny), read-only."""
        mask = np.ascontiguousarray(self.outline.grid_mask(self), dtype=bool)
        if mask.shape != self.shape:
            raise RuntimeError(f"outline mask of shape {mask.shape} on a grid {self.shape}")
        if not mask.any():
            raise ValueError(f"the {self.outline.describe()} has no pixel centre inside it at "
                             f"n = {self.n}: refine the grid")
        mask.flags.writeable = False
        return mask

    @property
    def face_area(self):
        """Face pixels times ``h^2``, m^2."""
        return float(self.mask.sum()) * self.pixel_area

    def coarsened(self, m):
        """The grid of the same outline with ``m`` pixels along the longer side."""
        return FaceGrid(self.outline, m)


class _Outline:
    """What every outline shares (its subclasses are frozen dataclasses)."""

    kind = ""
    keys = (set(), set())

    @property
    def scale(self):
        """``L``, the larger half side of the bounding box, m."""
        return max(self.half_extent)

    @property
    def aspect(self):
        """``(Lx / L, Ly / L)``: the bounding box in units of the scale."""
        lx, ly = self.half_extent
        L = self.scale
        return lx / L, ly / L

    def grid_shape(self, n):
        """``(nx, ny)`` of the grid with ``n`` pixels along the longer side."""
        n = _grid_size(n)
        ax, ay = self.aspect
        return (n if ax == 1.0 else max(1, math.floor(n * ax + 0.5)),
                n if ay == 1.0 else max(1, math.floor(n * ay + 0.5)))

    def grid(self, n):
        """The :class:`FaceGrid` of ``n`` pixels along the longer side."""
        return FaceGrid(self, n)

    def grid_mask(self, grid):
        """Face pixels of ``grid``: centres strictly inside the outline."""
        return self.contains(grid.x[:, None], grid.y[None, :])

    def min_grid(self):
        """Smallest ``n``: :data:`MIN_SIDE_PIXELS` across the shorter side of the box."""
        return max(MIN_SIDE_PIXELS, math.ceil(MIN_SIDE_PIXELS / min(self.aspect) - 1e-9))

    def check_grid(self, n):
        """``n`` as an int; ``ValueError`` naming ``n`` and the minimum if too coarse."""
        n = _grid_size(n)
        low = self.min_grid()
        if n < low:
            raise ValueError(f"grid too coarse for the {self.describe()}: n = {n}, the minimum "
                             f"is n = {low}")
        return n

    def encloses_disk(self, centre, radius):
        """Whether the disk of ``centre`` (x, y) and ``radius`` (m) lies in the face.

        Touching the outline is allowed (to round-off).  The default tests
        points on the disk's circle and its centre; outlines with a closed
        form override it.
        """
        cx, cy = centre
        t = np.linspace(0.0, 2.0 * np.pi, 721)[:-1]
        shrink = 1.0 - 1e-9
        x = np.append(cx + shrink * radius * np.cos(t), cx)
        y = np.append(cy + shrink * radius * np.sin(t), cy)
        return bool(np.all(self.contains(x, y)))

    def describe(self):
        """The outline in words with its lengths in mm."""
        parts = ", ".join(f"{name} {value * 1e3:.6g} mm"
                          for name, (value, _) in self.parameters().items()
                          if _ == "m")
        return f"{self.kind} face ({parts})"


@register_outline
@dataclasses.dataclass(frozen=True)
class Circle(_Outline):
    """A disk of radius ``a``: the paper's cylindrical punch.

    Parameters
    ----------
    radius : float, m

    Examples
    --------
    >>> grid = Circle(4e-3).grid(64)
    >>> grid.shape, round(grid.h * 1e3, 6)
    ((64, 64), 0.125)
    """

    radius: float
    kind = "circle"
    keys = ({"radius"}, set())

    def __post_init__(self):
        """Check the radius."""
        object.__setattr__(self, "radius", _length(self.radius, "radius"))

    @classmethod
    def from_table(cls, table, base_dir=None):
        """From ``[punch]`` keys (``radius``)."""
        return cls(_length(table["radius"], "[punch] radius"))

    @property
    def half_extent(self):
        """``(a, a)``, m."""
        return self.radius, self.radius

    @property
    def area(self):
        """``pi a^2``, m^2."""
        return math.pi * self.radius**2

    def contains(self, x, y):
        """Points strictly inside the disk."""
        return np.asarray(x) ** 2 + np.asarray(y) ** 2 < self.radius**2

    def grid_mask(self, grid):
        """:func:`steady.grid.face_mask`: exact in integers."""
        return disk_face_mask(grid.n)

    def encloses_disk(self, centre, radius):
        """``|c| + r <= a`` (to round-off)."""
        return math.hypot(*centre) + radius <= self.radius * (1.0 + 1e-12)

    def parameters(self):
        """``{"radius": (a, "m")}``."""
        return {"radius": (self.radius, "m")}


@register_outline
@dataclasses.dataclass(frozen=True)
class Rectangle(_Outline):
    """A rectangle ``width x length``, its width along x: a tread block.

    Parameters
    ----------
    width : float, m
        Side along x (axis 0).
    length : float, m
        Side along y (axis 1).

    Notes
    -----
    With ``n`` pixels along the longer side, the shorter one has
    ``round(n * short / long)``; when that is exact the pixels tile the
    rectangle and every grid pixel is a face pixel.

    Examples
    --------
    >>> grid = Rectangle(4e-3, 12e-3).grid(96)
    >>> grid.shape, bool(grid.mask.all())
    ((32, 96), True)
    """

    width: float
    length: float
    kind = "rectangle"
    keys = ({"width", "length"}, set())

    def __post_init__(self):
        """Check the sides."""
        object.__setattr__(self, "width", _length(self.width, "width"))
        object.__setattr__(self, "length", _length(self.length, "length"))

    @classmethod
    def from_table(cls, table, base_dir=None):
        """From ``[punch]`` keys (``width``, ``length``)."""
        return cls(_length(table["width"], "[punch] width"),
                   _length(table["length"], "[punch] length"))

    @property
    def half_extent(self):
        """``(width / 2, length / 2)``, m."""
        return 0.5 * self.width, 0.5 * self.length

    @property
    def area(self):
        """``width * length``, m^2."""
        return self.width * self.length

    def contains(self, x, y):
        """Points strictly inside the rectangle."""
        bx, by = self.half_extent
        return (np.abs(np.asarray(x)) < bx) & (np.abs(np.asarray(y)) < by)

    def encloses_disk(self, centre, radius):
        """The disk within both pairs of sides (to round-off)."""
        bx, by = self.half_extent
        slack = 1e-12 * self.scale
        return (abs(centre[0]) + radius <= bx + slack) and (abs(centre[1]) + radius <= by + slack)

    def parameters(self):
        """``{"width": ..., "length": ...}``, m."""
        return {"width": (self.width, "m"), "length": (self.length, "m")}


@register_outline
@dataclasses.dataclass(frozen=True)
class Ellipse(_Outline):
    """An ellipse with semi-axes ``semi_axis_x`` along x and ``semi_axis_y`` along y.

    Parameters
    ----------
    semi_axis_x, semi_axis_y : float, m

    Examples
    --------
    >>> Ellipse(2e-3, 4e-3).grid(64).shape
    (32, 64)
    """

    semi_axis_x: float
    semi_axis_y: float
    kind = "ellipse"
    keys = ({"semi_axis_x", "semi_axis_y"}, set())

    def __post_init__(self):
        """Check the semi-axes."""
        object.__setattr__(self, "semi_axis_x", _length(self.semi_axis_x, "semi_axis_x"))
        object.__setattr__(self, "semi_axis_y", _length(self.semi_axis_y, "semi_axis_y"))

    @classmethod
    def from_table(cls, table, base_dir=None):
        """From ``[punch]`` keys (``semi_axis_x``, ``semi_axis_y``)."""
        return cls(_length(table["semi_axis_x"], "[punch] semi_axis_x"),
                   _length(table["semi_axis_y"], "[punch] semi_axis_y"))

    @property
    def half_extent(self):
        """The semi-axes, m."""
        return self.semi_axis_x, self.semi_axis_y

    @property
    def area(self):
        """``pi a_x a_y``, m^2."""
        return math.pi * self.semi_axis_x * self.semi_axis_y

    def contains(self, x, y):
        """Points strictly inside the ellipse."""
        return ((np.asarray(x) / self.semi_axis_x) ** 2
                + (np.asarray(y) / self.semi_axis_y) ** 2 < 1.0)

    def parameters(self):
        """The semi-axes, m."""
        return {"semi_axis_x": (self.semi_axis_x, "m"), "semi_axis_y": (self.semi_axis_y, "m")}


@register_outline
@dataclasses.dataclass(frozen=True)
class Annulus(_Outline):
    """A ring between two concentric circles: a seal face.

    Parameters
    ----------
    inner_radius, outer_radius : float, m
        ``0 < inner_radius < outer_radius``.

    Notes
    -----
    The grid covers the outer disk; a pixel belongs to the face when its
    centre lies strictly inside the outer circle and strictly outside the
    inner one.  Resolution: at least three pixels across the ring,
    ``n >= 6 a_o / (a_o - a_i)``, and :data:`MIN_SIDE_PIXELS`.

    Examples
    --------
    >>> grid = Annulus(2e-3, 4e-3).grid(64)
    >>> bool(grid.mask[32, 32]), bool(grid.mask[32, 4])
    (False, True)
    """

    inner_radius: float
    outer_radius: float
    kind = "annulus"
    keys = ({"inner_radius", "outer_radius"}, set())

    def __post_init__(self):
        """Check the radii."""
        inner = _length(self.inner_radius, "inner_radius")
        outer = _length(self.outer_radius, "outer_radius")
        if not inner < outer:
            raise ValueError(f"inner_radius must be smaller than outer_radius, got "
                             f"{inner!r} m and {outer!r} m")
        object.__setattr__(self, "inner_radius", inner)
        object.__setattr__(self, "outer_radius", outer)

    @classmethod
    def from_table(cls, table, base_dir=None):
        """From ``[punch]`` keys (``inner_radius``, ``outer_radius``)."""
        try:
            return cls(_length(table["inner_radius"], "[punch] inner_radius"),
                       _length(table["outer_radius"], "[punch] outer_radius"))
        except ValueError as err:
            raise ValueError(f"[punch] {err}") from None

    @property
    def half_extent(self):
        """``(a_o, a_o)``, m."""
        return self.outer_radius, self.outer_radius

    @property
    def area(self):
        """``pi (a_o^2 - a_i^2)``, m^2."""
        return math.pi * (self.outer_radius**2 - self.inner_radius**2)

    def contains(self, x, y):
        """Points strictly between the two circles."""
        r2 = np.asarray(x) ** 2 + np.asarray(y) ** 2
        return (r2 < self.outer_radius**2) & (r2 > self.inner_radius**2)

    def grid_mask(self, grid):
        """The outer disk's :func:`steady.grid.face_mask` without the inner disk."""
        r2 = grid.x[:, None] ** 2 + grid.y[None, :] ** 2
        return disk_face_mask(grid.n) & (r2 > self.inner_radius**2)

    def min_grid(self):
        """Three pixels across the ring, and :data:`MIN_SIDE_PIXELS`."""
        ring = (self.outer_radius - self.inner_radius) / self.outer_radius
        return max(MIN_SIDE_PIXELS, math.ceil(6.0 / ring - 1e-9))

    def encloses_disk(self, centre, radius):
        """The disk inside the outer circle and clear of the inner one (to round-off)."""
        d = math.hypot(*centre)
        slack = 1e-12 * self.outer_radius
        return d + radius <= self.outer_radius + slack and d - radius >= self.inner_radius - slack

    def parameters(self):
        """The two radii, m."""
        return {"inner_radius": (self.inner_radius, "m"),
                "outer_radius": (self.outer_radius, "m")}


@register_outline
@dataclasses.dataclass(frozen=True, eq=False)
class MaskOutline(_Outline):
    """A face given as pixels: ``True`` on the face, on an ``mx x my`` grid of square pixels.

    Parameters
    ----------
    mask : ndarray of bool, shape (mx, my)
        The face's pixels, x along axis 0; at least one.
    pixel_size : float, m
        Side of the mask's pixels.
    source : str, optional
        Where the mask came from (for messages).

    Notes
    -----
    The bounding box is the mask's array, centred on the origin.  The face
    is the union of the mask's pixels, so a grid must refine the mask by a
    whole factor: ``n`` (pixels along the longer side) a multiple of
    ``max(mx, my)``, each mask pixel becoming ``k x k`` grid pixels.

    Examples
    --------
    >>> import numpy as np
    >>> mask = np.ones((6, 12), dtype=bool)
    >>> mask[:3, :4] = False                        # an L-shaped face
    >>> grid = MaskOutline(mask, 1e-3).grid(24)
    >>> grid.shape, int(grid.mask.sum()), MaskOutline(mask, 1e-3).area
    ((12, 24), 240, 6e-05)
    """

    mask: np.ndarray
    pixel_size: float
    source: str = "array"
    kind = "mask"
    keys = ({"path", "pixel_size"}, set())

    def __post_init__(self):
        """Check the mask; store it read-only."""
        m = np.asarray(self.mask)
        if m.ndim != 2:
            raise ValueError(f"face mask {self.source} must be a 2-d array, got shape {m.shape}")
        if m.dtype != bool:
            raise ValueError(f"face mask {self.source} must be boolean, got dtype {m.dtype}")
        if not m.any():
            raise ValueError(f"face mask {self.source} has no face pixel")
        m = np.array(m, dtype=bool)
        m.flags.writeable = False
        object.__setattr__(self, "mask", m)
        object.__setattr__(self, "pixel_size", _length(self.pixel_size, "pixel_size"))

    @classmethod
    def from_table(cls, table, base_dir="."):
        """From ``[punch]`` keys (``path``, ``pixel_size``): see :func:`read_face_mask`."""
        import pathlib

        from .phases import read_face_mask

        path = table["path"]
        if not isinstance(path, str) or not path:
            raise ValueError(f"[punch] path must be a non-empty string, got {shorten(path)}")
        size = _length(table["pixel_size"], "[punch] pixel_size")
        full = pathlib.Path(base_dir) / path
        return cls(read_face_mask(full), size, source=repr(str(full)))

    @property
    def half_extent(self):
        """Half the mask array's sides, m."""
        mx, my = self.mask.shape
        return 0.5 * mx * self.pixel_size, 0.5 * my * self.pixel_size

    @property
    def area(self):
        """Mask pixels times their area, m^2."""
        return float(self.mask.sum()) * self.pixel_size**2

    def grid_shape(self, n):
        """``k (mx, my)`` with ``k = n / max(mx, my)``."""
        n = self.check_grid(n)
        k = n // max(self.mask.shape)
        return k * self.mask.shape[0], k * self.mask.shape[1]

    def min_grid(self):
        """The mask's own size along its longer side."""
        return max(self.mask.shape)

    def check_grid(self, n):
        """``n`` as an int; ``ValueError`` unless a multiple of the mask's longer side."""
        n = _grid_size(n)
        m0 = self.min_grid()
        if n < m0 or n % m0:
            raise ValueError(f"grid size n = {n} must be a multiple of {m0}, the longer side "
                             f"of face mask {self.source} ({self.mask.shape[0]} x "
                             f"{self.mask.shape[1]} pixels)")
        return n

    def contains(self, x, y):
        """Points inside a mask pixel (on a pixel's edge: the pixel above and to the right)."""
        lx, ly = self.half_extent
        mx, my = self.mask.shape
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        i = np.floor((x + lx) / self.pixel_size).astype(np.int64)
        j = np.floor((y + ly) / self.pixel_size).astype(np.int64)
        inside = (i >= 0) & (i < mx) & (j >= 0) & (j < my)
        out = np.zeros(x.shape, dtype=bool)
        out[inside] = self.mask[i[inside], j[inside]]
        return out

    def grid_mask(self, grid):
        """The mask with each pixel replicated ``k x k`` times."""
        k = grid.shape[0] // self.mask.shape[0]
        return np.kron(self.mask, np.ones((k, k), dtype=bool)).astype(bool)

    def parameters(self):
        """Pixel size (m) and the mask's size in pixels."""
        return {"pixel_size": (self.pixel_size, "m"),
                "mask_pixels_x": (self.mask.shape[0], "1"),
                "mask_pixels_y": (self.mask.shape[1], "1")}

    def describe(self):
        """The mask in words."""
        mx, my = self.mask.shape
        return (f"mask face {self.source} ({mx} x {my} pixels of "
                f"{self.pixel_size * 1e3:.6g} mm)")


def as_outline(outline):
    """An outline object; a number stands for the radius of a circular face (m).

    Parameters
    ----------
    outline : outline object or float

    Returns
    -------
    outline object

    Examples
    --------
    >>> as_outline(4e-3)
    Circle(radius=0.004)
    """
    if isinstance(outline, _Outline):
        return outline
    if isinstance(outline, (bool, np.bool_)) or not isinstance(outline, (int, float, np.number)):
        raise ValueError(f"an outline or a radius (m) is needed, got {shorten(outline)}")
    return Circle(_length(outline, "radius"))


def outline_from_table(table, base_dir="."):
    """The outline of a scene's ``[punch]`` table.

    Parameters
    ----------
    table : dict
        ``shape`` (default ``"circle"``) and the keys of that outline
        (``Circle``: ``radius``; ``Rectangle``: ``width``, ``length``;
        ``Ellipse``: ``semi_axis_x``, ``semi_axis_y``; ``Annulus``:
        ``inner_radius``, ``outer_radius``; ``MaskOutline``: ``path``,
        ``pixel_size``), lengths in m.
    base_dir : path-like, optional
        Directory of the scene file (for ``path``).

    Returns
    -------
    outline object

    Raises
    ------
    ValueError
        An unknown shape, a missing or unknown key, a bad value; the
        message names them.

    Examples
    --------
    >>> outline_from_table({"shape": "rectangle", "width": 0.004, "length": 0.012})
    Rectangle(width=0.004, length=0.012)
    >>> outline_from_table({"radius": 0.004})
    Circle(radius=0.004)
    """
    if not isinstance(table, dict):
        raise ValueError(f"[punch] must be a table, got {shorten(table)}")
    kind = table.get("shape", "circle")
    if not isinstance(kind, str) or kind not in OUTLINES:
        raise ValueError(f"[punch] shape must be one of {sorted(OUTLINES)}, got {shorten(kind)}")
    cls = OUTLINES[kind]
    required, optional = cls.keys
    unknown = sorted(set(table) - required - optional - {"shape"})
    if unknown:
        allowed = ", ".join(sorted(required | optional | {"shape"}))
        raise ValueError(f"unknown key {shorten(unknown[0])} in [punch] (shape {kind!r}; "
                         f"allowed: {allowed})")
    missing = sorted(required - set(table))
    if missing:
        raise ValueError(f"missing key {missing[0]!r} in [punch] (shape {kind!r})")
    return cls.from_table(table, base_dir)
