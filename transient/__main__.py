"""``python -m transient`` and the console script ``runin-transient`` (:mod:`transient.cli.runin`).

:func:`main` enters through :func:`steady.cli.entry.launch`, which handles
Ctrl-C before the command's heavy imports (this module imports nothing
heavy: ``transient/__init__.py`` imports its names on first use).
"""

import sys

from steady.cli.entry import launch

__all__ = ["main"]


def main(argv=None):
    """Entry point of ``runin-transient``: :func:`transient.cli.runin.main`.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status (:func:`transient.cli.runin.main`).
    """
    return launch("transient.cli.runin", argv)


if __name__ == "__main__":
    sys.exit(main())
