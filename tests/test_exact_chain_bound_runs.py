"""The chain exact flow's parameters solved once per run (``ChainExactFlow.bind_run``, the run layer's
``run_map``): a run's rows are those of the flow with the parameters of X0 (solving them again at every chunk moved
them by round-off and paid the maps' 40-digit constants at every chunk: the Clebsch top's ``orbit --dt`` at ~2·10⁴
steps/s, ~1.3·10⁵ now); a run written the old way (per chunk) still resumes that way, bit for bit."""

from __future__ import annotations

import json
import os
import signal

import numpy as np
import pytest

import jetgaudin as jg
import jetgaudin.run as rl
from jetgaudin import exact_chain

X0 = np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])
H = jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0])
STEPS, EVERY = 800, 100  # kernel calls of 256 steps (the driver's fixed cuts of a non-invariant map)


def _count_solves(monkeypatch) -> dict:
    calls = {"n": 0}
    real = exact_chain._ChainExactFlow._parameters

    def counted(self, x, checked=False):
        calls["n"] += 1
        return real(self, x, checked)

    monkeypatch.setattr(exact_chain._ChainExactFlow, "_parameters", counted)
    return calls


def test_a_bound_flow_steps_with_the_parameters_of_x0():
    """The bound flow's first call is the unbound flow's, bit for bit (the same solve and loop); its next call keeps
    X0's parameters where the unbound flow solves them again at its start (they differ by round-off: 1e-12 after
    256 + 256 steps, and not bit for bit, else this would prove nothing); binding again at X0 is the same flow."""
    flow = jg.ChainExactFlow(H, 0.9)
    bound = flow.bind_run(X0)
    assert bound.bind_run(X0) is bound and bound.unbound().bind_run(X0) is not bound
    a, a0 = bound.advance(X0, None, 256, 1), flow.advance(X0, None, 256, 1)
    assert np.array_equal(a.rows, a0.rows) and np.array_equal(a.X, a0.X)
    b, b0 = bound.advance(a.X, None, 256, 1), flow.advance(a.X, None, 256, 1)
    assert not np.array_equal(b.rows, b0.rows)
    assert np.max(np.abs(b.rows - b0.rows)) < 1e-12
    eta, theta = flow.parameters(X0)
    again = jg.ChainExactFlow(H, 0.9).bind_run(X0)
    assert np.array_equal(again.advance(a.X, None, 256, 1).rows, b.rows)
    assert np.array_equal(flow.parameters(X0)[0], eta)  # binding changes nothing of the flow it was made from


def test_a_run_solves_once_and_is_the_bound_flow_s_orbit(tmp_path, monkeypatch):
    calls = _count_solves(monkeypatch)
    spec = rl.RunSpec(jg.ChainExactFlow(H, 0.9, backend="compiled"), X0, STEPS, save_every=EVERY, csv=False,
                      checkpoint_seconds=0)
    rl.start(spec, tmp_path / "run", handle_signals=False)
    assert calls["n"] == 1
    bound = jg.ChainExactFlow(H, 0.9, backend="compiled").bind_run(X0)
    rows, X = [X0[None]], X0
    for n in (256, 256, 256, 32):  # the driver's cuts: its rows are those of the same calls
        adv = bound.advance(X, None, n, 1)
        rows.append(adv.rows)
        X = adv.X
    every = np.concatenate(rows)[::EVERY]
    assert np.array_equal(rl.load(tmp_path / "run").X, every)


def test_a_batch_is_bound_per_orbit_and_an_infeasible_orbit_is_named():
    X = np.stack([X0, X0 * 1.05])
    bound = jg.ChainExactFlow(H, 0.9).bind_run(X)
    one = [jg.ChainExactFlow(H, 0.9).bind_run(x).advance(x, None, 300, 100).rows for x in X]
    assert np.array_equal(bound.advance(X, None, 300, 100).rows, np.stack(one, axis=1))
    with pytest.raises(jg.StepTooLargeError, match="orbit 1"):
        jg.ChainExactFlow(H, 0.9).bind_run(np.stack([X0, X0 * 3.0]))


def _spec(old: bool) -> rl.RunSpec:
    """The Clebsch top's exact run; ``old``: as the code before ``bind_run`` ran it (parameters solved at the start
    of every kernel call), which writes no ``map_setup`` in run.json, as that code did not."""
    return rl.RunSpec(jg.ChainExactFlow(H, 0.9, backend="compiled"), X0, STEPS, save_every=EVERY,
                      checkpoint_seconds=0, _per_chunk_setup=old)


def _stop_at(step: int):
    def progress(n, steps):
        if n >= step:
            os.kill(os.getpid(), signal.SIGINT)
    return progress


def test_a_chain_run_written_the_old_way_resumes_the_old_way_bit_for_bit(tmp_path):
    """A directory written by the per-chunk code, stopped past its first call, is resumed by the current code: the
    replay with the parameters of X0 does not meet its rows, the per-chunk replay does, and the run goes on that
    way (recorded: run.json ``map_setup``): the orbit equals, bit for bit, the uninterrupted old-way run (which
    differs from the new way's after the first call)."""
    rl.start(_spec(True), tmp_path / "old", handle_signals=False)
    rl.start(_spec(False), tmp_path / "new", handle_signals=False)
    old, new = rl.load(tmp_path / "old").X, rl.load(tmp_path / "new").X
    assert np.array_equal(old[:3], new[:3]) and not np.array_equal(old, new)
    cut = tmp_path / "cut"
    try:
        rl.start(_spec(True), cut, progress=_stop_at(300))
    except rl.RunInterrupted:
        pass
    run = json.loads((cut / "run.json").read_text())
    assert run["status"] == "interrupted" and "map_setup" not in run and run["checkpoint"]["step"] < STEPS
    res = rl.resume(cut, handle_signals=False)
    assert res.state is rl.RunStatus.COMPLETED
    assert json.loads((cut / "run.json").read_text())["map_setup"] == "per_chunk"
    assert np.array_equal(rl.load(cut).X, old)


def test_a_bound_chain_run_resumes_bit_for_bit(tmp_path):
    """Interrupted part-way and resumed: the uninterrupted run's rows, bit for bit (the parameters of X0 again)."""
    rl.start(_spec(False), tmp_path / "whole", handle_signals=False)
    cut = tmp_path / "cut"
    try:
        rl.start(_spec(False), cut, progress=_stop_at(300))
    except rl.RunInterrupted:
        pass
    assert json.loads((cut / "run.json").read_text())["status"] == "interrupted"
    rl.resume(cut, handle_signals=False)
    assert "map_setup" not in json.loads((cut / "run.json").read_text())
    assert np.array_equal(rl.load(cut).X, rl.load(tmp_path / "whole").X)
