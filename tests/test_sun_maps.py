"""The real two-point maps B^{(r)}_η of su(n) chains (issue 32): every property the docstrings claim."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jetgaudin as jg
from jetgaudin.gaudin.sun import SunGaudinModel
from jetgaudin.gaudin.sun_maps import dress

SITES = [(-1.0, 2), (0.7, 1)]
ETA = 0.3 + 0.25j


def _model(n=3, sites=SITES, b=0.5):
    return jg.GaudinModel(b, sites, algebra=f"su({n})")


def _state(model, seed=0, scale=0.5):
    return scale * np.random.default_rng(seed).normal(size=model.n_state)


def test_n2_is_the_su2_map_on_random_chains():
    """r = 0 is the su(2) chain's default branch, r = 1 its "opposite" (round-off: 1e-12 on O(1) states)."""
    rng = np.random.default_rng(4)
    for _trial in range(5):
        sites = [(float(p), int(N)) for p, N in zip(np.sort(rng.uniform(-2, 2, 3)), rng.integers(1, 4, 3),
                                                    strict=True)]
        b = float(rng.normal())
        a, g = jg.GaudinModel(b, sites), SunGaudinModel(b, sites, algebra="su(2)")
        X = rng.normal(size=a.n_state)
        eta = complex(rng.uniform(-2, 2), rng.uniform(0.05, 0.6))
        for r, name in ((0, "default"), (1, "opposite")):
            today = a.two_point_backlund(eta, branch=name, backend="numpy").iterate(X, 3)
            general = g.two_point_backlund(eta, branch=r).iterate(X, 3)
            assert np.allclose(general, today, atol=1e-12 * (1 + np.max(np.abs(today))))
        assert g.two_point_backlund(eta, branch="opposite").branch == 1


@pytest.mark.parametrize("n, sites", [(3, SITES), (3, [(0.0, 3)]), (4, [(-0.5, 1), (0.6, 2)])])
def test_real_keeps_integrals_and_inverse(n, sites):
    """Real (imaginary residue ~ round-off), integrals kept (1e-12 relative), B^{(r)}_{η̄} B^{(r)}_η = 1 (1e-12)."""
    m = _model(n, sites)
    X = _state(m, seed=n)
    I0 = m.integrals(X)
    for r in range(n):
        B = m.two_point_backlund(ETA, branch=r)
        Y, mu, imag = B.step(X)
        assert Y.dtype == float and imag < 1e-13
        assert np.max(np.abs(Y - X)) > 1e-3  # a genuine step
        assert np.allclose(m.integrals(Y), I0, atol=1e-12 * (1 + np.max(np.abs(I0))))
        assert np.allclose(B.inverse()(Y), X, atol=1e-12)
        assert mu == pytest.approx(m.eigenvalue(Y, ETA, r), abs=1e-12)  # μ_r(η) is an integral


@pytest.mark.parametrize("n", [3, 4])
def test_branch_product_is_the_identity(n):
    """Σ_r μ_r = tr ℓ = 0, so the n branch maps at one η compose to the identity (1e-12), in any order."""
    m = _model(n)
    X = _state(m, seed=1)
    for order in (range(n), reversed(range(n))):
        Y = X
        for r in order:
            Y = m.two_point_backlund(ETA, branch=r)(Y)
        assert np.allclose(Y, X, atol=1e-12)
    assert np.sum([m.interpolating_hamiltonian(X, ETA, r) for r in range(n)]) == pytest.approx(0, abs=1e-12)


def test_commuting_maps():
    """B^{(r)}_η B^{(s)}_ζ = B^{(s)}_ζ B^{(r)}_η (1e-12)."""
    m = _model()
    X = _state(m, seed=2)
    A, B = m.two_point_backlund(ETA, branch=0), m.two_point_backlund(-0.4 + 0.6j, branch=2)
    assert np.allclose(A(B(X)), B(A(X)), atol=1e-12)
    assert not np.allclose(A(B(X)), A(X), atol=1e-3)


@pytest.mark.parametrize("sites, r", [(SITES, 0), (SITES, 1), (SITES, 2), ([(0.0, 2)], 1)])
def test_poisson(sites, r):
    """J Π(X) Jᵀ = Π(B(X)) with J by central differences (h = 1e-6: error ~1e-10 on O(1) entries; tolerance 1e-8)."""
    m = _model(3, sites)
    X = _state(m, seed=3)
    B = m.two_point_backlund(ETA, branch=r)
    mu = B.start(X)
    h = 1e-6
    J = np.array([(B.step(X + h * e, mu)[0] - B.step(X - h * e, mu)[0]) / (2 * h) for e in np.eye(m.n_state)]).T
    assert np.allclose(J @ m.poisson_tensor(X) @ J.T, m.poisson_tensor(B(X)), atol=1e-8)


