"""Initial recession fields of the punch face.

Every function returns the recession ``h(x)`` of the face at the pixel centres
of the grid of a face outline (:class:`steady.outline.FaceGrid`:
``outline.grid(n)``, ``n`` pixels along the longer side of its bounding
box), in metres, with the convention of
:func:`transient.contact.solve_contact`: larger = farther from the
counter-body (recessed).  Only differences matter to the contact problem;
the fields below are zero at the first point of the ideal (continuum) face
to touch.  ``flat(Circle(4e-3).grid(64))`` is the flat disk of radius 4 mm
on the 64 x 64 grid, ``flat(Rectangle(4e-3, 12e-3).grid(96))`` the flat
tread block on its 32 x 96 grid.

Every shape is registered in :data:`INITIAL_FACES` (a
:class:`steady.schema.KindRegistry`) by the kind the scene section
``[initial_face]`` names, with its keys; :func:`initial_recession` builds one
by kind.  A kind may also give the exact rms slope and rms height of its
continuous face over the outline (:func:`exact_statistics`), the values the
run-in history starts from (docs/model.md, "The run-in history").

On a periodic cell (an outline whose ``periodic`` is True) the face repeats
with the cell: a kind whose face does not (``"tilted"``, ``"crowned"``)
would leave a seam at the cell's edges and is refused
(:func:`check_outline`); ``"flat"`` repeats, and a face read from a file
(``"file"``, a measured patch) is taken as periodic as it stands.
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np

from steady.array_files import REAL_NUMBERS, read_npy
from steady.outline import FaceGrid, as_outline
from steady.schema import Key, KindRegistry

__all__ = [
    "INITIAL_FACES",
    "ExactStatistics",
    "check_outline",
    "crowned",
    "exact_statistics",
    "flat",
    "from_array",
    "from_file",
    "initial_recession",
    "tilted",
]

#: Registered initial faces by ``[initial_face] kind`` (default ``"flat"``): functions
#: ``build(grid, **parameters)`` with the attributes ``kind``, ``keys``,
#: ``statistics`` (``statistics(outline, **parameters)``, the
#: :class:`ExactStatistics` of the continuous face over an outline, or None) and
#: ``periodic`` (whether the face repeats with a periodic cell, built on one).
INITIAL_FACES = KindRegistry("initial face", "kind", default="flat",
                             entry_point_group="runin.initial_faces")


def _register(kind, keys=(), statistics=None, periodic=False, doc=""):
    """Register ``build(grid, **parameters)`` as the initial face ``kind`` with its keys.

    ``periodic``: whether the face built on a periodic cell repeats with it
    (default False: refused on a cell, :func:`check_outline`).
    """
    def decorate(build):
        build = INITIAL_FACES.register(kind, keys, doc=doc)(build)
        build.statistics = statistics
        build.periodic = periodic
        return build
    return decorate


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
        recessions (:func:`transient.history.face_statistics`).

    Examples
    --------
    >>> from steady.outline import Circle
    >>> bool(exact_statistics("tilted", Circle(4e-3), angle=0.01).rms_slope == np.tan(0.01))
    True
    >>> stats = exact_statistics("crowned", Circle(4e-3), sphere_radius=8e-3)
    >>> print(f"{stats.rms_slope:.4f} {stats.rms_height * 1e6:.1f} um")
    0.3882 309.1 um
    """
    build = _kind(kind)
    if build.statistics is None:
        return None
    return build.statistics(as_outline(outline), **parameters)


def _kind(kind):
    """The registered initial face ``kind``; ``ValueError`` naming the kinds."""
    if kind not in INITIAL_FACES:
        raise ValueError(f"initial face kind must be one of {sorted(INITIAL_FACES)}, "
                         f"got {kind!r}")
    return INITIAL_FACES[kind]


def _grid(grid, kind=None):
    """``grid`` checked to be a :class:`~steady.outline.FaceGrid` that ``kind`` may be built on.

    Without ``kind`` (a field given pixel by pixel) any grid is accepted.
    """
    if not isinstance(grid, FaceGrid):
        raise ValueError(f"an initial face is built on a face's grid (outline.grid(n)), got "
                         f"{type(grid).__name__}")
    if kind is not None:
        check_outline(kind, grid.outline)
    return grid


