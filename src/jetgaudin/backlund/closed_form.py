r"""Closed forms of the N = 3 Bäcklund maps (Section 6.1 eq. (mp), Section 6.2 / Appendix 1), corrected.

Both maps are written out by the top-down Laurent division of the dressing relation, derived with SymPy
(``docs/closed_forms.md`` gives the derivation and every misprint of the printed formulas):

* one-point map (eq. (rr)): ``ℓ̃(λ) = M ℓ adj(M) / (λ − η)``, ``M = [[λ − η + pq, p], [q, 1]]`` (eq. (ansatz));
* real two-point map (eq. (128)): ``ℓ̆(λ) = M ℓ adj(M) / ((λ − η)(λ − η̄))``, ``M = λ + M0(s, t)`` (eq. (mm))
  with ``η1 = η``, ``η2 = η̄``.

Here ``ℓ = [[u, v], [w, −u]] = −2i L`` with ``u = b + y³/λ + x³/λ² + z³/λ³``,
``v = y⁻/λ + x⁻/λ² + z⁻/λ³``, ``w = y⁺/λ + …`` and the complex generators ``a^± = a¹ ± i a²`` of Sec. 4.1.
The coefficients of ``λ^0 … λ^{-3}`` of the Laurent series at ``λ = ∞`` are exact for *any* ``p, q``
(resp. ``s, t``); they equal the dressing (no pole at ``η``) when the parameters satisfy the spectrality
conditions (hh), (hhh) (resp. (x), (X)), which is what :class:`~jetgaudin.OnePointBacklund` and
:class:`~jetgaudin.TwoPointBacklund` compute.

The numerical cores :func:`_one_point_core` and :func:`_two_point_core` use only ``+ − * /`` and the
``.real``/``.imag`` attributes on their scalar arguments, so the same body runs on NumPy arrays and can be
compiled with ``numba.njit`` on complex scalars.

The printed (misprinted) formulas are transcribed only in :mod:`jetgaudin.verify.printed`
(``one_point_map``, ``appendix1``), where the checks ``mp``, ``App1-A``, ``App1-B``, ``App1-X0`` show that they
are wrong.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._errors import InvalidParameterError
from .._validate import as_state, nonzero_field, spectral_parameter

__all__ = [
    "one_point_closed_form",
    "two_point_closed_form",
    "two_point_matrices",
]


def _state3(X, allow_complex):
    X, N = as_state(X, allow_complex=allow_complex)
    if N != 3:
        raise InvalidParameterError(
            f"the closed forms (mp) and Appendix 1 are for N = 3 (states of length 9); got length {3 * N}. "
            "Use OnePointBacklund / TwoPointBacklund for other N"
        )
    return X


def _split(X: Any) -> Any:
    """The 9 components of ``X (..., 9)`` (typed ``Any``: a fixed-length tuple the cores unpack)."""
    return tuple(X[..., k] for k in range(9))


def _to_real_basis(ap, am, a3):
    """``(a¹, a², a³)`` from ``(a⁺, a⁻, a³)``, ``a^± = a¹ ± i a²``."""
    return 0.5 * (ap + am), -0.5j * (ap - am), a3


def _param(x, name):
    try:
        arr = np.asarray(x, dtype=complex)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a complex number or array, got {x!r}") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(
            f"{name} must be finite (an infinite {name} means a singular step: v(eta) = 0; use the generic "
            "route OnePointBacklund / TwoPointBacklund, which works projectively)"
        )
    return arr


# ---------------------------------------------------------------------------------------------
# one-point map, eq. (mp) corrected
# ---------------------------------------------------------------------------------------------


def _one_point_core(y1, y2, y3, x1, x2, x3, z1, z2, z3, b, eta, p, q):
    """Scalar core of :func:`one_point_closed_form`; returns the 9 new components ``(ỹ⁺, ỹ⁻, ỹ³, x̃⁺, …)``."""
    yp = y1 + 1j * y2
    ym = y1 - 1j * y2
    xp = x1 + 1j * x2
    xm = x1 - 1j * x2
    zm = z1 - 1j * z2
    r = 2.0 * b * p  # = y⁻ when (hh) holds
    pq = p * q
    # the w-, u- and v-rows of M ℓ adj(M) (the lead's corrected ũ, ṽ, w̃ above (mp)), divided top-down
    wy = yp + 2.0 * q * y3 - q * q * ym  # w + 2 q u − q² v, order-1 part
    wx = xp + 2.0 * q * x3 - q * q * xm
    ypt = 2.0 * b * q
    xpt = wy + 2.0 * b * eta * q
    zpt = wx + eta * wy + 2.0 * b * eta * eta * q
    y3t = y3 + q * (r - ym)
    x3t = x3 + p * wy - q * xm + eta * q * r
    z3t = z3 + p * wx - q * zm + eta * p * wy + eta * eta * q * r
    ymt = xm + (2.0 * pq - eta) * ym - 2.0 * p * y3 - pq * r
    xmt = zm + (2.0 * pq - eta) * xm - 2.0 * p * x3 - p * p * wy - eta * pq * r
    zmt = (2.0 * pq - eta) * zm - 2.0 * p * z3 - p * p * wx - eta * p * p * wy - eta * eta * pq * r
    return ypt, ymt, y3t, xpt, xmt, x3t, zpt, zmt, z3t


def one_point_closed_form(X: ArrayLike, b: float, eta: complex, p: ArrayLike, q: ArrayLike) -> np.ndarray:
    r"""Closed form of the one-point map ``B_η`` for N = 3 (eq. (mp), **corrected**; ``docs/errata.md``).

    With ``a^± = a¹ ± i a²`` and ``r = 2bp`` (``= y⁻`` by (hh)):

    .. math::
        ỹ^3 &= y^3 + q(r − y^-), \quad ỹ^- = x^- + (2pq − η) y^- − 2p y^3 − pq\,r, \quad ỹ^+ = 2bq, \\
        x̃^3 &= x^3 + p W_y − q x^- + ηq r, \quad
        x̃^- = z^- + (2pq − η) x^- − 2p x^3 − p^2 W_y − ηpq\,r, \quad x̃^+ = W_y + 2bηq, \\
        z̃^3 &= z^3 + p W_x − q z^- + ηp W_y + η^2 q r, \quad
        z̃^- = (2pq − η) z^- − 2p z^3 − p^2 W_x − ηp^2 W_y − η^2 pq\,r, \\
        z̃^+ &= W_x + η W_y + 2bη^2 q, \qquad W_a = a^+ + 2q a^3 − q^2 a^-.

    These are the coefficients of ``λ^{-1}, λ^{-2}, λ^{-3}`` of ``M ℓ adj(M)/(λ − η)`` expanded at
    ``λ = ∞`` (exact for any ``p, q``); they are the dressed state when ``p = y⁻/(2b)`` (hh) and
    ``q = (u(η) − ν)/v(η)`` (hhh), i.e. ``(p, q) = OnePointBacklund(b, eta).parameters(X)[:2]``.
    With ``r = y⁻`` they coincide with the printed (mp) except for ``x̃⁻`` (the printed one lacks ``+z⁻``)
    and the ``y⁻`` terms of ``z̃³, z̃⁻, z̃⁺`` (printed with the wrong sign).

    Parameters: ``X`` real or complex ``(..., 9)``; ``b`` real nonzero; ``eta`` complex; ``p, q``
    complex arrays broadcastable to ``X[..., 0]``.  Returns complex ``(..., 9)`` in the basis ``(y, x, z)``.
    """
    X = _state3(X, allow_complex=True)
    b = nonzero_field(b)
    eta = spectral_parameter(eta)
    p = _param(p, "p")
    q = _param(q, "q")
    args = (*_split(X), b, eta, p, q)
    ypt, ymt, y3t, xpt, xmt, x3t, zpt, zmt, z3t = _one_point_core(*args)
    out = [*_to_real_basis(ypt, ymt, y3t), *_to_real_basis(xpt, xmt, x3t), *_to_real_basis(zpt, zmt, z3t)]
    return np.stack(np.broadcast_arrays(*out), axis=-1).astype(complex)


# ---------------------------------------------------------------------------------------------
# real two-point map, Appendix 1 corrected
# ---------------------------------------------------------------------------------------------


def _two_point_coefficients(b, er, ei, s, t):
    """Entries ``(A12, A13, A23, B11, B12, B13, B21, B22, B23, B31, B32, B33, X0[6], X0[7], X0[8])`` of ``A``, ``B``
    and ``X0`` (see :func:`two_point_matrices`): the last 15 values of :func:`_two_point_core`, which do not depend
    on the state (read here at ``X = 0``; scalar arithmetic only, so ``b, s, t`` may be arrays or mpmath numbers)."""
    return _two_point_core(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, b, er, ei, s, t)[9:]


def _two_point_core(y1, y2, y3, x1, x2, x3, z1, z2, z3, b, er, ei, s, t):
    """Scalar core of :func:`two_point_closed_form` and :func:`two_point_matrices`: ``X̆ = Φ X + X0``.

    Returns the 9 complex components of ``X̆``, then the 15 entries of ``A``, ``B`` and ``X0[6:9]`` it used (as
    :func:`_two_point_coefficients`).  One self-contained function, so that ``numba.njit`` compiles it alone
    (:mod:`jetgaudin.backlund.kernels._closed`); the unused entries cost nothing there once inlined.
    """
    st = s * t
    a1 = 2j * ei - st  # α1 = η1 − η2 − st  (printed without the i)
    a2 = a1 - st  # α2 = α1 − st
    sa = s * a1
    R = er
    re2 = er * er - ei * ei  # Re(η²)
    # A: skew-symmetric (as printed)
    A12 = 1j * a2
    A13 = sa - t
    A23 = -1j * (sa + t)
    # B
    B11 = 0.5 * (1.0 - s * s) * (a1 * a1 - t * t)
    B12 = 0.5j * (2.0 * R * a2 + s * s * a1 * a1 - t * t)
    B13 = 0.5 * (sa * (a2 + 2.0 * R) + t * (a2 - 2.0 * R))
    B21 = -0.5j * (t * t - s * s * a1 * a1 + 2.0 * R * a2)
    B22 = 0.5 * (1.0 + s * s) * (a1 * a1 + t * t)
    B23 = -0.5j * (sa * (a2 + 2.0 * R) - t * (a2 - 2.0 * R))
    B31 = 0.5 * (sa * (a2 - 2.0 * R) + t * (a2 + 2.0 * R))
    B32 = 0.5j * (t * (a2 + 2.0 * R) - sa * (a2 - 2.0 * R))
    B33 = 2.0 * st * a1
    # X0 = b (A e3, B e3, C e3): the field b e3 enters as a level "y_{-1}"
    c1 = b * (re2 * (sa - t) + R * a2 * (sa + t))  # b C13
    c2 = b * (-1j * (re2 * (sa + t) + R * a2 * (sa - t)))  # b C23
    c3 = b * (4.0 * R * st * a1)  # b C33
    # A is skew: A21 = −A12, A31 = −A13, A32 = −A23
    Ay1 = A12 * y2 + A13 * y3
    Ay2 = -A12 * y1 + A23 * y3
    Ay3 = -A13 * y1 - A23 * y2
    Ax1 = A12 * x2 + A13 * x3
    Ax2 = -A12 * x1 + A23 * x3
    Ax3 = -A13 * x1 - A23 * x2
    n1 = y1 + b * A13
    n2 = y2 + b * A23
    n3 = y3 + 0.0 * s
    n4 = x1 + Ay1 + b * B13
    n5 = x2 + Ay2 + b * B23
    n6 = x3 + Ay3 + b * B33
    n7 = z1 + Ax1 + B11 * y1 + B12 * y2 + B13 * y3 + c1
    n8 = z2 + Ax2 + B21 * y1 + B22 * y2 + B23 * y3 + c2
    n9 = z3 + Ax3 + B31 * y1 + B32 * y2 + B33 * y3 + c3
    return (n1, n2, n3, n4, n5, n6, n7, n8, n9,
            A12, A13, A23, B11, B12, B13, B21, B22, B23, B31, B32, B33, c1, c2, c3)


def two_point_closed_form(
    X: ArrayLike, b: float, eta: complex, s: ArrayLike, t: ArrayLike, *, return_imag: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    r"""Closed form ``X̆ = Φ(s, t; η) X + X0(s, t; η)`` of the real two-point map (eq. (2p), Appendix 1,
    **corrected**; ``docs/errata.md``), ``Φ = [[1, 0, 0], [A, 1, 0], [B, A, 1]]``.

    With ``α1 = 2i Im η − st`` (printed without the ``i``), ``α2 = α1 − st``, ``R = Re η`` and
    ``X0 = b (A e3, B e3, C e3)`` (see :func:`two_point_matrices` for ``A, B, C``).  ``s, t`` are those
    of eqs. (x), (X) with ``η1 = η``, ``η2 = η̄``, ``ν2 = conj ν1``, i.e.
    ``TwoPointBacklund(b, eta).parameters(X)[:2]``; for them every entry is real and the imaginary part
    of the result is round-off, which is dropped.

    Returns the real ``(..., 9)`` array, or ``(X̆, imag)`` with ``imag = max|Im X̆| / (1 + max|Re X̆|)``
    per state when ``return_imag=True`` (large when ``s, t`` are not the real-reduction parameters).
    """
    X = _state3(X, allow_complex=False)
    b = nonzero_field(b)
    eta = spectral_parameter(eta)
    s = _param(s, "s")
    t = _param(t, "t")
    args = (*_split(X), b, eta.real, eta.imag, s, t)
    out = _two_point_core(*args)[:9]
    Xc = np.stack(np.broadcast_arrays(*out), axis=-1).astype(complex)
    Xr = Xc.real
    if not return_imag:
        return Xr
    imag = np.max(np.abs(Xc.imag), axis=-1) / (1.0 + np.max(np.abs(Xr), axis=-1))
    return Xr, imag


def two_point_matrices(
    b: float, eta: complex, s: ArrayLike, t: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""``(A, B, X0)`` of eq. (2p) in the real basis ``(y¹, y², y³)`` per block, shapes ``(..., 3, 3)``,
    ``(..., 3, 3)``, ``(..., 9)`` (complex; real up to round-off on the real reduction).

    With ``α1 = 2i Im η − st``, ``α2 = α1 − st``, ``R = Re η``:

    .. math::
        A &= \begin{pmatrix} 0 & iα_2 & sα_1 − t \\ −iα_2 & 0 & −i(sα_1 + t) \\ −(sα_1 − t) & i(sα_1 + t) & 0
             \end{pmatrix}, \\
        B_{11} &= \tfrac12(1 − s^2)(α_1^2 − t^2), \quad B_{22} = \tfrac12(1 + s^2)(α_1^2 + t^2), \quad
        B_{33} = 2stα_1, \\
        B_{12} &= −\tfrac i2[(t^2 − s^2α_1^2) − 2α_2R], \quad B_{21} = −\tfrac i2[(t^2 − s^2α_1^2) + 2α_2R], \\
        B_{13} &= \tfrac12[sα_1(α_2 + 2R) + t(α_2 − 2R)], \quad
        B_{23} = −\tfrac i2[sα_1(α_2 + 2R) − t(α_2 − 2R)], \\
        B_{31} &= \tfrac12[t(α_2 + 2R) + sα_1(α_2 − 2R)], \quad
        B_{32} = \tfrac i2[t(α_2 + 2R) − sα_1(α_2 − 2R)], \\
        X_0 &= b\,(A_{13}, A_{23}, 0, B_{13}, B_{23}, B_{33}, C_{13}, C_{23}, C_{33}), \\
        C_{13} &= \Re(η^2)(sα_1 − t) + Rα_2(sα_1 + t), \quad C_{23} = −i[\Re(η^2)(sα_1 + t) + Rα_2(sα_1 − t)],
        \quad C_{33} = 4Rstα_1.
    """
    b = nonzero_field(b)
    eta = spectral_parameter(eta)
    s = _param(s, "s")
    t = _param(t, "t")
    s, t = np.broadcast_arrays(s, t)
    A12, A13, A23, B11, B12, B13, B21, B22, B23, B31, B32, B33, c1, c2, c3 = _two_point_coefficients(
        b, eta.real, eta.imag, s, t
    )
    z = np.zeros(s.shape, dtype=complex)
    A = np.stack([np.stack([z, A12, A13], -1), np.stack([-A12, z, A23], -1), np.stack([-A13, -A23, z], -1)], -2)
    B = np.stack(
        [np.stack([B11, B12, B13], -1), np.stack([B21, B22, B23], -1), np.stack([B31, B32, B33], -1)], -2
    )
    X0 = np.stack([b * A13, b * A23, z, b * B13, b * B23, b * B33, c1, c2, c3], -1)
    return A, B, X0
