"""The tables of scene keys, from their declarations (``steady.schema.Key``).

Every key of a scene file is declared once, with its type, unit, range,
default and meaning: in ``steady.scene`` (``SECTIONS``, ``PHASE_KEYS``,
``DEPTH_KEYS``, ``LAYER_KEYS``), in the fields of
``transient.options.RunOptions`` (``[transient]``) and in the registries of
the tables that name a kind (outlines, phase maps, wear laws, sliding kinds,
initial faces).  :func:`tables` turns one table of the scene into rows of
text; the documentation's ``scene-keys`` directive (``runin_directives``)
draws them, and the tests check them against the declarations.

Nothing here imports Sphinx, so that the tests run without the ``docs``
extra.
"""

from __future__ import annotations

import dataclasses
import math

#: The scene's tables, in the order of docs/scenes.md: name -> what it is.
TABLES = {
    "punch": "the face outline, by its `shape`",
    "load": "the load",
    "counterbody": "the counter-body",
    "grid": "the grid",
    "wear": "the wear law, by its `law`",
    "phases": "the phases, beside their map",
    "phases.map": "the phase map, by its `kind`",
    "sliding": "the sliding kinematics, by its `kind`",
    "depth": "a phase map that changes with depth",
    "depth.layers": "each layer of `[depth]`, from the surface down",
    "transient": "the run-in's options",
    "initial_face": "the run-in's initial face, by its `kind`",
}

#: The columns of every table.
COLUMNS = ("key", "type", "unit", "range", "default", "meaning")


@dataclasses.dataclass(frozen=True)
class Table:
    """The keys of one scene table, or of one kind of it.

    Attributes
    ----------
    caption : str
        What the table is: the section, and the kind with its description.
    rows : tuple of tuple of str
        One row per key, in the order of :data:`COLUMNS`; empty for a kind
        without keys.
    """

    caption: str
    rows: tuple


def _registry(name):
    """The kind registry of a table, or None for a table of plain keys."""
    if name == "punch":
        from steady.outline import OUTLINES
        return OUTLINES
    if name == "wear":
        from steady.wear import WEAR_LAWS
        return WEAR_LAWS
    if name == "phases.map":
        from steady.phases import PHASE_MAPS
        return PHASE_MAPS
    if name == "sliding":
        from steady.sliding import SLIDING
        return SLIDING
    if name == "initial_face":
        from transient.initial_face import INITIAL_FACES
        return INITIAL_FACES
    return None


def _keys(name):
    """The keys of a table of plain keys, with the defaults they take when absent."""
    from steady.scene import DEPTH_KEYS, LAYER_KEYS, PHASE_KEYS, SECTIONS

    if name in SECTIONS:
        return [(key, key.default) for key in SECTIONS[name]]
    if name == "transient":
        from transient.options import RunOptions
        return [(field.metadata["key"], field.default)
                for field in dataclasses.fields(RunOptions)]
    return [(key, key.default) for key in {"phases": PHASE_KEYS, "depth": DEPTH_KEYS,
                                           "depth.layers": LAYER_KEYS}[name]]


def _text(value):
    """A default as it is written in a scene file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "inf" if math.isinf(value) else f"{value:g}"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple):
        return "[" + ", ".join(_text(v) for v in value) + "]"
    return str(value)


def row(key, default=None):
    """One row of :data:`COLUMNS` for a key.

    Parameters
    ----------
    key : steady.schema.Key
    default : object, optional
        The value an absent key takes (``key.default`` unless the key's
        owner keeps it elsewhere, as ``RunOptions`` does); None: none.

    Returns
    -------
    tuple of str
    """
    bare = dataclasses.replace(key, unit="", low=None, high=None, choices=None)
    if key.choices:
        bounds = "one of " + ", ".join(f'"{c}"' for c in key.choices)
    else:
        bounds = key.range_text()
    if key.required:
        given = "required"
    elif default is None:
        given = "optional"
    else:
        given = _text(default)
    return (key.name, bare.describe(), key.unit, bounds, given, key.doc)


def tables(name):
    """The tables of one scene table: one of its keys, or one per kind.

    Parameters
    ----------
    name : str
        A table of :data:`TABLES`.

    Returns
    -------
    list of Table

    Raises
    ------
    KeyError
        ``name`` is not in :data:`TABLES`.
    """
    what = TABLES[name]
    section = {"phases.map": "[phases] map", "depth.layers": "[[depth.layers]]"}.get(
        name, f"[{name}]")
    registry = _registry(name)
    if registry is None:
        return [Table(f"{section}: {what}", tuple(row(key, default)
                                                  for key, default in _keys(name)))]
    found = []
    for kind in registry:
        entry = registry[kind]
        default = " (the default)" if kind == registry.default else ""
        doc = getattr(entry, "kind_doc", "")
        caption = f'{section} {registry.selector} = "{kind}"{default}: {doc}'.rstrip(": ")
        found.append(Table(caption, tuple(row(key, key.default) for key in entry.keys)))
    return found