@pytest.mark.parametrize("sites, r", [(SITES, 0), (SITES, 1), (SITES, 2), ([(0.0, 2)], 2)])
def test_time_one_flow_of_G(sites, r):
    """B^{(r)}_η(X) is the time-1 flow of G^{(r)}_η: DOP853 (rtol = atol = 1e-12) on Ẋ = Π∇(Σ ω_I h_I), the weights
    ω = ∂G/∂h frozen at X (constant on the flow).  Tolerance 1e-9: the integrator's error is ~1e-12 per unit time,
    the quadrature of ω round-off."""
    m = _model(3, sites)
    X = _state(m, seed=4)
    H = m.interpolating_flow_hamiltonian(X, ETA, r)
    sol = solve_ivp(lambda t, x: H.vector_field(x), (0.0, 1.0), X, method="DOP853", rtol=1e-12, atol=1e-12)
    Y = m.two_point_backlund(ETA, branch=r)(X)
    assert np.allclose(sol.y[:, -1], Y, atol=1e-9)
    # another branch's map is not this flow: the spectral choice of v matters
    other = m.two_point_backlund(ETA, branch=(r + 1) % 3)(X)
    assert np.max(np.abs(other - sol.y[:, -1])) > 1e-2


def test_gradient_of_G_is_omega_times_gradients():
    """∇G^{(r)} = Σ ω_I ∇h_I against central differences of G (h = 1e-5; 1e-7)."""
    m = _model()
    X = _state(m, seed=6)
    grad = m.interpolating_weights(X, ETA, 1) @ m.integral_gradients(X)
    h = 1e-5
    fd = np.array([(m.interpolating_hamiltonian(X + h * e, ETA, 1) - m.interpolating_hamiltonian(X - h * e, ETA, 1))
                   / (2 * h) for e in np.eye(m.n_state)])
    assert np.allclose(grad, fd, atol=1e-7)


def test_a_wrong_vector_breaks_the_map():
    """Spectrality fixes v: the dressing with a vector that is no eigenvector of ℓ(η) (an eigenvector of ℓ(η)ᵀ, the
    right one rotated slightly) leaves poles at η, η̄ that the site-by-site principal parts drop, so the integrals
    change by O(1) (while the right v keeps them at 1e-12)."""
    m = _model()
    X = _state(m, seed=7)
    B = m.two_point_backlund(ETA, branch=0)
    P, mu, L = B.projector(X[None])
    Y = m.matrices(X[None])
    good = m.state_from_matrices(dress(m, Y, P, ETA)).real
    assert np.allclose(m.integrals(good), m.integrals(X), atol=1e-12)
    ev, V = np.linalg.eig(L[0].T)
    v = V[:, np.argmin(np.abs(ev - mu[0]))]
    for w in (v, np.linalg.eig(L[0])[1][:, np.argmin(np.abs(np.linalg.eig(L[0])[0] - mu[0]))] + 0.05):
        Pw = np.outer(w, np.conj(w)) / np.vdot(w, w)
        bad = m.state_from_matrices(dress(m, Y, Pw[None], ETA)).real
        assert np.max(np.abs(m.integrals(bad) - m.integrals(X))) > 1e-3


def test_refusals():
    m = _model()
    with pytest.raises(jg.InvalidParameterError, match="is a site"):
        m.two_point_backlund(-1.0 + 0.3j)
    with pytest.raises(jg.InvalidParameterError, match="Im\\(eta\\) = 0"):
        m.two_point_backlund(0.3)
    for bad in (3, -1, "opposite", 1.5, True):
        with pytest.raises(jg.InvalidParameterError, match="branch must be an integer 0..2"):
            m.two_point_backlund(ETA, branch=bad)
    # ℓ(Re η) ∝ diag(1, 1, −2) (every y and b along λ_8): μ_0 = μ_1 is degenerate there, μ_2 simple
    b = np.zeros(8)
    b[7] = 1.0
    md = jg.GaudinModel(b, [(0.0, 1)], algebra="su3")
    X = np.zeros(8)
    X[7] = 0.5
    for r in (0, 1):
        with pytest.raises(jg.BranchPointError, match=f"mu_{r} of ell\\(Re eta\\) is degenerate"):
            md.two_point_backlund(0.5 + 0.5j, branch=r).start(X)
    assert np.isfinite(md.two_point_backlund(0.5 + 0.5j, branch=2).start(X))


