r"""The dressing of any family, written once (``docs/families.md`` §maps, issue 23).

A family's dressing is ``D(λ) = Σ_p c_p B_p(λ)`` (:meth:`jetgaudin.families.Family.dressing_basis`); the map's
new principal parts at a site ``λ_i`` need the Taylor coefficients there of ``D``, of ``adj D`` (linear in ``D``
for 2×2 matrices: ``adj [[a, b], [c, d]] = [[d, −b], [−c, a]]``) and of ``1/det D`` (the Cauchy square of the
entries, inverted as a series, :mod:`jetgaudin.families._series`; ``det D ≠ 0`` at the sites because its zeros
are ``ξ, ξ̄`` modulo the period, off the real axis).  With them :func:`dress_sites` computes
``ℓ̃ = D ℓ adj(D)/det D`` site by site exactly as for the rational ``K = λ + M_0`` (:func:`dress_parts`,
:func:`monic_series`; re-exported by :mod:`jetgaudin.gaudin.maps`, their home before).
"""

from __future__ import annotations

import numpy as np

from ..backlund._dressing import adj, eigenvector, mm
from ..families import _series
from ._compensated import split_constant, times_split

__all__ = ["real_coefficients", "site_series", "dressing_at", "dress_parts", "dress_sites", "monic_series"]

_ID = np.eye(2, dtype=complex)


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
    """Per site ``(Ka, Aa, g)`` for :func:`dress_sites`: Taylor coefficients of ``D``,
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


def _inv_series(d, order):
    """Taylor coefficients of ``1/(d + z)``: ``(−1)^p d^{−(p+1)}``, ``p < order``."""
    return [(-1) ** p * d ** (-(p + 1)) for p in range(order)]


def dress_parts(model, parts, K0, E, A0, Ea, zeros):
    r"""Principal parts of ``K ℓ adj(K)/Π_r(λ − ζ_r)`` at every site (module docstring), ``(B, M, 2, 2)``.

    ``K = λE + K0``, ``adj K = λE_a + A0`` (``K0``, ``A0``: ``(B, 2, 2)``), ``zeros``: the scalars ``ζ_r``."""
    series = []
    for lam_i, N in model.sites:
        g = np.zeros(N, dtype=complex)
        g[0] = 1.0
        for z in zeros:
            g = np.convolve(g, _inv_series(lam_i - z, N))[:N]
        series.append(((K0 + lam_i * E, np.broadcast_to(E, K0.shape)),
                       (A0 + lam_i * Ea, np.broadcast_to(Ea, A0.shape)), g))
    return dress_sites(model, parts, series)


def dress_sites(model, parts, series):
    r"""Principal parts of ``D ℓ adj(D) / det D`` at every site, ``(B, M, 2, 2)``, from ``series[i] = (Ka, Aa, g)``:
    the Taylor coefficients at ``λ_i`` of ``D`` and ``adj D`` (sequences of ``(B, 2, 2)``) and of ``1/det D``
    (``(N_i,)`` or ``(N_i, B)``): ``ℓ̆_k = Σ_{j ≥ k} Σ_{a+c+e = j−k} D_a ℓ_j A_c g_e`` (module docstring)."""
    out = np.empty_like(parts)
    for i, (_, N) in enumerate(model.sites):
        o = model.offsets[i]
        Ka, Aa, g = series[i]
        g = np.asarray(g)[..., None, None] if np.ndim(g) > 1 else g  # (N, B): one series per batch member
        for k in range(N):
            acc = np.zeros(parts.shape[:-3] + (2, 2), dtype=complex)
            for j in range(k, N):
                Pj = parts[..., o + j, :, :]
                for a in range(min(len(Ka), j - k + 1)):
                    KP = mm(Ka[a], Pj)
                    for c in range(min(len(Aa), j - k - a + 1)):
                        e = j - k - a - c
                        acc = acc + g[e] * mm(KP, Aa[c])
            out[..., o + k, :, :] = acc
    return out


def monic_series(model, M0, A0, scale=None, *, scaled=False):
    r"""The Taylor series at every site of ``K = s(λ + M0)``, ``adj K = s(λ + A0)`` and ``1/det K`` for
    :func:`dress_sites` (the dressing ``K ℓ adj K / det K`` does not depend on the factor ``s``, ``scale`` ``(B,)``,
    default 1), with ``1/det K`` from the computed ``K`` itself: ``det K(λ_i + z) = d_0 + d_1 z + s² z²``,
    ``d_0 = det K(λ_i)``, ``d_1 = s tr K(λ_i)``, inverted as a series: ``g_0 = 1/d_0``, ``g_1 = −d_1 (g_0 g_0)``,
    ``g_m = −(d_1 (g_{m−1} g_0) + s² (g_{m−2} g_0))``.

    Why (issue 33; ``docs/reliability.md``, "Drift like round-off"): a quantity whose exact value is the same at every
    step rounds (nearly) alike at every step, and a relative error repeated at every step is a linear drift.
    ``det(λ + M0) = (λ − η)(λ − η̄)`` is such a constant (and the rounded ``1/((λ_i − η)(λ_i − η̄))`` used before
    multiplied each site's Casimir by the same ``1 + δ`` at every step), and so are ``d_1 g_0`` and ``s² g_0``.  With
    ``s`` varying along the orbit (the two-point map passes ``|k|²`` of its eigenvector) and the products grouped as
    above, every rounded quantity varies from step to step: the rounding errors add up as a random walk.

    ``scaled=True``: ``M0``, ``A0`` are already ``s M0``, ``s A0`` (``K(λ_i) = M0 + (s λ_i)``, the compiled kernel's
    form, :func:`jetgaudin.gaudin._compensated.scaled_two_point_K0`: no normalised ``M0`` is ever rounded; ``s λ_i``
    rounded once after a split of ``λ_i``, :func:`jetgaudin.gaudin._compensated.times_split`, as the compiled
    kernel: a decimal site's plain product is biased)."""
    s = np.ones(M0.shape[:-2]) if scale is None else np.asarray(scale, dtype=float)
    sI = s[..., None, None] * _ID
    series = []
    for lam_i, N in model.sites:
        if scaled:  # s λ_i as the compiled kernel's _tw(s, *_split(λ_i)): a decimal site (0.4) would round it with a
            # bias of its own (gaudin._compensated.times_split; issue 33)
            sl = times_split(s, *split_constant(lam_i))[..., None, None] * _ID
            K = M0 + sl
            A = A0 + sl
        else:
            K = s[..., None, None] * (M0 + lam_i * _ID)
            A = s[..., None, None] * (A0 + lam_i * _ID)
        g0 = 1.0 / (K[..., 0, 0] * K[..., 1, 1] - K[..., 0, 1] * K[..., 1, 0])
        d1 = s * (K[..., 0, 0] + K[..., 1, 1])
        g = [g0]
        if N > 1:
            g.append(-d1 * (g0 * g0))
        for _ in range(2, N):
            g.append(-(d1 * (g[-1] * g0) + s * s * (g[-2] * g0)))
        series.append(((K, sI), (A, sI), np.array(g)))
    return series
