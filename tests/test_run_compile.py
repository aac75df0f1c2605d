"""Compilation made visible by the run layer and the CLI, and kept out of the stepping rate (issue 14, item 4):
a map's ``prepare_kernels`` runs before the loop, its messages go to ``notify`` (stderr in the CLI), its time is
``RunResult.compile_seconds`` / ``run.json["compile_seconds"]``, and the rate counts the loop only."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as runlayer
from jetgaudin.backlund.kernels import CompileReport
from jetgaudin.cli import main
from jetgaudin.run.files import write_run

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

#: the fake compile's length: long against the run's stepping (a few ms), so that counting it would show
FAKE_COMPILE_S = 0.4


@pytest.fixture
def fake_compile(monkeypatch):
    """``TwoPointBacklund.prepare_kernels`` replaced by a compile that says so, lasts FAKE_COMPILE_S and reports it
    (the real kernels are then loaded by the first step, quietly)."""
    calls = []

    def prepare_kernels(self, X, steps, notify=None):
        say = notify or (lambda m: print(m, file=sys.stderr))
        say("jetgaudin: compiling the Numba kernels run_orbit3, nu_default_kernel (about 9 s) ...")
        t0 = time.perf_counter()
        time.sleep(FAKE_COMPILE_S)
        calls.append(steps)
        say("jetgaudin: kernels ready in 0.4 s")
        return CompileReport(("run_orbit3", "nu_default_kernel"), "cold", time.perf_counter() - t0)

    jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 2, kernel="compiled")  # load them
    monkeypatch.setattr(jg.TwoPointBacklund, "prepare_kernels", prepare_kernels)
    return calls


def _spec(steps=2000):
    m = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA, backend="compiled")
    return runlayer.RunSpec(m, np.array(APPENDIX2_X0), steps, 10)


def test_compile_time_is_reported_apart_and_not_in_the_rate(tmp_path, fake_compile):
    said = []
    t0 = time.perf_counter()
    res = runlayer.start(_spec(), tmp_path / "run", notify=said.append)
    wall = time.perf_counter() - t0
    assert fake_compile == [2000] and len(said) == 2 and "compiling" in said[0] and "about" in said[0]
    assert res.compile_seconds >= FAKE_COMPILE_S
    # the loop's time excludes the compile: session + compile fit in the call's wall time
    assert res.session_seconds + res.compile_seconds <= wall
    assert res.session_steps == 2000 and res.step_rate == pytest.approx(2000 / res.session_seconds)
    rec = json.loads((tmp_path / "run" / "run.json").read_text())
    assert rec["compile_seconds"] == pytest.approx(res.compile_seconds)
    assert rec["elapsed_seconds"] <= res.elapsed < wall - FAKE_COMPILE_S  # recorded at the last checkpoint
    assert rec["orbit_steps_per_second"] > 0


def test_cli_prints_the_compile_message_and_the_rate_without_it(tmp_path, capsys, fake_compile):
    with pytest.raises(SystemExit) as exc:
        main(["orbit", "--kernel", "compiled", "--steps", "3000", "--no-plots", "--no-progress", "--out",
              str(tmp_path / "o")])
    out = capsys.readouterr()
    assert exc.value.code in (0, None), out.err
    err = [ln for ln in out.err.splitlines() if ln.strip()]
    assert err[0].startswith("jetgaudin: compiling") and "about" in err[0] and "ready" in err[1]
    status = next(ln for ln in out.out.splitlines() if ln.startswith("status:"))
    assert "steps/s" in status and "kernels compiled or loaded in 0.4 s, not in the rate" in status


def test_no_message_when_the_kernels_are_loaded(tmp_path):
    from jetgaudin.backlund import kernels

    m = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA, backend="compiled")
    m.iterate(APPENDIX2_X0, 2)  # loads (or compiles) them in this process
    said = []
    assert m.prepare_kernels(np.array(APPENDIX2_X0), 10, said.append).seconds == 0.0
    res = runlayer.start(runlayer.RunSpec(m, np.array(APPENDIX2_X0), 100), tmp_path / "r", notify=said.append)
    assert said == [] and res.compile_seconds == 0.0
    assert kernels.kernels_state(kernels.kernel_names(9, False)) == "loaded"
    # the NumPy route compiles nothing and says nothing
    numpy_map = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA, backend="numpy")
    assert numpy_map.prepare_kernels(np.array(APPENDIX2_X0), 10, said.append) is None and said == []


def test_an_old_run_directory_without_the_new_fields_resumes(tmp_path, fake_compile):
    out = tmp_path / "old"

    def progress(n, total):  # stop the first session part-way, as a crash would (the run stays resumable)
        if n >= 500:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        runlayer.start(_spec(), out, progress=progress, max_chunk_steps=100, notify=lambda m: None)
    rec = runlayer.read_run(out)
    assert rec["status"] == "interrupted" and rec["compile_seconds"] >= FAKE_COMPILE_S
    for key in ("compile_seconds", "orbit_steps_per_second"):  # a run.json written before this change
        rec.pop(key, None)
    write_run(out, rec)
    res = runlayer.resume(out, notify=lambda m: None)
    assert res.status == "completed"
    assert res.compile_seconds >= FAKE_COMPILE_S and runlayer.read_run(out)["compile_seconds"] == pytest.approx(
        res.compile_seconds)
    assert res.session_steps == 2000 - rec["last_safe_step"]


_SLOW_COMPILE = textwrap.dedent("""
    import sys, time
    import jetgaudin as jg
    from jetgaudin.cli import main

    def prepare_kernels(self, X, steps, notify=None):
        notify("jetgaudin: compiling the Numba kernels (about 30 s) ...")
        t = time.monotonic()
        while time.monotonic() - t < 30:  # Python work, as most of Numba's compiler
            sum(range(1000))

    jg.TwoPointBacklund.prepare_kernels = prepare_kernels
    main(sys.argv[1:])
