"""``jetgaudin orbit``: iterate the real two-point Bäcklund map (Appendix 2 by default) (private)."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from .. import recording as rec
from . import app
from ._common import (
    APPENDIX2_B,
    APPENDIX2_ETA,
    APPENDIX2_INIT,
    APPENDIX2_STEPS,
    EXIT_FAILED,
    Branch,
    CliInputError,
    check_out_dir,
    check_state_scale,
    console,
    eta_label,
    fail,
    integrals_table,
    parse_b,
    parse_eta,
    parse_init,
    parse_steps,
    refuse_unfinished_run,
    reported_errors,
    resume_dir,
    run_with_progress,
)


class Kernel(StrEnum):
    auto = "auto"
    compiled = "compiled"
    numpy = "numpy"


def figure_title(b, eta, steps, init) -> str:
    return (
        f"(b; Re η, Im η; steps; y_0, y_1, …) = ({b:g}; {eta.real:g}, {eta.imag:g}; {steps}; "
        + ",".join(f"{v:g}" for v in init)
        + ")"
    )


def print_summary(con, res: rec.RunResult, N: int, files) -> None:
    con.print(
        integrals_table(
            rec.integral_names(N),
            res.integrals0,
            res.max_drift_abs,
            res.max_drift_rel,
            title=f"integrals over {res.last_safe_step} steps (saved rows)",
        )
    )
    block = "z" if N == 3 else f"y_{N - 1}"
    con.print(
        f"|{block}| = {res.sphere_radius0:.17g} at n = 0; max ||{block}(n)| - |{block}(0)|| = "
        f"{res.sphere_max_deviation:.3e}"
    )
    con.print(f"max imaginary residue of the real map: {res.max_imag_residue:.3e}")
    con.print(f"status: {res.status}; {res.rows} rows; kernel {res.kernel}; {res.elapsed:.2f} s")
    con.print("wrote: " + ", ".join(str(f) for f in files))


@app.command()
def orbit(
    b: Annotated[
        float | None, typer.Option("--b", help=f"field strength b (field b e_3), nonzero [default: {APPENDIX2_B:g}]")
    ] = None,
    eta: Annotated[
        str | None,
        typer.Option(
            "--eta",
            help=f"Bäcklund parameter η, e.g. 5+0.1i or 5+0.1j; Im η is the time "
            f"step and must be nonzero [default: {APPENDIX2_ETA}]",
        ),
    ] = None,
    steps: Annotated[int | None, typer.Option("--steps", help=f"number of steps [default: {APPENDIX2_STEPS}]")] = None,
    init: Annotated[
        str | None,
        typer.Option(
            "--init",
            help="3N comma-separated numbers y_0, y_1, ... (N inferred), e.g. "
            f"--init={APPENDIX2_INIT} [default: Appendix 2]",
        ),
    ] = None,
    branch: Annotated[
        Branch | None,
        typer.Option(
            "--branch", help="root ν1 = +ν(η) ('default') or −ν(η) ('opposite': the inverse map) [default: default]"
        ),
    ] = None,
    out: Annotated[str | None, typer.Option("--out", help="output directory [default: ./jetgaudin-orbit]")] = None,
    save_every: Annotated[
        int | None, typer.Option("--save-every", help="save every K-th step (and the last) [default: 1]")
    ] = None,
    no_csv: Annotated[bool, typer.Option("--no-csv", help="do not write orbit.csv (orbit.h5 only)")] = False,
    no_plots: Annotated[bool, typer.Option("--no-plots", help="do not draw the figures")] = False,
    resume: Annotated[
        str | None, typer.Option("--resume", help="continue the interrupted or killed run in this directory")
    ] = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="replace an interrupted run in --out instead of refusing")
    ] = False,
    max_drift: Annotated[
        float | None,
        typer.Option(
            "--max-drift",
            help="stop as failed when an integral drifts by more "
            f"than this (relative to max(1, |I_k(0)|)) [default: {rec.DEFAULT_MAX_DRIFT:g}]",
        ),
    ] = None,
    max_imag: Annotated[
        float | None,
        typer.Option(
            "--max-imag",
            help="stop as failed when the imaginary residue of a step "
            f"exceeds this [default: {rec.DEFAULT_MAX_IMAG:g}]",
        ),
    ] = None,
    checkpoint_seconds: Annotated[
        float, typer.Option("--checkpoint-seconds", help="write a checkpoint at most this often (seconds)")
    ] = 1.0,
    kernel: Annotated[
        Kernel | None,
        typer.Option(
            "--kernel",
            help="'compiled' (Numba kernels, fast), 'numpy' (reference route; checks the imaginary residue of every "
            "step) or 'auto' (NumPy for short runs, compiled where it pays off) [default: auto]",
        ),
    ] = None,
    progress: Annotated[
        bool | None,
        typer.Option("--progress/--no-progress", help="progress bar [default: on a terminal, for runs over 1 s]"),
    ] = None,
) -> None:
    """Iterate the real two-point Bäcklund map; with no options, reproduce Appendix 2 of the paper.

    Writes into --out: orbit.csv, orbit.h5, figure1.png (material point x − z and centre of mass z in 3D, with
    the sphere |z| = const), figure2.png (x–y projection), integrals.png and run.json.
    """
    con = console()
    with reported_errors():
        if save_every is not None and save_every < 1:
            raise CliInputError(f"--save-every: must be an integer >= 1, got {save_every}")
        for name, v in (("--max-drift", max_drift), ("--max-imag", max_imag)):
            if v is not None and not (v >= 0):
                raise CliInputError(f"{name}: must be a number >= 0 (inf disables the check), got {v}")
        if not (checkpoint_seconds >= 0) or checkpoint_seconds == float("inf"):
            raise CliInputError(f"--checkpoint-seconds: must be a finite number >= 0, got {checkpoint_seconds}")
        expect = {}
        if b is not None:
            expect["b"] = parse_b(b)
        if eta is not None:
            e = parse_eta(eta)
            expect["eta"] = [e.real, e.imag]
        if steps is not None:
            expect["steps"] = parse_steps(steps)
        if init is not None:
            expect["init"] = parse_init(init)
        if branch is not None:
            expect["branch"] = branch.value
        if save_every is not None:
            expect["save_every"] = save_every
        if no_csv:
            expect["csv"] = False
        if kernel is not None and kernel is not Kernel.auto:
            expect["kernel"] = kernel.value
        if max_drift is not None:
            expect["max_drift"] = max_drift
        if max_imag is not None:
            expect["max_imag"] = max_imag
        options = rec.RecordOptions(
            save_every=save_every or 1,
            csv=not no_csv,
            checkpoint_seconds=checkpoint_seconds,
            kernel=kernel.value if kernel is not None else "auto",
        )
        if resume is not None:
            if out is not None and Path(out).resolve() != Path(resume).resolve():
                raise CliInputError("--out and --resume name different directories; give only --resume DIR")
            out_dir = resume_dir(resume)
            spec = limits = None
            if not (out_dir / rec.RUN_JSON).exists():
                raise CliInputError(f"--resume: {out_dir} holds no run.json; not a jetgaudin run directory")
        else:
            out_dir = check_out_dir(out if out is not None else "jetgaudin-orbit")
            eta_c = parse_eta(eta) if eta is not None else parse_eta(APPENDIX2_ETA)
            if eta_c.imag == 0:
                raise CliInputError(
                    "--eta: Im(eta) = 0 makes the real two-point map the identity (Im eta is its time step); "
                    "give eta with a nonzero imaginary part, e.g. 5+0.1i"
                )
            check_state_scale(expect.get("init", parse_init(APPENDIX2_INIT)), expect.get("b", APPENDIX2_B))
            spec = rec.OrbitSpec(
                b=expect.get("b", APPENDIX2_B),
                eta=eta_c,
                steps=expect.get("steps", APPENDIX2_STEPS),
                X0=tuple(expect.get("init", parse_init(APPENDIX2_INIT))),
                branch=expect.get("branch", "default"),
            )
            limits = rec.HealthLimits(
                max_drift=rec.DEFAULT_MAX_DRIFT if max_drift is None else max_drift,
                max_imag=rec.DEFAULT_MAX_IMAG if max_imag is None else max_imag,
            )
            if not overwrite:
                refuse_unfinished_run(out_dir)
        res = run_with_progress("orbit", progress, lambda bar: rec.run_orbit(
            spec,
            out_dir,
            options=options,
            limits=limits,
            resume=resume is not None,
            expect=expect if resume is not None else None,
            progress=bar,
        ))
        run = rec.read_run(out_dir)
        spec = rec.OrbitSpec.from_json(run["inputs"])
        files = list(res.files)
        if not no_plots and res.rows > 0:
            from .. import plotting

            files += plotting.save_run_figures(out_dir)  # streamed from orbit.h5: constant memory
        rec.update_run(out_dir, files=[Path(f).name for f in files])
        print_summary(con, res, spec.N, files)
        if res.status.startswith("failed"):
            fail(f"run {res.status} (data up to step {res.last_safe_step} kept in {out_dir})", EXIT_FAILED)


def orbit_json_summary(out_dir) -> str:  # pragma: no cover - convenience for scripts
    return json.dumps(rec.read_run(out_dir), indent=1)


_ = (np, eta_label)
