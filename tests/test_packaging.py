"""The installed package: shipped example scenes, ``runin-examples``, ``--version``, the wheel.

The example scenes live in ``steady/examples`` (package data); ``runin-examples`` lists them
and copies one with the map files it names.  Every command answers ``--version``.  A slow test
builds the wheel and checks that the scenes and the map files are in it.
"""

import pathlib
import re
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from steady import examples
from steady.cli.entry import runin_examples
from steady.scene import load_scene
from steady.version import __version__

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: Every command and how ``python -m`` runs it.
COMMANDS = {"runin-steady": "steady", "runin-transient": "transient",
            "runin-fit": "steady.cli.fit", "runin-design": "steady.cli.design",
            "runin-examples": "steady.cli.examples"}

#: The examples that name map files, and those files.
MAP_FILES = {"aggregate_chip": ["aggregate_chip_mask.npy"],
             "checkerboard": ["checkerboard.npy"],
             "micrograph_steady": ["micrograph_example.png"],
             "voxel_stack_transient": ["voxel_stack.npy"]}


def test_every_scene_file_is_an_example_with_a_description():
    listed = examples.list_examples()
    on_disk = sorted(p.stem for p in (ROOT / "steady" / "examples").glob("*.toml"))
    assert list(listed) == on_disk, f"listed {list(listed)}, on disk {on_disk}"
    assert "voronoi_transient" in listed and "voronoi_biphasic" in listed, f"{list(listed)}"
    for name, description in listed.items():
        first = examples.path(name).read_text().splitlines()[0]
        assert first == f"# {description}", f"{name}: {description!r} is not {first!r}"
        assert 10 < len(description) <= 80, f"{name}: description {description!r}"


def test_every_example_names_only_files_that_ship_beside_it():
    for name in examples.list_examples():
        names = examples.files(name)
        assert names[0] == f"{name}.toml", f"{name}: {names}"
        assert names[1:] == MAP_FILES.get(name, []), f"{name}: map files {names[1:]}"
        for file in names:
            assert (examples.path(name).parent / file).is_file(), f"{name}: {file} missing"


def test_runin_examples_lists_names_and_descriptions(capsys):
    assert runin_examples([]) == 0, "listing failed"
    lines = capsys.readouterr().out.splitlines()
    listed = examples.list_examples()
    assert len(lines) == len(listed), f"{len(lines)} lines for {len(listed)} examples"
    for line, (name, description) in zip(lines, listed.items(), strict=True):
        assert re.fullmatch(rf"{name} +{re.escape(description)}", line), f"line {line!r}"


def test_copy_brings_the_map_files_and_the_copy_solves_as_the_original(tmp_path, capsys):
    assert runin_examples(["aggregate_chip", "-o", str(tmp_path / "ex")]) == 0, "copy failed"
    written = capsys.readouterr().out.split()
    expected = [str(tmp_path / "ex" / f) for f in ("aggregate_chip.toml",
                                                   "aggregate_chip_mask.npy")]
    assert written == expected, f"written {written}"
    for file in expected:
        original = examples.path("aggregate_chip").parent / pathlib.Path(file).name
        assert pathlib.Path(file).read_bytes() == original.read_bytes(), f"{file} differs"
    copy, shipped = (load_scene(p) for p in (expected[0], examples.path("aggregate_chip")))
    assert np.array_equal(copy.outline.mask, shipped.outline.mask), "the copy's mask"


def test_copy_refuses_to_overwrite_and_writes_nothing(tmp_path, capsys):
    target = tmp_path / "micrograph_example.png"
    target.write_bytes(b"mine")
    assert runin_examples(["micrograph_steady", "-o", str(tmp_path)]) == 2, "overwrote"
    err = capsys.readouterr().err
    assert err == f"error: {str(target)!r} exists (use --force to overwrite)\n", err
    assert target.read_bytes() == b"mine", "the user's file was overwritten"
    assert not (tmp_path / "micrograph_steady.toml").exists(), "a file was copied anyway"
    assert runin_examples(["micrograph_steady", "-o", str(tmp_path), "--force"]) == 0, "--force"
    assert target.read_bytes() == (examples.path("micrograph_steady").parent
                                   / target.name).read_bytes(), "--force did not copy"


