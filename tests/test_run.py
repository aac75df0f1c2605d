"""The run layer `jetgaudin.run` against the defects of issue 11: fault injection (EIO / ENOSPC at every write of
a checkpoint cycle, then resume: no step lost, no wrong resume), a second writer, symlinks, FIFOs and /dev/zero,
signals with huge save intervals, huge counts, honest `last_safe_step`, refusals that create nothing.

References are `TwoPointBacklund.iterate` in one call (no chunks, no files): `np.array_equal` checks the chunking,
the checkpoints and the resume."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.cli import main

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

X0 = np.array(APPENDIX2_X0)


def interrupted_run(out, steps):
    """A finished run of ``steps`` steps in ``out``, its ``run.json`` marked interrupted (so resumable); returns the
    record."""
    from jetgaudin.run.files import write_run

    rl.start(spec(steps), out)
    run = rl.read_run(out)
    run["status"] = "interrupted"
    write_run(out, run)
    return run


def spec(steps=120, kernel="numpy", every=1, **kw):
    return rl.RunSpec(jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA, backend=kernel), X0, steps, every,
                      checkpoint_seconds=0.0, **kw)


def reference(steps, kernel="numpy"):
    return jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(X0, steps, kernel=kernel)


def run_cli(capsys, *args):
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return (0 if code is None else code), out.out, out.err


def one_line_error(code, err, expected=2):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return code == expected and len(lines) == 1 and "Traceback" not in err


# ------------------------------------------------------------------------------------------ fault injection
class _Faulty:
    """`os.<name>` raising OSError(errno) at its `at`-th call (then working again: the fault was transient)."""

    def __init__(self, monkeypatch, name, at, code):
        self.real, self.at, self.code, self.calls = getattr(os, name), at, code, 0
        monkeypatch.setattr(os, name, self)
        self.name = name

    def __call__(self, *a, **kw):
        self.calls += 1
        if self.calls == self.at:
            raise OSError(self.code, os.strerror(self.code))
        return self.real(*a, **kw)


@pytest.mark.parametrize("code", [errno.EIO, errno.ENOSPC])
@pytest.mark.parametrize(("name", "at"), [("fsync", k) for k in range(1, 13)] + [("replace", k) for k in (1, 2, 3, 5)])
def test_io_fault_in_a_checkpoint_cycle_loses_nothing(tmp_path, monkeypatch, code, name, at):
    """Each fsync/rename of the first checkpoint cycles fails once: the run ends `failed: I/O error` or `failed: disk
    full` (exit 1 in the CLI) with the last *durable* checkpoint; nothing half-written is declared; the resume ends
    bit for bit equal to the uninterrupted orbit; no stray .tmp file."""
    out = tmp_path / "r"
    fault = _Faulty(monkeypatch, name, at, code)
    try:
        res = rl.start(spec(60), out, chunk_rows=4)  # >= 15 checkpoint cycles, whatever the machine's speed
    except jg.RunIOError:  # the fault hit the creation of the files: nothing durable, nothing declared
        res = None
    monkeypatch.setattr(os, name, fault.real)
    assert fault.calls >= at  # the fault was met
    assert not [p for p in os.listdir(out) if p.endswith(".tmp")]
    if res is None:
        assert not (out / "run.json").exists() or rl.read_run(out)["status"] != "completed"
        return
    assert res.state is rl.RunStatus.FAILED_IO
    assert res.status.startswith("failed: disk full" if code == errno.ENOSPC else "failed: I/O error")
    run = rl.read_run(out, verify=True)
    assert run["failure"] == "io" and run["last_safe_step"] == run["checkpoint"]["step"]
    d = rl.load(out)
    assert np.array_equal(d.X, reference(60)[d.n])  # what is declared is on disk and right
    res2 = rl.resume(out)
    assert res2.state is rl.RunStatus.COMPLETED
    d = rl.load(out)
    np.testing.assert_array_equal(d.n, np.arange(61))
    assert np.array_equal(d.X, reference(60))
    assert np.array_equal(rl.read_csv(out / "orbit.csv")[1], d.X)


def test_hdf5_write_error_ends_failed_not_killed(tmp_path, monkeypatch):
    """An HDF5 error while appending rows (h5py raises RuntimeError or OSError) ends the run `failed: I/O error`
    with its last durable checkpoint, no traceback; the resume completes the orbit bit for bit."""
    from jetgaudin.run import store

    calls = {"n": 0}
    real = store.OrbitStore._append_more

    def broken(self, n_idx, S):
        calls["n"] += 1
        if calls["n"] == 4:
            raise RuntimeError("Can't write data (file write failed)")  # what h5py raises on a failed write
        real(self, n_idx, S)

    monkeypatch.setattr(store.OrbitStore, "_append_more", broken)
    res = rl.start(spec(60), tmp_path / "h", chunk_rows=4)
    assert res.state is rl.RunStatus.FAILED_IO and "I/O error" in res.status and calls["n"] >= 4
    monkeypatch.undo()
    rl.resume(tmp_path / "h")
    assert np.array_equal(rl.load(tmp_path / "h").X, reference(60))


@pytest.mark.parametrize("field", ["X_hex", "nu1_hex", "step"])
def test_edited_checkpoint_with_recomputed_digest_is_refused(tmp_path, field):
    """Issue 11, 2: the checkpoint is cross-checked against the last saved row (state bits, step, nu1)."""
    from jetgaudin.run.files import write_run

    out = tmp_path / "e"
    run = interrupted_run(out, 40)
    ck = run["checkpoint"]
    if field == "X_hex":
        ck["X_hex"][0] = (float.fromhex(ck["X_hex"][0]) * (1 + 1e-12)).hex()
    elif field == "nu1_hex":
        ck["nu1_hex"][0] = (-float.fromhex(ck["nu1_hex"][0])).hex()
    else:
        ck["step"] = ck["step"] - 3
    write_run(out, run)  # a valid digest
    with pytest.raises(jg.RecordingError, match="does not match the saved rows"):
        rl.resume(out)


# ------------------------------------------------------------------------------------------ one writer
def test_second_writer_is_refused_with_the_holders_pid(tmp_path, capsys):
    out = tmp_path / "w"
    interrupted_run(out, 5)
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from jetgaudin._fs import RunDirLock\n"
                               f"l = RunDirLock({str(out)!r}).acquire(); print('locked', flush=True); time.sleep(60)"],
                              stdout=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONPATH=os.pathsep.join(
                                  sys.path)))
    try:
        assert holder.stdout.readline().strip() == "locked"
        before = (out / "orbit.csv").read_bytes()
        for args in (["orbit", "--resume", out, "--no-plots"], ["orbit", "--out", out, "--overwrite", "--no-plots"],
                     ["ensemble", "--resume", out]):
            code, _, err = run_cli(capsys, *args)
            assert one_line_error(code, err), err
            assert str(holder.pid) in err
        assert (out / "orbit.csv").read_bytes() == before
    finally:
        holder.kill()
        holder.wait()


# ------------------------------------------------------------------------------------------ hostile files
@pytest.mark.parametrize("name", ["orbit.csv.tmp", "orbit.h5.tmp", "run.json.tmp", ".jetgaudin-write-test",
                                  "figure1.png.tmp"])
def test_symlinks_in_the_run_directory_are_not_followed(tmp_path, name):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "s"
    out.mkdir()
    (out / name).symlink_to(victim)
    rl.start(spec(5), out, overwrite=True)
    assert victim.read_text() == "precious"


@pytest.mark.parametrize("name", ["run.json", "orbit.csv", "orbit.h5"])
def test_symlinked_run_files_are_refused(tmp_path, name):
    out = tmp_path / "l"
    interrupted_run(out, 5)
    victim = tmp_path / "victim"
    os.replace(out / name, victim)
    (out / name).symlink_to(victim)
    size = victim.stat().st_size
    with pytest.raises(jg.RecordingError):
        rl.resume(out)
    assert victim.stat().st_size == size


@pytest.mark.parametrize("target", ["/dev/zero", "fifo"])
def test_run_json_that_is_a_device_or_fifo_is_refused_quickly(tmp_path, target):
    out = tmp_path / "d"
    rl.start(spec(3), out)
    (out / "run.json").unlink()
    if target == "fifo":
        os.mkfifo(out / "run.json")
    else:
        (out / "run.json").symlink_to(target)
    t0 = time.monotonic()
    with pytest.raises(jg.RecordingError):
        rl.read_run(out)
    with pytest.raises(jg.RecordingError):
        rl.resume(out)
    assert time.monotonic() - t0 < 5  # no 24 GB read, no blocking open (functional bound, not a benchmark)


def test_ensemble_checkpoint_path_outside_the_directory_is_refused(tmp_path):
    from jetgaudin.ensemble import sample_on_leaf
    from jetgaudin.ensemble_recording import EnsembleSpec, run_ensemble
    from jetgaudin.run.files import write_run

    out = tmp_path / "e"
    run_ensemble(EnsembleSpec(sample_on_leaf(3, [0.4, -0.3, 1.5], 3, seed=1), 1.0, 5 + 0.1j, 10), out)
    run = rl.read_run(out)
    run["status"] = "interrupted"
    run["checkpoint"]["file"] = str(out / run["checkpoint"]["file"])  # absolute: refused even though it exists
    write_run(out, run)
    with pytest.raises(jg.RecordingError, match="plain file name|corrupted"):
        rl.resume(out)


def test_cli_input_dev_zero_is_refused(tmp_path, capsys):
    code, _, err = run_cli(capsys, "ensemble", "--input", "/dev/zero", "--out", tmp_path / "z")
    assert one_line_error(code, err) and "regular file" in err
    assert not (tmp_path / "z").exists()


def test_orbit_into_an_ensemble_directory_is_refused(tmp_path, capsys):
    out = tmp_path / "e"
    assert run_cli(capsys, "ensemble", "--orbits", 2, "--steps", 2, "--out", out, "--no-progress")[0] == 0
    code, _, err = run_cli(capsys, "orbit", "--steps", 2, "--no-plots", "--out", out)
    assert one_line_error(code, err) and "holds a run" in err
    assert (out / "ensemble.h5").exists() and not (out / "orbit.csv").exists()


# ------------------------------------------------------------------------------------------ counts, rules
def test_huge_counts_are_refused_before_allocating():
    B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    with pytest.raises(jg.InvalidParameterError, match="64 bits"):
        B.iterate(X0, 2**63, kernel="compiled", save_every=2**62)
    with pytest.raises(jg.InvalidParameterError, match="dt"):
        jg.FlowMap(jg.physical_hamiltonian(3, 1.0), 1e300)


@pytest.mark.parametrize(("args", "word"), [
    (["orbit", "--steps", str(2**64)], "--steps"),
    (["orbit", "--b", "1+1i"], "must be real"),
    (["orbit", "--eta", "5"], "Im eta = 0"),
    (["flow", "--dt", "1e300"], "--dt"),
    (["ensemble", "--orbits", "1e10"], "--orbits"),
    (["ensemble", "--seed", "-1"], "--seed"),
])
def test_cli_refusals_exit_2_and_create_nothing(tmp_path, capsys, args, word):
    out = tmp_path / "new"
    code, _, err = run_cli(capsys, *args, "--out", out)
    assert one_line_error(code, err), err
    assert word in err and err.startswith(f"jetgaudin {args[0]}: error: ")
    assert not out.exists()


def test_branch_point_eta_is_refused_alike_by_orbit_and_ensemble(tmp_path, capsys):
    bp = complex(jg.branch_points(X0, 1.0)[0])
    eta = f"{bp.real!r}{bp.imag:+.17g}i"
    a = run_cli(capsys, "orbit", "--eta", eta, "--no-plots", "--out", tmp_path / "o")
    X = tmp_path / "x.csv"
    np.savetxt(X, X0[None], delimiter=",")
    b = run_cli(capsys, "ensemble", "--eta", eta, "--input", X, "--out", tmp_path / "e")
    assert one_line_error(a[0], a[2]) and one_line_error(b[0], b[2])
    assert "branch point" in a[2] and "branch point" in b[2]
    assert not (tmp_path / "o").exists() and not (tmp_path / "e").exists()


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
def test_empty_batch_behaves_alike_on_both_routes(kernel):
    out = jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(np.zeros((0, 9)), 3, kernel=kernel)
    assert out.shape == (4, 0, 9)


def test_one_point_step_refuses_nan_nu():
    with pytest.raises(jg.InvalidParameterError, match="finite"):
        jg.OnePointBacklund(1.0, 5 + 0.1j).step(X0, np.nan)


def test_last_safe_step_is_the_last_step_that_passed(tmp_path):
    res = rl.start(spec(100, every=8, limits=rl.HealthLimits(max_drift=1e-15)), tmp_path / "f")
    assert res.state is rl.RunStatus.FAILED
    d = rl.load(tmp_path / "f")
    ref = reference(100)
    I0 = jg.integrals(X0, 1.0)
    rel = np.abs(jg.integrals(ref, 1.0) - I0) / np.maximum(1, np.abs(I0))
    # every state up to last_safe_step that was checked passed; the reported failure step did not
    fail_step = int(res.status.split("at step ")[1].split()[0])
    assert rel[fail_step].max() > 1e-15 and res.last_safe_step < fail_step
    assert d.n[-1] <= res.last_safe_step and np.all(rel[d.n].max(axis=1) <= 1e-15)


# ------------------------------------------------------------------------------------------ CLI behaviour
def test_resume_of_a_no_plots_run_draws_no_figures(tmp_path):
    out = tmp_path / "p"
    p = subprocess.Popen([sys.executable, "-m", "jetgaudin", "orbit", "--steps", "100000000", "--kernel", "compiled",
                          "--no-plots", "--checkpoint-seconds", "0.05", "--out", str(out)], stderr=subprocess.PIPE,
                         text=True)
    t0 = time.monotonic()
    while not (out / "run.json").exists() and time.monotonic() - t0 < 60:
        time.sleep(0.05)
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=60)
    run = rl.read_run(out)
    run["inputs"]["steps"] = run["last_safe_step"] + 10  # finish quickly (a run.json edited with its digest)
    from jetgaudin.run.files import write_run

    write_run(out, run)
    r = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--resume", str(out)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert not (out / "figure1.png").exists()


@pytest.mark.parametrize("every", ["200000000", str(2**63 - 1)])
def test_signal_is_honoured_quickly_whatever_save_every(tmp_path, every):
    """Issue 11, 7: kernel calls are bounded in time, not in saved rows (here 17 s to forever per save interval)."""
    out = tmp_path / "q"
    p = subprocess.Popen([sys.executable, "-m", "jetgaudin", "orbit", "--steps", str(2**62), "--kernel", "compiled",
                          "--save-every", every, "--no-plots", "--checkpoint-seconds", "0.05", "--out", str(out)],
                         stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60:  # running: kernels loaded, a checkpoint beyond step 0 on disk
        try:
            if json.loads((out / "run.json").read_text())["last_safe_step"] > 0:
                break
        except (OSError, ValueError):
            pass
        time.sleep(0.02)
    time.sleep(0.2)
    t1 = time.monotonic()
    p.send_signal(signal.SIGINT)
    while json.loads((out / "run.json").read_text())["status"] != "interrupted" and time.monotonic() - t1 < 60:
        time.sleep(0.01)
    took = time.monotonic() - t1  # signal -> checkpoint on disk marked interrupted (process exit not included)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130 and "Traceback" not in err and "resume with" in err
    assert took < 2.0, took  # 0.5 s promised (kernel calls of ~0.05 s); 2 s leaves room for a loaded machine


def test_init_from_continues_from_the_last_state(tmp_path, capsys):
    """`--init-from RUN_DIR` (issue 11, 10): orbit, flow and ensemble start from the last safe state of a run;
    the orbit with the run's own b, eta: 10 steps then 10 from the last state = 20 steps (same route: NumPy)."""
    a, b = tmp_path / "a", tmp_path / "b"
    assert run_cli(capsys, "orbit", "--steps", 10, "--kernel", "numpy", "--no-plots", "--out", a)[0] == 0
    assert run_cli(capsys, "orbit", "--init-from", a, "--steps", 10, "--kernel", "numpy", "--no-plots",
                   "--out", b)[0] == 0
    ref = reference(20)
    assert np.array_equal(rl.load(b).X[0], ref[10])
    # the next step from a state re-starts nu1 by the branch rule: equal to the continued orbit to round-off
    np.testing.assert_allclose(rl.load(b).X[-1], ref[20], rtol=0, atol=1e-13)
    assert run_cli(capsys, "ensemble", "--init-from", a, "--steps", 3, "--out", tmp_path / "e",
                   "--no-progress")[0] == 0
    assert np.array_equal(rl.load(tmp_path / "e").X0, ref[10][None])
    code, _, err = run_cli(capsys, "flow", "--init-from", a, "--steps", 2, "--no-plots", "--out", tmp_path / "f")
    assert code == 0, err
    assert np.array_equal(rl.load(tmp_path / "f").X[0], ref[10])
    # an orbit.csv (with its header and step column) is a valid --input
    code, _, err = run_cli(capsys, "ensemble", "--input", a / "orbit.csv", "--steps", 1, "--out", tmp_path / "c",
                           "--no-progress")
    assert code == 0, err
    assert np.array_equal(rl.load(tmp_path / "c").X0, ref[:11])


