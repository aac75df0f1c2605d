"""``jetgaudin plot``: redraw every figure of a run from its files (private).

Thin: the drawing is :func:`jetgaudin.plotting.save_run_figures`.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer

from . import app
from ._common import console, reported_errors


class Format(StrEnum):
    png = "png"
    pdf = "pdf"
    svg = "svg"


@app.command()
def plot(
    run_dir: Annotated[str, typer.Argument(help="an orbit, ensemble or flow run directory (finished or interrupted)")],
    out: Annotated[str | None, typer.Option("--out", help="directory for the figures [default: RUN_DIR]")] = None,
    dpi: Annotated[int, typer.Option("--dpi", help="resolution of raster figures (10..2000)")] = 130,
    fmt: Annotated[Format, typer.Option("--format", help="file format")] = Format.png,
    max_points: Annotated[
        int,
        typer.Option(
            "--max-points",
            help="draw at most this many rows: every k-th saved row, k = ceil(rows / max-points), and the last; "
            "the drift figure shows each bin's largest drift",
        ),
    ] = 20_000,
    orbit: Annotated[int | None, typer.Option("--orbit", help="orbit K of an ensemble run [default: 0]")] = None,
) -> None:
    """Redraw the figures of a run from its files: figure1 (3D points with the sphere), figure2 (e₁–e₂
    projection), integrals (drift of the 2N integrals); for flow --compare runs also compare_drift and
    compare_distance. Reads the run in slices (constant memory)."""
    with reported_errors():
        from .. import plotting

        paths = plotting.save_run_figures(
            run_dir, out, orbit=orbit, dpi=dpi, fmt=plotting.FigureFormat(fmt.value), max_points=max_points
        )
        console().print("wrote: " + ", ".join(str(p) for p in paths))
