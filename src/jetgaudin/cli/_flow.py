"""``jetgaudin flow``: continuous flows of H_2/2 (Section 4) or of G_η; ``--compare`` with the map (private)."""

from __future__ import annotations

import math
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

import jetgaudin as jg

from .. import run as runlayer
from ..flows import FlowMap
from ..flows import Method as FlowMethod
from . import _chains
from . import _common as cm
from ._app import app


class Hamiltonian(StrEnum):
    interpolating = "interpolating"
    physical = "physical"


class Kernel(StrEnum):
    """The values of ``--backend`` (alias ``--kernel``) on every command with a route (orbit, ensemble, flow)."""

    auto = "auto"
    compiled = "compiled"
    numpy = "numpy"


class Method(StrEnum):
    DOP853 = "DOP853"
    heyoka = "heyoka"
    exact = "exact"
    midpoint = "midpoint"


@app.command()
def flow(
    b: Annotated[str, typer.Option("--b", metavar="FLOAT",
            help="field strength b (field b e_3), real, nonzero")] = str(cm.APPENDIX2_B),
    eta: Annotated[str, typer.Option("--eta", metavar="COMPLEX",
            help="η of G_η (and of the map for --compare)")] = cm.APPENDIX2_ETA,
    steps: Annotated[str, typer.Option("--steps", metavar="INTEGER",
            help="number of samples after t = 0")] = str(cm.APPENDIX2_STEPS),
    init: Annotated[str | None, typer.Option("--init", metavar=_chains.INIT_METAVAR,
            help=_chains.INIT_HELP + " [default: Appendix 2]")] = None,
    hamiltonian: Annotated[
        str,
        typer.Option(
            "--hamiltonian", metavar="NAME|W1,...",
            help="'interpolating': G_η = i ∫ ν dλ from η̄ to η, whose time-1 flow is "
            "the map; 'physical': H_2/2 of eq. (H) (chains: ½Σ(λ_i h_i,1 + h_i,2) and its trigonometric "
            "analogue, docs/families.md); or " + WEIGHTS_HELP,
        ),
    ] = Hamiltonian.interpolating.value,
    dt: Annotated[float, typer.Option("--dt", help="time between samples (1 = one step of the map for G_η)")] = 1.0,
    method: Annotated[
        Method, typer.Option("--method", help="integrator: DOP853 (SciPy), heyoka (Taylor), exact (every step the "
                             "exact time-dt flow: jg.ExactFlow, jg.ChainExactFlow) or midpoint (implicit midpoint "
                             "rule, every model)")
    ] = Method.DOP853,
    substeps: Annotated[int, typer.Option("--substeps", help="--method exact: exact sub-steps per step (for a dt "
                                                             "larger than the leaf's largest feasible step)")] = 1,
    rtol: Annotated[float, typer.Option("--rtol", help="integrator tolerance (relative and absolute)")] = 1e-12,
    compare: Annotated[
        bool,
        typer.Option(
            "--compare",
            help="also iterate the map and report its distance to the flow of G_η at each step (needs --dt 1)",
        ),
    ] = False,
    out: Annotated[str, typer.Option("--out", help="output directory")] = "jetgaudin-flow",
    init_from_dir: Annotated[
        str | None, typer.Option("--init-from", help="start from the last saved state of this run directory")
    ] = None,
    overwrite: cm.OverwriteOption = False,
    progress: cm.ProgressOption = None,
    no_plots: cm.NoPlotsOption = False,
    sites: Annotated[str | None, typer.Option("--sites", help=_chains.SITES_HELP + "; the flow of the chain's G_η")
                     ] = None,
    family: Annotated[str | None, typer.Option("--family", help=_chains.FAMILY_HELP)] = None,
    gamma: Annotated[str | None, typer.Option("--gamma", help=_chains.GAMMA_HELP)] = None,
    modulus: Annotated[str | None, typer.Option("--modulus", help=_chains.MODULUS_HELP)] = None,
    algebra: Annotated[str | None, typer.Option("--algebra", help=_chains.ALGEBRA_HELP)] = None,
    kernel: Annotated[
        Kernel, typer.Option("--backend", "--kernel",
                             help="the route of --method exact on a top or an su(3) chain: 'compiled' (Numba kernels), "
                             "'numpy' (reference) or 'auto' (compiled); the other methods have one route (NumPy/SciPy, "
                             "heyoka) and refuse 'compiled'; --kernel is an alias")
    ] = Kernel.auto,
) -> None:
    """Integrate the continuous flow of G_η (default) or of H_2/2 from the same inputs as `orbit`.

    Writes into --out: flow.csv / flow.h5 (columns t, y_0, y_1, ...), figure1.png, figure2.png,
    integrals.png (a chain, --sites: chain_y0.png, chain_integrals.png), run.json; with --compare also
    orbit.csv / orbit.h5 (the map), compare.csv (n, |X_map(n) − X_flow(n)|), compare_drift.png and
    compare_distance.png, the orbit drawn as points over the flow drawn as lines.
    """
    con = cm.console()
    with cm.reported_errors():
        bf = cm.parse_b(b) if sites is None else _chains.parse_chain_b(b)
        eta_c = cm.parse_eta(eta, pole_at_zero=sites is None)
        n_steps = cm.parse_steps(steps)
        if init_from_dir is not None:
            from ._orbit import init_from

            if init is not None:
                raise cm.CliInputError("--init and --init-from both give the starting state; give one of them")
            X0 = init_from(init_from_dir)[0]
        else:
            X0 = np.array(cm.parse_init(cm.APPENDIX2_INIT if init is None else init,
                                        multiple=3 if algebra is None else 1))  # su(n): checked below
        N = len(X0) // 3
        fam = _chains.family_kw(sites, family, gamma, modulus=modulus, algebra=algebra)
        model = None if sites is None else _chains.chain_model(sites, bf, **fam)
        if model is not None:
            X0 = _chains.check_chain_state(model, X0, "--init" if init_from_dir is None else "--init-from")
        else:
            cm.check_state_scale(X0, bf)
        kind, weights = parse_hamiltonian(hamiltonian, X0, bf, model)
        hamiltonian = Hamiltonian(kind) if kind != "weights" else "weights"
        from ..flows import RTOL_FLOOR

        if not (RTOL_FLOOR <= rtol < 1):  # below the machine epsilon an adaptive method never meets it
            raise cm.CliInputError(f"--rtol: must be in [{RTOL_FLOOR:.3g}, 1) (below, no double-precision step "
                                   f"meets it), got {rtol}")
        if compare and hamiltonian is not Hamiltonian.interpolating:
            raise cm.CliInputError("--compare compares the map with the flow of G_η: use --hamiltonian interpolating")
        if compare and dt != 1.0:
            raise cm.CliInputError("--compare needs --dt 1 (one step of the map is the time-1 flow of G_η)")
        with cm.blame("--eta"):
            if model is not None:
                B = _chains.chain_map(model, eta_c, "default", "numpy")  # the chain map's rules for eta
                if hamiltonian is Hamiltonian.interpolating:
                    weights = model.interpolating_weights(X0, eta_c)
            else:
                B = jg.TwoPointBacklund(bf, eta_c)  # the map's rules for eta (Im eta = 0: G_eta = 0, refused)
                if hamiltonian is Hamiltonian.interpolating:
                    weights = jg.interpolating_flow_hamiltonian(X0, bf, eta_c).weights
        H = integral_hamiltonian(weights, N, bf, model)
        with cm.blame("--dt"):
            fm = _flow_map(H, dt, method, rtol, substeps, X0, model, kernel.value)
        with cm.blame("--init"):
            spec = runlayer.RunSpec(fm, X0, n_steps, 1, runlayer.HealthLimits(float("inf"), float("inf")),
                                    program="jetgaudin flow")
        out_dir = cm.out_path(out, "jetgaudin-flow")
        res = cm.run_with_progress("flow", progress, lambda bar: runlayer.start(
            spec, out_dir, overwrite=overwrite, progress=bar, notify=cm.compile_message))
        files = list(res.files)
        names = res.record.get("integral_names") or runlayer.integral_names(N)

        def extras():
            written, extra = [], {"inputs_cli": {"b": bf, "eta": [eta_c.real, eta_c.imag], "hamiltonian":
                                                 str(hamiltonian), "dt": dt, "method": method.value, "rtol": rtol,
                                                 "compare": compare}}
            data = runlayer.load(out_dir)
            t = data.n * dt
            orbit_X = None
            if compare:
                from .. import _fs
                from ..recording import write_table

                orbit_X = B.iterate(X0, n_steps)
                written += write_table(out_dir, "orbit", np.arange(n_steps + 1), orbit_X)
                dist = np.linalg.norm(orbit_X - data.X, axis=-1)
                _fs.atomic_write_text(out_dir, "compare.csv", "n,distance\n" + "".join(
                    f"{i},{v:.17g}\n" for i, v in enumerate(dist)))
                written.append(out_dir / "compare.csv")
                extra["compare"] = {"max_distance": float(dist.max()), "final_distance": float(dist[-1]),
                                    "distance": "Euclidean norm of X_map(n) - X_flow(n) in R^"
                                                + ("(3N)" if model is None else f"{len(X0)}")}
            if not no_plots:
                from .. import plotting

                what = ("physical H" if model is not None and hamiltonian is Hamiltonian.physical
                        else HAMILTONIAN_LABEL.get(str(hamiltonian), "H"))
                title = (
                    f"flow of {what}: b = {bf:g}, "
                    f"η = {eta_c.real:g}{eta_c.imag:+g}i, dt = {dt:g}, {n_steps} samples"
                )
                if model is not None:  # --compare: the map's points over the flow, and the top's compare figures
                    written += plotting.save_chain_figures(
                        out_dir, t, data.X, model, xlabel="time t", overlay=orbit_X, overlay_label="map, step n",
                        title=title + (" (dots: map, lines: flow)" if compare else ""))
                    if compare:
                        written += plotting.save_compare_figures(out_dir, t, data.X, np.arange(n_steps + 1), orbit_X,
                                                                 None, title=title, model=model)
                elif compare:
                    written += plotting.save_orbit_figures(out_dir, np.arange(n_steps + 1), orbit_X, bf,
                                                           title=title + " (points: map, lines: flow)",
                                                           overlay=data.X, overlay_label="flow of G_η")
                    written += plotting.save_compare_figures(out_dir, t, data.X, np.arange(n_steps + 1), orbit_X, bf,
                                                             title=title)
                else:
                    written += plotting.save_orbit_figures(out_dir, t, data.X, bf, title=title, xlabel="time t")
            if hamiltonian is Hamiltonian.interpolating:
                extra["G_eta_weights"] = np.asarray(H.weights).tolist()
            elif hamiltonian is Hamiltonian.physical and model is not None:
                extra["physical_weights"] = np.asarray(H.weights).tolist()
            from ..recording import update_run

            update_run(out_dir, files=[Path(f).name for f in files + written], plots=not no_plots, **extra)
            return written, extra

        written, extra = cm.after_run(out_dir, "the figures and tables", extras)
        files += written
        con.print(cm.integrals_table(names, res.integrals0, res.max_drift_abs, res.max_drift_rel,
                                  title=f"integrals along the flow ({hamiltonian}, t = 0 .. {n_steps * dt:g}, "
                                        f"{method.value})"))
        if compare:
            con.print(
                f"distance map - flow of G_η: max {extra['compare']['max_distance']:.3e}, "
                f"at n = {n_steps}: {extra['compare']['final_distance']:.3e}"
            )
        con.print(f"status: {res.status}; {res.rows} rows; {cm.timing_text(res)}")
        con.print("wrote: " + ", ".join(str(f) for f in files))
        if res.failed:
            cm.fail(f"run {res.status} (data up to step {res.last_safe_step} kept in {out_dir})", cm.EXIT_FAILED)


