r"""The N = 3 compiled route: the generic route unrolled in scalars (:func:`_step3`, :func:`run_orbit3`), with
two changes that shorten the chain of dependent operations (round-off level; ``tests/test_routes.py`` compares
this route with the generic route and with the NumPy route): ``ℓ(η)`` as ``b + Σ ℓ_m z^m`` with precomputed
``z^m`` (Estrin instead of Horner), and ``ν1`` continued by one Newton step ``ν ← ν + (ν² − ν_prev²)/(2ν_prev)``
(``ν²`` is an integral of the map, so the correction is at round-off level; the closest-root square root is
used otherwise).  The blocks here are scalars only and inlined, so the lock-step lanes (:mod:`._lanes`) perform
the same operations in the same order.  Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._scalar import (
    _RESIDUAL_TOL2,
    _abs2,
    _cdiv,
    _continue_nu,
    _cr,
    _division_constants,
    _drift_pass,
    _eigvec,
    _integrals,
    _m0_from_k,
    _products,
    _products0,
)
from ._status import STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL

# ---------------------------------------------------------------------------------------------
# N = 3: the same route, unrolled, with the parameters of M0 in closed form (shorter dependency chain)
# ---------------------------------------------------------------------------------------------
#
# For a real state the eigenvector datum at η̄ is κ = conj(1/s): with u(η̄) = conj u(η),
# v(η̄) = conj w(η), ν = −conj ν1,  κ = (ν − u(η̄))/v(η̄) = conj(−(u + ν1)/w) = conj(1/s)  since
# s = −w/(u + ν1).  Hence s + κ = (1 + |s|²)/conj(s) never vanishes and, writing s = n/d (the form with
# the larger |d|), q = n·conj(d), ρ = 1/(|n|² + |d|²), δ = η − η̄ = 2i Im η:
#     t = δ conj(s)/(1 + |s|²) = δ conj(q) ρ,      s t = δ |n|² ρ,      −s² t + δ s = δ q ρ,
# so M0 = [[−η + δ|n|²ρ, δ conj(q) ρ], [δ q ρ, −η̄ − δ|n|²ρ]] costs one real division.  ℓ(η) is
# evaluated as b + Σ_m ℓ_m z^m with the powers z^m = η^{-m} precomputed (Estrin instead of Horner),
# and ν1 is continued by one Newton step ν ← ν + (ν² − ν_prev²)/(2ν_prev) from the previous value
# (ν² is an integral of the map, so the correction is at round-off level; the square root with the
# closest-root rule is used if it is not).  These change the result at round-off level only; the
# tests compare this route with the generic route and with the NumPy route.


# ---------------------------------------------------------------------------------------------
# N = 3 building blocks, shared by the single-orbit step and the lock-step lanes (scalars only: inlined
# into both, so the two perform the same operations in the same order and give the same bits)
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always")
def _uvw3(x0, x1, x2, x3, x4, x5, x6, x7, x8):
    """``(u_m, v_m, w_m)`` of ``ℓ_m``, m = 1, 2, 3: ``u = y^3``, ``v = y^1 − i y^2``, ``w = y^1 + i y^2``."""
    return (x2, complex(x0, -x1), complex(x0, x1), x5, complex(x3, -x4), complex(x3, x4),
            x8, complex(x6, -x7), complex(x6, x7))


@njit(cache=True, error_model="numpy", inline="always")
def _ell3(b, z1, z2, z3, u1, v1, w1, u2, v2, w2, u3, v3, w3):
    """``ℓ(η) = ℓ_0 + Σ ℓ_m z^m`` (``z^m = η^-m`` precomputed): entries ``(u, v, w)``."""
    u = (complex(b, 0.0) + _cr(z1, u1)) + (_cr(z2, u2) + _cr(z3, u3))
    v = (v1 * z1 + v2 * z2) + v3 * z3
    w = (w1 * z1 + w2 * z2) + w3 * z3
    return u, v, w


@njit(cache=True, error_model="numpy", inline="always")
def _R3(m00, m01, m10, m11, b, u1, v1, w1, u2, v2, w2, u3, v3, w3):
    """Entries of ``R(λ) = λ² ℓ + λ (M0 ℓ + ℓ adj M0) + M0 ℓ adj M0`` by powers, ``R_0 … R_5`` (``R_0 = b``)."""
    T1u0, T1v0, T1w0, T2u0, T2v0, T2w0 = _products0(m00, m01, m10, m11, b)
    T1u1, T1v1, T1w1, T2u1, T2v1, T2w1 = _products(m00, m01, m10, m11, u1, v1, w1)
    T1u2, T1v2, T1w2, T2u2, T2v2, T2w2 = _products(m00, m01, m10, m11, u2, v2, w2)
    T1u3, T1v3, T1w3, T2u3, T2v3, T2w3 = _products(m00, m01, m10, m11, u3, v3, w3)
    return (complex(b, 0.0),
            complex(u1, 0.0) + T1u0, v1 + T1v0, w1 + T1w0,
            (complex(u2, 0.0) + T1u1) + T2u0, (v2 + T1v1) + T2v0, (w2 + T1w1) + T2w0,
            (complex(u3, 0.0) + T1u2) + T2u1, (v3 + T1v2) + T2v1, (w3 + T1w2) + T2w1,
            T1u3 + T2u2, T1v3 + T2v2, T1w3 + T2w2,
            T2u3, T2v3, T2w3)


@njit(cache=True, error_model="numpy", inline="always")
def _bottom_up3(Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, inv_d2):
    """Laurent division of ``R`` by ``λ² + δ1 λ + δ2`` from the lowest power (``|η| ≥ 1``): ``Q_1 … Q_3`` and
    the squared residual of the two unused equations."""
    Qu3 = _cr(Ru5, inv_d2)
    Qv3 = _cr(Rv5, inv_d2)
    Qw3 = _cr(Rw5, inv_d2)
    Qu2 = _cr(Ru4 - _cr(Qu3, d1), inv_d2)
    Qv2 = _cr(Rv4 - _cr(Qv3, d1), inv_d2)
    Qw2 = _cr(Rw4 - _cr(Qw3, d1), inv_d2)
    Qu1 = _cr((Ru3 - Qu3) - _cr(Qu2, d1), inv_d2)
    Qv1 = _cr((Rv3 - Qv3) - _cr(Qv2, d1), inv_d2)
    Qw1 = _cr((Rw3 - Qw3) - _cr(Qw2, d1), inv_d2)
    Qu0 = _cr((Ru2 - Qu2) - _cr(Qu1, d1), inv_d2)
    Qv0 = _cr((Rv2 - Qv2) - _cr(Qv1, d1), inv_d2)
    Qw0 = _cr((Rw2 - Qw2) - _cr(Qw1, d1), inv_d2)
    res2 = max(_abs2(Ru0 - Qu0), _abs2(Qv0), _abs2(Qw0))
    res2 = max(
        res2,
        _abs2(Ru1 - Qu1 - _cr(Qu0, d1)),
        _abs2(Rv1 - Qv1 - _cr(Qv0, d1)),
        _abs2(Rw1 - Qw1 - _cr(Qw0, d1)),
    )
    return Qu1, Qv1, Qw1, Qu2, Qv2, Qw2, Qu3, Qv3, Qw3, res2


@njit(cache=True, error_model="numpy", inline="always")
def _top_down3(Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, d2):
    """The same division from the highest power (``|η| < 1``)."""
    Qu0 = Ru0
    Qu1 = Ru1 - _cr(Qu0, d1)
    Qv1 = Rv1
    Qw1 = Rw1
    Qu2 = (Ru2 - _cr(Qu1, d1)) - _cr(Qu0, d2)
    Qv2 = Rv2 - _cr(Qv1, d1)
    Qw2 = Rw2 - _cr(Qw1, d1)
    Qu3 = (Ru3 - _cr(Qu2, d1)) - _cr(Qu1, d2)
    Qv3 = (Rv3 - _cr(Qv2, d1)) - _cr(Qv1, d2)
    Qw3 = (Rw3 - _cr(Qw2, d1)) - _cr(Qw1, d2)
    res2 = max(
        _abs2(Ru4 - _cr(Qu3, d1) - _cr(Qu2, d2)),
        _abs2(Rv4 - _cr(Qv3, d1) - _cr(Qv2, d2)),
        _abs2(Rw4 - _cr(Qw3, d1) - _cr(Qw2, d2)),
    )
    res2 = max(res2, _abs2(Ru5 - _cr(Qu3, d2)), _abs2(Rv5 - _cr(Qv3, d2)), _abs2(Rw5 - _cr(Qw3, d2)))
    return Qu1, Qv1, Qw1, Qu2, Qv2, Qw2, Qu3, Qv3, Qw3, res2


@njit(cache=True, error_model="numpy", inline="always")
def _step3(x, b, eta, z1, z2, z3, d1, d2, inv_d2, bottom_up, nu, nu_sq, inv_2nu, newton):
    """One N = 3 step from the tuple ``x`` (9 floats); returns ``(status, ν1, x_new)``."""
    u1, v1, w1, u2, v2, w2, u3, v3, w3 = _uvw3(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8])
    u, v, w = _ell3(b, z1, z2, z3, u1, v1, w1, u2, v2, w2, u3, v3, w3)  # ℓ(η) = Σ ℓ_m η^{-m}
    nu2 = u * u + v * w
    if newton:
        c = nu2 - nu_sq
        if _abs2(c) <= 1e-16 * _abs2(nu2):
            nu = nu + c * inv_2nu
        else:
            nu = _continue_nu(u, v, w, nu)
    k1, k2, nk, st = _eigvec(u, v, w, nu)
    if st != STATUS_OK:
        return st, nu, x
    m00, m01, m10, m11 = _m0_from_k(eta, k1, k2, nk)
    (Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5,
     Rw5) = _R3(m00, m01, m10, m11, b, u1, v1, w1, u2, v2, w2, u3, v3, w3)
    if bottom_up:
        Qu1, Qv1, Qw1, Qu2, Qv2, Qw2, Qu3, Qv3, Qw3, res2 = _bottom_up3(
            Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, inv_d2)
    else:
        Qu1, Qv1, Qw1, Qu2, Qv2, Qw2, Qu3, Qv3, Qw3, res2 = _top_down3(
            Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, d2)
    e2 = max(b * b, u1 * u1, _abs2(v1), u2 * u2, _abs2(v2), u3 * u3, _abs2(v3))
    sc = 1.0 + math.sqrt(e2)
    xn = (
        0.5 * (Qv1.real + Qw1.real),
        0.5 * (Qw1.imag - Qv1.imag),
        Qu1.real,
        0.5 * (Qv2.real + Qw2.real),
        0.5 * (Qw2.imag - Qv2.imag),
        Qu2.real,
        0.5 * (Qv3.real + Qw3.real),
        0.5 * (Qw3.imag - Qv3.imag),
        Qu3.real,
    )
    if not (res2 <= _RESIDUAL_TOL2 * sc * sc):
        return STATUS_RESIDUAL, nu, x
    acc = ((xn[0] + xn[1]) + (xn[2] + xn[3])) + ((xn[4] + xn[5]) + (xn[6] + xn[7])) + xn[8]
    if not (acc - acc == 0.0):  # NaN or inf somewhere
        return STATUS_NONFINITE, nu, x
    return STATUS_OK, nu, xn


@njit(cache=True, error_model="numpy")
def run_orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final, drift, want_drift):
    """:func:`run_orbit` for ``N = 3`` (``x0`` of shape ``(9,)``) by the closed-form route of :func:`_step3`
    (equal to the generic route to round-off)."""
    I0 = np.empty(6)
    Ib = np.empty(6)
    x = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8])
    for i in range(9):
        out[0, i] = x0[i]
    _integrals(x0, b, 3, I0)
    for k in range(6):
        drift[k] = 0.0
    z1 = _cdiv(complex(1.0, 0.0), eta)
    z2 = z1 * z1
    z3 = z2 * z1
    d1, d2, inv_d2, bottom_up = _division_constants(eta)
    nu = nu0
    status = STATUS_OK
    n = 0
    for n in range(steps):
        # quantities of the previous ν1, off the critical path of the step
        nu_sq = nu * nu
        inv_2nu = _cdiv(complex(1.0, 0.0), nu + nu)
        status, nu, x = _step3(x, b, eta, z1, z2, z3, d1, d2, inv_d2, bottom_up, nu, nu_sq, inv_2nu,
                               n > 0 or cont)
        if status != STATUS_OK:
            break
        if (n + 1) % save_every == 0:
            j = (n + 1) // save_every
            for i in range(9):
                out[j, i] = x[i]
    else:
        n = steps
    for i in range(9):
        final[i] = x[i]
    if want_drift:
        _drift_pass(out, final, n // save_every, b, 3, I0, Ib, drift)
    return status, n, nu
