r"""The default branch of ``ν(η)`` (the branch rule of :func:`jetgaudin.nu`), compiled, for the first step of a
run (:func:`._drivers.nu_default` is the driver).  One kernel, serial, without the GIL: the driver runs parts of a
large batch on threads of its own (the rule costs ~0.1 µs per orbit, so a parallel region of Numba's, compiled
separately, would cost more compile time than it saves).  Import only after
:func:`._target.configure`.
"""

from __future__ import annotations

import cmath
import math

from numba import njit

from ._scalar import _abs2, _cdiv, block


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


@block(inline="always")
def _nu2_real(kappa, a):
    r"""At a real ``λ = a``, in real arithmetic: ``P(a) = Σ κ_m a^{-m}``, ``S = Σ |κ_m| |a|^{-m}`` and
    ``D = Σ_{m≥1} m |κ_m| |a|^{-m-1}``, a bound of ``|dν²/dλ|`` on the vertical line ``Re λ = a`` (there
    ``|λ| ≥ |a|``, and ``dν²/dλ = −Σ m κ_m λ^{-m-1}``)."""
    z = 1.0 / a
    w = abs(z)
    p = 0.0
    sc = 0.0
    d = 0.0
    for m in range(kappa.shape[0] - 1, 0, -1):
        p = p * z + kappa[m]
        sc = sc * w + abs(kappa[m])
        d = (d + m * abs(kappa[m])) * w
    return p * z + kappa[0], sc * w + abs(kappa[0]), d * w


@block(inline="always")
def _nu2_only(kappa, lam):
    r"""``P = ν²(λ)`` and ``Σ |κ_m| |λ|^{-m}``: the same operations as :func:`_nu2_and_derivative` (same bits)
    without the derivative."""
    z = _cdiv(complex(1.0, 0.0), lam)
    az = math.sqrt(_abs2(z))
    p = complex(0.0, 0.0)
    sc = 0.0
    for m in range(kappa.shape[0] - 1, -1, -1):
        p = p * z + kappa[m]
        sc = sc * az + abs(kappa[m])
    return p, sc


@block(inline="always")
def _nu_default_one(X, i, b, eta, sheet, kappa):
    r"""``ν(η)`` on the default branch (:func:`jetgaudin.nu`): the root positive at ``a = Re η``, continued along
    the vertical segment ``[a, η]``, for the state ``X[i]``; ``kappa`` is a work array of ``2N + 1`` entries.

    **No stepping in the common case (exact test).**  Let ``P(λ) = ν²(λ)``, ``Y = Im η`` and
    ``D = Σ_{m≥1} m |κ_m| |a|^{-m-1}`` (:func:`_nu2_real`).  On the segment ``λ = a + iy``, ``|y| ≤ |Y|``,
    ``|λ| ≥ |a|``, so ``|P'(λ)| ≤ D`` and ``|P(λ) − P(a)| ≤ |Y| D``.  If ``|Y| D ≤ P(a)/2`` then
    ``Re P(λ) ≥ P(a)/2 > 0`` on the whole segment: ``P`` never meets the cut ``(−∞, 0]`` of the principal square
    root nor zero, so ``√P`` (principal) is continuous along the segment, equals the positive root at ``a``, and
    is therefore the continued root: ``ν(η) = √P(η)``.  The factor 1/2 covers the rounding of ``P(a)`` and ``D``
    (evaluated in real arithmetic; ``P(a) > 2·10⁻¹³ Σ|κ_m||a|^{-m}`` is required, twice the stepping's threshold,
    so their relative errors are below ``10⁻²`` and the stepping would not have refused ``a``).  The value is the
    same bits as the stepping below, whose last step takes the same ``√P(η)`` (same operations).

    **Otherwise: stepping** with the closest-root rule on steps ``h ≤ 0.1 |ν²|/|dν²/dλ|`` (``ν²`` changes by at
    most 10 % per step, so its square root turns by less than 0.06 rad and the closest root is the continued
    one; near a branch point at distance ``d`` the steps are ``≲ 0.1 d``).

    Returns ``sheet · ν(η)`` and ``ok``; ``ok`` is false for ``Re η = 0``, ``ν(a) = 0`` or a branch point on the
    segment (``|ν²| ≤ 1e-13 Σ|κ_m λ^{-m}|``).  No roots are computed (the NumPy rule uses them), which keeps
    LAPACK out of the compiled code."""
    N = X.shape[1] // 3
    kappa[0] = b * b
    for m in range(1, 2 * N + 1):  # κ_1..κ_2N: the operations of _scalar._integrals, on the row i of X (no view)
        kappa[m] = 0.0
    for k in range(1, N + 1):
        p = 3 * (k - 1)
        kappa[k] += 2.0 * b * X[i, p + 2]
        for j in range(1, N + 1):
            q = 3 * (j - 1)
            kappa[k + j] += X[i, p] * X[i, q] + X[i, p + 1] * X[i, q + 1] + X[i, p + 2] * X[i, q + 2]
    a = eta.real
    if a == 0.0:
        return complex(0.0, 0.0), False
    Y = eta.imag
    pa, sa, d = _nu2_real(kappa, a)
    if Y != 0.0 and pa > 2e-13 * sa and abs(Y) * d <= 0.5 * pa:
        p, sc = _nu2_only(kappa, eta)
        if not (math.sqrt(_abs2(p)) > 1e-13 * sc):  # the stepping's test at its last point
            return complex(0.0, 0.0), False
        return sheet * cmath.sqrt(p), True
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
        if not (math.sqrt(_abs2(p)) > 1e-13 * sc):
            return complex(0.0, 0.0), False
        r = cmath.sqrt(p)
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
