"""su(n) Gaudin models with jet sites (issue 32): the model core with the algebra as a parameter.

Independent routes: the Lax matrix against the su(2) chain's, the integrals against contour integrals of tr ℓ^k,
their gradients against finite differences, the bracket's Jacobi identity and the linear r-matrix relation from
the Poisson tensor, the involution, and the count of integrals against the leaves' dimension.
"""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin.sun import SunGaudinModel

SITES = [(-1.0, 2), (0.7, 1)]


def _state(model, seed=0, scale=0.7):
    return scale * np.random.default_rng(seed).normal(size=model.n_state)


def test_algebra_names_give_the_su3_model():
    for spec in ("su(3)", "su3", jg.su(3)):
        m = jg.GaudinModel(0.5, SITES, algebra=spec)
        assert isinstance(m, SunGaudinModel) and m.algebra == jg.su(3)
        assert m.n_state == 8 * 3 and m.n_integrals == (2 + 3) * 3
    m = jg.GaudinModel(0.5, SITES)  # the default: today's class, today's description
    assert type(m) is jg.GaudinModel and m.algebra == "su(2)"
    assert m.describe() == {"b": 0.5, "sites": [[-1.0, 2], [0.7, 1]]}
    assert type(jg.GaudinModel(0.5, SITES, algebra="su(2)")) is jg.GaudinModel


def test_description_round_trip():
    m = jg.GaudinModel([0.1 * a for a in range(8)], SITES, algebra="su3")
    d = m.describe()
    assert d["algebra"] == "su(3)"
    assert jg.GaudinModel.from_description(d) == m


@pytest.mark.parametrize("kwargs, match", [
    (dict(algebra="so(3)"), "unknown algebra"),
    (dict(algebra="su3", family="trigonometric"), "rational only"),
    (dict(algebra="su3", b=[1.0, 2.0]), "8 real components"),
    (dict(algebra="su3", b=np.eye(3)), "traceless and Hermitian"),
    (dict(algebra="su3", b=np.array([[0, 1j, 0], [1j, 0, 0], [0, 0, 0]])), "traceless and Hermitian"),
    (dict(algebra="su3", b=1j), "real"),
    (dict(algebra="su3", b=float("nan")), "finite"),
    (dict(algebra="su3", sites=[(0.0, 1), (0.0, 2)]), "distinct"),
])
def test_bad_input_is_refused(kwargs, match):
    kw = {"b": 0.5, "sites": SITES, **kwargs}
    with pytest.raises(jg.InvalidParameterError, match=match):
        jg.GaudinModel(kw.pop("b"), kw.pop("sites"), **kw)


def test_wrong_state_length_and_su2_only_methods():
    m = jg.GaudinModel(0.5, SITES, algebra="su3")
    with pytest.raises(jg.InvalidStateError, match="24 components"):
        m.integrals(np.zeros(9))
    for call in (lambda: m.nu(np.zeros(24), 1j), lambda: m.branch_points(np.zeros(24)),
                 lambda: m.one_point_backlund(1j), lambda: m.physical_hamiltonian()):
        with pytest.raises(jg.InvalidParameterError, match="su\\(2\\) chains only"):
            call()


def test_field_forms_agree():
    b3 = jg.GaudinModel(0.8, SITES, algebra="su3")
    v = np.zeros(8)
    v[2] = 0.8
    bv = jg.GaudinModel(v, SITES, algebra="su3")
    bm = jg.GaudinModel(0.8 * np.diag([1.0, -1.0, 0.0]), SITES, algebra="su3")
    X = _state(b3)
    assert np.array_equal(b3.field_vector, bv.field_vector)
    assert np.allclose(bm.field_vector, bv.field_vector, atol=1e-15)
    assert np.allclose(b3.integrals(X), bm.integrals(X), atol=1e-14)


