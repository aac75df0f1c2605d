"""Exact time steps of an su(3) chain (issue 32): the composition of commuting maps B^(r_k)_(eta_k) is the time-dt
flow of H = Σ w_I h_I with dt·w = Σ_k ω^(r_k)(eta_k) on the non-Casimir integrals (gaudin/sun_exact.py)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin.sun_exact import SunExactStep, _dmu_dh, exact_parameters, match_weights, step_weights

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


# ---- jg.solve(..., method="exact") for su(3) -------------------------------------------------------------------

W_ANY = np.random.default_rng(3).normal(size=MODEL.n_integrals)  # arbitrary weights, Casimirs included


def test_small_im_eta_limit_of_the_weights():
    """ω^(r)(a + iε) = −2ε Re ∂μ_r/∂h(a) + O(ε³) (_dmu_dh: the characteristic polynomial μ³ − τ₂μ − τ₃; the
    weights: quadrature of the Vandermonde route, sun_spectral): measured 5.3e-9 at ε = 1e-3 and 5.3e-12 at 1e-4
    (the ε³ law); asserted 1e-7 and 1e-10.  And ∂ω/∂ε = −2 Re ∂μ_r/∂h(a + iε) at finite ε (Newton's Jacobian)
    against a central difference of the quadrature weights (step 1e-5: error ~1e-10; asserted 1e-8)."""
    for r in range(3):
        for eps, tol in ((1e-3, 1e-7), (1e-4, 1e-10)):
            w = MODEL.interpolating_weights(X0, 0.4 + 1j * eps, r)
            assert np.abs(w + 2 * eps * _dmu_dh(MODEL, X0, 0.4 + 0j, r).real).max() <= tol
        h = 1e-5
        fd = (MODEL.interpolating_weights(X0, 0.4 + 0.2j + 1j * h, r)
              - MODEL.interpolating_weights(X0, 0.4 + 0.2j - 1j * h, r)) / (2 * h)
        assert np.abs(fd + 2 * _dmu_dh(MODEL, X0, 0.4 + 0.2j, r).real).max() <= 1e-8


def test_branch_gradients_at_one_point_span_two_directions():
    """Why exact_parameters takes 2M points: three points give rank 5 < 6 whatever the branches (the branches at
    a point span (u(a), 0), (0, v(a)) only); the 2M = 4 points it takes give 6 (singular values: the smallest
    is ~1e-17 vs ~0.2 -- asserted below 1e-12 and above 1e-3)."""
    mask = ~MODEL.casimir_mask()

    def smallest(pts, brs):
        J = np.stack([_dmu_dh(MODEL, X0, complex(a), r).real[mask] for a, r in zip(pts, brs, strict=True)], axis=1)
        return np.linalg.svd(J, compute_uv=False)[-1]

    three = [-0.7, -0.7, -0.7, 0.4, 0.4, 0.4, 1.6, 1.6, 1.6]
    assert smallest(three, [0, 1, 2] * 3) <= 1e-12
    etas, branches = exact_parameters(MODEL, X0, W_ANY, 0.05)
    assert smallest([e.real for e in etas], branches) >= 1e-3


def test_solve_exact_against_dop853():
    """jg.solve(H, method="exact") for arbitrary weights against DOP853 (rtol = atol = 1e-13): three steps of 0.2,
    measured 1.1e-13, and twenty steps of 0.25 (T = 5), measured 8.8e-13; asserted 1e-11 and 1e-10 (DOP853's
    global error at 1e-13, the quadrature of the weights at round-off; the orbit moves by O(1), and a wrong
    weight, branch or sign is off by > 1e-3)."""
    H = MODEL.hamiltonian(W_ANY)
    for T, dt, tol in ((0.6, 0.2, 1e-11), (5.0, 0.25, 1e-10)):
        ex = jg.solve(H, X0, (0.0, T), dt=dt, method="exact")
        ref = jg.solve(H, X0, (0.0, T), dt=dt, method="dop853", rtol=1e-13, atol=1e-13)
        assert ex.info["substeps"] == 1
        assert np.abs(ex.X - ref.X).max() <= tol
        assert np.abs(ex.X[-1] - X0).max() > 0.5  # it moved
        assert ex.drift.max() <= 1e-12  # integrals kept (measured 8e-15)


@pytest.mark.parametrize("sites", [[(0.0, 1), (1.0, 1)], [(0.3, 2)]])
def test_solve_exact_substeps_and_dense(sites):
    """dt = 1 is past what Newton reaches from the small-Im(eta) guess here: solve splits it into exact sub-steps
    (info["substeps"] = 3) and still meets DOP853 (measured 2.8e-13 / 3.5e-13, asserted 1e-10), as does the
    dense output at off-grid times (measured 2e-13 / 4e-13); substeps=1 raises StepTooLargeError."""
    m = jg.GaudinModel(0.5, sites, algebra="su3")
    x0 = 0.5 * np.random.default_rng(2).normal(size=m.n_state)
    H = m.hamiltonian(np.random.default_rng(3).normal(size=m.n_integrals))
    ex = jg.solve(H, x0, (0.0, 2.0), dt=1.0, method="exact")
    ref = jg.solve(H, x0, (0.0, 2.0), dt=1.0, method="dop853", rtol=1e-13, atol=1e-13)
    assert ex.info["substeps"] > 1
    assert np.abs(ex.X - ref.X).max() <= 1e-10
    dense = jg.solve(H, x0, (0.0, 2.0), t_eval=[0.3, 1.7], method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(ex.at([0.3, 1.7]) - dense.X).max() <= 1e-10
    with pytest.raises(jg.StepTooLargeError) as exc:
        jg.solve(H, x0, (0.0, 2.0), dt=1.0, method="exact", substeps=1)
    assert exc.value.dt_max is not None and 0 < exc.value.dt_max < 1.0


# ---- SunExactFlow as a map: compiled route, batches, integrals, refusals ---------------------------------------

def test_compiled_equals_numpy_and_batch_equals_single():
    """The compiled route (the su(3) kernel's loop with the K = 6 maps, 2 sub-steps) against the maps' NumPy route:
    20 steps, measured 1.6e-13, asserted 1e-11 (round-off of 240 map steps on O(1) states, two routes that agree
    to ~1e-15 a step; a map left out or a sub-step skipped is O(0.1)).  A batch (all cores) equals each orbit's
    single run bit for bit, and save_every keeps the rows of the full orbit."""
    from jetgaudin.gaudin import SunExactFlow

    H = MODEL.hamiltonian(W_ANY)
    X = 0.5 * np.random.default_rng(4).normal(size=(3, MODEL.n_state))
    c = SunExactFlow(H, 0.2, 2, backend="compiled")
    n = SunExactFlow(H, 0.2, 2, backend="numpy")
    oc, on = c.iterate(X, 20), n.iterate(X, 20)
    assert np.abs(oc - on).max() <= 1e-11 and np.abs(oc[-1] - oc[0]).max() > 0.1
    for i in range(3):
        assert np.array_equal(c.iterate(X[i], 20), oc[:, i])
    assert np.array_equal(c.iterate(X, 20, save_every=7), oc[::7])
    assert c.describe()["kind"] == "sun_exact" and jg.map_from_description(c.describe()).describe() == c.describe()


def test_compiled_steps_keep_the_integrals():
    """10^4 compiled exact steps of dt = 0.1 (6 * 10^4 map steps): every integral h^(k)_(j,m) kept to round-off
    (measured max |h - h0| = 6.3e-12 relative to max |h0| = 2.9, a linear growth as the maps' own; asserted 5e-11,
    the maps' 10^4-step bound), while the orbit moves by O(1); and after 100 steps it is the flow of H (DOP853 at
    1e-13 over t = 10: measured 1.6e-12, asserted 1e-10)."""
    from jetgaudin.gaudin import SunExactFlow

    H = MODEL.hamiltonian(W_ANY)
    orbit = SunExactFlow(H, 0.1, backend="compiled").iterate(X0, 10**4, save_every=100)
    I = MODEL.integrals(orbit)
    assert np.abs(I - I[0]).max() <= 5e-11 * np.abs(I[0]).max()
    assert np.abs(orbit - X0).max() > 0.5
    ref = jg.solve(H, X0, (0.0, 10.0), dt=0.1, save_every=100, method="dop853", rtol=1e-13, atol=1e-13).X
    assert np.abs(orbit[:2] - ref[:2]).max() <= 1e-10


def test_flow_refusals_and_max_dt():
    """su(4) and dt = 0 refused at construction; a step with no parameters raises StepTooLargeError whose dt_max is
    dt/k for the first k = 2, 3, 4, 6, ... that solves (here dt = 2: 1, 2/3 and 1/2 fail, 1/3 solves)."""
    from jetgaudin.gaudin import SunExactFlow

    m4 = jg.GaudinModel(0.5, [(0.0, 1)], algebra="su4")
    with pytest.raises(jg.InvalidParameterError, match="su\\(3\\)"):
        SunExactFlow(m4.hamiltonian(np.ones(m4.n_integrals)), 0.1)
    H = MODEL.hamiltonian(W_ANY)
    with pytest.raises(jg.InvalidParameterError, match="dt"):
        SunExactFlow(H, 0.0)
    with pytest.raises(jg.StepTooLargeError) as exc:
        SunExactFlow(H, 2.0).parameters(X0)
    assert exc.value.dt_max == 2.0 / 6 and "substeps >= 7" in str(exc.value)
    with pytest.raises(jg.StepTooLargeError):  # the split before (1 and 2/3 fail too: not re-run here)
        exact_parameters(MODEL, X0, W_ANY, 0.5)
    SunExactFlow(H, 2.0 / 6).parameters(X0)
