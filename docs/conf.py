"""Sphinx configuration of the runin documentation.

Build (warnings are errors)::

    python -m sphinx -W --keep-going -b html docs /tmp/docs_html

Needs ``sphinx``, ``numpydoc`` and ``myst-parser``; the packages ``steady``
and ``transient`` are imported from the repository root, so no install is
needed.
"""

import os
import sys

# The repository root, so that ``steady`` and ``transient`` import without install.
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, ROOT)

project = "runin"
author = "runin contributors"
copyright = "runin contributors"

try:
    from importlib.metadata import version as _version

    release = _version("runin")
except Exception:  # not installed: the docs build from the source tree
    release = "0.1.0"
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"

# figures/ holds images only; pages show them, but nothing there is a source page.
exclude_patterns = ["_build", "figures", "Thumbs.db", ".DS_Store"]

# -- MyST ----------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath"]
# Anchors for "## ..." headings, so that pages can link to "#section-name".
myst_heading_anchors = 3

# -- autodoc / autosummary / numpydoc --------------------------------------
autosummary_generate = False
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# Cross-reference checking of the type fields ("ndarray, shape (n, n), Pa")
# would flag the units; numpydoc leaves them as text.
numpydoc_xref_param_type = False

# -- HTML ------------------------------------------------------------------
html_theme = "alabaster"
html_title = "runin"
html_static_path = []
