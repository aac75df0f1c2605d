"""Independent symbolic (SymPy) and 50-digit (mpmath) building blocks for the checks.

Nothing here imports the numpy implementation: the Lax matrix, the brackets (LP) and the
dressing relation ``M L = L~ M`` are rebuilt from the paper's definitions.
"""

from __future__ import annotations

import itertools

import mpmath as mp
import sympy as sp

I = sp.I

# ---------------------------------------------------------------- symbolic: algebra g^(N)

#: sigma^1, sigma^2, sigma^3 exactly as printed after eq. (lax)
SIGMA = [
    sp.Matrix([[0, I], [I, 0]]) / 2,
    sp.Matrix([[0, 1], [-1, 0]]) / 2,
    sp.Matrix([[I, 0], [0, -I]]) / 2,
]


def eps(a, b, c):
    return sp.LeviCivita(a, b, c)


#: the field ``b = (b^1, b^2, b^3)`` as general symbols
BVEC = sp.symbols("b1:4")


def sym_state(N, prefix="y"):
    """``[y_0, ..., y_{N-1}]``, each a list of three real symbols ``y_i^1..y_i^3``."""
    return [[sp.Symbol(f"{prefix}{i}_{a + 1}", real=True) for a in range(3)] for i in range(N)]


def lp_bracket(f, g, ys):
    r"""``{f, g}`` for the Lie--Poisson structure (LP): ``{y_i^a, y_j^b} = eps^{abc} y_{i+j}^c`` (``i+j<N``)."""
    N = len(ys)
    out = 0
    for i in range(N):
        dfi = [sp.diff(f, ys[i][a]) for a in range(3)]
        if all(d == 0 for d in dfi):
            continue
        for j in range(N - i):
            dgj = [sp.diff(g, ys[j][b]) for b in range(3)]
            for a, b, c in itertools.permutations(range(3)):
                if dfi[a] != 0 and dgj[b] != 0:
                    out += dfi[a] * dgj[b] * eps(a, b, c) * ys[i + j][c]
    return sp.expand(out)


def hat(v):
    """``sum_a v^a sigma^a`` (the correspondence of Section 2)."""
    return sum((v[a] * SIGMA[a] for a in range(3)), sp.zeros(2, 2))


def dot(u, v):
    return sum(u[a] * v[a] for a in range(3))


def cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def is_zero(expr) -> bool:
    """Exact zero test: expand/together/simplify (rational functions in the symbols)."""
    e = sp.expand(expr)
    if e == 0:
        return True
    e = sp.together(e)
    num = sp.expand(sp.numer(e))
    if num == 0:
        return True
    return sp.simplify(num) == 0


def linear_identity(diff, syms) -> bool:
    """Whether the matrix ``diff``, affine in the symbols ``syms``, vanishes identically: each coefficient and the
    constant term (rational functions of the remaining symbols) cancel to zero (cheap to decide)."""
    return all(sp.cancel(sp.diff(e, x)) == 0 for x in syms for e in diff) and all(
        sp.cancel(e.subs({x: 0 for x in syms})) == 0 for e in diff)


def matrix_is_zero(Mx) -> bool:
    return all(is_zero(e) for e in Mx)


# ---------------------------------------------------------------- mpmath: random points


def rand_mpf(rng, lo=-2.0, hi=2.0):
    """A random rational (denominator 10^6) as a 50-digit mpf: reproducible from the seed."""
    return mp.mpf(rng.randint(int(lo * 10**6), int(hi * 10**6))) / 10**6


def rand_mpc(rng, lo=-2.0, hi=2.0):
    return mp.mpc(rand_mpf(rng, lo, hi), rand_mpf(rng, lo, hi))


def rand_state(rng, N=3, complex_=False):
    f = rand_mpc if complex_ else rand_mpf
    return [[f(rng) for _ in range(3)] for _ in range(N)]


def rel(a, b):
    """Relative difference ``|a - b| / (1 + |b|)`` (mpf)."""
    return abs(mp.mpmathify(a) - mp.mpmathify(b)) / (1 + abs(mp.mpmathify(b)))


# ---------------------------------------------------------------- mpmath: Lax matrix and dressing
# ell(lam) = [[u, v], [w, -u]] = -2i L(lam) = sum_m ell_m lam^{-m}; 2x2 matrices as nested lists.


def m_zero():
    return [[mp.mpc(0), mp.mpc(0)], [mp.mpc(0), mp.mpc(0)]]


def m_add(A, B):
    return [[A[i][j] + B[i][j] for j in range(2)] for i in range(2)]


def m_sub(A, B):
    return [[A[i][j] - B[i][j] for j in range(2)] for i in range(2)]


def m_scale(c, A):
    return [[c * A[i][j] for j in range(2)] for i in range(2)]


def m_mul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(2)) for j in range(2)] for i in range(2)]


def m_adj(A):
    return [[A[1][1], -A[0][1]], [-A[1][0], A[0][0]]]


