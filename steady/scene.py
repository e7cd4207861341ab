"""Scene files: one TOML file describes one punch, load, counter-body and grid.

Example (every key of the core sections)::

    [punch]
    radius = 0.004                      # m (a circular face; see below)
    [load]
    normal_force = 10.0                 # N
    [counterbody]
    E_star = 1.3e6                      # Pa
    [grid]
    n = 256                             # pixels across the diameter
    [wear]
    coefficients = [1.0e-9, 1.7e-9]     # 1/Pa, one per phase
    exponent = 1.0                      # optional, default 1 (Archard)
    [phases]
    map = { kind = "file", path = "phases.npy" }

Face outlines (``[punch]``, :mod:`steady.outline`): ``shape`` is
``"circle"`` (default; ``radius``), ``"rectangle"`` (``width`` along x,
``length`` along y), ``"ellipse"`` (``semi_axis_x``, ``semi_axis_y``),
``"annulus"`` (``inner_radius``, ``outer_radius``) or ``"mask"`` (``path``
to a ``.npy`` or ``.png`` face mask, ``pixel_size`` in m); lengths in m.
``[grid] n`` counts pixels along the longer side of the face's bounding
box (across the diameter of a disk), and phase geometries are in units of
the outline's scale ``L`` (the radius of a disk; else the larger half side
of the bounding box).

Map kinds (``[phases] map``):

- ``{ kind = "homogeneous" }``
- ``{ kind = "voronoi", n_seeds = 1600, fill_factors = [0.5, 0.5], seed = 2024 }``
- ``{ kind = "rods", centres = [[0.0, 0.0], ...], radii = [0.0025, ...],
  matrix_phase = 0, rod_phases = [1, ...] }`` -- centres and radii in m
  (like ``[punch] radius``); ``matrix_phase`` (default 0) and
  ``rod_phases`` (default 1 for every rod) optional.
- ``{ kind = "inclusions", radius = 0.0002, fill_factor = 0.2, seed = 2024 }``
  -- random non-overlapping circular inclusions (phase 1) in a matrix
  (phase 0); ``radius`` is the mean radius in m; ``count`` (expected
  inclusion centres on the face) instead of ``fill_factor``;
  ``radius_spread`` (relative standard deviation of log-normal radii,
  default 0) optional (see :class:`steady.inclusions.Inclusions`).
- ``{ kind = "file", path = "phases.npy" }`` -- ``.npy`` or ``.png``, the
  path relative to the scene file (see :func:`steady.phases.load_phase_map`).
- ``{ kind = "micrograph", path = "grains.png", n_phases = 2, smoothing = 1.0,
  min_speck = 20, pixel_size = 2e-6, cover = "crop", offset = [0.0, 0.0] }``
  -- a grey-level image segmented into ``n_phases`` phases; ``smoothing``
  (Gaussian sigma, pixels, default 0), ``min_speck`` (pixels, default 0),
  ``pixel_size`` (m, default: a square image spans the diameter), ``cover``
  (``"crop"``, default, or ``"tile"``) and ``offset`` (m, default centred)
  optional (see :func:`steady.micrograph.load_micrograph`).

Every key is checked; unknown sections and keys are errors, so that a typo
cannot pass silently.  Other packages can add sections through
``extra_sections``; this module knows nothing of their contents.  The
sections of the run-in (:data:`RUN_IN_SECTIONS`), when no parser is given
for them, are recorded in ``Scene.ignored_sections`` and otherwise left
alone, so that one scene file serves the steady and the run-in commands.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import stat
import types

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .inclusions import Inclusions
from .micrograph import load_micrograph
from .outline import Circle, FaceGrid, outline_from_table
from .phases import Homogeneous, Rods, Voronoi, load_phase_map, validate_labels
from .text import one_line, shorten

__all__ = ["CORE_SECTIONS", "MAX_SCENE_BYTES", "RUN_IN_SECTIONS", "Scene", "load_scene",
           "parse_scene"]

#: Largest scene file read, bytes: a scene is a few lines; large data belong in
#: ``.npy`` files (a 40 MB list would take Python's TOML parser half a minute).
MAX_SCENE_BYTES = 2 ** 20

#: Sections every scene file has, with their keys (required, optional).
CORE_SECTIONS = {
    "punch": (set(), {"shape"}),  # and the keys of the shape (steady.outline)
    "load": ({"normal_force"}, set()),
    "counterbody": ({"E_star"}, set()),
    "grid": ({"n"}, set()),
    "wear": ({"coefficients"}, {"exponent"}),
    "phases": ({"map"}, set()),
}

#: Sections read by the run-in command (package ``transient``).  Without a
#: parser for them in ``extra_sections`` they are skipped, not refused: the
#: steady state does not depend on them.  Only the names are known here.
RUN_IN_SECTIONS = ("initial_face", "transient")

_MAP_KEYS = {
    "homogeneous": (set(), set()),
    "voronoi": ({"n_seeds", "fill_factors", "seed"}, set()),
    "rods": ({"centres", "radii"}, {"matrix_phase", "rod_phases"}),
    "inclusions": ({"radius", "seed"}, {"fill_factor", "count", "radius_spread"}),
    "file": ({"path"}, set()),
    "micrograph": ({"path", "n_phases"},
                   {"smoothing", "min_speck", "pixel_size", "cover", "offset"}),
}


@dataclasses.dataclass(frozen=True)
class Scene:
    """A parsed scene file.

    Attributes
    ----------
    radius : float or None, m
        Punch radius ``a`` of a circular face; None for other outlines
        (their lengths are in ``outline``).
    normal_force : float, N
        ``F_N``.
    E_star : float, Pa
        Effective modulus of the counter-body.
    n : int
        Pixels along the longer side of the face's bounding box (across the
        diameter of a disk).
    wear_coefficients : tuple of float, 1/Pa
        ``k_i``, one per phase.
    exponent : float
        ``m`` in the wear law ``dw/ds = k p^m``.
    geometry : Homogeneous, Voronoi, Rods, ArrayMap, ...
        Phase geometry in units of the outline's scale (see
        :mod:`steady.phases`).
    source_path : pathlib.Path or None
        The scene file, if read from one.
    text : str
        The TOML text as read.
    extra : mapping
        Parsed extra sections, by name (only those present in the file).
    ignored_sections : tuple of str
        Run-in sections (:data:`RUN_IN_SECTIONS`) present in the file but
        not parsed (no ``extra_sections`` parser for them), sorted.
    outline : outline object
        The face's outline (:mod:`steady.outline`); default: the disk of
        ``radius``.
    """

    radius: float | None
    normal_force: float
    E_star: float
    n: int
    wear_coefficients: tuple
    exponent: float
    geometry: object
    source_path: pathlib.Path | None = None
    text: str = ""
    extra: types.MappingProxyType = dataclasses.field(
        default_factory=lambda: types.MappingProxyType({}))
    ignored_sections: tuple = ()
    outline: object = None

    def __post_init__(self):
        """Complete ``outline`` from ``radius`` (a disk) or ``radius`` from a circular outline."""
        if self.outline is None:
            if self.radius is None:
                raise ValueError("a scene needs a radius or an outline")
            object.__setattr__(self, "outline", Circle(self.radius))
        elif isinstance(self.outline, Circle):
            object.__setattr__(self, "radius", self.outline.radius)
        elif self.radius is not None:
            raise ValueError(f"a {self.outline.kind} face has no radius, got radius = "
                             f"{self.radius!r}")

    @property
    def n_phases(self):
        """Number of phases of the geometry."""
        return self.geometry.n_phases

    @property
    def scale(self):
        """The outline's length scale ``L``, m (the radius of a disk)."""
        return self.outline.scale

    def grid(self, n=None):
        """The :class:`~steady.outline.FaceGrid` of ``n`` pixels (default ``self.n``)."""
        return FaceGrid(self.outline, self.n if n is None else int(n))

    def phase_labels(self, n=None):
        """The phase map on the grid of ``n``, every phase checked to have a face pixel.

        Parameters
        ----------
        n : int, optional
            Grid size, pixels along the longer side (default ``self.n``).

        Returns
        -------
        ndarray, shape (nx, ny), int
            Phase index on the face, -1 off it.

        Raises
        ------
        ValueError
            A phase has no pixel on the face at this grid (a Voronoi phase
            whose seeds all lie off the face or whose cells fall between
            pixel centres); the message names the phase, the seeds and ``n``.
        """
        grid = self.grid(n)
        n = grid.n
        labels = self.geometry.labels(grid)
        counts = np.bincount(labels[labels >= 0], minlength=self.n_phases)
        empty = np.flatnonzero(counts[:self.n_phases] == 0)
        if empty.size:
            phase = int(empty[0])
            where = "" if self.source_path is None else f"{self.source_path}: "
            if isinstance(self.geometry, Voronoi):
                g = self.geometry
                raise ValueError(
                    f"{where}[phases] map: phase {phase} has no pixel on the face with these "
                    f"{g.n_seeds} seeds (seed = {g.seed}) at n = {n}: its seeds lie off the "
                    f"face or their cells fall between pixel centres; use more seeds, another "
                    f"seed or a finer grid")
            raise ValueError(f"{where}[phases] map: phase {phase} has no pixel on the face at "
                             f"n = {n}")
        validate_labels(labels, self.n_phases, face_mask=grid.mask)
        return labels


