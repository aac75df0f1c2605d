"""jg.solve for su(n) chain Hamiltonians (issue 32): DOP853 and heyoka (n = 3) on the flow of H = Σ w_I h_I, the
gradient polynomial heyoka's equations are built from, and the refused methods (typed, naming those that work)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin.sun_solve import gradient_polynomial

MODEL = jg.GaudinModel(0.5, [(-1.0, 2), (0.7, 1)], algebra="su3")  # 24 components, 15 integrals
X0 = 0.5 * np.random.default_rng(0).normal(size=MODEL.n_state)
W = np.linspace(0.1, 1.0, 15) * np.where(np.arange(15) % 2, 1.0, -1.0)  # cubic integrals h^(3) included


def test_gradient_polynomial_is_the_gradient():
    """g0 + a x + Σ q_jk x_j x_k against the exact gradient at random points (round-off: 1e-12 relative; a
    dropped or doubled coefficient is O(1))."""
    H = MODEL.hamiltonian(W)
    g0, a, q = gradient_polynomial(H)
    for seed in range(3):
        x = np.random.default_rng(seed).normal(size=MODEL.n_state)
        g = g0 + a @ x + sum(c * x[j] * x[k] for j, k, c in q)
        ref = H.gradient(x)
        assert np.abs(g - ref).max() <= 1e-12 * (1 + np.abs(ref).max())


def test_heyoka_and_dop853_agree():
    """heyoka (rtol 1e-15) and DOP853 (rtol = atol = 1e-13) over t = 2 agree to 1e-10 (the DOP853 global error on
    O(1) states; a wrong sign or factor in heyoka's equations is O(1)), and both keep the 15 integrals to 1e-11."""
    pytest.importorskip("heyoka")
    m = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")  # 16 components (heyoka compiles in ~1 s)
    X = X0[:16]
    H = m.hamiltonian(W[:10])
    a = jg.solve(H, X, (0.0, 2.0), dt=0.5, method="heyoka", rtol=1e-15)
    b = jg.solve(H, X, (0.0, 2.0), dt=0.5, method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(a.X - b.X).max() <= 1e-10
    assert np.abs(a.X[-1] - X).max() > 0.1  # it moved
    for tr in (a, b):
        assert np.abs(tr.integrals - m.integrals(X)).max() <= 1e-11


@pytest.mark.parametrize("method, words", [
    ("kahan", ["'kahan'", "quadratic", "'dop853', 'heyoka'"]),
    ("bt", ["'bt'", "matched", "'dop853', 'heyoka', 'midpoint'"]),
])
def test_refused_methods_are_named(method, words):
    with pytest.raises(jg.InvalidParameterError) as exc:
        jg.solve(MODEL.hamiltonian(W), X0, (0.0, 1.0), dt=0.25, method=method)
    assert all(w in str(exc.value) for w in words), str(exc.value)


def test_heyoka_refused_past_n3():
    m = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su4")
    with pytest.raises(jg.InvalidParameterError, match="n <= 3.*'dop853'"):
        jg.solve(m.hamiltonian(np.ones(len(m.integral_labels()))), np.full(m.n_state, 0.1), (0.0, 1.0),
                 method="heyoka")


def test_exact_refused_past_n3():
    """The exact step is built for su(3) (docs/sun.md §5): su(4) is refused naming it and the methods that work."""
    m = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su4")
    with pytest.raises(jg.InvalidParameterError, match=r"'exact'.*su\(3\).*'dop853'"):
        jg.solve(m.hamiltonian(np.ones(len(m.integral_labels()))), np.full(m.n_state, 0.1), (0.0, 1.0), dt=0.5,
                 method="exact")
