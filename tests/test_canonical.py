"""Tests of the canonical (Euler-angle) realisation of Section 5 (jetgaudin.canonical)."""

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import jetgaudin as jg
from jetgaudin import canonical as cn
from jetgaudin._errors import InvalidParameterError, InvalidStateError, OffLeafError
from jetgaudin.algebra import casimirs, poisson_tensor, structure_constants
from jetgaudin.verify import printed

NAMES = [f"{v}{a}" for v in "yxz" for a in (1, 2, 3)]
PCAN = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])  # {q_i, p_j} = delta_ij


def random_Q(rng, n):
    """Random canonical points inside the chart: theta in (0.2, pi-0.2), p_psi in (0.1, 2)."""
    return np.stack([
        rng.uniform(0.2, np.pi - 0.2, n), rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n),
        rng.normal(size=n), rng.normal(size=n), rng.uniform(0.1, 2.0, n),
    ], axis=-1)


def random_leaf_state(rng, n):
    """Points of the leaf built WITHOUT the canonical map: |z| = 1, x orthogonal to z, <y, z> = -|x|^2/2."""
    z = rng.normal(size=(n, 3))
    z /= np.linalg.norm(z, axis=-1, keepdims=True)
    x = rng.normal(size=(n, 3))
    x -= np.sum(x * z, axis=-1, keepdims=True) * z
    y = rng.normal(size=(n, 3))
    y -= (np.sum(y * z, axis=-1, keepdims=True) + np.sum(x * x, axis=-1, keepdims=True) / 2) * z
    return np.concatenate([y, x, z], axis=-1)


def fd_jacobian(f, Q, h=1e-5):
    """Central finite-difference Jacobian of f: (6,) -> (9,), shape (9, 6); error O(h^2) + O(eps/h) ~ 1e-10."""
    cols = []
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        cols.append((f(Q + e) - f(Q - e)) / (2 * h))
    return np.stack(cols, axis=-1)


# ------------------------------------------------------------------------------------------- symbolic
def _bracket_residuals(X, q, p):
    """{X_I, X_J}_can - sum_K c^{IJ}_K X_K for all I < J, computed here independently of check_realisation."""
    cst = structure_constants(3)
    out = {}
    for i in range(9):
        for j in range(i + 1, 9):
            br = sum(sp.diff(X[i], a) * sp.diff(X[j], b) - sp.diff(X[i], b) * sp.diff(X[j], a)
                     for a, b in zip(q, p, strict=True))
            expected = sum(int(cst[i, j, k]) * X[k] for k in range(9))
            r = sp.expand(br - expected)  # cheap; full simplify only for what is left
            r = r if r == 0 else sp.simplify(r)
            if r != 0:
                out[(NAMES[i], NAMES[j])] = r
    return out


def _leaf(X):
    y, x, z = X[0:3], X[3:6], X[6:9]
    dot = lambda u, v: sum(a * b for a, b in zip(u, v, strict=True))  # noqa: E731
    return [sp.simplify(dot(y, z) + dot(x, x) / 2), sp.simplify(dot(x, z)), sp.simplify(dot(z, z) - 1)]


def test_corrected_realisation_reproduces_algebra_and_leaf_symbolically():
    # exact: every canonical bracket minus (algebra) simplifies to 0, and C^(1) = C^(2) = 0, C^(3) = 1
    q, p, X = cn.symbolic_realisation()
    assert _bracket_residuals(X, q, p) == {}
    assert _leaf(X) == [0, 0, 0]
    assert cn.check_realisation() == (True, {})


def test_printed_realisation_fails_symbolically():
    # misprint of Section 5 (Proposition): exactly these brackets fail, and the image is off the leaf
    q, p, X = printed.symbolic_realisation()
    th, ph, ps = q
    pth, pph, pps = p
    res = _bracket_residuals(X, q, p)
    expected = {
        ("y1", "z2"): -2 * sp.cos(th), ("y1", "z3"): 2 * sp.sin(ph) * sp.sin(th),
        ("y2", "z1"): 2 * sp.cos(th), ("y2", "z3"): -2 * sp.sin(th) * sp.cos(ph),
        ("x1", "x2"): -2 * sp.cos(th),
    }
    assert set(res) == set(expected)
    for k, v in expected.items():
        assert sp.simplify(res[k] - v) == 0, k
    C1, C2, C3 = _leaf(X)
    assert sp.simplify(C1 - 2 * pph * sp.cos(th)) == 0
    assert sp.simplify(C2 + 2 * sp.sqrt(2 * pps) * sp.sin(th) * sp.cos(th) * sp.cos(ps)) == 0
    assert C3 == 0
    ok, res2 = cn.check_realisation(X)
    assert not ok and set(res2) == set(expected) | {"C1", "C2"}


