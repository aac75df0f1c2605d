r"""Generic dressing for any N (Section 6): exact Laurent division of ``M ℓ adj(M)``.

Everything here works on the Laurent coefficients ``ℓ_m`` (``m = 0..N``) of
``ℓ(λ) = [[u, v], [w, −u]] = Σ ℓ_m λ^{-m}`` and uses explicit 2x2 arithmetic
(no BLAS), so that a batch of states gives, element by element, bit-identical
results to a single state.
"""

from __future__ import annotations

import numpy as np

from .._errors import SingularStepError

# ---- explicit 2x2 helpers on arrays (..., 2, 2) -------------------------------------------


def mm(A, B):
    """2x2 matrix product, elementwise over leading axes."""
    out = np.empty(np.broadcast_shapes(A.shape, B.shape), dtype=np.result_type(A, B))
    out[..., 0, 0] = A[..., 0, 0] * B[..., 0, 0] + A[..., 0, 1] * B[..., 1, 0]
    out[..., 0, 1] = A[..., 0, 0] * B[..., 0, 1] + A[..., 0, 1] * B[..., 1, 1]
    out[..., 1, 0] = A[..., 1, 0] * B[..., 0, 0] + A[..., 1, 1] * B[..., 1, 0]
    out[..., 1, 1] = A[..., 1, 0] * B[..., 0, 1] + A[..., 1, 1] * B[..., 1, 1]
    return out


def adj(A):
    """Adjugate of a 2x2 matrix: ``adj(A) = tr(A) 1 − A``."""
    out = np.empty_like(A)
    out[..., 0, 0] = A[..., 1, 1]
    out[..., 1, 1] = A[..., 0, 0]
    out[..., 0, 1] = -A[..., 0, 1]
    out[..., 1, 0] = -A[..., 1, 0]
    return out


def horner(ell, lam):
    """Evaluate ``Σ_m ell[..., m, :, :] lam^{-m}`` by Horner's rule in ``1/lam``."""
    z = 1.0 / np.asarray(lam, dtype=complex)[..., None, None]
    acc = ell[..., -1, :, :]
    for m in range(ell.shape[-3] - 2, -1, -1):
        acc = acc * z + ell[..., m, :, :]
    return acc


def laurent_divide(R, delta):
    r"""Divide ``R(λ) = Σ_{k=0}^{N+d} R̂_k λ^{d-k}`` by the monic ``D(λ) = Σ_{i=0}^d δ_i λ^{d-i}``.

    ``R`` has shape ``(..., N+d+1, 2, 2)`` (``R̂_0`` first), ``delta`` is the list
    ``[δ_1, …, δ_d]`` of arrays broadcastable to ``(...)``.  Returns ``(Q, res)``:
    ``Q`` of shape ``(..., N+1, 2, 2)`` with ``D·Q = R`` and ``res`` the largest absolute
    residual of the ``d`` equations the division does not use (zero in exact arithmetic
    when ``D`` divides ``R``).  The recursion runs from the low powers (dividing by
    ``δ_d``) when ``|δ_d| ≥ 1`` and from the high powers otherwise, the direction in which
    the homogeneous solutions decay, so that round-off is not amplified.
    """
    d = len(delta)
    K = R.shape[-3]
    N = K - d - 1
    dl = [np.ones(())] + [np.asarray(x, dtype=complex)[..., None, None] for x in delta]
    Q = np.zeros(np.broadcast_shapes(R.shape[:-3], dl[-1].shape[:-2]) + (N + 1, 2, 2), dtype=complex)
    bottom_up = bool(np.all(np.abs(dl[-1]) >= 1.0))

    if not bottom_up:
        for k in range(N + 1):
            acc = R[..., k, :, :]
            for i in range(1, d + 1):
                if k - i >= 0:
                    acc = acc - dl[i] * Q[..., k - i, :, :]
            Q[..., k, :, :] = acc
        unused = range(N + 1, N + d + 1)
    else:
        for k in range(N + d, d - 1, -1):
            acc = R[..., k, :, :]
            for i in range(0, d):
                if k - i <= N:
                    acc = acc - dl[i] * Q[..., k - i, :, :]
            Q[..., k - d, :, :] = acc / dl[d]
        unused = range(0, d)
    res = np.zeros(Q.shape[:-3])
    for k in unused:
        acc = R[..., k, :, :]
        for i in range(d + 1):
            if 0 <= k - i <= N:
                acc = acc - dl[i] * Q[..., k - i, :, :]
        res = np.maximum(res, np.max(np.abs(acc), axis=(-2, -1)))
    return Q, res


