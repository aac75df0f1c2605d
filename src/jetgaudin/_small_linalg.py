"""Small dense linear algebra for the compiled Newton solves of :mod:`jetgaudin._exact_chain_kernels` (private): the
2-norm condition test by one-sided Jacobi (:func:`_cond_at_most`) and the solve by elimination with partial pivoting
(:func:`_lu_solve`), in place of LAPACK through Numba (~2 µs an iteration for a 3 × 3 system).  Split from
:mod:`jetgaudin._exact_chain_kernels` (its size)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__: list[str] = []


@njit(cache=True, error_model="numpy")
def _cond_at_most(J, limit, U):
    """Whether the 2-norm condition number ``σ_max/σ_min`` of the square ``J`` is at most ``limit`` (``np.linalg.cond
    (J) <= limit``): the singular values by one-sided Jacobi rotations (Hestenes) on the columns of ``U`` (scratch of
    ``J``'s shape), to high relative accuracy — ~0.2 µs for the 3 × 3 Jacobian of the Clebsch top against ~1.5 µs of
    LAPACK's SVD through Numba.  (The decision differs from LAPACK's only where the condition number is within the
    SVDs' round-off, ~1e-4 relative at 1e12, of ``limit``.)"""
    n = J.shape[0]
    for i in range(n):
        for j in range(n):
            U[i, j] = J[i, j]
    for _ in range(60):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                al = 0.0
                be = 0.0
                ga = 0.0
                for i in range(n):
                    al += U[i, p] * U[i, p]
                    be += U[i, q] * U[i, q]
                    ga += U[i, p] * U[i, q]
                if abs(ga) > n * 2.3e-16 * math.sqrt(al * be):  # not orthogonal to round-off yet
                    rotated = True
                    ze = (be - al) / (2.0 * ga)
                    t = (1.0 if ze >= 0 else -1.0) / (abs(ze) + math.sqrt(1.0 + ze * ze))
                    cs = 1.0 / math.sqrt(1.0 + t * t)
                    sn = cs * t
                    for i in range(n):
                        up = U[i, p]
                        uq = U[i, q]
                        U[i, p] = cs * up - sn * uq
                        U[i, q] = sn * up + cs * uq
        if not rotated:
            break
    smax = 0.0
    smin = np.inf
    for j in range(n):
        acc = 0.0
        for i in range(n):
            acc += U[i, j] * U[i, j]
        sj = math.sqrt(acc)
        smax = max(smax, sj)
        smin = min(smin, sj)
    return smin > 0.0 and smax <= limit * smin


@njit(cache=True, error_model="numpy")
def _lu_solve(J, b, A, x):
    """``x = J⁻¹ b`` by Gaussian elimination with partial pivoting (LAPACK ``getrf``/``getrs``'s pivots; ``A``
    scratch of ``J``'s shape; ``J`` nonsingular: the callers have checked its condition number)."""
    n = J.shape[0]
    for i in range(n):
        x[i] = b[i]
        for j in range(n):
            A[i, j] = J[i, j]
    for c in range(n):
        piv = c
        big = abs(A[c, c])
        for i in range(c + 1, n):
            if abs(A[i, c]) > big:
                big = abs(A[i, c])
                piv = i
        if piv != c:
            for j in range(n):
                tmp = A[c, j]
                A[c, j] = A[piv, j]
                A[piv, j] = tmp
            tmp = x[c]
            x[c] = x[piv]
            x[piv] = tmp
        inv = 1.0 / A[c, c]
        for i in range(c + 1, n):
            l = A[i, c] * inv
            for j in range(c + 1, n):
                A[i, j] -= l * A[c, j]
            x[i] -= l * x[c]
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for j in range(i + 1, n):
            acc -= A[i, j] * x[j]
        x[i] = acc / A[i, i]
