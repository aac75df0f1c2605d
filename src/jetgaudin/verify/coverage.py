"""The coverage map of the paper: one entry per labelled equation, proposition, lemma, remark and displayed
formula (and the checkable sentences of the text), with the checks of :data:`REGISTRY` that decide it.

``jetgaudin verify --coverage`` prints it as a table, ``--coverage --json`` as a JSON array of objects with the
keys ``statement``, ``section``, ``status``, ``checks``, ``reason``.  ``tests/test_verify.py`` asserts that
every cited check exists, that no entry is ``unchecked`` and that ``partly`` / ``definition`` /
``not checkable`` entries give their reason.
"""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["Coverage", "Statement", "STATEMENTS", "coverage", "counts"]


class Coverage(enum.StrEnum):
    """How far a statement of the paper is decided by ``jetgaudin verify``."""

    CHECKED = "checked"
    PARTLY = "partly"
    DEFINITION = "definition"
    NOT_CHECKABLE = "not checkable"
    UNCHECKED = "unchecked"


@dataclass(frozen=True)
class Statement:
    """One statement of the paper: its words or formula (short), where it is, how far it is checked."""

    statement: str
    section: str
    status: Coverage
    checks: tuple[str, ...] = ()
    reason: str = ""

    def to_dict(self) -> dict:
        d = asdict(self)
        d["status"] = self.status.value
        d["checks"] = list(self.checks)
        return d


_CITED = "a result of the cited literature, not derived in this paper"
_INTERP = "a physical interpretation (names given to vectors), not a mathematical claim"
_STATUS = {"C": Coverage.CHECKED, "P": Coverage.PARTLY, "D": Coverage.DEFINITION, "NC": Coverage.NOT_CHECKABLE}
_REASONS = {"$CITED": _CITED, "$INTERP": _INTERP}