def test_unknown_example_is_refused_with_the_names(tmp_path, capsys):
    assert runin_examples(["voronoi", "-o", str(tmp_path)]) == 2, "unknown name accepted"
    err = capsys.readouterr().err
    names = ", ".join(examples.list_examples())
    assert err == f"error: no example named 'voronoi'; the examples are: {names}\n", err
    assert not any(tmp_path.iterdir()), "something was written"


def test_output_without_a_name_is_refused(tmp_path, capsys):
    assert runin_examples(["-o", str(tmp_path)]) == 2, "-o without a name accepted"
    err = capsys.readouterr().err
    assert err.startswith("error: -o and --force copy an example: name one") and \
        err.count("\n") == 1, err
    assert not any(tmp_path.iterdir()), "something was written"


def test_copy_into_a_file_is_refused(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="is not a directory"):
        examples.copy("checkerboard", tmp_path / "f")


@pytest.mark.parametrize("where", ["loop", "loop/sub"])
def test_copy_into_a_loop_of_links_is_bad_input(tmp_path, capsys, where):
    (tmp_path / "loop").symlink_to("loop")
    target = tmp_path / where
    assert runin_examples(["checkerboard", "-o", str(target)]) == 2, "not bad input"
    err = capsys.readouterr().err
    assert err == f"error: {str(target)!r}: Too many levels of symbolic links\n", err


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_prints_its_version(command):
    proc = subprocess.run([sys.executable, "-m", COMMANDS[command], "--version"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert proc.returncode == 0, f"{command}: exit {proc.returncode}, {proc.stderr!r}"
    assert proc.stdout == f"python -m {COMMANDS[command]} (runin {__version__})\n", \
        f"{command}: {proc.stdout!r}"


def test_the_version_is_the_distribution_s():
    from importlib import metadata

    import steady
    import transient

    try:
        expected = metadata.version("runin")
    except metadata.PackageNotFoundError:
        expected = "0+unknown"
    assert steady.__version__ == transient.__version__ == expected, \
        f"{steady.__version__}, {transient.__version__}, expected {expected}"
    assert "__version__" not in steady.__all__, "__version__ is not a public name to import"


@pytest.mark.slow
def test_the_wheel_ships_the_examples_and_the_entry_point(tmp_path):
    # Built from a copy: pip builds in the source directory (build/, *.egg-info).
    source = tmp_path / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", "build", "*.egg-info", "__pycache__", ".*_cache", "out", "runin-studies-out"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps",
                           "-w", str(tmp_path / "dist")], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, f"pip wheel failed: {proc.stderr[-2000:]}"
    (wheel,) = (tmp_path / "dist").glob("runin-*.whl")
    with zipfile.ZipFile(wheel) as whl:
        names = set(whl.namelist())
        entry_points = next(whl.read(n).decode() for n in names
                            if n.endswith(".dist-info/entry_points.txt"))
    for scene in (ROOT / "steady" / "examples").iterdir():
        if scene.suffix in (".toml", ".npy", ".png") or scene.name == "__init__.py":
            assert f"steady/examples/{scene.name}" in names, f"{scene.name} not in the wheel"
    assert "steady/data/design_table.h5" in names, "the design table is not in the wheel"
    assert "runin-examples = steady.cli.entry:runin_examples" in entry_points, entry_points


def test_runin_examples_loads_no_numerical_module(tmp_path):
    """Listing and copying need neither numpy nor h5py: the command starts at once."""
    code = ("import sys\n"
            "from steady.cli.entry import runin_examples\n"
            f"assert runin_examples(['checkerboard', '-o', {str(tmp_path)!r}]) == 0\n"
            "print(sorted(m for m in sys.modules\n"
            "             if m.split('.')[0] in ('numpy', 'scipy', 'h5py', 'matplotlib')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == "[]", f"loaded {proc.stdout.splitlines()[-1]}"
