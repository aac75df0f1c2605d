"""``jetgaudin ensemble``: iterate the real two-point Bäcklund map on a batch of orbits (private).

Initial data from a file (CSV: one state per row, 3N numbers; NPZ: array ``X`` of shape ``(B, 3N)`` and
optionally per-orbit ``b`` and ``eta``) or from a seeded sampler (``--sample leaf`` with ``--casimirs``,
``--sample energy`` with ``--energy``).  Runs locally on all cores or on a Dask cluster
(``--scheduler tcp://host:port``), streams every k-th state into ``DIR/ensemble.h5`` with checkpoints
(``--resume DIR`` continues an interrupted or killed run bit for bit) and prints the per-orbit drift of
the integrals.  With neither ``--input`` nor ``--sample`` (nor ``--init-from``) it samples the default leaf
``--sample leaf --casimirs 0.4,-0.3,1.5`` (N = 3; :data:`jetgaudin.ensemble.DEFAULT_CASIMIRS`).
No mathematics here: everything comes from :mod:`jetgaudin.ensemble` and
:mod:`jetgaudin.ensemble_recording`.
"""

from __future__ import annotations

import dataclasses
import math
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from .. import run as runlayer
from . import _chains
from ._app import app
from ._common import (
    EXIT_FAILED,
    Branch,
    CheckpointOption,
    CliInputError,
    InitFromOption,
    OverwriteOption,
    ProgressOption,
    ResumeOption,
    SaveEveryOption,
    blame,
    compile_message,
    console,
    fail,
    out_path,
    parse_b,
    parse_count,
    parse_eta,
    parse_steps,
    reported_errors,
    resume_dir,
    route_notice,
    run_with_progress,
    timing_text,
    to_float,
)

#: largest --input file read (a CSV of 10^6 states of N = 3 is ~0.2 GB)
MAX_INPUT_BYTES = 1 << 31


class Sampler(StrEnum):
    leaf = "leaf"
    energy = "energy"


def _floats(text: str, option: str) -> list[float]:
    try:
        vals = [to_float(p, option) for p in str(text).split(",")]
    except ValueError:
        raise CliInputError(f"{option}: cannot read {text!r}; give comma-separated numbers, e.g. 0.5,0.2,1") from None
    if not all(np.isfinite(vals)):
        raise CliInputError(f"{option}: the numbers must be finite")
    return vals


def _read_input(path: Path):
    """``(X, b or None, eta or None)`` from a CSV or NPZ file, memory bounded by the declared shape
    (:mod:`jetgaudin.cli._input`)."""
    from ._input import read_input

    return read_input(path, MAX_INPUT_BYTES)


