"""Accuracy of the real two-point map next to a branch point of nu (docs/backlund.md, section 5).

Not a speed benchmark: a seeded, documented random sample.  For each of ``--states`` random N = 3 states
(entries standard normal, field b uniform in [0.5, 2], seed ``--seed``) and each branch point r of nu
(``jg.branch_points``) with Im r > 0, the map is evaluated at eta = r + d e^{0.3i} for d = 10^-1 ... 10^-12;
each evaluation is binned by the decade of |nu(eta)| / |ell(eta)| (``|ell| = max(|u|, |v|, |w|)`` at eta) and
records the distance to the inverse ``max|B^-1(B(X)) - X| / max(1, max|X|)`` and the relative drift of the
integrals ``max|I(B(X)) - I(X)| / max(1, max|I(X)|)``.  Points where the branch rule refuses eta (a branch
point on the segment [Re eta, eta]) are counted and skipped.  Prints, per decade, the number of cases, the
median, the 90th percentile and the worst case.

    python benchmarks/branch_point_accuracy.py [--states 200] [--seed 20261123]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import jetgaudin as jg


def measure(states: int, seed: int) -> tuple[dict[int, list[tuple[float, float]]], int]:
    """``({decade: [(inverse distance, integral drift), ...]}, refused)`` for the sample described above."""
    rng = np.random.default_rng(seed)
    bins: dict[int, list[tuple[float, float]]] = {}
    refused = 0
    for _ in range(states):
        X = rng.standard_normal(9)
        b = float(rng.uniform(0.5, 2.0))
        for r in jg.branch_points(X, b):
            if r.imag <= 0:
                continue
            for k in range(1, 13):
                eta = r + 10.0**-k * np.exp(0.3j)
                try:
                    B = jg.TwoPointBacklund(b, eta)
                    Y = B(X)
                    Z = B.inverse()(Y)
                except jg.JetGaudinError:
                    refused += 1
                    continue
                u, v, w = jg.uvw(eta, X, b)
                ratio = abs(jg.nu(eta, X, b)) / max(abs(u), abs(v), abs(w))
                if not 0 < ratio < 1:
                    continue
                dec = -math.ceil(-math.log10(ratio))  # ratio in [10^dec, 10^(dec+1))
                inv = float(np.abs(Z - X).max() / max(1.0, np.abs(X).max()))
                I0, I1 = jg.integrals(X, b), jg.integrals(Y, b)
                drift = float(np.abs(I1 - I0).max() / max(1.0, np.abs(I0).max()))
                bins.setdefault(dec, []).append((inv, drift))
    return bins, refused


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--states", type=int, default=200)
    ap.add_argument("--seed", type=int, default=20261123)
    a = ap.parse_args(argv)
    bins, refused = measure(a.states, a.seed)
    print(f"{a.states} states, seed {a.seed}; refused by the branch rule: {refused}")
    print("|nu|/|ell| in      n   inverse: median    p90    worst   drift: median    worst")
    for dec in sorted(bins, reverse=True):
        inv = np.array([x[0] for x in bins[dec]])
        dr = np.array([x[1] for x in bins[dec]])
        print(f"[1e{dec:+d}, 1e{dec + 1:+d})  {len(inv):5d}   {np.median(inv):12.1e} {np.quantile(inv, 0.9):8.1e} "
              f"{inv.max():8.1e}   {np.median(dr):12.1e} {dr.max():8.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
