"""The elliptic (XYZ) Gaudin family on the model core (issue 24): r-matrix, integrals, the real two-point map and
its half-period choice, limits (k -> 0, coalescence, Im eta -> 0), the Clebsch top, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import special

import jetgaudin as jg
from jetgaudin._errors import InvalidParameterError
from jetgaudin.families import EllipticFamily
from jetgaudin.families import _jacobi as J
from jetgaudin.families.elliptic import PAULI
from jetgaudin.gaudin import GaudinModel
from test_backlund import jacobian_fd
from test_gaudin_maps import check_interpolates_flow, check_poisson, check_real, check_symmetric

SITES = [(0.0, 1), (0.9, 1), (2.1, 1)]
JET_SITES = [(-0.6, 2), (0.7, 1)]
ETA = 0.45 + 0.15j


def model(k=0.6, sites=SITES, **kw):
    return GaudinModel(0.0, sites, family="elliptic", modulus=k, **kw)


def state(m, seed=3):
    return np.random.default_rng([24, seed]).normal(size=m.n_state)


def _scale(*Xs):
    return 1 + max(np.abs(X).max() for X in Xs)


# ---------------------------------------------------------------------------------------------- the model


def test_lax_matrix_is_the_definition():
    """ℓ = Σ_a ξ^a σ_a with ξ^a = Σ_j w_a(λ − λ_j) s_j^a (order 1) and the jet term −y_1^a w_a'(λ − λ_j): L = (i/2)ℓ
    in the paper's σ basis (1e-13 relative; w_a' from the Taylor series, checked against mpmath in test_jacobi)."""
    m = model(0.6, [(0.0, 2), (1.1, 1)])
    X = state(m)
    lam = 0.3 + 0.4j
    y = X.reshape(3, 3)
    T0 = J.w_taylor(np.array(lam), 0.6, 2)
    T1 = J.w_taylor(np.array(lam - 1.1), 0.6, 1)
    xi = y[0] * T0[:, 0] - y[1] * T0[:, 1] + y[2] * T1[:, 0]
    ell = np.einsum("a,aij->ij", xi, PAULI)
    assert np.allclose(m.lax_matrix(X, lam), 0.5j * ell, rtol=1e-13, atol=1e-13 * np.abs(ell).max())


def test_r_matrix_relation():
    r"""{ℓ(λ) ⊗ ℓ(μ)} = [r(λ−μ), ℓ(λ)⊗1 + 1⊗ℓ(μ)], r(x) = (i/2) Σ_a w_a(x) σ_a⊗σ_a, for order-1 and jet sites (the
    left side from the model's Poisson tensor: ξ is linear in X).  1e-12 relative: round-off of sums of ~10 terms."""
    for sites in (SITES, JET_SITES):
        m = model(0.7, sites)
        X = state(m, 5)
        lam, mu = 0.3 + 0.45j, 1.4 - 0.2j
        E = np.eye(m.n_state)
        gl, gm = m.xi(E, lam), m.xi(E, mu)  # (3M, 3): ∇ξ^a
        br = np.einsum("ia,ij,jb->ab", gl, m.poisson_tensor(X), gm)
        lhs = sum(br[a, b] * np.kron(PAULI[a], PAULI[b]) for a in range(3) for b in range(3))
        w = J.w_values(np.array(lam - mu), 0.7)
        r = 0.5j * sum(w[a] * np.kron(PAULI[a], PAULI[a]) for a in range(3))
        ell_l = np.einsum("a,aij->ij", m.xi(X, lam), PAULI)
        ell_m = np.einsum("a,aij->ij", m.xi(X, mu), PAULI)
        S = np.kron(ell_l, np.eye(2)) + np.kron(np.eye(2), ell_m)
        rhs = r @ S - S @ r
        assert np.abs(lhs - rhs).max() <= 1e-12 * np.abs(rhs).max()
        # a wrong sign of r (the relation for {y^a, y^b} = -eps y^c) fails
        assert np.abs(lhs + rhs).max() > 0.1 * np.abs(rhs).max()


@pytest.mark.parametrize("sites", [SITES, JET_SITES])
def test_nu_squared_expansion_is_exact(sites):
    """ν²(λ) = c0 + Σ h_{j,m} ψ_m(λ − λ_j) at random complex λ (1e-12 relative: evaluation round-off), and
    Σ_j h_{j,1} = 0 (residue theorem; 1e-12 relative)."""
    m = model(0.8, sites)
    X = state(m)
    I = m.integrals(X)
    fam = m.family
    for lam in (0.3 + 0.4j, 1.7 - 0.6j, -2.3 + 1.1j):
        tot, row = I[-1], 0
        for p, N in sites:
            for k in range(1, 2 * N + 1):
                tot += I[row] * fam.nu2_basis(k, np.asarray(lam - p))
                row += 1
        nu2 = m.nu_squared(X, lam)
        assert abs(tot - nu2) <= 1e-12 * (1 + abs(nu2))
    h1 = [I[i] for i, lab in enumerate(m.integral_labels()) if lab.endswith(",1")]
    assert abs(sum(h1)) <= 1e-12 * np.abs(I).max()


def test_integrals_against_contour_integrals():
    """h_{j,m} = (1/2πi)∮ ν² (λ−λ_j)^{m−1} dλ on the circle |λ − λ_j| = 0.25 (trapezoid rule, 256 nodes: exponentially
    accurate, ~1e-13), for order-1 and jet sites: 1e-11 relative to max|h|."""
    for sites in (SITES, JET_SITES):
        m = model(0.5, sites)
        X = state(m, 7)
        I = m.integrals(X)
        th = 2 * np.pi * np.arange(256) / 256
        row = 0
        for p, N in sites:
            z = 0.25 * np.exp(1j * th)
            nu2 = m.nu_squared(X[None], p + z)
            for k in range(1, 2 * N + 1):
                h = np.mean(nu2 * z**k)
                assert abs(h - I[row]) <= 1e-11 * np.abs(I).max()
                row += 1


def test_casimirs_and_labels():
    m = model(0.5, JET_SITES)
    assert m.integral_labels() == ["h1,1", "h1,2", "h1,3", "h1,4", "h2,1", "h2,2", "c0"]
    assert m.casimir_mask().tolist() == [False, False, True, True, False, True, False]
    X = state(m)
    y = X.reshape(-1, 3)
    I = m.integrals(X)
    # Casimirs of g^(2) at site 1 (2 y0.y1, |y1|^2) and of su(2) at site 2 (|s|^2): exact forms, 1e-14
    assert np.allclose(I[[2, 3, 5]], [2 * y[0] @ y[1], y[1] @ y[1], y[2] @ y[2]], rtol=1e-14, atol=0)


def test_involution():
    """All integrals Poisson-commute: ∇I_a Π ∇I_b = 0 to 1e-12 relative to |∇I_a||Π||∇I_b|."""
    for sites in (SITES, JET_SITES):
        m = model(0.7, sites)
        X = state(m, 11)
        G = m.integral_gradients(X)
        P = m.poisson_tensor(X)
        B = G @ P @ G.T
        scale = np.outer(np.linalg.norm(G, axis=1), np.linalg.norm(G, axis=1)) * np.abs(P).max()
        assert np.all(np.abs(B) <= 1e-12 * scale + 1e-300)


# ---------------------------------------------------------------------------------------------- the map


@pytest.mark.parametrize("k, eta", [(0.6, ETA), (0.95, -0.3 - 0.2j), (0.05, 1.2 + 0.4j)])
@pytest.mark.parametrize("sites", [SITES, JET_SITES])
def test_map_properties(sites, k, eta):
    """Integrals preserved (1e-12 relative), Poisson map (finite-difference Jacobian, test_gaudin_maps.check_poisson),
    real output, inverse = opposite branch = conj(eta), the time-1 flow of G_eta (check_interpolates_flow); moduli
    near 0 and 1, Im eta of both signs."""
    m = model(k, sites)
    X = state(m, 2)
    B = m.two_point_backlund(eta)
    Y = B(X)
    assert np.abs(m.integrals(Y) - m.integrals(X)).max() <= 1e-12 * np.abs(m.integrals(X)).max()
    rng = np.random.default_rng(0)
    check_poisson(B, X, rng, True)
    check_real(B, X, rng, True)
    check_symmetric(B, X, rng, True)
    check_interpolates_flow(B, X, rng, True)


def test_maps_commute():
    """B_η B_ζ = B_ζ B_η (both flows of functions of the integrals): 1e-11 relative."""
    m = model(0.6)
    X = state(m, 4)
    B1, B2 = m.two_point_backlund(ETA), m.two_point_backlund(-0.8 + 0.3j)
    assert np.abs(B1(B2(X)) - B2(B1(X))).max() <= 1e-11 * _scale(X)


ROTATION = {"K": 2, "iK'": 0, "K+iK'": 1}  # the axis b of the π-rotation composed with the map


def _rotate(X, b):
    y = X.reshape(-1, 3).copy()
    y[:, [a for a in range(3) if a != b]] *= -1
    return y.ravel()


@pytest.mark.parametrize("shift", ["K", "iK'", "K+iK'"])
def test_half_period_choice(shift):
    """The dressing with λ0 = Re ξ + ω: ω = 0 is the time-1 flow of G_ξ (test_map_properties); each other half period
    gives a real, integral-preserving map that is NOT that flow but the flow composed with the π-rotation about one
    axis (1e-11), and does not tend to the identity as Im ξ → 0 (distance ≥ 0.1 |X| at Im ξ = 1e-3, while ω = 0 is
    O(Im ξ))."""
    m = model(0.6)
    X = state(m)
    shifted = GaudinModel(0.0, SITES, family=EllipticFamily(0.6, half_period=shift))
    Y0 = m.two_point_backlund(ETA)(X)
    Ys = shifted.two_point_backlund(ETA)(X)
    assert np.abs(Ys - Y0).max() > 0.1 * np.abs(X).max()  # not the flow of G_ξ
    assert np.abs(Ys - _rotate(Y0, ROTATION[shift])).max() <= 1e-11 * _scale(X)
    small = 0.45 + 1e-3j
    assert np.abs(m.two_point_backlund(small)(X) - X).max() < 1e-2 * _scale(X)
    assert np.abs(shifted.two_point_backlund(small)(X) - X).max() > 0.1 * np.abs(X).max()


def test_trigonometric_limit_k0_and_order():
    """k = 0 is the trigonometric family (γ = 1) with b = 0: same Lax matrix, same map (1e-12), c0 = −J²; for small k
    the maps differ by O(k²): the measured order log2(err(k)/err(k/2)) is 2 within 0.1."""
    trig = GaudinModel(0.0, SITES, family="trigonometric")
    X = state(trig, 8)
    e0 = model(0.0)
    assert np.allclose(e0.lax_matrix(X, 0.3 + 0.2j), trig.lax_matrix(X, 0.3 + 0.2j), rtol=1e-13, atol=0)
    J3 = X.reshape(-1, 3)[:, 2].sum()
    assert abs(e0.integrals(X)[-1] + J3**2) <= 1e-12 * (1 + J3**2)
    Yt = trig.two_point_backlund(ETA)(X)
    assert np.abs(e0.two_point_backlund(ETA)(X) - Yt).max() <= 1e-12 * _scale(X)
    errs = [np.abs(model(k).two_point_backlund(ETA)(X) - Yt).max() for k in (0.04, 0.02, 0.01)]
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2) < 0.1), orders


