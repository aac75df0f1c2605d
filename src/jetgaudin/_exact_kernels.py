r"""Compiled parameter solve of :mod:`jetgaudin.exact` (private): the weights ``ω_m(ρ + i h)`` by Gauss–Legendre
and Newton's method for ``h``, one orbit per call of :func:`_solve_one` (a ``prange`` loop over a batch: every orbit
gets the bits of its single solve).

``ν`` along the vertical segment ``λ = ρ + i s``, ``s ∈ [0, h]``: the root of ``ν² = Σ_m κ_m λ^{-m}`` positive at
``s = 0`` (``ν(ρ)² = |ξ(ρ)|² > 0`` for a real state), continued node by node (the root closer to the previous
node's value; the nodes are sorted along the segment).  This is the default branch of :func:`jetgaudin.nu` as long
as no branch point lies near the segment; :mod:`jetgaudin.exact` checks the end value against the branch rule.
The NumPy twin is :func:`jetgaudin.exact._weights` (the tests compare the two).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy")
def _weights_one(kappa, a, h, x, w, om, dom, nu_end):
    """``om[m] = ω_{m+1}(a + i h)`` (``m = 0..2N−1``) by the rule ``(x, w)`` on ``[0, 1]``; ``dom[m] = ∂ω/∂h``;
    returns ``ν`` at the end point (continued from ``+√ν²(a)``)."""
    M = kappa.shape[0] - 1
    for m in range(M):
        om[m] = 0.0
    prev = complex(np.sqrt(max(_nu2(kappa, complex(a, 0.0)).real, 0.0)), 0.0)
    n = x.shape[0]
    for q in range(n + 1):
        s = h * x[q] if q < n else h
        lam = complex(a, s)
        r = np.sqrt(_nu2(kappa, lam))
        if (r.real * prev.real + r.imag * prev.imag) < 0.0:
            r = -r
        prev = r
        z = 1.0 / lam
        zm = z
        inv = 1.0 / r
        for m in range(M):
            f = (zm * inv).real
            if q < n:
                om[m] -= h * w[q] * f
            else:
                dom[m] = -f
            zm = zm * z
    nu_end[0] = prev


@njit(cache=True, error_model="numpy")
def _nu2(kappa, lam):
    z = 1.0 / lam
    acc = complex(kappa[kappa.shape[0] - 1], 0.0)
    for m in range(kappa.shape[0] - 2, -1, -1):
        acc = acc * z + kappa[m]
    return acc


@njit(cache=True, error_model="numpy")
def _gauss_solve(A, b):
    """``A y = b`` (small, partial pivoting) in place; returns ``False`` when singular."""
    k = b.shape[0]
    for c in range(k):
        p = c
        for r in range(c + 1, k):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if A[p, c] == 0.0 or not np.isfinite(A[p, c]):
            return False
        for j in range(k):
            A[c, j], A[p, j] = A[p, j], A[c, j]
        b[c], b[p] = b[p], b[c]
        for r in range(c + 1, k):
            f = A[r, c] / A[c, c]
            for j in range(c, k):
                A[r, j] -= f * A[c, j]
            b[r] -= f * b[c]
    for c in range(k - 1, -1, -1):
        acc = b[c]
        for j in range(c + 1, k):
            acc -= A[c, j] * b[j]
        b[c] = acc / A[c, c]
    return True


@njit(cache=True, error_model="numpy")
def _eval(kappa, rho, h, x, w, OM, DOM, NU):
    for j in range(rho.shape[0]):
        _weights_one(kappa, rho[j], h[j], x, w, OM[j], DOM[j], NU[j:j + 1])


@njit(cache=True, error_model="numpy")
def _newton(kappa, rho, target, h, x, w, OM, DOM, NU, step_tol, fold, iterations):
    k = rho.shape[0]
    A = np.empty((k, k))
    F = np.empty(k)
    for _ in range(iterations):
        _eval(kappa, rho, h, x, w, OM, DOM, NU)
        for mi in range(k):
            acc = -target[mi]
            for j in range(k):
                acc += OM[j, mi + 1]
                A[mi, j] = DOM[j, mi + 1]
            F[mi] = acc
        if not _gauss_solve(A, F):
            return False
        done = True
        for j in range(k):
            hn = h[j] - F[j]
            if not np.isfinite(hn) or abs(hn) > fold * abs(rho[j]):
                return False
            if abs(F[j]) > step_tol * abs(hn):
                done = False
            h[j] = hn
        if done:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _solve_one(kappa, rho, target, x, w, x2, w2, stages, step_tol, fold, iterations, h, nu_end, info):
    """Solve ``Σ_j ω_m(ρ_j + i h_j) = target_{m−2}`` (``m = 2..k+1``) into ``h``; ``info = (ok, residual,
    quadrature estimate, Σ_j ω_1)``, ``nu_end`` the end-point ``ν`` of each segment."""
    k = rho.shape[0]
    M = kappa.shape[0] - 1
    OM = np.zeros((k, M))
    DOM = np.zeros((k, M))
    OM2 = np.zeros((k, M))
    V = np.empty((k, k))
    ok = False
    for S in stages:
        for s in range(1, S + 1):
            tg = target * (s / S)
            if s == 1:
                for mi in range(k):
                    h[mi] = tg[mi]
                    for j in range(k):
                        nr = np.sqrt(max(_nu2(kappa, complex(rho[j], 0.0)).real, 1e-300))
                        V[mi, j] = -(rho[j] ** -(mi + 2)) / nr
                if not _gauss_solve(V, h):
                    break
            ok = _newton(kappa, rho, tg, h, x, w, OM, DOM, nu_end, step_tol, fold, iterations)
            if not ok:
                break
        if ok:
            break
    _eval(kappa, rho, h, x, w, OM, DOM, nu_end)
    _eval(kappa, rho, h, x2, w2, OM2, DOM, nu_end[k:])
    res = 0.0
    quad = 0.0
    for mi in range(k):
        tot = -target[mi]
        scale = abs(target[mi]) + 1e-300
        for j in range(k):
            tot += OM[j, mi + 1]
            scale += abs(OM[j, mi + 1])
        res = max(res, abs(tot) / scale)
    om1 = 0.0
    for j in range(k):
        om1 += OM[j, 0]
        for m in range(min(M, k + 1)):
            quad = max(quad, abs(OM[j, m] - OM2[j, m]) / (abs(OM[j, m]) + abs(OM[j, 0]) + 1e-300))
    info[0] = 1.0 if ok else 0.0
    info[1] = res
    info[2] = quad
    info[3] = om1


@njit(cache=True, error_model="numpy", parallel=True)
def solve_batch(kappa, rho, target, x, w, x2, w2, stages, step_tol, fold, iterations, h, nu_end, info):
    """:func:`_solve_one` for every orbit of a batch (``kappa`` (B, 2N+1), ``rho`` (B, k), ``target`` (B, k))."""
    for i in prange(kappa.shape[0]):
        _solve_one(kappa[i], rho[i], target[i], x, w, x2, w2, stages, step_tol, fold, iterations, h[i], nu_end[i],
                   info[i])


@njit(cache=True, error_model="numpy")
def solve_serial(kappa, rho, target, x, w, x2, w2, stages, step_tol, fold, iterations, h, nu_end, info):
    """:func:`solve_batch` on the calling thread (small batches: no thread start-up; the same bits per orbit)."""
    for i in range(kappa.shape[0]):
        _solve_one(kappa[i], rho[i], target[i], x, w, x2, w2, stages, step_tol, fold, iterations, h[i], nu_end[i],
                   info[i])
