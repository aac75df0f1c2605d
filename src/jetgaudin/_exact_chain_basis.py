r"""The basis ``ψ_m`` of ``ν²`` at a point for the compiled parameter solve of :class:`jetgaudin.ChainExactFlow`
(private; split from :mod:`jetgaudin._exact_chain_kernels`, which uses it): ``ν²(λ) = c + Σ_{i,m} h_{i,m} ψ_m(λ − λ_i)``
with ``ψ_m`` per family — rational ``z^{−m}``; trigonometric ``(−1)^{m−1} [x^{m−1}] w_3(z + x)``, ``w_3 = γ cot(γ ·)``;
elliptic :func:`jetgaudin._exact_elliptic.psi_elliptic_cached` (family ids: ``exact_chain.COMPILED_FAMILIES``).

Numba's cache keys each module by its own source: after an edit here or in :mod:`jetgaudin._exact_elliptic`, clear
``jetgaudin/__pycache__/_exact_chain_kernels.*`` (its compiled callers inline the old basis otherwise).
"""

from __future__ import annotations

import cmath

import numpy as np
from numba import njit

from ._exact_elliptic import psi_elliptic_cached

__all__ = ["psi_values"]


@njit(cache=True, error_model="numpy", inline="always")
def _psi_site(fid, fp, z, order, out, o, s, c, r):
    """``out[o + m − 1] = ψ_m(z)``, ``m = 1..order``, of the rational (``fid`` 0) and trigonometric (1) families
    (``s, c, r`` complex scratch of length ``order``; ``fp`` the family's constants: trigonometric ``(γ,)``; the
    elliptic family's basis is :func:`jetgaudin._exact_elliptic.psi_elliptic_cached`)."""
    if fid == 0:
        inv = 1.0 / z
        p = inv
        for m in range(order):
            out[o + m] = p
            p = p * inv
        return
    gamma = fp[0]
    t = gamma * z
    s0 = cmath.sin(t)
    c0 = cmath.cos(t)
    f = 1.0
    for n in range(order):
        q = n % 4
        if q == 0:
            s[n] = f * s0
            c[n] = f * c0
        elif q == 1:
            s[n] = f * c0
            c[n] = -f * s0
        elif q == 2:
            s[n] = -f * s0
            c[n] = -f * c0
        else:
            s[n] = -f * c0
            c[n] = f * s0
        f = f * gamma / (n + 1)
    r0 = 1.0 / s[0]
    r[0] = r0
    for m in range(1, order):
        acc = 0j
        for k in range(1, m + 1):
            acc += s[k] * r[m - k]
        r[m] = -acc * r0
    for m in range(order):
        r[m] = gamma * r[m]
    for n in range(order):
        acc = 0j
        for p in range(n + 1):
            acc += c[p] * r[n - p]
        out[o + n] = acc if n % 2 == 0 else -acc


@njit(cache=True, error_model="numpy", inline="always")
def _psi_point_inline(fid, fp, lam, site_pos, site_n, psi, s, c, r, d, xcache, slot):
    """``psi[o_i + m − 1] = ψ_m(λ − λ_i)`` for every site ``i`` and ``m = 1..2N_i`` (``o_i = 2 Σ_{i' < i} N_i'``);
    the elliptic functions of ``Re(λ − λ_i)`` kept in the row ``slot · (number of sites) + i`` of ``xcache`` (one slot
    per vertical segment: Newton's passes over the ``k`` segments then evaluate them once per segment and solve,
    not once per pass).  Inlined into the two loops over nodes (:func:`_segment`, :func:`nu_numerical`): a call
    passes its eight arrays with their reference counts, ~75 ns a Clebsch node (150 → 75 ns); the other callers
    take :func:`_psi_point` (one compiled copy of the basis: the compile time)."""
    o = 0
    if fid == 2:
        for i in range(site_pos.shape[0]):
            order = 2 * site_n[i]
            psi_elliptic_cached(lam - site_pos[i], fp, order, psi, o, s, c, r, d, xcache,
                                slot * site_pos.shape[0] + i)
            o += order
        return
    for i in range(site_pos.shape[0]):
        order = 2 * site_n[i]
        _psi_site(fid, fp, lam - site_pos[i], order, psi, o, s, c, r)
        o += order


@njit(cache=True, error_model="numpy")
def _psi_point(fid, fp, lam, site_pos, site_n, psi, s, c, r, d, xcache, slot):
    """:func:`_psi_point_inline` as a call (the callers off the loops over nodes)."""
    _psi_point_inline(fid, fp, lam, site_pos, site_n, psi, s, c, r, d, xcache, slot)


def psi_values(fid: int, fp: np.ndarray, lam: np.ndarray, site_pos: np.ndarray, site_n: np.ndarray) -> np.ndarray:
    """``ψ_m(λ − λ_i)`` for each point of ``lam`` (1-D complex), shape ``(len(lam), 2M)`` (the tests compare it with
    :meth:`jetgaudin.families.Family.nu2_basis`)."""
    return _psi_many(fid, np.asarray(fp, dtype=float), np.ascontiguousarray(lam, dtype=complex), site_pos, site_n)


@njit(cache=True, error_model="numpy")
def _psi_scratch(site_pos, site_n, slots):
    """The scratch of :func:`_psi_point`: the series buffers ``s, c, r, d`` (the largest ``2 N_j``) and the cache
    ``xcache`` (``slots`` segments × the sites)."""
    nmax = 1
    for i in range(site_n.shape[0]):
        nmax = max(nmax, 2 * site_n[i])
    return (np.empty(nmax, dtype=np.complex128), np.empty(nmax, dtype=np.complex128),
            np.empty(nmax, dtype=np.complex128), np.empty(nmax, dtype=np.complex128),
            np.zeros((slots * site_pos.shape[0], 9)))


@njit(cache=True, error_model="numpy")
def _psi_many(fid, fp, lam, site_pos, site_n):
    n2 = 0
    for i in range(site_n.shape[0]):
        n2 += 2 * site_n[i]
    out = np.empty((lam.shape[0], n2), dtype=np.complex128)
    s, c, r, d, xcache = _psi_scratch(site_pos, site_n, 1)
    psi = np.empty(n2, dtype=np.complex128)
    for q in range(lam.shape[0]):
        _psi_point(fid, fp, lam[q], site_pos, site_n, psi, s, c, r, d, xcache, 0)
        for m in range(n2):
            out[q, m] = psi[m]
    return out
