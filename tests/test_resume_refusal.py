"""A resume refused for another face says what differs, not two identical descriptions."""

import numpy as np
import pytest
from conftest import scene_text

import transient.__main__ as transient_cli
from steady.outline import Circle, MaskOutline, Rectangle, describe_change
from transient.output import read_run

FACE = np.ones((8, 12), dtype=bool)
FACE[:4, :5] = False


def run(argv, capsys):
    status = transient_cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def _stopped_run(tmp_path, capsys, punch, **scene):
    """A run of ``punch`` stopped after 2 steps (resumable); returns the scene and run paths."""
    text = scene_text("runin", map="homogeneous", coefficients=(1e-13,), punch=punch,
                      transient={"tol": 1e-3, "max_steps": 2}, **scene)
    (tmp_path / "s.toml").write_text(text)
    status, _, err = run([tmp_path / "s.toml", "-o", tmp_path / "run.h5"], capsys)
    assert status == 1 and "max_steps" in err, f"test setup: exit {status}, {err!r}"
    return tmp_path / "s.toml", tmp_path / "run.h5"


def test_resume_after_a_mask_edited_in_place_names_the_pixels(tmp_path, capsys):
    np.save(tmp_path / "m.npy", FACE)
    scene, out = _stopped_run(tmp_path, capsys, {"shape": "mask", "path": "m.npy",
                                                 "pixel_size": 5e-4}, n=24)
    edited = FACE.copy()
    edited[7, 9:12] = False
    np.save(tmp_path / "m.npy", edited)
    before = out.read_bytes()
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 2, f"exit {status}: {err!r}"
    line = err.strip()
    assert "with other pixels: 3 of its 96 pixels differ from the scene's" in line, line
    assert line.count("m.npy' (8 x 12 pixels of 0.5 mm)") == 1, \
        f"the description is repeated instead of saying what differs: {line!r}"
    assert line.endswith("use --force to start over"), line
    assert out.read_bytes() == before, "the run file changed"


def test_resume_with_a_radius_changed_below_six_digits_names_both(tmp_path, capsys):
    scene, out = _stopped_run(tmp_path, capsys, {"radius": 0.004}, n=16)
    scene.write_text(scene.read_text().replace("radius = 0.004", "radius = 0.0040000001"))
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 2, f"exit {status}: {err!r}"
    assert "radius 0.004 m, the scene has 0.0040000001 m" in err, err


@pytest.mark.parametrize("old, new, expected", [
    (Circle(4e-3), Circle(5e-3),
     "circle face (radius 4 mm), the scene has the circle face (radius 5 mm)"),
    (Circle(4e-3), Rectangle(4e-3, 4e-3),
     "circle face (radius 4 mm), the scene has the rectangle face (width 4 mm, length 4 mm)"),
    (MaskOutline(FACE, 5e-4, "'m.npy'"), MaskOutline(FACE, 5.000000001e-4, "'m.npy'"),
     "mask face 'm.npy' (8 x 12 pixels of 0.5 mm) with pixel_size 0.0005 m, the scene has "
     "0.0005000000001 m"),
])
def test_describe_change(old, new, expected):
    assert describe_change(old, new) == expected, describe_change(old, new)


# -- the kinematics and the phases below the face define the problem too ---------------------
PIN = '[sliding]\nkind = "pin_on_disk"\ntrack_radius = 0.02\n'
ANNULUS = {"shape": "annulus", "inner_radius": 0.002, "outer_radius": 0.004}
#: A Voronoi layer 0.3 mm thick over a homogeneous substrate: the surface of the gallery's map.
LAYER = ('[depth]\nkind = "layers"\n[[depth.layers]]\nthickness = 3e-4\nmap = { kind = '
         '"voronoi", n_seeds = 64, fill_factors = [0.7, 0.3], seed = 2029 }\n')


def _stopped_text(tmp_path, capsys, text):
    """A run of the scene ``text`` stopped after 2 steps; returns the scene and run paths."""
    (tmp_path / "s.toml").write_text(text)
    status, _, err = run([tmp_path / "s.toml", "-o", tmp_path / "run.h5"], capsys)
    assert status == 1 and "max_steps" in err, f"test setup: exit {status}, {err!r}"
    return tmp_path / "s.toml", tmp_path / "run.h5"


