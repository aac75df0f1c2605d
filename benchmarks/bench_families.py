"""Benchmark of the Gaudin families on the one model core (issue 23): one orbit of the real two-point map.

Run: ``python benchmarks/bench_families.py [--steps 1000000] [--numpy-steps 1000] [--work-steps 1000]
[--baseline-src DIR]``.  Prints the machine and, in one run on one machine (steps/s of this thread's CPU time, the
median of 5 calls after a warm-up that compiles or loads the kernel):

(a) the rational chain kernel (magnet of 4 spins, M = 4; mixed chain, M = 6) in this checkout and, with
    ``--baseline-src DIR`` (e.g. the ``src`` of the commit before the core), the same work in that source tree in a
    subprocess started at the same time: their ratio is the "rational speed kept" check (±10 %);
(b) the trigonometric map, compiled (the one family kernel, :mod:`jetgaudin.gaudin._family_kernel`) and NumPy, for
    M = 2, 3, 4 order-1 sites and a chain with jet sites, and the rational kernel on the same sites beside it;
(c) the rational family run through the family kernel (the one kernel every family can use) against its own kernel;
(d) the same work two ways (trigonometric and elliptic, M = 4): ``--work-steps`` steps of the compiled map against
    heyoka integrating the flow of ``G_ξ`` over the same time sampled at integer times (wall, whole calls, median
    of 3);
(e) an ensemble (trig magnet M = 4, 64 orbits): the batch on all cores (``prange``) against the orbits one by one
    (wall time, median of 3; orbit-steps/s);
(f) the elliptic map (modulus 0.6, issue 24), compiled and NumPy, on the sites of (b), the trigonometric kernel
    beside it;
(g) short calls (the per-call set-up): ``advance`` of one step from a new state, the branch rule of ``ν`` compiled
    (:func:`jetgaudin.gaudin._family_kernel.branch_rule`, today's route) against the NumPy rule that started every
    compiled call before (``advance(X, start(X), 1)``, the same kernel after it), rational and trigonometric M = 4,
    and 256 orbits of 10 steps in one batch call (wall, median of 5 after a warm-up; ms per call);
(h) the cost of the compensated sums (``docs/reliability.md``, "Compensated sums: the cost"): the compiled chain
    map of every family (rational, trigonometric, elliptic; the sites of ``benchmarks/chain_drift.py`` and a magnet
    of 4) in this checkout against ``--baseline-src DIR[,DIR2...]`` (ratios against the first), one fresh process
    per measurement, the trees alternated over ``--rounds`` rounds (the machine may be shared: compare the medians,
    read the load printed).
"""

import argparse
import os
import subprocess
import sys
import time

import numpy as np
from bench_chains import machine  # benchmarks/ is sys.path[0]
from harness import timed

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel

XI = 0.5 + 0.2j
TRIG = {
    "trig magnet M=2": [(-0.4, 1), (0.9, 1)],
    "trig magnet M=3": [(-0.9, 1), (0.1, 1), (1.0, 1)],
    "trig magnet M=4": [(-1.2, 1), (-0.4, 1), (0.3, 1), (1.1, 1)],
    "trig jets [(-1,2),(0.3,3),(1.2,1)] M=6": [(-1.0, 2), (0.3, 3), (1.2, 1)],
}
RATIONAL = {
    "magnet 4 sites (M=4)": "jg.gaudin_magnet(0.9, [-1.5, -0.2, 0.7, 1.9])",
    "mixed [(-1,2),(0.5,3),(2,1)] (M=6)": "jg.GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])",
}
_SNIPPET = """
import sys, time, numpy as np, jetgaudin as jg
m = {model}
X = np.random.default_rng(1).normal(size=m.n_state)
B = jg.ChainTwoPointBacklund(m, 0.9 + 0.05j, backend="compiled")
B.iterate(X, 10)
t = []
for _ in range(5):
    s = time.thread_time(); B.iterate(X, {steps}, save_every=1000); t.append(time.thread_time() - s)
print({steps} / float(np.median(t)))
"""


def rate(B, X, steps, save_every, kernel, repeats=5):
    """Steps per second of this thread's CPU time, median of ``repeats`` calls."""
    B.iterate(X, 10, kernel=kernel)
    return steps / float(np.median(timed(lambda: B.iterate(X, steps, save_every=save_every, kernel=kernel),
                                         repeats)))


def rational_kernel(args):
    print("(a) rational chain kernel, steps/s (median of 5, thread CPU time)")
    for name, expr in RATIONAL.items():
        code = _SNIPPET.format(model=expr, steps=args.steps)
        procs = {"this checkout": subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)}
        if args.baseline_src:
            env = {**os.environ, "PYTHONPATH": args.baseline_src}
            procs["baseline"] = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                                                 env=env)
        res = {k: float(p.communicate()[0].split()[-1]) for k, p in procs.items()}
        line = f"  {name:40s} this checkout {res['this checkout']:12.0f}"
        if "baseline" in res:
            line += f"   baseline {res['baseline']:12.0f}   ratio {res['this checkout'] / res['baseline']:.3f}"
        print(line)


