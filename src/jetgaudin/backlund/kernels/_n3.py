r"""The N = 3 compiled route: the dressing step in real form (:func:`_step3`, :func:`run_orbit3`).

**Real form of the step.**  For a real state ``ℓ_m = y_m·σ`` (``u = y³``, ``v = y¹ − i y²``, ``w = y¹ + i y²``,
``y_0 = b e_3``) and the ``M0`` of eq. (mm) with ``η_1 = η̄_2 = η = a + ic`` and ``κ = 1/s̄`` (reality, eq. (X))
(:func:`._scalar._m0_from_k`):

    ``M0 = −a I + i c (n̂·σ)``,   ``n̂_1 + i n̂_2 = −2 k̄_1 k_2/|k|²``,   ``n̂_3 = (|k_2|² − |k_1|²)/|k|²``

with ``k`` the eigenvector of ``ℓ(η)`` for ``ν1`` and ``n̂`` a real unit vector (``|n̂|² = (|k_1|² + |k_2|²)²/|k|⁴``).
Write ``K y = n̂ × y`` and ``m = −a``.  With ``[n̂·σ, y·σ] = 2i (n̂ × y)·σ`` and
``(n̂·σ)(y·σ)(n̂·σ) = (2 (n̂·y) n̂ − y)·σ``, ``adj M0 = m I − i c n̂·σ`` and

    ``R(λ) = (λ + M0) ℓ(λ) adj(λ + M0) = D(λ) ℓ(λ) − 2c Z(λ)``,   ``D(λ) = (λ − η)(λ − η̄) = λ² + δ1 λ + δ2``,
    ``Z(λ) = K (λ + m − c K) ℓ(λ)``,

all real 3×3 maps of the vectors ``y_m`` (``T1 = 2m − 2cK``, ``T2 = |η|² − 2mcK + 2c²K²`` are the products
``M0 ℓ + ℓ adj M0``, ``M0 ℓ adj M0`` of the generic route).  Hence the new state of the dressing relation
eq. (128), ``ℓ̆ = R/D`` (exact division), is ``ỹ_j = y_j − 2c W_j`` (j = 1, 2, 3) with ``W = Z/D``:

    ``Z_{−1} = K y_0``,   ``Z_k = K v_k``,   ``v_k = y_{k+1} + m y_k − c K y_k``  (k = 0..3, ``y_4 = 0``),
    ``W_{k+2} + δ1 W_{k+1} + δ2 W_k = Z_k``   (k = −1..3; ``W_j = 0`` outside j = 1..3).

Five vector equations for three unknowns: three are solved, the other two are the residual (exactness of the
division, i.e. the eigenvector condition).  Top-down (``|η| < 1``): k = −1, 0, 1 give ``W_1, W_2, W_3`` (this
is Appendix 1's lower-triangular affine map ``X̆ = Φ X + X_0`` of eq. (2p)); bottom-up (``|η| ≥ 1``): k = 3, 2,
1 give ``W_3, W_2, W_1`` (the same map, evaluated without the cancellation of the powers of ``η`` that costs the
top-down form accuracy for ``|η| > 1``).  The two recurrences have the same shape, so one set of per-run
constants (:func:`_constants3`) and selects of the ``Z_k`` give both without a branch; the residual is that of
the unused equations of the complex division, ``2|c|`` times the residual of the ``Z`` equations (k = 0, −1
recombined as the complex route's ``R_0 − Q_0``, ``R_1 − Q_1 − δ1 Q_0``; or k = 2, 3), tested against the same
relative tolerance.  ``tests/test_kernels.py`` checks ``T1``, ``T2`` and ``Z`` against the complex products of
the generic route; ``tests/test_routes.py`` checks the route against the generic and the NumPy routes.

The rest is as before: ``ℓ(η) = ℓ_0 + Σ ℓ_m z^m`` with ``z^m = η^{-m}`` precomputed (Horner-like fused multiply-adds
on the real components), ``ν1`` continued by Newton steps ``ν ← ν + (ν²(x_n) − ν_n²)/(2ν_n)`` (``ν²`` is an integral
of the map, so the correction is at round-off level; the closest-root square root is used when it is not below
1e-8), and the eigenvector of :func:`._scalar._eigvec`. **The update off the chain:** when the change of ``ν²`` is
at round-off level (below 1e-13 relative, every step of a normal run), the eigenvector of ``x_n`` takes the carried
``ν_n`` as it is and the update is carried to step n + 1, so the step's dependency chain runs from ``ℓ(η)`` to the
eigenvector without it (one orbit 10–20 % faster; per-step accuracy against the NumPy route in docs/performance.md);
above that, the update is applied first, as before. The blocks are scalars only, so the lock-step lanes
(:mod:`._lanes`) perform the same operations in the same order (no fastmath, no automatic contraction; the fused
multiply-adds ``F = _scalar._fma`` are written out: the same bits). The reciprocal ``r = 1/|k|²`` of the axis is
folded into ``c`` and the recurrence coefficients (:func:`_axis`, :func:`_zed3`), so no division sits on the step's
dependency chain. :func:`_dress3`, :func:`_zed3` and :func:`_step3` are inlined by Numba (left to LLVM, the lanes
lose their vectorisation); the small blocks and :func:`_solve3` are left to LLVM's inliner, which keeps the
first-use compile time down at an unchanged stepping rate (docs/performance.md). Import only after
:func:`._target.configure`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import _scalar as S
from ._scalar import block
from ._status import STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL

F = S._fma

#: number of per-run constants of :func:`_constants3`
NCONST = 17

#: ``|ν²(x_n) − ν_n²|² ≤ _CARRY_TOL2 |ν²(x_n)|²`` (a change of ``ν²`` at round-off level, 1e-13 relative): the
#: carried ``ν_n`` is used as is for the eigenvector of ``x_n`` and its Newton update is carried to the next step
#: (off the step's dependency chain); above it the update is applied first (up to 1e-8 relative), or the closest
#: root taken
_CARRY_TOL2 = 1e-26

#: ``|ν²(x_n) − ν_n²|² ≤ _NEWTON_TOL2 |ν²(x_n)|²`` (1e-8 relative): the Newton update of ``ν_n`` is accepted;
#: above it the closest root is taken
_NEWTON_TOL2 = 1e-16

#: twice the squared relative residual tolerance (``maps._RESIDUAL_TOL = 1e-8``): :func:`_tol3`
_RESIDUAL_TOL2X2 = 2.0 * S._RESIDUAL_TOL2


@block()
def _constants3(eta):
    r"""Per-run constants of the N = 3 step for ``η = a + ic`` (a tuple of ``NCONST`` floats):
    ``z^1, z^2, z^3`` (``z = 1/η``, real and imaginary parts), ``m = −a``, ``c``, ``bu`` (1.0: bottom-up,
    ``|η| ≥ 1``), the recurrence coefficients ``α, γ, ζ`` (with the factor ``−2c`` of ``ỹ = y − 2cW`` in ``α``),
    the residual coefficients ``s0, s1, δ1, r2`` and ``−2c``.

    ``f = αZ_a``, ``g = αZ_b + γf``, ``h = (αZ_1 + γg) + ζf`` with ``(Z_a, Z_b) = (Z_3, Z_2)`` bottom-up
    (``f, g, h = −2c (W_3, W_2, W_1)``: ``α = −2c/δ2``, ``γ = −δ1/δ2``, ``ζ = −1/δ2``) and ``(Z_{−1}, Z_0)`` top-down
    (``−2c (W_1, W_2, W_3)``: ``α = −2c``, ``γ = −δ1``, ``ζ = −δ2``); residuals
    ``e_A = s0 ((−2c Z_d − s1 g) − δ1 h)``, ``e_B = (−2c Z_e − s1 h) − r2 e_A`` with ``(Z_d, Z_e) = (Z_0, Z_{−1})``,
    ``(s0, s1, r2) = (1/δ2, 1, δ1)`` bottom-up and ``(Z_2, Z_3)``, ``(1, δ2, 0)`` top-down.  In both directions
    ``α = −2c s0``, ``γ = −δ1 s0`` and ``ζ = −s1 s0``, so that ``e_A = (α Z_d + ζ g) + γ h`` (:func:`_solve3`: one
    multiplication per component fewer than the form above; the residuals decide the test only, they do not enter
    the new state)."""
    z1 = S._cdiv(complex(1.0, 0.0), eta)
    z2 = z1 * z1
    z3 = z2 * z1
    d1, d2, inv_d2, bottom_up = S._division_constants(eta)
    c = eta.imag
    m2c = -(c + c)
    if bottom_up:
        return (z1.real, z1.imag, z2.real, z2.imag, z3.real, z3.imag, -eta.real, c, 1.0,
                m2c * inv_d2, -(inv_d2 * d1), -inv_d2, inv_d2, 1.0, d1, d1, m2c)
    return (z1.real, z1.imag, z2.real, z2.imag, z3.real, z3.imag, -eta.real, c, 0.0,
            m2c, -d1, -d2, 1.0, d2, d1, 0.0, m2c)


@block()
def _ell3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, z1r, z1i, z2r, z2i, z3r, z3i):
    """``ℓ(η) = ℓ_0 + Σ ℓ_m z^m``: components ``Y^a = Σ_m y_m^a z^m`` (fused, ``b`` added in the first fused
    operation of ``Y³``), then ``u = b + Y³``, ``v = Y¹ − iY²``, ``w = Y¹ + iY²``."""
    Y1r = F(x6, z3r, F(x3, z2r, x0 * z1r))
    Y1i = F(x6, z3i, F(x3, z2i, x0 * z1i))
    Y2r = F(x7, z3r, F(x4, z2r, x1 * z1r))
    Y2i = F(x7, z3i, F(x4, z2i, x1 * z1i))
    Y3r = F(x8, z3r, F(x5, z2r, F(x2, z1r, b)))
    Y3i = F(x8, z3i, F(x5, z2i, x2 * z1i))
    return (complex(Y3r, Y3i), complex(Y1r + Y2i, Y1i - Y2r), complex(Y1r - Y2i, Y1i + Y2r))


@block()
def _nu2(u, v, w):
    """``ν² = u² + vw`` (``ℓ(η)² = ν² I``), fused: ``Re = (Re u − Im u)(Re u + Im u) + Re(vw)``,
    ``Im = 2 Re u Im u + Im(vw)``."""
    p = F(v.real, w.real, -(v.imag * w.imag))
    q = F(v.real, w.imag, v.imag * w.real)
    return complex(F(u.real - u.imag, u.real + u.imag, p), F(u.real + u.real, u.imag, q))


@block()
def _newton_nu(nu, c, inv_2nu):
    """``ν + c/(2ν)`` (``c = ν²(state) − ν²``, ``inv_2nu = 1/(2ν)``), fused."""
    return complex(F(c.real, inv_2nu.real, F(-c.imag, inv_2nu.imag, nu.real)),
                   F(c.real, inv_2nu.imag, F(c.imag, inv_2nu.real, nu.imag)))


@block()
def _size2(x0, x1, x2, x3, x4, x5, x6, x7, x8, bb):
    """``max_m |ℓ_m|²`` (:func:`_size3` squared, less its ``1 +``, without the square root) from ``bb = b²``."""
    return max(bb, x2 * x2, F(x0, x0, x1 * x1), x5 * x5, F(x3, x3, x4 * x4), x8 * x8, F(x6, x6, x7 * x7))


@block()
def _size3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b):
    """``1 + max_m |ℓ_m|`` with ``|ℓ_m|`` the largest entry of ``ℓ_m = y_m·σ`` (``|u| = |y³|``,
    ``|v| = |w| = |y¹ + iy²|``; ``ℓ_0 = diag(b, −b)``): the size of the state for :func:`_scale3`."""
    return 1.0 + math.sqrt(_size2(x0, x1, x2, x3, x4, x5, x6, x7, x8, b * b))


@block()
def _scale3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b):
    """A power of two ``q = 2^(−2E)`` with ``2^(E−1) ≤ 1 + max_m |ℓ_m| < 2^E`` (per orbit and call, from the state
    at the start): :func:`_axis` multiplies the axis by it, so the cross products ``n' × y`` stay of the size of
    ``y`` (``|n'| = |k|²`` grows like ``|y|²``) and the step covers states up to ~1e150 as before the axis was
    unnormalised.  Scaling by a power of two is exact, so the steps' bits do not depend on ``q``."""
    sc = _size3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b)
    if not (sc < 1e300):  # inf or NaN: no scaling (the step reports the non-finite state)
        return 1.0
    # math.ldexp(1.0, -2 * math.frexp(sc)[1]) from the bits (the same value; no library calls, which were a fifth
    # of the lanes' per-call set-up): sc >= 1 is normal, with frexp's exponent E = biased exponent - 1022
    e = 1023 - 2 * (((S._bits(sc) >> 52) & 0x7FF) - 1022)  # the biased exponent of 2^(-2E)
    if e >= 1:
        return S._from_bits(e << 52)
    if e >= -51:  # subnormal: 2^(-2E) = 2^(e + 51) × 2^-1074
        return S._from_bits(np.int64(1) << (e + 51))
    return 0.0


