"""Parts (h) fixed cost of short calls, (i) first-use compile time, (j) Dask LocalCluster vs threads and (m) per-step
accuracy of the compiled routes of the benchmark harness (``benchmarks/harness.py`` loads this file; it has no
command line of its own)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

X0_APPENDIX2 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])


def _ensemble(orbits: int, seed: int = 2):
    from jetgaudin.ensemble import sample_on_leaf

    X = sample_on_leaf(3, [0.5, 0.2, 1.0], orbits, seed=seed)
    return X, np.full(orbits, 1.0), np.full(orbits, 5 + 0.1j)


def bench_fixed_cost(rows, Row, orbits=10**5, steps=10):
    """(h) ``TwoPointBacklund.iterate(X, 10)`` on a batch of ``orbits`` N = 3 orbits: compiled vs NumPy-vectorised
    (the reference), and the per-orbit fixed cost of a call (``steps = 0``: branch rule, set-up, output)."""
    from jetgaudin_benchmarks_harness import timed  # the harness (registered under this name) loads this file

    import jetgaudin as jg
    from jetgaudin.backlund import kernels

    X, b, eta = _ensemble(orbits)
    B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    kernels.prepare(9, orbits, notify=lambda m: None)
    B.iterate(X[:300], 1, kernel="compiled")
    wall = time.perf_counter  # all threads
    t = timed(lambda: B.iterate(X, steps, kernel="compiled"), 5, wall)
    tc, tcb = np.median(t), t.min()
    t0 = np.median(timed(lambda: B.iterate(X, 0, kernel="compiled"), 5, wall))
    faults = _minor_faults(lambda: B.iterate(X, 0, kernel="compiled"))
    tnu = np.median(timed(lambda: kernels.nu_default(X, b, eta), 5, wall))
    tn = np.median(timed(lambda: B.iterate(X, steps, kernel="numpy"), 3, wall))
    work = orbits * steps
    rows.append(Row("h", f"iterate(X, {steps}), {orbits:.0e} orbits, compiled", work / tc, "orbit-steps/s",
                    f"best {work / tcb:.3g}; wall, all threads"))
    rows.append(Row("h", f"iterate(X, {steps}), {orbits:.0e} orbits, NumPy-vectorised", work / tn, "orbit-steps/s",
                    "the reference"))
    rows.append(Row("h", "ratio compiled / NumPy-vectorised (10-step call)", tn / tc, "x", "target >= 20"))
    rows.append(Row("h", "fixed cost per orbit per call (iterate(X, 0))", t0 / orbits * 1e6, "µs",
                    f"of which the branch rule for ν1 {tnu / orbits * 1e6:.3f} µs; page faults per call {faults:.0f} "
                    "(freed memory faulted in again); target < 0.1 µs"))


def _minor_faults(fn, repeat=5) -> float:
    """Median number of minor page faults of the process during one call of ``fn`` (``getrusage``; NaN where
    the platform has no ``resource`` module)."""
    try:
        import resource
    except ImportError:
        return float("nan")
    counts = []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        fn()
        counts.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
    return float(np.median(counts))


_COMPILE_CODE = r"""
import json, time
t0 = time.perf_counter()
from jetgaudin.backlund import kernels as k
quiet = lambda m: None
r = {"orbit": k.prepare(9, None, notify=quiet), "ensemble_1e3": k.prepare(9, 1000, notify=quiet),
     "ensemble_1e5": k.prepare(9, 10**5, notify=quiet), "generic": k.prepare(12, None, notify=quiet)}
