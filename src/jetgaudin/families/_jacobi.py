r"""Jacobi elliptic functions of complex argument, real modulus ``k ∈ [0, 1)``, and their Taylor series.

What is used, and why
---------------------
No maintained NumPy-vectorised library evaluates ``sn, cn, dn`` at complex argument: SciPy's
``scipy.special.ellipj(u, m)`` (Cephes, parameter ``m = k²``) is real-only and ``mpmath.ellipfun`` is scalar
and arbitrary-precision (~10⁴ times slower).  So the complex values are assembled from **real** SciPy calls by
the addition theorem with Jacobi's imaginary transformation (Abramowitz & Stegun 16.21.1–4): with
``s, c, d = sn, cn, dn(x | m)``, ``s₁, c₁, d₁ = sn, cn, dn(y | 1 − m)``, ``δ = c₁² + m s² s₁²``,

.. math:: \operatorname{sn}(x+iy) = \frac{s d_1 + i\, c d s_1 c_1}{\delta},\quad
          \operatorname{cn}(x+iy) = \frac{c c_1 - i\, s d s_1 d_1}{\delta},\quad
          \operatorname{dn}(x+iy) = \frac{d c_1 d_1 - i m\, s c s_1}{\delta}.

``δ`` is a sum of two non-negative terms (no cancellation), so the relative accuracy is that of the real calls
up to the poles (against ``mpmath.ellipfun``, ``tests/test_jacobi.py``: ~1e-15 for 0.3 ≤ k ≤ 0.8, 7e-15 at 0.99,
9e-14 at 1e-4; ~1e-11 at k = 1e-6 and 0.999999, where Cephes' own expansions for m → 1 and ``cn = cos(am)`` limit
it).  The real arguments
are first reduced (``x`` modulo ``2K``, ``y`` modulo ``2K'``, with the sign rules ``sn, cn → −sn, −cn`` under
``x → x + 2K`` and ``cn, dn → −cn, −dn`` under ``y → y + 2K'``) because Cephes' phase ``am(x)`` loses absolute
accuracy proportionally to ``|x|``.  The ratios ``ns = δ/N_s``, ``ds = N_d/N_s``, ``cs = N_c/N_s`` of the three
numerators are taken directly, so ``w_a = (ns, ds, cs)`` are finite and accurate at the poles of ``sn``.
``K = K(k)`` is ``scipy.special.ellipk(m)`` and ``K' = K(√(1−k²))`` is ``scipy.special.ellipkm1(m)`` (accurate
for small ``k``; ``K' = ∞`` at ``k = 0``).

Taylor series at a point ``u₀`` (not a pole) come from the ODEs ``sn' = cn dn``, ``cn' = −sn dn``,
``dn' = −k² sn cn``: with ``S, C, D`` the coefficient sequences, ``(n+1) S_{n+1} = Σ_{i≤n} C_i D_{n−i}`` and
likewise (Cauchy products, exact recursion, O(order²)).  Then ``ns = 1/S``, ``ds = D/S``, ``cs = C/S`` by series
division.  Within ``K'/2`` of a pole row ``Im u = ±K'`` the shifted forms ``ns(u + iK') = k sn u``,
``ds(u + iK') = −ik cn u``, ``cs(u + iK') = −i dn u`` (A&S 16.8) are used instead, so no series is divided by a
large or vanishing ``sn``.

The functions ``w_1 = ns``, ``w_2 = ds``, ``w_3 = cs`` have Laurent expansion ``1/x + (odd regular part)`` at
0; at ``k = 0``: ``1/sin x``, ``1/sin x``, ``cot x``.  Their quasi-periods: ``w_a(x + 2K) = ε_a w_a(x)``,
``ε = (−1, −1, +1)``; ``w_a(x + 2iK') = ε'_a w_a(x)``, ``ε' = (+1, −1, −1)``.

``jacobi_zeta`` (``Z(u) = E(am u) − (E/K) u``) at complex argument by the addition theorem
``Z(x + iy) = Z(x) + Z(iy) − m sn x sn(iy) sn(x + iy)`` and ``Z(iy | m) = i[dn sc(y | m₁) − Z(y | m₁) −
π y/(2KK')]`` (A&S 17.4.35, 17.4.40), from ``scipy.special.ellipeinc`` at real arguments.  It gives the
``ν²``-expansion function ``F(x) = cs(x) dn(x) + Z(x)`` (Laurent ``1/x`` + odd regular part; regular at
``iK'``; ``F(x + 2K) = F(x)``, ``F(x + 2iK') = F(x) − iπ/K``; ``F' = 1 − E/K − ns²``; ``cot x`` at ``k = 0``).
"""

