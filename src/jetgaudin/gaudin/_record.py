r"""A chain's recorded integrals in one compiled pass (private; :meth:`jetgaudin.ChainHamiltonian.record_integrals`,
issue 33): the quadratic forms of :meth:`jetgaudin.GaudinModel._forms`,

.. math:: h_I = \sum_{a=1}^{3} \sum_{c,d} q_{a,I,c,d}\, y_c^a y_d^a + 2 b \sum_c l_{I,c}\, y_c^3, \qquad
          e_E = \sum_k F_{E,k} X_k

(the rational family's ``q`` is the same for the three components ``a``; the trigonometric and elliptic families'
weights differ per component, the trigonometric family has the linear extras ``e_E`` and the elliptic one the form
of ``c_0`` as one more ``h_I``), row by row without NumPy temporaries.  The same sums
as the NumPy form (``np.einsum``) in another order: equal to round-off (tested against it with the bound
``n ε Σ |terms|``), not bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def chain_integrals(X, q3, lin, b, forms, out):
    """``out[r] = (h_1..h_I, e_1..e_E)`` of every row of ``X`` (R, 3M): ``q3`` (3, I, M, M), ``lin`` (I, M),
    ``forms`` (E, 3M)."""
    I = q3.shape[1]
    M = q3.shape[2]
    E = forms.shape[0]
    n = X.shape[1]
    for r in range(X.shape[0]):
        for i in range(I):
            acc = 0.0
            for c in range(M):
                for d in range(M):
                    acc += (q3[0, i, c, d] * X[r, 3 * c] * X[r, 3 * d] + q3[1, i, c, d] * X[r, 3 * c + 1]
                            * X[r, 3 * d + 1]) + q3[2, i, c, d] * X[r, 3 * c + 2] * X[r, 3 * d + 2]
            lsum = 0.0
            for c in range(M):
                lsum += lin[i, c] * X[r, 3 * c + 2]
            out[r, i] = acc + 2.0 * b * lsum
        for e in range(E):
            s = 0.0
            for k in range(n):
                s += forms[e, k] * X[r, k]
            out[r, I + e] = s


@njit(cache=True, error_model="numpy")
def chain_integrals_gram(X, q, lin, b, out):
    """:func:`chain_integrals` for forms with one ``q`` (I, M, M) for the three components (the rational family):
    the Gram matrix ``⟨y_c, y_d⟩`` once per row, then ``h_I = Σ_{c,d} q[I, c, d] ⟨y_c, y_d⟩ + 2b Σ_c l[I, c] y_c^3``
    (the NumPy form's own grouping)."""
    I = q.shape[0]
    M = q.shape[1]
    gram = np.empty((M, M))
    for r in range(X.shape[0]):
        for c in range(M):
            for d in range(M):
                gram[c, d] = (X[r, 3 * c] * X[r, 3 * d] + X[r, 3 * c + 1] * X[r, 3 * d + 1]) + X[r, 3 * c + 2] * X[
                    r, 3 * d + 2]
        for i in range(I):
            acc = 0.0
            for c in range(M):
                for d in range(M):
                    acc += q[i, c, d] * gram[c, d]
            lsum = 0.0
            for c in range(M):
                lsum += lin[i, c] * X[r, 3 * c + 2]
            out[r, i] = acc + 2.0 * b * lsum
