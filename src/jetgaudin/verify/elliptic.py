"""Checks for the elliptic (XYZ) family (issue 24; the paper's conclusion announces it, Zullo 2011 builds its maps):
the addition identity of ``w_a = (ns, ds, cs)`` behind the r-matrix, the r-matrix relation itself, the exact
expansion of ``ν²`` with one constant term, and the Clebsch case of the order-2 site.

Independent of the runtime: every function is ``mpmath.ellipfun`` (and ``mpmath.ellipe``/``ellipk``, ``mpmath.quad``
for Jacobi's zeta, ``mpmath.taylor`` for Laurent coefficients) at ``ctx.dps`` digits; nothing from
:mod:`jetgaudin.families` is imported.
"""

from __future__ import annotations

import itertools

import mpmath as mp

from ._registry import Outcome, Verdict, register
from ._tools import eps

#: Pauli matrices (ℓ = Σ_a ξ^a σ_a)
_PAULI = [mp.matrix([[0, 1], [1, 0]]), mp.matrix([[0, -1j], [1j, 0]]), mp.matrix([[1, 0], [0, -1]])]
_NPTS = 4


def _w(a, x, k):
    sn, cn, dn = (mp.ellipfun(f, x, k=k) for f in ("sn", "cn", "dn"))
    return (1 / sn, dn / sn, cn / sn)[a]


def _rnd(rng, lo=-1.0, hi=1.0):
    return mp.mpc(mp.mpf(rng.uniform(lo, hi)), mp.mpf(rng.uniform(lo, hi)))


def _kron(A, B):
    out = mp.matrix(4, 4)
    for i, j, p, q in itertools.product(range(2), repeat=4):
        out[2 * i + p, 2 * j + q] = A[i, j] * B[p, q]
    return out


def _w_defect(k, x, y):
    """The largest relative defect of the addition identity over the permutations (a, b, c) at one point."""
    def one(a, b, c):
        lhs = _w(a, x, k) * _w(b, y, k)
        return abs(lhs - (_w(a, x - y, k) * _w(c, y, k) - _w(b, x - y, k) * _w(c, x, k))) / (1 + abs(lhs))

    return max(one(*p) for p in itertools.permutations(range(3)))


@register(
    "XYZ-w",
    "Conclusions",
    "w_a(x) w_b(y) = w_a(x-y) w_c(y) - w_b(x-y) w_c(x) for (a, b, c) distinct, w = (ns, ds, cs) (the identity that "
    "makes r = (i/2) sum_a w_a sigma_a (x) sigma_a an r-matrix; 1/(xy) partial fractions at k = 0)",
    "mpmath (ctx digits), 4 (8 with --full) seeded random complex x, y and moduli k in (0, 1)",
)
def _w_identity(ctx):
    with ctx.precise() as rng:
        points = [(mp.mpf(rng.uniform(0.05, 0.95)), _rnd(rng), _rnd(rng))
                  for _ in range(2 * _NPTS if ctx.full else _NPTS)]
        worst = max(_w_defect(k, x, y) for k, x, y in points)
    return Outcome(Verdict.from_residual(worst))


@register(
    "XYZ-r",
    "Conclusions",
    "{l(lam) (x) l(mu)} = [r(lam - mu), l(lam) (x) 1 + 1 (x) l(mu)], l = sum_a xi^a sigma_a, "
    "xi^a = sum_j w_a(lam - l_j) s_j^a, {s^a, s^b} = eps_abc s^c per site, r = (i/2) sum_a w_a sigma_a (x) "
    "sigma_a: three sites",
    "mpmath (ctx digits), seeded random complex spins, lam, mu, k",
)
def _r_matrix(ctx):
    worst = mp.mpf(0)
    with ctx.precise() as rng:
        for _ in range(2 if ctx.full else 1):
            k = mp.mpf(rng.uniform(0.1, 0.9))
            pos = [mp.mpf(0), mp.mpf("0.7"), mp.mpf("-1.3")]
            s = [[_rnd(rng) for _ in range(3)] for _ in pos]
            lam, mu = _rnd(rng), _rnd(rng)
            lhs = mp.matrix(4, 4)
            for p, sj in zip(pos, s, strict=True):
                for a, b, c in itertools.permutations(range(3)):
                    term = int(eps(a, b, c)) * sj[c] * _w(a, lam - p, k) * _w(b, mu - p, k)
                    lhs += _kron(_PAULI[a], _PAULI[b]) * term
            r = sum((_kron(_PAULI[a], _PAULI[a]) * (0.5j * _w(a, lam - mu, k)) for a in range(3)), mp.matrix(4, 4))
            ell = [sum((_PAULI[a] * sum(sj[a] * _w(a, at - p, k) for p, sj in zip(pos, s, strict=True))
                        for a in range(3)), mp.matrix(2, 2)) for at in (lam, mu)]
            S = _kron(ell[0], mp.eye(2)) + _kron(mp.eye(2), ell[1])
            d = lhs - (r * S - S * r)
            worst = max(worst, max(abs(d[i, j]) for i in range(4) for j in range(4)) / (1 + mp.mnorm(lhs, 1)))
    return Outcome(Verdict.from_residual(worst))


def _zeta(u, k):
    """Jacobi's Z(u) = ∫_0^u dn² − (E/K) u (straight path; the points used keep |Im u| < K'/2)."""
    m = k * k
    return mp.quad(lambda t: mp.ellipfun("dn", t * u, m=m) ** 2 * u, [0, 1]) - mp.ellipe(m) / mp.ellipk(m) * u


