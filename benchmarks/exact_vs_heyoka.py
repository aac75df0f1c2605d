"""Exact steps against heyoka at equal end-state error, T = 100, on the call that returns every row (issue 33).

For each model: ``dt = T/n`` with ``n = ⌈T / (0.9 dt_max)⌉`` (``max_dt`` of the start state); the exact flow's
**every-row** call (``advance(X0, None, n, 1)``: what ``iterate`` runs, the parameter solve included), the user's
call ``jg.solve(H, X0, (0, T), dt=dt, save_every=1)`` (the integrals of every row recorded too), the **end-state**
call (``advance(X0, None, n, n)``) and the parameter solve alone; heyoka's ``propagate_until(T)`` (construction
and JIT outside the time) at the largest tolerance of 1e-16 … 1e-9 whose end-state error is at most the exact
flow's ("equal error"; the default 2.2e-16 when none is), and one decade tighter (the exact flow's error is
round-off: a change of the code can move it across a decade).  Errors against heyoka in long double at tol 1e-19.
CPU time of this thread (``harness.timed``), median (and best) of ``repeat`` after one warm-up call of each.  One
run, one machine: the ratios are comparable, the absolute times on a shared machine are not.

``python benchmarks/exact_vs_heyoka.py [repeat]``
"""

from __future__ import annotations

import importlib.util
import platform
import sys
from pathlib import Path

import numpy as np

import jetgaudin as jg
from jetgaudin.flows import _heyoka_system

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("_bench_harness", HERE / "harness.py")
harness = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = harness
assert _spec.loader is not None
_spec.loader.exec_module(harness)

T = 100.0


def _ta(H, X0, tol, fp=float):
    import heyoka as hy

    if fp is float:
        return hy.taylor_adaptive(_heyoka_system(H, len(X0)), np.asarray(X0, dtype=float), tol=tol)
    return hy.taylor_adaptive(_heyoka_system(H, len(X0)), list(np.asarray(X0, dtype=fp)), tol=fp(tol), fp_type=fp)


def _heyoka_end(ta, X0):
    state0 = np.array(X0, dtype=float)

    def run():
        ta.time = 0.0
        ta.state[:] = state0
        ta.propagate_until(T)
        return ta.state.copy()

    return run


def cases():
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    clebsch = jg.clebsch_top(0.6)
    return {
        "twisted top (N = 3, b = 1)": (jg.physical_hamiltonian(3, 1.0),
                                       np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]), jg.ExactFlow),
        # not the state (0.72, 0.24, -0.54, 0.6, 0, 0.8): its orbit passes near a separatrix, DOP853 at
        # rtol 1e-12 and 1e-13 differ by 7e-6 at T = 100, so no integrator's end state is comparable there
        "Clebsch top (k = 0.6)": (clebsch.hamiltonian([0, 0.7, 0, 0, 1.0]), np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3]),
                                  jg.ChainExactFlow),
        "trigonometric chain, 3 sites": (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]),
                                         np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6]),
                                         jg.ChainExactFlow),
    }


def main(repeat: int = 5) -> None:
    import heyoka  # noqa: F401  (fail early)

    cpu = harness.machine_info().get("Model name", platform.processor() or platform.machine())
    print(f"machine: {cpu}; T = {T:g}; median of {repeat} (thread CPU time)")
    for name, (H, X0, cls) in cases().items():
        dtmax = float(cls(H, 1.0).max_dt(X0))
        n = int(np.ceil(T / (0.9 * dtmax)))
        E = cls(H, T / n)
        grid = np.array([0.0, T], dtype=np.longdouble)
        ref = np.asarray(_ta(H, X0, 1e-19, np.longdouble).propagate_grid(grid)[-1][-1], dtype=float)
        rows = lambda E=E, n=n, X0=X0: E.advance(X0, None, n, 1).X  # noqa: E731
        end = lambda E=E, n=n, X0=X0: E.advance(X0, None, n, n).X  # noqa: E731
        user = lambda H=H, n=n, X0=X0: jg.solve(H, X0, (0.0, T), dt=T / n, save_every=1)  # noqa: E731
        params = lambda E=E, X0=X0: E.parameters(X0)  # noqa: E731
        e_exact = float(np.max(np.abs(end() - ref)))
        e_rows = float(np.max(np.abs(rows() - ref)))
        pick = None
        for tol in (1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15, 1e-16, 2.2e-16):
            fh = _heyoka_end(_ta(H, X0, tol), X0)
            eh = float(np.max(np.abs(fh() - ref)))
            if eh <= e_exact or tol == 2.2e-16:
                pick = (tol, fh, eh)
                break
        assert pick is not None
        tol, fh, eh = pick
        fh10 = _heyoka_end(_ta(H, X0, tol / 10), X0)  # one decade tighter (the exact flow's error is round-off:
        eh10 = float(np.max(np.abs(fh10() - ref)))    # a change of the code can move it across a decade)
        for f in (rows, end, user, params, fh, fh10):  # warm-up (first-use loading of compiled code)
            f()
        times = [harness.timed(f, repeat) for f in (rows, end, user, params, fh, fh10)]
        t_rows, t_end, t_user, t_par, t_hy, t_hy10 = (float(np.median(t)) for t in times)
        b_rows, b_hy = float(np.min(times[0])), float(np.min(times[4]))
        print(f"{name}: {n} steps of {T / n:.4g} (dt_max {dtmax:.4g})\n"
              f"  exact every row {t_rows * 1e3:.3f} ms (best {b_rows * 1e3:.3f}; error {e_rows:.1e}), end state "
              f"{t_end * 1e3:.3f} ms (error {e_exact:.1e}; rows/end {t_rows / t_end:.2f}), jg.solve(save_every=1) "
              f"{t_user * 1e3:.3f} ms, parameter solve {t_par * 1e3:.3f} ms\n"
              f"  heyoka tol {tol:g} {t_hy * 1e3:.3f} ms (best {b_hy * 1e3:.3f}; error {eh:.1e}); heyoka / exact every "
              f"row {t_hy / t_rows:.2f}x (best / best {b_hy / b_rows:.2f}x), heyoka / jg.solve {t_hy / t_user:.2f}x, "
              f"heyoka / end state {t_hy / t_end:.2f}x; at tol {tol / 10:g} {t_hy10 * 1e3:.3f} ms (error {eh10:.1e}): "
              f"/ every row {t_hy10 / t_rows:.2f}x")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:2]))
