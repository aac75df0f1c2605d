"""Tests of jetgaudin.systems: (em), (H), the material point, the Lax pair, the Lagrange top (N = 2).

(em) and the other displayed equations are written out literally here with np.cross and compared
with Pi(X) grad H (gradient typed by hand) and with the package.
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import jetgaudin as jg
from jetgaudin.systems import material_point_rhs, twisted_top_rhs

# The right-hand sides are sums of a few products of O(1) numbers: rounding ~1e-15 relative to
# (1 + |X|)^2 (1 + |b|); RTOL = 1e-12 leaves > 100x margin and any wrong sign gives an O(1) error.
RTOL = 1e-12

finite = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)
fields = st.floats(0.1, 3.0) | st.floats(-3.0, -0.1)
SIG = jg.lax.SIGMA


def scale_of(X, b):
    return (1 + np.sum(np.abs(X))) ** 2 * (1 + abs(b))


@given(arrays(np.float64, 9, elements=finite), fields)
def test_em_is_pi_grad_H2_half(X, b):
    """(em): y' = b ^ x, x' = y ^ x + b ^ z, z' = y ^ z equals Pi grad(H_2/2) and twisted_top_rhs."""
    y, x, z = X[0:3], X[3:6], X[6:9]
    bv = np.array([0.0, 0.0, b])
    em = np.concatenate([np.cross(bv, x), np.cross(y, x) + np.cross(bv, z), np.cross(y, z)])
    # H = |y|^2/2 + <b, x> (eq. (H)): grad_y H = y, grad_x H = b, grad_z H = 0
    grad = np.concatenate([y, bv, np.zeros(3)])
    s = RTOL * scale_of(X, b)
    assert np.allclose(jg.hamiltonian_vector_field(grad, X), em, rtol=0, atol=s)
    assert np.allclose(twisted_top_rhs(X, b), em, rtol=0, atol=s)
    top = jg.generalized_lagrange_top(b)
    assert np.allclose(top.vector_field(X), em, rtol=0, atol=s)
    assert np.allclose(jg.physical_hamiltonian(3, b).gradient(X), grad, rtol=0, atol=s)
    assert np.isclose(top.energy(X), 0.5 * y @ y + b * x[2], rtol=0, atol=s)


@given(arrays(np.float64, 9, elements=finite), fields)
def test_H_trace_form(X, b):
    """(H): H = |y|^2/2 + <b, x> = -Tr(Y^2 + 2 B X) with the su(2) matrices of Section 4.1."""
    y, x = X[0:3], X[3:6]
    Y = np.einsum("a,aij->ij", y, SIG)
    Xm = np.einsum("a,aij->ij", x, SIG)
    B = 0.5j * np.diag([b, -b])
    tr = -np.trace(Y @ Y + 2 * B @ Xm)
    assert abs(tr - jg.physical_hamiltonian(3, b)(X)) <= RTOL * scale_of(X, b)


@given(arrays(np.float64, 9, elements=finite), fields)
def test_material_point_equation(X, b):
    """d/dt (x - z) = y ^ (x - z) + b ^ z (Section 4), from (em) and as material_point_rhs."""
    y, x, z = X[0:3], X[3:6], X[6:9]
    bv = np.array([0.0, 0.0, b])
    V = twisted_top_rhs(X, b)
    from_em = V[3:6] - V[6:9]
    printed = np.cross(y, x - z) + np.cross(bv, z)
    s = RTOL * scale_of(X, b)
    assert np.allclose(from_em, printed, rtol=0, atol=s)
    assert np.allclose(material_point_rhs(X, b), printed, rtol=0, atol=s)
    assert np.array_equal(jg.material_point(X), x - z)


