"""The compiled per-call set-up of the chain maps: the branch rule of ν at the first state, compiled for every
family (``jetgaudin.gaudin._family_kernel.branch_rule``), against the NumPy rule (``ChainTwoPointBacklund.start``:
the exact root product in the uniformizer; the numerical continuation for the elliptic family)."""

import numpy as np
import pytest

from jetgaudin.gaudin import GaudinModel, _family_kernel

MODELS = {
    "rational": GaudinModel(0.8, [(-1.0, 2), (0.3, 1), (1.1, 1)]),
    "trigonometric": GaudinModel(0.8, [(-1.0, 2), (0.3, 1), (1.1, 1)], family="trigonometric", gamma=0.7),
    "trig-b0": GaudinModel(0.0, [(-1.0, 1), (0.3, 3)], family="trigonometric"),
    "elliptic": GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6),  # numerical NumPy rule
}


def _states(model, n, seed=3):
    return np.random.default_rng(seed).normal(size=(n, model.n_state))


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("eta", [0.2 + 0.05j, -0.4 + 0.6j, 0.7 - 0.3j])
@pytest.mark.parametrize("branch", ["default", "opposite"])
def test_compiled_branch_rule_agrees_with_numpy_rule(name, eta, branch):
    """The compiled rule gives the NumPy rule's sign on 200 random states (only its sign reaches the kernels: the
    value is compared to 1e-9 relative, the round-off of two evaluations of ν(η); a wrong sign differs by 2|ν|)."""
    model = MODELS[name]
    B = model.two_point_backlund(eta, branch=branch, kernel="compiled")
    X = _states(model, 200)
    raw, ok = _family_kernel.branch_rule(X, model.b, _family_kernel.segment_constants(model, B.eta), B.sheet)
    want = B.start(X)
    # the compiled rule itself (not its NumPy fall-back) answers for nearly all states
    assert np.count_nonzero(ok) >= 0.95 * len(ok)
    assert np.max(np.abs(raw[ok] - want[ok]) / np.abs(want[ok])) < 1e-9
    got = B._compiled_start(X)
    assert np.max(np.abs(got - want) / np.abs(want)) < 1e-9


@pytest.mark.parametrize("name", sorted(MODELS))
def test_compiled_start_gives_the_numpy_started_orbits_bit_for_bit(name):
    """A compiled run started by the compiled rule (carry None) equals, bit for bit, the one started from the NumPy
    rule's ν1 (exact equality: the kernels take the root of ν² nearest to ν1, so only its sign matters)."""
    model = MODELS[name]
    B = model.two_point_backlund(0.2 + 0.05j, kernel="compiled")
    X = _states(model, 5, seed=11)
    a = B.advance(X, None, 50)
    b = B.advance(X, B.start(X), 50)
    assert np.array_equal(a.rows, b.rows) and np.array_equal(a.X, b.X) and np.array_equal(a.carry, b.carry)
    one = B.advance(X[2], None, 50)  # a single orbit (the per-orbit loop of the rational route)
    assert np.array_equal(one.rows, a.rows[:, 2])


def test_flagged_states_take_the_numpy_rule(monkeypatch):
    """With one step on the segment (n = 1) the compiled rule cannot vouch for its continuation on most states; those
    states get the NumPy rule's ν1 exactly (equality), the others agree with it (1e-9 relative, as above)."""
    model = MODELS["trigonometric"]
    B = model.two_point_backlund(-0.4 + 0.9j, kernel="compiled")
    X = _states(model, 100, seed=5)
    coarse = _family_kernel.segment_constants(model, B.eta, 1)
    _, ok = _family_kernel.branch_rule(X, model.b, coarse, 1)
    assert 0 < np.count_nonzero(~ok) < len(ok)  # the test exercises both kinds
    monkeypatch.setattr(_family_kernel, "segment_constants", lambda m, e: coarse)
    got = B._compiled_start(X)
    want = B.start(X)
    assert np.array_equal(got[~ok], want[~ok])
    assert np.max(np.abs(got - want) / np.abs(want)) < 1e-9


@pytest.mark.parametrize("name", ["rational", "trigonometric"])
def test_replace_backend_is_not_overridden_by_the_kernel_alias(name):
    """The run layer resolves AUTO by ``dataclasses.replace(map, backend=...)``; the constructor's ``kernel=`` alias
    must not bring the old route back (it did: every chunk of a CLI run then re-resolved AUTO on its own few steps
    and ran on NumPy, ~500 steps/s)."""
    import dataclasses

    from jetgaudin.maps import Backend

    B = MODELS[name].two_point_backlund(0.2 + 0.05j, kernel="auto")
    assert dataclasses.replace(B, backend=Backend.COMPILED).backend is Backend.COMPILED
    assert dataclasses.replace(B, backend=Backend.COMPILED).resolved_backend(np.zeros(B.n_state), 1) \
        is Backend.COMPILED
    assert MODELS[name].two_point_backlund(0.2 + 0.05j, kernel="numpy").backend is Backend.NUMPY


@pytest.mark.parametrize("name", ["rational", "elliptic"])
def test_a_flagged_state_takes_the_numpy_rule_and_the_others_keep_theirs(name, monkeypatch):
    """A batch with one state the compiled rule flags (here by wrapping it: the flag of state 1 forced) and one it
    answers: the flagged state gets the NumPy rule's ν of *that* state, the other its compiled value (issue 33: a
    mutant that gave the flagged states the NumPy rule of the unflagged ones survived the chain maps' tests)."""
    model = MODELS[name]
    B = model.two_point_backlund(0.2 + 0.05j, kernel="compiled")
    X = _states(model, 3, seed=11)
    real = _family_kernel.branch_rule

    def flag_state_1(*args):
        nu, ok = real(*args)
        ok = ok.copy()
        nu = nu.copy()
        ok[1] = False
        nu[1] = np.nan  # what a flagged state's compiled value may be: it must not be used
        return nu, ok

    monkeypatch.setattr(_family_kernel, "branch_rule", flag_state_1)
    got = B._compiled_start(X)
    want = B.start(X)
    assert got[1] == want[1]  # the NumPy rule at state 1 itself, exactly (the same call)
    ok_states = [0, 2]
    assert np.max(np.abs(got[ok_states] - want[ok_states]) / np.abs(want[ok_states])) < 1e-9  # as the test above
