"""Checks for Prop. 7 / (2p), Appendix 1 (X0, A, B, Phi) and Appendix 2 (z stays on the sphere).

The closed form is derived here from the dressing relation: with ``M = l + M0`` and
``M0 + adj(M0) = -(eta1 + eta2)``, the exact division of ``M ell adj(M)`` by ``(l - eta1)(l - eta2)``
gives, order by order, ``ell^_1 = ell_1 + [M0, ell_0]``, ``ell^_2 = ell_2 + [M0, ell_1] + ...``,
``ell^_3 = ell_3 + [M0, ell_2] + (M0 ell_1 adj(M0) + (eta1+eta2)[M0, ell_1] - eta1 eta2 ell_1) + ...``,
hence ``Phi = [[1, 0, 0], [A, 1, 0], [B, A, 1]]`` with ``A = ad(M0)`` in the real basis.
The corrected Appendix-1 entries are imported from :mod:`jetgaudin.backlund.closed_form` and checked
against the exact 50-digit dressing.
"""

from __future__ import annotations

from functools import cache

import mpmath as mp
import sympy as sp

from . import printed
from ._registry import FAILS, INTERPRETATION, NUMERIC_TOL, UNDECIDED, Erratum, Outcome, Verdict, register
from ._tools import ell_from_state, is_zero, nu_at, rand_mpc, rand_mpf, rand_state, state_from_ell, two_point_map

s_, t_, a_, h_, b_ = sp.symbols("s t a h b")
I = sp.I


@cache
def _derived():
    """SymPy (A, B, X0) of X^ = Phi X + X0 from the top-down division, and the structure flag."""
    e1, e2 = a_ + I * h_, a_ - I * h_
    ys = [[sp.Symbol(f"{n}{k}") for k in (1, 2, 3)] for n in "yxz"]

    def m(v):
        return sp.Matrix([[v[2], v[0] - I * v[1]], [v[0] + I * v[1], -v[2]]])

    ell = [sp.Matrix([[b_, 0], [0, -b_]])] + [m(v) for v in ys]
    M0 = sp.Matrix([[-e1 + s_ * t_, t_], [-s_**2 * t_ + (e1 - e2) * s_, -e2 - s_ * t_]])
    A0 = M0.adjugate()
    L = [ell[0]]
    L.append(sp.expand(ell[1] + M0 * ell[0] + ell[0] * A0 + (e1 + e2) * L[0]))
    L.append(sp.expand(ell[2] + M0 * ell[1] + ell[1] * A0 + M0 * ell[0] * A0 + (e1 + e2) * L[1] - e1 * e2 * L[0]))
    L.append(sp.expand(ell[3] + M0 * ell[2] + ell[2] * A0 + M0 * ell[1] * A0 + (e1 + e2) * L[2] - e1 * e2 * L[1]))
    new = []
    for E in L[1:]:
        new += [sp.expand((E[0, 1] + E[1, 0]) / 2), sp.expand((E[1, 0] - E[0, 1]) / (2 * I)), sp.expand(E[0, 0])]
    flat = [c for v in ys for c in v]
    J = sp.Matrix(9, 9, lambda i, j: sp.diff(new[i], flat[j]))
    X0 = sp.Matrix([sp.expand(e.subs({c: 0 for c in flat})) for e in new])
    blk = [[J[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] for j in range(3)] for i in range(3)]
    Z, E = sp.zeros(3, 3), sp.eye(3)
    A, B = blk[1][0], blk[2][0]
    structure = (all(is_zero(e) for e in (blk[0][0] - E)) and blk[0][1] == Z and blk[0][2] == Z
                 and all(is_zero(e) for e in (blk[1][1] - E)) and blk[1][2] == Z
                 and all(is_zero(e) for e in (blk[2][2] - E)) and all(is_zero(e) for e in (blk[2][1] - A)))
    # linear in X: no second derivatives
    linear = all(sp.diff(e, c1, c2) == 0 for e in new[:: 4] for c1 in flat[:3] for c2 in flat[:3])
    return A, B, X0, structure and linear


def _printed(b, R, Im, s, t, alpha_fix=False):
    """Appendix 1 as printed: :func:`jetgaudin.verify.printed.appendix1`."""
    return printed.appendix1(b, R, Im, s, t, alpha_fix)


