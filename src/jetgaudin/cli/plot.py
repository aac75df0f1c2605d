"""``jetgaudin plot``: redraw every figure of a run from its files (private).

Thin: the drawing is :func:`jetgaudin.plotting.save_run_figures`.
"""

from __future__ import annotations

import contextlib
import os
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from ._app import app
from ._common import CliInputError, OverwriteOption, console, reported_errors

#: the figures ``plot`` may write (``save_run_figures``; the last two for ``flow --compare`` runs)
FIGURE_STEMS = ("figure1", "figure2", "integrals", "compare_drift", "compare_distance")


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
    overwrite: OverwriteOption = False,
) -> None:
    """Redraw the figures of a run from its files: figure1 (3D points with the sphere), figure2 (e₁–e₂
    projection), integrals (drift of the 2N integrals); for flow --compare runs also compare_drift and
    compare_distance. Reads the run in slices (constant memory)."""
    with reported_errors():
        from .. import _fs, plotting

        out_dir = _figures_dir(run_dir, out, fmt.value, overwrite)
        # a run directory (this run's, or another's with --overwrite) is written under its lock: never while a run
        # is in progress there (one writer per run directory); every refusal is decided before the lock names this
        # process (a refusal changes nothing, not even the lock file)
        locked = (out_dir / "run.json").exists()
        lock = _fs.RunDirLock(out_dir, claim=False, create=False) if locked else contextlib.nullcontext()
        with lock:
            plotting.check_run_figures(run_dir, orbit=orbit, dpi=dpi, max_points=max_points)
            if isinstance(lock, _fs.RunDirLock):
                lock.claim()
            paths = plotting.save_run_figures(
                run_dir, out, orbit=orbit, dpi=dpi, fmt=plotting.FigureFormat(fmt.value), max_points=max_points
            )
        console().print("wrote: " + ", ".join(str(p) for p in paths))


def _figures_dir(run_dir: str, out: str | None, fmt: str, overwrite: bool) -> Path:
    """Where the figures go, decided before anything is drawn: the run's own directory (its figures are redrawn),
    or ``--out``, which must not hold another run nor figures of these names unless ``--overwrite``."""
    if out is not None and str(out).strip() == "":
        raise CliInputError("--out: empty path; give a directory name")
    out_dir = Path(run_dir if out is None else out)
    if overwrite or not out_dir.exists() or (Path(run_dir).exists() and out_dir.resolve() == Path(run_dir).resolve()):
        return out_dir
    if os.path.lexists(out_dir / "run.json"):
        raise CliInputError(f"--out: {out_dir} holds another run; its figures are its own (draw them with jetgaudin "
                            f"plot {out_dir}), or pass --overwrite")
    taken = [f"{s}.{fmt}" for s in FIGURE_STEMS if os.path.lexists(out_dir / f"{s}.{fmt}")]
    if taken:
        raise CliInputError(f"--out: {out_dir} already holds {', '.join(taken)}; choose another directory or pass "
                            "--overwrite to replace them")
    return out_dir
