r"""The elliptic family's basis ``ψ_m`` compiled (private), for the compiled solve of
:mod:`jetgaudin._exact_chain_kernels`: the twin of :mod:`jetgaudin.families._jacobi` (same formulas, same
reductions; the tests compare the two).

**Real arguments** (``0 ≤ m < 1``): ``sn, cn, dn`` and the amplitude by the arithmetic–geometric mean and descending
Landen transformation (A&S 16.4.1–3): ``a_0 = 1``, ``b_0 = √(1 − m)``, ``c_0 = √m``, ``a_{n+1} = (a_n + b_n)/2``,
``b_{n+1} = √(a_n b_n)``, ``c_{n+1} = (a_n − b_n)/2`` until ``c_N/a_N`` is below the double precision ulp, then
``φ_N = 2^N a_N u`` and ``φ_{n−1} = (φ_n + arcsin(c_n sin φ_n / a_n))/2``; ``sn = sin φ_0``, ``cn = cos φ_0``,
``dn = cos φ_0 / cos(φ_1 − φ_0)``.  Jacobi's zeta function from the same sequence (the AGM form of ``Z``, A&S
§17.6): ``Z(u | m) = Σ_{n=1}^{N} c_n sin φ_n`` (checked against ``E(am u) − (E/K) u`` of SciPy in the tests).
Beyond ``K/2`` the reflection ``t = K − |x|`` of ``_jacobi._reflected`` (A&S 16.8.1).

**Complex arguments** as in ``_jacobi``: the addition theorem with Jacobi's imaginary transformation
(A&S 16.21.1–4) on the reduced arguments; ``F = cs dn + Z`` by ``_jacobi._zeta_parts`` (the pole rows ``Im u = ±K'``
shifted away: ``F(v ± iK') = Z(v) ∓ iπ/(2K)``), its Taylor coefficients from ``F' = 1 − E/K − ns²`` with ``ns``
from the ODE series of ``sn, cn, dn`` (``_jacobi._w_series``).  ``ψ_m(z) = (−1)^{m−1} [x^{m−1}] F(z + x)``
(:func:`psi_elliptic_cached`; the tests compare it with ``EllipticFamily.nu2_basis``).

The constants ``ell = (k, m, K, K', E, E', k', …)`` come from SciPy (:func:`elliptic_constants`), once per family,
with the theta series of the parameter ``1 − m``: the imaginary parts' ``sn, cn, dn, Z`` (a new argument at every
node of a segment) by :func:`_theta_im` (one ``sin``/``cos`` and ≤ 9 terms, ~6× faster than the AGM), the AGM where
the nome ``q'`` exceeds 0.6.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import special

__all__ = ["elliptic_constants", "psi_elliptic_cached", "sncndn", "zeta_real"]

_EPS = 1.1102230246251565e-16


#: the largest nome ``q'`` for which the imaginary parts take the theta series (:func:`_theta_im`; ``q' ≤ 0.6``:
#: at most 9 terms, ``k ≳ 1e-3``); above it, the AGM
_Q_MAX = 0.6


def elliptic_constants(k: float) -> np.ndarray:
    """``(k, m, K, K', E, E', k', L, π/(2K'), S, C, D, o_0..o_L, e_1..e_L)`` for the modulus ``k`` (SciPy; ``K' = ∞``
    at ``k = 0``): the first seven the constants, then the theta series of the parameter ``m' = 1 − m`` (the
    imaginary parts, :func:`_theta_im`) — ``L`` terms (0: none, the AGM instead), the nome ``q' = e^{−πK/K'}``'s
    ``o_n = q'^{n(n+1)}``, ``e_n = q'^{n²}`` and the factors ``S = ϑ3(0)/ϑ2(0)``, ``C = ϑ4(0)/ϑ2(0)``,
    ``D = ϑ4(0)/ϑ3(0)`` (``ϑ2`` without its factor ``q'^{1/4}``, which cancels), all once per family."""
    m = k * k
    Kp = float(special.ellipkm1(m)) if m > 0 else math.inf
    K = float(special.ellipk(m))
    head = [k, m, K, Kp, float(special.ellipe(m)), float(special.ellipe(1.0 - m)), math.sqrt((1.0 - k) * (1.0 + k))]
    q = math.exp(-math.pi * K / Kp) if math.isfinite(Kp) else 1.0
    if not q <= _Q_MAX:
        return np.array(head + [0.0, 0.0, 0.0, 0.0, 0.0])
    L = 1
    while q ** (L * L) > 1e-18:  # the last even term (the odd ones, q^{n(n+1)}, are smaller) below round-off
        L += 1
    o = [q ** (n * (n + 1)) for n in range(L + 1)]
    e = [q ** (n * n) for n in range(1, L + 1)]
    t2 = math.fsum(o)
    t3 = 1.0 + 2.0 * math.fsum(e)
    t4 = 1.0 + 2.0 * math.fsum((-1) ** n * en for n, en in enumerate(e, 1))
    return np.array(head + [float(L), math.pi / (2.0 * Kp), t3 / t2, t4 / t2, t4 / t3] + o + e)


@njit(cache=True, error_model="numpy", inline="always")
def _theta_im(y, ell):
    """``(sn, cn, dn, Z)(y | 1 − m)`` of a real ``y`` with ``|y| ≤ K'/2`` by the theta series of the nome ``q'``
    (DLMF 22.2.4–6, 22.16.32; ``ζ = πy/(2K')``): ``sn = S ϑ1/ϑ4``, ``cn = C ϑ2/ϑ4``, ``dn = D ϑ3/ϑ4``,
    ``Z = (π/(2K')) ϑ4'/ϑ4`` with ``ϑ1 = Σ_n (−1)^n o_n sin((2n+1)ζ)``, ``ϑ2 = Σ_n o_n cos((2n+1)ζ)``,
    ``ϑ3, ϑ4 = 1 + 2 Σ_n (±1)^n e_n cos(2nζ)``, ``ϑ4' = 4 Σ_n (−1)^{n+1} n e_n sin(2nζ)`` (constants
    :func:`elliptic_constants`): one ``sin``/``cos``, the multiples by powers of ``e^{iζ}`` (their round-off, a few
    ulps, enters with the factors ``q'^{n(n+1)}``)."""
    L = int(ell[7])
    zeta = ell[8] * y
    c1 = math.cos(zeta)
    s1 = math.sin(zeta)
    pr = c1  # e^{ijζ}, j = 1, 2, ...
    pi = s1
    t1 = ell[12] * s1
    t2 = ell[12] * c1
    t3 = 0.0
    t4 = 0.0
    t4d = 0.0
    sgn = 1.0
    for n in range(1, L + 1):
        sgn = -sgn  # (−1)^n
        qr = pr * c1 - pi * s1  # j = 2n
        pi = pr * s1 + pi * c1
        pr = qr
        en = ell[12 + L + n]
        t3 += en * pr
        t4 += sgn * en * pr
        t4d -= sgn * n * en * pi
        qr = pr * c1 - pi * s1  # j = 2n + 1
        pi = pr * s1 + pi * c1
        pr = qr
        on = ell[12 + n]
        t1 += sgn * on * pi
        t2 += on * pr
    T4 = 1.0 + 2.0 * t4
    inv = 1.0 / T4
    return ell[9] * t1 * inv, ell[10] * t2 * inv, ell[11] * (1.0 + 2.0 * t3) * inv, ell[8] * 4.0 * t4d * inv


@njit(cache=True, error_model="numpy")
def _agm(u, m):
    """``(sn, cn, dn, Z)`` of the real ``u`` and parameter ``0 ≤ m < 1`` (module doc)."""
    if m == 0.0:
        return math.sin(u), math.cos(u), 1.0, 0.0
    a = np.empty(16)
    c = np.empty(16)
    a[0] = 1.0
    c[0] = math.sqrt(m)
    b = math.sqrt(1.0 - m)
    twon = 1.0
    i = 0
    while abs(c[i] / a[i]) > _EPS and i < 15:
        ai = a[i]
        i += 1
        c[i] = (ai - b) / 2.0
        t = math.sqrt(ai * b)
        a[i] = (ai + b) / 2.0
        b = t
        twon *= 2.0
    phi = twon * a[i] * u
    z = 0.0
    prev = phi
    while i:
        z += c[i] * math.sin(phi)
        t = c[i] * math.sin(phi) / a[i]
        prev = phi
        phi = (math.asin(t) + phi) / 2.0
        i -= 1
    cp = math.cos(phi)
    return math.sin(phi), cp, cp / math.cos(prev - phi), z


@njit(cache=True, error_model="numpy")
def sncndn(u, m):
    """``(sn, cn, dn)(u | m)``, real ``u`` (:func:`_agm`)."""
    s, c, d, _ = _agm(u, m)
    return s, c, d


@njit(cache=True, error_model="numpy")
def zeta_real(u, m):
    """Jacobi's ``Z(u | m)``, real ``u`` (:func:`_agm`)."""
    return _agm(u, m)[3]


@njit(cache=True, error_model="numpy")
def _reflected(x, m, K, kc):
    """``_jacobi._reflected``: ``sn, cn, dn(x | m)`` for ``|x| ≤ K``, beyond ``K/2`` from ``t = K − |x|``."""
    if abs(x) > 0.5 * K:
        st, ct, dt = sncndn(K - abs(x), m)
        return (ct / dt if x >= 0 else -ct / dt), kc * st / dt, kc / dt
    return sncndn(x, m)


@njit(cache=True, error_model="numpy")
def _ode_series(s0, c0, d0, m, order, S, C, D):
    S[0] = s0
    C[0] = c0
    D[0] = d0
    for n in range(order - 1):
        cd = 0j
        sd = 0j
        sc = 0j
        for i in range(n + 1):
            cd += C[i] * D[n - i]
            sd += S[i] * D[n - i]
            sc += S[i] * C[n - i]
        r = 1.0 / (n + 1)
        S[n + 1] = cd * r
        C[n + 1] = -sd * r
        D[n + 1] = -m * r * sc


@njit(cache=True, error_model="numpy", inline="always")
def psi_elliptic_cached(z, ell, order, out, o, S, C, D, ns, xcache, ic):
    """``out[o + m − 1] = ψ_m(z) = (−1)^{m−1} [x^{m−1}] F(z + x)``, ``m = 1..order`` (``S, C, D, ns`` complex scratch
    of length ``order``), with the functions of ``Re z`` kept in the row ``xcache[ic]`` (9 values; zeros before the
    first call) between calls of equal ``Re z`` (the nodes of one vertical segment): one theta series per point
    (``sn, cn, dn, Z`` of ``Im z``).  Inlined into the node loops (``inline="always"``: ~195 → ~154 ns a Clebsch
    node, ``ψ_1..ψ_4``); ``out`` and ``xcache`` by offset and row, not as views.

    ``z`` reduced as in ``_jacobi._zeta_parts`` (``Re`` modulo ``2K``, ``Im`` modulo ``2K'``, and within ``K'/2`` of a
    pole row shifted to ``v = z ∓ iK'``, where ``F(v ± iK') = Z(v) ∓ iπ/(2K)``); ``Z(v)`` by the addition theorem
    ``Z(x + iy) = Z(x) + Z(iy) − m sn x sn(iy) sn(x + iy)``; ``sn, cn, dn(v)`` by the addition theorem from the
    numerators ``(δ, N_s, N_c, N_d)`` of ``_jacobi._numerators`` (``|Im v| ≤ K'/2``: no reflection of ``Im v``); the
    Taylor series of ``F`` from ``F' = 1 − E/K − ns²``, ``ns = 1/sn`` by series inversion of the ODE series of
    ``sn, cn, dn`` at ``v`` (at a pole row ``ns(v ± iK') = k sn v``: ``_jacobi._w_series``; the sign of ``ns``
    under the reductions does not enter ``ns²``)."""
    k, m, K, Kp, E = ell[0], ell[1], ell[2], ell[3], ell[4]
    x0 = z.real
    if not (xcache[ic, 7] == 1.0 and xcache[ic, 0] == x0):
        nx = np.rint(x0 / (2.0 * K))
        x = x0 - 2.0 * K * nx
        xcache[ic, 0] = x0
        xcache[ic, 1] = x
        xcache[ic, 2] = zeta_real(x, m)
        xcache[ic, 3] = sncndn(x, m)[0]
        xcache[ic, 4], xcache[ic, 5], xcache[ic, 6] = _reflected(x, m, K, ell[6])
        xcache[ic, 7] = 1.0
        xcache[ic, 8] = 0.0 if not math.isfinite(Kp) else math.pi / (2.0 * K * Kp)  # once, not at every node
    y = z.imag
    const = 0j
    row = 0.0
    if math.isfinite(Kp):
        ny = 0.0
        if not abs(y) < Kp:  # else |y/(2K')| < 1/2: ny = 0 and y stays (no division at the solve's nodes)
            ny = np.rint(y / (2.0 * Kp))
            y = y - 2.0 * Kp * ny
        if abs(y) > 0.5 * Kp:
            row = 1.0 if y > 0 else -1.0
        y = y - Kp * row
        if ny != 0.0 or row != 0.0:  # −iπ ny/K − row iπ/(2K) (zero on the segments of the solve: no complex ops)
            const = complex(0.0, -(math.pi / K) * ny - (row * math.pi) / (2.0 * K))
    if ell[7] > 0.0:
        s1, c1, d1, zy = _theta_im(y, ell)
    else:
        s1, c1, d1, zy = _agm(y, 1.0 - m)
    if not math.isfinite(Kp):
        zy = 0.0
    s, c, d = xcache[ic, 4], xcache[ic, 5], xcache[ic, 6]
    # sn, cn, dn(v) = N_s, N_c, N_d / δ (real reciprocals: no complex division but the one of ns = 1/sn)
    idelta = 1.0 / (c1 * c1 + m * s * s * s1 * s1)
    sv = complex(s * d1 * idelta, c * d * s1 * c1 * idelta)
    cv = complex(c * c1 * idelta, -(s * d * s1 * d1) * idelta)
    dv = complex(d * c1 * d1 * idelta, -(m * s * c * s1) * idelta)
    lin = xcache[ic, 8]  # π/(2K K') (0 at K' = ∞)
    t = s1 / c1
    g = m * xcache[ic, 3] * t  # the addition theorem's last term −m sn x sn(iy) sn v = −g · i · sv (sn(iy) = i s1/c1)
    z0 = complex(xcache[ic, 2] + g * sv.imag, (d1 * t - zy - lin * y) - g * sv.real)
    if row != 0.0:
        out[o] = z0 + const
    else:
        a2 = 1.0 / (sv.real * sv.real + sv.imag * sv.imag)
        nsv = complex(sv.real * a2, -sv.imag * a2)  # 1/sn v
        out[o] = cv * dv * nsv + z0 + const
    if order == 1:
        return
    n1 = order - 1
    _ode_series(sv, cv, dv, m, n1, S, C, D)
    if row != 0.0:
        for n in range(n1):
            ns[n] = k * S[n]
    else:
        ns[0] = nsv
        for n in range(1, n1):
            acc = 0j
            for j in range(1, n + 1):
                acc += S[j] * ns[n - j]
            ns[n] = -acc * nsv
    c0 = 1.0 - E / K
    for n in range(1, order):
        acc = 0j
        for i in range(n):
            acc += ns[i] * ns[n - 1 - i]
        v = -acc * (1.0 / n)
        if n == 1:
            v = v + c0
        out[o + n] = v if n % 2 == 0 else -v
