"""Benchmark of the su(3) two-point map (issue 32): one orbit of an su(3) chain with two order-1 sites on the compiled
route, against the su(2) chain with the same sites in the same run (the baseline), then the same work two ways: the
compiled map against heyoka integrating the flow of ``G^{(r)}_η`` (whose time-1 flow is the map) over the same time.

Run: ``python benchmarks/bench_sun.py [--steps 1000000] [--work-steps 1000]`` (``--drift``: the drift table of
``docs/sun.md`` only).  Prints the machine, steps/s (thread CPU
time, median of 3, after a warm-up that compiles or loads the kernels), the drift of the integrals over the run, and
for the same-work comparison wall times (median of 3; heyoka's includes building its Taylor integrator) and the
distance between the two orbits.  heyoka's system: ``Ẋ = Π(X) ∇H``, ``H = Σ ω_I h_I`` with ``∇H`` a quadratic
polynomial whose coefficients are read off the exact gradients (``∇H(0)``, ``∇H(e_i)``, ``∇H(e_i + e_j)``).
"""

import argparse
import time

import numpy as np
from bench_chains import machine  # benchmarks/ is sys.path[0]
from harness import timed

import jetgaudin as jg

SITES = [(0.0, 1), (1.0, 1)]
ETA = 0.4 + 0.1j


def rate(B, X, steps):
    return steps / float(np.median(timed(lambda: B.iterate(X, steps, save_every=steps), 3)))


def heyoka_system(H, n):
    """``[(x_i, rhs_i)]`` for heyoka: ``∇H = g0 + A x + Σ_{K≤L} T_{JKL} x_K x_L`` exactly (cubic ``H``)."""
    import heyoka as hy

    g0 = H.gradient(np.zeros(n))
    E = np.eye(n)
    g1 = np.array([H.gradient(E[k]) for k in range(n)])
    gm = np.array([H.gradient(-E[k]) for k in range(n)])
    A = (g1 - gm).T / 2  # odd part: linear
    Q = ((g1 + gm) / 2 - g0).T  # even part: the diagonal quadratic terms T_JKK
    xs = hy.make_vars(*[f"x{i}" for i in range(n)])
    grads = []
    for J in range(n):
        terms = [hy.expression(float(g0[J]))] if g0[J] else []
        terms += [float(A[J, K]) * xs[K] for K in range(n) if A[J, K]]
        terms += [float(Q[J, K]) * xs[K] * xs[K] for K in range(n) if Q[J, K]]
        grads.append(terms)
    for K in range(n):
        for L in range(K + 1, n):
            cross = H.gradient(E[K] + E[L]) - g1[K] - g1[L] + g0  # T_{JKL} x_K x_L at x_K = x_L = 1
            for J in np.nonzero(np.abs(cross) > 0)[0]:
                grads[J].append(float(cross[J]) * xs[K] * xs[L])
    gexpr = [hy.sum(t) if t else hy.expression(0.0) for t in grads]
    c = H.model.structure_constants
    rhs = []
    for i in range(n):
        terms = [float(c[i, J, K]) * xs[K] * gexpr[J] for J in range(n) for K in range(n) if c[i, J, K]]
        rhs.append(hy.sum(terms))
    return list(zip(xs, rhs, strict=True))


def drift_table(steps=10_000):
    """The drift table of docs/sun.md: max |h − h0| / max |h0| after ``steps`` steps, each branch and route."""
    cases = [("su(3), [(0,1),(1,1)]", jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3"), 0.4 + 0.1j),
             ("su(3), [(0,3)]", jg.GaudinModel(0.5, [(0.0, 3)], algebra="su3"), -0.3 + 0.2j),
             ("su(3), [(-1,2),(0.7,1)]", jg.GaudinModel(0.5, [(-1.0, 2), (0.7, 1)], algebra="su3"), 0.3 + 0.25j),
             ("su(4), [(0,1),(1,1)]", jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su4"), 0.4 + 0.1j)]
    for name, m, eta in cases:
        X = 0.5 * np.random.default_rng(8).normal(size=m.n_state)
        I0 = m.integrals(X)
        row = [name]
        for r in range(m.n) if m.n == 3 else [0]:
            for be in ("numpy", "compiled") if m.n == 3 else ("numpy",):
                adv = m.two_point_backlund(eta, branch=r, backend=be).advance(X, None, steps, steps)
                row.append(f"r={r} {be}: {np.max(np.abs(m.integrals(adv.X) - I0)) / np.max(np.abs(I0)):.1e}")
        print(" | ".join(row))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1_000_000)
    p.add_argument("--work-steps", type=int, default=1000)
    p.add_argument("--drift", action="store_true", help="only the drift table of docs/sun.md (10^4 steps)")
    a = p.parse_args()
    print("machine:", machine())
    if a.drift:
        drift_table()
        return
    rng = np.random.default_rng(8)
    m3 = jg.GaudinModel(0.5, SITES, algebra="su3")
    m2 = jg.GaudinModel(0.5, SITES)
    X3, X2 = 0.5 * rng.normal(size=m3.n_state), 0.5 * rng.normal(size=m2.n_state)
    B3 = m3.two_point_backlund(ETA, branch=0, backend="compiled")
    B2 = m2.two_point_backlund(ETA, backend="compiled")
    for B, X in ((B3, X3), (B2, X2)):
        B.iterate(X, 10)  # compile or load
    r3, r2 = rate(B3, X3, a.steps), rate(B2, X2, a.steps)
    print(f"su(3), sites {SITES}: {r3:.3g} steps/s; su(2) chain, same sites: {r2:.3g} steps/s; ratio {r3 / r2:.2f}")
    I0 = m3.integrals(X3)
    Xe = B3.iterate(X3, a.steps, save_every=a.steps)[-1]
    print(f"su(3) drift over {a.steps} steps: max |h - h0| = {np.max(np.abs(m3.integrals(Xe) - I0)):.2e} "
          f"(max |h0| = {np.max(np.abs(I0)):.2g})")
    numpy_rate = rate(B3.with_backend("numpy"), X3, 2000)
    print(f"su(3) NumPy route: {numpy_rate:.3g} steps/s (compiled/NumPy {r3 / numpy_rate:.0f})")
    try:
        import heyoka as hy
    except ImportError:
        print("heyoka not installed: no same-work comparison")
        return
    n, T = a.work_steps, float(a.work_steps)
    H = m3.interpolating_flow_hamiltonian(X3, ETA, 0)
    sysm = heyoka_system(H, m3.n_state)
    orbit = B3.iterate(X3, n)
    t_map = float(np.median(timed(lambda: B3.iterate(X3, n), 3, clock=time.perf_counter)))
    for tol in (None,):  # heyoka's default tolerance (machine epsilon)
        def run(tol=tol):
            ta = hy.taylor_adaptive(sysm, X3.copy(), **({} if tol is None else {"tol": tol}))
            return np.asarray(ta.propagate_grid(np.arange(n + 1, dtype=float))[-1])

        t_hey = float(np.median(timed(run, 3, clock=time.perf_counter)))
        dist = np.max(np.abs(run() - orbit))
        print(f"same work (T = {T:g}): map {t_map:.3g} s, heyoka (tol {tol or 'default'}) {t_hey:.3g} s, "
              f"ratio {t_hey / t_map:.0f}; max distance of the orbits {dist:.1e}")


if __name__ == "__main__":
    main()
