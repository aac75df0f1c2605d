"""Tests of jetgaudin.spectral: the curve det(L - mu) (Lemma 1, Props. 2, 3), the integrals and the branch nu.

Independent route for the integrals: det(L(lambda) - mu) is computed *exactly* (SymPy rationals)
from the 2x2 matrix (lax) at 2N+1 random rational points lambda, and the Vandermonde system in
1/lambda is solved exactly for the Laurent coefficients; these are compared (exactly) with the
closed forms of Lemma 1 / Props. 2, 3 written out literally here, and (in floating point) with
jetgaudin.integrals.
"""

import itertools

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import jetgaudin as jg
from jetgaudin.spectral import curve_coefficients, spectral_determinant

finite = st.floats(-2.0, 2.0, allow_nan=False, allow_infinity=False)
I = sp.I
SIG = [sp.Matrix([[0, I], [I, 0]]) / 2, sp.Matrix([[0, 1], [-1, 0]]) / 2, sp.Matrix([[I, 0], [0, -I]]) / 2]


def rational(x):
    """A float turned into a nearby rational with a modest denominator (exact arithmetic downstream)."""
    return sp.Rational(x).limit_denominator(10**6)


def exact_f(i, lam, c):
    """f_i(lambda) by the partition formula of Section 2, exactly (c: list of rationals c_1..)."""
    L = sp.Symbol("L")
    total = 0
    for q in itertools.product(*[range(i // k + 1) for k in range(1, i + 1)]):
        if sum(k * qk for k, qk in zip(range(1, i + 1), q, strict=True)) == i:
            coeff = sp.Mul(*[c[k - 1] ** q[k - 1] / sp.factorial(q[k - 1]) for k in range(1, i + 1)])
            total += coeff * sp.diff(1 / L, L, sum(q))
    return total.subs(L, lam)


def curve_from_determinant(y, b, c, rng):
    """Laurent coefficients kappa_0..kappa_2N of 4 (det(L - mu) - mu^2), exactly, from 2N+1 points.

    y: N x 3 rationals; b: 3 rationals; c: rationals c_1..c_{N-1} (partition formula) or None (lax2).
    Also returns the mu used, after checking that 4 det(L - mu) - 4 mu^2 does not depend on mu.
    """
    N = len(y)
    pts = set()
    while len(pts) < 2 * N + 1:
        pts.add(rational(rng.choice([-1, 1]) * rng.uniform(0.5, 3.0)))
    pts = sorted(pts)
    rhs = []
    for lam in pts:
        f = [lam ** -(i + 1) for i in range(N)] if c is None else [exact_f(i, lam, c) for i in range(N)]
        xi = [b[a] + sum(f[i] * y[i][a] for i in range(N)) for a in range(3)]
        L = sum((SIG[a] * xi[a] for a in range(3)), sp.zeros(2, 2))
        vals = []
        for mu in (rational(rng.normal()), rational(rng.normal()) + I * rational(rng.normal())):
            d = sp.expand((L - mu * sp.eye(2)).det())
            vals.append(sp.expand(4 * d - 4 * mu**2))
        assert vals[0] == vals[1]  # (curve): det(L - mu) = mu^2 + (...)/4, exactly
        rhs.append(vals[0])
    V = sp.Matrix([[lam**-m for m in range(2 * N + 1)] for lam in pts])
    return list(V.LUsolve(sp.Matrix(rhs)))


def random_exact_state(rng, N):
    y = [[rational(v) for v in rng.normal(size=3)] for _ in range(N)]
    b = [rational(v) for v in rng.normal(size=3)]
    return y, b


def dot(p, q):
    return sum(pi * qi for pi, qi in zip(p, q, strict=True))


def prop2_literal(y, b):
    """Prop. 2 as printed: H_k = 2<b, y_{k-1}> + sum_{i=0}^{k-2} <y_i, y_{k-i-2}>,
    C_k = sum_{i=k-1}^{N-1} <y_i, y_{N+k-i-2}>."""
    N = len(y)
    H = [2 * dot(b, y[k - 1]) + sum(dot(y[i], y[k - i - 2]) for i in range(0, k - 1)) for k in range(1, N + 1)]
    C = [sum(dot(y[i], y[N + k - i - 2]) for i in range(k - 1, N)) for k in range(1, N + 1)]
    return H, C


def lemma1_H_coefficients(y, b, k_start):
    """(Hh): coefficient of lambda^-i in H(lambda) = 2<b, y_{i-1}> + sum_{k=k_start}^{i-2} <y_k, y_{i-k-2}>.

    As printed k_start = 1; the correct lower limit is 0."""
    N = len(y)
    return [2 * dot(b, y[i - 1]) + sum(dot(y[k], y[i - k - 2]) for k in range(k_start, i - 1)) for i in range(1, N + 1)]


def lemma1_C_coefficients(y):
    """(C): coefficient of lambda^-i, i = N+1..2N: sum_{k=i-N-1}^{N-1} <y_k, y_{i-k-2}> (printed; correct)."""
    N = len(y)
    return [sum(dot(y[k], y[i - k - 2]) for k in range(i - N - 1, N)) for i in range(N + 1, 2 * N + 1)]


def to_float_state(y):
    return np.array([float(v) for row in y for v in row])


@pytest.mark.parametrize("N", range(1, 6))
def test_integrals_from_determinant_prop2_and_lemma1(N, rng):
    """det(L - mu) at 2N+1 points -> (|b|^2, H_1..H_N, C_1..C_N): exactly Prop. 2; jg.integrals to 1e-12."""
    y, b = random_exact_state(rng, N)
    kappa = curve_from_determinant(y, b, None, rng)
    H, C = prop2_literal(y, b)
    assert kappa[0] == dot(b, b)
    assert kappa[1 : N + 1] == H  # exact rational equality
    assert kappa[N + 1 :] == C
    # Lemma 1: (C) as printed is right; (Hh) needs the inner sum from k = 0 (printed k = 1 drops <y_0, y_{i-2}>)
    assert kappa[N + 1 :] == lemma1_C_coefficients(y)
    assert kappa[1 : N + 1] == lemma1_H_coefficients(y, b, k_start=0)
    if N >= 2:
        printed = lemma1_H_coefficients(y, b, k_start=1)
        assert printed[1] != kappa[2]  # H_2 printed = 2<b, y_1> misses |y_0|^2
        assert printed[1] == kappa[2] - dot(y[0], y[0])
    # floating-point route: sums of O(N) products of O(1) numbers; rounding ~1e-15, tolerance 1e-12 relative
    X = to_float_state(y)
    ref = np.array([float(k) for k in kappa[1:]])
    scale = 1 + np.sum(X**2) + np.sum(np.abs(X)) * np.linalg.norm([float(v) for v in b])
    assert np.allclose(jg.integrals(X, np.array([float(v) for v in b])), ref, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("N", range(2, 6))
def test_integrals_general_c_from_determinant(N, rng):
    """With random constants c_k (partition formula), det(L - mu) gives jg.integrals(X, b, c)."""
    y, b = random_exact_state(rng, N)
    c = [rational(v) for v in rng.uniform(-1.5, 1.5, size=N - 1)]
    kappa = curve_from_determinant(y, b, c, rng)
    X = to_float_state(y)
    ref = np.array([float(k) for k in kappa[1:]])
    got = jg.integrals(X, np.array([float(v) for v in b]), np.array([float(v) for v in c]))
    # coefficients involve products of up to 2N-2 constants |c| <= 1.5 (<= 1.5^8 ~ 26) times O(1) states
    scale = 30 * (1 + np.sum(np.abs(X))) ** 2
    assert np.allclose(got, ref, rtol=0, atol=1e-12 * scale)


def prop3_printed(y, b, c1, c2):
    """Prop. 3 as printed (N = 3, Lax matrix (kk))."""
    y0, y1, y2 = y
    Cu1, Cu2, Cu3 = dot(y0, y2) + dot(y1, y1) / 2, dot(y1, y2), dot(y2, y2)
    y1c2y2 = [y1[a] + c2 * y2[a] for a in range(3)]
    H1 = 2 * dot(b, y0)
    H2 = dot(y0, y0) - 2 * c1 * dot(b, y1c2y2)
    H3 = 2 * c1 * (c1 * dot(b, y2) - dot(y0, y1c2y2))
    C1 = c1**2 * (c2**2 * Cu3 + 2 * c2 * Cu2 + 2 * Cu1)
    C2 = -2 * c1**3 * (c2 * Cu3 + Cu2)
    C3 = c1**4 * Cu3
    return [sp.expand(v) for v in (H1, H2, H3, C1, C2, C3)]


def prop3_corrected(y, b, c1, c2):
    """Prop. 3 corrected: the printed formulas with c_2 replaced by c_2 / c_1 (printed has c_1 c_2 for c_2)."""
    y0, y1, y2 = y
    Cu1, Cu2, Cu3 = dot(y0, y2) + dot(y1, y1) / 2, dot(y1, y2), dot(y2, y2)
    H1 = 2 * dot(b, y0)
    H2 = dot(y0, y0) - 2 * c1 * dot(b, y1) - 2 * c2 * dot(b, y2)
    H3 = 2 * c1**2 * dot(b, y2) - 2 * c1 * dot(y0, y1) - 2 * c2 * dot(y0, y2)
    C1 = c2**2 * Cu3 + 2 * c1 * c2 * Cu2 + 2 * c1**2 * Cu1
    C2 = -2 * c1**2 * (c2 * Cu3 + c1 * Cu2)
    C3 = c1**4 * Cu3
    return [sp.expand(v) for v in (H1, H2, H3, C1, C2, C3)]


def test_prop3_printed_is_wrong_corrected_holds(rng):
    """Prop. 3 (N = 3, (kk) with random c_1, c_2): the printed H_2, H_3, C_1, C_2 are the true ones with
    c_2 -> c_1 c_2; the corrected forms equal det(L - mu) exactly, and jg.integrals(X, b, [c1, c2])."""
    for _ in range(3):
        y, b = random_exact_state(rng, 3)
        c1, c2 = (rational(v) for v in rng.uniform(-1.5, 1.5, size=2))
        # (kk) itself, literally: xi = b + y0/l - c1 y1/l^2 + y2/l^2 (c1^2/l - c2); check it is the partition formula
        lam = sp.Symbol("lam")
        assert sp.simplify(exact_f(1, lam, [c1, c2]) - (-c1 / lam**2)) == 0
        assert sp.simplify(exact_f(2, lam, [c1, c2]) - (c1**2 / lam**3 - c2 / lam**2)) == 0
        kappa = curve_from_determinant(y, b, [c1, c2], rng)
        truth = [sp.expand(k) for k in kappa[1:]]
        assert kappa[0] == dot(b, b)
        assert truth == prop3_corrected(y, b, c1, c2)
        printed = prop3_printed(y, b, c1, c2)
        assert [printed[i] == truth[i] for i in range(6)] == [True, False, False, False, False, True]
        # and the printed form is exactly the truth at c_2 -> c_1 c_2
        assert printed == prop3_corrected(y, b, c1, c1 * c2)
        X = to_float_state(y)
        got = jg.integrals(X, np.array([float(v) for v in b]), [float(c1), float(c2)])
        scale = 10 * (1 + np.sum(np.abs(X))) ** 2
        assert np.allclose(got, [float(t) for t in truth], rtol=0, atol=1e-12 * scale)


@given(arrays(np.float64, 9, elements=finite), finite)
def test_reduced_N3_integrals_we_cas(X, b):
    """(we), (cas): H1 = 2<b,y>, H2 = |y|^2 + 2<b,x>, H3 = 2(<b,z> + <y,x>),
    C1 = 2<y,z> + |x|^2, C2 = 2<x,z>, C3 = |z|^2."""
    y, x, z = X[0:3], X[3:6], X[6:9]
    bv = np.array([0, 0, b])
    ref = [2 * bv @ y, y @ y + 2 * bv @ x, 2 * (bv @ z + y @ x), 2 * y @ z + x @ x, 2 * x @ z, z @ z]
    assert np.allclose(jg.integrals(X, b), ref, rtol=0, atol=1e-13 * (1 + np.sum(X**2) + abs(b) * np.sum(np.abs(X))))


@st.composite
def setups(draw, n_min=1, n_max=5, general_c=True):
    N = draw(st.integers(n_min, n_max))
    X = draw(arrays(np.float64, 3 * N, elements=finite))
    b = draw(arrays(np.float64, 3, elements=finite))
    c = draw(arrays(np.float64, 4, elements=st.floats(-1.5, 1.5)))[: N - 1] if general_c else None
    return N, X, b, c


def fd_gradients(X, b, c):
    """Central differences of the integrals: exact for quadratics up to rounding ~ eps |kappa| / h (h = 0.1)."""
    E = np.eye(len(X))
    h = 0.1
    return np.stack([(jg.integrals(X + h * E[j], b, c) - jg.integrals(X - h * E[j], b, c)) / (2 * h)
                     for j in range(len(X))], axis=-1)


@given(setups())
def test_integral_gradients_and_involution(setup):
    """grad kappa_m vs finite differences; {H_i, H_k} = 0, and {C_i, X_I} = 0 for every coordinate."""
    N, X, b, c = setup
    G = jg.integral_gradients(X, b, c)
    Gfd = fd_gradients(X, b, c)
    scale = 30 * (1 + np.sum(np.abs(X)) + np.sum(np.abs(b)))
    assert np.allclose(G, Gfd, rtol=0, atol=1e-11 * scale)
    P = jg.poisson_tensor(X)
    # {kappa_i, kappa_k} with the analytic gradients (just checked against finite differences): each bracket is
    # a sum of (3N)^2 products |G||Pi||G|, so exact zeros come out as round-off, <= 8 eps (3N)^2 |G|^2 |Pi| (a
    # nonzero bracket would be of the size of the products themselves, ~|G|^2 |Pi|)
    B = G @ P @ G.T
    size = np.max(np.abs(G)) ** 2 * max(1.0, np.max(np.abs(P)))
    bound = 8 * np.finfo(float).eps * (3 * N) ** 2 * size
    assert np.max(np.abs(B)) <= bound
    # Casimirs: Pi grad C_k = 0 (C_k = kappa_{N+k}), for the reduction and for general c_k
    eps = np.finfo(float).eps
    assert np.max(np.abs(G[N:] @ P.T)) <= 8 * eps * 3 * N * np.max(np.abs(G)) * max(1.0, np.max(np.abs(P)))


@given(setups(general_c=False))
def test_casimirs_are_top_coefficients(setup):
    N, X, b, _ = setup
    assert np.allclose(jg.integrals(X, b)[N:], jg.casimirs(X), rtol=0, atol=1e-13 * (1 + np.sum(X**2)))


@given(setups(), st.floats(0.5, 3.0), st.floats(0, 2 * np.pi))
def test_nu_squared_is_u2_plus_vw_and_determinant(setup, r, t):
    N, X, b, c = setup
    lam = r * np.exp(1j * t)
    u, v, w = jg.uvw(lam, X, b, c)
    n2 = jg.nu_squared(lam, X, b, c)
    scale = (1 + np.sum(np.abs(b)) + 32 * 10 * np.sum(np.abs(X))) ** 2
    assert abs(n2 - (u * u + v * w)) <= 1e-12 * scale
    mu = 0.3 - 0.7j
    # det(L - mu) = mu^2 + nu^2 / 4: mu of (curve) is an eigenvalue of L, nu = 2 i mu an eigenvalue of ell = -2iL
    assert abs(spectral_determinant(lam, mu, X, b, c) - (mu**2 + n2 / 4)) <= 1e-12 * scale
    if b @ b == 0 or lam.real == 0:  # the branch rule needs |b|^2 > 0 (tested in test_errors) and Re l != 0
        return
    nu = jg.nu(lam, X, b, c)
    assert abs(nu**2 - n2) <= 1e-12 * scale
    ell = -2j * jg.lax_matrix(lam, X, b, c)
    assert np.allclose(np.sort_complex(np.linalg.eigvals(ell)), np.sort_complex([nu, -nu]), rtol=0,
                       atol=1e-6 * np.sqrt(scale))  # eigenvalues of a 2x2: error ~ sqrt(eps) near a double root


# ---- the branch rule of nu ----------------------------------------------------------------------

@st.composite
def real_states(draw, n_min=1, n_max=5):
    N = draw(st.integers(n_min, n_max))
    X = draw(arrays(np.float64, 3 * N, elements=st.floats(-2, 2)))
    b = draw(st.floats(0.3, 2.0)) * draw(st.sampled_from([-1.0, 1.0]))
    return N, X, b


@given(real_states(), st.floats(0.2, 4.0), st.floats(-4.0, 4.0), st.sampled_from([-1.0, 1.0]))
def test_nu_conjugation_symmetry_and_sheet(state, a, h, sgn):
    """nu(conj l) = conj nu(l) for a real state; sheet=-1 is the negative; nu > 0 on the real axis."""
    N, X, b = state
    lam = sgn * a + 1j * h
    try:
        nu = jg.nu(lam, X, b)
    except jg.BranchPointError:
        return  # a branch point on the segment (measure zero): tested separately below
    nu_c = jg.nu(np.conj(lam), X, b)
    scale = abs(nu) + 1e-300
    # both computed from sqrt(nu^2) of conjugate arguments: equal up to rounding, ~1e-15 relative
    assert abs(nu_c - np.conj(nu)) <= 1e-12 * max(scale, np.sqrt(abs(jg.nu_squared(lam, X, b))))
    assert jg.nu(lam, X, b, sheet=-1) == -nu
    nu_real = jg.nu(sgn * a, X, b)
    assert abs(nu_real.imag) <= 1e-15 * abs(nu_real) and nu_real.real > 0


@given(real_states())
def test_nu_tends_to_abs_b(state):
    """nu -> |b| at large real lambda (both signs): nu = |b| + <b, y_0>/(|b| lambda) + O(lambda^-2)."""
    N, X, b = state
    for lam in (1e6, -1e6):
        nu = jg.nu(lam, X, b)
        # the O(1/lambda) term is <= |y_0| / lam <= 4e-6 here
        assert abs(nu - abs(b)) <= 1e-5 * (1 + np.max(np.abs(X)))
    big = jg.nu(1e6 + 1e3j, X, b)
    assert abs(big - abs(b)) <= 1e-5 * (1 + np.max(np.abs(X)))


def continue_along(nu2_path, start):
    """Fine-step analytic continuation of sqrt(nu^2) along a path: pick the root nearest the previous value."""
    out = np.empty_like(nu2_path)
    prev = start
    for k, n2 in enumerate(nu2_path):
        r = np.sqrt(n2)
        prev = r if abs(r - prev) <= abs(-r - prev) else -r
        out[k] = prev
    return out


def cut_crossings(lam_path, roots_path):
    """Number of times, between consecutive samples, that q_r = (lam - r)/(Re lam - r) crosses the
    negative real axis for some branch point r: exactly where the default rule changes sign relative to
    continuation (its product of principal square roots jumps).  roots_path: (K, 2N), matched."""
    a = lam_path.real
    q = (lam_path[:, None] - roots_path) / (a[:, None] - roots_path)
    q0, q1 = q[:-1], q[1:]
    crosses_axis = (np.sign(q0.imag) != np.sign(q1.imag))
    # real part at the crossing (linear interpolation in the fine step)
    t = q0.imag / np.where(q0.imag - q1.imag == 0, 1, q0.imag - q1.imag)
    re_at = q0.real + t * (q1.real - q0.real)
    return np.sum(crosses_axis & (re_at < 0), axis=1)


def match_roots(prev, new):
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(prev[:, None] - new[None, :])
    _, col = linear_sum_assignment(cost)
    return new[col]


@pytest.mark.parametrize("N", range(1, 6))
def test_nu_continuous_along_random_eta_paths(N, rng):
    """Along random smooth paths eta(s) (fixed state), the default nu equals the fine-step continuation
    except for a sign flip exactly where the path crosses a cut of the rule (vertical ray beyond a branch
    point); paths kept in Re eta > 0.2 or < -0.2.  Also: no flip at all on paths that cross no cut."""
    n_flips_seen = n_paths_without_cut = 0
    for _trial in range(6):
        X = rng.normal(size=3 * N)
        b = rng.uniform(0.5, 1.5)
        roots = jg.branch_points(X, b)
        K = 3000
        s = np.linspace(0, 1, K)
        side = rng.choice([-1, 1])
        p = rng.normal(size=(4, 2))
        re = side * (0.3 + 2.5 * np.abs(np.sin(np.pi * (p[0, 0] * s + p[0, 1])) + 0.3 * s * p[1, 0]) ** 1)
        im = 3 * np.sin(np.pi * (p[2, 0] * s + p[2, 1])) + p[3, 0] * s
        lam = re + 1j * im
        nu_def = jg.nu(lam, X, b)
        cont = continue_along(jg.nu_squared(lam, X, b), nu_def[0])
        ratio = np.round((nu_def / cont).real)
        assert np.allclose(nu_def / cont, ratio, rtol=0, atol=1e-8)  # +-1: nu_def is a root, continuation too
        flips = np.abs(np.diff(ratio)) > 0
        crossings = cut_crossings(lam, np.broadcast_to(roots, (K, len(roots)))) % 2 == 1
        assert np.array_equal(flips, crossings)
        n_flips_seen += flips.sum()
        n_paths_without_cut += not crossings.any()
        if not crossings.any():
            assert np.all(ratio == 1)  # continuous: no sign jump at all
    assert n_paths_without_cut > 0  # the test exercises both cases (deterministic seed)


@pytest.mark.parametrize("N", range(1, 6))
def test_nu_continuous_along_random_state_paths(N, rng):
    """At fixed eta, along random paths X(s), nu equals the fine-step continuation (no sign jumps), except
    exactly when a branch point crosses the vertical segment [Re eta, eta]."""
    for _trial in range(4):
        X0, X1 = rng.normal(size=(2, 3 * N))
        b = rng.uniform(0.5, 1.5)
        eta = rng.uniform(0.5, 3) + 1j * rng.uniform(-1, 1)
        K = 1500
        s = np.linspace(0, 1, K)[:, None]
        Xs = X0 + s * (X1 - X0) + 0.3 * np.sin(3 * s) * rng.normal(size=3 * N)
        nu_def = jg.nu(np.full(K, eta), Xs, b)
        cont = continue_along(jg.nu_squared(np.full(K, eta), Xs, b), nu_def[0])
        ratio = np.round((nu_def / cont).real)
        flips = np.abs(np.diff(ratio)) > 0
        roots = jg.branch_points(Xs, b)
        matched = [roots[0]]
        for k in range(1, K):
            matched.append(match_roots(matched[-1], roots[k]))
        crossings = cut_crossings(np.full(K, eta), np.array(matched)) % 2 == 1
        assert np.array_equal(flips, crossings)


def test_nu_branch_point_errors(rng):
    X = rng.normal(size=9)
    b = 1.0
    roots = jg.branch_points(X, b)
    kappa = curve_coefficients(X, b)
    # branch points are zeros of nu^2 (relative to the size of the terms)
    for r in roots:
        terms = np.abs(kappa) * np.abs(r) ** -np.arange(len(kappa))
        assert abs(jg.nu_squared(r, X, b)) <= 1e-10 * terms.sum()
    r = roots[np.argmax(np.abs(roots.imag))]
    with pytest.raises(jg.BranchPointError, match="branch point"):
        jg.nu(r, X, b)
    # a point straight above (beyond) a branch point: the vertical segment from Re(lambda) passes through it
    with pytest.raises(jg.BranchPointError, match="branch point"):
        jg.nu(r.real + 1.5j * r.imag, X, b)
    for lam in (0.0, 2.0j, -0.5j):
        with pytest.raises(jg.BranchPointError, match="Re\\(lambda\\)"):
            jg.nu(lam, X, b)
    with pytest.raises(jg.InvalidParameterError, match="field b must be nonzero"):
        jg.nu(1 + 1j, X, 0.0)
    with pytest.raises(jg.InvalidParameterError, match="lambda must be finite"):
        jg.nu(np.nan, X, b)


def test_nu_vectorised_bitwise(rng):
    X = rng.normal(size=(3, 4, 9))
    lam = 1.5 + 0.4j
    nu = jg.nu(lam, X, 1.0)
    for i, j in [(0, 0), (2, 3)]:
        assert nu[i, j] == jg.nu(lam, X[i, j], 1.0)


def test_branch_rule_tiny_real_part_does_not_overflow(rng):
    """Regression: for |Re lambda| = 1e-200 the value nu(Re lambda) overflows; the branch rule must still
    pick the root continuous with Re lambda = 1e-8 (same sheet: unit phases agree to 1e-3)."""
    for _ in range(50):
        X = rng.normal(size=9)
        v1 = jg.nu(1e-8 + 0.5j, X, 1.0)
        v2 = jg.nu(1e-200 + 0.5j, X, 1.0)
        assert abs(v1 / abs(v1) - v2 / abs(v2)) < 1e-3
