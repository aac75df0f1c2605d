"""Which flow the 1000 steps of Appendix 2 follow (docs/backlund.md, section 6): prints the weights of
G_eta = sum_m w_m kappa_m, and the distance of the orbit from the flows of G_eta, of w1 H1 + w2 H2 + w3 H3 and
of w1 H1 + w2 H2 (physical flow plus rotation).  Deterministic (no random input).

    python benchmarks/appendix2_flow.py
"""

from __future__ import annotations

import numpy as np

import jetgaudin as jg
from jetgaudin.hamiltonians import IntegralHamiltonian

X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
B_FIELD, ETA, STEPS = 1.0, 5 + 0.1j, 1000


def main() -> int:
    w = jg.interpolating_weights(X0, B_FIELD, ETA)
    X1 = jg.TwoPointBacklund(B_FIELD, ETA).iterate(X0, STEPS)[-1]
    print("weights w_1..w_6:", np.array2string(w, precision=4))
    print(f"w3/w2 = {w[2] / w[1]:.4f};  2 w2 = {2 * w[1]:.6f}, leading term -2 Im eta/(|b||eta|^2) = "
          f"{-2 * ETA.imag / (abs(B_FIELD) * abs(ETA) ** 2):.6f}")
    print(f"displacement |X_1000 - X_0|: 2-norm {np.linalg.norm(X1 - X0):.3f}, max {np.abs(X1 - X0).max():.3f}")
    for name, keep in (("G_eta (all weights)", 6), ("w1 H1 + w2 H2 + w3 H3", 3), ("w1 H1 + w2 H2", 2)):
        wk = np.zeros(6)
        wk[:keep] = w[:keep]
        Xf = jg.integrate(IntegralHamiltonian(B_FIELD, wk), X0, float(STEPS), rtol=1e-12, atol=1e-12).X[-1]
        print(f"orbit vs flow of {name:22s}: 2-norm {np.linalg.norm(X1 - Xf):.3g}, max {np.abs(X1 - Xf).max():.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
