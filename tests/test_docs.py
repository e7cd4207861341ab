"""The API pages list every module, and each module's summary is a whole sentence.

The Sphinx build (docs/conf.py) is run by CI; these checks are the parts of it
that fail silently: a module missing from ``docs/api`` or from its package's
docstring is simply absent, and autosummary cuts a summary at the first period
followed by a space, so that "(paper eq. 8)" shows as "(paper eq.".
"""

import ast
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("steady", "transient")


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
