"""The API pages, the module summaries and the command-line reference match the code.

The API pages list every module, and each module's summary is a whole sentence.

The Sphinx build (docs/conf.py) is run by CI; these checks are the parts of it
that fail silently: a module missing from ``docs/api`` or from its package's
docstring is simply absent, and autosummary cuts a summary at the first period
followed by a space, so that "(paper eq. 8)" shows as "(paper eq.".  The
options of docs/cli.md are each command's ``--help``, printed by the build; the
prose around them must name only options the commands have, and its table of
exit statuses the statuses the commands end with.
"""

import ast
import importlib
import pathlib
import re

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("steady", "transient")
CLI = (ROOT / "docs" / "cli.md").read_text()
SCRIPTS = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]


def _modules(package):
    """Dotted names, relative to the package, of every module but ``__init__``/``__main__``."""
    names = []
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = path.relative_to(ROOT / package).with_suffix("").parts
        if parts[-1] not in ("__init__", "__main__"):
            names.append(".".join(parts))
    return names


def _summary(path):
    """The first sentence of a module docstring, as autosummary takes it."""
    doc = ast.get_docstring(ast.parse(path.read_text()))
    paragraph = " ".join(doc.split("\n\n")[0].split())
    return re.split(r"\.\s+", paragraph)[0].rstrip(".") + "."


@pytest.mark.parametrize("package", PACKAGES)
def test_every_module_has_its_api_section(package):
    page = (ROOT / "docs" / "api" / f"{package}.rst").read_text()
    listed = re.findall(r"^   ([\w.]+)$", page, re.M)
    documented = re.findall(rf"^\.\. automodule:: {package}\.([\w.]+)$", page, re.M)
    for name in _modules(package):
        assert name in listed, f"{package}.{name} is not in the summary of docs/api/{package}.rst"
        assert name in documented, f"{package}.{name} has no automodule in docs/api/{package}.rst"


@pytest.mark.parametrize("package", PACKAGES)
def test_package_docstring_names_every_library_module(package):
    doc = ast.get_docstring(ast.parse((ROOT / package / "__init__.py").read_text()))
    for name in _modules(package):
        if name.startswith("cli") or name == "lazy":
            continue  # the commands are named as a group, steady.lazy with the lazy names
        assert f":mod:`{package}.{name}`" in doc, f"{package}/__init__.py does not name {name}"


@pytest.mark.parametrize("path", [ROOT / p / f"{m.replace('.', '/')}.py" for p in PACKAGES
                                  for m in _modules(p)], ids=lambda p: p.stem)
def test_module_summary_is_a_whole_sentence(path):
    summary = _summary(path)
    assert not re.search(r"\b(eq|eqs|Eq|Fig|Figs|Sec|cf|vs|e\.g|i\.e)\.$", summary), \
        f"{path.relative_to(ROOT)}: the summary is cut at an abbreviation: {summary!r}"


# -- the command line's reference (docs/cli.md) ----------------------------------------------
def _help(command, capsys):
    """The ``--help`` of an installed command, run in-process."""
    module, function = SCRIPTS[command].split(":")
    with pytest.raises(SystemExit) as done:
        getattr(importlib.import_module(module), function)(["--help"])
    assert done.value.code == 0, f"{command} --help: exit {done.value.code}"
    return capsys.readouterr().out


def _section(command):
    """The text of docs/cli.md under ``## command``, up to the next ``## `` heading."""
    parts = re.split(rf"^## {re.escape(command)}\n", CLI, flags=re.M)
    assert len(parts) == 2, f"docs/cli.md has no section '## {command}'"
    return re.split(r"^## ", parts[1], flags=re.M)[0]


@pytest.mark.parametrize("command", sorted(SCRIPTS))
def test_cli_reference_shows_the_help_and_names_only_real_options(command, capsys):
    section = _section(command)
    assert re.search(rf"```{{command-output}}\n{re.escape(command)} --help\n```", section), \
        f"docs/cli.md's section {command} does not print '{command} --help'"
    options = set(re.findall(r"(?<![\w-])(--?[a-z][\w-]*)", _help(command, capsys)))
    named = set(re.findall(r"`(--?[a-z][\w-]*)", section))
    # A run-in's companion, the command lines of another command quoted in the section.
    named -= {f for line in re.findall(r"```{command-output}\n(.*?)```", section, re.S)
              for f in re.findall(r"(?<![\w-])(--?[a-z][\w-]*)", line)}
    assert named <= options, f"docs/cli.md names options {sorted(named - options)} that " \
                             f"{command} does not have"


def test_cli_reference_lists_the_exit_statuses_of_the_commands():
    from steady.cli import common

    table = re.search(r"## Exit statuses\n.*?\| status \| meaning \|\n\|---\|---\|\n(.*?)\n\n",
                      CLI, re.S)
    assert table is not None, "docs/cli.md has no table of exit statuses"
    documented = [int(row.split("|")[1]) for row in table.group(1).splitlines()]
    statuses = [common.EXIT_OK, common.EXIT_FAILED, common.EXIT_BAD_INPUT,
                common.EXIT_INTERRUPTED]
    in_help = [int(s) for s in re.findall(r"(?:^exit status: |; )(\d+) ",
                                          common.EXIT_STATUS_EPILOG)]
    assert documented == statuses == in_help, \
        f"docs/cli.md lists {documented}, the commands end with {statuses}, --help says {in_help}"
