"""Numba kernels of Kahan's map (:mod:`jetgaudin.kahan`): ``steps`` steps of ``X + (I − (h/2) f'(X))^{−1} h f(X)``
for every orbit of a batch ``(m, n)``, ``f(X) = Π(X)(A X + g0)``, ``Π(X)_{iJ} = Σ_k c[i, J, k] X_k``; the linear
solve is Gaussian elimination with partial pivoting (``n`` is small: 6 or 9)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy")
def _step(x, c, A, g0, h, g, P, f, M):
    """One step in place; False when the matrix is singular."""
    n = x.shape[0]
    for J in range(n):
        s = g0[J]
        for k in range(n):
            s += A[J, k] * x[k]
        g[J] = s
    for i in range(n):
        for J in range(n):
            s = 0.0
            for k in range(n):
                s += c[i, J, k] * x[k]
            P[i, J] = s
    for i in range(n):
        s = 0.0
        for J in range(n):
            s += P[i, J] * g[J]
        f[i] = h * s
    for i in range(n):
        for k in range(n):
            s = 0.0
            for J in range(n):
                s += c[i, J, k] * g[J] + P[i, J] * A[J, k]
            M[i, k] = -0.5 * h * s
        M[i, i] += 1.0
    for col in range(n):  # elimination with partial pivoting, M d = f (f overwritten by d)
        p = col
        for r in range(col + 1, n):
            if abs(M[r, col]) > abs(M[p, col]):
                p = r
        if M[p, col] == 0.0:
            return False
        if p != col:
            for k in range(n):
                M[col, k], M[p, k] = M[p, k], M[col, k]
            f[col], f[p] = f[p], f[col]
        for r in range(col + 1, n):
            q = M[r, col] / M[col, col]
            for k in range(col, n):
                M[r, k] -= q * M[col, k]
            f[r] -= q * f[col]
    for i in range(n - 1, -1, -1):
        s = f[i]
        for k in range(i + 1, n):
            s -= M[i, k] * f[k]
        f[i] = s / M[i, i]
    for i in range(n):
        x[i] += f[i]
    return True


@njit(cache=True, error_model="numpy")
def _orbit(x, c, A, g0, h, steps, save_every, rows, o):
    n = x.shape[0]
    g = np.empty(n)
    P = np.empty((n, n))
    f = np.empty(n)
    M = np.empty((n, n))
    for s in range(steps):
        if not _step(x, c, A, g0, h, g, P, f, M):
            return False
        if (s + 1) % save_every == 0:
            rows[(s + 1) // save_every - 1, o] = x
    for i in range(n):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(cache=True, error_model="numpy")
def kahan_serial(X, c, A, g0, h, steps, save_every):
    """``(rows (steps // save_every, m, n), X_last (m, n), ok)``, one orbit after the other."""
    m, n = X.shape
    rows = np.empty((steps // save_every, m, n))
    out = X.copy()
    ok = True
    for o in range(m):
        ok = _orbit(out[o], c, A, g0, h, steps, save_every, rows, o) and ok
    return rows, out, ok


@njit(cache=True, error_model="numpy", parallel=True)
def kahan_parallel(X, c, A, g0, h, steps, save_every):
    """:func:`kahan_serial` with the orbits spread over the cores (the same bits per orbit)."""
    m, n = X.shape
    rows = np.empty((steps // save_every, m, n))
    out = X.copy()
    good = np.ones(m, dtype=np.bool_)
    for o in prange(m):
        good[o] = _orbit(out[o], c, A, g0, h, steps, save_every, rows, o)
    return rows, out, good.all()
