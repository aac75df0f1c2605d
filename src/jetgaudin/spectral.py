r"""Spectral curve, integrals and the eigenvalue branch ν(λ) (Lemma 1, Props. 2--3).

With ``L = (i/2) ℓ``, ``ℓ = [[u, v], [w, -u]]`` (eq. (yy)),

.. math::  \det(L(\lambda) - \mu) = \mu^2 + \tfrac14 \nu(\lambda)^2, \qquad
           \nu(\lambda)^2 = u^2 + v w = \langle \xi(\lambda), \xi(\lambda) \rangle
           = \sum_{m=0}^{2N} \kappa_m \lambda^{-m},

so the paper's curve (curve) ``4μ² + |b|² + H(λ) + C(λ) = 0`` has ``μ = ± i ν / 2``:
**μ of (curve) is an eigenvalue of L, while ν is an eigenvalue of ℓ = -2 i L**.
The spectrality formulas of Section 6, (hhh), (x), (X), hold with their ``μ``
replaced by ``ν`` (see ``docs/backlund.md``, section 1, and ``docs/errata.md``).

``κ_0 = |b|²``, ``κ_k = H_k`` and ``κ_{N+k} = C_k`` (``k = 1..N``), with
``κ_m = Σ_{i+j=m} ⟨ξ_i, ξ_j⟩`` (Prop. 2; for general ``c_k`` in terms of ``Y_n``,
which gives Prop. 3 for ``N = 3``).

**Branch rule.**  :func:`nu` returns the *default* root: positive at the real
point ``a = Re λ`` (where ``ν² = |ξ(a)|² ≥ 0`` for a real state) and continued
along the vertical segment ``[a, λ]``.  With ``P(λ) = λ^{2N} ν² = |b|² Π_k (λ - r_k)``
the continuation is exact:

.. math:: \nu(\lambda) = \nu(a) \Big(\frac{a}{\lambda}\Big)^N \prod_k
          \sqrt{\frac{\lambda - r_k}{a - r_k}}    \quad(\text{principal roots}),

because a straight segment not through ``r_k`` subtends an angle in ``(-π, π)`` at
``r_k``.  The roots only select the sign: the value returned is ``±√ν²(λ)``
evaluated directly.  ``sheet=-1`` gives the other root.  The rule needs ``Re λ ≠ 0``
and no branch point on the segment; otherwise :class:`BranchPointError`.
"""

from __future__ import annotations

import numpy as np

from ._errors import BranchPointError, InvalidParameterError
from ._validate import as_state, complex_points, finite_result, spectral_points
from .lax import jet_coefficients, lax_coefficients

__all__ = [
    "curve_coefficients",
    "integrals",
    "integral_gradients",
    "nu_squared",
    "nu",
    "branch_points",
    "spectral_determinant",
]


def curve_coefficients(X, b, c=None) -> np.ndarray:
    r"""Coefficients ``κ_0..κ_{2N}`` of ``ν²(λ) = Σ κ_m λ^{-m}``, shape ``(..., 2N+1)``."""
    xi = lax_coefficients(X, b, c)
    N = xi.shape[-2] - 1
    out = np.zeros(xi.shape[:-2] + (2 * N + 1,), dtype=xi.dtype)
    comp = [np.ascontiguousarray(xi[..., :, a]) for a in range(3)]  # (..., N+1) per component
    for i in range(N + 1):
        for j in range(N + 1):
            # ⟨ξ_i, ξ_j⟩ summed over the 3 components in order (as np.sum over a length-3 axis, ~5x faster on
            # large batches, where a reduction over a short last axis is slow)
            out[..., i + j] += (comp[0][..., i] * comp[0][..., j] + comp[1][..., i] * comp[1][..., j]) + \
                comp[2][..., i] * comp[2][..., j]
    return finite_result(out, "the spectral invariants (integrals)")


