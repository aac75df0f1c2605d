"""``jetgaudin.solve``: properties the mutation sample of issue 33 found unchecked, and a defect it led to.

Each test names the mutant (``docs/mutation.md``) or the defect it was written for; each was run on it, planted by
hand, and fails there.  Tolerances: an exact step is the flow to round-off (~1e-15 a step for states of size ~1);
references are DOP853 at rtol = atol = 1e-13 (error ~1e-13 over these spans): 1e-11 asserted unless stated.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import maps
from jetgaudin.exact_chain import ChainExactFlow

solve_module = importlib.import_module("jetgaudin.solve")  # the module (jetgaudin.solve is also the function)

H3 = jg.physical_hamiltonian(3, 1.0)
X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2
CHAIN = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
H_CHAIN = CHAIN.hamiltonian(np.array([0.3, 0, -0.2, 0, 0.5, 0, 0.4]))
X_CHAIN = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])


def _dop(H, X, T):
    return jg.solve(H, X, (0.0, T), method="dop853", rtol=1e-13, atol=1e-13).X[-1]


def test_a_chains_dense_output_takes_the_substeps_of_its_solve():
    """Defect found here (fixed in solve.py): a chain trajectory whose step needed sub-steps (``substeps="auto"``
    chose 5) answered ``tr.at(t)`` between saved states with one chain step of up to half a step, beyond the leaf's
    largest step: a StepTooLargeError reached the user of ``tr.at``, of ``find_events`` and of ``poincare_section``
    (which ``solve``'s documentation says never happens).  Now the dense output splits its step as the solve did."""
    dmax = float(ChainExactFlow(H_CHAIN, 1.0).max_dt(X_CHAIN))
    h = 4 * dmax
    tr = jg.solve(H_CHAIN, X_CHAIN, (0, 3 * h), dt=h)
    assert tr.info["substeps"] >= 5
    for t in (0.5 * h - 1e-9, 0.5 * h + 1e-9, 2.3 * h):  # half a step from a saved state, either side; mid-interval
        assert np.max(np.abs(tr.at(t) - _dop(H_CHAIN, X_CHAIN, t))) < 1e-11
    ev = jg.find_events(H_CHAIN, X_CHAIN, lambda X: X[0] - 0.3, (0, 3 * h), h)
    for t, X in zip(ev.t, ev.X, strict=True):
        assert abs(X[0] - 0.3) < 1e-11 and np.max(np.abs(X - _dop(H_CHAIN, X_CHAIN, t))) < 1e-11


def test_the_dense_output_flows_from_the_nearest_saved_state(monkeypatch):
    """``tr.at(t)`` is one exact step from the saved state nearest to ``t`` (at most half a step of flow: the least
    round-off, and within the step the solve took), on both sides of a saved state; at the end of the span (and up
    to its slack of 1e-12) too.  Written for the mutants ``flat - ts[j-1]`` → ``flat / ts[j-1]`` (the farther
    state, still the flow to round-off) and ``len(ts) - 1`` → ``len(ts)`` (an IndexError at the end)."""
    tr = jg.solve(H3, X3, (0, 1.0), dt=0.1)
    seen: list[float] = []
    real = solve_module.method_map  # the route table's map of one step (jetgaudin.methods)

    def spy(H, method, ds, *args, **kwargs):
        seen.append(ds)
        return real(H, method, ds, *args, **kwargs)

    monkeypatch.setattr(solve_module, "method_map", spy)
    for t in (0.31, 0.39, 0.04, 0.96):
        tr.at(t)
    assert np.allclose(seen, [0.01, -0.01, 0.04, -0.04], rtol=0, atol=1e-12)
    end = tr.at(1.0 + 1e-13)  # inside the slack: the last saved state, flowed by 1e-13
    assert np.max(np.abs(end - tr.X[-1])) < 1e-11


def test_the_dense_output_in_the_first_interval():
    """Times between the first two saved states (and the start itself) are in the span: the start state at ``t0``,
    the flow after it.  Written for the mutant ``ts[0] - slack`` → ``ts[1] - slack`` (the first interval refused)."""
    tr = jg.solve(H3, X3, (0, 1.0), dt=0.1)
    assert np.array_equal(tr.at(0.0), X3)
    assert np.max(np.abs(tr.at(0.03) - _dop(H3, X3, 0.03))) < 1e-11
    with pytest.raises(jg.InvalidParameterError, match="span"):
        tr.at(-0.01)


def test_the_output_cap_counts_the_bytes_of_every_row(monkeypatch):
    """``solve`` refuses, before stepping, an output larger than ``maps.MAX_OUTPUT_BYTES``: with a cap of 64 kB,
    1001 rows of a 9-component state (its 9 doubles, the time and the 6 integrals: 128 kB) are refused, naming the
    cap; 300 rows (38 kB) run.  Written for the mutant ``8 * (...)`` → ``8 / (...)`` (then nothing was refused)."""
    monkeypatch.setattr(maps, "MAX_OUTPUT_BYTES", 64_000)
    with pytest.raises(jg.OutputTooLargeError, match="64,000 bytes"):
        jg.solve(H3, X3, (0, 100.0), dt=0.1)
    assert jg.solve(H3, X3, (0, 29.9), dt=0.1).X.shape == (300, 9)


def test_auto_substeps_are_at_most_one_percent_above_the_least():
    """``substeps="auto"`` splits a step beyond the leaf's ``dt_max`` into ``ceil(|dt| / dt_max · 1.01)`` exact
    sub-steps (1 % above the least, for the bisection's 1e-3 in dt_max): never more.  Written for the mutant
    ``· 1.01`` → ``/ dt_max ** 1.01`` (52 sub-steps where 51 do at |dt| = 50.41 dt_max, dt_max = 0.27)."""
    dmax = float(jg.ExactFlow(H3, 1.0).max_dt(X3))
    for ratio in (2.5, 50.41):
        tr = jg.solve(H3, X3, (0, ratio * dmax), dt=ratio * dmax)
        s = tr.info["substeps"]
        assert ratio <= s <= math.ceil(ratio * 1.01), (ratio, s)
        assert np.max(np.abs(tr.X[-1] - _dop(H3, X3, ratio * dmax))) < 1e-11


def test_a_negative_dt_is_its_size():
    """``dt`` is the step's size, its sign ignored: ``dt = -0.1`` on ``(0, 1)`` is ``dt = 0.1``, and a backward span
    ``(1, 0)`` steps backward with either sign.  Written for the mutant ``dt == 0`` → ``dt <= 0`` (a negative dt
    refused)."""
    a = jg.solve(H3, X3, (0, 1.0), dt=0.1)
    b = jg.solve(H3, X3, (0, 1.0), dt=-0.1)
    assert np.array_equal(a.X, b.X) and np.array_equal(a.t, b.t)
    back = jg.solve(H3, X3, (1.0, 0.0), dt=-0.1)
    assert np.allclose(back.t, np.linspace(1.0, 0.0, 11), rtol=0, atol=1e-15)
    assert np.max(np.abs(back.X[-1] - _dop(H3, X3, -1.0))) < 1e-11


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_t_eval_is_absolute_for_every_method_with_dense_output():
    """``t_eval`` holds absolute times: on ``t_span = (2, 4)`` DOP853 (rtol = atol = 1e-13) and the exact flow's dense
    output give the same states at ``2.5, 3, 4`` (1e-10: DOP853's error over a span of 2 is ~1e-13, the exact flow's
    round-off ~1e-15 a step), and ``t`` is ``t_eval`` itself; a fixed-step map without dense output (midpoint) is
    refused, naming why.  Written for the mutants ``t_eval − t0`` → ``t_eval · t0`` (DOP853 sampled at 5, 6, 8) and
    ``if tr.dense is None`` → ``if not tr.dense is None`` (the exact flow's ``t_eval`` refused)."""
    te = [2.5, 3.0, 4.0]
    dop = jg.solve(H3, X3, (2.0, 4.0), method="dop853", rtol=1e-13, atol=1e-13, t_eval=te)
    ex = jg.solve(H3, X3, (2.0, 4.0), dt=0.1, t_eval=te)
    assert dop.t.tolist() == te and ex.t.tolist() == te
    assert np.max(np.abs(dop.X - ex.X)) < 1e-10 and np.max(np.abs(ex.X[0] - X3)) > 1e-2
    with pytest.raises(jg.InvalidParameterError, match="t_eval needs dense output"):
        jg.solve(H3, X3, (2.0, 4.0), dt=0.1, method="midpoint", t_eval=te)


def test_the_dense_output_of_a_backward_solve():
    """A solve backwards in time, ``(1, −1)`` at ``dt = 0.25``: its dense output gives the saved states at the saved
    times (bit for bit: no step is taken there) and, between them, the state one exact step from the nearest saved one
    -- the same as a direct solve from ``X3`` to that time (1e-11: two exact flows, ~1e-15 a step).  Written for the
    mutant ``t_grid[::-1]`` → ``t_grid[::-2]`` (the reversed grid's times no longer matched its states)."""
    tr = jg.solve(H3, X3, (1.0, -1.0), dt=0.25)
    assert np.array_equal(tr.at(tr.t), tr.X)
    for t in (0.1, -0.6, -0.95):
        direct = jg.solve(H3, X3, (1.0, t), dt=0.05).X[-1]
        assert np.max(np.abs(tr.at(t) - direct)) < 1e-11, t


def test_dense_output_refuses_times_beyond_the_span_by_more_than_its_slack():
    """The span is ``[0, 1]``; times beyond it by up to ``1e-12 · max(1, span)`` (round-off of the caller's times) are
    taken, farther ones refused: ``1 + 0.5e-12`` and ``−0.5e-12`` are taken, ``1 + 1.5e-12`` and ``−1.5e-12`` not.
    Written for the mutant ``max(1.0, span)`` → ``max(2.0, span)`` (twice the slack)."""
    tr = jg.solve(H3, X3, (0.0, 1.0), dt=0.25)
    for t in (1 + 0.5e-12, -0.5e-12):
        assert np.all(np.isfinite(tr.at(t)))
    for t in (1 + 1.5e-12, -1.5e-12):
        with pytest.raises(jg.InvalidParameterError, match="span"):
            tr.at(t)


def test_save_every_zero_is_refused():
    """``save_every = 0`` is refused naming it (at least 1; it was a ZeroDivisionError).  Written for the mutant
    ``check_count(save_every, "save_every", 1)`` → ``…, 0)``."""
    with pytest.raises(jg.InvalidParameterError, match="save_every"):
        jg.solve(H3, X3, (0.0, 1.0), dt=0.25, save_every=0)


def test_the_output_cap_is_reached_to_the_byte(monkeypatch):
    """A top of order 3 over 100 steps: ``100 // 1 + 2`` rows (the saved rows and a spare for the end state) of
    ``8 · (9 + 1 + 6)`` = 128 bytes (the state, the time, the 2N = 6 integrals): a cap of exactly that runs, one byte
    less is refused.  Written for the mutant ``X0.shape[-1] // 3`` → ``// 4`` (two integrals a row not counted)."""
    need = (100 + 2) * 8 * (9 + 1 + 6)
    monkeypatch.setattr(maps, "MAX_OUTPUT_BYTES", need)
    assert jg.solve(H3, X3, (0.0, 10.0), dt=0.1).X.shape == (101, 9)
    monkeypatch.setattr(maps, "MAX_OUTPUT_BYTES", need - 1)
    with pytest.raises(jg.OutputTooLargeError, match=f"{need:,} bytes"):
        jg.solve(H3, X3, (0.0, 10.0), dt=0.1)


def test_method_map_takes_one_substep_by_default():
    """``jetgaudin.methods.method_map(H, "exact", dt)`` is the exact flow of one sub-step: bit for bit
    ``ExactFlow(H, dt)``.  Written for the mutant ``substeps: int = 1`` → ``= 0`` (then refused)."""
    from jetgaudin.methods import method_map

    m = method_map(H3, "exact", 0.1)
    assert m.substeps == 1 and np.array_equal(m(X3), jg.ExactFlow(H3, 0.1)(X3))
