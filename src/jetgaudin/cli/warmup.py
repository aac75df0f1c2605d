"""``jetgaudin warmup``: compile (or load from Numba's cache) every compiled kernel once, and say how long it took."""

from __future__ import annotations

import typer

from . import app

__all__ = ["warmup_command"]


def _chain_warmup(notify):
    """The chains' kernel (``jetgaudin.gaudin``), compiled through a small compiled chain map's
    ``prepare_kernels`` (its signature does not depend on the chain: one compile serves every chain)."""
    import numpy as np

    import jetgaudin as jg
    from jetgaudin.gaudin import GaudinModel

    model = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    X = np.random.default_rng(7).normal(size=(1, model.n_state))
    return jg.ChainTwoPointBacklund(model, 0.9 + 0.05j, backend="compiled").prepare_kernels(X, 1, notify)


def _family_warmup(notify):
    """The one family kernel (``jetgaudin.gaudin._family_kernel``: the trigonometric family's compiled route), compiled
    through a small trigonometric chain's ``prepare_kernels`` (one compile serves every family and chain)."""
    import numpy as np

    from jetgaudin.gaudin import GaudinModel

    model = GaudinModel(0.8, [(-1.0, 2), (0.5, 1)], family="trigonometric")
    X = np.random.default_rng(7).normal(size=(1, model.n_state))
    return model.two_point_backlund(0.9 + 0.05j, kernel="compiled").prepare_kernels(X, 1, notify)


#: run in a child process: the chains' kernel compiled for Numba's default CPU target, the target it gets when a
#: process imports it before the Bäcklund kernels have chosen theirs (``backlund/kernels/_target.py``:
#: ``configure`` adds ``prefer-256-bit`` only while Numba's target does not exist yet), as ``ensemble --sites``
#: does.  Numba caches one version per target, so this warm-up serves those runs.
_CHILD = ("import jetgaudin.gaudin._kernels, jetgaudin.gaudin._family_kernel; "
          "from jetgaudin.cli.warmup import _chain_warmup, _family_warmup; _chain_warmup(None); _family_warmup(None)")


def _chain_warmup_default_target() -> float:
    """Seconds to compile (or load) the chains' and the family kernel for Numba's default target, in a child
    process."""
    import subprocess
    import sys
    import time

    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        typer.echo(f"jetgaudin warmup: the chains' kernel for ensembles failed to compile: {last}", err=True)
        raise typer.Exit(1)
    return time.perf_counter() - t0


@app.command("warmup")
def warmup_command() -> None:
    """Compile every Numba kernel once (N = 3 and generic routes, lanes, batch, branch rule, the chains' kernel and
    the family kernel for orbits and ensembles) so that later runs start at full speed; prints what it compiled and
    the time.  Compiled kernels are cached on disk."""
    from ..backlund import kernels

    def say(msg: str) -> None:
        typer.echo(msg, err=True)

    report = kernels.warmup(notify=say)
    if report.state == "loaded":
        typer.echo("jetgaudin: kernels already loaded in this process")
    typer.echo(f"warmup: {len(report.kernels)} kernels {report.state} before; {report.seconds:.1f} s")
    chain = _chain_warmup(say)
    fam = _family_warmup(say)
    typer.echo(f"warmup: the family kernel (trigonometric chains) {fam.state}; {fam.seconds:.1f} s")
    say("jetgaudin: compiling (or loading) the chains' and the family kernel for ensembles (Numba's default CPU "
        "target) ...")
    ens_s = _chain_warmup_default_target()
    typer.echo(f"warmup: the chains' kernel {chain.state}; {chain.seconds:.1f} s for orbits, "
               f"{ens_s:.1f} s for ensembles (both kernels)")