def _corrected():
    """(A, B, X0) of jetgaudin.backlund.closed_form (scalar formulas evaluated at 50 digits)."""
    from jetgaudin.backlund.closed_form import _two_point_coefficients

    def f(b, R, Im, s, t):
        (A12, A13, A23, B11, B12, B13, B21, B22, B23, B31, B32, B33, c1, c2, c3) = _two_point_coefficients(
            b, R, Im, s, t)
        A = [[0, A12, A13], [-A12, 0, A23], [-A13, -A23, 0]]
        B = [[B11, B12, B13], [B21, B22, B23], [B31, B32, B33]]
        X0 = [b * A13, b * A23, 0, b * B13, b * B23, b * B33, c1, c2, c3]
        return A, B, X0

    return f


def _apply(A, B, X0, X):
    y, x, z = X[0:3], X[3:6], X[6:9]
    Ay = [sum(A[i][j] * y[j] for j in range(3)) for i in range(3)]
    Ax = [sum(A[i][j] * x[j] for j in range(3)) for i in range(3)]
    By = [sum(B[i][j] * y[j] for j in range(3)) for i in range(3)]
    out = list(y) + [x[i] + Ay[i] for i in range(3)] + [z[i] + Ax[i] + By[i] for i in range(3)]
    return [o + c for o, c in zip(out, X0, strict=True)]


def _real_samples(ctx, n=12):
    n = 30 if ctx.full else n
    rng = ctx.rng()
    out = []
    with mp.workdps(ctx.dps):
        for _ in range(n):
            ys = rand_state(rng, 3)
            b = rand_mpf(rng, 0.5, 2)
            eta = rand_mpc(rng)
            ell = ell_from_state(ys, b)
            n1 = nu_at(ell, eta)
            new, res, s, t = two_point_map(ell, eta, mp.conj(eta), n1, mp.conj(n1))
            X = [c for y in ys for c in y]
            Xn = [c for y in state_from_ell(new) for c in y]
            out.append(dict(X=X, Xn=Xn, b=b, eta=eta, s=s, t=t, res=res))
    return out


@register(
    "2p",
    "6.2",
    "Prop. 7, (2p): the real two-point map is X^ = Phi(s,t;eta) X + X0(s,t;eta), Phi = [[1,0,0],[A,1,0],[B,A,1]]",
    "exact SymPy (top-down division of M ell adj(M) with symbolic s, t, eta) and mpmath (50 digits) against the "
    "exact dressing at 12 (30 with --full) seeded random real states",
)
def _prop5(ctx):
    A, B, X0, structure = _derived()
    fA = sp.lambdify((s_, t_, a_, h_, b_), A, "mpmath")
    fB = sp.lambdify((s_, t_, a_, h_, b_), B, "mpmath")
    fX = sp.lambdify((s_, t_, a_, h_, b_), X0, "mpmath")
    worst = mp.mpf(0)
    with mp.workdps(ctx.dps):
        for d in _real_samples(ctx):
            args = (d["s"], d["t"], mp.re(d["eta"]), mp.im(d["eta"]), d["b"])
            Am, Bm, Xm = fA(*args).tolist(), fB(*args).tolist(), [c[0] for c in fX(*args).tolist()]
            pred = _apply(Am, Bm, Xm, d["X"])
            worst = max(worst, max(abs(p - q) for p, q in zip(pred, d["Xn"], strict=True)), d["res"])
            worst = max(worst, max(abs(mp.im(c)) for c in d["Xn"]))
    if not structure:
        return Outcome(Verdict(FAILS, 1.0, "block structure of Phi not found symbolically"))
    return Outcome(Verdict.from_residual(worst, note="block structure exact (SymPy)"))