def _safe_ratio(num1, den1, num2, den2, what):
    """Return num1/den1 == num2/den2 using the larger denominator (both forms are equal on the curve)."""
    a1, a2 = np.abs(den1), np.abs(den2)
    use1 = a1 >= a2
    den = np.where(use1, den1, den2)
    num = np.where(use1, num1, num2)
    scale = np.abs(num1) + np.abs(num2) + a1 + a2
    bad = np.abs(den) <= 1e-13 * scale
    if np.any(bad):
        raise SingularStepError(what)
    return num / den


def spectral_s(u, v, w, nu):
    r"""``s = (u − ν)/v = −w/(u + ν)`` (eqs. (hhh), (x) with the paper's μ read as ν):
    ``[1, −s]`` is the eigenvector of ``ℓ(η)`` with eigenvalue ``ν``."""
    return _safe_ratio(
        u - nu,
        v,
        -w,
        u + nu,
        "singular Bäcklund step: v(eta) and u(eta) + nu(eta) both vanish, so the eigenvector "
        "[1, -s] of l(eta) is undefined (s would be infinite); change eta",
    )


def spectral_kappa(u, v, w, nu):
    r"""``κ = (ν − u)/v = w/(ν + u)``: ``[1, κ]`` is the eigenvector of ``ℓ(η)`` with eigenvalue ``ν``."""
    return _safe_ratio(
        nu - u,
        v,
        w,
        nu + u,
        "singular Bäcklund step: v(eta2) and u(eta2) + nu2 both vanish; change eta",
    )


def two_point_M0(eta1, eta2, s, t):
    r"""``M0`` of ``M(λ) = λ·1 + M0``, eq. (mm)."""
    M0 = np.empty(np.shape(s) + (2, 2), dtype=complex)
    M0[..., 0, 0] = -eta1 + s * t
    M0[..., 0, 1] = t
    M0[..., 1, 0] = -s * s * t + (eta1 - eta2) * s
    M0[..., 1, 1] = -eta2 - s * t
    return M0


def eigenvector(u, v, w, nu):
    r"""An eigenvector ``k`` of ``ℓ(η) = [[u, v], [w, −u]]`` for the eigenvalue ``ν`` (``ν² = u² + vw``).

    ``k = (v, ν − u)`` or ``k = (u + ν, w)`` (proportional on the curve), whichever is larger, so that
    ``s = −k_2/k_1`` of eq. (x) may be infinite without loss (``v(η) = 0``, ``u + ν = 0``).  Both vanish
    only if ``ℓ(η) = 0``, a double branch point: :class:`BranchPointError`.
    """
    a1, a2 = v, nu - u
    b1, b2 = u + nu, w
    na = np.abs(a1) ** 2 + np.abs(a2) ** 2
    nb = np.abs(b1) ** 2 + np.abs(b2) ** 2
    use_a = na >= nb
    k1 = np.where(use_a, a1, b1)
    k2 = np.where(use_a, a2, b2)
    scale = np.abs(u) + np.abs(v) + np.abs(w) + np.abs(nu)
    if np.any(np.maximum(na, nb) <= (1e-15 * scale) ** 2) or np.any(np.maximum(na, nb) == 0):
        from .._errors import BranchPointError

        raise BranchPointError(
            "l(eta) vanishes (eta is a double branch point of nu): the eigenvector of the Bäcklund step is "
            "undefined; change eta"
        )
    return k1, k2