@given(arrays(np.float64, 6, elements=finite), fields)
def test_lagrange_top_N2(X, b):
    """N = 2, H = H_2/2: y' = b ^ x, x' = y ^ x (Section 4, the Lagrange top)."""
    y, x = X[0:3], X[3:6]
    bv = np.array([0.0, 0.0, b])
    ref = np.concatenate([np.cross(bv, x), np.cross(y, x)])
    assert np.allclose(jg.lagrange_top(b).vector_field(X), ref, rtol=0, atol=RTOL * scale_of(X, b))


@given(arrays(np.float64, 3, elements=finite), fields)
def test_spin_N1(X, b):
    """N = 1, H = H_1/2 = <b, y>: y' = b ^ y (precession about the field)."""
    ref = np.cross([0.0, 0.0, b], X)
    assert np.allclose(jg.GaudinTop(1, b).vector_field(X), ref, rtol=0, atol=RTOL * scale_of(X, b))


def lax_time_derivative(lam, Xdot, N):
    """dL/dt = sum_a sigma^a sum_i ydot_i^a / lambda^(i+1) (b is constant)."""
    y = Xdot.reshape(N, 3)
    xi = sum(y[i] / lam ** (i + 1) for i in range(N))
    return np.einsum("a,aij->ij", xi, SIG)


@pytest.mark.parametrize("N", range(2, 6))
@given(data=st.data())
def test_lax_equation_sign(N, data):
    """dL/dt = [M, L] with M = sum_{i>=1} Y_i lambda^-i along the flow of H_2/2, N = 2..5; the printed
    [L, M] (Prop. in Section 4.1) fails: misprint (docs/errata.md)."""
    X = data.draw(arrays(np.float64, 3 * N, elements=finite))
    b = data.draw(fields)
    r = data.draw(st.floats(0.5, 3.0))
    t = data.draw(st.floats(0, 2 * np.pi))
    lam = r * np.exp(1j * t)
    top = jg.GaudinTop(N, b)
    Ldot = lax_time_derivative(lam, top.vector_field(X), N)
    y = X.reshape(N, 3)
    M = sum(np.einsum("a,aij->ij", y[i], SIG) / lam**i for i in range(1, N))
    L, M_pkg = top.lax_pair(lam, X)
    s = RTOL * scale_of(X, b) * 2.0 ** (2 * N)  # |lambda|^-k <= 2^k
    assert np.allclose(M_pkg, M, rtol=0, atol=s)
    assert np.allclose(Ldot, M @ L - L @ M, rtol=0, atol=s)
    if np.max(np.abs(Ldot)) > 1e-6:
        # [L, M] = -[M, L]: fails whenever dL/dt != 0
        assert np.max(np.abs(Ldot - (L @ M - M @ L))) > 1e3 * s


def test_lax_pair_N3_is_X_over_l_plus_Z_over_l2(rng):
    X = rng.normal(size=9)
    lam = 0.8 - 1.1j
    _, M = jg.generalized_lagrange_top(1.3).lax_pair(lam, X)
    Xm = np.einsum("a,aij->ij", X[3:6], SIG)
    Zm = np.einsum("a,aij->ij", X[6:9], SIG)
    assert np.allclose(M, Xm / lam + Zm / lam**2, rtol=1e-14, atol=1e-14)


def test_gaudin_top_integrals_and_validation(rng):
    X = rng.normal(size=9)
    top = jg.GaudinTop(3, 2.0)
    assert np.array_equal(top.integrals(X), jg.integrals(X, 2.0))
    with pytest.raises(jg.InvalidParameterError, match="field strength b must be nonzero"):
        jg.GaudinTop(3, 0.0)
    with pytest.raises(jg.InvalidParameterError, match="jet order N"):
        jg.GaudinTop(0, 1.0)
    with pytest.raises(jg.InvalidStateError, match="N = 2"):
        jg.lagrange_top(1.0).vector_field(X)
    with pytest.raises(jg.InvalidStateError, match="N = 3"):
        twisted_top_rhs(X[:6], 1.0)
    with pytest.raises(jg.InvalidStateError, match="N = 3"):
        jg.material_point(X[:6])
    with pytest.raises(jg.InvalidStateError, match="non-finite"):
        twisted_top_rhs(np.r_[X[:8], np.nan], 1.0)


