"""Fault injection for issue 26 (``docs/reliability.md``): random hostile edits, real full disks, file size limits and
``--overwrite`` refusals, each trial judged "held" or not.  Seeded; prints one line per category and a summary.

    PYTHONPATH=src python benchmarks/data_safety_fuzz.py [--trials-edit 200] [--trials-disk 16] [--seed 26]

Categories (what "held" means):

* ``edit``: an interrupted orbit (kernel, ``save_every``, interruption step random) whose ``run.json`` gets one random
  edit with its digest recomputed (checkpoint state / ``ν1`` / anchor moved by 1-4 ulps, step moved by 1-3,
  ``csv_bytes`` made smaller, ``rows`` changed, ``b`` / ``η`` changed by a relative 1e-6 ... 1e-16, ``save_every``
  changed); held = the resume is refused, or it completes to exactly the uninterrupted orbit (an edit below the
  resolution of a double changes nothing).
* ``tmpfs``: ``jetgaudin orbit``/``ensemble`` on a tmpfs of random size (200 kB - 3 MB; skipped without ``mount``);
  held = exit 0 completed, or exit 1 with ``failed: disk full`` then, after the tmpfs is enlarged, a resume that
  completes bit for bit, or (a disk too small for the run's first files) exit 1, one line and nothing left but the
  lock file.  Never a signal death.
* ``fsize``: the same under a random ``RLIMIT_FSIZE`` (50 kB - 2 MB), the resume without the limit.
* ``overwrite``: a directory of random files and one subdirectory, ``orbit --overwrite``; held = exit 2 and every
  entry unchanged.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.run.files import write_run

X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])
JG = [sys.executable, "-m", "jetgaudin"]


def _ulps(x: float, k: int) -> float:
    for _ in range(abs(k)):
        x = float(np.nextafter(x, np.inf if k > 0 else -np.inf))
    return x


def _interrupted(out: Path, kernel: str, every: int, steps: int, at: int) -> dict:
    m = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend=kernel)

    def progress(n, _total):
        if n >= at:
            os.kill(os.getpid(), signal.SIGINT)

    try:
        rl.start(rl.RunSpec(m, X0, steps, every, checkpoint_seconds=0.0), out, progress=progress, max_chunk_steps=3)
    except rl.RunInterrupted:
        pass
    return rl.read_run(out)


def _edit(run: dict, rng: np.random.Generator) -> tuple[dict, str]:
    ck = run["checkpoint"]
    kind = rng.choice(["state", "nu1", "anchor", "step", "csv_bytes", "rows", "b", "eta", "save_every"])
    k = int(rng.integers(1, 5)) * int(rng.choice([-1, 1]))
    if kind == "state":
        i = int(rng.integers(len(ck["X_hex"])))
        ck["X_hex"][i] = _ulps(float.fromhex(ck["X_hex"][i]), k).hex()
    elif kind == "nu1" and ck["nu1_hex"] is not None:
        i = int(rng.integers(2))
        ck["nu1_hex"][i] = _ulps(float.fromhex(ck["nu1_hex"][i]), k).hex()
    elif kind == "anchor" and "anchor" in ck:
        i = int(rng.integers(len(ck["anchor"]["X_hex"])))
        ck["anchor"]["X_hex"][i] = _ulps(float.fromhex(ck["anchor"]["X_hex"][i]), k).hex()
    elif kind == "step":
        ck["step"] = max(0, ck["step"] + int(rng.integers(1, 4)) * int(rng.choice([-1, 1])))
        run["last_safe_step"] = ck["step"]
    elif kind == "csv_bytes":
        ck["csv_bytes"] = int(rng.integers(0, ck["csv_bytes"]))
    elif kind == "rows":
        ck["rows"] = max(0, ck["rows"] + int(rng.choice([-1, 1])))
    elif kind in ("b", "eta"):
        eps = 10.0 ** -float(rng.uniform(6, 16))
        if kind == "b":
            run["map"]["b"] *= 1 + eps
            run["inputs"]["b"] = run["map"]["b"]
        else:
            run["map"]["eta"][int(rng.integers(2))] *= 1 + eps
            run["inputs"]["eta"] = list(run["map"]["eta"])
    elif kind == "save_every":
        run["inputs"]["save_every"] += int(rng.integers(1, 3))
    return run, str(kind)


def fuzz_edits(trials: int, rng: np.random.Generator) -> tuple[int, int, dict]:
    held, kinds = 0, {}
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            out = Path(d) / "r"
            kernel = str(rng.choice(["numpy", "compiled"]))
            every, steps = int(rng.integers(1, 10)), int(rng.integers(30, 90))
            run = _interrupted(out, kernel, every, steps, int(rng.integers(5, steps - 5)))
            edited, kind = _edit(copy.deepcopy(run), rng)
            write_run(out, edited)
            try:
                rl.resume(out)  # accepted: held only if it is the true orbit, bit for bit
                d_ = rl.load(out)
                ok = bool(np.array_equal(d_.X, jg.TwoPointBacklund(1.0, 5 + 0.1j, backend=kernel).iterate(
                    X0, steps)[d_.n]))
                kind += " (accepted)" if not _same_bits(run, edited) else " (no-op)"
            except jg.RecordingError:
                ok = True
            held += ok
            t, h = kinds.get(kind, (0, 0))
            kinds[kind] = (t + 1, h + ok)
    return trials, held, kinds


def _same_bits(a: dict, b: dict) -> bool:
    """An edit that a double cannot represent (``b * (1 + 1e-17) == b``) leaves the record unchanged."""
    strip = lambda r: {k: v for k, v in r.items() if k != "sha256"}  # noqa: E731
    return strip(a) == strip(b)


def _mount(m: Path, size: str) -> bool:
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(m)],
                          capture_output=True).returncode == 0


def _disk_trial(out: Path, command: list[str], limits: list, enlarge) -> bool:
    def setup():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        for which, n in limits:
            resource.setrlimit(which, (n, n))

    r = subprocess.run(JG + command + ["--out", str(out)], capture_output=True, text=True, preexec_fn=setup,
                       timeout=300)
    if r.returncode == 0:
        return rl.read_run(out)["status"] == "completed"
    if r.returncode != 1 or "Traceback" in r.stderr:
        print(f"  not held: {command} {limits}: exit {r.returncode}: {r.stderr.strip()[-300:]}", flush=True)
        return False
    if not (out / "run.json").exists():  # the files could not even be created: one line, nothing declared, nothing
        left = [p for p in os.listdir(out) if p != ".jetgaudin.lock"] if out.exists() else []  # left but the lock
        if not left and len(r.stderr.strip().splitlines()) == 1 and ("disk full" in r.stderr or "limit" in r.stderr):
            return True
    try:
        run = rl.read_run(out, verify=True)
    except jg.RecordingError as exc:
        print(f"  not held: {command} {limits}: {exc}; files {sorted(os.listdir(out)) if out.exists() else None}; "
              f"{r.stderr.strip()[-300:]}", flush=True)
        return False
    if not (run["status"].startswith("failed: disk full") or run["status"].startswith("failed: file size limit")):
        print(f"  not held: {command} {limits}: status {run['status']!r}", flush=True)
        return False
    enlarge()
    r = subprocess.run(JG + [command[0], "--resume", str(out)] + (["--no-plots"] if command[0] == "orbit" else []),
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        print(f"  not held: {command} {limits}: resume exit {r.returncode}: {r.stderr.strip()[-300:]}", flush=True)
        return False
    d = rl.load(out)
    if command[0] == "orbit":
        ref = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="compiled").iterate(X0, int(d.n[-1]))
    else:
        from jetgaudin.ensemble import BatchBacklund

        ref = BatchBacklund(d.b, d.eta).iterate(d.X0, int(d.n[-1]))
    return bool(np.array_equal(d.X, ref[d.n]))


def _command(rng) -> list[str]:
    if rng.random() < 0.6:
        steps = int(rng.integers(1000, 200000))
        return ["orbit", "--kernel", "compiled", "--steps", str(steps), "--save-every", str(int(rng.integers(1, 50))),
                "--no-plots", "--checkpoint-seconds", "0"] + (["--no-csv"] if rng.random() < 0.3 else [])
    return ["ensemble", "--orbits", str(int(rng.integers(10, 3000))), "--steps", str(int(rng.integers(5, 80))),
            "--no-progress", "--checkpoint-seconds", "0"]


def fuzz_tmpfs(trials: int, rng) -> tuple[int, int] | None:
    if os.geteuid() != 0:
        return None
    held = 0
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            m = Path(d) / "M"
            m.mkdir()
            if not _mount(m, f"{int(rng.integers(200, 3000))}k"):
                return None
            try:
                held += _disk_trial(m / "run", _command(rng), [], lambda m=m: subprocess.run(
                    ["mount", "-o", "remount,size=256m", str(m)], check=True))
            finally:
                subprocess.run(["umount", "-l", str(m)], check=False)
    return trials, held


def fuzz_fsize(trials: int, rng) -> tuple[int, int]:
    held = 0
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            limit = int(rng.integers(50, 2000)) * 1024
            held += _disk_trial(Path(d) / "run", _command(rng), [(resource.RLIMIT_FSIZE, limit)], lambda: None)
    return trials, held


def fuzz_overwrite(trials: int, rng) -> tuple[int, int]:
    from jetgaudin.cli import main

    held = 0
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            D = Path(d) / "D"
            D.mkdir()
            for i in range(int(rng.integers(0, 12))):
                (D / f"f{i}.txt").write_bytes(rng.bytes(int(rng.integers(0, 100))))
            if rng.random() < 0.5:
                rl.start(rl.RunSpec(jg.TwoPointBacklund(1.0, 5 + 0.1j), X0, 3), D, overwrite=True)
            (D / f"sub{int(rng.integers(100))}").mkdir()
            before = {p.name: (p.is_dir() or hashlib.sha256(p.read_bytes()).hexdigest()) for p in D.iterdir()}
            try:
                main(["orbit", "--out", str(D), "--overwrite", "--steps", "3", "--no-plots"])
                code = 0
            except SystemExit as exc:
                code = exc.code
            after = {p.name: (p.is_dir() or hashlib.sha256(p.read_bytes()).hexdigest()) for p in D.iterdir()}
            held += code == 2 and before == after
            shutil.rmtree(D)
    return trials, held


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials-edit", type=int, default=200)
    ap.add_argument("--trials-disk", type=int, default=16)
    ap.add_argument("--trials-overwrite", type=int, default=40)
    ap.add_argument("--seed", type=int, default=26)
    a = ap.parse_args()
    import contextlib
    import io

    def rng(category: int) -> np.random.Generator:  # one stream per category: each reproducible alone
        return np.random.default_rng([a.seed, category])

    if a.trials_edit:
        t, h, kinds = fuzz_edits(a.trials_edit, rng(0))
        print(f"edit: {h}/{t} held; " + ", ".join(f"{k} {hh}/{tt}" for k, (tt, hh) in sorted(kinds.items())))
    if a.trials_disk:
        r = fuzz_tmpfs(a.trials_disk, rng(1))
        print("tmpfs: skipped (mount not permitted)" if r is None else f"tmpfs: {r[1]}/{r[0]} held")
        t, h = fuzz_fsize(a.trials_disk, rng(2))
        print(f"fsize: {h}/{t} held")
    if a.trials_overwrite:
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            t, h = fuzz_overwrite(a.trials_overwrite, rng(3))
        print(f"overwrite: {h}/{t} held")


if __name__ == "__main__":
    main()
