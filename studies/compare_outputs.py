"""The files the shipped scenes produce are the same at two revisions of the code.

What it checks
    Every scene of ``steady/examples/`` is run through the commands of two
    source trees -- this one and another revision, checked out beside it
    with ``git worktree`` -- with the same Python: the steady result of
    every scene (``runin-steady``), the run file of every scene with a
    ``[transient]`` or ``[initial_face]`` section (``runin-transient``) and
    the fit file of a synthetic measured face of three scenes
    (``runin-fit``: the steady face of the base revision plus seeded
    noise, the same map for both trees).  Each pair of HDF5
    files is compared value by value and bit by bit: every group, dataset
    and attribute, their dtypes, shapes and bytes (NaN equal to NaN).
    Only what cannot repeat is left out: the wall-clock figures of a run
    (``wall_time`` and the checksums that cover it), and the trees' own
    paths inside stored text (replaced by ``<tree>``).

    A restructuring of the code must leave every file identical; a change
    of the numerics shows here as the list of what differs.

How to run
    python studies/compare_outputs.py --base 7d5b4a7        # about 3 min on 2 cores
    python studies/compare_outputs.py --base HEAD~3 --keep out/compare

The commands are started as ``python -c`` with each tree first on
``PYTHONPATH`` and their entry points read from each tree's
``pyproject.toml`` (``[project.scripts]``), so that a tree whose commands
moved between modules is run the way it was installed.  Exit status 0
when every pair is identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from steady.output import read_result

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = pathlib.Path(__file__).resolve().parent.parent

#: Scenes whose steady face is fitted back (a disk, a rectangle, an annulus).
FIT_SCENES = ("rods_steel_in_brass", "tread_block", "annular_seal")

#: Relative noise of the synthetic measured faces, and its seed.
FIT_NOISE, FIT_SEED = 0.02, 3571

#: Attributes that change from one run to the next whatever the code.
VOLATILE = ("wall_time",)


def entry_points(tree):
    """``command -> (module, function)`` of a source tree's ``[project.scripts]``."""
    with open(tree / "pyproject.toml", "rb") as f:
        scripts = tomllib.load(f)["project"]["scripts"]
    return {name: tuple(target.split(":")) for name, target in scripts.items()}


def run_command(tree, command, args, log):
    """Run one command of ``tree`` as it is installed; return its exit status."""
    module, function = entry_points(tree)[command]
    code = f"import sys; from {module} import {function} as main; sys.exit(main())"
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    with open(log, "a") as out:
        out.write(f"$ {command} {' '.join(map(str, args))}\n")
        out.flush()
        return subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=tree,
                              env=env, stdout=out, stderr=subprocess.STDOUT).returncode


def scene_directory(tree):
    """The directory of a tree's shipped scenes (``studies/scenes`` in older revisions)."""
    shipped = tree / "steady" / "examples"
    return shipped if shipped.is_dir() else tree / "studies" / "scenes"


def scenes(tree):
    """The shipped scene files of a tree, and which of them carry run-in sections."""
    found = []
    for path in sorted(scene_directory(tree).glob("*.toml")):
        text = path.read_text()
        run_in = "[transient]" in text or "[initial_face]" in text
        found.append((path.stem, path, run_in))
    return found


def measured_faces(base_outputs, where):
    """Synthetic measured faces: the base tree's steady faces with seeded noise (.npy)."""
    rng = np.random.default_rng(FIT_SEED)
    faces = {}
    for name in FIT_SCENES:
        # Read by this tree's reader, which reads every layout: the face indexed [i, j].
        stored = read_result(base_outputs / f"fitface_{name}.h5").result
        face, h = stored.face, float(stored.pixel_size)
        noise = FIT_NOISE * np.nanstd(face) * rng.standard_normal(face.shape)
        path = where / f"measured_{name}.npy"
        np.save(path, face + noise)
        faces[name] = (path, h)
    return faces


def run_tree(tree, out, log, *, measured_source=False):
    """Every output of one tree into ``out``; returns the statuses of the commands.

    With ``measured_source`` also the plain steady faces the synthetic
    measured faces are made of (:func:`measured_faces`).
    """
    out.mkdir(parents=True, exist_ok=True)
    status = {}
    for name, scene, run_in in scenes(tree):
        status[f"steady/{name}"] = run_command(
            tree, "runin-steady", [scene, "-o", out / f"steady_{name}.h5", "--force"], log)
        if run_in:
            status[f"transient/{name}"] = run_command(
                tree, "runin-transient", [scene, "-o", out / f"transient_{name}.h5",
                                          "--force", "--checkpoint-interval", "1e9"], log)
        if measured_source and name in FIT_SCENES:
            status[f"fitface/{name}"] = run_command(
                tree, "runin-steady", [scene, "-o", out / f"fitface_{name}.h5", "--force",
                                       "--no-slope-error"], log)
    return status


def run_fits(tree, out, log, faces):
    """The fit of every synthetic measured face by one tree."""
    status = {}
    for name in FIT_SCENES:
        measured, h = faces[name]
        scene = scene_directory(tree) / f"{name}.toml"
        status[f"fit/{name}"] = run_command(
            tree, "runin-fit", [scene, measured, "-o", out / f"fit_{name}.h5", "--force",
                                "--pixel-size", repr(h)], log)
    return status


def _normalise(value, trees):
    """A stored value with each tree's path replaced by ``<tree>``."""
    if isinstance(value, bytes):
        try:
            value = value.decode()
        except UnicodeDecodeError:
            return value
    if isinstance(value, str):
        for tree in trees:
            value = value.replace(str(tree), "<tree>")
    return value