def check_outline(kind, outline):
    """Refuse an initial face ``kind`` that does not repeat with a periodic cell.

    A face built on a periodic cell (``outline.periodic``) must repeat with
    it, or it leaves a seam at the cell's edges (a tilt or a crown jumps
    there); every kind is accepted on a finite face.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    outline : outline object
        The face (:mod:`steady.outline`).

    Raises
    ------
    ValueError
        ``kind`` unknown, or not periodic on a periodic cell: the message
        names the kind, the shape ``"periodic"`` and the kinds accepted.

    Examples
    --------
    >>> from steady.outline import Circle, PeriodicCell
    >>> check_outline("crowned", Circle(4e-3))
    >>> check_outline("crowned", PeriodicCell(8e-3, 8e-3))
    Traceback (most recent call last):
    ...
    ValueError: initial face kind 'crowned' on [punch] shape = "periodic": its face does not \
repeat with the cell and would leave a seam at the cell's edges; a periodic cell takes \
kind 'file' or 'flat'
    """
    if outline.periodic and not _kind(kind).periodic:
        accepted = " or ".join(repr(k) for k in sorted(INITIAL_FACES)
                               if INITIAL_FACES[k].periodic)
        raise ValueError(f"initial face kind {kind!r} on [punch] shape = \"periodic\": its face "
                         f"does not repeat with the cell and would leave a seam at the cell's "
                         f"edges; a periodic cell takes kind {accepted}")


def initial_recession(kind, grid, **parameters):
    """Initial face recession of a registered kind, checked.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    grid : steady.outline.FaceGrid
        The face's grid (``outline.grid(n)``).
    **parameters
        The kind's parameters.

    Returns
    -------
    ndarray, shape of the grid (``(n, n)`` for a disk), m

    Examples
    --------
    >>> from steady.outline import Circle, Rectangle
    >>> h = initial_recession("tilted", Circle(4e-3).grid(16), angle=1e-3)
    >>> h.shape, float(h.min()) >= 0.0
    ((16, 16), True)
    >>> initial_recession("flat", Rectangle(4e-3, 12e-3).grid(48)).shape
    (16, 48)
    """
    build = _kind(kind)
    grid = _grid(grid, kind)
    h = np.asarray(build(grid, **parameters), dtype=float)
    if h.shape != grid.shape:
        raise ValueError(f"initial face has shape {h.shape}, expected {grid.shape}")
    return h


def _coordinates(grid):
    return np.meshgrid(grid.x, grid.y, indexing="ij")


def _flat_statistics(outline):
    return ExactStatistics(rms_slope=0.0, rms_height=0.0)


@_register("flat", statistics=_flat_statistics, periodic=True, doc="a flat face (default)")
def flat(grid):
    """Flat face.

    Parameters
    ----------
    grid : steady.outline.FaceGrid

    Returns
    -------
    ndarray, shape of the grid, m
        Zeros.
    """
    return np.zeros(_grid(grid).shape)


def _tilted_statistics(outline, angle, azimuth=0.0):
    return ExactStatistics(rms_slope=float(np.tan(angle)), rms_height=0.0)


@_register("tilted", (
    Key("angle", "number", unit="rad", low=0.0, low_open=False, high=math.pi / 2,
        required=True, doc="tilt"),
    Key("azimuth", "number", unit="rad", default=0.0,
        doc="direction (from the x axis) in which the face recedes")),
    statistics=_tilted_statistics,
    doc="a flat face tilted towards an azimuth (not on a periodic cell)")
def tilted(grid, angle, azimuth=0.0):
    """Flat face tilted by ``angle`` so that it recedes towards ``azimuth``.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
    angle : float, rad
        Tilt, ``0 <= angle < pi/2``.
    azimuth : float, rad, optional
        Direction (from the x axis) in which the face recedes; default 0.

    Returns
    -------
    ndarray, shape of the grid, m
        ``tan(angle) * (x cos(azimuth) + y sin(azimuth) + d)``, ``d`` how
        far the face reaches opposite the azimuth (the outline's
        ``support``; ``a`` for a disk): zero at the face's point that leads, largest at the
        other end (``2 a tan(angle)`` for a disk).  Under load a rigid flat
        disk tilted this way (with no rotation allowed) stays in full
        contact while ``tan(angle) < F / (4 a^2 E*)``; above that the
        recessed side lifts off.

    Raises
    ------
    ValueError
        ``angle`` or ``azimuth`` out of range; a periodic cell's grid
        (:func:`check_outline`: a tilt does not repeat with the cell).
    """
    grid = _grid(grid, "tilted")
    if angle is None or not (np.isfinite(angle) and 0 <= angle < np.pi / 2):
        raise ValueError(f"angle must lie in [0, pi/2), got {angle!r} rad")
    if not np.isfinite(azimuth):
        raise ValueError(f"azimuth must be finite, got {azimuth!r} rad")
    c, s = np.cos(azimuth), np.sin(azimuth)
    X, Y = _coordinates(grid)
    return np.tan(angle) * (X * c + Y * s + grid.outline.support((-c, -s)))