from __future__ import annotations

import numpy as np
from scipy import special

from .._errors import InvalidParameterError
from ._series import div, mul

__all__ = [
    "check_modulus",
    "periods",
    "ellipfun",
    "w_values",
    "sncndn_taylor",
    "w_taylor",
    "w_regular",
    "jacobi_zeta",
    "curve_function",
    "curve_function_taylor",
    "curve_function_regular",
]

#: sign of w_a = (ns, ds, cs) under x -> x + 2K and under x -> x + 2iK'
EPS_K = np.array([-1.0, -1.0, 1.0])
EPS_KP = np.array([1.0, -1.0, -1.0])


def check_modulus(k) -> float:
    """``k`` as a float in ``[0, 1)``; :class:`InvalidParameterError` otherwise (names the fix)."""
    if isinstance(k, bool) or np.iscomplexobj(k):
        raise InvalidParameterError(f"the elliptic modulus k must be a real number in [0, 1), got {k!r}")
    try:
        kf = float(k)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"the elliptic modulus k must be a real number in [0, 1), got {k!r}") from None
    if not (0.0 <= kf < 1.0):
        raise InvalidParameterError(
            f"the elliptic modulus k must lie in [0, 1) (k = 1 is the degenerate hyperbolic limit, K = inf; "
            f"use |k| for negative k), got {kf}"
        )
    return kf


def periods(k: float) -> tuple[float, float]:
    """``(K, K')`` = complete elliptic integrals ``K(k)``, ``K(√(1−k²))`` (``K' = inf`` at ``k = 0``)."""
    m = check_modulus(k) ** 2
    return float(special.ellipk(m)), float(special.ellipkm1(m)) if m > 0 else float("inf")


def _real_parts(u, k):
    """Reduced real calls: ``(s, c, d, s1, c1, d1, flip_x, flip_y)`` for ``u = x + iy`` (``flip_*``: the
    ``(−1)^n`` of the reductions ``x → x − 2Kn``, ``y → y − 2K'n``)."""
    m = k * k
    K, Kp = periods(k)
    u = np.asarray(u, dtype=complex)
    x, y = u.real, u.imag
    nx = np.round(x / (2.0 * K))
    fx = 1.0 - 2.0 * np.mod(nx, 2.0)
    x = x - 2.0 * K * nx
    if np.isfinite(Kp):
        ny = np.round(y / (2.0 * Kp))
        fy = 1.0 - 2.0 * np.mod(ny, 2.0)
        y = y - 2.0 * Kp * ny
    else:
        fy = np.ones_like(y)
    s, c, d = _reflected(x, m, K, np.sqrt((1.0 - k) * (1.0 + k)))
    s1, c1, d1 = _reflected(y, 1.0 - m, Kp, k)
    return s * fx, c * fx, d, s1 * fy, c1 * fy, d1


def _reflected(x, m, K, kc):
    """``sn, cn, dn(x | m)`` for real ``|x| ≤ K`` (``kc = √(1−m)``): beyond ``K/2`` from ``t = K − |x|`` by
    ``sn = cd t``, ``cn = k' sd t``, ``dn = k' nd t`` (A&S 16.8.1), so that ``cn`` and ``dn`` keep their relative
    accuracy near ``K``, where they are small (Cephes computes ``cn = cos(am x)``, absolute accuracy only)."""
    s, c, d, _ = special.ellipj(x, m)
    far = np.abs(x) > 0.5 * K
    if np.any(far):
        st, ct, dt, _ = special.ellipj(np.where(far, K - np.abs(x), 0.0), m)
        s = np.where(far, np.sign(x) * ct / dt, s)
        c = np.where(far, kc * st / dt, c)
        d = np.where(far, kc / dt, d)
    return s, c, d