def test_complex_generators_section41(rng):
    """Section 4.1: {y^3, y^+-} = -+ i y^+-, {y^+, y^-} = -2i y^3, {x^3, x^+-} = -+ i z^+-, {x^+, x^-} = -2i z^3,
    {y^3, x^+-} = {x^3, y^+-} = -+ i x^+-, {y^+, x^-} = {x^+, y^-} = -2i x^3, {x, z} = {z, z} = 0."""
    X = rng.normal(size=9)
    P = jg.poisson_tensor(X)

    def g(block, kind):  # gradient of v^3 or v^+- for block 0 (y), 1 (x), 2 (z)
        e = np.zeros(9, dtype=complex)
        if kind == "3":
            e[3 * block + 2] = 1
        else:
            s = 1 if kind == "+" else -1
            e[3 * block] = 1
            e[3 * block + 1] = 1j * s
        return e

    def val(block, kind):
        v = X[3 * block : 3 * block + 3]
        return v[2] if kind == "3" else v[0] + (1j if kind == "+" else -1j) * v[1]

    def br(f, h):
        return g(*f) @ P @ g(*h)

    tol = 1e-13
    for s, sg in (("+", 1), ("-", -1)):
        assert abs(br((0, "3"), (0, s)) - (-sg * 1j * val(0, s))) < tol
        assert abs(br((1, "3"), (1, s)) - (-sg * 1j * val(2, s))) < tol
        assert abs(br((0, "3"), (1, s)) - (-sg * 1j * val(1, s))) < tol
        assert abs(br((1, "3"), (0, s)) - (-sg * 1j * val(1, s))) < tol
        assert abs(br((0, "3"), (2, s)) - (-sg * 1j * val(2, s))) < tol
    assert abs(br((0, "+"), (0, "-")) - (-2j * val(0, "3"))) < tol
    assert abs(br((1, "+"), (1, "-")) - (-2j * val(2, "3"))) < tol
    assert abs(br((0, "+"), (1, "-")) - (-2j * val(1, "3"))) < tol
    assert abs(br((1, "+"), (0, "-")) - (-2j * val(1, "3"))) < tol
    assert abs(br((0, "+"), (1, "+"))) < tol and abs(br((0, "3"), (1, "3"))) < tol
    for k1 in "3+-":
        for k2 in "3+-":
            assert abs(br((1, k1), (2, k2))) < tol and abs(br((2, k1), (2, k2))) < tol


@given(arrays(np.float64, 9, elements=finite), fields)
def test_em_matrix_form_sign(X, b):
    """Matrix form of (em) as printed, Y' = [B, X], X' = [Y, X] + [B, Z], Z' = [Y, Z], has the wrong sign with the
    paper's sigma's ([sigma^a, sigma^b] = -eps_abc sigma^c): the vector form (em) gives Y' = [X, B], etc."""
    def m(v):
        return np.einsum("a,aij->ij", v, SIG)

    def c(p, q):
        return p @ q - q @ p

    y, x, z = X[0:3], X[3:6], X[6:9]
    V = twisted_top_rhs(X, b)
    Ym, Xm, Zm, B = m(y), m(x), m(z), m(np.array([0.0, 0.0, b]))
    dY, dX, dZ = m(V[0:3]), m(V[3:6]), m(V[6:9])
    s = RTOL * scale_of(X, b)
    corrected = [c(Xm, B), c(Xm, Ym) + c(Zm, B), c(Zm, Ym)]
    printed = [c(B, Xm), c(Ym, Xm) + c(B, Zm), c(Ym, Zm)]
    for d, cor, pr in zip((dY, dX, dZ), corrected, printed, strict=True):
        assert np.allclose(d, cor, rtol=0, atol=s)
        if np.max(np.abs(d)) > 1e-6:
            assert np.max(np.abs(d - pr)) > 1e3 * s  # printed = -truth
