"""Checks for Section 4: (we), (cas), complex generators, the Lax form, (H), (em), the Lax pair."""

from __future__ import annotations

import sympy as sp

from ._registry import Erratum, Outcome, Verdict, register
from ._tools import cross, dot, hat, is_zero, lp_bracket, matrix_is_zero, sym_state

lam = sp.Symbol("lambda")
b = sp.Symbol("b", real=True)


def _yxz():
    ys = sym_state(3)
    return ys, ys[0], ys[1], ys[2]


def _grad_field(H, ys):
    """Xdot = Pi grad H, i.e. dX_I/dt = {X_I, H} (eq. (LP))."""
    return [[lp_bracket(ys[i][a], H, ys) for a in range(3)] for i in range(3)]


def _em_field():
    """``(ys, y, x, z, F)``: the g^(3) state and the vector field ``F`` of ``H = H_2/2 = <y,y>/2 + b x^3``
    (eq. (H)) by (LP), the right-hand side of (em)."""
    ys, y, x, z = _yxz()
    return ys, y, x, z, _grad_field(dot(y, y) / 2 + b * x[2], ys)


@register(
    "we-cas",
    "4",
    "(we), (cas): H_1 = 2<b,y>, H_2 = <y,y> + 2<b,x>, H_3 = 2(<b,z> + <y,x>), C_1 = 2C^(1) = 2<y,z> + <x,x>, "
    "C_2 = 2C^(2) = 2<x,z>, C_3 = C^(3) = <z,z> for (kkk), b = (0,0,b)",
    "exact SymPy: Laurent coefficients of u^2 + v w",
)
def _we(ctx):
    ys, y, x, z = _yxz()
    bv = [0, 0, b]
    zeta = sp.Symbol("zeta")
    u = b + y[2] * zeta + x[2] * zeta**2 + z[2] * zeta**3
    v = sum((c[0] - sp.I * c[1]) * zeta ** (i + 1) for i, c in enumerate(ys))
    w = sum((c[0] + sp.I * c[1]) * zeta ** (i + 1) for i, c in enumerate(ys))
    P = sp.Poly(sp.expand(u * u + v * w), zeta)
    k = [P.coeff_monomial(zeta**m) for m in range(7)]
    C1, C2, C3 = dot(y, z) + dot(x, x) / 2, dot(x, z), dot(z, z)
    expected = [b**2, 2 * dot(bv, y), dot(y, y) + 2 * dot(bv, x), 2 * (dot(bv, z) + dot(y, x)),
                2 * C1, 2 * C2, C3]
    ok = all(is_zero(a - e) for a, e in zip(k, expected, strict=True))
    ok = ok and is_zero(2 * C1 - (2 * dot(y, z) + dot(x, x)))
    return Outcome(Verdict.exact(ok))


@register(
    "Sec4-complex",
    "4.1",
    "Section 4.1: the brackets of the complex generators y^pm = y^1 pm i y^2, x^pm, z^pm (all displayed lines)",
    "exact SymPy with (LP)",
)
def _complex(ctx):
    ys, y, x, z = _yxz()

    def cg(v):
        return {"3": v[2], "+": v[0] + sp.I * v[1], "-": v[0] - sp.I * v[1]}

    Y, X, Z = cg(y), cg(x), cg(z)
    I = sp.I
    checks = []
    for s, sg in (("+", 1), ("-", -1)):
        checks += [
            (Y["3"], Y[s], -sg * I * Y[s]),
            (Y["3"], X[s], -sg * I * X[s]),
            (X["3"], Y[s], -sg * I * X[s]),
            (Y["3"], Z[s], -sg * I * Z[s]),
            (Z["3"], Y[s], -sg * I * Z[s]),
            (X["3"], X[s], -sg * I * Z[s]),
        ]
    checks += [
        (Y["+"], Y["-"], -2 * I * Y["3"]),
        (Y["+"], X["-"], -2 * I * X["3"]),
        (X["+"], Y["-"], -2 * I * X["3"]),
        (Y["+"], Z["-"], -2 * I * Z["3"]),
        (Z["+"], Y["-"], -2 * I * Z["3"]),
        (X["+"], X["-"], -2 * I * Z["3"]),
        (Y["3"], X["3"], 0), (Y["+"], X["+"], 0), (Y["-"], X["-"], 0),
        (Y["3"], Z["3"], 0), (Y["+"], Z["+"], 0), (Y["-"], Z["-"], 0),
    ]
    checks += [(X[a], Z[c], 0) for a in "3+-" for c in "3+-"]
    checks += [(Z[a], Z[c], 0) for a in "3+-" for c in "3+-"]
    ok = all(is_zero(lp_bracket(f, g, ys) - e) for f, g, e in checks)
    return Outcome(Verdict.exact(ok, f"{len(checks)} brackets"))


