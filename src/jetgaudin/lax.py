r"""Lax matrices of the jet-extended su(2) Gaudin hierarchy (Section 2).

The general Lax matrix, eq. (lax), is

.. math::  L(\lambda) = \sum_{\alpha=1}^3 \sigma^\alpha \Big[ b^\alpha
           + \sum_{i=0}^{N-1} f_i(\lambda)\, y_i^\alpha \Big],
           \qquad \sum_{i\ge 0} \varepsilon^i f_i(\lambda) = \frac{1}{\lambda + c(\varepsilon)},
           \quad c(\varepsilon) = \sum_{k\ge1} c_k \varepsilon^k,

the generating function being the partition formula of Section 2 summed
(Faà di Bruno).  Writing ``f_i(λ) = Σ_n T[i, n] λ^{-(n+1)}`` gives
``L(λ) = Σ_α σ^α ξ^α(λ)`` with ``ξ(λ) = b + Σ_n Y_n λ^{-(n+1)}``,
``Y_n = Σ_i T[i, n] y_i``.  The reduction (lax2) is ``c_1 = -1``, ``c_k = 0``
(``k ≥ 2``), for which ``T`` is the identity and ``Y_n = y_n``.

In the form (yy), ``L = (i/2) [[u, v], [w, -u]]`` with ``u = ξ^3``,
``v = ξ^1 - i ξ^2``, ``w = ξ^1 + i ξ^2``.
"""

from __future__ import annotations

import numpy as np

from ._errors import InvalidParameterError
from ._validate import as_state, check_N, field_vector, jet_constants, spectral_points

__all__ = [
    "SIGMA",
    "jet_coefficients",
    "jet_function",
    "lax_coefficients",
    "lax_matrix",
    "uvw",
    "ell_coefficients",
    "state_from_ell",
    "r_matrix",
]

#: The basis sigma^1, sigma^2, sigma^3 of su(2) of Section 2, shape (3, 2, 2).
SIGMA = 0.5 * np.array(
    [
        [[0, 1j], [1j, 0]],
        [[0, 1], [-1, 0]],
        [[1j, 0], [0, -1j]],
    ],
    dtype=complex,
)
SIGMA.setflags(write=False)


def _check_c(c, N):
    if c is None:
        c = np.zeros(max(N - 1, 0), dtype=complex)
        if N > 1:
            c[0] = -1.0
        return c
    return jet_constants(c, N)


def jet_coefficients(N: int, c=None) -> np.ndarray:
    r"""Matrix ``T`` (shape ``(N, N)``) with :math:`f_i(\lambda) = \sum_n T_{in} \lambda^{-(n+1)}`.

    :math:`T_{in} = (-1)^n [\varepsilon^i]\, c(\varepsilon)^n`, equivalent to the
    partition formula of Section 2 (``T[i, n] = (-1)^n n! Σ_{|q| = n, Σ k q_k = i} Π c_k^{q_k} / q_k!``).
    ``c = None`` means the reduction (lax2): ``c_1 = -1``, ``c_k = 0`` for ``k ≥ 2``, ``T = I``.
    Real when the ``c_k`` are real.
    """
    N = check_N(N)
    cc = _check_c(c, N)
    series = np.zeros(N, dtype=complex)  # c(eps) truncated at eps^(N-1)
    series[1:] = cc
    T = np.zeros((N, N), dtype=complex)
    power = np.zeros(N, dtype=complex)
    power[0] = 1.0  # c(eps)^0
    for n in range(N):
        T[:, n] = (-1) ** n * power
        power = np.convolve(power, series)[:N]
    if np.all(T.imag == 0):
        T = T.real
    return T


def jet_function(i: int, lam, N: int | None = None, c=None):
    r"""Evaluate :math:`f_i(\lambda)` of Section 2 (``f_0 = 1/λ``)."""
    if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or i < 0:
        raise InvalidParameterError(f"the index i of f_i must be an integer >= 0, got {i!r}")
    N = check_N(N if N is not None else i + 1)
    if i >= N:
        raise InvalidParameterError(f"f_i needs i <= N - 1, got i = {i} with N = {N}; pass a larger N")
    T = jet_coefficients(N, c)
    lam = spectral_points(lam)
    return sum(T[i, n] * lam ** (-(n + 1)) for n in range(N))


