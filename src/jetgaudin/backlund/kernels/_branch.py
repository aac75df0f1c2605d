r"""The default branch of ``ν(η)`` (the branch rule of :func:`jetgaudin.nu`), compiled, for the first step of a
run (:func:`._drivers.nu_default` is the driver).  Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from numba import njit, prange

from ._scalar import _abs2, _cdiv, _integrals


@njit(cache=True, error_model="numpy", inline="always")
def _nu2_and_derivative(kappa, lam):
    r"""``P = ν²(λ) = Σ κ_m λ^{-m}``, ``dP/dλ`` and ``Σ |κ_m| |λ|^{-m}`` (Horner in ``z = 1/λ``)."""
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


@njit(cache=True, error_model="numpy")
def _nu_default_one(x, b, eta, sheet):
    r"""``ν(η)`` on the default branch (:func:`jetgaudin.nu`): the root positive at ``a = Re η``, continued along
    the vertical segment ``[a, η]``.  The continuation is done numerically with the closest-root rule on steps
    ``h ≤ 0.1 |ν²|/|dν²/dλ|`` (``ν²`` changes by at most 10 % per step, so its square root turns by less than
    0.06 rad and the closest root is the continued one; near a branch point at distance ``d`` the steps are
    ``≲ 0.1 d``).  Returns ``sheet · (±√ν²(η))`` and ``ok``; ``ok`` is false for ``Re η = 0``, ``ν(a) = 0`` or
    a branch point on the segment (``|ν²| ≤ 1e-13 Σ|κ_m λ^{-m}|``).  No roots are computed (the NumPy rule
    uses them), which keeps LAPACK out of the compiled code."""
    N = x.shape[0] // 3
    kappa = np.empty(2 * N + 1)
    kappa[0] = b * b
    _integrals(x, b, N, kappa[1:])
    a = eta.real
    if a == 0.0:
        return complex(0.0, 0.0), False
    p, dp, sc = _nu2_and_derivative(kappa, complex(a, 0.0))
    if not (p.real > 1e-13 * sc):
        return complex(0.0, 0.0), False
    nu = complex(math.sqrt(p.real), 0.0)
    Y = eta.imag
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


@njit(cache=True, error_model="numpy", parallel=True)
def _nu_default_batch(X, b, eta, sheet, nu, ok):
    for i in prange(X.shape[0]):
        nu[i], ok[i] = _nu_default_one(X[i], b[i], eta[i], sheet)


@njit(cache=True, error_model="numpy")
def _nu_default_serial(X, b, eta, sheet, nu, ok):
    # small batches: no parallel region (its start-up costs more than the work and loads the threading layer)
    for i in range(X.shape[0]):
        nu[i], ok[i] = _nu_default_one(X[i], b[i], eta[i], sheet)
