"""The example scenes shipped with the package, and their map files.

Each example is a scene file ``<name>.toml`` in this package's directory,
with the ``.npy`` and ``.png`` files it names (``path`` keys: a mask, a
phase map, a micrograph; a voxel map's ``file``) beside it.  The first comment line of a scene is
its one-line description.  The command ``runin-examples`` lists them and
copies one, with its files, into a directory of the user's.

Examples
--------
>>> from steady import examples
>>> examples.list_examples()["voronoi_biphasic"]
"Biphasic Voronoi punch of the paper's Fig. 3-4 (40^2 seeds, k_1/k_0 = 10)"
>>> examples.path("voronoi_transient").name
'voronoi_transient.toml'
>>> examples.files("micrograph_steady")
['micrograph_steady.toml', 'micrograph_example.png']
"""

from __future__ import annotations

import pathlib
import shutil
import stat
from importlib import resources

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

__all__ = ["copy", "files", "list_examples", "path"]


def _directory():
    """The directory of the shipped scenes (a real directory: the package is not zipped)."""
    return pathlib.Path(str(resources.files(__name__)))


def list_examples():
    """The shipped example scenes and their one-line descriptions.

    Returns
    -------
    dict of str to str
        Scene name (the file stem, e.g. ``"voronoi_transient"``) -> the
        text of its first comment line, sorted by name.
    """
    return {scene.stem: _description(scene)
            for scene in sorted(_directory().glob("*.toml"))}


def _description(scene):
    """The first comment line of a scene file, without its ``#``; empty if it has none."""
    for line in scene.read_text().splitlines():
        if line.startswith("#"):
            return line.lstrip("#").strip()
        if line.strip():
            break
    return ""


def path(name):
    """The installed scene file of an example.

    Parameters
    ----------
    name : str
        The example's name (:func:`list_examples`), e.g. ``"voronoi_biphasic"``.

    Returns
    -------
    pathlib.Path
        ``<package>/steady/examples/<name>.toml``; the map files it names lie
        beside it, so ``steady.load_scene(path(name))`` reads it in place.

    Raises
    ------
    ValueError
        No example has that name; the message lists the names.
    """
    names = list(list_examples())
    if name not in names:
        raise ValueError(f"no example named {str(name)!r}; the examples are: "
                         f"{', '.join(names)}")
    return _directory() / f"{name}.toml"


def files(name):
    """The files of an example: its scene, then the files the scene names.

    Parameters
    ----------
    name : str
        The example's name.

    Returns
    -------
    list of str
        File names relative to the example directory: ``<name>.toml`` first,
        then every relative ``path`` value of the scene (any table, also a
        voxel map's ``file``), in the order of the file.
    """
    scene = path(name)
    found = [scene.name]

    def walk(table):
        for key, value in table.items():
            if isinstance(value, dict):
                walk(value)
            elif key in ("path", "file") and isinstance(value, str) and value not in found:
                found.append(value)

    walk(tomllib.loads(scene.read_text()))
    return found


def copy(name, directory, *, force=False):
    """Copy an example's scene and the files it names into a directory.

    Nothing is written unless every file can be: an existing file is
    refused (without ``force``) before the first one is copied.

    Parameters
    ----------
    name : str
        The example's name (:func:`list_examples`).
    directory : str or path-like
        Where to put the files; created if missing.
    force : bool, optional
        Replace files of the same names (default False).

    Returns
    -------
    list of pathlib.Path
        The files written, the scene first.

    Raises
    ------
    ValueError
        Unknown name (the message lists the names), ``directory`` is a file
        or cannot be looked up (a loop of symbolic links, a file on its
        way), or a target exists and ``force`` is False (the message names
        it).
    """
    source = path(name).parent
    directory = pathlib.Path(directory)
    try:
        mode = directory.stat().st_mode
    except FileNotFoundError:
        mode = None  # created below
    except OSError as err:  # a loop of symbolic links, a file on the way
        raise ValueError(f"{str(directory)!r}: {err.strerror or err}") from None
    if mode is not None and not stat.S_ISDIR(mode):
        raise ValueError(f"{str(directory)!r} is not a directory")
    targets = [(source / file, directory / file) for file in files(name)]
    for _, target in targets:
        if target.is_dir():
            raise ValueError(f"{str(target)!r} is a directory")
        if target.exists() and not force:
            raise ValueError(f"{str(target)!r} exists (use --force to overwrite)")
    written = []
    for origin, target in targets:
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(origin, target)
        written.append(target)
    return written