@block()
def _axis(k1, k2, nk, q):
    """The axis of ``M0 = −(Re η) I + i (Im η) n̂·σ`` from the eigenvector ``k`` (``nk = |k|²``), unnormalised:
    ``(n', r)`` with ``n' = q |k|² n̂ = q (−2 Re k̄1k2, −2 Im k̄1k2, |k2|² − |k1|²)`` and ``r = 1/(q|k|²)`` (``q`` of
    :func:`_scale3`, a power of two: exact).  The step multiplies by ``r`` only where it is needed
    (:func:`_dress3`), so the division is off the dependency chain."""
    r = 1.0 / (nk * q)
    pr = F(k1.real, k2.real, k1.imag * k2.imag)  # k̄1 k2
    pi = F(k1.real, k2.imag, -(k1.imag * k2.real))
    n3 = F(k2.real, k2.real, k2.imag * k2.imag) - F(k1.real, k1.real, k1.imag * k1.imag)
    m2q = -(q + q)
    return pr * m2q, pi * m2q, n3 * q, r


@block()
def _cross(n1, n2, n3, y1, y2, y3):
    """``K' y = n' × y``, fused."""
    return F(n2, y3, -(n3 * y2)), F(n3, y1, -(n1 * y3)), F(n1, y2, -(n2 * y1))


