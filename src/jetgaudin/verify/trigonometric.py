"""Checks for the trigonometric (XXZ) family (issue 23): its r-matrix, its integrals, the gauge rule of its real
two-point map and its one-point maps with their factorisation of the two-point map.  Not in the paper (its conclusion
announces the construction for the trigonometric r-matrix): these checks stand beside the paper's, in a section of
their own ("XXZ").

Everything is rebuilt from the definitions with SymPy and mpmath (the numpy implementation is not imported).
``γ = 1`` (``ℓ_γ(λ) = γ ℓ_1(γλ; γλ_j, b/γ)`` is an exact rescaling).  Trigonometric functions are written in
``E = e^{iλ}``, ``F = e^{iμ}``, ``P_j = e^{iλ_j}`` (symbolic, so every position at once):
``cot(λ − λ_j) = i(E² + P_j²)/(E² − P_j²)``, ``1/sin(λ − λ_j) = 2iEP_j/(E² − P_j²)``, ``d/dλ = iE d/dE``;
every identity is then one between rational functions, decided exactly.
"""

from __future__ import annotations

import itertools

import mpmath as mp
import sympy as sp

from ._registry import Outcome, Verdict, register
from ._tools import SIGMA, hat, is_zero, linear_identity, lp_bracket, rand_mpf, sym_state

I = sp.I
E, F = sp.symbols("E F")


def _w(x_exp, p_exp, a):
    """``w_a(λ − λ_j)`` in the exponentials ``x_exp = e^{iλ}``, ``p_exp = e^{iλ_j}``: ``1/sin`` (a = 0, 1), ``cot``
    (a = 2)."""
    d = x_exp**2 - p_exp**2
    return 2 * I * x_exp * p_exp / d if a < 2 else I * (x_exp**2 + p_exp**2) / d


def _phi(x_exp, p_exp, a, k):
    """``φ_{a,k} = (−1)^k w_a^{(k)}/k!`` with ``d/dλ = i x d/dx``."""
    f = _w(x_exp, p_exp, a)
    for _ in range(k):
        f = I * x_exp * sp.diff(f, x_exp)
    return (-1) ** k * f / sp.factorial(k)


def _xi(ys, orders, P, b, x_exp):
    out = [0, 0, b]
    for y, N, p in zip(ys, orders, P, strict=True):
        for k in range(N):
            for a in range(3):
                out[a] = out[a] + y[k][a] * _phi(x_exp, p, a, k)
    return out


def _bracket(f, g, ys):
    return sp.expand(sum(lp_bracket(f, g, y) for y in ys))


def _r_matrix_holds(orders) -> bool:
    ys = [sym_state(N, prefix=f"s{i + 1}y") for i, N in enumerate(orders)]
    P = sp.symbols(f"P1:{len(orders) + 1}")
    b = sp.Symbol("b")
    xl, xm = _xi(ys, orders, P, b, E), _xi(ys, orders, P, b, F)
    lhs = sp.zeros(4, 4)
    for a, c in itertools.product(range(3), range(3)):
        br = _bracket(xl[a], xm[c], ys)
        if br != 0:
            lhs += br * sp.kronecker_product(SIGMA[a], SIGMA[c])
    r = sum((_w(E, F, a) * sp.kronecker_product(SIGMA[a], SIGMA[a]) for a in range(3)), sp.zeros(4, 4))
    S = sp.kronecker_product(hat(xl), sp.eye(2)) + sp.kronecker_product(sp.eye(2), hat(xm))
    # both sides are linear in the y's and b: the identity holds iff each coefficient (a rational function of E, F
    # and the P_j) vanishes
    return linear_identity(lhs - (r * S - S * r), [x for site in ys for y in site for x in y] + [b])


@register(
    "Trig-r",
    "XXZ",
    "The trigonometric chain L(l) = b sigma^3 + sum_j sum_k sum_a y^(j)a_k phi_(a,k)(l - l_j) sigma^a (w_1 = w_2 = "
    "1/sin, w_3 = cot) satisfies {L(l) (x) L(m)} = [r(l - m), L(l) (x) 1 + 1 (x) L(m)] with r(x) = sum_a w_a(x) "
    "sigma^a (x) sigma^a: sites of orders (1, 2) at symbolic positions, symbolic b (with --full also (2, 2))",
    "exact SymPy: rational functions of e^(i l), e^(i m), e^(i l_j)",
)
def _trig_r(ctx):
    cases = [(1, 2)] + ([(2, 2)] if ctx.full else [])
    return Outcome(Verdict.exact(all(_r_matrix_holds(c) for c in cases)))


