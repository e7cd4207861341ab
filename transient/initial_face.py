"""Initial height fields of the punch face.

Every function returns the height ``h(x)`` of the face at the pixel centres
of the ``n x n`` grid covering ``[-a, a]^2`` (:mod:`steady.grid`), in
metres, with the convention of :func:`transient.contact.solve_contact`:
larger = farther from the counter-body (recessed).  Only differences
matter to the contact problem; the fields below are zero at the first
point of the ideal (continuum) face to touch.

Every shape is registered by the kind the scene section ``[initial_face]``
names (:data:`INITIAL_FACES`, :func:`register_initial_face`), with the
parameters it takes; :func:`initial_height` builds one by kind.  A kind may
also give the exact rms slope and rms height of its continuous face over the
disk (:func:`exact_statistics`), the values the run-in history starts from
(docs/model.md, "The run-in history").
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import scipy.integrate

from steady.grid import face_mask, pixel_centres

__all__ = [
    "INITIAL_FACES",
    "ExactStatistics",
    "InitialFaceKind",
    "crowned",
    "exact_statistics",
    "flat",
    "from_array",
    "from_file",
    "initial_height",
    "register_initial_face",
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
        ``build(n, radius, **parameters)``, returns the height, shape (n, n), m.
    required, optional : tuple of str
        Its parameters (``path`` is a file name; every other one a number).
    statistics : callable or None
        ``statistics(radius, **parameters)``, the :class:`ExactStatistics` of
        the continuous face over the disk; None when there is no closed form.
    """

    kind: str
    build: object
    required: tuple = ()
    optional: tuple = ()
    statistics: object = None


@dataclasses.dataclass(frozen=True)
class ExactStatistics:
    """Rms slope and rms height of a continuous initial face over the disk.

    Attributes
    ----------
    rms_slope : float
        Rms of ``|grad h|`` over the disk (dimensionless).
    rms_height : float, m
        Rms of ``h`` about its least-squares plane over the disk.
    """

    rms_slope: float
    rms_height: float


#: Registered initial face shapes by kind (see :func:`register_initial_face`).
INITIAL_FACES = {}


def register_initial_face(kind, *, required=(), optional=(), statistics=None):
    """Register ``build(n, radius, **parameters)`` as the initial face ``kind`` (a decorator).

    ``statistics(radius, **parameters)``, if given, returns the face's
    :class:`ExactStatistics`.
    """
    def decorate(build):
        INITIAL_FACES[kind] = InitialFaceKind(kind, build, tuple(required), tuple(optional),
                                              statistics)
        return build
    return decorate


