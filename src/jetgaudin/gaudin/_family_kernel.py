r"""One compiled (Numba) kernel of the real two-point map for every family (``docs/families.md`` §compiled).

Per step everything is linear in the state with constants that depend only on ``ξ``, the sites and the family,
hoisted out of the loop by :func:`orbit_constants`:

* ``f[a, c] = φ_{a,k_c}(ξ − λ_{i_c})``: ``ξ^a(ξ) = b δ_{a3} + Σ_c f[a, c] y^a_c``, so ``ℓ(ξ)`` costs ``3M`` products;
* ``T[i, n, e, t]``: the Taylor coefficients at the site ``λ_i`` of the dressing basis ``B_p``
  (:meth:`jetgaudin.families.Family.dressing_taylor`), stored sparsely: entry ``e`` of ``D`` (``00, 01, 10, 11``)
  is ``Σ_t c_{pidx[e, t]} T[i, n, e, t]`` (two terms per entry for the rational and trigonometric bases);
* ``rule``, ``gk``: the family's gauge rule as an id and its constants (:attr:`jetgaudin.families.Family.kernel_rule`,
  :meth:`~jetgaudin.families.Family.kernel_constants`): ``0`` rational (``K = λ + M_0`` of eq. (mm), ``gk[0] = ξ``),
  ``1`` trigonometric (:func:`jetgaudin.families.trigonometric.gauge_rule`, ``gk = (e^{−iγξ}, e^{−iγξ̄},
  e^{iγξ}, e^{iγξ̄}, sin(γ(ξ − ξ̄)))``), ``2`` elliptic (the null vector of spectrality,
  :func:`jetgaudin.families.elliptic.spectral_null_vector`, as the largest of the four generalised cross products of
  three of its four rows; ``gk = (w_a(ξ − λ_0), w_a(ξ̄ − λ_0))``).

A step: ``ν1`` (the root of ``u² + vw`` closest to the previous one), the eigenvector ``k1`` of ``ℓ(ξ)``, the
coefficients ``c_p`` by the rule, then per site ``D``'s Taylor coefficients ``D_n = Σ_p c_p T[i, n, p]``,
``adj D_n``, ``1/det D`` as a series (Cauchy square, then inversion) and the new principal parts
``ℓ̃_k = Σ_{j ≥ k} Σ_{a+c+e=j−k} D_a ℓ_j (adj D)_c g_e`` — the arithmetic of
:func:`jetgaudin.gaudin.maps.dress_sites`.  No residual check, no imaginary residue (as the rational kernel of
:mod:`jetgaudin.gaudin._kernels`); the orbits agree with the NumPy route to round-off
(``tests/test_trigonometric_kernels.py``).

Sites of order 1 and 2 (the Clebsch top is one elliptic site of order 2) take unrolled forms of the same arithmetic
(:func:`_site1`, :func:`_site2`), the elliptic rule its null vector with shared minors (:func:`_null_vector`), the
rule and the step are inlined (no calls, no reference counting per step): the same floating-point operations in the
same order as the general forms, so the same bits (``tests/test_family_step.py``; ``docs/performance.md``, "The
family kernel's map step").  Numba caches by file: a module that inlines the step (``jetgaudin._exact_chain_loop``)
needs its cache cleared after an edit here.
"""

from __future__ import annotations

import cmath
from functools import lru_cache

import numpy as np
from numba import njit, prange

from ..backlund.kernels._scalar import _bits, _from_bits
from ._compensated import exact_tables
from ._kernels import _abs2, _ctw, _put_site, _split, _tw  # first: it applies the Bäcklund kernels' Numba target


