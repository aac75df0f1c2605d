"""The GPU targets of issue 36 through the run layer, in one command for a machine with an NVIDIA GPU.

    python benchmarks/gpu_run_checks.py --json gpu_run.json                 # on the GPU machine (~10 minutes)
    NUMBA_ENABLE_CUDASIM=1 python benchmarks/gpu_run_checks.py --smoke      # the script's logic here (simulator)

Checks (each a fresh process of the command line tool, as a user runs it; sizes divided by 10⁴ with ``--smoke``):

1. **end to end** -- ``jetgaudin ensemble --backend gpu`` of 10⁷ N = 3 orbits × 10⁴ steps, ``--save-every 1000``: the
   wall time of the whole command (start-up, sampling, branch rule, compile, stepping, writing) and the rate the
   command prints, against the kernel's rate measured in the same run (``gpu.run_batch`` on 10⁶ orbits × 2000
   steps, final state only: ``gpu.last_timing().kernel``).  Target: ≥ 50 % of the kernel's rate end to end.
2. **SIGINT and resume** -- 10⁶ orbits × 2·10⁵ steps, ``--save-every 20000``, SIGINT after 1/3 of the uninterrupted
   run's time, ``--resume``; the saved rows equal the uninterrupted run's bit for bit (same device).
3. **chain** -- a trigonometric chain (4 order-1 sites, γ = 1) of 10⁶ orbits × 2000 steps through the CLI, against the
   chain kernel's rate (``gpu.run_chain`` on 10⁶ orbits × 100 steps).  Target: ≥ 30 %.
4. **tests** -- ``JETGAUDIN_TEST_REAL_GPU=1 pytest tests/test_gpu.py``.

Prints one JSON object per check (``--json`` writes them all); the GPU and host are named (``nvidia-smi``, lscpu).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))  # the checks import the tree's jetgaudin (the device has no install of it)
CLI = [sys.executable, "-m", "jetgaudin"]
KSCALE = 1  # the kernel-rate sizes' divisor: 10^4 under --smoke; --scale leaves them whole (a full GPU)
SITES = ["--sites", "0:1,0.5:1,1:1,1.5:1", "--family", "trigonometric", "--gamma", "1", "--eta", "0.4+0.05i"]


def env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""))


def device() -> dict:
    out: dict = {}
    for key, cmd in (("gpu", ["nvidia-smi", "--query-gpu=name,driver_version,memory.total", "--format=csv,noheader"]),
                     ("host", ["lscpu"])):
        try:
            text = subprocess.run(cmd, capture_output=True, text=True, timeout=20).stdout
        except (OSError, subprocess.SubprocessError):
            text = ""
        if key == "host":
            text = next((ln.split(":", 1)[1].strip() for ln in text.splitlines() if ln.startswith("Model name")), "")
        out[key] = text.strip()
    return out


def rate_of(output: str) -> float | None:
    m = re.search(r"rate: ([0-9.e+]+) orbit-steps/s", output)
    return float(m.group(1)) if m else None


def ensemble(args: list[str], out: Path, timeout: float, extra: list[str] = ()) -> tuple[float, str, int]:
    t0 = time.perf_counter()
    p = subprocess.run(CLI + ["ensemble", *args, "--out", str(out), "--no-progress", *extra], env=env(),
                       capture_output=True, text=True, timeout=timeout)
    return time.perf_counter() - t0, p.stdout + p.stderr, p.returncode


def kernel_rate(B: int, steps: int, chain: bool = False) -> float:
    """The GPU kernel's orbit-steps/s on ``B`` orbits × ``steps`` (final state only), the second of two calls."""
    from jetgaudin import gpu

    if chain:
        import jetgaudin as jg

        model = jg.GaudinModel(1.0, [(0.0, 1), (0.5, 1), (1.0, 1), (1.5, 1)], family="trigonometric", gamma=1.0)
        X = np.random.default_rng(1).normal(size=(B, model.n_state))
        nu0 = model.two_point_backlund(0.4 + 0.05j).start(X) if B <= 10**5 else None
        if nu0 is None:
            nu0 = np.resize(model.two_point_backlund(0.4 + 0.05j).start(X[:10**5]), B)
        for _ in range(2):
            gpu.run_chain(model, 0.4 + 0.05j, X, nu0, steps, steps)
    else:
        from jetgaudin.backlund.kernels import _drivers as C
        from jetgaudin.ensemble import sample_on_leaf

        X = sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=3)
        b, e = np.ones(B), np.full(B, 5 + 0.1j)
        nu0 = C.nu_default(X, b, e, 1)
        for _ in range(2):
            gpu.run_batch(X, b, e, nu0, False, steps, steps, want_drift=False)
    t = gpu.last_timing()
    return t.orbits * t.steps / t.kernel if t.kernel > 0 else float("nan")


