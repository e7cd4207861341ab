"""``python -m transient``: the command ``runin-transient`` (:mod:`transient.cli.runin`)."""

import sys

from .cli.runin import main

if __name__ == "__main__":
    sys.exit(main())
