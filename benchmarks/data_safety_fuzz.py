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


# ------------------------------------------------------------------------------------------ issue 35
def snapshot(d: Path) -> dict:
    """Bytes and ``mtime_ns`` of ``d`` and of everything under it (the directory comparison of issue 35)."""
    out = {}
    if not d.exists():
        return out
    for root, dirs, files in os.walk(d):
        for name in [".", *dirs, *files]:
            p = os.path.join(root, name)
            st = os.lstat(p)
            data = hashlib.sha256(open(p, "rb").read()).hexdigest() if os.path.isfile(p) else None
            out[os.path.normpath(os.path.relpath(p, d))] = (st.st_mode, data, st.st_mtime_ns)
    return out


def _cli(args: list, env: dict | None = None, timeout: float = 120, stdout=None, memory: int = 4 << 30):
    """``jetgaudin ARGS`` in a subprocess with at most ``memory`` bytes of address space (a bomb must not take the
    machine) and ``timeout`` seconds; ``(returncode, stderr, seconds)`` (returncode ``None``: timed out)."""
    import time

    def setup():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    t0 = time.monotonic()
    try:
        r = subprocess.run(JG + [str(a) for a in args], capture_output=stdout is None, stdout=stdout, errors="replace",
                           stderr=subprocess.PIPE if stdout is not None else None, text=True, timeout=timeout,
                           env=None if env is None else dict(os.environ, **env), preexec_fn=setup)
    except subprocess.TimeoutExpired:
        return None, "timed out", time.monotonic() - t0
    return r.returncode, r.stderr or "", time.monotonic() - t0


def _one_line(code, err: str, codes=(1, 2)) -> bool:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return code in codes and len(lines) == 1 and "Traceback" not in err


def _npz_bomb(path: Path, rows: int, declared_only: bool) -> None:
    """An NPZ whose member ``X.npy`` declares ``(rows, 9)`` doubles: with ``declared_only`` the data are absent (a
    lying header); otherwise ``rows * 72`` zero bytes deflated (a zip bomb: ~1000:1)."""
    import zipfile

    header = np.lib.format.header_data_from_array_1_0(np.zeros((0, 9)))
    header["shape"] = (rows, 9)
    buf = __import__("io").BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        with z.open("X.npy", "w", force_zip64=True) as f:
            f.write(buf.getvalue())
            if not declared_only:
                block, left = bytes(1 << 24), rows * 72
                while left > 0:
                    f.write(block[: min(left, len(block))])
                    left -= len(block)