def integrals(X, b, c=None) -> np.ndarray:
    r"""The 2N integrals ``(H_1, …, H_N, C_1, …, C_N)`` of Prop. 2, shape ``(..., 2N)``.

    .. math:: H_k = 2⟨b, y_{k-1}⟩ + \sum_{i=0}^{k-2} ⟨y_i, y_{k-i-2}⟩, \qquad
              C_k = \sum_{i=k-1}^{N-1} ⟨y_i, y_{N+k-i-2}⟩

    for the reduction (lax2) (``c = None``); ``b`` is a float (field ``(0, 0, b)``) or a
    3-vector.  With constants ``c = (c_1, …)`` the same formulas hold in terms of
    ``Y_n = Σ_i T[i, n] y_i`` (see :func:`jetgaudin.lax.jet_coefficients`).

    >>> import jetgaudin as jg
    >>> X = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]   # Appendix 2
    >>> H1, H2, H3, C1, C2, C3 = jg.integrals(X, 1.0)
    >>> float(H1), float(C3)                                   # 2 b y^3, |z|^2
    (-2.4, 1.0)
    """
    return curve_coefficients(X, b, c)[..., 1:]


def integral_gradients(X, b, c=None) -> np.ndarray:
    r"""Gradients of ``(H_1..H_N, C_1..C_N)`` with respect to ``X``, shape ``(..., 2N, 3N)``.

    ``∂κ_m/∂y_i = Σ_n T[i, n] 2 ξ_{m-n-1}``.
    """
    X, N = as_state(X, allow_complex=True)
    xi = lax_coefficients(X, b, c)
    T = jet_coefficients(N, c)
    g = np.zeros(X.shape[:-1] + (2 * N, N, 3), dtype=np.result_type(xi, T))
    for m in range(1, 2 * N + 1):
        for n in range(N):
            j = m - n - 1
            if 0 <= j <= N:
                # dκ_m/dY_n = 2 ξ_j ; chain rule through Y_n = Σ_i T[i,n] y_i
                g[..., m - 1, :, :] += 2 * T[:, n][:, None] * xi[..., j, None, :]
    return g.reshape(X.shape[:-1] + (2 * N, 3 * N))


def _poly_eval(kappa, lam):
    m = np.arange(kappa.shape[-1])
    lam = np.asarray(lam, dtype=complex)
    return np.sum(kappa * lam[..., None] ** (-m), axis=-1)


def nu_squared(lam, X, b, c=None):
    r"""``ν(λ)² = u(λ)² + v(λ) w(λ)`` (so ``det(L − μ) = μ² + ν²/4``)."""
    return _poly_eval(curve_coefficients(X, b, c), spectral_points(lam))


def spectral_determinant(lam, mu, X, b, c=None):
    r"""``det(L(λ) − μ·1)`` computed from the 2x2 matrix itself (for checks of Lemma 1)."""
    from .lax import lax_matrix

    L = lax_matrix(lam, X, b, c)
    mu = np.asarray(mu, dtype=complex)
    if not np.all(np.isfinite(mu)):
        raise InvalidParameterError("mu must be finite")
    return (L[..., 0, 0] - mu) * (L[..., 1, 1] - mu) - L[..., 0, 1] * L[..., 1, 0]


def _roots(kappa):
    """Roots of P(λ) = Σ_m κ_m λ^{2N-m}, shape (..., 2N), via batched companion matrices."""
    kappa = np.asarray(kappa, dtype=complex)
    deg = kappa.shape[-1] - 1
    lead = kappa[..., 0]
    if np.any(lead == 0):
        raise InvalidParameterError(
            "the field b must be nonzero for the branch rule of nu (|b|^2 = 0, or underflows); give b != 0"
        )
    comp = np.zeros(kappa.shape[:-1] + (deg, deg), dtype=complex)
    comp[..., 0, :] = -kappa[..., 1:] / lead[..., None]
    idx = np.arange(deg - 1)
    comp[..., idx + 1, idx] = 1.0
    return np.linalg.eigvals(comp)


def branch_points(X, b, c=None) -> np.ndarray:
    r"""The 2N branch points of ν: the roots of ``λ^{2N} ν(λ)²``, shape ``(..., 2N)``."""
    return _roots(curve_coefficients(X, b, c))