@block()
def _v3(p1, p2, p3, y1, y2, y3, a1, a2, a3, m, cr):
    """``v_k = (y_{k+1} + m y_k) − c K y_k`` (``p = y_{k+1}``, ``a = K' y_k``, ``cr = c/|k|²``), fused."""
    return F(-cr, a1, F(m, y1, p1)), F(-cr, a2, F(m, y2, p2)), F(-cr, a3, F(m, y3, p3))


@block()
def _sel3(c, a1, a2, a3, b1, b2, b3):
    return S._sel(c, a1, b1), S._sel(c, a2, b2), S._sel(c, a3, b3)


@block()
def _max2_ok(q1, q2, t):
    """``q1 <= t and q2 <= t`` for ``q_i >= 0`` or NaN (NaN fails) with one comparison: ``max(q1, q2, c) <= t``,
    ``c = min(0, q1 + q2)`` (0, or NaN when a ``q_i`` is: a sum of non-negative numbers is never ``inf − inf``).
    ``a if a > b else b`` is x86's ``maxpd`` exactly (a NaN in either operand gives ``b``), hence the NaN carried
    by ``c`` as the last ``max``'s second operand; ``0 if 0 < s else s`` is ``minpd``.  Without a NaN the maximum
    of non-negative numbers is compared, so the answer is the two comparisons' (infinities included).  On Zen 4
    ``maxpd``, ``minpd`` and adds take no FMA-pipe cycle, a comparison into a mask one (``benchmarks/fp_ports.py``).
    (All four residuals in one comparison made LLVM spill a register in the lanes' dressing loop: a store more.)"""
    m = q1 if q1 > q2 else q2
    s = q1 + q2
    c = 0.0 if 0.0 < s else s
    m = m if m > c else c
    return m <= t


