"""Scene files: parsing, validation, extra sections, shipped scenes."""

import pathlib
import re

import numpy as np
import pytest
from conftest import scene_text

from steady.phases import ArrayMap, Homogeneous, Rods, Voronoi
from steady.scene import load_scene, parse_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]

SCENES = pathlib.Path(__file__).resolve().parent.parent / "steady" / "examples"

#: The gallery's parser scene: every core key present, 100 Voronoi seeds, n = 64.
BASE = scene_text("parser")


def test_parse_base_scene(tmp_path):
    scene = parse_scene(BASE, tmp_path)
    assert scene.outline.radius == 0.004 and scene.normal_force == 10.0, f"{scene}"
    assert scene.E_star == 1.3e6 and scene.n == 64, f"{scene}"
    assert scene.wear.coefficients == (1.0e-9, 1.7e-9), f"{scene.wear.coefficients}"
    assert scene.geometry == Voronoi(100, (0.5, 0.5), 2024), f"{scene.geometry}"
    assert scene.text == BASE, "raw text must be kept"
    assert dict(scene.extra) == {}, f"extra {scene.extra}"


def test_exponent_defaults_to_one(tmp_path):
    text = scene_text("parser", exponent=None)
    assert "exponent" not in text, f"test setup: exponent still in {text!r}"
    scene = parse_scene(text, tmp_path)
    assert scene.wear.exponent == 1.0, f"exponent {scene.wear.exponent}"


def test_rods_in_metres(tmp_path):
    text = scene_text("parser", map="rods", centres=[[0.0, 0.0], [0.002, 0.0]],
                      radii=[0.001, 0.0008])
    scene = parse_scene(text, tmp_path)
    assert isinstance(scene.geometry, Rods), f"{scene.geometry}"
    assert scene.geometry.centres == ((0.0, 0.0), (0.002, 0.0)), "centres in m, as in the file"
    assert scene.geometry.radii == (0.001, 0.0008), "radii in m, as in the file"


def test_file_map_relative_to_scene(tmp_path):
    sub = tmp_path / "maps"
    sub.mkdir()
    np.save(sub / "m.npy", Rods(((0.0, 0.0),), (0.5,)).labels(32))
    (tmp_path / "s.toml").write_text(scene_text("parser", map="file", path="maps/m.npy"))
    scene = load_scene(tmp_path / "s.toml")
    assert isinstance(scene.geometry, ArrayMap), f"{scene.geometry}"
    assert scene.source_path == tmp_path / "s.toml", f"{scene.source_path}"


def test_extra_sections(tmp_path):
    """A section another package reads is kept as its table, checked only to be a table."""
    text = scene_text("parser", transient={"steps": 5})
    scene = parse_scene(text, tmp_path, extra_sections=("transient",))
    assert dict(scene.extra) == {"transient": {"steps": 5}}, f"extra {scene.extra}"
    assert scene.ignored_sections == (), f"a section read elsewhere is not ignored: {scene}"
    with pytest.raises(ValueError, match=r"\[transient\] must be a table, got 5"):
        parse_scene("transient = 5\n" + scene_text("parser"), tmp_path,
                    extra_sections=("transient",))
    with pytest.raises(ValueError, match=r"unknown section \[wear_history\]"):
        parse_scene(scene_text("parser", extra="[wear_history]\nsteps = 5"), tmp_path,
                    extra_sections=("transient",))
    with pytest.raises(ValueError, match=r"extra section 'wear' clashes with a core section"):
        parse_scene(text, tmp_path, extra_sections=("wear",))


