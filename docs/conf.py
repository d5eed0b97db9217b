"""Sphinx configuration of cgaskin's documentation (``bash scripts/build-docs.sh``).

Offline by design: no intersphinx, MathJax served from the site itself (sphinx-mathjax-offline), the
gallery's pictures made by its examples at build time. Environment switches (all default on):

- ``CGASKIN_DOCS_VALIDATE=0``: no numpydoc validation (``_ext/cgaskin_docstrings.py``);
- ``CGASKIN_DOCS_GALLERY=0``: the gallery's pages without running its examples (no pictures);
- ``CGASKIN_DOCS_ONLY=api``: the reference alone, nothing else read (what ``tests/docs`` builds to
  compare ``objects.inv`` with the public API; not a site to publish).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import cgaskin  # noqa: E402  (the version below; autodoc imports it anyway)
from cgaskin_gallery import GalleryFiles  # noqa: E402

project = "cgaskin"
author = "the cgaskin developers"
copyright = "the cgaskin developers, Apache-2.0"
version = release = cgaskin.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",        # MathJax 3 copied into _static/mathjax: no CDN
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "cgaskin_api",                   # the reference's module pages from the public API
    "cgaskin_docstrings",            # numpydoc validation as warnings
    "cgaskin_perf",                  # benchmark tables from docs/performance/*.txt
]

only_api = os.environ.get("CGASKIN_DOCS_ONLY", "").strip() == "api"
root_doc = "api/index" if only_api else "index"
exclude_patterns = ["_build", "_pages", "examples", "performance", "**/.ipynb_checkpoints"]
if only_api:
    exclude_patterns += ["index.rst", "guide", "auto_examples"]
    extensions.remove("sphinx_gallery.gen_gallery")
    for name in ("sphinx-mathjax-offline", "numpydoc", "cgaskin_docstrings", "cgaskin_perf"):
        extensions.remove(name)                     # not needed for the names (MathJax: 24 MB to copy)
templates_path = ["_templates"]
html_static_path = ["_static"]
html_extra_path = [str(GalleryFiles.PAGES)]      # pages the gallery's examples wrote (the viewer's)
html_css_files = ["cgaskin.css"]
default_role = "literal"
nitpicky = False
suppress_warnings = []

# -- the reference -----------------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"                  # numpydoc's Parameters say the types
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False         # members are documented in place by the class template
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()          # _ext/cgaskin_docstrings.py validates, per kind of object

# -- the gallery ---------------------------------------------------------------------------------------
# the examples' folder is sphinx-gallery's source (its pages are written to auto_examples/), not Sphinx's
run_gallery = os.environ.get("CGASKIN_DOCS_GALLERY", "1").strip().lower() not in ("0", "false", "no", "off")
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r".*\.py$",                  # run every example
    "ignore_pattern": r"(__init__|_common)\.py$",
    "within_subsection_order": "FileNameSortKey",
    "plot_gallery": str(run_gallery),
    "abort_on_example_error": True,
    "image_scrapers": ("matplotlib", GalleryFiles()),
    "remove_config_comments": True,
    "download_all_examples": False,
    "show_signature": False,
    "min_reported_time": 1e9,                         # no per-example timing line on the pages
    "write_computation_times": False,
    "reset_modules": ("matplotlib",),
    "capture_repr": (),
}

# -- HTML ----------------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = "cgaskin"
html_show_sourcelink = False
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "header_links_before_dropdown": 6,
    "footer_start": ["copyright"],
    "footer_end": [],
    "secondary_sidebar_items": ["page-toc"],
}
html_sidebars = {"index": []}
if only_api:
    html_theme, html_theme_options, html_sidebars = "basic", {}, {}   # the names, quickly
html_context = {"default_mode": "light"}