@block()
def _norm_ok(e1, e2, e3, t):
    """The residual test of the complex route for the Hermitian residual ``e·σ``: ``|u|² = e3²`` and
    ``|v|² = |w|² = e1² + e2²`` at most ``t`` (NaN fails); one comparison (:func:`_max2_ok`)."""
    return _max2_ok(e3 * e3, F(e1, e1, e2 * e2), t)


@block()
def _tol3(x0, x1, x2, x3, x4, x5, x6, x7, x8, bb):
    """The squared residual tolerance of the step, ``2 (1e-8)² (1 + max_m |ℓ_m|²)`` (:func:`_size2`; ``bb = b²``):
    the complex route's relative test ``(1e-8 (1 + max_m |ℓ_m|))²`` without its square root, which it bounds from
    above and is at most twice (``(1 + s)² ≤ 2 (1 + s²)``): every step that test accepts is accepted, and a
    residual at most √2 times larger.  (A square root and two multiplications fewer per step: on Zen 4 they took
    ~3.3 of the N = 3 lanes' ~244 FMA-pipe cycles per 8 lane-steps, docs/performance.md.)"""
    return _RESIDUAL_TOL2X2 * (1.0 + _size2(x0, x1, x2, x3, x4, x5, x6, x7, x8, bb))


@block(inline="always")
def _zed3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, r, cst):
    """First half of :func:`_dress3`: ``Z'_k = K' v_k`` (k = 0..3; 12 floats), ``v_k = (y_{k+1} + m y_k) − c K y_k``
    with ``K = r K'``, ``K' y = n' × y``."""
    m = cst[6]
    cr = cst[7] * r
    # K' y_k (K' y_0 = n' × b e_3 = Z'_{-1})
    a0x = n2 * b
    a0y = -(n1 * b)
    a1x, a1y, a1z = _cross(n1, n2, n3, x0, x1, x2)
    a2x, a2y, a2z = _cross(n1, n2, n3, x3, x4, x5)
    a3x, a3y, a3z = _cross(n1, n2, n3, x6, x7, x8)
    Z0 = _cross(n1, n2, n3, F(-cr, a0x, x0), F(-cr, a0y, x1), F(m, b, x2))
    v1x, v1y, v1z = _v3(x3, x4, x5, x0, x1, x2, a1x, a1y, a1z, m, cr)
    v2x, v2y, v2z = _v3(x6, x7, x8, x3, x4, x5, a2x, a2y, a2z, m, cr)
    Z1 = _cross(n1, n2, n3, v1x, v1y, v1z)
    Z2 = _cross(n1, n2, n3, v2x, v2y, v2z)
    Z3 = _cross(n1, n2, n3, F(m, x6, -(cr * a3x)), F(m, x7, -(cr * a3y)), F(m, x8, -(cr * a3z)))
    return Z0[0], Z0[1], Z0[2], Z1[0], Z1[1], Z1[2], Z2[0], Z2[1], Z2[2], Z3[0], Z3[1], Z3[2]


