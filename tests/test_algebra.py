"""Tests of jetgaudin.algebra: the Lie--Poisson algebra g^(N) of eq. (LP), N = 1..5.

Independent routes: the structure constants are rebuilt here literally from (LP) with a
Levi-Civita symbol computed from permutation parity; gradients of the Casimirs are checked
against central differences; the N = 3 bracket against the formula displayed in Section 3.
"""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import jetgaudin as jg
from jetgaudin.algebra import casimir_gradients

# Rounding: every quantity below is a sum of at most ~3N^2 products of O(|X|) numbers, so the
# rounding error is a few 1e-16 relative to the scale of the terms; RTOL = 1e-12 leaves a factor
# > 1000 of margin and still catches any wrong coefficient (which gives an O(1) relative error).
RTOL = 1e-12

finite = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)


@st.composite
def states(draw, n_min=1, n_max=5):
    N = draw(st.integers(n_min, n_max))
    return draw(arrays(np.float64, 3 * N, elements=finite))


def levi_civita(a, b, c):
    """epsilon_{abc} with epsilon_{123} = 1, from the parity of the permutation (independent of the code)."""
    if len({a, b, c}) < 3:
        return 0
    perm = [a, b, c]
    inversions = sum(1 for i in range(3) for j in range(i + 1, 3) if perm[i] > perm[j])
    return -1 if inversions % 2 else 1


def literal_structure_constants(N):
    """(LP): {y_i^a, y_j^b} = eps^{ab}_c y^c_{i+j} if i + j < N, else 0; index I = 3 i + a."""
    c = np.zeros((3 * N, 3 * N, 3 * N))
    for i, j, a, b, g in itertools.product(range(N), range(N), range(3), range(3), range(3)):
        if i + j < N:
            c[3 * i + a, 3 * j + b, 3 * (i + j) + g] = levi_civita(a, b, g)
    return c


def literal_casimirs(X):
    """Prop. 2 as printed: C_k = sum_{i=k-1}^{N-1} <y_i, y_{N+k-i-2}>, k = 1..N."""
    N = len(X) // 3
    y = X.reshape(N, 3)
    return np.array([sum(y[i] @ y[N + k - i - 2] for i in range(k - 1, N)) for k in range(1, N + 1)])


@pytest.mark.parametrize("N", range(1, 6))
def test_structure_constants_are_LP_exactly(N):
    # exact: both are arrays of integers 0, +-1
    assert np.array_equal(jg.structure_constants(N), literal_structure_constants(N))


@pytest.mark.parametrize("N", range(1, 6))
def test_structure_constants_antisymmetric_and_jacobi_exact(N):
    c = jg.structure_constants(N)
    assert np.array_equal(c, -np.swapaxes(c, 0, 1))
    # Jacobi for a linear Poisson structure: sum_L c^{IJ}_L c^{LK}_M + cyclic(I, J, K) = 0 (integers: exact)
    jac = np.einsum("ijl,lkm->ijkm", c, c)
    total = jac + np.transpose(jac, (1, 2, 0, 3)) + np.transpose(jac, (2, 0, 1, 3))
    assert np.array_equal(total, np.zeros_like(total))


def test_structure_constants_read_only_and_N3_brackets():
    c = jg.structure_constants(3)
    with pytest.raises(ValueError):
        c[0, 0, 0] = 1.0
    # (algebra), N = 3: {y_1^1, y_1^2} = y_2^3 (i.e. {x^1, x^2} = z^3), {y_1^a, y_2^b} = 0, {y_2, y_2} = 0
    assert c[3, 4, 8] == 1.0 and np.count_nonzero(c[3, 4]) == 1
    assert not np.any(c[3:6, 6:9]) and not np.any(c[6:9, 6:9]) and not np.any(c[6:9, 3:6])


@given(states())
def test_poisson_tensor_antisymmetric_and_linear(X):
    P = jg.poisson_tensor(X)
    N = len(X) // 3
    assert P.shape == (3 * N, 3 * N)
    # each entry of Pi is a single signed coordinate, so Pi = -Pi^T holds exactly
    assert np.array_equal(P, -P.T)
    assert np.allclose(P, np.einsum("ijk,k->ij", literal_structure_constants(N), X), rtol=0, atol=0)