def _dereferenced(f, value):
    """An attribute with each object reference (dimension scales) replaced by the object's name."""
    a = np.asarray(value)
    if a.dtype.kind != "O" and not (a.dtype.fields and any(
            a.dtype[k].kind == "O" for k in a.dtype.fields)):
        return value

    def name(v):
        if isinstance(v, h5py.Reference):
            return f[v].name if v else ""
        if isinstance(v, (np.ndarray, list, tuple, np.void)):
            return [name(u) for u in v]
        return v

    return repr(name(a.tolist() if a.dtype.fields else list(a.flat)))


def _same(a, b):
    """Whether two stored values are identical: dtype, shape and bytes (NaN equal)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind in "OSU":
        return a.tolist() == b.tolist()
    return a.tobytes() == b.tobytes()


def compare_files(path_a, path_b, trees):
    """What differs between two HDF5 files, one line per difference."""
    differences = []
    with h5py.File(path_a, "r") as fa, h5py.File(path_b, "r") as fb:
        names_a, names_b = [""], [""]
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        for name in sorted(set(names_a) ^ set(names_b)):
            side = "only in the base" if name in names_a else "only in this tree"
            differences.append(f"/{name}: {side}")
        volatile = set(VOLATILE)
        for name in names_a:
            node = fa[name] if name else fa
            if "wall_time" in node.attrs or name.rpartition("/")[2] in VOLATILE:
                # The checksums of the run file cover its wall time.
                volatile.add("sha256")
        for name in sorted(set(names_a) & set(names_b)):
            node_a = fa[name] if name else fa
            node_b = fb[name] if name else fb
            where = f"/{name}"
            if isinstance(node_a, h5py.Dataset) != isinstance(node_b, h5py.Dataset):
                differences.append(f"{where}: a group in one file, a dataset in the other")
                continue
            if isinstance(node_a, h5py.Dataset) and name.rpartition("/")[2] in VOLATILE:
                continue  # the wall time as a variable (run layout 5 on)
            if isinstance(node_a, h5py.Dataset):
                va = _normalise(node_a[()], trees)
                vb = _normalise(node_b[()], trees)
                if not _same(va, vb):
                    differences.append(f"{where}: dataset differs")
            keys_a, keys_b = set(node_a.attrs), set(node_b.attrs)
            for key in sorted(keys_a ^ keys_b):
                side = "only in the base" if key in keys_a else "only in this tree"
                differences.append(f"{where} @{key}: {side}")
            for key in sorted(keys_a & keys_b):
                if key in volatile:
                    continue
                va = _normalise(_dereferenced(fa, node_a.attrs[key]), trees)
                vb = _normalise(_dereferenced(fb, node_b.attrs[key]), trees)
                if not _same(va, vb):
                    differences.append(f"{where} @{key}: {_shown(va)} != {_shown(vb)}")
    return differences


def _shown(value):
    text = repr(value)
    return text if len(text) < 80 else text[:77] + "..."


def main(argv=None):
    """Run both trees, compare their files, print what differs; 0 if nothing does."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", required=True,
                        help="the other revision (a commit, tag or branch of this repository)")
    parser.add_argument("--base-tree", type=pathlib.Path,
                        help="an existing checkout of --base to use instead of a new worktree")
    parser.add_argument("--keep", type=pathlib.Path,
                        help="keep the outputs and the commands' logs in this directory")
    args = parser.parse_args(argv)

    work = pathlib.Path(tempfile.mkdtemp(prefix="compare-outputs-"))
    base_tree = args.base_tree
    made_worktree = base_tree is None
    if made_worktree:
        base_tree = work / "base"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(base_tree),
                        args.base], check=True, capture_output=True)
    base_tree = base_tree.resolve()
    trees = (base_tree, ROOT)
    try:
        out = args.keep if args.keep is not None else work / "outputs"
        base_out, this_out = out / "base", out / "this"
        status = {}
        for label, tree, where in (("base", base_tree, base_out), ("this", ROOT, this_out)):
            for key, code in run_tree(tree, where, out / f"{label}.log",
                                      measured_source=label == "base").items():
                status[f"{label} {key}"] = code
        faces = measured_faces(base_out, out)
        for label, tree, where in (("base", base_tree, base_out), ("this", ROOT, this_out)):
            for key, code in run_fits(tree, where, out / f"{label}.log", faces).items():
                status[f"{label} {key}"] = code
        failed = 0
        for key in sorted(k for k in status if k.startswith("base ")):
            what = key[len("base "):]
            if what.startswith("fitface/"):
                continue
            kind, name = what.split("/")
            file_name = f"{kind}_{name}.h5"
            codes = status[key], status.get(f"this {what}")
            if codes[0] != codes[1]:
                print(f"{what}: exit status {codes[0]} (base) against {codes[1]} (this tree)")
                failed += 1
                continue
            if not (base_out / file_name).exists():
                print(f"{what}: no file from either tree (exit status {codes[0]})")
                continue
            differences = compare_files(base_out / file_name, this_out / file_name, trees)
            print(f"{what}: {'identical' if not differences else 'DIFFERS'}")
            for line in differences:
                print(f"    {line}")
            failed += bool(differences)
        compared = sum(1 for k in status if k.startswith("base ") and "fitface/" not in k)
        print(f"{failed} of {compared} outputs differ" if failed
              else f"every output is identical ({compared} files)")
        return 1 if failed else 0
    finally:
        if made_worktree:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(base_tree)], capture_output=True)
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
        elif made_worktree:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
