"""Chains through the run layer (issue 12): `jetgaudin.run` records a chain map like any map, as an orbit (one state)
and as an ensemble (B states).  References are the map's own `iterate` in one call (no chunks, no files), so
`np.array_equal` checks the chunking, the files, the checkpoints and the resume bit for bit, on both routes."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.gaudin import GaudinModel

MODEL = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])  # M = 6, 18 components
ETA = 0.9 + 0.05j
BACKENDS = ["numpy", "compiled"]


def states(B: int, seed: int = 7) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(B, MODEL.n_state))


def chain_map(backend: str) -> jg.ChainTwoPointBacklund:
    return jg.ChainTwoPointBacklund(MODEL, ETA, backend=backend)


def spec(X0, steps, backend, every=1):
    return rl.RunSpec(chain_map(backend), X0, steps, every, checkpoint_seconds=0.0,
                      program="jetgaudin ensemble" if np.ndim(X0) == 2 else "jetgaudin orbit")


@pytest.mark.parametrize("backend", BACKENDS)
def test_orbit_run_equals_the_single_orbit_bit_for_bit(tmp_path, backend):
    X0 = states(1)[0]
    res = rl.start(spec(X0, 40, backend, every=3), tmp_path / "o", max_chunk_steps=5)
    assert res.state is rl.RunStatus.COMPLETED and res.kernel == backend
    d = rl.load(tmp_path / "o")
    ref = chain_map(backend).iterate(X0, 40)
    np.testing.assert_array_equal(d.n, list(range(0, 40, 3)) + [40])
    assert np.array_equal(d.X, ref[d.n])
    assert np.array_equal(rl.read_csv(tmp_path / "o" / "orbit.csv")[1], d.X)
    run = rl.read_run(tmp_path / "o")
    assert run["map"] == chain_map(backend).describe()
    assert run["integral_names"] == MODEL.integral_labels()
    # the drift the run reports is that of the reference orbit's saved rows (the same bits)
    I = MODEL.integrals(ref[d.n])
    assert np.array_equal(res.drift_abs, np.abs(I - I[0]).max(axis=0))


@pytest.mark.parametrize("backend", BACKENDS)
def test_ensemble_member_equals_its_single_orbit_run_bit_for_bit(tmp_path, backend):
    X0 = states(3)
    res = rl.start(spec(X0, 30, backend, every=2), tmp_path / "e", max_chunk_steps=7)
    assert res.state is rl.RunStatus.COMPLETED
    d = rl.load(tmp_path / "e")
    assert d.X.shape == (16, 3, MODEL.n_state)
    for k in range(3):
        assert np.array_equal(d.X[:, k], chain_map(backend).iterate(X0[k], 30, save_every=2))
    assert rl.read_run(tmp_path / "e")["map"]["kind"] == "chain_two_point"


def _interrupt_once(at: int):
    """A progress callback sending SIGINT to this process once the run passed step `at` (the run layer's own
    signal handling then writes a checkpoint and raises RunInterrupted)."""
    sent = []

    def progress(n, steps):
        if n >= at and not sent:
            sent.append(n)
            os.kill(os.getpid(), signal.SIGINT)

    return progress, sent


def interrupt(spec, out, at: int, **options):
    """Start ``spec`` into ``out`` in chunks of 3 steps with a SIGINT once step ``at`` is passed; checks that the
    signal was sent and the run stopped on it, and returns the :class:`jetgaudin.run.RunInterrupted` raised."""
    progress, sent = _interrupt_once(at)
    with pytest.raises(rl.RunInterrupted) as exc:
        rl.start(spec, out, progress=progress, max_chunk_steps=3, **options)
    assert sent
    return exc.value


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("B", [None, 2])
def test_interrupted_chain_run_resumes_bit_for_bit(tmp_path, backend, B):
    X0 = states(1)[0] if B is None else states(B)
    out = tmp_path / "i"
    assert 0 < interrupt(spec(X0, 60, backend, every=4), out, 9).last_safe_step < 60
    assert rl.read_run(out)["status"] == "interrupted"
    res = rl.resume(out)
    assert res.state is rl.RunStatus.COMPLETED
    d = rl.load(out)
    ref = chain_map(backend).iterate(X0, 60, save_every=4)
    assert np.array_equal(d.X, ref)



def test_chain_flow_map_is_a_map_rebuilt_from_its_description(tmp_path):
    """ChainFlowMap (the run layer's flow of a chain Hamiltonian): validated by FlowMap's rules, described as JSON,
    rebuilt by map_from_description, recorded as flow.h5 with the chain's integral names."""
    import json

    from jetgaudin.gaudin import ChainFlowMap
    from jetgaudin.maps import map_from_description

    X = states(1)[0]
    H = MODEL.interpolating_flow_hamiltonian(X, ETA)
    F = ChainFlowMap(H, 1.0)
    R = map_from_description(json.loads(json.dumps(F.describe())))
    assert isinstance(R, ChainFlowMap) and R.describe() == F.describe() and F.inverse().dt == -1.0
    with pytest.raises(jg.InvalidParameterError, match="dt"):
        ChainFlowMap(H, 0.0)
    with pytest.raises(jg.InvalidParameterError, match="ChainHamiltonian"):
        ChainFlowMap(jg.physical_hamiltonian(3, 1.0), 1.0)
    res = rl.start(rl.RunSpec(F, X, 3, program="jetgaudin flow"), tmp_path / "f")
    assert res.state is rl.RunStatus.COMPLETED and rl.read_run(tmp_path / "f")["integral_names"] == \
        MODEL.integral_labels()
    # one flow step is one map step (the time-1 flow of G_eta): DOP853 at 1e-12 over 3 units, <= 1e-9 relative
    ref = chain_map("numpy").iterate(X, 3)
    assert np.abs(rl.load(tmp_path / "f").X - ref).max() <= 1e-9 * (1 + np.abs(ref).max())


@pytest.mark.parametrize("flush", [0.0, 1e9])
def test_reported_drift_is_the_saved_rows_at_any_flush_interval(tmp_path, monkeypatch, flush):
    # The end of a kernel call off the save grid is health-checked but, unless it breaches, not folded into the
    # reported maxima: the drift must not depend on where the clock ended the calls (flush 0: every call is checked
    # and appended on its own; calls of 2 steps on a save grid of 7 end off the grid; 1e9: one append per chunk).
    # Exact equality: the same integrals of the same states. (Planted: the end state recorded again -> the flush-0
    # case fails; that the max over the saved rows differs from the max over every step is checked below.)
    from jetgaudin.run import driver

    monkeypatch.setattr(driver, "FLUSH_SECONDS", flush)
    monkeypatch.setattr(driver, "FLUSH_MAX_SECONDS", max(flush, 2.0))
    monkeypatch.setattr(driver, "FLUSH_SHARE", 1e12 if flush == 0 else 0.1)  # flush 0: no growth with the overhead
    monkeypatch.setattr(driver.Driver, "_adapt", lambda self, L, k, dt: 2)  # calls of 2 steps, not by the clock
    X0 = states(1)[0]
    res = rl.start(spec(X0, 40, "numpy", every=7), tmp_path / "o", max_chunk_steps=5)
    ref = chain_map("numpy").iterate(X0, 40)
    n = list(range(0, 40, 7)) + [40]
    I = MODEL.integrals(ref)
    saved = np.abs(I[n] - I[0]).max(axis=0)
    assert not np.array_equal(saved, np.abs(I - I[0]).max(axis=0))  # the test can tell the two apart
    assert np.array_equal(res.drift_abs, saved)