@register(
    "Sec4-laxform",
    "4.1",
    "Section 4.1: L(l) of (kkk) = B + Y/l + X/l^2 + Z/l^3 with B, Y, X, Z = (i/2)[[.3, .-], [.+, -.3]], all in su(2)",
    "exact SymPy",
)
def _laxform(ctx):
    ys, y, x, z = _yxz()

    def m(v):
        return sp.I / 2 * sp.Matrix([[v[2], v[0] - sp.I * v[1]], [v[0] + sp.I * v[1], -v[2]]])

    B = sp.I / 2 * sp.Matrix([[b, 0], [0, -b]])
    L = hat([0, 0, b]) + hat(y) / lam + hat(x) / lam**2 + hat(z) / lam**3
    ok = matrix_is_zero(L - (B + m(y) / lam + m(x) / lam**2 + m(z) / lam**3))
    for A in (B, m(y), m(x), m(z)):
        ok = ok and matrix_is_zero(A + A.H) and is_zero(A.trace())
    return Outcome(Verdict.exact(ok))


@register(
    "H",
    "4.1",
    "(H): H = H_2/2 = <y,y>/2 + <b,x> = -Tr(Y^2 + 2 B X)",
    "exact SymPy",
)
def _H(ctx):
    ys, y, x, z = _yxz()
    B = hat([0, 0, b])
    ok = is_zero(-(hat(y) * hat(y) + 2 * B * hat(x)).trace() - (dot(y, y) / 2 + b * x[2]))
    return Outcome(Verdict.exact(ok))


@register(
    "em",
    "4.1",
    "(em), vector form: ydot = b ^ x, xdot = y ^ x + b ^ z, zdot = y ^ z is the Hamiltonian field of H = H_2/2",
    "exact SymPy: dX/dt = {X, H} with (LP)",
)
def _em(ctx):
    _, y, x, z, F = _em_field()
    bv = [0, 0, b]
    rhs = [cross(bv, x), [p + q for p, q in zip(cross(y, x), cross(bv, z), strict=True)], cross(y, z)]
    ok = all(is_zero(F[i][a] - rhs[i][a]) for i in range(3) for a in range(3))
    return Outcome(Verdict.exact(ok))


@register(
    "em-matrix",
    "4.1",
    "(em), matrix form: Ydot = [B, X], Xdot = [Y, X] + [B, Z], Zdot = [Y, Z] (equivalent to the vector form)",
    "exact SymPy: hat of the vector field of H_2/2",
    erratum=Erratum(
        "Ydot = [B, X],  Xdot = [Y, X] + [B, Z],  Zdot = [Y, Z]",
        "Ydot = [X, B],  Xdot = [X, Y] + [Z, B],  Zdot = [Z, Y]",
        "With the paper's sigma's hat(a ^ b) = -[hat a, hat b] (check Sec2-iso), so every commutator changes sign.",
    ),
)
def _em_matrix(ctx):
    _, y, x, z, F = _em_field()
    Yd, Xd, Zd = (hat(F[i]) for i in range(3))
    B, Y, X, Z = hat([0, 0, b]), hat(y), hat(x), hat(z)

    def c(P, Q):
        return P * Q - Q * P

    printed = matrix_is_zero(Yd - c(B, X)) and matrix_is_zero(Xd - c(Y, X) - c(B, Z)) and matrix_is_zero(Zd - c(Y, Z))
    corr = matrix_is_zero(Yd - c(X, B)) and matrix_is_zero(Xd - c(X, Y) - c(Z, B)) and matrix_is_zero(Zd - c(Z, Y))
    return Outcome(Verdict.exact(printed), Verdict.exact(corr))