@block()
def _solve3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, r, Z, cst, t):
    """Second half of :func:`_dress3`: the recurrence for ``W`` on the selected equations, the residual of the
    other two (tested against ``t`` of :func:`_tol3`) and the new state, from ``Z = (Z'_0 … Z'_3)`` of
    :func:`_zed3`."""
    bu = cst[8] != 0.0
    al, ga, ze = cst[9], cst[10], cst[11]
    s1, r2, m2c = cst[13], cst[15], cst[16]
    alr = al * r
    m2cr = m2c * r
    a0x = n2 * b  # Z'_{-1}
    a0y = -(n1 * b)
    # the two directions of the division as one recurrence on selected equations
    Za = _sel3(bu, Z[9], Z[10], Z[11], a0x, a0y, 0.0)
    Zb = _sel3(bu, Z[6], Z[7], Z[8], Z[0], Z[1], Z[2])
    Zd = _sel3(bu, Z[0], Z[1], Z[2], Z[6], Z[7], Z[8])
    Ze = _sel3(bu, a0x, a0y, 0.0, Z[9], Z[10], Z[11])
    f1, f2, f3 = alr * Za[0], alr * Za[1], alr * Za[2]
    g1, g2, g3 = F(alr, Zb[0], ga * f1), F(alr, Zb[1], ga * f2), F(alr, Zb[2], ga * f3)
    h1 = F(ze, f1, F(ga, g1, alr * Z[3]))
    h2 = F(ze, f2, F(ga, g2, alr * Z[4]))
    h3 = F(ze, f3, F(ga, g3, alr * Z[5]))
    # residual of the unused equations (scaled as the complex route's): e_A = (α Z_d + ζ g) + γ h
    # (= s0 ((−2c Z_d − s1 g) − δ1 h), _constants3), e_B = (−2c Z_e − s1 h) − r2 e_A
    eA1 = F(ga, h1, F(ze, g1, alr * Zd[0]))
    eA2 = F(ga, h2, F(ze, g2, alr * Zd[1]))
    eA3 = F(ga, h3, F(ze, g3, alr * Zd[2]))
    eB1 = F(-r2, eA1, F(-s1, h1, m2cr * Ze[0]))
    eB2 = F(-r2, eA2, F(-s1, h2, m2cr * Ze[1]))
    eB3 = F(-r2, eA3, F(-s1, h3, m2cr * Ze[2]))
    ok = _norm_ok(eA1, eA2, eA3, t) & _norm_ok(eB1, eB2, eB3, t)
    w1 = _sel3(bu, h1, h2, h3, f1, f2, f3)  # −2c W_1
    w3 = _sel3(bu, f1, f2, f3, h1, h2, h3)  # −2c W_3
    return (ok, x0 + w1[0], x1 + w1[1], x2 + w1[2], x3 + g1, x4 + g2, x5 + g3, x6 + w3[0], x7 + w3[1],
            x8 + w3[2])


