"""Sphinx configuration of the ideas_hpc documentation site.

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (CI and
``tests/test_docs_build.py`` do this with warnings as errors). Every
``docs/*.md`` joins the site through the glob in ``index.md``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "ideas_hpc"
author = "ideas_hpc contributors"
copyright = "2026, ideas_hpc contributors"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "figures/make_figures.py", "Thumbs.db", ".DS_Store"]

# Markdown: $...$ maths, heading anchors for in-page links, ::: fences.
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference: one generated page per public module (docs/api/_generated,
# rebuilt on every build, never committed).
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()

html_theme = "alabaster"
html_title = "ideas_hpc"