def test_symbolic_hamiltonian_is_H2_over_2_and_printed_one_is_not():
    q, p, X = cn.symbolic_realisation()
    _, _, b, H = cn.symbolic_hamiltonian()
    H2half = sum(v**2 for v in X[0:3]) / 2 + b * X[5]
    assert sp.simplify(H - H2half) == 0
    th, _, ps = q
    pth, pph, pps = p
    Hp = printed.hamiltonian(sp, th, ps, pth, pph, pps, b)
    # printed H misses the sign of the cross term: H - H_printed = 2 p_psi p_phi cos(theta) / sin^2(theta)
    assert sp.simplify(H - Hp - 2 * pps * pph * sp.cos(th) / sp.sin(th) ** 2) == 0


# ------------------------------------------------------------------------------------------- numeric
def test_numeric_map_matches_symbolic_expressions(rng):
    # two routes: hand-written NumPy vs lambdified SymPy; rounding only (~1e-15 relative), tol 1e-12
    q, p, X = cn.symbolic_realisation()
    f = sp.lambdify((*q, *p), list(X), "numpy")
    Q = random_Q(rng, 50)
    ref = np.stack(np.broadcast_arrays(*f(*Q.T)), axis=-1)
    np.testing.assert_allclose(cn.euler_to_state(Q), ref, rtol=1e-12, atol=1e-12)


def test_poisson_tensor_pullback_numeric(rng):
    # J Pcan J^T == Pi(X): J by central differences of euler_to_state (error ~1e-9 for h = 1e-5 on O(1-10)
    # entries), so tol 1e-6 relative to max(1, |Pi|)
    for Q in random_Q(rng, 20):
        J = fd_jacobian(cn.euler_to_state, Q)
        P = poisson_tensor(cn.euler_to_state(Q))
        np.testing.assert_allclose(J @ PCAN @ J.T, P, rtol=0, atol=1e-6 * max(1.0, np.abs(P).max()))


def test_printed_realisation_fails_numerically(rng):
    # the printed map's pulled-back tensor differs from Pi(X) by O(1) (entries like 2 cos(theta)): assert > 0.1
    q, p, X = printed.symbolic_realisation()
    f = sp.lambdify((*q, *p), list(X), "numpy")

    def printed_map(Q):
        return np.array(np.broadcast_arrays(*f(*Q)), dtype=float)

    for Q in random_Q(rng, 10):
        Q[0] = rng.uniform(0.3, 1.2)  # keep cos(theta) and sin(theta) away from 0 so the defect is O(1)
        J = fd_jacobian(printed_map, Q)
        resid = np.abs(J @ PCAN @ J.T - poisson_tensor(printed_map(Q))).max()
        assert resid > 0.1
        assert not cn.on_canonical_leaf(printed_map(Q))


def test_image_on_leaf_and_casimirs(rng):
    X = cn.euler_to_state(random_Q(rng, 200))
    assert np.all(cn.on_canonical_leaf(X))
    assert np.all(cn.leaf_residuals(X) < 1e-13)  # exact identities up to rounding
    # independent route: jetgaudin.casimirs = (2 C^(1), 2 C^(2), C^(3)) = (0, 0, 1); tol: rounding, 1e-12
    np.testing.assert_allclose(casimirs(X), np.broadcast_to([0.0, 0.0, 1.0], (200, 3)), atol=1e-12)


