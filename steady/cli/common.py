"""What the command lines of both packages share.

Each command (``runin-steady``, ``runin-transient``, ``runin-fit``,
``runin-design``, ``runin-examples``) runs either as an installed console script or as a module
(``python -m steady`` ...); its usage line names it the way it was run
(:func:`program_name`).

Errors and exit statuses
------------------------
A command that cannot do what it was asked ends with one line
``error: ...`` on stderr, never a traceback, and one of these statuses:

=====  ==============================================================
0      success
1      a run stopped or failed (it can be resumed), or the operating
       system refused a read or a write (the message says what is saved)
2      bad input: arguments, scene, input files, an output that may not
       be overwritten; refused before any work, nothing written
130    interrupted (Ctrl-C)
=====  ==============================================================

Every command's ``--help`` ends with this table (:data:`EXIT_STATUS_EPILOG`).
:func:`run_command` turns exceptions into these lines and statuses; a
missing input file, :class:`FileNotFoundError` from the library's readers,
is bad input when a command reads it through :func:`read_input`;
:class:`ArgumentParser` reports argument errors the same way, a null byte
in an argument included.  Values echoed in messages are shortened
(:func:`steady.text.shorten`).  Ctrl-C before the command's own handling
is in place, while numpy, scipy and h5py load, is handled by the entry
points (:mod:`steady.cli.entry`).

Outputs and memory
------------------
:func:`prepare_output` checks an output path before the work starts (not a
directory, not a device, not existing without ``--force``, in a writable
directory, which it creates if missing); :func:`check_distinct` refuses an
output that names an input or another output; :func:`check_figure_path`
refuses a figure name that is not a ``.png``.  ``--memory-limit``
(:func:`add_memory_limit`) is the limit :func:`steady.memory.check_memory`
compares a command's memory estimate with.
"""

from __future__ import annotations

import _thread
import argparse
import functools
import logging
import os
import pathlib
import re
import stat
import sys
import tempfile
import warnings

from ..text import one_line, shorten
from ..validity import ValidityWarning

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_FAILED",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_STATUS_EPILOG",
    "ArgumentParser",
    "CommandError",
    "add_grid_flag",
    "FIGURE_SUFFIXES",
    "add_memory_limit",
    "check_distinct",
    "check_figure_path",
    "configure_logging",
    "describe_os_error",
    "key_type",
    "note",
    "prepare_output",
    "program_name",
    "read_input",
    "run_command",
]

logger = logging.getLogger(__name__)

#: Exit status of a command that did what it was asked.
EXIT_OK = 0
#: A run stopped or failed (resumable), or the operating system refused a read or write.
EXIT_FAILED = 1
#: Bad input: refused before any work.
EXIT_BAD_INPUT = 2
#: Interrupted (128 + SIGINT, the shell's convention).
EXIT_INTERRUPTED = 130

#: The end of every command's ``--help``: the table of exit statuses.
EXIT_STATUS_EPILOG = ("exit status: 0 done; 1 a run stopped or failed (it can be resumed), a fit "
                      "failed (its file is written, the reason on stderr) or the operating "
                      "system refused a read or a write (the message says what is saved); 2 bad "
                      "input or refused, nothing written; 130 interrupted")


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


class CommandError(Exception):
    """A failure that a command reports with its own message and exit status.

    Parameters
    ----------
    message : str
        The text after ``error:``.
    status : int, optional
        Exit status (default :data:`EXIT_FAILED`).
    """

    def __init__(self, message, status=EXIT_FAILED):
        super().__init__(message)
        self.status = status


def note(text):
    """Print ``note: text`` on stderr: what the user should know, not an error."""
    print(f"note: {text}", file=sys.stderr)


def read_input(read, *args, **kwargs):
    """``read(*args, **kwargs)`` for a command: a missing input file is bad input (exit 2).

    The library's readers raise :class:`FileNotFoundError` for a file the
    caller names that does not exist, as Python's own do; to a command that
    is bad input like any other, refused before the work (exit status 2),
    not a refusal of the operating system (:class:`OSError`, status 1).

    Parameters
    ----------
    read : callable
        A reader of input files (:func:`steady.scene.load_scene`, ...).
    *args, **kwargs
        Its arguments.

    Returns
    -------
    object
        What ``read`` returns.

    Raises
    ------
    ValueError
        The file does not exist (the reader's message).
    """
    try:
        return read(*args, **kwargs)
    except FileNotFoundError as err:
        raise ValueError(str(err)) from None