@register(
    "Sec4-material",
    "4.1",
    "Section 4.1: d/dt (x - z) = y ^ (x - z) + b ^ z along (em)",
    "exact SymPy",
)
def _material(ctx):
    _, y, x, z, F = _em_field()
    bv = [0, 0, b]
    d = [p - q for p, q in zip(x, z, strict=True)]
    rhs = [p + q for p, q in zip(cross(y, d), cross(bv, z), strict=True)]
    ok = all(is_zero(F[1][a] - F[2][a] - rhs[a]) for a in range(3))
    return Outcome(Verdict.exact(ok))


@register(
    "Sec4-lagrange",
    "4",
    "Section 4: for the Lagrange top (N = 2) the flow of H_2/2 is ydot = b ^ x, xdot = y ^ x",
    "exact SymPy with (LP), N = 2",
)
def _lagrange(ctx):
    ys = sym_state(2)
    y, x = ys
    bv = [0, 0, b]
    H = dot(y, y) / 2 + b * x[2]
    ok = all(is_zero(lp_bracket(y[a], H, ys) - cross(bv, x)[a]) for a in range(3))
    ok = ok and all(is_zero(lp_bracket(x[a], H, ys) - cross(y, x)[a]) for a in range(3))
    return Outcome(Verdict.exact(ok))


@register(
    "Prop-Lax",
    "4.1",
    "Proposition of Section 4.1: dL/dt = [L(l), M(l)], M = X/l + Z/l^2, along (em)",
    "exact SymPy: dL/dt from the vector field of H_2/2",
    erratum=Erratum(
        "dL/dt = [L(l), M(l)],  M(l) = X/l + Z/l^2",
        "dL/dt = [M(l), L(l)],  M(l) = X/l + Z/l^2",
        "Same origin as the sign of the matrix form of (em) (check Sec2-iso).",
    ),
)
def _lax(ctx):
    _, y, x, z, F = _em_field()
    L = hat([0, 0, b]) + hat(y) / lam + hat(x) / lam**2 + hat(z) / lam**3
    Ld = hat(F[0]) / lam + hat(F[1]) / lam**2 + hat(F[2]) / lam**3
    M = hat(x) / lam + hat(z) / lam**2
    printed = matrix_is_zero(Ld - (L * M - M * L))
    corr = matrix_is_zero(Ld - (M * L - L * M))
    return Outcome(Verdict.exact(printed), Verdict.exact(corr))


@register(
    "Sec4-constants",
    "4",
    "Section 4: y^3 and |z| are constants of the motion of H_2/2, |x| is not; z rotates rigidly (zdot = y ^ z)",
    "exact SymPy with (LP)",
)
def _constants(ctx):
    ys, y, x, z = _yxz()
    H = dot(y, y) / 2 + b * x[2]
    ok = is_zero(lp_bracket(y[2], H, ys)) and is_zero(lp_bracket(dot(z, z), H, ys))
    ok = ok and not is_zero(lp_bracket(dot(x, x), H, ys))
    return Outcome(Verdict.exact(ok))


@register(
    "Sec4-angle",
    "4.1",
    "Section 4.1: since |x| is not preserved, C_2 = 2<x,z> does not imply that the angle between x and z is "
    "constant",
    "exact SymPy with (LP): d<x,z>/dt = 0 but d/dt [<x,z>^2/(|x|^2 |z|^2)] is not identically 0 along (em)",
)
def _angle(ctx):
    ys, y, x, z = _yxz()
    H = dot(y, y) / 2 + b * x[2]
    xz, xx, zz = dot(x, z), dot(x, x), dot(z, z)
    cos2_dot = (2 * xz * lp_bracket(xz, H, ys) * xx * zz - xz**2 * (lp_bracket(xx, H, ys) * zz
                                                                    + xx * lp_bracket(zz, H, ys)))
    ok = is_zero(lp_bracket(xz, H, ys)) and sp.expand(cos2_dot) != 0  # a polynomial: expand is canonical
    return Outcome(Verdict.exact(ok))
