"""``jetgaudin orbit``: iterate the real two-point Bäcklund map (Appendix 2 by default) (private)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from .. import run as runlayer
from . import _chains
from ._app import app
from ._common import (
    APPENDIX2_B,
    APPENDIX2_ETA,
    APPENDIX2_INIT,
    APPENDIX2_STEPS,
    EXIT_FAILED,
    Branch,
    CheckpointOption,
    CliInputError,
    InitFromOption,
    NoPlotsOption,
    OverwriteOption,
    ProgressOption,
    ResumeOption,
    SaveEveryOption,
    after_run,
    blame,
    check_state_scale,
    compile_message,
    console,
    fail,
    integrals_table,
    out_path,
    parse_b,
    parse_count,
    parse_eta,
    parse_init,
    parse_steps,
    reported_errors,
    resume_dir,
    route_notice,
    run_with_progress,
    timing_text,
)
from ._flow import WEIGHTS_HELP, Kernel


def figure_title(b, eta, steps, init) -> str:
    return (
        f"(b; Re η, Im η; steps; y_0, y_1, …) = ({b:g}; {eta.real:g}, {eta.imag:g}; {steps}; "
        + ",".join(f"{v:g}" for v in init)
        + ")"
    )


def print_summary(con, res: runlayer.RunResult, files) -> None:
    N = res.spec.n_state // 3
    con.print(
        integrals_table(
            res.record.get("integral_names") or runlayer.integral_names(N),
            res.integrals0,
            res.max_drift_abs,
            res.max_drift_rel,
            title=f"integrals over {res.last_safe_step} steps (saved rows and chunk ends)",
        )
    )
    labels = getattr(res.spec.map, "state_labels", None)  # a chain: the last site's last block, e.g. s3_y0
    block = labels()[-1].split("^")[0] if callable(labels) else "z" if N == 3 else f"y_{N - 1}"
    con.print(
        f"|{block}| = {float(res.sphere_radius0):.17g} at n = 0; max ||{block}(n)| - |{block}(0)|| = "
        f"{res.sphere_max_deviation:.3e}"
    )
    con.print(f"max imaginary residue of the real map: {res.max_imag_residue:.3e}")
    con.print(f"status: {res.status}; {res.rows} rows; kernel {res.kernel}; {timing_text(res)}")
    con.print("wrote: " + ", ".join(str(f) for f in files))


def init_from(path: str, option: str = "--init-from"):
    """``(state, record)`` of the last safe saved state of a run directory (one state: an orbit, or an ensemble
    of one orbit)."""
    if str(path).strip() == "":
        raise CliInputError(f"{option}: empty path; give the directory of a run")
    d = runlayer.load(path, verify=True)  # the checks a resume makes: run.json's digest, the rows' digest
    if len(d.n) == 0:
        raise CliInputError(f"{option}: {path} holds no saved state")
    X = np.asarray(d.last_state, dtype=float)
    if X.ndim == 2:
        if X.shape[0] != 1:
            raise CliInputError(f"{option}: {path} holds an ensemble of {X.shape[0]} orbits; use "
                                "`jetgaudin ensemble --init-from` (or give one orbit)")
        X = X[0]
    return X, d.record


@app.command()
def orbit(
    b: Annotated[
        str | None,
        typer.Option("--b", metavar="FLOAT",
                help=f"field strength b (field b e_3), real, nonzero [default: {APPENDIX2_B:g}]"),
    ] = None,
    eta: Annotated[
        str | None,
        typer.Option(
            "--eta", metavar="COMPLEX",
            help=f"Bäcklund parameter η, e.g. 5+0.1i or 5+0.1j; Im η is the time "
            f"step and must be nonzero [default: {APPENDIX2_ETA}]",
        ),
    ] = None,
    steps: Annotated[str | None, typer.Option("--steps", metavar="INTEGER",
            help=f"number of steps [default: {APPENDIX2_STEPS}]")] = None,
    init: Annotated[
        str | None,
        typer.Option(
            "--init", metavar=_chains.INIT_METAVAR,
            help=_chains.INIT_HELP + f", e.g. --init={APPENDIX2_INIT} [default: Appendix 2]",
        ),
    ] = None,
    branch: Annotated[
        Branch | None,
        typer.Option(
            "--branch", help="root ν1 = +ν(η) ('default') or −ν(η) ('opposite': the inverse map); --algebra suN: "
            "r = 0..n-1, the r-th largest eigenvalue branch [default: default]"
        ),
    ] = None,
    out: Annotated[str | None, typer.Option("--out", help="output directory [default: ./jetgaudin-orbit]")] = None,
    save_every: SaveEveryOption = None,
    init_from_dir: InitFromOption = None,
    no_csv: Annotated[bool, typer.Option("--no-csv", help="do not write orbit.csv (orbit.h5 only)")] = False,
    no_plots: NoPlotsOption = False,
    resume: ResumeOption = None,
    overwrite: OverwriteOption = False,
    max_drift: Annotated[
        float | None,
        typer.Option(
            "--max-drift",
            help="stop as failed when an integral drifts by more "
            f"than this (relative to max(1, |I_k(0)|)) [default: {runlayer.DEFAULT_MAX_DRIFT:g}]",
        ),
    ] = None,
    max_imag: Annotated[
        float | None,
        typer.Option(
            "--max-imag",
            help="stop as failed when the imaginary residue of a step "
            f"exceeds this [default: {runlayer.DEFAULT_MAX_IMAG:g}]",
        ),
    ] = None,
    checkpoint_seconds: CheckpointOption = 1.0,
    kernel: Annotated[
        Kernel | None,
        typer.Option(
            "--backend", "--kernel",
            help="'compiled' (Numba kernels, fast), 'numpy' (reference route; checks the imaginary residue of every "
            "step) or 'auto' (the route of the smaller estimated time: NumPy for short runs, compiled where it pays "
            "off) [default: auto]; --kernel is an alias",
        ),
    ] = None,
    progress: ProgressOption = None,
    sites: Annotated[str | None, typer.Option("--sites", help=_chains.SITES_HELP)] = None,
    dt: Annotated[str | None, typer.Option(
        "--dt", metavar="FLOAT",
        help="exact time steps: the run's map is the exact time-dt flow of --hamiltonian (jg.ExactFlow; "
             "jg.ChainExactFlow with --sites), either sign; excludes --eta; orbit.csv / orbit.h5 gain the column "
             "t = n dt")] = None,
    hamiltonian: Annotated[str | None, typer.Option(
        "--hamiltonian", metavar="NAME|W1,...",
        help="with --dt: 'physical' (H_2/2 of eq. (H), the default of a top) or " + WEIGHTS_HELP)] = None,
    substeps: Annotated[int | None, typer.Option(
        "--substeps", help="with --dt: exact sub-steps per step (for a dt larger than the leaf's largest feasible "
                           "step) [default: 1]")] = None,
    family: Annotated[str | None, typer.Option("--family", help=_chains.FAMILY_HELP)] = None,
    gamma: Annotated[str | None, typer.Option("--gamma", help=_chains.GAMMA_HELP)] = None,
    modulus: Annotated[str | None, typer.Option("--modulus", help=_chains.MODULUS_HELP)] = None,
    algebra: Annotated[str | None, typer.Option("--algebra", help=_chains.ALGEBRA_HELP)] = None,
) -> None:
    """Iterate the real two-point Bäcklund map; with no options, reproduce Appendix 2 of the paper.

    Writes into --out: orbit.csv, orbit.h5, figure1.png (material point x − z and centre of mass z in 3D, with
    the sphere |z| = const), figure2.png (x–y projection), integrals.png and run.json.  With --sites (a chain of
    more than one site, or one site of order N != 3): chain_y0.png (each site's y_0 in 3D) and
    chain_integrals.png (drift of the h_{i,m}) instead of the figures of the paper.

    With --dt H (instead of --eta): every step is the exact time-H flow of --hamiltonian (default: the physical
    H_2/2), built from commuting Bäcklund maps and a rotation (docs/integrators.md); orbit.csv has the columns
    n, t, y_0, ... and orbit.h5 the dataset t.
    """
    con = console()
    with reported_errors():
        expect: dict = {}
        if b is not None:
            expect["b"] = parse_b(b) if sites is None else _chains.parse_chain_b(b)
        if eta is not None:
            e = parse_eta(eta, pole_at_zero=sites is None)
            expect["eta"] = [e.real, e.imag]
        if steps is not None:
            expect["steps"] = parse_steps(steps)
        if init is not None:
            expect["init"] = parse_init(init, multiple=3 if algebra is None else 1)  # su(n): (n²−1)M, checked below
        if branch is not None:
            expect["branch"] = branch.value
        if save_every is not None:
            expect["save_every"] = parse_count(save_every, "--save-every", 1)
        if no_csv:
            expect["csv"] = False
        if kernel is not None and kernel is not Kernel.auto:
            expect["kernel"] = kernel.value
        with blame("--max-drift"):
            runlayer.HealthLimits(max_drift=runlayer.DEFAULT_MAX_DRIFT if max_drift is None else max_drift)
        with blame("--max-imag"):
            runlayer.HealthLimits(max_imag=runlayer.DEFAULT_MAX_IMAG if max_imag is None else max_imag)
        limits = runlayer.HealthLimits(
            max_drift=runlayer.DEFAULT_MAX_DRIFT if max_drift is None else max_drift,
            max_imag=runlayer.DEFAULT_MAX_IMAG if max_imag is None else max_imag,
        )
        for name, v in (("max_drift", max_drift), ("max_imag", max_imag)):
            if v is not None:
                expect[name] = v
        opts: dict[str, Any] = dict(checkpoint_seconds=checkpoint_seconds)
        timed = _timed_options(dt, hamiltonian, substeps, eta, branch)
        if resume is not None:
            if timed is not None:
                raise CliInputError("--dt, --hamiltonian, --substeps: a resumed run keeps its recorded map; drop "
                                    "them with --resume")
            if out is not None and Path(out).resolve() != Path(resume).resolve():
                raise CliInputError("--out and --resume name different directories; give only --resume DIR")
            if init_from_dir is not None:
                raise CliInputError("--init-from starts a new run; it cannot be combined with --resume")
            if sites is not None or family is not None or gamma is not None or modulus is not None:
                raise CliInputError("--sites: a resumed run keeps its recorded sites; drop --sites with --resume")
            if algebra is not None:
                raise CliInputError("--algebra: a resumed run keeps its recorded algebra; drop --algebra with --resume")
            out_dir = resume_dir(resume)
            if not (out_dir / runlayer.RUN_JSON).exists():
                raise CliInputError(f"--resume: {out_dir} holds no run.json; not a jetgaudin run directory")
            with blame("--checkpoint-seconds"):
                runlayer.RunSpec.check_checkpoint_seconds(checkpoint_seconds)
            res = run_with_progress("orbit", progress, lambda bar: runlayer.resume(
                out_dir, expect=expect, program="jetgaudin orbit", progress=bar, notify=compile_message, **opts))
            plots = not no_plots and res.record.get("plots", True)
        else:
            out_dir = out_path(out, "jetgaudin-orbit")
            defaults: dict[str, Any] = {"b": APPENDIX2_B, "eta": parse_eta(APPENDIX2_ETA), "branch": "default",
                        "init": parse_init(APPENDIX2_INIT)}
            rec = None
            if init_from_dir is not None:
                if init is not None:
                    raise CliInputError("--init and --init-from both give the starting state; give one of them")
                X_last, rec = init_from(init_from_dir)
                defaults["init"] = X_last.tolist()
                m = rec.get("map", {})
                if m.get("kind") in ("two_point", "chain_two_point"):
                    try:
                        defaults.update(b=float(m["b"]), eta=complex(*m["eta"]), branch=str(m["branch"]))
                    except (KeyError, TypeError, ValueError):
                        raise CliInputError(f"--init-from: {init_from_dir}/run.json has no usable map description "
                                            "(b, eta, branch); give --b, --eta and --branch") from None
                elif "b" in m:  # an exact-flow run (orbit --dt, flow --method exact): its field
                    defaults.update(b=m["b"])
                sites = sites if sites is not None else _chains.sites_of(rec)
            X0 = expect.get("init", defaults["init"])
            bb = expect.get("b", defaults["b"])
            ee = complex(*expect["eta"]) if "eta" in expect else defaults["eta"]
            model = None
            if sites is not None:
                model = _chains.chain_model(sites, bb, **_chains.family_kw(sites, family, gamma, rec, modulus=modulus,
                                                                           algebra=algebra))
                X0 = _chains.check_chain_state(model, X0, "--init" if init_from_dir is None else "--init-from")
            else:
                # --family / --gamma / --algebra need --sites
                _chains.family_kw(sites, family, gamma, modulus=modulus, algebra=algebra)
                check_state_scale(X0, bb)
            if timed is not None:
                m = _exact(timed, np.array(X0, dtype=float), bb, model, kernel)
                opts["stem"] = "orbit"
            elif model is not None:
                m = _chains.chain_map(model, ee, expect.get("branch", defaults["branch"]),
                                      None if kernel is None else kernel.value)
            else:
                with blame("--eta"):
                    m = _two_point(bb, ee, expect.get("branch", defaults["branch"]), kernel)
            with blame("--init" if init_from_dir is None else "--init-from"):
                spec = runlayer.RunSpec(m, np.array(X0, dtype=float), expect.get("steps", APPENDIX2_STEPS),
                                        expect.get("save_every", 1), limits, csv=not no_csv, program="jetgaudin orbit",
                                        **opts)
            from .. import _fs

            _fs.check_new_run_dir(out_dir, overwrite=overwrite)  # a refusal is one line: before the route notice
            route_notice(spec.map, spec.X0, spec.steps)
            res = run_with_progress("orbit", progress, lambda bar: runlayer.start(
                spec, out_dir, overwrite=overwrite, record={"plots": not no_plots}, progress=bar,
                notify=compile_message))
            plots = not no_plots
        files = list(res.files)

        def figures():
            written = []
            if plots and res.rows > 0:
                from .. import plotting

                model = getattr(res.spec.map, "model", None)
                if model is not None and _chains.multi_site(model):
                    from .. import plotting

                    data = runlayer.load(out_dir)
                    m = res.spec.map.describe()
                    sites_text = ", ".join(f"{p:g}:{N}" for p, N in model.sites)
                    bt = m['b'] if isinstance(m['b'], list) else format(m['b'], 'g')  # su(n): a vector field
                    step = (f"η = {m['eta'][0]:g}{m['eta'][1]:+g}i" if "eta" in m  # an exact flow (--dt): its dt
                            else f"dt = {m['dt']:g}")
                    title = f"chain (λ:N) = {sites_text}; b = {bt}; {step}; {res.spec.steps} steps"
                    written = plotting.save_chain_figures(out_dir, data.n, data.X, model, title=title)
                else:
                    written = plotting.save_run_figures(out_dir)  # streamed from orbit.h5: constant memory
            from ..recording import update_run

            update_run(out_dir, files=[Path(f).name for f in files + written], plots=bool(plots))
            return written

        files += after_run(out_dir, "the figures", figures)
        print_summary(con, res, files)
        if res.failed:
            fail(f"run {res.status} (data up to step {res.last_safe_step} kept in {out_dir})", EXIT_FAILED)


def _timed_options(dt, hamiltonian, substeps, eta, branch) -> tuple[float, str, int] | None:
    """``(dt, hamiltonian, substeps)`` of ``--dt`` (exact time steps), or ``None`` (the map of ``--eta``)."""
    if dt is None:
        if hamiltonian is not None or substeps is not None:
            raise CliInputError("--hamiltonian and --substeps go with --dt (exact time steps); give --dt H")
        return None
    if eta is not None:
        raise CliInputError("--dt and --eta exclude each other: --dt H steps the exact time-H flow of --hamiltonian, "
                            "--eta iterates the Bäcklund map B_η; give one of them")
    if branch is not None:
        raise CliInputError("--branch goes with --eta; an exact time step takes the default roots (the inverse step "
                            "is --dt with the opposite sign)")
    try:
        h = float(dt)
    except ValueError:
        raise CliInputError(f"--dt: not a number: {dt!r}; give the time step, e.g. --dt 0.05") from None
    if not math.isfinite(h) or h == 0:
        raise CliInputError(f"--dt: must be finite and nonzero (either sign), got {dt!r}")
    return h, "physical" if hamiltonian is None else hamiltonian, 1 if substeps is None else substeps


def _exact(timed: tuple[float, str, int], X0: np.ndarray, b: float, model, kernel):
    """The run's map of ``--dt``: the same construction as ``jetgaudin flow --method exact``."""
    from ._flow import Method, _flow_map, integral_hamiltonian, parse_hamiltonian

    dt, text, substeps = timed
    if model is not None and text == "physical":
        n = int(model.n_integrals)  # su(2): 2M (+ the family's J or c0); su(3): 5M
        raise CliInputError(f"--hamiltonian: a chain (--sites) has no physical default; give its {n} weights "
                            f"'w_1,...,w_{n}' (the integrals in the order of `jetgaudin info --sites`)")
    _, weights = parse_hamiltonian(text, X0, b, model)
    if weights is None:
        raise CliInputError("--hamiltonian: 'interpolating' is G_η of --eta, whose time-1 flow is the map itself: "
                            "run `jetgaudin orbit --eta` instead, or give 'physical' or weights with --dt")
    H = integral_hamiltonian(weights, len(X0) // 3, b, model)
    return _flow_map(H, dt, Method.exact, 0.0, substeps, X0, model, "auto" if kernel is None else kernel.value)


def _two_point(b: float, eta: complex, branch: str, kernel):
    import jetgaudin as jg

    br = jg.Branch.parse(_chains.su2_branch(branch))
    return jg.TwoPointBacklund(b, eta, br, jg.Backend.parse("auto" if kernel is None else kernel.value))