def describe_os_error(err):
    """One line for an :class:`OSError`: the file it names and the reason."""
    reason = err.strerror or str(err)
    if err.filename is not None:
        return f"{str(err.filename)!r}: {reason}"
    return reason


#: Digits, with single underscores between them, as Python's ``float`` reads them.
_DIGITS = r"\d(?:_?\d)*"
#: A negative number as ``float`` reads it (``-1``, ``-.5``, ``-1e-4``, ``-1_000``,
#: ``-inf``, ``-nan``): an argument of the command lines, never an option.
_NEGATIVE_NUMBER = re.compile(rf"^-(?:(?:{_DIGITS}(?:\.(?:{_DIGITS})?)?|\.{_DIGITS})"
                             rf"(?:[eE][-+]?{_DIGITS})?|inf|infinity|nan)$", re.IGNORECASE)


class ArgumentParser(argparse.ArgumentParser):
    """:class:`argparse.ArgumentParser` whose errors are one line, exit status 2.

    ``error: <what is wrong> (see '<prog> --help')`` on stderr.  An argument
    with a null byte (which no path may hold; only a caller of ``main(argv)``
    can pass one) is such an error, naming the argument, before the
    operating system sees it.  Every command built on it has ``--version``:
    ``<prog> (runin <version>)``, the installed distribution's version
    (:mod:`steady.version`).
    """

    def __init__(self, *args, **kwargs):
        from ..version import DISTRIBUTION, __version__

        super().__init__(*args, **kwargs)
        # argparse takes an argument for a value, not an option, if it looks like a
        # negative number; its pattern misses the exponent form and the special values
        # ('-1e-4', '-inf'), which a number flag would then report as missing its value
        # rather than refuse as out of range.
        self._negative_number_matcher = _NEGATIVE_NUMBER
        self.add_argument("--version", action="version",
                          version=f"%(prog)s ({DISTRIBUTION} {__version__})")

    def error(self, message):
        """Print one ``error:`` line and exit with :data:`EXIT_BAD_INPUT`."""
        self.exit(EXIT_BAD_INPUT,
                  f"error: {one_line(message)} (see '{self.prog} --help')\n")

    def parse_known_args(self, args=None, namespace=None):
        """Parse as argparse does, then refuse a value with a null byte, naming its argument."""
        parsed, extras = super().parse_known_args(args, namespace)
        for action in self._actions:
            value = getattr(parsed, action.dest, None)
            for item in value if isinstance(value, (list, tuple)) else [value]:
                if isinstance(item, (str, os.PathLike)) and "\0" in os.fspath(item):
                    name = "/".join(action.option_strings) or action.metavar or action.dest
                    self.error(f"argument {name}: {shorten(os.fspath(item))} holds a null "
                               f"byte, which no file name may hold")
        return parsed, extras


def configure_logging(verbose):
    """Log to stderr: errors only by default, progress with ``-v``, details with ``-vv``.

    Python warnings (e.g. numpy's overflow warnings on a hostile input,
    which the solvers detect and report themselves) and exceptions Python
    can only ignore (in destructors) go to the log too, so that by default
    a failure is the command's one ``error:`` line; a Ctrl-C that landed
    there is delivered again to the command.

    Parameters
    ----------
    verbose : int
        How many ``-v`` were given.
    """
    level = (logging.ERROR, logging.INFO, logging.DEBUG)[min(int(verbose), 2)]
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    logging.captureWarnings(True)
    # Errors Python cannot raise (in destructors) would print tracebacks beside
    # the command's error line.
    sys.unraisablehook = _log_unraisable


def _log_unraisable(unraisable):
    if issubclass(unraisable.exc_type, KeyboardInterrupt):
        # Ctrl-C landed where Python cannot raise it (a destructor, a weakref callback):
        # deliver it again, to the command's own flow.
        _thread.interrupt_main()
        return
    logger.debug("ignored in %r: %s: %s", unraisable.object,
                 type(unraisable.exc_value).__name__, unraisable.exc_value)


def _show_warning(default, message, category, *args, **kwargs):
    """Print a :class:`ValidityWarning` as one line ``warning: ...``; others as Python does."""
    if issubclass(category, ValidityWarning):
        print(f"warning: {one_line(str(message))}", file=sys.stderr)
    else:
        default(message, category, *args, **kwargs)