WEIGHTS_HELP = ("the weights 'w_1,...,w_2N' of H = Σ w_m κ_m, κ = (H_1..H_N, C_1..C_N) of ν² (with --sites: the "
                "weights of the h_(i,m) and the family's J or c0, in the order of `jetgaudin info --sites`)")
HAMILTONIAN_LABEL = {"interpolating": "G_η", "physical": "H_2/2"}


def parse_hamiltonian(text: str, X0, b: float, model=None) -> tuple[str, np.ndarray | None]:
    """``--hamiltonian``: ``("interpolating", None)``, ``("physical", weights)`` (H_2/2 of eq. (H); a top only) or
    ``("weights", weights)`` from ``w_1,...`` (2N numbers for a top, 2M for a chain)."""
    name = str(text).strip().lower()
    if name in ("interpolating", "physical"):
        if name == "physical" and model is not None:
            # ν²/2's coefficient at the family's infinity (H_2/2 for one site at 0): jetgaudin.gaudin.physical
            with cm.blame("--hamiltonian"):
                return name, np.asarray(model.physical_hamiltonian().weights, dtype=float)
        return name, None if name == "interpolating" else np.asarray(
            jg.physical_hamiltonian(len(X0) // 3, b).weights, dtype=float)
    n = 2 * (len(X0) // 3) if model is None else int(model.n_integrals)  # a family's extras (J, c0) last
    try:  # any count (not parse_init's 3N: a chain has 2M integrals plus its family's J or c0)
        w = np.array([cm.to_float(p.strip(), "--hamiltonian") for p in str(text).split(",")], dtype=float)
    except ValueError:
        raise cm.CliInputError(f"--hamiltonian: give 'interpolating', 'physical' or {n} comma-separated weights "
                               f"w_1,...,w_{n}, got {text!r}") from None
    if not np.all(np.isfinite(w)):
        raise cm.CliInputError(f"--hamiltonian: the weights must be finite, got {text!r}")
    if len(w) != n:
        raise cm.CliInputError(f"--hamiltonian: the state has {n} integrals; give {n} weights w_1,...,w_{n}, got "
                               f"{len(w)}")
    return "weights", w


def integral_hamiltonian(weights, N: int, b: float, model=None):
    """``Σ w_m κ_m`` of a top (:class:`jetgaudin.IntegralHamiltonian`) or of the chain ``model``."""
    if model is not None:
        return model.hamiltonian(np.asarray(weights, dtype=float))
    return jg.IntegralHamiltonian(b, np.asarray(weights, dtype=float))


def _flow_map(H, dt: float, method: Method, rtol: float, substeps: int, X0, model=None, kernel: str = "auto"):
    """The run's map: the adaptive integrators' FlowMap, or a fixed-step map of the route table
    (:data:`jetgaudin.methods.ROUTES`: ExactFlow / ChainExactFlow, ImplicitMidpoint for every model), whose
    feasibility is checked on X0 before the run (an exact step too large for the leaf names the largest dt and
    the --substeps that makes it feasible; ``jetgaudin orbit --dt`` shares this)."""
    if method is Method.exact:
        return exact_map(H, dt, substeps, X0, model, kernel)
    if method is Method.midpoint:
        from ..methods import method_map

        with cm.blame("--backend"):
            mp = method_map(H, "midpoint", dt, backend=kernel)
        try:  # one step on X0 first, as exact_map does: a dt too large is one line (exit 2), not a failed run
            mp.step(np.asarray(X0, dtype=float))
        except jg.IntegrationError as exc:
            raise cm.CliInputError(f"--dt: {exc}") from None  # names dt and says: give a smaller dt
        return mp
    if kernel == "compiled":
        raise cm.CliInputError(f"--backend compiled: --method {method.value} has no compiled route (an adaptive "
                               "integrator); give --backend auto or numpy, or --method exact")
    if model is not None:
        if method is Method.heyoka and getattr(model, "n", 2) > 3:
            raise cm.CliInputError(f"--method heyoka: built for su(2) and su(3) chains, not {model.algebra.name}; "
                                   "use --method DOP853")
        return _chains.chain_flow_map(H, dt, method.value, rtol)
    return FlowMap(H, dt, FlowMethod.parse(method.value), rtol, rtol)


def exact_map(H, dt: float, substeps: int, X0, model=None, kernel: str = "auto"):
    """:class:`jetgaudin.ExactFlow` (a top) or :class:`jetgaudin.ChainExactFlow` (``model``: a chain) of ``H``
    over ``dt``, solved once on ``X0`` so that an infeasible ``dt`` is one line before the run."""
    if isinstance(model, jg.SunGaudinModel) and model.n != 3:  # issue 32: the exact step is built for su(3)
        raise cm.CliInputError(f"--dt: an exact time step of an {model.algebra.name} chain is built for su(3) only "
                               "(docs/sun.md §5); use `jetgaudin flow --method DOP853`, or `orbit --eta`")
    if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
        raise cm.CliInputError(f"--substeps: must be an integer >= 1, got {substeps!r}")
    fm: jg.ExactFlow | jg.ChainExactFlow | Any
    with cm.blame("--dt"):
        if isinstance(model, jg.SunGaudinModel):  # su(3): SunExactFlow (gaudin/sun_exact.py)
            fm = model.exact_flow(H, dt, substeps, jg.Backend.parse(kernel))
        elif model is not None:
            fm = jg.ChainExactFlow(H, dt, substeps=substeps)
        else:
            fm = jg.ExactFlow(H, dt, substeps, jg.Backend.parse(kernel))
    if model is not None and not isinstance(model, jg.SunGaudinModel) and kernel != "auto":
        with cm.blame("--backend"):  # a family without the compiled solve refuses 'compiled', naming --backend
            fm = fm.with_backend(kernel)
    try:  # su(3), chains: solved here once for the run (bind_run), not again at every chunk; a top: checked here
        bind = getattr(fm, "bind_run", None)
        bound = fm if bind is None else bind(np.asarray(X0, dtype=float))
        if bound is fm:  # binding solved nothing (the top's flow has no per-run set-up)
            fm.parameters(np.asarray(X0, dtype=float))
        fm = bound
    except jg.StepTooLargeError as exc:
        dmax = getattr(exc, "dt_max", None)
        if dmax is None:
            raise cm.CliInputError(f"--dt: {dt:g} is too large for this orbit (no well-conditioned Bäcklund "
                                   "parameters give the exact step); give a smaller --dt") from None
        ratio = abs(dt) / substeps / max(abs(dmax), 1e-300)
        sun = isinstance(model, jg.SunGaudinModel)  # su(3): dmax = dt/k, the first k that solves (not monotone)
        need = (round(ratio) if sun else math.ceil(ratio * 1.01)) * substeps
        what = "a feasible time step (the first dt/k that solves)" if sun else "the largest feasible time step"
        raise cm.CliInputError(f"--dt: {dt:g} is too large for this orbit's leaf: {what} is dt = {dmax:.4g}; give "
                               f"|--dt| <= {abs(dmax) * substeps:.4g} or --substeps {need}") from None
    return fm