@block(inline="always")
def _dress3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, r, cst):
    """The real form of the dressing (module docstring) from the unnormalised axis ``n' = n̂/r`` of
    :func:`_axis`: returns ``(residual_ok, ỹ_1 … ỹ_9)``.  ``K = r K'`` with ``K' y = n' × y``: ``Z_k = r K' v_k``,
    so ``r`` is folded into ``c`` and the coefficients that multiply ``Z`` (computed while the cross products
    ``K' y_k`` wait for no division).  Two halves (:func:`_zed3`, :func:`_solve3`), which the lanes run as two
    loops."""
    Z = _zed3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, r, cst)
    t = _tol3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b * b)
    return _solve3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, r, Z, cst, t)


@block()
def _finite9(y0, y1, y2, y3, y4, y5, y6, y7, y8):
    acc = ((y0 + y1) + (y2 + y3)) + ((y4 + y5) + (y6 + y7)) + y8
    return acc - acc == 0.0  # false for NaN or inf anywhere


@block(inline="always")
def _step3(x, b, cst, q, nu, nu_sq, inv_2nu, newton):
    """One N = 3 step from the tuple ``x`` (9 floats) with the constants ``cst`` of :func:`_constants3` and the
    carried ``ν1`` (``nu``; ``nu_sq = ν1²``, ``inv_2nu = 1/(2ν1)``, computed off the chain); returns
    ``(status, ν1 for the next step, x_new)`` (``x`` itself on a failed step).  ``newton`` false (the first step
    of a run from the branch rule): ``nu`` is used and carried as it is."""
    x0, x1, x2, x3, x4, x5, x6, x7, x8 = x
    u, v, w = _ell3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, cst[0], cst[1], cst[2], cst[3], cst[4], cst[5])
    nu_next = nu
    if newton:
        nu2 = _nu2(u, v, w)
        c = nu2 - nu_sq
        a2 = S._abs2(c)
        s2 = S._abs2(nu2)
        if a2 <= _CARRY_TOL2 * s2:  # the carried ν1 is exact to round-off: used as is, its update carried
            nu_next = _newton_nu(nu, c, inv_2nu)
        elif a2 <= _NEWTON_TOL2 * s2:
            nu = _newton_nu(nu, c, inv_2nu)
            nu_next = nu
        else:
            nu = S._continue_nu(u, v, w, nu)
            nu_next = nu
    k1, k2, nk, st = S._eigvec(u, v, w, nu)
    if st != STATUS_OK:
        return st, nu_next, x
    n1, n2, n3, rk = _axis(k1, k2, nk, q)
    r = _dress3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, n3, rk, cst)
    xn = (r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9])
    if not r[0]:
        return STATUS_RESIDUAL, nu_next, x
    if not _finite9(r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]):
        return STATUS_NONFINITE, nu_next, x
    return STATUS_OK, nu_next, xn