def run_command(work, args, *, verbose=0):
    """Run a command's work and turn every failure into one line and an exit status.

    Parameters
    ----------
    work : callable
        ``work(args)`` does the work and returns the exit status.
    args : argparse.Namespace
        Parsed arguments.
    verbose : int, optional
        With 2 or more (``-vv``) an unexpected exception is also logged with
        its traceback.

    Returns
    -------
    int
        The status of ``work``, or: :class:`CommandError` its own;
        :class:`ValueError` (bad input) and :class:`RecursionError` (input
        nested too deeply) 2; :class:`OSError` and :class:`MemoryError` 1;
        :class:`KeyboardInterrupt` 130; a closed stdout (``| head``) 0;
        anything else 1, with the exception's type named.
    """
    try:
        with warnings.catch_warnings():
            # A problem outside the model's range is answered, with one line.
            warnings.simplefilter("always", ValidityWarning)
            warnings.showwarning = functools.partial(_show_warning, warnings.showwarning)
            return work(args)
    except CommandError as err:
        message, status = str(err), err.status
    except ValueError as err:
        message, status = str(err), EXIT_BAD_INPUT
    except RecursionError:
        message, status = "input nested too deeply to read", EXIT_BAD_INPUT
    except BrokenPipeError:
        # The reader of stdout went away (e.g. `| head`): nothing left to say.
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 -- stays open until exit
        return EXIT_OK
    except OSError as err:
        message, status = describe_os_error(err), EXIT_FAILED
    except MemoryError:
        message = ("out of memory; the estimate of the memory needed was too low "
                   "(a smaller --memory-limit refuses such scenes before they start)")
        status = EXIT_FAILED
    except KeyboardInterrupt:
        message, status = "interrupted", EXIT_INTERRUPTED
    except Exception as err:  # noqa: BLE001 -- the last line of defence: no traceback
        logger.debug("unexpected error", exc_info=True)
        hint = "" if verbose >= 2 else " (run with -vv for the traceback)"
        message, status = f"unexpected {type(err).__name__}: {err}{hint}", EXIT_FAILED
    print(f"error: {one_line(message)}", file=sys.stderr)
    return status


# -- outputs ------------------------------------------------------------
def check_distinct(named):
    """Refuse two paths that name the same file (an output over an input, say).

    Parameters
    ----------
    named : sequence of (str, path-like or None)
        How messages name each path (``"-o"``, ``"the scene"``...) and the
        path; None entries are skipped.

    Raises
    ------
    ValueError
        Two of them resolve to the same file; the message names both.

    Examples
    --------
    >>> try:
    ...     check_distinct([("the scene", "s.toml"), ("-o", "out.h5"), ("--plot", "./s.toml")])
    ... except ValueError as err:
    ...     print(err)
    --plot and the scene name the same file './s.toml'
    """
    seen = {}
    for what, path in named:
        if path is None:
            continue
        # Not Path.resolve: before Python 3.13 it raises RuntimeError on a loop of
        # symbolic links, which realpath leaves unresolved for the reader or writer
        # of the file to refuse, naming it.
        key = os.path.realpath(path)
        if key in seen:
            raise ValueError(f"{what} and {seen[key]} name the same file {str(path)!r}")
        seen[key] = what


