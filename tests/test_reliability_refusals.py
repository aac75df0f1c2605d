"""Issue 35, item 1: a refusal changes nothing.

Every refusal of ``--resume`` (and of ``plot``) decides before anything is written: the run directory -- every
file's and directory's bytes and ``mtime_ns``, and the lock file's content -- is the same before and after.
Before the fix, a resume claimed the lock (its PID rewritten) and rebuilt ``orbit.h5`` / ``ensemble.h5`` from the
declared rows before the replay, the CSV checks or the digest refused (``orbit.h5`` shrank by 2 kB on a refusal).

Every edit of ``run.json`` recomputes its digest (``write_run``), as anyone editing it would.  The mtimes are set
to an old time before the refusal, so that any write, even within the file system's timestamp granularity, moves
them.  Orbits, ensembles, chains (``--sites``) and exact-flow runs."""

from __future__ import annotations

import copy
import hashlib
import io
import os
import stat

import h5py
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.run.files import write_run
from test_data_safety import EVERY, STEPS, X0, _edit, interrupt_at, two_point
from test_run import run_cli

OLD_NS = 1_000_000_000 * 10**9  # 2001-09-09: any write after this moves an mtime


def snapshot(d) -> dict:
    """``{relative path: (mode, bytes or None, mtime_ns)}`` of ``d`` itself and everything under it."""
    out = {}
    for root, dirs, files in os.walk(d):
        for name in [".", *dirs, *files]:
            p = os.path.join(root, name)
            st = os.lstat(p)
            data = open(p, "rb").read() if stat.S_ISREG(st.st_mode) else None
            out[os.path.normpath(os.path.relpath(p, d))] = (st.st_mode, data, st.st_mtime_ns)
    return out


def age(d) -> None:
    """Set every mtime under ``d`` (and its own) to :data:`OLD_NS`."""
    for root, dirs, files in os.walk(d, topdown=False):
        for name in dirs + files:
            os.utime(os.path.join(root, name), ns=(OLD_NS, OLD_NS), follow_symlinks=False)
    os.utime(d, ns=(OLD_NS, OLD_NS))


# ------------------------------------------------------------------------------------------ the runs
def _orbit(tmp_path):
    out = tmp_path / "orbit"
    return out, interrupt_at(out, two_point("numpy"), X0, STEPS, EVERY, 37)


def _ensemble(tmp_path):
    from jetgaudin.ensemble import BatchBacklund, sample_on_leaf

    Xb = sample_on_leaf(3, [0.4, -0.3, 1.5], 5, seed=3)
    out = tmp_path / "ensemble"
    m = BatchBacklund(np.full(5, 1.0), np.full(5, 5 + 0.1j), backend="numpy")
    return out, interrupt_at(out, m, Xb, 50, 4, 21, program="jetgaudin ensemble")


def _chain(tmp_path):
    model = jg.GaudinModel(1.0, ((-1.0, 1), (0.5, 1), (2.0, 1)))
    m = jg.ChainTwoPointBacklund(model, 5 + 0.1j, backend="numpy")
    out = tmp_path / "chain"
    return out, interrupt_at(out, m, np.array([0.1, 0.2, 1.0, 0.3, -0.2, 0.9, 0.1, 0.1, 1.1]), 40, 3, 20)


def _flow(tmp_path):
    E = jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), 0.05, backend="numpy")
    out = tmp_path / "flow"
    return out, interrupt_at(out, E, X0, 40, 3, 20)


RUNS = {"orbit": _orbit, "ensemble": _ensemble, "chain": _chain, "flow": _flow}


def _ulp(hexes, i=0):
    hexes[i] = np.nextafter(float.fromhex(hexes[i]), np.inf).hex()


def _edit_slot(out, run, change):
    ck = run["checkpoint"]
    with np.load(out / ck["file"]) as d:
        arrays = {k: np.array(d[k]) for k in d.files}
    change(arrays)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    (out / ck["file"]).write_bytes(buf.getvalue())
    ck["sha256"] = hashlib.sha256(buf.getvalue()).hexdigest()
    write_run(out, run)


def _flip_row(path, data):
    with h5py.File(path, "r+") as f:
        x = f[data][0]
        x.flat[0] = np.nextafter(x.flat[0], np.inf)
        f[data][0] = x


