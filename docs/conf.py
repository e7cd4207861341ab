"""Sphinx configuration of the runin documentation.

Build (warnings are errors)::

    python -m sphinx -W --keep-going -b html docs /tmp/docs_html

Needs the ``docs`` extra (``sphinx``, ``numpydoc``, ``myst-parser``,
``sphinx-mathjax-offline``, ``sphinx-gallery``); the packages ``steady`` and
``transient`` are imported from the repository root, so no install is
needed.  The build needs no network: MathJax is copied into the site
(``sphinx-mathjax-offline``), and the examples of ``docs/examples`` run
during the build (sphinx-gallery), their pages written to
``docs/auto_examples``.  The tables of scene keys are drawn from the keys'
declarations and the command outputs the pages quote are printed by the
commands during the build (``docs/_ext/runin_directives.py``).
"""

import os
import sys

# The repository root, so that ``steady`` and ``transient`` import without install;
# _ext, the directives of these pages (runin_directives: scene-key tables drawn from
# the keys' declarations, command outputs run at build time).
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "docs", "_ext"))

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
    # MathJax from the package, copied into _static/mathjax: equations without a CDN.
    "sphinx-mathjax-offline",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "runin_directives",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"

# figures/ holds images only; pages show them, but nothing there is a source page.
# examples/ holds the gallery's scripts; their pages are generated into auto_examples/.
exclude_patterns = ["_build", "_ext", "figures", "examples", "Thumbs.db", ".DS_Store"]

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

# -- Examples (sphinx-gallery) ---------------------------------------------
# Every script of docs/examples runs during the build, in file-name order, so
# that the examples a user copies are the ones that ran; an error fails it.
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "show_signature": False,
    "image_scrapers": ("matplotlib",),
    "reference_url": {},
    # The timing page would load a table script from a CDN: not written.
    "write_computation_times": False,
}


def _every_example_has_its_figure(app, exception):
    """Fail the build when a gallery page has no figure (the page would show a placeholder).

    sphinx-gallery keeps the figures an example leaves open in pyplot as
    ``auto_examples/images/sphx_glr_<example>_001.png``; an example whose
    figures never reached pyplot has none.
    """
    if exception is not None:
        return
    import pathlib

    source = pathlib.Path(app.srcdir)
    images = source / "auto_examples" / "images"
    missing = [path.name for path in sorted((source / "examples").glob("plot_*.py"))
               if not (images / f"sphx_glr_{path.stem}_001.png").exists()]
    if missing:
        raise RuntimeError(f"gallery pages without a figure: {', '.join(missing)}")


def setup(app):
    """The checks of this build beyond Sphinx's own."""
    app.connect("build-finished", _every_example_has_its_figure)
