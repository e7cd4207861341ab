"""Registries: named entries of one kind, filled by a decorator where each entry is defined.

Every choice by name in the project -- the kinds of a scene table
(:class:`steady.schema.KindRegistry`), the time integrators
(:data:`transient.stepping.SCHEMES`), the preconditioners of the contact
solver (:data:`transient.preconditioners.PRECONDITIONERS`) -- is an entry of
a :class:`Registry`.  An entry is registered where it is defined
(``@registry.register(name)``), looked up by name (an unknown name is a
:class:`ValueError` listing the names known), iterated over in the order of
registration and, for a plug-in withdrawn or a test's own entry,
unregistered.

A registry may name the modules that define its built-in entries
(``modules``) and a group of entry points (``entry_point_group``): both are
imported on the first lookup or iteration, so that an entry defined in a
new module registers itself without an edit to the module that reads the
registry, and a package installed beside this one adds entries by naming
its module in the group ``[project.entry-points."runin.phase_maps"]`` of
its ``pyproject.toml`` (the module registers its entries when imported).

Examples
--------
>>> colours = Registry("colour")
>>> @colours.register("red")
... def red():
...     return (1.0, 0.0, 0.0)
>>> colours["red"]()
(1.0, 0.0, 0.0)
>>> try:
...     colours["blue"]
... except ValueError as err:
...     print(err)
unknown colour 'blue'; expected one of ['red']
"""

from __future__ import annotations

import functools
import importlib
import importlib.metadata
import logging
import warnings

from .text import shorten

__all__ = ["Registry"]

logger = logging.getLogger(__name__)

# The value of ``entry`` that makes :meth:`Registry.register` a decorator (None is an entry).
_DECORATE = object()


@functools.cache
def _installed_entry_points():
    """Every entry point of the installed distributions (read once per process)."""
    return importlib.metadata.entry_points()


class Registry:
    """Named entries of one kind: registered by decorator, looked up by name.

    Parameters
    ----------
    what : str
        What the entries are, for messages (``"scheme"``).
    modules : sequence of str, optional
        Dotted names of the modules that register built-in entries besides
        the one that declares the registry; imported on the first lookup.
    entry_point_group : str, optional
        A group of entry points (``"runin.schemes"``) whose modules are
        imported on the first lookup, after ``modules``: entries of other
        installed packages.

    Notes
    -----
    A lookup (``name in registry``, ``registry[name]``, iteration, ``len``)
    loads ``modules`` and the entry points once; registering does not, so
    that the modules it imports can register into it.  An entry point that
    cannot be loaded is reported by a :class:`RuntimeWarning` and skipped.
    """

    def __init__(self, what, *, modules=(), entry_point_group=None):
        self.what = what
        self._entries = {}
        self._modules = tuple(modules)
        self._entry_point_group = entry_point_group
        self._loaded = not self._modules and entry_point_group is None

    def _load(self):
        """Import the modules and entry points that register entries, once."""
        if self._loaded:
            return
        # Set first: a module being imported may look the registry up.
        self._loaded = True
        try:
            for module in self._modules:
                importlib.import_module(module)
        except BaseException:
            self._loaded = False
            raise
        if self._entry_point_group is not None:
            for point in _installed_entry_points().select(group=self._entry_point_group):
                try:
                    point.load()
                except Exception as err:  # a broken plug-in must not break the built-ins
                    warnings.warn(f"{self.what} plug-in {point.name!r} ({point.value}) cannot "
                                  f"be loaded: {str(err)[:200]}", RuntimeWarning, stacklevel=3)

    def register(self, name, entry=_DECORATE):
        """Register ``entry`` under ``name``; without ``entry``, a decorator that does.

        Parameters
        ----------
        name : str
        entry : object, optional
            Anything (None too).  Omitted: ``register(name)`` returns a
            decorator that registers what it decorates and returns it.

        Returns
        -------
        object
            ``entry``, or the decorator.

        Raises
        ------
        ValueError
            ``name`` is not a non-empty string, or is already registered.
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"a {self.what} is registered under a non-empty string, got "
                             f"{shorten(name)}")
        if name in self._entries:
            raise ValueError(f"{self.what} {name!r} is already registered")
        if entry is _DECORATE:
            def decorate(obj):
                self.register(name, obj)
                return obj
            return decorate
        self._entries[name] = entry
        logger.debug("registered %s %r", self.what, name)
        return entry

    def unregister(self, name):
        """Remove the entry ``name`` (a plug-in withdrawn, a test's own entry).

        Raises
        ------
        ValueError
            No entry has that name.
        """
        self[name]
        del self._entries[name]

    def __getitem__(self, name):
        """The entry registered as ``name``; ``ValueError`` naming the known names if none."""
        self._load()
        try:
            return self._entries[name]
        except (KeyError, TypeError):  # TypeError: an unhashable name
            raise ValueError(f"unknown {self.what} {shorten(name)}; expected one of "
                             f"{sorted(self._entries)}") from None

    def __contains__(self, name):
        """Whether ``name`` is registered."""
        self._load()
        try:
            return name in self._entries
        except TypeError:
            return False

    def __iter__(self):
        """The names, in the order of registration."""
        self._load()
        return iter(list(self._entries))

    def __len__(self):
        """Number of entries."""
        self._load()
        return len(self._entries)

    def keys(self):
        """The names, in the order of registration."""
        return list(self)

    def values(self):
        """The entries, in the order of registration."""
        self._load()
        return list(self._entries.values())

    def items(self):
        """``(name, entry)`` pairs, in the order of registration."""
        self._load()
        return list(self._entries.items())

    def __repr__(self):
        """The kind of entries and their names."""
        return f"<{type(self).__name__} of {self.what}s: {', '.join(self)}>"
