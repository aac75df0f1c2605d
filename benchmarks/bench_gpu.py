"""The GPU route (``backend="gpu"``, :mod:`jetgaudin.gpu`) against the compiled CPU route on all cores of the same
host: accuracy per step, orbit-steps per second at 10^5..10^8 orbits (kernel alone and with the copies), the
fraction of the GPU's FP64 peak, the cross-over that ``backend="auto"`` uses, and a chain family.

    python benchmarks/bench_gpu.py --json gpu.json            # on a machine with an NVIDIA GPU (minutes)
    NUMBA_ENABLE_CUDASIM=1 python benchmarks/bench_gpu.py --smoke   # the script's logic, without a GPU (seconds)

Every rate is measured in this run, the CPU baseline beside it (``docs/performance.md``, the GPU section).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

#: FP64 peak (FLOP/s, vector units without the tensor cores) of the GPUs this is run on: NVIDIA's data sheets
FP64_PEAK = {"H100": 34e12, "H200": 34e12, "A100": 9.7e12}


def host() -> dict:
    out = {"cpus": os.cpu_count()}
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
        out["cpu"] = next((ln.split(":", 1)[1].strip() for ln in text.splitlines() if ln.startswith("Model name")), "")
    except (OSError, subprocess.SubprocessError):
        out["cpu"] = "unknown"
    return out


def states(B: int, seed: int = 28) -> np.ndarray:
    """``B`` states of the N = 3 top on the leaf of Appendix 2's Casimirs, scattered (``sample_on_leaf``)."""
    from jetgaudin.ensemble import sample_on_leaf

    return sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=seed)


def tile(X: np.ndarray, B: int) -> np.ndarray:
    return np.ascontiguousarray(np.resize(X, (B, X.shape[1])))


def accuracy(B: int, steps: int) -> dict:
    """Relative difference GPU − CPU (compiled route) after one step from the same states and ν1, and after
    ``steps`` steps; N = 3 real form and the generic route at N = 4."""
    from jetgaudin import gpu
    from jetgaudin.backlund.kernels import _drivers as C

    res = {}
    for n3, spec in ((9, True), (9, False), (12, False)):
        X = states(B) if n3 == 9 else np.random.default_rng(4).normal(size=(B, n3))
        b = np.full(B, 1.0)
        e = np.full(B, 5 + 0.1j, dtype=complex)
        nu0 = C.nu_default(X, b, e, 1)
        row = {}
        for k in (1, steps):
            g = gpu.run_batch(X, b, e, nu0, False, k, k, spec, want_drift=False)
            c = C.run_batch(X, b, e, nu0, False, k, k, spec, want_drift=False)
            scale = 1.0 + np.max(np.abs(c[1]), axis=1)
            row[f"max_rel_diff_after_{k}"] = float(np.max(np.max(np.abs(g[1] - c[1]), axis=1) / scale))
            row[f"bitwise_equal_after_{k}"] = float(np.mean(np.all(g[1] == c[1], axis=1)))
            row[f"status_equal_{k}"] = bool(np.array_equal(g[4], c[4]))
        res[f"N={n3 // 3}{' real form' if spec and n3 == 9 else ' generic'}"] = row
    return res


def gpu_rate(B: int, steps: int, X1: np.ndarray) -> dict:
    from jetgaudin import gpu
    from jetgaudin.backlund.kernels import _drivers as C

    X = tile(X1, B)
    b = np.full(B, 1.0)
    e = np.full(B, 5 + 0.1j, dtype=complex)
    nu0 = C.nu_default(X, b, e, 1)
    gpu.run_batch(X, b, e, nu0, False, steps, steps, True, want_drift=False)
    t = gpu.last_timing()
    return {"orbits": B, "steps": steps, "kernel_s": t.kernel, "total_s": t.total,
            "rate_kernel": B * steps / t.kernel, "rate_total": B * steps / t.total}


def cpu_rate(B: int, steps: int, X1: np.ndarray) -> dict:
    from jetgaudin.backlund.kernels import _drivers as C

    X = tile(X1, B)
    b = np.full(B, 1.0)
    e = np.full(B, 5 + 0.1j, dtype=complex)
    nu0 = C.nu_default(X, b, e, 1)
    t0 = time.perf_counter()
    C.run_batch(X, b, e, nu0, False, steps, steps, True, want_drift=False)
    dt = time.perf_counter() - t0
    return {"orbits": B, "steps": steps, "seconds": dt, "rate": B * steps / dt}


