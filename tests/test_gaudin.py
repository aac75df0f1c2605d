"""Tests of jetgaudin.gaudin.model: sites, state layout, the integrals h_(i,m) (partial fractions of nu^2),
Casimirs and involution, the Poisson tensor, the branch rule of nu, Hamiltonians and flows (issue 12)."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel, parse_sites


@pytest.fixture
def rng(request):
    """Seeded per test and per parameter set (CRC-32 of the test id)."""
    return np.random.default_rng([20261123, zlib.crc32(request.node.nodeid.encode())])


def random_chain(rng, n_sites=None, b=None):
    """2-4 sites of orders 1-3 at positions at least 0.4 apart, field of random size and sign."""
    n = int(rng.integers(2, 5)) if n_sites is None else n_sites
    pos = np.sort(rng.uniform(-2, 2, size=n))
    while n > 1 and np.min(np.diff(pos)) < 0.4:
        pos = np.sort(rng.uniform(-2, 2, size=n))
    orders = rng.integers(1, 4, size=n)
    if b is None:
        b = float(rng.uniform(0.5, 1.5) * rng.choice([-1, 1]))
    return GaudinModel(b, [(float(p), int(N)) for p, N in zip(pos, orders, strict=True)])


def partial_fractions(m, h, lam, absolute=False):
    """b^2 + sum h_(i,m) (lam - lam_i)^-m, the claimed expansion of nu^2 (absolute=True: the sum of the moduli of
    the terms, the scale of its rounding error)."""
    out = m.b**2 + 0j
    k = 0
    for p, N in m.sites:
        for mm in range(1, 2 * N + 1):
            term = h[..., k] * (lam - p) ** (-mm)
            out = out + (np.abs(term) if absolute else term)
            k += 1
    return out


# ---- sites and layout ------------------------------------------------------------------------


def test_parse_sites_and_errors():
    assert parse_sites("-1:2,0.5:3,2:1") == [(-1.0, 2), (0.5, 3), (2.0, 1)]
    assert parse_sites(" 1e-1 : +2 ") == [(0.1, 2)]
    for bad, what in [("", "pairs"), ("1", "position:order"), ("1:0", "integer >= 1"), ("1:1.5", "integer"),
                      ("x:2", "real number"), ("1:2,1:3", "distinct"), ("1:2:3", "position:order"),
                      ("nan:1", "finite")]:
        with pytest.raises(jg.InvalidParameterError, match=what):
            parse_sites(bad)


def test_model_validation():
    with pytest.raises(jg.InvalidParameterError, match="distinct"):
        GaudinModel(1.0, [(0.5, 1), (0.5, 2)])
    with pytest.raises(jg.InvalidParameterError, match="real"):
        GaudinModel(1.0, [(0.5 + 1j, 1)])
    with pytest.raises(jg.InvalidParameterError, match="integer >= 1"):
        GaudinModel(1.0, [(0.5, 0)])
    with pytest.raises(jg.InvalidParameterError, match="integer >= 1"):
        GaudinModel(1.0, [(0.5, 1.0)])
    with pytest.raises(jg.InvalidParameterError, match="at least one"):
        GaudinModel(1.0, [])
    with pytest.raises(jg.InvalidParameterError, match="field strength b"):
        GaudinModel(np.inf, [(0.0, 1)])
    with pytest.raises(jg.InvalidParameterError, match="field strength b"):
        GaudinModel(1j, [(0.0, 1)])
    m = GaudinModel(0.8, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    assert m.M == 6 and m.n_state == 18 and m.offsets == (0, 2, 5)
    assert m.labels()[:4] == ["s1_y0^1", "s1_y0^2", "s1_y0^3", "s1_y1^1"] and len(m.labels()) == 18
    with pytest.raises(jg.InvalidStateError, match="3M = 18"):
        m.integrals(np.ones(15))
    with pytest.raises(jg.InvalidStateError, match="3M = 18"):
        m.two_point_backlund(0.1 + 0.2j)(np.ones(9))
    assert jg.gaudin_magnet(1.0, [0, 1]).sites == ((0.0, 1), (1.0, 1))
    assert jg.lagrange_chain(1.0, [0, 1]).orders == (2, 2)
    assert jg.twisted_chain(1.0, [0, 1, 3]).M == 9


# ---- integrals ---------------------------------------------------------------------------------


@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_one_site_at_zero_is_todays_model(rng, N):
    """One site at 0: the same integrals (H_1..H_N, C_1..C_N), Poisson tensor, Lax matrix and nu as the one-site
    API (round-off: 1e-14 relative to |X|^2 + |b||X|)."""
    b = float(rng.choice([-1.3, 0.7]))
    m = GaudinModel(b, [(0.0, N)])
    X = rng.normal(size=(3, 3 * N))
    sc = 1 + np.abs(X).max() ** 2
    assert np.abs(m.integrals(X) - jg.integrals(X, b)).max() <= 1e-14 * sc
    assert np.array_equal(m.poisson_tensor(X), jg.poisson_tensor(X))
    lam = 0.6 + 0.3j
    assert np.abs(m.lax_matrix(X, lam) - jg.lax_matrix(lam, X, b)).max() <= 1e-14 * sc
    assert np.abs(m.nu(X, lam) - jg.nu(lam, X, b)).max() <= 1e-13 * sc
    assert np.array_equal(m.casimir_mask(), np.arange(2 * N) >= N)


@pytest.mark.parametrize("seed", range(6))
def test_integrals_are_the_partial_fractions_of_nu2(rng, seed):
    """nu^2(lam) = u^2 + vw computed from the 2x2 Lax matrix (det L = nu^2/4) equals b^2 + sum h (lam - lam_i)^-m at
    random complex lam: an independent route (the h come from quadratic forms built once).  Tolerance 1e-12
    relative to sum |h||lam - lam_i|^-m + b^2 (round-off of the two evaluations)."""
    m = random_chain(rng)
    X = rng.normal(size=(2, m.n_state))
    h = m.integrals(X)
    for lam in rng.normal(size=4) + 1j * rng.uniform(0.1, 1, size=4):
        L = m.lax_matrix(X, lam)
        det = L[..., 0, 0] * L[..., 1, 1] - L[..., 0, 1] * L[..., 1, 0]
        scale = partial_fractions(m, h, lam, absolute=True).real + 1
        assert np.abs(4 * det - partial_fractions(m, h, lam)).max() <= 1e-12 * scale.max()
        assert np.abs(m.nu_squared(X, lam) - 4 * det).max() <= 1e-12 * scale.max()


@pytest.mark.parametrize("seed", range(6))
def test_casimirs_and_involution(rng, seed):
    """The h_(i,m), m > N_i, are Casimirs ({h, X_J} = 0: Pi grad h = 0); all 2M integrals Poisson-commute;
    the gradients are exact (central differences of a quadratic are exact up to round-off, step 0.5).
    Tolerance 1e-12 relative to |grad|^2 |Pi| (a few sums of O(10) products)."""
    m = random_chain(rng)
    X = rng.normal(size=m.n_state)
    G = m.integral_gradients(X)
    E = np.eye(m.n_state)
    fd = np.stack([(m.integrals(X + 0.5 * E[j]) - m.integrals(X - 0.5 * E[j])) for j in range(m.n_state)], -1)
    assert np.abs(G - fd).max() <= 1e-12 * (1 + np.abs(G).max() * np.abs(X).max())
    P = m.poisson_tensor(X)
    scale = np.abs(G).max() ** 2 * np.abs(P).max()
    assert np.abs(G @ P @ G.T).max() <= 1e-12 * scale
    cas = m.casimir_mask()
    assert cas.sum() == m.M
    assert np.abs(P @ G[cas].T).max() <= 1e-12 * scale
    # the M Hamiltonians are independent (their vector fields span M dimensions) for b != 0: integrable
    V = (P @ G[~cas].T).T
    assert np.linalg.matrix_rank(V, tol=1e-8 * np.abs(V).max()) == m.M


def test_zero_field_relation(rng):
    """b = 0: sum_i h_(i,1) = 2<b, S> = 0 identically, so the Hamiltonians' fields span only M - 1 dimensions (the
    total spin S is conserved and generates the missing rotations)."""
    m = GaudinModel(0.0, [(-1.0, 1), (0.2, 2), (1.5, 1)])
    X = rng.normal(size=m.n_state)
    h = m.integrals(X)
    first = [k for k, lab in enumerate(m.integral_labels()) if lab.endswith(",1")]
    assert abs(h[first].sum()) <= 1e-13 * np.abs(h).max()
    G, P = m.integral_gradients(X), m.poisson_tensor(X)
    V = (P @ G[~m.casimir_mask()].T).T
    assert np.linalg.matrix_rank(V, tol=1e-8 * np.abs(V).max()) == m.M - 1


def test_poisson_tensor_blocks(rng):
    """Sites commute; inside a site the bracket of g^(N_i) (LP)."""
    m = GaudinModel(1.0, [(-1.0, 2), (0.5, 3), (2.0, 1)])
    X = rng.normal(size=(2, 18))
    P = m.poisson_tensor(X)
    for i, (_, N) in enumerate(m.sites):
        s = slice(3 * m.offsets[i], 3 * (m.offsets[i] + N))
        assert np.array_equal(P[..., s, s], jg.poisson_tensor(X[..., s]))
        mask = np.ones(18, bool)
        mask[s] = False
        assert np.all(P[..., s, :][..., :, mask] == 0)


# ---- nu, flows ---------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_nu_branch_rule(rng, seed):
    """nu^2 = nu(eta)^2; positive at real points; nu(conj eta) = conj nu(eta); continuous along the vertical segment
    (no jumps between 200 points: consecutive values differ by < 0.2 |nu|)."""
    m = random_chain(rng)
    X = rng.normal(size=m.n_state)
    a = float(np.mean(m.positions[:2]))
    v = m.nu(X, a)
    assert v.real > 0 and v.imag == 0
    lam = a + 1j * np.linspace(1e-3, 1.0, 200)
    vals = m.nu(np.broadcast_to(X, (200, m.n_state)), lam)
    assert np.allclose(vals**2, m.nu_squared(X, lam), rtol=1e-12, atol=1e-12)
    assert np.abs(np.diff(vals)).max() < 0.2 * np.abs(vals).max()
    assert np.allclose(m.nu(X, np.conj(lam[50])), np.conj(vals[50]), rtol=1e-13)
    with pytest.raises(jg.BranchPointError, match="site"):
        m.nu(X, m.positions[0] + 0.3j)


@pytest.mark.parametrize("seed", range(3))
def test_flows_of_any_combination(rng, seed):
    """jg.integrate on a ChainHamiltonian: the 2M integrals are conserved (drift <= 1e-10 at rtol = atol = 1e-12 over
    t = 2), the recorded integrals are the chain's, and a flow of one h_(i,m) commutes with the flow of another
    (exp(t X_h1) exp(t X_h2) = exp(t X_h2) exp(t X_h1): the involution, checked on the flows to 1e-9)."""
    m = random_chain(rng)
    X = rng.normal(size=m.n_state) * 0.7
    w = rng.normal(size=2 * m.M)
    tr = jg.integrate(m.hamiltonian(w), X, 2.0, t_eval=np.linspace(0, 2, 5))
    assert tr.integrals.shape == (5, 2 * m.M)
    assert np.allclose(tr.integrals[0], m.integrals(X), rtol=0, atol=1e-14 * (1 + np.abs(tr.integrals[0]).max()))
    assert tr.drift.max() <= 1e-10
    assert not np.allclose(tr.X[-1], X)
    e1, e2 = np.eye(2 * m.M)[0], np.eye(2 * m.M)[2 * m.orders[0]]  # h_(1,1) and h_(2,1)

    def flow(e, Y):
        return jg.integrate(m.hamiltonian(e), Y, 0.7, rtol=1e-13, atol=1e-13).X[-1]

    assert np.abs(flow(e1, flow(e2, X)) - flow(e2, flow(e1, X))).max() <= 1e-9 * (1 + np.abs(X).max())
    with pytest.raises(jg.InvalidParameterError, match="2M"):
        m.hamiltonian(np.ones(3))


def test_symbolic_chain_checks_can_fail(monkeypatch):
    """The verify checks Chain-r and Chain-integrals hold (also run by tests/test_verify.py with the registry), and
    Chain-r is not vacuous: with the bracket's sign flipped it fails."""
    import sympy as sp

    import jetgaudin.verify.chains as vc
    from jetgaudin.verify import run_checks

    assert [r.status for r in run_checks(only=["Chain-r", "Chain-integrals"])] == ["holds", "holds"]
    orig = vc.eps
    monkeypatch.setattr(vc, "eps", lambda a, b, c: -orig(a, b, c))
    assert not vc._r_matrix_holds([(-1, 1), (sp.Rational(1, 2), 2)])


