"""Sphinx configuration of the jetgaudin documentation site.

Build (strict: every warning is an error), from the repository root after ``pip install -e ".[docs]"``::

    sphinx-build -W --keep-going -b html docs docs/_build/html

Why Sphinx (and not mkdocs-material): the API reference comes from NumPy-style docstrings, and Sphinx with
numpydoc is the tool that SciPy and NumPy use for exactly that; MyST-NB executes the tutorials (MyST Markdown
notebooks) at every build and fails it on an error in any cell, as heyoka.py's documentation does; the
mathematics pages are the repository's Markdown files, read as they are by MyST.

Importing this file has no side effects beyond setting names (pytest imports it with --doctest-modules);
pages generated from the code (the API reference, the architecture page) are written in ``setup``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(ROOT / "src"))

project = "jetgaudin"
author = "The jetgaudin developers"
copyright = "2026, The jetgaudin developers"  # noqa: A001 - Sphinx's name

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",
    "numpydoc",
    "typer_cli",
]

source_suffix = {".md": "myst-nb", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints", "jupyter_execute", "_ext"]
suppress_warnings = ["myst.header"]  # the repository's pages start at level-2 headings in places

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# tutorials: executed at every build; a failing cell fails the build
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 240
nb_execution_show_tb = True
nb_merge_streams = True

autodoc_typehints = "none"
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

intersphinx_mapping: dict = {}

html_theme = "pydata_sphinx_theme"
html_title = "jetgaudin"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path: list[str] = []


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def _generate(app) -> None:
    """Write ``site/_generated/api.rst`` (one entry per name of ``jetgaudin.__all__``) and the architecture page."""
    import inspect

    import jetgaudin as jg

    gen = HERE / "site" / "_generated"
    lines = [
        ".. Generated from jetgaudin.__all__ by docs/conf.py at build time; do not edit.",
        "",
        "Every public name",
        "=================",
        "",
        ".. currentmodule:: jetgaudin",
        "",
    ]
    for name in jg.__all__:
        if name == "__version__":
            continue
        obj = getattr(jg, name)
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            lines += [f".. autoexception:: {name}", ""]
        elif inspect.isclass(obj):
            lines += [f".. autoclass:: {name}", "   :members:", ""]
        else:
            lines += [f".. autofunction:: {name}", ""]
    _write_if_changed(gen / "api.rst", "\n".join(lines))
    arch = ROOT / "docs" / "architecture.md"
    if arch.exists():  # the page itself is listed by the index's glob toctree; link to it (an include would
        # rebase its relative links)
        text = "# Architecture\n\nThe architecture of jetgaudin is described in {doc}`../../architecture`.\n"
    else:
        text = (
            "# Architecture\n\nThe architecture page (`docs/architecture.md`: system, method and recording; the run "
            "layer; the map interface) is being written; this placeholder stands in for it until it lands.\n"
        )
    _write_if_changed(gen / "architecture.md", text)


def setup(app):
    # the tutorials' kernels import this source tree (also without an editable install)
    os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    os.environ.setdefault("MPLBACKEND", "Agg")
    app.connect("builder-inited", _generate)
