"""Scene files: one TOML file describes one punch, load, counter-body and grid.

Example (every section a scene needs)::

    [punch]
    radius = 0.004                      # m (a circular face; other shapes: [punch] shape)
    [load]
    normal_force = 10.0                 # N
    [counterbody]
    E_star = 1.3e6                      # Pa
    [grid]
    n = 256                             # pixels along the longer side of the face's box
    [wear]
    coefficients = [1.0e-9, 1.7e-9]     # 1/Pa, one per phase
    [phases]
    map = { kind = "file", path = "phases.npy" }

The keys are declared once, with their types, units, ranges and meanings:
:data:`SECTIONS` for ``[load]``, ``[counterbody]`` and ``[grid]``, and the
registries of the tables that name a kind -- the face outline
(:data:`steady.outline.OUTLINES`, ``[punch] shape``), the phase map
(:data:`steady.phases.PHASE_MAPS`, ``[phases] map kind``) and the wear law
(:data:`steady.wear.WEAR_LAWS`, ``[wear] law``), and of the optional
``[sliding]`` section, the sliding kinematics (:data:`steady.sliding.SLIDING`,
``[sliding] kind``; absent, a translation), and of the optional ``[depth]``
section, layers from the surface down over the ``[phases] map``
(:data:`DEPTH_KEYS`, :data:`LAYER_KEYS`; :meth:`Scene.depth_columns`).  The
tables of scene keys in docs/scenes.md are drawn from them.  Lengths of
phase geometries are in m, in the file and in the geometry objects alike.

Every key is checked; unknown sections and keys are errors, so that a typo
cannot pass silently.  Another package reads sections of its own: it names
them in ``extra_sections``, finds their tables in ``Scene.extra`` and
parses them itself (this module knows nothing of their contents and calls
nothing back).  The sections of the run-in (:data:`RUN_IN_SECTIONS`), when
not named, are recorded in ``Scene.ignored_sections`` and otherwise left
alone, so that one scene file serves the steady and the run-in commands.
"""

from __future__ import annotations

import dataclasses
import pathlib
import stat
import types

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .counterbody import POISSON, THICKNESS, Counterbody
from .depth_maps import DepthLayers, LayerPhase
from .load_programme import LoadProgramme
from .outline import FaceGrid, outline_from_table
from .phases import PHASE_MAPS
from .problem import (
    FacePhases,
    Problem,
    check_load_scales,
    check_phase_names,
    check_pixel_scale,
    check_rate_scales,
    check_scale,
)
from .schema import Context, Key, read_table
from .sliding import sliding_from_table
from .text import one_line, shorten
from .wear import wear_law_from_table

__all__ = ["DEPTH_KEYS", "GRID_N", "LAYER_KEYS", "MAX_SCENE_BYTES", "OPTIONAL_SECTIONS",
           "PHASE_KEYS", "RUN_IN_SECTIONS", "SECTIONS", "SLIDING_SPEED", "Scene", "load_scene",
           "parse_scene", "problem_of"]

#: Largest scene file read, bytes: a scene is a few lines; large data belong in
#: ``.npy`` files (a 40 MB list would take Python's TOML parser half a minute).
MAX_SCENE_BYTES = 2 ** 20

#: ``[load] sliding_speed``: a speed, checked against the range of every scale; a run-in
#: built in Python (:class:`transient.problem.WearProblem`) checks its speed through it too.
SLIDING_SPEED = Key("sliding_speed", "number", unit="m/s", low=0.0,
                    doc="sliding speed, optional: the run-in distance is also given as a time")

