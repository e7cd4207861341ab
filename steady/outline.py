"""Outlines of the punch face, and the pixel grid that covers each.

The punch face is a plane region centred on the origin: a disk (the paper's
cylinder), a rectangle (a tread block), an ellipse, an annulus (a seal) or
any region given as a pixel mask.  Every outline has

- ``kind`` : its name in scene files (``[punch] shape``);
- ``periodic`` : whether the face is a cell that repeats in both directions
  (:class:`PeriodicCell`, with no rim); False for every finite face.  Callers
  ask it, and choose the operator by it (:meth:`steady.counterbody.Counterbody.operator`);
- ``half_extent`` : ``(Lx, Ly)``, m, the half sides of its bounding box,
  x along axis 0;
- ``scale`` : ``L = max(Lx, Ly)``, m, the length unit of phase geometries
  (the radius ``a`` of a disk);
- ``area`` : the exact area of the region, m^2 (``pbar = F_N / area``);
- ``contains(x, y)`` : whether points (m) lie strictly inside;
  ``covers(x, y)`` : inside or on the outline (the closed face);
- ``grid(n)`` : the :class:`FaceGrid` of ``n`` pixels along the longer
  side of the bounding box;
- ``min_grid()``, ``check_grid(n)`` : the coarsest grid that resolves it;
- ``encloses_disk(centre, radius)`` : whether a disk (m) lies in the face;
- ``support(direction)``, ``circumradius()`` : how far the face reaches
  along a direction, and from its centre, m;
- ``parameters()`` : its defining lengths, ``name -> (value, unit)``;
- what files record of it beside its lengths: ``root_attributes()`` (a
  disk's radius), ``group_record()`` (a mask's pixels) and, to read it
  back, ``from_group(attributes, read)``;
- its closed forms, None where it has none: the homogeneous face's rms
  slope (``homogeneous_slope_factor()``, used by
  :mod:`steady.normalisation`), the distance to the rim
  (``exact_rim_distance(x, y)``) and the statistics of a sphere cap over
  the face (``cap_statistics(sphere_radius)``).

Grid
----
Pixels are square, of side ``h = 2 L / n``; the bounding box is covered by
``nx x ny`` pixels centred on the origin, ``n`` along the longer side and
``round(n Ls / L)`` along the shorter one (``Ls`` its half side), so that a
rectangle whose sides are whole numbers of pixels is covered exactly.  A
pixel belongs to the face when its centre lies strictly inside the
outline; areas are pixel counts times ``h^2``.  For a disk this is the
``n x n`` grid over ``[-a, a]^2``, pixel centres ``-a + (i + 1/2) h``.
:func:`as_grid` turns a bare ``n`` into the grid of the unit disk (radius
1 m).

Outlines are registered in :data:`OUTLINES` (a
:class:`steady.schema.KindRegistry`) with their ``[punch]`` keys;
:func:`outline_from_table` builds one from the ``[punch]`` table of a scene
file.  Outlines compare by value (a mask by its pixels and pixel size).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import pathlib
import sys

import numpy as np
import scipy.integrate

from . import reference
from .array_files import read_face_mask
from .schema import Context, Key, KindRegistry
from .text import format_bytes, shorten

__all__ = [
    "MAX_GRID_SIZE",
    "MIN_SIDE_PIXELS",
    "OUTLINES",
    "UNIT_DISK",
    "Annulus",
    "Circle",
    "Ellipse",
    "FaceGrid",
    "MaskOutline",
    "PeriodicCell",
    "Rectangle",
    "as_grid",
    "as_outline",
    "describe_change",
    "grid_size",
    "grid_size_text",
    "outline_from_table",
]

#: Fewest pixels across the shorter side of a grid's box (and across the ring
#: of an annulus, in units of three), for an outline and for a phase map.
MIN_SIDE_PIXELS = 8

#: Most pixels along the longer side of a grid's box: an ``n x n`` field of 8-byte
#: values (every solve holds several) beyond it would not fit the memory a process can
#: address (``sys.maxsize`` bytes), nor its sizes a C integer.
MAX_GRID_SIZE = math.isqrt(sys.maxsize // 8)

#: Registered outlines, by ``shape`` (``[punch] shape``; default ``"circle"``).
OUTLINES = KindRegistry("face outline", "shape", default="circle",
                        entry_point_group="runin.outlines")


def _length_key(name, doc):
    """A required ``[punch]`` length, m, positive.

    An outline built in Python checks its lengths through the keys of its
    scene table (``key.parse(value, "", scale=False)``); the scale range is
    a problem's to check (:func:`steady.problem.check_input_scales`).
    """
    return Key(name, "number", unit="m", low=0.0, required=True, doc=doc)


def grid_size(n):
    """A grid size ``n`` (pixels along the longer side of a box) as an int, checked.

    The one place a grid size given by a user is checked for its type and
    its upper bound, :data:`MAX_GRID_SIZE`; outlines and phase maps check
    the smallest size they need.

    Raises
    ------
    ValueError
        ``n`` is not an integer (a float, a bool, a string), or is larger
        than :data:`MAX_GRID_SIZE`.

    Examples
    --------
    >>> grid_size(64)
    64
    >>> try:
    ...     grid_size(10**20)
    ... except ValueError as err:
    ...     print(str(err).split(":")[0].replace(str(MAX_GRID_SIZE), "MAX_GRID_SIZE"))
    grid size n = 1e+20 is larger than MAX_GRID_SIZE
    """
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"grid size n must be an integer, got {shorten(n)}")
    n = int(n)
    if n > MAX_GRID_SIZE:
        raise ValueError(f"grid size n = {shorten(n)} is larger than {MAX_GRID_SIZE}: "
                         f"an n x n grid of 8-byte values would exceed the memory a process "
                         f"can address ({format_bytes(sys.maxsize)})")
    return n


def grid_size_text(n):
    """A grid size for messages: the integer, or 3 digits of one beyond 10^9 (never allocated).

    Examples
    --------
    >>> grid_size_text(512), grid_size_text(8 * 10**60)
    ('512', '8e+60')
    """
    return str(n) if n < 10**9 else f"{float(n):.3g}"


def _disk_mask(n):
    """Pixels of the ``n x n`` grid whose centre lies strictly inside the inscribed disk."""
    # Integer arithmetic: (2i + 1 - n)^2 + (2j + 1 - n)^2 < n^2 is exact.
    c = 2 * np.arange(n) + 1 - n
    return c[:, None] ** 2 + c[None, :] ** 2 < n * n


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
        The same in units of the outline's scale ``L`` (where phase
        geometries are rasterised, their lengths in m divided by ``L``).
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
        # -m/n + (i + 1/2) 2/n: for m = n the centres -1 + (i + 1/2) h of the
        # unit disk's grid, the same numbers as _axis gives for L = 1.
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

    @functools.cached_property
    def radii(self):
        """Distance of every pixel centre from the face's centre, m, shape (nx, ny)."""
        return np.hypot(self.x[:, None], self.y[None, :])

    def polar(self):
        """Radius (m) and azimuth (rad) of every pixel centre, each shape (nx, ny)."""
        return self.radii, np.arctan2(self.y[None, :], self.x[:, None])