def _number(value, key, unit, *, positive=True):
    """A finite float (``int`` accepted, ``bool`` not)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{key} must be a number ({unit}), got {shorten(value)}")
    v = float(value)
    if not math.isfinite(v) or (positive and v <= 0):
        raise ValueError(f"{key} must be a positive finite number ({unit}), got "
                         f"{shorten(value)}")
    return v


def _integer(value, key, *, minimum):
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{key} must be an integer, got {shorten(value)}")
    if value < minimum:
        raise ValueError(f"{key} must be at least {minimum}, got {shorten(value)}")
    return value


def _list(value, key):
    if not isinstance(value, list):
        raise ValueError(f"{key} must be an array, got {shorten(value)}")
    return value


def _check_keys(table, where, required, optional):
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table, got {shorten(table)}")
    unknown = sorted(set(table) - required - optional)
    if unknown:
        allowed = ", ".join(sorted(required | optional)) or "none"
        raise ValueError(f"unknown key {shorten(unknown[0])} in {where} (allowed: {allowed})")
    missing = sorted(required - set(table))
    if missing:
        raise ValueError(f"missing key {missing[0]!r} in {where}")


def _geometry(spec, outline, base_dir, n):
    where = "[phases] map"
    if not isinstance(spec, dict):
        raise ValueError(f"{where} must be an inline table with a 'kind', got {shorten(spec)}")
    kind = spec.get("kind")
    if kind not in _MAP_KEYS:
        raise ValueError(f"{where} kind must be one of {sorted(_MAP_KEYS)}, got "
                         f"{shorten(kind)}")
    required, optional = _MAP_KEYS[kind]
    _check_keys(spec, f"{where} (kind {kind!r})", required | {"kind"}, optional)
    scale = outline.scale
    if kind == "homogeneous":
        return Homogeneous()
    if kind == "voronoi":
        n_seeds = _integer(spec["n_seeds"], f"{where} n_seeds", minimum=1)
        fill = [_number(v, f"{where} fill_factors", "dimensionless")
                for v in _list(spec["fill_factors"], f"{where} fill_factors")]
        seed = _integer(spec["seed"], f"{where} seed", minimum=0)
        try:
            return Voronoi(n_seeds, tuple(fill), seed)
        except ValueError as err:
            raise ValueError(f"{where}: {one_line(err, 300)}") from None
    if kind == "rods":
        centres = []
        for c in _list(spec["centres"], f"{where} centres"):
            if not isinstance(c, list) or len(c) != 2:
                raise ValueError(f"{where} centres must be [x, y] pairs in m, got {shorten(c)}")
            centres.append(tuple(_number(v, f"{where} centres", "m", positive=False) / scale
                                 for v in c))
        radii = [_number(v, f"{where} radii", "m") / scale
                 for v in _list(spec["radii"], f"{where} radii")]
        matrix_phase = _integer(spec.get("matrix_phase", 0), f"{where} matrix_phase",
                                minimum=0)
        rod_phases = spec.get("rod_phases")
        if rod_phases is not None:
            rod_phases = tuple(_integer(v, f"{where} rod_phases", minimum=0)
                               for v in _list(rod_phases, f"{where} rod_phases"))
        try:
            rods = Rods(tuple(centres), tuple(radii), matrix_phase, rod_phases)
            rods.check_outline(outline)
        except ValueError as err:
            raise ValueError(f"{where}: {one_line(err, 300)}") from None
        return rods
    if kind == "inclusions":
        options = {"seed": _integer(spec["seed"], f"{where} seed", minimum=0),
                   "radius": _number(spec["radius"], f"{where} radius", "m") / scale}
        for key, unit in (("fill_factor", "dimensionless"), ("count", "dimensionless"),
                          ("radius_spread", "dimensionless")):
            if key in spec:
                options[key] = _number(spec[key], f"{where} {key}", unit,
                                       positive=key != "radius_spread")
        if not isinstance(outline, Circle):  # count is per face area (the unit disk's pi)
            options["face_area"] = outline.area / scale**2
        try:
            return Inclusions(**options)
        except ValueError as err:
            raise ValueError(f"{where}: {one_line(err, 300)}") from None
    # kind == "file" or "micrograph"
    path = spec["path"]
    if not isinstance(path, str) or not path:
        raise ValueError(f"{where} path must be a non-empty string, got {shorten(path)}")
    if kind == "micrograph":
        # The keys are load_micrograph's parameters, which check their values.
        options = {key: value for key, value in spec.items() if key not in ("kind", "path")}
        try:
            return load_micrograph(pathlib.Path(base_dir) / path, outline, **options)
        except ValueError as err:
            raise ValueError(f"{where}: {one_line(err, 300)}") from None
    # The map's size must divide n: a larger one is refused before its data are read.
    return load_phase_map(pathlib.Path(base_dir) / path, max_size=n, outline=outline)


def parse_scene(text, base_dir, *, extra_sections=None, source_path=None):
    """Parse and check the text of a scene file.

    Parameters
    ----------
    text : str
        TOML text.
    base_dir : str or path-like
        Directory against which relative paths in the scene are resolved.
    extra_sections : mapping of str to callable, optional
        ``name -> parse(table, base_dir)`` for sections beyond the core
        ones; each result is kept in ``Scene.extra[name]``.  Sections
        absent from the file are not called.  Run-in sections
        (:data:`RUN_IN_SECTIONS`) without a parser here are skipped and
        listed in ``Scene.ignored_sections``.
    source_path : path-like, optional
        Recorded in ``Scene.source_path``.

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        Malformed TOML, unknown or missing section or key, bad value (the
        message names the key and the value), missing map file.
    """
    extra_sections = dict(extra_sections or {})
    clash = sorted(set(extra_sections) & set(CORE_SECTIONS))
    if clash:
        raise ValueError(f"extra section {clash[0]!r} clashes with a core section")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"malformed TOML: {one_line(err, 200)}") from None
    except RecursionError:
        raise ValueError("malformed TOML: arrays or tables nested too deeply") from None
    base_dir = pathlib.Path(base_dir)
    ignored = tuple(sorted(name for name in RUN_IN_SECTIONS
                           if name in doc and name not in extra_sections))
    unknown = sorted(set(doc) - set(CORE_SECTIONS) - set(extra_sections) - set(ignored))
    if unknown:
        allowed = ", ".join(sorted(set(CORE_SECTIONS) | set(extra_sections)
                                   | set(RUN_IN_SECTIONS)))
        raise ValueError(f"unknown section [{shorten(unknown[0])[1:-1]}] (allowed: {allowed})")
    for name in ignored:
        if not isinstance(doc[name], dict):
            raise ValueError(f"[{name}] must be a table, got {shorten(doc[name])}")
    for name, (required, optional) in CORE_SECTIONS.items():
        if name not in doc:
            raise ValueError(f"missing section [{name}]")
        if name != "punch":  # the outline checks its own keys
            _check_keys(doc[name], f"[{name}]", required, optional)

    try:
        outline = outline_from_table(doc["punch"], base_dir)
    except ValueError as err:
        message = one_line(err, 300)
        raise ValueError(message if message.startswith("[punch]") or "[punch]" in message
                         else f"[punch] {message}") from None
    normal_force = _number(doc["load"]["normal_force"], "[load] normal_force", "N")
    E_star = _number(doc["counterbody"]["E_star"], "[counterbody] E_star", "Pa")
    n = _integer(doc["grid"]["n"], "[grid] n", minimum=2)
    exponent = _number(doc["wear"].get("exponent", 1.0), "[wear] exponent", "dimensionless")
    try:
        outline.check_grid(n)
    except ValueError as err:
        raise ValueError(f"[grid] n: {err}") from None
    geometry = _geometry(doc["phases"]["map"], outline, base_dir, n)
    coefficients = _list(doc["wear"]["coefficients"], "[wear] coefficients")
    if len(coefficients) != geometry.n_phases:  # counted before any value is looked at
        raise ValueError(f"[wear] coefficients has {len(coefficients)} values "
                         f"{shorten(coefficients)} but the phase map has {geometry.n_phases} "
                         f"phases")
    k = tuple(_number(v, "[wear] coefficients", "1/Pa") for v in coefficients)
    try:
        geometry.check_grid(FaceGrid(outline, n))
    except ValueError as err:
        raise ValueError(f"[grid] n: {err}") from None

    extra = {}
    for name, parse in extra_sections.items():
        if name in doc:
            try:
                extra[name] = parse(doc[name], base_dir)
            except ValueError as err:
                raise ValueError(f"[{name}]: {err}") from None
    return Scene(radius=outline.radius if isinstance(outline, Circle) else None,
                 outline=outline, normal_force=normal_force, E_star=E_star, n=n,
                 wear_coefficients=k, exponent=exponent, geometry=geometry,
                 source_path=None if source_path is None else pathlib.Path(source_path),
                 text=text, extra=types.MappingProxyType(extra), ignored_sections=ignored)


def load_scene(path, *, extra_sections=None):
    """Read and check a scene file.

    Parameters
    ----------
    path : str or path-like
        The ``.toml`` file; relative paths inside it are resolved against
        its directory.
    extra_sections : mapping of str to callable, optional
        As in :func:`parse_scene`.

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        Missing or unreadable file, a directory or device, a file larger
        than :data:`MAX_SCENE_BYTES`, not UTF-8, or any error of
        :func:`parse_scene`; the message starts with the path.
    """
    path = pathlib.Path(path)
    what = f"scene file {str(path)!r}"
    try:
        mode = path.stat().st_mode
        if stat.S_ISDIR(mode):
            raise ValueError(f"{what} is a directory, not a file")
        if not stat.S_ISREG(mode):
            raise ValueError(f"{what} is not a regular file (a device or a pipe?)")
        with open(path, "rb") as f:
            data = f.read(MAX_SCENE_BYTES + 1)
    except FileNotFoundError:
        raise ValueError(f"{what} does not exist") from None
    except OSError as err:
        raise ValueError(f"cannot read {what}: {err.strerror or err}") from None
    if len(data) > MAX_SCENE_BYTES:
        raise ValueError(f"{what} is larger than {MAX_SCENE_BYTES // 2 ** 20} MiB, the most a "
                         f"scene may have (large data belong in .npy files, e.g. a phase map)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ValueError(f"{what} is not UTF-8 text: byte {err.start} is "
                         f"{data[err.start:err.start + 1]!r}") from None
    try:
        return parse_scene(text, path.parent, extra_sections=extra_sections, source_path=path)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None
