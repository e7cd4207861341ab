"""Scene sections of the run-in: ``[transient]`` and ``[initial_face]``.

:func:`load_transient_scene` asks :func:`steady.scene.load_scene` to keep
their tables (``extra_sections``; ``steady`` knows nothing of them) and
parses them itself::

    [transient]
    scheme = "esdirk3"          # registered integrator (transient.stepping.SCHEMES)
    tol = 1e-5                  # local error per step, rms shape / f*
    snapshots_s_star = [0.1, 1.0, 3.0]  # face and pressure stored there

    [initial_face]
    kind = "tilted"             # "flat" (default), "tilted", "crowned" or "file"
    angle = 1e-3                # rad (tilted)

The keys of ``[transient]`` are the fields of
:class:`transient.options.RunOptions`, declared there with their types,
units, ranges and meanings; those of ``[initial_face]`` are declared by
each kind of :data:`transient.initial_face.INITIAL_FACES`.  Distances are
in m; a key in units of the run-in distance ``s* = L / (k_min E*)`` says so
in its name (``snapshots_s_star``; ``L`` the face outline's scale, the
radius ``a`` of a disk; docs/model.md, "Natural scales").  Every key is
optional and checked; unknown keys are errors, and a key that was a
distance in s* under another name is refused with its value in m.
"""

from __future__ import annotations

import dataclasses
import pathlib
import types

import numpy as np

from steady.array_files import REAL_NUMBERS, npy_header
from steady.scene import RUN_IN_SECTIONS, load_scene, problem_of
from steady.schema import Context
from steady.text import one_line

from .initial_face import INITIAL_FACES, check_outline, initial_recession
from .options import RunOptions, options_from_table
from .problem import WearProblem

__all__ = [
    "InitialFace",
    "check_run_in_law",
    "load_transient_scene",
    "parse_initial_face",
    "parse_transient",
    "wear_problem_of",
]


@dataclasses.dataclass(frozen=True)
class InitialFace:
    """The ``[initial_face]`` section: how to build the initial recession field.

    Attributes
    ----------
    kind : str
        A registered kind (:data:`transient.initial_face.INITIAL_FACES`):
        ``"flat"`` (default), ``"tilted"``, ``"crowned"`` or ``"file"``.
    parameters : mapping
        The kind's parameters: numbers (rad, m), or for ``"file"`` the
        ``path`` of the ``.npy`` file (resolved against the scene's
        directory).
    """

    kind: str = "flat"
    parameters: types.MappingProxyType = dataclasses.field(
        default_factory=lambda: types.MappingProxyType({}))

    def recession(self, grid):
        """Initial recession on the grid of a face outline.

        Parameters
        ----------
        grid : steady.outline.FaceGrid
            The face's grid (``scene.grid(n)``, ``problem.grid``).

        Returns
        -------
        ndarray, shape of the grid, m
            Larger = recessed.

        Raises
        ------
        ValueError
            A parameter out of range for this grid and face, or a file of
            another shape, named.
        """
        path = self.parameters.get("path")
        try:
            return initial_recession(self.kind, grid, **self.parameters)
        except (OSError, EOFError) as err:  # the file changed since the scene was read
            raise ValueError(f"[initial_face]: cannot read {str(path)!r}: {err}") from None
        except ValueError as err:
            raise ValueError(f"[initial_face]: {one_line(err, 300)}") from None


def parse_transient(table, base_dir=".", *, distance_scale=None):
    """Parse a ``[transient]`` table.

    Parameters
    ----------
    table : dict
    base_dir : path-like, optional
        Unused (no paths in this section).
    distance_scale : float, optional, m
        The scene's ``s*``, for the refusal of a key renamed from s* to m
        (:func:`transient.options.options_from_table`).

    Returns
    -------
    RunOptions

    Raises
    ------
    ValueError
        Unknown key or bad value, named.
    """
    return options_from_table(table, base_dir, distance_scale=distance_scale)


def parse_initial_face(table, base_dir):
    """Parse an ``[initial_face]`` table.

    Parameters
    ----------
    table : dict
    base_dir : pathlib.Path
        Directory of the scene file (for ``kind = "file"``).

    Returns
    -------
    InitialFace

    Raises
    ------
    ValueError
        Unknown kind or key, missing key, a value of the wrong type or range,
        or a missing or damaged file, named.
    """
    context = Context(base_dir=pathlib.Path(base_dir), where="[initial_face]")
    build, values = INITIAL_FACES.read(table, context)
    for key in build.keys:
        if key.type == "path" and key.name in values:
            # Exists, is a .npy file of real numbers, not truncated: checked before the run.
            npy_header(values[key.name], what="initial face file", holds=REAL_NUMBERS)
    return InitialFace(build.kind, types.MappingProxyType(values))


def _distance_scale(scene):
    """The scene's run-in distance ``s* = L / (g'(pbar) E*)`` of its slowest phase, m.

    At the outline's mean pressure ``F / A`` (the run takes the face's
    pixel area, within a pixel of it); for the messages that give a
    distance in m.
    """
    wear = scene.wear
    with np.errstate(all="ignore"):
        constants = wear.rate_constant(wear.wear_field(np.arange(wear.n_phases)),
                                       scene.final_force / scene.outline.area)
        return float(scene.outline.scale / (np.min(constants) * scene.E_star))


