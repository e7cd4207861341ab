"""Directives of the runin documentation: scene-key tables and command outputs.

``scene-keys``
    The keys of one scene table, drawn from their declarations
    (:mod:`scene_tables`): one table per kind for the tables that name a
    kind, one table of keys for the others.  In a page::

        ```{scene-keys} phases.map
        ```

``command-output``
    Runs the commands of its body, one a line, in a new empty directory,
    each as its console script is installed (``[project.scripts]`` of
    ``pyproject.toml``, under its own name) with the source tree first on
    ``PYTHONPATH`` and a terminal 100 columns wide, and shows each command
    and what it printed (stdout, then stderr).  ``NAME --help`` shows the
    options of the command's argument parser, so that the reference of the
    command line is the parser's own.  A line
    may end with ``# exit N``: the command must end with status ``N``
    (default 0), else the build fails.  So the outputs the pages quote are
    the ones the code prints when the documentation is built::

        ```{command-output}
        runin-examples voronoi_transient -o example
        runin-transient example/voronoi_transient.toml -o run.h5
        ```
"""

from __future__ import annotations

import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from docutils import nodes
from docutils.parsers.rst import Directive
from scene_tables import COLUMNS, TABLES, tables

#: The source tree: its commands are the ones run.
ROOT = pathlib.Path(__file__).resolve().parents[2]

#: Relative widths of the columns of a key table.
WIDTHS = (14, 14, 6, 10, 8, 48)

#: Width of the terminal the commands print to, characters.
TERMINAL_WIDTH = 100

#: Longest a documented command may take, s.
TIMEOUT = 600


def _cell(text, literal=False):
    entry = nodes.entry()
    paragraph = nodes.paragraph()
    paragraph += nodes.literal(text=text) if literal and text else nodes.Text(text)
    entry += paragraph
    return entry


def _row(cells, literal=False):
    row = nodes.row()
    for i, text in enumerate(cells):
        row += _cell(text, literal=literal and i == 0)
    return row


def key_table(table):
    """A docutils table of a :class:`scene_tables.Table` with rows."""
    node = nodes.table(classes=["scene-keys"])
    node += nodes.title(text=table.caption)
    group = nodes.tgroup(cols=len(COLUMNS))
    node += group
    for width in WIDTHS:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    head += _row(COLUMNS)
    group += head
    body = nodes.tbody()
    for cells in table.rows:
        body += _row(cells, literal=True)
    group += body
    return node


class SceneKeys(Directive):
    """``scene-keys NAME``: the keys of the scene table ``NAME`` (:data:`scene_tables.TABLES`)."""

    required_arguments = 1
    has_content = False

    def run(self):
        """The tables, and a line for each kind without keys."""
        name = self.arguments[0]
        if name not in TABLES:
            raise self.error(f"scene-keys: no table {name!r}; the tables are "
                             f"{', '.join(TABLES)}")
        found = []
        for table in tables(name):
            if table.rows:
                found.append(key_table(table))
            else:
                found.append(nodes.paragraph(text=f"{table.caption}; no keys."))
        return found


def _scripts():
    """``command -> (module, function)`` of the tree's ``[project.scripts]``."""
    with open(ROOT / "pyproject.toml", "rb") as f:
        scripts = tomllib.load(f)["project"]["scripts"]
    return {name: tuple(target.split(":")) for name, target in scripts.items()}


def run_commands(lines):
    """Run documented command lines in a new directory; the text to show and any failure.

    Parameters
    ----------
    lines : list of str
        Command lines, each ``COMMAND ARGS... [# exit N]``.

    Returns
    -------
    text : str
        Each command after ``$ ``, then what it printed; a status other
        than 0 shown as ``(exit status N)``.
    failure : str or None
        What went wrong: an unknown command, or a status other than the
        one expected.
    """
    scripts = _scripts()
    # COLUMNS: the width argparse wraps its help to, the same at every build.
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS=str(TERMINAL_WIDTH),
               PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT),
                                                        os.environ.get("PYTHONPATH")])))
    shown = []
    with tempfile.TemporaryDirectory(prefix="runin-docs-") as where:
        for line in lines:
            command, _, note = line.partition("#")
            expected = int(re.fullmatch(r"\s*exit (\d+)\s*", note).group(1)) if note else 0
            name, *args = shlex.split(command)
            if name not in scripts:
                return "", f"{name!r} is not a command of this package ({', '.join(scripts)})"
            module, function = scripts[name]
            # argv[0] is the command's name, as the installed script's would be.
            code = (f"import sys; sys.argv[0] = {name!r}; "
                    f"from {module} import {function} as main; sys.exit(main())")
            proc = subprocess.run([sys.executable, "-c", code, *args], cwd=where, env=env,
                                  capture_output=True, text=True, timeout=TIMEOUT)
            shown.append(f"$ {command.strip()}")
            printed = (proc.stdout + proc.stderr).replace(f"{where}{os.sep}", "").rstrip()
            if printed:
                shown.append(printed)
            if proc.returncode != 0:
                shown.append(f"(exit status {proc.returncode})")
            if proc.returncode != expected:
                return "\n".join(shown), (f"{command.strip()!r} ended with status "
                                          f"{proc.returncode}, expected {expected}")
    return "\n".join(shown), None


class CommandOutput(Directive):
    """``command-output``: run the commands of the body and show what they print."""

    has_content = True

    def run(self):
        """One literal block: the commands and their output."""
        lines = [line for line in self.content if line.strip()]
        if not lines:
            raise self.error("command-output: no command given")
        # Run again at every build: the output is the code's, not the page's.
        self.state.document.settings.env.note_reread()
        text, failure = run_commands(lines)
        if failure is not None:
            raise self.error(f"command-output: {failure}\n{text}")
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        return [block]


def setup(app):
    """Register the directives."""
    app.add_directive("scene-keys", SceneKeys)
    app.add_directive("command-output", CommandOutput)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