class _Outline:
    """What every outline shares (its subclasses are frozen dataclasses)."""

    #: Whether the face is a periodic cell (no rim); a finite face is not.
    periodic = False

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
        n = grid_size(n)
        ax, ay = self.aspect
        return (n if ax == 1.0 else max(1, math.floor(n * ax + 0.5)),
                n if ay == 1.0 else max(1, math.floor(n * ay + 0.5)))

    def grid(self, n):
        """The :class:`FaceGrid` of ``n`` pixels along the longer side."""
        return FaceGrid(self, n)

    def grid_mask(self, grid):
        """Face pixels of ``grid``: centres strictly inside the outline."""
        return self.contains(grid.x[:, None], grid.y[None, :])

    def covers(self, x, y):
        """Points inside the outline or on it (the closed face); by default :meth:`contains`."""
        return self.contains(x, y)

    def min_grid(self):
        """Smallest ``n``: :data:`MIN_SIDE_PIXELS` across the shorter side of the box."""
        return max(MIN_SIDE_PIXELS, math.ceil(MIN_SIDE_PIXELS / min(self.aspect) - 1e-9))

    def check_grid(self, n):
        """``n`` as an int; ``ValueError`` naming ``n`` and the minimum if too coarse."""
        n = grid_size(n)
        low = self.min_grid()
        if n < low:
            raise ValueError(f"grid too coarse for the {self.describe()}: n = {n}, the minimum "
                             f"is n = {grid_size_text(low)}")
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

    def support(self, direction):
        """``max (x, y) . direction`` over the face, m: how far it reaches along a unit vector.

        Exact for the disk, the annulus, the rectangle and the ellipse, and
        for a mask (its pixels' corners); otherwise the largest value over
        the pixel corners of a fine grid's face.

        Parameters
        ----------
        direction : (float, float)
            A unit vector.

        Returns
        -------
        float

        Examples
        --------
        >>> print(f"{Rectangle(4e-3, 12e-3).support((0.6, 0.8)) * 1e3:.3f} mm")
        6.000 mm
        """
        ux, uy = (float(v) for v in direction)
        x0, x1, y0, y1 = self._pixel_edges()
        return float(np.max(np.maximum(x0 * ux, x1 * ux) + np.maximum(y0 * uy, y1 * uy)))

    def circumradius(self):
        """Largest distance of the face from its centre, m (the radius of a disk).

        Exact for the disk, the annulus, the rectangle and the ellipse, and
        for a mask (its pixels' corners); otherwise over the pixel corners
        of a fine grid's face.
        """
        x0, x1, y0, y1 = self._pixel_edges()
        return float(np.sqrt(np.max(np.maximum(x0**2, x1**2) + np.maximum(y0**2, y1**2))))

    def _pixel_edges(self):
        """Lower and upper x and y edges of the face's pixels on a fine grid, m."""
        grid = FaceGrid(self, max(512, self.min_grid()))
        i, j = np.nonzero(grid.mask)
        half = 0.5 * grid.h
        x, y = grid.x[i], grid.y[j]
        return x - half, x + half, y - half, y + half

    def describe(self):
        """The outline in words with its lengths in mm."""
        parts = ", ".join(f"{name} {value * 1e3:.6g} mm"
                          for name, (value, _) in self.parameters().items()
                          if _ == "m")
        return f"{self.kind} face ({parts})"

    def grid_at_least(self, n):
        """The smallest grid size the outline accepts that is at least ``n`` pixels.

        Parameters
        ----------
        n : int

        Returns
        -------
        int
        """
        return max(n, self.min_grid())

    # -- closed forms (None where the outline has none) ---------------------------------
    def homogeneous_slope_factor(self):
        """``(S, error, source)``: the homogeneous face's rms slope in units of ``pbar / E*``.

        The homogeneous steady face is the displacement under the uniform
        pressure ``pbar``; its rms slope is ``S pbar / E*`` with ``S`` set by
        the outline's shape alone (:mod:`steady.normalisation`).

        Returns
        -------
        (float, float, str) or None
            ``S``, its uncertainty and where it comes from, in words; None
            without a closed form (the default: :mod:`steady.normalisation`
            then estimates ``S``).
        """
        return None

    def homogeneous_rms_slope(self, factor, mean_pressure, E_star):
        """The homogeneous face's rms slope ``S pbar / E*``: the reference slope ``grad_f0``.

        Parameters
        ----------
        factor : float
            ``S`` (:meth:`homogeneous_slope_factor`, or an estimate).
        mean_pressure : float, Pa
            ``pbar = F_N / area``.
        E_star : float, Pa

        Returns
        -------
        float
        """
        return factor * mean_pressure / E_star

    def exact_rim_distance(self, x, y):
        """Distance (m) from points of the face to its rim, or None without a closed form.

        Parameters
        ----------
        x, y : ndarray, m
            Points of the face, from its centre.

        Returns
        -------
        ndarray, m, or None
            None by default (:meth:`steady.fit.FaceModel.rim_distance` then
            takes the distance transform of the face's pixels).
        """
        return None

    def cap_statistics(self, sphere_radius):
        """Rms slope and rms height of a sphere cap over the face, exactly; None without a form.

        Parameters
        ----------
        sphere_radius : float, m
            ``R``: the cap ``R - sqrt(R^2 - r^2)`` of the sphere centred over
            the face's centre.

        Returns
        -------
        (float, float) or None
            The rms of ``|grad h|`` (1) and the rms of ``h`` about its
            least-squares plane (m); None by default.
        """
        return None

    # -- what files record --------------------------------------------------------------
    def root_attributes(self):
        """Root attributes a file records of the outline beside its group (default none).

        Returns
        -------
        dict of str to (value, str)
            ``name -> (value, udunits unit)``.
        """
        return {}

    def group_record(self):
        """What the outline's group holds beyond its kind, area and :meth:`parameters`.

        Returns
        -------
        attributes : dict of str to object
            Further attributes of the group.
        arrays : dict of str to (ndarray, str, str, (ndarray, ndarray) or None)
            ``name -> (values, units, long_name, coordinates)``; the
            coordinates (m) of the pixel centres along each axis, or None.
            Default: neither.
        """
        return {}, {}

    @classmethod
    def from_group(cls, attributes, read):
        """The outline a group records: its lengths, the required keys of its kind.

        Parameters
        ----------
        attributes : mapping
            The group's attributes (:func:`steady.output.write_outline`).
        read : callable
            ``read(name)``: the values of the group's dataset ``name``.

        Returns
        -------
        outline object
        """
        return cls(**{key.name: float(attributes[key.name]) for key in cls.keys
                      if key.required})


