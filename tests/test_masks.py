"""Integer arrays that mark a face: one rule for face masks and phase maps.

A face mask of integers is either a 0/1 image (1 on the face) or holds -1 off
the face and values >= 0 on it (a phase map with -1 off its face is its own
mask); anything else is refused with the values found, never read as a face
of every pixel.  In a phase map a negative value marks a pixel off the face
and is refused on it.  An empty array is named as empty.
"""

import numpy as np
import pytest
from conftest import scene_text

import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.array_files import read_face_mask
from steady.outline import Circle, MaskOutline
from steady.phases import ArrayMap, load_phase_map

#: An L-shaped face of 8 x 12 mask pixels.
FACE = np.ones((8, 12), dtype=bool)
FACE[:4, :5] = False

PIXEL = 5e-4  # m


def write_mask(path, values):
    np.save(path, np.asarray(values))
    return path


@pytest.mark.parametrize("name, values", [
    ("boolean", FACE),
    ("0/1 uint8", FACE.astype(np.uint8)),
    ("0/1 int64", FACE.astype(np.int64)),
    ("-1 off, 3 on", np.where(FACE, 3, -1)),
    ("-1 off, a phase map on", np.where(FACE, np.arange(96).reshape(8, 12) % 3, -1)
     .astype(np.int16)),
])
def test_integer_masks_of_either_form_give_the_face(tmp_path, name, values):
    mask = read_face_mask(write_mask(tmp_path / "m.npy", values))
    assert mask.dtype == bool, f"{name}: dtype {mask.dtype}"
    assert np.array_equal(mask, FACE), \
        f"{name}: {int(mask.sum())} face pixels, expected the L of {int(FACE.sum())}"


@pytest.mark.parametrize("name, values, listed", [
    ("{0, 2, 7}", np.where(FACE, 2, 0) + 5 * np.eye(8, 12, dtype=int) * FACE, "[0, 2, 7]"),
    ("0/-2", np.where(FACE, 0, -2), "[-2, 0]"),
    ("-1/-2/0", np.where(FACE, 0, -1) - np.eye(8, 12, dtype=int) * ~FACE, "[-2, -1, 0]"),
    ("2/5 uint8", np.where(FACE, 5, 2).astype(np.uint8), "[2, 5]"),
    ("one value 7", np.full((8, 12), 7), "[7]"),
])
def test_other_integer_masks_are_refused_with_their_values(tmp_path, name, values, listed):
    path = write_mask(tmp_path / "m.npy", values)
    with pytest.raises(ValueError) as info:
        read_face_mask(path)
    message = str(info.value)
    assert f"holds the integer values {listed}" in message, f"{name}: {message!r}"
    assert "m.npy" in message and "-1 off the face" in message, f"{name}: {message!r}"


def test_many_distinct_values_are_listed_shortly(tmp_path):
    path = write_mask(tmp_path / "m.npy", np.arange(96).reshape(8, 12) * 3)
    with pytest.raises(ValueError, match=r"\[0, 3, 6, 9, 12, 15, \.\.\., 279, 282, 285\] "
                                         r"\(96 distinct values\)"):
        read_face_mask(path)


def test_masks_without_face_or_pixels(tmp_path):
    with pytest.raises(ValueError, match="has no face pixel"):
        read_face_mask(write_mask(tmp_path / "zeros.npy", np.zeros((8, 8), dtype=np.uint8)))
    with pytest.raises(ValueError, match="has no face pixel"):
        read_face_mask(write_mask(tmp_path / "off.npy", np.full((8, 8), -1)))
    with pytest.raises(ValueError, match=r"'.*empty.npy' is empty: an array of shape \(0, 0\)"):
        read_face_mask(write_mask(tmp_path / "empty.npy", np.zeros((0, 0), dtype=np.int8)))


def test_a_0_1_mask_through_the_scene_is_the_boolean_face(tmp_path):
    """The 0/1 image and the boolean array are the same outline, not the whole box."""
    from steady.outline import outline_from_table

    write_mask(tmp_path / "b.npy", FACE)
    write_mask(tmp_path / "u.npy", FACE.astype(np.uint8))
    boolean = outline_from_table({"shape": "mask", "path": "b.npy", "pixel_size": PIXEL},
                                 tmp_path)
    image = outline_from_table({"shape": "mask", "path": "u.npy", "pixel_size": PIXEL},
                               tmp_path)
    assert image == boolean, f"{image.describe()} differs from {boolean.describe()}"
    assert image.area == pytest.approx(FACE.sum() * PIXEL**2, rel=1e-15), \
        f"area {image.area} m^2 of the 0/1 mask"
    assert MaskOutline(FACE, PIXEL).area < 96 * PIXEL**2, "test setup: the L is not the box"