def _crowned_statistics(outline, sphere_radius):
    """The sphere cap's exact statistics over the face (``outline.cap_statistics``), or None."""
    stats = outline.cap_statistics(sphere_radius)
    return None if stats is None else ExactStatistics(rms_slope=stats[0], rms_height=stats[1])


@_register("crowned", (
    Key("sphere_radius", "number", unit="m", low=0.0, required=True,
        doc="radius of the sphere, at least the face's largest distance from its centre"),),
    statistics=_crowned_statistics, doc="a face crowned to a sphere (not on a periodic cell)")
def crowned(grid, sphere_radius):
    """Spherical cap: the face crowned to a sphere of radius ``sphere_radius``.

    Parameters
    ----------
    grid : steady.outline.FaceGrid
    sphere_radius : float, m
        Radius of the sphere, centred over the face's centre; at least the
        punch radius (for other outlines, the largest distance of the face
        from its centre, the outline's ``circumradius``).

    Returns
    -------
    ndarray, shape of the grid, m
        ``R - sqrt(R^2 - r^2)`` (exact sphere; Hertz theory uses its
        paraboloid ``r^2 / (2 R)``, which differs by ``r^4 / (8 R^3)``).
        Off the sphere's footprint (``r >= R``, off the face) the
        paraboloid continues it.

    Raises
    ------
    ValueError
        ``sphere_radius`` below the face's reach; a periodic cell's grid
        (:func:`check_outline`: a crown does not repeat with the cell).
    """
    grid = _grid(grid, "crowned")
    outline = grid.outline
    reach = outline.circumradius()
    if sphere_radius is None or not (np.isfinite(sphere_radius) and sphere_radius >= reach):
        raise ValueError(f"sphere_radius must be finite and at least the largest distance "
                         f"{reach:.6g} m of the {outline.describe()} from its centre, got "
                         f"{sphere_radius!r} m")
    X, Y = _coordinates(grid)
    r2 = X**2 + Y**2
    inside = r2 < sphere_radius**2
    cap = sphere_radius - np.sqrt(np.where(inside, sphere_radius**2 - r2, 0.0))
    return np.where(inside, cap, r2 / (2 * sphere_radius))


def from_array(values, grid):
    """Height field given pixel by pixel (on a periodic cell taken as periodic, as it stands).

    Parameters
    ----------
    values : array_like, shape of the grid, m
        Heights at the pixel centres; finite on the face (values off the
        face are kept as given and ignored by the contact solver).
    grid : steady.outline.FaceGrid

    Returns
    -------
    ndarray, shape of the grid, m
        A float copy.
    """
    grid = _grid(grid)
    values = np.asarray(values)
    REAL_NUMBERS.check(values.dtype, "recession field")
    values = np.array(values, dtype=float)
    if values.shape != grid.shape:
        raise ValueError(f"recession field must have shape {grid.shape}, got {values.shape}")
    bad = ~np.isfinite(values[grid.mask])
    if bad.any():
        raise ValueError(f"recession field must be finite on the face, got {int(bad.sum())} "
                         "non-finite values")
    return values


@_register("file", (Key("path", "path", required=True,
                         doc=".npy recession field, m, on the grid (n x n for a disk)"),),
           periodic=True,
           doc="a recession field read from a .npy file (on a periodic cell, taken as periodic)")
def from_file(grid, path):
    """Recession field (m, larger = recessed) read from a ``.npy`` file; see :func:`from_array`.

    On a periodic cell the field is taken as periodic, as it stands (a
    measured patch of the surface): its last row and column neighbour its
    first, and nothing checks that they join without a step.

    The file is checked before its data are read
    (:func:`steady.array_files.read_npy`: a wrong shape, an empty or
    truncated file are refused naming it).

    Parameters
    ----------
    grid : steady.outline.FaceGrid
    path : str or os.PathLike
        A ``.npy`` file holding a float array of the grid's shape
        (``(n, n)`` for a disk), metres.

    Returns
    -------
    ndarray, shape of the grid, m
    """
    grid = _grid(grid)
    path = os.fspath(path)
    if not path.endswith(".npy"):
        raise ValueError(f"recession file must be a .npy file, got {path!r}")
    values = read_npy(path, what="initial face file", holds=REAL_NUMBERS, shape=grid.shape,
                      square=False)
    try:
        return from_array(values, grid)
    except ValueError as err:  # NaN on the face: the file is what to fix
        raise ValueError(f"initial face file {path!r}: {err}") from None
