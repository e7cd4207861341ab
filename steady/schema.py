"""Declarative schemas of scene tables: every key with its type, unit, range and meaning.

A scene file (:mod:`steady.scene`) is read through schemas: a :class:`Key`
says what one key holds (a number, an integer, a string, a path, a list of
numbers or of pairs), its unit, its range and what it means; a table's keys
are read and checked together by :func:`read_table` (unknown keys, missing
keys, each value), and every error names the table, the key and the value.

Tables that name a *kind* -- the face outline (``[punch] shape``), the phase
map (``[phases] map kind``), the wear law (``[wear] law``), the initial face
of a run-in (``[initial_face] kind``) -- read it from a :class:`KindRegistry`
(a :class:`steady.registry.Registry`): each kind is a class registered with
its keys by a decorator, and builds itself from the checked values with
``from_values(values, context)``.  Adding a kind is one registration in one
module: the scene reader, the error messages and the documentation tables
come from it.

Examples
--------
>>> ratio = Key("ratio", "number", unit="1", low=0.0, doc="a ratio")
>>> read_table({"ratio": 0.5}, "[demo]", (ratio,))
{'ratio': 0.5}
>>> try:
...     read_table({"ratio": -1}, "[demo]", (ratio,))
... except ValueError as err:
...     print(err)
[demo] ratio must be a number > 0 (1), got -1
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import pathlib

from .registry import Registry
from .text import shorten

__all__ = ["SCALE_RANGE", "SCALE_UNITS", "Context", "Key", "KindRegistry", "read_table"]

#: Types a key may hold.
TYPES = ("number", "integer", "string", "path", "numbers", "integers", "pairs", "pair",
         "strings", "boolean", "number_lists")

#: The range of every scale of a problem, in SI units: lengths, forces,
#: moduli, speeds and what follows from them (:func:`steady.problem.check_scales`).
#: Physical problems lie far inside it; beyond it double precision overflows.
SCALE_RANGE = (1e-30, 1e30)

#: Units of the scales a key may hold: a positive number (``low = 0``) in one
#: of them -- a length, a force, a modulus, a speed -- must lie in :data:`SCALE_RANGE`.
SCALE_UNITS = ("m", "N", "Pa", "m/s")


@dataclasses.dataclass(frozen=True)
class Key:
    """One key of a scene table.

    Parameters
    ----------
    name : str
        The key as written in the scene file.
    type : str
        ``"number"`` (an int or a float, finite), ``"integer"``,
        ``"string"`` (non-empty), ``"path"`` (a non-empty string, resolved
        against the scene file's directory), ``"numbers"``,
        ``"integers"``, ``"strings"`` (arrays of those), ``"pairs"`` (an
        array of ``[x, y]``), ``"pair"`` (one ``[x, y]``), ``"boolean"``
        (``true`` or ``false``).
    unit : str, optional
        Unit of the value (``"m"``, ``"N"``, ``"Pa"``, ``"1/Pa"``, ``"1"``
        for a pure number, ``"s*"`` for a distance in run-in units, ...);
        empty for strings.
    doc : str, optional
        What the key means, for the documentation.
    required : bool, optional
        Whether the key must be present (default False).
    default : object, optional
        The value of an absent optional key (default None: absent).
    low, high : float, optional
        Bounds of a number (of each number of a list).
    low_open, high_open : bool, optional
        Whether the bounds are excluded (default True: ``low < v < high``).
    choices : tuple of str, optional
        The values a string may take.
    finite : bool, optional
        Whether a number must be finite (default True).
    per_phase : bool, optional
        Whether the value is a list with one entry per phase (a wear law's
        coefficients): the law of some of the phases keeps those entries
        (:meth:`steady.wear.WearLaw.restrict`).  Default False.

    Notes
    -----
    A positive number (``low = 0``) in a unit of :data:`SCALE_UNITS` (a
    length, a force, a modulus, a speed) must also lie in
    :data:`SCALE_RANGE`: a value beyond it is refused with the range, not
    met later as an overflow.
    """

    name: str
    type: str
    unit: str = ""
    doc: str = ""
    required: bool = False
    default: object = None
    low: float | None = None
    high: float | None = None
    low_open: bool = True
    high_open: bool = True
    choices: tuple | None = None
    finite: bool = True
    per_phase: bool = False

    def __post_init__(self):
        """Check the declaration itself."""
        if self.type not in TYPES:
            raise ValueError(f"key {self.name!r}: unknown type {self.type!r}")

    def range_text(self):
        """The range in words, e.g. ``"> 0"`` or ``"in (0, 1)"``; empty without bounds."""
        lo, hi = self.low, self.high
        if lo is not None and hi is not None:
            return (f"in {'(' if self.low_open else '['}{lo:g}, {hi:g}"
                    f"{')' if self.high_open else ']'}")
        if lo is not None:
            return f"{'>' if self.low_open else '>='} {lo:g}"
        if hi is not None:
            return f"{'<' if self.high_open else '<='} {hi:g}"
        return ""

    def describe(self):
        """What the key holds, for messages and docs: ``"a number > 0 (m)"``."""
        noun = {"number": "a number", "integer": "an integer", "string": "a string",
                "path": "a file name", "numbers": "an array of numbers",
                "integers": "an array of integers",
                "strings": "an array of non-empty strings", "pairs": "an array of [x, y] pairs",
                "pair": "an [x, y] pair", "boolean": "true or false",
                "number_lists": "an array of arrays of numbers"}[self.type]
        bound = self.range_text()
        if bound:
            each = self.type in ("numbers", "integers", "pairs", "number_lists")
            noun += f" {'each ' if each else ''}{bound}"
        if self.choices:
            noun = "one of " + ", ".join(repr(c) for c in self.choices)
        return f"{noun} ({self.unit})" if self.unit else noun

    def parse(self, value, where, base_dir=".", *, scale=True):
        """The value of this key, checked; ``ValueError`` naming ``where``, the key and the value.

        Parameters
        ----------
        value : object
            As read from the TOML file.
        where : str
            The table, for messages (``"[load]"``, ``"[phases] map"``).
        base_dir : path-like, optional
            Directory against which a ``"path"`` is resolved.
        scale : bool, optional
            Check a length, force, modulus or speed against :data:`SCALE_RANGE`
            (default True); False leaves that to a caller that names the
            value in its own words (:func:`steady.problem.check_input_scales`).

        Returns
        -------
        float, int, str, pathlib.Path, tuple of float, int or str, or tuple of
        (float, float)
        """
        name = f"{where} {self.name}" if where else self.name
        if self.type == "number_lists":
            if not isinstance(value, list) or not all(isinstance(v, list) for v in value):
                raise ValueError(f"{name} must be {self.describe()}, got {shorten(value)}")
            single = dataclasses.replace(self, type="number")
            try:
                return tuple(tuple(single._scalar(v, name, value, base_dir) for v in row)
                             for row in value)
            except ValueError:
                raise ValueError(f"{name} must be {self.describe()}, got "
                                 f"{shorten(value)}") from None
        if self.type in ("numbers", "integers", "pairs", "strings"):
            if not isinstance(value, list):
                raise ValueError(f"{name} must be {self.describe()}, got {shorten(value)}")
            item = {"numbers": "number", "integers": "integer", "pairs": "pair",
                    "strings": "string"}[self.type]
            single = dataclasses.replace(self, type=item)
            try:
                values = tuple(single._scalar(v, name, value, base_dir) for v in value)
            except ValueError:
                raise ValueError(f"{name} must be {self.describe()}, got "
                                 f"{shorten(value)}") from None
            if scale:
                self._check_scale(values, name, value)
            return values
        parsed = self._scalar(value, name, value, base_dir)
        if scale:
            self._check_scale((parsed,), name, value)
        return parsed

    def parse_text(self, text):
        """The value of a command-line argument ``text`` for this key (a flag's check).

        Parameters
        ----------
        text : str
            The argument as typed.

        Returns
        -------
        float, int or str

        Raises
        ------
        ValueError
            ``"expected a number > 0 (m), got 'abc'"``, or for a length,
            force, modulus or speed outside :data:`SCALE_RANGE`, the value and
            that range; the caller names the flag.

        Examples
        --------
        >>> Key("limit", "number", unit="m", low=0.0).parse_text("1e3")
        1000.0
        >>> try:
        ...     Key("limit", "number", unit="m", low=0.0).parse_text("1e300")
        ... except ValueError as err:
        ...     print(err)
        1e+300 m is outside [1e-30, 1e+30] m, the range of every scale of a problem (SI units)
        """
        expected = f"expected {self.describe()}, got {shorten(text)}"
        try:
            value = int(text) if self.type == "integer" else float(text)
        except ValueError:
            if self.type != "string":
                raise ValueError(expected) from None
            value = text
        try:
            parsed = self.parse(value, "", scale=False)
        except ValueError:
            raise ValueError(expected) from None
        self._check_scale((parsed,), "", parsed)
        return parsed

    def _check_scale(self, values, name, shown):
        """Refuse a length, force, modulus or speed outside :data:`SCALE_RANGE` (see Notes)."""
        if self.unit not in SCALE_UNITS or self.low != 0.0 or self.type not in (
                "number", "numbers"):
            return
        low, high = SCALE_RANGE
        for v in values:
            if (math.isinf(v) and not self.finite) or (v == 0 and not self.low_open):
                continue  # "no limit", or a value the key admits at its bound
            if not low <= v <= high:
                given = (f"{shorten(shown)} {self.unit}" if len(values) == 1 and
                         not isinstance(shown, list)
                         else f"{shorten(shown)}: {v!r} {self.unit}")
                value = f"{name} = {given}" if name else given
                raise ValueError(f"{value} is outside [{low:g}, {high:g}] {self.unit}, "
                                 f"the range of every scale of a problem (SI units)")

    def _scalar(self, value, name, shown, base_dir):
        """One value; messages show ``shown`` (the whole list for a list's item)."""
        bad = f"{name} must be {self.describe()}, got {shorten(shown)}"
        if self.type == "boolean":
            if not isinstance(value, bool):
                raise ValueError(bad)
            return value
        if self.type in ("string", "path"):
            if not isinstance(value, str) or not value:
                raise ValueError(bad)
            if "\0" in value:
                raise ValueError(f"{name} must not contain a null byte, got {shorten(value)}")
            if self.choices is not None and value not in self.choices:
                raise ValueError(bad)
            return pathlib.Path(base_dir) / value if self.type == "path" else value
        if self.type == "pair":
            if not isinstance(value, list) or len(value) != 2:
                raise ValueError(bad)
            number = dataclasses.replace(self, type="number")
            return tuple(number._scalar(v, name, shown, base_dir) for v in value)
        # numpy's numbers too (from Python); a bool is not a number.
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(bad)
        if self.type == "integer":
            if not isinstance(value, numbers.Integral):
                raise ValueError(bad)
            value = int(value)
        else:
            value = float(value)
            if self.finite and not math.isfinite(value):
                raise ValueError(bad)
            if math.isnan(value):
                raise ValueError(bad)
        if not self._in_range(value):
            raise ValueError(bad)
        return value

    def _in_range(self, value):
        if self.low is not None and not (value > self.low if self.low_open
                                         else value >= self.low):
            return False
        if self.high is not None and not (value < self.high if self.high_open
                                          else value <= self.high):
            return False
        return True


def read_table(table, where, keys, base_dir=".", *, ignore=(), kind=""):
    """Read a scene table through its keys: unknown and missing keys refused, values checked.

    Parameters
    ----------
    table : dict
        As read from the TOML file.
    where : str
        The table, for messages (``"[load]"``).
    keys : sequence of Key
    base_dir : path-like, optional
        Directory of the scene file (for ``"path"`` keys).
    ignore : collection of str, optional
        Keys read elsewhere (e.g. ``kind``), neither refused nor returned.
    kind : str, optional
        The table's kind, named by the messages on unknown and missing
        keys (e.g. ``"kind 'voronoi'"``).

    Returns
    -------
    dict
        ``name -> value`` for every key present, and the ``default`` of
        every absent optional key that has one.

    Raises
    ------
    ValueError
        Not a table, an unknown or missing key, or a bad value; the message
        names ``where``, the key and the value.
    """
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table, got {shorten(table)}")
    names = {key.name for key in keys} | set(ignore)
    table_name = f"{where} ({kind})" if kind else where
    unknown = sorted(set(table) - names)
    if unknown:
        allowed = ", ".join(sorted(names)) or "none"
        raise ValueError(f"unknown key {shorten(unknown[0])} in {table_name} (allowed: "
                         f"{allowed})")
    for key in keys:
        if key.required and key.name not in table:
            raise ValueError(f"missing key {key.name!r} in {table_name}")
    values = {}
    for key in keys:
        if key.name in table:
            values[key.name] = key.parse(table[key.name], where, base_dir)
        elif key.default is not None:
            values[key.name] = key.default
    return values


@dataclasses.dataclass(frozen=True)
class Context:
    """What a kind may need beside its own keys to build itself from a scene.

    Attributes
    ----------
    base_dir : pathlib.Path
        Directory of the scene file.
    outline : outline object or None
        The face's outline (:mod:`steady.outline`), once read.
    n : int or None
        The scene's grid size, pixels along the longer side.
    n_phases : int or None
        Phases of the phase map, once read.
    where : str
        The table being read, for messages.
    """

    base_dir: pathlib.Path = pathlib.Path(".")
    outline: object = None
    n: int | None = None
    n_phases: int | None = None
    where: str = ""


class KindRegistry(Registry):
    """The kinds of one scene table, each a class registered with its keys.

    A :class:`steady.registry.Registry` whose entries are the kinds a
    table names by its ``selector`` key; the scene reader, its messages and
    the documentation's tables of keys (docs/scenes.md) come from it.

    Parameters
    ----------
    what : str
        What the kinds are, for messages and docs (``"phase map"``).
    selector : str
        The key that names the kind (``"kind"``, ``"shape"``, ``"law"``).
    default : str, optional
        The kind of a table that does not name one.
    base : type, optional
        The class every kind subclasses: its written contract
        (:class:`steady.phases.PhaseMap` for phase maps).  Default: none.
    modules, entry_point_group : optional
        Where kinds defined elsewhere are registered from, imported on the
        first lookup (:class:`steady.registry.Registry`).

    Examples
    --------
    >>> shapes = KindRegistry("demo shape", "shape", default="dot")
    >>> @shapes.register("dot", (Key("size", "number", unit="m", low=0.0, required=True),))
    ... class Dot:
    ...     def __init__(self, size):
    ...         self.size = size
    ...     @classmethod
    ...     def from_values(cls, values, context):
    ...         return cls(values["size"])
    >>> shapes.build({"size": 2}, Context(where="[demo]")).size
    2.0
    >>> sorted(shapes)
    ['dot']
    """

    def __init__(self, what, selector, default=None, *, base=None, modules=(),
                 entry_point_group=None):
        super().__init__(what, modules=modules, entry_point_group=entry_point_group)
        self.selector = selector
        self.default = default
        self.base = base

    def register(self, kind, keys=(), doc=""):
        """Class decorator: register a kind with its keys (a sequence of :class:`Key`).

        The class gets the attributes ``kind`` and ``keys`` (and ``kind_doc``
        with ``doc``) and must have a classmethod ``from_values(values,
        context)`` (``values`` the checked keys, ``context`` a
        :class:`Context`); with a ``base``, it must subclass it.

        Raises
        ------
        ValueError
            ``kind`` is already registered.
        TypeError
            The class does not subclass the registry's ``base``.
        """
        keys = tuple(keys)
        if kind in self._entries:
            raise ValueError(f"{self.what} kind {kind!r} is already registered")

        def decorate(cls):
            if self.base is not None and not (isinstance(cls, type)
                                              and issubclass(cls, self.base)):
                raise TypeError(f"{self.what} kind {kind!r}: {cls!r} must subclass "
                                f"{self.base.__module__}.{self.base.__qualname__}")
            cls.kind = kind
            cls.keys = keys
            if doc:
                cls.kind_doc = doc
            return super(KindRegistry, self).register(kind, cls)
        return decorate

    def kind_of(self, table, where):
        """The class a table names; ``ValueError`` naming the choices for an unknown kind."""
        if not isinstance(table, dict):
            raise ValueError(f"{where} must be a table, got {shorten(table)}")
        kind = table.get(self.selector, self.default)
        if not isinstance(kind, str) or kind not in self:
            raise ValueError(f"{where} {self.selector} must be one of {sorted(self)}, "
                             f"got {shorten(kind)}")
        return self[kind]

    def read(self, table, context):
        """The class a table names and its checked values."""
        cls = self.kind_of(table, context.where)
        return cls, read_table(table, context.where, cls.keys, context.base_dir,
                               ignore=(self.selector,), kind=f"{self.selector} {cls.kind!r}")

    def build(self, table, context):
        """The object a table describes: its kind's ``from_values`` on the checked values."""
        cls, values = self.read(table, context)
        return cls.from_values(values, context)
