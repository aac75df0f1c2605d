"""Numba kernel of Kahan's map (:mod:`jetgaudin.kahan`): ``steps`` steps of ``X + (I − (h/2) f'(X))^{−1} h f(X)``
for every orbit of a batch ``(m, n)``, ``f(X) = Π(X)(A X + g0)``, ``Π(X)_{iJ} = Σ_k c[i, J, k] X_k``."""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy")
def _step(x, c, A, g0, h, g, P, f, M):
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
    d = np.linalg.solve(M, f)
    for i in range(n):
        x[i] += d[i]


@njit(cache=True, error_model="numpy", parallel=True)
def kahan_advance(X, c, A, g0, h, steps, save_every):
    """``(rows (steps // save_every, m, n), X_last (m, n), ok)``: ``ok`` is false when a state became non-finite."""
    m, n = X.shape
    k = steps // save_every
    rows = np.empty((k, m, n))
    out = X.copy()
    bad = np.zeros(m, dtype=np.bool_)
    for o in prange(m):
        x = out[o].copy()
        g = np.empty(n)
        P = np.empty((n, n))
        f = np.empty(n)
        M = np.empty((n, n))
        for s in range(steps):
            _step(x, c, A, g0, h, g, P, f, M)
            if (s + 1) % save_every == 0:
                rows[(s + 1) // save_every - 1, o] = x
        for i in range(n):
            if not np.isfinite(x[i]):
                bad[o] = True
        out[o] = x
    return rows, out, not bad.any()