def wear_problem_of(scene, *, n=None, problem=None):
    """The wear problem of a scene (:class:`transient.problem.WearProblem`), the one factory.

    Parameters
    ----------
    scene : steady.scene.Scene
        As read by :func:`steady.scene.load_scene` or
        :func:`load_transient_scene`.
    n : int, optional
        Grid size; default ``scene.n``.  The phase geometry is rasterised
        at this size.
    problem : steady.problem.Problem, optional
        ``problem_of(scene, n=n)`` (:func:`steady.scene.problem_of`), if the
        caller has built it (a command that checks the scene's map before
        the run): the map is then not rasterised again.

    Returns
    -------
    transient.problem.WearProblem
        On the grid ``scene.grid(n)`` of the scene's outline, with the
        scene's load programme, sliding speed and phase geometry.

    Raises
    ------
    ValueError
        A grid too coarse for the outline or the phase geometry (the
        message names ``n`` and the minimum), a phase without a pixel on
        the face at this grid, or a scale out of range
        (:func:`transient.problem.check_run_in_scales`, naming the scene's
        keys); the message starts with the scene file.

    Examples
    --------
    >>> from steady import examples
    >>> scene, options, initial = load_transient_scene(examples.path("voronoi_transient"))
    >>> problem = wear_problem_of(scene, n=40)
    >>> problem.n, problem.n_phases
    (40, 2)
    """
    if problem is None:
        problem = problem_of(scene, n=n)
    try:
        return WearProblem(problem, load_programme=scene.load_programme,
                           sliding_speed=scene.sliding_speed, geometry=scene.geometry,
                           names=scene.input_names())
    except ValueError as err:
        where = "" if scene.source_path is None else f"{scene.source_path}: "
        raise ValueError(f"{where}{err}") from None


def check_run_in_law(scene):
    """Refuse a run-in across interfaces under a law that does not factorise, naming both keys.

    Across the interfaces of a phase map that changes with depth
    (``[depth]``, a 3-d map kind) the run integrates the wear work
    ``g(p)`` and maps it to depth through each segment's ``k_i``: the law
    must be ``k_i g(p)`` (:attr:`steady.wear.WearLaw.factor`).  One
    section of such a scene is a steady problem like any other
    (``runin-steady --depth``), whatever its law.

    Raises
    ------
    ValueError
        ``[wear] law`` without a factorisation on a depth-varying scene.
    """
    if not scene.depth_varying or scene.wear.factor is not None:
        return
    from steady.wear import WEAR_LAWS

    where = ("[depth]" if scene.depth is not None
             else f"[phases] map kind = {scene.geometry.kind!r}")
    laws = " or ".join(repr(kind) for kind in sorted(WEAR_LAWS)
                       if getattr(WEAR_LAWS[kind], "factor", None) is not None)
    raise ValueError(f"[wear] law = {scene.wear.kind!r} and {where}: a run-in across the "
                     f"interfaces of phases that change with depth needs a law k_i g(p) "
                     f"([wear] law = {laws}), whose coefficients k_i change at each "
                     f"interface; runin-steady solves one section of this scene (--depth)")


def load_transient_scene(path, *, n=None):
    """Read a scene file with its ``[transient]`` and ``[initial_face]`` sections.

    Parameters
    ----------
    path : str or path-like
        The scene file.
    n : int, optional
        The grid instead of the scene's ``[grid] n`` (:func:`steady.scene.load_scene`).

    Returns
    -------
    scene : steady.scene.Scene
    options : RunOptions
        The ``[transient]`` options; defaults when the section is absent.
    initial : InitialFace
        Flat when the section is absent.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Any other error of :func:`steady.scene.load_scene` or of the two
        sections, a wear law without a run-in across the scene's
        interfaces (:func:`check_run_in_law`), or an initial face that does
        not repeat with a periodic cell
        (:func:`transient.initial_face.check_outline`).

    Examples
    --------
    >>> from steady import examples
    >>> scene, options, initial = load_transient_scene(examples.path("tilted_transient"))
    >>> initial.kind, initial.recession(scene.grid()).shape
    ('tilted', (64, 64))
    """
    scene = load_scene(path, extra_sections=RUN_IN_SECTIONS, n=n)
    base_dir = pathlib.Path(path).parent
    try:
        check_run_in_law(scene)
        options = (parse_transient(scene.extra["transient"], base_dir,
                                   distance_scale=_distance_scale(scene))
                   if "transient" in scene.extra else RunOptions())
        initial = (parse_initial_face(scene.extra["initial_face"], base_dir)
                   if "initial_face" in scene.extra else InitialFace())
        try:
            check_outline(initial.kind, scene.outline)
        except ValueError as err:
            raise ValueError(f"[initial_face]: {err}") from None
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None
    return scene, options, initial