@njit(cache=True, error_model="numpy")
def orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final):
    """The stepping loop of :func:`run_orbit3` without allocations (the GPU kernels of :mod:`jetgaudin.gpu` call it
    for one orbit per thread, compiled for the device): ``out[j] = x_{j·save_every}`` (rows ``0..steps//save_every``
    as far as the orbit got), ``final`` the last state; returns ``(status, step, ν1)`` as :func:`run_orbit3`."""
    x = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8])
    for i in range(9):
        out[0, i] = x0[i]
    cst = _constants3(eta)
    q = _scale3(x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8], b)
    nu = nu0
    status = STATUS_OK
    n = 0
    j = 0  # the last saved row
    left = save_every  # steps to the next saved row (a countdown: no integer division per step)
    for n in range(steps):
        # quantities of the previous ν1, off the critical path of the step
        nu_sq = nu * nu
        inv_2nu = S._cdiv(complex(1.0, 0.0), nu + nu)
        status, nu, x = _step3(x, b, cst, q, nu, nu_sq, inv_2nu, n > 0 or cont)
        if status != STATUS_OK:
            break
        left -= 1
        if left == 0:
            left = save_every
            j += 1
            for i in range(9):
                out[j, i] = x[i]
    else:
        n = steps
    for i in range(9):
        final[i] = x[i]
    return status, n, nu


@njit(cache=True, error_model="numpy")
def run_orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final, drift, want_drift):
    """:func:`._generic.run_orbit` for ``N = 3`` (``x0`` of shape ``(9,)``) by the real form of :func:`_step3`
    (equal to the generic route to round-off): :func:`orbit3`, then the drift pass."""
    I0 = np.empty(6)
    Ib = np.empty(12)
    S._integrals3(x0, b, I0)
    for k in range(6):
        drift[k] = 0.0
    status, n, nu = orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final)
    if want_drift:
        # out[:, :] has Numba's layout 'A', as the lanes' strided rows: one compiled drift pass serves both
        S._drift_pass(out[:, :], final, n // save_every, b, 3, I0, Ib, drift)
    return status, n, nu