#: The keys of the sections that name no kind.
SECTIONS = {
    "load": (Key("normal_force", "number", unit="N", low=0.0, required=True,
                 doc="the normal force F_N"),
             SLIDING_SPEED,
             Key("programme", "pairs", unit="m, N",
                 doc="load programme, optional: [[s_1, F_1], [s_2, F_2], ...], the force F_i "
                     "(N) from the sliding distance s_i (m, increasing, >= 0) on; "
                     "normal_force holds before s_1; the steady state is the one under the "
                     "last force")),
    "counterbody": (Key("E_star", "number", unit="Pa", low=0.0, required=True,
                        doc="effective modulus E / (1 - nu^2) of the counter-body"),
                    THICKNESS, POISSON),
    "grid": (Key("n", "integer", low=2, low_open=False, required=True,
                 doc="pixels along the longer side of the face's bounding box"),),
}
#: ``[grid] n``, also the command line's ``--n``.
GRID_N = SECTIONS["grid"][0]

#: The keys of ``[phases]`` besides the map (read by its kind).
PHASE_KEYS = (Key("names", "strings",
                  doc="a name for each phase, in the order of the phase indices 0, 1, ... "
                      "(default: 'phase 0', 'phase 1', ...); used in summaries, figures and "
                      "files"),)

#: The keys of ``[depth]`` besides its ``[[depth.layers]]`` (read by :data:`LAYER_KEYS`).
DEPTH_KEYS = (Key("kind", "string", choices=("layers",), required=True,
                  doc="how the phase map changes with depth: \"layers\", layers from the "
                      "surface down over the [phases] map (the substrate)"),)

#: The keys of each ``[[depth.layers]]`` entry, from the surface down; ``map`` is read by its kind.
LAYER_KEYS = (Key("thickness", "number", unit="m", low=0.0, required=True,
                  doc="thickness of the layer"),
              Key("phase", "integer", low=0, low_open=False,
                  doc="the phase of a homogeneous layer (or a map, not both)"))

#: Every section a scene file has: those of :data:`SECTIONS` and the ones that name a kind.
CORE_SECTIONS = ("punch", "load", "counterbody", "grid", "wear", "phases")

#: Optional sections of the model, read here when present: ``[sliding]``, the
#: sliding kinematics (:data:`steady.sliding.SLIDING`; absent: a translation), and
#: ``[depth]``, a phase map that changes with depth (absent: columnar, or a 3-d
#: ``[phases] map`` kind).
OPTIONAL_SECTIONS = ("sliding", "depth")

#: Sections read by the run-in command (package ``transient``).  Unless named
#: in ``extra_sections`` they are skipped, not refused: the steady state does
#: not depend on them.  Only the names are known here.
RUN_IN_SECTIONS = ("initial_face", "transient")