def lax_coefficients(X, b, c=None) -> np.ndarray:
    r"""Coefficients :math:`\xi_m` of :math:`\xi(\lambda) = \sum_{m=0}^{N} \xi_m \lambda^{-m}`,
    shape ``(..., N+1, 3)``; ``ξ_0 = b`` and ``ξ_{n+1} = Y_n = Σ_i T[i, n] y_i``.

    ``b`` is a float (field ``(0, 0, b)``) or a 3-vector.
    """
    X, N = as_state(X, allow_complex=True)
    bvec = field_vector(b)
    T = jet_coefficients(N, c)
    y = X.reshape(X.shape[:-1] + (N, 3))
    # T = I for the reduction (lax2): Y_n = y_n without the product (an einsum over 10^5 states costs ~30 ms)
    Y = y if c is None else np.einsum("in,...ia->...na", T, y)
    b_b = np.broadcast_to(bvec, Y.shape[:-2] + (1, 3)).astype(Y.dtype)
    return np.concatenate([b_b, Y], axis=-2)


def _xi(lam, X, b, c=None):
    xi = lax_coefficients(X, b, c)
    lam = spectral_points(lam)
    m = np.arange(xi.shape[-2])
    powers = lam[..., None] ** (-m)  # (..., N+1)
    return np.einsum("...m,...ma->...a", powers, xi)


def uvw(lam, X, b, c=None):
    r"""The functions ``u, v, w`` of eq. (yy) at ``lam`` (broadcast against ``X[..., 0]``).

    ``u = b^3 + Σ f_i y_i^3``, ``v = (b^1 - i b^2) + Σ f_i (y_i^1 - i y_i^2)``,
    ``w = (b^1 + i b^2) + Σ f_i (y_i^1 + i y_i^2)``.
    """
    xi = _xi(lam, X, b, c)
    return xi[..., 2], xi[..., 0] - 1j * xi[..., 1], xi[..., 0] + 1j * xi[..., 1]


def lax_matrix(lam, X, b, c=None) -> np.ndarray:
    r"""The Lax matrix :math:`L(\lambda) = \sum_\alpha \sigma^\alpha \xi^\alpha(\lambda)` of
    eq. (lax) (eq. (lax2) for ``c = None``; (kk) / (kkk) for ``N = 3``), shape ``(..., 2, 2)``.

    >>> import numpy as np, jetgaudin as jg
    >>> L = jg.lax_matrix(2.0, [0.0, 0.0, 1.0], 1.0)   # N = 1: L = sigma^3 (1 + 1/2)
    >>> np.allclose(L, [[0.75j, 0], [0, -0.75j]])
    True
    """
    xi = _xi(lam, X, b, c)
    return np.einsum("...a,aij->...ij", xi, SIGMA)


def ell_coefficients(X, b, c=None) -> np.ndarray:
    r"""Laurent coefficients :math:`\ell_m` of :math:`\ell(\lambda) = [[u, v], [w, -u]]
    = \sum_{m=0}^N \ell_m \lambda^{-m} = -2 i L(\lambda)`, shape ``(..., N+1, 2, 2)``."""
    return ell_from_xi(lax_coefficients(X, b, c))


def ell_from_xi(xi) -> np.ndarray:
    r"""``ℓ = Σ_a ξ^a (−2iσ^a) = [[ξ^3, ξ^1 − iξ^2], [ξ^1 + iξ^2, −ξ^3]]`` from vectors ``ξ`` ``(..., 3)``, shape
    ``(..., 2, 2)`` (complex)."""
    xi = np.asarray(xi).astype(complex)
    out = np.empty(xi.shape[:-1] + (2, 2), dtype=complex)
    out[..., 0, 0] = xi[..., 2]
    out[..., 1, 1] = -xi[..., 2]
    out[..., 0, 1] = xi[..., 0] - 1j * xi[..., 1]
    out[..., 1, 0] = xi[..., 0] + 1j * xi[..., 1]
    return out


def state_from_ell(ell) -> np.ndarray:
    r"""Inverse of :func:`ell_coefficients` for ``m >= 1`` (reduction (lax2)):
    ``y^3 = ℓ_11``, ``y^1 = (ℓ_12 + ℓ_21)/2``, ``y^2 = (ℓ_21 - ℓ_12)/(2i)``; returns ``(..., 3N)``
    (complex)."""
    ell = np.asarray(ell)[..., 1:, :, :]
    y1 = 0.5 * (ell[..., 0, 1] + ell[..., 1, 0])
    y2 = (ell[..., 1, 0] - ell[..., 0, 1]) / 2j
    y3 = ell[..., 0, 0]
    y = np.stack([y1, y2, y3], axis=-1)
    return y.reshape(y.shape[:-2] + (-1,))


def r_matrix(lam) -> np.ndarray:
    r"""The rational r-matrix :math:`r(\lambda) = \lambda^{-1} \sum_\alpha \sigma^\alpha \otimes \sigma^\alpha`
    of Prop. 1, shape ``(..., 4, 4)`` (Kronecker-product basis)."""
    lam = spectral_points(lam)
    P = sum(np.kron(SIGMA[a], SIGMA[a]) for a in range(3))
    return P / lam[..., None, None]