#: The coverage map, section by section (``== section``), in the paper's order.  One entry per statement: a line
#: ``- STATUS CHECK, CHECK, ... | statement`` (STATUS: C checked, P partly, D definition, NC not checkable; the labels
#: of the checks that decide it), then, where needed, ``  reason: ...``; an indented line continues the statement or
#: the reason.  ``$CITED`` and ``$INTERP`` stand for the two recurring reasons.
_MAP = r"""
== 1
- C Prop1, Prop2-involution, LP-rank | Abstract/Intro: a hierarchy of Liouville completely integrable models with a
  linear r-matrix structure
- P Intro-algebras, Sec4-lagrange | Intro: N = 1 is the Euler top on su(2); N = 2 the Lagrange top on e(3) = su(2)
  (+)_s R^3
  reason: the algebras are checked (structure constants of (LP) for N = 1, 2: su(2) and e(3)), and for N = 2 the
  flow of H_2/2 is the Lagrange top's (Sec4-lagrange); for N = 1 the model's only non-Casimir integral is
  H_1 = 2<b, y> (a spin in the field), so only the phase space su(2)* is the Euler top's: no Euler top Hamiltonian
  (quadratic, with moments of inertia) is derived or checked
- P Chain-r, Chain-integrals, Trig-r, Trig-integrals, XYZ-w, XYZ-r, XYZ-nu2, XYZ-Clebsch | Intro: direct sums give
  n-body chains (Gaudin model, Lagrange chain) with rational, trigonometric, elliptic r-matrices
  reason: the rational, trigonometric and elliptic cases are checked (r-matrix structure of the sum over sites,
  integrals in involution; jetgaudin's trigonometric family, issue 23; the elliptic family, issue 24: the addition
  identity of ns, ds, cs and the r-matrix relation, the exact expansion of nu^2, the Clebsch case of the order-2
  site); the constructions themselves are cited, not derived in this paper
- P SUn-r, SUn-dressing | Intro: the construction generalises to any simple Lie algebra
  reason: announced, not done in the paper; su(n) with jet sites (rational) is built and checked by jetgaudin
  (issue 32: the r-matrix relation, the rank-one dressing of the real two-point maps); other simple algebras and the
  trigonometric and elliptic su(n) families are not
- P Sec3-structure, Sec3-cocycle | Intro: the N = 3 algebra includes su(2) and R^3 as proper subalgebras but is no
  longer a semidirect sum
  reason: read literally this contradicts Section 3 (g^(3) = su(2) (+)_s G); checked in Section 3's sense: G is not
  R^3 (+)_s R^3 and g^(3) is not e(3,2)
- P Sec3-cocycle | Intro: the system is the twisted Lagrange top of Thiffeault-Morrison (a cocycle added to the
  two-field top)
  reason: the cocycle over e(3,2) is checked; the identification with [T1] is a citation
- NC | Intro: Vivolo's Lax matrix; the generalised Lagrange top has monodromy (no global action-angle variables)
  reason: $CITED

== 2
- D | (lax): L(l) = sum_a sigma^a [b^a + sum_i f_i(l) y_i^a], f_0 = 1/l
  reason: definition of the Lax matrix (its consequences are checked by Prop1, yy, Lemma1)
- D | sigma^1, sigma^2, sigma^3 (after (lax))
  reason: definition (used by every check of L)
- D | (LP): {y_i^a, y_j^b} = eps^{ab}_c y_{i+j}^c (i+j < N), 0 otherwise
  reason: definition of g^(N); that it is a Lie-Poisson algebra is checked by LP-jacobi
- C LP-jacobi | (LP) is a Lie-Poisson algebra (antisymmetry and Jacobi identity)
- C LP-rank | N is the order of the jet-extension; it coincides with the number of degrees of freedom
- D | f_i(l) = sum over {q_i} prod_k c_k^{q_k}/q_k! (d/dl)^{|q_i|} f_0, c_k arbitrary complex constants
  reason: definition; evaluated by the checks kk, lax2, yy, Prop1
- D | {q_i} = {q in N^i : q_1 + 2 q_2 + ... + i q_i = i}, |q_i| = sum q_k
  reason: definition
- C Prop1 | Prop. 1, (er): {L(l) x 1, 1 x L(m)} = [r(l - m), L(l) x 1 + 1 x L(m)], r(l) = sum sigma^a x sigma^a / l
- C yy | (yy): L(l) = (i/2)[[u, v], [w, -u]] with u, v, w as displayed (general c_k)
- C Prop1, Sec2-uvw, Sec2-uvw-general | (er) is equivalent to the displayed brackets of u(l), v(l), w(l)
- C Sec2-uvw, Sec2-uvw-general | Brackets of u, v, w displayed after (yy) (misprinted: see docs/errata.md)
- C Sec2-iso | xi in R^3 -> (1/2)[[i xi3, i xi1 + xi2], [i xi1 - xi2, -i xi3]] is an isomorphism su(2) ~ (R^3, ^)
- C Sec2-trace | <xi, eta> = -2 tr(xi eta) = 2 tr(eta xi^*)
- C lax2 | (lax2): c_1 = -1, c_k = 0 gives L(l) = sum sigma^a [b^a + sum_i y_i^a / l^(i+1)]
- D | Notation y_i = (y_i^1, y_i^2, y_i^3), b = (b^1, b^2, b^3)
  reason: notation
- C Lemma1 | Lemma 1, (curve): det(L - mu) = 0 is the hyperelliptic curve 4 mu^2 + <b,b> + H(l) + C(l) = 0
- C Hh | Lemma 1, (Hh): H(l) (misprinted lower limit of the inner sum)
- C C | Lemma 1, (C): C(l)
- C Prop2 | Prop. 2: H_k and C_k as displayed (2N integrals)
- C Prop2-involution | Prop. 2: {H_i, H_k} = {C_i, H_k} = {C_i, C_k} = 0
- C Prop2-involution | Prop. 2: the H_k are first integrals; the C_k are (combinations of) Casimirs, {C_k, y_j^b} =
  0
- C LP-rank | Prop. 2: the 2N integrals are independent (a set of 2N integrals, Liouville integrability)
- C Prop2 | Proof of Prop. 2: H_k = Res l^(k-1) H(l), C_k = Res l^(N+k-1) C(l)
- C Prop1, Prop2-involution | Proof of Prop. 2: H(l) gives N commuting integrals thanks to the r-matrix structure
  (er)
- C Prop2-proof | Proof of Prop. 2: {C_k, y_j^b} = ... = 2 sum eps y_{i+j} y_{N+k-i-2+j} (misprinted index) and the
  symmetrised display = 0

== 3
- C kk | (kk): L(l) for N = 3 = b + y0/l - c1 y1/l^2 + y2 (c1^2/l - c2)/l^2
- D | b^a an external field, uniform and constant; c1, c2 real constants
  reason: definition
- C algebra | (algebra): the brackets of g^(3)
- C Sec3-structure | g^(3) = su(2) (+)_s G, dim G = 6
- C Sec3-structure | G includes the abelian proper subalgebra R^3 spanned by y2
- P Sec3-structure | G does not have a semidirect structure
  reason: checked: no subalgebra of G complements span(y2), so G is not R^3 (+)_s R^3; literally G = span(y1^1)
  (+)_s span(y1^2, y1^3, y2) is a semidirect sum of a 1-dimensional subalgebra and an ideal
- C Sec3-cocycle | g^(3) is obtained by adding a cocycle to e(3,2) = su(2) (+)_s (R^3 (+) R^3)
- NC | e(3,2) describes a two-field top
  reason: $CITED
- C Sec3-bracket | The Lie-Poisson bracket of functions f, g on g^(3) (four terms)
- C Sec3-cocycle | The non-semidirect structure lies in the last term <y2, grad1 f ^ grad1 g>, absent in e(3,2)
- C Sec3-casimirs, LP-rank | g^(3) has 3 Casimirs C^(1) = <y0,y2> + <y1,y1>/2, C^(2) = <y1,y2>, C^(3) = <y2,y2>
- C Sec3-cocycle | The Casimirs differ from those of e(3,2) only by <y0,y2> in C^(1)
- C Prop3 | Prop. 3, (cu3): the N = 3 curve and H_1, H_2, H_3, C_1, C_2, C_3 (misprinted)

== 4
- D | (kkk): L = b sigma^3 + sum sigma^a [y^a/l + x^a/l^2 + z^a/l^3] (renaming y0, y1, y2 = y, x, z)
  reason: definition (the reduction (lax2) with N = 3 and b = (0, 0, b)); checked via Sec4-laxform, we-cas
- P Sec4-lagrange | (kkk) extends the Lagrange top Lax matrix to a third-order pole
  reason: the N = 2 reduction is checked to give the Lagrange top flow; 'extension' is descriptive
- C we-cas | (we): H_1 = 2<b,y>, H_2 = <y,y> + 2<b,x>, H_3 = 2(<b,z> + <y,x>)
- C we-cas | (cas): C_1 = 2C^(1), C_2 = 2C^(2), C_3 = C^(3)
- C Sec4-constants | y^3 and |z| are constants of the motion (as in the Lagrange case)
- NC | y, z interpreted as total angular momentum and centre of mass of a Lagrange top
  reason: $INTERP
- NC | y is not the angular momentum of the top because of x; x is the moving centre of mass of top plus a material
  point at x - z, unit masses; C_1, C_2 link the two
  reason: $INTERP
- C Sec5-momenta | x must depend on momenta since {x^a, x^b} = eps^{ab}_c z^c
- C Sec4-lagrange | H_2 coincides with the physical Hamiltonian of the Lagrange top, x on the sphere |x| = c (N = 2)
- C Sec4-lagrange | Lagrange top: ydot = b ^ x, xdot = y ^ x; x rotates rigidly

== 4.1
- C Sec4-complex | Section 4.1: brackets of the complex generators y^pm, x^pm, z^pm
- C Sec4-laxform | Section 4.1: L(l) = B + Y/l + X/l^2 + Z/l^3, all in su(2)
- C H | (H): H = H_2/2 = <y,y>/2 + <b,x> = -Tr(Y^2 + 2 B X)
- NC | (H): kinetic term is the norm of the total angular momentum, potential the projection of the centre of mass
  on the field
  reason: $INTERP
- C em | (em), vector form: ydot = b ^ x, xdot = y ^ x + b ^ z, zdot = y ^ z
- C em-matrix | (em), matrix form (misprinted signs)
- C Sec4-constants | x does not rotate rigidly though z does; |x| is not preserved
- C Sec4-angle | C_2 = 2<x,z> does not imply that the angle between x and z is constant
- C Sec4-material | d/dt (x - z) = y ^ (x - z) + b ^ z
- C Prop-Lax | Prop. 4: Lax representation dL/dt = [L, M], M = X/l + Z/l^2 (misprinted order)

== 5
- C Sec5-ranges | Euler angles theta in [0, 2pi), phi in [0, 2pi), psi in [0, pi) (misprinted ranges)
- D | (fo): the leaf O = {C^(1) = 0, C^(2) = 0, C^(3) = 1}
  reason: definition; the realisation's image is checked to lie on it (Prop-canonical)
- C Prop-canonical | Prop. 5: the canonical realisation of g^(3) on O in Euler angles (misprinted)
- C Prop-canonical | Proof of Prop. 5: the well-known realisation of an angular momentum y and a unit vector z
  reason: the same (misprinted) y, z as the proposition
- D | The canonical bracket {f, g} = sum df/dq dg/dp - df/dp dg/dq
  reason: definition
- C Prop-canonical | Proof of Prop. 5: requiring (algebra) on O gives x
- C Sec5-xnorm | |x|^2 = 2 p_psi > 0
- P Sec5-momenta | As a consequence the Hamiltonian (H) describes a non-holonomic dynamics
  reason: checked: x depends on the momentum p_psi (not a function of the configuration); 'non-holonomic' is an
  interpretation (no constraint on velocities is stated), not decidable by a computation
- C Sec5-H | H in canonical variables (misprinted sign of the cross term)
- C Sec5-cyclic | phi is cyclic as in the Lagrange case; psi enters the potential
- C Sec5-I | I_1 = H_2/2 = p_phi and I_2 = H_3/2 = ... (misprinted)

== 6
- NC | Veselov's Lagrange correspondences; BTs for soliton equations
  reason: $CITED
- C BT-poisson-one-point, BT-poisson-two-point, BT-integrals | BT property 1: a BT is a Poisson map preserving the
  integrals of the flow it discretises
- C mp, 2p | BT property 2: a BT is given by explicit formulae
  reason: the explicit formulas (mp) and (2p) are checked against the dressing
- P BT-integrals, 2p-real | BT property 3: multi-valued, but single-valued on a level manifold of the integrals
  reason: the two values are the two signs of nu(eta), and nu(eta)^2 is a function of the integrals (checked, so the
  choice is fixed on a level set); 'single-valued' is a property of a choice, not a formula
- P Rem-spectrality | BT property 4: a one-parameter family, eta conjugate to mu (spectrality)
  reason: an interpretation: the generating function as printed fails; the corrected F of the check fu was fitted
  (factors, the missing term, b eta) so that (e1), (e2) and the spectrality hold, so the check shows that such an F
  exists, not that the paper's F is right
- P BT-poisson-two-point, App2-timestep | BT property 5: the BT is iterative, a symplectic integrator, eta an
  adjustable time step
  reason: the step is -2 Im(eta) of the flow of nu(Re eta) (checked), not eta itself

== 6.1
- D | Section 6.1: u, v, w of the reduced system
  reason: definition; checked through we-cas, hh
- C Prop4-casimirs, BT-integrals | One-point BT: L -> M L M^-1 (a similarity, so the spectrum is preserved)
- D | Updated variables u~, v~, w~ (tilde notation)
  reason: notation
- D | (rr): M(l; eta) L(l) = L~(l) M(l; eta)
  reason: the defining relation of the map; the checks build the map from it
- C ansatz | (ansatz): M = [[l - eta + pq, p], [q, 1]], det M = l - eta
- NC | The number of zeros of det M is the number of essential Bäcklund parameters; p, q dynamical
  reason: a remark on the method, not a formula
- C hh | (hh): p = y^-/(2b), q = y~^+/(2b), y~^3 = y^3
- D | P = (eta, mu) and Q = (eta, -mu) on the curve, exchanged by the hyperelliptic involution
  reason: definition of the points
- C hhh | (hhh): q = (u(eta) - mu)/v(eta) = -w(eta)/(u(eta) + mu), with the curve displayed after it
- C mp-u, mp-v, mp-w | The tilde u, v, w formulas of the one-point map
- C BT-poisson-one-point, BT-integrals | (rr) gives an integrable Poisson map
- C mp | (mp): the explicit one-point map (misprinted)
- D | (leaf): the leaf C^(1) = gamma_1, C^(2) = gamma_2, C^(3) = 1
  reason: definition
- D | Psi, Psi~, chi^-, chi~^+ notation
  reason: notation
- P fu | Prop. 6, (e1), (e2), (fu): the generating function (fails as printed; corrected by interpretation)
  reason: an interpretation, not a located misprint: the corrected F (gamma_i read as 2C^(i), the term -k/(4 eta^2)
  added, the factor -i, b eta) was fitted so that (e1), (e2) hold; the check shows that this F works, not which
  reading the authors meant
- C Prop4-casimirs | Proof of Prop. 6: the Casimirs do not change under the map
- C Prop4-leaf | Proof of Prop. 6: y^+, x^+, z^+ and y~^-, x~^-, z~^- eliminated with the Casimirs (misprinted)
- C Prop4-Psi | Proof of Prop. 6: the map in the variables Psi, chi^-, Psi~, chi~^+ (misprinted), k^2 = 1 + eta z^-
  z~^+
- P Rem-spectrality | Remark 1: spectrality, mu = u(eta) - y~^+ v(eta)/(2b) = -dF/deta (fails as printed;
  corrected by interpretation)
  reason: the first equality is checked as printed; the second holds with the fitted F of the check fu (an
  interpretation, see there), with the sign + and mu read as nu
- C Rem-complex | Remark 2: the one-point map is complex, not a physical BT

== 6.2
- C 128 | Section 6.2: the composite B_(P1,Q2) = B_(Q2) o B_(P1)
- C 2p-inverse | The two one-point maps are inverse to each other when eta1 = eta2, mu1 = mu2
- C 128 | (128): M(l; eta1, eta2) L = L^ M
- C mm | (mm): M(l; eta1, eta2) and det M = (l - eta1)(l - eta2)
- C x | (x): s (two forms)
- C X | (X): t (two forms)
- C x, X, BT-integrals | -(2 mu_j)^2 = u^2 + v w = u^2 + v w after the map (misprinted normalisation)
- C 2p-identity | For eta1 = eta2 (mu1 = mu2) the two-point map is the identity
- C 2p-real, BT-poisson-two-point, BT-integrals | (gg): eta1 = conj(eta2) reduces the two-point map to a real
  Poisson integrable map
- C 2p-real | The two-point map is a physical BT with two real parameters
- D | X = (y, x, z) in R^9 notation
  reason: notation
- C 2p | Prop. 7, (2p): X^ = Phi(s,t;eta) X + X0(s,t;eta), Phi = [[1,0,0],[A,1,0],[B,A,1]]
- C Rem-nonlinear | Remark 3: (2p) is a nonlinear transformation

== 7
- C Sec3-cocycle | Conclusions: a rigid body on an extension of the two-field top's Lie-Poisson structure
- C Prop1, Prop-Lax, Prop-canonical, mp, 2p | Conclusions: r-matrix formulation, Lax formulation, canonical
  realisation, explicit BTs
- P Trig-r, Trig-integrals, Trig-gauge, Trig-one-point | Conclusions: n-body chains from each N-th jet extension with
  trigonometric and elliptic dependences on the spectral parameter
  reason: announced, not done in the paper; the trigonometric family (XXZ) with jet sites is built and checked by
  jetgaudin (issue 23: r-matrix, integrals, the gauge rule of its real two-point map, its one-point maps and their
  factorisation of it); the elliptic one is not yet
- P Chain-r, Chain-integrals | Conclusions: n-body chains for each N (done for N = 2 in [MPRS])
  reason: the rational chains of any sites and orders are built and checked (jetgaudin.GaudinModel); the content of
  [MPRS] is cited

== Appendix 1
- C 2p | Appendix 1: the form X^ = Phi X + X0 recalled
- C x, X | Appendix 1: s, t recalled from (x), (X)
- C App1-X0 | Appendix 1: X0(s,t;eta) (misprinted)
- C App1-A | Appendix 1: alpha_1 = 2 Im(eta) - st (misprinted), alpha_2 = alpha_1 - st
- C App1-A | Appendix 1: the entries of A; A is skew-symmetric
- C App1-B | Appendix 1: the entries of B (misprinted)

== Appendix 2
- NC | Appendix 2: a MAPLE 8 program, a variant of Kuznetsov's MATLAB program
  reason: the program is not available
- P App2-timestep | Appendix 2: inputs b, eta, number of iterations, initial data; Im(eta) is the time step
  reason: an interpretation of a loose phrase, not a misprint: read as 'the map is a step Im(eta) of a flow' it
  fails, the map being a step -2 Im(eta) of the flow of nu(Re eta) (checked to O(Im(eta)^3)); 'time step' may mean
  no more than 'proportional to the step', which holds
- NC | Appendix 2: the output plots x - z (material point) and z (centre of mass of the top)
  reason: $INTERP; the orbit itself is computed by App2-sphere
- C App2-sphere | Appendix 2: the points z lie on the sphere <z, z> = const
- P App2-sphere | Figure 1: the orbit for (b; eta; N; X0) = (1; 5 + 0.1i; 1000; -2.4, -0.6, -1.2, -2.19, 0.89, 1.34,
  1, 0, 0)
  reason: the orbit is computed (z on the sphere, integrals kept); the figure file is empty in the source
  (\includegraphics{ }), so there is no picture to compare with
- NC | Figure 2: projection of Figure 1 on the x-y plane
  reason: the figure file is empty in the source
"""