def test_run_in_sections_are_ignored_without_a_parser(tmp_path):
    """One scene file serves both commands: steady records the run-in sections it skips."""
    text = scene_text("parser", transient={"scheme": "sdirk2", "not_checked_here": 1},
                      initial_face={"kind": "tilted", "angle": 1e-3})
    scene = parse_scene(text, tmp_path)
    assert scene.ignored_sections == ("initial_face", "transient"), \
        f"ignored sections {scene.ignored_sections}"
    assert dict(scene.extra) == {}, f"nothing parsed: {scene.extra}"
    plain = parse_scene(BASE, tmp_path)
    assert plain.ignored_sections == (), f"no run-in section: {plain.ignored_sections}"
    assert ((scene.outline.radius, scene.n, scene.geometry)
            == (plain.outline.radius, plain.n, plain.geometry)), \
        "the run-in sections must not change the steady scene"
    # With one of them read elsewhere, only the other is ignored.
    scene = parse_scene(text, tmp_path, extra_sections=("initial_face",))
    assert scene.ignored_sections == ("transient",), f"{scene.ignored_sections}"
    assert scene.extra["initial_face"]["kind"] == "tilted", f"{scene.extra}"
    with pytest.raises(ValueError, match=r"unknown section \[transients\]"):
        parse_scene(scene_text("parser", extra="[transients]\nsteps = 5"), tmp_path)
    with pytest.raises(ValueError, match=r"\[transient\] must be a table, got 5"):
        parse_scene("transient = 5\n" + BASE, tmp_path)


def test_shipped_run_in_scene_loads_for_steady():
    scene = load_scene(SCENES / "tilted_transient.toml")
    assert scene.ignored_sections == ("initial_face", "transient"), \
        f"ignored sections {scene.ignored_sections}"


@pytest.mark.parametrize("old, new, fragment", [
    ("radius = 0.004", "radius = -0.004",
     "[punch] radius must be a number > 0 (m), got -0.004"),
    ("radius = 0.004", 'radius = "4 mm"', "[punch] radius must be a number > 0 (m), got '4 mm'"),
    ("normal_force = 10.0", "normal_force = 0",
     "[load] normal_force must be a number > 0 (N), got 0"),
    ("normal_force = 10.0", "normal_force = nan", "got nan"),
    ("E_star = 1300000.0", "E_star = true",
     "[counterbody] E_star must be a number > 0 (Pa), got True"),
    ("n = 64", "n = 64.0", "[grid] n must be an integer >= 2, got 64.0"),
    ("n = 64", "n = 10",
     "[grid] n: grid too coarse for 100 Voronoi seeds: n = 10, the minimum is n = 20"),
    ("[1e-09, 1.7e-09]", "[1e-09, -1.7e-09]",
     "[wear] coefficients must be an array of numbers each > 0 (1/Pa), got [1e-09, -1.7e-09]"),
    ("[1e-09, 1.7e-09]", "[1e-09]",
     "[wear] coefficients has 1 values [1e-09] but the phase map has 2 phases"),
    ("[1e-09, 1.7e-09]", "1e-09",
     "[wear] coefficients must be an array of numbers each > 0 (1/Pa), got 1e-09"),
    ("exponent = 1.0", "exponent = -2.0", "[wear] exponent must be a number > 0 (1), got -2.0"),
    ("[0.5, 0.5]", "[0.5, 0.6]", "fill factors must sum to 1, got [0.5, 0.6]"),
    ("[0.5, 0.5]", "[1.5, -0.5]", "[phases] map fill_factors must be an array of numbers each "
                                  "in (0, 1) (1), got [1.5, -0.5]"),
    ("[0.5, 0.5]", "[1.2, 0.3]", "[phases] map fill_factors must be an array of numbers each "
                                 "in (0, 1) (1), got [1.2, 0.3]"),
    ("[0.5, 0.5]", "[1.0, 0.0]", "fill_factors must be an array of numbers each in (0, 1) (1), "
                                 "got [1.0, 0.0]"),
    ("seed = 2024", "seed = -3", "[phases] map seed must be an integer >= 0, got -3"),
    ('kind = "voronoi"', 'kind = "hexagons"',
     "kind must be one of ['file', 'homogeneous', 'inclusions', 'micrograph', 'rods', "
     "'spheres', 'voronoi', 'voxels'], got 'hexagons'"),
    ("seed = 2024", "seed = 2024, colour = 1",
     "unknown key 'colour' in [phases] map (kind 'voronoi')"),
    ("radius = 0.004", "radius = 0.004\nradus = 0.004", "unknown key 'radus' in [punch]"),
    ("[grid]", "[grids]", "unknown section [grids]"),
    ("n = 64\n", "", "missing key 'n' in [grid]"),
    ("radius = 0.004", "radius = 0.004 0.005", "malformed TOML"),
])
def test_bad_keys(tmp_path, old, new, fragment):
    assert old in BASE, f"test setup: {old!r} not in the base scene"
    with pytest.raises(ValueError) as err:
        parse_scene(BASE.replace(old, new, 1), tmp_path)
    assert fragment in str(err.value), f"message {err.value!r} lacks {fragment!r}"


