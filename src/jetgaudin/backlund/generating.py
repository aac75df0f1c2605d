r"""Generating function of the one-point map on a symplectic leaf (Section 6.1, Proposition with (e1), (e2),
(fu), and the spectrality remark), N = 3, **corrected** (``docs/closed_forms.md``, ``docs/errata.md``).

Leaf (leaf): ``C^(1) = ⟨y, z⟩ + ½⟨x, x⟩ = γ1``, ``C^(2) = ⟨x, z⟩ = γ2``, ``C^(3) = ⟨z, z⟩ = 1``.
Variables: ``Ψ = (y³, x³, z³)``, ``χ⁻ = (y⁻, x⁻, z⁻)`` of the old state, ``Ψ̃``, ``χ̃⁺ = (ỹ⁺, x̃⁺, z̃⁺)`` of the
new one (``a^± = a¹ ± i a²``), and ``k = z³ − ỹ⁺ z⁻/(2b)``, a root of ``k² = 1 + η z⁻ z̃⁺`` (the map fixes the
root; the generating function is two-valued in ``k``).

What holds (tests in ``tests/test_generating.py``):

* the Poisson brackets are ``{Ψ_i, χ⁻_j} = i H(χ⁻)_{ij}`` and ``{χ̃⁺_j, Ψ̃_i} = i H(χ̃⁺)_{ij}`` with the Hankel
  matrix ``H(a, b, c) = [[a, b, c], [b, c, 0], [c, 0, 0]]``;
* with the corrected ``F`` of :func:`generating_function`, ``Ψ = H(χ⁻) ∇_{χ⁻} F`` and
  ``Ψ̃ = H(χ̃⁺) ∇_{χ̃⁺} F``, i.e. (e1), (e2) hold for ``−iF`` (or for ``F`` with ``{·,·}`` replaced by
  ``−i{·,·}``);
* spectrality: ``∂F/∂η = ν = u(η) − ỹ⁺ v(η)/(2b)`` at fixed ``(χ⁻, χ̃⁺)``, ``ν`` the eigenvalue of
  ``ℓ(η) = −2i L(η)`` used by the map (``q = (u(η) − ν)/v(η)``).  For ``−iF`` (the normalisation of the
  printed (e1), (e2)) this reads ``−∂(−iF)/∂η = iν = 2μ``, ``μ = iν/2`` the eigenvalue of ``L(η)``.

The numerical cores use only ``+ − * /`` (and a ``log`` passed in), so they run on NumPy arrays and on
``mpmath`` numbers (the tests use 50 digits).  The printed (misprinted) (fu), Ψ formulas and Casimir elimination
are transcribed only in :mod:`jetgaudin.verify.printed` (checks ``fu``, ``Prop4-Psi``, ``Prop4-leaf``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._errors import InvalidParameterError, OffLeafError
from .._validate import as_state, nonzero_field

__all__ = [
    "generating_variables",
    "generating_function",
    "generating_psi",
    "casimir_elimination",
]


# ---------------------------------------------------------------------------------------------
# scalar cores (NumPy or mpmath)
# ---------------------------------------------------------------------------------------------


def _F_core(ym, xm, zm, ypt, xpt, zpt, eta, b, g1, g2, k, log):
    """Corrected (fu) plus ``bη`` (the η-dependent constant fixed by spectrality)."""
    bracket = (
        zpt * xm
        + zm * xpt
        - eta * xpt * xm
        + (xm / zm) * (xm / zm + 0.5 * eta * xm * zpt - 2 * g2)
        + (xpt / zpt) * (xpt / zpt + 0.5 * eta * xpt * zm - 2 * g2)
    )
    return (
        ym * ypt / (2 * b)
        + k * (ym / zm + ypt / zpt)
        - (1 + 2 * eta * g2) ** 2 / (4 * eta * eta * k)
        - k / (4 * eta * eta)
        + 0.5 * (g2 * g2 - 2 * g1) * log((k + 1) / (k - 1))
        - bracket / (2 * k)
        + b * eta
    )


def _psi_core(ym, xm, zm, ypt, xpt, zpt, eta, b, g1, g2, k):
    """Corrected displayed Ψ, Ψ̃ formulas of the proof (Ψ̃_1 = Ψ_1)."""
    P = zm * zpt
    S = xm * zpt + xpt * zm
    D = xm * zpt - xpt * zm
    T = zpt * ym + zm * ypt
    Q = (
        0.25 * eta * eta * D * D
        - eta * eta * P * T
        - eta * T
        - eta * xm * xpt
        + (1 + eta * g2 + 0.5 * eta * P) * S
        - (g2 + 2 * eta * g1) * P
        + 0.25 * P * P
        + g2 * g2
        - 2 * g1
    )
    y3 = ym * ypt / (2 * b) - Q / (2 * k * k * k)
    common = (eta * S - P + 2 * g2) / (2 * k)
    x3 = xm * ypt / (2 * b) + common
    z3 = ypt * zm / (2 * b) + k
    x3t = xpt * ym / (2 * b) + common
    z3t = zpt * ym / (2 * b) + k
    return y3, x3, z3, y3, x3t, z3t


def _elim_core(a3, b3, c3, am, bm, cm, g1, g2):
    """Corrected Casimir elimination: ``(y⁺, x⁺, z⁺)`` from ``Ψ = (y³, x³, z³)``, ``χ⁻``
    (the same formula gives ``(ỹ⁻, x̃⁻, z̃⁻)`` from ``Ψ̃``, ``χ̃⁺``)."""
    cp = (1 - c3 * c3) / cm
    bp = (2 * g2 - 2 * b3 * c3 - bm * cp) / cm
    ap = (2 * g1 - 2 * a3 * c3 - b3 * b3 - bp * bm - am * cp) / cm
    return ap, bp, cp


# ---------------------------------------------------------------------------------------------
# public array API
# ---------------------------------------------------------------------------------------------


def _vec3(a: ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(a, dtype=complex)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise InvalidParameterError(f"{name} must have shape (..., 3), got {arr.shape}")
    return arr


def generating_variables(
    X: ArrayLike, X_new: ArrayLike, b: float, *, leaf_tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The variables of (fu) from an old state ``X`` and its image ``X_new`` under the one-point map.

    Returns ``(chi_minus, chi_plus_new, gamma1, gamma2, k)``: ``χ⁻ = (y⁻, x⁻, z⁻)`` of ``X``,
    ``χ̃⁺ = (ỹ⁺, x̃⁺, z̃⁺)`` of ``X_new`` (shape ``(..., 3)``), ``γ1 = C^(1)(X)``, ``γ2 = C^(2)(X)`` and
    ``k = z³ − ỹ⁺ z⁻/(2b)`` (the root of ``k² = 1 + η z⁻ z̃⁺`` selected by the map).  Raises
    :class:`OffLeafError` if ``C^(3) = ⟨z, z⟩`` differs from 1 by more than ``leaf_tol`` (the formulas use
    ``C^(3) = 1``; rescale ``z``).
    """
    X, N = as_state(X, allow_complex=True)
    Xn, Nn = as_state(X_new, allow_complex=True, name="X_new")
    if N != 3 or Nn != 3:
        raise InvalidParameterError("the generating function (fu) is for N = 3 (states of length 9)")
    b = nonzero_field(b)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    c3 = np.sum(z * z, axis=-1)
    if np.any(np.abs(c3 - 1) > leaf_tol):
        raise OffLeafError(
            f"the generating function (fu) is written on the leaf C^(3) = <z, z> = 1; got |C^(3) - 1| = "
            f"{np.max(np.abs(c3 - 1)):.2e}. Rescale z (and b, eta) so that |z| = 1"
        )
    g1 = np.sum(y * z, axis=-1) + 0.5 * np.sum(x * x, axis=-1)
    g2 = np.sum(x * z, axis=-1)
    minus = lambda a: a[..., 0] - 1j * a[..., 1]  # noqa: E731
    plus = lambda a: a[..., 0] + 1j * a[..., 1]  # noqa: E731
    chi_minus = np.stack([minus(y), minus(x), minus(z)], axis=-1)
    chi_plus_new = np.stack([plus(Xn[..., 0:3]), plus(Xn[..., 3:6]), plus(Xn[..., 6:9])], axis=-1)
    k = z[..., 2] - chi_plus_new[..., 0] * chi_minus[..., 2] / (2 * b)
    return chi_minus, chi_plus_new, g1, g2, k


