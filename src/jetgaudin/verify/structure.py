"""Structural checks of Sections 1-3: (LP) is a Lie algebra, its rank (Liouville count), the reduction (lax2),
the matrix form (yy) for general c_k, g^(1) = su(2), g^(2) = e(3), and Section 3's su(2) (+)_s G with the
cocycle over e(3,2).

The structure constants are rebuilt here from (LP) (``c^{IJ}_K`` with ``I = 3i + a``), independently of
:mod:`jetgaudin.algebra`; every check is exact (integer or rational arithmetic, SymPy).
"""

from __future__ import annotations

import itertools
from typing import Any

import sympy as sp

from ._registry import Outcome, Verdict, exact_for_each, register
from ._tools import BVEC, dot, eps, is_zero, matrix_is_zero, sym_state
from .sec2 import _f_partition, _HC_prop2, _lax, _uvw_at, lam


def lp_constants(N: int, drop=()) -> dict[tuple[int, int], dict[int, int]]:
    """``{(I, J): {K: c^{IJ}_K}}`` of (LP) for ``g^(N)`` (``I = 3 i + a``); ``drop`` lists level pairs
    ``(i, j)`` whose brackets are set to zero (``drop=((1, 1),)`` gives e(3,2) from g^(3))."""
    c: dict[tuple[int, int], dict[int, int]] = {}
    for i, j in itertools.product(range(N), repeat=2):
        if i + j >= N or (i, j) in drop or (j, i) in drop:
            continue
        for a, b in itertools.product(range(3), repeat=2):
            for g in range(3):
                e = int(eps(a, b, g))
                if e:
                    c.setdefault((3 * i + a, 3 * j + b), {})[3 * (i + j) + g] = e
    return c


def _br(c, u: dict[int, object], v: dict[int, object]) -> dict[int, object]:
    """Bracket of two elements (dicts basis index -> coefficient) with structure constants ``c``."""
    out: dict[int, object] = {}
    for i, ui in u.items():
        for j, vj in v.items():
            for k, ck in c.get((i, j), {}).items():
                out[k] = out.get(k, 0) + ck * ui * vj
    return {k: sp.expand(x) for k, x in out.items() if sp.expand(x) != 0}


def _jacobi_defect(c, n: int) -> int:
    """Number of basis triples violating the Jacobi identity (exact integers)."""
    bad = 0
    for i, j, k in itertools.combinations(range(n), 3):
        e: dict[int, Any] = {i: 1}
        f: dict[int, Any] = {j: 1}
        g: dict[int, Any] = {k: 1}
        tot: dict[int, Any] = {}
        for a, b, cc in ((e, f, g), (f, g, e), (g, e, f)):
            for m, x in _br(c, _br(c, a, b), cc).items():
                tot[m] = tot.get(m, 0) + x
        bad += any(x != 0 for x in tot.values())
    return bad


def _bracket_fn(c, f, g, coords):
    """Lie--Poisson bracket of functions: ``sum_{I,J,K} df/dX_I dg/dX_J c^{IJ}_K X_K``."""
    out = 0
    for (i, j), ks in c.items():
        fi = sp.diff(f, coords[i])
        if fi == 0:
            continue
        gj = sp.diff(g, coords[j])
        if gj == 0:
            continue
        out += fi * gj * sum(v * coords[k] for k, v in ks.items())
    return sp.expand(out)


@register(
    "LP-jacobi",
    "2",
    "(LP) is a Lie algebra: {y_i^a, y_j^b} = eps^{ab}_c y_{i+j}^c (0 if i+j >= N) is antisymmetric and "
    "satisfies the Jacobi identity, N = 1..6",
    "exact integer arithmetic on every triple of basis elements (structure constants rebuilt from (LP))",
)
def _jacobi(ctx):
    bad = 0
    for N in range(1, 7):
        c = lp_constants(N)
        anti = all(c.get((j, i), {}).get(k) == -v for (i, j), ks in c.items() for k, v in ks.items())
        bad += _jacobi_defect(c, 3 * N) + (not anti)
    return Outcome(Verdict.exact(bad == 0, f"{bad} violating triples"))


def _rand_rational(rng):
    return sp.Rational(rng.randint(-999, 999), rng.randint(1, 97))


