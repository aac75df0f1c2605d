"""ChainExactFlow: the exact time-dt flow of a chain Hamiltonian (jetgaudin.exact_chain).

Tolerances: a step is M − 1 chain maps and a rotation (round-off ~1e-15 for states of size ~1); the reference is
DOP853 at rtol = atol = 1e-13 over |T| <= 0.2 (its error ~1e-14): 1e-12 asserted.  (Planted: the rotation's
opposite sign fails by > 1e-3.)
"""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.exact import rotate_about_field
from jetgaudin.exact_chain import ChainExactFlow

CASES = {
    "magnet": (jg.gaudin_magnet(1.0, [0.0, 1.0, 2.5]), [0.3, 0.0, -0.2, 0.0, 0.5, 0.0], (0.05, -0.05)),
    "lagrange chain": (jg.lagrange_chain(1.0, [0.0, 1.5]), [0, 0.5, 0, 0, 0, 0.5, 0, 0], (0.02, -0.01)),
    "twisted top as a chain": (jg.twisted_chain(0.8, [0.0]), [0.1, 0.5, 0.2, 0, 0, 0], (0.05, -0.2)),
}


def _state(model, seed=2):
    return np.random.default_rng(seed).standard_normal(model.n_state) * 0.6


@pytest.mark.parametrize("case", list(CASES))
def test_chain_step_is_the_flow(case):
    """One step equals the DOP853 flow of the chain Hamiltonian (1e-12); −dt inverts it (1e-13)."""
    model, w, dts = CASES[case]
    H = model.hamiltonian(np.array(w, dtype=float))
    X = _state(model)
    for dt in dts:
        E = ChainExactFlow(H, dt)
        X1 = E(X)
        ref = jg.integrate(H, X, dt, rtol=1e-13, atol=1e-13).X[-1]
        assert np.max(np.abs(X1 - ref)) < 1e-12
        assert np.max(np.abs(X1 - X)) > 1e-3  # it moves
        assert np.max(np.abs(E.inverse()(X1) - X)) < 1e-13


def test_sum_of_first_integrals_is_the_rotation():
    """Σ_i h_{i,1} generates the rotation of every spin about e_3 at rate 2b (the rotation the construction undoes):
    DOP853 over τ = 0.3, 1e-11."""
    model = jg.lagrange_chain(0.7, [0.0, 1.5])
    m = np.concatenate([np.arange(1, 2 * n + 1) for n in model.orders])
    X = _state(model)
    ref = jg.integrate(model.hamiltonian((m == 1).astype(float)), X, 0.3, rtol=1e-13, atol=1e-13).X[-1]
    assert np.max(np.abs(rotate_about_field(X, 2 * 0.7 * 0.3) - ref)) < 1e-11


def test_chain_step_too_large_and_description():
    model, w, _ = CASES["lagrange chain"]
    H = model.hamiltonian(np.array(w, dtype=float))
    with pytest.raises(jg.StepTooLargeError, match="smaller dt"):
        ChainExactFlow(H, 0.5)(_state(model))
    E = ChainExactFlow(H, 0.02)
    F = jg.map_from_description(E.describe())
    assert F.describe() == E.describe() and np.array_equal(F(_state(model)), E(_state(model)))
    # one class for every system (issue 33): the top's Hamiltonian builds the top's exact flow; a non-Hamiltonian is
    # refused naming both kinds accepted
    assert ChainExactFlow(jg.physical_hamiltonian(3, 1.0), 0.1).kind == "exact"
    with pytest.raises(jg.InvalidParameterError, match="IntegralHamiltonian .*model.hamiltonian"):
        ChainExactFlow(model, 0.1)


def test_solve_takes_a_chain_hamiltonian():
    """jg.solve(chain H, method="exact") returns the trajectory of ChainExactFlow with the chain's integrals, equal to
    DOP853 at the end (1e-12, T = 0.1: five exact steps).  (Other methods on a chain: tests/test_solve_models.py.)"""
    model, w, _ = CASES["magnet"]
    H = model.hamiltonian(np.array(w, dtype=float))
    X = _state(model)
    tr = jg.solve(H, X, (0.0, 0.1), dt=0.02)
    assert tr.X.shape == (6, model.n_state) and tr.integrals.shape == (6, 2 * model.M)
    assert tr.drift.max() < 1e-13
    assert np.max(np.abs(tr.X[-1] - jg.solve(H, X, (0.0, 0.1), method="dop853", rtol=1e-13, atol=1e-13).X[-1])) < 1e-12


FAMILIES = {  # (model, weights of the matched integrals (non-Casimirs, extras last), dt): three spins, M = 3
    "XXZ magnet (trigonometric, gamma = 0.5)": (
        jg.GaudinModel(1.0, ((0.0, 1), (0.4, 1), (0.9, 1)), family="trigonometric", gamma=0.5), [0.5, 0.2, 0.3, 0.1],
        0.02),
    "XYZ magnet (elliptic, k = 0.5)": (
        jg.GaudinModel(0.0, ((0.0, 1), (0.4, 1), (0.9, 1)), family="elliptic", modulus=0.5), [0.5, 0.2, 0.3, 0.1],
        0.02),
    "trigonometric, orders (2, 1)": (
        jg.GaudinModel(0.8, ((0.0, 2), (0.7, 1)), family="trigonometric", gamma=0.7), [0.4, -0.3, 0.2, 0.1], 0.01),
}


@pytest.mark.parametrize("case", list(FAMILIES))
def test_family_chain_step_is_the_flow(case):
    """The trigonometric (XXZ) and elliptic (XYZ) families: one step of ChainExactFlow equals DOP853 of the chain
    Hamiltonian at rtol = atol = 1e-13 over |dt| = 0.01-0.02 (its error ~1e-15 here) to 1e-12, two steps of dt equal
    one of 2 dt (1e-12: composition, each step exact), and −dt inverts it (1e-13: round-off of k maps and a rotation).
    (Planted: J's rotation rate 1 → 2 fails the XXZ case by 8e-2.  The rational basis (λ − λ_i)^{-m} in place of
    ψ_m in the Jacobian still passes: the residual uses the model's own weights, the Jacobian only steers Newton.)"""
    model, wk, dt = FAMILIES[case]
    w = np.zeros(model.n_integrals)
    w[~model.casimir_mask()] = wk
    H = model.hamiltonian(w)
    X = np.random.default_rng(3).standard_normal(model.n_state) * 0.5
    E = ChainExactFlow(H, dt)
    X1 = E(X)
    ref = jg.integrate(H, X, dt, rtol=1e-13, atol=1e-13).X[-1]
    assert np.max(np.abs(X1 - X)) > 1e-3  # it moves
    assert np.max(np.abs(X1 - ref)) < 1e-12
    assert np.max(np.abs(E(X1) - ChainExactFlow(H, 2 * dt)(X))) < 1e-12
    assert np.max(np.abs(E.inverse()(X1) - X)) < 1e-13
    assert np.max(np.abs(model.integrals(X1) - model.integrals(X))) < 1e-13  # integrals kept (round-off)
    F = jg.map_from_description(E.describe())  # the family travels with the description
    assert F.describe() == E.describe() and np.array_equal(F(X), X1)