def _family_rates(args, rng, title, other, make, make_other, rename=str):
    """steps/s of one orbit, NumPy and compiled, for each site list of ``TRIG``; ``make_other``'s kernel beside."""
    print(title)
    print(f"  {'sites':42s} {'numpy':>9s} {'compiled':>11s} {'ratio':>7s} {other:>16s}")
    for name, sites in TRIG.items():
        m = make(sites)
        X = rng.normal(size=m.n_state)
        B = m.two_point_backlund(XI)
        rn = rate(B, X, args.numpy_steps, 1, "numpy", repeats=3)
        rc = rate(B, X, args.steps, 1000, "compiled")
        ro = rate(make_other(sites).two_point_backlund(XI), X, args.steps, 1000, "compiled")
        print(f"  {rename(name):42s} {rn:9.0f} {rc:11.0f} {rc / rn:7.0f} {ro:16.0f}")


def trigonometric(args, rng):
    _family_rates(args, rng, "(b) trigonometric map (gamma = 0.7), steps/s; the rational kernel on the same sites",
                  "rational kernel", lambda s: GaudinModel(0.8, s, family="trigonometric", gamma=0.7),
                  lambda s: GaudinModel(0.8, s))


def elliptic(args, rng):
    _family_rates(args, rng, "(f) elliptic map (modulus k = 0.6, b = 0), steps/s; the trigonometric kernel (gamma = "
                  "0.7) on the same sites", "trig kernel",
                  lambda s: GaudinModel(0.0, s, family="elliptic", modulus=0.6),
                  lambda s: GaudinModel(0.8, s, family="trigonometric", gamma=0.7), lambda n: n.replace("trig", "XYZ"))


def one_kernel(args, rng):
    from jetgaudin.gaudin import _family_kernel as F

    print("(c) the rational family through the family kernel vs its own kernel, steps/s")
    for name, expr in RATIONAL.items():
        m = eval(expr)  # noqa: S307 - the benchmark's own table
        X = rng.normal(size=m.n_state)
        B = m.two_point_backlund(0.9 + 0.05j)
        nu = complex(B.start(X))
        c = F.orbit_constants(m, B.eta)
        F.run_orbit(X, m.b, nu, *c, 10, 1)
        rf = args.steps / float(np.median(timed(lambda m=m, X=X, nu=nu, c=c: F.run_orbit(X, m.b, nu, *c, args.steps,
                                                                                          1000), 5)))
        ro = rate(B, X, args.steps, 1000, "compiled")
        print(f"  {name:40s} family kernel {rf:12.0f}   rational kernel {ro:12.0f}   ratio {rf / ro:.2f}")


def same_work(args, rng):
    try:
        import heyoka  # noqa: F401
    except ImportError:
        print("(d) heyoka not installed (pip install jetgaudin[heyoka]): skipped")
        return
    for label, m in (("trig", GaudinModel(0.8, TRIG["trig magnet M=4"], family="trigonometric", gamma=0.7)),
                     ("XYZ", GaudinModel(0.0, TRIG["trig magnet M=4"], family="elliptic", modulus=0.6))):
        _same_work(args, rng, label, m)


def _same_work(args, rng, label, m):
    n = args.work_steps
    X = rng.normal(size=m.n_state)
    B = m.two_point_backlund(XI, kernel="compiled")
    B.iterate(X, 10)
    t_eval = np.arange(n + 1, dtype=float)
    H = m.interpolating_flow_hamiltonian(X, XI)
    print(f"(d) same work, {label} magnet M=4: {n} map steps vs heyoka's flow of G_xi over t = 0..{n} (wall, median "
          "of 3)")
    tm = float(np.median(timed(lambda: B.iterate(X, n), 3, time.perf_counter)))
    orbit = B.iterate(X, n)
    for tol in (2.220446049250313e-16, 1e-11):
        out = []
        th = float(np.median(timed(lambda tol=tol, out=out: out.append(jg.integrate(H, X, float(n), t_eval=t_eval,
                                                                          method="heyoka", rtol=tol)), 3,
                                   time.perf_counter)))
        print(f"  map {tm:.4f} s   heyoka {th:.4f} s (tol {tol:.0e})   ratio {th / tm:.0f}   max distance "
              f"{np.abs(out[-1].X - orbit).max():.2e}")


def ensemble(args, rng):
    m = GaudinModel(0.8, TRIG["trig magnet M=4"], family="trigonometric", gamma=0.7)
    X = rng.normal(size=(64, m.n_state))
    B = m.two_point_backlund(XI, kernel="compiled")
    B.iterate(X[:2], 10)
    n = args.steps // 64
    tb = float(np.median(timed(lambda: B.iterate(X, n, save_every=n), 3, time.perf_counter)))
    ts = float(np.median(timed(lambda: [B.iterate(x, n, save_every=n) for x in X], 3, time.perf_counter)))
    print(f"(e) ensemble, trig magnet M=4, 64 orbits x {n} steps (wall, {os.cpu_count()} cores): batch "
          f"{64 * n / tb:.3g} orbit-steps/s, one by one {64 * n / ts:.3g} ({ts / tb:.2f}x)")