def m_norm(A):
    return max(abs(A[i][j]) for i in range(2) for j in range(2))


def ell_from_state(ys, b):
    """Laurent coefficients ``ell_0..ell_N`` for field ``b e_3`` and the reduction (lax2)."""
    out = [[[mp.mpc(b), mp.mpc(0)], [mp.mpc(0), mp.mpc(-b)]]]
    for y in ys:
        y1, y2, y3 = y
        out.append([[mp.mpc(y3), y1 - 1j * y2], [y1 + 1j * y2, -mp.mpc(y3)]])
    return out


def state_from_ell(ell):
    ys = []
    for E in ell[1:]:
        ys.append([(E[0][1] + E[1][0]) / 2, (E[1][0] - E[0][1]) / 2j, E[0][0]])
    return ys


def ell_at(ell, lam):
    acc = m_zero()
    for m, E in enumerate(ell):
        acc = m_add(acc, m_scale(mp.mpc(lam) ** (-m), E))
    return acc


def uvw_at(ell, lam):
    E = ell_at(ell, lam)
    return E[0][0], E[0][1], E[1][0]


def nu_at(ell, lam, sign=1):
    u, v, w = uvw_at(ell, lam)
    return sign * mp.sqrt(u * u + v * w)


def poly_mul(P, Q):
    """Product of matrix polynomials given as coefficient lists (highest power first)."""
    out = [m_zero() for _ in range(len(P) + len(Q) - 1)]
    for i, A in enumerate(P):
        for j, B in enumerate(Q):
            out[i + j] = m_add(out[i + j], m_mul(A, B))
    return out


def dress(ell, M, detM):
    r"""``ell~ = M ell adj(M) / det M`` (the dressing relation (rr)/(128)) by exact long division.

    ``M``: matrix polynomial in lam (list, highest power first), ``detM``: scalar polynomial
    (list, highest first, monic).  Returns ``(ell~ coefficients, remainder norm)``; the remainder
    vanishes exactly when the spectral data are consistent.
    """
    N = len(ell) - 1
    P = list(ell)  # lam^N ell(lam) = sum_m ell_m lam^{N-m}: highest power first
    adjM = [m_adj(A) for A in M]
    R = poly_mul(poly_mul(M, P), adjM)
    d = len(detM) - 1
    R = [list(map(list, A)) for A in R]
    Q = []
    for k in range(len(R) - d):
        c = R[k]
        Q.append(c)
        for i in range(1, d + 1):
            R[k + i] = m_sub(R[k + i], m_scale(detM[i], c))
    rem = max(m_norm(A) for A in R[len(R) - d :])
    # Q has degree deg(R) - d; lam^N ell~ has degree N: drop leading (zero) coefficients
    lead = Q[: len(Q) - (N + 1)]
    lead_norm = max((m_norm(A) for A in lead), default=mp.mpf(0))
    return Q[len(Q) - (N + 1) :], max(rem, lead_norm)


def one_point_M(eta, p, q):
    return [[[1, 0], [0, 0]], [[-eta + p * q, p], [q, mp.mpc(1)]]]


def two_point_M(eta1, eta2, s, t):
    return [[[1, 0], [0, 1]], [[-eta1 + s * t, t], [-s * s * t + (eta1 - eta2) * s, -eta2 - s * t]]]


def one_point_map(ell, b, eta, nu):
    """Forward one-point map: ``p = y^-/(2b)`` (hh), ``q = (u(eta) - nu)/v(eta)`` (hhh, mu read as nu)."""
    u, v, w = uvw_at(ell, eta)
    p = ell[1][0][1] / (2 * b)
    q = (u - nu) / v
    new, res = dress(ell, one_point_M(eta, p, q), [1, -eta])
    return new, res, p, q


def two_point_st(ell, eta1, eta2, nu1, nu2):
    """``s``, ``t`` of (x), (X) with the paper's mu read as nu."""
    u1, v1, w1 = uvw_at(ell, eta1)
    u2, v2, w2 = uvw_at(ell, eta2)
    s = (u1 - nu1) / v1
    t = (eta1 - eta2) * (u1 + nu1) * (u2 - nu2) / ((u1 + nu1) * w2 - (u2 - nu2) * w1)
    return s, t


def two_point_map(ell, eta1, eta2, nu1, nu2):
    s, t = two_point_st(ell, eta1, eta2, nu1, nu2)
    new, res = dress(ell, two_point_M(eta1, eta2, s, t), [1, -(eta1 + eta2), eta1 * eta2])
    return new, res, s, t


def spectral_kappas(ys, b):
    """Coefficients ``kappa_0..kappa_2N`` of ``u^2 + v w = <xi, xi>`` (xi = b e3 + sum y_i lam^{-i-1})."""
    xi = [[0, 0, b]] + ys
    N = len(ys)
    out = [mp.mpf(0)] * (2 * N + 1)
    for i in range(N + 1):
        for j in range(N + 1):
            out[i + j] += sum(xi[i][a] * xi[j][a] for a in range(3))
    return out