def test_coalescence_gives_the_jet_site():
    """Two order-1 sites at 0 and ε with spins y0 − y1/ε... (ξ = s1 w(λ) + s2 w(λ−ε) = (s1+s2) w − ε s2 w' + O(ε²)):
    s2 = y1/ε, s1 = y0 − y1/ε.  The map of the pair, recombined (y0 = s1 + s2, y1 = ε s2), tends to the map of the
    order-2 site: measured order 1 within 0.15."""
    k = 0.5
    jet = model(k, [(0.0, 2), (1.3, 1)])
    X = state(jet, 6)
    Yj = jet.two_point_backlund(ETA)(X)
    errs = []
    for eps in (0.02, 0.01, 0.005):
        pair = model(k, [(0.0, 1), (eps, 1), (1.3, 1)])
        y0, y1, s3 = X[:3], X[3:6], X[6:]
        Z = pair.two_point_backlund(ETA)(np.concatenate([y0 - y1 / eps, y1 / eps, s3]))
        back = np.concatenate([Z[:3] + Z[3:6], eps * Z[3:6], Z[6:]])
        errs.append(np.abs(back - Yj).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 1) < 0.15), orders


def _nu_hamiltonian(m, X, a):
    """ν(a) as a Hamiltonian: Σ ψ_m(a − λ_j) h_{j,m}/(2ν(a)) + c0/(2ν(a)) (weights constant on its flow)."""
    nu_a = float(m.nu(X, a).real)
    w = [float(np.real(m.family.nu2_basis(k, np.asarray(a - p)))) for p, N in m.sites for k in range(1, 2 * N + 1)]
    return m.hamiltonian(np.array(w + [1.0]) / (2 * nu_a))