def _compare(ctx, which):
    """max |entry - derived| over the samples for (A, B, X0) of ``which`` and the state residual."""
    A, B, X0, _ = _derived()
    fA = sp.lambdify((s_, t_, a_, h_, b_), A, "mpmath")
    fB = sp.lambdify((s_, t_, a_, h_, b_), B, "mpmath")
    fX = sp.lambdify((s_, t_, a_, h_, b_), X0, "mpmath")
    bad = {"A": set(), "B": set(), "X0": set()}
    worst = {"A": mp.mpf(0), "B": mp.mpf(0), "X0": mp.mpf(0), "state": mp.mpf(0)}
    with mp.workdps(ctx.dps):
        for d in _real_samples(ctx):
            R, Im = mp.re(d["eta"]), mp.im(d["eta"])
            args = (d["s"], d["t"], R, Im, d["b"])
            Ad, Bd, Xd = fA(*args).tolist(), fB(*args).tolist(), [c[0] for c in fX(*args).tolist()]
            Aw, Bw, Xw = which(d["b"], R, Im, d["s"], d["t"])
            for i in range(3):
                for j in range(3):
                    for name, W, D in (("A", Aw, Ad), ("B", Bw, Bd)):
                        r = abs(W[i][j] - D[i][j]) / (1 + abs(D[i][j]))
                        worst[name] = max(worst[name], r)
                        if r > NUMERIC_TOL:
                            bad[name].add(f"{i + 1}{j + 1}")
            for k in range(9):
                r = abs(Xw[k] - Xd[k]) / (1 + abs(Xd[k]))
                worst["X0"] = max(worst["X0"], r)
                if r > NUMERIC_TOL:
                    bad["X0"].add(str(k + 1))
            pred = _apply(Aw, Bw, Xw, d["X"])
            worst["state"] = max(worst["state"], max(abs(p - q) / (1 + abs(q)) for p, q in
                                                     zip(pred, d["Xn"], strict=True)))
    return worst, bad


def _app1_check(ctx, name):
    wp, badp = _compare(ctx, _printed)
    _, bada = _compare(ctx, lambda *a: _printed(*a, alpha_fix=True))
    note = (f"printed entries differing: {sorted(badp[name])}; with alpha_1 = 2i Im(eta) - st only: "
            f"{sorted(bada[name])}")
    printed = Verdict.from_residual(max(wp[name], wp["state"] if name == "X0" else 0), note=note)
    try:
        corr = _corrected()
    except ImportError as exc:  # pragma: no cover - depends on another module
        return Outcome(printed, Verdict(UNDECIDED, None, f"jetgaudin.backlund.closed_form unavailable: {exc}"))
    wc, _ = _compare(ctx, corr)
    return Outcome(printed, Verdict.from_residual(max(wc[name], wc["state"])))


_APP1_NOTE = ("Corrected entries are those of jetgaudin.backlund.closed_form.two_point_matrices (docstring there), "
              "verified here against an independent SymPy derivation and the exact 50-digit dressing.")


@register(
    "App1-A",
    "Appendix 1",
    "Appendix 1: the skew matrix A(s,t;eta) (alpha_1 = 2 Im(eta) - s t, alpha_2 = alpha_1 - s t)",
    "mpmath (50 digits) at the spectral (s, t) of 12 (30 with --full) seeded random real states: "
    "entries vs the SymPy derivation",
    erratum=Erratum(
        "alpha_1 = 2 Im(eta) - s t",
        "alpha_1 = eta_1 - eta_2 - s t = 2i Im(eta) - s t  (A itself is then right as printed)",
        _APP1_NOTE,
    ),
)
def _app1_A(ctx):
    return _app1_check(ctx, "A")


@register(
    "App1-B",
    "Appendix 1",
    "Appendix 1: the matrix B(s,t;eta)",
    "mpmath (50 digits) at the spectral (s, t) of 12 (30 with --full) seeded random real states: "
    "entries vs the SymPy derivation",
    erratum=Erratum(
        "B_13 = s a1 (a2 + R)/2, B_22 = (1 + s^2)(a1^2 - t^2)/2, B_23 = -(i/2) s a1 (a2 + R), B_32 = (1/2)[t(a2 + 2R) "
        "- s a1 (a2 - 2R)], B_33 = 4 s t a1  (R = Re eta, a1 = 2 Im(eta) - s t)",
        "B_13 = (1/2)[s a1 (a2 + 2R) + t (a2 - 2R)], B_22 = (1 + s^2)(a1^2 + t^2)/2, B_23 = -(i/2)[s a1 (a2 + 2R) "
        "- t (a2 - 2R)], B_32 = (i/2)[t(a2 + 2R) - s a1 (a2 - 2R)], B_33 = 2 s t a1, with a1 = 2i Im(eta) - s t "
        "(B_11, B_12, B_21, B_31 right as printed)",
        _APP1_NOTE,
    ),
)
def _app1_B(ctx):
    return _app1_check(ctx, "B")


