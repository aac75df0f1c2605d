"""``jetgaudin warmup``: compile (or load from Numba's cache) every compiled kernel once, and say how long it took."""

from __future__ import annotations

import typer

from . import app

__all__ = ["warmup_command"]


@app.command("warmup")
def warmup_command() -> None:
    """Compile every Numba kernel once (N = 3 and generic routes, lanes, batch, branch rule) so that later runs start
    at full speed; prints what it compiled and the time.  Compiled kernels are cached on disk."""
    from ..backlund import kernels

    report = kernels.warmup(notify=lambda msg: typer.echo(msg, err=True))
    if report.state == "loaded":
        typer.echo("jetgaudin: kernels already loaded in this process")
    typer.echo(f"warmup: {len(report.kernels)} kernels {report.state} before; {report.seconds:.1f} s")
