"""Benchmark of the chain two-point map (issue 12): one orbit, compiled (Numba) route against the NumPy route, for
chains with M <= 9 (magnet of 4 spins, Lagrange chain of 3 sites, twisted chain of 3 sites, a mixed chain).

Run: ``python benchmarks/bench_chains.py [--steps 1000000] [--numpy-steps 2000]``.  Prints the machine, steps/s of
each route (median of 3 runs, thread CPU time, after a warm-up that compiles or loads the kernel) and their ratio.
"""

import argparse
import platform
import subprocess
import time

import numpy as np

import jetgaudin as jg

CHAINS = {
    "magnet 4 sites (M=4)": lambda: jg.gaudin_magnet(0.9, [-1.5, -0.2, 0.7, 1.9]),
    "Lagrange chain 3 sites (M=6)": lambda: jg.lagrange_chain(0.9, [-1.0, 0.4, 1.5]),
    "twisted chain 3 sites (M=9)": lambda: jg.twisted_chain(0.9, [-1.0, 0.4, 1.5]),
    "mixed [(-1,2),(0.5,3),(2,1)] (M=6)": lambda: jg.GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)]),
}


def machine() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        name = next((ln.split(":", 1)[1].strip() for ln in out.splitlines() if ln.startswith("Model name")), "")
    except OSError:
        name = ""
    return f"{name or platform.processor()} ({platform.machine()}, {platform.system()})"


def rate(B, X, steps, save_every, repeats=3):
    times = []
    for _ in range(repeats):
        t = time.thread_time()
        B.iterate(X, steps, save_every=save_every)
        times.append(time.thread_time() - t)
    return steps / float(np.median(times))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1_000_000, help="steps of the compiled route")
    p.add_argument("--numpy-steps", type=int, default=2000, help="steps of the NumPy route")
    a = p.parse_args()
    print("machine:", machine())
    rng = np.random.default_rng(1)
    print(f"{'chain':40s} {'numpy steps/s':>14s} {'compiled steps/s':>17s} {'ratio':>8s}")
    for name, make in CHAINS.items():
        m = make()
        X = rng.normal(size=m.n_state)
        eta = 0.9 + 0.05j
        Bn = m.two_point_backlund(eta)
        Bc = jg.ChainTwoPointBacklund(m, eta, backend="compiled")
        Bc.iterate(X, 10)  # compile or load from Numba's cache
        rn = rate(Bn, X, a.numpy_steps, 1)
        rc = rate(Bc, X, a.steps, 1000)
        print(f"{name:40s} {rn:14.0f} {rc:17.0f} {rc / rn:8.0f}")


if __name__ == "__main__":
    main()