@register(
    "Trig-integrals",
    "XXZ",
    "Order-1 sites: nu^2 = u^2 + vw = b^2 - J^2 + sum_j [C_j / sin^2(l - l_j) + 2 H_j cot(l - l_j)] exactly, with "
    "C_j = |s_j|^2 and H_j = b s_j^3 + sum_(k != j) [cot(l_j - l_k) s_j^3 s_k^3 + (s_j^1 s_k^1 + s_j^2 s_k^2) / "
    "sin(l_j - l_k)]; sum_j H_j = bJ; the H_j and J Poisson-commute; the C_j are Casimirs (2 sites at symbolic "
    "positions, symbolic b; 3 sites with --full)",
    "exact SymPy: rational functions of e^(i l), e^(i l_j)",
)
def _trig_integrals(ctx):
    n = 3 if ctx.full else 2
    ys = [sym_state(1, prefix=f"s{i + 1}y") for i in range(n)]
    s = [y[0] for y in ys]
    P = sp.symbols(f"P1:{n + 1}")
    b = sp.Symbol("b")
    xi = _xi(ys, [1] * n, P, b, E)
    nu2 = xi[2] ** 2 + xi[0] ** 2 + xi[1] ** 2
    J = sum(x[2] for x in s)
    C = [sum(x[a] ** 2 for a in range(3)) for x in s]
    H = [b * s[j][2] + sum(_w(P[j], P[k], 2) * s[j][2] * s[k][2] + _w(P[j], P[k], 0) * (s[j][0] * s[k][0]
                                                                                           + s[j][1] * s[k][1])
                           for k in range(n) if k != j) for j in range(n)]
    expansion = b**2 - J**2 + sum(C[j] * _w(E, P[j], 0) ** 2 + 2 * H[j] * _w(E, P[j], 2) for j in range(n))
    notes = []
    if not is_zero(nu2 - expansion):
        notes.append("nu^2 is not the stated expansion")
    if not is_zero(sum(H) - b * J):
        notes.append("sum H_j != bJ")
    if any(not is_zero(_bracket(f, g, ys)) for f, g in itertools.combinations(H + [J], 2)):
        notes.append("two of the H_j, J do not commute")
    flat = [x for y in s for x in y]
    if any(not is_zero(_bracket(c, x, ys)) for c in C for x in flat):
        notes.append("a C_j is not a Casimir")
    return Outcome(Verdict.exact(not notes, "; ".join(notes)))


def _lax(state, pos, b, lam):
    """``ℓ(λ) = [[u, v], [w, −u]]`` of order-1 sites (mpmath)."""
    u, v, w = mp.mpc(b), mp.mpc(0), mp.mpc(0)
    for (s1, s2, s3), p in zip(state, pos, strict=True):
        u += s3 * mp.cot(lam - p)
        v += (s1 - 1j * s2) / mp.sin(lam - p)
        w += (s1 + 1j * s2) / mp.sin(lam - p)
    return mp.matrix([[u, v], [w, -u]])


def _residues(state):
    """The residues ``[[s^3, s^-], [s^+, −s^3]]`` of ``ℓ`` at order-1 sites."""
    return [mp.matrix([[s3, s1 - 1j * s2], [s1 + 1j * s2, -s3]]) for s1, s2, s3 in state]


def _dressed(D, res, pos):
    """The residues ``D(λ_j) R_j D(λ_j)^{-1}`` of ``ℓ̃ = D ℓ D^{-1}`` (``D`` a function of ``λ``, regular at the
    sites)."""
    return [D(p) * R * D(p) ** -1 for R, p in zip(res, pos, strict=True)]


def _rebuild(res, pos, b, lam):
    """``b σ_3 + Σ_j`` the residue ``R_j`` times ``cot`` (diagonal) and ``1/sin`` (off-diagonal) at ``λ − λ_j``: the
    trigonometric Lax matrix of those residues."""
    out = mp.matrix([[b, 0], [0, -b]])
    for R, p in zip(res, pos, strict=True):
        out += mp.matrix([[R[0, 0] * mp.cot(lam - p), R[0, 1] / mp.sin(lam - p)],
                          [R[1, 0] / mp.sin(lam - p), R[1, 1] * mp.cot(lam - p)]])
    return out


