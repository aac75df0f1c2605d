r"""Compiled (Numba) kernels for the real two-point Bäcklund map (Section 6.2, Appendix 1).

The kernels mirror, operation by operation, the NumPy reference route of
:class:`jetgaudin.backlund.maps.TwoPointBacklund` (``maps.py`` and ``_dressing.py``):

1. ``ℓ(η) = Σ_m ℓ_m η^{-m}`` by Horner's rule in ``z = 1/η``;  ``ℓ(η̄)`` is *not* re-evaluated:
   for a real state ``u(η̄) = conj u(η)``, ``v(η̄) = conj w(η)``, ``w(η̄) = conj v(η)``, and
   Horner's rule in ``conj z`` reproduces these conjugates exactly in floating point
   (``conj(a)·conj(b) = conj(a·b)`` and ``conj(a) + conj(b) = conj(a + b)`` bit for bit);
2. ``ν1`` continued from the previous step by the root of ``u² + vw`` closest to it
   (the first step takes ``ν1`` from the caller, i.e. from the default branch of :func:`jetgaudin.nu`);
3. ``s = (u − ν1)/v = −w/(u + ν1)`` at ``η`` and ``κ = (ν − u)/v = w/(ν + u)`` at ``η̄`` with
   ``ν = −conj ν1``, each with the larger denominator (eqs. (hhh), (x));
   ``t = (η − η̄)/(s + κ)`` (eq. (X));
4. ``M0`` of (mm), ``R(λ) = λ² ℓ + λ (M0 ℓ + ℓ adj M0) + M0 ℓ adj M0`` and the exact Laurent
   division by ``(λ − η)(λ − η̄) = λ² + δ1 λ + δ2`` (``δ1 = −2 Re η``, ``δ2 = |η|²``), bottom-up
   when ``|δ2| ≥ 1`` and top-down otherwise, with the residual of the unused equations;
5. the new state from ``ℓ̆_1..ℓ̆_N`` (:func:`jetgaudin.lax.state_from_ell`), real part.

Differences from the NumPy route, all at round-off level (so orbits agree to round-off, not bit
for bit): complex square root (Numba's ``cmath.sqrt``), and only the three independent entries
``(0,0), (0,1), (1,0)`` of the traceless matrices ``ℓ``, ``R`` and ``ℓ̆`` are formed (``R`` is
traceless because ``tr(M ℓ adj M) = det M · tr ℓ = 0``).  The choice between the two equal forms
of ``s`` and ``κ`` compares squared moduli, and the singularity tests are written in squared moduli:
``|den|² ≤ 4·10⁻²⁶ Σ|·|²`` contains the NumPy test ``|den| ≤ 10⁻¹³ Σ|·|`` (``(Σ a)² ≤ 4 Σ a²``
for four terms), so the compiled route reports a singular step whenever the NumPy route does,
and in addition in a band at most a factor 2 wider.

Complex division is NumPy's (Smith's algorithm with a reciprocal scale), written out so that
no Python exception can be raised inside a parallel loop.  Arithmetic is IEEE without
``fastmath`` (no reassociation, no FMA contraction), so the same kernel gives the same bits in a
single-orbit run and as a member of a parallel ensemble.

Kernels never raise: they return a status code (``STATUS_*``) and the failing step, and the
Python drivers raise :class:`jetgaudin.SingularStepError`.

Flop count of one step (used by ``benchmarks/``): see :func:`flops_per_step`.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from numba import njit, prange

__all__ = [
    "STATUS_OK",
    "STATUS_SINGULAR_S",
    "STATUS_SINGULAR_KAPPA",
    "STATUS_SINGULAR_T",
    "STATUS_RESIDUAL",
    "STATUS_NONFINITE",
    "STATUS_MESSAGES",
    "run_orbit",
    "run_orbit3",
    "run_ensemble",
    "flops_per_step",
]

STATUS_OK = 0
STATUS_SINGULAR_S = 1
STATUS_SINGULAR_KAPPA = 2
STATUS_SINGULAR_T = 3
STATUS_RESIDUAL = 4
STATUS_NONFINITE = 5

STATUS_MESSAGES = {
    STATUS_SINGULAR_S: "v(eta) and u(eta) + nu(eta) both vanish, so the eigenvector [1, -s] of l(eta) is "
    "undefined (s would be infinite); change eta",
    STATUS_SINGULAR_KAPPA: "v(eta2) and u(eta2) + nu2 both vanish; change eta",
    STATUS_SINGULAR_T: "the denominator s + kappa of t (eq. (X)) vanishes (the two eigenvectors at eta1 and "
    "eta2 coincide); change eta",
    STATUS_RESIDUAL: "the dressing division left a remainder above 1e-8 (relative); the step is numerically "
    "singular (eta close to a branch point or a vanishing denominator)",
    STATUS_NONFINITE: "the step produced non-finite values; change eta",
}

#: (1e-13)^2 * 4: squared form of the NumPy test |den| <= 1e-13 * (|n1| + |n2| + |d1| + |d2|)
_RATIO_TOL2 = 4e-26
#: (1e-13)^2 * 2: squared form of |s + kappa| <= 1e-13 (|s| + |kappa|)
_DEN_TOL2 = 2e-26
#: squared relative residual tolerance (maps._RESIDUAL_TOL = 1e-8)
_RESIDUAL_TOL2 = 1e-16


@njit(cache=True, inline="always")
def _abs2(z):
    return z.real * z.real + z.imag * z.imag


@njit(cache=True, inline="always")
def _cdiv(a, b):
    """NumPy's complex division (Smith's algorithm, reciprocal scale); never raises."""
    ar = a.real
    ai = a.imag
    br = b.real
    bi = b.imag
    if abs(br) >= abs(bi):
        if br == 0.0 and bi == 0.0:
            return complex(ar / abs(br), ai / abs(bi))
        rat = bi / br
        scl = 1.0 / (br + bi * rat)
        return complex((ar + ai * rat) * scl, (ai - ar * rat) * scl)
    rat = br / bi
    scl = 1.0 / (bi + br * rat)
    return complex((ar * rat + ai) * scl, (ai * rat - ar) * scl)


@njit(cache=True, inline="always")
def _ratio(n1, d1, n2, d2):
    """``n1/d1 == n2/d2`` with the larger denominator; returns ``(value, ok)``."""
    a1 = _abs2(d1)
    a2 = _abs2(d2)
    scale2 = _abs2(n1) + _abs2(n2) + a1 + a2
    if a1 >= a2:
        return _cdiv(n1, d1), not (a1 <= _RATIO_TOL2 * scale2)
    return _cdiv(n2, d2), not (a2 <= _RATIO_TOL2 * scale2)


@njit(cache=True, inline="always")
def _continue_nu(u, v, w, nu_prev):
    r"""Root of ``u² + vw`` closest to ``nu_prev`` (``maps._continue_nu``)."""
    r = cmath.sqrt(u * u + v * w)
    if r.real * nu_prev.real + r.imag * nu_prev.imag >= 0.0:
        return r
    return -r


@njit(cache=True, inline="always")
def _params(u, v, w, nu, eta, de):
    """``(s, t, status)`` of eqs. (x), (X) from ``ℓ(η) = [[u, v], [w, −u]]`` and ``ν1``."""
    s, ok = _ratio(u - nu, v, -w, u + nu)
    if not ok:
        return s, s, STATUS_SINGULAR_S
    # ℓ(η̄) of a real state, and ν = −ν2 = −conj ν1 at η̄
    u2 = u.conjugate()
    v2 = w.conjugate()
    w2 = v.conjugate()
    nb = -nu.conjugate()
    kap, ok = _ratio(nb - u2, v2, w2, nb + u2)
    if not ok:
        return s, s, STATUS_SINGULAR_KAPPA
    den = s + kap
    if _abs2(den) <= _DEN_TOL2 * (_abs2(s) + _abs2(kap)) or den == 0:
        return s, s, STATUS_SINGULAR_T
    return s, _cdiv(de, den), STATUS_OK


@njit(cache=True)
def _integrals(x, b, N, out):
    r"""``κ_1..κ_2N`` (``H_1..H_N, C_1..C_N``) of a real state with field ``b e_3`` (:func:`jetgaudin.integrals`)."""
    for m in range(2 * N):
        out[m] = 0.0
    for i in range(N + 1):
        for j in range(N + 1):
            m = i + j
            if m == 0:
                continue
            if i == 0:
                d = b * x[3 * (j - 1) + 2]
            elif j == 0:
                d = x[3 * (i - 1) + 2] * b
            else:
                p = 3 * (i - 1)
                q = 3 * (j - 1)
                d = x[p] * x[q] + x[p + 1] * x[q + 1] + x[p + 2] * x[q + 2]
            out[m - 1] += d


@njit(cache=True)
def _drift_update(x, b, N, I0, Ibuf, drift):
    _integrals(x, b, N, Ibuf)
    for k in range(2 * N):
        e = abs(Ibuf[k] - I0[k]) / max(1.0, abs(I0[k]))
        if not (e <= drift[k]):  # also propagates NaN
            drift[k] = e


# ---------------------------------------------------------------------------------------------
# generic route, any N
# ---------------------------------------------------------------------------------------------


@njit(cache=True)
def _step_generic(x, N, b, eta, z, de, d1, d2, bottom_up, nu, eu, ev, ew, Ru, Rv, Rw, Qu, Qv, Qw, xnew):
    """One step from ``x`` (3N) with ``ν1 = nu`` already fixed; writes ``xnew``; returns a status."""
    # ---- s, t
    u = eu[N]
    v = ev[N]
    w = ew[N]
    for m in range(N - 1, -1, -1):
        u = u * z + eu[m]
        v = v * z + ev[m]
        w = w * z + ew[m]
    s, t, st = _params(u, v, w, nu, eta, de)
    if st != STATUS_OK:
        return st
    # ---- M0 (mm) and adj M0
    st_ = s * t
    m00 = -eta + st_
    m01 = t
    m10 = -s * s * t + de * s
    m11 = -eta.conjugate() - st_
    a00 = m11
    a01 = -m01
    a10 = -m10
    # ---- R_k: λ^{2-k} coefficients, k = 0..N+2
    for k in range(N + 3):
        if k <= N:
            Ru[k] = eu[k]
            Rv[k] = ev[k]
            Rw[k] = ew[k]
        else:
            Ru[k] = 0.0
            Rv[k] = 0.0
            Rw[k] = 0.0
    for m in range(N + 1):
        lu = eu[m]
        lv = ev[m]
        lw = ew[m]
        lx = -lu
        p00 = m00 * lu + m01 * lw
        p01 = m00 * lv + m01 * lx
        p10 = m10 * lu + m11 * lw
        p11 = m10 * lv + m11 * lx
        s00 = lu * a00 + lv * a10
        s01 = lu * a01 + lv * m00
        s10 = lw * a00 + lx * a10
        Ru[m + 1] += p00 + s00
        Rv[m + 1] += p01 + s01
        Rw[m + 1] += p10 + s10
        Ru[m + 2] += p00 * a00 + p01 * a10
        Rv[m + 2] += p00 * a01 + p01 * m00
        Rw[m + 2] += p10 * a00 + p11 * a10
    # ---- exact division by λ² + d1 λ + d2 (d1, d2 real)
    res2 = 0.0
    if bottom_up:
        for k in range(N + 2, 1, -1):
            au = Ru[k]
            av = Rv[k]
            aw = Rw[k]
            if k <= N:
                au = au - Qu[k]
                av = av - Qv[k]
                aw = aw - Qw[k]
            if k - 1 <= N:
                au = au - d1 * Qu[k - 1]
                av = av - d1 * Qv[k - 1]
                aw = aw - d1 * Qw[k - 1]
            Qu[k - 2] = complex(au.real / d2, au.imag / d2)
            Qv[k - 2] = complex(av.real / d2, av.imag / d2)
            Qw[k - 2] = complex(aw.real / d2, aw.imag / d2)
        # unused equations k = 0, 1
        ru = Ru[0] - Qu[0]
        rv = Rv[0] - Qv[0]
        rw = Rw[0] - Qw[0]
        res2 = max(_abs2(ru), _abs2(rv), _abs2(rw))
        ru = Ru[1] - Qu[1] - d1 * Qu[0]
        rv = Rv[1] - Qv[1] - d1 * Qv[0]
        rw = Rw[1] - Qw[1] - d1 * Qw[0]
        res2 = max(res2, _abs2(ru), _abs2(rv), _abs2(rw))
    else:
        for k in range(N + 1):
            au = Ru[k]
            av = Rv[k]
            aw = Rw[k]
            if k >= 1:
                au = au - d1 * Qu[k - 1]
                av = av - d1 * Qv[k - 1]
                aw = aw - d1 * Qw[k - 1]
            if k >= 2:
                au = au - d2 * Qu[k - 2]
                av = av - d2 * Qv[k - 2]
                aw = aw - d2 * Qw[k - 2]
            Qu[k] = au
            Qv[k] = av
            Qw[k] = aw
        ru = Ru[N + 1] - d1 * Qu[N] - d2 * Qu[N - 1] if N >= 1 else Ru[N + 1] - d1 * Qu[N]
        rv = Rv[N + 1] - d1 * Qv[N] - d2 * Qv[N - 1] if N >= 1 else Rv[N + 1] - d1 * Qv[N]
        rw = Rw[N + 1] - d1 * Qw[N] - d2 * Qw[N - 1] if N >= 1 else Rw[N + 1] - d1 * Qw[N]
        res2 = max(_abs2(ru), _abs2(rv), _abs2(rw))
        ru = Ru[N + 2] - d2 * Qu[N]
        rv = Rv[N + 2] - d2 * Qv[N]
        rw = Rw[N + 2] - d2 * Qw[N]
        res2 = max(res2, _abs2(ru), _abs2(rv), _abs2(rw))
    # relative residual: res / (1 + max |ℓ entry|)
    e2 = b * b
    for m in range(1, N + 1):
        e2 = max(e2, _abs2(eu[m]), _abs2(ev[m]), _abs2(ew[m]))
    sc = 1.0 + math.sqrt(e2)
    if not (res2 <= _RESIDUAL_TOL2 * sc * sc):
        return STATUS_RESIDUAL
    # ---- new state (state_from_ell, real part)
    for m in range(1, N + 1):
        y1 = 0.5 * (Qv[m].real + Qw[m].real)
        y2 = 0.5 * (Qw[m].imag - Qv[m].imag)
        y3 = Qu[m].real
        if not (math.isfinite(y1) and math.isfinite(y2) and math.isfinite(y3)):
            return STATUS_NONFINITE
        xnew[3 * (m - 1)] = y1
        xnew[3 * (m - 1) + 1] = y2
        xnew[3 * (m - 1) + 2] = y3
    return STATUS_OK


@njit(cache=True, inline="always")
def _fill_ell(x, N, b, eu, ev, ew):
    eu[0] = b
    ev[0] = 0.0
    ew[0] = 0.0
    for m in range(1, N + 1):
        y1 = x[3 * (m - 1)]
        y2 = x[3 * (m - 1) + 1]
        y3 = x[3 * (m - 1) + 2]
        eu[m] = complex(y3, 0.0)
        ev[m] = complex(y1, -y2)
        ew[m] = complex(y1, y2)


@njit(cache=True)
def run_orbit(x0, b, eta, nu0, cont, steps, save_every, out, final, drift):
    r"""Iterate the map ``steps`` times from ``x0`` (shape ``(3N,)``), generic route.

    ``nu0``: ``ν1`` for the first step (``cont = False``) or the value to continue from
    (``cont = True``).  Saves ``x_{j·save_every}`` in ``out[j]`` (``j = 0..steps//save_every``),
    the last state in ``final``, and ``max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over
    the saved states and the last one in ``drift`` (shape ``(2N,)``).
    Returns ``(status, step, nu)``: the status code, the failing step (or ``steps``) and the
    last ``ν1`` used (``nu0`` if ``steps == 0``).
    """
    n3 = x0.shape[0]
    N = n3 // 3
    eu = np.empty(N + 1, np.complex128)
    ev = np.empty(N + 1, np.complex128)
    ew = np.empty(N + 1, np.complex128)
    Ru = np.empty(N + 3, np.complex128)
    Rv = np.empty(N + 3, np.complex128)
    Rw = np.empty(N + 3, np.complex128)
    Qu = np.zeros(N + 1, np.complex128)
    Qv = np.zeros(N + 1, np.complex128)
    Qw = np.zeros(N + 1, np.complex128)
    x = np.empty(n3)
    xn = np.empty(n3)
    I0 = np.empty(2 * N)
    Ib = np.empty(2 * N)
    for i in range(n3):
        x[i] = x0[i]
        out[0, i] = x0[i]
    _integrals(x, b, N, I0)
    for k in range(2 * N):
        drift[k] = 0.0
    z = _cdiv(complex(1.0, 0.0), eta)
    de = eta - eta.conjugate()
    d1 = -(eta.real + eta.real)
    d2 = eta.real * eta.real + eta.imag * eta.imag
    bottom_up = d2 >= 1.0
    nu = nu0
    status = STATUS_OK
    n = 0
    for n in range(steps):
        _fill_ell(x, N, b, eu, ev, ew)
        if n > 0 or cont:
            u = eu[N]
            v = ev[N]
            w = ew[N]
            for m in range(N - 1, -1, -1):
                u = u * z + eu[m]
                v = v * z + ev[m]
                w = w * z + ew[m]
            nu = _continue_nu(u, v, w, nu)
        status = _step_generic(x, N, b, eta, z, de, d1, d2, bottom_up, nu, eu, ev, ew, Ru, Rv, Rw, Qu, Qv, Qw, xn)
        if status != STATUS_OK:
            break
        for i in range(n3):
            x[i] = xn[i]
        if (n + 1) % save_every == 0:
            j = (n + 1) // save_every
            for i in range(n3):
                out[j, i] = x[i]
            _drift_update(x, b, N, I0, Ib, drift)
    else:
        n = steps
    for i in range(n3):
        final[i] = x[i]
    if status == STATUS_OK:
        _drift_update(x, b, N, I0, Ib, drift)
    return status, n, nu


# ---------------------------------------------------------------------------------------------
# N = 3, fully unrolled (same operations as the generic route, in the same order, so the two give
# identical bits; zero and real entries of ℓ_0 = diag(b, −b) are exploited only where that
# leaves the result bit for bit unchanged: x + 0·y = x and (b + 0i)(c + di) = bc + i bd for finite y)
# ---------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _step3(x, b, eta, z, de, d1, d2, bottom_up, nu, cont, xnew):
    """One N = 3 step; returns ``(status, nu)``; writes ``xnew`` (9)."""
    u1 = complex(x[2], 0.0)
    v1 = complex(x[0], -x[1])
    w1 = complex(x[0], x[1])
    u2 = complex(x[5], 0.0)
    v2 = complex(x[3], -x[4])
    w2 = complex(x[3], x[4])
    u3 = complex(x[8], 0.0)
    v3 = complex(x[6], -x[7])
    w3 = complex(x[6], x[7])
    bc = complex(b, 0.0)
    zero = complex(0.0, 0.0)
    # Horner at η
    u = (((u3 * z + u2) * z) + u1) * z + bc
    v = (((v3 * z + v2) * z) + v1) * z + zero
    w = (((w3 * z + w2) * z) + w1) * z + zero
    if cont:
        nu = _continue_nu(u, v, w, nu)
    s, t, st = _params(u, v, w, nu, eta, de)
    if st != STATUS_OK:
        return st, nu
    st_ = s * t
    m00 = -eta + st_
    m01 = t
    m10 = -s * s * t + de * s
    m11 = -eta.conjugate() - st_
    a00 = m11
    a01 = -m01
    a10 = -m10
    # m = 0: ℓ_0 = diag(b, −b) (lv = lw = 0)
    lu = bc
    lx = -lu
    p00 = m00 * lu + m01 * zero
    p01 = m00 * zero + m01 * lx
    p10 = m10 * lu + m11 * zero
    p11 = m10 * zero + m11 * lx
    s00 = lu * a00 + zero * a10
    s01 = lu * a01 + zero * m00
    s10 = zero * a00 + lx * a10
    T1u0 = p00 + s00
    T1v0 = p01 + s01
    T1w0 = p10 + s10
    T2u0 = p00 * a00 + p01 * a10
    T2v0 = p00 * a01 + p01 * m00
    T2w0 = p10 * a00 + p11 * a10
    # m = 1
    lx = -u1
    p00 = m00 * u1 + m01 * w1
    p01 = m00 * v1 + m01 * lx
    p10 = m10 * u1 + m11 * w1
    p11 = m10 * v1 + m11 * lx
    T1u1 = p00 + (u1 * a00 + v1 * a10)
    T1v1 = p01 + (u1 * a01 + v1 * m00)
    T1w1 = p10 + (w1 * a00 + lx * a10)
    T2u1 = p00 * a00 + p01 * a10
    T2v1 = p00 * a01 + p01 * m00
    T2w1 = p10 * a00 + p11 * a10
    # m = 2
    lx = -u2
    p00 = m00 * u2 + m01 * w2
    p01 = m00 * v2 + m01 * lx
    p10 = m10 * u2 + m11 * w2
    p11 = m10 * v2 + m11 * lx
    T1u2 = p00 + (u2 * a00 + v2 * a10)
    T1v2 = p01 + (u2 * a01 + v2 * m00)
    T1w2 = p10 + (w2 * a00 + lx * a10)
    T2u2 = p00 * a00 + p01 * a10
    T2v2 = p00 * a01 + p01 * m00
    T2w2 = p10 * a00 + p11 * a10
    # m = 3
    lx = -u3
    p00 = m00 * u3 + m01 * w3
    p01 = m00 * v3 + m01 * lx
    p10 = m10 * u3 + m11 * w3
    p11 = m10 * v3 + m11 * lx
    T1u3 = p00 + (u3 * a00 + v3 * a10)
    T1v3 = p01 + (u3 * a01 + v3 * m00)
    T1w3 = p10 + (w3 * a00 + lx * a10)
    T2u3 = p00 * a00 + p01 * a10
    T2v3 = p00 * a01 + p01 * m00
    T2w3 = p10 * a00 + p11 * a10
    # R_k = ℓ_k + T1_{k-1} + T2_{k-2}, k = 0..5
    Ru0 = bc
    Rv0 = zero
    Rw0 = zero
    Ru1 = u1 + T1u0
    Rv1 = v1 + T1v0
    Rw1 = w1 + T1w0
    Ru2 = (u2 + T1u1) + T2u0
    Rv2 = (v2 + T1v1) + T2v0
    Rw2 = (w2 + T1w1) + T2w0
    Ru3 = (u3 + T1u2) + T2u1
    Rv3 = (v3 + T1v2) + T2v1
    Rw3 = (w3 + T1w2) + T2w1
    Ru4 = (zero + T1u3) + T2u2
    Rv4 = (zero + T1v3) + T2v2
    Rw4 = (zero + T1w3) + T2w2
    Ru5 = zero + T2u3
    Rv5 = zero + T2v3
    Rw5 = zero + T2w3
    if bottom_up:
        # k = 5: Q3 = R5/d2; k = 4: Q2 = (R4 − d1 Q3)/d2; k = 3: Q1 = (R3 − Q3 − d1 Q2)/d2;
        # k = 2: Q0 = (R2 − Q2 − d1 Q1)/d2; unused k = 1, 0
        Qu3 = complex(Ru5.real / d2, Ru5.imag / d2)
        Qv3 = complex(Rv5.real / d2, Rv5.imag / d2)
        Qw3 = complex(Rw5.real / d2, Rw5.imag / d2)
        au = Ru4 - d1 * Qu3
        av = Rv4 - d1 * Qv3
        aw = Rw4 - d1 * Qw3
        Qu2 = complex(au.real / d2, au.imag / d2)
        Qv2 = complex(av.real / d2, av.imag / d2)
        Qw2 = complex(aw.real / d2, aw.imag / d2)
        au = (Ru3 - Qu3) - d1 * Qu2
        av = (Rv3 - Qv3) - d1 * Qv2
        aw = (Rw3 - Qw3) - d1 * Qw2
        Qu1 = complex(au.real / d2, au.imag / d2)
        Qv1 = complex(av.real / d2, av.imag / d2)
        Qw1 = complex(aw.real / d2, aw.imag / d2)
        au = (Ru2 - Qu2) - d1 * Qu1
        av = (Rv2 - Qv2) - d1 * Qv1
        aw = (Rw2 - Qw2) - d1 * Qw1
        Qu0 = complex(au.real / d2, au.imag / d2)
        Qv0 = complex(av.real / d2, av.imag / d2)
        Qw0 = complex(aw.real / d2, aw.imag / d2)
        res2 = max(_abs2(Ru0 - Qu0), _abs2(Rv0 - Qv0), _abs2(Rw0 - Qw0))
        res2 = max(
            res2,
            _abs2(Ru1 - Qu1 - d1 * Qu0),
            _abs2(Rv1 - Qv1 - d1 * Qv0),
            _abs2(Rw1 - Qw1 - d1 * Qw0),
        )
    else:
        Qu0 = Ru0
        Qv0 = Rv0
        Qw0 = Rw0
        Qu1 = Ru1 - d1 * Qu0
        Qv1 = Rv1 - d1 * Qv0
        Qw1 = Rw1 - d1 * Qw0
        Qu2 = (Ru2 - d1 * Qu1) - d2 * Qu0
        Qv2 = (Rv2 - d1 * Qv1) - d2 * Qv0
        Qw2 = (Rw2 - d1 * Qw1) - d2 * Qw0
        Qu3 = (Ru3 - d1 * Qu2) - d2 * Qu1
        Qv3 = (Rv3 - d1 * Qv2) - d2 * Qv1
        Qw3 = (Rw3 - d1 * Qw2) - d2 * Qw1
        res2 = max(
            _abs2(Ru4 - d1 * Qu3 - d2 * Qu2),
            _abs2(Rv4 - d1 * Qv3 - d2 * Qv2),
            _abs2(Rw4 - d1 * Qw3 - d2 * Qw2),
        )
        res2 = max(res2, _abs2(Ru5 - d2 * Qu3), _abs2(Rv5 - d2 * Qv3), _abs2(Rw5 - d2 * Qw3))
    e2 = max(b * b, _abs2(u1), _abs2(v1), _abs2(w1), _abs2(u2), _abs2(v2), _abs2(w2))
    e2 = max(e2, _abs2(u3), _abs2(v3), _abs2(w3))
    sc = 1.0 + math.sqrt(e2)
    if not (res2 <= _RESIDUAL_TOL2 * sc * sc):
        return STATUS_RESIDUAL, nu
    xnew[0] = 0.5 * (Qv1.real + Qw1.real)
    xnew[1] = 0.5 * (Qw1.imag - Qv1.imag)
    xnew[2] = Qu1.real
    xnew[3] = 0.5 * (Qv2.real + Qw2.real)
    xnew[4] = 0.5 * (Qw2.imag - Qv2.imag)
    xnew[5] = Qu2.real
    xnew[6] = 0.5 * (Qv3.real + Qw3.real)
    xnew[7] = 0.5 * (Qw3.imag - Qv3.imag)
    xnew[8] = Qu3.real
    for i in range(9):
        if not math.isfinite(xnew[i]):
            return STATUS_NONFINITE, nu
    return STATUS_OK, nu


@njit(cache=True)
def run_orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final, drift):
    """:func:`run_orbit` specialised to ``N = 3`` (``x0`` of shape ``(9,)``); same results bit for bit."""
    x = np.empty(9)
    xn = np.empty(9)
    I0 = np.empty(6)
    Ib = np.empty(6)
    for i in range(9):
        x[i] = x0[i]
        out[0, i] = x0[i]
    _integrals(x, b, 3, I0)
    for k in range(6):
        drift[k] = 0.0
    z = _cdiv(complex(1.0, 0.0), eta)
    de = eta - eta.conjugate()
    d1 = -(eta.real + eta.real)
    d2 = eta.real * eta.real + eta.imag * eta.imag
    bottom_up = d2 >= 1.0
    nu = nu0
    status = STATUS_OK
    n = 0
    for n in range(steps):
        status, nu = _step3(x, b, eta, z, de, d1, d2, bottom_up, nu, n > 0 or cont, xn)
        if status != STATUS_OK:
            break
        for i in range(9):
            x[i] = xn[i]
        if (n + 1) % save_every == 0:
            j = (n + 1) // save_every
            for i in range(9):
                out[j, i] = x[i]
            _drift_update(x, b, 3, I0, Ib, drift)
    else:
        n = steps
    for i in range(9):
        final[i] = x[i]
    if status == STATUS_OK:
        _drift_update(x, b, 3, I0, Ib, drift)
    return status, n, nu


@njit(cache=True, parallel=True)
def run_ensemble(X0, b, eta, nu0, cont, steps, save_every, specialise, out, final, drift, status, fail, nu_last):
    r"""A batch of independent orbits: ``X0`` (B, 3N), per-orbit ``b``, ``eta``, ``nu0`` (B,);
    ``out`` (B, S, 3N), ``final`` (B, 3N), ``drift`` (B, 2N), ``status``/``fail`` (B,) int64,
    ``nu_last`` (B,) complex.  Each orbit runs :func:`run_orbit3` (``specialise`` and N = 3) or
    :func:`run_orbit`, the same code as a single-orbit run, in a ``prange`` loop over orbits."""
    B = X0.shape[0]
    n3 = X0.shape[1]
    use3 = specialise and n3 == 9
    for i in prange(B):
        if use3:
            st, n, nu = run_orbit3(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[i], final[i], drift[i])
        else:
            st, n, nu = run_orbit(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[i], final[i], drift[i])
        status[i] = st
        fail[i] = n
        nu_last[i] = nu


def flops_per_step(N: int) -> dict:
    r"""Floating-point operations of one step of the compiled route, counted from the kernel source.

    Counting rules (one real ``+ − × ÷ √`` = 1 flop, comparisons and ``abs`` not counted):
    complex ``+``/``−`` = 2, complex × complex = 6, real × complex = 2, complex ÷ (Smith) = 9
    (1 div + 1 mul + 1 add for the scale, 1 reciprocal, 2×(mul+add), 2 mul), ``|z|²`` = 3,
    complex square root ≈ 8 (hypot-like modulus + one real sqrt + scaling, Numba's ``cmath.sqrt``).
    Returns a dict of the counted parts and the total.
    """
    horner = 3 * N * 8  # u, v, w: N complex multiply-adds each (the N=3 kernel adds 0 for v, w at m=0)
    nu = 6 + 6 + 2 + 8 + 3  # u², vw, +, sqrt, sign test
    ratio = 2 + 2 + 4 * 3 + 3 + 9  # u∓ν, −w (negation free), four |·|², scale sum, one division
    params = 2 * ratio + 2 + 2 * 3 + 2 + 9  # s, κ, s+κ, test, scale, t
    m0 = 6 + 2 + 6 + 6 + 2 + 6 + 2 + 2  # st, m00, s·s·t, de·s, m10, m11
    per_m = 4 * 14 + 3 * 14 + 3 * 2 + 3 * 14  # P (4 entries: 2 cmul + cadd), S (3), T1 (3 cadd), T2 (3)
    rsum = 3 * (N + 1) * 2 * 2  # R_k += T1, R_k += T2
    division = 3 * (N + 1) * (2 + 2 + 2 + 2)  # per Q entry ~ one cmul by real d1, two csub, real div (2)
    residual = 2 * 3 * (3 + 6) + 3 * (N + 1) * 3 + 3  # two unused equations, |ℓ|² max, sqrt
    state = 3 * N * 2
    total = horner + nu + params + m0 + (N + 1) * per_m + rsum + division + residual + state
    return {
        "horner": horner,
        "nu": nu,
        "s_kappa_t": params,
        "M0": m0,
        "R_products": (N + 1) * per_m + rsum,
        "division": division,
        "residual": residual,
        "state": state,
        "total": total,
    }