print(json.dumps({n: [v.state, v.seconds, list(v.kernels)] for n, v in r.items()}))
"""


def bench_compile(rows, Row):
    """(i) First-use compile time (fresh process, empty ``NUMBA_CACHE_DIR``) of the kernels of the main job /
    ``orbit --kernel compiled`` (N = 3 orbit + the branch rule), of ``ensemble`` (lanes + the same branch rule) and
    of the generic route; then the load time from the cache in a second process."""
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, NUMBA_CACHE_DIR=d)
        res = []
        for _ in range(2):  # cold, then cached
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", _COMPILE_CODE], capture_output=True, text=True, env=env,
                                 timeout=1800, check=True).stdout
            res.append((json.loads(out.strip().splitlines()[-1]), time.perf_counter() - t0))
    (cold, t_cold), (warm, t_warm) = res
    for name, (state, sec, names) in cold.items():
        rows.append(Row("i", f"compile, {name} ({state})", sec, "s", "+".join(names) + "; only the kernels not "
                        "already compiled by the lines above"))
    main = cold["orbit"][1] + cold["ensemble_1e3"][1] + cold["ensemble_1e5"][1]
    rows.append(Row("i", "compile, main job + orbit --kernel compiled + ensemble", main, "s",
                    f"target <= 15 s; whole fresh process {t_cold:.1f} s"))
    load = sum(v[1] for v in warm.values())
    rows.append(Row("i", "load from the cache, the same kernels (second process)", load, "s",
                    f"states {sorted({v[0] for v in warm.values()})}; whole process {t_warm:.1f} s"))


def bench_dask(rows, Row, orbits=10**5, steps=1000, chunks=(2500, 10**4, 25000)):
    """(j) The same ensemble (``orbits`` × ``steps``, N = 3, final states only) on the threaded kernel (2 threads)
    and on a Dask ``LocalCluster`` of 2 worker processes × 1 thread, one task per chunk; the overhead per task
    (empty tasks), and the bits compared."""
    import numba
    from dask.distributed import Client, LocalCluster
    from jetgaudin_benchmarks_harness import timed  # the harness (registered under this name) loads this file

    from jetgaudin.backlund import kernels

    X, b, eta = _ensemble(orbits)
    nu0 = kernels.nu_default(X, b, eta)
    kernels.run_batch(X[:4], b[:4], eta[:4], nu0[:4], False, 2, 2)
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    ref = None

    def threaded():
        nonlocal ref
        ref = kernels.run_batch(X, b, eta, nu0, False, steps, steps)[1]

    tt = np.median(timed(threaded, 3, time.perf_counter))
    rows.append(Row("j", f"threads (2): {orbits:.0e} × {steps}", orbits * steps / tt, "orbit-steps/s",
                    f"{tt:.2f} s wall"))
    old = os.environ.get("NUMBA_NUM_THREADS")
    os.environ["NUMBA_NUM_THREADS"] = "1"  # one thread per worker process (inherited by the workers)
    try:
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            client.run(kernels.prepare, 9, orbits, notify=print)  # load the cached kernels in each worker
            client.gather(client.map(kernels.run_batch, [X[:4]] * 2, [b[:4]] * 2, [eta[:4]] * 2, [nu0[:4]] * 2,
                                     [False] * 2, [2] * 2, [2] * 2, pure=False))
            n_empty = 200
            t0 = time.perf_counter()
            client.gather(client.map(int, range(n_empty), pure=False))
            per_task = (time.perf_counter() - t0) / n_empty
            rows.append(Row("j", "Dask overhead per task (empty tasks, 2 workers)", per_task * 1e3, "ms",
                            f"{n_empty} tasks"))
            for c in chunks:
                starts = range(0, orbits, c)

                def run(starts=starts, c=c):
                    futs = client.map(kernels.run_batch, [X[i:i + c] for i in starts], [b[i:i + c] for i in starts],
                                      [eta[i:i + c] for i in starts], [nu0[i:i + c] for i in starts],
                                      [False] * len(starts), [steps] * len(starts), [steps] * len(starts),
                                      pure=False)
                    return np.concatenate([r[1] for r in client.gather(futs)])

                final = run()
                td = np.median(timed(run, 3, time.perf_counter))
                same = bool(np.array_equal(final, ref))
                rows.append(Row("j", f"Dask LocalCluster 2×1, chunk {c} ({len(starts)} tasks)",
                                orbits * steps / td, "orbit-steps/s",
                                f"ratio to threads {tt / td:.2f}; {td:.2f} s wall; bitwise equal to threads: {same}"))
    finally:
        if old is None:
            os.environ.pop("NUMBA_NUM_THREADS", None)
        else:
            os.environ["NUMBA_NUM_THREADS"] = old


_PROCESS_RATE = r"""
import json, sys, time
sys.path[:] = json.loads(sys.argv[1])  # the parent's path: the same jetgaudin
import numpy as np
from jetgaudin.backlund import kernels
d = np.load(sys.argv[2])
X, b, eta, nu, steps = d["X"], d["b"], d["eta"], d["nu"], int(sys.argv[3])
kernels.run_batch(X[:4], b[:4], eta[:4], nu[:4], False, 2, 1)  # load the cached kernel before the barrier
print("ready", flush=True)
sys.stdin.readline()  # the barrier: the parent releases every process at once
out = []
for _ in range(int(sys.argv[4])):
    w, c = time.perf_counter(), time.thread_time()
    kernels.run_batch(X, b, eta, nu, False, steps, steps)
    out.append((w, time.perf_counter(), time.thread_time() - c))
