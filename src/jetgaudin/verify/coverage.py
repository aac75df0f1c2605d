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


C, P, D, NC = Coverage.CHECKED, Coverage.PARTLY, Coverage.DEFINITION, Coverage.NOT_CHECKABLE


def _s(statement: str, section: str, status: Coverage, checks: tuple[str, ...] | str = (),
       reason: str = "") -> Statement:
    return Statement(statement, section, status, (checks,) if isinstance(checks, str) else tuple(checks), reason)


_CITED = "a result of the cited literature, not derived in this paper"
_INTERP = "a physical interpretation (names given to vectors), not a mathematical claim"

STATEMENTS: tuple[Statement, ...] = (
    # ------------------------------------------------------------------------------------------- Abstract, 1
    _s("Abstract/Intro: a hierarchy of Liouville completely integrable models with a linear r-matrix structure",
       "1", C, ("Prop1", "Prop2-involution", "LP-rank")),
    _s("Intro: N = 1 is the Euler top on su(2); N = 2 the Lagrange top on e(3) = su(2) (+)_s R^3", "1", C,
       "Intro-algebras"),
    _s("Intro: direct sums give n-body chains (Gaudin model, Lagrange chain) with rational, trigonometric, "
       "elliptic r-matrices", "1", P, ("Chain-r", "Chain-integrals"),
       "the rational case is checked (r-matrix structure of the sum over sites, integrals in involution); the "
       "trigonometric and elliptic cases are cited, not derived in this paper"),
    _s("Intro: the construction generalises to any simple Lie algebra", "1", NC, (), _CITED),
    _s("Intro: the N = 3 algebra includes su(2) and R^3 as proper subalgebras but is no longer a semidirect sum",
       "1", P, ("Sec3-structure", "Sec3-cocycle"),
       "read literally this contradicts Section 3 (g^(3) = su(2) (+)_s G); checked in Section 3's sense: G is not "
       "R^3 (+)_s R^3 and g^(3) is not e(3,2)"),
    _s("Intro: the system is the twisted Lagrange top of Thiffeault-Morrison (a cocycle added to the two-field "
       "top)", "1", P, "Sec3-cocycle", "the cocycle over e(3,2) is checked; the identification with [T1] is a "
       "citation"),
    _s("Intro: Vivolo's Lax matrix; the generalised Lagrange top has monodromy (no global action-angle "
       "variables)", "1", NC, (), _CITED),
    # ------------------------------------------------------------------------------------------- Section 2
    _s("(lax): L(l) = sum_a sigma^a [b^a + sum_i f_i(l) y_i^a], f_0 = 1/l", "2", D, (),
       "definition of the Lax matrix (its consequences are checked by Prop1, yy, Lemma1)"),
    _s("sigma^1, sigma^2, sigma^3 (after (lax))", "2", D, (), "definition (used by every check of L)"),
    _s("(LP): {y_i^a, y_j^b} = eps^{ab}_c y_{i+j}^c (i+j < N), 0 otherwise", "2", D, (),
       "definition of g^(N); that it is a Lie-Poisson algebra is checked by LP-jacobi"),
    _s("(LP) is a Lie-Poisson algebra (antisymmetry and Jacobi identity)", "2", C, "LP-jacobi"),
    _s("N is the order of the jet-extension; it coincides with the number of degrees of freedom", "2", C,
       "LP-rank"),
    _s("f_i(l) = sum over {q_i} prod_k c_k^{q_k}/q_k! (d/dl)^{|q_i|} f_0, c_k arbitrary complex constants", "2", D,
       (), "definition; evaluated by the checks kk, lax2, yy, Prop1"),
    _s("{q_i} = {q in N^i : q_1 + 2 q_2 + ... + i q_i = i}, |q_i| = sum q_k", "2", D, (), "definition"),
    _s("Prop. 1, (er): {L(l) x 1, 1 x L(m)} = [r(l - m), L(l) x 1 + 1 x L(m)], r(l) = sum sigma^a x sigma^a / l",
       "2", C, "Prop1"),
    _s("(yy): L(l) = (i/2)[[u, v], [w, -u]] with u, v, w as displayed (general c_k)", "2", C, "yy"),
    _s("(er) is equivalent to the displayed brackets of u(l), v(l), w(l)", "2", C,
       ("Prop1", "Sec2-uvw", "Sec2-uvw-general")),
    _s("Brackets of u, v, w displayed after (yy) (misprinted: see docs/errata.md)", "2", C,
       ("Sec2-uvw", "Sec2-uvw-general")),
    _s("xi in R^3 -> (1/2)[[i xi3, i xi1 + xi2], [i xi1 - xi2, -i xi3]] is an isomorphism su(2) ~ (R^3, ^)",
       "2", C, "Sec2-iso"),
    _s("<xi, eta> = -2 tr(xi eta) = 2 tr(eta xi^*)", "2", C, "Sec2-trace"),
    _s("(lax2): c_1 = -1, c_k = 0 gives L(l) = sum sigma^a [b^a + sum_i y_i^a / l^(i+1)]", "2", C, "lax2"),
    _s("Notation y_i = (y_i^1, y_i^2, y_i^3), b = (b^1, b^2, b^3)", "2", D, (), "notation"),
    _s("Lemma 1, (curve): det(L - mu) = 0 is the hyperelliptic curve 4 mu^2 + <b,b> + H(l) + C(l) = 0", "2", C,
       "Lemma1"),
    _s("Lemma 1, (Hh): H(l) (misprinted lower limit of the inner sum)", "2", C, "Hh"),
    _s("Lemma 1, (C): C(l)", "2", C, "C"),
    _s("Prop. 2: H_k and C_k as displayed (2N integrals)", "2", C, "Prop2"),
    _s("Prop. 2: {H_i, H_k} = {C_i, H_k} = {C_i, C_k} = 0", "2", C, "Prop2-involution"),
    _s("Prop. 2: the H_k are first integrals; the C_k are (combinations of) Casimirs, {C_k, y_j^b} = 0", "2", C,
       "Prop2-involution"),
    _s("Prop. 2: the 2N integrals are independent (a set of 2N integrals, Liouville integrability)", "2", C,
       "LP-rank"),
    _s("Proof of Prop. 2: H_k = Res l^(k-1) H(l), C_k = Res l^(N+k-1) C(l)", "2", C, "Prop2"),
    _s("Proof of Prop. 2: H(l) gives N commuting integrals thanks to the r-matrix structure (er)", "2", C,
       ("Prop1", "Prop2-involution")),
    _s("Proof of Prop. 2: {C_k, y_j^b} = ... = 2 sum eps y_{i+j} y_{N+k-i-2+j} (misprinted index) and the "
       "symmetrised display = 0", "2", C, "Prop2-proof"),
    # ------------------------------------------------------------------------------------------- Section 3
    _s("(kk): L(l) for N = 3 = b + y0/l - c1 y1/l^2 + y2 (c1^2/l - c2)/l^2", "3", C, "kk"),
    _s("b^a an external field, uniform and constant; c1, c2 real constants", "3", D, (), "definition"),
    _s("(algebra): the brackets of g^(3)", "3", C, "algebra"),
    _s("g^(3) = su(2) (+)_s G, dim G = 6", "3", C, "Sec3-structure"),
    _s("G includes the abelian proper subalgebra R^3 spanned by y2", "3", C, "Sec3-structure"),
    _s("G does not have a semidirect structure", "3", P, "Sec3-structure",
       "checked: no subalgebra of G complements span(y2), so G is not R^3 (+)_s R^3; literally G = span(y1^1) "
       "(+)_s span(y1^2, y1^3, y2) is a semidirect sum of a 1-dimensional subalgebra and an ideal"),
    _s("g^(3) is obtained by adding a cocycle to e(3,2) = su(2) (+)_s (R^3 (+) R^3)", "3", C, "Sec3-cocycle"),
    _s("e(3,2) describes a two-field top", "3", NC, (), _CITED),
    _s("The Lie-Poisson bracket of functions f, g on g^(3) (four terms)", "3", C, "Sec3-bracket"),
    _s("The non-semidirect structure lies in the last term <y2, grad1 f ^ grad1 g>, absent in e(3,2)", "3", C,
       "Sec3-cocycle"),
    _s("g^(3) has 3 Casimirs C^(1) = <y0,y2> + <y1,y1>/2, C^(2) = <y1,y2>, C^(3) = <y2,y2>", "3", C,
       ("Sec3-casimirs", "LP-rank")),
    _s("The Casimirs differ from those of e(3,2) only by <y0,y2> in C^(1)", "3", C, "Sec3-cocycle"),
    _s("Prop. 3, (cu3): the N = 3 curve and H_1, H_2, H_3, C_1, C_2, C_3 (misprinted)", "3", C, "Prop3"),
    # ------------------------------------------------------------------------------------------- Section 4
    _s("(kkk): L = b sigma^3 + sum sigma^a [y^a/l + x^a/l^2 + z^a/l^3] (renaming y0, y1, y2 = y, x, z)", "4", D,
       (), "definition (the reduction (lax2) with N = 3 and b = (0, 0, b)); checked via Sec4-laxform, we-cas"),
    _s("(kkk) extends the Lagrange top Lax matrix to a third-order pole", "4", P, "Sec4-lagrange",
       "the N = 2 reduction is checked to give the Lagrange top flow; 'extension' is descriptive"),
    _s("(we): H_1 = 2<b,y>, H_2 = <y,y> + 2<b,x>, H_3 = 2(<b,z> + <y,x>)", "4", C, "we-cas"),
    _s("(cas): C_1 = 2C^(1), C_2 = 2C^(2), C_3 = C^(3)", "4", C, "we-cas"),
    _s("y^3 and |z| are constants of the motion (as in the Lagrange case)", "4", C, "Sec4-constants"),
    _s("y, z interpreted as total angular momentum and centre of mass of a Lagrange top", "4", NC, (), _INTERP),
    _s("y is not the angular momentum of the top because of x; x is the moving centre of mass of top plus a "
       "material point at x - z, unit masses; C_1, C_2 link the two", "4", NC, (), _INTERP),
    _s("x must depend on momenta since {x^a, x^b} = eps^{ab}_c z^c", "4", C, "Sec5-momenta"),
    _s("H_2 coincides with the physical Hamiltonian of the Lagrange top, x on the sphere |x| = c (N = 2)", "4", C,
       "Sec4-lagrange"),
    _s("Lagrange top: ydot = b ^ x, xdot = y ^ x; x rotates rigidly", "4", C, "Sec4-lagrange"),
    _s("Section 4.1: brackets of the complex generators y^pm, x^pm, z^pm", "4.1", C, "Sec4-complex"),
    _s("Section 4.1: L(l) = B + Y/l + X/l^2 + Z/l^3, all in su(2)", "4.1", C, "Sec4-laxform"),
    _s("(H): H = H_2/2 = <y,y>/2 + <b,x> = -Tr(Y^2 + 2 B X)", "4.1", C, "H"),
    _s("(H): kinetic term is the norm of the total angular momentum, potential the projection of the centre of "
       "mass on the field", "4.1", NC, (), _INTERP),
    _s("(em), vector form: ydot = b ^ x, xdot = y ^ x + b ^ z, zdot = y ^ z", "4.1", C, "em"),
    _s("(em), matrix form (misprinted signs)", "4.1", C, "em-matrix"),
    _s("x does not rotate rigidly though z does; |x| is not preserved", "4.1", C, "Sec4-constants"),
    _s("C_2 = 2<x,z> does not imply that the angle between x and z is constant", "4.1", C, "Sec4-angle"),
    _s("d/dt (x - z) = y ^ (x - z) + b ^ z", "4.1", C, "Sec4-material"),
    _s("Prop. 4: Lax representation dL/dt = [L, M], M = X/l + Z/l^2 (misprinted order)", "4.1", C, "Prop-Lax"),
    # ------------------------------------------------------------------------------------------- Section 5
    _s("Euler angles theta in [0, 2pi), phi in [0, 2pi), psi in [0, pi) (misprinted ranges)", "5", C,
       "Sec5-ranges"),
    _s("(fo): the leaf O = {C^(1) = 0, C^(2) = 0, C^(3) = 1}", "5", D, (),
       "definition; the realisation's image is checked to lie on it (Prop-canonical)"),
    _s("Prop. 5: the canonical realisation of g^(3) on O in Euler angles (misprinted)", "5", C, "Prop-canonical"),
    _s("Proof of Prop. 5: the well-known realisation of an angular momentum y and a unit vector z", "5", C,
       "Prop-canonical", "the same (misprinted) y, z as the proposition"),
    _s("The canonical bracket {f, g} = sum df/dq dg/dp - df/dp dg/dq", "5", D, (), "definition"),
    _s("Proof of Prop. 5: requiring (algebra) on O gives x", "5", C, "Prop-canonical"),
    _s("|x|^2 = 2 p_psi > 0", "5", C, "Sec5-xnorm"),
    _s("As a consequence the Hamiltonian (H) describes a non-holonomic dynamics", "5", P, "Sec5-momenta",
       "checked: x depends on the momentum p_psi (not a function of the configuration); 'non-holonomic' is an "
       "interpretation (no constraint on velocities is stated), not decidable by a computation"),
    _s("H in canonical variables (misprinted sign of the cross term)", "5", C, "Sec5-H"),
    _s("phi is cyclic as in the Lagrange case; psi enters the potential", "5", C, "Sec5-cyclic"),
    _s("I_1 = H_2/2 = p_phi and I_2 = H_3/2 = ... (misprinted)", "5", C, "Sec5-I"),
    # ------------------------------------------------------------------------------------------- Section 6
    _s("Veselov's Lagrange correspondences; BTs for soliton equations", "6", NC, (), _CITED),
    _s("BT property 1: a BT is a Poisson map preserving the integrals of the flow it discretises", "6", C,
       ("BT-poisson-one-point", "BT-poisson-two-point", "BT-integrals")),
    _s("BT property 2: a BT is given by explicit formulae", "6", C, ("mp", "2p"),
       "the explicit formulas (mp) and (2p) are checked against the dressing"),
    _s("BT property 3: multi-valued, but single-valued on a level manifold of the integrals", "6", P,
       ("BT-integrals", "2p-real"),
       "the two values are the two signs of nu(eta), and nu(eta)^2 is a function of the integrals (checked, so "
       "the choice is fixed on a level set); 'single-valued' is a property of a choice, not a formula"),
    _s("BT property 4: a one-parameter family, eta conjugate to mu (spectrality)", "6", C, "Rem-spectrality"),
    _s("BT property 5: the BT is iterative, a symplectic integrator, eta an adjustable time step", "6", P,
       ("BT-poisson-two-point", "App2-timestep"),
       "the step is -2 Im(eta) of the flow of nu(Re eta) (checked), not eta itself"),
    _s("Section 6.1: u, v, w of the reduced system", "6.1", D, (), "definition; checked through we-cas, hh"),
    _s("One-point BT: L -> M L M^-1 (a similarity, so the spectrum is preserved)", "6.1", C,
       ("Prop4-casimirs", "BT-integrals")),
    _s("Updated variables u~, v~, w~ (tilde notation)", "6.1", D, (), "notation"),
    _s("(rr): M(l; eta) L(l) = L~(l) M(l; eta)", "6.1", D, (),
       "the defining relation of the map; the checks build the map from it"),
    _s("(ansatz): M = [[l - eta + pq, p], [q, 1]], det M = l - eta", "6.1", C, "ansatz"),
    _s("The number of zeros of det M is the number of essential Bäcklund parameters; p, q dynamical", "6.1", NC,
       (), "a remark on the method, not a formula"),
    _s("(hh): p = y^-/(2b), q = y~^+/(2b), y~^3 = y^3", "6.1", C, "hh"),
    _s("P = (eta, mu) and Q = (eta, -mu) on the curve, exchanged by the hyperelliptic involution", "6.1", D, (),
       "definition of the points"),
    _s("(hhh): q = (u(eta) - mu)/v(eta) = -w(eta)/(u(eta) + mu), with the curve displayed after it", "6.1", C,
       "hhh"),
    _s("The tilde u, v, w formulas of the one-point map", "6.1", C, ("mp-u", "mp-v", "mp-w")),
    _s("(rr) gives an integrable Poisson map", "6.1", C, ("BT-poisson-one-point", "BT-integrals")),
    _s("(mp): the explicit one-point map (misprinted)", "6.1", C, "mp"),
    _s("(leaf): the leaf C^(1) = gamma_1, C^(2) = gamma_2, C^(3) = 1", "6.1", D, (), "definition"),
    _s("Psi, Psi~, chi^-, chi~^+ notation", "6.1", D, (), "notation"),
    _s("Prop. 6, (e1), (e2), (fu): the generating function (misprinted)", "6.1", C, "fu"),
    _s("Proof of Prop. 6: the Casimirs do not change under the map", "6.1", C, "Prop4-casimirs"),
    _s("Proof of Prop. 6: y^+, x^+, z^+ and y~^-, x~^-, z~^- eliminated with the Casimirs (misprinted)", "6.1", C,
       "Prop4-leaf"),
    _s("Proof of Prop. 6: the map in the variables Psi, chi^-, Psi~, chi~^+ (misprinted), k^2 = 1 + eta z^- z~^+",
       "6.1", C, "Prop4-Psi"),
    _s("Remark 1: spectrality, mu = u(eta) - y~^+ v(eta)/(2b) = -dF/deta (misprinted)", "6.1", C,
       "Rem-spectrality"),
    _s("Remark 2: the one-point map is complex, not a physical BT", "6.1", C, "Rem-complex"),
    _s("Section 6.2: the composite B_(P1,Q2) = B_(Q2) o B_(P1)", "6.2", C, "128"),
    _s("The two one-point maps are inverse to each other when eta1 = eta2, mu1 = mu2", "6.2", C, "2p-inverse"),
    _s("(128): M(l; eta1, eta2) L = L^ M", "6.2", C, "128"),
    _s("(mm): M(l; eta1, eta2) and det M = (l - eta1)(l - eta2)", "6.2", C, "mm"),
    _s("(x): s (two forms)", "6.2", C, "x"),
    _s("(X): t (two forms)", "6.2", C, "X"),
    _s("-(2 mu_j)^2 = u^2 + v w = u^2 + v w after the map (misprinted normalisation)", "6.2", C,
       ("x", "X", "BT-integrals")),
    _s("For eta1 = eta2 (mu1 = mu2) the two-point map is the identity", "6.2", C, "2p-identity"),
    _s("(gg): eta1 = conj(eta2) reduces the two-point map to a real Poisson integrable map", "6.2", C,
       ("2p-real", "BT-poisson-two-point", "BT-integrals")),
    _s("The two-point map is a physical BT with two real parameters", "6.2", C, "2p-real"),
    _s("X = (y, x, z) in R^9 notation", "6.2", D, (), "notation"),
    _s("Prop. 7, (2p): X^ = Phi(s,t;eta) X + X0(s,t;eta), Phi = [[1,0,0],[A,1,0],[B,A,1]]", "6.2", C, "2p"),
    _s("Remark 3: (2p) is a nonlinear transformation", "6.2", C, "Rem-nonlinear"),
    # ------------------------------------------------------------------------------------------- Section 7
    _s("Conclusions: a rigid body on an extension of the two-field top's Lie-Poisson structure", "7", C,
       "Sec3-cocycle"),
    _s("Conclusions: r-matrix formulation, Lax formulation, canonical realisation, explicit BTs", "7", C,
       ("Prop1", "Prop-Lax", "Prop-canonical", "mp", "2p")),
    _s("Conclusions: n-body chains for each N (done for N = 2 in [MPRS])", "7", P, ("Chain-r", "Chain-integrals"),
       "the rational chains of any sites and orders are built and checked (jetgaudin.GaudinModel); the content of "
       "[MPRS] is cited"),
    # ------------------------------------------------------------------------------------------- Appendices
    _s("Appendix 1: the form X^ = Phi X + X0 recalled", "Appendix 1", C, "2p"),
    _s("Appendix 1: s, t recalled from (x), (X)", "Appendix 1", C, ("x", "X")),
    _s("Appendix 1: X0(s,t;eta) (misprinted)", "Appendix 1", C, "App1-X0"),
    _s("Appendix 1: alpha_1 = 2 Im(eta) - st (misprinted), alpha_2 = alpha_1 - st", "Appendix 1", C, "App1-A"),
    _s("Appendix 1: the entries of A; A is skew-symmetric", "Appendix 1", C, "App1-A"),
    _s("Appendix 1: the entries of B (misprinted)", "Appendix 1", C, "App1-B"),
    _s("Appendix 2: a MAPLE 8 program, a variant of Kuznetsov's MATLAB program", "Appendix 2", NC, (),
       "the program is not available"),
    _s("Appendix 2: inputs b, eta, number of iterations, initial data; Im(eta) is the time step (misprinted)",
       "Appendix 2", C, "App2-timestep"),
    _s("Appendix 2: the output plots x - z (material point) and z (centre of mass of the top)", "Appendix 2", NC,
       (), _INTERP + "; the orbit itself is computed by App2-sphere"),
    _s("Appendix 2: the points z lie on the sphere <z, z> = const", "Appendix 2", C, "App2-sphere"),
    _s("Figure 1: the orbit for (b; eta; N; X0) = (1; 5 + 0.1i; 1000; -2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0)",
       "Appendix 2", P, "App2-sphere",
       "the orbit is computed (z on the sphere, integrals kept); the figure file is empty in the source "
       "(\\includegraphics{ }), so there is no picture to compare with"),
    _s("Figure 2: projection of Figure 1 on the x-y plane", "Appendix 2", NC, (),
       "the figure file is empty in the source"),
)


def coverage() -> list[dict]:
    """The coverage map as JSON-able dicts, in the paper's order."""
    return [s.to_dict() for s in STATEMENTS]


def counts() -> dict[str, int]:
    """``{status: number of statements}`` for every status (zeros included)."""
    out = {c.value: 0 for c in Coverage}
    for s in STATEMENTS:
        out[s.status.value] += 1
    return out
