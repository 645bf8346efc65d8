"""Sphinx configuration: the API reference from the docstrings (numpy style), and the
README's sections on scenes, outputs and conventions.  Build it with
``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (Debian's python3-sphinx
and python3-myst-parser)."""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import dolfinx_friction  # noqa: E402

project = "dolfinx_friction"
release = version = dolfinx_friction.__version__
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"members": True, "show-inheritance": False}
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]  # $...$ and $$...$$ in theory.md
suppress_warnings = ["myst.header"]  # the README's sections start at level 2
html_theme = "alabaster"
html_theme_options = {"nosidebar": False}


def _check_public_api(app, env) -> None:
    """Warn (an error with -W) about a name of ``dolfinx_friction.__all__`` not documented."""
    from sphinx.util import logging

    documented = set(env.get_domain("py").objects)
    for name in dolfinx_friction.__all__:
        module = dolfinx_friction._PUBLIC[name]
        if not {f"dolfinx_friction.{name}", f"dolfinx_friction.{module}.{name}"} & documented:
            logging.getLogger(__name__).warning(f"dolfinx_friction.{name} is not documented")


def setup(app) -> None:
    app.connect("env-check-consistency", _check_public_api)
