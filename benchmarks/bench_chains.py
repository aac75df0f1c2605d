"""Benchmark of the chain two-point map (issue 12): one orbit, compiled (Numba) route against the NumPy route, for
chains with M <= 9 (magnet of 4 spins, Lagrange chain of 3 sites, twisted chain of 3 sites, a mixed chain).

Run: ``python benchmarks/bench_chains.py [--steps 1000000] [--numpy-steps 2000] [--work-steps 1000]``.  Prints the
machine, steps/s of each route (median of 3 runs, thread CPU time, after a warm-up that compiles or loads the kernel)
and their ratio; then the same work done two ways (issue 12): ``--work-steps`` steps of the compiled map against
heyoka integrating the flow of ``G_η`` (whose time-1 flow is the map) over the same time, sampled at every integer
time (whole calls, wall time, median of 3; heyoka's time includes building its Taylor integrator, as a user's
call does), at heyoka's default tolerance and at 1e-11, with the distance between the two orbits.
"""

import argparse
import platform
import subprocess
import time

import numpy as np
from harness import timed  # benchmarks/harness.py (this script's directory is sys.path[0])

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
    """Steps per second of this thread's CPU time, median of ``repeats`` calls."""
    return steps / float(np.median(timed(lambda: B.iterate(X, steps, save_every=save_every), repeats)))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1_000_000, help="steps of the compiled route")
    p.add_argument("--numpy-steps", type=int, default=2000, help="steps of the NumPy route")
    p.add_argument("--work-steps", type=int, default=1000, help="steps of the same-work comparison with heyoka")
    a = p.parse_args()
    print("machine:", machine())
    rng = np.random.default_rng(1)
    print(f"{'chain':40s} {'numpy steps/s':>14s} {'compiled steps/s':>17s} {'ratio':>8s}")
    for name, make in CHAINS.items():
        m = make()
        X = rng.normal(size=m.n_state)
        eta = 0.9 + 0.05j
        Bn = m.two_point_backlund(eta, backend="numpy")
        Bc = jg.ChainTwoPointBacklund(m, eta, backend="compiled")
        Bc.iterate(X, 10)  # compile or load from Numba's cache
        rn = rate(Bn, X, a.numpy_steps, 1)
        rc = rate(Bc, X, a.steps, 1000)
        print(f"{name:40s} {rn:14.0f} {rc:17.0f} {rc / rn:8.0f}")
    same_work(rng, a.work_steps)


def _wall(f, repeats=3):
    """Median wall time of ``repeats`` calls of ``f`` and the last call's result."""
    out = []
    t = timed(lambda: out.append(f()), repeats, time.perf_counter)
    return float(np.median(t)), out[-1]


def same_work(rng, steps):
    """The map's orbit against heyoka's flow of G_eta on the same chain, the same time span and samples."""
    try:
        import heyoka  # noqa: F401
    except ImportError:
        print("heyoka not installed (pip install jetgaudin[heyoka]): same-work comparison skipped")
        return
    print(f"\nsame work: {steps} steps of the map vs heyoka's flow of G_eta over t = 0..{steps} (wall, whole calls)")
    print(f"{'chain':40s} {'map s':>9s} {'heyoka s (tol)':>22s} {'ratio':>7s} {'max distance':>13s}")
    t_eval = np.arange(steps + 1, dtype=float)
    for name, make in CHAINS.items():
        m = make()
        X = rng.normal(size=m.n_state)
        eta = 0.9 + 0.05j
        Bc = jg.ChainTwoPointBacklund(m, eta, backend="compiled")
        Bc.iterate(X, 10)
        tm, orbit = _wall(lambda Bc=Bc, X=X: Bc.iterate(X, steps))
        H = m.interpolating_flow_hamiltonian(X, eta)
        for tol in (2.220446049250313e-16, 1e-11):  # heyoka's default tolerance is the machine epsilon
            th, tr = _wall(lambda H=H, X=X, tol=tol: jg.integrate(H, X, float(steps), t_eval=t_eval,
                                                                  method="heyoka", rtol=tol))
            dist = float(np.max(np.abs(tr.X - orbit)))
            print(f"{name:40s} {tm:9.4f} {th:13.4f} ({tol:.0e}) {th / tm:7.1f} {dist:13.2e}")


if __name__ == "__main__":
    main()