def short_calls(args, rng):
    sites = TRIG["trig magnet M=4"]
    for fam in ("rational", "trigonometric"):
        m = GaudinModel(0.8, sites, family=fam)
        B = m.two_point_backlund(XI, kernel="compiled")
        for what, X, n in (("1 step", rng.normal(size=m.n_state), 1),
                           ("256 orbits x 10 steps", rng.normal(size=(256, m.n_state)), 10)):
            def new(B=B, X=X, n=n):
                return B.advance(X, None, n)

            def old(B=B, X=X, n=n):
                return B.advance(X, B.start(X), n)

            new(), old()
            tn = float(np.median(timed(new, 5, time.perf_counter)))
            to = float(np.median(timed(old, 5, time.perf_counter)))
            print(f"(g) {fam} M=4, {what}: compiled set-up {1e3 * tn:.3f} ms, NumPy set-up {1e3 * to:.3f} ms "
                  f"({to / tn:.1f}x)")


_COST = """
import time, numpy as np, jetgaudin as jg
from jetgaudin.gaudin import GaudinModel
m = GaudinModel({b}, {sites}, family={fam!r}, **{kw})
X = 0.5 * np.random.default_rng(2026).normal(size=m.n_state)
B = m.two_point_backlund(1.5 + 0.2j, kernel="compiled")
B.iterate(X, 10)
t = []
for _ in range(3):
    s = time.thread_time(); B.iterate(X, {steps}, save_every=1000); t.append(time.thread_time() - s)
print({steps} / float(np.median(t)))
"""
COST = {
    "rational [(-0.5,1),(0.4,2)]": (1.0, [(-0.5, 1), (0.4, 2)], "rational", {}),
    "trigonometric [(-0.5,1),(0.4,2)]": (1.0, [(-0.5, 1), (0.4, 2)], "trigonometric", {"gamma": 1.0}),
    "elliptic [(-0.5,1),(0.4,2)]": (0.0, [(-0.5, 1), (0.4, 2)], "elliptic", {"modulus": 0.6}),
    "trigonometric magnet M=4": (1.0, TRIG["trig magnet M=4"], "trigonometric", {"gamma": 1.0}),
    "elliptic magnet M=4": (0.0, TRIG["trig magnet M=4"], "elliptic", {"modulus": 0.6}),
}


def compensated_cost(args):
    """Part (h): steps/s of this checkout and of ``--baseline-src``, alternated, one process each (module doc)."""
    trees = {"this checkout": os.environ.get("PYTHONPATH", "")}
    for i, path in enumerate((args.baseline_src or "").split(",") if args.baseline_src else []):
        trees["baseline" if i == 0 else f"baseline{i + 1}"] = path  # ratios against the first
    print(f"(h) compensated sums' cost: steps/s (median of 3 calls per process; {args.rounds} rounds alternated)")
    for name, (b, sites, fam, kw) in COST.items():
        code = _COST.format(b=b, sites=sites, fam=fam, kw=kw, steps=args.steps // 4)
        res = {k: [] for k in trees}
        for r in range(args.rounds):
            for k, path in (list(trees.items()) if r % 2 == 0 else list(trees.items())[::-1]):
                out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                     env={**os.environ, "PYTHONPATH": path})
                res[k].append(float(out.stdout.split()[-1]))
        med = {k: float(np.median(v)) for k, v in res.items()}
        line = "  ".join(f"{k} {v:10.0f}" for k, v in med.items())
        ratio = f"  ratio {med['this checkout'] / med['baseline']:5.2f}" if "baseline" in med else ""
        print(f"  {name:34s} {line}{ratio}   load {os.getloadavg()[0]:.2f}", flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1_000_000)
    p.add_argument("--numpy-steps", type=int, default=1000)
    p.add_argument("--work-steps", type=int, default=1000)
    p.add_argument("--baseline-src", default=None, help="a source tree (its src/) for the rational baseline")
    p.add_argument("--parts", default="abcdefg")
    p.add_argument("--rounds", type=int, default=4, help="part (h): alternated rounds per tree")
    a = p.parse_args()
    print("machine:", machine())
    rng = np.random.default_rng(1)
    for part, fn in (("a", lambda: rational_kernel(a)), ("b", lambda: trigonometric(a, rng)),
                     ("c", lambda: one_kernel(a, rng)), ("d", lambda: same_work(a, rng)),
                     ("e", lambda: ensemble(a, rng)), ("f", lambda: elliptic(a, rng)),
                     ("g", lambda: short_calls(a, rng)), ("h", lambda: compensated_cost(a))):
        if part in a.parts:
            fn()


if __name__ == "__main__":
    main()
