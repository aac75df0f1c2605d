"""The top as a one-site model (issue 33 item 1): ``GaudinTop(N, b).model`` is ``GaudinModel(b, [(0, N)])`` and
``IntegralHamiltonian.as_model()`` / ``ChainHamiltonian.as_top()`` go both ways with the same weights (one site at 0
has ``h_m = H_m``, ``h_{N+k} = C_k``, module docstring of ``jetgaudin.gaudin.model``).  Checked independently of
the views' code: the model's own forms (``GaudinModel.integrals``, built site by site from the Taylor coefficients)
against the top's (``jetgaudin.spectral.integrals``, from the Lax coefficients), the vector fields, the two-point map
on both NumPy routes, and the exact flows (two independent constructions: ``ExactFlow`` and ``ChainExactFlow``).
The route table sends a top's compiled two-point map and ``solve``'s exact and bt to the top's hand-tuned kernels:
the orbits are then the top's bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.exact_chain import ChainExactFlow

B = 1.3
ETA = 2.0 + 0.3j


def _state(N, seed=0):
    return np.random.default_rng(seed + N).standard_normal(3 * N) * 0.6


@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_integrals_and_vector_field_equal_the_tops(N):
    """Integrals and the Hamiltonian vector field of every integral agree to 1e-14 (round-off on O(1) states: a
    wrong Taylor coefficient or sign is O(1e-1) here)."""
    top = jg.GaudinTop(N, B)
    model = top.model
    assert isinstance(model, jg.GaudinModel) and model.sites == ((0.0, N),) and model.b == B and model.is_top
    X = np.stack([_state(N, s) for s in range(4)])
    assert np.abs(model.integrals(X) - top.integrals(X)).max() < 1e-14
    for m in range(2 * N):
        w = np.eye(2 * N)[m] + 0.3
        Ht = jg.IntegralHamiltonian(B, w)
        Hc = Ht.as_model()
        assert isinstance(Hc, jg.ChainHamiltonian) and Hc.model == model
        assert np.abs(Hc.vector_field(X) - Ht.vector_field(X)).max() < 1e-14
        back = Hc.as_top()
        assert isinstance(back, jg.IntegralHamiltonian) and back.b == B and np.array_equal(back.weights, w)
    if N >= 2:  # the physical H_2/2; for N = 1 the top's is H_1/2, the model's ½ h_(1,2) (a Casimir): not a view
        assert np.abs(top.model.physical_hamiltonian()(X) - top.energy(X)).max() < 1e-14


def test_refusals_name_why():
    # jet constants are a site option (tests/test_site_constants.py); c_1 = 0 (T singular) and complex c are refused
    with pytest.raises(jg.InvalidParameterError, match="c_1 = 0 makes the jet matrix T singular"):
        jg.IntegralHamiltonian(B, np.ones(6), c=[0.0, 0.5]).as_model()
    with pytest.raises(jg.InvalidParameterError, match="must be real"):
        jg.IntegralHamiltonian(B, np.ones(6), c=[-1.0, 0.5j]).as_model()
    with pytest.raises(jg.InvalidParameterError, match="b e_3"):
        jg.IntegralHamiltonian([1.0, 0.0, 1.0], np.ones(4)).as_model()
    for model in (jg.GaudinModel(B, [(0.5, 2)]), jg.GaudinModel(B, [(0.0, 1), (1.0, 1)]),
                  jg.GaudinModel(0.0, [(0.0, 2)]), jg.GaudinModel(B, [(0.0, 2)], family="trigonometric", gamma=1.0)):
        assert not model.is_top
        with pytest.raises(jg.InvalidParameterError, match="not a top: a top is one rational site at 0"):
            model.hamiltonian(np.ones(model.n_integrals)).as_top()


@pytest.mark.parametrize("N", [2, 3])
def test_two_point_map_equals_the_tops(N):
    """The NumPy routes (the chain's dressing site by site, the top's (hh)/(hhh)) agree to 1e-12 over 100 steps
    (round-off growing along the orbit; a wrong branch or sign is O(1)), single orbits and a batch.  The compiled
    route of the one-site model *is* the top's kernel: bit for bit, and a run split in two (the carry ν1 handed on)
    equals the unsplit run bit for bit."""
    top = jg.TwoPointBacklund(B, ETA, backend="numpy")
    chain = jg.GaudinModel(B, [(0.0, N)]).two_point_backlund(ETA, backend="numpy")
    X = np.stack([_state(N, s) for s in range(3)])
    assert np.abs(top.iterate(X, 100) - chain.iterate(X, 100)).max() < 1e-12
    ctop = jg.TwoPointBacklund(B, ETA, backend="compiled")
    cch = chain.with_backend("compiled")
    for x in (X[0], X):
        assert np.array_equal(ctop.iterate(x, 100), cch.iterate(x, 100))
    o1, c1 = cch.iterate(X, 30, save_every=3, return_carry=True)
    o2, c2 = ctop.iterate(X, 30, save_every=3, return_carry=True)
    assert np.array_equal(o1, o2) and np.array_equal(c1, c2)
    assert np.array_equal(cch.iterate(o1[-1], 5, carry=c1), ctop.iterate(o2[-1], 5, carry=c2))
    a = cch.advance(X[0], None, 40, 1)
    b1 = cch.advance(X[0], None, 25, 1)
    b2 = cch.advance(b1.X, b1.carry, 15, 1)
    assert np.array_equal(a.rows, np.concatenate([b1.rows, b2.rows])) and np.array_equal(a.X, b2.X)


@pytest.mark.parametrize("N", [2, 3])
def test_exact_flow_and_solve_take_the_tops_route(N):
    """Two independent exact flows (the top's ExactFlow, N − 1 maps from the top's weights; ChainExactFlow, from the
    chain's design) agree to 1e-12 over 10 steps; ``solve`` on the one-site model takes the top's rows of the route
    table (exact and bt: bit for bit the top's trajectories) and records the same integrals."""
    w = np.linspace(0.2, 0.9, 2 * N)
    Ht = jg.IntegralHamiltonian(B, w)
    Hc = Ht.as_model()
    X = _state(N)
    dt = 0.05
    ref = jg.ExactFlow(Ht, dt).iterate(X, 10)
    assert np.abs(ChainExactFlow(Hc, dt).iterate(X, 10) - ref).max() < 1e-12
    for method in ("exact", "bt"):
        a = jg.solve(Ht, X, (0.0, 0.5), dt=dt, method=method)
        c = jg.solve(Hc, X, (0.0, 0.5), dt=dt, method=method)
        assert np.array_equal(a.X, c.X) and np.abs(a.integrals - c.integrals).max() < 1e-14
