"""Exact time steps of an su(3) chain (issue 32): the composition of commuting maps B^(r_k)_(eta_k) is the time-dt
flow of H = Σ w_I h_I with dt·w = Σ_k ω^(r_k)(eta_k) on the non-Casimir integrals (gaudin/sun_exact.py)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin.sun_exact import SunExactStep, match_weights, step_weights

MODEL = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")  # 6 non-Casimir integrals: 3 maps
X0 = 0.5 * np.random.default_rng(2).normal(size=MODEL.n_state)
ETAS = (0.4 + 0.1j, -0.6 + 0.15j, 1.5 + 0.08j)
BRANCHES = (0, 1, 2)
DT = 0.3


def _hamiltonian(weights):
    w = np.where(MODEL.casimir_mask(), 0.0, weights)  # the Casimirs generate no flow: left out of H
    return MODEL.hamiltonian(w)


def test_step_is_the_flow_of_H():
    """Three steps against DOP853 (rtol = atol = 1e-13) on the flow of H = Ω/dt over 3 dt: 1e-9 (the quadrature
    of the weights, 16 x 16 Gauss-Legendre nodes, and DOP853's global error; an omitted map or a wrong branch is
    O(0.1))."""
    S = SunExactStep(MODEL, ETAS, BRANCHES)
    W = S.weights(X0) / DT
    orbit = S.iterate(X0, 3)
    tr = jg.solve(_hamiltonian(W), X0, (0.0, 3 * DT), dt=DT, method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(orbit - tr.X).max() <= 1e-9
    assert np.abs(orbit[-1] - X0).max() > 0.05  # it moved
    wrong = SunExactStep(MODEL, ETAS, (0, 1, 1)).iterate(X0, 3)
    assert np.abs(wrong - tr.X).max() > 1e-3


def test_match_weights_recovers_the_parameters():
    """Newton from a perturbed guess meets dt·w on the 6 non-Casimir integrals (1e-12 relative) and the step it
    gives is the flow of H (1e-9, as above)."""
    W = step_weights(MODEL, X0, ETAS, BRANCHES) / DT
    guess = tuple(e + 0.02 * (1 - 1j) for e in ETAS)
    etas = match_weights(MODEL, X0, W, DT, guess, BRANCHES)
    mask = ~MODEL.casimir_mask()
    got = step_weights(MODEL, X0, etas, BRANCHES)[mask]
    assert np.abs(got - DT * W[mask]).max() <= 1e-10 * (1 + np.abs(DT * W).max())
    orbit = SunExactStep(MODEL, etas, BRANCHES).iterate(X0, 2)
    tr = jg.solve(_hamiltonian(W), X0, (0.0, 2 * DT), dt=DT, method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(orbit - tr.X).max() <= 1e-9


def test_refusals():
    with pytest.raises(jg.InvalidParameterError, match="give 3 etas"):
        match_weights(MODEL, X0, np.ones(10), DT, ETAS[:2], BRANCHES[:2])
    with pytest.raises(jg.StepTooLargeError):
        match_weights(MODEL, X0, 50 * np.ones(10), DT, ETAS, BRANCHES, max_iter=2)
