"""Sphinx configuration of pfaff's documentation (``sphinx-build -W -b html docs docs/_build/html``).

Offline by design: no intersphinx, no theme or extension that fetches anything while building.
The gallery (``docs/gallery/plot_*.py``) is run by sphinx-gallery at build time; each script keeps
its runs short so the whole gallery builds in well under five minutes.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "pfaff"
author = "the pfaff developers"
copyright = "pfaff developers, MIT licence"
release = "0.1.0"

extensions = [
    "sphinx.ext.autodoc",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

# numpydoc: the docstrings are the reference; members are listed by autodoc, not by numpydoc.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
autodoc_default_options = {"members": False}
autodoc_typehints = "none"
autodoc_member_order = "bysource"

sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "abort_on_example_error": True,
    "capture_repr": (),
    "download_all_examples": False,
    "show_memory": False,
    "min_reported_time": 1,
    "within_subsection_order": "FileNameSortKey",
    "remove_config_comments": True,
    "reset_modules": ("matplotlib",),
}

templates_path: list[str] = []
exclude_patterns = ["_build", "_generated"]
html_theme = "alabaster"
html_title = "pfaff"
html_static_path: list[str] = []
html_theme_options = {
    "description": "Dynamics of constrained mechanical systems",
    "fixed_sidebar": True,
}
suppress_warnings: list[str] = []


def setup(app):
    """Make the generated pages (README sections, CLI help) before anything is read."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import generate

    app.connect("builder-inited", lambda _app: generate.write())
    app.connect("autodoc-process-docstring", lambda *args: generate.escape_docstring(args[-1]))
    return {"parallel_read_safe": True}
