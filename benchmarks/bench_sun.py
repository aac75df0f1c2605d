"""Benchmark of the su(3) two-point map (issue 32): one orbit of an su(3) chain with two order-1 sites on the compiled
route, against the su(2) chain with the same sites in the same run (the baseline), then the same work two ways: the
compiled map against heyoka integrating the flow of ``G^{(r)}_η`` (whose time-1 flow is the map) over the same time.

Run: ``python benchmarks/bench_sun.py [--steps 1000000] [--work-steps 1000]`` (``--drift``: the drift table of
``docs/sun.md`` only; ``--ensemble``: ensembles on 1 and 2 threads, :func:`ensembles`; ``--checks``: the measured
numbers of the issue's checks, :func:`checks`).  Prints the machine, steps/s (thread CPU
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


def _threads(call, rounds):
    """``{k: (median wall s, median process CPU s)}`` of ``call()`` on ``k = 1, 2`` threads (``numba.set_num_threads``,
    alternating ``rounds`` times): wall time is what a user waits; CPU time, summed over the threads, is the work (on
    a machine shared with other jobs the wall-time gain is bounded by the CPU share the job gets)."""
    import numba

    t: dict = {1: [], 2: []}
    for _ in range(rounds):
        for k in (1, 2):
            numba.set_num_threads(k)
            w0, c0 = time.perf_counter(), time.process_time()
            call()
            t[k].append((time.perf_counter() - w0, time.process_time() - c0))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return {k: tuple(np.median(np.array(v), axis=0)) for k, v in t.items()}


def ensembles(orbits=256, steps=1000, exact_orbits=16, exact_steps=5000, rounds=3):
    """Ensembles on 1 and 2 threads (:func:`_threads`; the load average printed before and after) and heyoka on the
    same flows.

    (1) the map ``B^{(0)}_η``, ``orbits`` × ``steps`` (the kernel's ``run_batch``); heyoka on the same flow: the flow of
    ``G^{(0)}_η`` of each orbit (its weights are the orbit's: one integrator per orbit, ``sun_solve``'s compact-mode
    one at its default tolerance) over ``T = steps``, on two orbits, per orbit, building apart.  (2) the exact flow
    ``SunExactFlow`` of one ``H = Σ w h`` (random weights, ``dt = 0.1``), ``exact_orbits`` × ``exact_steps``: the
    parameter solve (Python, per orbit) and the compiled stepping timed apart; heyoka on the same flow (one
    integrator for all orbits) over ``T = exact_steps · dt`` per orbit, and the distance of the final states."""
    import os

    import numba

    from jetgaudin.gaudin import SunExactFlow
    from jetgaudin.gaudin.sun_solve import heyoka_integrator

    def load():
        return "load average " + ", ".join(f"{v:.1f}" for v in os.getloadavg())

    def line(name, n, t):
        (w1, c1), (w2, c2) = t[1], t[2]
        return (f"{name}: 1 thread {n / w1:.3g}, 2 threads {n / w2:.3g} orbit-steps/s of wall time (x{w1 / w2:.2f}); "
                f"CPU s per 10^6 orbit-steps {1e6 * c1 / n:.3g} / {1e6 * c2 / n:.3g}; {load()}")

    print(f"threads available: {numba.config.NUMBA_NUM_THREADS}; {load()}")
    m = jg.GaudinModel(0.5, SITES, algebra="su3")
    X = 0.5 * np.random.default_rng(8).normal(size=(orbits, m.n_state))
    B = m.two_point_backlund(ETA, branch=0, backend="compiled")
    B.iterate(X[:2], 2)  # compile or load
    t = _threads(lambda: B.advance(X, None, steps, steps), rounds)
    print(line(f"(1) map ensemble {orbits} x {steps}", orbits * steps, t))
    per_map = t[1][0] / orbits
    tol = float(np.finfo(float).eps)
    try:
        import heyoka  # noqa: F401
    except ImportError:
        print("heyoka not installed: no comparison")
        return
    build, prop, dist = [], [], 0.0
    for x in X[:2]:
        t0 = time.perf_counter()
        ta = heyoka_integrator(m.interpolating_flow_hamiltonian(x, ETA, 0), tol)
        t1 = time.perf_counter()
        ta.time, ta.state[:] = 0.0, x
        ta.propagate_until(float(steps))
        prop.append(time.perf_counter() - t1)
        build.append(t1 - t0)
        dist = max(dist, float(np.max(np.abs(ta.state - B.iterate(x, steps, save_every=steps)[-1]))))
    print(f"    heyoka (compact mode, default tol), same flow over T = {steps}: {np.mean(prop):.3g} s per orbit "
          f"propagating, {np.mean(build):.3g} s building; the map on 1 thread {per_map:.3g} s per orbit: ratio "
          f"{np.mean(prop) / per_map:.0f} ({(np.mean(prop) + np.mean(build)) / per_map:.0f} with the build); "
          f"max distance of the final states {dist:.1e}")
    H = m.hamiltonian(np.random.default_rng(3).normal(size=m.n_integrals))
    F = SunExactFlow(H, 0.1, backend="compiled")
    Xe = X[:exact_orbits]
    t0 = time.perf_counter()
    maps = [F._maps(x) for x in Xe]
    t_solve = (time.perf_counter() - t0) / exact_orbits
    F._compiled(Xe[:2], maps[:2], 2, 2)  # compile or load
    t0 = time.perf_counter()
    F._compiled(Xe, maps, 1, 1)
    print(f"    per-orbit set-up of the compiled call (each map's branch rule and constants): "
          f"{(time.perf_counter() - t0) / exact_orbits:.3g} s per orbit")
    t = _threads(lambda: F._compiled(Xe, maps, exact_steps, exact_steps), rounds)
    print(line(f"(2) exact-flow ensemble {exact_orbits} x {exact_steps} (K = {len(maps[0])} maps a step); parameters "
               f"{t_solve:.3g} s per orbit (Python); stepping", exact_orbits * exact_steps, t))
    final = F._compiled(Xe[:4], maps[:4], exact_steps, exact_steps)[1]
    T = exact_steps * 0.1
    t0 = time.perf_counter()
    ta = heyoka_integrator(H, tol)
    t_build = time.perf_counter() - t0
    prop, dist = [], 0.0
    for x, xf in zip(Xe[:4], final, strict=True):
        ta.time, ta.state[:] = 0.0, x
        t0 = time.perf_counter()
        ta.propagate_until(T)
        prop.append(time.perf_counter() - t0)
        dist = max(dist, float(np.max(np.abs(ta.state - xf))))
    per = t[1][0] / exact_orbits
    print(f"    heyoka, same flow over T = {T:g}: {np.mean(prop):.3g} s per orbit ({t_build:.3g} s building, once); "
          f"the exact flow on 1 thread {per:.3g} s per orbit stepping, {per + t_solve:.3g} s with its parameters: "
          f"ratio {np.mean(prop) / per:.1f} (stepping), {np.mean(prop) / (per + t_solve):.2f} (with the solve); max "
          f"distance of the final states {dist:.1e}")


def checks():
    """The measured numbers of the issue's checks in ``docs/sun.md`` (the cases of ``tests/test_sun_model.py`` and
    ``tests/test_sun_maps.py``, which assert the bounds): the largest error of each route, printed."""
    from jetgaudin.gaudin.sun import SunGaudinModel

    sites = [(-1.0, 2), (0.7, 1)]
    eta = 0.3 + 0.25j
    out = {}
    for n in (2, 3):  # r-matrix relation from the Poisson tensor
        m = SunGaudinModel([0.2, -0.3, 0.5, 0.1, 0, 0, 0.2, 0.4][: n * n - 1], [(0.0, 2), (1.3, 1)],
                           algebra=f"su({n})")
        X = 0.7 * np.random.default_rng(7).normal(size=m.n_state)
        lam, mu = 0.4 + 0.3j, -0.7 + 0.2j
        e = np.eye(m.n_state)
        dL = np.array([m.lax_matrix(v, lam) - m.field_matrix for v in e])
        dM = np.array([m.lax_matrix(v, mu) - m.field_matrix for v in e])
        lhs = np.einsum("IJ,Iij,Jkl->ikjl", m.poisson_tensor(X), dL, dM).reshape(n * n, n * n)
        r = 1j * np.einsum("il,kj->ikjl", np.eye(n), np.eye(n)).reshape(n * n, n * n) / (lam - mu)
        S = np.kron(m.lax_matrix(X, lam), np.eye(n)) + np.kron(np.eye(n), m.lax_matrix(X, mu))
        out[f"r-matrix su({n})"] = np.max(np.abs(lhs - (r @ S - S @ r)))
    for n, st in ((3, sites), (3, [(0.0, 3)]), (4, [(0.0, 1), (1.0, 2)])):  # contour integrals
        m = jg.GaudinModel(0.4, st, algebra=f"su({n})")
        X = 0.7 * np.random.default_rng(n).normal(size=m.n_state)
        got = dict(zip(m.integral_labels(), m.integrals(X), strict=True))
        err = 0.0
        for j, (p, N) in enumerate(st):
            z = 0.3 * np.exp(2j * np.pi * np.arange(256) / 256)
            L = m.lax_matrix(X, p + z)
            Lk = np.broadcast_to(np.eye(n), L.shape)
            for k in range(1, n + 1):
                Lk = Lk @ L
                for mm in range(1, k * N + 1) if k >= 2 else ():
                    c = np.mean(np.trace(Lk, axis1=-2, axis2=-1) / k * z**mm)
                    lb = f"h{j + 1},{mm}" if k == 2 else f"t{k}_h{j + 1},{mm}"
                    err = max(err, abs(got[lb] - c) / max(1.0, abs(got[lb])))
        out[f"contour integrals su({n}) {st}"] = err
    for n, st, b in ((3, sites, [0.3, -0.2, 0.5, 0.1, -0.1, 0.1, 0.2, -0.4]), (3, [(0.0, 1), (1.0, 1), (2.5, 1)], 0.8),
                     (4, [(0.0, 1), (1.0, 2)], list(np.random.default_rng(2).normal(size=15)))):  # involution
        m = jg.GaudinModel(b, st, algebra=f"su({n})")
        X = 0.7 * np.random.default_rng(11).normal(size=m.n_state)
        g, P = m.integral_gradients(X), m.poisson_tensor(X)
        out[f"involution su({n}) {st} (relative)"] = np.max(np.abs(g @ P @ g.T)) / (
            np.max(np.abs(g)) ** 2 * np.max(np.abs(P)))
    for n, st in ((3, sites), (3, [(0.0, 3)]), (4, [(-0.5, 1), (0.6, 2)])):  # reality: the imaginary residue
        m = jg.GaudinModel(0.5, st, algebra=f"su({n})")
        X = 0.5 * np.random.default_rng(n).normal(size=m.n_state)
        out[f"imaginary residue su({n}) {st}, every branch"] = max(
            float(m.two_point_backlund(eta, branch=r).step(X)[2]) for r in range(n))
    m = jg.GaudinModel(0.5, sites, algebra="su3")
    X = 0.5 * np.random.default_rng(2).normal(size=m.n_state)
    A, B = m.two_point_backlund(eta, branch=0), m.two_point_backlund(-0.4 + 0.6j, branch=2)
    out["commuting maps su(3)"] = np.max(np.abs(A(B(X)) - B(A(X))))
    for n in (3, 4):
        m = jg.GaudinModel(0.5, sites, algebra=f"su({n})")
        X = 0.5 * np.random.default_rng(1).normal(size=m.n_state)
        Y = X
        for r in range(n):
            Y = m.two_point_backlund(eta, branch=r)(Y)
        out[f"branch product su({n})"] = np.max(np.abs(Y - X))
    rng = np.random.default_rng(4)
    err = 0.0
    for _ in range(5):  # n = 2 against the su(2) chain on random chains
        st = [(float(p), int(N)) for p, N in zip(np.sort(rng.uniform(-2, 2, 3)), rng.integers(1, 4, 3), strict=True)]
        b = float(rng.normal())
        a, g = jg.GaudinModel(b, st), SunGaudinModel(b, st, algebra="su(2)")
        X = rng.normal(size=a.n_state)
        e = complex(rng.uniform(-2, 2), rng.uniform(0.05, 0.6))
        for r, name in ((0, "default"), (1, "opposite")):
            today = a.two_point_backlund(e, branch=name, backend="numpy").iterate(X, 3)
            err = max(err, np.max(np.abs(g.two_point_backlund(e, branch=r).iterate(X, 3) - today))
                      / (1 + np.max(np.abs(today))))
    out["n = 2 vs the su(2) chain's map (relative, 5 chains, 3 steps, both branches)"] = err
    for k, v in out.items():
        print(f"{k}: {v:.1e}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1_000_000)
    p.add_argument("--work-steps", type=int, default=1000)
    p.add_argument("--drift", action="store_true", help="only the drift table of docs/sun.md (10^4 steps)")
    p.add_argument("--ensemble", action="store_true", help="only the ensembles on 1 and 2 threads (and heyoka)")
    p.add_argument("--checks", action="store_true", help="only the measured numbers of the issue's checks")
    a = p.parse_args()
    print("machine:", machine())
    if a.drift:
        drift_table()
        return
    if a.ensemble:
        ensembles()
        return
    if a.checks:
        checks()
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