def real_two_point_M0(eta, k1, k2):
    r"""``M0`` of the real two-point map (``η1 = η``, ``η2 = η̄``, ``μ2 = conj μ1``) from the eigenvector
    ``k`` of ``ℓ(η)`` for ``ν1``, projectively (valid at ``s = −k_2/k_1 = ∞``):

    .. math:: M_0 = -\operatorname{diag}(\eta, \bar\eta) + \frac{2 i\, \Im\eta}{|k|^2}
              \begin{pmatrix} |k_2|^2 & -k_1 \bar k_2 \\ -\bar k_1 k_2 & -|k_2|^2 \end{pmatrix}.

    This is eq. (mm) with ``t = 2i Im(η) s̄/(1 + |s|²)``: reality forces ``κ = 1/s̄`` in eq. (X), so the
    denominator ``s + κ`` of ``t`` never vanishes (``docs/backlund.md``).
    """
    eta = np.asarray(eta, dtype=complex)
    n2 = np.abs(k1) ** 2 + np.abs(k2) ** 2
    c = 2j * eta.imag / n2
    a2 = np.abs(k2) ** 2
    M0 = np.empty(np.broadcast_shapes(np.shape(k1), eta.shape) + (2, 2), dtype=complex)
    M0[..., 0, 0] = -eta + c * a2
    M0[..., 0, 1] = -c * k1 * np.conj(k2)
    M0[..., 1, 0] = -c * np.conj(k1) * k2
    M0[..., 1, 1] = -np.conj(eta) - c * a2
    return M0


def dress_two_point(ell, eta1, eta2, M0):
    r"""``ℓ̆ = M ℓ adj(M) / ((λ−η1)(λ−η2))`` for ``M = λ + M0`` (eq. (128)); returns ``(ℓ̆, res)``."""
    A0 = adj(M0)
    N = ell.shape[-3] - 1
    M0e = M0[..., None, :, :]
    A0e = A0[..., None, :, :]
    # R(λ) = λ² ℓ + λ (M0 ℓ + ℓ A0) + M0 ℓ A0, as coefficients of λ^{2-k}, k = 0..N+2
    shape = np.broadcast_shapes(ell.shape[:-3], M0.shape[:-2]) + (N + 3, 2, 2)
    R = np.zeros(shape, dtype=complex)
    R[..., 0 : N + 1, :, :] += ell
    R[..., 1 : N + 2, :, :] += mm(M0e, ell) + mm(ell, A0e)
    R[..., 2 : N + 3, :, :] += mm(mm(M0e, ell), A0e)
    ones = np.ones(M0.shape[:-2])
    return laurent_divide(R, [-(eta1 + eta2) * ones, eta1 * eta2 * ones])


