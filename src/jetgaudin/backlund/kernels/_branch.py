r"""The default branch of ``ν(η)`` (the branch rule of :func:`jetgaudin.nu`), compiled, for the first step of a
run (:func:`._drivers.nu_default` is the driver).  One kernel, serial, without the GIL: the driver runs parts of a
large batch on threads of its own (the rule costs ~0.05 µs per orbit for N = 3, so a parallel region of Numba's,
compiled separately, would cost more compile time than it saves).  Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import math

from numba import njit

from ._scalar import _abs2, _cdiv, _csqrt, block


@block()
def _nu2_and_derivative(kappa, lam):
    r"""``P = ν²(λ) = Σ κ_m λ^{-m}``, ``dP/dλ`` and ``Σ |κ_m| |λ|^{-m}`` (Horner in ``z = 1/λ``).  Only the
    stepping (the rare case) calls it: left to LLVM rather than inlined by Numba at its two call sites, which
    compiles faster (A/B in fresh processes: 9.5 s against 11.6 s over three rounds, load ≈ 3)."""
    z = _cdiv(complex(1.0, 0.0), lam)
    az = math.sqrt(_abs2(z))
    p = complex(0.0, 0.0)
    dp = complex(0.0, 0.0)
    sc = 0.0
    for m in range(kappa.shape[0] - 1, -1, -1):
        dp = dp * z + p
        p = p * z + kappa[m]
        sc = sc * az + abs(kappa[m])
    return p, -(dp * z * z), sc


@block()
def _root_nu2(p, sc):
    r"""The principal ``√p`` and the rule's test against a branch point, ``|p| > 10⁻¹³ sc``.  The root is
    :func:`._scalar._csqrt` (the square root of the steps; ``|p|`` is its own ``√(a² + b²)``, shared by LLVM), on
    ``p`` scaled by an exact power of 4 where that ``|p|`` is outside ``(1e-150, 1e150)`` (then ``|p|`` is
    ``math.hypot``'s, which neither overflows nor underflows): ``√(cX) = √c·√X`` bit for bit for ``c = 4^k``."""
    ap = math.sqrt(_abs2(p))
    if 1e-150 < ap < 1e150:
        return _csqrt(p), ap > 1e-13 * sc
    ap = math.hypot(p.real, p.imag)
    if not (ap > 1e-13 * sc):  # also for p not finite
        return complex(0.0, 0.0), False
    k = math.frexp(ap)[1] // 2
    return _csqrt(p * math.ldexp(1.0, -2 * k)) * math.ldexp(1.0, k), True


@block(inline="always")
def _kappa(X, i, b, N, kappa):
    r"""``κ_1..κ_2N`` of the row ``X[i]`` into ``kappa[1:]``: for each ``m`` the dot products ``X_k·X_{m−k}``,
    ``k = 1, 2, …``, then ``2 b X_{m,z}`` (``m ≤ N``), summed from 0 in that order: the operations, hence the bits,
    of :func:`._scalar._integrals`."""
    for m in range(1, 2 * N + 1):
        km = 0.0
        for k in range(max(1, m - N), min(N, m - 1) + 1):
            u = 3 * (k - 1)
            v = 3 * (m - k - 1)
            km += X[i, u] * X[i, v] + X[i, u + 1] * X[i, v + 1] + X[i, u + 2] * X[i, v + 2]
        if m <= N:
            km += 2.0 * b * X[i, 3 * m - 1]
        kappa[m] = km


@block(inline="always")
def _kappa3(X, i, b, kappa):
    r""":func:`_kappa` for N = 3 written out (the same operations in the same order, the same bits; 5× faster
    than the loops, whose bounds depend on ``m``)."""
    x0, x1, x2 = X[i, 0], X[i, 1], X[i, 2]
    x3, x4, x5 = X[i, 3], X[i, 4], X[i, 5]
    x6, x7, x8 = X[i, 6], X[i, 7], X[i, 8]
    kappa[1] = 0.0 + 2.0 * b * x2
    kappa[2] = (0.0 + (x0 * x0 + x1 * x1 + x2 * x2)) + 2.0 * b * x5
    kappa[3] = ((0.0 + (x0 * x3 + x1 * x4 + x2 * x5)) + (x3 * x0 + x4 * x1 + x5 * x2)) + 2.0 * b * x8
    kappa[4] = ((0.0 + (x0 * x6 + x1 * x7 + x2 * x8)) + (x3 * x3 + x4 * x4 + x5 * x5)) + (x6 * x0 + x7 * x1 + x8 * x2)
    kappa[5] = (0.0 + (x3 * x6 + x4 * x7 + x5 * x8)) + (x6 * x3 + x7 * x4 + x8 * x5)
    kappa[6] = 0.0 + (x6 * x6 + x7 * x7 + x8 * x8)


@block(inline="always")
def _nu_default_one(X, i, b, eta, sheet, kappa):
    r"""``ν(η)`` on the default branch (:func:`jetgaudin.nu`): the root positive at ``a = Re η``, continued along
    the vertical segment ``[a, η]``, for the state ``X[i]``; ``kappa`` is a work array of ``2N + 1`` entries.

    **No stepping in the common case (exact test).**  Let ``P(λ) = ν²(λ)``, ``Y = Im η`` and
    ``D = Σ_{m≥1} m |κ_m| |a|^{-m-1}``, a bound of ``|P'|`` on the vertical line ``Re λ = a``
    (``P'(λ) = −Σ m κ_m λ^{-m-1}``, ``|λ| ≥ |a|`` there).  On the segment ``λ = a + iy``, ``|y| ≤ |Y|``,
    ``|λ| ≥ |a|``, so ``|P'(λ)| ≤ D`` and ``|P(λ) − P(a)| ≤ |Y| D``.  If ``|Y| D ≤ P(a)/2`` then
    ``Re P(λ) ≥ P(a)/2 > 0`` on the whole segment: ``P`` never meets the cut ``(−∞, 0]`` of the principal square
    root nor zero, so ``√P`` (principal) is continuous along the segment, equals the positive root at ``a``, and
    is therefore the continued root: ``ν(η) = √P(η)``.  The factor 1/2 covers the rounding of ``P(a)`` and ``D``
    (evaluated in real arithmetic; ``P(a) > 2·10⁻¹³ Σ|κ_m||a|^{-m}`` is required, twice the stepping's threshold,
    so their relative errors are below ``10⁻²`` and the stepping would not have refused ``a``).  The value is the
    same bits as the stepping below, whose last step takes the same ``√P(η)`` (same operations).

    **Speed.**  ``κ`` (:func:`_kappa3` for N = 3, written out; :func:`_kappa` otherwise; the bits of
    :func:`._scalar._integrals`), then one loop of the three Horner sums in real arithmetic at ``a`` (``P(a)``,
    ``Σ|κ_m||a|^{-m}``, ``D``) and the complex one at ``η`` (``P(η)``, ``Σ|κ_m||η|^{-m}``: the operations of
    :func:`_nu2_and_derivative`), and the root of :func:`_root_nu2` in place of ``cmath.sqrt``: 0.054 against
    0.095 µs per orbit for κ accumulated in place, three loops and ``cmath.sqrt`` (N = 3, one thread, AMD EPYC).

    **Otherwise: stepping** with the closest-root rule on steps ``h ≤ 0.1 |ν²|/|dν²/dλ|`` (``ν²`` changes by at
    most 10 % per step, so its square root turns by less than 0.06 rad and the closest root is the continued
    one; near a branch point at distance ``d`` the steps are ``≲ 0.1 d``).

    Returns ``sheet · ν(η)`` and ``ok``; ``ok`` is false for ``Re η = 0``, ``ν(a) = 0`` or a branch point on the
    segment (``|ν²| ≤ 1e-13 Σ|κ_m λ^{-m}|``).  No roots are computed (the NumPy rule uses them), which keeps
    LAPACK out of the compiled code."""
    a = eta.real
    if a == 0.0:
        return complex(0.0, 0.0), False
    Y = eta.imag
    N = X.shape[1] // 3
    if N == 3:
        _kappa3(X, i, b, kappa)
    else:
        _kappa(X, i, b, N, kappa)
    zr = 1.0 / a
    wr = abs(zr)
    zc = _cdiv(complex(1.0, 0.0), eta)
    az = math.sqrt(_abs2(zc))
    pa = 0.0
    sa = 0.0
    d = 0.0
    p = complex(0.0, 0.0)
    sc = 0.0
    for m in range(2 * N, 0, -1):
        km = kappa[m]
        pa = pa * zr + km
        sa = sa * wr + abs(km)
        d = (d + m * abs(km)) * wr
        p = p * zc + km
        sc = sc * az + abs(km)
    k0 = b * b
    kappa[0] = k0
    pa = pa * zr + k0
    sa = sa * wr + abs(k0)
    d = d * wr
    p = p * zc + k0
    sc = sc * az + abs(k0)
    if Y != 0.0 and pa > 2e-13 * sa and abs(Y) * d <= 0.5 * pa:
        r, ok = _root_nu2(p, sc)  # the stepping's test and root at its last point
        if not ok:
            return complex(0.0, 0.0), False
        return sheet * r, True
    p, dp, sc = _nu2_and_derivative(kappa, complex(a, 0.0))
    if not (p.real > 1e-13 * sc):
        return complex(0.0, 0.0), False
    nu = complex(math.sqrt(p.real), 0.0)
    y = 0.0
    for _ in range(100000):
        if y == Y:
            break
        h = 0.1 * math.sqrt(_abs2(p)) / max(math.sqrt(_abs2(dp)), 1e-300)
        if h >= abs(Y - y):
            y = Y
        else:
            y = y + math.copysign(h, Y)
        p, dp, sc = _nu2_and_derivative(kappa, complex(a, y))
        r, ok = _root_nu2(p, sc)
        if not ok:
            return complex(0.0, 0.0), False
        nu = r if r.real * nu.real + r.imag * nu.imag >= 0.0 else -r
    else:
        return complex(0.0, 0.0), False
    return sheet * nu, True


@njit(cache=True, error_model="numpy", nogil=True)
def nu_default_kernel(X, b, eta, sheet, kappa, nu, ok):
    """:func:`_nu_default_one` for each orbit of ``X`` (B, 3N) with per-orbit ``b``, ``eta``; ``kappa`` (2N + 1,)
    is the work array (allocated once per call, not per orbit)."""
    for i in range(X.shape[0]):
        nu[i], ok[i] = _nu_default_one(X, i, b[i], eta[i], sheet, kappa)