def _random_case(rng):
    """Three order-1 sites near ``−1, 0, 1``, their spins, ``b`` in ``[0.5, 1.5]`` and ``ξ`` (mpmath, the caller's
    precision)."""
    pos = [mp.mpf(-1) + rand_mpf(rng, 0, 0.3), rand_mpf(rng, -0.2, 0.2), 1 + rand_mpf(rng, 0, 0.3)]
    state = [[rand_mpf(rng) for _ in range(3)] for _ in pos]
    return pos, state, rand_mpf(rng, 0.5, 1.5), mp.mpc(rand_mpf(rng, 0.3, 0.6), rand_mpf(rng, 0.2, 0.5))


def _dressing(k, xi, lam):
    """The gauge rule's closed form ``D(λ)`` (docs/families.md), ``p = |k_1|²``, ``q = |k_2|²``."""
    p, q = abs(k[0]) ** 2, abs(k[1]) ** 2
    s1, s2, s0 = mp.sin(lam - xi), mp.sin(lam - mp.conj(xi)), mp.sin(xi - mp.conj(xi))
    return mp.matrix([[p * s1 + q * s2, -k[0] * mp.conj(k[1]) * s0],
                      [-mp.conj(k[0]) * k[1] * s0, q * s1 + p * s2]]) / (p + q)


@register(
    "Trig-gauge",
    "XXZ",
    "The real two-point map of order-1 sites: D(l) = [[p s(l - xi) + q s(l - conj xi), -k1 conj(k2) s(xi - conj xi)], "
    "[-conj(k1) k2 s(xi - conj xi), q s(l - xi) + p s(l - conj xi)]] / (p + q), s = sin, k the eigenvector of l(xi) "
    "for nu, p = |k1|^2, q = |k2|^2: D(xi) k = 0, D(conj xi) (-conj k2, conj k1) = 0, alpha alpha_0 = delta delta_0, "
    "and l~ = D l D^-1 is again a real trigonometric Lax matrix with the same b and J (its residues at the sites, "
    "b sigma^3 and the 1/sin, cot functions reproduce it at random l; l~(conj l) = l~(l)^dagger); "
    "at Im xi -> 0 the map is the identity (which fixes the sign of the gauge)",
    "50-digit evaluation at random points (3 sites)",
)
def _trig_gauge(ctx):
    with ctx.precise() as rng:
        pos, state, b, xi = _random_case(rng)
        L = _lax(state, pos, b, xi)
        nu = mp.sqrt(L[0, 0] ** 2 + L[0, 1] * L[1, 0])
        k = [L[0, 1], nu - L[0, 0]]
        # the coefficients of e^{+-i l} on the diagonal: alpha alpha_0 = delta delta_0
        p, q = abs(k[0]) ** 2, abs(k[1]) ** 2
        e1, e2 = mp.exp(-1j * xi), mp.exp(-1j * mp.conj(xi))
        al, al0 = (p * e1 + q * e2) / 2j, -(p / e1 + q / e2) / 2j
        de, de0 = (q * e1 + p * e2) / 2j, -(q / e1 + p / e2) / 2j
        res = [abs(al * al0 - de * de0) / abs(al * al0),mp.norm(_dressing(k, xi, xi) * mp.matrix(k)),
               mp.norm(_dressing(k, xi, mp.conj(xi)) * mp.matrix([-mp.conj(k[1]), mp.conj(k[0])]))]
        # new residues at the sites: D R_j adj D / det D at lambda_j
        new = _dressed(lambda lam: _dressing(k, xi, lam), _residues(state), pos)
        Jn = sum(R[0, 0] for R in new)
        res.append(abs(Jn - sum(s[2] for s in state)))
        for _ in range(2):
            lam = mp.mpc(rand_mpf(rng), rand_mpf(rng, 0.1, 1))
            D = _dressing(k, xi, lam)
            Lt = D * _lax(state, pos, b, lam) * D ** -1
            res.append(mp.norm(Lt - _rebuild(new, pos, b, lam)) / mp.norm(Lt))
            D2 = _dressing(k, xi, mp.conj(lam))
            Lc = D2 * _lax(state, pos, b, mp.conj(lam)) * D2 ** -1
            res.append(mp.norm(Lc - Lt.H) / mp.norm(Lt))
        # continuity: at Im xi = 10^-40 the map is the identity up to O(10^-40) (this fixes the sign of the gauge)
        xi0 = mp.mpc(xi.real, mp.mpf(10) ** -40)
        L0 = _lax(state, pos, b, xi0)
        nu0 = mp.sqrt(L0[0, 0] ** 2 + L0[0, 1] * L0[1, 0])
        k0 = [L0[0, 1], nu0 - L0[0, 0]]
        for R, Rt in zip(_residues(state), _dressed(lambda lam: _dressing(k0, xi0, lam), _residues(state), pos),
                         strict=True):
            res.append(mp.norm(Rt - R) / mp.norm(R))  # O(10^-40)
    return Outcome(Verdict.from_residual(max(res)))


