"""The real two-point Bäcklund map of the trigonometric family (issue 23): every declared property (the generic
checks of test_gaudin_maps on trigonometric models), the dressing relation, the gauge rule (found from the time-1
flow of G_xi, and wrong rules that fail), commuting maps, the rational limit's order, pole coalescence, and the
second order in Im xi."""

from __future__ import annotations

import dataclasses
import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.families import trigonometric as trig
from jetgaudin.gaudin import GaudinModel
from test_gaudin_maps import CHECKS
from test_trigonometric import coalesced, random_trig


@pytest.fixture
def rng(request):
    """Seeded per test and per parameter set (CRC-32 of the test id)."""
    return np.random.default_rng([20261125, zlib.crc32(request.node.nodeid.encode())])


def random_xi(rng, m):
    """Re xi at least 0.15 from every site modulo pi/gamma, |Im xi| in [0.2, 0.6] of random sign."""
    T = m.family.period
    while True:
        a = float(rng.uniform(-T / 2, T / 2))
        d = (m.positions - a) / T
        if np.min(np.abs(d - np.round(d))) * T > 0.15:
            return complex(a, rng.choice([-1, 1]) * rng.uniform(0.2, 0.6))


def integral_scale(m, X):
    """Natural size of each integral (its rounding error is eps times this): sum of |terms| of the forms."""
    q, lin = m._forms
    n = np.abs(X).reshape(X.shape[:-1] + (m.M, 3))
    h = np.einsum("aIcd,...ca,...da->...I", np.abs(q), n, n) + 2 * abs(m.b) * np.einsum("Ic,...c->...I", lin,
                                                                                          n[..., 2])
    return np.concatenate([h, np.abs(X).sum(-1, keepdims=True)], -1) + 1e-300


def check_preserves_integrals(B, X, rng, declared):
    if declared:  # <= 1e-12 relative to each integral's natural scale (one step of round-off)
        Y = B(X)
        rel = np.abs(B.integrals(Y) - B.integrals(X)) / np.maximum(integral_scale(B.model, X),
                                                                    integral_scale(B.model, Y))
        assert rel.max() <= 1e-12, rel.max()


def nu_hamiltonian(m, X, a):
    """nu(a) as a Hamiltonian: d nu(a) = d nu^2(a) / (2 nu(a)), weights psi_m(a - lam_j)/(2 nu(a)) on h_(j,m) and
    -2 gamma^2 J / (2 nu(a)) on J (constant along its flow)."""
    nu_a = float(m.nu(X, a).real)
    w = [m.family.nu2_basis(k, a - p).real for p, N in m.sites for k in range(1, 2 * N + 1)]
    w.append(-2 * m.gamma**2 * m.integrals(X)[-1])
    return m.hamiltonian(np.array(w) / (2 * nu_a))


def check_order(B, X, rng, declared):
    """Im xi = h -> 0 against the flow of nu(a) over t = 0.4 (time -2h per step, +2h on the opposite branch):
    measured log2 error ratios within 0.15 of the declared order."""
    if declared is None:
        return
    m, sheet = B.model, B.sheet
    X = 0.7 * X
    a = B.eta.real
    H = nu_hamiltonian(m, X, a)
    errs = []
    for h in (0.02, 0.01, 0.005):
        n = int(round(0.4 / (2 * h)))
        exact = jg.integrate(H, X, -2 * sheet * h * n, rtol=1e-13, atol=1e-14).X[-1]
        Bh = m.two_point_backlund(a + 1j * h, B.branch)
        errs.append(np.abs(Bh.iterate(X, n)[-1] - exact).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - declared) < 0.15), orders


TRIG_CHECKS = {**CHECKS, "preserves_integrals": check_preserves_integrals, "order": check_order}


def test_every_property_has_a_check():
    assert set(TRIG_CHECKS) == {f.name for f in dataclasses.fields(jg.MapProperties)}


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("branch", ["default", "opposite"])
@pytest.mark.parametrize("prop", list(TRIG_CHECKS))
def test_declared_properties_hold(rng, seed, branch, prop):
    """Every declared property of the trigonometric two-point map, with the rational suite's checks and tolerances
    (test_gaudin_maps: Poisson by 6th-order finite-difference Jacobians J Pi J^T = Pi, real output, inverse and
    conj xi inverse, time-1 flow of G_xi at 1e-10) and the trigonometric integrals (J included)."""
    m = random_trig(rng)
    B = m.two_point_backlund(random_xi(rng, m), branch)
    X = rng.normal(size=m.n_state)
    TRIG_CHECKS[prop](B, X, rng, getattr(B.properties, prop))