@register(
    "LP-rank",
    "2",
    "Section 2: N is the number of degrees of freedom and Prop. 2's 2N integrals are independent: at generic "
    "points rank Pi = 2N (N Casimirs, leaves of dimension 2N), rank(grad H_k, grad C_k) = 2N, the N fields "
    "Pi grad H_k are independent (Liouville count), N = 1..5",
    "exact rational ranks (SymPy) at 4 (10 with --full) seeded random rational points per N, general b",
)
def _rank(ctx):
    rng = ctx.rng()
    npts = 10 if ctx.full else 4
    bad = []
    for N in range(1, 6):
        ys = sym_state(N)
        coords = [x for y in ys for x in y]
        c = lp_constants(N)
        H, C = _HC_prop2(N, ys, BVEC)
        grads = [[sp.diff(f, x) for x in coords] for f in H + C]
        for _ in range(npts):
            pt = {x: _rand_rational(rng) for x in coords}
            pt.update({bb: _rand_rational(rng) for bb in BVEC})
            Pi = sp.zeros(3 * N, 3 * N)
            for (i, j), ks in c.items():
                Pi[i, j] = sum(v * pt[coords[k]] for k, v in ks.items())
            G = sp.Matrix([[g.subs(pt) for g in row] for row in grads])
            fields = (Pi * G[:N, :].T)
            ranks = (Pi.rank(), G.rank(), G[N:, :].rank(), fields.rank())
            if ranks != (2 * N, 2 * N, N, N):
                bad.append((N, ranks))
    return Outcome(Verdict.exact(not bad, f"(rank Pi, rank grad(H,C), rank grad C, rank Pi grad H) off at {bad}" if bad
                       else "rank Pi = 2N, rank grad(H, C) = 2N, rank grad C = N, rank Pi grad H = N"))


@register(
    "yy",
    "2",
    "(yy): L(l) of (lax) = (i/2)[[u, v], [w, -u]] with u = b^3 + sum f_i y_i^3, v = b^1 - i b^2 + sum f_i "
    "(y_i^1 - i y_i^2), w = b^1 + i b^2 + sum f_i (y_i^1 + i y_i^2), general c_k (partition formula), N = 1..4",
    "exact SymPy",
)
def _yy(ctx):
    def holds(N):
        c = sp.symbols(f"c1:{N}") if N > 1 else ()
        fs = [_f_partition(i, c) for i in range(N)]
        ys = sym_state(N)
        u, v, w = _uvw_at(ys, BVEC, fs, lam)
        return matrix_is_zero(_lax(ys, BVEC, fs, lam) - sp.I / 2 * sp.Matrix([[u, v], [w, -u]]))

    return exact_for_each(range(1, 5), holds)


@register(
    "lax2",
    "2",
    "(lax2): with c_1 = -1, c_k = 0 (2 <= k <= N-1) the partition formula gives f_i = 1/l^(i+1), so (lax) "
    "becomes sum sigma^a [b^a + sum_i y_i^a / l^(i+1)], N = 1..7",
    "exact SymPy (partition formula of Section 2)",
)
def _lax2(ctx):
    def holds(N):
        c = [-1] + [0] * (N - 2)  # c_1 = -1, c_k = 0 (2 <= k <= N - 1)
        return all(is_zero(_f_partition(i, c) - lam ** -(i + 1)) for i in range(N))

    return exact_for_each(range(1, 8), holds)


def _is_sub(c, basis_idx, target_idx) -> bool:
    """``[span(basis_idx), span(basis_idx)] ⊂ span(target_idx)`` for basis vectors."""
    return all(set(_br(c, {i: 1}, {j: 1})) <= set(target_idx) for i in basis_idx for j in basis_idx)


def _maps_into(c, A, B, target) -> bool:
    return all(set(_br(c, {i: 1}, {j: 1})) <= set(target) for i in A for j in B)


@register(
    "Intro-algebras",
    "1",
    "Introduction: g^(1) = su(2) (Euler top) and g^(2) = e(3) = su(2) (+)_s R^3 (Lagrange top)",
    "exact: structure constants of (LP) for N = 1, 2",
)
def _intro(ctx):
    c1 = lp_constants(1)
    su2 = all(c1.get((a, b), {}) == {k: int(eps(a, b, k)) for k in range(3) if eps(a, b, k)}
              for a in range(3) for b in range(3))
    c2 = lp_constants(2)
    y0, y1 = range(3), range(3, 6)
    e3 = (_is_sub(c2, y0, y0) and _maps_into(c2, y0, y1, y1) and _is_sub(c2, y1, ())  # R^3 abelian ideal
          and all(c2[(a, 3 + b)] == {3 + k: int(eps(a, b, k)) for k in range(3) if eps(a, b, k)}
                  for a in range(3) for b in range(3) if a != b))
    return Outcome(Verdict.exact(su2 and e3))


