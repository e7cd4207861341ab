"""Entry points of the five commands: Ctrl-C is one line and status 130 from the start.

A command's module imports numpy, scipy, h5py and the library, which takes
up to a second; Ctrl-C during that import used to end in a
``KeyboardInterrupt`` traceback.  The console scripts (``[project.scripts]``
of ``pyproject.toml``) and ``python -m steady``, ``python -m transient``,
``python -m steady.cli.fit``, ``python -m steady.cli.design``,
``python -m steady.cli.examples`` therefore
enter through :func:`launch`, in this module, which imports nothing heavy:
it catches the interrupt around the import of the command and around the
command itself, whose own handling (:func:`steady.cli.common.run_command`)
says what was saved.  Its SIGINT handler also notes the signal, for the
imports that lose the interrupt (numpy's C import turns it into an
``ImportError``; one in a weakref callback cannot be raised at all).

Only the interpreter's own start-up (``site`` and its ``.pth`` files, a
few tens of milliseconds before any of this code runs) is out of reach:
Ctrl-C there is Python's.

This module and the packages' ``__init__`` modules above it must stay light:
``tests/test_interrupts.py`` checks that importing it loads none of numpy,
scipy, h5py or the library's modules.
"""

import signal
import sys

__all__ = ["launch", "runin_design", "runin_examples", "runin_fit", "runin_steady"]

#: :data:`steady.cli.common.EXIT_INTERRUPTED`, not imported from there: that would load
#: argparse, logging and tempfile before the handling is in place.
_EXIT_INTERRUPTED = 130


def launch(module, argv=None):
    """Import a command's module and run its ``main``; Ctrl-C at any moment exits 130.

    Parameters
    ----------
    module : str
        The command's module (``"steady.cli.solve"``...), imported here.
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``: the process's own command, a
        console script or ``python -m``).

    Returns
    -------
    int
        The command's exit status; 130 with one line ``error: interrupted...``
        on stderr when Ctrl-C comes before the command's own handling (then
        nothing was written) or escapes it.  Further Ctrl-C are ignored once
        that line is being printed and, for the process's own command
        (``argv`` None), once the command has returned: the process exits
        with the command's status.
    """
    received = []

    def interrupt(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt

    def unraisable(info):
        # Ctrl-C in a destructor or a weakref callback, where Python cannot raise it: the
        # handler has noted it (received), the import below reports it.
        if not issubclass(info.exc_type, KeyboardInterrupt):
            previous_hook(info)

    previous = signal.signal(signal.SIGINT, interrupt)
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    started = False
    try:
        main = _import_command(module, received)
        started = True
        return main(argv)
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not cut the line
        # Before main() runs nothing was written; once it runs, an interrupt that escapes
        # its own handling (argument parsing, the last lines) has nothing to add.
        where = "" if started else "; nothing was written"
        sys.stderr.write(f"error: interrupted{where}\n")
        return _EXIT_INTERRUPTED
    finally:
        _forget_handled_interrupt()
        # The process's own command is done: a Ctrl-C while the interpreter shuts down
        # would kill it with SIGINT, silently, whatever the command's status.  A caller's
        # handler is put back.
        if argv is None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        else:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
            if sys.unraisablehook is unraisable:  # not replaced by the command
                sys.unraisablehook = previous_hook


def _import_command(module, received):
    """The ``main`` of a command's module; KeyboardInterrupt if Ctrl-C came meanwhile.

    Parameters
    ----------
    module : str
    received : list
        Grows when SIGINT arrives (the handler of :func:`launch`).
    """
    from importlib import import_module

    try:
        main = import_module(module).main
    except Exception:
        if received:  # numpy's C import turns an interrupt into an ImportError
            raise KeyboardInterrupt from None
        raise
    if received:  # an import caught the interrupt and carried on
        raise KeyboardInterrupt
    return main


def _forget_handled_interrupt():
    """Clear CPython's mark of an interrupt that left code run from a string.

    When a KeyboardInterrupt leaves code that CPython runs from a string
    (``exec`` of a string, which dataclasses, namedtuple and scipy do while
    they are imported), it marks the interrupt as unhandled; under ``python
    -m`` the interpreter then kills itself with SIGINT at exit (status -2
    instead of the command's 130, or its 0), even though the interrupt was
    caught and reported.  Running a string resets the mark.
    """
    exec("pass")  # a constant string: resets the mark, nothing else


def runin_steady(argv=None):
    """``runin-steady`` (:mod:`steady.cli.solve`)."""
    return launch("steady.cli.solve", argv)


def runin_fit(argv=None):
    """``runin-fit`` (:mod:`steady.cli.fit`)."""
    return launch("steady.cli.fit", argv)


def runin_design(argv=None):
    """``runin-design`` (:mod:`steady.cli.design`)."""
    return launch("steady.cli.design", argv)


def runin_examples(argv=None):
    """``runin-examples`` (:mod:`steady.cli.examples`)."""
    return launch("steady.cli.examples", argv)