@pytest.mark.parametrize("seed", range(3))
def test_dressing_relation(rng, seed):
    """D(lam) l(X) = l(X') D(lam) at random complex lam, D the family's dressing at X: checks the site-wise principal
    parts against the defining relation.  1e-10 relative to |D| |l| (round-off of a few products)."""
    m = random_trig(rng)
    B = m.two_point_backlund(random_xi(rng, m))
    X = rng.normal(size=(2, m.n_state))
    assert_dressing_relation(B, X, B(X), rng.normal(size=3) + 1j * rng.normal(size=3))


def assert_dressing_relation(B, X, Y, lams):
    """``D(λ) ℓ(X) = ℓ(Y) D(λ)`` at each ``λ`` for the map's ``D`` at ``X``, 1e-10 relative to ``|D| |ℓ|``."""
    m = B.model
    for lam in lams:
        D = B.dressing_matrix(X, lam)
        L, Lt = m.lax_matrix(X, lam), m.lax_matrix(Y, lam)
        assert np.abs(D @ L - Lt @ D).max() <= 1e-10 * np.abs(D).max() * max(np.abs(L).max(), np.abs(Lt).max())


def _rotation_angle(Y, Z):
    """The angle phi with Z = R_3(phi) Y on every 3-vector (v = y^1 - i y^2 turns by e^{-i phi}), and the largest
    misfit of that model."""
    yv, zv = Y[..., 0::3] - 1j * Y[..., 1::3], Z[..., 0::3] - 1j * Z[..., 1::3]
    phi = -np.angle(np.sum(np.conj(yv) * zv))
    return phi, np.abs(zv - np.exp(-1j * phi) * yv).max() + np.abs(Z[..., 2::3] - Y[..., 2::3]).max()


@pytest.mark.parametrize("seed", range(3))
def test_gauge_rule_from_the_flow(rng, seed, monkeypatch):
    """The gauge freedom is diag(rho, 1), |rho| = 1 for real output: the map composed with a rotation R_3(phi)
    about e_3.  The time-1 flow of G_xi (DOP853 at 1e-13) fixes phi: with the rule alpha alpha_0 = delta delta_0 the
    flow is the map itself, phi* = 0 to 1e-10 (measured ~1e-14), misfit 1e-10.  Two wrong rules fail: alpha = delta
    is not real (|rho| != 1: imaginary residue > 1e-3), and the other root rho = -1 of alpha alpha_0 = delta delta_0
    (the raw cross products of spectrality) is real, Poisson, integral-preserving, but the flow rotated by phi* = pi
    (to 1e-10): not the flow of G_xi (and not the identity at Im xi -> 0)."""
    m = random_trig(rng, orders=(1, 2))
    xi = random_xi(rng, m)
    X = rng.normal(size=m.n_state)
    Z = jg.integrate(m.interpolating_flow_hamiltonian(X, xi), X, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    Y = m.two_point_backlund(xi)(X)
    phi, misfit = _rotation_angle(Y, Z)
    assert abs(phi) <= 1e-10 and misfit <= 1e-10 * (1 + np.abs(X).max())
    rule = trig.gauge_rule

    def wrong(name):
        monkeypatch.setattr(trig.TrigonometricFamily, "real_dressing",
                            lambda self, xi, k1, k2: rule(self.gamma, xi, k1, k2, rule=name))
        return m.two_point_backlund(xi).step(X)

    _, _, imag = wrong("alpha")
    assert imag.max() > 1e-3
    Yp, _, imag = wrong("sign")
    assert imag.max() <= 1e-13 and np.abs(Yp - Z).max() > 1e-3
    phi, misfit = _rotation_angle(Yp, Z)
    assert abs(abs(phi) - np.pi) <= 1e-10 and misfit <= 1e-10 * (1 + np.abs(X).max())


@pytest.mark.parametrize("seed", range(2))
def test_maps_with_different_xi_commute(rng, seed):
    """B_xi1 B_xi2 = B_xi2 B_xi1 (both time-1 flows of commuting Hamiltonians G_xi1, G_xi2): 1e-11 relative (four
    steps of round-off)."""
    m = random_trig(rng)
    X = rng.normal(size=m.n_state)
    B1, B2 = m.two_point_backlund(random_xi(rng, m)), m.two_point_backlund(random_xi(rng, m))
    d = np.abs(B1(B2(X)) - B2(B1(X))).max()
    assert d <= 1e-11 * (1 + np.abs(X).max())
    assert np.abs(B1(B2(X)) - B2(X)).max() > 1e-3  # not vacuous: B1 moves the state


def test_rational_limit_of_the_map(rng):
    """gamma -> 0 with the same sites, b, xi and state: the trigonometric map tends to the rational chain map at
    order 2 (the model differs by O(gamma^2), the dressing tends to (1 + O(gamma)) (lam + M_0)): measured log2
    ratios 2.00 (accepted within 0.1)."""
    sites = [(-0.4, 1), (0.3, 2), (1.1, 1)]
    X = rng.normal(size=12)
    xi = 0.2 + 0.25j
    R = GaudinModel(0.8, sites).two_point_backlund(xi)(X)
    errs = [np.abs(GaudinModel(0.8, sites, family="trigonometric", gamma=g).two_point_backlund(xi)(X) - R).max()
            for g in (0.1, 0.05, 0.025)]
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2) < 0.1), orders