class EnsembleBackend(StrEnum):
    auto = "auto"
    compiled = "compiled"
    numpy = "numpy"
    gpu = "gpu"


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
    orbits: Annotated[str, typer.Option("--orbits", metavar="INTEGER", help="number of sampled orbits")] = "100",
    seed: Annotated[str, typer.Option("--seed", metavar="INTEGER", help="seed of the sampler (an integer >= 0)")] = "0",
    n: Annotated[int | None, typer.Option("--n", help="jet order N of the states drawn by --sample (one top; a "
                                          "chain's orders come from --sites) [default: 3]")] = None,
    casimirs: Annotated[str | None, typer.Option("--casimirs", metavar="C1,...,CN",
            help="C_1,...,C_N of the leaf (C_N > 0)")] = None,
    energy: Annotated[float | None, typer.Option("--energy", help="energy E of the shell H_2/2 = E")] = None,
    scale: Annotated[float, typer.Option("--scale", help="spread of the sampled components")] = 1.0,
    b: Annotated[str | None, typer.Option("--b", metavar="FLOAT",
            help="field strength b (field b e_3), real, nonzero [default: 1.0; with --init-from a chain: its b]")]
    = None,
    eta: Annotated[str, typer.Option("--eta", metavar="COMPLEX", help="Bäcklund parameter, e.g. 5+0.1i")] = "5+0.1i",
    steps: Annotated[str | None, typer.Option("--steps", metavar="INTEGER",
            help="number of steps [default: 100]")] = None,
    save_every: SaveEveryOption = None,
    init_from_dir: InitFromOption = None,
    out: Annotated[
        str | None,
        typer.Option("--out", help="output directory (ensemble.h5, run.json) [default: ./jetgaudin-ensemble]"),
    ] = None,
    resume: ResumeOption = None,
    overwrite: OverwriteOption = False,
    max_drift: Annotated[
        float | None,
        typer.Option("--max-drift", help="stop as failed when an orbit's relative integral drift exceeds this "
                     f"[default: {runlayer.DEFAULT_MAX_DRIFT:g}]"),
    ] = None,
    checkpoint_seconds: CheckpointOption = 2.0,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="Dask scheduler address tcp://host:port (needs jetgaudin[distributed])"),
    ] = None,
    chunk_size: Annotated[str | None, typer.Option("--chunk-size", metavar="INTEGER",
            help="orbits per Dask task")] = None,
    branch: Annotated[
        Branch | None, typer.Option("--branch", help="'opposite' gives the inverse map; --algebra suN: r = 0..n-1 "
                                      "[default: default]")
    ] = None,
    show: Annotated[int, typer.Option("--show", help="orbits listed in the drift report")] = 10,
    sites: Annotated[str | None, typer.Option("--sites", help=_chains.SITES_HELP + "; states from --input, "
                                              "--init-from or the chain's leaf sampler (--casimirs)")] = None,
    progress: ProgressOption = None,
    family: Annotated[str | None, typer.Option("--family", help=_chains.FAMILY_HELP)] = None,
    gamma: Annotated[str | None, typer.Option("--gamma", help=_chains.GAMMA_HELP)] = None,
    modulus: Annotated[str | None, typer.Option("--modulus", help=_chains.MODULUS_HELP)] = None,
    algebra: Annotated[str | None, typer.Option("--algebra", help=_chains.ALGEBRA_HELP)] = None,
    backend: Annotated[EnsembleBackend | None, typer.Option(
        "--backend", "--kernel", help="'compiled' (Numba kernels on all CPU cores), 'gpu' (one thread per orbit on "
        "an NVIDIA GPU; needs jetgaudin[gpu]), 'numpy' (the reference route, slow) or 'auto' (the route of the smaller "
        "estimated time; the GPU where one is present and the run is large) [default: auto]; --kernel is an alias")] \
        = None,
) -> None:
    """Iterate the real two-point Bäcklund map on an ensemble of orbits, streamed to disk; report the drift."""
    from jetgaudin import ensemble as ens
    from jetgaudin import ensemble_recording as er

    with reported_errors():
        if not 0 <= show <= MAX_SHOW:
            raise CliInputError(f"--show: the number of orbits listed must be between 0 and {MAX_SHOW:,}, got {show}")
        chunk = None if chunk_size is None else parse_count(chunk_size, "--chunk-size", 1)
        with blame("--max-drift"):
            runlayer.HealthLimits(max_drift=runlayer.DEFAULT_MAX_DRIFT if max_drift is None else max_drift)
        with blame("--checkpoint-seconds"):
            runlayer.RunSpec.check_checkpoint_seconds(checkpoint_seconds)
        expect: dict = {}
        if steps is not None:
            expect["steps"] = parse_steps(steps)
        if save_every is not None:
            expect["save_every"] = parse_count(save_every, "--save-every", 1)
        if branch is not None:
            expect["branch"] = branch.value
        if max_drift is not None:
            expect["max_drift"] = max_drift
        if backend not in (None, EnsembleBackend.auto):
            expect["backend"] = backend.value
        if backend is EnsembleBackend.gpu:
            if scheduler is not None:
                raise CliInputError("--backend gpu runs on this machine's GPU; do not give --scheduler")
            import jetgaudin.gpu as jgpu

            jgpu.require("--backend gpu")  # one line naming what is missing (numba-cuda, a driver, a GPU)
        common: dict[str, Any] = dict(max_drift=runlayer.DEFAULT_MAX_DRIFT if max_drift is None else max_drift,
                      checkpoint_seconds=checkpoint_seconds, scheduler=scheduler, chunk_size=chunk,
                      backend=None if backend is None else backend.value)
        if resume is not None:  # as `orbit --resume`: the recorded model, never silently another one
            given = [o for o, v in (("--sites", sites), ("--family", family), ("--gamma", gamma),
                                    ("--modulus", modulus), ("--algebra", algebra), ("--b", b)) if v is not None]
            if given:
                raise CliInputError(f"{given[0]}: a resumed ensemble keeps its recorded model (sites, family, algebra, "
                                    f"b); drop {', '.join(given)} with --resume")
        source = None  # a chain continues as that chain: its sites and family
        if resume is None and sites is None and init_from_dir is not None and str(init_from_dir).strip():
            source = runlayer.read_run(init_from_dir)
            sites = _chains.sites_of(source)
            if sites is not None and b is None and "b" in source.get("map", {}):  # its field (0 for elliptic chains)
                b = repr(float(source["map"]["b"]))
        b = "1.0" if b is None else b
        n = _jet_order(n, resume, sites, input, init_from_dir)
        if resume is not None:
            if input is not None or sample is not None or init_from_dir is not None:
                raise CliInputError("--resume continues a recorded ensemble: do not give --input, --sample or "
                                    "--init-from")
            if out is not None and Path(out).resolve() != Path(resume).resolve():
                raise CliInputError("--out and --resume name different directories; give only --resume DIR")
            out_dir = resume_dir(resume)
            if not (out_dir / runlayer.RUN_JSON).exists():
                raise CliInputError(f"--resume: {out_dir} holds no run.json; not a jetgaudin run directory")
            common.pop("backend")  # a resume keeps the recorded route (checked against --backend: expect)
            res = run_with_progress("ensemble", progress, lambda bar: er.run_ensemble(
                None, out_dir, resume=True, expect=expect, progress=bar, notify=compile_message, **common))
        elif sites is not None:
            out_dir = out_path(out, "jetgaudin-ensemble")
            draw = dict(orbits=orbits, seed=seed, casimirs=casimirs, scale=scale)
            res = _chain_ensemble(sites, input, sample, init_from_dir, scheduler, b, eta, expect, common, out_dir,
                                  overwrite, progress,
                                  _chains.family_kw(sites, family, gamma, source, modulus=modulus, algebra=algebra),
                                  draw)
        else:
            # --family / --gamma / --algebra need --sites
            _chains.family_kw(sites, family, gamma, modulus=modulus, algebra=algebra)
            if sum(x is not None for x in (input, sample, init_from_dir)) > 1:
                raise CliInputError("give at most one of --input FILE, --sample leaf|energy and --init-from DIR")
            bb = parse_b(b)
            ee = parse_eta(eta)
            if input is not None:
                X0, b_file, eta_file = _read_input(input)
                bb = bb if b_file is None else b_file
                ee = ee if eta_file is None else eta_file
            elif init_from_dir is not None:
                X0 = _init_from(init_from_dir)
            else:
                n_orbits = parse_count(orbits, "--orbits", 1)
                s_seed = parse_count(seed, "--seed", 0)
                if sample is None:  # the documented default: the leaf DEFAULT_CASIMIRS (N = 3)
                    sample = Sampler.leaf
                    casimirs = casimirs if casimirs is not None else ",".join(map(str, ens.DEFAULT_CASIMIRS))
                if sample is Sampler.leaf:
                    if casimirs is None:
                        raise CliInputError("--sample leaf needs --casimirs C_1,...,C_N")
                    c = _floats(casimirs, "--casimirs")
                    if len(c) != n:
                        raise CliInputError(f"--casimirs: give N = {n} numbers (set N with --n), got {len(c)}")
                    with blame("--orbits"):
                        _check_memory(n_orbits, 3 * n)
                    with blame("--casimirs"):
                        X0 = ens.sample_on_leaf(n, c, n_orbits, seed=s_seed, scale=scale)
                else:
                    if energy is None:
                        raise CliInputError("--sample energy needs --energy E")
                    with blame("--orbits"):
                        _check_memory(n_orbits, 3 * n)
                    with blame("--energy"):
                        X0 = ens.sample_on_energy_shell(n, bb, energy, n_orbits, seed=s_seed, scale=scale)
            with blame("--input" if input is not None else "--init-from" if init_from_dir is not None else "--eta"):
                spec = er.EnsembleSpec(X0, bb, ee, expect.get("steps", 100), expect.get("save_every", 1),
                                       _chains.su2_branch(expect.get("branch", "default")))
            out_dir = out_path(out, "jetgaudin-ensemble")
            res = run_with_progress("ensemble", progress, lambda bar: er.run_ensemble(
                spec, out_dir, overwrite=overwrite, progress=bar, notify=compile_message, **common))
        _report(res, show)
        if res.failed:
            fail(f"run {res.status} (data up to step {res.last_safe_step} kept in {out_dir})", EXIT_FAILED)