def _continued_sign_reference(kappa, a, lam, roots):
    """``λ^N`` times the continuation of the positive root at ``a`` to ``λ`` (vertical segment).

    Computed from ``P(a) = a^{2N} ν²(a)`` (no overflow for tiny ``|a|``): ``ν(a) = √P(a)/|a|^N``, so
    ``λ^N ν(λ) = √P(a) sign(a)^N Π_k √((λ − r_k)/(a − r_k))``.
    """
    N = (kappa.shape[-1] - 1) // 2
    m = np.arange(kappa.shape[-1])
    P_a = np.sum(kappa * a[..., None].astype(complex) ** (2 * N - m), axis=-1)
    sqrt_Pa = np.sqrt(P_a)
    return sqrt_Pa * np.sign(a) ** N * _segment_factor(lam, a, roots, sqrt_Pa)


def _segment_factor(lam, a, roots, root_at_a):
    """``Π_k √((λ − r_k)/(a − r_k))``: continues a square root of ``Π_k (λ − r_k)`` from the real point ``a`` to
    ``λ`` along the vertical segment; :class:`BranchPointError` when a root ``r_k`` lies on the segment or the
    square root at ``a``, ``root_at_a``, vanishes."""
    ratio = (lam[..., None] - roots) / (a[..., None] - roots)
    # a root on the segment [a, lam] makes the ratio real and <= 0
    on_seg = (np.abs(ratio.imag) <= 1e-13 * np.abs(ratio)) & (ratio.real <= 0)
    if np.any(on_seg) or np.any(root_at_a == 0):
        raise BranchPointError(
            "nu has a branch point on the vertical segment from Re(eta) to eta "
            "(nu(eta) = 0 or nu(Re eta) = 0); move eta or the state off the branch point"
        )
    return np.prod(np.sqrt(ratio), axis=-1)


def N_of(kappa) -> int:
    """N from the number 2N + 1 of curve coefficients."""
    return (kappa.shape[-1] - 1) // 2


def _nu_from_kappa(kappa, lam, sheet=1, roots=None):
    lam = complex_points(lam)
    kappa, lam = np.broadcast_arrays(kappa, lam[..., None])
    lam = lam[..., 0]
    a = lam.real
    if np.any(a == 0):
        raise BranchPointError(
            "the default branch of nu is defined by continuation from the real point Re(lambda); "
            "it needs Re(lambda) != 0 (lambda = 0 is the pole of the Lax matrix)"
        )
    if roots is None:
        roots = _roots(kappa)
    ref = _continued_sign_reference(kappa, a, lam, np.broadcast_to(roots, kappa.shape[:-1] + (roots.shape[-1],)))
    direct = np.sqrt(_poly_eval(kappa, lam))
    # compare phases only (unit-modulus factors: no overflow for tiny or huge lambda)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        phase_lam = (np.conj(lam) / np.abs(lam)) ** N_of(kappa)
        test = (np.conj(direct / np.abs(direct)) * (ref / np.abs(ref)) * phase_lam).real
    if not np.all(np.isfinite(test)) or not np.all(np.isfinite(direct)):
        raise BranchPointError(
            "nu(lambda) is zero or not representable at this lambda (a branch point, or |Re lambda| so small that "
            "nu overflows); move lambda away from the branch points and the pole lambda = 0"
        )
    sign = np.where(test >= 0, 1.0, -1.0)
    return sheet * sign * direct


def nu(lam, X, b, c=None, *, sheet: int = 1):
    r"""The eigenvalue ν(λ) of ``ℓ = [[u, v], [w, −u]]`` on the default branch (see module doc).

    ``ν² = u² + v w``; ``sheet=+1`` is the root positive at ``Re λ`` continued vertically,
    ``sheet=-1`` its negative.  For a real state ``ν(λ̄) = conj ν(λ)``.

    >>> import jetgaudin as jg
    >>> X = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> v = jg.nu(5 + 0.1j, X, 1.0)
    >>> bool(abs(v**2 - jg.nu_squared(5 + 0.1j, X, 1.0)) < 1e-14), bool(v.real > 0)
    (True, True)
    """
    if sheet not in (1, -1):
        raise InvalidParameterError(f"sheet must be +1 or -1, got {sheet!r}")
    return _nu_from_kappa(curve_coefficients(X, b, c), lam, sheet)
