"""How long an ensemble's row append and checkpoint hold the run's thread, current sources against a baseline commit
(issue 36): the host work the GPU's stepping waits for.

In a fresh process per tree: an ensemble run directory of ``B`` orbits (N = 3), then ``rounds`` times: append one
saved row (a fresh ``(1, B, 9)`` array), write a checkpoint (state, ``ν1``, anchor, drift), then sleep ``device``
seconds -- the run's thread waiting for the GPU's next call (the GIL free, as in a CUDA synchronize).  Printed: the
median seconds the append and the checkpoint calls hold the run's thread, and the whole loop's wall time against
``rounds × device`` (what a device that never waits for the host would take).

    python benchmarks/store_main_thread.py --baseline 9c81781 [--orbits 1000000 --rounds 6 --device 1.0]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from _baseline import extract_src  # benchmarks/ is the script's directory: on sys.path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = r"""
import json, sys, time
from pathlib import Path
import numpy as np
from jetgaudin import run as rl
from jetgaudin.run import api
from jetgaudin.run.health import Health
from jetgaudin.ensemble import BatchBacklund, sample_on_leaf
B, rounds, device, out = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), Path(sys.argv[4])
X0 = sample_on_leaf(3, [1.0, 0.5, 2.0], B, seed=0)
m = BatchBacklund(np.ones(B), np.full(B, 5 + 0.1j), backend="compiled")
spec = rl.RunSpec(m, X0, 10 * rounds, 10, rl.HealthLimits(max_drift=1e-6), csv=False, program="jetgaudin ensemble")
health = Health(spec.map, spec.X0, spec.limits)
out.mkdir()
store = api._open_store(spec, out, api._new_record(spec, health), fresh=True)
store.begin(True)
rng = np.random.default_rng(1)
t_app, t_ck = [], []
t0 = time.perf_counter()
for r in range(rounds):
    S = X0[None] + rng.normal(scale=1e-3, size=(1, B, 9))
    t = time.perf_counter(); store.append(np.array([10 * (r + 1)]), S); t_app.append(time.perf_counter() - t)
    store.anchor = (10 * r, X0 + r, np.full(B, 1 + 0j))
    store.drift_rel = np.zeros((B, 6))
    t = time.perf_counter(); store.checkpoint(10 * (r + 1), S[0], np.full(B, 1 + 0j), {"status": "running"})
    t_ck.append(time.perf_counter() - t)
    time.sleep(device)
t = time.perf_counter()
getattr(store, "wait", lambda: None)()
t_end = time.perf_counter() - t
wall = time.perf_counter() - t0
store.close()
print(json.dumps({"append_median": float(np.median(t_app)), "checkpoint_median": float(np.median(t_ck)),
                  "final_wait": t_end, "wall": wall, "device_total": rounds * device}))
"""


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--baseline", required=True)
    p.add_argument("--orbits", type=int, default=10**6)
    p.add_argument("--rounds", type=int, default=6)
    p.add_argument("--device", type=float, default=1.0, help="seconds of (simulated) device work per round")
    p.add_argument("--repeat", type=int, default=2, help="processes per tree, alternated")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"current": ROOT / "src", args.baseline: extract_src(ROOT, args.baseline, Path(tmp))}
        for k in range(args.repeat):
            for name, src in trees.items():
                out = Path(tmp) / f"{name}-{k}"
                r = subprocess.run([sys.executable, "-c", _CHILD, str(args.orbits), str(args.rounds), str(args.device),
                                    str(out)], env=dict(os.environ, PYTHONPATH=str(src)), capture_output=True,
                                   text=True, timeout=1800)
                if r.returncode:
                    raise SystemExit(r.stderr[-2000:])
                v = json.loads(r.stdout.strip().splitlines()[-1])
                print(f"{name:>10}: append holds the run's thread {v['append_median']:.3f} s, checkpoint "
                      f"{v['checkpoint_median']:.3f} s (medians); loop {v['wall']:.2f} s for {v['device_total']:.1f} s "
                      f"of device work (final wait {v['final_wait']:.2f} s)", flush=True)


if __name__ == "__main__":
    main()