_RADIUS = _length_key("radius", "the disk's radius a")


@OUTLINES.register("circle", (_RADIUS,),
                   doc="the disk of radius a: the paper's cylinder")
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

    def __post_init__(self):
        """Check the radius."""
        object.__setattr__(self, "radius", _RADIUS.parse(self.radius, "", scale=False))

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[punch]`` keys."""
        return cls(values["radius"])

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

    def covers(self, x, y):
        """Points inside the disk or on its circle."""
        return np.hypot(x, y) <= self.radius

    def grid_mask(self, grid):
        """Pixel centres inside the disk, exact in integers."""
        return _disk_mask(grid.n)

    def encloses_disk(self, centre, radius):
        """``|c| + r <= a`` (to round-off)."""
        return math.hypot(*centre) + radius <= self.radius * (1.0 + 1e-12)

    def support(self, direction):
        """``a`` in every direction, m."""
        return self.radius

    def circumradius(self):
        """``a``, m."""
        return self.radius

    def parameters(self):
        """``{"radius": (a, "m")}``."""
        return {"radius": (self.radius, "m")}

    def root_attributes(self):
        """``{"radius": (a, "m")}``: files written before the outline group record only it."""
        return {"radius": (self.radius, "m")}

    def homogeneous_slope_factor(self):
        """``(4 / pi, 0, ...)``: eq. 12, exact for the continuum face."""
        return 4.0 / math.pi, 0.0, "disk: 4 pbar / (pi E*) (eq. 12)"

    def homogeneous_rms_slope(self, factor, mean_pressure, E_star):
        """Eq. 12 as written, ``4 pbar / (pi E*)`` (:func:`steady.reference.disk_reference_slope`).

        ``factor`` is ``4 / pi`` (:meth:`homogeneous_slope_factor`); the
        equation is evaluated as the paper writes it, not as the product.
        """
        return reference.disk_reference_slope(mean_pressure, E_star)

    def exact_rim_distance(self, x, y):
        """``a - r``, m."""
        return self.radius - np.hypot(x, y)

    def cap_statistics(self, sphere_radius):
        """The sphere cap ``R - sqrt(R^2 - r^2)`` over the disk ``r < a``.

        Mean-square slope ``(2/a^2) int_0^a r^3 / (R^2 - r^2) dr
        = (R/a)^2 (-ln(1 - x) - x)``, ``x = (a/R)^2`` (infinite for ``R = a``);
        the rms height (the best plane of a radial face is a constant) by
        adaptive quadrature of the cap, written ``r^2 / (R + sqrt(R^2 - r^2))``
        to avoid cancellation.
        """
        a, big = self.radius, float(sphere_radius)
        x = (a / big) ** 2
        mean_square = (-math.log1p(-x) - x) / x if x < 1 else math.inf

        def cap(r):
            return r * r / (big + math.sqrt(max(big * big - r * r, 0.0)))

        def disk_mean(f):
            return 2.0 / a**2 * scipy.integrate.quad(lambda r: f(r) * r, 0.0, a, epsabs=0.0,
                                                     epsrel=1e-12)[0]

        mean = disk_mean(cap)
        variance = disk_mean(lambda r: (cap(r) - mean) ** 2)
        return math.sqrt(mean_square), math.sqrt(variance)


_WIDTH = _length_key("width", "side along x")
_LENGTH = _length_key("length", "side along y")


@OUTLINES.register("rectangle", (_WIDTH, _LENGTH),
                   doc="a rectangle, e.g. a tread block")
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

    def __post_init__(self):
        """Check the sides."""
        for key in (_WIDTH, _LENGTH):
            object.__setattr__(self, key.name, key.parse(getattr(self, key.name), "", scale=False))

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[punch]`` keys."""
        return cls(values["width"], values["length"])

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

    def covers(self, x, y):
        """Points inside the rectangle or on its sides."""
        bx, by = self.half_extent
        return (np.abs(np.asarray(x)) <= bx) & (np.abs(np.asarray(y)) <= by)

    def encloses_disk(self, centre, radius):
        """The disk within both pairs of sides (to round-off)."""
        bx, by = self.half_extent
        slack = 1e-12 * self.scale
        return (abs(centre[0]) + radius <= bx + slack) and (abs(centre[1]) + radius <= by + slack)

    def support(self, direction):
        """``Lx |ux| + Ly |uy|``, m (a corner)."""
        lx, ly = self.half_extent
        return lx * abs(float(direction[0])) + ly * abs(float(direction[1]))

    def circumradius(self):
        """Half the diagonal, m."""
        return math.hypot(*self.half_extent)

    def parameters(self):
        """``{"width": ..., "length": ...}``, m."""
        return {"width": (self.width, "m"), "length": (self.length, "m")}

    def homogeneous_slope_factor(self):
        """``S`` by quadrature of Love's closed-form gradient.

        See :func:`steady.reference.rectangle_rms_slope`.
        """
        factor = reference.rectangle_rms_slope(self.width, self.length)
        return float(factor), 0.0, ("homogeneous rectangle: quadrature of Love's closed-form "
                                     "gradient")

    def exact_rim_distance(self, x, y):
        """Distance to the nearer pair of sides, m."""
        bx, by = self.half_extent
        return np.minimum(bx - np.abs(x), by - np.abs(y))