def test_a_figure_that_cannot_be_drawn_is_one_line_and_the_run_is_kept(tmp_path, capsys, monkeypatch):
    """An unexpected error while drawing (here injected into the figure writer) used to escape as a traceback after a
    completed run; it is now one line naming the cause, exit 1, and the run's data stay complete."""
    from jetgaudin import plotting

    def broken(*args, **kwargs):
        raise RuntimeError("injected plotting failure")

    monkeypatch.setattr(plotting, "save_run_figures", broken)
    code, _, err = run_cli(capsys, "orbit", "--steps", "5", "--out", tmp_path / "r")
    assert one_line_error(code, err, expected=1), err
    assert "injected plotting failure" in err and "jetgaudin plot" in err
    from jetgaudin.recording import load_orbit

    n, X = load_orbit(tmp_path / "r")
    assert X.shape == (6, 9)


def test_complex_maps_are_refused_by_the_spec():
    """A complex map (the one-point map) used to start a run that ended as 'failed: I/O error' (HDF5 cannot store
    complex rows as real); the spec, built before any directory is touched, now refuses it naming the reason."""
    from jetgaudin import run as rl

    with pytest.raises(jg.InvalidParameterError, match="complex"):
        rl.RunSpec(jg.OnePointBacklund(1.0, 5 + 0.1j), np.array(APPENDIX2_X0), 5)


