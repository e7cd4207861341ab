"""What the command lines of the package share.

Each command (``runin-steady``, ``runin-transient``, ``runin-design``) runs
either as an installed console script or as a module (``python -m steady``
...); its usage line names it the way it was run (:func:`program_name`).

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

:func:`run_command` turns exceptions into these lines and statuses;
:class:`ArgumentParser` reports argument errors the same way.  Values
echoed in messages are shortened (:func:`shorten`), so that a hostile input
(a 50 MB string, a list of millions of numbers, an array nested 100,000
deep) gives a short line.

Outputs and memory
------------------
:func:`prepare_output` checks an output path before the work starts (not a
directory, not a device, not existing without ``--force``, in a writable
directory, which it creates if missing); :func:`check_distinct` refuses an
output that names an input or another output.  :func:`steady_memory`
estimates the peak memory of a steady solve from the arrays it allocates;
:func:`check_memory` compares an estimate with the memory the machine has
available (:func:`available_memory`) or with the limit given by
``--memory-limit`` (:func:`add_memory_limit`), and refuses a scene that
does not fit.
"""

from __future__ import annotations

import argparse
import ctypes
import logging
import math
import os
import pathlib
import platform
import stat
import sys
import tempfile

import scipy.fft

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_FAILED",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "ArgumentParser",
    "CommandError",
    "add_memory_limit",
    "available_memory",
    "check_distinct",
    "check_memory",
    "configure_logging",
    "describe_os_error",
    "format_bytes",
    "halfspace_memory",
    "one_line",
    "prepare_output",
    "product_memory",
    "program_name",
    "run_command",
    "shorten",
    "slope_estimator_memory",
    "steady_memory",
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

# Longest error line, characters: a safety net behind shorten().
_MAX_LINE = 500


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


# -- messages -----------------------------------------------------------
def _short(value, limit, depth):
    """``repr`` of ``value`` in about ``limit`` characters; never the whole of a huge value."""
    if depth > 6:
        return "..."
    if isinstance(value, (str, bytes)):
        if len(value) <= limit:
            return repr(value)
        unit = "characters" if isinstance(value, str) else "bytes"
        return f"{value[:limit]!r}... ({len(value)} {unit})"
    if isinstance(value, (list, tuple, dict)):
        if isinstance(value, dict):
            opening, closing, noun, items = "{", "}", "keys", value.items()
        elif isinstance(value, tuple):
            opening, closing, noun, items = "(", ")", "items", value
        else:
            opening, closing, noun, items = "[", "]", "items", value
        parts, length = [], 0
        for count, item in enumerate(items):
            if length > limit:
                return (f"{opening}{', '.join(parts)}, ...{closing} "
                        f"({len(value)} {noun}, {len(value) - count} not shown)")
            if isinstance(value, dict):
                text = f"{_short(item[0], limit, depth + 1)}: {_short(item[1], limit, depth + 1)}"
            else:
                text = _short(item, limit, depth + 1)
            parts.append(text)
            length += len(text) + 2
        if len(value) == 1 and isinstance(value, tuple):
            return f"({parts[0]},)"
        return f"{opening}{', '.join(parts)}{closing}"
    try:
        text = repr(value)
    except RecursionError:
        return f"<{type(value).__name__} nested too deeply to show>"
    if len(text) > limit:
        return f"{text[:limit]}... ({len(text)} characters)"
    return text


def shorten(value, limit=80):
    """``repr`` of a value for a message, at most about ``limit`` characters.

    Parameters
    ----------
    value : object
        A value read from the user's input.
    limit : int, optional
        Characters of the value to show (default 80).

    Returns
    -------
    str
        ``repr(value)`` when it is short; otherwise its beginning and what
        was left out.  Only the part shown is ever formatted, so a list of
        millions of numbers or an array nested 100,000 deep costs nothing.

    Examples
    --------
    >>> shorten([1.0, 2.0])
    '[1.0, 2.0]'
    >>> shorten([1e-9] * 7_000_000, limit=20)
    '[1e-09, 1e-09, 1e-09, ...] (7000000 items, 6999997 not shown)'
    >>> shorten("x" * 50_000_000, limit=10)
    "'xxxxxxxxxx'... (50000000 characters)"
    """
    return _short(value, int(limit), 0)


def one_line(text, limit=_MAX_LINE):
    """A message as one line of at most about ``limit`` characters.

    Parameters
    ----------
    text : str
    limit : int, optional
        Characters kept (default 500).

    Returns
    -------
    str

    Examples
    --------
    >>> one_line(ValueError("two" + chr(10) + "lines"))
    'two lines'
    """
    text = " ".join(str(text).split("\n"))
    if len(text) > limit:
        return f"{text[:limit]}... (message of {len(text)} characters shortened)"
    return text


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