def test_n2_is_the_su2_chain():
    """The general code at n = 2 against the su(2) chain: ℓ = −2iL (today's ℓ), the same integrals, gradients,
    labels, Casimirs, bracket and G_η with its weights (round-off: 1e-13 on O(1) values)."""
    rng = np.random.default_rng(3)
    for trial in range(4):
        sites = [(float(p), int(N)) for p, N in zip(rng.permutation(5)[:3] - 2.0 + 0.1 * trial,
                                                     rng.integers(1, 4, size=3), strict=True)]
        a, g = jg.GaudinModel(0.6, sites), SunGaudinModel(0.6, sites, algebra="su(2)")
        X = rng.normal(size=a.n_state)
        lam = 0.31 + 0.4j
        assert np.allclose(g.lax_matrix(X, lam), -2j * a.lax_matrix(X, lam), atol=1e-13)
        assert np.allclose(g.integrals(X), a.integrals(X), atol=1e-12)
        assert np.allclose(g.integral_gradients(X), a.integral_gradients(X), atol=1e-12)
        assert g.integral_labels() == a.integral_labels()
        assert np.array_equal(g.casimir_mask(), a.casimir_mask())
        assert np.array_equal(g.structure_constants, a.structure_constants)
        assert np.allclose(g.interpolating_hamiltonian(X, lam), a.interpolating_hamiltonian(X, lam), atol=1e-11)
        assert np.allclose(g.interpolating_weights(X, lam), a.interpolating_weights(X, lam), atol=1e-11)
        assert np.allclose(g.eigenvalue(X, lam, 0), a.nu(X, lam), atol=1e-12)
        assert np.allclose(g.eigenvalue(X, lam, 1), -a.nu(X, lam), atol=1e-12)


@pytest.mark.parametrize("n, sites", [(3, SITES), (3, [(0.0, 3)]), (4, [(-0.5, 1), (0.5, 2)])])
def test_integrals_are_contour_integrals(n, sites):
    """h^{(k)}_{j,m} = (1/2πi)∮ (λ−λ_j)^{m−1} tr ℓ^k/k dλ on a circle of radius 0.3 about λ_j (the trapezoidal rule
    with 256 points is exact to round-off for a Laurent polynomial of this degree; tolerance 1e-10 relative)."""
    m = jg.GaudinModel(0.4, sites, algebra=f"su({n})")
    X = _state(m, seed=n)
    theta = 2 * np.pi * np.arange(256) / 256
    got = dict(zip(m.integral_labels(), m.integrals(X), strict=True))
    for j, (p, N) in enumerate(sites):
        z = 0.3 * np.exp(1j * theta)
        L = m.lax_matrix(X, p + z)
        Lk = np.broadcast_to(np.eye(n), L.shape)
        for k in range(1, n + 1):
            Lk = Lk @ L
            if k < 2:
                continue
            tau = np.trace(Lk, axis1=-2, axis2=-1) / k
            for mm in range(1, k * N + 1):
                c = np.mean(tau * z**mm)  # (1/2πi)∮ z^{m−1} τ dz with dz = iz dθ
                label = f"h{j + 1},{mm}" if k == 2 else f"t{k}_h{j + 1},{mm}"
                assert got[label] == pytest.approx(c.real, rel=1e-10, abs=1e-10)
                assert abs(c.imag) < 1e-10


def test_gradients_by_finite_differences():
    """Central differences with h = 1e-5 on cubic polynomials: error O(h²) ~ 1e-9 (tolerance 1e-7)."""
    m = jg.GaudinModel(0.4, SITES, algebra="su3")
    X = _state(m, seed=5)
    h = 1e-5
    fd = np.array([(m.integrals(X + h * e) - m.integrals(X - h * e)) / (2 * h) for e in np.eye(m.n_state)]).T
    assert np.allclose(m.integral_gradients(X), fd, atol=1e-7)


def test_lax_hermitian_on_the_real_axis_and_conjugation():
    m = jg.GaudinModel([0.3, -0.2, 0.5, 0, 0, 0.1, 0, -0.4], SITES, algebra="su3")
    X = _state(m)
    L = m.lax_matrix(X, 0.2)
    assert np.allclose(L, np.conj(L.T), atol=1e-15)
    assert np.allclose(m.lax_matrix(X, 0.2 - 0.5j), np.conj(m.lax_matrix(X, 0.2 + 0.5j).T), atol=1e-15)
    assert np.allclose(m.lax_matrix(X, 1e9), m.field_matrix, atol=1e-8)  # ℓ → b at infinity (1/λ terms ~ 1e-9)


def test_bracket_is_lie_poisson():
    """Jacobi identity of the structure constants (exact small rationals: 1e-13) and antisymmetry of Π."""
    m = jg.GaudinModel(0.0, [(0.0, 2), (1.0, 1)], algebra="su3")
    c = m.structure_constants
    jac = np.einsum("ijl,lkm->ijkm", c, c)
    assert np.allclose(jac + np.transpose(jac, (1, 2, 0, 3)) + np.transpose(jac, (2, 0, 1, 3)), 0, atol=1e-13)
    P = m.poisson_tensor(_state(m))
    assert np.allclose(P, -P.T, atol=0)


