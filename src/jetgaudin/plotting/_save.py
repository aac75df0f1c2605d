"""Writing one figure to disk (private): the piece every figure module shares, below them all (issue 33: ``_files``
imports ``_chains``, ``_compare``, ``_ensemble`` on use, and they imported ``save_figure`` back from ``_files``, a
4-module import circle).  Re-exported by :mod:`jetgaudin.plotting._files` and :mod:`jetgaudin.plotting`."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path

from .._errors import InvalidParameterError

__all__ = ["FigureFormat", "save_figure"]


class FigureFormat(StrEnum):
    """File format of the written figures."""

    png = "png"
    pdf = "pdf"
    svg = "svg"


def save_figure(fig, path, dpi: int) -> Path:
    """Write ``fig`` to ``path`` durably and atomically, never through a symlink (rendered in memory, then
    :func:`jetgaudin._fs.atomic_write_bytes`: a ``.tmp`` created with ``O_EXCL|O_NOFOLLOW``, fsynced, renamed)."""
    import io

    from .. import _fs

    path = Path(path)
    if path.suffix.lower().lstrip(".") not in {f.value for f in FigureFormat}:
        raise InvalidParameterError(f"the figure file must end in .png, .pdf or .svg, got {path.name!r}")
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, bbox_inches="tight", format=path.suffix.lower().lstrip("."))
    _fs.atomic_write_bytes(path.parent, path.name, buf.getvalue())
    return path