def test_second_order_in_im_eta():
    """Small Im ξ = h: n = 0.4/(2h) steps of B_(a + ih) approximate the flow of ν(a) for time −2hn; the global error
    is O(h²): measured orders 2 within 0.15 (h = 0.02, 0.01, 0.005)."""
    m = model(0.6)
    X = 0.7 * state(m, 9)
    a = 0.45
    H = _nu_hamiltonian(m, X, a)
    errs = []
    for h in (0.02, 0.01, 0.005):
        n = int(round(0.4 / (2 * h)))
        exact = jg.integrate(H, X, -2 * h * n, rtol=1e-13, atol=1e-14).X[-1]
        errs.append(np.abs(m.two_point_backlund(a + 1j * h).iterate(X, n)[-1] - exact).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2) < 0.15), orders


# ---------------------------------------------------------------------------------------------- the Clebsch top


@pytest.mark.parametrize("k", [0.3, 0.7])
def test_clebsch_top_is_the_clebsch_case(k):
    """clebsch_top(k): e(3) bracket; h_{1,2} = |M|² − 2Σ r_a p_a²; c0 = Σ A_a M_a² + Σ B_a p_a² with
    A = (1, k'², 0) − E/K (derived by hand from the Laurent series: c0 = [x^0]ν² − f_1 h_2 − f_3 h_4 with
    F' = 1 − E/K − ns², module docstring of clebsch_top); for μ = 0.7, 2.5 the Kirchhoff coefficients a = A + μ,
    b = B − 2μ r satisfy Clebsch's condition b_i − a_j a_k = const (1e-12)."""
    top = jg.clebsch_top(k)
    assert np.allclose(top.structure_constants, jg.structure_constants(2))
    q = top._forms[0]
    r = np.array([(1 + k * k) / 6, (1 - 2 * k * k) / 6, -(2 - k * k) / 6])
    A = np.array([1.0, 1 - k * k, 0.0]) - special.ellipe(k * k) / special.ellipk(k * k)
    assert np.allclose(q[:, 1, 0, 0], 1.0, atol=1e-14) and np.allclose(q[:, 1, 1, 1], -2 * r, atol=1e-14)
    assert np.allclose(q[:, 4, 0, 0], A, atol=1e-13) and np.allclose(q[:, 4, 0, 1], 0.0, atol=1e-14)
    B = q[:, 4, 1, 1]
    for mu in (0.7, 2.5):
        a, b = A + mu, B - 2 * mu * r
        c = b - np.array([a[1] * a[2], a[2] * a[0], a[0] * a[1]])
        assert np.ptp(c) <= 1e-12 * np.abs(b).max()
        assert abs((a[0] - a[1]) / (a[0] - a[2]) - k * k) <= 1e-13  # the modulus from the body's a_i
    # not the Clebsch case for a wrong b (e.g. a sign flip of B): the check bites
    c = -B - np.array([A[1] * A[2], A[2] * A[0], A[0] * A[1]])
    assert np.ptp(c) > 1e-3