def check_end_to_end(tmp: Path, scale: int) -> dict:
    B, steps = 10**7 // scale, 10**4 // max(1, scale // 100)
    k = kernel_rate(max(1000, 10**6 // KSCALE), max(20, 2000 // KSCALE))
    wall, out, rc = ensemble(["--orbits", str(B), "--steps", str(steps), "--save-every", str(max(1, steps // 10)),
                              "--backend", "gpu"], tmp / "e2e", 3000)
    printed = rate_of(out)
    return {"check": "end to end", "orbits": B, "steps": steps, "rc": rc, "wall_s": wall,
            "rate_whole_command": B * steps / wall, "rate_printed": printed, "kernel_rate": k,
            "printed_over_kernel": None if printed is None else printed / k,
            "whole_command_over_kernel": B * steps / wall / k, "target": ">= 0.5", "tail": out[-600:]}


def launch(args: list[str], out: Path) -> tuple[subprocess.Popen, float, float]:
    """Start ``ensemble`` and wait until its run directory holds a checkpoint (the stepping has begun): the process, its
    start time and the seconds until then (start-up, sampling, compiles)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(CLI + ["ensemble", *args, "--out", str(out), "--no-progress"], env=env(),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    while p.poll() is None and not any(out.glob("checkpoint*")) and time.perf_counter() - t0 < 600:
        time.sleep(0.02)
    return p, t0, time.perf_counter() - t0


def check_sigint_resume(tmp: Path, scale: int) -> dict:
    from jetgaudin import run as rl

    B, steps = 10**6 // scale, 2 * 10**5 // max(1, scale // 100)
    args = ["--orbits", str(B), "--steps", str(steps), "--save-every", str(max(1, steps // 10)), "--backend", "gpu"]
    p, t0, t_up_full = launch(args, tmp / "full")
    out_full = p.communicate(timeout=3000)[0]
    t_full, rc_full = time.perf_counter() - t0, p.returncode
    # SIGINT halfway through the stepping (the full run's printed stepping time, counted from the first checkpoint),
    # not during the start-up or the summary after it
    m = re.search(r"([0-9.]+) s stepping", out_full)
    stepping = float(m.group(1)) if m else (t_full - t_up_full) / 4
    p, t0, t_up = launch(args, tmp / "int")
    time.sleep(max(0.02, stepping / 2))
    p.send_signal(signal.SIGINT)
    out_int = p.communicate(timeout=600)[0]
    t0 = time.perf_counter()
    q = subprocess.run(CLI + ["ensemble", "--resume", str(tmp / "int"), "--no-progress"], env=env(),
                       capture_output=True, text=True, timeout=3000)
    t_res, out_res, rc_res = time.perf_counter() - t0, q.stdout + q.stderr, q.returncode
    a, b = rl.load(tmp / "full"), rl.load(tmp / "int")
    equal = bool(np.array_equal(a.X, b.X) and np.array_equal(getattr(a, "n", 0), getattr(b, "n", 0)))
    return {"check": "SIGINT and resume", "orbits": B, "steps": steps, "rc_full": rc_full,
            "rc_interrupted": p.returncode, "rc_resumed": rc_res, "wall_full_s": t_full,
            "startup_full_s": t_up_full, "startup_interrupted_s": t_up, "wall_resume_s": t_res,
            "bit_for_bit": equal, "interrupted_while_stepping": rc_res == 0 and p.returncode == 130,
            "interrupted_tail": out_int[-300:], "resumed_tail": out_res[-300:], "full_tail": out_full[-300:]}


def check_chain(tmp: Path, scale: int) -> dict:
    B, steps = 10**6 // scale, 2000 // max(1, scale // 100)
    k = kernel_rate(max(1000, 10**6 // KSCALE), max(10, 100 // KSCALE), chain=True)
    wall, out, rc = ensemble(SITES + ["--orbits", str(B), "--steps", str(steps), "--save-every", str(steps),
                                      "--backend", "gpu"], tmp / "chain", 3000)
    printed = rate_of(out)
    return {"check": "trigonometric chain", "orbits": B, "steps": steps, "rc": rc, "wall_s": wall,
            "rate_printed": printed, "kernel_rate": k, "printed_over_kernel": None if printed is None else printed / k,
            "whole_command_over_kernel": B * steps / wall / k, "target": ">= 0.3", "tail": out[-600:]}


def check_tests(files: list[str]) -> dict:
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *files],
                       env=dict(env(), JETGAUDIN_TEST_REAL_GPU="1"), cwd=ROOT, capture_output=True, text=True,
                       timeout=1200)
    return {"check": f"pytest {' '.join(files)} on the GPU", "rc": p.returncode, "wall_s": time.perf_counter() - t0,
            "tail": (p.stdout + p.stderr)[-1500:]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", type=Path, help="write the results here")
    ap.add_argument("--smoke", action="store_true", help="sizes / 10^4 (the script's logic; under the simulator)")
    ap.add_argument("--only", default="1234", help="which checks, in this order (digits 1-4; default all)")
    ap.add_argument("--scale", type=int, default=1, help="divide the sizes by this (a short lease; default 1)")
    ap.add_argument("--tests", default="tests/test_gpu.py tests/test_gpu_sun.py tests/test_bite_gpu.py",
                    help="the test files of check 4")
    a = ap.parse_args(argv)
    if a.scale < 1:
        ap.error(f"--scale must be a positive integer, got {a.scale}")
    scale = 10**4 if a.smoke else a.scale
    global KSCALE
    KSCALE = 10**4 if a.smoke else 1
    results = [dict(device(), check="device")]
    print(json.dumps(results[0]), flush=True)
    with tempfile.TemporaryDirectory(prefix="jetgaudin-gpu-checks-") as d:
        tmp = Path(d)
        checks = {"1": lambda: check_end_to_end(tmp, scale), "2": lambda: check_sigint_resume(tmp, scale),
                  "3": lambda: check_chain(tmp, scale), "4": lambda: check_tests(a.tests.split())}
        for digit in dict.fromkeys(a.only):
            if digit not in checks or (digit == "4" and a.smoke):
                continue
            try:
                r = checks[digit]()
            except Exception as exc:  # one check's failure is reported, the others still run
                r = {"check": digit, "error": f"{type(exc).__name__}: {exc}"}
            results.append(r)
            print(json.dumps(r, default=str), flush=True)
            if a.json:  # after every check: a lease that ends early keeps what was measured
                a.json.write_text(json.dumps(results, indent=1, default=str) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
