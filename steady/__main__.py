"""``python -m steady``: the command ``runin-steady`` (:mod:`steady.cli.solve`).

Entered through :func:`steady.cli.entry.launch`, which handles Ctrl-C
before the command's heavy imports.
"""

import sys

from .cli.entry import runin_steady

if __name__ == "__main__":
    sys.exit(runin_steady())