def fuzz_bombs(rng) -> dict:
    """Resource bombs: each must end within its time with one line (exit 1 or 2) or a completed run, under a 4 GiB
    address-space limit, and create nothing when refused."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        sites = ",".join(f"{i + 0.5}:1" for i in range(2000))  # off Re(eta) = 5
        big_csv = d / "nul.csv"
        with open(big_csv, "wb") as f:
            f.truncate(int(1.9e9))  # sparse: 1.9 GB of NUL bytes, no disk used
        _npz_bomb(d / "header.npz", 10**10, True)
        _npz_bomb(d / "zip.npz", int(rng.integers(8, 16)) * 10**6, False)
        run = d / "run"
        assert _cli(["orbit", "--steps", 30, "--kernel", "numpy", "--no-plots", "--out", run])[0] == 0
        cases = {
            "ensemble --orbits 1e9": ["ensemble", "--orbits", "1e9", "--steps", 2, "--no-progress"],
            "orbit 2000 sites": ["orbit", "--sites", sites, "--steps", 2, "--no-plots"],
            "ensemble 2000 sites": ["ensemble", "--sites", sites, "--orbits", 2, "--steps", 2, "--no-progress"],
            "npz lying header 1e10 rows": ["ensemble", "--input", d / "header.npz", "--steps", 2, "--no-progress"],
            "npz zip bomb": ["ensemble", "--input", d / "zip.npz", "--steps", 2, "--no-progress"],
            "1.9 GB NUL csv": ["ensemble", "--input", big_csv, "--steps", 2, "--no-progress"],
        }
        for name, args in cases.items():
            target = d / f"o{len(out)}"
            code, err, secs = _cli(args + ["--out", target], timeout=180)
            ok = (code == 0 and rl.read_run(target)["status"] == "completed") or (
                _one_line(code, err) and not target.exists())
            out[name] = (ok, f"exit {code} in {secs:.1f} s: {err.strip()[-160:]}")
        for name, args in {"plot --dpi 1e5": ["plot", run, "--dpi", "1e5"],
                           "plot --dpi 100000": ["plot", run, "--dpi", "100000"],
                           "plot --max-points 1e12": ["plot", run, "--max-points", str(10**12)]}.items():
            before = snapshot(run)
            code, err, secs = _cli(args, timeout=180)
            ok = (_one_line(code, err) or code == 0) and (code == 0 or snapshot(run) == before)
            out[name] = (ok, f"exit {code} in {secs:.1f} s: {err.strip()[-160:]}")
    return out


def fuzz_backend_resume(trials: int, rng) -> tuple[int, int]:
    """An interrupted ensemble resumed with another ``--backend``: refused (exit 2, one line), directory unchanged."""
    from jetgaudin.ensemble import BatchBacklund, sample_on_leaf

    held = 0
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            out = Path(d) / "e"
            rec = str(rng.choice(["numpy", "compiled"]))
            X = sample_on_leaf(3, [0.4, -0.3, 1.5], int(rng.integers(2, 20)), seed=int(rng.integers(100)))
            m = BatchBacklund(np.full(len(X), 1.0), np.full(len(X), 5 + 0.1j), backend=rec)
            steps = int(rng.integers(20, 80))
            stop_at = int(rng.integers(3, steps - 3))

            def progress(n, _t, at=stop_at):
                if n >= at:
                    os.kill(os.getpid(), signal.SIGINT)
            try:
                rl.start(rl.RunSpec(m, X, steps, int(rng.integers(1, 6)), checkpoint_seconds=0.0,
                                    program="jetgaudin ensemble"), out, progress=progress, max_chunk_steps=3)
            except rl.RunInterrupted:
                pass
            if rl.read_run(out)["status"] != "interrupted":  # not a trial of a resume
                raise RuntimeError("the ensemble was not interrupted")
            other = "compiled" if rec == "numpy" else "numpy"
            before = snapshot(out)
            code, err, _ = _cli(["ensemble", "--resume", out, "--backend", other, "--no-progress"])
            held += _one_line(code, err, (2,)) and snapshot(out) == before
    return trials, held


def fuzz_flow_t(trials: int, rng) -> tuple[int, int, dict]:
    """An interrupted exact-flow run (``orbit --dt``: columns ``n, t``) whose ``t`` is edited (in ``orbit.h5`` at a
    random row; or in the CSV's last row, digests recomputed): held = the resume refused with the directory
    unchanged, or completed with ``t == n dt`` in ``orbit.h5`` and in the CSV's last row."""
    from jetgaudin.run.files import read_csv

    held, kinds = 0, {}
    for _ in range(trials):
        with tempfile.TemporaryDirectory() as d:
            out = Path(d) / "f"
            dt = float(rng.choice([0.05, -0.03, 0.1]))
            E = jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), dt, backend="numpy")
            steps = int(rng.integers(300, 700))  # a flow is cut in fixed calls of 256 steps: stopped after one
            stop_at = int(rng.integers(5, steps - 300))

            def progress(n, _t, at=stop_at):
                if n >= at:
                    os.kill(os.getpid(), signal.SIGINT)
            try:
                rl.start(rl.RunSpec(E, X0, steps, int(rng.integers(1, 5)), checkpoint_seconds=0.0, stem="orbit"),
                         out, progress=progress, max_chunk_steps=3)
            except rl.RunInterrupted:
                pass
            run = rl.read_run(out)
            if run["status"] != "interrupted":  # not a trial of a resume
                raise RuntimeError(f"the exact-flow run was not interrupted: {run['status']}")
            kind = str(rng.choice(["h5 t", "csv last t"]))
            if kind == "h5 t":
                import h5py

                with h5py.File(out / "orbit.h5", "r+") as f:
                    i = int(rng.integers(f["t"].shape[0]))
                    f["t"][i] = float(f["t"][i]) + float(rng.choice([1e-12, 1.0, -dt]))
            else:
                lines = (out / "orbit.csv").read_bytes().splitlines(keepends=True)
                cells = lines[-1].split(b",")
                cells[1] = repr(float(cells[1]) + 1e-9).encode()
                lines[-1] = b",".join(cells)
                data = b"".join(lines)
                (out / "orbit.csv").write_bytes(data)
                run["checkpoint"].update(csv_bytes=len(data), csv_sha256=hashlib.sha256(data).hexdigest())
                write_run(out, run)
            before = snapshot(out)
            try:
                rl.resume(out)
                data = rl.load(out)
                import h5py

                with h5py.File(out / "orbit.h5") as f:
                    t = f["t"][()]
                n_csv, _ = read_csv(out / "orbit.csv")[:2]
                ok = bool(np.array_equal(t, data.n * dt)) and float(open(out / "orbit.csv").read().splitlines()[-1]
                                                                    .split(",")[1]) == data.n[-1] * dt
                kind += " (resumed, t repaired)" if ok else " (resumed, t wrong)"
                del n_csv
            except jg.RecordingError:
                ok = snapshot(out) == before
                kind += " (refused)"
            held += ok
            t_, h_ = kinds.get(kind, (0, 0))
            kinds[kind] = (t_ + 1, h_ + ok)
    return trials, held, kinds