# Relative tolerance of a periodic cell's shorter side in whole pixels.
_WHOLE_PIXELS = 1e-9
# Grid sizes :meth:`PeriodicCell.grid_at_least` tries before it gives up.
_GRID_SEARCH = 100_000


@OUTLINES.register("periodic", (_WIDTH, _LENGTH),
                   doc="a periodic cell width x length, repeating in both directions: a "
                       "representative patch of a large surface, with no rim")
@dataclasses.dataclass(frozen=True)
class PeriodicCell(Rectangle):
    """A cell ``width x length`` (x along its width) that repeats in both directions.

    The face covers the whole cell: every grid pixel is a face pixel, the
    grid covers the cell exactly and ``area`` is ``width * length`` (the load is
    the force on one cell).  The operator is the periodic half-space
    (:class:`steady.periodic.PeriodicHalfSpace`, through
    :meth:`steady.counterbody.Counterbody.operator`): the face has no rim, so there is no
    rim distance and no rim term in its rms slope.  ``scale`` is the larger
    half side, as for a rectangle, and the pixel ``h = 2 L / n`` the longer
    side over ``n``.

    Parameters
    ----------
    width : float, m
        Side along x (axis 0).
    length : float, m
        Side along y (axis 1).

    Notes
    -----
    Pixels are square and tile the cell: the shorter side must be a whole
    number of pixels, ``n * short / long`` an integer to within ``1e-9``
    (:meth:`check_grid` refuses other ``n``, naming the sides).

    Examples
    --------
    >>> grid = PeriodicCell(4e-3, 12e-3).grid(96)
    >>> grid.shape, bool(grid.mask.all()), PeriodicCell(4e-3, 12e-3).periodic
    ((32, 96), True, True)
    """

    periodic = True

    def grid_shape(self, n):
        """``(nx, ny)``: ``n`` along the longer side, the shorter side in whole pixels."""
        n = self.check_grid(n)
        return super().grid_shape(n)

    def _whole_pixels(self, n):
        """Whether the shorter side is a whole number of the pixels of ``n``."""
        ratio = min(self.width, self.length) / max(self.width, self.length)
        pixels = n * ratio
        return abs(pixels - round(pixels)) <= _WHOLE_PIXELS * max(pixels, 1.0)

    def check_grid(self, n):
        """``n`` as an int; ``ValueError`` if too coarse or the sides are not whole pixels."""
        n = super().check_grid(n)
        if not self._whole_pixels(n):
            raise ValueError(
                f"the sides of the {self.describe()} are not whole pixels at n = {n}: width "
                f"{self.width!r} m and length {self.length!r} m, pixel "
                f"{max(self.width, self.length) / n!r} m; the periodic cell must be tiled "
                f"exactly (n = {self.grid_at_least(n)} is the next size that tiles it)")
        return n

    def grid_at_least(self, n):
        """The smallest grid size at least ``n`` that tiles the cell in square pixels."""
        for m in range(max(n, self.min_grid()), max(n, self.min_grid()) + _GRID_SEARCH):
            if self._whole_pixels(m):
                return m
        raise ValueError(f"no grid size from n = {n} to {n + _GRID_SEARCH} tiles the "
                         f"{self.describe()} in square pixels: width {self.width!r} m, "
                         f"length {self.length!r} m")

    def grid_mask(self, grid):
        """Every pixel: the face is the whole cell."""
        return np.ones(grid.shape, dtype=bool)

    def homogeneous_slope_factor(self):
        """``(4 / pi, 0, ...)``: the disk's scale ``4 pbar / (pi E*)`` (eq. 12).

        The homogeneous face of a periodic cell is flat; its slopes are given in
        the units of the disk's, so that a cell and a punch under the same mean
        pressure compare directly.
        """
        return 4.0 / math.pi, 0.0, ("periodic cell (homogeneous face flat): the disk's "
                                     "4 pbar / (pi E*) as the unit")

    def exact_rim_distance(self, x, y):
        """None: a periodic cell has no rim."""
        return None