def _numerators(u, k):
    """``(δ, N_s, N_c, N_d)``: ``sn = N_s/δ``, ``cn = N_c/δ``, ``dn = N_d/δ`` (module docstring)."""
    s, c, d, s1, c1, d1 = _real_parts(u, k)
    m = k * k
    delta = c1 * c1 + m * s * s * s1 * s1
    ns = s * d1 + 1j * c * d * s1 * c1
    nc = c * c1 - 1j * s * d * s1 * d1
    nd = d * c1 * d1 - 1j * m * s * c * s1
    return delta, ns, nc, nd


def ellipfun(u, k) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(sn u, cn u, dn u)`` of modulus ``k`` at complex ``u`` (array), each of ``u``'s shape (inf/nan at a
    pole of ``sn``: use :func:`w_values` there)."""
    k = check_modulus(k)
    delta, ns, nc, nd = _numerators(u, k)
    with np.errstate(divide="ignore", invalid="ignore"):
        return ns / delta, nc / delta, nd / delta


def w_values(x, k) -> np.ndarray:
    """``(ns x, ds x, cs x)``, shape ``(3,) + x.shape``: finite everywhere except at the zeros ``2mK + 2inK'`` of
    ``sn`` (the poles of every ``w_a``; inf or nan there), including at the poles of ``sn`` (the first Taylor
    coefficient of :func:`w_taylor`, whose shifted form serves the pole rows)."""
    return _w_series(x, check_modulus(k), 1, strict=False)[:, 0]


# ---------------------------------------------------------------- Taylor series (leading axis = order)


def _ode_series(s0, c0, d0, m, order):
    """Taylor coefficients ``(S, C, D)``, each ``(order,) + shape``, from the values at the point."""
    shape = np.broadcast_shapes(np.shape(s0), np.shape(c0), np.shape(d0))
    S, C, D = (np.zeros((order,) + shape, dtype=complex) for _ in range(3))
    S[0], C[0], D[0] = s0, c0, d0
    for n in range(order - 1):
        cd = np.sum(C[: n + 1] * D[n::-1], axis=0)
        sd = np.sum(S[: n + 1] * D[n::-1], axis=0)
        sc = np.sum(S[: n + 1] * C[n::-1], axis=0)
        S[n + 1] = cd / (n + 1)
        C[n + 1] = -sd / (n + 1)
        D[n + 1] = -m * sc / (n + 1)
    return S, C, D


def sncndn_taylor(u0, k, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Taylor coefficients of ``sn, cn, dn`` at ``u0`` (not a pole of ``sn``), each ``(order,) + u0.shape``."""
    k = check_modulus(k)
    s, c, d = ellipfun(u0, k)
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(c)) and np.all(np.isfinite(d))):
        raise InvalidParameterError("sncndn_taylor: u0 is a pole of sn (k·u0 at iK' modulo the periods)")
    return _ode_series(s, c, d, k * k, int(order))


def _split(x0, k):
    """Reduce ``x0`` to the rectangle ``|Re| ≤ K``, ``|Im| ≤ K'`` (signs ``(3,) + shape`` of each ``w_a``), and
    mark the points within ``K'/2`` of a pole row of ``sn`` (``u = x − iK' sign(Im x)`` there)."""
    K, Kp = periods(k)
    x0 = np.asarray(x0, dtype=complex)
    nx = np.round(x0.real / (2.0 * K))
    par_x = np.mod(nx, 2.0)
    x = x0 - 2.0 * K * nx
    sign = np.where(par_x[None] == 1.0, EPS_K.reshape((3,) + (1,) * x.ndim), 1.0)
    if not np.isfinite(Kp):
        return x, sign * np.ones((3,) + x.shape), np.zeros(x.shape, dtype=bool)
    ny = np.round(x.imag / (2.0 * Kp))
    par_y = np.mod(ny, 2.0)
    x = x - 2j * Kp * ny
    sign = sign * np.where(par_y[None] == 1.0, EPS_KP.reshape((3,) + (1,) * x.ndim), 1.0)
    return x, sign, np.abs(x.imag) > 0.5 * Kp