#: Phase maps and wear laws of different phase counts, and the refusal of each; the map is
#: never built (a micrograph of 10 phases would be segmented for hours, a missing image read).
COUNT_MISMATCHES = {
    "micrograph of 10, power law of 2": (
        'map = { kind = "micrograph", path = "absent.png", n_phases = 10 }',
        "coefficients = [1e-09, 1e-08]", "",
        "[wear] coefficients has 2 values [1e-09, 1e-08] but [phases] map n_phases = 10"),
    "voronoi of 3, table of 2": (
        'map = { kind = "voronoi", n_seeds = 100, fill_factors = [0.2, 0.3, 0.5], seed = 2024 }',
        'law = "table"\npressures = [[0, 1e5], [0, 1e5]]\nrates = [[0, 1e-9], [0, 1e-8]]', "",
        "[wear] pressures has 2 lists [[0.0, 100000.0], [0.0, 100000.0]] but the phase map has 3 "
        "phases"),
    "inclusions of 2, threshold law of 3": (
        'map = { kind = "inclusions", radius = 4e-4, seed = 2024, fill_factor = 0.2 }',
        'law = "threshold"\ncoefficients = [1e-9, 1e-8, 1e-7]\nthresholds = [0, 0, 0]', "",
        "[wear] coefficients has 3 values [1e-09, 1e-08, 1e-07] but the phase map has 2 phases"),
    "rods of 3, Archard's law of 2": (
        'map = { kind = "rods", centres = [[0.0, 0.0], [0.002, 0.0]], radii = [1e-3, 5e-4], '
        'rod_phases = [1, 2] }', 'law = "archard"\ncoefficients = [1e-9, 1e-8]', "",
        "[wear] coefficients has 2 values [1e-09, 1e-08] but the phase map has 3 phases"),
    "substrate of 3 under a layer, law of 2": (
        'map = { kind = "voronoi", n_seeds = 100, fill_factors = [0.2, 0.3, 0.5], seed = 2024 }',
        "coefficients = [1e-9, 1e-8]",
        '[depth]\nkind = "layers"\n[[depth.layers]]\nthickness = 1e-4\nphase = 1\n',
        "[phases] map has 3 phases, the wear law 2"),
    "layer micrograph of 3, law of 2": (
        'map = { kind = "homogeneous" }', "coefficients = [1e-9, 1e-8]",
        '[depth]\nkind = "layers"\n[[depth.layers]]\nthickness = 1e-4\n'
        'map = { kind = "micrograph", path = "absent.png", n_phases = 3 }\n',
        "[depth] layers[0] map n_phases = 3, the wear law 2"),
}


@pytest.mark.parametrize("case", sorted(COUNT_MISMATCHES))
def test_phase_counts_are_compared_before_the_map_is_built(tmp_path, monkeypatch, case):
    from steady.phases import PHASE_MAPS

    def built(cls, values, context):
        pytest.fail(f"{case}: the {cls.kind} map was built before the phase counts were compared")

    for kind in PHASE_MAPS:
        if kind != "homogeneous":
            monkeypatch.setattr(PHASE_MAPS[kind], "from_values", classmethod(built))
    phase_map, wear, depth, fragment = COUNT_MISMATCHES[case]
    text = re.sub(r"^map = .*$", lambda _: phase_map, BASE, count=1, flags=re.M)
    text = re.sub(r"^coefficients = .*\nexponent = .*$", lambda _: wear, text, count=1,
                  flags=re.M)
    with pytest.raises(ValueError) as err:
        parse_scene(text + depth, tmp_path)
    assert fragment in str(err.value), f"{case}: {str(err.value)!r} lacks {fragment!r}"


