"""A seeded storm of bad and edge inputs over every scene section and every command.

A generator (seed :data:`SEED`) draws its cases from the scene schema
itself -- every key of ``[load]``, ``[counterbody]``, ``[grid]``,
``[phases]`` and ``[depth]``, of every registered kind of ``[punch]``,
``[phases] map``, ``[wear]``, ``[sliding]`` and ``[initial_face]``, and every
``[transient]`` option -- and from the flags of the five commands:

- mutations of a valid scene: wrong types, NaN and infinities, negative,
  zero, huge and tiny values, empty lists, wrong counts, missing and
  unknown keys and sections;
- bad files wherever a file is named (the scene, masks, phase maps,
  micrographs, voxel stacks, initial faces, measured maps, design tables,
  outputs): missing, empty, truncated, a directory, a symbolic-link loop, a
  named pipe, another format, complex or boolean arrays;
- bad flags (negative values in exponent form among them), and ``--resume``
  of a run made under another problem;
- valid edge cases: extreme forces, moduli, wear ratios and exponents,
  n = 8, a one-pixel phase, every kind of every table.

Each case runs in a process of its own, with a timeout: most in a worker
process that runs the commands in-process (``launch(module, argv)``, as
``python -m`` does) and is replaced when a case hangs, some in a fresh
``python -m`` process.  Every case must end without a traceback, within
:data:`TIMEOUT`, with a status of the README's table (0, 1, 2, 130).  A
bad input exits 2 with one line ``error: ...`` holding the fragment its
case names (the key as the scene writes it, the flag, or the file name) and
writes nothing.  A valid edge case exits 0 (1 where the README says so: a
run stopped by its limits) and writes a result of finite numbers whose
pressures carry the load.  Some inputs are bad or valid depending on how far
the model reaches (a tolerance of 1e300, a tiny volume fraction): refused
naming their key, or a valid result.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import os
import pathlib
import re
import select
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np
import pytest
from conftest import CRITICAL_TILT, E_STAR, FORCE, K1, RADIUS, one_error_line, temporaries
from test_bad_inputs import header_only

from steady.cli.common import EXIT_STATUS_EPILOG
from steady.schema import SCALE_UNITS, Key

TESTS = pathlib.Path(__file__).resolve().parent
ROOT = TESTS.parent

#: The generator's seed.
SEED = 3583
#: Seconds a case may take (the slowest valid case takes about 5 s alone).
TIMEOUT = 30.0
#: Worker processes run side by side.
WORKERS = 2
#: Share of the cases run in a fresh ``python -m`` process instead of a worker.
FRESH_SHARE = 0.06
#: The exit statuses of the README's table.
STATUSES = (0, 1, 2, 130)

#: Each command: its module (what :func:`steady.cli.entry.launch` imports) and ``python -m``.
COMMANDS = {
    "steady": ("steady.cli.solve", "steady"),
    "transient": ("transient.cli.runin", "transient"),
    "fit": ("steady.cli.fit", "steady.cli.fit"),
    "design": ("steady.cli.design", "steady.cli.design"),
    "examples": ("steady.cli.examples", "steady.cli.examples"),
}

DELETE = object()


# -- scenes as data ----------------------------------------------------------------------------
class Raw(str):
    """TOML text written as it is (what no Python value writes: a date, a bare word)."""


def toml_value(value):
    """TOML text of a value (nested tables inline)."""
    if isinstance(value, Raw):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"test setup: no TOML for {value!r}")


def toml_text(scene):
    """A scene (``section -> table``) as TOML; a section that is not a table comes first."""
    lines = [f"{name} = {toml_value(table)}" for name, table in scene.items()
             if not isinstance(table, dict)]
    for name, table in scene.items():
        if isinstance(table, dict):
            lines.append(f"[{name}]")
            lines += [f"{key} = {toml_value(value)}" for key, value in table.items()]
    return "\n".join(lines) + "\n"


def voronoi(n_seeds=16, fill=(0.7, 0.3), seed=2029):
    return {"kind": "voronoi", "n_seeds": n_seeds, "fill_factors": list(fill), "seed": seed}


def base(d=None, *, n=16, **sections):
    """A valid scene: the epoxy cylinder with 16 Voronoi seeds, k_1/k_0 = 10; ``sections`` replace.

    ``d``, the case's directory, is unused: every scene maker takes it.
    """
    scene = {"punch": {"radius": RADIUS}, "load": {"normal_force": FORCE},
             "counterbody": {"E_star": E_STAR}, "grid": {"n": n},
             "wear": {"coefficients": [K1, 10 * K1]}, "phases": {"map": voronoi()}}
    scene.update(sections)
    return scene


def as_runin(scene):
    """The scene with a ``[transient]`` section (a coarse tolerance: runs of a second)."""
    scene.setdefault("transient", {})
    scene["transient"].setdefault("tol", 1e-3)
    return scene


def set_at(scene, path, value):
    """Set (or with :data:`DELETE` remove) the value at ``path`` (sections, keys, indices).

    A missing section or table on the way is added.
    """
    *parents, last = path
    table = scene
    for part in parents:
        table = table.setdefault(part, {}) if isinstance(part, str) else table[part]
    if value is DELETE:
        del table[last]
    else:
        table[last] = copy.deepcopy(value)  # a maker runs once per case: never shared


# -- files ---------------------------------------------------------------------------------------
def disk_labels(n, phase_of=lambda x, y: (x > 0.3).astype(np.int8)):
    """Phase labels on the disk's n x n grid, -1 off the face; ``phase_of(x, y)`` in units of a."""
    from steady.outline import Circle

    grid = Circle(RADIUS).grid(n)
    x, y = np.meshgrid(grid.unit_x, grid.unit_y, indexing="ij")
    return np.where(grid.mask, phase_of(x, y), -1).astype(np.int8)


def write_labels(d, name="labels.npy", n=16):
    np.save(d / name, disk_labels(n))


def write_mask(d, name="mask.npy"):
    mask = np.ones((8, 8), dtype=bool)
    mask[0, 0] = mask[0, -1] = mask[-1, 0] = mask[-1, -1] = False
    np.save(d / name, mask)