def exact_statistics(kind, radius, **parameters):
    """Exact rms slope and rms height over the disk of a registered initial face.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    radius : float, m
    **parameters
        The kind's parameters.

    Returns
    -------
    ExactStatistics or None
        None for a kind without a closed form (``"file"``: the run-in then
        measures its pixel heights, :func:`transient.history.face_statistics`).

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
    return spec.statistics(float(radius), **parameters)


def initial_height(kind, n, radius, **parameters):
    """Initial face height of a registered kind, checked.

    Parameters
    ----------
    kind : str
        A key of :data:`INITIAL_FACES`.
    n : int
        Pixels across the diameter.
    radius : float, m
    **parameters
        The kind's parameters.

    Returns
    -------
    ndarray, shape (n, n), m

    Examples
    --------
    >>> h = initial_height("tilted", 16, 4e-3, angle=1e-3)
    >>> h.shape, float(h.min()) >= 0.0
    ((16, 16), True)
    """
    try:
        spec = INITIAL_FACES[kind]
    except KeyError:
        raise ValueError(f"initial face kind must be one of {sorted(INITIAL_FACES)}, "
                         f"got {kind!r}") from None
    h = np.asarray(spec.build(n, radius, **parameters), dtype=float)
    if h.shape != (n, n):
        raise ValueError(f"initial face has shape {h.shape}, expected {(n, n)}")
    return h


def _check_grid(n, radius):
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ValueError(f"grid size n must be an integer >= 2, got {n!r}")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be positive and finite, got {radius!r} m")
    return int(n), float(radius)


def _coordinates(n, radius):
    x = pixel_centres(n, radius)
    return np.meshgrid(x, x, indexing="ij")


def _flat_statistics(radius):
    return ExactStatistics(rms_slope=0.0, rms_height=0.0)


@register_initial_face("flat", statistics=_flat_statistics)
def flat(n, radius):
    """Flat face.

    Parameters
    ----------
    n : int
        Pixels across the diameter.
    radius : float, m
        Punch radius ``a``.

    Returns
    -------
    ndarray, shape (n, n), m
        Zeros.
    """
    n, radius = _check_grid(n, radius)
    return np.zeros((n, n))


def _tilted_statistics(radius, angle, azimuth=0.0):
    return ExactStatistics(rms_slope=float(np.tan(angle)), rms_height=0.0)


@register_initial_face("tilted", required=("angle",), optional=("azimuth",),
                       statistics=_tilted_statistics)
def tilted(n, radius, angle, azimuth=0.0):
    """Flat face tilted by ``angle`` so that it recedes towards ``azimuth``.

    Parameters
    ----------
    n : int
    radius : float, m
    angle : float, rad
        Tilt, ``0 <= angle < pi/2``.
    azimuth : float, rad, optional
        Direction (from the x axis) in which the face recedes; default 0.

    Returns
    -------
    ndarray, shape (n, n), m
        ``tan(angle) * (x cos(azimuth) + y sin(azimuth) + a)``: zero at the
        rim point opposite ``azimuth``, ``2 a tan(angle)`` at the other
        end.  Under load a rigid flat punch tilted this way (with no
        rotation allowed) stays in full contact while
        ``tan(angle) < F / (4 a^2 E*)``; above that the recessed side lifts
        off.
    """
    n, radius = _check_grid(n, radius)
    if not (np.isfinite(angle) and 0 <= angle < np.pi / 2):
        raise ValueError(f"angle must lie in [0, pi/2), got {angle!r} rad")
    if not np.isfinite(azimuth):
        raise ValueError(f"azimuth must be finite, got {azimuth!r} rad")
    X, Y = _coordinates(n, radius)
    return np.tan(angle) * (X * np.cos(azimuth) + Y * np.sin(azimuth) + radius)


def _crowned_statistics(radius, sphere_radius):
    """Sphere cap ``R - sqrt(R^2 - r^2)`` over the disk ``r < a``.

    Mean-square slope ``(2/a^2) int_0^a r^3 / (R^2 - r^2) dr
    = (R/a)^2 (-ln(1 - x) - x)``, ``x = (a/R)^2`` (infinite for ``R = a``);
    the rms height (the best plane of a radial face is a constant) by
    adaptive quadrature of the cap, written ``r^2 / (R + sqrt(R^2 - r^2))``
    to avoid cancellation.
    """
    a, big = float(radius), float(sphere_radius)
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
def crowned(n, radius, sphere_radius):
    """Spherical cap: the face crowned to a sphere of radius ``sphere_radius``.

    Parameters
    ----------
    n : int
    radius : float, m
    sphere_radius : float, m
        Radius of the sphere, at least the punch radius.

    Returns
    -------
    ndarray, shape (n, n), m
        ``R - sqrt(R^2 - r^2)`` (exact sphere; Hertz theory uses its
        paraboloid ``r^2 / (2 R)``, which differs by ``r^4 / (8 R^3)``).
        Off the disk the paraboloid continues it.
    """
    n, radius = _check_grid(n, radius)
    if not (np.isfinite(sphere_radius) and sphere_radius >= radius):
        raise ValueError(
            f"sphere_radius must be finite and at least the punch radius {radius!r} m, "
            f"got {sphere_radius!r} m")
    X, Y = _coordinates(n, radius)
    r2 = X**2 + Y**2
    inside = r2 < sphere_radius**2
    cap = sphere_radius - np.sqrt(np.where(inside, sphere_radius**2 - r2, 0.0))
    return np.where(inside, cap, r2 / (2 * sphere_radius))


def from_array(values, n):
    """Height field given pixel by pixel.

    Parameters
    ----------
    values : array_like, shape (n, n), m
        Heights at the pixel centres; finite on the face (values off the
        face are kept as given and ignored by the contact solver).
    n : int
        Expected grid size.

    Returns
    -------
    ndarray, shape (n, n), m
        A float copy.
    """
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ValueError(f"grid size n must be an integer >= 2, got {n!r}")
    n = int(n)
    values = np.array(values, dtype=float)
    if values.shape != (n, n):
        raise ValueError(f"height field must have shape {(n, n)}, got {values.shape}")
    bad = ~np.isfinite(values[face_mask(n)])
    if bad.any():
        raise ValueError(f"height field must be finite on the face, got {int(bad.sum())} "
                         "non-finite values")
    return values


def from_file(path, n):
    """Height field (m) read from a ``.npy`` file; see :func:`from_array`.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.npy`` file holding an ``(n, n)`` float array, metres.
    n : int
        Expected grid size.

    Returns
    -------
    ndarray, shape (n, n), m
    """
    path = os.fspath(path)
    if not path.endswith(".npy"):
        raise ValueError(f"height file must be a .npy file, got {path!r}")
    values = np.load(path, allow_pickle=False)
    return from_array(values, n)


@register_initial_face("file", required=("path",))
def _file(n, radius, path):
    """Height field of a ``.npy`` file (the scene's ``kind = "file"``)."""
    return from_file(path, n)
