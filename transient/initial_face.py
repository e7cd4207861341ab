"""Initial height fields of the punch face.

Every function returns the height ``h(x)`` of the face at the pixel centres
of the grid of a face outline (:class:`steady.outline.FaceGrid`: ``n``
pixels along the longer side of its bounding box; for a disk of radius
``a`` the ``n x n`` grid over ``[-a, a]^2`` of :mod:`steady.grid`), in
metres, with the convention of :func:`transient.contact.solve_contact`:
larger = farther from the counter-body (recessed).  Only differences
matter to the contact problem; the fields below are zero at the first
point of the ideal (continuum) face to touch.

A face is given as ``(n, outline)``: ``n`` the grid size (or a
:class:`~steady.outline.FaceGrid`, which carries its outline), ``outline``
an outline object of :mod:`steady.outline` or a number, the radius (m) of
a circular face.  ``flat(64, 4e-3)`` is the flat disk of radius 4 mm on
the 64 x 64 grid, ``flat(96, Rectangle(4e-3, 12e-3))`` the flat tread
block on its 32 x 96 grid.

Every shape is registered by the kind the scene section ``[initial_face]``
names (:data:`INITIAL_FACES`, :func:`register_initial_face`), with the
parameters it takes; :func:`initial_height` builds one by kind.  A kind may
also give the exact rms slope and rms height of its continuous face over the
outline (:func:`exact_statistics`), the values the run-in history starts
from (docs/model.md, "The run-in history").
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import scipy.integrate

from steady.outline import Annulus, Circle, Ellipse, FaceGrid, MaskOutline, Rectangle, as_outline

__all__ = [
    "INITIAL_FACES",
    "ExactStatistics",
    "InitialFaceKind",
    "circumradius",
    "crowned",
    "exact_statistics",
    "face_grid",
    "flat",
    "from_array",
    "from_file",
    "initial_height",
    "register_initial_face",
    "support",
    "tilted",
]


@dataclasses.dataclass(frozen=True)
class InitialFaceKind:
    """A registered initial face shape.

    Attributes
    ----------
    kind : str
        Its name in ``[initial_face] kind``.
    build : callable
        ``build(grid, outline, **parameters)``, returns the height on the
        grid, shape ``grid.shape``, m (``grid`` a
        :class:`~steady.outline.FaceGrid`, ``outline`` its outline).
    required, optional : tuple of str
        Its parameters (``path`` is a file name; every other one a number).
    statistics : callable or None
        ``statistics(outline, **parameters)``, the :class:`ExactStatistics` of
        the continuous face over the outline, or None when there is no
        closed form for that outline; None when there is none at all.
    """

    kind: str
    build: object
    required: tuple = ()
    optional: tuple = ()
    statistics: object = None


@dataclasses.dataclass(frozen=True)
class ExactStatistics:
    """Rms slope and rms height of a continuous initial face over its outline.

    Attributes
    ----------
    rms_slope : float
        Rms of ``|grad h|`` over the face (dimensionless).
    rms_height : float, m
        Rms of ``h`` about its least-squares plane over the face.
    """

    rms_slope: float
    rms_height: float


#: Registered initial face shapes by kind (see :func:`register_initial_face`).
INITIAL_FACES = {}


def register_initial_face(kind, *, required=(), optional=(), statistics=None):
    """Register ``build(n, outline, **parameters)`` as the initial face ``kind`` (a decorator).

    ``build`` is called with the :class:`~steady.outline.FaceGrid` and its
    outline.  ``statistics(outline, **parameters)``, if given, returns the
    face's :class:`ExactStatistics` (or None for an outline without a
    closed form).
    """
    def decorate(build):
        INITIAL_FACES[kind] = InitialFaceKind(kind, build, tuple(required), tuple(optional),
                                              statistics)
        return build
    return decorate


def exact_statistics(kind, outline, **parameters):
    """Exact rms slope and rms height over the face of a registered initial face.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is a disk's radius (m).
    **parameters
        The kind's parameters.

    Returns
    -------
    ExactStatistics or None
        None for a kind without a closed form (``"file"``; ``"crowned"`` on
        a face other than a disk): the run-in then measures its pixel
        heights (:func:`transient.history.face_statistics`).

    Examples
    --------
    >>> bool(exact_statistics("tilted", 4e-3, angle=0.01).rms_slope == np.tan(0.01))
    True
    >>> stats = exact_statistics("crowned", 4e-3, sphere_radius=8e-3)
    >>> print(f"{stats.rms_slope:.4f} {stats.rms_height * 1e6:.1f} um")
    0.3882 309.1 um
    """
    try:
        spec = INITIAL_FACES[kind]
    except KeyError:
        raise ValueError(f"initial face kind must be one of {sorted(INITIAL_FACES)}, "
                         f"got {kind!r}") from None
    if spec.statistics is None:
        return None
    return spec.statistics(as_outline(outline), **parameters)


def face_grid(n, outline=None):
    """The :class:`~steady.outline.FaceGrid` of a grid size and an outline, checked.

    Parameters
    ----------
    n : int or FaceGrid
        Pixels along the longer side of the outline's bounding box (across
        the diameter of a disk), or the grid itself.
    outline : outline object or float, optional
        The face; a number is a disk's radius (m).  Needed with an ``int``
        ``n``; with a grid, it must be the grid's outline if given.

    Returns
    -------
    FaceGrid

    Raises
    ------
    ValueError
        A grid size that is not an integer, a bad outline or radius, or a
        grid too coarse for the outline (naming ``n`` and the minimum).

    Examples
    --------
    >>> face_grid(16, 4e-3).shape
    (16, 16)
    """
    if isinstance(n, FaceGrid):
        if outline is not None and as_outline(outline) != n.outline:
            raise ValueError(f"the grid is of the {n.outline.describe()}, not of the "
                             f"{as_outline(outline).describe()}")
        return n
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, float, np.number)) \
            or int(n) != n:
        raise ValueError(f"grid size n must be an integer, got {n!r}")
    if outline is None:
        raise ValueError("an initial face needs the face's outline (or a disk's radius)")
    return FaceGrid(as_outline(outline), int(n))


def initial_height(kind, n, outline=None, **parameters):
    """Initial face height of a registered kind, checked.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    n : int or FaceGrid
        Pixels along the longer side of the face's bounding box (across the
        diameter of a disk), or the grid (then ``outline`` may be left out).
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is a disk's radius (m).
    **parameters
        The kind's parameters.

    Returns
    -------
    ndarray, shape of the grid (``(n, n)`` for a disk), m

    Examples
    --------
    >>> h = initial_height("tilted", 16, 4e-3, angle=1e-3)
    >>> h.shape, float(h.min()) >= 0.0
    ((16, 16), True)
    >>> from steady.outline import Rectangle
    >>> initial_height("flat", 48, Rectangle(4e-3, 12e-3)).shape
    (16, 48)
    """
    try:
        spec = INITIAL_FACES[kind]
    except KeyError:
        raise ValueError(f"initial face kind must be one of {sorted(INITIAL_FACES)}, "
                         f"got {kind!r}") from None
    grid = face_grid(n, outline)
    h = np.asarray(spec.build(grid, grid.outline, **parameters), dtype=float)
    if h.shape != grid.shape:
        raise ValueError(f"initial face has shape {h.shape}, expected {grid.shape}")
    return h


def _coordinates(grid):
    return np.meshgrid(grid.x, grid.y, indexing="ij")


def support(outline, direction):
    """``max (x, y) . direction`` over the face, m: how far it reaches along a unit vector.

    Exact for the disk, the annulus, the rectangle and the ellipse, and
    for a mask (its pixels' corners); otherwise the largest value over the
    pixel corners of a fine grid's face.

    Parameters
    ----------
    outline : outline object
    direction : (float, float)
        A unit vector.

    Returns
    -------
    float

    Examples
    --------
    >>> from steady.outline import Rectangle
    >>> print(f"{support(Rectangle(4e-3, 12e-3), (0.6, 0.8)) * 1e3:.3f} mm")
    6.000 mm
    """
    ux, uy = (float(v) for v in direction)
    if isinstance(outline, Circle):
        return outline.radius
    if isinstance(outline, Annulus):
        return outline.outer_radius
    lx, ly = outline.half_extent
    if isinstance(outline, Rectangle):
        return lx * abs(ux) + ly * abs(uy)
    if isinstance(outline, Ellipse):
        return math.hypot(lx * ux, ly * uy)
    x0, x1, y0, y1 = _pixel_edges(outline)
    return float(np.max(np.maximum(x0 * ux, x1 * ux) + np.maximum(y0 * uy, y1 * uy)))


def circumradius(outline):
    """Largest distance of the face from its centre, m (the radius of a disk).

    Exact for the disk, the annulus, the rectangle and the ellipse, and
    for a mask (its pixels' corners); otherwise over the pixel corners of a
    fine grid's face.
    """
    if isinstance(outline, Circle):
        return outline.radius
    if isinstance(outline, Annulus):
        return outline.outer_radius
    lx, ly = outline.half_extent
    if isinstance(outline, Rectangle):
        return math.hypot(lx, ly)
    if isinstance(outline, Ellipse):
        return max(lx, ly)
    x0, x1, y0, y1 = _pixel_edges(outline)
    return float(np.sqrt(np.max(np.maximum(x0**2, x1**2) + np.maximum(y0**2, y1**2))))


def _pixel_edges(outline):
    """Lower and upper x and y edges of the face's pixels, m (one entry per pixel).

    A mask's own pixels; for another outline, those of its face on a grid
    of at least 512 pixels.
    """
    if isinstance(outline, MaskOutline):
        lx, ly = outline.half_extent
        i, j = np.nonzero(outline.mask)
        ps = outline.pixel_size
        x0, y0 = -lx + i * ps, -ly + j * ps
        return x0, x0 + ps, y0, y0 + ps
    grid = FaceGrid(outline, max(512, outline.min_grid()))
    i, j = np.nonzero(grid.mask)
    half = 0.5 * grid.h
    x, y = grid.x[i], grid.y[j]
    return x - half, x + half, y - half, y + half


def _flat_statistics(outline):
    return ExactStatistics(rms_slope=0.0, rms_height=0.0)


@register_initial_face("flat", statistics=_flat_statistics)
def flat(n, outline=None):
    """Flat face.

    Parameters
    ----------
    n : int or FaceGrid
        Pixels along the longer side of the face's bounding box (across the
        diameter of a disk), or the grid.
    outline : outline object or float
        The face; a number is the punch radius ``a`` (m) of a disk.

    Returns
    -------
    ndarray, shape of the grid (``(n, n)`` for a disk), m
        Zeros.
    """
    grid = face_grid(n, outline)
    return np.zeros(grid.shape)


def _tilted_statistics(outline, angle, azimuth=0.0):
    return ExactStatistics(rms_slope=float(np.tan(angle)), rms_height=0.0)


@register_initial_face("tilted", required=("angle",), optional=("azimuth",),
                       statistics=_tilted_statistics)
def tilted(n, outline=None, angle=None, azimuth=0.0):
    """Flat face tilted by ``angle`` so that it recedes towards ``azimuth``.

    Parameters
    ----------
    n : int or FaceGrid
    outline : outline object or float
        The face; a number is the punch radius ``a`` (m) of a disk.
    angle : float, rad
        Tilt, ``0 <= angle < pi/2``.
    azimuth : float, rad, optional
        Direction (from the x axis) in which the face recedes; default 0.

    Returns
    -------
    ndarray, shape of the grid, m
        ``tan(angle) * (x cos(azimuth) + y sin(azimuth) + d)``, ``d`` how
        far the face reaches opposite the azimuth (:func:`support`; ``a``
        for a disk): zero at the face's point that leads, largest at the
        other end (``2 a tan(angle)`` for a disk).  Under load a rigid flat
        disk tilted this way (with no rotation allowed) stays in full
        contact while ``tan(angle) < F / (4 a^2 E*)``; above that the
        recessed side lifts off.
    """
    grid = face_grid(n, outline)
    if angle is None or not (np.isfinite(angle) and 0 <= angle < np.pi / 2):
        raise ValueError(f"angle must lie in [0, pi/2), got {angle!r} rad")
    if not np.isfinite(azimuth):
        raise ValueError(f"azimuth must be finite, got {azimuth!r} rad")
    c, s = np.cos(azimuth), np.sin(azimuth)
    X, Y = _coordinates(grid)
    return np.tan(angle) * (X * c + Y * s + support(grid.outline, (-c, -s)))


def _crowned_statistics(outline, sphere_radius):
    """Sphere cap ``R - sqrt(R^2 - r^2)`` over the disk ``r < a``; None for other outlines.

    Mean-square slope ``(2/a^2) int_0^a r^3 / (R^2 - r^2) dr
    = (R/a)^2 (-ln(1 - x) - x)``, ``x = (a/R)^2`` (infinite for ``R = a``);
    the rms height (the best plane of a radial face is a constant) by
    adaptive quadrature of the cap, written ``r^2 / (R + sqrt(R^2 - r^2))``
    to avoid cancellation.
    """
    if not isinstance(outline, Circle):
        return None
    a, big = outline.radius, float(sphere_radius)
    x = (a / big) ** 2
    mean_square = (-math.log1p(-x) - x) / x if x < 1 else math.inf

    def cap(r):
        return r * r / (big + math.sqrt(max(big * big - r * r, 0.0)))

    def disk_mean(f):
        return 2.0 / a**2 * scipy.integrate.quad(lambda r: f(r) * r, 0.0, a, epsabs=0.0,
                                                 epsrel=1e-12)[0]

    mean = disk_mean(cap)
    variance = disk_mean(lambda r: (cap(r) - mean) ** 2)
    return ExactStatistics(rms_slope=math.sqrt(mean_square), rms_height=math.sqrt(variance))


@register_initial_face("crowned", required=("sphere_radius",), statistics=_crowned_statistics)
def crowned(n, outline=None, sphere_radius=None):
    """Spherical cap: the face crowned to a sphere of radius ``sphere_radius``.

    Parameters
    ----------
    n : int or FaceGrid
    outline : outline object or float
        The face; a number is the punch radius ``a`` (m) of a disk.
    sphere_radius : float, m
        Radius of the sphere, centred over the face's centre; at least the
        punch radius (for other outlines, the largest distance of the face
        from its centre, :func:`circumradius`).

    Returns
    -------
    ndarray, shape of the grid, m
        ``R - sqrt(R^2 - r^2)`` (exact sphere; Hertz theory uses its
        paraboloid ``r^2 / (2 R)``, which differs by ``r^4 / (8 R^3)``).
        Off the sphere's footprint (``r >= R``, off the face) the
        paraboloid continues it.
    """
    grid = face_grid(n, outline)
    outline = grid.outline
    reach = circumradius(outline)
    if sphere_radius is None or not (np.isfinite(sphere_radius) and sphere_radius >= reach):
        what = (f"the punch radius {outline.radius!r} m" if isinstance(outline, Circle) else
                f"the largest distance {reach:.6g} m of the {outline.describe()} from its "
                f"centre")
        raise ValueError(f"sphere_radius must be finite and at least {what}, got "
                         f"{sphere_radius!r} m")
    X, Y = _coordinates(grid)
    r2 = X**2 + Y**2
    inside = r2 < sphere_radius**2
    cap = sphere_radius - np.sqrt(np.where(inside, sphere_radius**2 - r2, 0.0))
    return np.where(inside, cap, r2 / (2 * sphere_radius))


def from_array(values, n, outline=None):
    """Height field given pixel by pixel.

    Parameters
    ----------
    values : array_like, shape of the grid, m
        Heights at the pixel centres; finite on the face (values off the
        face are kept as given and ignored by the contact solver).
    n : int or FaceGrid
        Expected grid size (or the grid).
    outline : outline object or float, optional
        The face (default: a disk, ``n x n`` pixels).

    Returns
    -------
    ndarray, shape of the grid (``(n, n)`` for a disk), m
        A float copy.
    """
    grid = face_grid(n, 1.0 if outline is None and not isinstance(n, FaceGrid) else outline)
    values = np.array(values, dtype=float)
    if values.shape != grid.shape:
        raise ValueError(f"height field must have shape {grid.shape}, got {values.shape}")
    bad = ~np.isfinite(values[grid.mask])
    if bad.any():
        raise ValueError(f"height field must be finite on the face, got {int(bad.sum())} "
                         "non-finite values")
    return values


def from_file(path, n, outline=None):
    """Height field (m) read from a ``.npy`` file; see :func:`from_array`.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.npy`` file holding a float array of the grid's shape
        (``(n, n)`` for a disk), metres.
    n : int or FaceGrid
        Expected grid size (or the grid).
    outline : outline object or float, optional
        The face (default: a disk).

    Returns
    -------
    ndarray, shape of the grid, m
    """
    path = os.fspath(path)
    if not path.endswith(".npy"):
        raise ValueError(f"height file must be a .npy file, got {path!r}")
    values = np.load(path, allow_pickle=False)
    return from_array(values, n, outline)


@register_initial_face("file", required=("path",))
def _file(n, outline, path):
    """Height field of a ``.npy`` file (the scene's ``kind = "file"``)."""
    return from_file(path, n, outline)
