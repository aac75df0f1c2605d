"""Sphinx extension ``mathjax_local``: MathJax served from the site itself, so formulas render offline.

The MathJax 3.2.2 distribution is taken from the ``sphinx-mathjax-offline`` package (PyPI, in the ``docs``
extra; it ships MathJax's files as package data) and copied into ``_static/mathjax/`` of the built site:
``tex-chtml.js`` (the TeX input and the CHTML output in one file), the CHTML web fonts, and the TeX extensions
and accessibility modules that MathJax loads on demand.  The other ready-made combined files (SVG output,
MathML input, ``*-full``), which these pages never load, are left out (about 14 of the 24 MB).

``mathjax_path`` is set to the copied ``tex-chtml.js``, a path relative to ``_static``, so Sphinx's own
``sphinx.ext.mathjax`` emits ``<script defer src="_static/mathjax/tex-chtml.js">``: no page refers to a CDN.
The package's own Sphinx hook is not used: it copies the files only after a successful build, so a failed
build leaves pages whose script is missing.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

from sphinx.errors import ExtensionError

#: the package that ships the MathJax files, and MathJax's entry point inside them
PACKAGE = "sphinx-mathjax-offline"
ENTRY = "tex-chtml.js"


def mathjax_source() -> Path:
    """The directory of the installed MathJax files (``.../sphinx-mathjax-offline/static/mathjax``)."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or spec.origin is None:
        raise ExtensionError(
            f"the MathJax files are missing: pip install {PACKAGE} (or pip install -e '.[docs]') to build the site"
        )
    src = Path(spec.origin).parent / "static" / "mathjax"
    if not (src / ENTRY).is_file():
        raise ExtensionError(f"{src / ENTRY} is missing; reinstall {PACKAGE}")
    return src


def _skip(directory: str, names: list[str]) -> list[str]:
    """The combined files other than ``tex-chtml.js`` at MathJax's top level (never loaded by these pages)."""
    if Path(directory).name != "mathjax":
        return []
    return [n for n in names if n.endswith(".js") and n not in (ENTRY, "loader.js", "startup.js", "core.js")]


def _config(app, config) -> None:
    mathjax_source()  # fail early, with the fix, when the package is missing
    config.mathjax_path = f"mathjax/{ENTRY}"


def _copy(app) -> None:
    if app.builder.format != "html":
        return
    dest = Path(app.outdir) / "_static" / "mathjax"
    if not (dest / ENTRY).is_file():
        shutil.copytree(mathjax_source(), dest, ignore=_skip, dirs_exist_ok=True)


def setup(app):
    app.connect("config-inited", _config)
    app.connect("builder-inited", _copy)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