def _runin(punch=None, extra="", **scene):
    return scene_text("runin", map="homogeneous", coefficients=(1e-13,),
                      punch=punch, transient={"tol": 1e-3, "max_steps": 2}, extra=extra,
                      **scene)


@pytest.mark.parametrize("before, after, expected", [
    (_runin(extra=PIN), _runin(),
     "was run under [sliding] pin_on_disk, track_radius = 0.02 m; the scene has [sliding] "
     "translation"),
    (_runin(), _runin(extra=PIN),
     "was run under [sliding] translation; the scene has [sliding] pin_on_disk, "
     "track_radius = 0.02 m"),
    (_runin(extra=PIN), _runin(extra=PIN.replace("0.02", "0.03")),
     "was run under [sliding] pin_on_disk, track_radius = 0.02 m; the scene has [sliding] "
     "pin_on_disk, track_radius = 0.03 m"),
    (_runin(ANNULUS, extra='[sliding]\nkind = "rotation"\n'), _runin(ANNULUS),
     "was run under [sliding] rotation about the face's centre; the scene has [sliding] "
     "translation"),
], ids=["pin on disk -> translation", "translation -> pin on disk", "track radius",
        "rotation -> translation"])
def test_resume_under_other_kinematics_is_refused(tmp_path, capsys, before, after, expected):
    scene, out = _stopped_text(tmp_path, capsys, before)
    saved = out.read_bytes()
    scene.write_text(after)
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 2, f"exit {status}: {err!r}"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], err
    assert lines[0].endswith("use --force to start over"), lines[0]
    assert out.read_bytes() == saved, "the run file changed"


PROGRAMME = "normal_force = 10.0\nprogramme = [[0.05, 20.0]]"


@pytest.mark.parametrize("before, after, expected", [
    (_runin(), _runin(normal_force=20.0),
     "was run with normal_force = 10.0, the scene has 20.0; use --force to start over"),
    (_runin().replace("normal_force = 10.0", PROGRAMME), _runin(),
     "was run with another [load] programme ([[0.05, 20.0]]), the scene has none; use --force "
     "to start over"),
    (_runin(), _runin().replace("normal_force = 10.0", PROGRAMME),
     "was run with another [load] programme (none), the scene has [[0.05, 20.0]]; use --force "
     "to start over"),
], ids=["force", "programme -> none", "none -> programme"])
def test_resume_under_another_load_shows_both_as_written(tmp_path, capsys, before, after,
                                                          expected):
    """The file's values are numpy's when read: shown as numbers and lists, as a scene has them."""
    scene, out = _stopped_text(tmp_path, capsys, before)
    scene.write_text(after)
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].endswith(expected), err


def _layered(thickness=None):
    """The gallery's run-in, columnar, or its map as a layer of ``thickness`` (m)."""
    if thickness is None:
        return scene_text("runin", transient={"tol": 1e-3, "max_steps": 2})
    return scene_text("runin", map="homogeneous", transient={"tol": 1e-3, "max_steps": 2},
                      extra=LAYER.replace("3e-4", repr(thickness)))


@pytest.mark.parametrize("before, after, expected", [
    (_layered(3e-4), _layered(),
     "was run on other phases below the face (248 interfaces at depth 0.0003 m below 248 of "
     "812 face pixels); the scene has phases that do not change with depth (no [depth], a "
     "2-d map)"),
    (_layered(), _layered(3e-4),
     "was run on phases that do not change with depth; the scene has phases that change with "
     "depth ([depth] or a 3-d map: 248 interfaces at depth 0.0003 m below 248 of 812 face "
     "pixels)"),
    (_layered(3e-4), _layered(2e-4),
     "was run on other phases below the face (248 interfaces at depth 0.0003 m below 248 of "
     "812 face pixels); the scene has phases that change with depth ([depth] or a 3-d map: "
     "248 interfaces at depth 0.0002 m below 248 of 812 face pixels)"),
], ids=["layer -> columnar", "columnar -> layer", "thickness"])
def test_resume_on_other_phases_below_the_face_is_refused(tmp_path, capsys, before, after,
                                                         expected):
    scene, out = _stopped_text(tmp_path, capsys, before)
    saved = out.read_bytes()
    scene.write_text(after)
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 2, f"exit {status}: {err!r}"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], err
    assert out.read_bytes() == saved, "the run file changed"