@register(
    "App1-X0",
    "Appendix 1",
    "Appendix 1: the vector X0(s,t;eta) (and the full map X^ = Phi X + X0 as printed)",
    "mpmath (50 digits) at the spectral (s, t) of 12 (30 with --full) seeded random real states vs the exact dressing",
    erratum=Erratum(
        "[X0]_2 = -b(s a1 + t),  [X0]_4 = b[s a1 (a2 + R)/2 + t(a2 - 2R)],  "
        "[X0]_5 = i b[s a1 (a2 + R)/2 - t(a2 - 2R)],  "
        "[X0]_7 = -(i b/4)[(Im eta + Re eta)^2 (t + a1) + 8 s t R (t - a1)],  [X0]_8 = -(b/4)[(Im eta + Re eta)^2 "
        "(t - a1) + 8 s t R (t + a1)]",
        "X0 = b (A_13, A_23, 0, B_13, B_23, B_33, C_13, C_23, C_33): [X0]_2 = -i b (s a1 + t), [X0]_4 = b B_13, "
        "[X0]_5 = b B_23 (corrected B), [X0]_7 = b[Re(eta^2)(s a1 - t) + R a2 (s a1 + t)], [X0]_8 = -i b[Re(eta^2)"
        "(s a1 + t) + R a2 (s a1 - t)]; [X0]_1, [X0]_3, [X0]_6, [X0]_9 right as printed; a1 = 2i Im(eta) - s t",
        _APP1_NOTE,
    ),
)
def _app1_X0(ctx):
    return _app1_check(ctx, "X0")


@register(
    "App2-sphere",
    "Appendix 2",
    "Appendix 2: along the real two-point orbit (b = 1, eta = 5 + 0.1i, the printed initial data) z stays on the "
    "sphere <z, z> = const",
    "mpmath (50 digits) exact dressing for 100 steps (1000 with --full), seeded by the data; second route: the "
    "numpy library TwoPointBacklund for 1000 steps (drift < 1e-11)",
)
def _app2(ctx):
    steps = 1000 if ctx.full else 100
    worst = mp.mpf(0)
    with mp.workdps(ctx.dps):
        vals = [mp.mpf(v) for v in ("-2.4", "-0.6", "-1.2", "-2.19", "0.89", "1.34", "1", "0", "0")]
        ys = [vals[0:3], vals[3:6], vals[6:9]]
        b, eta = mp.mpf(1), mp.mpc("5", "0.1")
        r0 = sum(c * c for c in ys[2])
        nu = None
        for _ in range(steps):
            ell = ell_from_state(ys, b)
            n = nu_at(ell, eta)
            if nu is not None and abs(n + nu) < abs(n - nu):  # continue the same root along the orbit
                n = -n
            nu = n
            new, res, _, _ = two_point_map(ell, eta, mp.conj(eta), n, mp.conj(n))
            st = state_from_ell(new)
            worst = max(worst, res, max(abs(mp.im(c)) for y in st for c in y))
            ys = [[mp.re(c) for c in y] for y in st]
            worst = max(worst, abs(sum(c * c for c in ys[2]) - r0))
    v = Verdict.from_residual(worst)
    if v.status == FAILS:  # the 50-digit route decides a failure on its own
        return Outcome(v)
    try:  # second route (not the truth): the numpy implementation
        import numpy as np

        import jetgaudin as jg

        orbit = jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(np.array([float(v) for v in vals]), 1000)
        lib = float(np.max(np.abs(np.sum(orbit[:, 6:9] ** 2, axis=-1) - 1.0)))
    except Exception as exc:  # a route that cannot run leaves the check undecided, never a pass
        return Outcome(Verdict(UNDECIDED, float(worst), f"second route (numpy TwoPointBacklund) could not run: "
                                                        f"{type(exc).__name__}: {exc}"))
    note = f"numpy route: max | |z|^2 - 1 | over 1000 steps = {lib:.1e}"
    if not lib <= 1e-11:  # float64 round-off over 1000 steps: ~1e-13; 1e-11 is a wide margin (NaN fails too)
        return Outcome(Verdict(FAILS, lib, note))
    return Outcome(Verdict(v.status, v.residual, note))


