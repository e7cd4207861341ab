"""The version of the installed distribution ``runin``.

Read from the installed package's metadata (:mod:`importlib.metadata`), so
that it is written once, in ``pyproject.toml``.  Code run from a source tree
that was never installed has no metadata: its version is ``"0+unknown"``.

Examples
--------
>>> import steady, transient
>>> steady.__version__ == transient.__version__ == __version__
True
"""

from importlib import metadata

__all__ = ["DISTRIBUTION", "__version__"]

#: The distribution's name, as ``pip install`` knows it.
DISTRIBUTION = "runin"

try:
    __version__ = metadata.version(DISTRIBUTION)
except metadata.PackageNotFoundError:  # a source tree, not installed
    __version__ = "0+unknown"