@dataclasses.dataclass(frozen=True)
class Scene:
    """A parsed scene file.

    Attributes
    ----------
    outline : outline object
        The face's outline (:mod:`steady.outline`, ``[punch]``).
    normal_force : float, N
        ``F_N``.
    E_star : float, Pa
        Effective modulus of the counter-body.
    n : int
        Pixels along the longer side of the face's bounding box (across the
        diameter of a disk).
    wear : wear law
        The local wear law of the phases (:mod:`steady.wear`, ``[wear]``).
    geometry : Homogeneous, Voronoi, Rods, ArrayMap, ...
        Phase geometry in units of the outline's scale (see
        :mod:`steady.phases`).
    source_path : pathlib.Path or None
        The scene file, if read from one.
    text : str
        The TOML text as read.
    extra : mapping
        The tables of the sections named in ``extra_sections``, by name
        (only those present in the file), as read from it: their reader
        checks them.
    ignored_sections : tuple of str
        Run-in sections (:data:`RUN_IN_SECTIONS`) present in the file but
        not named in ``extra_sections``, sorted.
    phase_names : tuple of str or None
        ``[phases] names``, one per phase; None when the scene names none
        (:attr:`steady.problem.FacePhases.names` then holds the defaults).
    sliding_speed : float or None, m/s
        ``[load] sliding_speed``; None when the scene gives none.  Nothing
        depends on it but the conversion of sliding distances into times.
    sliding : sliding kinematics or None
        ``[sliding]`` (:mod:`steady.sliding`); None when the scene has no
        such section or its kind is ``"translation"``: the paper's uniform
        sliding speed.
    load_programme : steady.load_programme.LoadProgramme or None
        ``[load] programme`` (with ``normal_force`` before its first
        breakpoint); None when the scene gives none: the load is constant.
    depth : steady.depth_maps.DepthLayers or None
        The ``[depth]`` section, parsed: layers over ``geometry`` (the
        substrate); None without one.
    thickness, poisson : float or None
        ``[counterbody] thickness`` (m) and ``poisson``: the counter-body is a
        layer on a rigid flat (:attr:`counterbody`); None, a half-space.
    """

    outline: object
    normal_force: float
    E_star: float
    n: int
    wear: object
    geometry: object
    source_path: pathlib.Path | None = None
    text: str = ""
    extra: types.MappingProxyType = dataclasses.field(
        default_factory=lambda: types.MappingProxyType({}))
    ignored_sections: tuple = ()
    phase_names: tuple | None = None
    sliding_speed: float | None = None
    sliding: object = None
    load_programme: LoadProgramme | None = None
    depth: DepthLayers | None = None
    thickness: float | None = None
    poisson: float | None = None
    #: The inputs as :func:`parse_scene` checked them (None: a scene built in Python).
    _checked: tuple | None = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def checked(self):
        """Whether the scales of its inputs were checked as it was read (:func:`parse_scene`).

        True for a scene read from a file and not changed since (a scene
        built in Python, or with another grid, load or law, is checked
        where it enters a problem, :func:`steady.scene.problem_of`).
        """
        return self._checked is not None and self._checked == self._inputs()

    def _inputs(self):
        """What the scales depend on: outline, load, modulus, grid, law and programme."""
        return (self.outline, self.normal_force, self.E_star, self.n, self.wear,
                self.load_programme)

    @property
    def counterbody(self):
        """The counter-body (:class:`steady.counterbody.Counterbody`): modulus and layer."""
        return Counterbody(self.E_star, self.thickness, self.poisson)

    @property
    def final_force(self):
        """The force of the steady state, N: the programme's last, else ``normal_force``."""
        if self.load_programme is None:
            return self.normal_force
        return self.load_programme.final_force

    @property
    def n_phases(self):
        """Number of phases of the geometry (with ``[depth]``: of the layers and the substrate)."""
        return self.layout.n_phases

    @property
    def layout(self):
        """The phase geometry in 3-d: the ``[depth]`` layers if any, else ``geometry``."""
        return self.geometry if self.depth is None else self.depth

    @property
    def depth_varying(self):
        """Whether the phase map may change with depth (``[depth]`` or a 3-d map kind)."""
        return hasattr(self.layout, "columns")

    def depth_columns(self, n=None):
        """The phase below every face pixel (:class:`steady.depth.DepthColumns`), or None.

        Parameters
        ----------
        n : int or FaceGrid, optional
            Grid size (default ``self.n``) or the scene outline's grid.

        Returns
        -------
        DepthColumns or None
            None for a columnar scene (no ``[depth]``, a 2-d map kind): its
            map is :meth:`phase_labels` at every depth.

        Raises
        ------
        ValueError
            A phase that occurs nowhere in the columns at this grid.
        """
        if not self.depth_varying:
            return None
        grid = n if isinstance(n, FaceGrid) else self.grid(n)
        try:
            return self.layout.columns(grid)
        except ValueError as err:
            where = "" if self.source_path is None else f"{self.source_path}: "
            raise ValueError(f"{where}{one_line(err, 300)} at n = {grid.n}") from None

    def input_names(self):
        """The scene's keys and values, by input, for messages (see :func:`input_names`)."""
        return input_names(self.outline, self.normal_force, self.E_star, self.n, self.wear)

    @property
    def scale(self):
        """The outline's length scale ``L``, m (the radius of a disk)."""
        return self.outline.scale

    def grid(self, n=None):
        """The :class:`~steady.outline.FaceGrid` of ``n`` pixels (default ``self.n``)."""
        return FaceGrid(self.outline, self.n if n is None else n)

    def phase_labels(self, n=None):
        """The phase map on the grid of ``n``, every phase checked to have a face pixel.

        Parameters
        ----------
        n : int or FaceGrid, optional
            Grid size, pixels along the longer side (default ``self.n``),
            or the scene outline's grid itself.

        Returns
        -------
        ndarray, shape (nx, ny), int
            Phase index on the face, -1 off it.  For a depth-varying scene
            the surface section (depth 0), whose phases are checked over the
            columns (:meth:`depth_columns`): a coating's surface is one phase.

        Raises
        ------
        ValueError
            A phase has no pixel on the face at this grid (a Voronoi phase
            whose seeds all lie off the face or whose cells fall between
            pixel centres); the message names the phase, the seeds and ``n``.
        """
        grid = n if isinstance(n, FaceGrid) else self.grid(n)
        n = grid.n
        if self.depth_varying:  # the surface section; every phase is looked for in the columns
            return self.depth_columns(grid).phase_at(0.0)
        labels = self.geometry.labels(grid)
        counts = np.bincount(labels[labels >= 0], minlength=self.n_phases)
        empty = np.flatnonzero(counts[:self.n_phases] == 0)
        if empty.size:
            phase = int(empty[0])
            where = "" if self.source_path is None else f"{self.source_path}: "
            raise ValueError(f"{where}[phases] map: "
                             f"{self.geometry.empty_phase_words(phase, n)}")
        return labels  # the rest is checked once, where it enters a problem (FacePhases)