@register(
    "Sec3-structure",
    "3",
    "Section 3: g^(3) = su(2) (+)_s G, dim G = 6, G = span(y1, y2) an ideal containing the abelian proper "
    "subalgebra R^3 = span(y2); G is not abelian and is not R^3 (+)_s R^3: no subalgebra of G is complementary "
    "to span(y2); Introduction: g^(3) contains su(2) and R^3 as proper subalgebras",
    "exact: structure constants of (LP), N = 3; the complement span{y1^a + sum_b A_ab y2^b} with symbolic A",
)
def _structure(ctx):
    c = lp_constants(3)
    y0, y1, y2 = list(range(3)), list(range(3, 6)), list(range(6, 9))
    G = y1 + y2
    ok_su2 = _is_sub(c, y0, y0)
    ok_ideal = _maps_into(c, y0, G, G) and _is_sub(c, G, G)
    ok_r3 = _is_sub(c, y2, ()) and _maps_into(c, G, y2, ()) and _maps_into(c, y0, y2, y2)
    nonabelian = any(_br(c, {i: 1}, {j: 1}) for i in y1 for j in y1)
    A = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"A{i}{j}"))
    W = [{3 + a: 1, **{6 + b: A[a, b] for b in range(3)}} for a in range(3)]
    # [w_a, w_b] lies in span(y2) \ {0}, which meets W only in 0: W is never a subalgebra
    no_complement = all(set(_br(c, W[a], W[b])) <= set(y2) and _br(c, W[a], W[b])
                        for a in range(3) for b in range(3) if a != b)
    # the literal reading fails: G = span(y1^1) (+)_s span(y1^2, y1^3, y2) (a 1-dim subalgebra and a 5-dim ideal)
    I5 = [4, 5] + y2
    literal = _maps_into(c, [3], I5, I5) and _is_sub(c, I5, I5)
    ok = ok_su2 and ok_ideal and ok_r3 and nonabelian and no_complement and len(G) == 6
    return Outcome(Verdict.exact(ok, "G is not R^3 (+)_s R^3; literally it is a semidirect sum span(y1^1) (+)_s "
                           f"span(y1^2, y1^3, y2): {literal}"))


@register(
    "Sec3-cocycle",
    "3",
    "Section 3 (and Introduction, Conclusions): g^(3) is e(3,2) = su(2) (+)_s (R^3 (+) R^3) plus a cocycle, the "
    "last term <y2, grad1 f ^ grad1 g> of the bracket; e(3,2) has the Casimirs <y1,y1>/2, <y1,y2>, <y2,y2>, "
    "which differ from C^(1..3) only by <y0,y2> in C^(1); the cocycle is not trivial (g^(3) is not e(3,2))",
    "exact: Jacobi of e(3,2), cocycle condition d omega = 0, Casimirs by SymPy, radicals G abelian / not abelian",
)
def _cocycle(ctx):
    cg = lp_constants(3)
    ce = lp_constants(3, drop=((1, 1),))
    n = 9
    # omega = c_g - c_e: only {y1^a, y1^b} = eps y2^c
    omega = {k: v for k, v in cg.items() if k not in ce}
    ok_omega = set(omega) == {(3 + a, 3 + b) for a in range(3) for b in range(3) if a != b}
    ok_e = _jacobi_defect(ce, n) == 0
    # cocycle condition (adjoint module of e(3,2)): sum_cyc omega([a,b]_e, c) + [omega(a,b), c]_e = 0
    cocycle_bad = 0
    for i, j, k in itertools.combinations(range(n), 3):
        tot: dict[int, object] = {}
        for a, b, cc in (({i: 1}, {j: 1}, {k: 1}), ({j: 1}, {k: 1}, {i: 1}), ({k: 1}, {i: 1}, {j: 1})):
            for part in (_br(omega, _br(ce, a, b), cc), _br(ce, _br(omega, a, b), cc)):
                for m, x in part.items():
                    tot[m] = tot.get(m, 0) + x
        cocycle_bad += any(x != 0 for x in tot.values())
    ys = sym_state(3)
    coords = [x for y in ys for x in y]
    y0, y1, y2 = ys
    e_cas = [dot(y1, y1) / 2, dot(y1, y2), dot(y2, y2)]
    ok_cas = all(is_zero(_bracket_fn(ce, f, x, coords)) for f in e_cas for x in coords)
    C1 = dot(y0, y2) + dot(y1, y1) / 2
    differ = (not all(is_zero(_bracket_fn(ce, C1, x, coords)) for x in coords)
              and not all(is_zero(_bracket_fn(cg, e_cas[0], x, coords)) for x in coords))
    # radical = the ideal G = span(y1, y2) in both (solvable, quotient su(2)); abelian in e(3,2) only
    G = range(3, 9)
    rad_e_abelian = all(not _br(ce, {i: 1}, {j: 1}) for i in G for j in G)
    rad_g_abelian = all(not _br(cg, {i: 1}, {j: 1}) for i in G for j in G)
    ok = ok_omega and ok_e and cocycle_bad == 0 and ok_cas and differ and rad_e_abelian and not rad_g_abelian
    return Outcome(Verdict.exact(ok, f"cocycle-condition violations: {cocycle_bad}"))
