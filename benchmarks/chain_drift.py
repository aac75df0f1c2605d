"""Growth of the integral drift of the chain maps (every family) and the top's map with the number of steps: the
exponent p of ``max drift ~ n^p`` on an ensemble of orbits (issue 33: round-off gives p ≈ 1/2, a bias p ≈ 1).

    python benchmarks/chain_drift.py                           # 64 orbits, compiled to 10^6, NumPy to 10^5
    python benchmarks/chain_drift.py --orbits 64 --compiled-max 100000 --numpy-max 1000
    python benchmarks/chain_drift.py --compiled-max 0 --only rational   # the NumPy route only

For each map and route, the ensemble of ``--orbits`` orbits (states drawn with a fixed seed, scale 0.5) is advanced
to ``n = 10^3, 10^3.5, ...`` steps; at each ``n`` the largest relative drift ``max_k |I_k(X_n) − I_k(X_0)| /
max(1, |I_k(X_0)|)`` over the integrals (the map's ``integrals``) and the orbits is printed, with the exponent of
the least-squares fit of ``log drift`` on ``log n``, and the bias test ``z``: the largest over the integrals of the mean
signed relative change at the last ``n`` over the orbits in units of its standard error (sd / √orbits): a random walk
gives ``|z| ~ 1``, an error of one sign at every step ``|z| ~ √n``.  Accuracy, not speed: no timings.
"""

from __future__ import annotations

import argparse
import platform

import numpy as np

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel

SITES = [(-0.5, 1), (0.4, 2)]
ETA = 1.5 + 0.2j


def maps() -> dict:
    return {
        "rational chain": GaudinModel(1.0, SITES).two_point_backlund(ETA),
        "trigonometric chain": GaudinModel(1.0, SITES, family="trigonometric", gamma=1.0).two_point_backlund(ETA),
        "elliptic chain": GaudinModel(0.0, SITES, family="elliptic", modulus=0.6).two_point_backlund(ETA),
        "top (N = 3)": jg.TwoPointBacklund(1.0, 5 + 0.1j),
    }


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--orbits", type=int, default=64, help="orbits of the ensemble (>= 64 for the issue's fit)")
    ap.add_argument("--compiled-max", type=int, default=10**6, help="longest compiled run (from 10^3)")
    ap.add_argument("--numpy-max", type=int, default=10**5, help="longest NumPy run (from 10^3)")
    ap.add_argument("--only", default="", help="run the maps whose name contains this text")
    return ap


def grid(n_max: int) -> list[int]:
    """``10^3, 10^3.5, ...`` up to ``n_max`` (rounded to integers)."""
    out = []
    e = 3.0
    while round(10**e) <= n_max:
        out.append(int(round(10**e)))
        e += 0.5
    return out


def states(m, orbits: int) -> np.ndarray:
    rng = np.random.default_rng(2026)
    return 0.5 * rng.normal(size=(orbits, m.n_state or 9))


def drift_curve(m, X0: np.ndarray, ns: list[int]) -> tuple[list[float], float]:
    """The largest relative drift over the orbits and integrals at each ``n`` in ``ns``, and the bias score ``z`` at
    the last ``n`` (module docstring)."""
    I0 = m.integrals(X0)
    scale = np.maximum(1.0, np.abs(I0))
    X, carry, done, out, worst = X0, None, 0, [], 0.0
    for n in ns:
        adv = m.advance(X, carry, n - done, n - done)
        X, carry, done = adv.X, adv.carry, n
        change = (m.integrals(X) - I0) / scale
        worst = max(worst, float(np.max(np.abs(change))))  # the running largest drift
        out.append(worst)
    sd = change.std(axis=0) / np.sqrt(len(X0))
    z = np.abs(change.mean(axis=0)) / np.where(sd > 0, sd, np.inf)
    return out, float(np.max(z))


def exponent(ns: list[int], d: list[float]) -> float:
    return float(np.polyfit(np.log(ns), np.log(d), 1)[0]) if len(ns) > 1 else float("nan")


def main(argv=None) -> None:
    args = parser().parse_args(argv)
    print(f"machine: {platform.processor() or platform.machine()}; {args.orbits} orbits; largest relative drift")
    for name, m in maps().items():
        if args.only not in name:
            continue
        X0 = states(m, args.orbits)
        for route, n_max in (("compiled", args.compiled_max), ("numpy", args.numpy_max)):
            ns = grid(n_max)
            if not ns:
                continue
            d, z = drift_curve(m.with_backend(route), X0, ns)
            cells = "  ".join(f"{n:.0e}: {v:.2e}" for n, v in zip(ns, d, strict=True))
            print(f"{name:20s} {route:9s} exponent {exponent(ns, d):5.2f}  bias |z| {z:5.1f}   {cells}", flush=True)


if __name__ == "__main__":
    main()
