"""``python -m steady``: the command ``runin-steady`` (:mod:`steady.cli.solve`)."""

import sys

from .cli.solve import main

if __name__ == "__main__":
    sys.exit(main())