def test_a_file_map_is_compared_with_the_law_once_read(tmp_path):
    np.save(tmp_path / "three.npy", np.repeat(np.arange(3), 22)[None, :64].repeat(64, 0))
    text = scene_text("parser", map="file", path="three.npy")
    with pytest.raises(ValueError, match=r"\[wear\] coefficients has 2 values \[1e-09, 1.7e-09\] "
                                         r"but the phase map has 3 phases"):
        parse_scene(text, tmp_path)


def test_bad_rods_scene(tmp_path):
    text = scene_text("parser", map="rods", centres=[[0.0, 0.0], [0.001, 0.0]],
                      radii=[0.001, 0.001])
    with pytest.raises(ValueError, match=r"\[phases\] map: rods 0 and 1 overlap"):
        parse_scene(text, tmp_path)


def test_missing_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="scene file .*nope.toml' does not exist"):
        load_scene(tmp_path / "nope.toml")
    (tmp_path / "s.toml").write_text(scene_text("parser", map="file", path="gone.npy"))
    with pytest.raises(ValueError) as err:
        load_scene(tmp_path / "s.toml")
    assert "s.toml" in str(err.value) and "gone.npy" in str(err.value), f"{err.value!r}"
    (tmp_path / "bad.toml").write_text("[punch\nradius = 1")
    with pytest.raises(ValueError, match="bad.toml: malformed TOML"):
        load_scene(tmp_path / "bad.toml")


@pytest.mark.parametrize("name, geometry_type, n_phases", [
    ("epoxy_cylinder.toml", Homogeneous, 1),
    ("voronoi_biphasic.toml", Voronoi, 2),
    ("rods_steel_in_brass.toml", Rods, 2),
    ("rods_brass_in_steel.toml", Rods, 2),
    ("checkerboard.toml", ArrayMap, 2),
])
def test_shipped_scenes_load(name, geometry_type, n_phases):
    scene = load_scene(SCENES / name)
    assert isinstance(scene.geometry, geometry_type), f"{name}: {scene.geometry}"
    assert scene.n_phases == n_phases, f"{name}: {scene.n_phases} phases"
    labels = scene.geometry.labels(scene.grid())
    assert labels.shape == (scene.n, scene.n), f"{name}: shape {labels.shape}"


def test_scene_files_that_are_not_scenes(tmp_path):
    """A directory, a device, a huge or binary file: one clear error each, nothing parsed."""
    with pytest.raises(ValueError, match="is a directory, not a file"):
        load_scene(tmp_path)
    with pytest.raises(ValueError, match="is not a regular file"):
        load_scene("/dev/zero")  # would never end if read
    big = tmp_path / "big.toml"
    big.write_text(BASE.replace("[1e-09, 1.7e-09]", "[" + "1e-9, " * 200_000 + "1e-9]"))
    with pytest.raises(ValueError, match="is larger than 1 MiB, the most a scene may have"):
        load_scene(big)
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"[punch]\nradius = \xff\n")
    with pytest.raises(ValueError, match=r"is not UTF-8 text: byte 17 is b'\\xff'"):
        load_scene(binary)


def test_a_byte_order_mark_is_skipped(tmp_path):
    """UTF-8 with a byte-order mark (as editors on Windows save it) is the same scene."""
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    plain.write_text(BASE, encoding="utf-8")
    marked.write_text(BASE, encoding="utf-8-sig")
    assert marked.read_bytes()[:3] == b"\xef\xbb\xbf", "test setup: no byte-order mark"
    scene, ref = load_scene(marked), load_scene(plain)
    assert scene.text == ref.text == BASE, "the text without the mark"
    assert (scene.geometry, scene.wear.coefficients, scene.n) == \
        (ref.geometry, ref.wear.coefficients, ref.n), "another scene"