def _jet_order(n: int | None, resume, sites, input, init_from_dir) -> int:
    """``--n`` (default 3), refused in one line where nothing reads it (it was ignored silently: a chain's orders
    come from ``--sites``, those of read states from their file or run)."""
    if n is None:
        return 3
    given = ("--resume" if resume is not None else "--sites" if sites is not None else
             "--input" if input is not None else "--init-from" if init_from_dir is not None else None)
    if given == "--sites":
        raise CliInputError(f"--n: the jet orders of a chain's sites come from --sites (λ:N per site, e.g. "
                            f"--sites 0:{n},1:1); drop --n")
    if given is not None:
        raise CliInputError(f"--n: the jet order of the states of {given} is theirs; drop --n (it sets the order of "
                            "the states --sample draws)")
    if n < 1:
        raise CliInputError(f"--n: the jet order N must be an integer >= 1, got {n}")
    return n


#: the most orbits ``--show`` lists (the drift table; every orbit's drift is in ensemble.h5 and run.json)
MAX_SHOW = 10**6


def _chain_ensemble(sites, input, sample, init_from_dir, scheduler, b, eta, expect, common, out_dir, overwrite,
                    progress, fam=None, draw=None):
    """``ensemble --sites``: the chain's two-point map on the states of ``--input``, ``--init-from`` or the chain's
    leaf sampler (:func:`jetgaudin.ensemble.sample_chain_on_leaf`: ``--casimirs`` M numbers site by site, default
    :func:`jetgaudin.ensemble.default_chain_casimirs`)."""
    from jetgaudin import ensemble as ens

    if sample is Sampler.energy:
        raise CliInputError("--sites: the energy-shell sampler (--sample energy) draws states of one top; a chain "
                            "samples its leaf: --sample leaf [--casimirs C...] (M numbers, site by site)")
    if sum(x is not None for x in (input, sample, init_from_dir)) > 1:
        raise CliInputError("--sites: give at most one of --input FILE, --init-from DIR and --sample leaf")
    bb = _chains.parse_chain_b(b)
    ee = parse_eta(eta, pole_at_zero=False)
    model = _chains.chain_model(sites, bb, **(fam or {}))
    if input is not None:
        X0, b_file, eta_file = _read_input(input)
        if b_file is not None or eta_file is not None:
            raise CliInputError("--sites: per-orbit b and eta in --input are not supported for chains; give --b and "
                                "--eta")
    elif init_from_dir is not None:
        X0 = _init_from(init_from_dir)
    else:  # the chain's leaf sampler (the default, as --sample leaf for one top)
        d = draw or {}
        n_orbits = parse_count(d.get("orbits", "100"), "--orbits", 1)
        s_seed = parse_count(d.get("seed", "0"), "--seed", 0)
        c = None if d.get("casimirs") is None else _floats(d["casimirs"], "--casimirs")
        if model.n_state != 3 * model.M:  # su(n): no leaf sampler; Gaussian states
            X0 = _sun_states(model, d, n_orbits, s_seed)
        elif c is not None and len(c) != model.M:
            raise CliInputError(f"--casimirs: the sites need M = {model.M} numbers, site by site C_1..C_N_i "
                                f"(orders {list(model.orders)}), got {len(c)}")
        if model.n_state == 3 * model.M:
            with blame("--orbits"):
                _check_memory(n_orbits, model.n_state)
            with blame("--casimirs"):
                X0 = ens.sample_chain_on_leaf(model, c, n_orbits, seed=s_seed, scale=d.get("scale", 1.0))
    where = "--input" if input is not None else "--init-from" if init_from_dir is not None else "--casimirs"
    X0 = _chains.check_chain_state(model, X0, where)
    m = _chains.chain_map(model, ee, expect.get("branch", "default"), common.pop("backend", None))
    with blame(where):
        spec = runlayer.RunSpec(m, X0, expect.get("steps", 100), expect.get("save_every", 1),
                                runlayer.HealthLimits(max_drift=common["max_drift"]), csv=False,
                                program="jetgaudin ensemble", checkpoint_seconds=common["checkpoint_seconds"])
    from .. import _fs

    _fs.check_new_run_dir(out_dir, overwrite=overwrite)  # a refusal is one line: before the route notice
    route_notice(m, spec.X0, spec.steps)
    client = None if scheduler is None else ens.dask_client(scheduler)  # one client for the run (the one-body way)
    try:
        if client is not None:  # the orbits split over the cluster (jetgaudin.ensemble.DaskBatch; same bits)
            spec = dataclasses.replace(spec, map=ens.DaskBatch(m, client, common["chunk_size"]))
        return run_with_progress("ensemble", progress, lambda bar: runlayer.start(
            spec, out_dir, overwrite=overwrite, progress=bar, notify=compile_message))
    finally:
        if client is not None and client is not scheduler:
            client.close()