def generating_function(
    chi_minus: ArrayLike, chi_plus_new: ArrayLike, eta: complex, b: float, gamma1: ArrayLike, gamma2: ArrayLike,
    k: ArrayLike,
) -> np.ndarray:
    r"""The generating function ``F_η(χ⁻ | χ̃⁺)`` of the one-point map on the leaf (eq. (fu), **corrected**).

    .. math::
        F_η &= \frac{y^- ỹ^+}{2b} + k\Big(\frac{y^-}{z^-} + \frac{ỹ^+}{z̃^+}\Big)
              − \frac{(1 + 2ηγ_2)^2}{4η^2 k} − \frac{k}{4η^2}
              + \tfrac12(γ_2^2 − 2γ_1) \ln\frac{k+1}{k−1} \\
            &\quad − \frac{1}{2k}\Big[z̃^+x^- + z^-x̃^+ − η x̃^+x^-
              + \frac{x^-}{z^-}\Big(\frac{x^-}{z^-} + \frac η2 x^-z̃^+ − 2γ_2\Big)
              + \frac{x̃^+}{z̃^+}\Big(\frac{x̃^+}{z̃^+} + \frac η2 x̃^+z^- − 2γ_2\Big)\Big] + bη,

    ``k² = 1 + η z⁻ z̃⁺`` (the root from :func:`generating_variables`).  It satisfies
    ``Ψ = H(χ⁻)∇_{χ⁻}F``, ``Ψ̃ = H(χ̃⁺)∇_{χ̃⁺}F`` ((e1), (e2) for ``−iF``) and ``∂F/∂η = ν`` (spectrality);
    printed (fu) has ``γ2`` for ``2γ2`` (three times), ``γ2²/4 − γ1`` for ``γ2² − 2γ1``, lacks ``−k/(4η²)``
    (and the ``bη`` that makes ``∂F/∂η = ν`` exact).  Defined up to a constant (the branch of ``ln``).
    """
    cm = _vec3(chi_minus, "chi_minus")
    cp = _vec3(chi_plus_new, "chi_plus_new")
    b = nonzero_field(b)
    eta = complex(eta)
    if eta == 0:
        raise InvalidParameterError("eta must be nonzero (F contains 1/eta^2)")
    ym, xm, zm = (cm[..., j] for j in range(3))
    ypt, xpt, zpt = (cp[..., j] for j in range(3))
    g1 = np.asarray(gamma1, dtype=complex)
    g2 = np.asarray(gamma2, dtype=complex)
    return _F_core(ym, xm, zm, ypt, xpt, zpt, eta, b, g1, g2, np.asarray(k, dtype=complex), np.log)


