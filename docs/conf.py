"""Sphinx configuration of the conformal documentation.

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (CI: .ci/run).  The
reference pages of scene keys, commands and API are generated from the code at build time
(``docs/_ext/generated.py``).
"""
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent))          # the package of this checkout, not an installed copy
os.environ.setdefault("MPLBACKEND", "Agg")    # autodoc imports plotting modules: no display needed

from conformal import __version__  # noqa: E402

project = "conformal"
author = "the conformal authors"
copyright = "the conformal authors, Apache-2.0"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "generated",
    "docstrings",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# docs/incoming/: text that other branches hand to the lead, merged by hand, never built
exclude_patterns = ["_build", "incoming", "**/incoming", "Thumbs.db", ".DS_Store"]

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# numpydoc-style docstrings through napoleon (bundled with Sphinx: no extra dependency)
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
autodoc_default_options = {"members": True, "member-order": "bysource", "ignore-module-all": True}
autodoc_typehints = "none"            # signatures stay short; the docstrings give types and units
autodoc_preserve_defaults = True

html_theme = "alabaster"
html_title = f"conformal {release}"
html_static_path = []