def test_hostile_values_give_short_messages(tmp_path):
    """Deep nesting, long lists and long strings: the message shows a shortened value."""
    deep = BASE.replace("[1e-09, 1.7e-09]", "[" * 100_000 + "]" * 100_000)
    with pytest.raises(ValueError, match="malformed TOML: arrays or tables nested too deeply"):
        parse_scene(deep, tmp_path)
    long_list = BASE.replace("[1e-09, 1.7e-09]", "[" + "1e-9, " * 100_000 + "1e-9]")
    with pytest.raises(ValueError) as err:
        parse_scene(long_list, tmp_path)
    message = str(err.value)
    assert message.startswith("[wear] coefficients has 100001 values [1e-09, 1e-09"), message[:99]
    assert "(100001 items," in message and len(message) < 300, \
        f"message of {len(message)} characters: {message[:300]!r}"
    long_string = BASE.replace("exponent = 1.0", 'exponent = "' + "x" * 900_000 + '"')
    with pytest.raises(ValueError) as err:
        parse_scene(long_string, tmp_path)
    message = str(err.value)
    assert "(900000 characters)" in message and len(message) < 300, \
        f"message of {len(message)} characters"
    long_key = BASE.replace("[grid]", "[" + "g" * 100_000 + "]")
    with pytest.raises(ValueError) as err:
        parse_scene(long_key, tmp_path)
    assert "unknown section [ggg" in str(err.value) and len(str(err.value)) < 400, \
        f"message of {len(str(err.value))} characters"


def test_file_map_larger_than_the_grid_is_refused_before_loading(tmp_path):
    import numpy.lib.format as npy_format

    with open(tmp_path / "huge.npy", "wb") as f:  # a header that claims 80 GB, no data
        npy_format.write_array_header_1_0(f, {"descr": "<i8", "fortran_order": False,
                                             "shape": (100000, 100000)})
    text = scene_text("parser", map="file", path="huge.npy")
    with pytest.raises(ValueError, match=r"'.*huge.npy' has 100000 x 100000 pixels, more than "
                                         r"the grid's n = 64"):
        parse_scene(text, tmp_path)


def test_phase_labels_name_a_phase_without_face_pixel(tmp_path):
    """Two seeds (seed 2306) whose phase-1 seed lies off the face of an 8 x 8 grid."""
    text = scene_text("parser", n=8, n_seeds=2, fill_factors=(0.5, 0.5), seed=2306)
    scene = parse_scene(text, tmp_path, source_path=tmp_path / "s.toml")
    with pytest.raises(ValueError) as err:
        scene.phase_labels()
    assert str(err.value).startswith(f"{tmp_path / 's.toml'}: [phases] map: phase 1 has no "
                                     f"pixel on the face with these 2 seeds (seed = 2306) at "
                                     f"n = 8"), f"{err.value}"
    ok = parse_scene(BASE, tmp_path)
    assert np.array_equal(ok.phase_labels(), ok.geometry.labels(64)), "labels of a good map"


def test_phase_names_reach_the_problem_and_are_checked():
    """``[phases] names`` is one name per phase, distinct; the default numbers from 0."""
    from steady.scene import problem_of
    base = (ROOT / "steady/examples/rods_brass_in_steel.toml")
    scene = load_scene(base)
    assert scene.phase_names == ("steel", "brass")
    problem = problem_of(scene, n=48)
    assert problem.phase_names == ("steel", "brass")
    text = base.read_text()
    unnamed = parse_scene(text.replace('names = ["steel", "brass"]', ""), base.parent)
    assert problem_of(unnamed, n=48).phase_names == ("phase 0", "phase 1")
    for bad, words in (('["steel"]', "1 phase name(s) given for 2"),
                       ('["steel", "steel"]', "'steel' is given twice"),
                       ('["steel", ""]', "[phases] names must be an array of non-empty strings"),
                       ('"steel"', "[phases] names must be an array")):
        with pytest.raises(ValueError, match=re.escape(words)):
            parse_scene(text.replace('["steel", "brass"]', bad), base.parent)
