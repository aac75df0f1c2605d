"""The run layer's host-side overhead, current sources against a baseline commit, alternated in one run (issue 36).

``jetgaudin ensemble --backend compiled`` (the CPU route shares the run loop, the checkpoints and the health checks
with the GPU route) on ``B`` orbits × ``steps``, ``--save-every``, in fresh processes with either tree's ``src`` on
``PYTHONPATH``: the whole command's wall time, the stepping rate it prints, and the kernel's own rate (``run_batch``
of the same size in one call, measured in the same process after the command's kernels are loaded).  The fraction
printed rate / kernel rate is what the GPU check 1 of ``benchmarks/gpu_run_checks.py`` measures on a device.

    python benchmarks/run_layer_host.py --baseline 9c81781 [--orbits 1000000 --steps 40 --save-every 10 --rounds 2]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _baseline import extract_src  # benchmarks/ is the script's directory: on sys.path

ROOT = Path(__file__).resolve().parents[1]

_KERNEL = r"""
import json, sys, time
import numpy as np
from jetgaudin.backlund._compiled import kernels
from jetgaudin.ensemble import sample_on_leaf
B, steps = int(sys.argv[1]), int(sys.argv[2])
X = sample_on_leaf(3, [1.0, 0.5, 2.0], B, seed=0)
b, eta = np.ones(B), np.full(B, 5 + 0.1j)
K = kernels()
nu = K.nu_default(X, b, eta, 1)
K.run_batch(X[:64], b[:64], eta[:64], nu[:64], False, 2, 2, True, False)
t = time.perf_counter()
K.run_batch(X, b, eta, nu, False, steps, steps, True, False)
print(json.dumps({"kernel_rate": B * steps / (time.perf_counter() - t)}))
"""


def run_cli(src: Path, out: Path, args: argparse.Namespace) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, "-m", "jetgaudin", "ensemble", "--sample", "leaf", "--casimirs", "1,0.5,2", "--orbits",
           str(args.orbits), "--steps", str(args.steps), "--save-every", str(args.save_every), "--backend",
           "compiled", "--out", str(out), "--overwrite", "--no-progress"]
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        raise SystemExit(f"{src}: exit {r.returncode}: {r.stderr[-2000:]}")
    m = re.search(r"([0-9.]+) s stepping \(([0-9.e+]+) orbit-steps/s\)", r.stdout)
    if m is None:
        raise SystemExit(f"no stepping line in the output of {src}:\n{r.stdout[-2000:]}")
    k = subprocess.run([sys.executable, "-c", _KERNEL, str(args.orbits), str(args.steps)], env=env,
                       capture_output=True, text=True, timeout=1800)
    kernel = json.loads(k.stdout.strip().splitlines()[-1])["kernel_rate"]
    return {"wall": wall, "stepping_s": float(m.group(1)), "rate": float(m.group(2)), "kernel_rate": kernel}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--baseline", required=True, help="the commit to compare with")
    p.add_argument("--orbits", type=int, default=10**6)
    p.add_argument("--steps", type=int, default=40)
    p.add_argument("--save-every", type=int, default=10)
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--json", help="write the results here")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"current": ROOT / "src", args.baseline: extract_src(ROOT, args.baseline, Path(tmp))}
        for src in trees.values():  # compile or load every kernel once per tree, outside the timings
            run_cli(src, Path(tmp) / "warm", argparse.Namespace(**{**vars(args), "orbits": 64, "steps": 4}))
        res: dict[str, list[dict]] = {k: [] for k in trees}
        for r in range(args.rounds):
            for name, src in trees.items():
                res[name].append(run_cli(src, Path(tmp) / name, args))
                v = res[name][-1]
                whole = args.orbits * args.steps / v["wall"] / v["kernel_rate"]
                print(f"round {r} {name:>10}: command {v['wall']:.1f} s, stepping {v['stepping_s']:.2f} s, "
                      f"rate {v['rate']:.3g} = {100 * v['rate'] / v['kernel_rate']:.1f} % of the kernel's "
                      f"{v['kernel_rate']:.3g}, end to end {100 * whole:.1f} %", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