def problem_of(scene, *, n=None):
    """The problem of a scene (:class:`steady.problem.Problem`): the one factory from a scene.

    Parameters
    ----------
    scene : Scene
    n : int, optional
        Grid size, pixels along the longer side; default ``scene.n``.
        The phase geometry is rasterised at this size.

    Returns
    -------
    steady.problem.Problem
        Under the scene's load, the last force of a ``[load] programme``
        (the steady state's) when it has one.  The scales the scene checked
        as it was read are not checked again (:attr:`Scene.checked`).

    Raises
    ------
    ValueError
        A grid too coarse for the outline or the geometry, a phase without
        a pixel on the face at this grid (named, with what to change; for a
        depth-varying scene, a phase nowhere in the columns), or a scale out
        of range (:func:`steady.problem.check_scales`, naming the scene's
        keys); the message starts with the scene file.

    Notes
    -----
    A depth-varying scene (``[depth]`` or a 3-d map kind,
    :meth:`Scene.depth_columns`) gives a problem with ``phases.columns``,
    its labels the surface section: :meth:`steady.problem.Problem.section`
    gives the problem of a deeper one.

    Examples
    --------
    >>> from steady import examples
    >>> problem = problem_of(load_scene(examples.path("voronoi_biphasic")), n=96)
    >>> problem.n_phases, problem.shape
    (2, (96, 96))
    """
    grid = scene.grid(n)
    columns = scene.depth_columns(grid)
    labels = scene.phase_labels(grid) if columns is None else columns.phase_at(0.0)
    phases = FacePhases(grid, labels, scene.n_phases, scene.phase_names, columns)
    # Under a load programme the steady state is the one of its last force.
    force = scene.final_force
    names = scene.input_names()
    if force != scene.normal_force:
        names["normal_force"] = f"[load] programme force {force!r}"
    try:
        checked = scene.checked  # as read from its file (else: checked here)
        if checked and grid.n != scene.n:  # the scene checked its own grid's pixel
            check_pixel_scale(scene.outline, grid.n, dict(names, n=f"n = {grid.n!r}"))
        return Problem(phases, scene.wear, force, scene.E_star, scene.sliding,
                       thickness=scene.thickness, poisson=scene.poisson, checked=checked,
                       names=names)
    except ValueError as err:
        where = "" if scene.source_path is None else f"{scene.source_path}: "
        raise ValueError(f"{where}{err}") from None