def _parse(text: str) -> tuple[Statement, ...]:
    """The :class:`Statement` entries of a coverage map written as :data:`_MAP`."""
    entries: list[dict[str, Any]] = []
    section, field = "", "statement"
    for line in text.strip().splitlines():
        if not line.strip():
            continue
        if line.startswith("== "):
            section = line[3:]
        elif line.startswith("- "):
            head, statement = line[2:].split(" | ", 1)
            status, _, checks = head.partition(" ")
            entries.append(dict(statement=statement, section=section, status=_STATUS[status],
                                checks=tuple(c for c in checks.split(", ") if c), reason=""))
            field = "statement"
        elif line.startswith("  reason: "):
            entries[-1]["reason"], field = line[len("  reason: "):], "reason"
        elif line.startswith("  ") and entries:
            entries[-1][field] += " " + line[2:]
        else:
            raise ValueError(f"coverage map: cannot read the line {line!r}")
    for e in entries:
        for token, reason in _REASONS.items():
            e["reason"] = e["reason"].replace(token, reason)
    return tuple(Statement(**e) for e in entries)


STATEMENTS: tuple[Statement, ...] = _parse(_MAP)


def coverage() -> list[dict]:
    """The coverage map as JSON-able dicts, in the paper's order."""
    return [s.to_dict() for s in STATEMENTS]


def counts() -> dict[str, int]:
    """``{status: number of statements}`` for every status (zeros included)."""
    out = {c.value: 0 for c in Coverage}
    for s in STATEMENTS:
        out[s.status.value] += 1
    return out
