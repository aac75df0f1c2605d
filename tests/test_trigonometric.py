"""Tests of the trigonometric (XXZ) family on the model core (issue 23): the Lax matrix against its closed form,
the rational limit of the model, jet sites as coalesced order-1 sites, the r-matrix relation, the exact expansion
of nu^2 (vs the direct evaluation and vs contour integrals), sum H_j = bJ, Casimirs and involution, the branch
rule of nu, the weights of G_xi, and bad input."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel
from jetgaudin.lax import SIGMA


@pytest.fixture
def rng(request):
    """Seeded per test and per parameter set (CRC-32 of the test id)."""
    return np.random.default_rng([20261125, zlib.crc32(request.node.nodeid.encode())])


def random_trig(rng, gamma=None, orders=(1, 2, 3), b=None):
    """2-3 sites of the given orders at positions at least 0.3 apart modulo pi/gamma, gamma in [0.5, 1.5]."""
    g = float(rng.uniform(0.5, 1.5)) if gamma is None else gamma
    n = int(rng.integers(2, 4))
    T = np.pi / g
    while True:
        pos = np.sort(rng.uniform(-0.5 * T, 0.5 * T, size=n))
        d = np.diff(np.concatenate([pos, [pos[0] + T]]))
        if d.min() > 0.3:
            break
    b = float(rng.uniform(0.5, 1.5) * rng.choice([-1, 1])) if b is None else b
    return GaudinModel(b, [(float(p), int(rng.choice(orders))) for p in pos], family="trigonometric", gamma=g)


def coalesced(y, lam0, eps, b, g):
    """N = len(y) order-1 sites at lam0 + eps t_i (t = -1, 0.35, 1.2) with the spins S solving the moment equations
    sum_i (eps t_i)^k S_i = y_k: ``(V, S, chain)``, V[k, i] = (eps t_i)^k."""
    N = len(y)
    t = np.array([-1.0, 0.35, 1.2])[:N]
    V = (eps * t)[None, :] ** np.arange(N)[:, None]
    chain = GaudinModel(b, [(lam0 + e, 1) for e in eps * t], family="trigonometric", gamma=g)
    return V, np.linalg.solve(V, y), chain


def xi_gradients(m, lam):
    """d xi^a(lam)/dX_I, shape (3, 3M): xi is affine in X, so differences of basis states are exact."""
    E = np.eye(m.n_state)
    return np.stack([m.xi(E[i], lam) - m.xi(0 * E[i], lam) for i in range(m.n_state)], -1)


def test_lax_matrix_is_the_closed_form(rng):
    """Order-1 sites, gamma = 1: u = b + sum cot(lam - lam_j) s_j^3, v = sum s_j^- / sin, w = sum s_j^+ / sin
    (the issue's formula, typed independently of the family's series); general gamma: l_g(lam) =
    g l_1(g lam; g lam_j, b/g).  Tolerance 1e-13 relative: a few products of O(1-10) numbers."""
    pos = np.array([-0.7, 0.2, 1.1])
    s = rng.normal(size=(3, 3))
    m = GaudinModel(0.6, [(p, 1) for p in pos], family="trigonometric")
    for lam in rng.normal(size=3) + 1j * rng.normal(size=3):
        d = lam - pos
        u = 0.6 + np.sum(s[:, 2] / np.tan(d))
        v = np.sum((s[:, 0] - 1j * s[:, 1]) / np.sin(d))
        w = np.sum((s[:, 0] + 1j * s[:, 1]) / np.sin(d))
        ell = -2j * m.lax_matrix(s.reshape(-1), lam)
        ref = np.array([[u, v], [w, -u]])
        assert np.abs(ell - ref).max() <= 1e-13 * np.abs(ref).max()
        g = 0.37
        mg = GaudinModel(0.6, [(p, 1) for p in pos], family="trigonometric", gamma=g)
        m1 = GaudinModel(0.6 / g, [(g * p, 1) for p in pos], family="trigonometric")
        ref = g * m1.lax_matrix(s.reshape(-1), g * lam)
        assert np.abs(mg.lax_matrix(s.reshape(-1), lam) - ref).max() <= 1e-13 * np.abs(ref).max()


def test_rational_limit_of_the_model(rng):
    """gamma -> 0: l_gamma -> the rational chain's l with the same sites, b and state; gamma cot(gamma x) = 1/x -
    gamma^2 x/3 + ..., gamma/sin(gamma x) = 1/x + gamma^2 x/6: the difference is O(gamma^2), measured ratio 4.00 per
    halving (accepted in [3.9, 4.1])."""
    sites = [(-0.8, 2), (0.4, 1), (1.3, 3)]
    X = rng.normal(size=18)
    lam = 0.3 + 0.5j
    R = GaudinModel(0.7, sites).lax_matrix(X, lam)
    errs = [np.abs(GaudinModel(0.7, sites, family="trigonometric", gamma=g).lax_matrix(X, lam) - R).max()
            for g in (0.04, 0.02, 0.01)]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 3.9) & (ratios < 4.1)), ratios


@pytest.mark.parametrize("N", [2, 3])
def test_jet_site_is_the_coalescence_of_order_one_sites(rng, N):
    """N order-1 sites at lam0 + eps t_i with spins S_i: sum_i S_i w_a(x - eps t_i) = sum_k (sum_i S_i (eps t_i)^k)
    phi_(a,k)(x) + O(eps^N sum|S_i|) (Taylor), so with S_i solving the moment equations sum_i (eps t_i)^k S_i = y_k
    the order-1 chain's Lax matrix tends to the jet site's at rate eps (S_i ~ eps^-(N-1)): ratios per halving of
    eps in [1.9, 2.1]."""
    g, lam0, b = 0.8, 0.3, 0.9
    y = rng.normal(size=(N, 3))
    jet = GaudinModel(b, [(lam0, N)], family="trigonometric", gamma=g)
    lam = 1.0 + 0.4j
    ref = jet.lax_matrix(y.reshape(-1), lam)
    errs = []
    for eps in (0.02, 0.01, 0.005):
        _, S, chain = coalesced(y, lam0, eps, b, g)
        errs.append(np.abs(chain.lax_matrix(S.reshape(-1), lam) - ref).max())
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 1.9) & (ratios < 2.1)), ratios


@pytest.mark.parametrize("seed", range(3))
def test_r_matrix_relation(rng, seed):
    """{L(lam) (x) L(mu)} = [r(lam - mu), L(lam) (x) 1 + 1 (x) L(mu)] with the trigonometric r-matrix
    r(x) = sum_a w_a(x) sigma^a (x) sigma^a, w_1 = w_2 = gamma/sin(gamma x), w_3 = gamma cot(gamma x) (the rational
    r = P/x of jetgaudin.r_matrix with 1/x replaced by w_a; L = (i/2) l and the paper's sigma, jetgaudin.lax.SIGMA),
    jet sites included.  The bracket from the Poisson tensor and the exact gradients of xi.  Tolerance 1e-12
    relative to the largest entry (O(1)): round-off of sums of O(10) terms."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    lam, mu = complex(rng.normal(), rng.uniform(0.1, 1)), complex(rng.normal(), -rng.uniform(0.1, 1))
    br = np.einsum("ai,ij,bj->ab", xi_gradients(m, lam), m.poisson_tensor(X), xi_gradients(m, mu))
    lhs = np.einsum("ab,aij,bkl->ikjl", br, SIGMA, SIGMA).reshape(4, 4)
    S = np.kron(m.lax_matrix(X, lam), np.eye(2)) + np.kron(np.eye(2), m.lax_matrix(X, mu))
    g, x = m.gamma, lam - mu
    w = [g / np.sin(g * x), g / np.sin(g * x), g / np.tan(g * x)]
    r = sum(w[a] * np.kron(SIGMA[a], SIGMA[a]) for a in range(3))
    assert np.abs(lhs).max() > 1e-2  # not vacuous
    assert np.abs(lhs - (r @ S - S @ r)).max() <= 1e-12 * np.abs(lhs).max()
    # the rational r-matrix does not satisfy it (the relation can fail)
    r0 = jg.r_matrix(x)
    assert np.abs(lhs - (r0 @ S - S @ r0)).max() > 1e-3


def _expansion(m, X, lam):
    """b^2 - gamma^2 J^2 + sum_(j,m) h_(j,m) psi_m(lam - lam_j), psi_m = (-1)^(m-1) (gamma cot)^(m-1)/(m-1)!,
    psi_1, psi_2 by their closed forms (cot and 1/sin^2, typed here), psi_3, psi_4 = cot/sin^2 and
    (1 + 2 cos^2)/(3 sin^4) (times gamma^m at gamma x)."""
    g = m.gamma
    h = m.integrals(X)
    out = m.b**2 - g**2 * h[..., -1] ** 2 + 0j
    k = 0
    for p, N in m.sites:
        x = g * (lam - p)
        psi = [g / np.tan(x), g**2 / np.sin(x) ** 2, g**3 * np.cos(x) / np.sin(x) ** 3,
               g**4 * (1 + 2 * np.cos(x) ** 2) / (3 * np.sin(x) ** 4), None, None]
        for mm in range(1, 2 * N + 1):
            out = out + h[..., k] * (psi[mm - 1] if mm <= 4 else m.family.nu2_basis(mm, lam - p))
            k += 1
    return out


@pytest.mark.parametrize("seed", range(3))
def test_nu2_expansion_exact(rng, seed):
    """nu^2 = u^2 + vw (direct, from the Lax matrix) equals the documented expansion at random complex lam; psi_m
    typed in closed form for m <= 4 (orders <= 2 here) so the family's series are checked too.  Tolerance 1e-11
    relative to the largest term (cancellations among O(10-100) terms)."""
    m = random_trig(rng, orders=(1, 2))
    X = rng.normal(size=m.n_state)
    for lam in rng.normal(size=3) + 1j * rng.uniform(0.1, 1, size=3):
        L = -2j * m.lax_matrix(X, lam)
        direct = L[0, 0] ** 2 + L[0, 1] * L[1, 0]
        assert abs(direct - _expansion(m, X, lam)) <= 1e-11 * (1 + abs(direct) + np.abs(m.integrals(X)).max())


@pytest.mark.parametrize("seed", range(2))
def test_integrals_are_contour_integrals(rng, seed):
    """h_(j,m) = (1/2 pi i) oint nu^2(lam) (lam - lam_j)^(m-1) dlam on the circle |lam - lam_j| = 0.1 (inside: only
    the site); the trapezoid rule on 256 points converges geometrically (error ~ (0.1/0.3)^256): round-off 1e-12
    relative to max |nu^2| r^(m-1) on the circle."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    h = m.integrals(X)
    th = 2 * np.pi * np.arange(256) / 256
    k = 0
    for p, N in m.sites:
        z = 0.1 * np.exp(1j * th)
        nu2 = m.nu_squared(X, p + z)
        for mm in range(1, 2 * N + 1):
            val = np.mean(nu2 * z**mm)
            assert abs(val - h[k]) <= 1e-12 * np.abs(nu2).max() * 0.1**mm, (p, mm)
            k += 1


@pytest.mark.parametrize("seed", range(4))
def test_sum_of_hamiltonians_casimirs_involution(rng, seed):
    """sum_j h_(j,1) = 2 b J (i.e. sum H_j = bJ); the h_(j,m), m > N_j, are Casimirs; all integrals, J included,
    Poisson-commute; the gradients are exact (central differences of quadratics).  Tolerances 1e-12 relative to the
    natural scale (|grad|^2 |Pi|, or sum |h|): round-off of O(10) products."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    h = m.integrals(X)
    first = [k for k, lab in enumerate(m.integral_labels()) if lab.endswith(",1")]
    assert abs(h[first].sum() - 2 * m.b * h[-1]) <= 1e-12 * (1 + np.abs(h).sum())
    G = m.integral_gradients(X)
    E = np.eye(m.n_state)
    fd = np.stack([(m.integrals(X + 0.5 * E[j]) - m.integrals(X - 0.5 * E[j])) for j in range(m.n_state)], -1)
    assert np.abs(G - fd).max() <= 1e-12 * (1 + np.abs(G).max() * np.abs(X).max())
    P = m.poisson_tensor(X)
    scale = np.abs(G).max() ** 2 * np.abs(P).max()
    assert np.abs(G @ P @ G.T).max() <= 1e-12 * scale
    cas = m.casimir_mask()
    assert cas.sum() == m.M and not cas[-1]
    assert np.abs(P @ G[cas].T).max() <= 1e-12 * scale
    V = (P @ G[~cas].T).T  # M Hamiltonians and J: M independent fields (J = sum h_(j,1) / 2b)
    assert np.linalg.matrix_rank(V, tol=1e-8 * np.abs(V).max()) == m.M


def test_poisson_tensor_is_the_rational_one(rng):
    """The bracket is per site that of g^(N_j), whatever the family: the same tensor as the rational chain."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    r = GaudinModel(m.b, m.sites)
    assert np.array_equal(m.poisson_tensor(X), r.poisson_tensor(X))


@pytest.mark.parametrize("seed", range(3))
def test_nu_branch_rule(rng, seed):
    """nu by the exact product rule in z = e^(2i gamma lam) equals the root continued numerically along the segment
    from Re eta (20001 points, always the root nearest to the previous one), positive at real points, and
    nu(conj eta) = conj nu(eta); relative 1e-12 (the same square root, round-off)."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    a = float(np.mean(m.positions[:2]))
    assert m.nu(X, a).real > 0
    eta = a + 1j * rng.uniform(0.3, 1.2)
    nu2 = m.nu_squared(X, a + 1j * np.linspace(0, eta.imag, 20001))
    v = np.sqrt(nu2[0])
    for q in nu2[1:]:
        r = np.sqrt(q)
        v = r if abs(r - v) < abs(r + v) else -r
    assert abs(m.nu(X, eta) - v) <= 1e-12 * abs(v)
    assert abs(m.nu(X, np.conj(eta)) - np.conj(v)) <= 1e-12 * abs(v)
    bp = m.branch_points(X)
    assert np.abs(m.nu_squared(X, bp)).max() <= 1e-8 * np.abs(m.integrals(X)).max()


def test_interpolating_weights_are_the_gradient_of_G(rng):
    """dG_eta/dX = sum_I omega_I grad I (the chain rule through the integrals, J included): G by quadrature at X +-
    h e_j (central differences, h = 1e-4: error ~h^2 |G'''| ~ 1e-8), relative 1e-6."""
    m = random_trig(rng, orders=(1, 2))
    X = rng.normal(size=m.n_state)
    eta = float(np.mean(m.positions[:2])) + 0.3j
    w = m.interpolating_weights(X, eta)
    grad = w @ m.integral_gradients(X)
    E = np.eye(m.n_state)
    fd = np.array([(m.interpolating_hamiltonian(X + 1e-4 * E[j], eta) - m.interpolating_hamiltonian(X - 1e-4 * E[j],
                                                                                                    eta)) / 2e-4
                   for j in range(m.n_state)])
    assert np.abs(grad - fd).max() <= 1e-6 * (1 + np.abs(grad).max())
    assert abs(w[-1]) > 1e-6  # G depends on J through the constant b^2 - gamma^2 J^2 (not vacuous)


def test_bad_input():
    sites = [(0.0, 1), (1.0, 2)]
    for g in (0.0, -1.0, np.nan, np.inf, 1j, True, "x"):
        with pytest.raises(jg.InvalidParameterError, match="gamma"):
            GaudinModel(1.0, sites, family="trigonometric", gamma=g)
    with pytest.raises(jg.InvalidParameterError, match="modulo its period"):
        GaudinModel(1.0, [(0.0, 1), (np.pi / 2, 1)], family="trigonometric", gamma=2.0)
    with pytest.raises(jg.InvalidParameterError, match="gamma"):
        GaudinModel(1.0, sites, gamma=0.5)  # the rational family has no anisotropy
    with pytest.raises(jg.InvalidParameterError, match="unknown family"):
        GaudinModel(1.0, sites, family="hyperbolic")
    m = GaudinModel(1.0, sites, family="trigonometric", gamma=2.0)
    with pytest.raises(jg.InvalidParameterError, match="is a site"):
        m.two_point_backlund(np.pi / 2 + 0.3j)  # Re eta = the site 0 modulo pi/gamma
    with pytest.raises(jg.InvalidParameterError, match="is a site"):  # the one-point map too (test_trig_one_point)
        m.one_point_backlund(np.pi / 2 + 0.3j)
    m0 = GaudinModel(0.0, sites, family="trigonometric")
    X = np.array([1.0, 0.0, 0.5, 0.2, 0.1, -0.5, 0.0, 0.0, 0.0])  # J = 0.5 - 0.5 = 0 and b = 0: nu(-i inf) = 0
    with pytest.raises(jg.BranchPointError, match="b != 0 or J != 0"):
        m0.two_point_backlund(0.5 + 0.3j)(X)


def test_description_round_trip():
    m = GaudinModel(0.5, [(0.0, 1), (1.0, 2)], family="trigonometric", gamma=0.8)
    assert m.describe() == {"b": 0.5, "sites": [[0.0, 1], [1.0, 2]], "family": "trigonometric", "gamma": 0.8}
    assert GaudinModel.from_description(m.describe()) == m
    assert GaudinModel(0.5, [(0.0, 1)]).describe() == {"b": 0.5, "sites": [[0.0, 1]]}  # rational: as today


def test_symbolic_trigonometric_checks_can_fail(monkeypatch):
    """The verify section's checks are not vacuous: the rational r-matrix in place of the trigonometric one breaks
    Trig-r's identity, and the other sign of the gauge (rho = -1) breaks Trig-gauge."""
    import jetgaudin.verify.trigonometric as vt
    from jetgaudin.verify import run_checks

    w = vt._w
    monkeypatch.setattr(vt, "_w", lambda x, p, a: w(x, p, 0))  # cot -> 1/sin everywhere: not the XXZ r-matrix
    assert not vt._r_matrix_holds((1, 1))
    monkeypatch.setattr(vt, "_w", w)
    d = vt._dressing
    monkeypatch.setattr(vt, "_dressing", lambda k, xi, lam: vt.mp.matrix([[-1, 0], [0, 1]]) * d(k, xi, lam))
    (r,) = run_checks(only=["Trig-gauge"])
    assert r.status != "holds"


def test_numerical_branch_rule_of_families_without_uniformizer(rng):
    """A family that declares no uniformizer (as an elliptic one may) gets the core's numerical continuation of nu
    along the segment: on trigonometric models (the uniformizer hidden) it gives the exact rule's nu (1e-12: the same
    square root, the sign decided), and the map through it is the same map (1e-12)."""
    from jetgaudin.families import TrigonometricFamily

    class Hidden(TrigonometricFamily):
        def uniformizer(self, lam):
            return None

    m = random_trig(rng)
    h = GaudinModel(m.b, m.sites, family=Hidden(m.gamma))
    X = rng.normal(size=(3, m.n_state))
    xi = float(np.mean(m.positions[:2])) + 0.7j
    assert np.abs(h.nu(X, xi) - m.nu(X, xi)).max() <= 1e-12 * np.abs(m.nu(X, xi)).max()
    assert h.branch_points(X).shape == (3, 0)
    assert np.abs(h.two_point_backlund(xi)(X) - m.two_point_backlund(xi)(X)).max() <= 1e-12 * (1 + np.abs(X).max())


def test_exact_chain_flow_takes_the_trigonometric_family():
    """ChainExactFlow (issue 25) uses the family's ψ_m and J: a trigonometric Hamiltonian's exact step is its flow
    (DOP853 at 1e-13 over dt = 0.05: 1e-12; the full checks are in tests/test_exact_chain.py).  All-ones weights
    (h_{1,1} + h_{2,1} + J on two spins) is a pure rotation: the map's Im η comes out at round-off and is skipped."""
    from jetgaudin.exact_chain import ChainExactFlow

    m = GaudinModel(0.8, [(0.0, 1), (1.0, 1)], family="trigonometric", gamma=0.7)
    X = np.array([0.3, -0.2, 0.5, 0.1, 0.2, -0.1])
    for w in (np.ones(m.n_integrals), np.array([0.6, 0.0, -0.3, 0.0, 0.2])):
        H = m.hamiltonian(w)
        ref = jg.integrate(H, X, 0.05, rtol=1e-13, atol=1e-13).X[-1]
        assert np.max(np.abs(ChainExactFlow(H, 0.05)(X) - ref)) < 1e-12
