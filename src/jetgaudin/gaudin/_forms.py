r"""The integrals of any family as quadratic forms in the state (``docs/families.md``, issue 23).

``ν²(λ) = Σ_a ξ^a(λ)²`` has at the site ``λ_j`` the principal part ``Σ_{m=1}^{2N_j} h_{j,m} (λ − λ_j)^{−m}``.
Expanding every ``φ_{a,k}(λ − λ_i)`` at ``λ_j`` in ``x = λ − λ_j``, ``Σ_p L^{a}_{c,j,p} x^p`` (``p ≥ −N_j``;
``x^{−(k+1)}`` plus the Taylor coefficients of the regular part ``(−1)^k C(p+k, k) r_{p+k}`` of ``w_a`` for the
site's own components, the Taylor coefficients ``(−1)^k C(p+k, k) t_{p+k}`` of ``w_a`` at ``λ_j − λ_i``
otherwise):

.. math:: h_{j,m} = \sum_a \sum_{c,d} y^a_c y^a_d \sum_{p+q=-m} L^a_{c,j,p} L^a_{d,j,q}
          + 2b\, y^{(j)3}_{m-1}\,[m \le N_j],

the last term from the constant ``b e_3``.  The ``h_{j,m}`` are conserved by every map of the core (``ν²`` is
invariant under ``ℓ → DℓD^{-1}``).  For ``m > N_j`` only the site's own components contribute to the singular
orders and ``h_{j,m}`` is the Casimir ``C_{m−N_j}`` of ``g^(N_j)`` (the regular parts enter only with ``p ≥ 0``,
which needs ``q ≤ −m − 0 < −N_j``: impossible).
"""

from __future__ import annotations

import numpy as np

from ..families._series import shift_derivative

__all__ = ["generic_forms", "evaluate", "gradients"]


def _laurent(model, a: int, j: int, more: int = 0) -> np.ndarray:
    """``L[c, p + N_j]`` for ``p = −N_j … N_j − 1 + more``: the expansion at ``λ_j`` of every component's
    function."""
    fam = model.family
    lam_j, N_j = model.sites[j]
    out = np.zeros((model.M, 2 * N_j + more), dtype=complex)
    for i, (lam_i, N_i) in enumerate(model.sites):
        t = fam.regular(a, N_j + N_i + more) if i == j else fam.taylor(a, lam_j - lam_i, N_j + N_i + more)
        for k in range(N_i):
            c = model.offsets[i] + k
            out[c, N_j:] = shift_derivative(t, k, N_j + more)
            if i == j and k < N_j:
                out[c, N_j - k - 1] = 1.0
    return out


def generic_forms(model):
    """``(q, lin)``: ``q`` ``(3, 2M, M, M)`` (real, symmetric in the last two axes), ``lin`` ``(2M, M)``."""
    M = model.M
    q = np.zeros((3, 2 * M, M, M))
    lin = np.zeros((2 * M, M))
    row = 0
    for j, (_, N_j) in enumerate(model.sites):
        tabs = [_laurent(model, a, j) for a in (1, 2, 3)]
        for m in range(1, 2 * N_j + 1):
            for a in range(3):
                L = tabs[a]
                acc = np.zeros((M, M), dtype=complex)
                for p in range(-N_j, N_j):
                    r = -m - p
                    if -N_j <= r < N_j:
                        acc += np.outer(L[:, p + N_j], L[:, r + N_j])
                q[a, row] = (0.5 * (acc + acc.T)).real  # the functions are real on the real axis
            if m <= N_j:
                lin[row, model.offsets[j] + m - 1] = 1.0
            row += 1
    if model.family.constant_integral:
        q = np.concatenate([q, constant_form(model, q)[:, None]], axis=1)
        lin = np.concatenate([lin, np.zeros((1, M))], axis=0)
    q.setflags(write=False)
    lin.setflags(write=False)
    return q, lin


def constant_form(model, q) -> np.ndarray:
    r"""The quadratic form ``(3, M, M)`` of the constant ``c_0`` of ``ν² = c_0 + Σ_{j,m} h_{j,m} ψ_m(λ − λ_j)``
    (a family with :attr:`~jetgaudin.families.Family.constant_integral`; needs ``b = 0``): the ``x^0`` Laurent
    coefficient of ``ν²`` at the first site ``λ_1`` minus that of the sum,

    .. math:: c_0 = [x^0]\nu^2(\lambda_1 + x) - \sum_m h_{1,m}\, [x^0](\psi_m(x) - x^{-m})
              - \sum_{i \ne 1} \sum_m h_{i,m}\, \psi_m(\lambda_1 - \lambda_i),

    with ``q`` the forms of the ``h_{j,m}`` (rows in the order of the integrals)."""
    fam = model.family
    M = model.M
    _, N_1 = model.sites[0]
    out = np.zeros((3, M, M))
    for a in range(3):
        L = _laurent(model, a + 1, 0, more=1)
        acc = np.zeros((M, M), dtype=complex)
        for p in range(-N_1, N_1 + 1):
            acc += np.outer(L[:, p + N_1], L[:, -p + N_1])
        out[a] = (0.5 * (acc + acc.T)).real
    row = 0
    for i, (lam_i, N_i) in enumerate(model.sites):
        for m in range(1, 2 * N_i + 1):
            coef = fam.nu2_basis_constant(m) if i == 0 else fam.nu2_basis(m, np.asarray(model.sites[0][0] - lam_i))
            out -= float(np.real(coef)) * q[:, row]
            row += 1
    return out


def evaluate(model, q, lin, X) -> np.ndarray:
    """``(h_{j,m}…, extras…)`` at ``X`` ``(..., 3M)``."""
    y = X.reshape(X.shape[:-1] + (model.M, 3))
    h = np.einsum("aIcd,...ca,...da->...I", q, y, y) + 2.0 * model.b * np.einsum("Ic,...c->...I", lin, y[..., 2])
    forms = model.family.extra_integrals(model.sites)[1]
    return np.concatenate([h, np.einsum("Ei,...i->...E", forms, X)], axis=-1)


def gradients(model, q, lin, X) -> np.ndarray:
    """Gradients of :func:`evaluate`, shape ``(..., n_integrals, 3M)``."""
    y = X.reshape(X.shape[:-1] + (model.M, 3))
    g = 2.0 * np.einsum("aIcd,...da->...Ica", q, y)
    g[..., 2] += 2.0 * model.b * lin
    g = g.reshape(X.shape[:-1] + (q.shape[1], 3 * model.M))
    forms = model.family.extra_integrals(model.sites)[1]
    return np.concatenate([g, np.broadcast_to(forms, X.shape[:-1] + forms.shape).astype(g.dtype)], axis=-2)