_SEMI_AXIS_X = _length_key("semi_axis_x", "semi-axis along x")
_SEMI_AXIS_Y = _length_key("semi_axis_y", "semi-axis along y")


@OUTLINES.register("ellipse", (_SEMI_AXIS_X, _SEMI_AXIS_Y),
                   doc="an ellipse")
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

    def __post_init__(self):
        """Check the semi-axes."""
        for key in (_SEMI_AXIS_X, _SEMI_AXIS_Y):
            object.__setattr__(self, key.name, key.parse(getattr(self, key.name), "", scale=False))

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[punch]`` keys."""
        return cls(values["semi_axis_x"], values["semi_axis_y"])

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

    def covers(self, x, y):
        """Points inside the ellipse or on it."""
        return ((np.asarray(x) / self.semi_axis_x) ** 2
                + (np.asarray(y) / self.semi_axis_y) ** 2 <= 1.0)

    def support(self, direction):
        """``hypot(ax ux, ay uy)``, m."""
        lx, ly = self.half_extent
        return math.hypot(lx * float(direction[0]), ly * float(direction[1]))

    def circumradius(self):
        """The larger semi-axis, m."""
        return max(self.half_extent)

    def parameters(self):
        """The semi-axes, m."""
        return {"semi_axis_x": (self.semi_axis_x, "m"), "semi_axis_y": (self.semi_axis_y, "m")}


_INNER_RADIUS = _length_key("inner_radius", "radius of the inner circle")
_OUTER_RADIUS = _length_key("outer_radius", "radius of the outer circle")


@OUTLINES.register("annulus", (_INNER_RADIUS, _OUTER_RADIUS),
                   doc="a ring, e.g. a seal face")
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

    def __post_init__(self):
        """Check the radii."""
        inner = _INNER_RADIUS.parse(self.inner_radius, "", scale=False)
        outer = _OUTER_RADIUS.parse(self.outer_radius, "", scale=False)
        if not inner < outer:
            raise ValueError(f"inner_radius must be smaller than outer_radius, got "
                             f"{inner!r} m and {outer!r} m")
        object.__setattr__(self, "inner_radius", inner)
        object.__setattr__(self, "outer_radius", outer)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[punch]`` keys."""
        return cls(values["inner_radius"], values["outer_radius"])

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

    def covers(self, x, y):
        """Points between the two circles or on one of them."""
        r = np.hypot(x, y)
        return (r <= self.outer_radius) & (r >= self.inner_radius)

    def grid_mask(self, grid):
        """The outer disk's pixels (exact in integers) without the inner disk."""
        r2 = grid.x[:, None] ** 2 + grid.y[None, :] ** 2
        return _disk_mask(grid.n) & (r2 > self.inner_radius**2)

    def min_grid(self):
        """Three pixels across the ring, and :data:`MIN_SIDE_PIXELS`."""
        ring = (self.outer_radius - self.inner_radius) / self.outer_radius
        return max(MIN_SIDE_PIXELS, math.ceil(6.0 / ring - 1e-9))

    def encloses_disk(self, centre, radius):
        """The disk inside the outer circle and clear of the inner one (to round-off)."""
        d = math.hypot(*centre)
        slack = 1e-12 * self.outer_radius
        return d + radius <= self.outer_radius + slack and d - radius >= self.inner_radius - slack

    def support(self, direction):
        """The outer radius in every direction, m."""
        return self.outer_radius

    def circumradius(self):
        """The outer radius, m."""
        return self.outer_radius

    def parameters(self):
        """The two radii, m."""
        return {"inner_radius": (self.inner_radius, "m"),
                "outer_radius": (self.outer_radius, "m")}

    def homogeneous_slope_factor(self):
        """``S`` of superposed disks (:func:`steady.reference.annulus_rms_slope`)."""
        factor = reference.annulus_rms_slope(self.inner_radius / self.outer_radius)
        return float(factor), 0.0, "homogeneous annulus: superposed disks (elliptic integrals)"

    def exact_rim_distance(self, x, y):
        """Distance to the nearer circle, m."""
        r = np.hypot(x, y)
        return np.minimum(self.outer_radius - r, r - self.inner_radius)


