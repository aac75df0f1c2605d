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
