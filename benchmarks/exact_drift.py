"""How the integrals' drift of exact steps grows with the number of steps when every step is saved (issue 33).

Round-off that is unbiased grows like √n; a bias (the same error every step) like n.  For an ensemble of orbits we
record, at n = 10^a … 10^b steps, each orbit's largest relative drift ``max_{m ≤ n} max_k |I_k(X_m) − I_k(X_0)| /
max(1, |I_k(X_0)|)`` over every saved row, and fit the exponent ``p`` of ``drift ~ n^p`` (least squares in log-log) to
the RMS over the orbits and to the ensemble's largest.  Target (issue 33): ``p ≤ 0.65``.

* ``top``: :class:`jetgaudin.ExactFlow` of the twisted top (N = 3, b = 1, the physical Hamiltonian), dt = 0.1, orbits
  the Appendix-2 state scaled by 0.9–1.1 and rotated; runs of ``advance(X, None, chunk, 1)`` (every row returned,
  as ``solve``), the parameters solved again at the start of every chunk (as the run layer does).
* ``chain``: :class:`jetgaudin.ChainExactFlow` of a rational Lagrange chain (sites 0, 1.5; orders 2, 2), dt = 0.01,
  runs of 10^4 steps (its parameter solve costs ~60 ms per orbit).

``python benchmarks/exact_drift.py top 64 6`` (orbits, largest power of ten).  Prints one table per model.
"""

from __future__ import annotations

import sys
import time

import numpy as np

import jetgaudin as jg


def _fit(n: np.ndarray, d: np.ndarray) -> float:
    return float(np.polyfit(np.log(n), np.log(d), 1)[0])


def measure(flow, integrals, X0: np.ndarray, top: int, chunk: int, start: int = 3) -> dict:
    marks = [10 ** a for a in range(start, top + 1)]
    I0 = integrals(X0)
    scale = np.maximum(1.0, np.abs(I0))
    worst = np.zeros(len(X0))
    X = X0.copy()
    done, out = 0, {}
    t0 = time.perf_counter()
    while done < marks[-1]:
        adv = flow.advance(X, None, chunk, 1)
        rows = adv.rows
        d = np.abs(integrals(rows.reshape(-1, X.shape[-1])).reshape(rows.shape[:2] + (-1,)) - I0) / scale
        run = np.maximum(np.maximum.accumulate(d.max(axis=2), axis=0), worst)  # (chunk, B): the worst so far
        for m in marks:
            if done < m <= done + chunk:
                out[m] = run[m - done - 1].copy()
        worst = run[-1]
        X = adv.X
        done += chunk
    n = np.array(marks, dtype=float)
    rms = np.array([np.sqrt(np.mean(out[m] ** 2)) for m in marks])
    mx = np.array([out[m].max() for m in marks])
    return {"n": n, "rms": rms, "max": mx, "p_rms": _fit(n, rms), "p_max": _fit(n, mx),
            "seconds": time.perf_counter() - t0}


def _orbits(X: np.ndarray, B: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = np.empty((B, X.size))
    for i in range(B):
        th = rng.uniform(0, 2 * np.pi)
        out[i] = jg.exact.rotate_about_field(X * rng.uniform(0.9, 1.1), th)
    return out


def main(which: str = "top", B: int = 64, top: int = 6) -> None:
    if which == "top":
        H = jg.physical_hamiltonian(3, 1.0)
        X0 = _orbits(np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]), B)
        flow = jg.ExactFlow(H, 0.1)
        r = measure(flow, flow.integrals, X0, top, chunk=1000)
    else:
        model = jg.lagrange_chain(1.0, [0.0, 1.5])
        m = np.concatenate([np.arange(1, 2 * n + 1) for n in model.orders])
        w = np.where(m == 2, 0.5, 0.0) + np.where(m == 1, 0.2, 0.0)
        w[model.casimir_mask()] = 0.0
        flow = jg.ChainExactFlow(model.hamiltonian(w), 0.01)
        X0 = _orbits(np.array([0, 0.5, 0, 0, 0, 0.5, 0.3, 0, 0, 0.1, 0.2, 0.0]), B)
        r = measure(flow, flow.integrals, X0, top, chunk=10 ** min(top, 4), start=2)
    print(f"{which}: {B} orbits, every row saved, {r['seconds']:.0f} s")
    for n, a, b in zip(r["n"], r["rms"], r["max"], strict=True):
        print(f"  n = {int(n):>8d}   rms drift {a:.3e}   max drift {b:.3e}")
    print(f"  exponent: rms {r['p_rms']:.3f}, max {r['p_max']:.3f}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "top", *(int(a) for a in sys.argv[2:4]))
