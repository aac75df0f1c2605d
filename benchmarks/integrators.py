"""Work–precision of the exact flow (docs/integrators.md): ExactFlow, the plain Bäcklund map (MatchedBacklund),
DOP853 (SciPy), heyoka (Taylor, several tolerances), the implicit midpoint rule and Kahan's map (compiled), on the
N = 3 twisted top (Appendix 2 state, b = 1), the N = 2 Lagrange top, the heavy top with I3 = 2 I1 and the Clebsch
top (jg.kirchhoff_clebsch, a chain: ChainExactFlow over T = 10 only, no plain map or midpoint rule), all in one run
on one machine.

Reference: heyoka in 80-bit long double at tol 1e-19 (error ~1e-17, below double round-off).  Times: CPU time of
the calling thread (time.thread_time), median of ``--repeat``; heyoka's JIT compile is outside its timing (its
integrator is built once per tolerance), ExactFlow's parameter solve is inside.  Writes the figures
docs/figures/integrators_work_precision.png, integrators_energy.png, integrators_step_error.png and prints the
tables of docs/integrators.md.

    python benchmarks/integrators.py            # full run (~10 minutes on 2 vCPU, most in the midpoint rule)
    python benchmarks/integrators.py --quick    # smaller, for a smoke test
    python benchmarks/integrators.py --no-speed # the diagrams only
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

import jetgaudin as jg
from jetgaudin.ensemble import sample_on_leaf
from jetgaudin.exact import MatchedBacklund
from jetgaudin.flows import _heyoka_system
from jetgaudin.midpoint import ImplicitMidpoint

HERE = Path(__file__).resolve().parent
FIG = HERE.parent / "docs" / "figures"
_spec = importlib.util.spec_from_file_location("_bench_harness", HERE / "harness.py")
harness = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = harness
_spec.loader.exec_module(harness)

HEAVY = jg.heavy_top(1.0, 2.0, 0.7)  # I3 = 2 I1 (docs/physical.md): model Hamiltonian ½H_2 + w_1(P0) H_1
P_HEAVY = np.array([0.3, -0.2, 1.5, 0.6, 0.0, 0.8])
CLEBSCH = jg.kirchhoff_clebsch((3.0, 2.2, 0.5), 0.7, 0.3)  # a chain (one elliptic site): ChainExactFlow, NumPy only
P_CLEBSCH = np.array([0.4, -0.3, 0.5, 0.6, 0.2, -0.7])
TOPS = {
    "N = 3 twisted top": (jg.physical_hamiltonian(3, 1.0), np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])),
    "N = 2 Lagrange top": (jg.physical_hamiltonian(2, 1.0), np.array([0.3, -0.5, 0.8, 1.0, 0.2, 0.4])),
    "heavy top I3 = 2 I1": (HEAVY.hamiltonian(P_HEAVY), HEAVY.to_state(P_HEAVY)),
    "Clebsch top": (CLEBSCH.hamiltonian(), CLEBSCH.to_state(P_CLEBSCH)),
}
#: the chain top's exact steps cost ~5 s each (adaptive quadrature): it runs over a shorter time, fewer points
CHAIN_T = 10.0


def _chain(H) -> bool:
    return getattr(H, "route_kind", None) != "top"


def _kahan(H, dt, n):
    from jetgaudin.kahan import KahanMap

    m = KahanMap(H, dt, backend="compiled")
    return lambda X0: m.advance(X0, None, n, n).X


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="shorter times, fewer points")
    p.add_argument("--repeat", type=int, default=3, help="timings per point (median)")
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--no-speed", action="store_true", help="skip the speed ratio and the ensemble rate")
    return p


def _ta(H, X0, tol, fp=float):
    import heyoka as hy

    if fp is float:
        return hy.taylor_adaptive(_heyoka_system(H, len(X0)), np.asarray(X0, dtype=float), tol=tol)
    return hy.taylor_adaptive(_heyoka_system(H, len(X0)), list(np.asarray(X0, dtype=fp)), tol=fp(tol), fp_type=fp)


def reference(H, X0, times):
    """States at ``times`` by heyoka in long double (tol 1e-19)."""
    ta = _ta(H, X0, 1e-19, np.longdouble)
    grid = np.asarray(times, dtype=np.longdouble)
    return np.asarray(ta.propagate_grid(grid)[-1], dtype=float)


def _heyoka_end(H, X0, T, tol):
    ta = _ta(H, X0, tol)
    state0 = np.array(X0, dtype=float)

    def run():
        ta.time = 0.0
        ta.state[:] = state0
        ta.propagate_until(T)
        return ta.state.copy()

    return run


def methods(H, X0, T, quick):
    """``(family, label, parameter, fn)``: ``fn()`` returns the state at T."""
    out = []
    kahan_dts = [0.05, 0.02, 0.01, 0.005, 0.002, 0.001] if not quick else [0.02]
    for dt in kahan_dts:
        n = round(T / dt)
        f = _kahan(H, T / n, n)
        out.append(("Kahan", f"dt={dt:g}", dt, lambda f=f: f(X0)))
    if _chain(H):  # the Clebsch top: ChainExactFlow (no plain Bäcklund map, no midpoint rule for a chain)
        for dt in ([0.3125, 0.2] if not quick else [0.3125]):
            n = round(T / dt)
            m = jg.ChainExactFlow(H, T / n)
            out.append(("ExactFlow", f"dt={dt:g}", dt, lambda m=m, n=n: m.advance(X0, None, n, n).X))
        for tol in ([1e-8, 1e-10, 1e-12, 1e-13] if not quick else [1e-12]):
            out.append(("DOP853", f"rtol={tol:g}", tol,
                        lambda tol=tol: jg.integrate(H, X0, T, rtol=tol, atol=tol).X[-1]))
        for tol in ([1e-9, 1e-12, 1e-15, 2.2e-16] if not quick else [2.2e-16]):
            out.append(("heyoka", f"tol={tol:g}", tol, _heyoka_end(H, X0, T, tol)))
        return out, None
    dtmax = float(jg.ExactFlow(H, 1.0).max_dt(X0))
    for fam, cls in (("ExactFlow", jg.ExactFlow), ("plain Bäcklund map", MatchedBacklund)):
        top = float(cls(H, 1.0).max_dt(X0))
        for dt in [1e-3, 1e-2, 0.05, 0.1, 0.9 * top] if not quick else [1e-2, 0.9 * top]:
            n = int(np.ceil(T / dt))
            m = cls(H, T / n)
            out.append((fam, f"dt={T / n:.3g}", T / n, lambda m=m, n=n: m.advance(X0, None, n, n).X))
    for tol in ([1e-6, 1e-8, 1e-10, 1e-12, 1e-13] if not quick else [1e-8, 1e-12]):
        out.append(("DOP853", f"rtol={tol:g}", tol,
                    lambda tol=tol: jg.integrate(H, X0, T, rtol=tol, atol=tol).X[-1]))
    for tol in ([1e-6, 1e-9, 1e-12, 1e-15, 2.2e-16] if not quick else [1e-9, 2.2e-16]):
        out.append(("heyoka", f"tol={tol:g}", tol, _heyoka_end(H, X0, T, tol)))
    for dt in ([0.1, 0.05, 0.02, 0.01] if not quick else [0.1]):
        n = round(T / dt)
        m = ImplicitMidpoint(H, T / n)
        out.append(("implicit midpoint", f"dt={dt:g}", dt, lambda m=m, n=n: m.advance(X0, None, n, n).X))
    return out, dtmax


def work_precision(quick, repeat, echo=print):
    T = 20.0 if quick else 100.0
    res = {}
    for name, (H, X0) in TOPS.items():
        Tn = min(T, CHAIN_T) if _chain(H) else T
        ref = reference(H, X0, [0.0, Tn])[-1]
        meth, dtmax = methods(H, X0, Tn, quick)
        rows = []
        for fam, label, par, fn in meth:
            slow = _chain(H) and fam == "ExactFlow"
            if not slow:
                fn()  # warm (compile, load)
            times = harness.timed(fn, 1 if slow else repeat)
            err = float(np.max(np.abs(fn() - ref)))
            rows.append((fam, label, par, float(np.median(times)), err))
            echo(f"| {name} | {fam} | {label} | {np.median(times) * 1e3:.3g} ms | {err:.2e} |")
        res[name] = (rows, dtmax, Tn)
    return res


def step_error(quick, echo=print):
    """One-step error of ExactFlow against the long-double reference for dt from 1e-3 to the largest feasible."""
    out = {}
    for name, (H, X0) in TOPS.items():
        if _chain(H):
            continue
        dtmax = float(jg.ExactFlow(H, 1.0).max_dt(X0))
        dts = np.geomspace(1e-3, 0.999 * dtmax, 6 if quick else 16)
        errs = []
        for dt in dts:
            ref = reference(H, X0, [0.0, dt])[-1]
            errs.append(float(np.max(np.abs(jg.ExactFlow(H, dt)(X0) - ref))))
        out[name] = (dts, np.array(errs), dtmax)
        echo(f"{name}: dt_max = {dtmax:.4g}; one-step error for dt in [1e-3, dt_max]: max {max(errs):.2e}, "
             f"median {np.median(errs):.2e}")
    return out


def energy(quick, echo=print):
    """Relative energy error |H(t) − H(0)|/|H(0)| over a long run, sampled every 10 time units."""
    T = 100.0 if quick else 1000.0
    out = {}
    for name, (H, X0) in TOPS.items():
        H0 = float(H(X0))
        curves = {}
        runs: list = [
            ("DOP853 rtol=1e-10", dict(dt=10.0, method="dop853", rtol=1e-10, atol=1e-10)),
            ("heyoka tol=2.2e-16", dict(dt=10.0, method="heyoka", rtol=2.2e-16)),
            ("Kahan dt=0.05", dict(dt=0.05, method="kahan", save_every=20)),
        ]
        if not _chain(H):  # the chain's exact steps (~2-5 s each) are left out of the long run
            dtmax = float(jg.ExactFlow(H, 1.0).max_dt(X0))
            dt = T / np.ceil(T / (0.9 * dtmax))
            every = round(10 / dt) or 1
            runs = [("ExactFlow", dict(dt=dt, save_every=every)),
                    ("plain Bäcklund map", dict(dt=dt, method="bt", save_every=every)), *runs,
                    ("implicit midpoint dt=0.05", dict(dt=0.05, method="midpoint", save_every=200))]
        for fam, kw in runs:
            tr = jg.solve(H, X0, (0, T), **kw)
            e = np.abs(H(tr.X) - H0) / abs(H0)
            curves[fam] = (tr.t, e)
            tenth = max(1, len(e) // 10)
            echo(f"| {name} | {fam} | {e.max():.2e} | {e[-1]:.2e} | first / last tenth: {e[:tenth].max():.2e} / "
                 f"{e[-tenth:].max():.2e} |")
        out[name] = curves
    return out


def ensemble_rate(quick, echo=print):
    """Composite steps per second of ExactFlow on an ensemble (compiled route, all threads, wall time)."""
    B, steps = (2000, 100) if quick else (100_000, 200)
    H = jg.physical_hamiltonian(3, 1.0)
    X = sample_on_leaf(3, [0.4, -0.3, 1.5], B, seed=1)
    E = jg.ExactFlow(H, 0.05)
    E.advance(X[:10], None, 2, 2)  # warm
    t0 = time.perf_counter()
    p = E.parameters(X)
    t1 = time.perf_counter()
    Xb = E._run(X, p.eta, p.theta, p.nu, steps, steps)[1]
    t2 = time.perf_counter()
    assert np.all(np.isfinite(Xb))
    echo(f"ensemble B = {B}, {steps} steps: parameter solve {t1 - t0:.2f} s ({(t1 - t0) / B * 1e6:.1f} µs/orbit), "
         f"stepping {t2 - t1:.2f} s = {B * steps / (t2 - t1):.3g} composite steps/s "
         f"({B * steps / (t2 - t0):.3g} with the solve)")
    return B * steps / (t2 - t1), B * steps / (t2 - t0)


def speed_ratio(repeat, echo=print):
    """The physical flow of the N = 3 top over T = 100 and 1000: ExactFlow (dt = 0.9 dt_max, solve included) against
    heyoka at its default tolerance (propagate only; construction with JIT timed apart)."""
    H, X0 = TOPS["N = 3 twisted top"]
    dtmax = float(jg.ExactFlow(H, 1.0).max_dt(X0))
    out = {}
    for T in (100.0, 1000.0):
        ref = reference(H, X0, [0.0, T])[-1]
        n = int(np.ceil(T / (0.9 * dtmax)))
        E = jg.ExactFlow(H, T / n)
        fe = lambda E=E, n=n: E.advance(X0, None, n, n).X  # noqa: E731
        fe()
        t_build = harness.timed(lambda: _ta(H, X0, 2.2e-16), 1)[0]
        fh = _heyoka_end(H, X0, T, 2.2e-16)
        fh()
        te, th = np.median(harness.timed(fe, repeat)), np.median(harness.timed(fh, repeat))
        ee, eh = np.max(np.abs(fe() - ref)), np.max(np.abs(fh() - ref))
        echo(f"T = {T:g}: ExactFlow ({n} steps of {T / n:.4g}) {te * 1e3:.2f} ms, error {ee:.1e}; heyoka default "
             f"tol {th * 1e3:.2f} ms (+ {t_build * 1e3:.0f} ms to build), error {eh:.1e}; ratio {th / te:.2f}x")
        out[T] = (te, th, ee, eh)
    return out


COLORS = {"ExactFlow": "C0", "plain Bäcklund map": "C1", "DOP853": "C2", "heyoka": "C3", "implicit midpoint": "C4",
          "Kahan": "C5"}


def figures(wp, se, en):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = {"ExactFlow": "o-", "plain Bäcklund map": "x--", "DOP853": "s-", "heyoka": "^-", "implicit midpoint": "d-",
              "Kahan": "v:"}
    fig, axes = plt.subplots(2, 2, figsize=(11, 8.4))
    axes = axes.ravel()
    for ax, (name, (rows, _dtmax, T)) in zip(axes, wp.items(), strict=True):
        for fam, st in styles.items():
            r = [x for x in rows if x[0] == fam]
            if r:
                ax.loglog([x[3] * 1e3 for x in r], [max(x[4], 1e-17) for x in r], st, label=fam, color=COLORS[fam])
        ax.set(title=f"{name}: error at T = {T:g}", xlabel="CPU time (ms)", ylabel="max |X(T) − X_ref(T)|")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIG / "integrators_work_precision.png", dpi=110)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8.0))
    axes = axes.ravel()
    for ax, (name, curves) in zip(axes, en.items(), strict=True):
        for fam, (t, e) in curves.items():
            ax.semilogy(t[1:], np.maximum(e[1:], 1e-17), label=fam, color=COLORS[fam.split(" dt=")[0].split(" rtol")[0]
                                                                               .split(" tol")[0]])
        ax.set(title=f"{name}: relative energy error", xlabel="t", ylabel="|H(t) − H(0)| / |H(0)|")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIG / "integrators_energy.png", dpi=110)
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, (dts, errs, dtmax) in se.items():
        ax.loglog(dts, np.maximum(errs, 1e-17), "o-", label=f"{name} (dt_max = {dtmax:.3g})")
    ax.set(title="ExactFlow: error of one step vs long-double heyoka", xlabel="dt", ylabel="max |error|",
           ylim=(1e-17, 1e-12))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIG / "integrators_step_error.png", dpi=110)


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    info = harness.machine_info()
    print(f"machine: {info.get('Model name', '?')}, {info.get('CPU(s)', '?')} CPUs; load {info.get('loadavg', '?')}")
    se = step_error(args.quick)
    print("| top | method | parameter | CPU time | error at T |\n|---|---|---|---|---|")
    wp = work_precision(args.quick, args.repeat)
    print("| top | method | max energy error | at the end |\n|---|---|---|---|")
    en = energy(args.quick)
    if not args.no_speed:
        speed_ratio(args.repeat)
        ensemble_rate(args.quick)
    if not args.no_figures:
        figures(wp, se, en)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
