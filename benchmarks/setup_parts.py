"""Parts (k) per-call set-up of ``iterate()`` on a batch and (l) first-use compile time kernel by kernel, of the
benchmark harness (``benchmarks/harness.py`` loads this file; it has no command line of its own).

(k) splits the fixed cost of a call on ``10^5`` N = 3 orbits (``iterate(X, 0)``: a first call, with the branch rule
for ``ν1``; a continued call, ``nu1=`` given) into its parts, each timed alone in the same run, with the
NumPy-vectorised route of the same calls as the baseline.  (l) compiles each kernel in a fresh process with an
empty ``NUMBA_CACHE_DIR`` (one process per kernel, so each time is that kernel's alone) and the kernels of the
main job + ``orbit --kernel compiled`` + ``ensemble`` together in one fresh process (the first-use total).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def bench_setup(rows, Row, orbits=10**5, repeat=15):
    """(k) Per-orbit cost of the parts of a call of ``TwoPointBacklund.iterate`` on ``orbits`` N = 3 orbits: CPU
    time of one thread (Numba's threads set to 1 for the part, so the lanes run on the timed thread; robust to the
    other jobs of a shared machine), median and best of ``repeat``."""
    import numba
    from jetgaudin_benchmarks_harness import timed  # the harness (registered under this name) loads this file

    import jetgaudin as jg
    from jetgaudin._validate import as_state
    from jetgaudin.backlund import kernels
    from jetgaudin.ensemble import sample_on_leaf

    X = sample_on_leaf(3, [0.5, 0.2, 1.0], orbits, seed=1)
    b, eta = np.full(orbits, 1.0), np.full(orbits, 5 + 0.1j)
    m = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="compiled")
    m.prepare_kernels(X, 10, notify=lambda s: None)
    _, nu = m.iterate(X, 1, return_nu=True)
    mn = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy")
    us = 1e6 / orbits
    parts = [
        ("iterate(X, 0), first call (branch rule for ν1)", lambda: m.iterate(X, 0), "target: as low as possible"),
        ("iterate(X, 0, nu1=ν), continued call", lambda: m.iterate(X, 0, nu1=nu), "target < 0.1 µs"),
        ("  branch rule (nu_default; one thread here)", lambda: kernels.nu_default(X, b, eta), ""),
        ("  kernel call, 0 steps, first call (cont=False), no drift pass",
         lambda: kernels.run_batch(X, b, eta, nu, False, 0, 1, want_drift=False), ""),
        ("  kernel call, 0 steps, no drift pass (lanes' set-up)",
         lambda: kernels.run_batch(X, b, eta, nu, True, 0, 1, want_drift=False), "run_lanes3's body (helper speed)"),
        ("  kernel call, 0 steps, with the drift pass", lambda: kernels.run_batch(X, b, eta, nu, True, 0, 1),
         "the drift pass that iterate() skips"),
        ("  input checks (as_state: shape, finiteness)", lambda: as_state(X), ""),
        ("iterate(X, 10, nu1=ν), continued call", lambda: m.iterate(X, 10, nu1=nu), ""),
    ]
    base = [("NumPy branch rule nu1(X) (roots; the first call's set-up)", lambda: mn.nu1(X[: orbits // 10]), 10),
            ("NumPy-vectorised iterate(X, 10, nu1=ν)", lambda: mn.iterate(X[: orbits // 10], 10,
                                                                         nu1=nu[: orbits // 10]), 10)]
    t = {}
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for what, fn, note in parts:
            fn()
            cpu = timed(fn, repeat, time.thread_time)  # this thread's CPU time: the lanes run on it (1 thread)
            t[what], best = np.median(cpu) * us, cpu.min()
            rows.append(Row("k", what, t[what], "µs/orbit", f"best {best * us:.3f}; {note}".rstrip("; ")))
        for what, fn, scale in base:
            fn()
            t[what] = np.median(timed(fn, 3, time.thread_time)) * us * scale
            rows.append(Row("k", what, t[what], "µs/orbit", f"baseline (measured on {orbits // scale} orbits)"))
    finally:
        numba.set_num_threads(threads)
    rows.append(Row("k", "ratio NumPy / compiled, branch rule", t[base[0][0]] / t[parts[2][0]], "x", ""))
    rows.append(Row("k", "ratio NumPy / compiled, 10-step continued call", t[base[1][0]] / t[parts[7][0]], "x",
                    "issue 14 target >= 20"))


_COMPILE_ONE = r"""
import json, sys, time
t0 = time.perf_counter()
from jetgaudin.backlund.kernels import _select
import numba
t_import = time.perf_counter() - t0
out = {"import": t_import}
for name in sys.argv[1:]:
    t = time.perf_counter()
    _select._compile_one(name, 9)
    out[name] = time.perf_counter() - t
