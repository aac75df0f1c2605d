"""The one-point Bäcklund maps of the trigonometric family (issue 23; docs/families.md §3.1): every declared property
(the generic checks of test_gaudin_maps / test_trigonometric_maps: integrals, Poisson by finite differences, complex
output, inverse), the dressing relation, the factorisation of the real two-point map B_xi into two one-point maps (up
to the stated constant rotation), the rational limit's order and its first-order term, pole coalescence into a jet
site, b = 0, the refusals (b + i gamma J = 0, the elliptic family, the compiled route) and the description round
trip."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel
from test_trigonometric import coalesced, random_trig
from test_trigonometric_maps import TRIG_CHECKS, assert_dressing_relation, integral_scale, random_xi


@pytest.fixture
def rng(request):
    """Seeded per test and per parameter set (CRC-32 of the test id)."""
    return np.random.default_rng([20261126, zlib.crc32(request.node.nodeid.encode())])


VARIANTS = {
    "forward": lambda m, xi: m.one_point_backlund(xi),
    "opposite": lambda m, xi: m.one_point_backlund(xi, "opposite"),
    "inverse": lambda m, xi: m.one_point_backlund(xi, inverse_map=True),
}


def rotate(Y, rho):
    """``ℓ → diag(ρ, 1) ℓ diag(ρ, 1)^{-1}`` on every 3-vector: ``y^- → ρ y^-``, ``y^+ → y^+/ρ``, ``y^3`` kept."""
    y = Y.reshape(Y.shape[:-1] + (-1, 3))
    ym, yp = (y[..., 0] - 1j * y[..., 1]) * rho, (y[..., 0] + 1j * y[..., 1]) / rho
    return np.stack([(ym + yp) / 2, (yp - ym) / 2j, y[..., 2]], axis=-1).reshape(Y.shape)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("prop", list(TRIG_CHECKS))
def test_declared_properties_hold(rng, seed, variant, prop):
    """Every declared property of the trigonometric one-point map with the two-point suite's checks and tolerances:
    the h_(j,m) and J preserved (1e-12 of each integral's scale), Poisson as a holomorphic map (J Pi(X) J^T =
    Pi(B(X)) with the 6th-order finite-difference Jacobian, 1e-10 relative; Pi is linear, so it is evaluated at the
    complex image), genuinely complex output (|Im| > 1e-6), inverse() undoes it (1e-9); random gamma in [0.5, 1.5],
    2-3 sites of orders 1-3 (jet sites), b of either sign."""
    m = random_trig(rng)
    B = VARIANTS[variant](m, random_xi(rng, m))
    X = rng.normal(size=m.n_state)
    TRIG_CHECKS[prop](B, X, rng, getattr(B.properties, prop))


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("inverse", [False, True])
def test_dressing_relation(rng, seed, inverse):
    """D(lam) l(X) = l(X~) D(lam) at random complex lam for the map's own D (the site-wise principal parts against
    the defining relation; for the inverse map D = adj of the forward form), a batch of two states; det D vanishes at
    xi (modulo pi/gamma) and nowhere else on a sample.  1e-10 relative to |D| |l| (round-off of a few products)."""
    m = random_trig(rng)
    xi = random_xi(rng, m)
    B = m.one_point_backlund(xi, inverse_map=inverse)
    X = rng.normal(size=(2, m.n_state))
    lams = rng.normal(size=3) + 1j * rng.normal(size=3)
    assert_dressing_relation(B, X, B(X), lams)
    for lam in lams:
        D = B.dressing_matrix(X, lam)
        assert np.all(np.abs(np.linalg.det(D)) > 1e-8 * np.abs(D).max() ** 2)
    for shift in (0.0, m.family.period, -2 * m.family.period):
        D = B.dressing_matrix(X, xi + shift)
        assert np.abs(np.linalg.det(D)).max() <= 1e-13 * np.abs(D).max() ** 2


CASES = [  # (gamma, b, sites, xi): order-1 sites, jet sites, negative b, Im xi of both signs
    (1.0, 0.7, [(-0.5, 1), (0.8, 1)], 0.3 + 0.45j),
    (0.6, -1.1, [(-0.5, 2), (0.8, 1)], -0.2 - 0.35j),
    (1.3, 0.4, [(0.1, 3), (1.0, 1), (2.0, 2)], 0.55 + 0.3j),
    (0.8, 1.5, [(-1.2, 1), (0.0, 2), (1.1, 1), (2.3, 1)], 0.6 - 0.5j),
]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_factorisation_of_the_two_point_map(rng, case):
    """B^inv_(conj xi) o B_xi = R_xi o B_xi^(2): the one-point map at xi, then the inverse one-point map at conj xi (nu
    by the branch rule at the intermediate complex state, which gives conj nu(xi)), is the real two-point map followed
    by the constant rotation R_xi: y^- -> rho y^-, y^+ -> y^+/rho, rho = e^{2 gamma Im xi} (docs/families.md §3.1:
    derived from q' = e^{i gamma (xi - conj xi)} q and the symmetric gauge).  1e-12 relative: two complex steps whose
    dressings have entries ~1/(2 gamma) (measured <= 3e-14).  Without R_xi, or with rho^-1, the states differ by
    O(1): the rotation is not a tolerance artefact."""
    g, b, sites, xi = CASES[case]
    m = GaudinModel(b, sites, family="trigonometric", gamma=g)
    X = rng.normal(size=(3, m.n_state))
    A = m.one_point_backlund(xi)
    Bi = m.one_point_backlund(np.conj(xi), inverse_map=True)
    Y1, nu1, _ = A.step(X)
    Z, nu2, _ = Bi.step(Y1)
    assert np.abs(nu2 - np.conj(nu1)).max() <= 1e-12 * np.abs(nu1).max()  # the branch rule continues: conj nu
    W = m.two_point_backlund(xi, backend="numpy")(X)
    rho = np.exp(2 * g * xi.imag)
    scale = 1 + np.abs(W).max()
    assert np.abs(Z - rotate(W, rho)).max() <= 1e-12 * scale
    assert np.abs(Z - W).max() > 1e-2 * scale
    assert np.abs(Z - rotate(W, 1 / rho)).max() > 1e-2 * scale


def test_factorisation_tends_to_the_rationals_as_gamma_goes_to_zero(rng):
    """rho = e^{2 gamma Im xi} -> 1: at gamma = 1e-3 the composition is B_xi to O(gamma) (|rho - 1| = 9e-4 here) and
    the rational chain's own factorisation (tests/test_backlund.py) is exact; the trigonometric composition is within
    1e-2 of the rational two-point map."""
    sites, b, xi = [(-0.5, 2), (0.8, 1)], 0.9, 0.3 + 0.45j
    X = rng.normal(size=9)
    m = GaudinModel(b, sites, family="trigonometric", gamma=1e-3)
    Z = m.one_point_backlund(np.conj(xi), inverse_map=True)(m.one_point_backlund(xi)(X))
    assert np.abs(Z - m.two_point_backlund(xi)(X)).max() <= 1e-2
    assert np.abs(Z - GaudinModel(b, sites).two_point_backlund(xi)(X)).max() <= 1e-2


def _rational_nu_start(b, sites, xi, X, inverse):
    """The rational map and its nu at X: both routes are then stepped from this carry (the trigonometric branch rule
    finds its roots in z = e^{2i gamma lam}, ill-conditioned as gamma -> 0; the carry only picks the root)."""
    R = GaudinModel(b, sites).one_point_backlund(xi, inverse_map=inverse)
    return R, R.start(X)


@pytest.mark.parametrize("inverse", [False, True])
def test_rational_limit_order_one(rng, inverse):
    """gamma -> 0: the trigonometric one-point map tends to the rational one (same sites, b, spins, xi, nu) with
    error O(gamma): measured log2 ratios 1.01-1.04 for gamma = 0.04 ... 0.005 (within 0.1 of 1).  Unlike the
    two-point map (order 2) the normalisation point, Im lam -> -infinity, is not on the rational model's finite
    plane: see test_rational_limit_first_order_term."""
    b, sites, xi = 0.9, [(-0.5, 2), (0.8, 1)], 0.3 + 0.45j
    X = rng.normal(size=9)
    R, nu = _rational_nu_start(b, sites, xi, X, inverse)
    Yr = R.step(X, nu)[0]
    errs = []
    for g in (0.04, 0.02, 0.01, 0.005):
        T = GaudinModel(b, sites, family="trigonometric", gamma=g).one_point_backlund(xi, inverse_map=inverse)
        errs.append(np.abs(T.step(X, nu)[0] - Yr).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 1) < 0.1), orders


@pytest.mark.parametrize("case", range(3))
@pytest.mark.parametrize("inverse", [False, True])
def test_rational_limit_first_order_term(rng, case, inverse):
    """T_gamma = Phi_(gamma F) o T_0 + O(gamma^2), Phi the flow of F = xi J - nu_2 (the inverse map: -F) at the
    rational image, nu(lam) = b + J/lam + nu_2/lam^2 + ... at infinity, nu_2 = (H - J^2/2)/b, H the physical
    Hamiltonian 1/2 sum_i (lam_i h_(i,1) + h_(i,2)): the first-order term is (T_gamma - T_0)/gamma = Pi grad F.  At
    gamma = 1e-4 the remainder is O(gamma) relative: measured 1e-4 to 7.5e-4 of |Pi grad F|; asserted 2e-3."""
    b, sites, xi = [(0.9, [(-0.5, 2), (0.8, 1)], 0.3 + 0.45j), (-1.3, [(-1.0, 1), (0.2, 3), (1.1, 1)], -0.4 - 0.3j),
                    (0.6, [(0.0, 1), (0.7, 1), (1.5, 2)], 1.0 + 0.8j)][case]
    X = rng.normal(size=3 * sum(N for _, N in sites))
    R, nu = _rational_nu_start(b, sites, xi, X, inverse)
    m0 = R.model
    T0 = R.step(X, nu)[0]
    g = 1e-4
    Tg = GaudinModel(b, sites, family="trigonometric", gamma=g).one_point_backlund(xi, inverse_map=inverse).step(X,
                                                                                                               nu)[0]
    gradJ = np.zeros(m0.n_state)
    gradJ[[3 * o + 2 for o in m0.offsets]] = 1.0
    J = gradJ @ T0
    gradF = (xi + J / b) * gradJ - m0.physical_hamiltonian().gradient(T0) / b  # d(xi J - (H - J^2/2)/b)
    field = m0.poisson_tensor(T0) @ gradF * (-1 if inverse else 1)
    d = (Tg - T0) / g
    assert np.abs(d - field).max() <= 2e-3 * np.abs(field).max()


@pytest.mark.parametrize("N", [2, 3])
def test_pole_coalescence_gives_the_jet_site(rng, N):
    """N order-1 sites at lam0 + eps t_i with the moment-matched spins -> one site of order N: the one-point images
    agree to O(eps) (moments of the image, as for the two-point map; measured ratios 2.00-2.03 per halving of eps)."""
    g, b, lam0, xi = 0.9, 0.8, 0.2, 1.0 + 0.4j
    y = rng.normal(size=(N, 3))
    jet = GaudinModel(b, [(lam0, N), (-1.1, 1)], family="trigonometric", gamma=g)
    s_other = rng.normal(size=3)
    Xj = np.concatenate([y.ravel(), s_other])
    A = jet.one_point_backlund(xi)
    nu = A.start(Xj)
    Yj = A.step(Xj, nu)[0].reshape(-1, 3)
    errs = []
    for eps in (0.02, 0.01, 0.005):
        V, S, _ = coalesced(y, lam0, eps, b, g)
        chain = GaudinModel(b, [(lam0 + e, 1) for e in eps * np.array([-1.0, 0.35, 1.2])[:N]] + [(-1.1, 1)],
                            family="trigonometric", gamma=g)
        Yc = chain.one_point_backlund(xi).step(np.concatenate([S.ravel(), s_other]), nu)[0].reshape(-1, 3)
        moments = V @ Yc[:N]  # y_k of the coalesced image: sum_i (eps t_i)^k s~_i
        errs.append(max(np.abs(moments - Yj[:N]).max(), np.abs(Yc[N] - Yj[N]).max()))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 1.7) & (ratios < 2.3)), ratios


def test_zero_field_needs_J_and_the_refusals(rng):
    """b = 0 is allowed when J != 0 (the condition is b + i gamma J != 0, unlike the rational map's b != 0): the map
    keeps b = 0 and J; b = J = 0, or a complex state with J = i b / gamma, is refused with a typed error naming the
    condition; the elliptic family refuses with its reason; the compiled route is a typed error (no kernel)."""
    m = GaudinModel(0.0, [(0.0, 1), (1.0, 2)], family="trigonometric", gamma=0.7)
    X = rng.normal(size=m.n_state)
    A = m.one_point_backlund(0.5 + 0.3j)
    Y = A(X)
    # 1e-12 of each integral's natural scale (one step of round-off; the image grows as J -> 0: p = S/(2i gamma J))
    rel = np.abs(m.integrals(Y) - m.integrals(X)) / np.maximum(integral_scale(m, X), integral_scale(m, Y))
    assert rel.max() <= 1e-12 and np.abs(A.inverse()(Y) - X).max() <= 1e-9 * (1 + np.abs(Y).max())
    X0 = X.copy()
    X0[5] = -X0[2]  # J = y_0^3 of site 1 + y_0^3 of site 2 = 0
    with pytest.raises(jg.InvalidStateError, match="b \\+ i gamma J != 0"):
        A(X0)
    mb = GaudinModel(1.4, [(0.0, 1), (1.0, 2)], family="trigonometric", gamma=0.7)
    Xc = X.astype(complex)
    Xc[5] = 1j * 1.4 / 0.7 - Xc[2]  # b + i gamma J = 0 with b != 0 (a complex state)
    with pytest.raises(jg.InvalidStateError, match="b \\+ i gamma J != 0"):
        mb.one_point_backlund(0.5 + 0.3j)(Xc)
    with pytest.raises(jg.InvalidParameterError, match="elliptic function of order 2"):
        GaudinModel(0.0, [(0.0, 1), (1.0, 1)], family="elliptic", modulus=0.5).one_point_backlund(0.3 + 0.2j)
    with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
        mb.one_point_backlund(0.5 + 0.3j, backend="compiled").iterate(X, 2)


def test_iterate_batch_and_description(rng):
    """iterate on a batch equals the single runs bit for bit (the same 2-D code path); the description rebuilds an
    equal map (family and gamma included) that gives the same bits."""
    m = random_trig(rng)
    xi = random_xi(rng, m)
    B = m.one_point_backlund(xi, inverse_map=True)
    X = rng.normal(size=(3, m.n_state))
    rows = B.iterate(X, 3)
    assert rows.shape == (4, 3, m.n_state) and np.iscomplexobj(rows)
    for n in range(3):
        assert np.array_equal(B.iterate(X[n], 3), rows[:, n])
    d = B.describe()
    assert d["family"] == "trigonometric" and d["gamma"] == m.gamma and d["inverse_map"] is True
    C = jg.map_from_description(d)
    assert C == B and np.array_equal(C(X), B(X))


def test_verify_check_can_fail(monkeypatch):
    """`jetgaudin verify --only Trig-one-point` (50 digits, rebuilt from the definitions) holds, and fails when the
    two-point gauge has the other sign (rho = -1: the factorisation statement is then false) or when the second map
    is the forward one-point map instead of the inverse one (the wrong kind of dressing at conj xi)."""
    import jetgaudin.verify.trigonometric as vt
    from jetgaudin.verify import run_checks

    (r,) = run_checks(only=["Trig-one-point"])
    assert r.status == "holds"
    d = vt._dressing
    monkeypatch.setattr(vt, "_dressing", lambda k, xi, lam: vt.mp.matrix([[-1, 0], [0, 1]]) * d(k, xi, lam))
    (r,) = run_checks(only=["Trig-one-point"])
    assert r.status != "holds"
    monkeypatch.setattr(vt, "_dressing", d)
    one = vt._one_point
    monkeypatch.setattr(vt, "_one_point", lambda res, pos, b, eta, nu, inverse: one(res, pos, b, eta, nu, False))
    (r,) = run_checks(only=["Trig-one-point"])
    assert r.status != "holds"


def test_determinant_formula_and_degenerate_dressing(rng):
    """The family's one-point dressing has det D = e^{-i gamma x} sin(gamma x)(1 - 2i gamma pq)/gamma, x = lam - eta
    (forward and inverse forms, random p, q, lam; 1e-13 relative: a few products), and where 1 - 2i gamma pq = 0
    (det D = 0 identically) a step is refused with a SingularStepError naming it."""
    g, eta = 0.7, 0.2 + 0.3j
    fam = GaudinModel(1.0, [(0.0, 1)], family="trigonometric", gamma=g).family
    p, q = rng.normal(size=(2, 4)) + 1j * rng.normal(size=(2, 4))
    for inverse in (False, True):
        c = fam.one_point_dressing(eta, q if inverse else p, p if inverse else q, inverse)
        for lam in rng.normal(size=3) + 1j * rng.normal(size=3):
            D = np.einsum("bp,pij->bij", c, fam.dressing_basis(lam))
            x = lam - eta
            expected = np.exp(-1j * g * x) * np.sin(g * x) * (1 - 2j * g * p * q) / g
            assert np.abs(np.linalg.det(D) - expected).max() <= 1e-13 * np.abs(D).max() ** 2
    with pytest.raises(jg.SingularStepError, match="1 - 2i gamma p q = 0"):
        fam.one_point_dressing(eta, p, 1 / (2j * g * p), False)
