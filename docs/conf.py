"""Sphinx configuration of the mortar1d3d documentation (``make docs``).

Pages are MyST Markdown (so that docs/conventions.md and the README's style carry over), the API
reference is autodoc with numpydoc, and the tutorials are the scripts in examples/tutorials/,
shown with literalinclude: they run as tests in ``make test``, so the site does not run them again.
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import mortar1d3d  # noqa: E402

project = "mortar1d3d"
author = "the mortar1d3d authors"
copyright = "the mortar1d3d authors (MIT licence)"
release = version = mortar1d3d.__version__

extensions = ["myst_parser", "sphinx.ext.autodoc", "numpydoc"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "img"]
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

# API pages: every name of each module's __all__, in source order
autodoc_default_options = {"members": True, "undoc-members": True, "imported-members": True, "member-order": "bysource", "show-inheritance": False}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()

html_theme = "alabaster"
html_static_path = []
html_theme_options = {"description": "1D beams embedded in 3D solids with mortar-type coupling",
                      "fixed_sidebar": False, "page_width": "1180px"}
html_show_sourcelink = False
# no network: nothing here refers to another project's inventory
intersphinx_mapping = {}
linkcheck_ignore = [r"https?://.*"]
