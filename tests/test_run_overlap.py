"""An ensemble's appends and checkpoints overlap the next steps (``Store.overlap``, a writer thread; issue 36, item 3):
the overlap happens, changes no byte of what is recorded, and an interruption during it -- SIGINT, SIGKILL --
loses nothing declared and resumes bit for bit."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from jetgaudin import run as rl
from jetgaudin.ensemble import BatchBacklund, iterate_ensemble, sample_on_leaf
from jetgaudin.run import driver
from jetgaudin.run.store import EnsembleStore, read_checkpoint_npz

STEPS, EVERY, B = 48, 4, 30
SRC = str(Path(__file__).resolve().parents[1] / "src")


def _spec() -> rl.RunSpec:
    X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=9)
    m = BatchBacklund(np.linspace(0.9, 1.1, B), (5 + 0.1j) + 0.01 * np.arange(B), backend="compiled")
    return rl.RunSpec(m, X0, STEPS, EVERY, rl.HealthLimits(max_drift=1e-6), csv=False, program="jetgaudin ensemble",
                      checkpoint_seconds=0.0)


def _reference(spec: rl.RunSpec) -> np.ndarray:
    return iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, STEPS, save_every=EVERY, want_drift=False).states


def _rows(out: Path) -> np.ndarray:
    d = rl.load(out)
    return d.X if d.X.shape[0] != B else np.moveaxis(d.X, 0, 1)


class _SlowWriter:
    """``EnsembleStore._write_checkpoint`` made slow (``delay`` s after writing the slot), noting while it runs and
    in which thread; ``advance`` calls made meanwhile are counted (the overlap)."""

    def __init__(self, monkeypatch, delay: float):
        self.busy, self.threads, self.overlapped, self.delay = 0, set(), 0, delay
        self.written, self.during = 0, None  # ``during(k)``: called in the writer while the k-th checkpoint is held
        write, advance = EnsembleStore._write_checkpoint, BatchBacklund.advance
        writer = self

        def slow(store, *args):
            writer.busy += 1
            writer.threads.add(threading.current_thread().name)
            try:
                write(store, *args)
                writer.written += 1
                if writer.during is not None:
                    writer.during(writer.written)
                time.sleep(writer.delay)
            finally:
                writer.busy -= 1

        def counted(m, *args, **kw):
            if writer.busy:
                writer.overlapped += 1
            return advance(m, *args, **kw)

        monkeypatch.setattr(EnsembleStore, "_write_checkpoint", slow)
        monkeypatch.setattr(BatchBacklund, "advance", counted)


@pytest.mark.parametrize("overlap", [True, False])
def test_checkpoints_overlap_the_steps_and_record_the_same_bytes(tmp_path, monkeypatch, overlap):
    """Calls of 4 steps on the save grid of 4 and a checkpoint after every chunk, each held 0.05 s in the writer:
    with the overlap, kernel calls run while a checkpoint is being written (in the writer thread); without it (the
    control: ``overlap = False``) none do.  Either way the rows, their digest and the last checkpoint's arrays (state,
    ``ν1``, drift, anchor) are those of the run without any delay, bit for bit.  (One call per chunk:
    ``FLUSH_MAX_SECONDS = 0``.)"""
    monkeypatch.setattr(driver, "FLUSH_MAX_SECONDS", 0.0)
    plain = rl.start(_spec(), tmp_path / "plain", max_chunk_steps=4)
    monkeypatch.setattr(EnsembleStore, "overlap", overlap)
    w = _SlowWriter(monkeypatch, 0.05)
    res = rl.start(_spec(), tmp_path / "o", max_chunk_steps=4)
    assert res.status == plain.status == "completed"
    if overlap:
        assert w.overlapped > 0 and w.threads == {"jetgaudin-store"}
    else:
        assert w.overlapped == 0 and w.threads == {threading.main_thread().name}
    np.testing.assert_array_equal(_rows(tmp_path / "o"), _rows(tmp_path / "plain"))
    np.testing.assert_array_equal(_rows(tmp_path / "o"), _reference(_spec()))
    a, b = (json.loads((tmp_path / d / "run.json").read_text())["checkpoint"] for d in ("o", "plain"))
    assert a["rows_sha256"] == b["rows_sha256"] and a["step"] == b["step"] == STEPS and a["rows"] == b["rows"]
    ca, cb = (read_checkpoint_npz(tmp_path / d, c, (B, 9)) for d, c in (("o", a), ("plain", b)))
    for k in ("X", "nu1", "drift", "anchor_step", "anchor_X", "anchor_nu1"):
        np.testing.assert_array_equal(ca[k], cb[k])


def test_sigint_during_a_checkpoint_in_the_writer_resumes_bit_for_bit(tmp_path, monkeypatch):
    """SIGINT while a checkpoint is held in the writer thread (0.3 s): the loop stops at the next call, the last
    checkpoint waits for that one and is written after it; the run is interrupted, and its resume equals the
    uninterrupted run bit for bit.  The signal is sent from the writer thread while it holds the third checkpoint
    (the main thread is then at most one chunk ahead: the fourth checkpoint waits for the third), so it lands during
    the overlap on a loaded machine too (sending it from the loop's progress callback when the writer looked busy
    raced with the writer thread's start and sometimes sent nothing)."""
    monkeypatch.setattr(driver, "FLUSH_MAX_SECONDS", 0.0)
    w = _SlowWriter(monkeypatch, 0.3)
    sent = []

    def during(k):
        if k == 3 and not sent:
            sent.append(k)
            os.kill(os.getpid(), signal.SIGINT)  # delivered to the main thread's handler (the driver's)

    w.during = during
    with pytest.raises(rl.RunInterrupted) as exc:
        rl.start(_spec(), tmp_path / "i", max_chunk_steps=4)
    assert sent and 0 < exc.value.last_safe_step < STEPS
    run = rl.read_run(tmp_path / "i")
    assert run["status"] == "interrupted" and run["last_safe_step"] == exc.value.last_safe_step
    w.delay = 0.0
    assert rl.resume(tmp_path / "i").state is rl.RunStatus.COMPLETED
    np.testing.assert_array_equal(_rows(tmp_path / "i"), _reference(_spec()))


_KILLED = textwrap.dedent("""
    import sys, time
    sys.path.insert(0, {src!r})
    sys.path.insert(0, {tests!r})
    import numpy as np
    from jetgaudin import run as rl
    from jetgaudin.run import driver
    from jetgaudin.run.store import EnsembleStore
    from test_run_overlap import _spec

    driver.FLUSH_MAX_SECONDS = 0.0  # one call per chunk: a checkpoint after each

    write = EnsembleStore._write_checkpoint
    seen = []

    def hold(store, new, step, *args):
        write(store, new, step, *args)  # the slot is written; run.json is not yet
        seen.append(step)
        if len(seen) == 4:
            print("HELD", step, flush=True)
            time.sleep(120)  # killed here: in the writer thread, during the overlap

    EnsembleStore._write_checkpoint = hold
    rl.start(_spec(), {out!r}, max_chunk_steps=4, handle_signals=False)
""")


def test_sigkill_during_a_checkpoint_in_the_writer_loses_nothing_and_resumes_bit_for_bit(tmp_path):
    """A process killed (SIGKILL) while its writer thread is inside a checkpoint -- the new slot written, ``run.json``
    not yet: ``run.json`` still declares the previous checkpoint, whose slot (the other one) and rows are intact and
    equal the uninterrupted run's; the resume completes the run bit for bit."""
    out = tmp_path / "k"
    code = _KILLED.format(src=SRC, tests=str(Path(__file__).parent), out=str(out))
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        assert line.startswith("HELD"), (line, proc.stderr.read() if proc.stderr else "")
        held = int(line.split()[1])
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    run = rl.read_run(out, verify=True)
    assert run["status"] == "running" and 0 < run["last_safe_step"] < held  # the previous checkpoint is declared
    ref = _reference(_spec())
    part = _rows(out)  # the declared rows load (digest checked) and are the uninterrupted run's
    np.testing.assert_array_equal(part, ref[:len(part)])
    assert rl.resume(out).state is rl.RunStatus.COMPLETED
    np.testing.assert_array_equal(_rows(out), ref)


def test_a_checkpoint_records_what_it_was_given_when_asked(tmp_path, monkeypatch):
    """The writer thread writes what the checkpoint was asked with: the anchor and the drift are taken at the call,
    not when the thread gets to them (here the thread is held at its first file operation until both were changed);
    ``wait`` returns once the checkpoint is durable, and the slot holds the values of the call."""
    from jetgaudin.run import api
    from jetgaudin.run.health import Health
    from jetgaudin.run.store import Store

    spec = _spec()
    health = Health(spec.map, spec.X0, spec.limits)
    out = tmp_path / "s"
    out.mkdir()
    store = api._open_store(spec, out, api._new_record(spec, health), fresh=True)
    gate = threading.Event()
    sync = Store._sync_data
    monkeypatch.setattr(Store, "_sync_data", lambda self: (gate.wait(30), sync(self))[1])
    try:
        store.begin(True)
        store.append(np.array([0]), spec.X0[None])
        store.anchor, store.drift_rel = (0, spec.X0.copy(), None), np.zeros((B, 6))
        store.checkpoint(0, spec.X0, np.ones(B, complex), {"status": "running"})
        store.anchor, store.drift_rel = (4, spec.X0 + 1.0, np.ones(B, complex)), np.ones((B, 6))  # changed meanwhile
        gate.set()
        store.wait()
        ck = rl.read_run(out, verify=True)["checkpoint"]
        got = read_checkpoint_npz(out, ck, (B, 9))
        assert int(got["anchor_step"]) == 0 and got["anchor_nu1"].size == 0
        np.testing.assert_array_equal(got["anchor_X"], spec.X0)
        np.testing.assert_array_equal(got["drift"], np.zeros((B, 6)))
        assert ck["rows"] == 1
    finally:
        gate.set()
        store.close()


def test_an_error_in_the_loop_waits_for_the_writer_inside_the_signal_guard(tmp_path, monkeypatch):
    """An unexpected error in the loop while a checkpoint is held in the writer thread (0.3 s): the writer's job has
    ended before the error leaves the driver's signal guard (where SIGXFSZ is ignored: a write past ``ulimit -f``
    then fails instead of killing the process); the run is marked interrupted with the error, and resumes bit for
    bit."""
    monkeypatch.setattr(driver, "FLUSH_MAX_SECONDS", 0.0)
    _SlowWriter(monkeypatch, 0.3)  # kept alive by the methods it patched
    ended, left = [], []
    write = EnsembleStore._write_checkpoint  # the slow one
    monkeypatch.setattr(EnsembleStore, "_write_checkpoint",
                        lambda store, *a: (write(store, *a), ended.append(time.monotonic()))[0])
    chunk, run = driver.Driver._chunk, driver.Driver.run
    calls = []

    def failing(self, *a, **kw):
        calls.append(1)
        if len(calls) == 4:
            assert self.store._job is not None and self.store._job.is_alive()  # a checkpoint in the writer now
            raise RuntimeError("planted bug")
        return chunk(self, *a, **kw)

    def timed(self):
        try:
            return run(self)
        finally:
            left.append(time.monotonic())

    monkeypatch.setattr(driver.Driver, "_chunk", failing)
    monkeypatch.setattr(driver.Driver, "run", timed)
    with pytest.raises(RuntimeError, match="planted bug"):
        rl.start(_spec(), tmp_path / "b", max_chunk_steps=4)
    assert ended and left and max(ended) <= left[0]
    assert rl.read_run(tmp_path / "b")["status"] == "interrupted"
    monkeypatch.undo()
    assert rl.resume(tmp_path / "b").state is rl.RunStatus.COMPLETED
    np.testing.assert_array_equal(_rows(tmp_path / "b"), _reference(_spec()))