_MASK_PIXEL_SIZE = _length_key("pixel_size", "side of the mask's pixels")


@OUTLINES.register("mask", (Key("path", "path", required=True,
                                doc=".npy: booleans, True on the face, or integers: only 0 "
                                    "and 1 (1 on the face), or -1 off the face and values "
                                    ">= 0 on it; .png: the non-transparent pixels"),
                            _MASK_PIXEL_SIZE),
                   doc="any face, as pixels")
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
    ``max(mx, my)``, each mask pixel becoming ``k x k`` grid pixels.  Two
    masks are equal when their pixels and pixel sizes are (wherever they
    came from).

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
        object.__setattr__(self, "pixel_size",
                           _MASK_PIXEL_SIZE.parse(self.pixel_size, "", scale=False))

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[punch]`` keys: see :func:`steady.array_files.read_face_mask`."""
        path = values["path"]
        return cls(read_face_mask(path), values["pixel_size"], source=repr(str(path)))

    def __eq__(self, other):
        """Equal pixels and pixel size (the source is not compared)."""
        if not isinstance(other, MaskOutline):
            return NotImplemented
        return (self.pixel_size == other.pixel_size and self.mask.shape == other.mask.shape
                and bool(np.array_equal(self.mask, other.mask)))

    def __hash__(self):
        """Hash of the pixel size, the shape and the pixels."""
        return hash((self.pixel_size, self.mask.shape, self.mask.tobytes()))

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
        n = grid_size(n)
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

    def _pixel_edges(self):
        """The mask's own pixels' edges, m."""
        lx, ly = self.half_extent
        i, j = np.nonzero(self.mask)
        ps = self.pixel_size
        x0, y0 = -lx + i * ps, -ly + j * ps
        return x0, x0 + ps, y0, y0 + ps

    def parameters(self):
        """Pixel size (m) and the mask's size in pixels."""
        return {"pixel_size": (self.pixel_size, "m"),
                "mask_pixels_x": (self.mask.shape[0], "1"),
                "mask_pixels_y": (self.mask.shape[1], "1")}

    def grid_at_least(self, n):
        """The smallest multiple of the mask's longer side that is at least ``n``."""
        m0 = self.min_grid()
        return m0 * max(1, -(-n // m0))

    def group_record(self):
        """The attribute ``source`` and the dataset ``mask`` (1 on the face), at its pixels."""
        centres = tuple((np.arange(m) - 0.5 * (m - 1)) * self.pixel_size
                        for m in self.mask.shape)
        return ({"source": self.source},
                {"mask": (self.mask.astype(np.int8), "1", "1 inside the face, 0 outside",
                          centres)})

    @classmethod
    def from_group(cls, attributes, read):
        """The mask ``read("mask")`` with the pixel size and the source of ``attributes``."""
        source = attributes.get("source", "stored mask")
        if isinstance(source, bytes):
            source = source.decode()
        return cls(np.asarray(read("mask"), dtype=bool), float(attributes["pixel_size"]),
                   source=str(source))

    def describe(self):
        """The mask in words."""
        mx, my = self.mask.shape
        return (f"mask face {self.source} ({mx} x {my} pixels of "
                f"{self.pixel_size * 1e3:.6g} mm)")


#: The outline of grids given by their size alone: the unit disk, radius 1 m.
UNIT_DISK = Circle(1.0)


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
    return Circle(outline)


def as_grid(grid):
    """A :class:`FaceGrid`: ``grid`` itself, or for a bare ``n`` the unit disk's ``n x n`` grid.

    Phase geometries take lengths in m: on the unit disk (radius 1 m) their
    numbers are also in units of its scale.

    Examples
    --------
    >>> as_grid(16).outline, as_grid(16).shape
    (Circle(radius=1.0), (16, 16))
    """
    if isinstance(grid, FaceGrid):
        return grid
    return FaceGrid(UNIT_DISK, grid_size(grid))


def describe_change(old, new):
    """How a face ``new`` differs from ``old``, in words: ``"<old>, the scene has the <new>"``.

    For messages that refuse to continue work done on another face (a
    resumed run).  Two faces that differ below the six digits of
    ``describe()``, or masks with other pixels, would read the same; then
    the words say what differs: how many of the mask's pixels, or which
    length (to all its digits).

    Parameters
    ----------
    old, new : outline objects
        The face the work was done on, and the scene's.

    Returns
    -------
    str

    Examples
    --------
    >>> import numpy as np
    >>> mask = np.ones((6, 8), dtype=bool)
    >>> edited = mask.copy()
    >>> edited[0, :3] = False
    >>> print(describe_change(MaskOutline(mask, 1e-3, "'m.npy'"),
    ...                       MaskOutline(edited, 1e-3, "'m.npy'")))
    mask face 'm.npy' (6 x 8 pixels of 1 mm) with other pixels: 3 of its 48 pixels differ from
    the scene's
    >>> print(describe_change(Circle(4e-3), Circle(4.0000001e-3)))
    circle face (radius 4 mm) with radius 0.004 m, the scene has 0.0040000001 m
    """
    was, now = old.describe(), new.describe()
    if was != now or type(old) is not type(new):
        return f"{was}, the scene has the {now}"
    if isinstance(old, MaskOutline) and old.mask.shape == new.mask.shape:
        differ = int(np.count_nonzero(old.mask != new.mask))
        if differ:
            return (f"{was} with other pixels: {differ} of its {old.mask.size} pixels differ "
                    f"from the scene's")
    changed = [f"{name} {value!r} {unit}, the scene has {new.parameters()[name][0]!r} {unit}"
               for name, (value, unit) in old.parameters().items()
               if new.parameters().get(name, (None,))[0] != value]
    if changed:
        return f"{was} with {'; '.join(changed)}"
    return f"{was}, the scene has another {now}"


def outline_from_table(table, base_dir="."):
    """The outline of a scene's ``[punch]`` table.

    Parameters
    ----------
    table : dict
        ``shape`` (default ``"circle"``) and the keys of that outline
        (:data:`OUTLINES`: ``Circle``: ``radius``; ``Rectangle``:
        ``width``, ``length``; ``PeriodicCell``: ``width``, ``length``;
        ``Ellipse``: ``semi_axis_x``,
        ``semi_axis_y``; ``Annulus``: ``inner_radius``, ``outer_radius``;
        ``MaskOutline``: ``path``, ``pixel_size``), lengths in m.
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
    context = Context(base_dir=pathlib.Path(base_dir), where="[punch]")
    try:
        return OUTLINES.build(table, context)
    except ValueError as err:
        message = str(err)
        raise ValueError(message if "[punch]" in message else f"[punch] {message}") from None
