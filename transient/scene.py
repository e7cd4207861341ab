"""Scene sections of the run-in: ``[transient]`` and ``[initial_face]``.

They are registered with :func:`steady.scene.load_scene` through its
``extra_sections`` (``steady`` knows nothing of them)::

    [transient]
    scheme = "esdirk3"          # registered integrator (transient.stepping.SCHEMES)
    tol = 1e-5                  # local error per step, rms shape / f*
    spread_tol = 1e-6           # steady: (max - min) / mean of k p^m over the contact ...
    shape_tol = 1e-6            # ... and shape change per s*, in f*
    jump_spread = 1e-3          # jump to the steady state below this spread (0: never)
    jump_step = 1e8             # s*, length of a jump
    max_distance = 1e12         # s*, stop (resumable) beyond this distance
    max_steps = 100000
    step = 0.01                 # s*, optional: fixed steps, no adaptivity
    initial_step = 1e-5         # s*, optional: first adaptive step
    snapshots = [0.1, 1.0, 3.0] # s*, face and pressure stored there
    contact_rtol = 1e-10        # relative tolerance of every contact solve (floor)
    checkpoint_interval = 10.0  # least s of wall clock between checkpoints

    [initial_face]
    kind = "tilted"             # "flat" (default), "tilted", "crowned" or "file"
    angle = 1e-3                # rad (tilted)
    azimuth = 0.0               # rad (tilted, optional)
    # sphere_radius = 0.5       # m (crowned)
    # path = "face.npy"         # (file) height in m on the grid (n x n for a disk),
                                # beside the scene file

Distances are in units of the run-in distance ``s* = L / (k_min E*)``, ``L``
the face outline's scale (the radius ``a`` of a disk; docs/model.md,
"Natural scales").  Every key is optional and checked; unknown
keys are errors.  The initial face kinds and their keys are those registered
in :mod:`transient.initial_face`.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import types

from steady.phases import npy_header
from steady.scene import load_scene
from steady.text import one_line, shorten

from .initial_face import INITIAL_FACES, face_grid, initial_height
from .runin import RunOptions

__all__ = [
    "InitialFace",
    "TransientSettings",
    "load_transient_scene",
    "parse_initial_face",
    "parse_transient",
]

_FLOAT_KEYS = {"tol", "spread_tol", "shape_tol", "jump_spread", "jump_step", "max_distance",
               "step", "initial_step", "checkpoint_interval", "contact_rtol"}
_INT_KEYS = {"max_steps", "max_failures"}
_TRANSIENT_KEYS = _FLOAT_KEYS | _INT_KEYS | {"scheme", "snapshots"}

@dataclasses.dataclass(frozen=True)
class TransientSettings:
    """The ``[transient]`` section.

    Attributes
    ----------
    options : transient.runin.RunOptions
    contact_rtol : float
        Relative tolerance of every contact solve (default 1e-10).
    """

    options: RunOptions = dataclasses.field(default_factory=RunOptions)
    contact_rtol: float = 1e-10


@dataclasses.dataclass(frozen=True)
class InitialFace:
    """The ``[initial_face]`` section: how to build the initial height field.

    Attributes
    ----------
    kind : str
        A registered kind (:data:`transient.initial_face.INITIAL_FACES`):
        ``"flat"`` (default), ``"tilted"``, ``"crowned"`` or ``"file"``.
    parameters : mapping
        The kind's parameters: numbers (rad, m), or for ``"file"`` the
        absolute ``path`` of the ``.npy`` file.
    """

    kind: str = "flat"
    parameters: types.MappingProxyType = dataclasses.field(
        default_factory=lambda: types.MappingProxyType({}))

    def height(self, n, outline=None):
        """Initial height on the grid of ``n`` pixels of a face outline.

        Parameters
        ----------
        n : int or steady.outline.FaceGrid
            Pixels along the longer side of the outline's bounding box
            (across the diameter of a disk), or the grid itself.
        outline : outline object or float
            The face (``scene.outline``); a number is a disk's radius (m)
            (``scene.radius``).

        Returns
        -------
        ndarray, shape of the grid (``(n, n)`` for a disk), m
            Larger = recessed.

        Raises
        ------
        ValueError
            A parameter out of range for this grid and face, or a grid too
            coarse for the outline, named.
        """
        path = self.parameters.get("path")
        try:
            grid = face_grid(n, outline)
            if path is not None:
                # The header first: a wrong shape is refused before the data are read.
                npy_header(path, what="initial face file", shape=grid.shape)
            return initial_height(self.kind, grid, **self.parameters)
        except (OSError, EOFError) as err:  # the file changed since the scene was read
            raise ValueError(f"[initial_face]: cannot read {str(path)!r}: {err}") from None
        except ValueError as err:
            raise ValueError(f"[initial_face]: {one_line(err, 300)}") from None


def _float(table, key):
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{key} must be a number, got {shorten(value)}")
    return float(value)


def parse_transient(table, base_dir):
    """Parse a ``[transient]`` table (``extra_sections`` callback).

    Parameters
    ----------
    table : dict
    base_dir : pathlib.Path
        Unused (no paths in this section).

    Returns
    -------
    TransientSettings

    Raises
    ------
    ValueError
        Unknown key or bad value, named.
    """
    unknown = sorted(set(table) - _TRANSIENT_KEYS)
    if unknown:
        raise ValueError(f"unknown key {shorten(unknown[0])} (allowed: "
                         f"{', '.join(sorted(_TRANSIENT_KEYS))})")
    kw = {}
    for key in _FLOAT_KEYS & set(table):
        kw[key] = _float(table, key)
    for key in _INT_KEYS & set(table):
        value = table[key]
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{key} must be an integer, got {shorten(value)}")
        kw[key] = value
    if "scheme" in table:
        if not isinstance(table["scheme"], str):
            raise ValueError(f"scheme must be a string, got {shorten(table['scheme'])}")
        kw["scheme"] = table["scheme"]
    if "snapshots" in table:
        snaps = table["snapshots"]
        if not isinstance(snaps, list) or any(isinstance(v, bool) or not
                                              isinstance(v, (int, float)) for v in snaps):
            raise ValueError(f"snapshots must be an array of distances in s*, got "
                             f"{shorten(snaps)}")
        kw["snapshots"] = tuple(float(v) for v in snaps)
    contact_rtol = kw.pop("contact_rtol", 1e-10)
    if not (math.isfinite(contact_rtol) and 0 < contact_rtol < 1):
        raise ValueError(f"contact_rtol must lie in (0, 1), got {shorten(contact_rtol)}")
    try:
        options = RunOptions(**kw)
    except ValueError as err:
        raise ValueError(one_line(err, 300)) from None
    return TransientSettings(options=options, contact_rtol=contact_rtol)


def parse_initial_face(table, base_dir):
    """Parse an ``[initial_face]`` table (``extra_sections`` callback).

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
        Unknown kind or key, missing key, a value of the wrong type or a
        missing file, named.
    """
    kind = table.get("kind", "flat")
    if kind not in INITIAL_FACES:
        raise ValueError(f"kind must be one of {sorted(INITIAL_FACES)}, got {shorten(kind)}")
    spec = INITIAL_FACES[kind]
    allowed = set(spec.required) | set(spec.optional) | {"kind"}
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ValueError(f"unknown key {shorten(unknown[0])} for kind {kind!r} (allowed: "
                         f"{', '.join(sorted(allowed))})")
    missing = sorted(set(spec.required) - set(table))
    if missing:
        raise ValueError(f"missing key {missing[0]!r} for kind {kind!r}")
    parameters = {}
    for key in sorted(set(table) - {"kind"}):
        if key == "path":
            path = table[key]
            if not isinstance(path, str) or not path:
                raise ValueError(f"path must be a non-empty string, got {shorten(path)}")
            full = pathlib.Path(base_dir) / path
            npy_header(full, what="initial face file")  # exists, is a .npy, not truncated
            parameters[key] = full
        else:
            value = _float(table, key)
            if not math.isfinite(value):
                raise ValueError(f"{key} must be finite, got {shorten(value)}")
            parameters[key] = value
    return InitialFace(kind, types.MappingProxyType(parameters))


def load_transient_scene(path):
    """Read a scene file with its ``[transient]`` and ``[initial_face]`` sections.

    Returns
    -------
    scene : steady.scene.Scene
    settings : TransientSettings
        Defaults when the section is absent.
    initial : InitialFace
        Flat when the section is absent.

    Raises
    ------
    ValueError
        Any error of :func:`steady.scene.load_scene` or of the two sections.
    """
    scene = load_scene(path, extra_sections={"transient": parse_transient,
                                             "initial_face": parse_initial_face})
    settings = scene.extra.get("transient", TransientSettings())
    initial = scene.extra.get("initial_face", InitialFace())
    return scene, settings, initial