def _sun_states(model, d: dict, n_orbits: int, seed: int) -> np.ndarray:
    """``--algebra suN`` without ``--input``: ``n_orbits`` states ``0.5 · scale · N(0, 1)`` per component (``--seed``);
    su(n) leaves have no sampler (``--casimirs`` is refused in one line)."""
    if d.get("casimirs") is not None:
        raise CliInputError(f"--casimirs: the leaf sampler draws su(2) sites; an {model.algebra.name} ensemble draws "
                            "Gaussian states (--orbits, --seed, --scale) or reads --input FILE")
    with blame("--orbits"):
        _check_memory(n_orbits, model.n_state)
    scale = float(d.get("scale", 1.0))
    return 0.5 * scale * np.random.default_rng(seed).normal(size=(n_orbits, model.n_state))


def _check_memory(orbits: int, n_state: int) -> None:
    """Refuse an ensemble whose states alone would not fit in memory (before anything is allocated)."""
    import os

    from jetgaudin import InvalidParameterError

    need = 8 * orbits * n_state * 4  # the states, the kernel's output and final state, the checkpoint
    try:
        avail = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        avail = 1 << 40
    if need > avail:
        raise InvalidParameterError(f"{orbits} orbits need about {need / 2**30:.3g} GiB, more than this machine's "
                                    f"{avail / 2**30:.3g} GiB; give fewer orbits")