def generating_psi(
    chi_minus: ArrayLike, chi_plus_new: ArrayLike, eta: complex, b: float, gamma1: ArrayLike, gamma2: ArrayLike,
    k: ArrayLike,
) -> tuple[np.ndarray, np.ndarray]:
    r"""``(Ψ, Ψ̃)`` as functions of ``(χ⁻, χ̃⁺)`` (the displayed formulas of the proof, **corrected**).

    With ``P = z⁻z̃⁺``, ``S = x⁻z̃⁺ + x̃⁺z⁻``, ``D = x⁻z̃⁺ − x̃⁺z⁻``, ``T = z̃⁺y⁻ + z⁻ỹ⁺``:

    .. math::
        y^3 = ỹ^3 &= \frac{y^-ỹ^+}{2b} − \frac{1}{2k^3}\Big[\tfrac14η^2D^2 − η^2PT − ηT − ηx^-x̃^+
                   + (1 + ηγ_2 + \tfrac12ηP)S − (γ_2 + 2ηγ_1)P + \tfrac14P^2 + γ_2^2 − 2γ_1\Big], \\
        x^3 &= \frac{x^-ỹ^+}{2b} + \frac{ηS − P + 2γ_2}{2k}, \qquad
        x̃^3 = \frac{x̃^+y^-}{2b} + \frac{ηS − P + 2γ_2}{2k}, \\
        z^3 &= \frac{ỹ^+z^-}{2b} + k, \qquad z̃^3 = \frac{z̃^+y^-}{2b} + k.

    Returns two arrays of shape ``(..., 3)``.
    """
    cm = _vec3(chi_minus, "chi_minus")
    cp = _vec3(chi_plus_new, "chi_plus_new")
    b = nonzero_field(b)
    out = _psi_core(cm[..., 0], cm[..., 1], cm[..., 2], cp[..., 0], cp[..., 1], cp[..., 2], complex(eta), b,
                    np.asarray(gamma1, dtype=complex), np.asarray(gamma2, dtype=complex), np.asarray(k, dtype=complex))
    out = np.broadcast_arrays(*out)
    return np.stack(out[:3], axis=-1), np.stack(out[3:], axis=-1)


def casimir_elimination(psi: ArrayLike, chi: ArrayLike, gamma1: ArrayLike, gamma2: ArrayLike) -> np.ndarray:
    r"""``(y⁺, x⁺, z⁺)`` from ``Ψ`` and ``χ⁻`` on the leaf (proof of the Proposition, **corrected**); the
    same function gives ``(ỹ⁻, x̃⁻, z̃⁻)`` from ``Ψ̃`` and ``χ̃⁺``.

    .. math::
        z^+ = \frac{1 − (z^3)^2}{z^-}, \quad x^+ = \frac{2γ_2 − 2x^3z^3 − x^-z^+}{z^-}, \quad
        y^+ = \frac{2γ_1 − 2y^3z^3 − (x^3)^2 − x^+x^- − y^-z^+}{z^-}

    (printed: ``2γ1 − 1`` in place of ``2γ1 − (x³)² − x⁺x⁻``).  Returns shape ``(..., 3)``.
    """
    ps = _vec3(psi, "psi")
    ch = _vec3(chi, "chi")
    out = _elim_core(ps[..., 0], ps[..., 1], ps[..., 2], ch[..., 0], ch[..., 1], ch[..., 2],
                     np.asarray(gamma1, dtype=complex), np.asarray(gamma2, dtype=complex))
    return np.stack(np.broadcast_arrays(*out), axis=-1)
