"""``jetgaudin ensemble``: iterate the real two-point Bäcklund map on a batch of orbits (private).

Initial data from a file (CSV: one state per row, 3N numbers; NPZ: array ``X`` of shape ``(B, 3N)`` and
optionally per-orbit ``b`` and ``eta``) or from a seeded sampler (``--sample leaf`` with ``--casimirs``,
``--sample energy`` with ``--energy``).  Runs locally on all cores or on a Dask cluster
(``--scheduler tcp://host:port``), saves every k-th state to an NPZ file and prints the per-orbit drift
of the integrals.  No mathematics here: everything comes from :mod:`jetgaudin.ensemble`.
"""

from __future__ import annotations

import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from . import app
from ._common import EXIT_FAILED, Branch, CliInputError, console, fail, parse_b, parse_eta, parse_steps, reported_errors


class Sampler(StrEnum):
    leaf = "leaf"
    energy = "energy"


def _floats(text: str, option: str) -> list[float]:
    try:
        vals = [float(p) for p in str(text).split(",")]
    except ValueError:
        raise CliInputError(f"{option}: cannot read {text!r}; give comma-separated numbers, e.g. 0.5,0.2,1") from None
    if not all(np.isfinite(vals)):
        raise CliInputError(f"{option}: the numbers must be finite")
    return vals


def _read_input(path: Path):
    """``(X, b or None, eta or None)`` from a CSV or NPZ file."""
    if not path.exists():
        raise CliInputError(f"--input: no such file: {path}")
    b = eta = None
    if path.suffix.lower() == ".npz":
        try:
            with np.load(path) as d:
                if "X" not in d:
                    raise CliInputError(f"--input: {path} has no array 'X' (the initial states, shape (B, 3N))")
                X = np.array(d["X"], dtype=float)
                b = np.array(d["b"]) if "b" in d else None
                eta = np.array(d["eta"]) if "eta" in d else None
        except (OSError, ValueError) as exc:
            raise CliInputError(f"--input: cannot read {path} as NPZ: {exc}") from None
    else:
        try:
            X = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
        except ValueError as exc:
            raise CliInputError(f"--input: cannot read {path} as CSV of numbers: {exc}") from None
    if X.ndim != 2 or X.shape[0] == 0 or X.shape[1] == 0 or X.shape[1] % 3:
        raise CliInputError(
            f"--input: the states must form a (B, 3N) table (one state y_0, y_1, ... per row, 3N numbers); "
            f"got shape {X.shape}"
        )
    return X, b, eta


