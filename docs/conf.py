"""Sphinx configuration of the mobmanip documentation.

Build (warnings are errors) and run the examples::

    sphinx-build -W --keep-going -b html docs docs/_build/html
    sphinx-build -W --keep-going -b doctest docs docs/_build/doctest

A build starts by making the pages' pictures with the project's own commands (``figures.py``,
into ``_generated/``, not committed).
"""

from __future__ import annotations

import os
import sys

import mobmanip

project = "mobmanip"
author = "the mobmanip developers"
copyright = "the mobmanip developers"  # noqa: A001 - Sphinx setting
release = mobmanip.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    # MathJax 3 shipped with the built site (PyPI: sphinx-mathjax-offline), so that equations
    # render from a local build opened without internet; it sets mathjax_path to _static/mathjax
    "sphinx-mathjax-offline",
    "sphinx.ext.doctest",
    "sphinx.ext.viewcode",
    "sphinxarg.ext",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_generated"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference from the Google-style docstrings.
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_use_ivar = True
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_typehints_format = "short"
autodoc_default_options = {"members": True, "show-inheritance": True}
# Names in annotations that Sphinx cannot resolve to a page of their own (third-party types
# without intersphinx, private helpers); listed so that everything else stays an error.
nitpicky = False
suppress_warnings = ["myst.header"]

# Examples in the pages run under `-b doctest`; numbers printed with the precision they carry.
doctest_global_setup = """
import numpy as np
np.set_printoptions(precision=4, suppress=True)
import mobmanip
"""

html_theme = "furo"
html_title = f"mobmanip {release}"
html_static_path: list[str] = []

# Matplotlib draws off screen while the docs are built.
os.environ.setdefault("MPLBACKEND", "Agg")
sys.dont_write_bytecode = True


def _command_notes_directive():
    """``.. command-notes:: NAME``: the epilog of ``mobmanip NAME --help`` as preformatted text.

    The commands format their epilogs themselves (argparse's RawDescriptionHelpFormatter), so
    they are shown as written rather than parsed as reStructuredText.
    """
    from docutils import nodes
    from sphinx.util.docutils import SphinxDirective

    class CommandNotes(SphinxDirective):
        required_arguments = 1

        def run(self):
            from mobmanip.cli import build_parser

            parser = build_parser()
            (subparsers,) = (a for a in parser._actions if a.dest == "command")
            epilog = subparsers.choices[self.arguments[0]].epilog or ""
            return [nodes.literal_block(epilog, epilog.strip("\n"))] if epilog else []

    return CommandNotes


def parser_without_epilogs():
    """The ``mobmanip`` parser with the subcommands' epilogs left out (shown by ``command-notes``)."""
    from mobmanip.cli import build_parser

    parser = build_parser()
    for action in parser._actions:
        for sub in (getattr(action, "choices", None) or {}).values():
            if hasattr(sub, "epilog"):
                sub.epilog = None
    return parser


def _generate_figures(app):
    """The pages' pictures, made by the project's own commands (``docs/figures.py``)."""
    import importlib.util

    from sphinx.util import logging

    spec = importlib.util.spec_from_file_location(
        "mobmanip_docs_figures", os.path.join(os.path.dirname(__file__), "figures.py")
    )
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    figures.generate(log=logging.getLogger(__name__).info)


def setup(app):
    import types

    helpers = types.ModuleType("mobmanip_docs_conf")  # what cli.md's argparse directive imports
    helpers.parser_without_epilogs = parser_without_epilogs
    sys.modules[helpers.__name__] = helpers
    app.add_directive("command-notes", _command_notes_directive())
    app.connect("builder-inited", _generate_figures)
    return {"parallel_read_safe": True}
