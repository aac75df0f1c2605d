r"""The Lie--Poisson algebra :math:`\mathfrak g^{(N)}` (paper, eq. (LP)).

Coordinates are the components :math:`y_i^\alpha` (``i = 0..N-1``,
``alpha = 1..3``), stored in a trailing axis of length ``3N`` in the order
``(y_0^1, y_0^2, y_0^3, y_1^1, ..., y_{N-1}^3)``; for ``N = 3`` this is
``(y, x, z)`` of Section 4.  The brackets are

.. math::  \{y_i^\alpha, y_j^\beta\} = \epsilon^{\alpha\beta\gamma} y^\gamma_{i+j}
           \quad (i + j < N), \qquad 0 \quad (i + j \ge N).

All functions act on arrays of shape ``(..., 3N)``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from ._validate import as_state, check_gradient, check_N, finite_result

__all__ = [
    "structure_constants",
    "poisson_tensor",
    "bracket",
    "hamiltonian_vector_field",
    "casimirs",
    "casimir_gradients",
]

_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0


@cache
def _structure_constants(N: int) -> np.ndarray:
    c = np.zeros((3 * N, 3 * N, 3 * N))
    for i in range(N):
        for j in range(N - i):
            c[3 * i : 3 * i + 3, 3 * j : 3 * j + 3, 3 * (i + j) : 3 * (i + j) + 3] = _EPS
    c.setflags(write=False)
    return c


def structure_constants(N: int) -> np.ndarray:
    r"""Structure constants :math:`c^{IJ}_K` of :math:`\mathfrak g^{(N)}`, shape ``(3N, 3N, 3N)``.

    ``{X_I, X_J} = sum_K c[I, J, K] X_K`` with ``X_{3i+a} = y_i^{a+1}`` (eq. (LP)).
    The returned array is read-only.
    """
    return _structure_constants(check_N(N))


def poisson_tensor(X) -> np.ndarray:
    r"""Poisson tensor :math:`\Pi(X)_{IJ} = \{X_I, X_J\}` of eq. (LP), shape ``(..., 3N, 3N)``.

    >>> import jetgaudin as jg
    >>> P = jg.poisson_tensor([0.0, 0.0, 1.0])   # N = 1: su(2), y = e_3
    >>> P.tolist()
    [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    X, N = as_state(X, allow_complex=True)
    return np.einsum("ijk,...k->...ij", structure_constants(N), X)


def bracket(grad_f, grad_g, X) -> np.ndarray:
    r"""Lie--Poisson bracket :math:`\{f, g\}(X) = \nabla f^T \Pi(X) \nabla g` from gradients.

    ``grad_f``, ``grad_g`` and ``X`` have shape ``(..., 3N)``; the result has shape ``(...)``.
    For ``N = 3`` this is the displayed formula after (algebra) in Section 3.
    """
    P = poisson_tensor(X)
    n = P.shape[-1]
    grad_f = check_gradient(grad_f, n, name="grad_f")
    grad_g = check_gradient(grad_g, n, name="grad_g")
    return np.einsum("...i,...ij,...j->...", grad_f, P, grad_g)


def hamiltonian_vector_field(grad_H, X) -> np.ndarray:
    r"""Hamiltonian vector field :math:`\dot X = \Pi(X) \nabla H` (so :math:`\dot f = \{f, H\}`)."""
    P = poisson_tensor(X)
    grad_H = check_gradient(grad_H, P.shape[-1], name="grad_H")
    return np.einsum("...ij,...j->...i", P, grad_H)


def _blocks(X, N):
    return X.reshape(X.shape[:-1] + (N, 3))


def casimirs(X) -> np.ndarray:
    r"""The N Casimir functions :math:`C_k = \sum_{i=k-1}^{N-1} \langle y_i, y_{N+k-i-2}\rangle`
    (Prop. 2), shape ``(..., N)``.

    For ``N = 3``: ``C_1 = 2 C^(1)``, ``C_2 = 2 C^(2)``, ``C_3 = C^(3)`` of Section 3, eq. (cas).
    """
    X, N = as_state(X, allow_complex=True)
    y = _blocks(X, N)
    out = []
    for k in range(1, N + 1):
        out.append(sum(np.sum(y[..., i, :] * y[..., N + k - i - 2, :], axis=-1) for i in range(k - 1, N)))
    return finite_result(np.stack(out, axis=-1), "the Casimirs")


def casimir_gradients(X) -> np.ndarray:
    r"""Gradients of the Casimirs :math:`C_k`, shape ``(..., N, 3N)``:
    :math:`\partial C_k / \partial y_m = 2 y_{N+k-2-m}` for ``k-1 <= m <= N-1``."""
    X, N = as_state(X, allow_complex=True)
    y = _blocks(X, N)
    g = np.zeros(X.shape[:-1] + (N, N, 3), dtype=X.dtype)
    for k in range(1, N + 1):
        for m in range(k - 1, N):
            g[..., k - 1, m, :] = 2 * y[..., N + k - 2 - m, :]
    return g.reshape(X.shape[:-1] + (N, 3 * N))