def write_grey(d, name="grey.png", size=64, levels=2, seed=4093):
    """A grey-level micrograph: ``levels`` grey levels in bands, with noise, as a PNG."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    band = (np.arange(size)[:, None] * levels // size) * np.ones((1, size), dtype=int)
    grey = (band + 0.5) / levels + rng.normal(0.0, 0.02, (size, size))
    Image.fromarray((np.clip(grey, 0, 1) * 255).astype(np.uint8)).save(d / name)


def write_stack(d, name="stack.npy"):
    """A voxel stack (16 x 16 x 4): phase 1 grows with depth."""
    slices = [disk_labels(16, lambda x, y, c=c: (x > c).astype(np.int8))
              for c in (0.5, 0.2, -0.1, -0.4)]
    np.save(d / name, np.stack(slices, axis=-1))


def write_recession(d, name="rec.npy", n=16):
    grid_x = np.linspace(-1, 1, n)[:, None] * np.ones((1, n))
    np.save(d / name, 1e-6 * grid_x)


def npy(path, array):
    """Save ``array`` as a ``.npy`` file at ``path`` exactly (whatever its suffix)."""
    with open(path, "wb") as f:
        np.save(f, array, allow_pickle=array.dtype == object)


def symlink_loop(path):
    os.symlink(path.name, path)


def fifo(path):
    os.mkfifo(path)


def write_hdf5(path):
    with h5py.File(path, "w") as f:
        f["x"] = np.zeros(3)


#: Bad contents of a file: ``name -> writer(path)``.
BAD_FILES = {
    "missing": lambda p: None,
    "empty": lambda p: p.write_bytes(b""),
    "a directory": lambda p: p.mkdir(),
    "a symbolic-link loop": symlink_loop,
    "a named pipe": fifo,
    "text": lambda p: p.write_text("0 1\n1 0\n"),
    "an HDF5 file": write_hdf5,
    "a PNG signature only": lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n"),
    "a GIF": lambda p: p.write_bytes(b"GIF89a" + bytes(64)),
    "a truncated .npy": lambda p: header_only(p, (16, 16)),
    "a .npy claiming 10^5 x 10^5": lambda p: header_only(p, (100000, 100000)),
    "complex numbers": lambda p: npy(p, np.ones((16, 16), dtype=complex)),
    "booleans": lambda p: npy(p, np.ones((16, 16), dtype=bool)),
    "floats": lambda p: npy(p, np.zeros((16, 16))),
    "NaN": lambda p: npy(p, np.full((16, 16), np.nan)),
    "a 1-d array": lambda p: npy(p, np.arange(16, dtype=np.int8) % 2),
    "a 3-d array": lambda p: npy(p, np.arange(512, dtype=np.int8).reshape(16, 16, 2) % 2),
    "pickled objects": lambda p: npy(p, np.array([{"a": 1}], dtype=object)),
    "the wrong shape": lambda p: npy(p, np.arange(144, dtype=np.int8).reshape(12, 12) % 2),
}


# -- cases ---------------------------------------------------------------------------------------
@dataclasses.dataclass
class Case:
    """One input and what must come of it.

    ``prepare(d)`` writes the case's files into the directory ``d`` and
    returns the command's arguments; ``before(d)`` (optional) the set-up
    runs, ``[(command, argv, statuses)]``, run first.  ``expect``:
    ``"bad"`` (exit 2, one ``error:`` line holding ``fragment``, a string or
    a compiled pattern, nothing written), ``"valid"`` (an exit status of
    ``statuses``, then ``check(d, stdout, argv)`` lists what is wrong) or ``"either"`` (one or the
    other).  ``forbid``: a pattern the error line must not hold.
    """

    name: str
    command: str
    prepare: object
    expect: str
    fragment: object = None
    check: object = None
    statuses: tuple = (0,)
    before: object = None
    forbid: object = None
    fresh: bool = False


def scene_case(name, command, make, expect, fragment=None, *, flags=(), statuses=(0,),
               **options):
    """A case running ``command`` on the scene ``make(d)`` (a dict) written to ``s.toml``."""
    def prepare(d):
        scene = make(d)
        if command == "transient":
            as_runin(scene)
        (d / "s.toml").write_text(toml_text(scene))
        return [d / "s.toml", "-o", d / "out.h5", *[str(f).format(d=d) for f in flags]]
    check = options.pop("check", CHECKS.get(command))
    return Case(name, command, prepare, expect, fragment, check=check, statuses=statuses,
                **options)


# -- what a result must hold -------------------------------------------------------------------
def check_steady(d, stdout, argv):
    """A steady result: finite, its pressures carry the load (phase by phase without sliding)."""
    from steady.output import read_result

    stored = read_result(d / "out.h5")
    r = stored.result
    face = r.labels >= 0
    h = r.outline.grid(r.n).h
    problems = []
    for name, values in (("pressure", r.pressure[face]), ("face", r.face[face]),
                         ("reference_slope", r.reference_slope),
                         ("rms_slope_plain", r.rms_slope_plain)):
        if not np.all(np.isfinite(values)):
            problems.append(f"{name} not finite")
    if not (math.isfinite(r.rms_slope) or math.isnan(r.rms_slope) and "--no-slope-error"
            in argv):
        problems.append(f"rms_slope {r.rms_slope}")
    load = float(np.sum(r.pressure)) * h * h
    if not abs(load - r.normal_force) <= 1e-9 * r.normal_force:
        problems.append(f"sum p h^2 = {load!r} N, F_N = {r.normal_force!r} N")
    if "[sliding]" not in stored.scene_text:
        counts = np.array([np.sum(r.labels == i) for i in range(len(r.phase_pressures))])
        present = counts > 0
        phases = float(np.sum(counts[present] * r.phase_pressures[present])) * h * h
        if not np.all(np.isfinite(r.phase_pressures[present])) or not abs(
                phases - r.normal_force) <= 1e-9 * r.normal_force:
            problems.append(f"sum A_i p_i = {phases!r} N, F_N = {r.normal_force!r} N")
    return problems


def check_run(d, stdout, argv):
    """A run file: a finite state whose final pressure carries the force of its distance."""
    from transient.output import read_run

    result, attrs, arrays = read_run(d / "out.h5")
    face = arrays["phase"] >= 0
    h = float(attrs["pixel_size"])
    force = (result.load_programme.force_at(result.distance) if result.load_programme
             else float(attrs["normal_force"]))
    problems = []
    for name, values in (("pressure", result.pressure[face]),
                         ("worn_depth", result.worn_depth[face]),
                         *((f"history {k}", result.history[k]) for k in (
                             "distance", "rms_slope", "spread", "rms_height"))):
        if not np.all(np.isfinite(values)):
            problems.append(f"{name} not finite")
    load = float(np.sum(result.pressure)) * h * h
    if not abs(load - force) <= 1e-9 * force:
        problems.append(f"final sum p h^2 = {load!r} N, force {force!r} N")
    return problems


def check_fit(d, stdout, argv):
    """A fit of a face the model made: finite ratios, pressures that carry the load."""
    from steady.fit_files import read_fit

    attrs = read_fit(d / "out.h5").attrs
    problems = []
    if not np.all(np.isfinite(attrs["ratios"])) or not np.all(attrs["ratios"] > 0):
        problems.append(f"ratios {attrs['ratios']}")
    # The model's face interpolated onto the measured pixels of its own grid: measured
    # within 2e-3 of 1 on these scenes.
    if not abs(float(attrs["load_scale"]) - 1) < 1e-2:
        problems.append(f"load scale {attrs['load_scale']}")
    return problems


def check_design(d, stdout, argv):
    numbers = re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|nan|inf", stdout)
    bad = [v for v in numbers if not math.isfinite(float(v))]
    return [f"not finite in {stdout!r}"] if bad or not numbers else []


def check_examples(d, stdout, argv):
    from steady.scene import load_scene

    written = [pathlib.Path(line) for line in stdout.splitlines() if line.strip()]
    problems = [f"{p} not written" for p in written if not (d / p).is_file()]
    for p in written:
        if p.suffix == ".toml" and (d / p).is_file():
            load_scene(d / p)
    return problems


CHECKS = {"steady": check_steady, "transient": check_run, "fit": check_fit,
          "design": check_design, "examples": check_examples}


# -- one valid scene per kind ------------------------------------------------------------------
def _mask_scene(d):
    write_mask(d)
    return base(punch={"shape": "mask", "path": "mask.npy", "pixel_size": 1e-3})


SHAPES = {
    "circle": lambda d: base(),
    "rectangle": lambda d: base(n=24, punch={"shape": "rectangle", "width": 2 * RADIUS / 3,
                                           "length": 2 * RADIUS}),
    "ellipse": lambda d: base(punch={"shape": "ellipse", "semi_axis_x": RADIUS,
                                     "semi_axis_y": RADIUS / 2}),
    "annulus": lambda d: base(punch={"shape": "annulus", "inner_radius": RADIUS / 2,
                                     "outer_radius": RADIUS}),
    "mask": _mask_scene,
    "periodic": lambda d: base(punch={"shape": "periodic", "width": 2 * RADIUS,
                                      "length": 2 * RADIUS}),
}


def _file_map(d):
    write_labels(d)
    return base(phases={"map": {"kind": "file", "path": "labels.npy"}})


def _micrograph(d, **keys):
    write_grey(d)
    table = {"kind": "micrograph", "path": "grey.png", "n_phases": 2, "thresholds": [0.5],
             "crop": [[0, 64], [0, 64]], "smoothing": 0.5, "fill_holes": True,
             "fill_phases": [1], "min_speck": 1, "pixel_size": 1.3e-4, "cover": "crop",
             "offset": [0.0, 0.0]}
    table.update(keys)
    return base(phases={"map": {k: v for k, v in table.items() if v is not DELETE}})


def _voxels(d):
    write_stack(d)
    return base(phases={"map": {"kind": "voxels", "file": "stack.npy", "voxel_depth": 2e-4}})


def _inclusions(**keys):
    table = {"kind": "inclusions", "radius": RADIUS / 4, "seed": 2417, "fill_factor": 0.2,
             "radius_spread": 0.1, **keys}
    return base(n=24, phases={"map": {k: v for k, v in table.items() if v is not DELETE}})


MAPS = {
    "homogeneous": lambda d: base(wear={"coefficients": [K1]},
                                  phases={"map": {"kind": "homogeneous"}}),
    "voronoi": lambda d: base(),
    "rods": lambda d: base(n=24, phases={"map": {
        "kind": "rods", "centres": [[0.0, 0.0], [0.6 * RADIUS, 0.0]],
        "radii": [RADIUS / 4, RADIUS / 4], "matrix_phase": 0, "rod_phases": [1, 1]}}),
    "inclusions": lambda d: _inclusions(),
    "inclusions by count": lambda d: _inclusions(fill_factor=DELETE, count=4.0),
    "file": _file_map,
    "micrograph": _micrograph,
    "voxels": _voxels,
    "spheres": lambda d: base(phases={"map": {
        "kind": "spheres", "radius": RADIUS / 4, "volume_fraction": 0.2, "seed": 2411,
        "depth": 2e-3, "spread": 0.2, "matrix_phase": 0, "particle_phase": 1}}),
}

LAWS = {
    "power": {"law": "power", "coefficients": [K1, 10 * K1], "exponent": 1.5},
    "archard": {"law": "archard", "coefficients": [K1, 10 * K1]},
    "threshold": {"law": "threshold", "coefficients": [K1, 10 * K1], "thresholds": [1e4, 0.0],
                  "exponent": 1.0},
    "table": {"law": "table", "pressures": [[0.0, 1e5, 2e5], [0.0, 1e5, 2e5]],
              "rates": [[0.0, 1e-9, 3e-9], [0.0, 1e-8, 3e-8]]},
}

SLIDINGS = {
    "translation": lambda d: base(sliding={"kind": "translation"}),
    "pin_on_disk": lambda d: base(sliding={"kind": "pin_on_disk", "track_radius": 5 * RADIUS}),
    "rotation": lambda d: dict(SHAPES["annulus"](d), sliding={"kind": "rotation"}),
}


def _face(kind, **keys):
    def make(d):
        if kind == "file":
            write_recession(d)
        return base(initial_face={"kind": kind, **keys})
    return make


FACES = {
    "flat": _face("flat"),
    "tilted": _face("tilted", angle=0.2 * CRITICAL_TILT, azimuth=0.3),
    "crowned": _face("crowned", sphere_radius=1.0),
    "file": _face("file", path="rec.npy"),
}


def layered(*layers, substrate=None, law=None):
    """Layers from the surface down over a homogeneous substrate (phase 0); coating phase 1."""
    return lambda d: base(wear=dict(law or {"coefficients": [10 * K1, K1]}),
                          phases={"names": ["substrate", "coating"],
                                  "map": substrate or {"kind": "homogeneous"}},
                          depth={"kind": "layers", "layers": [dict(x) for x in layers]})


COATING = {"thickness": 3e-4, "phase": 1}
DEPTH = layered(COATING, {"thickness": 2e-4, "map": voronoi(fill=(0.5, 0.5))})

#: Valid values of the optional keys absent from the scenes above.
SAMPLES = {
    ("load", "sliding_speed"): 0.1, ("load", "programme"): [[500.0, 20.0]],
    ("phases", "names"): ["matrix", "grains"],
    ("transient", "scheme"): "sdirk2", ("transient", "tol"): 1e-3,
    ("transient", "fixed_step"): 4000.0, ("transient", "first_step"): 10.0,
    ("transient", "spread_tol"): 1e-5, ("transient", "shape_tol"): 1e-5,
    ("transient", "jump_spread"): 1e-2, ("transient", "jump_step_s_star"): 1e6,
    ("transient", "distance_limit"): 1e7, ("transient", "max_steps"): 500,
    ("transient", "end_depth"): 1e-3, ("transient", "snapshot_distances"): [1e3, 1e4],
    ("transient", "snapshots_s_star"): [0.1, 1.0], ("transient", "max_failures"): 5,
    ("transient", "checkpoint_interval"): 5.0, ("transient", "contact_rtol"): 1e-9,
}


@dataclasses.dataclass(frozen=True)
class Target:
    """A key of the schema: where it sits in a scene, its declaration, a scene that has it."""

    what: str          # for case names: "[punch] (rectangle) width"
    path: tuple        # ("phases", "map", "n_seeds")
    key: Key
    make: object       # make(d) -> a valid scene holding the key
    runin: bool = False


def _with(make, path, value):
    def scene(d):
        s = make(d)
        set_at(s, path, value)
        return s
    return scene


def _value_at(scene, path):
    for part in path:
        scene = scene[part]
    return scene


def schema_targets():
    """Every key of the scene schema, with a valid scene that holds it."""
    from steady.outline import OUTLINES
    from steady.phases import PHASE_MAPS
    from steady.scene import DEPTH_KEYS, LAYER_KEYS, PHASE_KEYS, SECTIONS
    from steady.sliding import SLIDING
    from steady.wear import WEAR_LAWS
    from transient.initial_face import INITIAL_FACES
    from transient.options import option_keys

    load = _with(base, ("load",), {"normal_force": FORCE, "sliding_speed": 0.1,
                                   "programme": [[500.0, 20.0]]})
    # The layer's keys go together: each is mutated beside the other.
    layer = _with(load, ("counterbody",), {"E_star": E_STAR, "thickness": 2e-3, "poisson": 0.3})
    targets = [Target(f"[{section}] {key.name}", (section, key.name), key,
                      layer if key.name in ("thickness", "poisson") else load)
               for section, keys in SECTIONS.items() for key in keys]
    targets += [Target(f"[phases] {key.name}", ("phases", key.name), key,
                       _with(base, ("phases", key.name), SAMPLES["phases", key.name]))
                for key in PHASE_KEYS]
    targets += [Target(f"[depth] {key.name}", ("depth", key.name), key, DEPTH)
                for key in DEPTH_KEYS]
    targets += [Target(f"[depth] layers[0] {key.name}", ("depth", "layers", 0, key.name), key,
                       DEPTH) for key in LAYER_KEYS]
    for registry, section, scenes, path in (
            (OUTLINES, "punch", SHAPES, ("punch",)),
            (PHASE_MAPS, "phases", MAPS, ("phases", "map")),
            (SLIDING, "sliding", SLIDINGS, ("sliding",)),
            (INITIAL_FACES, "initial_face", FACES, ("initial_face",))):
        for kind in registry:
            for key in registry[kind].keys:
                make = scenes["inclusions by count"] if key.name == "count" else scenes[kind]
                targets.append(Target(f"[{section}] ({kind}) {key.name}",
                                      (*path, key.name), key, make, section == "initial_face"))
    for law in WEAR_LAWS:
        for key in WEAR_LAWS[law].keys:
            targets.append(Target(f"[wear] ({law}) {key.name}", ("wear", key.name), key,
                                  _with(base, ("wear",), dict(LAWS[law]))))
    runin = lambda d: as_runin(base())  # noqa: E731
    for key in option_keys():
        targets.append(Target(f"[transient] {key.name}", ("transient", key.name), key,
                              _with(runin, ("transient", key.name),
                                    SAMPLES["transient", key.name]), True))
    return targets


# -- mutations of one key, from its declaration ------------------------------------------------
def _scale(key):
    """Whether the key is a length, force or modulus: a scale whose range is checked."""
    return key.unit in SCALE_UNITS and key.low == 0.0


def _number_mutations(key, value, rng):
    """(label, value, verdict) of a number or an integer."""
    out = [("a string", str(value), "bad"), ("true", True, "bad"), ("a list", [value], "bad"),
           ("NaN", math.nan, "bad"), ("a date", Raw("1979-05-27"), "bad")]
    out.append(("inf", math.inf, "bad" if key.finite or key.type == "integer" else "either"))
    out.append(("-inf", -math.inf, "bad" if key.low is not None or key.finite else "either"))
    magnitude = abs(value) or 1.0
    if key.low is not None:
        below = key.low - magnitude * float(rng.choice([1e-3, 1.0, 1e3]))
        out.append(("below its range", int(below) if key.type == "integer" else below, "bad"))
        out.append(("at its lower bound", key.low, "bad" if key.low_open else "either"))
    else:
        out.append(("negative", -magnitude, "either"))
    if key.high is not None:
        out.append(("above its range", key.high * 2 + 1, "bad"))
        out.append(("at its upper bound", key.high, "bad" if key.high_open else "either"))
    if key.type == "integer":
        out += [("not whole", value + 0.5, "bad"), ("a whole float", float(value), "bad"),
                ("2^63", 2 ** 63, "either"), ("10^30", 10 ** 30, "either")]
    elif key.high is None:
        verdict = "bad" if _scale(key) else "either"
        out += [("huge", float(rng.choice([1e40, 1e300, 1.7e308])), verdict),
                ("tiny", float(rng.choice([1e-40, 1e-300, 5e-324])), verdict)]
    return out


def _list_mutations(key, value, rng):
    """(label, value, verdict) of an array key."""
    counted = "bad" if key.required or key.per_phase else "either"
    out = [("a scalar", value[0] if value else 1.0, "bad"), ("a table", {"a": 1}, "bad"),
           ("empty", [], counted), ("one more", [*value, value[-1]], counted),
           ("one fewer", value[:-1], counted)]
    if key.type in ("numbers", "integers"):
        first = value[0]
        out += [("strings", ["a"] * len(value), "bad"), ("NaN inside", [math.nan, *value[1:]],
                                                          "bad"),
                ("nested", [value], "bad")]
        if key.low is not None:
            out.append(("a negative entry", [-abs(first) - 1, *value[1:]], "bad"))
        if key.high is not None:
            out.append(("an entry above its range", [key.high * 2 + 1, *value[1:]], "bad"))
        if key.type == "integers":
            out.append(("a fraction inside", [first + 0.5, *value[1:]], "bad"))
        elif _scale(key):
            out.append(("a huge entry", [1e300, *value[1:]], "bad"))
    elif key.type == "pairs":
        out += [("a flat list", [1.0, 2.0], "bad"), ("a triple", [[0.0, 0.0, 0.0]], "bad"),
                ("NaN inside", [[math.nan, 1.0], *value[1:]], "bad")]
    elif key.type == "number_lists":
        out += [("a flat list", list(value[0]), "bad"), ("strings inside", [["a"]] * len(value),
                                                          "bad"),
                ("NaN inside", [[math.nan, *value[0][1:]], *value[1:]], "bad")]
    elif key.type == "strings":
        out += [("an empty name", ["", *value[1:]], "bad"), ("numbers", [1, 2], "bad")]
    return out


def mutations(key, value, rng):
    """Every (label, new value or :data:`DELETE`, verdict) of a key holding ``value``."""
    out = [("missing", DELETE, "bad" if key.required else "either")]
    if key.type in ("number", "integer"):
        out += _number_mutations(key, value, rng)
    elif key.type == "pair":
        out += [("three numbers", [0.0, 0.0, 0.0], "bad"), ("one number", [0.0], "bad"),
                ("NaN inside", [math.nan, 0.0], "bad"), ("a string", "0 0", "bad")]
    elif key.type in ("string", "path"):
        out += [("a number", 1, "bad"), ("empty", "", "bad"), ("a list", [value], "bad"),
                ("a null byte", "a\0b", "bad"), ("true", True, "bad")]
        if key.type == "string":
            out.append(("an unknown name", "bogus", "bad"))
    elif key.type == "boolean":
        out += [("a string", "true", "bad"), ("an integer", 1, "bad")]
    else:
        out += _list_mutations(key, list(value), rng)
    return out


#: Mutations per key (drawn at random among its applicable ones).
PER_KEY = 3


def schema_cases(rng, scratch):
    """Mutations of every key of the schema (``scratch``: a directory for the scenes' files)."""
    cases = []
    for target in schema_targets():
        value = _value_at(target.make(scratch), target.path)
        options = mutations(target.key, value, rng)
        chosen = rng.choice(len(options), size=min(PER_KEY, len(options)), replace=False)
        for i in sorted(chosen):
            label, new, verdict = options[i]
            command = "transient" if target.runin else str(rng.choice(["steady", "transient"]))
            # A run-in that accepts an odd setting may stop on it (exit 1, resumable).
            statuses = (0, 1) if command == "transient" else (0,)
            cases.append(scene_case(f"{target.what}: {label}", command,
                                    _with(target.make, target.path, new), verdict,
                                    target.key.name, forbid=_forbidden(target),
                                    statuses=statuses))
    return cases


def _forbidden(target):
    """What a message on the table law must not say: the power law's key (and its reprs)."""
    return re.compile(r"\bcoefficients\b") if "(table)" in target.what else None


# -- tables, sections and scene files ----------------------------------------------------------
def table_cases(rng):
    """An unknown key in every table; every selector mistyped; sections missing or unknown."""
    tables = [("[load]", base, ("load",)), ("[counterbody]", base, ("counterbody",)),
              ("[grid]", base, ("grid",)), ("[phases]", base, ("phases",)),
              ("[depth]", DEPTH, ("depth",)), ("[depth] layers[0]", DEPTH, ("depth", "layers", 0))]
    tables += [(f"[punch] ({k})", make, ("punch",)) for k, make in SHAPES.items()]
    tables += [(f"[phases] map ({k})", make, ("phases", "map")) for k, make in MAPS.items()]
    tables += [(f"[wear] ({k})", _with(base, ("wear",), dict(law)), ("wear",))
               for k, law in LAWS.items()]
    tables += [(f"[sliding] ({k})", make, ("sliding",)) for k, make in SLIDINGS.items()]
    tables += [(f"[initial_face] ({k})", make, ("initial_face",)) for k, make in FACES.items()]
    tables.append(("[transient]", lambda d: as_runin(base()), ("transient",)))
    cases = []
    for what, make, path in tables:
        runin = path[0] in ("initial_face", "transient")
        command = "transient" if runin else str(rng.choice(["steady", "transient"]))
        cases.append(scene_case(f"{what}: an unknown key", command,
                                _with(make, (*path, "colour"), "red"), "bad",
                                "unknown key 'colour'"))
    selectors = [("[punch] shape", SHAPES["rectangle"], ("punch", "shape"), "either"),
                 ("[phases] map kind", base, ("phases", "map", "kind"), "bad"),
                 ("[wear] law", _with(base, ("wear",), dict(LAWS["table"])), ("wear", "law"),
                  "either"),
                 ("[sliding] kind", SLIDINGS["pin_on_disk"], ("sliding", "kind"), "either"),
                 ("[initial_face] kind", FACES["tilted"], ("initial_face", "kind"), "either")]
    for what, make, path, missing in selectors:
        name = path[-1]
        runin = path[0] == "initial_face"
        for label, value, verdict in (("an unknown name", "bogus", "bad"),
                                      ("a number", 1, "bad"), ("a list", ["circle"], "bad"),
                                      ("missing", DELETE, missing)):
            command = "transient" if runin else str(rng.choice(["steady", "transient"]))
            # A missing kind takes the default, whose keys then differ: either is named.
            fragment = name if verdict == "bad" else re.compile(
                rf"{name}|unknown key|missing key")
            cases.append(scene_case(f"{what}: {label}", command, _with(make, path, value),
                                    verdict, fragment))
    for section in ("punch", "load", "counterbody", "grid", "wear", "phases"):
        cases.append(scene_case(f"[{section}]: missing", str(rng.choice(["steady", "transient"])),
                                _with(base, (section,), DELETE), "bad", section))
        cases.append(scene_case(f"[{section}]: a number", str(rng.choice(["steady", "transient"])),
                                _with(base, (section,), 3), "bad", section))
    cases.append(scene_case("[colour]: an unknown section", "steady",
                            _with(base, ("colour",), {"red": 1}), "bad", "colour"))
    return cases


def _scene_file(write):
    """A case maker: the scene ``s.toml`` written by ``write(path)``."""
    def prepare(d):
        write(d / "s.toml")
        return [d / "s.toml", "-o", d / "out.h5"]
    return prepare


def scene_file_cases(rng):
    """The scene file itself: every bad file, bad text, a BOM, for the three scene commands."""
    text = toml_text(base())
    cases = []
    writers = {kind: write for kind, write in BAD_FILES.items()
               if kind not in ("complex numbers", "booleans", "floats", "NaN", "a 1-d array",
                               "a 3-d array", "the wrong shape", "a .npy claiming 10^5 x 10^5")}
    writers.update({
        "not UTF-8": lambda p: p.write_bytes(text.encode() + b"# \xff\n"),
        "malformed TOML": lambda p: p.write_text(text.replace("[grid]", "[grid")),
        "a duplicate key": lambda p: p.write_text(text.replace("[grid]", "[grid]\nn = 8")),
        "over 1 MiB": lambda p: p.write_text(text + "#" * 2 ** 20 + "\n"),
        "nested 10^5 deep": lambda p: p.write_text(text.replace(
            "[grid]", "[grid]\nbad = " + "[" * 100_000 + "]" * 100_000)),
        "only comments": lambda p: p.write_text("# nothing here\n"),
        "a NUL byte": lambda p: p.write_text(text.replace("[grid]", "[grid]\0")),
    })
    for kind, write in writers.items():
        for command in ("steady", "transient") if kind in ("a symbolic-link loop", "a named pipe",
                                                          "not UTF-8") else (
                str(rng.choice(["steady", "transient"])),):
            cases.append(Case(f"scene file: {kind}", command, _scene_file(write), "bad",
                              "s.toml"))
    bom = re.compile(r"(?i)byte.order mark|\bBOM\b|U\+FEFF")
    for command in ("steady", "transient"):
        body = text if command == "steady" else toml_text(as_runin(base()))
        cases.append(Case("scene file: a UTF-8 byte-order mark", command, _scene_file(
            lambda p, body=body: p.write_bytes(b"\xef\xbb\xbf" + body.encode())), "either", bom,
            check=CHECKS[command]))
    return cases


# -- bad files where a scene or a command names one --------------------------------------------
def _file_place(key_path, make, npy, png=None):
    """A place a file is named: the scene ``make(d)`` with ``key_path`` set to the file's name."""
    def scene_with(kind):
        name = png if png and kind in ("a PNG signature only", "a GIF") else npy

        def scene(d):
            s = make(d)
            set_at(s, key_path, name)
            BAD_FILES[kind](d / name)
            return s
        return scene, name
    return scene_with


#: Places a scene names a file: (place, command, maker, verdicts other than bad).
FILE_PLACES = [
    ("[punch] mask path", None, _file_place(("punch", "path"), SHAPES["mask"], "m.npy", "m.png"),
     {"booleans": "either", "the wrong shape": "either"}),
    ("[phases] map file path", None, _file_place(("phases", "map", "path"), MAPS["file"],
                                                 "p.npy", "p.png"),
     {"booleans": "either"}),
    ("[phases] map micrograph path", None, _file_place(
        ("phases", "map", "path"), MAPS["micrograph"], "g.npy", "g.png"),
     {"booleans": "either", "floats": "either", "the wrong shape": "either"}),
    ("[phases] map voxels file", None, _file_place(("phases", "map", "file"), MAPS["voxels"],
                                                   "v.npy"),
     {"booleans": "either", "a 3-d array": "valid"}),
    ("[initial_face] file path", "transient", _file_place(("initial_face", "path"),
                                                          FACES["file"], "h.npy"),
     {"floats": "valid"}),
]


def file_cases(rng):
    """Every bad file at every place a scene names one.

    Symbolic-link loops, complex and boolean arrays and PNG signatures always; others drawn.
    """
    always = ("a symbolic-link loop", "complex numbers", "booleans", "a PNG signature only")
    cases = []
    for place, command, scene_with, verdicts in FILE_PLACES:
        others = [k for k in BAD_FILES if k not in always]
        drawn = [others[i] for i in sorted(rng.choice(len(others), size=8, replace=False))]
        for kind in (*always, *drawn):
            make, name = scene_with(kind)
            verdict = verdicts.get(kind, "bad")
            cmd = command or str(rng.choice(["steady", "transient"]))
            cases.append(scene_case(f"{place}: {kind}", cmd, make, verdict, name))
    return cases


def output_cases(rng):
    """Outputs (-o, --plot, --segmentation) that cannot be written."""
    cases = []
    for command in ("steady", "transient", "fit"):
        for option, name in (("-o", "out.h5"), ("--plot", "fig.png")):
            if command == "fit" and option == "--plot" and rng.random() < 0.5:
                continue
            for kind in ("a directory", "a symbolic-link loop", "a named pipe"):
                cases.append(_output_case(command, option, name, kind))
    return cases


def _output_case(command, option, name, kind):
    def prepare(d):
        argv = _valid_argv(command, d)
        BAD_FILES[kind](d / name)
        if option != "-o":
            argv += [option, d / name]
        return argv
    return Case(f"{command} {option}: {kind}", command, prepare, "bad", name)


def _valid_argv(command, d, scene=None, flags=()):
    """A valid run of ``command`` in ``d`` writing ``out.h5`` (the fit of a model's face)."""
    scene = scene or base()
    if command == "transient":
        as_runin(scene)
    (d / "s.toml").write_text(toml_text(scene))
    if command != "fit":
        return [d / "s.toml", "-o", d / "out.h5", *flags]
    path, pixel = _measured(d)
    return [d / "s.toml", path, "-o", d / "out.h5", "--pixel-size", pixel, *flags]


def _measured(d, name="measured.npy"):
    """The steady face of ``d/s.toml`` as a measured map: its path and pixel size (m, text)."""
    from steady.scene import load_scene
    from steady.solution import solve_scene

    scene = load_scene(d / "s.toml")
    face = solve_scene(scene, face_only=True).face
    if name.endswith(".npy"):
        np.save(d / name, face)
    else:
        np.savetxt(d / name, face)
    return d / name, repr(scene.outline.grid(scene.n).h)


# -- flags -------------------------------------------------------------------------------------
def _flag_keys():
    """``command -> {flag: (Key, fragment)}``: every number flag of the commands."""
    from transient.options import RunOptions

    def number(low=0.0, low_open=True, high=None, finite=True, kind="number", unit=""):
        return Key("flag", kind, low=low, low_open=low_open, high=high, finite=finite, unit=unit)

    memory = number(finite=False)
    flags = {
        "steady": {"--depth": number(low_open=False, unit="m"), "--memory-limit": memory},
        "transient": {"--memory-limit": memory},
        "fit": {"--pixel-size": number(unit="m"), "--height-scale": number(),
                "--max-shift": number(low_open=False, unit="m"),
                "--rim-margin": number(low_open=False, unit="m"),
                "--n": number(low=8, low_open=False, kind="integer"),
                "--reference-phase": number(low=0, low_open=False, high=1, kind="integer"),
                "--confidence": number(high=1.0), "--memory-limit": memory},
        "design": {"--pbar-over-estar": number(), "--wear-ratio": number(),
                   "--fill-factor": number(low_open=False, high=1.0),
                   "--target-slope": number()},
    }
    for field in dataclasses.fields(RunOptions):
        if field.metadata["flag"] and field.name != "scheme":
            flags["transient"]["--" + field.name.replace("_", "-")] = field.metadata["key"]
    return flags


#: How messages may name a flag besides its name and its words.
FLAG_WORDS = {"--n": r"\bn = \d", "--target-slope": r"target", "--pbar-over-estar": r"pbar/E\*"}


def _flag_fragment(flag, value=None):
    """The flag's name (or its words), and the value when given."""
    words = flag.strip("-").replace("-", "[ _-]") if flag != "--n" else FLAG_WORDS[flag]
    if flag in FLAG_WORDS:
        words += "|" + FLAG_WORDS[flag]
    named = rf"(?:{re.escape(flag)}\b|{words})"
    return re.compile(named + (rf".*{value}" if value else ""))


def _flag_values(key):
    """(label, text, verdict) of a flag's value."""
    scale_free = "either"
    out = [("a word", "abc", "bad"), ("NaN", "nan", "bad"), ("empty", "", "bad"),
           ("inf", "inf", "bad" if key.finite else scale_free),
           ("1e999", "1e999", "bad" if key.finite else scale_free)]
    if key.low is not None and key.low >= 0:
        out += [("-1", "-1", "bad"), ("-1e-4", "-1e-4", "bad")]
        if key.low == 0:
            out.append(("0", "0", "bad" if key.low_open else "either"))
        else:
            out.append(("below its range", str(int(key.low) - 1), "bad"))
    if key.high is not None:
        out.append(("above its range", repr(key.high * 2 + 1), "bad"))
    if key.type == "integer":
        out += [("2.5", "2.5", "bad"), ("1e3", "1e3", "bad")]
    else:
        # A length beyond the range of every scale is refused, saying so.
        out.append(("huge", "1e300", "bad" if _scale(key) else "either"))
    return out


DESIGN = {"--pbar-over-estar": "0.08", "--wear-ratio": "0.01", "--fill-factor": "0.2"}


def _flag_argv(command, d, flag, value):
    if command == "design":
        values = dict(DESIGN)
        if flag == "--target-slope":
            del values["--fill-factor"]
        values[flag] = value
        return [a for pair in values.items() for a in pair]
    scene = DEPTH(d) if flag == "--depth" else base()
    argv = _valid_argv(command, d, scene)
    if flag == "--pixel-size":
        argv = argv[:-2]  # the valid one
    return [*argv, flag, value] if value != "" else [*argv, f"{flag}="]


def flag_cases(rng):
    """Bad values of every number flag: three drawn, and the negative ones in exponent form."""
    cases = []
    for command, flags in _flag_keys().items():
        for flag, key in flags.items():
            options = _flag_values(key)
            chosen = set(rng.choice(len(options), size=min(3, len(options)), replace=False))
            chosen |= {i for i, (label, _, _) in enumerate(options) if label == "-1e-4"}
            for i in sorted(chosen):
                label, value, verdict = options[i]
                value_text = {"-1e-4": r"-(?:1e-0?4|0\.0001)"}.get(label)
                if label == "huge" and verdict == "bad":
                    value_text = r"1e\+30\b"  # the range it is outside
                fragment = _flag_fragment(flag, value_text)
                cases.append(Case(f"{command} {flag} {label}", command,
                                  lambda d, c=command, f=flag, v=value: _flag_argv(c, d, f, v),
                                  verdict, fragment, check=CHECKS[command]))
    words = [("steady", ["--fast"], "--fast"), ("transient", ["--scheme", "rk4"], "--scheme"),
             ("transient", ["--resume", "--force"], "--force"), ("fit", ["--bogus"], "--bogus"),
             ("steady", ["--plot", "{d}/fig.txt"], "--plot"),
             ("transient", ["--plot", "{d}/fig"], "--plot"),
             ("steady", ["--segmentation", "{d}/seg.png"], "--segmentation")]
    for command, extra, fragment in words:
        cases.append(Case(f"{command} {' '.join(extra)}", command,
                          lambda d, c=command, e=extra: _valid_argv(
                              c, d, flags=[x.format(d=d) for x in e]), "bad", fragment))
    cases.append(Case("steady without -o", "steady", lambda d: _valid_argv("steady", d)[:1],
                      "bad", "-o"))
    cases.append(Case("design without --wear-ratio", "design",
                      lambda d: ["--pbar-over-estar", "0.08", "--fill-factor", "0.2"], "bad",
                      "--wear-ratio"))
    cases.append(Case("design with two questions", "design",
                      lambda d: [*sum(DESIGN.items(), ()), "--target-slope", "0.2"],
                      "bad", "--target-slope"))
    return cases


# -- --resume ----------------------------------------------------------------------------------
def _stopped(make, steps=2):
    """Set-up: the scene ``make(d)`` run for ``steps`` steps (stopped, resumable) as out.h5."""
    def before(d):
        scene = as_runin(make(d))
        scene["transient"]["max_steps"] = steps
        (d / "first.toml").write_text(toml_text(scene))
        return [("transient", [d / "first.toml", "-o", d / "out.h5"], (1,))]
    return before


def _resume(make, *extra):
    def prepare(d):
        (d / "s.toml").write_text(toml_text(as_runin(make(d))))
        return [d / "s.toml", "-o", d / "out.h5", "--resume", *extra]
    return prepare


def resume_cases(rng):
    """``--resume`` of a run made under another problem (refused), or of the same one."""
    law = lambda name: _with(base, ("wear",), dict(LAWS[name]))  # noqa: E731
    other = [
        ("other kinematics", SLIDINGS["pin_on_disk"], base),
        ("pin-on-disk at another track radius", SLIDINGS["pin_on_disk"],
         _with(SLIDINGS["pin_on_disk"], ("sliding", "track_radius"), 7 * RADIUS)),
        ("another wear law", law("threshold"), law("power")),
        ("other thresholds", law("threshold"),
         _with(law("threshold"), ("wear", "thresholds"), [2e4, 0.0])),
        ("another exponent", law("power"), _with(law("power"), ("wear", "exponent"), 2.0)),
        ("another load programme", _with(base, ("load", "programme"), [[500.0, 20.0]]), base),
        ("another initial face", FACES["tilted"], FACES["flat"]),
        ("other layers", DEPTH, layered(COATING)),
    ]
    cases = [Case(f"--resume under {what}", "transient", _resume(then), "bad",
                  re.compile(r"out\.h5"), before=_stopped(first)) for what, first, then in other]
    cases.append(Case("--resume of the same scene", "transient", _resume(base), "valid",
                      check=check_run, before=_stopped(base)))
    cases.append(Case("--resume with no run file", "transient", _resume(base), "valid",
                      check=check_run))
    for kind in ("empty", "text", "an HDF5 file", "a symbolic-link loop", "a directory"):
        def prepare(d, kind=kind):
            BAD_FILES[kind](d / "out.h5")
            return _resume(base)(d)
        cases.append(Case(f"--resume of {kind}", "transient", prepare, "bad", "out.h5"))
    cases.append(Case("--resume of a steady result", "transient", _resume(base), "bad", "out.h5",
                      before=lambda d: [("steady", _valid_argv("steady", d), (0,))]))
    cases.append(Case("a run file without --resume or --force", "transient",
                      lambda d: _valid_argv("transient", d), "bad", "out.h5",
                      before=_stopped(base)))
    return cases


# -- the classes a round of reports found ------------------------------------------------------
def _otsu(n_phases, coefficients):
    def make(d):
        write_grey(d, "grey128.png", size=128, levels=6)
        return base(wear={"coefficients": [K1 * (i + 1) for i in range(coefficients)]},
                    phases={"map": {"kind": "micrograph", "path": "grey128.png",
                                    "n_phases": n_phases, "pixel_size": 6.5e-5}})
    return make


def _law(name, **keys):
    return _with(base, ("wear",), {**LAWS[name], **keys})


def known_cases(rng):
    """Cases of each class reported before (hangs, silent results, unclear refusals)."""
    grid_n = re.compile(r"\[grid\] n\b|\bn = \d")
    table = re.compile(r"\b(rates|pressures)\b")
    coefficients = re.compile(r"\bcoefficients\b")
    # A plateau is a valid table (rates non-decreasing): solved, or refused in its own terms.
    power = re.compile(r"\bcoefficients\b|power law")
    plateau = [[0.0, 1e-9, 1e-9], [0.0, 1e-8, 3e-8]]
    cases = [
        scene_case("[transient] end_depth 1e-12", "transient",
                   _with(base, ("transient",), {"tol": 1e-3, "end_depth": 1e-12}), "either",
                   "end_depth"),
        scene_case("[transient] end_depth 1e-13 under layers", "transient",
                   _with(DEPTH, ("transient",), {"tol": 1e-3, "end_depth": 1e-13,
                                                 "scheme": "bdf2"}), "either", "end_depth"),
        scene_case("micrograph: Otsu of 6 phases", "steady", _otsu(6, 6), "either",
                   re.compile(r"thresholds|n_phases")),
        scene_case("micrograph: 10 phases, 2 coefficients", "steady", _otsu(10, 2), "bad",
                   re.compile(r"n_phases|coefficients")),
        scene_case("micrograph: 4 phases, 3 coefficients", "transient", _otsu(4, 3), "bad",
                   re.compile(r"n_phases|coefficients")),
        scene_case("[wear] (table) a plateau", "steady", _law("table", rates=plateau), "either",
                   table, forbid=power),
        scene_case("[wear] (table) a plateau, run in", "transient", _law("table", rates=plateau),
                   "either", table, forbid=power),
        scene_case("[wear] (table) rates of 1e-300", "steady", _law("table", rates=[
            [0.0, 1e-300, 3e-300], [0.0, 1e-300, 3e-300]]), "bad", table, forbid=coefficients),
        scene_case("[wear] (table) rates of 1e300", "transient", _law("table", rates=[
            [0.0, 1e300, 3e300], [0.0, 1e300, 3e300]]), "bad", table, forbid=coefficients),
    ]
    for value in (1e-320, 1e-40, 1e40):
        cases.append(scene_case(f"[load] sliding_speed {value:g}", "transient",
                                _with(base, ("load", "sliding_speed"), value), "bad",
                                "sliding_speed"))
    cases.append(scene_case("[load] sliding_speed 1e-320, steady", "steady",
                            _with(base, ("load", "sliding_speed"), 1e-320), "bad",
                            "sliding_speed"))
    for name in ("threshold", "table"):
        layers = layered(COATING, law={**LAWS[name]})
        cases.append(scene_case(f"[depth] layers with the {name} law", "transient", layers,
                                "either", re.compile(r"\[wear\] law"),
                                forbid=re.compile(r"Law\b")))
    cases.append(scene_case("[depth] layers with the threshold law, steady", "steady",
                            layered(COATING, law=LAWS["threshold"]), "either",
                            re.compile(r"\[wear\] law")))
    for value in (2 ** 63, 10 ** 19, 10 ** 30):
        cases.append(scene_case(f"[grid] n = {value}", str(rng.choice(["steady", "transient"])),
                                _with(base, ("grid", "n"), value), "bad", grid_n))
    for value in (1e-6, 1e-9):
        cases.append(scene_case(f"[phases] map (spheres) volume_fraction {value:g}",
                                str(rng.choice(["steady", "transient"])),
                                _with(MAPS["spheres"], ("phases", "map", "volume_fraction"),
                                      value), "either",
                                re.compile(r"volume_fraction|no voxel")))
    return cases


# -- valid edge cases --------------------------------------------------------------------------
def _log_uniform(rng, low, high):
    return float(10 ** rng.uniform(math.log10(low), math.log10(high)))


def _one_pixel_phase(d):
    labels = np.where(disk_labels(16) >= 0, 0, -1).astype(np.int8)
    labels[8, 8] = 1
    np.save(d / "one.npy", labels)
    return base(phases={"map": {"kind": "file", "path": "one.npy"}})


def _n8(d):
    np.save(d / "eight.npy", disk_labels(8, lambda x, y: (y > 0).astype(np.int8)))
    return base(n=8, phases={"map": {"kind": "file", "path": "eight.npy"}})


def edge_scenes(rng):
    """(name, scene maker, flags, statuses) of valid scenes: extremes within range, every kind."""
    edges = []
    for low, high, path, what in ((1e-6, 1e6, ("load", "normal_force"), "force"),
                                  (1e3, 1e12, ("counterbody", "E_star"), "E*"),
                                  (0.3, 3.0, ("wear", "exponent"), "exponent m")):
        for value in (low, high, _log_uniform(rng, low, high)):
            edges.append((f"{what} {value:.3g}", _with(base, path, value)))
    for ratio in (1e-6, 1e6, _log_uniform(rng, 1e-6, 1e6)):
        edges.append((f"k ratio {ratio:.3g}", _with(base, ("wear", "coefficients"),
                                                    [K1, K1 * ratio])))
    edges += [("n = 8", _n8), ("a one-pixel phase", _one_pixel_phase),
              ("[load] programme", SAMPLED["programme"]),
              ("[load] sliding_speed", SAMPLED["sliding_speed"]),
              ("[phases] names", SAMPLED["names"]),
              ("[depth] layers", DEPTH), ("[depth] a coating", layered(COATING))]
    edges += [(f"[punch] {k}", make) for k, make in SHAPES.items()]
    edges += [(f"[phases] map {k}", make) for k, make in MAPS.items()]
    edges += [("[phases] map micrograph by Otsu", lambda d: _micrograph(d, thresholds=DELETE))]
    edges += [(f"[wear] {k}", _with(base, ("wear",), dict(law))) for k, law in LAWS.items()]
    edges += [(f"[sliding] {k}", make) for k, make in SLIDINGS.items()]
    return edges


SAMPLED = {
    "programme": _with(base, ("load", "programme"), [[500.0, 20.0]]),
    "sliding_speed": _with(base, ("load", "sliding_speed"), 0.1),
    "names": _with(base, ("phases", "names"), ["matrix", "grains"]),
}


def valid_cases(rng):
    """Every edge scene through both commands; run-in options, faces and flags; --depth."""
    cases = []
    for name, make in edge_scenes(rng):
        for command in ("steady", "transient"):
            cases.append(scene_case(f"valid: {name}", command, make, "valid"))
    for kind, make in FACES.items():
        cases.append(scene_case(f"valid: [initial_face] {kind}", "transient", make, "valid"))
    for (section, key), value in SAMPLES.items():
        if section == "transient":
            # A run ended by its own limits exits 1 (stopped): the README's table.
            statuses = (0, 1) if key in ("distance_limit", "max_steps", "fixed_step") else (0,)
            cases.append(scene_case(f"valid: [transient] {key} = {value}", "transient",
                                    _with(base, ("transient", key), value), "valid",
                                    statuses=statuses))
    cases.append(scene_case("valid: [transient] max_steps = 1", "transient",
                            _with(base, ("transient", "max_steps"), 1), "valid", statuses=(1,)))
    cases.append(scene_case("valid: [transient] jump_spread = inf", "transient",
                            _with(base, ("transient", "jump_spread"), math.inf), "valid"))
    cases.append(scene_case("valid: [transient] end_depth reached under layers", "transient",
                            _with(DEPTH, ("transient", "end_depth"), 6e-4), "valid"))
    from transient.stepping import SCHEMES

    for scheme in sorted(SCHEMES):
        cases.append(scene_case(f"valid: --scheme {scheme}", "transient", base, "valid",
                                flags=["--scheme", scheme], statuses=(0, 1)))
    for depth in ("0", "1e-4", "4e-4", "1.0"):
        cases.append(scene_case(f"valid: --depth {depth}", "steady", DEPTH, "valid",
                                flags=["--depth", depth]))
    for flags in (["-v"], ["--plot", "{d}/fig.png"], ["--memory-limit", "inf"], ["--force"]):
        for command in ("steady", "transient"):
            cases.append(scene_case(f"valid: {' '.join(flags)}", command, base, "valid",
                                    flags=flags))
    cases.append(scene_case("valid: --no-slope-error", "steady", base, "valid",
                            flags=["--no-slope-error"]))
    cases.append(scene_case("valid: --no-grid-error", "transient", base, "valid",
                            flags=["--no-grid-error"]))
    cases.append(scene_case("valid: --segmentation", "steady", MAPS["micrograph"], "valid",
                            flags=["--segmentation", "{d}/seg.png"]))
    return cases


# -- runin-fit, runin-design, runin-examples ---------------------------------------------------
def _fit(make=base, measured="measured.npy", flags=(), bad=None):
    """A fit of the model's face of ``make(d)``; ``bad``: (writer, name) of a bad measured map."""
    def prepare(d):
        (d / "s.toml").write_text(toml_text(make(d)))
        path, pixel = _measured(d, measured)
        if bad is not None:
            write, name = bad
            path = d / name
            write(path)
        return [d / "s.toml", path, "-o", d / "out.h5", "--pixel-size", pixel, *flags]
    return prepare


def fit_cases(rng):
    """Measured maps good and bad, scenes the fit refuses."""
    cases = [Case("valid: fit of the model's face", "fit", _fit(), "valid", check=check_fit),
             Case("valid: fit of a text grid", "fit", _fit(measured="measured.txt"), "valid",
                  check=check_fit),
             Case("valid: fit of rods, --shift --rim-margin", "fit", _fit(
                 MAPS["rods"], flags=["--shift", "--rim-margin", "5e-4"]), "valid",
                  check=check_fit),
             Case("valid: fit with --confidence 0.5", "fit", _fit(flags=["--confidence", "0.5"]),
                  "valid", check=check_fit)]
    for kind in ("missing", "empty", "a directory", "a symbolic-link loop", "a named pipe",
                 "an HDF5 file", "complex numbers", "booleans", "NaN", "a 1-d array",
                 "a truncated .npy", "pickled objects", "text", "a 3-d array"):
        cases.append(Case(f"fit measured map: {kind}", "fit",
                          _fit(bad=(BAD_FILES[kind], "m.npy")), "bad", "m.npy"))
    for kind in ("a PNG signature only", "a GIF"):
        cases.append(Case(f"fit measured map: {kind}", "fit",
                          _fit(bad=(BAD_FILES[kind], "m.png")), "bad", "m.png"))
    for kind in ("empty", "a NUL byte", "words"):
        write = {"empty": lambda p: p.write_text("# only a comment\n"),
                 "a NUL byte": lambda p: p.write_bytes(b"1 2\n\x00 3\n"),
                 "words": lambda p: p.write_text("one two\nthree four\n")}[kind]
        cases.append(Case(f"fit measured text grid: {kind}", "fit", _fit(bad=(write, "m.txt")),
                          "bad", "m.txt"))
    cases.append(Case("fit measured map: zeros", "fit", _fit(
        bad=(lambda p: np.save(p, np.zeros((16, 16))), "m.npy")), "either", "m.npy",
        check=check_fit, statuses=(0, 1)))
    for what, make, fragment in (
            ("the table law", _with(base, ("wear",), dict(LAWS["table"])), "law"),
            ("pin-on-disk sliding", SLIDINGS["pin_on_disk"], "sliding")):
        cases.append(Case(f"fit refuses {what}", "fit", _fit(make), "bad", fragment))
    return cases


def _design_table(kind):
    def prepare(d):
        BAD_FILES[kind](d / "t.h5")
        return [*sum(DESIGN.items(), ()), "--table", d / "t.h5"]
    return prepare


def design_cases(rng):
    """Queries in and out of the table; design tables that are not one."""
    cases = []
    for _ in range(4):
        ratio, fill = _log_uniform(rng, 1e-4, 1e4), float(rng.uniform(0.01, 0.99))
        argv = ["--pbar-over-estar", f"{_log_uniform(rng, 1e-3, 0.3):.4g}",
                "--wear-ratio", f"{ratio:.4g}", "--fill-factor", f"{fill:.4g}"]
        cases.append(Case(f"valid: design {' '.join(argv)}", "design", lambda d, a=argv: a,
                          "valid", check=check_design))
    for target in ("0.05", "0.2"):
        argv = ["--pbar-over-estar", "0.08", "--wear-ratio", "0.01", "--target-slope", target]
        cases.append(Case(f"design --target-slope {target}", "design", lambda d, a=argv: a,
                          "either", re.compile("target"), check=check_design))
    for flag, value in (("--wear-ratio", "1e6"), ("--wear-ratio", "1e-9"),
                        ("--fill-factor", "0.999"), ("--pbar-over-estar", "10")):
        values = {**DESIGN, flag: value}
        cases.append(Case(f"design {flag} {value}", "design",
                          lambda d, v=values: [*sum(v.items(), ())], "either",
                          _flag_fragment(flag), check=check_design))
    for kind in ("missing", "empty", "a directory", "a symbolic-link loop", "text",
                 "an HDF5 file", "a named pipe"):
        cases.append(Case(f"design --table: {kind}", "design", _design_table(kind), "bad",
                          "t.h5"))
    return cases


def examples_cases(rng):
    """Listing, copying, and where a copy cannot go."""
    from steady.examples import list_examples

    names = sorted(list_examples())
    cases = [Case("valid: examples list", "examples", lambda d: [], "valid",
                  check=lambda d, out, argv: [] if all(n in out for n in names) else [out])]
    for name in rng.choice(names, size=4, replace=False):
        cases.append(Case(f"valid: examples {name}", "examples",
                          lambda d, n=str(name): [n, "-o", d / "ex"], "valid",
                          check=check_examples))
    copy = lambda d: [names[0], "-o", d / "ex"]  # noqa: E731
    cases += [
        Case("examples: an unknown name", "examples", lambda d: ["bogus", "-o", d / "ex"], "bad",
             "bogus"),
        Case("examples: copied twice", "examples", copy, "bad", names[0],
             before=lambda d: [("examples", copy(d), (0,))]),
        Case("examples: -o a file", "examples",
             lambda d: (d / "ex").write_text("x") and copy(d), "bad", "ex"),
        Case("examples: -o a symbolic-link loop", "examples",
             lambda d: symlink_loop(d / "ex") or copy(d), "bad", "ex"),
        Case("examples: --force without a name", "examples", lambda d: ["--force"], "bad",
             "--force"),
    ]
    return cases


# -- the storm ---------------------------------------------------------------------------------
FAMILIES = (schema_cases, table_cases, scene_file_cases, file_cases, output_cases, flag_cases,
            resume_cases, known_cases, valid_cases, fit_cases, design_cases, examples_cases)


def storm(seed, scratch):
    """Every case, in a random order; a share of them marked to run in a fresh process."""
    rng = np.random.default_rng(seed)
    cases = []
    for family in FAMILIES:
        cases += family(rng, scratch) if family is schema_cases else family(rng)
    for case in cases:
        case.fresh = bool(rng.random() < FRESH_SHARE)
    return [cases[i] for i in rng.permutation(len(cases))]


def serve():
    """Worker: run the commands a parent sends on stdin, one JSON line each; answer on stdout.

    As ``python -m`` runs them (:func:`steady.cli.entry.launch`), with the
    interpreter's default warnings (not the test suite's), stdout and stderr
    captured; an exception that escapes the command is printed as Python
    prints it (a traceback) with status 1.
    """
    import contextlib
    import io
    import logging
    import traceback

    from steady.cli.entry import launch

    answer = sys.stdout
    for line in sys.stdin:
        request = json.loads(line)
        os.chdir(request["cwd"])
        logging.root.handlers.clear()  # each command sets up its log on its own stderr
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                status = launch(request["module"], request["argv"])
            except SystemExit as done:
                status = done.code if isinstance(done.code, int) else (
                    0 if done.code is None else 1)
            except BaseException:  # noqa: BLE001 -- what Python would print
                traceback.print_exc()
                status = 1
        answer.write(json.dumps({"status": status, "stdout": out.getvalue(),
                                 "stderr": err.getvalue()}) + "\n")
        answer.flush()


class Worker:
    """A worker process (:func:`serve`), started on demand and replaced after a hang."""

    def __init__(self, log):
        self.log = log
        self.proc = None

    def run(self, module, argv, cwd, timeout):
        """``(status, stdout, stderr)``; None after ``timeout`` seconds (the worker is killed)."""
        if self.proc is None or self.proc.poll() is not None:
            code = f"import sys; sys.path.insert(0, {str(TESTS)!r}); import test_input_storm " \
                   f"as storm; storm.serve()"
            self.proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=self.log, text=True)
        self.proc.stdin.write(json.dumps({"module": module, "argv": argv, "cwd": str(cwd)})
                              + "\n")
        self.proc.stdin.flush()
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            self.close()
            return None
        line = self.proc.stdout.readline()
        if not line:  # the worker died (a crash of the interpreter)
            status = self.proc.wait()
            return status, "", f"the process ended with status {status}"
        done = json.loads(line)
        return done["status"], done["stdout"], done["stderr"]

    def close(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
        if self.proc is not None:
            self.proc.wait()
            self.proc.stdin.close()
            self.proc.stdout.close()
        self.proc = None


def run_fresh(command, argv, cwd, timeout):
    """``(status, stdout, stderr)`` of ``python -m ...`` in a process of its own, or None."""
    try:
        done = subprocess.run([sys.executable, "-m", COMMANDS[command][1], *argv], cwd=cwd,
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    return done.returncode, done.stdout, done.stderr


def _files(d):
    """Every file below ``d`` (not following links) with its size and time."""
    found = {}
    for path in sorted(d.rglob("*")):
        st = path.lstat()
        if not path.is_dir() or path.is_symlink():
            found[str(path.relative_to(d))] = (st.st_size, st.st_mtime_ns)
    return found


def _matches(pattern, text):
    return pattern.search(text) if isinstance(pattern, re.Pattern) else pattern in text


def _key_fragment(fragment):
    """A key's name as a whole word (``seed`` is not ``n_seeds``); other fragments as given."""
    if isinstance(fragment, str) and re.fullmatch(r"\w+", fragment):
        return re.compile(rf"(?<![\w.]){fragment}(?!\w)")
    return fragment


#: What a message must not show: Python's reprs (numpy scalars and arrays, TOML dates as
#: datetime objects) and the catch-all of errors nobody foresaw.
INTERNALS = re.compile(r"\bnp\.\w+\(|\barray\(|\bdatetime\.\w+\("
                       r"|\bunexpected \w+(Error|Exception)\b")


def judge(case, outcome, d, argv, files_before):
    """What is wrong with the outcome of a case (an empty list: nothing)."""
    if outcome is None:
        return [f"no answer within {TIMEOUT:g} s (a hang)"]
    status, out, err = outcome
    problems = []
    if "Traceback" in err:
        return [f"a traceback: {err[-600:]!r}"]
    if status not in STATUSES:
        return [f"exit status {status}, not one of {STATUSES}: {err[-300:]!r}"]
    lines = [line for line in err.splitlines() if line.startswith("error: ")]
    if lines:
        if re.search(INTERNALS, lines[0]):
            problems.append(f"the message shows Python's internals: {lines[0][:300]!r}")
        if case.forbid is not None and _matches(case.forbid, lines[0]):
            problems.append(f"the message names {case.forbid.pattern!r}: {lines[0][:300]!r}")
    expected = {"bad": (2,), "valid": case.statuses,
                "either": (2, *case.statuses)}[case.expect]
    if status not in expected:
        return problems + [f"exit {status}, expected {expected}: {err[-400:]!r}"]
    if status == 2:
        try:
            line = one_error_line(err)
        except AssertionError as failed:
            return problems + [str(failed)[:400]]
        if not _matches(_key_fragment(case.fragment), line):
            wanted = getattr(case.fragment, "pattern", case.fragment)
            problems.append(f"the error line lacks {wanted!r}: {line[:400]!r}")
        if out:
            problems.append(f"stdout after a refusal: {out[:200]!r}")
        if _files(d) != files_before:
            problems.append("files written or changed after a refusal: "
                            f"{sorted(set(_files(d)) ^ set(files_before))}")
        return problems
    # A stopped run-in (exit 1) keeps a valid state; a failed fit's file need not be finite.
    stopped = status == 1 and case.command == "transient" and (d / "out.h5").exists()
    if case.check is not None and (status == 0 or stopped):
        try:
            problems += case.check(d, out, [str(a) for a in argv])
        except Exception as failed:  # noqa: BLE001 -- a result that cannot be read is a finding
            problems.append(f"the result: {type(failed).__name__}: {str(failed)[:300]}")
    left = temporaries(d) + sorted(p.name for p in d.glob("*.lock"))
    if left:
        problems.append(f"left behind: {left}")
    return problems


def run_case(case, d, worker):
    """Prepare, run (after the set-up runs) and judge one case: its problems."""
    d.mkdir()
    problems = []
    for command, argv, statuses in case.before(d) if case.before else ():
        done = worker.run(COMMANDS[command][0], [str(a) for a in argv], d, TIMEOUT)
        if done is None or done[0] not in statuses:
            return [f"set-up {command} {argv}: {done}"]
    argv = [str(a) for a in case.prepare(d)]
    before = _files(d)
    if case.fresh:
        outcome = run_fresh(case.command, argv, d, TIMEOUT)
    else:
        outcome = worker.run(COMMANDS[case.command][0], argv, d, TIMEOUT)
    return problems + judge(case, outcome, d, argv, before)


@pytest.mark.slow
def test_input_storm(tmp_path):
    """Every case of the storm: no traceback, no hang, the documented status and message."""
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    cases = storm(SEED, scratch)
    logs = [open(tmp_path / f"worker{i}.log", "w") for i in range(WORKERS)]  # noqa: SIM115
    workers = [Worker(log) for log in logs]
    started = time.monotonic()

    def run(i):
        import threading

        worker = workers[int(threading.current_thread().name.rsplit("_", 1)[-1])]
        return run_case(cases[i], tmp_path / f"case{i:03d}", worker)

    try:
        with ThreadPoolExecutor(WORKERS, thread_name_prefix="storm") as pool:
            results = list(pool.map(run, range(len(cases))))
    finally:
        for worker in workers:
            worker.close()
        for log in logs:
            log.close()
    failures = [f"{cases[i].name} [{cases[i].command}"
                f"{', fresh' if cases[i].fresh else ''}]: {'; '.join(p)}"
                for i, p in enumerate(results) if p]
    stray = [line for log in logs for line in pathlib.Path(log.name).read_text().splitlines()
             if "Traceback" in line]
    print(f"{len(cases)} cases in {time.monotonic() - started:.0f} s, {len(failures)} failed")
    assert not failures and not stray, \
        f"{len(failures)} of {len(cases)} cases failed:\n" + "\n".join(failures) + \
        "".join(f"\nworker stderr: {line}" for line in stray)


# -- fast checks: the generator, and the table the statuses come from --------------------------
def test_the_storm_covers_every_key_kind_and_command(tmp_path):
    """At least 300 cases; every key of the schema mutated, every kind and command run."""
    from steady.outline import OUTLINES
    from steady.phases import PHASE_MAPS
    from steady.sliding import SLIDING
    from steady.wear import WEAR_LAWS
    from transient.initial_face import INITIAL_FACES

    cases = storm(SEED, tmp_path)
    assert len(cases) >= 300, f"only {len(cases)} cases"
    names = [(c.name, c.command) for c in cases]
    assert len(set(names)) == len(names), \
        f"repeated cases: {sorted({n for n in names if names.count(n) > 1})[:5]}"
    missing = [t.what for t in schema_targets()
               if not any(c.name.startswith(t.what + ": ") for c in cases)]
    assert not missing, f"keys never mutated: {missing}"
    text = " ".join(c.name for c in cases)
    kinds = [f"{section} {kind}" for section, registry in (
        ("[punch]", OUTLINES), ("[phases] map", PHASE_MAPS), ("[wear]", WEAR_LAWS),
        ("[sliding]", SLIDING), ("[initial_face]", INITIAL_FACES)) for kind in registry
        if f"valid: {section} {kind}" not in text]
    assert not kinds, f"kinds without a valid case: {kinds}"
    for command in COMMANDS:
        for expect in ("bad", "valid"):
            assert any(c.command == command and c.expect == expect for c in cases), \
                f"no {expect} case of {command}"
    fresh = sum(c.fresh for c in cases)
    assert 5 <= fresh <= 0.15 * len(cases), f"{fresh} cases in fresh processes"


def _section(text, title):
    body = text.split(f"\n## {title}\n", 1)[1]
    return " ".join(body.split("\n## ", 1)[0].split())


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_help_ends_with_the_exit_statuses(command, capsys):
    """The exit statuses are the end of every ``--help``, word for word."""
    from steady.cli.entry import launch

    with pytest.raises(SystemExit) as done:
        launch(COMMANDS[command][0], ["--help"])
    assert done.value.code == 0, f"--help exit {done.value.code}"
    help_text = " ".join(capsys.readouterr().out.split())
    assert help_text.endswith(EXIT_STATUS_EPILOG), \
        f"{command} --help does not end with the exit statuses: {help_text[-300:]!r}"
    # The table of docs/cli.md is checked against the epilog by tests/test_docs.py.


def test_every_status_the_docs_name_is_in_the_table():
    """Each ``exit status N`` (or ``status N``) the README and docs/cli.md name is the table's."""
    text = " ".join(" ".join((ROOT / name).read_text().split())
                    for name in ("README.md", "docs/cli.md"))
    table = {int(s) for s in re.findall(r"(?:^|; )(\d+) ", EXIT_STATUS_EPILOG.removeprefix(
        "exit status: "))}
    assert table == set(STATUSES), f"the epilog's statuses {sorted(table)}"
    named = {int(s) for s in re.findall(r"\b(?:exit )?status(?:es)? (\d+)\b", text)}
    named |= {int(s) for s in re.findall(r"\(exit (\d+)", text)}
    assert named and named <= table, f"the docs name statuses {sorted(named - table)} " \
                                     f"outside the table {sorted(table)}"