def _one_point(res, pos, b, eta, nu, inverse):
    """The one-point dressing ``D(λ)`` (docs/families.md §3.1, ``γ = 1``) of the state with residues ``res`` at
    ``η`` for ``ν``: ``[[sin(λ−η) + pq e^{−i(λ−η)}, p], [q, e^{−i(λ−η)}]]`` with ``q = (u(η) − ν)/v(η)``,
    ``p = Σ_j e^{i(λ_j − η)} s_j^-/(2(b + iJ))``; the inverse map ``adj`` of it with ``p = (u(η) − ν)/w(η)``,
    ``q = Σ_j e^{i(λ_j − η)} s_j^+/(2(b + iJ))``.  Returns ``(D, (p, q))``."""
    L = _rebuild(res, pos, b, eta)
    S = sum(mp.exp(1j * (lj - eta)) * R[1 if inverse else 0, 0 if inverse else 1] for R, lj in zip(res, pos,
                                                                                                  strict=True))
    norm = S / (2 * (b + 1j * sum(R[0, 0] for R in res)))
    spec = (L[0, 0] - nu) / (L[1, 0] if inverse else L[0, 1])
    p, q = (spec, norm) if inverse else (norm, spec)

    def D(lam):
        e = mp.exp(-1j * (lam - eta))
        M = mp.matrix([[mp.sin(lam - eta) + p * q * e, p], [q, e]])
        return mp.matrix([[M[1, 1], -M[0, 1]], [-M[1, 0], M[0, 0]]]) if inverse else M

    return D, (p, q)


#: the statement of Trig-one-point (docs/families.md §3.1)
_ONE_POINT = (
    "The one-point map of order-1 sites, D(l) = [[sin(l - xi) + pq e^(-i(l - xi)), p], [q, e^(-i(l - xi))]] with "
    "q = (u(xi) - nu)/v(xi), p = sum_j e^(i(l_j - xi)) s_j^- / (2(b + iJ)): D(xi) k = 0, and l~ = D l D^-1 is again a "
    "trigonometric Lax matrix with the same b and J (residues at the sites reproduce it at random l); then the "
    "inverse one-point map (adj D with p' = (u~ - conj nu)/w~, q' = sum_j e^(i(l_j - conj xi)) s~_j^+ / (2(b + iJ))) "
    "at conj xi has q' = e^(i(xi - conj xi)) q, and the composition is the real two-point map (Trig-gauge's D) "
    "followed by l -> diag(rho, 1) l diag(rho, 1)^-1, rho = e^(2 Im xi)"
)


@register("Trig-one-point", "XXZ", _ONE_POINT, "50-digit evaluation at random points (3 sites)")
def _trig_one_point(ctx):
    with ctx.precise() as rng:
        pos, state, b, xi = _random_case(rng)
        R0 = _residues(state)
        L = _lax(state, pos, b, xi)
        nu = mp.sqrt(L[0, 0] ** 2 + L[0, 1] * L[1, 0])
        k = [L[0, 1], nu - L[0, 0]]
        DA, (_, q) = _one_point(R0, pos, b, xi, nu, False)
        R1 = _dressed(DA, R0, pos)
        res = [mp.norm(DA(xi) * mp.matrix(k)) / mp.norm(DA(xi)),
               abs(sum(R[0, 0] for R in R1) - sum(R[0, 0] for R in R0))]
        for _ in range(2):
            lam = mp.mpc(rand_mpf(rng), rand_mpf(rng, -1, 1))
            Lt = DA(lam) * _rebuild(R0, pos, b, lam) * DA(lam) ** -1
            res.append(mp.norm(Lt - _rebuild(R1, pos, b, lam)) / mp.norm(Lt))
        DB, (_, q2) = _one_point(R1, pos, b, mp.conj(xi), mp.conj(nu), True)
        res.append(abs(q2 - mp.exp(1j * (xi - mp.conj(xi))) * q) / abs(q))
        rho = mp.exp(2 * xi.imag)
        G = mp.matrix([[rho, 0], [0, 1]])
        for R2, Rs in zip(_dressed(DB, R1, pos), _dressed(lambda lam: _dressing(k, xi, lam), R0, pos), strict=True):
            res.append(mp.norm(R2 - G * Rs * G ** -1) / mp.norm(Rs))
    return Outcome(Verdict.from_residual(max(res)))
