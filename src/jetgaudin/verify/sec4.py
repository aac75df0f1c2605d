"""Checks for Section 4: (we), (cas), complex generators, the Lax form, (H), (em), the Lax pair."""

from __future__ import annotations

import functools
import re

import sympy as sp

from ._registry import Erratum, Outcome, Verdict, register
from ._tools import cross, dot, hat, is_zero, lp_bracket, matrix_is_zero, sym_state

lam = sp.Symbol("lambda")
b = sp.Symbol("b", real=True)
#: the field of (kkk): b = (0, 0, b)
BV = [0, 0, b]


def _yxz():
    ys = sym_state(3)
    return ys, ys[0], ys[1], ys[2]


def _grad_field(H, ys):
    """Xdot = Pi grad H, i.e. dX_I/dt = {X_I, H} (eq. (LP))."""
    return [[lp_bracket(ys[i][a], H, ys) for a in range(3)] for i in range(3)]


def _hamiltonian(y, x):
    """``H = H_2/2 = <y,y>/2 + <b,x>`` (eq. (H)) for the field ``b = (0, 0, b)``."""
    return dot(y, y) / 2 + b * x[2]


def _em_field():
    """``(y, x, z, F)``: the g^(3) state and the vector field ``F`` of ``H = H_2/2`` (eq. (H)) by (LP), the
    right-hand side of (em)."""
    ys, y, x, z = _yxz()
    return y, x, z, _grad_field(_hamiltonian(y, x), ys)


def _reversed_commutators(text: str) -> str:
    """``text`` with every commutator ``[P, Q]`` written ``[Q, P]``."""
    return re.sub(r"\[([^],\[]+), ([^]\[]+)\]", r"[\2, \1]", text)


def _commutator_misprint(label, statement, method, printed, comment):
    """Register the check of a formula of Section 4.1 written with commutators that holds only with every
    commutator reversed (the paper's hat is an anti-isomorphism: check Sec2-iso); the erratum's correction is
    ``printed`` with its commutators reversed.

    Decorates ``holds(c, B, Y, X, Z, Yd, Xd, Zd) -> bool``, the formula with the commutator ``c`` for the
    matrices ``B = hat(b), Y, X, Z`` of (kkk) and ``Yd, Xd, Zd``, those of the vector field of ``H_2/2``; the
    check evaluates it with ``c(P, Q) = PQ - QP`` (as printed) and ``QP - PQ`` (corrected)."""
    erratum = Erratum(printed, _reversed_commutators(printed), comment)

    def deco(holds):
        @register(label, "4.1", statement, method, erratum=erratum)
        @functools.wraps(holds)
        def check(ctx):
            y, x, z, F = _em_field()
            hats = (hat(BV), hat(y), hat(x), hat(z), *(hat(F[i]) for i in range(3)))
            return Outcome(Verdict.exact(holds(lambda P, Q: P * Q - Q * P, *hats)),
                           Verdict.exact(holds(lambda P, Q: Q * P - P * Q, *hats)))

        return holds

    return deco


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
    L = hat(BV) + hat(y) / lam + hat(x) / lam**2 + hat(z) / lam**3
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
    ok = is_zero(-(hat(y) * hat(y) + 2 * hat(BV) * hat(x)).trace() - _hamiltonian(y, x))
    return Outcome(Verdict.exact(ok))


@register(
    "em",
    "4.1",
    "(em), vector form: ydot = b ^ x, xdot = y ^ x + b ^ z, zdot = y ^ z is the Hamiltonian field of H = H_2/2",
    "exact SymPy: dX/dt = {X, H} with (LP)",
)
def _em(ctx):
    y, x, z, F = _em_field()
    rhs = [cross(BV, x), [p + q for p, q in zip(cross(y, x), cross(BV, z), strict=True)], cross(y, z)]
    ok = all(is_zero(F[i][a] - rhs[i][a]) for i in range(3) for a in range(3))
    return Outcome(Verdict.exact(ok))


@_commutator_misprint(
    "em-matrix",
    "(em), matrix form: Ydot = [B, X], Xdot = [Y, X] + [B, Z], Zdot = [Y, Z] (equivalent to the vector form)",
    "exact SymPy: hat of the vector field of H_2/2",
    "Ydot = [B, X],  Xdot = [Y, X] + [B, Z],  Zdot = [Y, Z]",
    "With the paper's sigma's hat(a ^ b) = -[hat a, hat b] (check Sec2-iso), so every commutator changes sign.",
)
def _em_matrix(c, B, Y, X, Z, Yd, Xd, Zd):
    return matrix_is_zero(Yd - c(B, X)) and matrix_is_zero(Xd - c(Y, X) - c(B, Z)) and matrix_is_zero(Zd - c(Y, Z))


@register(
    "Sec4-material",
    "4.1",
    "Section 4.1: d/dt (x - z) = y ^ (x - z) + b ^ z along (em)",
    "exact SymPy",
)
def _material(ctx):
    y, x, z, F = _em_field()
    d = [p - q for p, q in zip(x, z, strict=True)]
    rhs = [p + q for p, q in zip(cross(y, d), cross(BV, z), strict=True)]
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
    H = _hamiltonian(y, x)
    ok = all(is_zero(lp_bracket(y[a], H, ys) - cross(BV, x)[a]) for a in range(3))
    ok = ok and all(is_zero(lp_bracket(x[a], H, ys) - cross(y, x)[a]) for a in range(3))
    return Outcome(Verdict.exact(ok))


@_commutator_misprint(
    "Prop-Lax",
    "Proposition of Section 4.1: dL/dt = [L(l), M(l)], M = X/l + Z/l^2, along (em)",
    "exact SymPy: dL/dt from the vector field of H_2/2",
    "dL/dt = [L(l), M(l)],  M(l) = X/l + Z/l^2",
    "Same origin as the sign of the matrix form of (em) (check Sec2-iso).",
)
def _lax(c, B, Y, X, Z, Yd, Xd, Zd):
    L = B + Y / lam + X / lam**2 + Z / lam**3
    M = X / lam + Z / lam**2
    return matrix_is_zero(Yd / lam + Xd / lam**2 + Zd / lam**3 - c(L, M))


@register(
    "Sec4-constants",
    "4",
    "Section 4: y^3 and |z| are constants of the motion of H_2/2, |x| is not; z rotates rigidly (zdot = y ^ z)",
    "exact SymPy with (LP)",
)
def _constants(ctx):
    ys, y, x, z = _yxz()
    H = _hamiltonian(y, x)
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
    H = _hamiltonian(y, x)
    xz, xx, zz = dot(x, z), dot(x, x), dot(z, z)
    cos2_dot = (2 * xz * lp_bracket(xz, H, ys) * xx * zz - xz**2 * (lp_bracket(xx, H, ys) * zz
                                                                    + xx * lp_bracket(zz, H, ys)))
    ok = is_zero(lp_bracket(xz, H, ys)) and sp.expand(cos2_dot) != 0  # a polynomial: expand is canonical
    return Outcome(Verdict.exact(ok))