""")


#: a compile that spends seconds in ONE call of C code releasing the GIL, as Numba inside an LLVM pass: a matrix
#: product (single-threaded BLAS) sized in the subprocess itself to last about 3 s on the machine at hand
_C_COMPILE = textwrap.dedent("""
    import sys, time
    import numpy as np
    import jetgaudin as jg
    from jetgaudin.cli import main

    def prepare_kernels(self, X, steps, notify=None):
        a = np.random.default_rng(0).random((600, 600))
        t = time.perf_counter(); a @ a; t = time.perf_counter() - t
        n = int(600 * (3.0 / max(t, 1e-6)) ** (1 / 3))
        b = np.random.default_rng(1).random((n, n))
        notify(f"jetgaudin: compiling the Numba kernels (one C call of about {(n / 600) ** 3 * t:.1f} s) ...")
        b @ b

    jg.TwoPointBacklund.prepare_kernels = prepare_kernels
    main(sys.argv[1:])
""")


def test_a_signal_during_a_long_c_call_of_the_compile_is_honoured_at_once(tmp_path):
    """The compile runs in a worker thread and the main thread waits in steps of 0.05 s, so a signal is honoured
    while the compiler is inside one C call (which a handler on the compiling thread could not interrupt)."""
    import os
    import re

    out = tmp_path / "run"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, "-c", _C_COMPILE, "orbit", "--kernel", "compiled", "--no-plots",
                             "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    line = proc.stderr.readline()
    call_s = float(re.search(r"about ([0-9.]+) s", line).group(1))
    time.sleep(0.2)  # inside the C call by now
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    took = time.monotonic() - t0
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "while compiling the kernels" in lines[0], err
    # honoured well before the C call could have returned (it had call_s - 0.2 s to go); 1.0 s allows for a loaded
    # machine's process exit, and the call is sized to ~3 s so that waiting for it would fail this
    assert call_s >= 2.0 and took < min(1.0, call_s - 0.8), (took, call_s)
    assert not out.exists()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_the_compile_ends_with_one_line(tmp_path, signum):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_COMPILE, "orbit", "--kernel", "compiled", "--no-plots",
                             "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()  # the compile message: the compile has started
    assert "compiling" in line, line
    t0 = time.monotonic()
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=30)
    took = time.monotonic() - t0
    assert proc.returncode == 128 + signum, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "while compiling the kernels; nothing was written" in lines[0]
    assert took < 5.0  # honoured at once (0.5 s on an idle machine; a loaded one delays the process start-up)
    assert not out.exists()  # nothing was created


def test_the_chain_kernel_is_prepared_visibly_once():
    from jetgaudin.gaudin import GaudinModel

    model = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    X = np.random.default_rng(7).normal(size=(2, model.n_state))
    m = jg.ChainTwoPointBacklund(model, 0.9 + 0.05j, backend="compiled")
    said = []
    first = m.prepare_kernels(X, 10, said.append)
    # compiled here (two messages, the first with the expected time), loaded from the cache or before (silent)
    assert (first.state, len(said)) in (("compiled", 2), ("cached", 0), ("loaded", 0))
    if said:
        assert "about" in said[0] and "ready" in said[1]
    said.clear()
    again = m.prepare_kernels(X, 10, said.append)
    assert again.state == "loaded" and again.seconds == 0.0 and said == []
    assert jg.ChainTwoPointBacklund(model, 0.9 + 0.05j, backend="numpy").prepare_kernels(X, 10, said.append) is None


def test_a_dask_run_says_that_the_workers_compile():
    from jetgaudin.ensemble import BatchBacklund

    X = np.array([APPENDIX2_X0, APPENDIX2_X0])
    said = []
    report = BatchBacklund([1.0, 1.0], [5 + 0.1j, 5 + 0.1j], scheduler="tcp://127.0.0.1:1").prepare_kernels(
        X, 10, said.append)
    assert "Dask workers" in said[0] and "run_lanes3" in said[0] and "warmup" in said[0]
    assert report.kernels == ("nu_default_kernel",)  # here only the branch rule (ν1 is computed locally)


def test_a_cache_of_other_kernel_sources_counts_as_cold(tmp_path, monkeypatch):
    # a cache directory whose stamp records other sources is dropped at the first use (a compile follows), so the
    # run must announce a compile, not a quiet load
    from jetgaudin.backlund.kernels import _select, _target

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    (tmp_path / "_branch.nu_default_kernel-99.py311.nbi").write_bytes(b"")
    (tmp_path / _target.STAMP_NAME).write_text("0" * 64 + "\n")
    assert not _select._cached("nu_default_kernel")
    (tmp_path / _target.STAMP_NAME).write_text(_target.sources_digest() + "\n")
    assert _select._cached("nu_default_kernel")


def test_a_directory_filled_during_the_compile_is_refused(tmp_path, monkeypatch):
    # the directory is checked before the compile (a fast refusal) and again after it: another writer may have
    # used it meanwhile, and its files must not be taken over
    out = tmp_path / "run"

    def prepare_kernels(self, X, steps, notify=None):
        out.mkdir()
        (out / "other.txt").write_text("written by someone else during the compile\n")
        return CompileReport(("run_orbit3",), "cold", 0.1)

    monkeypatch.setattr(jg.TwoPointBacklund, "prepare_kernels", prepare_kernels)
    with pytest.raises(jg.RunDirectoryError, match="not empty"):
        runlayer.start(_spec(100), out, notify=lambda m: None)
    assert sorted(p.name for p in out.iterdir()) == ["other.txt"]


def test_the_compile_guard_s_handler_only_records_the_signal():
    """The handler of the compile guard never raises (it did: a signal landing inside ``Thread.start``'s wait for
    the compile's worker thread broke ``threading.Condition``'s lock, ``RuntimeError: release unlocked lock`` and a
    traceback instead of one line, one run in ~50 of ``test_a_signal_during_the_compile_ends_with_one_line`` under
    load); the waiting thread raises ``CompileInterrupted`` itself, within its 0.05 s poll, and a signal recorded after
    the compile and before the handlers are restored is raised on leaving the guard."""
    import threading

    from jetgaudin.run.driver import CompileInterrupted, RaiseOnSignal

    started = threading.Event()

    def compile_():
        started.set()
        time.sleep(0.5)

    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(CompileInterrupted) as exc:
        with RaiseOnSignal(True) as guard:
            assert guard.enabled
            threading.Timer(0.1, lambda: guard._handler(signal.SIGTERM, None)).start()  # as the handler is called
            t0 = time.monotonic()
            guard.call(compile_)
    assert exc.value.signum == signal.SIGTERM and time.monotonic() - t0 < 0.4 and started.is_set()
    with RaiseOnSignal(True) as guard:
        guard._handler(signal.SIGINT, None)  # records, raises nothing here
        assert guard.signum == signal.SIGINT
        guard.signum = 0
    with pytest.raises(CompileInterrupted):
        with RaiseOnSignal(True) as guard:
            assert guard.call(lambda: 7) == 7
            guard._handler(signal.SIGINT, None)  # after the compile: raised on leaving
    assert signal.getsignal(signal.SIGINT) == before  # the handlers restored