def chain_rates(B: int, steps: int) -> dict:
    """A trigonometric chain of M = 4 order-1 sites: the GPU against the family kernel on all cores."""
    import jetgaudin as jg
    from jetgaudin import gpu
    from jetgaudin.gaudin import _family_kernel as F

    m = jg.GaudinModel(0.7, [(0.0, 1), (0.5, 1), (1.1, 1), (1.9, 1)], family="trigonometric", gamma=1.0)
    T = m.two_point_backlund(0.3 + 0.05j)
    X = np.random.default_rng(5).normal(size=(B, m.n_state))
    nu = T._compiled_start(X)
    c = F.orbit_constants(m, T.eta)
    gpu.run_chain(m, T.eta, X[:2], nu[:2], 1, 1)  # compile
    t0 = time.perf_counter()
    g = gpu.run_chain(m, T.eta, X, nu, steps, steps)
    tg = time.perf_counter() - t0
    tk = gpu.last_timing().kernel
    F.run_batch(X[:2], float(m.b), nu[:2], *c, 1, 1)  # compile / load
    t0 = time.perf_counter()
    r = F.run_batch(X, float(m.b), nu, *c, steps, steps)
    tc = time.perf_counter() - t0
    diff = float(np.max(np.abs(g[1] - r[1]) / (1 + np.abs(r[1]))))
    g1 = gpu.run_chain(m, T.eta, X, nu, 1, 1)[1]
    r1 = F.run_batch(X, float(m.b), nu, *c, 1, 1)[1]
    diff1 = float(np.max(np.max(np.abs(g1 - r1), axis=1) / (1 + np.max(np.abs(r1), axis=1))))
    return {"orbits": B, "steps": steps, "gpu_total_s": tg, "gpu_kernel_s": tk, "cpu_s": tc,
            "gpu_rate_total": B * steps / tg, "gpu_rate_kernel": B * steps / tk, "cpu_rate": B * steps / tc,
            "max_rel_diff_after_steps": diff, "max_rel_diff_after_1": diff1,
            "bitwise_equal_after_1": float(np.mean(np.all(g1 == r1, axis=1)))}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--smoke", action="store_true", help="tiny sizes (the simulator; checks the script only)")
    p.add_argument("--json", help="write the results to this file")
    p.add_argument("--max-orbits", type=float, default=1e8, help="largest ensemble of the GPU table")
    a = p.parse_args()
    from jetgaudin import gpu

    ok, what = gpu.probe()
    out: dict = {"host": host(), "device": what, "gpu_usable": ok}
    print(json.dumps(out), flush=True)
    if not ok:
        sys.exit(f"no GPU: {what}")
    X1 = states(4096)
    t0 = time.perf_counter()
    gpu.prepare(9)
    out["gpu_compile_s"] = time.perf_counter() - t0
    out["accuracy"] = accuracy(4 if a.smoke else 20000, 3 if a.smoke else 50)
    print(json.dumps(out["accuracy"]), flush=True)
    work = 400 if a.smoke else 2e10
    sizes = [8, 16] if a.smoke else [s for s in (1e5, 1e6, 1e7, 1e8) if s <= a.max_orbits]
    out["gpu"] = []
    for B in sizes:
        r = gpu_rate(int(B), max(2, int(work // B)), X1)
        out["gpu"].append(r)
        print(json.dumps(r), flush=True)
    # the CPU route on all cores (lanes kernel compiled or loaded first)
    cpu_rate(64, 2, X1)
    out["cpu"] = [cpu_rate(*((64, 20) if a.smoke else (1_000_000, 1000)), X1)]
    print(json.dumps(out["cpu"]), flush=True)
    # cross-over of backend="auto": total GPU time (copies included) against the CPU lanes on all cores
    out["crossover"] = []
    grid = [(16, 2), (64, 4)] if a.smoke else [(2**14, 100), (2**16, 100), (2**16, 1000), (2**18, 1000),
                                               (10**6, 100), (10**6, 1000)]
    for B, n in grid:
        g = gpu_rate(B, n, X1)
        c = cpu_rate(B, n, X1)
        row = {"orbits": B, "steps": n, "gpu_total_s": g["total_s"], "cpu_s": c["seconds"],
               "gpu_over_cpu_speed": c["seconds"] / g["total_s"]}
        out["crossover"].append(row)
        print(json.dumps(row), flush=True)
    name = next((k for k in FP64_PEAK if k in what), None)
    best = max(r["rate_kernel"] for r in out["gpu"])
    from jetgaudin.backlund.kernels import flops_per_step  # the hand count of one real N = 3 step (issue 36)

    out["fp64_fraction"] = None if name is None else best * flops_per_step(3)["total"] / FP64_PEAK[name]
    out["speedup_vs_cpu_all_cores"] = {str(r["orbits"]): r["rate_total"] / out["cpu"][0]["rate"] for r in out["gpu"]}
    out["chain"] = chain_rates(*((4, 3) if a.smoke else (1_000_000, 100)))
    print(json.dumps(out["chain"]), flush=True)
    print(json.dumps({k: out[k] for k in ("fp64_fraction", "speedup_vs_cpu_all_cores")}), flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
