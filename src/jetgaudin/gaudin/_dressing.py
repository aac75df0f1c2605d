r"""The dressing of any family, written once (``docs/families.md`` §maps, issue 23).

A family's dressing is ``D(λ) = Σ_p c_p B_p(λ)`` (:meth:`jetgaudin.families.Family.dressing_basis`); the map's
new principal parts at a site ``λ_i`` need the Taylor coefficients there of ``D``, of ``adj D`` (linear in ``D``
for 2×2 matrices: ``adj [[a, b], [c, d]] = [[d, −b], [−c, a]]``) and of ``1/det D`` (the Cauchy square of the
entries, inverted as a series, :mod:`jetgaudin.families._series`; ``det D ≠ 0`` at the sites because its zeros
are ``ξ, ξ̄`` modulo the period, off the real axis).  With them :func:`jetgaudin.gaudin.maps.dress_sites` computes
``ℓ̃ = D ℓ adj(D)/det D`` site by site exactly as for the rational ``K = λ + M_0``.
"""

from __future__ import annotations

import numpy as np

from ..backlund._dressing import adj, eigenvector
from ..families import _series

__all__ = ["real_coefficients", "site_series", "dressing_at"]


def real_coefficients(model, xi: complex, L: np.ndarray, nu1: np.ndarray) -> np.ndarray:
    """``c`` ``(B, P)`` of the real two-point map from ``ℓ(ξ)`` ``(B, 2, 2)`` and ``ν1``: the eigenvector ``k1`` of
    ``ℓ(ξ)`` for ``ν1``, ``k2 = (−conj k1_2, conj k1_1)`` (orthogonal to ``k1``: the eigenvector of
    ``ℓ(ξ̄) = ℓ(ξ)^†`` of a real state for ``−conj ν1``; the reality of eq. (X), ``κ = 1/s̄`` with ``k1 ∝ (1, −s)``),
    then the family's gauge rule."""
    u, v, w = L[..., 0, 0], L[..., 0, 1], L[..., 1, 0]
    k1 = np.stack(eigenvector(u, v, w, nu1), axis=-1)
    k2 = np.stack([-np.conj(k1[..., 1]), np.conj(k1[..., 0])], axis=-1)
    return model.family.real_dressing(xi, k1, k2)


def dressing_at(model, c: np.ndarray, lam, xi=None) -> np.ndarray:
    """``D(λ) = Σ_p c_p B_p(λ)``, shape ``(B, 2, 2)`` for a scalar ``λ`` (``xi``: the map's, for a family whose basis
    depends on it, :attr:`jetgaudin.families.Family.dressing_needs_xi`)."""
    fam = model.family
    B = fam.dressing_basis(lam, xi) if fam.dressing_needs_xi else fam.dressing_basis(lam)
    return np.einsum("bp,pij->bij", c, B)


def site_series(model, c: np.ndarray, xi=None) -> list:
    """Per site ``(Ka, Aa, g)`` for :func:`jetgaudin.gaudin.maps.dress_sites`: Taylor coefficients of ``D``,
    ``adj D`` (lists of ``(B, 2, 2)``) and ``1/det D`` (``(N_i, B)``) at ``λ_i``."""
    out = []
    fam = model.family
    for lam_i, N in model.sites:
        T = fam.dressing_taylor(lam_i, N, xi) if fam.dressing_needs_xi else fam.dressing_taylor(lam_i, N)
        Dt = np.einsum("bp,npij->nbij", c, T)
        At = adj(Dt)
        det = _series.mul(Dt[..., 0, 0], Dt[..., 1, 1], N) - _series.mul(Dt[..., 0, 1], Dt[..., 1, 0], N)
        out.append((list(Dt), list(At), _series.inv(det, N)))
    return out