def prepare_output(path, *, force, what="output"):
    """Check an output path before the work starts; create its directory.

    Parameters
    ----------
    path : str or path-like
        The file the command will write.
    force : bool
        Whether an existing file may be replaced.
    what : str, optional
        How messages name it (default ``"output"``; e.g. ``"--plot"``).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``path`` is a directory or not a regular file (a device, a pipe),
        exists and ``force`` is False, or lies below a file; or its
        directory cannot be created or written (the message names it and
        the reason).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> where = pathlib.Path(tempfile.mkdtemp())
    >>> prepare_output(where / "new" / "out.h5", force=False).parent.is_dir()
    True
    >>> try:
    ...     prepare_output(where / "new", force=True)
    ... except ValueError as err:
    ...     print(str(err).replace(str(where), "DIR"))
    output 'DIR/new' is a directory
    """
    path = pathlib.Path(path)
    try:
        mode = path.stat().st_mode
    except (FileNotFoundError, NotADirectoryError):  # the latter: a file on the way
        mode = None
    except OSError as err:
        raise ValueError(f"{what} {str(path)!r}: {err.strerror or err}") from None
    if mode is not None:
        if stat.S_ISDIR(mode):
            raise ValueError(f"{what} {str(path)!r} is a directory")
        if not stat.S_ISREG(mode):
            raise ValueError(f"{what} {str(path)!r} is not a regular file")
        if not force:
            raise ValueError(f"{what} {str(path)!r} exists (use --force to overwrite)")
    parent = path.parent
    # The nearest existing ancestor must be a directory: mkdir would say "File exists".
    ancestor = parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise ValueError(f"{what} {str(path)!r}: {str(ancestor)!r} is a file, not a directory")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        # Writable?  (Permission bits say nothing for root or a read-only mount.)
        with tempfile.TemporaryFile(dir=parent, prefix=f".{path.name}.", suffix=".probe"):
            pass
    except OSError as err:
        raise ValueError(f"{what} {str(path)!r}: cannot write into {str(parent)!r}: "
                         f"{err.strerror or err}") from None
    return path


#: Suffixes of the figure files the commands write: a PNG image, or vector PDF or SVG for papers.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def check_figure_path(path, what="--plot"):
    """Refuse a figure file name whose suffix is not a figure format, before any work.

    The figures are PNG images or vector PDF or SVG files
    (:data:`FIGURE_SUFFIXES`, matplotlib's format follows the suffix);
    another suffix would be refused (``.txt``) or give another format
    (``.jpg``) only once the figure is drawn, after the work, and no
    suffix would write ``NAME.png`` beside the name checked.

    Parameters
    ----------
    path : str or path-like
        The figure's file.
    what : str, optional
        How messages name it (default ``"--plot"``).

    Raises
    ------
    ValueError
        The suffix is not one of :data:`FIGURE_SUFFIXES` (in any case); the
        message names it.

    Examples
    --------
    >>> check_figure_path("out/run.PNG"), check_figure_path("paper/run.pdf")
    (None, None)
    >>> try:
    ...     check_figure_path("out/run.txt")
    ... except ValueError as err:
    ...     print(err)
    --plot 'out/run.txt': expected the suffix .png, .pdf or .svg, got '.txt'
    """
    suffix = pathlib.PurePath(os.fspath(path)).suffix
    if suffix.lower() not in FIGURE_SUFFIXES:
        got = shorten(suffix) if suffix else "none"
        raise ValueError(f"{what} {shorten(str(path))}: expected the suffix .png, .pdf or .svg, "
                         f"got {got}")


def key_type(key):
    """The argparse type of a flag checked by a scene key (:meth:`steady.schema.Key.parse_text`).

    Parameters
    ----------
    key : steady.schema.Key

    Returns
    -------
    callable
        ``text -> value``; a bad value is one line naming the flag (argparse
        adds it), the value and what was expected.

    Examples
    --------
    >>> from steady.schema import Key
    >>> key_type(Key("margin", "number", unit="m", low=0.0, low_open=False))("2e-3")
    0.002
    """
    def parse(text):
        try:
            return key.parse_text(text)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None
    return parse


def add_grid_flag(parser):
    """Add ``--n N`` to an argument parser (dest ``n``): the grid instead of the scene's.

    Checked as the scene's ``[grid] n`` is (:data:`steady.scene.GRID_N`), at
    parse time.
    """
    from ..scene import GRID_N

    def grid(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= 2, got "
                                             f"{shorten(text)}") from None
        try:
            return GRID_N.parse(value, "")
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    parser.add_argument("--n", type=grid, metavar="N",
                        help="the grid: pixels along the longer side of the face's bounding "
                             "box, instead of the scene's [grid] n (the output file records "
                             "the grid it ran on)")


def add_memory_limit(parser):
    """Add ``--memory-limit GIB`` to an argument parser (dest ``memory_limit``)."""
    def gib(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a size in GiB, got "
                                             f"{shorten(text)}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"expected a positive size in GiB, got "
                                             f"{shorten(text)}")
        return value

    parser.add_argument("--memory-limit", type=gib, metavar="GIB",
                        help="memory the command may use, GiB (default: what the machine has "
                             "available; 'inf' skips the check); a scene whose estimated "
                             "peak memory exceeds it is refused before it starts")
