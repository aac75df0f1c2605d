"""Jet constants ``c`` of eq. (lax) as a site option of ``GaudinModel`` (issue 33 item 1;
``jetgaudin.gaudin._site_constants``).

The derivation (a site with constants is the reduced site (lax2) in ``Y = T^T y``, a Poisson isomorphism of ``g^(N)``
for ``c_1 != 0``) is checked two independent ways: numerically (the bracket pulled back by ``y -> Y`` against (LP) at
random points) and symbolically (SymPy, ``T`` from the paper's partition formula, not from
``jetgaudin.lax.jet_coefficients``).  The model with constants is then checked against code that does not conjugate:
the top's own ``c`` route (``jetgaudin.spectral``: integrals, gradients, ``ν²`` from the Lax coefficients), the direct
sum ``ξ(λ) = b e_3 + Σ_s Σ_i f_i(λ − λ_s) y_i`` with ``f_i`` from ``jetgaudin.lax.jet_function``, the involution of the
integrals under the model's (LP) bracket, and, for the maps, the time-1 flow of ``G_η`` integrated by DOP853."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.algebra import structure_constants
from jetgaudin.exact_chain import ChainExactFlow
from jetgaudin.lax import jet_coefficients, jet_function
from jetgaudin.maps import map_from_description

B = 0.9
C4 = (-0.7, 0.3, 1.1)  # c_1..c_3 of an order-4 site: generic (no zero, c_1 != -1)


def _state(n, seed=0, scale=0.6):
    return np.random.default_rng(seed).standard_normal(n) * scale


def _paper_T(N, c):
    """``T[i, n]`` from the paper's partition formula (Section 2) with SymPy: ``f_i = Σ_{Σ k q_k = i} Π c_k^{q_k}/q_k!
    (d/dλ)^{|q|} f_0``, ``f_0 = 1/λ``, read off as the coefficients of ``λ^{-(n+1)}`` (independent of
    ``jet_coefficients``, which convolves the series ``c(ε)^n``)."""
    import sympy as sp

    lam = sp.Symbol("lam")
    T = sp.zeros(N, N)
    for i in range(N):
        f = sp.Integer(0)
        if i == 0:
            f = 1 / lam
        for q in itertools.product(*[range(i // k + 1) for k in range(1, i + 1)]):
            if i == 0 or sum((k + 1) * qk for k, qk in enumerate(q)) != i:
                continue
            coef = sp.Integer(1)
            for k, qk in enumerate(q):
                coef *= c[k] ** qk / sp.factorial(qk)
            f += coef * sp.diff(1 / lam, lam, sum(q))
        f = sp.expand(f)
        for n in range(N):
            T[i, n] = f.coeff(lam, -(n + 1))
    return T


@pytest.mark.parametrize("N", [2, 3, 4, 5])
def test_jet_coefficients_are_the_papers_partition_formula(N):
    """``jetgaudin.lax.jet_coefficients`` (the matrix every route with constants uses) against the printed partition
    formula evaluated by SymPy at dyadic constants (exact in binary: 1e-12 only absorbs the float products of up to
    ``N - 1`` factors of size <= 1.25)."""
    import sympy as sp

    c = [sp.Rational(v) for v in ("-3/4", "1/2", "5/4", "-1/4")[: N - 1]]
    T = np.array(_paper_T(N, c).tolist(), dtype=float)
    assert np.abs(jet_coefficients(N, [float(v) for v in c]) - T).max() < 1e-12
    assert np.array_equal(jet_coefficients(N), np.eye(N))  # the reduction (lax2)


def _pulled_back_defect(N, c, y):
    """``max |J Π(y) J^T − Π_LP(J y)|`` for ``J = T^T ⊗ 1_3`` (``Y = J y``)."""
    sc = structure_constants(N)
    J = np.kron(jet_coefficients(N, c).T, np.eye(3))
    Pi = np.einsum("ijk,k->ij", sc, y)
    Y = J @ y
    return np.abs(J @ Pi @ J.T - np.einsum("ijk,k->ij", sc, Y)).max()


@pytest.mark.parametrize("N", [2, 3, 4, 5])
def test_the_change_to_Y_is_a_poisson_map_numerically(N):
    """The bracket of the ``y`` (LP) pushed forward by ``Y = T^T y`` is (LP) in the ``Y`` at 5 random points and random
    ``c`` (``c_1 = 0`` included: a homomorphism, not an isomorphism).  Entries O(1)-O(10): 1e-12 is round-off.  The
    transposed matrix (``Y = T y``, the bug it is for) is not Poisson: checked to fail by 1e-2 or more."""
    rng = np.random.default_rng(N)
    for _ in range(5):
        c = rng.uniform(-1.5, 1.5, N - 1)
        y = rng.standard_normal(3 * N)
        assert _pulled_back_defect(N, c, y) < 1e-12
        assert _pulled_back_defect(N, np.r_[0.0, c[1:]], y) < 1e-12
        if N >= 3:  # T^T instead of T: the bug
            sc = structure_constants(N)
            J = np.kron(jet_coefficients(N, c), np.eye(3))
            bad = np.abs(J @ np.einsum("ijk,k->ij", sc, y) @ J.T - np.einsum("ijk,k->ij", sc, J @ y)).max()
            assert bad > 1e-2


@pytest.mark.parametrize("N", [2, 3, 4])
def test_the_change_to_Y_is_a_poisson_isomorphism_symbolically(N):
    """SymPy, symbolic ``c_k`` and ``y``: ``{Y_n^a, Y_m^b} = ε_abc Y_{n+m}^c`` (zero for ``n + m >= N``) from (LP) and
    bilinearity, with ``T`` from the partition formula; ``det T = Π_n (−c_1)^n``: invertible iff ``c_1 != 0``."""
    import sympy as sp

    c = sp.symbols(f"c1:{N}")
    y = [[sp.Symbol(f"y{i}_{a}") for a in range(3)] for i in range(N)]
    T = _paper_T(N, c)
    Y = [[sum(T[i, n] * y[i][a] for i in range(N)) for a in range(3)] for n in range(N)]

    def eps(a, b, k):
        return sp.LeviCivita(a, b, k)

    for n, m in itertools.product(range(N), repeat=2):
        for a, b in itertools.product(range(3), repeat=2):
            lhs = sum(T[i, n] * T[j, m] * eps(a, b, k) * y[i + j][k]
                      for i in range(N) for j in range(N) for k in range(3) if i + j < N)
            rhs = sum(eps(a, b, k) * Y[n + m][k] for k in range(3)) if n + m < N else 0
            assert sp.expand(lhs - rhs) == 0
    assert sp.expand(T.det() - math.prod((-c[0]) ** n for n in range(N))) == 0


@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_as_model_with_constants_equals_the_tops_c_code(N):
    """``IntegralHamiltonian(b, w, c).as_model()``: integrals, gradients, vector field, ``ν²`` and the Lax matrix equal
    the top's own ``c`` route (``jetgaudin.spectral``, ``jetgaudin.lax``; no conjugation there) to 1e-13 on O(1)
    states (round-off; a wrong or transposed ``T`` is O(1e-1))."""
    rng = np.random.default_rng(10 + N)
    c = list(C4[: N - 1])
    X = rng.standard_normal((4, 3 * N)) * 0.6
    w = rng.standard_normal(2 * N)
    Ht = jg.IntegralHamiltonian(B, w, c)
    Hm = Ht.as_model()
    model = Hm.model
    assert model.sites == ((0.0, N),) and (model.constants is None) == (N == 1)
    assert np.abs(model.integrals(X) - jg.integrals(X, B, c)).max() < 1e-13
    assert np.abs(Hm.gradient(X) - Ht.gradient(X)).max() < 1e-13
    assert np.abs(Hm.vector_field(X) - Ht.vector_field(X)).max() < 1e-13
    assert np.abs(Hm.record_integrals(X) - Ht.record_integrals(X)).max() < 1e-13  # the compiled record pass
    lam = 0.4 + 0.7j
    assert np.abs(model.nu_squared(X, lam) - jg.nu_squared(lam, X, B, c)).max() < 1e-13
    assert np.abs(model.lax_matrix(X, lam) - jg.lax_matrix(lam, X, B, c)).max() < 1e-13


def test_the_reduction_and_the_constructions_agree():
    """The three spellings give one model; ``c = (−1, 0, …)`` is the reduction (lax2), i.e. no constants; the
    description round-trips; a model with constants is not the top's route (``is_top`` false)."""
    a = jg.GaudinModel(B, [(0.0, 4, C4), (1.5, 2)])
    b = jg.GaudinModel(B, [(0.0, 4), (1.5, 2)], constants=[C4, None])
    assert a == b and a.constants == (C4, None) and hash(a) == hash(b)
    assert jg.GaudinModel(B, [(0.0, 3, (-1, 0)), (1.5, 2)]) == jg.GaudinModel(B, [(0.0, 3), (1.5, 2)])
    assert jg.GaudinModel(B, [(0.0, 1, ())]).constants is None
    assert jg.GaudinModel.from_description(a.describe()) == a
    assert "constants" not in jg.GaudinModel(B, [(0.0, 4)]).describe()
    top = jg.GaudinModel(B, [(0.0, 3, (-0.5, 0.2))])
    assert not top.is_top
    with pytest.raises(jg.InvalidParameterError, match="not a top.*with jet constants"):
        top.as_top()


