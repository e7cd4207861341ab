"""A resume refused for another face says what differs, not two identical descriptions."""

import numpy as np
import pytest
from conftest import scene_text

import transient.__main__ as transient_cli
from steady.outline import Circle, MaskOutline, Rectangle, describe_change

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
