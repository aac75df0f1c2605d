"""``jetgaudin animate``: an animation of the moving body from a run directory (private).

Thin: the drawing is :func:`jetgaudin.plotting.animate_run`.
"""

from __future__ import annotations

from typing import Annotated

import typer

from ._app import app
from ._common import CliInputError, OverwriteOption, console, reported_errors


@app.command()
def animate(
    run_dir: Annotated[str, typer.Argument(help="an orbit, ensemble or flow run directory (finished or interrupted)")],
    out: Annotated[str, typer.Option("--out", help="output file: .gif (Pillow) or .mp4 (needs imageio-ffmpeg)")],
    frames: Annotated[int, typer.Option("--frames", help="largest number of frames (>= 2)")] = 100,
    fps: Annotated[float, typer.Option("--fps", help="frames per second")] = 20.0,
    stride: Annotated[
        int | None,
        typer.Option("--stride", help="saved rows between frames [default: the frames spread over the whole run]"),
    ] = None,
    trail: Annotated[int, typer.Option("--trail", help="frames in the fading trail")] = 30,
    orbit: Annotated[int | None, typer.Option("--orbit", help="orbit K of an ensemble run [default: 0]")] = None,
    dpi: Annotated[int, typer.Option("--dpi", help="resolution (the picture is 6 x 6.4 inches)")] = 100,
    overwrite: OverwriteOption = False,
) -> None:
    """Animate the body along a run: the fixed point, the body axis to the centre of mass z on its sphere, the
    material point x − z, with fading trails (N = 3; y_0 and y_{N−1} otherwise).

    Rows are read from the run's HDF5 file in slices (constant memory for runs of any length); frame j shows
    saved row j·stride.
    """
    with reported_errors():
        import os

        from .. import plotting

        if os.path.lexists(out) and not overwrite:
            raise CliInputError(f"--out: {out} exists; choose another file or pass --overwrite to replace it")

        path = plotting.animate_run(
            run_dir, out, orbit=orbit, frames=frames, fps=fps, stride=stride, trail=trail, dpi=dpi
        )
        console().print(f"wrote: {path}")
