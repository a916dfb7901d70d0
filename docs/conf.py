"""Sphinx configuration of the shakedown documentation.

Build (no network, ~1 min; math is rendered by the MathJax copy of the package
``sphinx-mathjax-offline``, an extra of ``.[docs]``, so pages read offline too):

    python docs/execute_notebooks.py          # once: the notebooks with their figures (small size)
    python -m sphinx -W --keep-going -b html docs docs/_build/html

The scene-file reference and the benchmark tables are generated from the code and from
``benchmarks/RESULTS_*.md`` at every build (``docs/_ext/generate.py``), so they cannot drift.
Notebooks are rendered from their executed copies without running them again: from the folder
``SHAKEDOWN_DOCS_NOTEBOOKS`` names (the test suite passes the copies its notebook test made),
else ``docs/_executed/`` (written by ``docs/execute_notebooks.py``), else the notebooks as
stored in git (no outputs).
"""

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

import generate  # noqa: E402

from shakedown.model.version import __version__  # noqa: E402

generate.scene_reference(DOCS / "generated" / "scene_reference.rst")
generate.benchmark_tables(ROOT / "benchmarks", DOCS / "generated" / "benchmarks.md")
generate.notebooks(ROOT / "notebooks", DOCS / "notebooks",
                   [os.environ.get("SHAKEDOWN_DOCS_NOTEBOOKS"), DOCS / "_executed"])

project = "shakedown"
author = "The shakedown developers"
copyright = "2026, The shakedown developers"
version = release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 from the package into _static/mathjax: no CDN
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "_executed", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints"]
root_doc = "index"

# notebooks: never executed by the docs build (the test suite executes them)
nb_execution_mode = "off"
nb_merge_streams = True
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# docstrings are edited by many hands: render them, do not lint them here (ruff and the
# tests do); warnings stay errors (-W) for everything the build itself can get wrong
numpydoc_validation_checks = set()
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "none"
autodoc_member_order = "bysource"
nitpicky = False
smartquotes = False  # option values and help texts stay as the code writes them
intersphinx_mapping = {}  # no network
suppress_warnings = ["mystnb.unknown_mime_type"]

html_theme = "pydata_sphinx_theme"
html_title = f"shakedown {__version__}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "icon_links": [],
}
html_static_path = ["_static"]
html_css_files = ["wide_math.css"]  # wide display equations scroll instead of being cut off
html_last_updated_fmt = None