def test_the_refusals_name_the_quantity_and_the_fix():
    with pytest.raises(jg.InvalidParameterError, match="c_1 = 0 makes the jet matrix T singular"):
        jg.GaudinModel(B, [(0.0, 3, (0.0, 1.0))])
    with pytest.raises(jg.InvalidParameterError, match="must be real"):
        jg.GaudinModel(B, [(0.0, 3, (-1.0, 1j))])
    with pytest.raises(jg.InvalidParameterError, match="exactly N-1 = 2"):
        jg.GaudinModel(B, [(0.0, 3, (-1.0,))])
    with pytest.raises(jg.InvalidParameterError, match="not both"):
        jg.GaudinModel(B, [(0.0, 3, (-1.0, 0.5))], constants=[None])
    with pytest.raises(jg.InvalidParameterError, match="one entry per site"):
        jg.GaudinModel(B, [(0.0, 3), (1.0, 1)], constants=[(-1.0, 0.5)])
    with pytest.raises(jg.InvalidParameterError, match="su\\(3\\) models take no jet constants"):
        jg.GaudinModel(B, [(0.0, 3)], algebra="su(3)", constants=[(-0.5, 0.2)])
    model = jg.GaudinModel(B, [(0.0, 3, (-0.5, 0.2)), (1.5, 1)])
    with pytest.raises(jg.InvalidParameterError, match="model.two_point_backlund"):
        jg.ChainTwoPointBacklund(model, 0.5 + 0.4j)
    with pytest.raises(jg.InvalidParameterError, match="method='exact'"):
        ChainExactFlow(model.hamiltonian(np.ones(model.n_integrals)), 0.1)