@pytest.mark.parametrize("N", [2, 3])
def test_pole_coalescence(rng, N):
    """The map of the order-N jet site at lam0 is the limit of the map of N order-1 sites at lam0 + eps t_i with
    spins from the moment equations (as test_gaudin_maps.test_pole_coalescence, trigonometric): moments of the image
    converge at rate eps, ratios per halving in [1.9, 2.1]."""
    g, lam0, b, xi = 0.8, 0.3, 0.9, 1.0 + 0.4j
    y = rng.normal(size=(N, 3))
    ref = GaudinModel(b, [(lam0, N)], family="trigonometric", gamma=g).two_point_backlund(xi)(y.reshape(-1))
    errs = []
    for eps in (0.02, 0.01, 0.005):
        V, S, chain = coalesced(y, lam0, eps, b, g)
        Sn = chain.two_point_backlund(xi)(S.reshape(-1)).reshape(N, 3)
        errs.append(np.abs(V @ Sn - ref.reshape(N, 3)).max())
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 1.9) & (ratios < 2.1)), ratios


def test_batch_member_equals_single_run_bit_for_bit(rng):
    m = random_trig(rng)
    B = m.two_point_backlund(random_xi(rng, m))
    X = rng.normal(size=(3, m.n_state))
    orb = B.iterate(X, 5, kernel="numpy")
    for i in range(3):
        assert np.array_equal(orb[:, i], B.iterate(X[i], 5, backend="numpy"))


def test_description_rebuilds_the_map():
    from jetgaudin.maps import map_from_description

    m = GaudinModel(0.5, [(0.0, 1), (1.0, 2)], family="trigonometric", gamma=0.8)
    B = m.two_point_backlund(0.4 + 0.2j, "opposite")
    d = B.describe()
    assert d["family"] == "trigonometric" and d["gamma"] == 0.8
    assert map_from_description(d) == B


def test_zero_field(rng):
    """b = 0 (J != 0: nu^2 -> -gamma^2 J^2 at +-i infinity): the map is real, keeps the integrals, is the time-1 flow
    of G_xi (tolerances as the declared properties: 1e-12 relative, 1e-10) and inverted by the other branch."""
    m = GaudinModel(0.0, [(-0.4, 1), (0.3, 2), (1.1, 1)], family="trigonometric", gamma=1.3)
    X = rng.normal(size=m.n_state)
    xi = 0.6 - 0.4j
    B = m.two_point_backlund(xi)
    Y, _, imag = B.step(X)
    assert imag.max() <= 1e-13
    assert np.abs(m.integrals(Y) - m.integrals(X)).max() <= 1e-12 * (1 + np.abs(m.integrals(X)).max())
    Z = jg.integrate(m.interpolating_flow_hamiltonian(X, xi), X, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    assert np.abs(Y - Z).max() <= 1e-10 * (1 + np.abs(X).max())
    assert np.abs(B.inverse()(Y) - X).max() <= 1e-9 * (1 + np.abs(X).max())