@njit(cache=True, inline="always")
def _half_scale(x):
    """``math.ldexp(1.0, −⌊(e + 1)/2⌋)`` with ``e = math.frexp(x)[1]`` (``x = m 2^e``, ``|m| in [1/2, 1)``; ``e = 0``
    for ``x`` zero, infinite or NaN, as C's ``frexp``): the power of two that scales ``x`` into ``[1/4, 1)`` when
    applied twice, from the bits of ``x`` (no library calls; equal to the ``frexp``/``ldexp`` form for every double,
    ``tests/test_family_step.py``).  ``e`` lies in ``[−1073, 1024]``, so the result is always a normal double."""
    be = (_bits(x) >> 52) & 0x7FF
    if be == 0x7FF or x == 0:
        e = 0
    elif be == 0:  # subnormal: the exponent of x 2^54 (exact), less 54
        e = ((_bits(x * 18014398509481984.0) >> 52) & 0x7FF) - 1022 - 54
    else:
        e = be - 1022
    return _from_bits((1023 - (e + 1) // 2) << 52)


@njit(cache=True, inline="always")
def _wk(gk, j, G, k):
    """``w·k`` for the constant ``w = gk[j] + gk[G + j]`` (two words), the low word counted (:func:`._kernels._ctw`)."""
    return _ctw(k, gk[j], gk[G + j])


@njit(cache=True, inline="always")
def _elliptic_rows(k1, k2, gk, o, G):
    """The two rows of the spectrality system for one point: ``B_0 k = k``, ``B_1 k = w1 (k2, k1)``,
    ``B_2 k = w2 (−i k2, i k1)``, ``B_3 k = w3 (k1, −k2)``, with ``w_a = gk[o + a − 1]`` plus its low word
    ``gk[G + o + a − 1]`` (:func:`orbit_constants`), each product rounded once (:func:`_wk`)."""
    w2k2 = _wk(gk, o + 1, G, k2)
    w2k1 = _wk(gk, o + 1, G, k1)
    w3k2 = _wk(gk, o + 2, G, k2)
    return (k1, _wk(gk, o, G, k2), -1j * w2k2, _wk(gk, o + 2, G, k1)), (k2, _wk(gk, o, G, k1), 1j * w2k1, -w3k2)


@njit(cache=True, inline="always")
def _norm2(R):
    return _abs2(R[0]) + _abs2(R[1]) + _abs2(R[2]) + _abs2(R[3])


@njit(cache=True, inline="always")
def _candidate(R0, R1, R2, best, c):
    """The cofactor vector ``n`` of the rows ``R0, R1, R2`` (4-tuples) into ``c[:4]`` where ``|n|² > best``; returns
    the larger.  ``n_0 = det(cols 1, 2, 3)``, ``n_1 = −det(0, 2, 3)``, ``n_2 = det(0, 1, 3)``, ``n_3 = −det(0, 1, 2)``,
    each a 3 × 3 determinant expanded along ``R0`` (``Σ ± R0[c] · minor``) with the 2 × 2 minors of ``R1, R2``
    computed once (each is shared by two cofactors; the same operations as four separate expansions, bit for bit)."""
    m23 = R1[2] * R2[3] - R1[3] * R2[2]
    m13 = R1[1] * R2[3] - R1[3] * R2[1]
    m12 = R1[1] * R2[2] - R1[2] * R2[1]
    m03 = R1[0] * R2[3] - R1[3] * R2[0]
    m02 = R1[0] * R2[2] - R1[2] * R2[0]
    m01 = R1[0] * R2[1] - R1[1] * R2[0]
    n0 = R0[1] * m23 - R0[2] * m13 + R0[3] * m12
    n1 = -(R0[0] * m23 - R0[2] * m03 + R0[3] * m02)
    n2 = R0[0] * m13 - R0[1] * m03 + R0[3] * m01
    n3 = -(R0[0] * m12 - R0[1] * m02 + R0[2] * m01)
    s = _abs2(n0) + _abs2(n1) + _abs2(n2) + _abs2(n3)
    if s > best:
        c[0] = n0
        c[1] = n1
        c[2] = n2
        c[3] = n3
        return s
    return best


@njit(cache=True, inline="always")
def _null_vector(A0, A1, A2, A3, c):
    """The null vector of the rank-3 system with rows ``A0 … A3`` (4-tuples) into ``c[:4]``: the cofactor vector of
    rows ``0, 1, 2`` unless its ``|n|²`` is below ``1e-4`` times the product of the three rows' ``|·|²`` (Hadamard-
    relative), then of rows ``3, 0, 1``, ``2, 3, 0``, ``1, 2, 3`` in turn (skipping row 3, 2, 1, 0; any order of the
    three rows: the null vector is defined up to a factor) until one is large enough, the largest kept; returns its
    ``|n|²`` (``−1``, ``c`` untouched, where every ``|n|²`` is NaN).  Unrolled: no tuple indexing at run time."""
    rn0 = _norm2(A0)
    rn1 = _norm2(A1)
    rn2 = _norm2(A2)
    best = _candidate(A0, A1, A2, -1.0, c)
    if not best > 1e-4 * rn0 * rn1 * rn2:
        rn3 = _norm2(A3)
        best = _candidate(A3, A0, A1, best, c)
        if not best > 1e-4 * rn3 * rn0 * rn1:
            best = _candidate(A2, A3, A0, best, c)
            if not best > 1e-4 * rn2 * rn3 * rn0:
                best = _candidate(A1, A2, A3, best, c)
    return best


@njit(cache=True, inline="always")
def _elliptic_coefficients(gk, a1, a2, c):
    """``(S_0, S_1, S_2, S_3)`` into ``c[:4]``: ``D(ξ) k_1 = 0``, ``D(ξ̄) k_2 = 0`` with ``D = S_0 + Σ S_a W_a σ_a``,
    ``k_2 = (−ā_2, ā_1)``; the null vector of the rank-3 system ``A`` (4 × 4) as the cofactor vector of the three rows
    whose cofactors are largest.  Tuples, no arrays: the GPU kernel (:mod:`jetgaudin.gpu`) compiles it too."""
    G = gk.shape[0] // 2
    A0, A1 = _elliptic_rows(a1, a2, gk, 0, G)
    A2, A3 = _elliptic_rows(-a2.conjugate(), a1.conjugate(), gk, 3, G)
    best = _null_vector(A0, A1, A2, A3, c)
    # scaled by a power of two (exact) to |c|² in [1/4, 1): unnormalised (the mantissas, hence the rounding of det D,
    # vary from step to step) but of size 1 for states of any size
    scale = _half_scale(best)
    for r in range(4):
        c[r] *= scale


@njit(cache=True, inline="always")
def _pq(p, q, gk, i, j):
    """``p·gk[i] + q·gk[j]`` (real ``p, q``; the constants with their low words ``gk[i + 5]``, ``gk[j + 5]``: the
    trigonometric rule's five), each product rounded once (:func:`._kernels._tw`)."""
    hi, hj, li, lj = gk[i], gk[j], gk[i + 5], gk[j + 5]
    return complex(_tw(p, hi.real, li.real) + _tw(q, hj.real, lj.real),
                   _tw(p, hi.imag, li.imag) + _tw(q, hj.imag, lj.imag))


@njit(cache=True, inline="always")
def _coefficients(rule, gk, a1, a2, c):
    """The dressing coefficients ``c`` (P,) of the gauge rule ``rule`` from the eigenvector ``(a1, a2)`` (rules 0
    and 1: P = 6; a new family adds its rule here)."""
    p = _abs2(a1)
    q = _abs2(a2)
    n = p + q
    # the eigenvector scaled by a power of two (exact: the rounding is kept) to n in [1/4, 1): D unnormalised but of
    # the size of its normalised form for states of any size
    sc = _half_scale(n)
    a1 = a1 * sc
    a2 = a2 * sc
    p = _abs2(a1)
    q = _abs2(a2)
    n = p + q
    # every rule leaves D unnormalised (times n, or the cofactors as they come): a normalised D has the same
    # determinant at every step, whose reciprocal then rounds alike at every step (a linear drift of the integrals;
    # gaudin.maps.monic_series, issue 33); the dressing D ℓ adj D / det D does not depend on D's scale
    if rule == 0:  # rational: n (1, M0_00, M0_01, M0_10, 1, M0_11), M0 of backlund._dressing.real_two_point_M0
        # each product with η's parts split and rounded once (gaudin._kernels._split: a decimal η, 0.2 = the double
        # nearest 1/5, rounds its products with a bias of its own, a linear drift of each orbit's integrals)
        eta = gk[0]
        ra, rb = _split(eta.real)
        ia, ib = _split(eta.imag)
        er = _tw(n, ra, rb)
        ei = _tw(n, ia, ib) - _tw(q, 2.0 * ia, 2.0 * ib)
        t1 = complex(_tw(a1.imag, 2.0 * ia, 2.0 * ib), -_tw(a1.real, 2.0 * ia, 2.0 * ib))  # −cc a1, cc = 2i Im η
        c[0] = n
        c[1] = complex(-er, -ei)  # −η n + cc q
        c[2] = t1 * a2.conjugate()
        c[3] = complex(-t1.real, t1.imag) * a2  # −cc ā1 = −conj(−cc a1)
        c[4] = n
        c[5] = complex(-er, ei)  # −η̄ n − cc q
    elif rule == 2:
        _elliptic_coefficients(gk, a1, a2, c)
    else:  # trigonometric: families.trigonometric.gauge_rule("symmetric")
        d = -0.5j  # the constants e^{∓iγξ}, e^{∓iγξ̄} (gk[0..3]) and sin(γ(ξ − ξ̄)) (gk[4]), low words gk[5..9]
        c[0] = _pq(p, q, gk, 0, 1) * d
        c[1] = -_pq(p, q, gk, 2, 3) * d
        t = a1 * a2.conjugate()
        c[2] = -_wk(gk, 4, 5, t)
        t = a1.conjugate() * a2
        c[3] = -_wk(gk, 4, 5, t)
        c[4] = _pq(q, p, gk, 0, 1) * d
        c[5] = -_pq(q, p, gk, 2, 3) * d


@njit(cache=True, inline="always")
def _entry(c, T, pidx, i, m, e):
    """Entry ``e`` of ``D_m`` at site ``i``: ``Σ_t c_p (T_hi + T_lo)``, interleaved two words, each product's low
    word counted (:func:`._kernels._ctw`); the zero padding (a term of another entry) adds nothing."""
    s = 0j
    for t in range(0, pidx.shape[1], 2):
        h = T[i, m, e, t]
        if h != 0:
            s += _ctw(c[pidx[e, t]], h, T[i, m, e, t + 1])
    return s


@njit(cache=True, inline="always")
def _dl(d0, d1, d2, d3, p0, p1, p2, p3):
    """``K = D_a ℓ_j`` (2 × 2, row-major)."""
    return d0 * p0 + d1 * p2, d0 * p1 + d1 * p3, d2 * p0 + d3 * p2, d2 * p1 + d3 * p3


@njit(cache=True, inline="always")
def _add(s, ge, k, a0, a1, a2, a3):
    """``s += g_e K (adj D)_c`` for the entries ``00, 01, 10`` (``(ℓ̃)_11 = −(ℓ̃)_00``, not computed), ``adj D_c =
    (a0, a1, a2, a3)``."""
    k00, k01, k10, k11 = k
    return (s[0] + ge * (k00 * a0 + k01 * a2), s[1] + ge * (k00 * a1 + k01 * a3),
            s[2] + ge * (k10 * a0 + k11 * a2))


@njit(cache=True, inline="always")
def _ell(x, cj):
    """``ℓ_j`` of coordinate ``cj`` as ``(P_00, P_01, P_10, P_11)``."""
    return (complex(x[3 * cj + 2]), complex(x[3 * cj], -x[3 * cj + 1]), complex(x[3 * cj], x[3 * cj + 1]),
            -complex(x[3 * cj + 2]))


@njit(cache=True, inline="always")
def _site1(x, out, c, T, pidx, i, o):
    """Site ``i`` (at coordinate ``o``) of order 1: :func:`_site` at ``N = 1`` unrolled, the same operations in the
    same order (bit for bit, ``tests/test_family_step.py``): ``ℓ̃_0 = D_0 ℓ_0 adj D_0 / det D_0``."""
    d0 = _entry(c, T, pidx, i, 0, 0)
    d1 = _entry(c, T, pidx, i, 0, 1)
    d2 = _entry(c, T, pidx, i, 0, 2)
    d3 = _entry(c, T, pidx, i, 0, 3)
    det0 = 0j
    det0 += d0 * d3 - d1 * d2
    g0 = 1.0 / det0
    p = _ell(x, o)
    s = _add((0j, 0j, 0j), g0, _dl(d0, d1, d2, d3, p[0], p[1], p[2], p[3]), d3, -d1, -d2, d0)
    _put_site(out, o, s[0], s[1], s[2])


@njit(cache=True, inline="always")
def _site2(x, out, c, T, pidx, i, o):
    """Site ``i`` of order 2 (the Clebsch top): :func:`_site` at ``N = 2`` unrolled, the same operations in the same
    order (bit for bit, ``tests/test_family_step.py``)."""
    d0 = _entry(c, T, pidx, i, 0, 0)
    d1 = _entry(c, T, pidx, i, 0, 1)
    d2 = _entry(c, T, pidx, i, 0, 2)
    d3 = _entry(c, T, pidx, i, 0, 3)
    e0 = _entry(c, T, pidx, i, 1, 0)
    e1 = _entry(c, T, pidx, i, 1, 1)
    e2 = _entry(c, T, pidx, i, 1, 2)
    e3 = _entry(c, T, pidx, i, 1, 3)
    det0 = 0j
    det0 += d0 * d3 - d1 * d2
    det1 = 0j
    det1 += d0 * e3 - d1 * e2
    det1 += e0 * d3 - e1 * d2
    g0 = 1.0 / det0
    t = 0j
    t += det1 * g0
    g1 = -t * g0
    p = _ell(x, o)
    q = _ell(x, o + 1)
    k0 = _dl(d0, d1, d2, d3, p[0], p[1], p[2], p[3])  # D_0 ℓ_0
    k1 = _dl(d0, d1, d2, d3, q[0], q[1], q[2], q[3])  # D_0 ℓ_1
    k2 = _dl(e0, e1, e2, e3, q[0], q[1], q[2], q[3])  # D_1 ℓ_1
    s = _add((0j, 0j, 0j), g0, k0, d3, -d1, -d2, d0)  # k = 0: j = 0
    s = _add(s, g1, k1, d3, -d1, -d2, d0)  # j = 1, a = 0, c = 0, e = 1
    s = _add(s, g0, k1, e3, -e1, -e2, e0)  # j = 1, a = 0, c = 1, e = 0
    s = _add(s, g0, k2, d3, -d1, -d2, d0)  # j = 1, a = 1, c = 0, e = 0
    _put_site(out, o, s[0], s[1], s[2])
    s = _add((0j, 0j, 0j), g0, k1, d3, -d1, -d2, d0)  # k = 1: j = 1, a = 0
    _put_site(out, o + 1, s[0], s[1], s[2])


@njit(cache=True)
def _site(x, out, c, T, pidx, i, o, N, Dt, At, det, g, P):
    """Site ``i`` (coordinates ``o … o + N − 1``) of any order ``N``: ``D``'s Taylor coefficients, ``adj D``, ``1/det
    D`` as a series and the new principal parts (module docstring) into ``out``."""
    for m in range(N):
        for e in range(4):  # Σ c_p (T_hi + T_lo): interleaved two words, each product's low word counted (_ctw)
            s = 0j
            for t in range(0, pidx.shape[1], 2):
                if T[i, m, e, t] != 0:  # zero padding (a term of another entry) adds nothing
                    s += _ctw(c[pidx[e, t]], T[i, m, e, t], T[i, m, e, t + 1])
            Dt[m, e] = s
        At[m, 0] = Dt[m, 3]
        At[m, 1] = -Dt[m, 1]
        At[m, 2] = -Dt[m, 2]
        At[m, 3] = Dt[m, 0]
        s = 0j
        for a in range(m + 1):
            s += Dt[a, 0] * Dt[m - a, 3] - Dt[a, 1] * Dt[m - a, 2]
        det[m] = s
    g[0] = 1.0 / det[0]
    for m in range(1, N):
        s = 0j
        for a in range(1, m + 1):
            s += det[a] * g[m - a]
        g[m] = -s * g[0]
    for j in range(N):
        cj = o + j
        P[j, 0] = complex(x[3 * cj + 2])
        P[j, 1] = complex(x[3 * cj], -x[3 * cj + 1])
        P[j, 2] = complex(x[3 * cj], x[3 * cj + 1])
        P[j, 3] = -complex(x[3 * cj + 2])
    for k in range(N):
        s00 = 0j  # (ℓ̃_k)_11 is −(ℓ̃_k)_00 (traceless): not computed
        s01 = 0j
        s10 = 0j
        for j in range(k, N):
            for a in range(j - k + 1):
                # K = D_a ℓ_j
                k00 = Dt[a, 0] * P[j, 0] + Dt[a, 1] * P[j, 2]
                k01 = Dt[a, 0] * P[j, 1] + Dt[a, 1] * P[j, 3]
                k10 = Dt[a, 2] * P[j, 0] + Dt[a, 3] * P[j, 2]
                k11 = Dt[a, 2] * P[j, 1] + Dt[a, 3] * P[j, 3]
                for cc in range(j - k - a + 1):
                    ge = g[j - k - a - cc]
                    s00 += ge * (k00 * At[cc, 0] + k01 * At[cc, 2])
                    s01 += ge * (k00 * At[cc, 1] + k01 * At[cc, 3])
                    s10 += ge * (k10 * At[cc, 0] + k11 * At[cc, 2])
        _put_site(out, o + k, s00, s01, s10)


@njit(cache=True, inline="always")
def _step(x, out, b, nu_prev, f, rule, gk, T, pidx, site_off, site_n, c, Dt, At, det, g, P):
    """One step from ``x`` (3M,) into ``out`` (3M,); returns the ``ν1`` used."""
    M = x.shape[0] // 3
    # f[a] + f[a + 3]: the weights as two words (orbit_constants), each product rounded once (_tw), summed plainly
    x1r, x1i, x2r, x2i, x3r, x3i = 0.0, 0.0, 0.0, 0.0, b, 0.0
    for k in range(M):
        y1, y2, y3 = x[3 * k], x[3 * k + 1], x[3 * k + 2]
        x1r += _tw(y1, f[0, k].real, f[3, k].real)
        x1i += _tw(y1, f[0, k].imag, f[3, k].imag)
        x2r += _tw(y2, f[1, k].real, f[4, k].real)
        x2i += _tw(y2, f[1, k].imag, f[4, k].imag)
        x3r += _tw(y3, f[2, k].real, f[5, k].real)
        x3i += _tw(y3, f[2, k].imag, f[5, k].imag)
    x1 = complex(x1r, x1i)
    x2 = complex(x2r, x2i)
    x3 = complex(x3r, x3i)
    u = x3
    v = x1 - 1j * x2
    w = x1 + 1j * x2
    r = cmath.sqrt(u * u + v * w)
    if (r.conjugate() * nu_prev).real < 0:
        r = -r
    # eigenvector of ℓ(ξ) for ν: (v, ν − u) or (u + ν, w), whichever is larger (backlund._dressing.eigenvector)
    if _abs2(v) + _abs2(r - u) >= _abs2(u + r) + _abs2(w):
        a1 = v
        a2 = r - u
    else:
        a1 = u + r
        a2 = w
    _coefficients(rule, gk, a1, a2, c)
    for i in range(site_off.shape[0]):
        N = site_n[i]
        if N == 1:
            _site1(x, out, c, T, pidx, i, site_off[i])
        elif N == 2:
            _site2(x, out, c, T, pidx, i, site_off[i])
        else:
            _site(x, out, c, T, pidx, i, site_off[i], N, Dt, At, det, g, P)
    return r


@njit(cache=True)
def orbit_loop(x, y, rows, final, b, nu, f, rule, gk, T, pidx, site_off, site_n, c, Dt, At, det, g, P, steps,
               save_every):
    """The stepping loop of :func:`run_orbit` on caller-given scratch, without allocations (the GPU kernel of
    :mod:`jetgaudin.gpu` calls it for one orbit per thread, compiled for the device, with thread-local scratch):
    ``x`` (3M,) holds the start state and ``y`` (3M,) is scratch (both overwritten), ``rows[j] = x_{j·save_every}``,
    ``final`` the last state; ``c`` (P,) zeroed, ``Dt, At, P`` (Nmax, 4), ``det, g`` (Nmax,).  Returns the last
    ``ν1``."""
    n = x.shape[0]
    for i in range(n):
        rows[0, i] = x[i]
    left = save_every  # a countdown to the next saved row (no integer division per step)
    j = 0
    for _ in range(steps):
        nu = _step(x, y, b, nu, f, rule, gk, T, pidx, site_off, site_n, c, Dt, At, det, g, P)
        x, y = y, x
        left -= 1
        if left == 0:
            left = save_every
            j += 1
            for i in range(n):
                rows[j, i] = x[i]
    for i in range(n):
        final[i] = x[i]
    return nu


@njit(cache=True)
def run_orbit(x0, b, nu0, f, rule, gk, T, pidx, n_basis, site_off, site_n, steps, save_every):
    """``steps`` steps from ``x0``; returns ``(rows (steps//save_every + 1, 3M), final state (3M,), last ν1)``
    (:func:`orbit_loop`)."""
    n = x0.shape[0]
    rows = np.empty((steps // save_every + 1, n))
    final = np.empty(n)
    Nmax = T.shape[1]
    nu = orbit_loop(x0.copy(), np.empty(n), rows, final, b, nu0, f, rule, gk, T, pidx, site_off, site_n,
                    np.zeros(n_basis, dtype=np.complex128), np.empty((Nmax, 4), dtype=np.complex128),
                    np.empty((Nmax, 4), dtype=np.complex128), np.empty(Nmax, dtype=np.complex128),
                    np.empty(Nmax, dtype=np.complex128), np.empty((Nmax, 4), dtype=np.complex128), steps, save_every)
    return rows, final, nu


@njit(cache=True, parallel=True)
def run_batch(X0, b, nu0, f, rule, gk, T, pidx, n_basis, site_off, site_n, steps, save_every):
    """A batch of independent orbits ``X0`` (B, 3M), one :func:`run_orbit` per iteration of a ``prange`` loop (all
    cores): ``(rows (steps//save_every, B, 3M) without the start states, final (B, 3M), last ν1 (B,))``; every
    orbit gets the bits of its single run."""
    B, n = X0.shape
    rows = np.empty((steps // save_every, B, n))
    final = np.empty((B, n))
    last = np.empty(B, dtype=np.complex128)
    for i in prange(B):
        r, x, nu = run_orbit(X0[i].copy(), b, nu0[i], f, rule, gk, T, pidx, n_basis, site_off, site_n, steps,
                             save_every)
        rows[:, i] = r[1:]
        final[i] = x
        last[i] = nu
    return rows, final, last


def orbit_constants(model, xi):
    """``(f, rule, gk, T, pidx, P, site_off, site_n)``: the per-orbit constants of :func:`run_orbit` (module
    docstring), each **as two words** ``hi + lo`` where the family gives its functions in :mod:`mpmath`
    (:meth:`jetgaudin.families.Family.mp_w`; every family here): ``f`` ``(6, M)`` (rows ``3..5`` the low words),
    ``gk`` ``(2G,)`` (the low words after the high ones), and ``T`` ``(S, Nmax, 4, 2K)`` with term ``t``'s high
    word at ``2t`` and its low word at ``2t + 1`` (``pidx[e, 2t] = pidx[e, 2t + 1]``); the kernel rounds each product
    with the constants once, the low word counted (:func:`jetgaudin.gaudin._kernels._tw`, ``_ctw``).

    Why two words (issue 33; ``docs/reliability.md``, "Drift like round-off"): ``ℓ(ξ)`` (``f``), the spectrality of
    ``D`` at ``ξ, ξ̄`` (``gk``) and ``D``'s Taylor coefficients at the sites (``T``) must be those of one ``ξ`` for
    the step to preserve the integrals; a constant rounded once repeats its error at every step, so the step misses
    the integrals by the same ~1e-16 each time: a linear drift.  With ``hi + lo`` (~1e-32) and each product with them
    rounded once (the low word alone, added to a rounded product, changes nothing), the remaining errors are roundings
    of quantities that vary from step to step (a random walk)."""
    fam = model.family
    Nmax = max(model.orders)
    P = fam.n_dressing
    exact = exact_tables(model, complex(xi))
    if exact is None:  # a family without mpmath functions: the double constants, no low words
        f1 = np.zeros((3, model.M), dtype=complex)
        full1 = np.zeros((len(model.sites), Nmax, P, 4), dtype=complex)
        for i, (p, N) in enumerate(model.sites):
            o = model.offsets[i]
            for a in range(3):
                f1[a, o:o + N] = fam.phi(a + 1, complex(xi) - p, N)
            Ti = fam.dressing_taylor(p, N, complex(xi)) if fam.dressing_needs_xi else fam.dressing_taylor(p, N)
            full1[i, :N] = Ti.reshape(N, P, 4)
        gk1 = np.asarray(fam.kernel_constants(complex(xi)), dtype=complex)
        f2, full, gk2 = np.stack([f1, 0 * f1]), np.stack([full1, 0 * full1]), np.stack([gk1, 0 * gk1])
    else:
        f2, full, gk2 = exact
    f = f2.reshape(6, model.M)
    used = np.any(full[0] != 0, axis=(0, 1))  # (P, 4): which basis matrices feed which entry
    K = max(1, int(used.sum(axis=0).max()))
    pidx = np.zeros((4, 2 * K), dtype=np.int64)
    T = np.zeros((len(model.sites), Nmax, 4, 2 * K), dtype=complex)
    for e in range(4):  # interleaved: term t's high word at 2t, its low word at 2t + 1 (zero padding adds nothing)
        for t, p in enumerate(np.flatnonzero(used[:, e])):
            pidx[e, 2 * t] = pidx[e, 2 * t + 1] = p
            T[:, :, e, 2 * t] = full[0, :, :, p, e]
            T[:, :, e, 2 * t + 1] = full[1, :, :, p, e]
    return (f, int(fam.kernel_rule), gk2.reshape(-1), T, pidx, P, np.array(model.offsets, dtype=np.int64),
            np.array(model.orders, dtype=np.int64))


#: points of the vertical segment ``[Re η, η]`` on which :func:`branch_rule` continues ``ν`` (``n`` steps)
SEGMENT_STEPS = 64


@lru_cache(maxsize=64)
def segment_constants(model, eta, n: int = SEGMENT_STEPS) -> np.ndarray:
    """``F[k, a, c] = φ_{a,k_c}(t_k − λ_{i_c})`` at ``t_k = Re η + i (k/n) Im η``, ``k = 0..n``, shape
    ``(n + 1, 3, M)`` (every family: :meth:`jetgaudin.families.Family.phi`; rational ``φ = x^{−k−1}``), so that
    ``ξ^a(t_k) = b δ_{a3} + Σ_c F[k, a, c] y^a_c`` costs ``3M`` products per point (the constants of
    :func:`branch_rule`, computed once per ``(model, η)`` and read-only)."""
    eta = complex(eta)
    t = eta.real + 1j * eta.imag * np.arange(n + 1) / n
    F = np.zeros((n + 1, 3, model.M), dtype=complex)
    for i, (p, N) in enumerate(model.sites):
        o = model.offsets[i]
        for a in range(3):
            F[:, a, o:o + N] = model.family.phi(a + 1, t - p, N).T
    F.setflags(write=False)
    return F


@njit(cache=True, parallel=True)
def branch_rule(X, b, F, sheet):
    r"""The branch rule of ``ν(η)`` compiled, for every family: for each state ``X[i]`` (real, (B, 3M)) the root
    ``√ν²(t_0) > 0`` at ``t_0 = Re η`` continued over the points ``t_k`` of :func:`segment_constants`, each time
    the root of ``ν²(t_k) = u² + vw`` nearer to the previous one — the numerical rule of
    :func:`jetgaudin.gaudin._curve._nu_numerical` at its first ``n``.  Returns ``(sheet · ν(η) (B,), ok (B,))``;
    ``ok`` is false where a step moved ``ν`` by more than a quarter of its size (the nearer root would not be
    unambiguous: a branch point on or near the segment), ``ν`` vanished or is not finite: the caller takes the
    exact NumPy rule for those states."""
    B, n3 = X.shape
    M = n3 // 3
    K = F.shape[0]
    nu = np.empty(B, dtype=np.complex128)
    ok = np.ones(B, dtype=np.bool_)
    for i in prange(B):  # the orbits on all cores (each its own arithmetic: the same bits on any number of threads)
        v = 0j
        for k in range(K):
            x1 = 0j
            x2 = 0j
            x3 = complex(b)
            for c in range(M):
                x1 += F[k, 0, c] * X[i, 3 * c]
                x2 += F[k, 1, c] * X[i, 3 * c + 1]
                x3 += F[k, 2, c] * X[i, 3 * c + 2]
            r = np.sqrt(x3 * x3 + (x1 - 1j * x2) * (x1 + 1j * x2))
            if k > 0:
                if abs(r - v) > abs(r + v):
                    r = -r
                if not abs(r - v) <= 0.25 * max(abs(r), abs(v)):
                    ok[i] = False
            v = r
        if not (v != 0 and np.isfinite(v.real) and np.isfinite(v.imag)):
            ok[i] = False
        nu[i] = sheet * v
    return nu, ok
