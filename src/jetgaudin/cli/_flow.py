"""``jetgaudin flow``: continuous flows of H_2/2 (Section 4) or of G_η; ``--compare`` with the map (private)."""

from __future__ import annotations

import json
import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

import jetgaudin as jg

from .. import recording as rec
from . import app
from ._common import (
    APPENDIX2_B,
    APPENDIX2_ETA,
    APPENDIX2_INIT,
    APPENDIX2_STEPS,
    CliInputError,
    check_out_dir,
    check_state_scale,
    console,
    integrals_table,
    parse_b,
    parse_eta,
    parse_init,
    parse_steps,
    reported_errors,
)


class Hamiltonian(StrEnum):
    interpolating = "interpolating"
    physical = "physical"


class Method(StrEnum):
    DOP853 = "DOP853"
    heyoka = "heyoka"


def _drifts(I):
    I = np.asarray(I, dtype=float)
    d = np.max(np.abs(I - I[0]), axis=0)
    return d, d / np.where(I[0] != 0, np.abs(I[0]), 1.0)


@app.command()
def flow(
    b: Annotated[float, typer.Option("--b", help="field strength b (field b e_3), nonzero")] = APPENDIX2_B,
    eta: Annotated[str, typer.Option("--eta", help="η of G_η (and of the map for --compare)")] = APPENDIX2_ETA,
    steps: Annotated[int, typer.Option("--steps", help="number of samples after t = 0")] = APPENDIX2_STEPS,
    init: Annotated[str, typer.Option("--init", help="3N comma-separated numbers y_0, y_1, ...")] = APPENDIX2_INIT,
    hamiltonian: Annotated[
        Hamiltonian,
        typer.Option(
            "--hamiltonian",
            help="'interpolating': G_η = i ∫ ν dλ from η̄ to η, whose time-1 flow is "
            "the map; 'physical': H_2/2 of eq. (H)",
        ),
    ] = Hamiltonian.interpolating,
    dt: Annotated[float, typer.Option("--dt", help="time between samples (1 = one step of the map for G_η)")] = 1.0,
    method: Annotated[
        Method, typer.Option("--method", help="integrator: DOP853 (SciPy) or heyoka (Taylor)")
    ] = Method.DOP853,
    rtol: Annotated[float, typer.Option("--rtol", help="integrator tolerance (relative and absolute)")] = 1e-12,
    compare: Annotated[
        bool,
        typer.Option(
            "--compare",
            help="also iterate the map and report its distance to the flow of G_η at each step (needs --dt 1)",
        ),
    ] = False,
    out: Annotated[str, typer.Option("--out", help="output directory")] = "jetgaudin-flow",
    no_plots: Annotated[bool, typer.Option("--no-plots", help="do not draw the figures")] = False,
) -> None:
    """Integrate the continuous flow of G_η (default) or of H_2/2 from the same inputs as `orbit`.

    Writes into --out: flow.csv / flow.h5 (columns t, y_0, y_1, ...), figure1.png, figure2.png,
    integrals.png, run.json; with --compare also orbit.csv / orbit.h5 (the map) and compare.csv
    (n, |X_map(n) − X_flow(n)|), the orbit drawn as points over the flow drawn as lines.
    """
    con = console()
    with reported_errors():
        b = parse_b(b)
        eta_c = parse_eta(eta)
        steps = parse_steps(steps)
        X0 = np.array(parse_init(init))
        N = len(X0) // 3
        check_state_scale(X0, b)
        if not (dt > 0) or dt == float("inf"):
            raise CliInputError(f"--dt: must be a finite number > 0, got {dt}")
        if not (0 < rtol < 1):
            raise CliInputError(f"--rtol: must be in (0, 1), got {rtol}")
        if compare and hamiltonian is not Hamiltonian.interpolating:
            raise CliInputError("--compare compares the map with the flow of G_η: use --hamiltonian interpolating")
        if compare and dt != 1.0:
            raise CliInputError("--compare needs --dt 1 (one step of the map is the time-1 flow of G_η)")
        if hamiltonian is Hamiltonian.interpolating and eta_c.imag == 0:
            raise CliInputError("--eta: Im(eta) = 0 makes G_η = 0 (its flow is the identity); give Im(eta) != 0")
        out_dir = check_out_dir(out)
        t0 = time.monotonic()
        if hamiltonian is Hamiltonian.interpolating:
            H = jg.interpolating_flow_hamiltonian(X0, b, eta_c)
        else:
            H = jg.physical_hamiltonian(N, b)
        t = np.arange(steps + 1) * dt
        tr = jg.integrate(H, X0, float(t[-1]), t_eval=t, method=method.value, rtol=rtol, atol=rtol)
        names = rec.integral_names(N)
        d_abs, d_rel = _drifts(tr.integrals)
        files = rec.write_table(out_dir, "flow", t, tr.X, index_name="t")
        run = {
            "program": "jetgaudin flow",
            "version": jg.__version__,
            "inputs": {
                "b": b,
                "eta": [eta_c.real, eta_c.imag],
                "steps": steps,
                "init": X0.tolist(),
                "N": N,
                "hamiltonian": hamiltonian.value,
                "dt": dt,
                "method": method.value,
                "rtol": rtol,
                "compare": compare,
            },
            "status": "completed",
            "integral_names": names,
            "integrals0": tr.integrals[0].tolist(),
            "max_drift_abs": d_abs.tolist(),
            "max_drift_rel": d_rel.tolist(),
        }
        if hamiltonian is Hamiltonian.interpolating:
            run["G_eta_weights"] = np.asarray(H.weights).tolist()
        orbit_X = None
        if compare:
            orbit_X = jg.TwoPointBacklund(b, eta_c).iterate(X0, steps)
            files += rec.write_table(out_dir, "orbit", np.arange(steps + 1), orbit_X)
            dist = np.linalg.norm(orbit_X - tr.X, axis=-1)
            cpath = out_dir / "compare.csv"
            cpath.write_text("n,distance\n" + "".join(f"{i},{v:.17g}\n" for i, v in enumerate(dist)), encoding="utf-8")
            files.append(cpath)
            run["compare"] = {
                "max_distance": float(dist.max()),
                "final_distance": float(dist[-1]),
                "distance": "Euclidean norm of X_map(n) - X_flow(n) in R^(3N)",
            }
        if not no_plots:
            from .. import plotting

            title = (
                f"flow of {'G_η' if hamiltonian is Hamiltonian.interpolating else 'H_2/2'}: b = {b:g}, "
                f"η = {eta_c.real:g}{eta_c.imag:+g}i, dt = {dt:g}, {steps} samples"
            )
            if compare:
                files += plotting.save_orbit_figures(
                    out_dir,
                    np.arange(steps + 1),
                    orbit_X,
                    b,
                    title=title + " (points: map, lines: flow)",
                    overlay=tr.X,
                    overlay_label="flow of G_η",
                )
                files += plotting.save_compare_figures(out_dir, t, tr.X, np.arange(steps + 1), orbit_X, b, title=title)
            else:
                files += plotting.save_orbit_figures(out_dir, t, tr.X, b, title=title, xlabel="time t")
        run["elapsed_seconds"] = time.monotonic() - t0
        run["files"] = [Path(f).name for f in files] + ["run.json"]
        (out_dir / "run.json").write_text(json.dumps(run, indent=1) + "\n", encoding="utf-8")
        con.print(
            integrals_table(
                names,
                tr.integrals[0],
                d_abs,
                d_rel,
                title=f"integrals along the flow ({hamiltonian.value}, t = 0 .. {t[-1]:g}, {method.value})",
            )
        )
        if compare:
            con.print(
                f"distance map - flow of G_η: max {run['compare']['max_distance']:.3e}, "
                f"at n = {steps}: {run['compare']['final_distance']:.3e}"
            )
        con.print("wrote: " + ", ".join(str(f) for f in files + [out_dir / "run.json"]))
