# SPDX-License-Identifier: MIT
"""Sphinx configuration of vpcontact's manual (built by ``bash scripts/docs.sh``).

The scene-key reference and the demo pages are generated into ``_generated/`` at build time by
the local extension ``_ext/vpdocs.py`` (not committed).
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))  # vpcontact itself: the venv's (editable) install

project = "vpcontact"
author = "the vpcontact authors"
copyright = "2026, the vpcontact authors"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "vpdocs",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "README.md"]
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# The demos' docstrings are written for their scripts, whose headings may skip a level.
suppress_warnings = ["myst.header"]

html_theme = "furo"
html_title = "vpcontact"
html_static_path = []

# autodoc: the docstrings are Google style (napoleon); signatures keep their type hints.
autodoc_default_options = {"show-inheritance": True}  # members: listed per page
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_inherit_docstrings = False
napoleon_google_docstring = True
napoleon_numpy_docstring = False
nitpicky = False


# -- docstrings: |x| is a norm, not an RST substitution ------------------------------------

def _escape_bars(line: str) -> str:
    """Escape ``|`` outside inline literals, so ``|x − c|`` reads as a norm."""
    parts = line.split("``")
    for i in range(0, len(parts), 2):  # even parts lie outside ``...``
        parts[i] = parts[i].replace("|", "\\|")
    return "``".join(parts)


def _process_docstring(app, what, name, obj, options, lines):
    literal_indent = None  # indentation of the line that opened a literal block (::)
    for i, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if "|" in line:
            lines[i] = _escape_bars(line)
        if stripped.endswith("::"):
            literal_indent = indent


def setup(app):
    app.connect("autodoc-process-docstring", _process_docstring)