def test_scheduler_that_cannot_be_used_is_refused_before_the_directory_exists(tmp_path, capsys, monkeypatch):
    """Issue 11, item 9: ``--scheduler`` without Dask used to leave an 'interrupted' run behind.  Dask's absence is
    simulated (the client factory raises what it raises when ``distributed`` is missing): exit 2, one line, and the
    --out directory is never created."""
    from jetgaudin import ensemble as ens

    def no_dask(*args, **kwargs):
        raise jg.InvalidParameterError("a Dask scheduler was given but the 'distributed' package is missing: "
                                       "pip install 'jetgaudin[distributed]'")

    monkeypatch.setattr(ens, "dask_client", no_dask)
    out = tmp_path / "ens"
    code, _, err = run_cli(capsys, "ensemble", "--orbits", "4", "--steps", "3", "--scheduler", "tcp://127.0.0.1:9",
                           "--out", out)
    assert one_line_error(code, err), err
    assert "distributed" in err
    assert not out.exists()


def test_slow_health_checks_take_a_bounded_share_of_the_run(tmp_path, monkeypatch):
    # a large ensemble's health check (integrals of every orbit) can take longer than the 0.1 s between checks; the
    # driver then spaces the checks so that they take about FLUSH_SHARE (10 %) of the time.  Here each check sleeps
    # 0.1 s: at a fixed 0.1 s interval they would take half the run or more; bound 35 % (the first interval is
    # 0.1 s, and a loaded machine slows the steps, not the sleeps).  The orbit is still the unchunked one.
    from jetgaudin.run import health as health_mod

    spent = []
    original = health_mod.Health.check

    def slow_check(self, steps, S, **kw):
        t = time.monotonic()
        time.sleep(0.1)
        out = original(self, steps, S, **kw)
        spent.append(time.monotonic() - t)
        return out

    monkeypatch.setattr(health_mod.Health, "check", slow_check)
    t0 = time.monotonic()
    res = rl.start(spec(3000, every=500), tmp_path / "slow")
    total = time.monotonic() - t0
    assert res.state is rl.RunStatus.COMPLETED
    assert sum(spent) <= 0.35 * total, (sum(spent), total, len(spent))
    assert np.array_equal(rl.load(tmp_path / "slow").X[-1], reference(3000)[-1])


