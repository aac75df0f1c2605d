"""The N = 3 ensemble against the CPU's measured FP64 peak, side by side with a baseline commit (issue 36).

    python benchmarks/cpu_peak.py --baseline-src /tmp/base/src --rounds 3

Measures, each in a fresh process, alternated between this tree and the baseline (``--baseline-src``: the ``src`` of
a checkout of another commit, e.g. ``git worktree add /tmp/base 143288c``):

* the **peak**: a dependent chain of fused multiply-adds gives the clock (4 cycles of FMA latency on AMD Zen 3/4
  and Intel since Skylake), 16 independent vector accumulators the FMA throughput per core (FLOP/s and flops per
  cycle); both on one thread, Numba, the same target as the kernels;
* the **lanes** (``run_batch`` of 2·10⁴ N = 3 orbits × 500 steps, Appendix 2's leaf, ``η`` near 5 + 0.1i): one
  thread (the thread's CPU time) and all of Numba's threads (wall time), best and median of 7 calls; FLOP/s at the
  hand count of :func:`jetgaudin.backlund.kernels.flops_per_step` and the fraction of the measured peak (per core
  × the threads);
* with ``--appendix2``: the Appendix 2 call (1000 steps of one orbit, every step saved: ``TwoPointBacklund.iterate``
  with ``kernel="compiled"`` as ``jetgaudin orbit`` computes it) against heyoka's ``propagate_grid`` at the
  tolerance that reaches 1e-12 and at its default (``benchmarks/harness.py``, part b).

Prints one JSON line per measurement and a Markdown table of min/median over the rounds.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"


def peak() -> dict:
    from jetgaudin.backlund.kernels import _target

    _target.configure()
    from numba import njit

    from jetgaudin.backlund.kernels._scalar import _fma as F

    @njit
    def chain(n, a, b):
        x = 1.0
        for _ in range(n):
            x = F(x, a, b)
        return x

    @njit(nogil=True)
    def through(n, a, b, acc):
        for _ in range(n):
            for j in range(64):  # 16 independent 4-wide accumulators (8 8-wide ones with AVX-512)
                acc[j] = F(acc[j], a, b)
        return acc.sum()

    a, b = 0.999999, 1e-7
    acc = np.ones(64)
    chain(10, a, b)
    through(10, a, b, acc)
    n, m = 10**8, 10**7
    ghz, gf = [], []
    for _ in range(3):
        t = time.thread_time()
        chain(n, a, b)
        ghz.append(4 * n / (time.thread_time() - t) / 1e9)
        t = time.thread_time()
        through(m, a, b, acc)
        gf.append(2 * 64 * m / (time.thread_time() - t) / 1e9)
    # every core at once (the machine's peak: its cores' clocks may be lower together than one alone): the same
    # loop on all of Numba's threads, each its own accumulators, wall time
    from concurrent.futures import ThreadPoolExecutor

    import numba

    nt = numba.config.NUMBA_NUM_THREADS
    accs = [np.ones(64) for _ in range(nt)]
    allc = []
    with ThreadPoolExecutor(nt) as ex:
        for _ in range(3):
            t = time.perf_counter()
            list(ex.map(lambda acc: through(m, a, b, acc), accs))
            allc.append(2 * 64 * m * nt / (time.perf_counter() - t) / 1e9)
    return {"clock_GHz": max(ghz), "peak_GFLOPs_per_core": max(gf), "flops_per_cycle": max(gf) / max(ghz),
            "threads": nt, "peak_GFLOPs_all_cores": max(allc)}


def lanes(threads: int) -> dict:
    import numba

    numba.set_num_threads(threads)
    from jetgaudin import ensemble as ens
    from jetgaudin.backlund import kernels as K

    B, steps = 20000, 500
    X0 = ens.sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=2)
    b = np.full(B, 1.0)
    eta = 5.0 + np.random.default_rng(1).uniform(-0.5, 0.5, B) + 0.1j
    nu0 = K.nu_default(X0, b, eta, 1)
    K.run_batch(X0[:64], b[:64], eta[:64], nu0[:64], False, 2, 1)
    clock = time.thread_time if threads == 1 else time.perf_counter
    ts = []
    for _ in range(7):
        t = clock()
        K.run_batch(X0, b, eta, nu0, False, steps, steps)
        ts.append(clock() - t)
    ts = np.array(ts)
    return {"threads": threads, "best": B * steps / ts.min(), "median": B * steps / float(np.median(ts)),
            "flops_per_step": K.flops_per_step(3)["total"]}


def appendix2() -> dict:
    import importlib.util

    spec = importlib.util.spec_from_file_location("jg_harness", HERE / "harness.py")
    h = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = h
    spec.loader.exec_module(h)
    rows: list = []
    h.bench_appendix2(rows, repeat=50)
    return {r.what: r.value for r in rows}


def child(what: str) -> None:
    if what == "peak":
        print(json.dumps(peak()))
    elif what.startswith("lanes"):
        print(json.dumps(lanes(int(what[5:]))))
    else:
        print(json.dumps(appendix2()))


def run(src: Path, what: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run([sys.executable, __file__, "--child", what], env=env, capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--baseline-src", type=Path, help="the src directory of a baseline checkout")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--appendix2", action="store_true", help="also the Appendix 2 call against heyoka (part b)")
    p.add_argument("--child", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.child:
        child(a.child)
        return 0
    trees = {"this": SRC} | ({"baseline": a.baseline_src} if a.baseline_src else {})
    import numba

    nthreads = numba.config.NUMBA_NUM_THREADS
    res: dict = {}
    for r in range(a.rounds):
        for what in ["peak", "lanes1", f"lanes{nthreads}"] + (["appendix2"] if a.appendix2 else []):
            for name, src in trees.items():
                if what == "peak" and name != "this":
                    continue
                v = run(src, what)
                v.update(tree=name, what=what, round=r, loadavg=os.getloadavg())
                print(json.dumps(v), flush=True)
                res.setdefault((name, what), []).append(v)
    pk = [v["peak_GFLOPs_per_core"] for v in res[("this", "peak")]]
    per_core = max(pk)
    allc = max(v["peak_GFLOPs_all_cores"] for v in res[("this", "peak")])
    print(f"\npeak per core {min(pk):.1f}-{max(pk):.1f} GFLOP/s; clock "
          f"{max(v['clock_GHz'] for v in res[('this', 'peak')]):.2f} GHz; all {nthreads} cores at once {allc:.1f} "
          f"GFLOP/s; fractions against {per_core:.1f} per core (one thread) and the all-core peak (more)\n")
    print("| tree | threads | orbit-steps/s min / median of the calls' medians | best | GFLOP/s (median) | "
          "% of the best peak (one core / all cores) |")
    print("|---|---:|---:|---:|---:|---:|")
    for (name, what), vs in res.items():
        if not what.startswith("lanes"):
            continue
        th = vs[0]["threads"]
        med = np.array([v["median"] for v in vs])
        gfl = float(np.median(med)) * vs[0]["flops_per_step"] / 1e9
        # each round against the peak measured in that round (the machine's speed moves between rounds)
        # (more than one thread: against the peak measured on all cores at once)
        frac = [100 * v["median"] * v["flops_per_step"] / 1e9 / (p["peak_GFLOPs_per_core"] * th if th == 1 else
                                                                  p["peak_GFLOPs_all_cores"] * th / p["threads"])
                for v, p in zip(vs, res[("this", "peak")], strict=True)]
        print(f"| {name} | {th} | {med.min():.3g} / {np.median(med):.3g} | {max(v['best'] for v in vs):.3g} | "
              f"{gfl:.1f} | {100 * gfl / (per_core * th if th == 1 else allc * th / nthreads):.0f} % "
              f"(per round: {min(frac):.0f}-{max(frac):.0f} %) |")
    for (name, what), vs in res.items():
        if what == "appendix2":
            for key in ("ratio heyoka / map iterate()", "ratio heyoka(default tol) / map iterate()",
                        "ratio heyoka / map kernel"):
                x = np.array([v[key] for v in vs])
                print(f"{name}: {key}: min {x.min():.2f}, median {np.median(x):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
