"""One declaration per scene key: the registries, the documentation's tables, adding a kind.

The scene's keys are declared once (``steady.schema.Key``) in the registries of outlines,
phase maps, wear laws and initial faces, and in the fields of ``RunOptions``; the tables of
docs/scenes.md, drawn from the declarations (``docs/_ext/scene_tables.py``), must list exactly
what is registered, and one registration must be all a new kind needs.
"""

import dataclasses
import pathlib
import re
import sys

import numpy as np
import pytest
from conftest import FORCE, K1, RADIUS, problem, scene_text

from steady.outline import OUTLINES, Circle, MaskOutline
from steady.phases import PHASE_MAPS, PhaseMap
from steady.scene import (
    CORE_SECTIONS,
    DEPTH_KEYS,
    LAYER_KEYS,
    OPTIONAL_SECTIONS,
    PHASE_KEYS,
    RUN_IN_SECTIONS,
    SECTIONS,
    load_scene,
    parse_scene,
)
from steady.schema import Key, read_table
from steady.sliding import SLIDING
from steady.solution import solve, solve_scene
from steady.wear import WEAR_LAWS, ArchardLaw, PowerLaw
from transient.cli.runin import build_parser
from transient.initial_face import INITIAL_FACES, initial_recession
from transient.options import RunOptions, option_keys
from transient.scene import wear_problem_of

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = (ROOT / "docs" / "scenes.md").read_text()
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import scene_tables  # noqa: E402 -- docs/_ext, the documentation's tables of keys


def _documented(name):
    """``kind -> key names`` of the tables docs/scenes.md draws for the scene table ``name``."""
    assert re.search(rf"^```{{scene-keys}} {re.escape(name)}$", SCENES, re.M), \
        f"docs/scenes.md draws no table of {name!r}"
    rows = {}
    for table in scene_tables.tables(name):
        kind = re.search(r'= "(\w+)"', table.caption)
        rows[kind.group(1) if kind else None] = {row[0] for row in table.rows}
    return rows


@pytest.mark.parametrize("registry, name", [(OUTLINES, "punch"), (PHASE_MAPS, "phases.map"),
                                            (WEAR_LAWS, "wear"), (SLIDING, "sliding"),
                                            (INITIAL_FACES, "initial_face")])
def test_docs_tables_list_what_is_registered(registry, name):
    rows = _documented(name)
    assert set(rows) == set(registry), \
        f"docs/scenes.md's tables of {name!r} list {sorted(rows)}, registered {sorted(registry)}"
    for kind, named in rows.items():
        keys = {key.name for key in registry[kind].keys}
        assert named == keys, f"docs/scenes.md's table of {kind!r} names keys {sorted(named)}, " \
                              f"the registered keys are {sorted(keys)}"


def test_docs_tables_cover_every_section_and_run_option():
    """Every section a scene may have, and every option of a run, has its table."""
    sections = set(CORE_SECTIONS) | set(OPTIONAL_SECTIONS) | set(RUN_IN_SECTIONS)
    assert sections | {"phases.map", "depth.layers"} == set(scene_tables.TABLES), \
        f"sections {sorted(sections)}, tables {sorted(scene_tables.TABLES)}"
    for section, keys in {**SECTIONS, "phases": PHASE_KEYS, "depth": DEPTH_KEYS,
                          "depth.layers": LAYER_KEYS}.items():
        assert _documented(section) == {None: {key.name for key in keys}}, section
    options = _documented("transient")[None]
    assert options == {key.name for key in option_keys()}, f"[transient] table: {options}"
    defaults = {row[0]: row[4] for row in scene_tables.tables("transient")[0].rows}
    assert defaults["scheme"] == '"esdirk3"' and defaults["tol"] == f"{RunOptions().tol:g}", \
        f"the run options' defaults: {defaults}"


def test_core_sections_name_their_keys_in_the_docs_example():
    block = SCENES.split("```toml", 1)[1].split("```", 1)[0]
    for section, keys in SECTIONS.items():
        for key in keys:
            assert re.search(rf"\[{section}\]\s*\n(?:[^\[\n]*\n)*{key.name} =", block), \
                f"docs/scenes.md's scene example lacks [{section}] {key.name}"


# -- keys ----------------------------------------------------------------
@pytest.mark.parametrize("key, value, fragment", [
    (Key("n", "integer", low=2, low_open=False), 1.5, "[t] n must be an integer >= 2, got 1.5"),
    (Key("n", "integer", low=2, low_open=False), True, "got True"),
    (Key("f", "number", unit="N", low=0.0), 0, "[t] f must be a number > 0 (N), got 0"),
    (Key("f", "number", unit="N", low=0.0), float("inf"), "got inf"),
    (Key("f", "number", unit="N", low=0.0), "10", "got '10'"),
    (Key("r", "numbers", unit="1", low=0.0, high=1.0), [0.5, 1.5],
     "[t] r must be an array of numbers each in (0, 1) (1), got [0.5, 1.5]"),
    (Key("c", "string", choices=("crop", "tile")), "stretch", "one of 'crop', 'tile'"),
    (Key("p", "path"), "a\0b", "[t] p must not contain a null byte"),
    (Key("o", "pair", unit="m"), [1.0], "[t] o must be an [x, y] pair (m), got [1.0]"),
])
def test_a_bad_value_is_named_with_its_table_key_and_value(key, value, fragment):
    with pytest.raises(ValueError) as err:
        key.parse(value, "[t]")
    assert fragment in str(err.value), f"message {str(err.value)!r}"