@register(
    "XYZ-nu2",
    "Conclusions",
    "nu^2 = sum_a xi_a^2 = c0 + sum_j [h_j2 psi_2(lam - l_j) + h_j1 psi_1(lam - l_j)] exactly for order-1 sites, "
    "psi_1 = F = cs dn + Z (Jacobi zeta), psi_2 = -F' = ns^2 - 1 + E/K, with sum_j h_j1 = 0: the constant c0 is the "
    "same at every lam",
    "mpmath (ctx digits): h_jm as Laurent coefficients (mpmath.taylor of (lam - l_j)^2 nu^2), nu^2 - sum h psi at 2 "
    "seeded points (Z by quadrature)",
)
def _nu2(ctx):
    with ctx.precise() as rng:
        k = mp.mpf(rng.uniform(0.2, 0.8))
        EK = mp.ellipe(k * k) / mp.ellipk(k * k)
        pos = [mp.mpf(0), mp.mpf("0.8"), mp.mpf("-0.9")]
        s = [[mp.mpf(rng.uniform(-1, 1)) for _ in range(3)] for _ in pos]

        def nu2(lam):
            return sum(sum(sj[a] * _w(a, lam - p, k) for p, sj in zip(pos, s, strict=True)) ** 2 for a in range(3))

        h = []
        for p in pos:
            c = mp.taylor(lambda z, p=p: z * z * nu2(p + z) if z != 0 else sum(x * x for x in s[pos.index(p)]),
                          0, 1)
            h.append((c[1], c[0]))  # (h_j1, h_j2)

        def F(x):
            return _w(2, x, k) * mp.ellipfun("dn", x, k=k) + _zeta(x, k)

        consts = []
        for _ in range(2):
            lam = mp.mpc(mp.mpf(rng.uniform(-1.5, 1.5)), mp.mpf(rng.uniform(0.1, 0.6)))
            rest = sum(h1 * F(lam - p) + h2 * (_w(0, lam - p, k) ** 2 - 1 + EK) for (h1, h2), p in zip(h, pos,
                                                                                                       strict=True))
            consts.append(nu2(lam) - rest)
        scale = 1 + max(abs(h2) for _, h2 in h)
        resid = max(abs(consts[0] - c) for c in consts[1:]) / scale
        resid = max(resid, abs(sum(h1 for h1, _ in h)) / scale)
    # mp.taylor (differences at raised precision) and mp.quad for Z: round-off of the working precision; a wrong
    # expansion (F without Z, or sum_j h_j1 != 0) leaves an O(1) residual
    return Outcome(Verdict.from_residual(resid))


@register(
    "XYZ-Clebsch",
    "Conclusions",
    "one elliptic site of order 2 (xi^a = M_a w_a(lam) - p_a w_a'(lam)): nu^2 = c0 + h2 psi_2 + h3 psi_3 + h4 psi_4 "
    "with c0 + mu h2 = sum a_i M_i^2 + b_i p_i^2, a = (1, k'^2, 0) - E/K + mu, and b_i - a_j a_k independent of i "
    "(Clebsch's case of the Kirchhoff equations) for every mu",
    "mpmath (ctx digits): Laurent coefficients of w_a at 0 (mpmath.taylor of x w_a(x)), the regular part of F from "
    "F' = 1 - E/K - ns^2",
)
def _clebsch(ctx):
    worst = mp.mpf(0)
    with ctx.precise() as rng:
        k = mp.mpf(rng.uniform(0.2, 0.8))
        EK = mp.ellipe(k * k) / mp.ellipk(k * k)
        co = [mp.taylor(lambda x, a=a: x * _w(a, x, k) if x != 0 else mp.mpf(1), 0, 4) for a in range(3)]
        r = [c[2] for c in co]  # w_a = 1/x + r_a x + s_a x^3 + ...
        s3 = [c[4] for c in co]
        # F - 1/x = f1 x + f3 x^3 from F' = 1 - E/K - ns^2, ns^2 = 1/x^2 + 2 r_1 + (2 s_1 + r_1^2) x^2 + ...
        f1 = 1 - EK - 2 * r[0]
        f3 = -(2 * s3[0] + r[0] ** 2) / 3
        # [x^0] (xi^a)^2 = 2 r_a M_a^2 + (r_a^2 - 6 s_a) p_a^2; h2 = |M|^2 - 2 sum r_a p_a^2; h4 = |p|^2
        A = [2 * r[a] + f1 for a in range(3)]
        B = [r[a] ** 2 - 6 * s3[a] - 2 * f1 * r[a] + f3 for a in range(3)]
        # c0 = [x^0] nu^2 - h2 [x^0] psi_2 - h4 [x^0] psi_4, [x^0] psi_2 = -f1, [x^0] psi_4 = -f3
        expect = [1 - EK, 1 - k * k - EK, -EK]
        worst = max(abs(A[a] - expect[a]) for a in range(3))
        for mu in (mp.mpf("0.7"), mp.mpf("2.5")):
            a_ = [A[i] + mu for i in range(3)]
            b_ = [B[i] - 2 * mu * r[i] for i in range(3)]
            c = [b_[i] - a_[(i + 1) % 3] * a_[(i + 2) % 3] for i in range(3)]
            worst = max(worst, abs(c[0] - c[1]), abs(c[1] - c[2]))
    return Outcome(Verdict.from_residual(worst, tol=1e-25))
