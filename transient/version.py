"""The version of the installed distribution ``runin``: :data:`steady.version.__version__`."""

from steady.version import __version__

__all__ = ["__version__"]