def damage(kind, out, run, reason) -> None:
    """Apply ``reason`` to the interrupted run ``out`` of ``kind`` (``run``: its ``run.json``)."""
    run = copy.deepcopy(run)
    if kind == "orbit" and reason in _ORBIT_EDITS:
        write_run(out, _edit(run, reason))
    elif reason == "csv digit changed":
        text = (out / "orbit.csv").read_bytes()
        i = text.rindex(b"1")  # a digit of the last declared row
        (out / "orbit.csv").write_bytes(text[:i] + b"2" + text[i + 1:])
    elif reason == "csv line added, digest recomputed":
        extra = (out / "orbit.csv").read_bytes().splitlines(keepends=True)[-1]
        with open(out / "orbit.csv", "ab") as fh:
            fh.write(extra)
        data = (out / "orbit.csv").read_bytes()
        run["checkpoint"].update(csv_bytes=len(data), csv_sha256=hashlib.sha256(data).hexdigest())
        write_run(out, run)
    elif reason == "h5 row flipped":
        name, data = {"ensemble": ("ensemble.h5", "states"), "flow": ("flow.h5", "X")}.get(kind, ("orbit.h5", "X"))
        _flip_row(out / name, data)
    elif reason == "state by one ulp" and kind in ("chain", "flow"):
        _ulp(run["checkpoint"]["X_hex"], 4)
        write_run(out, run)
    elif reason == "sites by 1e-12":
        run["map"]["sites"][1][0] *= 1 + 1e-12
        write_run(out, run)
    elif reason == "dt by 1e-12":
        run["map"]["dt"] *= 1 + 1e-12
        write_run(out, run)
    elif reason == "slot state by one ulp":
        _edit_slot(out, run, lambda a: a["X"].__setitem__((2, 5), np.nextafter(a["X"][2, 5], np.inf)))
    elif reason == "slot anchor removed":
        _edit_slot(out, run, lambda a: a.__setitem__("anchor_step", np.int64(-1)))
    elif reason == "save_every" and kind == "ensemble":
        run["inputs"]["save_every"] += 1
        write_run(out, run)
    elif reason == "backend":
        run["inputs"]["backend"] = "compiled"
        write_run(out, run)
    else:  # pragma: no cover - a reason without a damage
        raise AssertionError(reason)


_ORBIT_EDITS = ["state by one ulp", "nu1 by one ulp", "step + 1", "step - 1", "csv_bytes = 0", "eta by 1e-12",
                "b by 1e-12", "save_every", "kernel", "anchor by one ulp", "anchor removed"]
CASES = ([("orbit", r) for r in [*_ORBIT_EDITS, "csv digit changed", "csv line added, digest recomputed",
                                  "h5 row flipped"]]
         + [("ensemble", r) for r in ["slot state by one ulp", "slot anchor removed", "save_every", "backend",
                                      "h5 row flipped"]]
         + [("chain", r) for r in ["sites by 1e-12", "state by one ulp", "csv digit changed"]]
         + [("flow", r) for r in ["dt by 1e-12", "state by one ulp", "h5 row flipped"]])


@pytest.mark.parametrize(("kind", "reason"), CASES, ids=[f"{k}-{r}" for k, r in CASES])
def test_a_refused_resume_changes_nothing(tmp_path, kind, reason):
    out, run = RUNS[kind](tmp_path)
    damage(kind, out, run, reason)
    age(out)
    before = snapshot(out)
    assert (out / ".jetgaudin.lock").exists()
    with pytest.raises(jg.JetGaudinError, match="cannot resume"):
        rl.resume(out)
    after = snapshot(out)
    changed = sorted(k for k in before.keys() | after.keys() if before.get(k) != after.get(k))
    assert not changed, f"a refused resume changed {changed}"


@pytest.mark.parametrize("options", [["--orbit", "2"], ["--max-points", "1"]])
def test_a_refused_plot_changes_nothing(tmp_path, capsys, options):
    out, _ = _orbit(tmp_path)
    age(out)
    before = snapshot(out)
    code, _, err = run_cli(capsys, "plot", out, *options)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert snapshot(out) == before


def test_a_resume_without_a_lock_file_creates_it_only_when_it_writes(tmp_path):
    """A directory copied without its dot files: a refusal leaves it without a lock file; a resume takes it."""
    out, run = _orbit(tmp_path)
    (out / ".jetgaudin.lock").unlink()
    write_run(out, _edit(copy.deepcopy(run), "step + 1"))
    age(out)
    before = snapshot(out)
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(out)
    assert snapshot(out) == before
    write_run(out, run)
    rl.resume(out)
    assert (out / ".jetgaudin.lock").read_text().strip() == str(os.getpid())
    d = rl.load(out)
    assert np.array_equal(d.X, two_point("numpy").iterate(X0, STEPS)[d.n])


# --------------------------------------------------------------------------------------------- item 2
@pytest.mark.parametrize("name", ["orbit.csv", "orbit.h5", "run.json"])
def test_a_hard_link_in_a_run_is_refused_as_a_symlink_is(tmp_path, name):
    """A hard link planted next to a file of the run (before: ``--resume`` appended the rows to ``orbit.csv`` in
    place, so the other name received them): refused for reading and for writing, both names unchanged."""
    out, _ = _orbit(tmp_path)
    other = tmp_path / "elsewhere"
    os.link(out / name, other)
    age(out)
    before, kept = snapshot(out), other.read_bytes()
    with pytest.raises(jg.RunDirectoryError, match="hard links"):
        rl.resume(out)
    assert snapshot(out) == before and other.read_bytes() == kept
    if name != "orbit.csv":  # load reads run.json and orbit.h5 only
        with pytest.raises(jg.RunDirectoryError, match="hard links"):
            rl.load(out)