def test_clebsch_top_map():
    """The Clebsch top's map keeps its integrals (1e-12), the e(3) Casimirs M·p, |p|² (1e-12) and is the time-1 flow of
    G_ξ (check_interpolates_flow)."""
    top = jg.clebsch_top(0.6)
    X = state(top, 12)
    B = top.two_point_backlund(0.4 + 0.2j)
    Y = B.iterate(X, 5)[-1]
    assert np.abs(top.integrals(Y) - top.integrals(X)).max() <= 1e-12 * np.abs(top.integrals(X)).max()
    check_interpolates_flow(B, X, np.random.default_rng(0), True)


# ---------------------------------------------------------------------------------------------- refusals


def test_refusals():
    with pytest.raises(InvalidParameterError, match="no field"):
        GaudinModel(0.5, SITES, family="elliptic", modulus=0.5)
    for bad in (1.0, -0.2, 2.0):
        with pytest.raises(InvalidParameterError, match="modulus"):
            model(bad)
    with pytest.raises(InvalidParameterError, match="modulus"):
        GaudinModel(0.0, SITES, family="elliptic")
    with pytest.raises(InvalidParameterError, match="no parameter"):
        GaudinModel(0.0, SITES, family="trigonometric", modulus=0.5)
    m = model(0.6)
    K, Kp = m.family.K, m.family.Kp
    with pytest.raises(InvalidParameterError, match="coincide modulo"):
        model(0.6, [(0.0, 1), (2 * K, 1)])
    with pytest.raises(InvalidParameterError, match="is a site"):
        m.two_point_backlund(0.9 + 2 * K + 0.2j)
    with pytest.raises(InvalidParameterError, match="too close to K'"):
        m.two_point_backlund(0.45 + 0.95j * Kp)
    m.two_point_backlund(0.45 + 0.85j * Kp)  # allowed