@pytest.mark.parametrize("n", [2, 3])
def test_linear_r_matrix_relation(n):
    """{ℓ(λ) ⊗ ℓ(μ)} = [iΠ/(λ−μ), ℓ(λ)⊗1 + 1⊗ℓ(μ)] with Π the permutation, from the Poisson tensor (1e-12)."""
    m = SunGaudinModel([0.2, -0.3, 0.5, 0.1, 0, 0, 0.2, 0.4][: n * n - 1], [(0.0, 2), (1.3, 1)], algebra=f"su({n})")
    X = _state(m, seed=7)
    lam, mu = 0.4 + 0.3j, -0.7 + 0.2j
    e = np.eye(m.n_state)
    dL = np.array([m.lax_matrix(v, lam) - m.field_matrix for v in e])  # linear in X
    dM = np.array([m.lax_matrix(v, mu) - m.field_matrix for v in e])
    P = m.poisson_tensor(X)
    lhs = np.einsum("IJ,Iij,Jkl->ikjl", P, dL, dM).reshape(n * n, n * n)
    perm = np.einsum("il,kj->ikjl", np.eye(n), np.eye(n)).reshape(n * n, n * n)
    r = 1j * perm / (lam - mu)
    s = np.kron(m.lax_matrix(X, lam), np.eye(n)) + np.kron(np.eye(n), m.lax_matrix(X, mu))
    assert np.allclose(lhs, r @ s - s @ r, atol=1e-12)
    assert not np.allclose(lhs, -(r @ s - s @ r), atol=1e-6)  # the sign of r is fixed


@pytest.mark.parametrize("n, sites, b", [
    (3, SITES, [0.3, -0.2, 0.5, 0.1, -0.1, 0.1, 0.2, -0.4]),
    (3, [(0.0, 1), (1.0, 1), (2.5, 1)], 0.8),
    (3, [(0.0, 3)], [0.3, -0.2, 0.5, 0.1, -0.1, 0.1, 0.2, -0.4]),
    (4, [(0.0, 1), (1.0, 2)], list(np.random.default_rng(2).normal(size=15))),
])
def test_involution_and_count(n, sites, b):
    """{h_I, h_J} = 0 (1e-11 relative to |∇h|²), every integral independent, the Casimirs span the kernel of Π
    and the non-Casimirs are half the leaf dimension: ½ n(n−1) M."""
    m = jg.GaudinModel(b, sites, algebra=f"su({n})")
    X = _state(m, seed=11)
    g = m.integral_gradients(X)
    P = m.poisson_tensor(X)
    scale = np.max(np.abs(g)) ** 2 * np.max(np.abs(P))
    assert np.max(np.abs(g @ P @ g.T)) < 1e-12 * scale
    cas = m.casimir_mask()
    assert np.max(np.abs(g[cas] @ P)) < 1e-12 * scale  # Casimirs
    rank_all, rank_cas, rank_P = (np.linalg.matrix_rank(a, tol=1e-9 * np.max(np.abs(a))) for a in (g, g[cas], P))
    assert rank_all == m.n_integrals
    assert rank_cas == m.n_state - rank_P
    assert rank_all - rank_cas == rank_P // 2 == n * (n - 1) * m.M // 2


def test_hamiltonian_vector_field_keeps_integrals():
    """Ẋ = Π∇H of H = Σ w h is tangent to every level set (exactly: involution; 1e-12)."""
    m = jg.GaudinModel(0.5, SITES, algebra="su3")
    X = _state(m)
    H = m.hamiltonian(np.random.default_rng(1).normal(size=m.n_integrals))
    assert np.max(np.abs(m.integral_gradients(X) @ H.vector_field(X))) < 1e-11


def test_a_degenerate_field_loses_an_integral():
    """b = 0.5 λ_3 = diag(½, −½, 0, 0) in su(4) has a repeated eigenvalue: its stabiliser U(2) × U(1) is larger than
    the torus, and one of the 27 integrals becomes dependent (a generic b: none, test above); docs/sun.md."""
    m = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 2)], algebra="su4")
    g = m.integral_gradients(_state(m, seed=11))
    assert np.linalg.matrix_rank(g, tol=1e-9 * np.max(np.abs(g))) == m.n_integrals - 1


def test_pickle_and_replace_keep_the_class():
    """Dask ships models by pickle; dataclasses.replace rebuilds them: both keep the su(n) class and the su(2) one."""
    import dataclasses
    import pickle

    m = jg.GaudinModel(0.5, SITES, algebra="su3")
    for x in (m, jg.GaudinModel(0.5, SITES), m.two_point_backlund(0.3 + 0.2j, branch=2)):
        y = pickle.loads(pickle.dumps(x))
        assert y == x and type(y) is type(x)
    assert type(dataclasses.replace(m, b=1.0)) is SunGaudinModel