def input_names(outline, normal_force, E_star, n, wear=None):
    """How messages name a scene's inputs: its keys and values (``"[load] normal_force = 10.0"``).

    The keys of :func:`steady.problem.input_names`: ``"outline"`` (the
    ``[punch]`` lengths), each ``[punch]`` length by name,
    ``"normal_force"``, ``"E_star"``, ``"n"`` and ``"wear"``.
    """
    lengths = {name: value for name, (value, unit) in outline.parameters().items()
               if unit == "m"}
    names = {name: f"[punch] {name} = {value!r}" for name, value in lengths.items()}
    names["outline"] = "[punch] " + ", ".join(f"{k} = {v!r}" for k, v in lengths.items())
    names.update(normal_force=f"[load] normal_force = {normal_force!r}",
                 E_star=f"[counterbody] E_star = {E_star!r}", n=f"[grid] n = {shorten(n)}")
    if wear is not None:
        names["wear"] = wear.scene_words()
    return names


def _geometry(table, outline, base_dir, n, wear, where="[phases] map", *, whole=True):
    """The phase geometry of ``[phases] map`` (a registered kind of :data:`PHASE_MAPS`).

    Its phases are the wear law's (``whole``; for a map of a ``[depth]``
    section, some of them): compared before the map does its work (a
    segmentation, a file read) when its keys declare them
    (:meth:`steady.phases.PhaseMap.declared_phases`), else once it is built.
    """
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be an inline table with a 'kind', got {shorten(table)}")
    context = Context(base_dir=base_dir, outline=outline, n=n, where=where)
    cls, values = PHASE_MAPS.read(table, context)
    declared = cls.declared_phases(values)
    if declared is not None:  # named by the key that declares them, if one does
        _check_map_phases(declared, wear, where, whole,
                          "n_phases" if "n_phases" in values else None)
    try:
        geometry = cls.from_values(values, context)
    except ValueError as err:
        message = one_line(err, 300)
        raise ValueError(message if where in message else f"{where}: {message}") from None
    _check_map_phases(geometry.n_phases, wear, where, whole)
    return geometry


def _check_map_phases(n_phases, wear, where, whole, key=None):
    """Refuse a map of ``n_phases`` other than the law's (``whole``), or more (a depth layer's).

    ``key``, the map's key that declares ``n_phases``, is named with its value.
    """
    if whole:
        if key is None:
            wear.check_phase_count(n_phases)
        else:
            wear.check_phase_count(n_phases, where, key)
    elif n_phases > wear.n_phases:
        has = f"{key} = {shorten(n_phases)}" if key else f"has {shorten(n_phases)} phases"
        raise ValueError(f"{where} {has}, the wear law {wear.n_phases}")


