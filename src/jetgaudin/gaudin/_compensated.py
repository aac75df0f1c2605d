r"""Compensated arithmetic with two-word constants for the chain maps (issue 33; ``docs/reliability.md``, "Drift like
round-off"): a constant rounded once puts the same relative error into every step, which the integrals then show as a
linear drift.  The kernels' constants are therefore kept as two words ``hi + lo`` (:func:`exact_tables`, 40-digit
:mod:`mpmath` from the families' ``mp_*`` functions).  The NumPy routes compensate every sum of products with them
and round it once (:func:`acc` here); the compiled kernels round each product with a two-word constant once, low word
counted, and sum plainly (:func:`jetgaudin.gaudin._kernels._tw`, ``_ctw``: the bias is the constant's, not the sum's).
Numba-free: the NumPy routes import it without loading the kernels.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["two_prod", "acc", "split", "exact_tables", "cacc", "scaled_two_point_K0", "KAPPA", "split_constant",
           "times_split"]


def two_prod(a, b):
    """``a·b = p + e`` exactly (real arrays; Dekker's product with Veltkamp's split, no fused multiply-add)."""
    p = a * b
    ta, tb = 134217729.0 * a, 134217729.0 * b  # 2^27 + 1
    ah, bh = ta - (ta - a), tb - (tb - b)
    al, bl = a - ah, b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


#: the generic factor of :func:`split_constant` (the fixed point of cos: a mantissa with no short period); the
#: compiled kernels' ``_split`` (:mod:`jetgaudin.gaudin._kernels`) uses the same one
KAPPA = 0.7390851332151607


def split_constant(c: float) -> tuple[float, float]:
    """``c = a + b`` exactly, ``a = fl(κ c)`` (``κ`` = :data:`KAPPA`; ``b = c − a`` is exact: ``a`` is within a factor
    2 of ``c``): the NumPy twin of :func:`jetgaudin.gaudin._kernels._split`, for :func:`times_split`.

    Why (issue 33; ``docs/reliability.md``, "Drift like round-off"): ``fl(c·x)`` is biased when ``c``'s binary
    mantissa has a short period, as constants typed as decimals do (``0.2``, ``0.4``: over uniformly random mantissas
    of ``x``, ``fl(0.2 x)`` is low by 0.006 ulp on average), which made each orbit of the rational chain drift
    linearly, the sign depending on the orbit."""
    a = c * KAPPA
    return a, c - a


def times_split(x, a, b):
    """``c·x`` with ``c = a + b`` (:func:`split_constant`) as the compiled ``_tw(x, a, b) = fma(x, a, fl(x·b))``: the
    exact ``x·a`` (Dekker's product, :func:`two_prod`: NumPy has no fused multiply-add) plus ``fl(x·b)``, rounded
    once (TwoSum of the two high parts, then the two error terms added to its low part: the correctly rounded
    ``x·a + fl(x·b)`` but where the low part's own rounding falls on a tie; the same bits as ``_tw``).  The final
    rounding is of ``c·x`` plus the generic product ``x·b``'s own rounding error: dithered, unbiased on uniformly
    random mantissas (within ±0.0015 ulp where ``fl(0.2·x)`` is −0.006), within ~0.001 ulp on the step's own
    (``tests/test_chain_drift.py``; real arrays, ``a``, ``b`` of one sign)."""
    p, e = two_prod(x, a)
    y = x * b
    s = p + y
    z = s - p
    return s + (((p - (s - z)) + (y - z)) + e)


def acc(s, e, a, bh, bl):
    """``s + e += a·(bh + bl)`` compensated (real arrays; the NumPy form of the kernels'
    :func:`jetgaudin.gaudin._kernels._acc`: ``s`` the rounded running sum, ``e`` the exact rounding errors of the
    product and of the addition plus ``a·bl``; the sum is ``s + e``, the exact one rounded once)."""
    p, ep = two_prod(a, bh)
    t = s + p
    z = t - s
    return t, e + (ep + ((s - (t - z)) + (p - z)) + a * bl)


def cacc(sr, si, er, ei, a, h, lo):
    """``(sr + er) + i(si + ei) += a·(h + lo)`` compensated (:func:`acc`), ``a`` complex arrays, ``h``, ``lo`` complex
    (broadcasting)."""
    h, lo = np.asarray(h), np.asarray(lo)
    sr, er = acc(sr, er, a.real, h.real, lo.real)
    sr, er = acc(sr, er, -a.imag, h.imag, lo.imag)
    si, ei = acc(si, ei, a.real, h.imag, lo.imag)
    si, ei = acc(si, ei, a.imag, h.real, lo.real)
    return sr, si, er, ei


def split(z) -> tuple[complex, complex]:
    """An ``mpc`` as two words ``hi + lo`` (``hi`` the nearest double, ``lo`` the rest rounded)."""
    import mpmath

    hi = complex(z)
    return hi, complex(z - mpmath.mpc(hi.real, hi.imag))


@lru_cache(maxsize=64)
def exact_tables(model, xi: complex) -> tuple | None:
    """``(f, T, gk)`` of :func:`jetgaudin.gaudin._family_kernel.orbit_constants` as ``(hi, lo)`` pairs (read-only)
    from the family's :mod:`mpmath` functions at 40 digits (:meth:`jetgaudin.families.Family.mp_w`), or ``None``
    for a family without them.  Taylor coefficients by :meth:`~jetgaudin.families.Family.mp_w_taylor` and
    :meth:`~jetgaudin.families.Family.mp_dressing_taylor` (closed-form series for the elliptic family;
    :func:`mpmath.taylor`, whose numerical derivatives work at raised precision, ~1e-40 relative, for the others)."""
    import mpmath

    fam = model.family
    Nmax = max(model.orders)
    f = np.zeros((2, 3, model.M), dtype=complex)
    T = np.zeros((2, len(model.sites), Nmax, fam.n_dressing, 4), dtype=complex)
    try:
        with mpmath.workdps(40):
            x = mpmath.mpc(complex(xi).real, complex(xi).imag)
            for i, (p, N) in enumerate(model.sites):
                o = model.offsets[i]
                W = fam.mp_w_taylor(x - mpmath.mpf(p), N)
                for a in range(3):
                    for k in range(N):
                        f[:, a, o + k] = split((-1) ** k * W[a][k])  # φ_{a,k} = (−1)^k [x^k] w_a
                D = fam.mp_dressing_taylor(mpmath.mpf(p), x, N)
                for q in range(fam.n_dressing):
                    for e in range(4):
                        # every coefficient, not only those of entries nonzero at λ_i: the rational basis entry λ
                        # vanishes at a site λ_i = 0 but its derivative does not (a site of order ≥ 2 at 0 lost it)
                        if all(t == 0 for t in D[q][e]):
                            continue
                        for n in range(N):
                            T[:, i, n, q, e] = split(mpmath.mpmathify(D[q][e][n]))
            gk = np.array([split(z) for z in fam.mp_kernel_constants(x)], dtype=complex).T
    except NotImplementedError:
        return None
    for table in (f, T, gk):
        table.setflags(write=False)
    return f, T, gk


def family_lax(model, X: np.ndarray, xi: complex) -> np.ndarray | None:
    """``ℓ(ξ) = [[u, v], [w, −u]]`` ``(B, 2, 2)`` at the states ``X`` ``(B, 3M)`` from the two-word weights of
    :func:`exact_tables`, each ``ξ^a`` a compensated sum rounded once (the NumPy route's form of the family kernel's
    first lines); ``None`` for a family without :mod:`mpmath` functions."""
    tables = exact_tables(model, complex(xi))
    if tables is None:
        return None
    f = tables[0]  # (2, 3, M): the weights φ_{a,k} as hi + lo
    y = np.asarray(X, dtype=float).reshape(X.shape[:-1] + (model.M, 3))
    # the three components and their real and imaginary parts side by side, axis (..., 3, 2): element for element the
    # same operations in the same order as three separate sums (one NumPy call per term, not six: the NumPy route's
    # speed is the call overhead here)
    hi = np.stack([f[0].real, f[0].imag], axis=-1)  # (3, M, 2)
    lo = np.stack([f[1].real, f[1].imag], axis=-1)
    s = np.zeros(X.shape[:-1] + (3, 2))
    s[..., 2, 0] += model.b
    e = np.zeros_like(s)
    for k in range(model.M):
        s, e = acc(s, e, y[..., k, :, None], hi[:, k], lo[:, k])
    t = s + e
    comp = [t[..., a, 0] + 1j * t[..., a, 1] for a in range(3)]
    x1, x2, u = comp
    L = np.empty(X.shape[:-1] + (2, 2), dtype=complex)
    L[..., 0, 0], L[..., 0, 1], L[..., 1, 0], L[..., 1, 1] = u, x1 - 1j * x2, x1 + 1j * x2, -u
    return L


def family_site_series(model, c: np.ndarray, xi: complex) -> list | None:
    """:func:`jetgaudin.gaudin._dressing.site_series` with ``D``'s Taylor coefficients at the sites
    ``Σ_p c_p (T_p + T_p^lo)`` compensated and rounded once (the two-word tables of :func:`exact_tables`); ``None``
    for a family without :mod:`mpmath` functions."""
    from ..backlund._dressing import adj
    from ..families import _series

    tables = exact_tables(model, complex(xi))
    if tables is None:
        return None
    idx, hi, lo = _series_plan(model, complex(xi))
    # every entry (site, n, e) of D's Taylor coefficients side by side (axis -1), its nonzero terms p in turn: one
    # NumPy call per term for all entries (the NumPy route's speed is the call overhead here)
    z = np.zeros(c.shape[:-1] + (idx.shape[1],))
    sr, si, er, ei = z, z.copy(), z.copy(), z.copy()
    for k in range(idx.shape[0]):
        sr, si, er, ei = cacc(sr, si, er, ei, c[..., idx[k]], hi[k], lo[k])
    D = (sr + er) + 1j * (si + ei)
    out, col = [], 0
    for _, N in model.sites:
        Dt = np.ascontiguousarray(np.moveaxis(D[..., col:col + 4 * N].reshape(c.shape[:-1] + (N, 2, 2)), -3, 0))
        col += 4 * N
        At = adj(Dt)
        det = _series.mul(Dt[..., 0, 0], Dt[..., 1, 1], N) - _series.mul(Dt[..., 0, 1], Dt[..., 1, 0], N)
        out.append((list(Dt), list(At), _series.inv(det, N)))
    return out


@lru_cache(maxsize=64)
def _series_plan(model, xi: complex) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(idx, hi, lo)`` ``(K, J)``: for each entry ``j`` of the sites' Taylor coefficients of ``D`` (site, order
    ``n``, entry ``e``, in that order) its ``k``-th term with a nonzero constant, ``c[idx[k, j]] (hi + lo)[k, j]``,
    the terms in increasing ``p``; an entry with fewer than ``K`` terms is padded with zero constants, which add
    exact zeros (``a·0 = ±0``, ``two_prod``'s error ``0``: the sums and their errors never being ``−0``, the same bits
    as the term left out)."""
    tables = exact_tables(model, xi)
    assert tables is not None  # called by family_site_series after its own check
    T = tables[1]  # (2, S, Nmax, P, 4)
    terms = [[p for p in range(T.shape[3]) if T[0, i, n, p, e] != 0]
             for i, (_, N) in enumerate(model.sites) for n in range(N) for e in range(4)]
    where = [(i, n, e) for i, (_, N) in enumerate(model.sites) for n in range(N) for e in range(4)]
    K = max(1, max(len(t) for t in terms))
    idx = np.zeros((K, len(terms)), dtype=np.intp)
    hi = np.zeros((K, len(terms)), dtype=complex)
    lo = np.zeros_like(hi)
    for j, (t, (i, n, e)) in enumerate(zip(terms, where, strict=True)):
        for k, p in enumerate(t):
            idx[k, j], hi[k, j], lo[k, j] = p, T[0, i, n, p, e], T[1, i, n, p, e]
    for a in (idx, hi, lo):
        a.setflags(write=False)
    return idx, hi, lo


def scaled_two_point_K0(eta: complex, k1, k2) -> tuple:
    r"""``(n2 M0, n2)``: ``M0`` of :func:`jetgaudin.backlund._dressing.real_two_point_M0` times ``n2 = |k|²``, with
    ``k`` first scaled by a power of two (exact) to ``n2`` in ``[1/4, 1)``, computed without a division:
    ``n2 M0 = −n2 diag(η, η̄) + 2i Im η [[|k_2|², −k_1 k̄_2], [−k̄_1 k_2, −|k_2|²]]`` (the compiled kernel's
    arithmetic, :func:`jetgaudin.gaudin._kernels._step`).

    Why (``docs/reliability.md``, "Drift like round-off"): with the normalised ``M0``, ``Re M0_00 = −Re η``
    exactly (the added term is imaginary), so ``Re(λ_i + M0_00)`` is the constant ``λ_i − Re η`` rounded once, with
    the same error at every step (a linear drift: ``n^0.93`` over ``10^3 … 10^5``, and none at a site where
    ``λ_i − Re η`` is exact); ``n2 M0 + n2 λ_i`` rounds the products ``n2 Re η`` and ``n2 λ_i``, which vary with
    the step.  Each product with ``Re η``, ``Im η`` or ``2 Im η`` is :func:`times_split` of the constant split by
    :func:`split_constant`, as the compiled kernel's ``_tw(x, *_split(c))`` (the same bits; ``monic_series`` forms
    ``n2 λ_i`` alike): a decimal ``Im η = 0.2`` rounds its plain products with a bias of its own, which made each
    orbit drift linearly (``n^0.68`` over ``10^3 … 10^6``; ``docs/reliability.md``, "The rational chain's bias per
    orbit")."""
    n2 = np.abs(k1) ** 2 + np.abs(k2) ** 2
    p2 = np.ldexp(1.0, -((np.frexp(n2)[1] + 1) // 2))
    k1, k2 = k1 * p2, k2 * p2
    n2 = np.abs(k1) ** 2 + np.abs(k2) ** 2
    ak2 = np.abs(k2) ** 2
    # every product with η's parts as the compiled kernel's _tw(x, *_split(c)) (times_split: a decimal Im η = 0.2
    # rounds its plain products with a bias of its own, a linear drift per orbit; issue 33), the five in one call
    ra, rb = split_constant(complex(eta).real)
    ia, ib = split_constant(complex(eta).imag)
    x = np.stack(np.broadcast_arrays(n2, n2, ak2, k1.imag, k1.real))
    a = np.array([ra, ia, 2.0 * ia, 2.0 * ia, 2.0 * ia]).reshape((5,) + (1,) * n2.ndim)
    b = np.array([rb, ib, 2.0 * ib, 2.0 * ib, 2.0 * ib]).reshape(a.shape)
    er, ein, eik, t_k1i, t_k1r = times_split(x, a, b)  # Re η n2, Im η n2, 2 Im η times |k2|², k1i, k1r
    ei = ein - eik  # Im η (n2 − 2|k2|²)
    tk1 = t_k1i - 1j * t_k1r  # −t k1, t = 2i Im η
    K0 = np.empty(np.shape(k1) + (2, 2), dtype=complex)
    K0[..., 0, 0] = -er - 1j * ei  # −η n2 + t |k2|²
    K0[..., 0, 1] = tk1 * np.conj(k2)
    K0[..., 1, 0] = (-tk1.real + 1j * tk1.imag) * k2  # −t k̄1 = −conj(−t k1)
    K0[..., 1, 1] = -er + 1j * ei  # −η̄ n2 − t |k2|²
    return K0, n2