def _two_site():
    return jg.GaudinModel(B, [(0.0, 3, (-0.6, 0.45)), (1.7, 2, (1.3,))])


def test_multi_site_integrals_are_the_principal_parts_of_nu2_built_directly():
    """``ν²(λ) − b² = Σ_{s,m} h_{s,m} (λ − λ_s)^{-m}`` (module doc of ``gaudin.model``) with ``ν² = ⟨ξ, ξ⟩`` and
    ``ξ(λ) = b e_3 + Σ_s Σ_i f_i(λ − λ_s) y_i^{(s)}`` summed here with ``jetgaudin.lax.jet_function`` (the top's
    ``f_i``, no conjugation), at 6 points ``λ``: 1e-12 on O(1)-O(10) values (round-off)."""
    model = _two_site()
    X = _state(model.n_state, 3)
    y = X.reshape(model.M, 3)
    h = model.integrals(X)
    for lam in (0.3 + 0.5j, -0.8 + 0.2j, 2.2 - 0.4j, 1.1 + 1.3j, -2.0 + 0.1j, 0.9 - 0.9j):
        xi = np.array([0.0, 0.0, B], dtype=complex)
        for o, (p, N), c in zip(model.offsets, model.sites, model.constants, strict=True):
            for i in range(N):
                xi = xi + jet_function(i, lam - p, N, c) * y[o + i]
        nu2 = np.sum(xi * xi)
        basis = [(lam - p) ** (-m) for p, N in model.sites for m in range(1, 2 * N + 1)]
        assert abs(nu2 - B * B - np.dot(h, basis)) < 1e-12
        assert abs(model.nu_squared(X, lam) - nu2) < 1e-12