def test_read_table_refuses_unknown_and_missing_keys():
    keys = (Key("a", "number", required=True), Key("b", "integer", default=3))
    assert read_table({"a": 1}, "[t]", keys) == {"a": 1.0, "b": 3}, "default filled"
    with pytest.raises(ValueError, match=r"unknown key 'c' in \[t\] \(allowed: a, b\)"):
        read_table({"a": 1, "c": 2}, "[t]", keys)
    with pytest.raises(ValueError, match=r"missing key 'a' in \[t\]"):
        read_table({"b": 1}, "[t]", keys)


def test_a_section_prefix_is_given_once():
    text = scene_text("parser", punch={"shape": "annulus", "inner_radius": -1.0,
                                       "outer_radius": 0.004})
    with pytest.raises(ValueError) as err:
        parse_scene(text, ".")
    assert "[punch] inner_radius must be a number > 0 (m), got -1.0" in str(err.value), \
        str(err.value)
    assert "[punch] [punch]" not in str(err.value), str(err.value)


# -- one registration makes a kind ----------------------------------------
@dataclasses.dataclass(frozen=True)
class _Halves(PhaseMap):
    """Phase 0 left of the face's centre, phase 1 right of it."""

    @property
    def n_phases(self):
        return 2

    def min_grid(self, outline=None):
        return 8

    def check_grid(self, grid):
        return grid.n

    def labels(self, grid):
        right = np.broadcast_to(grid.unit_x[:, None] > 0, grid.shape)
        return np.where(grid.mask, right.astype(np.int64), -1)

    @classmethod
    def from_values(cls, values, context):
        return cls()


def test_a_phase_map_kind_is_one_registration(tmp_path):
    PHASE_MAPS.register("halves", (), doc="two half-disks")(_Halves)
    try:
        path = tmp_path / "s.toml"
        path.write_text(scene_text("steady").replace(
            scene_text("steady").split("map = ", 1)[1].split("\n", 1)[0], '{ kind = "halves" }'))
        result = solve_scene(load_scene(path), face_only=True)
    finally:
        PHASE_MAPS.unregister("halves")
    # Eq. 7: equal areas, k_1 = 10 k_0 -> p_0 = 10 p_1; the map is mirror-symmetric in x.
    p0, p1 = result.phase_pressures
    assert p0 / p1 == pytest.approx(10.0, rel=1e-12), f"phase pressures {p0}, {p1}"
    assert result.fill_factors[0] == pytest.approx(0.5, abs=1e-12), \
        f"half-disks of equal area: {result.fill_factors}"


@dataclasses.dataclass(frozen=True)
class _ScaledArchard(ArchardLaw):
    """Archard's law with every coefficient multiplied by ``factor``."""

    factor: float = 1.0

    @classmethod
    def from_values(cls, values, context):
        return cls(tuple(values["factor"] * k for k in values["coefficients"]),
                   factor=values["factor"])


def test_a_wear_law_is_one_registration(tmp_path):
    keys = ArchardLaw.keys + (Key("factor", "number", unit="1", low=0.0, required=True),)
    WEAR_LAWS.register("scaled_archard", keys)(_ScaledArchard)
    try:
        text = scene_text("steady").replace(
            "[wear]\n", '[wear]\nlaw = "scaled_archard"\nfactor = 4.0\n')
        scaled = parse_scene(text, tmp_path)
    finally:
        WEAR_LAWS.unregister("scaled_archard")
    plain = parse_scene(scene_text("steady"), tmp_path)
    assert isinstance(scaled.wear, _ScaledArchard), f"law {scaled.wear}"
    # The steady face depends on the ratios only; the run-in distance s* = a / (k E*).
    a, b = solve_scene(scaled, face_only=True), solve_scene(plain, face_only=True)
    assert np.allclose(a.face, b.face, rtol=1e-12, equal_nan=True), "steady face"
    ratio = (wear_problem_of(plain).distance_scale
             / wear_problem_of(scaled).distance_scale)
    assert ratio == pytest.approx(4.0, rel=1e-12), f"s* ratio {ratio}"