def parse_scene(text, base_dir, *, extra_sections=(), source_path=None, n=None):
    """Parse and check the text of a scene file.

    Parameters
    ----------
    text : str
        TOML text.
    base_dir : str or path-like
        Directory against which relative paths in the scene are resolved.
    extra_sections : collection of str, optional
        Sections beyond the core ones that the caller reads itself: their
        tables are kept in ``Scene.extra`` (they must be tables).  Run-in
        sections (:data:`RUN_IN_SECTIONS`) not named here are skipped and
        listed in ``Scene.ignored_sections``; any other section is an error.
    source_path : path-like, optional
        Recorded in ``Scene.source_path``.
    n : int, optional
        The grid to use instead of the scene's ``[grid] n`` (the command
        line's ``--n``), checked as that key is; the scene must still
        hold a valid ``n``.

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        Malformed TOML, unknown or missing section or key, bad value (the
        message names the key and the value), missing map file.
    """
    extra_sections = tuple(extra_sections)
    clash = sorted(set(extra_sections) & set(CORE_SECTIONS + OPTIONAL_SECTIONS))
    if clash:
        raise ValueError(f"extra section {clash[0]!r} clashes with a core section")
    doc = _toml(text)
    base_dir = pathlib.Path(base_dir)
    ignored = tuple(sorted(name for name in RUN_IN_SECTIONS
                           if name in doc and name not in extra_sections))
    unknown = sorted(set(doc) - set(CORE_SECTIONS) - set(OPTIONAL_SECTIONS) - set(extra_sections)
                     - set(ignored))
    if unknown:
        allowed = ", ".join(sorted(set(CORE_SECTIONS) | set(OPTIONAL_SECTIONS)
                                   | set(extra_sections) | set(RUN_IN_SECTIONS)))
        raise ValueError(f"unknown section [{shorten(unknown[0])[1:-1]}] (allowed: {allowed})")
    for name in CORE_SECTIONS:
        if name not in doc:
            raise ValueError(f"missing section [{name}]")
    optional = tuple(name for name in OPTIONAL_SECTIONS if name in doc)
    for name in (*CORE_SECTIONS, *optional, *ignored, *(n for n in extra_sections if n in doc)):
        if not isinstance(doc[name], dict):
            raise ValueError(f"[{name}] must be a table, got {shorten(doc[name])}")
    values = {name: read_table(doc[name], f"[{name}]", keys, base_dir)
              for name, keys in SECTIONS.items()}
    phase_keys = read_table(doc["phases"], "[phases]", PHASE_KEYS, ignore=("map",))
    if "map" not in doc["phases"]:
        raise ValueError("missing key 'map' in [phases]")
    outline = outline_from_table(doc["punch"], base_dir)
    if n is not None:
        values["grid"]["n"] = GRID_N.parse(n, "")
    n = values["grid"]["n"]
    force, E_star = values["load"]["normal_force"], values["counterbody"]["E_star"]
    counterbody = Counterbody(**values["counterbody"])  # a layer's keys go together
    # The scales that follow from the face and the load (the keys checked their own),
    # before a phase map is drawn on it.
    check_load_scales(outline, force, E_star, input_names(outline, force, E_star, n), n)
    try:
        outline.check_grid(n)
    except ValueError as err:
        raise ValueError(f"[grid] n: {err}") from None
    # The law first: the map's phases are checked against it before the map's work.
    wear = wear_law_from_table(doc["wear"], base_dir)
    geometry = _geometry(doc["phases"]["map"], outline, base_dir, n, wear,
                         whole="depth" not in doc)
    depth = None
    if "depth" in doc:
        depth = _depth(doc["depth"], geometry, outline, base_dir, n, wear)
        _check_layer_phases(depth, wear)
    layout = geometry if depth is None else depth
    names = phase_keys.get("names")
    if names is not None:
        try:
            names = check_phase_names(names, layout.n_phases)
        except ValueError as err:
            raise ValueError(f"[phases] names: {err}") from None
    check_rate_scales(wear, outline, force, input_names(outline, force, E_star, n, wear))
    programme = _programme(values["load"], outline, E_star, n, wear)
    try:
        layout.check_grid(FaceGrid(outline, n))
    except ValueError as err:
        raise ValueError(f"[grid] n: {err}") from None

    sliding = None
    if "sliding" in doc:
        sliding = sliding_from_table(doc["sliding"], outline, base_dir)
        sliding = None if sliding.uniform else sliding

    extra = {name: doc[name] for name in extra_sections if name in doc}
    scene = Scene(outline=outline, normal_force=force, E_star=E_star, n=n, wear=wear,
                  geometry=geometry,
                  source_path=None if source_path is None else pathlib.Path(source_path),
                  text=text, extra=types.MappingProxyType(extra), ignored_sections=ignored,
                  phase_names=names, sliding_speed=values["load"].get("sliding_speed"),
                  sliding=sliding, load_programme=programme, depth=depth,
                  thickness=counterbody.thickness, poisson=counterbody.poisson)
    return dataclasses.replace(scene, _checked=scene._inputs())


