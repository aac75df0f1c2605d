"""Whether a change of the exact chain step moved its results at round-off only (issue 33: "η_j, dt_max unchanged to
~1e-15 relative; the same states feasible"): run ``dump`` once per source tree, then ``compare``.

``dump OUT.npy [other]`` (with ``PYTHONPATH`` on the tree's ``src``): for the Clebsch top (k = 0.6: the benchmark's
state of ``exact_vs_heyoka.py`` and 11 perturbed ones; k = 0.3: 5 states) and a 3-site elliptic chain (5 states), or
with ``other`` the trigonometric and rational chains of the tests (6 states each): ``dt_max`` (``max_dt``), the
parameters ``(η_j, θ)`` at ``dt = T/⌈T/(0.9 dt_max)⌉``, whether the solve is feasible at ``f · dt_max`` for ten ``f``
from 0.3 to 4, and the end state at T = 100 (not for the 3-site elliptic and the rational chain: their ``dt_max`` is
small).  ``compare A.npy B.npy``: the largest relative change of ``η``, of ``dt_max`` and of the end state, the largest
change of ``θ``, the number of feasibility differences, and, for the Clebsch states, the end-state errors of both
against heyoka in long double (tol 1e-19), relative to ``max |X(T)|``.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

import jetgaudin as jg

T = 100.0
FRACTIONS = (0.3, 0.7, 0.9, 0.97, 0.995, 1.005, 1.03, 1.2, 2.0, 4.0)
X9 = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])
X6 = np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])


def models(other: bool) -> dict:
    if other:
        trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
        rat = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)])
        return {"trig": (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]), X9, 6, True),
                "rat": (rat.hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2]), X9, 6, False)}
    ell = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.5)
    return {"clebsch": (jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0]), X6, 12, True),
            "clebsch03": (jg.clebsch_top(0.3).hamiltonian([0.1, 0.5, 0, 0.2, 1.0]), X6, 5, True),
            "ell3": (ell.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4]), X9, 5, False)}


def dump(out: str, other: bool = False) -> None:
    rng = np.random.default_rng(7)
    res = {}
    for name, (H, X0, count, end) in models(other).items():
        for s in range(count):
            x = X0 if s == 0 else X0 * (1 + 0.15 * rng.standard_normal(X0.shape))
            E1 = jg.ExactFlow(H, 1.0)
            dmax = float(E1.max_dt(x))
            n = int(np.ceil(T / (0.9 * dmax)))
            while E1._solve(x, T / n) is None:  # a hole below dt_max (feasibility is not monotone): the next n
                n += 1
            E = jg.ExactFlow(H, T / n)
            eta, theta = E.parameters(x)
            feas = np.array([E1._solve(x, f * dmax) is not None for f in FRACTIONS])
            final = E.advance(x, None, n, n).X if end else np.zeros_like(x)
            res[f"{name}_{s}"] = dict(x=x, dmax=dmax, eta=eta, theta=theta, feas=feas, end=final)
    np.save(out, res, allow_pickle=True)  # type: ignore[arg-type]
    print(f"{len(res)} states written to {out}")


def compare(a_path: str, b_path: str) -> None:
    A = np.load(a_path, allow_pickle=True).item()
    B = np.load(b_path, allow_pickle=True).item()
    worst = dict(eta=0.0, theta=0.0, dmax=0.0, end=0.0)
    feas = 0
    for key in A:
        a, b = A[key], B[key]
        worst["eta"] = max(worst["eta"], float(np.max(np.abs(a["eta"] - b["eta"]) / np.abs(a["eta"]))))
        worst["theta"] = max(worst["theta"], abs(a["theta"] - b["theta"]))
        worst["dmax"] = max(worst["dmax"], abs(a["dmax"] - b["dmax"]) / a["dmax"])
        if np.any(a["end"]):
            worst["end"] = max(worst["end"], float(np.max(np.abs(a["end"] - b["end"])) / np.max(np.abs(a["end"]))))
        feas += int(np.sum(a["feas"] != b["feas"]))
    print(f"{len(A)} states: largest change eta {worst['eta']:.2e} (relative), theta {worst['theta']:.2e}, dt_max "
          f"{worst['dmax']:.2e} (relative), end state {worst['end']:.2e} (relative); feasibility differences {feas} "
          f"of {len(A) * len(FRACTIONS)}")
    keys = [k for k in A if k.startswith("clebsch_")]
    if not keys:
        return
    spec = importlib.util.spec_from_file_location("_exact_vs_heyoka", Path(__file__).with_name("exact_vs_heyoka.py"))
    bench = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(bench)  # type: ignore[union-attr]
    H = models(False)["clebsch"][0]
    ea, eb = [], []
    for key in keys:
        x = A[key]["x"]
        grid = np.array([0.0, T], dtype=np.longdouble)
        ref = np.asarray(bench._ta(H, x, 1e-19, np.longdouble).propagate_grid(grid)[-1][-1], dtype=float)
        scale = np.max(np.abs(ref))
        ea.append(np.max(np.abs(A[key]["end"] - ref)) / scale)
        eb.append(np.max(np.abs(B[key]["end"] - ref)) / scale)
    for label, e in (("A", np.array(ea)), ("B", np.array(eb))):
        print(f"Clebsch end-state error against long double ({len(e)} states), {label}: median {np.median(e):.2g}, "
              f"RMS {np.sqrt(np.mean(e ** 2)):.2g}, max {e.max():.2g}")
    print(f"geometric mean of the per-state ratios B/A: {np.exp(np.mean(np.log(np.array(eb) / np.array(ea)))):.3g}")


if __name__ == "__main__":
    if sys.argv[1] == "dump":
        dump(sys.argv[2], len(sys.argv) > 3)
    else:
        compare(sys.argv[2], sys.argv[3])
