"""The same timings on the current sources and on a baseline commit, alternated in one run (ratios current/baseline).

Used for the "before/after the kernels split" line of ``docs/performance.md``: the baseline's ``src/`` is taken
with ``git archive`` into a temporary directory and each measurement runs in a fresh process with that ``src`` on
``PYTHONPATH`` (kernels compiled once per side first, then loaded from Numba's cache; compile time excluded).

Examples (every value shown is accepted):

    python benchmarks/before_after.py --baseline a6da685
    python benchmarks/before_after.py --baseline a6da685 --rounds 5
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

_SNIPPET = r"""
import json, time
import numpy as np
import jetgaudin as jg
from jetgaudin.backlund import _kernels as K
from jetgaudin.ensemble import sample_on_leaf
X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])
B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
nu0 = K.nu_default(X0[None], [1.0], [5 + 0.1j])[0]
n = 10**5
X = sample_on_leaf(3, [0.5, 0.2, 1.0], n, seed=2); b = np.full(n, 1.0); eta = np.full(n, 5 + 0.1j)
nu = K.nu_default(X, b, eta)
B.iterate(X0, 10, kernel="compiled"); B.iterate(X[:300], 2, kernel="compiled")
K.iterate_single(X0, 1.0, 5 + 0.1j, nu0, False, 10, 10); K.run_batch(X[:4], b[:4], eta[:4], nu[:4], False, 2, 2)
def med(f, r, clock=time.perf_counter):
    v = []
    for _ in range(r):
        t = clock(); f(); v.append(clock() - t)
    return float(np.median(v))
res = {
  "one orbit N=3, 1e6 steps (steps/s, CPU time)":
      1e6 / med(lambda: K.iterate_single(X0, 1.0, 5 + 0.1j, nu0, False, 10**6, 1000), 3, time.thread_time),
  "iterate() Appendix 2, 1000 steps (calls/s, CPU time)":
      1 / med(lambda: B.iterate(X0, 1000, kernel="compiled"), 20, time.thread_time),
  "ensemble 1e5 x 100, run_batch (orbit-steps/s, wall)":
      n * 100 / med(lambda: K.run_batch(X, b, eta, nu, False, 100, 100), 3),
  "iterate(X, 10), 1e5 orbits (orbit-steps/s, wall)":
      n * 10 / med(lambda: B.iterate(X, 10, kernel="compiled"), 3),
}
print(json.dumps(res))
"""


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--baseline", required=True, help="a git commit of this repository (e.g. a6da685)")
    p.add_argument("--rounds", type=int, default=3, help="alternations current/baseline (default 3)")
    return p


def _run(src: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run([sys.executable, "-c", _SNIPPET], capture_output=True, text=True, env=env, check=True,
                         timeout=3600).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> None:
    a = parser().parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", a.baseline, "src"], capture_output=True,
                                 check=True).stdout
        subprocess.run(["tar", "-x", "-C", d], input=archive, check=True)
        sides = {"current": ROOT / "src", "baseline": Path(d) / "src"}
        for src in sides.values():  # compile / load once per side
            _run(src)
        results: dict[str, list[dict]] = {k: [] for k in sides}
        for _ in range(a.rounds):
            for k, src in sides.items():
                results[k].append(_run(src))
    for name in results["current"][0]:
        cur = [r[name] for r in results["current"]]
        base = [r[name] for r in results["baseline"]]
        ratio = np.median(cur) / np.median(base)
        print(f"{name}: current {np.median(cur):.3g}, baseline {np.median(base):.3g}, ratio {ratio:.2f} "
              f"(current {min(cur):.3g}-{max(cur):.3g}, baseline {min(base):.3g}-{max(base):.3g})")
    print("load average at the end:", os.getloadavg())


if __name__ == "__main__":
    main()