def test_round_trips(rng):
    Q = random_Q(rng, 200)
    Q2 = cn.state_to_euler(cn.euler_to_state(Q))
    assert np.all((Q2[:, 0] > 0) & (Q2[:, 0] < np.pi))  # documented chart ranges
    assert np.all((Q2[:, 1:3] >= 0) & (Q2[:, 1:3] < 2 * np.pi))
    # angles come back in [0, 2 pi); compare modulo 2 pi; tolerance: a few ulps amplified by 1/sin(theta) <= 5
    d = Q2 - Q
    d[..., 1:3] = (d[..., 1:3] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(d).max() < 1e-12
    X = random_leaf_state(rng, 200)  # built independently of the canonical map
    np.testing.assert_allclose(cn.euler_to_state(cn.state_to_euler(X)), X, rtol=0, atol=1e-12)


@given(st.floats(0.05, np.pi - 0.05), st.floats(0, 2 * np.pi), st.floats(0, 2 * np.pi),
       st.floats(-5, 5), st.floats(-5, 5), st.floats(1e-3, 5))
def test_round_trip_property(th, ph, ps, pth, pph, pps):
    Q = np.array([th, ph, ps, pth, pph, pps])
    X = cn.euler_to_state(Q)
    # tolerance 1e-10 * scale: rounding amplified by 1/sin(theta) <= 20 and 1/|x| <= 23
    np.testing.assert_allclose(cn.euler_to_state(cn.state_to_euler(X)), X, rtol=0, atol=1e-10 * max(1, np.abs(X).max()))


def test_batch_equals_single_bit_for_bit(rng):
    Q = random_Q(rng, 7).reshape(7, 1, 6)
    X = cn.euler_to_state(Q)
    for i in range(7):
        assert np.array_equal(X[i, 0], cn.euler_to_state(Q[i, 0]))
        assert np.array_equal(cn.state_to_euler(X)[i, 0], cn.state_to_euler(X[i, 0]))
        assert np.array_equal(cn.canonical_vector_field(Q, 0.7)[i, 0], cn.canonical_vector_field(Q[i, 0], 0.7))


def test_printed_angle_ranges_are_not_euler_angles(rng):
    # printed: theta in [0, 2 pi), psi in [0, pi).  theta -> 2 pi - theta (with phi, psi -> +pi, p_theta -> -p_theta)
    # gives the same state, so the printed ranges are another fundamental domain of the same parametrisation
    # (harmless), but for theta in (pi, 2 pi) theta is not the polar angle of z, and with the Euler range
    # theta in (0, pi) the range psi in [0, pi) misses half of the leaf (psi -> psi + pi gives x -> -x)
    Q = random_Q(rng, 20)
    Qb = Q.copy()
    Qb[:, 0] = 2 * np.pi - Q[:, 0]
    Qb[:, 1] += np.pi
    Qb[:, 2] += np.pi
    Qb[:, 3] *= -1
    np.testing.assert_allclose(cn.euler_to_state(Qb), cn.euler_to_state(Q), atol=1e-12)
    Xb = cn.euler_to_state(Qb)
    assert np.all(np.abs(np.arccos(Xb[:, 8]) - Qb[:, 0]) > 0.1)  # theta in (pi, 2 pi) is not the polar angle
    Qc = Q.copy()
    Qc[:, 2] += np.pi
    Xc = cn.euler_to_state(Qc)
    np.testing.assert_allclose(Xc[:, 3:6], -cn.euler_to_state(Q)[:, 3:6], atol=1e-12)
    assert np.all(cn.on_canonical_leaf(Xc))
    ps_back = cn.state_to_euler(np.concatenate([cn.euler_to_state(Q), Xc]))[:, 2]
    assert np.any(ps_back > np.pi)


# ------------------------------------------------------------------------------------------- dynamics
@pytest.mark.parametrize("b", [1.0, -0.7])
def test_canonical_hamiltonian_and_integrals(rng, b):
    Q = random_Q(rng, 100)
    X = cn.euler_to_state(Q)
    ints = jg.integrals(X, b)  # (H_1, H_2, H_3, C_1, C_2, C_3), Prop. 2 via the spectral curve
    # rounding only; tolerance 1e-12 relative to max(1, |value|)
    np.testing.assert_allclose(cn.canonical_hamiltonian(Q, b), ints[:, 1] / 2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cn.canonical_hamiltonian(Q, b), jg.physical_hamiltonian(3, b)(X), rtol=1e-12,
                               atol=1e-12)
    I = cn.canonical_integrals(Q, b)
    # I_1 = p_phi = H_1/(2b) (the paper's value; H_1 = 2<b, y> = 2 b y^3), I_2 = H_3/2
    np.testing.assert_allclose(I[:, 0], ints[:, 0] / (2 * b), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(I[:, 0], Q[:, 4], rtol=0, atol=0)
    np.testing.assert_allclose(I[:, 1], ints[:, 2] / 2, rtol=1e-12, atol=1e-12)
    th, ph, ps, pth, pph, pps = Q.T
    # misprints: printed I_1 = H_2/2 = p_phi (p_phi is right, the label is H_1/(2b)); printed I_2 has the opposite
    # sign of sqrt(2 p_psi)(p_theta sin psi + p_psi cot theta cos psi)
    assert np.abs(ints[:, 1] / 2 - pph).max() > 0.1
    I2_printed = printed.integral_I2(np, th, ps, pth, pph, pps, b)
    np.testing.assert_allclose(I[:, 1] - I2_printed,
                               -2 * np.sqrt(2 * pps) * (pth * np.sin(ps) + pps / np.tan(th) * np.cos(ps)),
                               rtol=1e-10, atol=1e-10)
    H_printed = printed.hamiltonian(np, th, ps, pth, pph, pps, b)
    assert np.abs(H_printed - ints[:, 1] / 2).max() > 0.1


def test_vector_field_pushes_forward_to_em(rng):
    # J(Q) dQ/dt == Pi(X) grad(H_2/2) at X = euler_to_state(Q); J by central differences (tol 1e-6, as above)
    b = 1.3
    H = jg.physical_hamiltonian(3, b)
    for Q in random_Q(rng, 10):
        J = fd_jacobian(cn.euler_to_state, Q)
        lhs = J @ cn.canonical_vector_field(Q, b)
        rhs = H.vector_field(cn.euler_to_state(Q))
        np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-6 * max(1.0, np.abs(rhs).max()))


def test_vector_field_is_hamiltonian_of_canonical_hamiltonian(rng):
    # dq/dt = dH/dp, dp/dt = -dH/dq with dH by central differences of canonical_hamiltonian (tol 1e-7)
    b = -0.4
    for Q in random_Q(rng, 10):
        g = np.array([(cn.canonical_hamiltonian(Q + h, b) - cn.canonical_hamiltonian(Q - h, b)) / 2e-6
                      for h in 1e-6 * np.eye(6)])
        np.testing.assert_allclose(cn.canonical_vector_field(Q, b), PCAN @ g, rtol=0, atol=1e-7 * max(1, abs(g).max()))


@pytest.mark.parametrize(("Q0", "b"), [([1.1, 0.3, 2.0, 0.4, -0.3, 0.8], 1.0), ([2.0, 5.0, 0.5, -0.6, 0.9, 1.5], -0.7)])
def test_canonical_flow_matches_em(Q0, b):
    # Hamilton's equations in (theta, ..., p_psi) vs (em) = Pi grad(H_2/2) in (y, x, z); both DOP853 with
    # rtol = atol = 1e-12 over T = 5. Each run's global error is ~1e-12 x (error growth over T = 5, at most
    # ~10^2 for these orbits) and the chart map is O(1)-Lipschitz away from the singularities (asserted below),
    # so the images agree to ~1e-10 at worst; measured ~5e-12. Assert 1e-9 absolute on states of size O(1).
    T = 5.0
    ts = np.linspace(0.0, T, 6)
    sol = solve_ivp(lambda _t, q: cn.canonical_vector_field(q, b), (0, T), Q0, method="DOP853",
                    t_eval=np.linspace(0, T, 501), rtol=1e-12, atol=1e-12, dense_output=True)
    assert sol.success
    assert np.sin(sol.y[0]).min() > 0.3 and sol.y[5].min() > 0.1  # the orbit stays inside the chart
    Xc = cn.euler_to_state(sol.sol(ts).T)
    tr = jg.integrate(jg.physical_hamiltonian(3, b), cn.euler_to_state(Q0), T, t_eval=ts)
    assert np.abs(Xc - tr.X).max() < 1e-9
    assert np.abs(Xc[-1] - Xc[0]).max() > 0.1  # the motion is not trivial
    assert np.all(cn.on_canonical_leaf(tr.X))


# ------------------------------------------------------------------------------------------- bad input
def test_bad_canonical_input():
    with pytest.raises(InvalidStateError, match="shape"):
        cn.euler_to_state(np.zeros(5))
    with pytest.raises(InvalidStateError, match="non-finite"):
        cn.euler_to_state([np.nan, 0, 0, 0, 0, 1])
    with pytest.raises(InvalidStateError, match="sin\\(theta\\) = 0"):
        cn.euler_to_state([np.pi, 0, 0, 0, 0, 1])
    with pytest.raises(InvalidStateError, match="p_psi must be >= 0"):
        cn.euler_to_state([1, 0, 0, 0, 0, -1])
    with pytest.raises(InvalidStateError, match="p_psi must be > 0"):
        cn.canonical_vector_field([1, 0, 0, 0, 0, 0], 1.0)
    with pytest.raises(InvalidStateError, match="real"):
        cn.euler_to_state([1j, 0, 0, 0, 0, 1])
    for bad_b in (np.nan, "x", [1.0, 2.0], True):
        with pytest.raises(InvalidParameterError, match="field strength b"):
            cn.canonical_hamiltonian([1, 0, 0, 0, 0, 1], bad_b)


def test_bad_state_input(rng):
    X = cn.euler_to_state([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    with pytest.raises(InvalidStateError, match="N = 3"):
        cn.state_to_euler(X[:6])
    with pytest.raises(InvalidParameterError, match="tol"):
        cn.on_canonical_leaf(X, tol=-1)
    bad = X.copy()
    bad[6:9] *= 1.1
    with pytest.raises(OffLeafError, match=r"C\^\(3\) = \|z\|\^2 = 1.*normalise z"):
        cn.state_to_euler(bad)
    bad = X.copy()
    bad[3:6] += 0.1 * X[6:9]
    with pytest.raises(OffLeafError, match=r"C\^\(2\) = <x, z> = 0.*project x"):
        cn.state_to_euler(bad)
    bad = X.copy()
    bad[0:3] += 0.1 * X[6:9]
    with pytest.raises(OffLeafError, match=r"C\^\(1\).*shift y along z"):
        cn.state_to_euler(bad)
    # within tolerance: accepted (residual 1e-12 < LEAF_TOL = 1e-9)
    ok = X.copy()
    ok[0:3] += 1e-12 * X[6:9]
    cn.state_to_euler(ok)
    # Appendix 2 data is not on this leaf (<x, z> = -2.19)
    from conftest import APPENDIX2_X0

    with pytest.raises(OffLeafError, match="C\\^\\(2\\)"):
        cn.state_to_euler(APPENDIX2_X0)
    # coordinate singularities of the chart
    pole = np.array([0.3, -0.2, 0.0, 1.0, 0.5, 0.0, 0.0, 0.0, 1.0])  # z = e_3, <y,z> = -|x|^2/2
    pole[2] = -np.sum(pole[3:6] ** 2) / 2
    with pytest.raises(OffLeafError, match="sin\\(theta\\) = 0"):
        cn.state_to_euler(pole)
    origin = np.array([0.3, -0.2, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0])  # x = 0 (p_psi = 0), y orthogonal to z
    origin[0:3] = [0.0, 0.4, -0.2]
    with pytest.raises(OffLeafError, match="x = 0"):
        cn.state_to_euler(origin)


def test_leaf_casimirs_are_the_section3_casimirs(rng):
    """leaf_casimirs = (C^(1), C^(2), C^(3)): equal to (C_1/2, C_2/2, C_3) of eq. (cas) (a few ulps of |X|^2), and
    central: Pi(X) grad C^(k) = 0 with the gradient by central differences (exact for quadratics up to
    round-off ~ eps |X|^2 / h with h = 1e-4: 1e-10 absolute for |X| ~ 1)."""
    from jetgaudin.canonical import leaf_casimirs

    X = rng.normal(size=(4, 9))
    C = leaf_casimirs(X)
    I = jg.integrals(X, 1.0)
    np.testing.assert_allclose(C, np.stack([I[:, 3] / 2, I[:, 4] / 2, I[:, 5]], axis=-1), rtol=0, atol=1e-13)
    h = 1e-4
    for x in X:
        grad = np.stack([(leaf_casimirs(x + h * e) - leaf_casimirs(x - h * e)) / (2 * h) for e in np.eye(9)], axis=-1)
        assert np.abs(grad @ jg.poisson_tensor(x).T).max() <= 1e-10
