"""Public names of a package imported from their modules on first use (PEP 562).

``import steady`` and ``import transient`` stay quick and light (no h5py,
matplotlib or the numerics until a name is asked for): each package maps
its public names to their modules and takes its module-level
``__getattr__`` and ``__dir__`` from :func:`lazy_names`.
"""

import importlib
import sys

__all__ = ["lazy_names"]


def lazy_names(package, module_of):
    """The ``__getattr__`` and ``__dir__`` of a package whose names load on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    module_of : mapping of str to str or None
        Public name -> the submodule that defines it; None for a name that
        is itself a submodule.

    Returns
    -------
    getattr : callable
        Imports the name's module, keeps the name in the package, returns it.
    dir : callable
        The package's names, the ones not imported yet included.
    """
    namespace = sys.modules[package].__dict__

    def __getattr__(name):
        """A public name, imported from its module on first use."""
        if name not in module_of:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = importlib.import_module(f".{module_of[name] or name}", package)
        value = module if module_of[name] is None else getattr(module, name)
        namespace[name] = value
        return value

    def __dir__():
        """The package's names, the lazily imported ones included."""
        return sorted(set(namespace) | set(module_of))

    return __getattr__, __dir__