def _mask_scene(tmp_path, values):
    write_mask(tmp_path / "m.npy", values)
    text = scene_text("runin", n=24, map="homogeneous", coefficients=(1e-13,),
                      punch={"shape": "mask", "path": "m.npy", "pixel_size": PIXEL})
    (tmp_path / "s.toml").write_text(text)
    return tmp_path / "s.toml"


@pytest.mark.parametrize("command", ["steady", "transient"])
def test_command_refuses_a_0_2_7_mask_naming_its_values(tmp_path, capsys, command):
    values = np.where(FACE, 2, 0) + 5 * np.eye(8, 12, dtype=int) * FACE
    scene = _mask_scene(tmp_path, values)
    module = steady_cli if command == "steady" else transient_cli
    status = module.main([str(scene), "-o", str(tmp_path / "out.h5")])
    out, err = capsys.readouterr()
    assert status == 2, f"{command}: exit {status}, stderr {err!r}"
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), f"{command}: {err!r}"
    assert "[punch]" in lines[0] and "holds the integer values [0, 2, 7]" in lines[0], \
        f"{command}: {lines[0]!r}"
    assert not (tmp_path / "out.h5").exists(), f"{command}: a result was written"


def test_steady_solves_the_face_of_a_0_1_mask(tmp_path, capsys):
    import h5py

    scene = _mask_scene(tmp_path, FACE.astype(np.uint8))
    status = steady_cli.main([str(scene), "-o", str(tmp_path / "out.h5"), "--no-slope-error"])
    _, err = capsys.readouterr()
    assert status == 0, f"exit {status}: {err!r}"
    with h5py.File(tmp_path / "out.h5") as f:
        area = float(f["outline/area"][()])
        on_face = np.isfinite(f["face"][()]).T  # stored (y, x)
    assert area == pytest.approx(FACE.sum() * PIXEL**2, rel=1e-15), \
        f"stored area {area} m^2: the 0/1 mask was read as another face"
    assert np.array_equal(on_face, np.kron(FACE, np.ones((2, 2), dtype=bool))), \
        "the result's face pixels are not the mask's"


# -- phase maps: a negative value marks a pixel off the face ------------------
def _disk_labels(n=16):
    mask = Circle(1.0).grid(n).mask
    labels = np.where(mask, 0, -1)
    labels[n // 2, n // 2] = 1
    return mask, labels


def test_phase_map_refuses_a_negative_value_on_the_face():
    mask, labels = _disk_labels()
    labels[8, 3] = -2
    assert mask[8, 3], "test setup: pixel (8, 3) is on the face"
    with pytest.raises(ValueError) as info:
        ArrayMap(labels, source="'p.npy'")
    message = str(info.value)
    assert "phase label -2 found on the face at pixel (8, 3) (1 face pixel(s) negative)" \
        in message, message
    assert "marks a pixel off the face" in message, message


def test_phase_map_takes_any_value_off_the_face():
    mask, labels = _disk_labels()
    for off in (-1, -7, 0, 1, 5):
        labels = np.where(mask, labels, off)
        geometry = ArrayMap(labels)
        assert geometry.n_phases == 2, f"off-face value {off}: {geometry.n_phases} phases"
        assert np.array_equal(geometry.labels(16) >= 0, mask), f"off-face value {off}: face"


def test_an_empty_phase_map_is_named_as_empty(tmp_path):
    np.save(tmp_path / "p.npy", np.zeros((0, 0), dtype=np.int64))
    with pytest.raises(ValueError) as info:
        load_phase_map(tmp_path / "p.npy")
    message = str(info.value)
    assert "is empty: an array of shape (0, 0)" in message, message
    assert "too coarse" not in message and "n = 0" not in message, message


def test_the_command_names_an_empty_phase_map(tmp_path, capsys):
    np.save(tmp_path / "p.npy", np.zeros((0, 0), dtype=np.int64))
    (tmp_path / "s.toml").write_text(scene_text("steady", map="file", path="p.npy"))
    status = steady_cli.main([str(tmp_path / "s.toml"), "-o", str(tmp_path / "out.h5")])
    _, err = capsys.readouterr()
    assert status == 2, f"exit {status}: {err!r}"
    assert "[phases] map: phase map" in err, err
    assert "p.npy' is empty: an array of shape (0, 0)" in err, err
