"""Checks for the su(n) chains (issue 32): the linear r-matrix relation and the rank-one dressing of the real two-point
map.  Not in the paper (its introduction says the construction "can be generalized to any finite-dimensional simple Lie
algebra"): these checks stand in a section of their own ("su(n)").

Everything is rebuilt from the definitions with SymPy and mpmath: the Gell-Mann matrices are written here from the
nested rule, the structure constants come from their commutators, the dressing from D(λ) = (λ − η̄)(1 − P) + (λ − η)P
evaluated as a matrix function (the numpy implementation is not imported).
"""

from __future__ import annotations

import itertools

import mpmath as mp
import sympy as sp

from ._registry import Outcome, Verdict, register
from ._tools import rand_mpf

I = sp.I


def _gell_mann(n):
    out = []
    for k in range(2, n + 1):
        for j in range(k - 1):
            s, a = sp.zeros(n, n), sp.zeros(n, n)
            s[j, k - 1] = s[k - 1, j] = 1
            a[j, k - 1], a[k - 1, j] = -I, I
            out += [s, a]
        d = sp.zeros(n, n)
        for i in range(k - 1):
            d[i, i] = 1
        d[k - 1, k - 1] = -(k - 1)
        out.append(sp.sqrt(sp.Rational(2, k * (k - 1))) * d)
    return out


def _f(lam):
    dim = len(lam)
    return {(a, b, c): v for a, b, c in itertools.product(range(dim), repeat=3)
            if (v := sp.nsimplify(sp.simplify(((lam[a] * lam[b] - lam[b] * lam[a]) * lam[c]).trace() / (4 * I))))
            != 0}


def _r_matrix_holds(n, orders) -> bool:
    """Both sides are linear in the y's and b: compare the coefficient of each (an n²×n² matrix of rational functions
    of x = λ − p, y = μ − p, p the site's position) exactly: (x − y) lhs = [iΠ, S] after multiplying by x^{m+1} y^{m+1}
    (polynomials)."""
    lam = _gell_mann(n)
    dim = len(lam)
    f = _f(lam)
    x, y = sp.symbols("x y")
    perm = sp.zeros(n * n, n * n)
    for i, k in itertools.product(range(n), repeat=2):
        perm[i * n + k, k * n + i] = 1
    r = I * perm  # r(λ − μ) (x − y): the factor 1/(x − y) is moved to the left side
    one = sp.eye(n)
    for c in range(dim):
        for N in sorted(set(orders)):  # a site of order N at the symbolic position p (sites commute)
            for m in range(N):
                # {ξ^a(λ), ξ^b(μ)} ∋ f_abc y^c_m Σ_{j+k=m} (λ − p)^{−j−1} (μ − p)^{−k−1}
                g = sum(1 / (x ** (j + 1) * y ** (m - j + 1)) for j in range(m + 1))
                lhs = sum((v * g * sp.kronecker_product(lam[a], lam[b]) for (a, b, cc), v in f.items() if cc == c),
                          sp.zeros(n * n, n * n))
                S = sp.kronecker_product(lam[c], one) / x ** (m + 1) + \
                    sp.kronecker_product(one, lam[c]) / y ** (m + 1)
                mult = x ** (m + 1) * y ** (m + 1)
                if any(sp.expand(e * mult) != 0 for e in (x - y) * lhs - (r * S - S * r)):
                    return False
        S = sp.kronecker_product(lam[c], one) + sp.kronecker_product(one, lam[c])  # the field b^c: [r, S] = 0
        if any(sp.expand(e) != 0 for e in r * S - S * r):
            return False
    return True


@register(
    "SUn-r",
    "su(n)",
    "The su(n) chain l(x) = sum_a lambda_a xi^a(x), xi^a = b^a + sum_j sum_k y^(j)a_k (x - x_j)^-(k+1) (generalised "
    "Gell-Mann basis, [lambda_a, lambda_b] = 2i f_abc lambda_c, {y^a_j, y^b_k} = f_abc y^c_(j+k)) satisfies "
    "{l(x) (x) l(y)} = [r(x - y), l(x) (x) 1 + 1 (x) l(y)] with r(x) = i Pi / x, Pi the permutation: su(3), sites "
    "of orders up to 3 at symbolic positions, symbolic field (with --full also su(4))",
    "exact SymPy: rational functions of x, y and the positions",
)
def _sun_r(ctx):
    cases = [(3, (3,))] + ([(4, (2,))] if ctx.full else [])
    return Outcome(Verdict.exact(all(_r_matrix_holds(n, o) for n, o in cases)))


