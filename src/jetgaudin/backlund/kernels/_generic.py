r"""The generic compiled route (any N): one step (:func:`_step_generic`), one orbit (:func:`run_orbit`) and a
batch of orbits in a ``prange`` loop (:func:`run_batch_generic`).

Mirrors the NumPy reference route of :class:`jetgaudin.backlund.maps.TwoPointBacklund` (``maps.py``,
``_dressing.py``) step by step:

1. ``ℓ(η) = Σ_m ℓ_m η^{-m}`` by Horner's rule in ``z = 1/η`` (``ℓ(η̄)`` is not needed: for a real
   state it is the conjugate-transpose pattern of ``ℓ(η)``, which the closed-form ``M0`` uses);
2. ``ν1`` continued from the previous step by the root of ``u² + vw`` closest to it (the first step
   takes ``ν1`` from the caller, i.e. from the default branch of :func:`jetgaudin.nu`);
3. the eigenvector ``k = (v, ν1 − u)`` or ``(u + ν1, w)`` of ``ℓ(η)``, the larger one
   (``s = −k2/k1`` of eq. (x) may be infinite), and
   ``M0 = −diag(η, η̄) + (2i Im η/|k|²) [[|k2|², −k1 k̄2], [−k̄1 k2, −|k2|²]]`` (eq. (mm) with
   ``κ = 1/s̄`` forced by reality in eq. (X); ``docs/backlund.md``);
4. ``R(λ) = λ² ℓ + λ (M0 ℓ + ℓ adj M0) + M0 ℓ adj M0`` (summed in NumPy's order) and the exact
   Laurent division by ``(λ − η)(λ − η̄) = λ² + δ1 λ + δ2`` (``δ1 = −2 Re η``, ``δ2 = |η|²``),
   bottom-up when ``δ2 ≥ 1`` and top-down otherwise, with the residual of the unused equations;
5. the new state from ``ℓ̆_1..ℓ̆_N`` (:func:`jetgaudin.lax.state_from_ell`), real part.

Differences from the NumPy route, all at round-off level (the orbits agree to round-off, not bit
for bit): only the three independent entries ``(0,0), (0,1), (1,0)`` of the traceless ``ℓ``, ``R``,
``ℓ̆`` are formed (``tr(M ℓ adj M) = det M · tr ℓ = 0``); ``÷δ2`` is done as ``×(1/δ2)``; complex
division as ``a·b̄/|b|²``; the square root is written out (:func:`._scalar._csqrt`); real × complex products
skip the zero imaginary part (identical for finite values).  The test for a vanishing eigenvector
uses ``(Σ|·|)² ≤ 4 Σ|·|²``, so it fires whenever the NumPy test does, in a band at most twice as wide.
Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._scalar import (
    _RESIDUAL_TOL2,
    _abs2,
    _cdiv,
    _commutator,
    _continue_nu,
    _cr,
    _division_constants,
    _drift_pass,
    _eigvec,
    _horner_step_u,
    _integrals,
    _m0_from_k,
    _m0_times,
    block,
)
from ._status import STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL


@block()
def _step_generic(x, N, b, eta, z, d1, d2, inv_d2, bottom_up, nu, cont, eu, ev, ew, Ru, Rv, Rw, Qu, Qv, Qw, xnew):
    """One step from ``x`` (3N); returns ``(status, ν1)``; writes ``xnew``."""
    # ---- ℓ_m, m = 1..N (u real)
    for m in range(1, N + 1):
        y1 = x[3 * (m - 1)]
        y2 = x[3 * (m - 1) + 1]
        eu[m] = x[3 * (m - 1) + 2]
        ev[m] = complex(y1, -y2)
        ew[m] = complex(y1, y2)
    # ---- ℓ(η) by Horner's rule in z = 1/η
    u = complex(eu[N], 0.0)
    v = ev[N]
    w = ew[N]
    for m in range(N - 1, 0, -1):
        u = _horner_step_u(u, z, eu[m])
        v = v * z + ev[m]
        w = w * z + ew[m]
    u = _horner_step_u(u, z, b)
    v = v * z
    w = w * z
    if cont:
        nu = _continue_nu(u, v, w, nu)
    k1, k2, nk, st = _eigvec(u, v, w, nu)
    if st != STATUS_OK:
        return st, nu
    m00, m01, m10, m11 = _m0_from_k(eta, k1, k2, nk)
    # ---- R_k of M(λ)[P, ℓ(λ)], k = 0..N+2 (λ^{2-k}; R_0 = 0): C_m = [P, ℓ_m], R_{m+1} = C_m + M0 C_{m-1}
    # (P = M0 + Re(η) I, the traceless part: its diagonal is i Im m00; _dressing.dress_real_two_point)
    p00 = complex(0.0, m00.imag)
    Ru[0] = 0.0
    Rv[0] = 0.0
    Rw[0] = 0.0
    cu, cv, cw = _commutator(p00, m01, m10, b, 0.0, 0.0)
    Ru[1] = cu
    Rv[1] = cv
    Rw[1] = cw
    for m in range(1, N + 1):
        au, av, aw = _m0_times(m00, m01, m10, m11, cu, cv, cw)
        cu, cv, cw = _commutator(p00, m01, m10, eu[m], ev[m], ew[m])
        Ru[m + 1] = cu + au
        Rv[m + 1] = cv + av
        Rw[m + 1] = cw + aw
    Ru[N + 2], Rv[N + 2], Rw[N + 2] = _m0_times(m00, m01, m10, m11, cu, cv, cw)
    # ---- exact division by λ² + d1 λ + d2 (d1, d2 real; ÷d2 as ×(1/d2))
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
                au = au - _cr(Qu[k - 1], d1)
                av = av - _cr(Qv[k - 1], d1)
                aw = aw - _cr(Qw[k - 1], d1)
            Qu[k - 2] = _cr(au, inv_d2)
            Qv[k - 2] = _cr(av, inv_d2)
            Qw[k - 2] = _cr(aw, inv_d2)
        # the unused equations k = 0, 1
        res2 = max(_abs2(Ru[0] - Qu[0]), _abs2(Rv[0] - Qv[0]), _abs2(Rw[0] - Qw[0]))
        res2 = max(
            res2,
            _abs2(Ru[1] - Qu[1] - _cr(Qu[0], d1)),
            _abs2(Rv[1] - Qv[1] - _cr(Qv[0], d1)),
            _abs2(Rw[1] - Qw[1] - _cr(Qw[0], d1)),
        )
    else:
        for k in range(N + 1):
            au = Ru[k]
            av = Rv[k]
            aw = Rw[k]
            if k >= 1:
                au = au - _cr(Qu[k - 1], d1)
                av = av - _cr(Qv[k - 1], d1)
                aw = aw - _cr(Qw[k - 1], d1)
            if k >= 2:
                au = au - _cr(Qu[k - 2], d2)
                av = av - _cr(Qv[k - 2], d2)
                aw = aw - _cr(Qw[k - 2], d2)
            Qu[k] = au
            Qv[k] = av
            Qw[k] = aw
        res2 = max(
            _abs2(Ru[N + 1] - _cr(Qu[N], d1) - _cr(Qu[N - 1], d2)),
            _abs2(Rv[N + 1] - _cr(Qv[N], d1) - _cr(Qv[N - 1], d2)),
            _abs2(Rw[N + 1] - _cr(Qw[N], d1) - _cr(Qw[N - 1], d2)),
        )
        res2 = max(
            res2,
            _abs2(Ru[N + 2] - _cr(Qu[N], d2)),
            _abs2(Rv[N + 2] - _cr(Qv[N], d2)),
            _abs2(Rw[N + 2] - _cr(Qw[N], d2)),
        )
    # relative residual: res / (1 + max |ℓ entry|)
    e2 = b * b
    for m in range(1, N + 1):
        e2 = max(e2, eu[m] * eu[m], _abs2(ev[m]))
    sc = 1.0 + math.sqrt(e2)
    if not (res2 <= _RESIDUAL_TOL2 * sc * sc):
        return STATUS_RESIDUAL, nu
    # ---- new state ℓ_m + Q_m (state_from_ell, real part)
    acc = 0.0
    for m in range(1, N + 1):
        nv = ev[m] + Qv[m]
        nw = ew[m] + Qw[m]
        y1 = 0.5 * (nv.real + nw.real)
        y2 = 0.5 * (nw.imag - nv.imag)
        y3 = eu[m] + Qu[m].real
        xnew[3 * (m - 1)] = y1
        xnew[3 * (m - 1) + 1] = y2
        xnew[3 * (m - 1) + 2] = y3
        acc += y1 + y2 + y3
    if not (acc - acc == 0.0):  # NaN or inf somewhere
        return STATUS_NONFINITE, nu
    return STATUS_OK, nu


@njit(cache=True, error_model="numpy")
def orbit_generic(x0, b, eta, nu0, cont, steps, save_every, out, final, eu, ev, ew, Ru, Rv, Rw, Qu, Qv, Qw, x, xn):
    """The stepping loop of :func:`run_orbit` on caller-given scratch (``eu`` (N+1,) real; ``ev, ew, Qu, Qv, Qw``
    (N+1,) and ``Ru, Rv, Rw`` (N+3,) complex, the ``Q`` zeroed; ``x, xn`` (3N,)), without allocations: the GPU kernels
    of :mod:`jetgaudin.gpu` call it for one orbit per thread, compiled for the device, with thread-local scratch.
    Writes ``out[j]`` (rows ``0..`` as far as the orbit got) and ``final``; returns ``(status, step, ν1)``."""
    n3 = x0.shape[0]
    N = n3 // 3
    for i in range(n3):
        x[i] = x0[i]
        out[0, i] = x0[i]
    z = _cdiv(complex(1.0, 0.0), eta)
    d1, d2, inv_d2, bottom_up = _division_constants(eta)
    nu = nu0
    status = STATUS_OK
    n = 0
    for n in range(steps):
        status, nu = _step_generic(x, N, b, eta, z, d1, d2, inv_d2, bottom_up, nu, n > 0 or cont,
                                   eu, ev, ew, Ru, Rv, Rw, Qu, Qv, Qw, xn)
        if status != STATUS_OK:
            break
        for i in range(n3):
            x[i] = xn[i]
        if (n + 1) % save_every == 0:
            j = (n + 1) // save_every
            for i in range(n3):
                out[j, i] = x[i]
    else:
        n = steps
    for i in range(n3):
        final[i] = x[i]
    return status, n, nu


@njit(cache=True, error_model="numpy")
def run_orbit(x0, b, eta, nu0, cont, steps, save_every, out, final, drift, want_drift):
    r"""Iterate the map ``steps`` times from ``x0`` (shape ``(3N,)``), generic route.

    ``nu0``: ``ν1`` for the first step (``cont = False``) or the value to continue from
    (``cont = True``).  Saves ``x_{j·save_every}`` in ``out[j]`` (``j = 0..steps//save_every``),
    the last state in ``final``, and ``max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over
    the saved states and the last one in ``drift`` (shape ``(2N,)``; zeros if ``want_drift`` is false).
    Returns ``(status, step, nu)``: the status code, the failing step (or ``steps``) and the
    last ``ν1`` used (``nu0`` if ``steps == 0``).  The loop is :func:`orbit_generic`.
    """
    n3 = x0.shape[0]
    N = n3 // 3
    I0 = np.empty(2 * N)
    Ib = np.empty(4 * N)
    _integrals(x0, b, N, I0)
    for k in range(2 * N):
        drift[k] = 0.0
    status, n, nu = orbit_generic(
        x0, b, eta, nu0, cont, steps, save_every, out, final, np.empty(N + 1), np.empty(N + 1, np.complex128),
        np.empty(N + 1, np.complex128), np.empty(N + 3, np.complex128), np.empty(N + 3, np.complex128),
        np.empty(N + 3, np.complex128), np.zeros(N + 1, np.complex128), np.zeros(N + 1, np.complex128),
        np.zeros(N + 1, np.complex128), np.empty(n3), np.empty(n3))
    if want_drift:
        _drift_pass(out, final, n // save_every, b, N, I0, Ib, drift)
    return status, n, nu


@njit(cache=True, error_model="numpy", parallel=True)
def run_batch_generic(X0, b, eta, nu0, cont, steps, save_every, out, final, drift, status, fail, nu_last,
                      want_drift):
    r"""A batch of independent orbits by :func:`run_orbit`, one per iteration of a ``prange`` loop: ``X0`` (B, 3N),
    per-orbit ``b``, ``eta``, ``nu0`` (B,); ``out`` (S, B, 3N) (step-major), ``final`` (B, 3N), ``drift`` (B, 2N),
    ``status``/``fail`` (B,) int64, ``nu_last`` (B,) complex.  Every orbit gets the bits of its single-orbit run."""
    for i in prange(X0.shape[0]):
        st, n, nu = run_orbit(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[:, i], final[i], drift[i],
                              want_drift)
        status[i] = st
        fail[i] = n
        nu_last[i] = nu
