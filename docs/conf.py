"""Sphinx configuration of the hexapod_kin documentation (offline build, warnings are errors).

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (the ``docs`` extra).
The gallery (``docs/gallery/plot_*.py``) runs at build time through sphinx-gallery; its
figures are the ones the scripts draw.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")

from hexapod_kin import __version__  # noqa: E402

project = "hexapod_kin"
author = "hexapod_kin developers"
copyright = "hexapod_kin developers, BSD-3-Clause"  # noqa: A001
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static: maths render offline
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "gallery/README.txt", "gallery/*.py", "gallery/*.md5"]
root_doc = "index"

# MyST: headings get anchors for cross-page links; $...$ maths.
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# autodoc + napoleon: Google-style docstrings, as the package writes them.
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True
python_use_unqualified_type_names = True
suppress_warnings = ["myst.xref_missing", "myst.header"]


sphinx_gallery_conf = {
    "examples_dirs": ["gallery"],
    "gallery_dirs": ["auto_gallery"],
    "filename_pattern": r"plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "plot_gallery": "True",
    "abort_on_example_error": True,
}

html_theme = "furo"
html_title = f"hexapod_kin {__version__}"
html_static_path: list[str] = []
html_show_sourcelink = False


# The docstrings write absolute values as |x| (plain text for a terminal); reST would read
# them as substitutions. Escape the bars outside literals and roles before Sphinx parses them.
_LITERAL = re.compile(r"(``.*?``|:[a-z:]+:`[^`]*`)")


def _escape_bars(app, what, name, obj, options, lines):  # noqa: ANN001, ARG001
    for i, line in enumerate(lines):
        if "|" not in line or line.lstrip().startswith(("|", "+-", "+=")):
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(
            p if k % 2 else re.sub(r"(?<!\\)\|", r"\\|", p) for k, p in enumerate(parts)
        )


def setup(app):  # noqa: ANN001
    app.connect("autodoc-process-docstring", _escape_bars, priority=600)