def test_describe_round_trip():
    B = model(0.6, JET_SITES).two_point_backlund(ETA)
    d = B.describe()
    assert d["family"] == "elliptic" and d["modulus"] == 0.6
    C = jg.map_from_description(d)
    X = state(B.model)
    assert np.array_equal(C(X), B(X))


def test_jacobian_helper_is_used():  # keep the import honest (ruff) and document the FD helper's accuracy
    assert jacobian_fd.__doc__ and "6th-order" in jacobian_fd.__doc__


# ---------------------------------------------------------------------------------------------- compiled route


@pytest.mark.parametrize("sites", [SITES, JET_SITES])
def test_compiled_kernel_matches_numpy(sites):
    """The family kernel's elliptic rule (cofactor null vector) against the NumPy route (SVD null vector): 100 steps
    agree to 1e-11 relative (round-off growth along the orbit; measured ~1e-13), and a batch member equals its single
    run bit for bit."""
    m = model(0.6, sites)
    X = state(m, 13)
    a = m.two_point_backlund(ETA, backend="numpy").iterate(X, 100)
    Bc = m.two_point_backlund(ETA, backend="compiled")
    b = Bc.iterate(X, 100)
    assert np.abs(a - b).max() <= 1e-11 * _scale(a)
    Xb = np.stack([X, 0.5 * X])
    assert np.array_equal(Bc.iterate(Xb, 7)[:, 0], Bc.iterate(X, 7))


def test_flows_of_the_integrals():
    """model.hamiltonian(weights) flows with jg.integrate: the flow of c0 keeps every integral (1e-10: DOP853 at
    1e-13 over t = 1) and commutes with the map (both are flows of commuting functions: 1e-9)."""
    m = model(0.6)
    X = state(m, 14)
    w = np.zeros(m.n_integrals)
    w[-1] = 1.0  # c0
    H = m.hamiltonian(w)
    Y = jg.integrate(H, X, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    assert np.abs(m.integrals(Y) - m.integrals(X)).max() <= 1e-10 * np.abs(m.integrals(X)).max()
    assert np.abs(Y - X).max() > 0.1  # it moves
    B = m.two_point_backlund(ETA)
    YB = jg.integrate(H, B(X), 1.0, rtol=1e-13, atol=1e-13).X[-1]
    assert np.abs(B(Y) - YB).max() <= 1e-9 * _scale(X)