print(json.dumps(out), flush=True)
"""


def _steal_jiffies() -> tuple[int, int]:
    """(steal, total) jiffies of all CPUs from ``/proc/stat`` (Linux; ``(0, 0)`` elsewhere): the time the
    hypervisor ran something else on this VM's vCPUs."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
    except (OSError, ValueError):
        return 0, 0
    return (v[7] if len(v) > 7 else 0), sum(v[:8])


def process_rates(X, b, eta, nu, steps: int, processes: int, reps: int = 5) -> dict:
    """``run_batch(X, b, eta, nu, False, steps, steps)`` in ``processes`` fresh processes at once (this interpreter,
    this ``sys.path``, ``NUMBA_NUM_THREADS=1``): each loads the cached kernel, waits at a barrier (a line on its
    stdin), then times ``reps`` calls (wall with :func:`time.perf_counter`, a system-wide monotonic clock on Linux,
    and its thread's CPU time).  Only the calls that lie wholly inside the window where every process was calling
    count (the overlap).  Returns ``{"wall": [orbit-steps/s per process], "cpu": [...], "kept": [calls],
    "steal": fraction of CPU time stolen by the hypervisor meanwhile}`` (medians of the kept calls)."""
    import json
    import tempfile

    work = X.shape[0] * steps
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "batch.npz")
        np.savez(path, X=X, b=b, eta=eta, nu=nu)
        env = dict(os.environ, NUMBA_NUM_THREADS="1")
        argv = [sys.executable, "-c", _PROCESS_RATE, json.dumps(sys.path), path, str(steps), str(reps)]
        procs = [subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
                 for _ in range(processes)]
        try:
            for p in procs:
                if p.stdout.readline().strip() != "ready":
                    raise RuntimeError(f"a timing process failed before the barrier (exit {p.wait(60)})")
            steal0 = _steal_jiffies()
            for p in procs:
                p.stdin.write("go\n")
                p.stdin.flush()
            runs = [json.loads(p.communicate(timeout=3600)[0].strip().splitlines()[-1]) for p in procs]
            steal1 = _steal_jiffies()
        finally:
            for p in procs:
                if p.poll() is None:
                    p.kill()
                    p.wait()
    lo, hi = max(r[0][0] for r in runs), min(r[-1][1] for r in runs)
    out: dict = {"wall": [], "cpu": [], "kept": []}
    for r in runs:
        inside = [c for c in r if c[0] >= lo and c[1] <= hi]
        kept = inside or r  # every call if the start skew left none inside (then "kept" says 0)
        out["wall"].append(work / float(np.median([c[1] - c[0] for c in kept])))
        out["cpu"].append(work / float(np.median([c[2] for c in kept])))
        out["kept"].append(len(inside))
    total = steal1[1] - steal0[1]
    out["steal"] = (steal1[0] - steal0[0]) / total if total > 0 else 0.0
    return out