print(json.dumps(out))
"""


def _cold(names: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, NUMBA_CACHE_DIR=d)
        out = subprocess.run([sys.executable, "-c", _COMPILE_ONE, *names], capture_output=True, text=True, env=env,
                             timeout=1800, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def bench_compile_parts(rows, Row):
    """(l) Cold compile (fresh process, empty cache) of each kernel alone, and of the main job's + ``orbit
    --kernel compiled``'s + ``ensemble``'s kernels together (``run_orbit3``, ``nu_default_kernel``, ``run_lanes3``:
    the shared blocks are compiled once)."""
    from jetgaudin.backlund.kernels import _select

    for name in ("nu_default_kernel", "run_orbit3", "run_lanes3"):
        r = _cold([name])
        rows.append(Row("l", f"cold compile, {name} alone", r[name], "s",
                        f"expected {_select.EXPECTED_COMPILE_S[name]:g} s (the message's figure); Numba import "
                        f"{r['import']:.2f} s apart"))
    names = ["nu_default_kernel", "run_orbit3", "run_lanes3"]
    r = _cold(names)
    total = sum(r[n] for n in names)
    rows.append(Row("l", "cold compile, main job + orbit --kernel compiled + ensemble", total, "s",
                    " + ".join(f"{n} {r[n]:.1f}" for n in names) + "; target <= 15 s"))


_BRANCH_BASELINE = r"""
import json, sys, time
import numpy as np
from jetgaudin.backlund.kernels import _drivers
import numba
k = _drivers.kernel_module("_branch")
if sys.argv[1:] == ["after_orbit3"]:  # the marginal cost: Numba's first-compile set-up paid by run_orbit3 first
    _drivers.iterate_single(np.array([0, 0, 1.0, 0, 0, 0, 0, 0, 0]), 1.0, 2 + 1j, 1 + 0j, False, 0, 1)
t = time.perf_counter()
names = [n for n in ("nu_default_kernel", "_nu_default_serial", "_nu_default_batch") if hasattr(k, n)]
X = np.zeros((1, 9)); X[0, 2] = 1.0
for n in names:
    if n == "nu_default_kernel":
        _drivers.nu_default(X, np.ones(1), np.full(1, 2 + 1j))
    else:
        getattr(k, n)(X, np.ones(1), np.full(1, 2 + 1j), 1.0, np.empty(1, complex), np.zeros(1, bool))
print(json.dumps({"names": names, "seconds": time.perf_counter() - t}))
"""


def branch_compile_ab(baseline_src: str, rounds: int = 3, after_orbit3: bool = False) -> list[tuple[str, float, float]]:
    """Cold compile of the branch-rule kernels (fresh process, empty cache), this tree against the sources in
    ``baseline_src`` (e.g. a worktree of the commit before the change), alternated ``rounds`` times
    (``after_orbit3``: timed after ``run_orbit3`` was compiled in the same process, as in ``orbit``).  Returns
    ``[(names, this, baseline)]`` per round."""
    here = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")
    out = []
    for _ in range(rounds):
        t = {}
        for label, src in (("this", here), ("baseline", baseline_src)):
            with tempfile.TemporaryDirectory() as d:
                env = dict(os.environ, NUMBA_CACHE_DIR=d, PYTHONPATH=src)
                args = ["after_orbit3"] if after_orbit3 else []
                r = json.loads(subprocess.run([sys.executable, "-c", _BRANCH_BASELINE, *args], capture_output=True,
                                              text=True, env=env, timeout=600, check=True).stdout.splitlines()[-1])
            t[label] = r
        out.append(("+".join(t["this"]["names"]) + " vs " + "+".join(t["baseline"]["names"]), t["this"]["seconds"],
                    t["baseline"]["seconds"]))
    return out


if __name__ == "__main__":  # python benchmarks/setup_parts.py BASELINE_SRC: the branch rule's compile, A/B
    for after in (False, True):
        for names, a, b in branch_compile_ab(sys.argv[1], after_orbit3=after):
            print(f"{'after run_orbit3: ' if after else ''}{names}: {a:.2f} s against {b:.2f} s (ratio {b / a:.2f}); "
                  f"load {os.getloadavg()[0]:.2f}")
