"""``jetgaudin warmup``: compile (or load from Numba's cache) every compiled kernel once, and say how long it took."""

from __future__ import annotations

import typer

from ._app import app

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
    X = np.random.default_rng(7).normal(size=(2, model.n_state))
    B = model.two_point_backlund(0.9 + 0.05j, kernel="compiled")
    report = B.prepare_kernels(X[:1], 1, notify)
    B.advance(X, None, 1)  # the ensembles' batch kernel (run_batch) too
    return report


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
    # one process, one Numba target for every kernel: the chains' kernel modules apply the Bäcklund kernels'
    # target themselves (``gaudin/_kernels.py``), so these entries serve orbits and ensembles alike
    chain = _chain_warmup(say)
    fam = _family_warmup(say)
    typer.echo(f"warmup: the family kernel (trigonometric chains) {fam.state}; {fam.seconds:.1f} s")
    typer.echo(f"warmup: the chains' kernel {chain.state}; {chain.seconds:.1f} s (orbits and ensembles)")