def w_taylor(x0, k, order: int) -> np.ndarray:
    r"""Taylor coefficients of ``w_a = (ns, ds, cs)`` at ``x0`` (not a zero of ``sn``), shape
    ``(3, order) + x0.shape``; ``φ_{a,n}(x0) = (−1)^n · w_taylor(x0, k, n + 1)[a, n]``."""
    return _w_series(x0, check_modulus(k), int(order), strict=True)


def _w_series(x0, k, order, strict):
    x, sign, near = _split(x0, k)
    out = np.zeros((3, order) + x.shape, dtype=complex)
    K, Kp = periods(k)
    far = ~near
    if np.any(far):
        s, c, d = ellipfun(x[far], k)
        S, C, D = _ode_series(s, c, d, k * k, order)
        if strict and np.any(S[0] == 0):
            raise InvalidParameterError("w_taylor: x0 is a pole of w_a (a zero of sn: 2mK + 2inK')")
        one = np.zeros_like(S)
        one[0] = 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            out[0][:, far] = div(one, S)
            out[1][:, far] = div(D, S)
            out[2][:, far] = div(C, S)
    if np.any(near):
        xs = x[near]
        up = xs.imag > 0  # x = u + iK' (up) or u − iK'
        u = xs - 1j * Kp * np.where(up, 1.0, -1.0)
        S, C, D = sncndn_taylor(u, k, order)
        pm = np.where(up, 1.0, -1.0)  # ds, cs flip under the shift by 2iK' between the two rows
        out[0][:, near] = k * S
        out[1][:, near] = -1j * k * pm * C
        out[2][:, near] = -1j * pm * D
    return out * sign[:, None]


def w_regular(k, order: int) -> np.ndarray:
    """Taylor coefficients at 0 of ``w_a(x) − 1/x``, shape ``(3, order)`` (real; the odd coefficients of
    ``x^{2j+1}`` only are nonzero).  From ``sn = x T(x)``: ``w_a − 1/x = (N_a/T − 1)/x``, ``N = (1, dn, cn)``."""
    k = check_modulus(k)
    order = int(order)
    S, C, D = _ode_series(np.zeros(()), np.ones(()), np.ones(()), k * k, order + 2)
    T = S[1:]
    out = np.empty((3, order))
    for a, N in enumerate((np.eye(order + 1, 1).ravel().astype(complex), D[: order + 1], C[: order + 1])):
        q = div(N, T)
        out[a] = q[1 : order + 1].real
    return out


# ---------------------------------------------------------------- the ν²-expansion function F = cs dn + Z


def _zeta_real(x, m, K, E):
    """``Z(x | m) = E(am x | m) − (E/K) x`` for real ``x`` (``K`` may be inf at ``m = 1``)."""
    _, _, _, ph = special.ellipj(x, m)
    lin = 0.0 if not np.isfinite(K) else E / K
    return special.ellipeinc(ph, m) - lin * x