def test_archard_is_the_power_law_of_exponent_one(tmp_path):
    plain = parse_scene(scene_text("steady"), tmp_path)
    archard = parse_scene(scene_text("steady").replace("[wear]\n", '[wear]\nlaw = "archard"\n'),
                          tmp_path)
    assert isinstance(archard.wear, ArchardLaw) and archard.wear.exponent == 1.0, archard.wear
    a, b = solve_scene(archard, face_only=True), solve_scene(plain, face_only=True)
    assert np.array_equal(a.face, b.face, equal_nan=True), "bit for bit the power law's face"
    with pytest.raises(ValueError, match=r"unknown key 'exponent' in \[wear\] \(law 'archard'\)"):
        parse_scene(scene_text("parser").replace("[wear]\n", '[wear]\nlaw = "archard"\n'),
                    tmp_path)


# -- run options ------------------------------------------------------------
def test_every_run_option_is_a_key_and_every_flag_option_a_flag():
    keys = {key.name for key in option_keys()}
    fields = {f.name for f in dataclasses.fields(RunOptions)}
    assert keys == fields, f"[transient] keys {sorted(keys)} against fields {sorted(fields)}"
    flags = {a.dest for a in build_parser()._actions}
    marked = {f.name for f in dataclasses.fields(RunOptions) if f.metadata["flag"]}
    assert marked <= flags, f"flags missing: {sorted(marked - flags)}"
    assert "contact_rtol" in fields, "contact_rtol is a run option"


def test_a_flag_is_checked_by_its_key(capsys):
    with pytest.raises(SystemExit) as exit_:
        build_parser().parse_args(["s.toml", "-o", "r.h5", "--tol", "-1"])
    assert exit_.value.code == 2, "bad input"
    err = capsys.readouterr().err
    assert "--tol" in err and "a number in (2.22045e-16, 1] (f*)" in err and "'-1'" in err, err


def test_a_run_option_from_python_is_checked_by_its_key():
    with pytest.raises(ValueError,
                       match=r"tol must be a number in \(2.22045e-16, 1\] \(f\*\), got -1"):
        RunOptions(tol=-1)
    with pytest.raises(ValueError, match=r"contact_rtol must be a number in \(0, 1\)"):
        RunOptions(contact_rtol=2.0)
    assert RunOptions(max_steps=10.0).max_steps == 10.0, "a whole float is a whole number"


def test_an_initial_face_kind_is_one_registration():
    keys = (Key("depth", "number", unit="m", low=0.0, required=True, doc="a dimple"),)

    def dimple(grid, depth):
        return np.where(grid.radii < 0.5 * grid.outline.scale, depth, 0.0)

    INITIAL_FACES.register("dimple", keys)(dimple)
    dimple.statistics = None
    try:
        h = initial_recession("dimple", Circle(RADIUS).grid(16), depth=1e-6)
    finally:
        INITIAL_FACES.unregister("dimple")
    assert h.max() == 1e-6 and h.min() == 0.0, "the registered face"


# -- the two messages the restructure mends ---------------------------------
def test_a_phase_without_pixels_is_named_not_counted(tmp_path):
    """A Voronoi phase whose seeds miss every pixel centre: the phase, not the coefficients."""
    text = scene_text("steady", n=16, n_seeds=8, fill_factors=(0.875, 0.125), seed=6)
    scene = parse_scene(text, tmp_path)
    for build in (lambda: solve_scene(scene), lambda: wear_problem_of(scene)):
        with pytest.raises(ValueError) as err:
            build()
        message = str(err.value)
        assert "phase 1 has no pixel on the face" in message and "seed = 6" in message, message
        assert "wear coefficient" not in message, message


def test_a_declared_phase_count_is_not_guessed_from_labels():
    labels = Circle(RADIUS).grid(16).mask.astype(int) - 1  # every face pixel phase 0
    with pytest.raises(ValueError, match=r"phase 1 has no pixel on the face"):
        problem(labels, [K1, 10 * K1], n_phases=2)
    result = solve(problem(labels, [K1], n_phases=1))
    assert result.phase_pressures[0] * result.fill_factors[0] > 0, "one phase carries the load"
    assert result.normal_force == FORCE, "the load"


def test_equal_masks_are_one_outline():
    mask = np.ones((4, 8), dtype=bool)
    mask[0, :2] = False
    a = MaskOutline(mask, 1e-3, source="'a.npy'")
    b = MaskOutline(mask.copy(), 1e-3, source="'b.png'")
    assert a == b and hash(a) == hash(b), "equal pixels and pixel size: one face"
    assert a != MaskOutline(mask, 2e-3), "another pixel size is another face"
    assert initial_recession("flat", a.grid(8)).shape == b.grid(8).shape == (4, 8), \
        "a grid of one mask serves the other"
    shifted = mask.copy()
    shifted[0, 2] = False
    assert a != MaskOutline(shifted, 1e-3), "other pixels are another face"


def test_the_power_law_is_the_default(tmp_path):
    scene = parse_scene(scene_text("parser"), tmp_path)
    assert scene.wear == PowerLaw((1.0e-9, 1.7e-9), 1.0), scene.wear