@app.command("ensemble")
def ensemble_command(
    input: Annotated[
        Path | None,
        typer.Option(
            "--input", help="initial states: CSV (one state per row) or NPZ (array X, optional per-orbit b and eta)"
        ),
    ] = None,
    sample: Annotated[
        Sampler | None,
        typer.Option(
            "--sample",
            help="draw the initial states: on a leaf (--casimirs) or on the energy shell H_2/2 = E (--energy)",
        ),
    ] = None,
    orbits: Annotated[int, typer.Option("--orbits", help="number of sampled orbits")] = 100,
    seed: Annotated[int, typer.Option("--seed", help="seed of the sampler")] = 0,
    n: Annotated[int, typer.Option("--n", help="jet order N of the sampled states")] = 3,
    casimirs: Annotated[str | None, typer.Option("--casimirs", help="C_1,...,C_N of the leaf (C_N > 0)")] = None,
    energy: Annotated[float | None, typer.Option("--energy", help="energy E of the shell H_2/2 = E")] = None,
    scale: Annotated[float, typer.Option("--scale", help="spread of the sampled components")] = 1.0,
    b: Annotated[float, typer.Option("--b", help="field strength b (field b e_3)")] = 1.0,
    eta: Annotated[str, typer.Option("--eta", help="Bäcklund parameter, e.g. 5+0.1i")] = "5+0.1i",
    steps: Annotated[int, typer.Option("--steps", help="number of steps")] = 100,
    save_every: Annotated[int, typer.Option("--save-every", help="keep every k-th state")] = 1,
    output: Annotated[Path | None, typer.Option("--output", help="NPZ file for states, final, drift, nu")] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="Dask scheduler address tcp://host:port (needs jetgaudin[distributed])"),
    ] = None,
    chunk_size: Annotated[int | None, typer.Option("--chunk-size", help="orbits per Dask task")] = None,
    branch: Annotated[Branch, typer.Option("--branch", help="'opposite' gives the inverse map")] = Branch.default,
    show: Annotated[int, typer.Option("--show", help="orbits listed in the drift report")] = 10,
) -> None:
    """Iterate the real two-point Bäcklund map on an ensemble of orbits; report the per-orbit integral drift."""
    import jetgaudin as jg
    from jetgaudin import ensemble as ens

    with reported_errors():
        if (input is None) == (sample is None):
            raise CliInputError("give exactly one of --input FILE and --sample leaf|energy")
        bb = parse_b(b)
        ee = parse_eta(eta)
        steps = parse_steps(steps)
        if save_every < 1:
            raise CliInputError(f"--save-every: must be >= 1, got {save_every}")
        if input is not None:
            X0, b_file, eta_file = _read_input(input)
            bb = bb if b_file is None else b_file
            ee = ee if eta_file is None else eta_file
        else:
            if orbits < 1:
                raise CliInputError(f"--orbits: must be >= 1, got {orbits}")
            if sample is Sampler.leaf:
                if casimirs is None:
                    raise CliInputError("--sample leaf needs --casimirs C_1,...,C_N")
                c = _floats(casimirs, "--casimirs")
                if len(c) != n:
                    raise CliInputError(f"--casimirs: give N = {n} numbers (set N with --n), got {len(c)}")
                X0 = ens.sample_on_leaf(n, c, orbits, seed=seed, scale=scale)
            else:
                if energy is None:
                    raise CliInputError("--sample energy needs --energy E")
                X0 = ens.sample_on_energy_shell(n, bb, energy, orbits, seed=seed, scale=scale)
        t0 = time.perf_counter()
        try:
            res = ens.iterate_ensemble(
                X0,
                bb,
                ee,
                steps,
                save_every=save_every,
                branch=branch.value,
                scheduler=scheduler,
                chunk_size=chunk_size,
            )
        except (jg.SingularStepError, jg.BranchPointError) as exc:
            fail(exc, EXIT_FAILED)
        elapsed = time.perf_counter() - t0
        if output is not None:
            np.savez(
                output,
                states=res.states,
                final=res.final,
                drift=res.drift,
                nu=res.nu,
                b=res.b,
                eta=res.eta,
                steps=res.steps,
                save_every=res.save_every,
                X0=X0,
            )
    _report(res, X0.shape[0], elapsed, output, show)


def _report(res, B, elapsed, output, show):
    from rich.table import Table

    N = res.final.shape[-1] // 3
    names = [f"H_{k}" for k in range(1, N + 1)] + [f"C_{k}" for k in range(1, N + 1)]
    con = console()
    t = Table(
        title=f"relative drift max_n |I(X_n) - I(X_0)| / max(1, |I(X_0)|) (first {min(show, B)} of {B})",
        title_justify="left",
    )
    t.add_column("orbit", justify="right")
    for name in names:
        t.add_column(name, justify="right")
    for i in range(min(show, B)):
        t.add_row(str(i), *[f"{d:.2e}" for d in res.drift[i]])
    con.print(t)
    md = res.max_drift
    rate = B * res.steps / elapsed if elapsed > 0 else float("inf")
    con.print(
        f"{B} orbits x {res.steps} steps in {elapsed:.3f} s ({rate:.3g} orbit-steps/s); "
        f"max drift {md.max():.2e} (orbit {int(np.argmax(md))}), median {np.median(md):.2e}"
    )
    if output is not None:
        con.print(f"saved {res.states.shape[0]} states per orbit to {output}")
