"""Checks of Section 6's central claims for the maps themselves, any N: both Bäcklund maps are Poisson maps of
(LP) and preserve every integral of Prop. 2; the one-point map is complex (Remark 2), the two-point map nonlinear
(Remark 3); (ansatz).

The maps are the exact 50-digit dressings of :mod:`jetgaudin.verify._tools` (nothing from the numpy library).
The Jacobian ``J = dB/dX`` is computed by an independent route, central differences at 80 digits with step
``h = 1e-25``: truncation error ``O(h^2) ~ 1e-50`` and round-off ``~1e-80/h = 1e-55`` (both times the size of
the third derivatives, O(1) at the random points), far below ``NUMERIC_TOL = 1e-30``, while a map that is not
Poisson gives an O(1) defect.  The branch of ``nu`` is continued from the unperturbed point (the root closest
to it), so every difference quotient differentiates one smooth branch.
"""

from __future__ import annotations

import mpmath as mp
import sympy as sp

from ._registry import Outcome, Verdict, register
from ._tools import (
    ell_from_state,
    is_zero,
    nu_at,
    one_point_map,
    rand_mpc,
    rand_mpf,
    rand_state,
    rel,
    spectral_kappas,
    state_from_ell,
    two_point_map,
)
from .structure import lp_constants

NS = range(1, 6)  # N = 1..5
JAC_DPS = 80
JAC_H = mp.mpf("1e-25")


def _flat(ys):
    return [c for y in ys for c in y]


