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

The constants ``ell = (k, m, K, K', E, E', k')`` come from SciPy (:func:`elliptic_constants`), once per family.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import special

__all__ = ["elliptic_constants", "psi_elliptic_cached", "sncndn", "zeta_real"]

_EPS = 1.1102230246251565e-16


def elliptic_constants(k: float) -> np.ndarray:
    """``(k, m, K, K', E, E', k')`` for the modulus ``k`` (SciPy; ``K' = ∞`` at ``k = 0``)."""
    m = k * k
    Kp = float(special.ellipkm1(m)) if m > 0 else math.inf
    return np.array([k, m, float(special.ellipk(m)), Kp, float(special.ellipe(m)), float(special.ellipe(1.0 - m)),
                     math.sqrt((1.0 - k) * (1.0 + k))])


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
        S[n + 1] = cd / (n + 1)
        C[n + 1] = -sd / (n + 1)
        D[n + 1] = -m * sc / (n + 1)


@njit(cache=True, error_model="numpy")
def psi_elliptic_cached(z, ell, order, out, S, C, D, ns, xc):
    """``out[m − 1] = ψ_m(z) = (−1)^{m−1} [x^{m−1}] F(z + x)``, ``m = 1..order`` (``S, C, D, ns`` complex scratch of
    length ``order``), with the functions of ``Re z`` kept in ``xc`` (8,; zeros before the first call) between calls
    of equal ``Re z`` (the nodes of one vertical segment): one AGM per point (``sn, cn, dn, Z`` of ``Im z``).

    ``z`` reduced as in ``_jacobi._zeta_parts`` (``Re`` modulo ``2K``, ``Im`` modulo ``2K'``, and within ``K'/2`` of a
    pole row shifted to ``v = z ∓ iK'``, where ``F(v ± iK') = Z(v) ∓ iπ/(2K)``); ``Z(v)`` by the addition theorem
    ``Z(x + iy) = Z(x) + Z(iy) − m sn x sn(iy) sn(x + iy)``; ``sn, cn, dn(v)`` by the addition theorem from the
    numerators ``(δ, N_s, N_c, N_d)`` of ``_jacobi._numerators`` (``|Im v| ≤ K'/2``: no reflection of ``Im v``); the
    Taylor series of ``F`` from ``F' = 1 − E/K − ns²``, ``ns = 1/sn`` by series inversion of the ODE series of
    ``sn, cn, dn`` at ``v`` (at a pole row ``ns(v ± iK') = k sn v``: ``_jacobi._w_series``; the sign of ``ns``
    under the reductions does not enter ``ns²``)."""
    k, m, K, Kp, E = ell[0], ell[1], ell[2], ell[3], ell[4]
    x0 = z.real
    if not (xc[7] == 1.0 and xc[0] == x0):
        nx = np.rint(x0 / (2.0 * K))
        x = x0 - 2.0 * K * nx
        xc[0] = x0
        xc[1] = x
        xc[2] = zeta_real(x, m)
        xc[3] = sncndn(x, m)[0]
        xc[4], xc[5], xc[6] = _reflected(x, m, K, ell[6])
        xc[7] = 1.0
    x = xc[1]
    y = z.imag
    const = 0j
    row = 0.0
    if math.isfinite(Kp):
        ny = np.rint(y / (2.0 * Kp))
        y = y - 2.0 * Kp * ny
        const = -1j * math.pi / K * ny
        if abs(y) > 0.5 * Kp:
            row = 1.0 if y > 0 else -1.0
        y = y - Kp * row
        const = const - row * 1j * math.pi / (2.0 * K)
    s1, c1, d1, zy = _agm(y, 1.0 - m)
    if not math.isfinite(Kp):
        zy = 0.0
    s, c, d = xc[4], xc[5], xc[6]
    delta = c1 * c1 + m * s * s * s1 * s1
    Ns = complex(s * d1, c * d * s1 * c1)
    Nc = complex(c * c1, -(s * d * s1 * d1))
    Nd = complex(d * c1 * d1, -(m * s * c * s1))
    lin = 0.0 if not math.isfinite(Kp) else math.pi / (2.0 * K * Kp)
    z0 = xc[2] + 1j * (d1 * s1 / c1 - zy - lin * y) - m * xc[3] * (1j * s1 / c1) * (Ns / delta)
    out[0] = z0 + const if row != 0.0 else Nc * Nd / (Ns * delta) + z0 + const
    if order == 1:
        return
    n1 = order - 1
    _ode_series(Ns / delta, Nc / delta, Nd / delta, m, n1, S, C, D)
    if row != 0.0:
        for n in range(n1):
            ns[n] = k * S[n]
    else:
        r0 = 1.0 / S[0]
        ns[0] = r0
        for n in range(1, n1):
            acc = 0j
            for j in range(1, n + 1):
                acc += S[j] * ns[n - j]
            ns[n] = -acc * r0
    c0 = 1.0 - E / K
    for n in range(1, order):
        acc = 0j
        for i in range(n):
            acc += ns[i] * ns[n - 1 - i]
        v = -acc / n
        if n == 1:
            v = v + c0
        out[n] = v if n % 2 == 0 else -v