@register(
    "SUn-dressing",
    "su(n)",
    "The real two-point map of an su(3) chain (sites of orders 2 and 1, random real state and field, eta off the "
    "axis): with v the eigenvector of l(eta) for an eigenvalue mu, P = v v^+/(v^+ v) and D(x) = (x - conj eta)(1 - P) "
    "+ (x - eta) P, D l D^-1 has no pole at eta nor at conj eta (residues D(eta) l(eta) P and P l(conj eta)(1 - P) "
    "vanish), is Hermitian on the real axis, equals b + the principal parts Y~_k = sum_(j>=k) D_0 Y_j Dinv_(j-k) + "
    "Y_j Dinv_(j-k-1) at the sites, and has the spectrum of l; a non-eigenvector leaves the pole",
    "mpmath, 50 digits: residues, Hermiticity defect, reconstruction at a complex point, char. polynomial",
)
def _sun_dressing(ctx):
    rng = ctx.rng()
    with mp.workdps(50):
        lam = [mp.matrix(sp.N(m, 60).tolist()) for m in _gell_mann(3)]
        sites = [(rand_mpf(rng, -1.5, -0.5), 2), (rand_mpf(rng, 0.5, 1.5), 1)]
        ys = [[[rand_mpf(rng) for _ in range(8)] for _ in range(N)] for _, N in sites]
        bv = [rand_mpf(rng) for _ in range(8)]

        def mat(v):
            out = mp.matrix(3, 3)
            for a in range(8):
                out += v[a] * lam[a]
            return out

        Y = [[mat(y) for y in site] for site in ys]
        B = mat(bv)

        def ell(x):
            out = B.copy()
            for (p, N), Ys in zip(sites, Y, strict=True):
                for k in range(N):
                    out += Ys[k] / (x - p) ** (k + 1)
            return out

        eta = mp.mpc(rand_mpf(rng, -0.3, 0.3), rand_mpf(rng, 0.2, 0.6))
        E, ER = mp.eig(ell(eta))
        v = ER[:, 0]
        one = mp.eye(3)

        def proj(w):
            return (w * w.H) / (w.H * w)[0]

        def dressing(Pm):
            D = lambda x: (x - mp.conj(eta)) * (one - Pm) + (x - eta) * Pm  # noqa: E731
            Dinv = lambda x: (one - Pm) / (x - mp.conj(eta)) + Pm / (x - eta)  # noqa: E731
            return D, Dinv

        P = proj(v)
        D, Dinv = dressing(P)
        size = 1 + max(abs(x) for x in ell(eta))
        res_eta = mp.mnorm(D(eta) * ell(eta) * P, 1) / size
        res_bar = mp.mnorm(P * ell(mp.conj(eta)) * (one - P), 1) / size
        x0 = rand_mpf(rng, 1.6, 2.0)
        Lt = D(x0) * ell(x0) * Dinv(x0)
        herm = mp.mnorm(Lt - Lt.H, 1) / mp.mnorm(Lt, 1)
        # the new principal parts by the Taylor rule, then ℓ̃ at a complex point against D ℓ D^{-1} there
        new = []
        for (p, N), Ys in zip(sites, Y, strict=True):
            D0 = (p - mp.conj(eta)) * (one - P) + (p - eta) * P
            Di = [(-1) ** c * ((one - P) / (p - mp.conj(eta)) ** (c + 1) + P / (p - eta) ** (c + 1)) for c in range(N)]
            new.append([sum((D0 * Ys[j] * Di[j - k] + (Ys[j] * Di[j - k - 1] if j > k else mp.matrix(3, 3))
                             for j in range(k, N)), mp.matrix(3, 3)) for k in range(N)])
        z = mp.mpc(rand_mpf(rng, -2, 2), rand_mpf(rng, 0.7, 1.2))
        rebuilt = B.copy()
        for (p, N), Ys in zip(sites, new, strict=True):
            for k in range(N):
                rebuilt += Ys[k] / (z - p) ** (k + 1)
        recon = mp.mnorm(rebuilt - D(z) * ell(z) * Dinv(z), 1) / mp.mnorm(rebuilt, 1)
        spec = max(abs(a - b) for a, b in zip(sorted(mp.eig(rebuilt)[0], key=lambda c: (c.real, c.imag)),
                                             sorted(mp.eig(ell(z))[0], key=lambda c: (c.real, c.imag)), strict=True))
        # a vector that is no eigenvector: the residue at eta does not vanish
        bad = mp.mnorm(dressing(proj(v + mp.matrix([0.01, 0, 0])))[0](eta) * ell(eta) *
                       proj(v + mp.matrix([0.01, 0, 0])), 1) / size
        residual = max(res_eta, res_bar, herm, recon, spec / size)
        note = "" if bad > 1e-6 else "a non-eigenvector left no pole (the check cannot fail)"
        return Outcome(Verdict.from_residual(residual if not note else 1.0, note=note))