def test_docs_chains_examples_run():
    """docs/chains.md is executable: its python blocks run (and assert what they claim)."""
    import pathlib
    import re

    text = (pathlib.Path(__file__).resolve().parents[1] / "docs" / "chains.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    for i, block in enumerate(blocks):
        exec(compile(block, f"docs/chains.md[python block {i}]", "exec"), {})


def test_flow_routes_agree(rng):
    """The fast DOP853 right-hand side (affine gradient times the chain's structure constants) equals the generic
    Pi(X) grad H (round-off, 1e-13 relative), and heyoka's Taylor integrator agrees with DOP853 on a chain flow
    (rtol 1e-15 vs 1e-13 over t = 2: 1e-10 relative)."""
    pytest.importorskip("heyoka")
    from jetgaudin.flows import _fast_rhs

    m = GaudinModel(-0.8, [(-1.0, 2), (0.5, 1)])
    X = rng.normal(size=m.n_state) * 0.7
    H = m.hamiltonian(rng.normal(size=2 * m.M))
    assert np.abs(_fast_rhs(H, X)(0.0, X) - H.vector_field(X)).max() <= 1e-13 * (1 + np.abs(X).max()) ** 2
    a = jg.integrate(H, X, 2.0, rtol=1e-13, atol=1e-13)
    h = jg.integrate(H, X, 2.0, method="heyoka", rtol=1e-15)
    assert np.abs(a.X[-1] - h.X[-1]).max() <= 1e-10 * (1 + np.abs(X).max())
    assert h.drift.max() <= 1e-12


def test_named_systems_match_their_classical_forms(rng):
    """Gaudin magnet: h_(i,1) = 2 b S_i^3 + 2 sum_(j != i) <S_i, S_j> / (lam_i - lam_j) (the rational Gaudin
    Hamiltonians with a field; h_(i,2) = |S_i|^2 the Casimirs).  Lagrange top (one site, N = 2): the flow of
    h_2/2 is KPR's Euler-Poisson system J' = P x x, x' = J x x with J = y_0, x = y_1, P = b e_3.  Round-off: 1e-13."""
    pos = np.array([-1.2, 0.3, 0.9, 2.0])
    b = -0.7
    m = jg.gaudin_magnet(b, pos)
    S = rng.normal(size=(4, 3))
    h = m.integrals(S.reshape(-1)).reshape(4, 2)
    for i in range(4):
        ref = 2 * b * S[i, 2] + 2 * sum(S[i] @ S[j] / (pos[i] - pos[j]) for j in range(4) if j != i)
        assert abs(h[i, 0] - ref) <= 1e-13 * (1 + abs(ref))
        assert abs(h[i, 1] - S[i] @ S[i]) <= 1e-13 * (1 + S[i] @ S[i])
    top = jg.lagrange_chain(b, [0.0])
    J, x = rng.normal(size=3), rng.normal(size=3)
    V = top.hamiltonian([0.0, 0.5, 0.0, 0.0]).vector_field(np.concatenate([J, x]))
    P = np.array([0.0, 0.0, b])
    assert np.allclose(V, np.concatenate([np.cross(P, x), np.cross(J, x)]), rtol=0, atol=1e-13)
