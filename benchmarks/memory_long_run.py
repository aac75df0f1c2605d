"""Resident memory of a long streamed orbit (issue 7): ``jetgaudin orbit --steps 100000000 --save-every 1000``
must stay under 200 MB.

Runs the real command in a subprocess and samples its resident set size (``VmRSS`` of ``/proc/PID/status``,
Linux) every 0.2 s; prints the peak, the time, the steps per second and the size of the files written.
A second, 100 times shorter run in the same process gives a baseline: the peak must not grow with the
length of the run (constant memory).

    python benchmarks/memory_long_run.py                     # 10^8 steps (about a minute, compiled kernel)
    python benchmarks/memory_long_run.py --steps 1000000     # quick
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LIMIT_MB = 200.0


def rss_mb(pid: int) -> tuple[float, float]:
    """``(VmRSS, RssAnon)`` in MB: all resident pages, and the anonymous ones (heap, arrays; without the
    pages of shared libraries such as libLLVM, OpenBLAS, scipy's extension modules)."""
    out = {"VmRSS:": 0.0, "RssAnon:": 0.0}
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                key = line.split()[0] if line.strip() else ""
                if key in out:
                    out[key] = int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return out["VmRSS:"], out["RssAnon:"]


def run(steps: int, save_every: int, out: Path, kernel: str) -> dict:
    cmd = [
        sys.executable,
        "-m",
        "jetgaudin",
        "orbit",
        "--steps",
        str(steps),
        "--save-every",
        str(save_every),
        "--kernel",
        kernel,
        "--no-plots",
        "--out",
        str(out),
    ]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    peak = peak_anon = 0.0
    while proc.poll() is None:
        rss, anon = rss_mb(proc.pid)
        peak, peak_anon = max(peak, rss), max(peak_anon, anon)
        time.sleep(0.05)
    elapsed = time.perf_counter() - t0
    err = proc.stderr.read()
    if proc.returncode != 0:
        raise SystemExit(f"run failed ({proc.returncode}): {err}")
    run_json = json.loads((out / "run.json").read_text())
    sizes = {p.name: p.stat().st_size for p in out.iterdir() if p.is_file()}
    return {
        "steps": steps,
        "peak_rss_mb": peak,
        "peak_anon_mb": peak_anon,
        "seconds": elapsed,
        "steps_per_second": steps / elapsed,
        "status": run_json["status"],
        "rows": run_json["checkpoint"]["rows"],
        "file_bytes": sizes,
    }


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=10**8, help="steps of the long run (an integer; default 100000000)")
    ap.add_argument("--save-every", type=int, default=1000, help="save every k-th state (default 1000)")
    ap.add_argument("--kernel", choices=("auto", "compiled", "numpy"), default="auto", help="default auto")
    return ap


def main() -> None:
    args = parser().parse_args()
    steps = args.steps
    with tempfile.TemporaryDirectory() as d:
        base = run(max(steps // 100, args.save_every), args.save_every, Path(d) / "baseline", args.kernel)
        long = run(steps, args.save_every, Path(d) / "long", args.kernel)
    for name, r in (("baseline", base), ("long run", long)):
        print(
            f"{name:9s}: {r['steps']:.3g} steps, save every {args.save_every}: peak RSS {r['peak_rss_mb']:.1f} MB "
            f"(anonymous {r['peak_anon_mb']:.1f} MB), "
            f"{r['seconds']:.1f} s ({r['steps_per_second']:.3g} steps/s), {r['rows']} rows, status {r['status']}, "
            f"files {r['file_bytes']}"
        )
    growth = long["peak_rss_mb"] - base["peak_rss_mb"]
    print(f"peak RSS growth from the baseline to a 100x longer run: {growth:+.1f} MB (constant memory: ~0)")
    print(
        "(the fixed part is the import of jetgaudin -- NumPy, SciPy, SymPy, h5py: ~116 MB -- and Numba/LLVM "
        "loading the compiled kernels: ~150 MB; see docs/reliability.md)"
    )
    ok = long["peak_rss_mb"] < LIMIT_MB and long["status"] == "completed"
    print(("PASS" if ok else "FAIL") + f": peak {long['peak_rss_mb']:.1f} MB (limit {LIMIT_MB:.0f} MB)")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