def _init_from(path: str) -> np.ndarray:
    if str(path).strip() == "":
        raise CliInputError("--init-from: empty path; give the directory of a run")
    d = runlayer.load(path, verify=True)  # the checks a resume makes: run.json's digest, the rows' digest
    if len(d.n) == 0:
        raise CliInputError(f"--init-from: {path} holds no saved state")
    X = np.asarray(d.last_state, dtype=float)
    return X[None] if X.ndim == 1 else X


def _report(res, show):
    from rich.table import Table

    B = res.drift.shape[0]
    N = res.drift.shape[1] // 2
    steps = res.spec.steps
    names = res.record.get("integral_names") or runlayer.integral_names(N)
    con = console(**({"width": 12 * (len(names) + 1)} if len(names) > 7 else {}))  # chains: one column per h_(i,m)
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
    con.print(
        f"{B} orbits x {steps} steps: {timing_text(res)}; "
        f"max drift {md.max():.2e} (orbit {int(np.argmax(md))}), median {np.median(md):.2e}" if B else
        f"{B} orbits: nothing to iterate"
    )
    if B:
        _report_quantiles(con, res.drift, names, res.out_dir)
    con.print(f"status: {res.status}; {res.rows} saved rows of {B} states in {res.out_dir / 'ensemble.h5'}")
    if B and math.isfinite(res.step_rate):
        con.print(f"rate: {_rate_line(res)}")


def _rate_line(res) -> str:
    """The session's stepping rate with the fraction of the device's FP64 peak (:mod:`jetgaudin.peak`)."""
    from jetgaudin import peak as pk

    m = res.spec.map
    chain = getattr(m, "model", None) is not None  # a chain's map (a top's: no model; one class for both)
    if m.resolved_backend(res.spec.X0, res.spec.steps).value == "gpu":
        from jetgaudin import gpu

        peak = pk.gpu_peak(gpu.probe()[1])
    else:
        peak = pk.cpu_peak()
    return pk.rate_text(res.step_rate, pk.flops_per_step_of(res.spec.n_state // 3, chain), peak)


def _report_quantiles(con, drift, names, out_dir) -> None:
    """The drift's quantiles over the orbits, per integral (:func:`jetgaudin.ensemble.drift_quantiles`), and the
    histogram figure ``drift_hist.png`` beside the run's files."""
    from rich.table import Table

    from jetgaudin import ensemble as ens
    from jetgaudin.plotting._ensemble import save_drift_histogram

    q = ens.DRIFT_QUANTILES
    table = ens.drift_quantiles(drift, q)
    t = Table(title=f"relative drift over the {drift.shape[0]} orbits: quantiles per integral", title_justify="left")
    t.add_column("quantile", justify="right")
    for name in names:
        t.add_column(name, justify="right")
    for qq, row in zip(q, table, strict=True):
        t.add_row("max" if qq == 1 else f"{100 * qq:g} %", *[f"{d:.2e}" for d in row])
    con.print(t)
    con.print(f"drift histogram: {save_drift_histogram(out_dir, drift, names)}")
