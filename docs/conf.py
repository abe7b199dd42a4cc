"""Sphinx configuration of clsolid's documentation.

Build (warnings are errors)::

    pip install -e ".[docs]"
    sphinx-build -W --keep-going -b html docs docs/_build/html
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
# Document the checkout being built, not whichever clsolid is installed.
sys.path.insert(0, str(DOCS.parent))
sys.path.insert(0, str(DOCS / "_ext"))

import clsolid  # noqa: E402

project = "clsolid"
author = "the clsolid developers"
copyright = "2026, the clsolid developers"
release = clsolid.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "cli_reference",
    "option_reference",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# gallery/gallery.md is tools/gallery.py's output, shown inside gallery.md ({include}).
exclude_patterns = ["_build", "gallery/gallery.md", "Thumbs.db", ".DS_Store"]

# Markdown pages (MyST): $...$ and $$...$$ maths, \begin{align} blocks, ::: fences, and
# GitHub-style heading anchors, so that "design.md#bandwidth" works on GitHub and here.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# The generated command-line reference (docs/_ext/cli_reference.py).
cli_reference_parser = "clsolid.cli:build_parser"
cli_reference_output = "reference/cli.md"
# The generated option reference (docs/_ext/option_reference.py), from the options' declarations.
option_reference_source = "clsolid.cli.synth:option_reference"
option_reference_output = "reference/options.md"

# API reference: numpydoc renders the docstrings; signatures without type hints (the
# docstrings give the types).
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autosummary_generate = False
# numpydoc's per-class member tables would list every dataclass field and every inherited
# exception method a second time; its docstring validation is a linter's job, not the build's.
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False

html_theme = "pydata_sphinx_theme"
html_title = f"clsolid {release}"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_show_sourcelink = False

# Docstrings that reST misreads, fixed on the way in until the code's own text changes
# (each replacement is a no-op once the docstring is fixed): name -> (text, replacement).
_DOCSTRING_FIXES = {
    # "|F_a - F_b|" reads as a substitution reference.
    "clsolid.metrics.wasserstein_1d": ("|F_a - F_b|", "``|F_a - F_b|``"),
}


def _fix_docstring(app, what, name, obj, options, lines):
    fix = _DOCSTRING_FIXES.get(name)
    if fix is not None:
        lines[:] = [line.replace(*fix) for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _fix_docstring, priority=100)