def _zeta_parts(u, k):
    """``(Z_0(v), csdn(v), c)`` with ``Z(u) = Z_0(v) + csdn(v) + c`` and ``F(u) = Z_0(v) + c`` where ``F = cs dn + Z``:
    ``u`` is reduced to ``|Re| ≤ K``, ``|Im| ≤ K'`` (``Z(u + 2K) = Z(u)``, ``Z(u + 2iK') = Z(u) − iπ/K``) and, within
    ``K'/2`` of a pole row, written ``u = v ± iK'`` with ``Z(v ± iK') = Z(v) + cs(v) dn(v) ∓ iπ/(2K)`` and
    ``cs dn(v ± iK') = −cs dn(v)`` (A&S 17.4.38), so that the poles at ``iK'`` are never evaluated; elsewhere
    ``v = u``, ``csdn = 0`` and ``c`` the reduction's shift."""
    m = k * k
    K, Kp = periods(k)
    E = float(special.ellipe(m))
    Ep = float(special.ellipe(1.0 - m))
    u = np.asarray(u, dtype=complex)
    nx = np.round(u.real / (2.0 * K))
    u = u - 2.0 * K * nx
    const = np.zeros(u.shape, dtype=complex)
    csdn = np.zeros(u.shape, dtype=complex)
    if np.isfinite(Kp):
        ny = np.round(u.imag / (2.0 * Kp))
        u = u - 2j * Kp * ny
        const = -1j * np.pi / K * ny
        row = np.where(np.abs(u.imag) > 0.5 * Kp, np.sign(u.imag), 0.0)
        u = u - 1j * Kp * row
        const = const - row * 1j * np.pi / (2.0 * K)
        if np.any(row != 0):
            _, _, dn = ellipfun(u, k)
            with np.errstate(divide="ignore", invalid="ignore"):
                csdn = np.where(row != 0, w_values(u, k)[2] * dn, 0.0)
    x, y = u.real, u.imag
    zx = _zeta_real(x, m, K, E)
    s1, c1, d1, _ = special.ellipj(y, 1.0 - m)
    lin = 0.0 if not np.isfinite(Kp) else np.pi / (2.0 * K * Kp)
    # |y| <= K'/2 here: c1 >= cn(K'/2 | m1) > 0, no division by zero
    ziy = 1j * (d1 * s1 / c1 - _zeta_real(y, 1.0 - m, Kp, Ep) - lin * y)
    snu = ellipfun(u, k)[0]
    z0 = zx + ziy - m * special.ellipj(x, m)[0] * (1j * s1 / c1) * snu
    return z0, csdn, const


def jacobi_zeta(u, k) -> np.ndarray:
    """Jacobi's ``Z(u)`` at complex ``u`` (module docstring, :func:`_zeta_parts`), shape of ``u``; poles at ``iK'``
    modulo the periods."""
    z0, csdn, const = _zeta_parts(u, check_modulus(k))
    return z0 + csdn + const


def curve_function(x, k) -> np.ndarray:
    """``F(x) = cs(x) dn(x) + Z(x)`` (module docstring), the simple-pole function of the ``ν²`` expansion; near the
    pole rows of ``sn`` ``F(v ± iK') = Z(v) ∓ iπ/(2K)`` (the poles of ``cs dn`` and ``Z`` cancel exactly)."""
    k = check_modulus(k)
    x = np.asarray(x, dtype=complex)
    z0, csdn, const = _zeta_parts(x, k)
    near = csdn != 0
    _, _, dn = ellipfun(x, k)
    with np.errstate(divide="ignore", invalid="ignore"):
        direct = w_values(x, k)[2] * dn
    return np.where(near, 0.0, direct) + z0 + const


def curve_function_taylor(x0, k, order: int) -> np.ndarray:
    """Taylor coefficients of ``F`` at ``x0`` (not a lattice point ``2mK + 2inK'``), ``(order,) + x0.shape``,
    from ``F(x0)`` and ``F' = 1 − E/K − ns²``."""
    k = check_modulus(k)
    order = int(order)
    K, _ = periods(k)
    x0 = np.asarray(x0, dtype=complex)
    out = np.zeros((order,) + x0.shape, dtype=complex)
    out[0] = curve_function(x0, k)
    if order > 1:
        ns = w_taylor(x0, k, order - 1)[0]
        dF = -mul(ns, ns)
        dF[0] += 1.0 - float(special.ellipe(k * k)) / K
        out[1:] = dF / np.arange(1, order).reshape((-1,) + (1,) * x0.ndim)
    return out


def curve_function_regular(k, order: int) -> np.ndarray:
    """Taylor coefficients at 0 of ``F(x) − 1/x`` (real, odd), shape ``(order,)``: from ``F' = 1 − E/K − ns²``
    and ``ns = 1/x + ρ(x)``: ``(F − 1/x)' = 1 − E/K − 2ρ/x − ρ²``."""
    k = check_modulus(k)
    order = int(order)
    K, _ = periods(k)
    rho = w_regular(k, order + 1)[0]
    d = -mul(rho, rho)[:order]  # −ρ²
    d[: order] -= 2.0 * rho[1 : order + 1]  # −2ρ/x (ρ(0) = 0: ρ is odd)
    d[0] += 1.0 - float(special.ellipe(k * k)) / K
    out = np.zeros(order)
    out[1:] = d[: order - 1] / np.arange(1, order)
    return out
