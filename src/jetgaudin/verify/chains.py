"""Checks for the chains (issue 12; the paper's introduction and conclusion): the r-matrix structure of the sum
over sites, the exact partial-fraction form of the integrals h_(i,m), their involution and the Casimirs.

Everything is rebuilt from the definitions with SymPy (the numpy implementation is not imported): the chain Lax
matrix ``L(l) = b.sigma + sum_i sum_k sigma.y^(i)_k / (l - l_i)^(k+1)`` and the bracket (LP) inside each site, zero
between sites.
"""

from __future__ import annotations

import itertools

import sympy as sp

from ._registry import Outcome, Verdict, register
from ._tools import BVEC, SIGMA, eps, hat, is_zero, linear_identity, lp_bracket, sym_state

lam, mu = sp.symbols("lambda mu")


def _chain_state(orders):
    return [sym_state(N, prefix=f"s{i + 1}y") for i, N in enumerate(orders)]


def _xi(ys, sites, bvec, at):
    out = list(bvec)
    for (p, N), y in zip(sites, ys, strict=True):
        for k in range(N):
            for a in range(3):
                out[a] = out[a] + y[k][a] / (at - p) ** (k + 1)
    return out


def _bracket(f, g, ys):
    """The chain bracket: (LP) inside each site, sites commute."""
    return sp.expand(sum(lp_bracket(f, g, y) for y in ys))


def _r_matrix_holds(sites) -> bool:
    ys = _chain_state([N for _, N in sites])
    lhs = sp.zeros(4, 4)
    for (p, N), y in zip(sites, ys, strict=True):
        for k, m in itertools.product(range(N), range(N)):
            if k + m >= N:
                continue
            for a, b, c in itertools.permutations(range(3)):
                lhs += (sp.kronecker_product(SIGMA[a], SIGMA[b]) * eps(a, b, c) * y[k + m][c]
                        / ((lam - p) ** (k + 1) * (mu - p) ** (m + 1)))
    r = sum((sp.kronecker_product(SIGMA[a], SIGMA[a]) for a in range(3)), sp.zeros(4, 4)) / (lam - mu)
    S = (sp.kronecker_product(hat(_xi(ys, sites, BVEC, lam)), sp.eye(2))
         + sp.kronecker_product(sp.eye(2), hat(_xi(ys, sites, BVEC, mu))))
    # both sides are linear in the y's and b: the identity holds iff the coefficient of each of them (a matrix of
    # rational functions of lam, mu and the positions) vanishes, which is cheap to decide
    diff = lhs - (r * S - S * r)
    return linear_identity(diff, [x for site in ys for y in site for x in y] + list(BVEC))


@register(
    "Chain-r",
    "1",
    "The sum over sites of jet Lax matrices at distinct points l_i, plus a constant b.sigma, satisfies (er) with the "
    "same r(l - m) (the direct-sum construction of the introduction): sites [(-1, 1), (1/2, 2)], symbolic b (with "
    "--full also [(a1, 1), (a2, 2)] with symbolic a1, a2, and [(-1, 2), (2, 3)])",
    "exact SymPy simplification of the 4x4 rational matrices",
)
def _chain_r(ctx):
    a1, a2 = sp.symbols("a1 a2", real=True)
    cases = [[(-1, 1), (sp.Rational(1, 2), 2)]] + ([[(a1, 1), (a2, 2)], [(-1, 2), (2, 3)]] if ctx.full else [])
    ok = all(_r_matrix_holds(s) for s in cases)
    return Outcome(Verdict.exact(ok))


def _h_partial_fractions(sites, ys, b):
    """h_(i,m) as the Laurent coefficients of nu^2 = <xi, xi> at l_i (derivatives of (l - l_i)^(2N_i) nu^2)."""
    xi = _xi(ys, sites, (0, 0, b), lam)
    nu2 = sum(x * x for x in xi)
    out = []
    for p, N in sites:
        g = sp.cancel(sp.together(nu2 * (lam - p) ** (2 * N)))
        for m in range(1, 2 * N + 1):
            n = 2 * N - m
            out.append(sp.expand(sp.diff(g, lam, n).subs(lam, p) / sp.factorial(n)))
    return nu2, out


def _h_closed_form(sites, ys, b):
    """h_(i,m) by the closed formula of jetgaudin.gaudin.model (Taylor coefficients of the other sites)."""
    out = []
    for i, (p, N) in enumerate(sites):
        for m in range(1, 2 * N + 1):
            h = sum(sum(ys[i][k][a] * ys[i][m - 2 - k][a] for a in range(3)) for k in range(N) if 0 <= m - 2 - k < N)
            for n in range(N - m + 1):
                r = [0, 0, b if n == 0 else 0]
                for j, (q, Nj) in enumerate(sites):
                    if j != i:
                        for k in range(Nj):
                            c = (-1) ** n * sp.binomial(k + n, n) / sp.Integer(1) / (p - q) ** (k + n + 1)
                            r = [r[a] + c * ys[j][k][a] for a in range(3)]
                h += 2 * sum(ys[i][m - 1 + n][a] * r[a] for a in range(3))
            out.append(sp.expand(h))
    return out


@register(
    "Chain-integrals",
    "2",
    "nu^2 = <xi, xi> = b^2 + sum_i sum_(m=1..2N_i) h_(i,m) (l - l_i)^-m exactly; the h_(i,m) equal the closed formula "
    "of jetgaudin.gaudin; they Poisson-commute; h_(i,m), m > N_i, are Casimirs of g^(N_i) (sites [(-1, 1), (1/2, 2)] "
    "and [(-1, 1), (0, 1), (3/2, 1)]; [(0, 3), (1, 2)] with --full)",
    "exact SymPy: partial fractions, symbolic brackets",
)
def _chain_integrals(ctx):
    b = sp.Symbol("b", real=True)
    cases = [[(-1, 1), (sp.Rational(1, 2), 2)], [(-1, 1), (0, 1), (sp.Rational(3, 2), 1)]]
    if ctx.full:
        cases.append([(0, 3), (1, 2)])
    notes = []
    for sites in cases:
        sites = [(sp.nsimplify(p), N) for p, N in sites]
        ys = _chain_state([N for _, N in sites])
        nu2, h = _h_partial_fractions(sites, ys, b)
        expansion = b**2 + sum(hh * (lam - p) ** (-m) for hh, (p, m) in zip(
            h, [(p, m) for p, N in sites for m in range(1, 2 * N + 1)], strict=True))
        if not is_zero(nu2 - expansion):
            notes.append(f"{sites}: nu^2 is not b^2 + its principal parts")
        if any(not is_zero(x - y) for x, y in zip(h, _h_closed_form(sites, ys, b), strict=True)):
            notes.append(f"{sites}: the closed formula differs from the partial fractions")
        if any(not is_zero(_bracket(f, g, ys)) for f, g in itertools.combinations(h, 2)):
            notes.append(f"{sites}: two integrals do not commute")
        k = 0
        flat = [x for site in ys for y in site for x in y]
        for p, N in sites:
            for m in range(1, 2 * N + 1):
                if m > N and any(not is_zero(_bracket(h[k], x, ys)) for x in flat):
                    notes.append(f"{sites}: h_({p},{m}) is not a Casimir")
                k += 1
    ok = not notes
    return Outcome(Verdict.exact(ok, "; ".join(notes)))