def bench_step_accuracy(rows, Row, steps=200, states=4, etas=(5 + 0.1j, 2 - 1j, 1.2 + 0.7j, 0.6 - 0.2j,
                                                               0.3 + 0.5j, -3 + 2j)):
    """(m) Per-step error of the compiled N = 3 and generic routes against the NumPy reference route, relative to
    ``max|X|`` over the orbit: ``max_n err_n / n`` over ``steps`` steps (the row's value) and the error after one
    step, on Appendix 2 and ``states`` random leaf states (``sample_on_leaf``, ``b = 1.3``) for each η of ``etas``
    (both division directions; ``|η| < 1``: near the Lax pole λ = 0); and the NumPy route's own sensitivity (the same
    measure for a 1e-16 relative perturbation of X0), which bounds what "round-off level" can mean.  One row per
    route and case group, then one summary row per route: its value is the worst per-step error over all cases,
    its note (and ``extra``) the max over the random cases with ``|η| ≥ 1``, over those with ``|η| < 1``, and
    Appendix 2.  ``ν1`` comes from the NumPy branch rule, so the routes start from the same carry."""
    import jetgaudin as jg
    from jetgaudin.backlund import kernels
    from jetgaudin.ensemble import sample_on_leaf

    rng = np.random.default_rng(7)
    cases = [("Appendix 2", X0_APPENDIX2, 1.0, 5 + 0.1j)]
    for eta in etas:
        c = np.array([rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), 1.0])
        for x in sample_on_leaf(3, c, states, seed=int(rng.integers(1 << 30)), scale=0.5):
            cases.append((f"η = {eta}", x, 1.3, eta))
    n = np.arange(1, steps + 1)
    routes = ("N = 3", "generic")
    worst: dict[str, list[float]] = {}  # "route case": [after one step, per step, NumPy route's sensitivity]
    groups = {r: {"|η| ≥ 1": [0.0, 0.0], "|η| < 1": [0.0, 0.0], "Appendix 2": [0.0, 0.0]} for r in routes}
    for name, x, b, eta in cases:
        B = jg.TwoPointBacklund(b, eta)
        ref = B.iterate(x, steps, kernel="numpy")
        moved = B.iterate(x * (1 + 1e-16 * rng.choice([-1, 1], 9)), steps, kernel="numpy")
        nu0 = B.nu1(x)
        s = np.max(np.abs(ref))
        sens = float(np.max(np.max(np.abs(moved - ref), axis=1)[1:] / s / n))
        group = "Appendix 2" if name == "Appendix 2" else ("|η| < 1" if abs(eta) < 1 else "|η| ≥ 1")
        for r in routes:
            orbit = kernels.iterate_single(x, b, eta, nu0, False, steps, 1, specialise=r == "N = 3")[0]
            d = np.max(np.abs(orbit - ref), axis=1) / s
            one, per = float(d[1]), float(np.max(d[1:] / n))
            w = worst.setdefault(f"{r} {name}", [0.0, 0.0, 0.0])
            w[:] = max(w[0], one), max(w[1], per), max(w[2], sens)
            g = groups[r][group]
            g[:] = max(g[0], per), max(g[1], one)
    for key, (one, per, sens) in worst.items():
        rows.append(Row("m", f"{key}: per-step error vs NumPy", per, "relative",
                        f"after one step {one:.2g}; NumPy route moved by 1e-16 in X0: {sens:.2g} per step"))
    for r in routes:
        g = groups[r]
        rows.append(Row("m", f"{r} route: worst per-step error vs NumPy", max(v[0] for v in g.values()), "relative",
                        "; ".join(f"{k} {v[0]:.2g}" for k, v in g.items())
                        + f"; after one step, all cases {max(v[1] for v in g.values()):.2g}; {len(cases)} cases, "
                        f"{steps} steps", extra={k: v[0] for k, v in g.items()}))
