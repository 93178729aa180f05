"""Sphinx configuration: the API reference, built from the numpydoc docstrings.

Built by the test suite (tests/test_docs.py), so a docstring that breaks the build fails CI.
Build by hand: ``sphinx-build -b html docs docs/_build/html``.
"""

import dam

project = "dam"
author = "the dam developers"
copyright = "2026, the dam developers"
release = version = dam.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
]
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False
numpydoc_validation_checks: set = set()
exclude_patterns = ["_build"]
templates_path = ["_templates"]
html_theme = "alabaster"
html_static_path: list = []
suppress_warnings = ["autosummary.import_cycle"]
nitpicky = False