def describe_os_error(err):
    """One line for an :class:`OSError`: the file it names and the reason."""
    reason = err.strerror or str(err)
    if err.filename is not None:
        return f"{str(err.filename)!r}: {reason}"
    return reason


class ArgumentParser(argparse.ArgumentParser):
    """:class:`argparse.ArgumentParser` whose errors are one line, exit status 2.

    ``error: <what is wrong> (see '<prog> --help')`` on stderr.
    """

    def error(self, message):
        """Print one ``error:`` line and exit with :data:`EXIT_BAD_INPUT`."""
        self.exit(EXIT_BAD_INPUT,
                  f"error: {one_line(message)} (see '{self.prog} --help')\n")


def configure_logging(verbose):
    """Log to stderr: errors only by default, progress with ``-v``, details with ``-vv``.

    Python warnings (e.g. numpy's overflow warnings on a hostile input,
    which the solvers detect and report themselves) and exceptions Python
    can only ignore (in destructors) go to the log too, so that by default
    a failure is the command's one ``error:`` line.

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


def keep_freed_memory():
    """Let the C allocator keep large freed blocks for reuse (glibc only; the command lines).

    glibc maps every block above its mmap threshold (32 MiB at most) afresh
    and unmaps it when freed, and trims its heap whenever twice the
    threshold is free at its top: an array of a large grid allocated once per iteration
    (an FFT spectrum, a product) is then faulted in page by page every time.
    This sets ``M_MMAP_MAX = 0`` (blocks come from the heap) and a trim
    threshold of 2 GiB (freed memory stays for the next array).  The peak
    memory is that of the largest set of arrays alive at once, as before;
    freed memory is returned at exit.  Process-wide, so called by the
    command lines only, not on import.  Elsewhere (another C library) it
    does nothing.

    Returns
    -------
    bool
        True if the allocator took the settings.
    """
    if not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc":
        return False
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return False
    m_trim_threshold, m_mmap_max = -1, -4  # <malloc.h>
    return bool(libc.mallopt(m_mmap_max, 0)) and bool(libc.mallopt(m_trim_threshold, 2**31 - 1))


def _log_unraisable(unraisable):
    logger.debug("ignored in %r: %s: %s", unraisable.object,
                 type(unraisable.exc_value).__name__, unraisable.exc_value)


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
        key = pathlib.Path(path).resolve()
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


# -- memory -------------------------------------------------------------
_GIB = 2 ** 30
_FLOAT = 8  # bytes of a float64
#: Allocator overhead and short-lived copies the inventories below do not list.
_MARGIN = 1.25
#: Allocations that do not grow with the grid (FFT plans, HDF5 buffers), bytes.
_BASE = 16 * 2 ** 20


def format_bytes(value):
    """Bytes as ``'1.5 GiB'``, ``'20 MiB'`` or ``'512 bytes'``.

    Examples
    --------
    >>> format_bytes(3 * 2**30 // 2), format_bytes(20 * 2**20), format_bytes(512)
    ('1.5 GiB', '20 MiB', '512 bytes')
    """
    if value >= 100 * _GIB:
        return f"{value / _GIB:.0f} GiB"
    if value >= _GIB:
        return f"{value / _GIB:.3g} GiB"
    if value >= 2 ** 20:
        return f"{value / 2 ** 20:.3g} MiB"
    return f"{int(value)} bytes"


def available_memory():
    """Memory available to a new computation, bytes, or None if unknown.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux: free memory plus the
    caches the kernel can drop), else the free physical pages of
    :func:`os.sysconf`.
    """
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


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


def check_memory(needed, what, limit_gib=None):
    """Refuse a computation whose memory estimate exceeds what may be used.

    Parameters
    ----------
    needed : int
        Estimated peak, bytes (e.g. :func:`steady_memory`).
    what : str
        The computation, for the message (``"a steady solve at n = 4096"``).
    limit_gib : float, optional
        ``--memory-limit``, GiB (``inf``: no check).  Default: the
        available memory (:func:`available_memory`); no check if unknown.

    Raises
    ------
    ValueError
        ``needed`` exceeds the limit; the message gives both numbers and
        names ``--memory-limit``.
    """
    if limit_gib is None:
        limit = available_memory()
        if limit is None:
            return
        source = "are available"
    elif math.isinf(limit_gib):
        return
    else:
        limit = limit_gib * _GIB
        source = "may be used (--memory-limit)"
    if needed > limit:
        raise ValueError(f"{what} needs about {format_bytes(needed)} of memory; "
                         f"{format_bytes(limit)} {source} (a larger --memory-limit GIB "
                         f"overrides this check)")


def halfspace_memory(n, *, gradient=False):
    """Bytes held by a :class:`steady.halfspace.HalfSpace` of grid ``n``.

    Parameters
    ----------
    n : int
        Pixels across the grid.
    gradient : bool, optional
        Include the two gradient spectra, built on the first slope
        (default False).

    Returns
    -------
    int
        The influence spectrum (real, ``2n x (n+1)``), the zero-padded
        buffer (``2n x 2n``), the complex work buffer (``2n x (n+1)``), the
        corner lattice and influence quadrant (``(n+2)^2`` each), and with
        ``gradient`` the two gradient spectra (real, ``2n x (n+1)`` each):
        96 bytes per pixel, 128 with the gradient.
    """
    spectrum = 2 * n * (n + 1) * _FLOAT
    total = spectrum + (2 * n) ** 2 * _FLOAT + 2 * spectrum + 2 * (n + 2) ** 2 * _FLOAT
    if gradient:
        total += 2 * spectrum
    return total


def product_memory(n):
    """Bytes of the short-lived transforms of one half-space product of grid ``n``.

    The padded spectrum of the pressure and ``i`` times it for the gradient
    (complex ``2n x (n+1)`` each), the column pass of the inverse (complex
    ``2n x (n+1)``; only ``n`` rows are kept but the whole array stays
    alive) and the row pass (real ``n x 2n``): 112 bytes per pixel.
    """
    spectrum = 2 * n * (n + 1) * 2 * _FLOAT
    return 3 * spectrum + n * 2 * n * _FLOAT


def slope_estimator_memory(n):
    """Bytes of the energy-corrected slope estimator of grid ``n``: kept, and while applied.

    :class:`steady.accuracy.SlopeEnergy` convolves on a fine box of FFT
    size ``S`` (about ``2.2 n``) and a coarse one of size ``S_c`` (about
    ``1.2 n``), the same arithmetic as its constructor with the default
    margin ``max(8, n // 16)``, coarsening 8 and far radius 8.

    Returns
    -------
    kept : int
        Two gradient spectra on the fine box and five on the coarse one
        (the gradient's and the three second derivatives' that carry the
        blocks' first moments), complex ``S x (S/2+1)``:
        ``16 S^2 + 40 S_c^2`` bytes, about 130 per pixel.
    applied : int
        The transforms of one application on the fine box (source
        spectrum, product, column and row passes): ``32 S^2`` bytes, about
        150 per pixel.
    """
    c = 8
    margin = c * -(-max(8, n // 16) // c)
    fine = c * -(-(n + 2 * margin) // c)
    nc = fine // c
    extra = max(1, math.ceil((8.0 * n / 2 - fine / 2) / c))
    coarse_out = nc + 2 * extra
    size = scipy.fft.next_fast_len(n + fine - 1, real=True)
    coarse = scipy.fft.next_fast_len(nc + coarse_out - 1, real=True)
    return 16 * size ** 2 + 40 * coarse ** 2, 32 * size ** 2


def steady_memory(n, *, slope_error=True):
    """Estimated peak memory of a steady solve at grid ``n``, bytes.

    Counted from the arrays :func:`steady.solution.solve_scene` allocates:

    - the half-space operator with its gradient spectra
      (:func:`halfspace_memory`, 128 bytes per pixel);
    - the solution: labels, pressure, face, slope and the two gradient
      components (the face and the components are views of ``n x 2n``
      arrays): 64 bytes per pixel;
    - without ``slope_error``: the transforms of the products
      (:func:`product_memory`, 112 bytes per pixel);
    - with ``slope_error`` (the default of the command): the labels and
      pressure of the finest grid of the ladder (17 bytes per pixel) and
      the slope estimator of :mod:`steady.accuracy`, kept and applied
      (:func:`slope_estimator_memory`, about 250 bytes per pixel), the
      peak.

    The sum is multiplied by 1.25 (allocator overhead, short-lived copies
    not listed) and 16 MiB are added for what does not grow with ``n``.
    Measured against the peak resident memory of a steady solve (from
    ``resource.getrusage``), the estimate is an upper bound by a factor of
    1.7 at ``n = 256`` (where the constant dominates), 1.46 at 512, 1.42 at
    1024 and 1.39 at 2048 (``tests/test_memory.py``).

    Parameters
    ----------
    n : int or (int, int)
        Pixels across a square grid, or ``(nx, ny)``: a rectangular grid
        is counted as the square of the same number of pixels (the arrays
        scale with ``nx ny``; the margins of the slope estimator, a few per
        cent, with the sides).
    slope_error : bool, optional
        Whether the corrected rms slope and its error bar are computed
        (default True).

    Returns
    -------
    int

    Examples
    --------
    >>> print(format_bytes(steady_memory(1024)), format_bytes(steady_memory(12000)))
    620 MiB 80.6 GiB
    """
    n = int(n) if not isinstance(n, (tuple, list)) else math.ceil(math.sqrt(n[0] * n[1]))
    peak = halfspace_memory(n, gradient=True) + 8 * n * n * _FLOAT
    if slope_error:
        peak += 17 * n * n + sum(slope_estimator_memory(n))
    else:
        peak += product_memory(n)
    return int(_MARGIN * peak) + _BASE
