"""The family kernel's map step (``gaudin/_family_kernel._step``) against the step of another source tree, same run.

Each case is one orbit of ``steps`` map steps of :func:`jetgaudin.gaudin._family_kernel.run_orbit` (the rational
family's own kernel :func:`jetgaudin.gaudin._kernels.run_orbit` in the last case; end state only), thread CPU time
per map step, the best and the median of ``repeat`` calls after a warm-up call.  The two
trees run in separate processes, alternated ``rounds`` times (``PYTHONPATH`` on each tree's ``src``); the ratio
"before / after" is per round, and the end states of the two trees are compared bit for bit (a SHA-1 of the bytes).

``python benchmarks/bench_family_step.py BASE_SRC [rounds] [repeat]`` (``BASE_SRC``: the ``src`` folder of the
tree to compare with, e.g. a ``git archive`` of the base commit); ``--worker`` is the per-process part.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STEPS = 20000


def cases():
    import jetgaudin as jg

    trig3 = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    trig4 = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1), (-1.3, 1)], family="trigonometric", gamma=0.5)
    trig12 = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)], family="trigonometric", gamma=0.5)
    ell2 = jg.GaudinModel(0.0, [(0.0, 1), (0.7, 1)], family="elliptic", modulus=0.6)
    rat3 = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="rational")
    x3 = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])
    return {
        "Clebsch top (elliptic, 1 site of order 2)": (jg.clebsch_top(0.6), np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3]),
                                                      0.31 + 0.27j),
        "elliptic chain, 2 sites of order 1": (ell2, x3[:6], 0.31 + 0.27j),
        "trigonometric chain, 3 sites of order 1": (trig3, x3, 0.4 + 0.3j),
        "trigonometric chain, 4 sites of order 1": (trig4, np.concatenate([x3, [0.2, 0.3, -0.1]]), 0.4 + 0.3j),
        "rational chain, 3 sites of order 1 (GPU route's kernel)": (rat3, x3, 0.4 + 0.3j),
        "trigonometric chain, orders (1, 2)": (trig12, x3, 0.4 + 0.3j),
        "rational chain, 3 sites of order 1 (the rational kernel, gaudin/_kernels)": (rat3, x3, 0.4 + 0.3j),
    }


def worker(repeat: int) -> None:
    from jetgaudin.gaudin import _family_kernel as F
    from jetgaudin.gaudin import _kernels as R

    out = {}
    for name, (model, x0, eta) in cases().items():
        b = float(model.b)
        nu0 = 1.0 + 0.0j
        if "gaudin/_kernels" in name:  # the rational family's own kernel (its CPU route)
            c = R.orbit_constants(model, eta)

            def run(c=c, b=b, x0=x0, nu0=nu0, eta=eta):
                return R.run_orbit(x0, b, eta, nu0, *c, STEPS, STEPS)
        else:
            c = F.orbit_constants(model, eta)

            def run(c=c, b=b, x0=x0, nu0=nu0):
                return F.run_orbit(x0, b, nu0, *c, STEPS, STEPS)

        rows, final, nu = run()  # compile / load, warm up
        ts = []
        for _ in range(repeat):
            t = time.thread_time()
            run()
            ts.append(time.thread_time() - t)
        ts = np.array(ts) / STEPS * 1e6
        out[name] = {"best_us": float(ts.min()), "median_us": float(np.median(ts)),
                     "sha1": hashlib.sha1(np.concatenate([final, [nu.real, nu.imag]]).tobytes()).hexdigest()[:12],
                     "finite": bool(np.all(np.isfinite(final)))}
    print(json.dumps(out))


def _run(src: str, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=src)
    p = subprocess.run([sys.executable, __file__, "--worker", str(repeat)], env=env, capture_output=True, text=True,
                       check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(base: str, rounds: int = 3, repeat: int = 15) -> None:
    mine = str(HERE.parent / "src")
    cpu = next((ln.split(":", 1)[1].strip() for ln in subprocess.run(["lscpu"], capture_output=True, text=True)
                .stdout.splitlines() if ln.startswith("Model name")), "?")
    print(f"machine: {cpu}; load {os.getloadavg()[0]:.1f}; {STEPS} map steps per call, µs per map step, "
          f"best (median) of {repeat}; before = {base}, after = {mine}")
    res: dict[str, list] = {}
    for _ in range(rounds):
        before = _run(base, repeat)
        after = _run(mine, repeat)
        for name in before:
            res.setdefault(name, []).append((before[name], after[name]))
    for name, pairs in res.items():
        print(name)
        for bf, af in pairs:
            same = "bit for bit" if bf["sha1"] == af["sha1"] else f"DIFFERENT ({bf['sha1']} vs {af['sha1']})"
            print(f"  before {bf['best_us']:.3f} ({bf['median_us']:.3f})  after {af['best_us']:.3f} "
                  f"({af['median_us']:.3f})  best/best {bf['best_us'] / af['best_us']:.2f}x  end states {same}")


if __name__ == "__main__":
    if sys.argv[1] == "--worker":
        worker(int(sys.argv[2]))
    else:
        main(sys.argv[1], *(int(a) for a in sys.argv[2:]))