def test_call_length_grows_when_the_pieces_never_reach_it(tmp_path, monkeypatch):
    """The driver's call length (about CALL_SECONDS of steps) grows past save_every even when every call is a short
    piece (up to the save grid, or whole save intervals below the length): it stalled at 14 steps per call for
    save_every = 7 (the pieces 14 < L = 16 never updated L).  The compiled route does ~10^7 steps/s here, so 0.1 s of
    steps is far above 1000; the orbit is unchanged (the map is chunk-invariant)."""
    calls = []
    advance = jg.TwoPointBacklund.advance

    def spy(self, X, carry, steps, save_every=1):
        calls.append(steps)
        return advance(self, X, carry, steps, save_every)

    monkeypatch.setattr(jg.TwoPointBacklund, "advance", spy)
    res = rl.start(spec(60000, "compiled", every=7), tmp_path / "o")
    assert res.state is rl.RunStatus.COMPLETED
    assert max(calls) > 1000, calls[:20]
    ref = reference(60000, "compiled")
    d = rl.load(tmp_path / "o")  # the rows every 7 steps and the last state (step 60000 is off the grid)
    np.testing.assert_array_equal(d.X, np.concatenate([ref[::7], ref[-1:]]))


def test_call_length_grows_past_a_large_fixed_cost_per_call(tmp_path, monkeypatch):
    """A route whose calls each cost a fixed 0.15 s (above CALL_SECONDS = 0.1 s: copies of 10^6 states to and from a
    GPU) still gets long calls: the rate k/dt made the next call shorter than the last, one step per call for good
    (100 calls here, 15 s); the marginal rate, the shortest call taken as the fixed cost, makes it grow."""
    calls = []
    advance = jg.TwoPointBacklund.advance

    def slow(self, X, carry, steps, save_every=1):
        calls.append(steps)
        time.sleep(0.15)
        return advance(self, X, carry, steps, save_every)

    monkeypatch.setattr(jg.TwoPointBacklund, "advance", slow)
    res = rl.start(spec(100, "compiled"), tmp_path / "o")
    assert res.state is rl.RunStatus.COMPLETED
    assert len(calls) <= 8, calls
    np.testing.assert_array_equal(rl.load(tmp_path / "o").X, reference(100, "compiled"))