def test_resume_with_other_phase_names_continues(tmp_path, capsys):
    # Names are labels: the run they name is the same.
    text = _layered(3e-4)
    scene, out = _stopped_text(tmp_path, capsys, text)
    renamed = text.replace("[phases]", '[phases]\nnames = ["steel", "bronze"]')
    scene.write_text(renamed.replace("max_steps = 2", "max_steps = 3"))
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 1 and "max_steps 3" in err and "was run" not in err, f"exit {status}: {err!r}"
    assert read_run(out)[0].steps == 3, "the resumed run did not continue"


def test_a_checkpoint_records_the_digest_of_its_columns(tmp_path):
    from conftest import wear_problem

    from steady.depth import DepthColumns
    from transient.cli.run_file import check_same_columns, stored_columns_digest
    from transient.options import RunOptions
    from transient.output import write_run
    from transient.runin import run_in

    def layered(depth):
        columnar = wear_problem("voronoi", (1.0, 10.0), 16)
        face = columnar.face_mask
        interfaces = np.where(face, depth, np.inf)[None]
        phases = np.stack([np.where(face, columnar.labels, -1), np.where(face, 0, -1)])
        return wear_problem("voronoi", (1.0, 10.0), 16,
                            columns=DepthColumns(interfaces, phases, 2))

    problem_ = layered(1e-6)
    checkpoints = []
    run_in(problem_, np.zeros(problem_.shape), RunOptions(tol=1e-3, max_steps=2,
                                                          checkpoint_interval=0.0),
           on_checkpoint=checkpoints.append)
    path = tmp_path / "checkpoint.h5"
    write_run(path, checkpoints[0])
    stored, attrs, _ = read_run(path)
    assert stored.status == "running" and stored.columns is None, "a checkpoint with columns"
    assert stored_columns_digest(attrs, stored) == problem_.columns.digest, \
        "the checkpoint's digest is not its columns'"
    check_same_columns(path, attrs, stored, layered(1e-6).columns)  # the same columns again
    with pytest.raises(ValueError, match=r"was run on other phases below the face \(its "
                                         r"checkpoint's columns_sha256 differs\)"):
        check_same_columns(path, attrs, stored, layered(2e-6).columns)
    with pytest.raises(ValueError, match=r"the scene has phases that do not change with depth"):
        check_same_columns(path, attrs, stored, None)
    # A file written before the digest was recorded: a depth run, columns unknown.
    earlier = {key: value for key, value in attrs.items() if key != "columns_sha256"}
    assert stored_columns_digest(earlier, stored) is None, "unrecorded columns taken as known"
    check_same_columns(path, earlier, stored, layered(2e-6).columns)  # resumed with a note
    with pytest.raises(ValueError, match=r"was run on phases that change with depth; the scene "
                                         r"has phases that do not change with depth"):
        check_same_columns(path, earlier, stored, None)


@pytest.mark.parametrize("before, after, expected", [
    ("", "thickness = 0.002\npoisson = 0.5\n",
     "was run on a half-space ([counterbody]), the scene has a layer of thickness 0.002 m"),
    ("thickness = 0.002\npoisson = 0.5\n", "thickness = 0.002\npoisson = 0.3\n",
     "poisson 0.5 ([counterbody]), the scene has a layer of thickness 0.002 m, poisson 0.3"),
])
def test_resume_on_another_counterbody_is_refused(tmp_path, capsys, before, after, expected):
    scene, out = _stopped_run(tmp_path, capsys, {"radius": 0.004}, n=16)
    text = scene.read_text()
    if before:
        scene.write_text(text.replace("[counterbody]\n", "[counterbody]\n" + before))
        _stopped_run_again(scene, out, capsys)
        text = scene.read_text()
    scene.write_text(text.replace("[counterbody]\n" + before, "[counterbody]\n" + after)
                     if before else text.replace("[counterbody]\n", "[counterbody]\n" + after))
    status, _, err = run([scene, "-o", out, "--resume"], capsys)
    assert status == 2, f"exit {status}: {err!r}"
    assert expected in err and err.strip().endswith("use --force to start over"), err


def _stopped_run_again(scene, out, capsys):
    """Run ``scene`` over ``out`` from the start, stopped after its 2 steps."""
    status, _, err = run([scene, "-o", out, "--force"], capsys)
    assert status == 1 and "max_steps" in err, f"test setup: exit {status}, {err!r}"
