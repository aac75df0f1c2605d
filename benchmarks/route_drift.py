"""Integral drift of the routes of the real two-point map along the Appendix 2 orbit (docs/backlund.md, section 7).

    python benchmarks/route_drift.py                      # NumPy to 10^5 steps, compiled to 10^7 (~1 min)
    python benchmarks/route_drift.py --numpy-max 10000 --compiled-max 100000000

Prints, for each route and step count n, the largest relative drift |I_k(X_n) - I_k(X_0)| / max(1, |I_k(X_0)|) over
the six integrals and that of H_2 (jg.integrals of the saved rows).  Accuracy, not speed: no timings.
"""

from __future__ import annotations

import argparse

import numpy as np

import jetgaudin as jg
from jetgaudin.backlund import kernels

B_FIELD, ETA = 1.0, 5 + 0.1j
X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--numpy-max", type=int, default=10**5, help="longest NumPy run (powers of 10 from 10^3)")
    ap.add_argument("--compiled-max", type=int, default=10**7, help="longest compiled run (powers of 10 from 10^3)")
    return ap


def drift(orbit: np.ndarray) -> tuple[float, float]:
    I = jg.integrals(orbit, B_FIELD)
    d = np.abs(I[-1] - I[0]) / np.maximum(1.0, np.abs(I[0]))
    return float(d.max()), float(d[1])


def main(argv: list[str] | None = None) -> None:
    args = parser().parse_args(argv)
    B = jg.TwoPointBacklund(B_FIELD, ETA)
    nu0 = complex(B.nu1(X0))
    print(f"{'route':18s} {'n':>10s} {'max drift':>10s} {'H_2':>10s}")
    n = 1000
    while n <= max(args.numpy_max, args.compiled_max):
        rows = []
        if n <= args.numpy_max:
            rows.append(("numpy", B.iterate(X0, n, save_every=n, backend="numpy")))
        if n <= args.compiled_max:
            for name, spec in (("compiled generic", False), ("compiled N = 3", True)):
                out, final, _, _ = kernels.iterate_single(X0, B_FIELD, ETA, nu0, False, n, n, specialise=spec)
                rows.append((name, np.stack([X0, final])))
        for name, orbit in rows:
            dmax, dh2 = drift(orbit)
            print(f"{name:18s} {n:10d} {dmax:10.2e} {dh2:10.2e}", flush=True)
        n *= 10


if __name__ == "__main__":
    main()