@pytest.mark.parametrize("family", ["rational", "trigonometric"])
def test_the_integrals_commute_under_the_models_bracket(family):
    """``{h_I, h_J} = ∇h_I · Π(X) ∇h_J = 0`` with the sites' own (LP) bracket in the ``y`` (not conjugated): the forms
    ``S^T q S`` are in involution because ``y → Y`` is Poisson; with ``S`` transposed they are not (O(1e-1)).  1e-12:
    round-off on O(1) gradients."""
    model = jg.GaudinModel(B, [(0.0, 3, (-0.6, 0.45)), (1.1, 2, (1.3,))], family=family)
    for seed in range(3):
        X = _state(model.n_state, seed)
        G = model.integral_gradients(X)
        Pi = model.poisson_tensor(X)
        assert np.abs(G @ Pi @ G.T).max() < 1e-12


def _flow_of_G(model, X, eta):
    H = model.interpolating_flow_hamiltonian(X, eta)
    return jg.integrate(H, X, 1.0, rtol=1e-13, atol=1e-13).X[-1]


@pytest.mark.parametrize("family", ["rational", "trigonometric"])
def test_the_two_point_map_is_the_time_one_flow_of_G_eta(family):
    """The conjugated two-point map ``P^{-1} B(P X)`` against the time-1 flow of ``G_η`` of the model with constants,
    integrated by DOP853 at rtol 1e-13 with the model's own vector field (no conjugation of states): agreement 1e-9
    (the integrator's global error over time 1; a transposed or wrong ``T`` in the conjugation is O(1e-1)).  The map
    keeps the integrals to 1e-12 (round-off), its inverse undoes it, and its description round-trips."""
    model = jg.GaudinModel(B, [(0.0, 3, (-0.6, 0.45)), (1.7, 2, (1.3,))], family=family)
    eta = 0.6 + 0.35j
    Bm = model.two_point_backlund(eta, backend="numpy")
    X = _state(model.n_state, 5, 0.5)
    X1 = Bm(X)
    assert np.abs(X1 - _flow_of_G(model, X, eta)).max() < 1e-9
    assert np.abs(model.integrals(X1) - model.integrals(X)).max() < 1e-12
    assert np.abs(Bm.inverse()(X1) - X).max() < 1e-12
    again = map_from_description(Bm.describe())
    assert np.abs(again(X) - X1).max() == 0.0  # the same map, the same arithmetic
    orbit = Bm.iterate(X, 4, save_every=2)
    assert orbit.shape == (3, model.n_state) and np.abs(orbit[1] - Bm(X1)).max() < 1e-12