@register(
    "App2-timestep",
    "Appendix 2",
    "Appendix 2: Im(eta) is the time step of the discretisation (of the flow the real two-point map interpolates)",
    "mpmath (60 digits): odd part [B_(a+ih)(X) - B_(a-ih)(X)]/2 of the exact real two-point map, h = 1e-17 "
    "(error O(h^3): relative 1e-34), vs h X_F for F = nu(a) and F = H = H_2/2; 6 seeded real states, N = 1..3",
    erratum=Erratum(
        "Im(eta) is the time-step of the discretization",
        "B_eta = exp(tau X_nu(Re eta)) + O(Im(eta)^3) with tau = -2 Im(eta), nu(Re eta) = sqrt(<xi, xi>) at "
        "l = Re eta (> 0, the default branch); for large |eta| this is a step of about -2 Im(eta)/(|b| |eta|^2) of "
        "the physical flow of H = H_2/2 (run backwards for Im(eta) > 0) composed with a rotation about the field",
        "Checked here: the O(h) term of the map is -2h X_nu(a) to 1e-34 (and neither h X_nu(a) nor h X_H). "
        "The large-|eta| form is a consequence (nu = |b| + H_1/(2|b|l) + (H_2/(2|b|) - H_1^2/(8|b|^3))/l^2 + ...): "
        "tests/test_backlund.py::test_large_eta_limit_is_physical_flow_times_rotation and docs/backlund.md section 6. "
        "An interpretation of a loose phrase, not a misprint: 'the time step' read as 'a step Im(eta) of a flow' "
        "fails; read as 'proportional to the step' it holds.",
        kind=INTERPRETATION,
    ),
)
def _app2_timestep(ctx):
    from ._tools import rand_state
    from .maps import _flat, _pi, _unflat, two_point_real
    from .structure import lp_constants

    rng = ctx.rng()
    wp = wh = wc = mp.mpf(0)
    with mp.workdps(60):
        h = mp.mpf("1e-17")
        for k in range(6):
            N = 1 + k % 3
            c = lp_constants(N)
            X = _flat(rand_state(rng, N))
            b, a = rand_mpf(rng, 0.5, 2), rand_mpf(rng, 0.5, 3)
            ys = _unflat(X)
            xi = [[0, 0, b][i] + sum(ys[m][i] * a ** -(m + 1) for m in range(N)) for i in range(3)]
            nu = mp.sqrt(sum(v * v for v in xi))  # > 0: the default branch at l = Re eta = a
            grad_nu = [xi[i] * a ** -(m + 1) / nu for m in range(N) for i in range(3)]
            grad_H = [0] * (3 * N)
            grad_H[0:3] = ys[0]  # H = |y_0|^2/2 + b y_1^3 (for N = 1: |y_0|^2/2 + 0)
            if N > 1:
                grad_H[5] = b
            Pi = _pi(c, X)
            V = [sum(Pi[i][j] * grad_nu[j] for j in range(3 * N)) for i in range(3 * N)]
            VH = [sum(Pi[i][j] * grad_H[j] for j in range(3 * N)) for i in range(3 * N)]
            Bp, _, _ = two_point_real(X, b, mp.mpc(a, h), nu)
            Bm, _, _ = two_point_real(X, b, mp.mpc(a, -h), nu)
            D = [(p - m_) / 2 for p, m_ in zip(Bp, Bm, strict=True)]
            scale = h * (1 + max(abs(v) for v in V))
            wc = max(wc, max(abs(d + 2 * h * v) for d, v in zip(D, V, strict=True)) / scale)
            wp = max(wp, max(abs(d - h * v) for d, v in zip(D, V, strict=True)) / scale)
            wh = max(wh, max(abs(d - h * v) for d, v in zip(D, VH, strict=True)) / scale)
    return Outcome(Verdict.from_residual(min(wp, wh), note=f"vs h X_nu: {mp.nstr(wp, 3)}, vs h X_H: {mp.nstr(wh, 3)}"),
                   Verdict.from_residual(wc))