def fuzz_environment() -> dict:
    """stdout to /dev/full, odd encodings, odd Numba settings: held = exit 0 with a completed run, or one line
    (exit 1 or 2) with no traceback; a refusal leaves nothing."""
    out: dict = {}
    base = ["orbit", "--steps", 300, "--no-plots"]
    cases: dict[str, tuple[list, dict, bool]] = {
        "stdout /dev/full": (base + ["--kernel", "numpy"], {}, True),
        "LANG=C LC_ALL=C": (base, {"LANG": "C", "LC_ALL": "C"}, False),
        "PYTHONIOENCODING=ascii": (base, {"PYTHONIOENCODING": "ascii"}, False),
        "PYTHONIOENCODING=latin-1, info": (["info"], {"PYTHONIOENCODING": "latin-1"}, False),
        "PYTHONIOENCODING=ascii, info": (["info"], {"PYTHONIOENCODING": "ascii"}, False),
        "NUMBA_DISABLE_JIT=1 compiled": (base + ["--kernel", "compiled"], {"NUMBA_DISABLE_JIT": "1"}, False),
        "NUMBA_DISABLE_JIT=1 numpy": (base + ["--kernel", "numpy"], {"NUMBA_DISABLE_JIT": "1"}, False),
        "NUMBA_NUM_THREADS=0": (base + ["--kernel", "compiled"], {"NUMBA_NUM_THREADS": "0"}, False),
        "NUMBA_NUM_THREADS=abc": (base + ["--kernel", "compiled"], {"NUMBA_NUM_THREADS": "abc"}, False),
        "NUMBA_THREADING_LAYER=tbb": (base + ["--kernel", "compiled"], {"NUMBA_THREADING_LAYER": "tbb"}, False),
        "NUMBA_CACHE_DIR unwritable": (base + ["--kernel", "compiled"], {"NUMBA_CACHE_DIR": "/proc/none"}, False),
        "NUMBA_OPT=0": (base + ["--kernel", "compiled"], {"NUMBA_OPT": "0"}, False),
        "NUMBA_BOUNDSCHECK=1": (base + ["--kernel", "compiled"], {"NUMBA_BOUNDSCHECK": "1"}, False),
    }
    for name, (args, env, full) in cases.items():
        with tempfile.TemporaryDirectory() as d:
            target = Path(d) / "o"
            extra = ["--out", target] if args[0] != "info" else []
            if full:
                with open("/dev/full", "w") as devfull:
                    code, err, secs = _cli(args + extra, env=env, stdout=devfull, timeout=300)
            else:
                code, err, secs = _cli(args + extra, env=env, timeout=300)
            done = args[0] == "info" or (target.exists() and (target / "run.json").exists()
                                        and rl.read_run(target)["status"] == "completed")
            ok = (code == 0 and done) or (_one_line(code, err) and (full and done or not target.exists()))
            out[name] = (ok, f"exit {code} in {secs:.1f} s: {err.strip()[-160:]}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials-edit", type=int, default=200)
    ap.add_argument("--trials-disk", type=int, default=16)
    ap.add_argument("--trials-overwrite", type=int, default=40)
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--issue35", action="store_true", help="also the categories of issue 35 (bombs, environment, "
                    "resume with another --backend, exact-flow t edits)")
    ap.add_argument("--trials-backend", type=int, default=6)
    ap.add_argument("--trials-flow", type=int, default=20)
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
    if a.issue35:
        for title, res in (("bombs", fuzz_bombs(rng(4))), ("environment", fuzz_environment())):
            print(f"{title}: {sum(ok for ok, _ in res.values())}/{len(res)} held", flush=True)
            for name, (ok, text) in res.items():
                print(f"  {'held' if ok else 'NOT HELD'}: {name}: {text}", flush=True)
        t, h = fuzz_backend_resume(a.trials_backend, rng(5))
        print(f"resume with another --backend: {h}/{t} held", flush=True)
        t, h, kinds = fuzz_flow_t(a.trials_flow, rng(6))
        print(f"exact-flow t edits: {h}/{t} held; " + ", ".join(f"{k} {hh}/{tt}" for k, (tt, hh) in
                                                                sorted(kinds.items())), flush=True)
    if a.trials_overwrite:
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            t, h = fuzz_overwrite(a.trials_overwrite, rng(3))
        print(f"overwrite: {h}/{t} held")


if __name__ == "__main__":
    main()