def dress_one_point(ell, eta, p, q, inverse=False):
    r"""One-point dressing; returns ``(ℓ̃, res)``.

    Forward (eq. (rr)): ``ℓ̃ = M ℓ adj(M) / (λ − η)`` with ``M = [[λ − η + pq, p], [q, 1]] = λE11 + M0``
    (eq. (ansatz)).  Inverse: ``ℓ = adj(M) ℓ̃ M / (λ − η)``, i.e. the same formula with
    ``adj(M) = λE22 + adj(M0)`` in place of ``M``.
    """
    N = ell.shape[-3] - 1
    M0 = np.empty(np.shape(p) + (2, 2), dtype=complex)
    M0[..., 0, 0] = -eta + p * q
    M0[..., 0, 1] = p
    M0[..., 1, 0] = q
    M0[..., 1, 1] = 1.0
    E11 = np.array([[1.0, 0.0], [0.0, 0.0]], dtype=complex)
    E22 = np.array([[0.0, 0.0], [0.0, 1.0]], dtype=complex)
    if inverse:
        E, K0, adjE, adjK0 = E22, adj(M0), E11, M0
    else:
        E, K0, adjE, adjK0 = E11, M0, E22, adj(M0)
    K0e = K0[..., None, :, :]
    A0e = adjK0[..., None, :, :]
    shape = np.broadcast_shapes(ell.shape[:-3], M0.shape[:-2]) + (N + 3, 2, 2)
    R = np.zeros(shape, dtype=complex)
    R[..., 0 : N + 1, :, :] += mm(mm(E, ell), adjE)
    R[..., 1 : N + 2, :, :] += mm(mm(E, ell), A0e) + mm(mm(K0e, ell), adjE)
    R[..., 2 : N + 3, :, :] += mm(mm(K0e, ell), A0e)
    # the λ^2 coefficient E ℓ_0 adj(E) vanishes for b along e_3: drop it, divide the rest by (λ − η)
    lead = np.max(np.abs(R[..., 0, :, :]), axis=(-2, -1))
    Q, res = laurent_divide(R[..., 1:, :, :], [-eta * np.ones(np.shape(p))])
    return Q, np.maximum(res, lead)


def dress_real_two_point(ell, eta, M0):
    r"""The real two-point dressing ``ℓ̆ = M ℓ adj(M) / D`` (eq. (128)), ``M = λ + M0``, ``D = (λ − η)(λ − η̄)``,
    evaluated as ``ℓ̆ = ℓ + M [P, ℓ] / D``; returns ``(ℓ̆, res)`` as :func:`dress_two_point`.

    With ``m = tr(M0)/2 = −Re η`` and ``P = M0 − m`` (traceless), ``adj M = M − 2P`` and ``ℓ adj M = adj M ℓ +
    [P, ℓ]``, so ``M ℓ adj M = det(M) ℓ + M [P, ℓ]``; ``det M = (λ + m)² − P² = D`` because ``P² = −(Im η)²`` for
    the ``M0`` of :func:`real_two_point_M0` (``P = i Im η (n̂·σ)`` with a unit vector ``n̂``).  The exact division
    then acts on ``M [P, ℓ]`` only, of size ``|Im η| |ℓ|``: its round-off is a random walk of that size.  The
    form ``R / D`` of :func:`dress_two_point` divides the whole ``D ℓ`` too, and the rounded ``δ2 = |η|²`` is the
    same every step, so there its relative error ``ε`` rescales ``ℓ`` by ``1 + O(ε)`` at every step, the same
    way: the integrals drift linearly (``docs/reliability.md``, "Integral drift of the two routes").
    """
    N = ell.shape[-3] - 1
    P = M0.copy()
    # the traceless part: M0 + Re(eta) I; the diagonal's real part is -Re(eta) exactly, so only Im survives
    P[..., 0, 0] = 1j * M0[..., 0, 0].imag
    P[..., 1, 1] = 1j * M0[..., 1, 1].imag
    Pe = P[..., None, :, :]
    C = mm(Pe, ell) - mm(ell, Pe)  # [P, ℓ_m], m = 0..N
    shape = np.broadcast_shapes(ell.shape[:-3], M0.shape[:-2]) + (N + 3, 2, 2)
    S = np.zeros(shape, dtype=complex)  # coefficients of λ^{2-k}: M(λ)[P, ℓ(λ)] has no λ² term
    S[..., 1 : N + 2, :, :] += C
    S[..., 2 : N + 3, :, :] += mm(M0[..., None, :, :], C)
    eta = np.asarray(eta, dtype=complex)
    ones = np.ones(M0.shape[:-2])
    Q, res = laurent_divide(S, [-2.0 * eta.real * ones, (eta * np.conj(eta)).real * ones])
    return ell + Q, res
