"""What the command lines of the package share: the program name as typed.

Each command runs either as an installed console script (``runin-steady``,
``runin-design``) or as a module (``python -m steady``,
``python -m steady.design``); its usage line names it the way it was run.
"""

from __future__ import annotations

import os
import sys

__all__ = ["program_name"]


def program_name(module_command):
    """Name of the running command, for the ``prog`` of its argument parser.

    Parameters
    ----------
    module_command : str
        How the command is run as a module, e.g. ``"python -m steady"``.

    Returns
    -------
    str
        The console script's name (``runin-steady``) when run as one, else
        ``module_command``: under ``python -m`` the interpreter reports the
        module's file (``__main__.py``, ``design.py``), which is not what
        the user typed.

    Examples
    --------
    >>> import sys
    >>> argv0 = sys.argv[0]
    >>> sys.argv[0] = "/usr/local/bin/runin-steady"
    >>> program_name("python -m steady")
    'runin-steady'
    >>> sys.argv[0] = "/site-packages/steady/__main__.py"
    >>> program_name("python -m steady")
    'python -m steady'
    >>> sys.argv[0] = argv0
    """
    name = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else ""
    if not name or name.endswith(".py") or name == "-c":
        return module_command
    return name