def test_the_two_point_map_is_poisson():
    """``DB Π(X) DB^T = Π(B X)``, ``DB`` by central differences (h = 1e-6: truncation 1e-12, rounding 1e-10 on
    O(1) entries; tolerance 1e-6)."""
    model = _two_site()
    Bm = model.two_point_backlund(0.6 + 0.35j, backend="numpy")
    X = _state(model.n_state, 7, 0.5)
    h, n = 1e-6, model.n_state
    D = np.stack([(Bm(X + h * e) - Bm(X - h * e)) / (2 * h) for e in np.eye(n)], axis=1)
    assert np.abs(D @ model.poisson_tensor(X) @ D.T - model.poisson_tensor(Bm(X))).max() < 1e-6


def test_the_one_point_map_keeps_the_integrals():
    """The complex one-point map, conjugated: the integrals of the image (complex) equal the start's to 1e-12."""
    model = _two_site()
    Bm = model.one_point_backlund(0.6 + 0.35j, backend="numpy")
    X = _state(model.n_state, 9, 0.5)
    X1 = Bm(X)
    assert np.abs(model.integrals(X1) - model.integrals(X)).max() < 1e-12


def test_solve_exact_with_constants_equals_dop853():
    """``jg.solve(method="exact")`` on a model with constants (the route table conjugates the reduced model's exact
    flow) against DOP853 at rtol 1e-13 over t = 0.5: 1e-9 (the adaptive integrator's error)."""
    model = jg.GaudinModel(B, [(0.0, 2, (0.8,)), (1.3, 1)])
    H = model.hamiltonian(np.r_[0.3, 0.7, 0.0, 0.0, 0.4, 0.0])
    X = _state(model.n_state, 11, 0.5)
    ex = jg.solve(H, X, (0.0, 0.5), dt=0.25, method="exact", backend="numpy")
    ref = jg.solve(H, X, (0.0, 0.5), method="dop853", rtol=1e-13, atol=1e-13)
    assert np.abs(ex.X[-1] - ref.X[-1]).max() < 1e-9


def test_a_run_of_the_conjugated_map_is_recorded_and_described(tmp_path):
    """The run layer records the map of a model with constants like any map: completed, ``run.json`` holds its
    description (kind ``site_constants``, which rebuilds it) and the model's integral names; the recorded orbit equals
    the map's own ``iterate`` to 1e-12 (chunked: one conversion to ``Y`` and back per chunk, round-off)."""
    from jetgaudin import run as rl

    model = _two_site()
    Bm = model.two_point_backlund(0.6 + 0.35j, backend="numpy")
    X0 = _state(model.n_state, 13, 0.5)
    res = rl.start(rl.RunSpec(Bm, X0, 12, 3, checkpoint_seconds=0.0), tmp_path / "o", max_chunk_steps=5)
    assert res.state is rl.RunStatus.COMPLETED
    d = rl.load(tmp_path / "o")
    assert np.abs(d.X - Bm.iterate(X0, 12)[d.n]).max() < 1e-12
    run = rl.read_run(tmp_path / "o")
    assert run["map"] == Bm.describe() and run["integral_names"] == model.integral_labels()
    assert map_from_description(run["map"]) == Bm


def test_the_exact_flow_of_the_top_with_constants_equals_the_tops_c_flow():
    """One site with constants (``as_model``): ``solve(method="exact")`` (the reduced model's exact step, conjugated)
    against DOP853 on the top's own ``IntegralHamiltonian(b, w, c)`` (its ``c`` route: no model, no conjugation) at
    rtol 1e-13 over t = 0.6: 1e-9 (the adaptive integrator's error)."""
    Ht = jg.IntegralHamiltonian(B, [0.2, 0.5, -0.3, 0.0, 0.0, 0.0], c=[0.7, -0.4])
    Hm = Ht.as_model()
    X = _state(9, 17, 0.5)
    ex = jg.solve(Hm, X, (0.0, 0.6), dt=0.3, method="exact", backend="numpy")
    ref = jg.integrate(Ht, X, 0.6, rtol=1e-13, atol=1e-13)
    assert np.abs(ex.X[-1] - ref.X[-1]).max() < 1e-9
    assert np.abs(Ht.record_integrals(ex.X) - Ht.record_integrals(X)).max() < 1e-12  # the top's c integrals
