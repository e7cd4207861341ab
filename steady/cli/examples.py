"""The command ``runin-examples``: list the shipped example scenes, copy one.

Usage (``runin-examples`` once installed, or ``python -m steady.cli.examples``)::

    runin-examples                                # names and one-line descriptions
    runin-examples voronoi_transient -o example   # the scene and its map files
    runin-transient example/voronoi_transient.toml -o run.h5

The scenes are the package's (:mod:`steady.examples`); a copy is the user's
to edit.  Existing files are not replaced without ``--force``.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m steady.cli.examples: Ctrl-C handled from here on
    from .entry import runin_examples

    raise SystemExit(runin_examples())

from .. import examples
from .common import EXIT_STATUS_EPILOG, ArgumentParser, program_name, run_command

__all__ = ["main"]


def main(argv=None):
    """The command ``runin-examples``: list the example scenes, or copy one.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0; 2 for an unknown name or a file that exists
        (without ``--force``), nothing written; 1 when the operating system
        refuses a write; 130 when interrupted.
    """
    parser = ArgumentParser(
        prog=program_name("python -m steady.cli.examples"),
        description="List the example scenes shipped with runin, or copy one (the scene file "
                    "and the map files it names) into a directory.",
        epilog=EXIT_STATUS_EPILOG)
    parser.add_argument("name", nargs="?", help="example to copy (without: list them)")
    parser.add_argument("-o", "--output", default=None, metavar="DIR",
                        help="directory to copy into, created if missing (default: the "
                             "current directory)")
    parser.add_argument("--force", action="store_true", help="overwrite existing files")
    return run_command(_run, parser.parse_args(argv))


def _run(args):
    """List the examples or copy one, for parsed arguments; return the exit status."""
    if args.name is None:
        if args.output is not None or args.force:
            raise ValueError("-o and --force copy an example: name one (runin-examples NAME "
                             "-o DIR); without a name runin-examples lists them")
        listed = examples.list_examples()
        width = max(map(len, listed))
        for name, description in listed.items():
            print(f"{name:<{width}}  {description}")
        return 0
    for written in examples.copy(args.name, args.output or ".", force=args.force):
        print(written)
    return 0