def test_description_and_batches():
    m = _model()
    B = m.two_point_backlund(ETA, branch=2)
    assert jg.map_from_description(B.describe()) == B
    X = np.stack([_state(m, seed=s) for s in range(3)])
    batch = B.iterate(X, 4)
    single = np.stack([B.iterate(x, 4) for x in X], axis=1)
    assert np.array_equal(batch, single)  # a batch member is its single orbit, bit for bit
    orbit, carry = B.iterate(X[0], 2, return_carry=True)
    rest = B.iterate(orbit[-1], 2, carry=carry)
    assert np.array_equal(np.concatenate([orbit, rest[1:]]), B.iterate(X[0], 4))  # split = unsplit


def test_drift_over_1e4_steps():
    """Integrals kept over 10⁴ steps of an su(3) chain with two order-1 sites: round-off accumulating about linearly
    (measured 3.7e-12 relative to max |h|, as the su(2) chain's map with the same sites: 8.6e-12 absolute, 2.2e-12
    relative; tolerance 5e-11, a planted O(1e-13) error per step would give 1e-9)."""
    m = _model(3, [(0.0, 1), (1.0, 1)])
    X = _state(m, seed=8)
    adv = m.two_point_backlund(0.4 + 0.1j, branch=0).advance(X, None, 10_000, 10_000)
    I0, I1 = m.integrals(X), m.integrals(adv.X)
    assert np.max(np.abs(I1 - I0)) < 5e-11 * np.max(np.abs(I0))
    assert np.max(adv.imag_max) < 1e-12


def test_integrate_and_flow_map():
    """jg.integrate takes the generic right-hand side for n ≥ 3 (the integrals are cubic: the affine-gradient route
    would be wrong) and reproduces the map (DOP853 at 1e-12: 1e-9); ChainFlowMap runs it and its description
    rebuilds the same Hamiltonian."""
    m = _model(3, [(0.0, 1), (1.0, 1)])
    X = _state(m, seed=9)
    H = m.interpolating_flow_hamiltonian(X, ETA, 1)
    assert H.structure_constants is None
    tr = jg.integrate(H, X, 1.0)
    assert np.allclose(tr.X[-1], m.two_point_backlund(ETA, branch=1)(X), atol=1e-9)
    assert np.allclose(tr.integrals[-1], m.integrals(X), atol=1e-10)
    F = jg.gaudin.ChainFlowMap(H, 0.5)
    assert np.allclose(F.iterate(X, 2)[-1], tr.X[-1], atol=1e-9)
    G = jg.map_from_description(F.describe())
    assert type(G.H) is type(H) and np.array_equal(G.H.weights, H.weights)


def test_order_two_in_im_eta():
    """MapProperties.order = 2: B^{(r)}_{a+ih} is the flow of μ_r(a) over the time −2h up to O(h³) per step (G =
    −2∫₀ʰ Re μ_r(a + is) ds = −2h μ_r(a) + O(h³), the O(s) term of μ_r being imaginary).  The weights of μ_r(a) are
    ω(a + iε)/(−2ε) at ε = 1e-7 (relative error O(ε²)); halving h divides the error by 8 (log₂ ratio in [2.7, 3.3])."""
    m = _model()
    X = _state(m, seed=10)
    a = 0.3
    w = m.interpolating_weights(X, a + 1e-7j, 1) / (-2e-7)
    H = m.hamiltonian(w)
    errs = []
    for h in (0.08, 0.04):
        flow = solve_ivp(lambda t, x: H.vector_field(x), (0.0, -2 * h), X, method="DOP853", rtol=1e-13, atol=1e-13)
        errs.append(np.max(np.abs(m.two_point_backlund(a + 1j * h, branch=1)(X) - flow.y[:, -1])))
    assert 2.7 < np.log2(errs[0] / errs[1]) < 3.3


def test_su2_chain_maps_refuse_an_sun_model():
    with pytest.raises(jg.InvalidParameterError, match="two_point_backlund\\(eta, branch=r\\)"):
        jg.ChainTwoPointBacklund(_model(), ETA)
