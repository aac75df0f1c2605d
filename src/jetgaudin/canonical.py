r"""Canonical (Euler-angle) realisation of :math:`\mathfrak g^{(3)}` on the leaf :math:`\mathcal O` (Section 5).

Canonical coordinates ``Q = (θ, φ, ψ, p_θ, p_φ, p_ψ)`` with ``{f, g} = Σ_i ∂f/∂q_i ∂g/∂p_i − ∂f/∂p_i ∂g/∂q_i``
are mapped to states ``X = (y, x, z)`` of the N = 3 top (field ``b e_3``) on the symplectic leaf (fo)

.. math:: \mathcal O = \{C^{(1)} = \langle y, z\rangle + \tfrac12 |x|^2 = 0,\; C^{(2)} = \langle x, z\rangle = 0,\;
          C^{(3)} = |z|^2 = 1\}.

With :math:`e_\theta = (\cos\theta\cos\phi, \cos\theta\sin\phi, -\sin\theta)`,
:math:`e_\phi = (-\sin\phi, \cos\phi, 0)` the (corrected) realisation is

.. math::
    z &= (\sin\theta\cos\phi,\ \sin\theta\sin\phi,\ \cos\theta), \\
    y &= \big(-\sin\phi\,p_\theta - \cot\theta\cos\phi\,p_\phi - \tfrac{\cos\phi}{\sin\theta}\,p_\psi,\
              \cos\phi\,p_\theta - \cot\theta\sin\phi\,p_\phi - \tfrac{\sin\phi}{\sin\theta}\,p_\psi,\ p_\phi\big)
       = p_\theta e_\phi - \tfrac{p_\phi + p_\psi\cos\theta}{\sin\theta} e_\theta + (\ldots)\,z, \\
    x &= \sqrt{2 p_\psi}\,\big(\sin\psi\sin\phi + \cos\theta\cos\psi\cos\phi,\
              -\sin\psi\cos\phi + \cos\theta\cos\psi\sin\phi,\ -\sin\theta\cos\psi\big)
       = \sqrt{2 p_\psi}\,(\cos\psi\, e_\theta - \sin\psi\, e_\phi),

so ``⟨y, z⟩ = −p_ψ``, ``|x|² = 2 p_ψ``, ``p_θ = ⟨y, e_φ⟩``, ``p_φ = y³``.  The printed proposition of
Section 5 is misprinted (its canonical brackets fail (algebra) and its image is off the leaf); the
corrections are: the signs of the ``p_θ`` and ``p_φ`` terms of ``y¹, y²`` and of the ``cos θ cos ψ`` terms
of ``x¹, x²``.  See ``docs/canonical.md`` and ``docs/errata.md``.  Chart: ``θ ∈ (0, π)``, ``φ, ψ ∈ [0, 2π)``,
``p_ψ > 0`` (the standard Euler angles; the printed ranges ``θ ∈ [0, 2π)``, ``ψ ∈ [0, π)`` swap those of ``θ`` and
``ψ``: check ``Sec5-ranges``).

Hamiltonian ``H = H_2/2 = |y|²/2 + b x³`` (eq. (H)) and integrals ``I_1 = y³ = p_φ`` (``= H_1/(2b)``),
``I_2 = H_3/2 = b z³ + ⟨y, x⟩`` in these variables: :func:`canonical_hamiltonian`,
:func:`canonical_integrals`; Hamilton's equations: :func:`canonical_vector_field` (derived with SymPy).
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import sympy as sp
from numpy.typing import ArrayLike

from ._errors import InvalidParameterError, InvalidStateError, OffLeafError
from ._validate import as_state, real_number

__all__ = [
    "LEAF_TOL",
    "SINGULAR_TOL",
    "euler_to_state",
    "state_to_euler",
    "leaf_residuals",
    "leaf_casimirs",
    "on_canonical_leaf",
    "canonical_hamiltonian",
    "canonical_integrals",
    "canonical_vector_field",
    "symbolic_realisation",
    "symbolic_hamiltonian",
    "check_realisation",
]

#: default tolerance of the leaf conditions (relative residuals, see :func:`leaf_residuals`)
LEAF_TOL = 1e-9
#: ``|sin θ|`` (resp. ``|x|``) below this is treated as the coordinate singularity θ ∈ πZ (resp. p_ψ = 0)
SINGULAR_TOL = 1e-12

_NAMES = ("theta", "phi", "psi", "p_theta", "p_phi", "p_psi")


# ----------------------------------------------------------------------------------------------- symbolic
@cache
def _symbols():
    th, ph, ps = sp.symbols("theta phi psi", real=True)
    pth, pph, pps = sp.symbols("p_theta p_phi p_psi", real=True)
    b = sp.Symbol("b", real=True)
    return (th, ph, ps), (pth, pph, pps), b


@cache
def symbolic_realisation() -> tuple[tuple, tuple, tuple]:
    r"""The realisation as SymPy expressions: ``(q, p, X)`` with ``q = (θ, φ, ψ)``, ``p = (p_θ, p_φ, p_ψ)``
    (real symbols) and ``X`` a tuple of the 9 components ``(y¹, y², y³, x¹, x², x³, z¹, z², z³)`` of the corrected
    realisation of the module docstring (Section 5, Proposition; the printed one is transcribed only in
    :mod:`jetgaudin.verify.printed`).
    """
    (th, ph, ps), (pth, pph, pps), _ = _symbols()
    s, c, cot = sp.sin, sp.cos, sp.cot
    z = (s(th) * c(ph), s(th) * s(ph), c(th))
    r = sp.sqrt(2 * pps)
    y = (-s(ph) * pth - cot(th) * c(ph) * pph - c(ph) / s(th) * pps,
         c(ph) * pth - cot(th) * s(ph) * pph - s(ph) / s(th) * pps,
         pph)
    x = (r * (s(ps) * s(ph) + c(th) * c(ps) * c(ph)),
         r * (-s(ps) * c(ph) + c(th) * c(ps) * s(ph)),
         r * (-s(th) * c(ps)))
    return (th, ph, ps), (pth, pph, pps), tuple(y) + tuple(x) + tuple(z)


@cache
def symbolic_hamiltonian() -> tuple[tuple, tuple, sp.Symbol, sp.Expr]:
    r"""``(q, p, b, H)``: the canonical Hamiltonian (``= H_2/2`` o realisation, eq. (H)) as a SymPy expression:

    .. math:: H = \frac{p_\theta^2}{2} + \frac{p_\psi^2 + p_\phi^2 + 2 p_\psi p_\phi\cos\theta}{2\sin^2\theta}
                  - b\sqrt{2 p_\psi}\,\sin\theta\cos\psi

    (the paper prints ``− 2 p_ψ p_φ cos θ``: ``docs/errata.md``, check ``Sec5-H``).
    """
    (th, ph, ps), (pth, pph, pps), b = _symbols()
    H = (pth**2 / 2 + (pps**2 + pph**2 + 2 * pps * pph * sp.cos(th)) / (2 * sp.sin(th) ** 2)
         - b * sp.sqrt(2 * pps) * sp.sin(th) * sp.cos(ps))
    return (th, ph, ps), (pth, pph, pps), b, H


def _canonical_bracket(f, g, q, p):
    return sum(sp.diff(f, qi) * sp.diff(g, pi) - sp.diff(f, pi) * sp.diff(g, qi) for qi, pi in zip(q, p, strict=True))


def _simplify(expr):
    # expand first (cheap, settles most brackets), full simplify only for what is left
    r = sp.expand(expr)
    return r if r == 0 else sp.simplify(r)


def check_realisation(X: tuple | None = None) -> tuple[bool, dict]:
    r"""Symbolic check that a realisation reproduces (algebra) and lies on the leaf (fo).

    ``X``: 9 SymPy expressions in the symbols of :func:`symbolic_realisation` (default: the corrected
    realisation).  Returns ``(ok, residuals)``: ``residuals`` maps a pair of component names (e.g.
    ``("y1", "z2")``) to the simplified ``{X_I, X_J}_can − Σ_K c^{IJ}_K X_K``, and ``"C1"``, ``"C2"``, ``"C3"`` to
    ``C^(1)``, ``C^(2)``, ``C^(3) − 1``; only nonzero residuals are listed, so ``ok`` iff it is empty.
    Takes about a second (36 brackets and 3 Casimirs through ``sympy``); the result is cached.

    >>> check_realisation()
    (True, {})

    ``docs/canonical.md`` applies it to the printed proposition (:mod:`jetgaudin.verify.printed`).
    """
    ok, res = _check_realisation(symbolic_realisation()[2] if X is None else tuple(X))
    return ok, dict(res)


@cache
def _check_realisation(X: tuple) -> tuple[bool, dict]:
    from .algebra import structure_constants

    q, p, _ = symbolic_realisation()
    cst = structure_constants(3)
    names = [f"{v}{a}" for v in "yxz" for a in (1, 2, 3)]
    res: dict[Any, Any] = {}  # keys: (name, name) for brackets, "C1".. for the Casimirs
    for i in range(9):
        for j in range(i + 1, 9):
            expected = sum(int(cst[i, j, k]) * X[k] for k in range(9) if cst[i, j, k] != 0)
            r = _simplify(_canonical_bracket(X[i], X[j], q, p) - expected)
            if r != 0:
                res[(names[i], names[j])] = r
    y, x, z = X[0:3], X[3:6], X[6:9]

    def dot(u, v):
        return sum(a * b for a, b in zip(u, v, strict=True))

    for key, expr in (("C1", dot(y, z) + dot(x, x) / 2), ("C2", dot(x, z)), ("C3", dot(z, z) - 1)):
        r = _simplify(expr)
        if r != 0:
            res[key] = r
    return not res, res


# ----------------------------------------------------------------------------------------------- numeric
def _as_canonical(Q, *, strict_ppsi: bool = False) -> np.ndarray:
    try:
        arr = np.asarray(Q)
    except Exception as exc:  # pragma: no cover
        raise InvalidStateError(f"Q must be an array of numbers: {exc}") from None
    if arr.dtype == object or arr.dtype.kind not in "biuf":
        raise InvalidStateError(f"Q must be a real array, got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    if arr.ndim == 0 or arr.shape[-1] != 6:
        n = "scalar" if arr.ndim == 0 else arr.shape[-1]
        raise InvalidStateError(
            "Q must have shape (..., 6) = (theta, phi, psi, p_theta, p_phi, p_psi); "
            f"its last axis has length {n}"
        )
    if not np.all(np.isfinite(arr)):
        raise InvalidStateError("Q has non-finite entries (NaN or inf); give finite numbers")
    sth = np.sin(arr[..., 0])
    if np.any(np.abs(sth) < SINGULAR_TOL):
        raise InvalidStateError(
            "theta is a multiple of pi (sin(theta) = 0): the Euler chart is singular there "
            "(y has 1/sin(theta) terms); take theta in (0, pi)"
        )
    pps = arr[..., 5]
    if strict_ppsi and np.any(pps <= 0):
        raise InvalidStateError(
            "p_psi must be > 0 here (dH/dp_psi has a 1/sqrt(2 p_psi) term; p_psi = |x|^2/2 = 0 is the polar "
            "origin of the (psi, p_psi) chart); take p_psi > 0"
        )
    if np.any(pps < 0):
        raise InvalidStateError("p_psi must be >= 0 (x = sqrt(2 p_psi) (...), p_psi = |x|^2/2); take p_psi >= 0")
    return arr


def _frame(th, ph):
    st, ct, sf, cf = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    z = np.stack([st * cf, st * sf, ct], axis=-1)
    e_th = np.stack([ct * cf, ct * sf, -st], axis=-1)
    e_ph = np.stack([-sf, cf, np.zeros_like(sf)], axis=-1)
    return z, e_th, e_ph


def euler_to_state(Q: ArrayLike) -> np.ndarray:
    r"""``(θ, φ, ψ, p_θ, p_φ, p_ψ) ↦ (y, x, z)``, shape ``(..., 6) → (..., 9)`` (Section 5, corrected).

    .. math:: z = e_r(\theta, \phi), \quad
              y = p_\theta e_\phi - \frac{p_\phi + p_\psi\cos\theta}{\sin\theta} e_\theta + \ldots
              \ (\text{written out in the module docstring}), \quad
              x = \sqrt{2 p_\psi}(\cos\psi\,e_\theta - \sin\psi\,e_\phi).

    The image lies on the leaf (fo) and the canonical brackets of the components are (algebra).
    Raises :class:`InvalidStateError` for a bad shape, non-finite entries, ``sin θ = 0`` or ``p_ψ < 0``.

    >>> import numpy as np
    >>> X = euler_to_state([np.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.5])
    >>> np.round(X, 12).tolist()   # z = e_1, x = e_theta = -e_3, y = -p_psi z
    [-0.5, 0.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0]
    """
    Q = _as_canonical(Q)
    th, ph, ps, pth, pph, pps = Q.reshape(-1, 6).T  # 1-D batch: see canonical_vector_field
    st, ct, sf, cf = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    sp_, cp = np.sin(ps), np.cos(ps)
    y = np.stack([-sf * pth - ct / st * cf * pph - cf / st * pps,
                  cf * pth - ct / st * sf * pph - sf / st * pps,
                  pph], axis=-1)
    r = np.sqrt(2 * pps)
    x = np.stack([r * (sp_ * sf + ct * cp * cf), r * (-sp_ * cf + ct * cp * sf), -r * st * cp], axis=-1)
    z = np.stack([st * cf, st * sf, ct], axis=-1)
    return np.concatenate([y, x, z], axis=-1).reshape(Q.shape[:-1] + (9,))


def _as_state3(X) -> np.ndarray:
    X, N = as_state(X)
    if N != 3:
        raise InvalidStateError(
            f"the canonical realisation is for N = 3 (states (y, x, z) of shape (..., 9)); got N = {N}"
        )
    return X


def leaf_casimirs(X: ArrayLike) -> np.ndarray:
    r"""The Casimirs of :math:`\mathfrak g^{(3)}` of Section 3, ``(C^(1), C^(2), C^(3))``, shape ``(..., 3)``:

    .. math:: C^{(1)} = \langle y, z\rangle + \tfrac12 |x|^2, \quad C^{(2)} = \langle x, z\rangle, \quad
              C^{(3)} = |z|^2

    (eq. (cas): ``C_1 = 2 C^(1)``, ``C_2 = 2 C^(2)``, ``C_3 = C^(3)``); the leaf (fo) is ``(0, 0, 1)``.

    >>> [round(float(c), 12) for c in leaf_casimirs([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])]  # Appendix 2
    [1.2919, -2.19, 1.0]
    """
    X = _as_state3(X)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    return np.stack([np.sum(y * z, axis=-1) + np.sum(x * x, axis=-1) / 2, np.sum(x * z, axis=-1),
                     np.sum(z * z, axis=-1)], axis=-1)


def leaf_residuals(X: ArrayLike) -> np.ndarray:
    r"""Relative residuals ``(r_1, r_2, r_3)`` of the leaf conditions (fo), shape ``(..., 3)``:

    .. math:: r_1 = \frac{|\langle y,z\rangle + |x|^2/2|}{\max(1, |y||z| + |x|^2/2)}, \quad
              r_2 = \frac{|\langle x,z\rangle|}{\max(1, |x||z|)}, \quad r_3 = \big||z|^2 - 1\big| .
    """
    X = _as_state3(X)
    shape = X.shape[:-1]
    X = X.reshape(-1, 9)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    ny, nx, nz = (np.linalg.norm(v, axis=-1) for v in (y, x, z))
    r1 = np.abs(np.sum(y * z, axis=-1) + nx**2 / 2) / np.maximum(1.0, ny * nz + nx**2 / 2)
    r2 = np.abs(np.sum(x * z, axis=-1)) / np.maximum(1.0, nx * nz)
    r3 = np.abs(nz**2 - 1)
    return np.stack([r1, r2, r3], axis=-1).reshape(shape + (3,))


def _check_tol(tol) -> float:
    tol = real_number(tol, "tol")
    if not tol > 0:
        raise InvalidParameterError(f"tol must be finite and > 0, got {tol}")
    return tol


def on_canonical_leaf(X: ArrayLike, tol: float = LEAF_TOL) -> np.ndarray:
    r"""``True`` where ``X = (y, x, z)`` lies on the leaf (fo) ``C^(1) = 0, C^(2) = 0, C^(3) = 1``, i.e. where
    every relative residual of :func:`leaf_residuals` is ``<= tol``; shape ``(...)``.

    >>> bool(on_canonical_leaf(euler_to_state([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])))
    True
    >>> bool(on_canonical_leaf([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]))   # Appendix 2: <x, z> != 0
    False
    """
    tol = _check_tol(tol)
    return np.all(leaf_residuals(X) <= tol, axis=-1)


_LEAF_FIXES = (
    ("C^(1) = <y, z> + |x|^2/2 = 0", "shift y along z: y -> y - (<y, z> + |x|^2/2) z / |z|^2"),
    ("C^(2) = <x, z> = 0", "project x orthogonally to z: x -> x - <x, z> z / |z|^2"),
    ("C^(3) = |z|^2 = 1", "normalise z: z -> z / |z| (then fix C^(2), C^(1))"),
)


def state_to_euler(X: ArrayLike, tol: float = LEAF_TOL) -> np.ndarray:
    r"""Inverse of :func:`euler_to_state` on the leaf: ``(y, x, z) ↦ (θ, φ, ψ, p_θ, p_φ, p_ψ)``, ``(..., 9) → (..., 6)``
    (Section 5).

    .. math:: \theta = \operatorname{atan2}(\sqrt{z_1^2+z_2^2}, z_3) \in (0, \pi), \
              \phi = \operatorname{atan2}(z_2, z_1), \ \psi = \operatorname{atan2}(-\langle x, e_\phi\rangle,
              \langle x, e_\theta\rangle), \ p_\theta = \langle y, e_\phi\rangle, \ p_\phi = y^3, \
              p_\psi = |x|^2/2,

    with ``φ, ψ`` reduced to ``[0, 2π)``.  Raises :class:`OffLeafError` if a leaf condition (fo) fails
    beyond ``tol`` (relative, see :func:`leaf_residuals`; the message names the condition and the fix), or at
    a coordinate singularity of the chart: ``sin θ < SINGULAR_TOL`` (``z = ±e_3``) or ``|x| < SINGULAR_TOL``
    (``p_ψ = 0``: ``ψ`` undefined).

    >>> Q = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    >>> np.allclose(state_to_euler(euler_to_state(Q)), Q, rtol=0, atol=1e-14)
    True
    """
    tol = _check_tol(tol)
    X = _as_state3(X)
    res = leaf_residuals(X)
    for k in (2, 1, 0):
        bad = res[..., k] > tol
        if np.any(bad):
            cond, fix = _LEAF_FIXES[k]
            worst = float(np.max(res[..., k]))
            raise OffLeafError(
                f"X is off the leaf O of Section 5: {cond} fails (relative residual {worst:.3g} > tol = {tol:g} "
                f"at {int(np.count_nonzero(bad))} point(s)); {fix}"
            )
    shape = X.shape[:-1]
    X = X.reshape(-1, 9)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    rho = np.hypot(z[..., 0], z[..., 1])
    th = np.arctan2(rho, z[..., 2])
    if np.any(np.sin(th) < SINGULAR_TOL):
        raise OffLeafError(
            "X is at a coordinate singularity of the Euler chart: sin(theta) = 0 (z = +-e_3, phi undefined); "
            "the chart does not cover these points (rotate the frame, or perturb z)"
        )
    nx = np.linalg.norm(x, axis=-1)
    if np.any(nx < SINGULAR_TOL):
        raise OffLeafError(
            "X is at a coordinate singularity of the Euler chart: x = 0, i.e. p_psi = |x|^2/2 = 0 and psi is "
            "undefined (polar origin of the (psi, p_psi) chart); the chart needs p_psi > 0"
        )
    ph = np.arctan2(z[..., 1], z[..., 0])
    _, e_th, e_ph = _frame(th, ph)
    ps = np.arctan2(-np.sum(x * e_ph, axis=-1), np.sum(x * e_th, axis=-1))
    pth = np.sum(y * e_ph, axis=-1)
    two_pi = 2 * np.pi
    out = np.stack([th, np.mod(ph, two_pi), np.mod(ps, two_pi), pth, y[..., 2], nx**2 / 2], axis=-1)
    return out.reshape(shape + (6,))


def _scalar_b(b) -> float:
    if isinstance(b, bool):
        raise InvalidParameterError("the field strength b must be a real number, got a bool")
    return real_number(b, "the field strength b (field b e_3)")


def canonical_hamiltonian(Q: ArrayLike, b: float) -> np.ndarray:
    r"""``H = H_2/2`` (eq. (H)) in canonical variables, shape ``(...)``:

    .. math:: H = \frac{p_\theta^2}{2} + \frac{p_\psi^2 + p_\phi^2 + 2 p_\psi p_\phi\cos\theta}{2\sin^2\theta}
                  - b\sqrt{2 p_\psi}\,\sin\theta\cos\psi .

    The paper prints ``− 2 p_ψ p_φ cos θ`` (misprint, inherited from the printed realisation; see
    ``docs/errata.md``).  ``b`` is the field strength (field ``b e_3``).

    >>> Q = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    >>> import jetgaudin as jg
    >>> bool(np.isclose(canonical_hamiltonian(Q, 1.5), jg.physical_hamiltonian(3, 1.5)(euler_to_state(Q))))
    True
    """
    b = _scalar_b(b)
    Q = _as_canonical(Q)
    th, _, ps, pth, pph, pps = Q.reshape(-1, 6).T
    st, ct = np.sin(th), np.cos(th)
    H = pth**2 / 2 + (pps**2 + pph**2 + 2 * pps * pph * ct) / (2 * st**2) - b * np.sqrt(2 * pps) * st * np.cos(ps)
    return H.reshape(Q.shape[:-1])


def canonical_integrals(Q: ArrayLike, b: float) -> np.ndarray:
    r"""The integrals ``(I_1, I_2)`` of Section 5 in canonical variables, shape ``(..., 2)``:

    .. math:: I_1 = y^3 = p_\phi \;(= H_1/(2b) \text{ for } b \ne 0), \qquad
              I_2 = \tfrac12 H_3 = b\cos\theta - \sqrt{2 p_\psi}\Big(p_\theta\sin\psi
                    + \frac{p_\phi + p_\psi\cos\theta}{\sin\theta}\cos\psi\Big).

    The paper prints ``I_1 = H_2/2 = p_φ``: the value ``p_φ`` is right (``φ`` is cyclic), the label is not
    (``H_2/2`` is the Hamiltonian; ``H_1 = 2⟨b, y⟩ = 2b p_φ``, so ``I_1 = H_1/(2b)``, and ``H_1/2 = b p_φ`` only
    for ``b = 1``).  The printed ``I_2`` has the opposite signs of the ``p_θ sin ψ`` and ``p_ψ cot θ cos ψ``
    terms.  See ``docs/errata.md`` (check ``Sec5-I``).  On the leaf the remaining integrals are the Casimirs
    ``C_1 = C_2 = 0``, ``C_3 = 1``.

    Parameters
    ----------
    Q : array_like, shape (..., 6)
        ``(θ, φ, ψ, p_θ, p_φ, p_ψ)`` with ``sin θ ≠ 0``, ``p_ψ ≥ 0``.
    b : float
        The field strength (field ``b e_3``); enters ``I_2`` only.

    Returns
    -------
    ndarray, shape (..., 2)

    Raises
    ------
    InvalidStateError, InvalidParameterError
        Bad shape, non-finite entries, ``sin θ = 0``, ``p_ψ < 0``; ``b`` not a finite real number.
    """
    b = _scalar_b(b)
    Q = _as_canonical(Q)
    th, _, ps, pth, pph, pps = Q.reshape(-1, 6).T
    st, ct = np.sin(th), np.cos(th)
    I1 = pph
    I2 = b * ct - np.sqrt(2 * pps) * (pth * np.sin(ps) + (pph + pps * ct) / st * np.cos(ps))
    return np.stack([I1, I2], axis=-1).reshape(Q.shape[:-1] + (2,))


@cache
def _vector_field_kernel():
    q, p, b, H = symbolic_hamiltonian()
    rhs = [sp.diff(H, pi) for pi in p] + [-sp.diff(H, qi) for qi in q]
    return sp.lambdify((*q, *p, b), rhs, modules="numpy", cse=True)


def canonical_vector_field(Q: ArrayLike, b: float) -> np.ndarray:
    r"""Hamilton's equations of :func:`canonical_hamiltonian`, shape ``(..., 6)``:

    .. math:: \dot q_i = \partial H/\partial p_i, \qquad \dot p_i = -\partial H/\partial q_i,

    derived with SymPy from ``H`` and lambdified once (``cse=True``).  ``φ`` is cyclic, so ``ṗ_φ = 0``.
    Needs ``sin θ ≠ 0`` and ``p_ψ > 0`` (``∂H/∂p_ψ`` contains ``1/√(2 p_ψ)``), else :class:`InvalidStateError`.
    Its push-forward by :func:`euler_to_state` is the vector field of (em), ``Π ∇(H_2/2)``.
    """
    b = _scalar_b(b)
    Q = _as_canonical(Q, strict_ppsi=True)
    # evaluate on a 1-D batch: NumPy scalar arithmetic (pow, ...) can differ in the last bit from the array loops,
    # and an ensemble member must equal the single run bit for bit
    flat = Q.reshape(-1, 6)
    out = _vector_field_kernel()(*flat.T, b)
    out = np.stack(np.broadcast_arrays(*[np.asarray(o, dtype=float) for o in out], flat[:, 0]), axis=-1)[:, :6]
    return out.reshape(Q.shape)