@given(states())
def test_jacobi_identity_at_random_X(X):
    """{X_I, {X_J, X_K}} + cyclic = 0, with the outer bracket computed by jg.bracket."""
    N = len(X) // 3
    n = 3 * N
    c = jg.structure_constants(N)
    E = np.eye(n)
    # {X_J, X_K} = Pi_JK(X) is linear with gradient c[J, K, :]; {X_I, Pi_JK} = bracket(e_I, c[J, K], X)
    inner = jg.bracket(E[:, None, None, :], c[None, :, :, :], X)  # (I, J, K)
    total = inner + np.transpose(inner, (1, 2, 0)) + np.transpose(inner, (2, 0, 1))
    scale = 1.0 + np.max(np.abs(X))
    assert np.max(np.abs(total)) <= RTOL * scale


@given(states(), st.integers(0, 2**32 - 1))
def test_jacobi_identity_for_random_polynomials(X, seed):
    """Jacobi for three random quadratic functions f(X) = X^T A X / 2 + g.X (gradients A X + g)."""
    rng = np.random.default_rng(seed)
    n = len(X)
    fs = []
    for _ in range(3):
        A = rng.normal(size=(n, n))
        fs.append((A + A.T, rng.normal(size=n)))
    c = jg.structure_constants(n // 3)

    def grad(f, X):
        return f[0] @ X + f[1]

    def grad_bracket(f, g, X):
        # gradient of {f, g}(X) = grad f^T Pi(X) grad g:  Hess f Pi grad g - Hess g Pi grad f + grad f^T c grad g
        P = jg.poisson_tensor(X)
        return f[0] @ P @ grad(g, X) - g[0] @ P @ grad(f, X) + np.einsum("i,ijk,j->k", grad(f, X), c, grad(g, X))

    f, g, h = fs
    terms = [
        jg.bracket(grad(f, X), grad_bracket(g, h, X), X),
        jg.bracket(grad(g, X), grad_bracket(h, f, X), X),
        jg.bracket(grad(h, X), grad_bracket(f, g, X), X),
    ]
    scale = sum(abs(t) for t in terms) + np.prod([np.linalg.norm(f[0]) for f in fs]) * (1 + np.linalg.norm(X)) ** 4
    assert abs(sum(terms)) <= RTOL * scale


@given(states())
def test_casimirs_match_prop2_literally(X):
    C = jg.casimirs(X)
    ref = literal_casimirs(X)
    scale = 1.0 + np.sum(X**2)
    assert np.max(np.abs(C - ref)) <= RTOL * scale


@given(arrays(np.float64, 9, elements=finite))
def test_casimirs_N3_section3(X):
    """Section 3: C^(1) = <y0,y2> + |y1|^2/2, C^(2) = <y1,y2>, C^(3) = |y2|^2;
    (cas): C_1 = 2C^(1), C_2 = 2C^(2), C_3 = C^(3)."""
    y0, y1, y2 = X[0:3], X[3:6], X[6:9]
    C1, C2, C3 = y0 @ y2 + 0.5 * y1 @ y1, y1 @ y2, y2 @ y2
    scale = 1.0 + np.sum(X**2)
    assert np.allclose(jg.casimirs(X), [2 * C1, 2 * C2, C3], rtol=0, atol=RTOL * scale)


@given(states())
def test_casimir_gradients_finite_differences(X):
    # central differences are exact for quadratic functions; rounding error ~ eps |C| / h with h = 0.1,
    # i.e. ~1e-14 (1 + |X|^2): tolerance 1e-11 relative to 1 + |X|^2
    n = len(X)
    h = 0.1
    E = np.eye(n)
    fd = np.stack([(jg.casimirs(X + h * E[j]) - jg.casimirs(X - h * E[j])) / (2 * h) for j in range(n)], axis=-1)
    assert np.allclose(casimir_gradients(X), fd, rtol=0, atol=1e-11 * (1 + np.sum(X**2)))


@given(states())
def test_casimirs_central(X):
    """Pi(X) grad C_k = 0: {C_k, X_I} = 0 for every coordinate (Prop. 2)."""
    n = len(X)
    h = 0.1
    E = np.eye(n)
    # gradient from central differences (exact for quadratics) so the check does not rely on casimir_gradients
    fd = np.stack([(jg.casimirs(X + h * E[j]) - jg.casimirs(X - h * E[j])) / (2 * h) for j in range(n)], axis=-1)
    P = jg.poisson_tensor(X)
    scale = (1 + np.max(np.abs(X))) ** 2
    assert np.max(np.abs(fd @ P.T)) <= 1e-11 * scale
    assert np.max(np.abs(jg.hamiltonian_vector_field(casimir_gradients(X), X))) <= RTOL * scale


@given(arrays(np.float64, 9, elements=finite), arrays(np.float64, (2, 9), elements=finite))
def test_bracket_N3_matches_section3_formula(X, G):
    """{f, g} = <y0, f0 ^ g0> + <y1, f0 ^ g1 + f1 ^ g0> + <y2, f0 ^ g2 + f2 ^ g0> + <y2, f1 ^ g1> (Section 3)."""
    y0, y1, y2 = X[0:3], X[3:6], X[6:9]
    f0, f1, f2 = G[0, 0:3], G[0, 3:6], G[0, 6:9]
    g0, g1, g2 = G[1, 0:3], G[1, 3:6], G[1, 6:9]
    cr = np.cross
    ref = y0 @ cr(f0, g0) + y1 @ (cr(f0, g1) + cr(f1, g0)) + y2 @ (cr(f0, g2) + cr(f2, g0)) + y2 @ cr(f1, g1)
    scale = 1 + np.sum(np.abs(X)) * np.sum(np.abs(G[0])) * np.sum(np.abs(G[1]))
    assert abs(jg.bracket(G[0], G[1], X) - ref) <= RTOL * scale


@given(states(), st.integers(0, 2**32 - 1))
def test_hamiltonian_vector_field_is_bracket_with_coordinates(X, seed):
    """Xdot_I = {X_I, H}: the vector field Pi grad H generates df/dt = {f, H}."""
    g = np.random.default_rng(seed).normal(size=len(X))
    E = np.eye(len(X))
    V = jg.hamiltonian_vector_field(g, X)
    ref = np.array([jg.bracket(E[i], g, X) for i in range(len(X))])
    assert np.allclose(V, ref, rtol=0, atol=RTOL * (1 + np.sum(np.abs(X)) * np.sum(np.abs(g))))


def test_vectorised_over_leading_axes(rng):
    """Style rule 2: an ensemble member equals the single evaluation bit for bit."""
    X = rng.normal(size=(4, 5, 12))
    P = jg.poisson_tensor(X)
    C = jg.casimirs(X)
    g = rng.normal(size=(4, 5, 12))
    B = jg.bracket(g, g[::-1], X)
    for i, j in [(0, 0), (3, 4), (2, 1)]:
        assert np.array_equal(P[i, j], jg.poisson_tensor(X[i, j]))
        assert np.array_equal(C[i, j], jg.casimirs(X[i, j]))
        assert np.array_equal(B[i, j], jg.bracket(g[i, j], g[::-1][i, j], X[i, j]))


@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_casimir_gradients_of_complex_states(N):
    # the one-point map's states are complex and its Casimirs are checked there: the gradients accept complex states
    # and, the Casimirs being quadratic, are complex-linear in X: grad C(Xr + i Xi) = grad C(Xr) + i grad C(Xi)
    # exactly up to the rounding of one complex product per term (1e-14 relative).  Kills the mutant
    # allow_complex=True -> False in casimir_gradients (docs/mutation.md).
    rng = np.random.default_rng(N)
    Xr, Xi = rng.normal(size=(2, 5, 3 * N))
    got = casimir_gradients(Xr + 1j * Xi)
    want = casimir_gradients(Xr) + 1j * casimir_gradients(Xi)
    assert got.dtype.kind == "c"
    assert np.max(np.abs(got - want)) <= 1e-14 * (1 + np.max(np.abs(want)))