def _depth(table, substrate, outline, base_dir, n, wear):
    """The :class:`DepthLayers` of ``[depth]`` over the ``[phases] map`` ``substrate``."""
    values = read_table(table, "[depth]", DEPTH_KEYS, base_dir, ignore=("layers",))
    layers = table.get("layers")
    if not isinstance(layers, list) or not layers or not all(isinstance(t, dict)
                                                             for t in layers):
        raise ValueError(f"[depth] (kind {values['kind']!r}) needs [[depth.layers]] tables, "
                         f"one per layer from the surface down, got {shorten(layers)}")
    thicknesses, maps = [], []
    for i, layer in enumerate(layers):
        where = f"[depth] layers[{i}]"
        keys = read_table(layer, where, LAYER_KEYS, base_dir, ignore=("map",))
        if ("phase" in keys) == ("map" in layer):
            raise ValueError(f"{where} needs either 'phase' (a homogeneous layer) or 'map' (a "
                             f"[phases] map kind), not {'both' if 'phase' in keys else 'neither'}")
        if "phase" in keys:
            maps.append(LayerPhase(keys["phase"]))
        else:
            maps.append(_geometry(layer["map"], outline, base_dir, n, wear,
                                  where=f"{where} map", whole=False))
        thicknesses.append(keys["thickness"])
    return DepthLayers(tuple(thicknesses), tuple(maps), substrate)


def _check_layer_phases(depth, wear):
    """Refuse a layer phase outside the wear law's phases, and a law for other phases.

    Each map's phases were checked against the law as it was read (:func:`_geometry`).
    """
    top = wear.n_phases - 1
    for i, g in enumerate(depth.maps):
        if isinstance(g, LayerPhase) and g.phase > top:
            raise ValueError(f"[depth] layers[{i}] phase = {g.phase} is outside the wear law's "
                             f"phases 0..{top}")
    if depth.n_phases != wear.n_phases:
        raise ValueError(f"[wear] has {wear.n_phases} phases, the [depth] layers and the "
                         f"[phases] map use {depth.n_phases} (phases 0..{depth.n_phases - 1})")


def _programme(load, outline, E_star, n, wear):
    """The :class:`LoadProgramme` of ``[load]`` (None without one), every force's scales checked.

    Each force other than ``normal_force`` (checked already) is a load the
    run meets: it and its scales must lie in range.
    """
    if "programme" not in load:
        return None
    programme = LoadProgramme(load["normal_force"], load["programme"])
    for force in sorted(set(programme.forces) - {load["normal_force"]}):
        names = input_names(outline, force, E_star, n, wear)
        names["normal_force"] = f"[load] programme force {force!r}"
        check_scale(force, None, "N", ("normal_force",), names)
        check_load_scales(outline, force, E_star, names)
        check_rate_scales(wear, outline, force, names)
    return programme


def _toml(text):
    """The TOML document of a scene's text; ``ValueError`` with the parser's message."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"malformed TOML: {one_line(err, 200)}") from None
    except RecursionError:
        raise ValueError("malformed TOML: arrays or tables nested too deeply") from None


def load_scene(path, *, extra_sections=(), n=None):
    """Read and check a scene file.

    Parameters
    ----------
    path : str or path-like
        The ``.toml`` file, UTF-8 text (a leading byte-order mark is
        skipped); relative paths inside it are resolved against its
        directory.
    extra_sections : collection of str, optional
        As in :func:`parse_scene`.
    n : int, optional
        The grid instead of the scene's, as in :func:`parse_scene`.

    Returns
    -------
    Scene

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Unreadable file, a directory or device, a file larger than
        :data:`MAX_SCENE_BYTES`, not UTF-8, or any error of
        :func:`parse_scene` (a file the scene names that does not exist
        included: a bad value of its key); the message starts with the path.
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
        raise FileNotFoundError(f"{what} does not exist") from None
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
    # A UTF-8 document may open with a byte-order mark (EF BB BF), as editors on
    # Windows save it; TOML allows it (toml-lang/toml#437), Python's parser does not.
    text = text.removeprefix("\ufeff")
    try:
        return parse_scene(text, path.parent, extra_sections=extra_sections, source_path=path,
                           n=n)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None
