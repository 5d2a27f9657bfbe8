"""Sphinx configuration of simgrip's documentation (``pip install ".[docs]"``).

Build (as CI does, warnings are errors)::

    python -m sphinx -W --keep-going -b html docs /tmp/simgrip-docs

Sphinx with MyST-Parser: the pages stay Markdown (readable on any forge as they are), and the
docstrings, already reStructuredText (``literal``, :func:, :data: roles, NumPy-style sections), are read
by autodoc as written. No network: intersphinx is off and the theme is Sphinx's built-in alabaster.
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "simgrip"
author = "simgrip developers"
copyright = "simgrip developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",  # the dataclasses' "Attributes / ----------" sections are NumPy style
    "sphinx.ext.mathjax",
    "cli_reference",  # docs/_ext/cli_reference.py: the CLI reference from simgrip.cli.build_parser()
    "markdown_docstrings",  # docs/_ext/markdown_docstrings.py: the environments' Markdown tables
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "baselines"]

# MyST: $...$ maths for the physics page, heading anchors for links such as limits.md#parameter-limits
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

# autodoc: document what each module exports (its __all__), in source order, with signatures as written
autodoc_default_options = {"members": True, "member-order": "bysource", "show-inheritance": False}
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
# a method without its own docstring is not listed (Gymnasium's step/reset texts describe CartPole, not these)
autodoc_inherit_docstrings = False
autosummary_generate = False
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True

# option names such as --profile stay two hyphens (docutils would make them an en dash)
smartquotes = False

nitpicky = False  # cross-references to NumPy/MuJoCo types stay plain text (no intersphinx: no network in CI)

html_theme = "alabaster"
html_title = "simgrip"
html_static_path = []
html_theme_options = {"description": "Fast, theory-checked simulation of soft pneumatic robot fingers"}