def _unflat(X):
    return [list(X[3 * i : 3 * i + 3]) for i in range(len(X) // 3)]


def _closest(nu, ref):
    return nu if ref is None or abs(nu - ref) <= abs(nu + ref) else -nu


def one_point(X: list, b: mp.mpf, eta: mp.mpc, ref: mp.mpc | None = None) -> tuple[list, mp.mpc, mp.mpf]:
    """The one-point map (rr) at ``(eta, nu)``, ``nu`` the root closest to ``ref``: ``(image, nu, residual)``."""
    ell = ell_from_state(_unflat(X), b)
    nu = _closest(nu_at(ell, eta), ref)
    new, res, _, _ = one_point_map(ell, b, eta, nu)
    return _flat(state_from_ell(new)), nu, res


def two_point_real(X: list, b: mp.mpf, eta: mp.mpc, ref: mp.mpc | None = None) -> tuple[list, mp.mpc, mp.mpf]:
    """The real two-point map (128) with ``eta1 = eta``, ``eta2 = conj(eta)``, ``nu2 = conj(nu1)``."""
    ell = ell_from_state(_unflat(X), b)
    nu = _closest(nu_at(ell, eta), ref)
    new, res, _, _ = two_point_map(ell, eta, mp.conj(eta), nu, mp.conj(nu))
    return [mp.re(c) for c in _flat(state_from_ell(new))], nu, res


def _pi(c, X):
    n = len(X)
    P = [[mp.mpf(0)] * n for _ in range(n)]
    for (i, j), ks in c.items():
        P[i][j] = sum(v * X[k] for k, v in ks.items())
    return P


def _poisson_defect(F, X, c):
    """``max |J Pi(X) J^T - Pi(F(X))| / (1 + max |Pi(F(X))|)`` with ``J`` by central differences."""
    n = len(X)
    Y, ref, res = F(X, None)
    cols = []
    for j in range(n):
        Xp = list(X)
        Xm = list(X)
        Xp[j] += JAC_H
        Xm[j] -= JAC_H
        Fp, _, _ = F(Xp, ref)
        Fm, _, _ = F(Xm, ref)
        cols.append([(a - b_) / (2 * JAC_H) for a, b_ in zip(Fp, Fm, strict=True)])
    J = [[cols[j][i] for j in range(n)] for i in range(n)]
    P = _pi(c, X)
    JP = [[sum(J[i][k] * P[k][m] for k in range(n)) for m in range(n)] for i in range(n)]
    JPJ = [[sum(JP[i][m] * J[j][m] for m in range(n)) for j in range(n)] for i in range(n)]
    PB = _pi(c, Y)
    scale = 1 + max(abs(x) for row in PB for x in row)
    return max(max(abs(JPJ[i][j] - PB[i][j]) for i in range(n) for j in range(n)) / scale, res)


def _npts(ctx, default):
    return 10 if ctx.full else default


@register(
    "BT-poisson-one-point",
    "6.1",
    "Section 6.1: the one-point map (rr), (hh), (hhh) is a Poisson map of (LP) (complex states, complex eta): "
    "J Pi(X) J^T = Pi(B(X)), any N (N = 1..5)",
    "J by central differences at 80 digits (h = 1e-25; error ~1e-50) of the exact dressing, 3 (10 with --full) "
    "seeded random complex points per N (15 in all)",
)
def _bt_poisson_one(ctx):
    return _poisson_check(ctx, one_point, complex_=True)


def _poisson_check(ctx, step, complex_: bool) -> Outcome:
    """Worst Poisson defect of ``step(X, b, eta, ref)`` at seeded random points, N = 1..5."""
    rng = ctx.rng()
    worst = mp.mpf(0)
    with mp.workdps(JAC_DPS):
        for N in NS:
            c = lp_constants(N)
            for _ in range(_npts(ctx, 3)):
                X = _flat(rand_state(rng, N, complex_=complex_))
                b, eta = rand_mpf(rng, 0.5, 2), rand_mpc(rng)
                worst = max(worst, _poisson_defect(lambda Z, ref, b=b, eta=eta: step(Z, b, eta, ref), X, c))
    return Outcome(Verdict.from_residual(worst))


@register(
    "BT-poisson-two-point",
    "6.2",
    "Section 6.2: the real two-point map (eta1 = conj eta2 = eta, nu2 = conj nu1) is a Poisson map of (LP): "
    "J Pi(X) J^T = Pi(B(X)), any N (N = 1..5)",
    "J by central differences at 80 digits (h = 1e-25; error ~1e-50) of the exact dressing, 3 (10 with --full) "
    "seeded random real points per N (15 in all)",
)
def _bt_poisson_two(ctx):
    return _poisson_check(ctx, two_point_real, complex_=False)


@register(
    "BT-integrals",
    "6",
    "Section 6 (BT property 1; 'integrable map'): the one-point map, the real two-point map and the complex "
    "two-point map preserve every integral of Prop. 2 (<b,b>, H_1..H_N, C_1..C_N), any N (N = 1..5)",
    "mpmath (50 digits): Laurent coefficients of <xi, xi> before and after the exact dressing, 8 (20 with --full) "
    "seeded random points per map and N (120 in all)",
)
def _bt_integrals(ctx):
    worst = mp.mpf(0)
    with ctx.precise() as rng:
        for N in NS:
            for _ in range(20 if ctx.full else 8):
                Xc = _flat(rand_state(rng, N, complex_=True))
                Xr = _flat(rand_state(rng, N))
                b, e1, e2 = rand_mpf(rng, 0.5, 2), rand_mpc(rng), rand_mpc(rng)
                ell = ell_from_state(_unflat(Xc), b)
                two, res2, _, _ = two_point_map(ell, e1, e2, nu_at(ell, e1), nu_at(ell, e2))
                for X, (Y, _, res) in ((Xc, one_point(Xc, b, e1)), (Xr, two_point_real(Xr, b, e1)),
                                       (Xc, (_flat(state_from_ell(two)), None, res2))):
                    k0, k1 = spectral_kappas(_unflat(X), b), spectral_kappas(_unflat(Y), b)
                    worst = max(worst, res, max(rel(a, c) for a, c in zip(k1, k0, strict=True)))
    return Outcome(Verdict.from_residual(worst))


def _bounded_below(ctx, n, value, bound, what):
    """Holds when ``value(rng, k) > bound`` for every ``k < n`` (at ``ctx.dps`` digits, ``rng`` the check's seeded
    source); the note gives the smallest value, called ``what``."""
    with ctx.precise() as rng:
        smallest = min(value(rng, k) for k in range(n))
    return Outcome(Verdict.exact(smallest > bound, f"{what}: {mp.nstr(smallest, 3)}"))


@register(
    "Rem-complex",
    "6.1",
    "Remark 2 of Section 6.1: the one-point map is a complex transformation (not a physical BT): it maps real "
    "states to complex ones, for real and for complex eta",
    "mpmath (50 digits): imaginary part of the exact one-point image of 10 seeded random real states (5 with real "
    "eta, 5 with complex eta), N = 3",
)
def _rem_complex(ctx):
    def imaginary_part(rng, k):
        X = _flat(rand_state(rng, 3))
        b = rand_mpf(rng, 0.5, 2)
        eta = rand_mpf(rng, 0.5, 3) if k < 5 else rand_mpc(rng)
        Y, _, _ = one_point(X, b, eta)
        return max(abs(mp.im(y)) for y in Y)

    return _bounded_below(ctx, 10, imaginary_part, 1e-3, "smallest max|Im B(X)| over the samples")


@register(
    "Rem-nonlinear",
    "6.2",
    "Remark 3 of Section 6.2: despite its matrix form, the map (2p) X -> Phi(s,t) X + X0(s,t) is nonlinear "
    "(s, t depend on X)",
    "mpmath (50 digits): B((X+Y)/2) - (B(X) + B(Y))/2 at 6 seeded random real pairs (an affine map gives 0)",
)
def _rem_nonlinear(ctx):
    def midpoint_defect(rng, _):
        X = _flat(rand_state(rng, 3))
        Y = [x + rand_mpf(rng, -0.3, 0.3) for x in X]
        b, eta = rand_mpf(rng, 0.5, 2), rand_mpc(rng)
        BX, ref, _ = two_point_real(X, b, eta)
        BY, _, _ = two_point_real(Y, b, eta, ref)
        BM, _, _ = two_point_real([(x + y) / 2 for x, y in zip(X, Y, strict=True)], b, eta, ref)
        return max(abs(m - (p + q) / 2) for m, p, q in zip(BM, BX, BY, strict=True))

    return _bounded_below(ctx, 6, midpoint_defect, 1e-6, "smallest midpoint defect")


@register(
    "ansatz",
    "6.1",
    "(ansatz): M(l; eta) = [[l - eta + p q, p], [q, 1]] has det M = l - eta",
    "exact SymPy",
)
def _ansatz(ctx):
    lam, eta, p, q = sp.symbols("lambda eta p q")
    ok = is_zero(sp.Matrix([[lam - eta + p * q, p], [q, 1]]).det() - (lam - eta))
    return Outcome(Verdict.exact(ok))
