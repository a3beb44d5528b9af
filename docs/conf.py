"""Sphinx configuration of the srr documentation (MyST Markdown, furo).

Build: ``python -m sphinx -W -b html docs docs/_build/html``. The reference pages are
generated from the code at build time (``_ext/srr_reference.py``, sphinx-argparse, autodoc).
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent))

project = "srr"
author = "the srr developers"
copyright = "the srr developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinxarg.ext",
    "srr_reference",
]
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build", "_generated", "Thumbs.db", ".DS_Store"]
html_theme = "furo"
html_title = "srr"
autodoc_typehints = "description"
autodoc_member_order = "bysource"
nitpicky = False
# option names such as --set stay as written (no en dashes), in help texts and prose alike
smartquotes = False
