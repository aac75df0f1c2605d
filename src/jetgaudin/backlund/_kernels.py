r"""Compiled (Numba) kernels for the real two-point Bäcklund map (Section 6.2, Appendix 1).

**Generic route (any N)** — mirrors the NumPy reference route of
:class:`jetgaudin.backlund.maps.TwoPointBacklund` (``maps.py``, ``_dressing.py``) step by step:

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
division as ``a·b̄/|b|²``; the square root is written out (:func:`_csqrt`); real × complex products
skip the zero imaginary part (identical for finite values).  The test for a vanishing eigenvector
uses ``(Σ|·|)² ≤ 4 Σ|·|²``, so it fires whenever the NumPy test does, in a band at most twice as wide.

**N = 3 route** (:func:`run_orbit3`) — the same steps unrolled in scalars, with two changes that
shorten the chain of dependent operations (again round-off level; tested against both routes):
``ℓ(η)`` as ``b + Σ ℓ_m z^m`` with precomputed ``z^m`` (Estrin instead of Horner), and ``ν1``
continued by one Newton step ``ν ← ν + (ν² − ν_prev²)/(2ν_prev)`` (``ν²`` is an integral of the map,
so the correction is at round-off level; the closest-root square root is used otherwise).

**Reproducibility.** Arithmetic is IEEE without ``fastmath`` (no reassociation, no FMA contraction),
so a kernel gives the same bits in a single-orbit run and as a member of a parallel ensemble
(:func:`run_ensemble`).  Kernels never raise: they return a status code (``STATUS_*``) and the
failing step; the Python drivers raise :class:`jetgaudin.SingularStepError` /
:class:`jetgaudin.BranchPointError`.  Operation counts: :func:`flops_per_step`.
"""

from __future__ import annotations

import cmath
import math

import numpy as np


def _prefer_256_bit_vectors() -> bool:
    """Ask LLVM for 256-bit vectors on AVX-512 hosts (the target feature ``prefer-256-bit``, a tuning hint).

    Measured on an AMD EPYC (znver4) host: the lock-step ensemble kernel runs 3.7e7-3.8e7 orbit-steps/s per thread
    with it against 2.1e7-2.3e7 with LLVM's default 512-bit choice there (on the Intel Xeon of
    docs/performance.md LLVM already picks 256 bits).  The arithmetic is unchanged (IEEE operations, no
    contraction), so the bits are the same.  Applied only when Numba has not compiled anything yet in this process
    and the user has set neither NUMBA_CPU_NAME nor NUMBA_CPU_FEATURES; it then holds for the process's Numba code.
    """
    import numba.core.config as config
    from numba.core import registry

    if config.CPU_FEATURES is not None or config.CPU_NAME is not None or "target_context" in vars(registry.cpu_target):
        return False
    try:
        import llvmlite.binding as ll

        features = ll.get_host_cpu_features()
    except (ImportError, RuntimeError):
        return False
    if not features.get("avx512f", False):
        return False
    config.CPU_FEATURES = features.flatten() + ",+prefer-256-bit"
    return True


PREFER_256_BIT = _prefer_256_bit_vectors()

from numba import njit, prange  # noqa: E402

__all__ = [
    "STATUS_OK",
    "STATUS_BRANCH",
    "STATUS_RESIDUAL",
    "STATUS_NONFINITE",
    "STATUS_MESSAGES",
    "run_orbit",
    "run_orbit3",
    "run_ensemble",
    "flops_per_step",
]

STATUS_OK = 0
STATUS_BRANCH = 1
STATUS_RESIDUAL = 4
STATUS_NONFINITE = 5

STATUS_MESSAGES = {
    STATUS_BRANCH: "l(eta) vanishes (eta is a double branch point of nu): the eigenvector of the Bäcklund step is "
    "undefined; change eta",
    STATUS_RESIDUAL: "the dressing division left a remainder above 1e-8 (relative); the step is numerically "
    "singular (eta close to a branch point or a vanishing denominator)",
    STATUS_NONFINITE: "the step produced non-finite values; change eta",
}

#: (1e-15)^2: squared form of the eigenvector test max(|k_a|², |k_b|²) <= (1e-15 * scale)² of the NumPy route
_EIG_TOL2 = 1e-30
#: squared relative residual tolerance (maps._RESIDUAL_TOL = 1e-8)
_RESIDUAL_TOL2 = 1e-16


@njit(cache=True, error_model="numpy", inline="always")
def _abs2(z):
    return z.real * z.real + z.imag * z.imag


@njit(cache=True, error_model="numpy", inline="always")
def _cdiv(a, b):
    r"""``a/b = a·conj(b)·(1/|b|²)``: one real division (shorter latency than Smith's algorithm, which
    the NumPy route uses; the two agree to a few ulp for ``1e-150 < |b| < 1e150``); never raises
    (``b = 0`` gives inf/NaN, caught by the callers' singularity tests and the final finiteness test)."""
    br = b.real
    bi = b.imag
    r = 1.0 / (br * br + bi * bi)
    return complex((a.real * br + a.imag * bi) * r, (a.imag * br - a.real * bi) * r)


@njit(cache=True, error_model="numpy", inline="always")
def _rmul(d, q):
    """real × complex, as NumPy's complex product with ``d + 0i`` (identical for finite values)."""
    return complex(d * q.real, d * q.imag)


@njit(cache=True, error_model="numpy", inline="always")
def _csqrt(z):
    r"""A square root of ``z`` (principal; the sign is fixed by the caller): ``t = √((|z| + |a|)/2)``,
    no cancellation; ``|z|`` as ``√(a² + b²)`` (no overflow guard: fine for ``|z| < 1e150``)."""
    a = z.real
    b = z.imag
    t = math.sqrt(0.5 * (math.sqrt(a * a + b * b) + abs(a)))
    if t == 0.0:
        return complex(0.0, 0.0)
    if a >= 0.0:
        return complex(t, 0.5 * b / t)
    return complex(0.5 * abs(b) / t, math.copysign(t, b))


@njit(cache=True, error_model="numpy", inline="always")
def _continue_nu(u, v, w, nu_prev):
    r"""Root of ``u² + vw`` closest to ``nu_prev`` (``maps._continue_nu``)."""
    r = _csqrt(u * u + v * w)
    if r.real * nu_prev.real + r.imag * nu_prev.imag >= 0.0:
        return r
    return -r


@njit(cache=True, error_model="numpy", inline="always")
def _eigvec(u, v, w, nu):
    r"""Eigenvector ``k`` of ``ℓ(η) = [[u, v], [w, −u]]`` for ``ν`` (:func:`jetgaudin.backlund._dressing.eigenvector`):
    ``(v, ν − u)`` or ``(u + ν, w)``, the one with the larger ``|k|²``; ``s = −k_2/k_1`` may be infinite.
    Returns ``(k1, k2, |k|², status)``: ``STATUS_BRANCH`` when both vanish (``ℓ(η) = 0``, a double branch
    point), ``STATUS_NONFINITE`` on overflow."""
    # the same values as _eigvec_flags, with an if instead of selects: ~5 % faster on the single-orbit chain
    a1 = v
    a2 = nu - u
    b1 = u + nu
    b2 = w
    na = _abs2(a1) + _abs2(a2)
    nb = _abs2(b1) + _abs2(b2)
    if na >= nb:
        k1, k2, nk = a1, a2, na
    else:
        k1, k2, nk = b1, b2, nb
    scale2 = 4.0 * (_abs2(u) + _abs2(v) + _abs2(w) + _abs2(nu))
    if not (scale2 - scale2 == 0.0):  # overflow or NaN in ℓ(η) or ν
        return k1, k2, nk, STATUS_NONFINITE
    if nk <= _EIG_TOL2 * scale2 or nk == 0.0:
        return k1, k2, nk, STATUS_BRANCH
    return k1, k2, nk, STATUS_OK


@njit(cache=True, error_model="numpy", inline="always")
def _eigvec_flags(u, v, w, nu):
    """:func:`_eigvec` without data-dependent branches (both candidates formed, one selected; for the
    lock-step lanes): returns ``(k1, k2, |k|², nonfinite, branch)``."""
    a1 = v
    a2 = nu - u
    b1 = u + nu
    b2 = w
    na = _abs2(a1) + _abs2(a2)
    nb = _abs2(b1) + _abs2(b2)
    use_a = na >= nb
    k1 = _selc(use_a, a1, b1)
    k2 = _selc(use_a, a2, b2)
    nk = _sel(use_a, na, nb)
    # NumPy: max(na, nb) <= (1e-15 (|u| + |v| + |w| + |ν|))²; here the bound (Σ|·|)² <= 4 Σ|·|² (no
    # square roots): the compiled route refuses whenever the NumPy route does, and in a band twice as wide
    scale2 = 4.0 * (_abs2(u) + _abs2(v) + _abs2(w) + _abs2(nu))
    nonfinite = not (scale2 - scale2 == 0.0)
    branch = nk <= _EIG_TOL2 * scale2 or nk == 0.0
    return k1, k2, nk, nonfinite, branch


@njit(cache=True, error_model="numpy", inline="always")
def _m0_from_k(eta, k1, k2, nk):
    r"""``M0`` of the real two-point map from the eigenvector ``k``
    (:func:`jetgaudin.backlund._dressing.real_two_point_M0`):

    ``M0 = −diag(η, η̄) + (2i Im η/|k|²) [[|k2|², −k1 k̄2], [−k̄1 k2, −|k2|²]]``

    (eq. (mm) with ``t = 2i Im(η) s̄/(1 + |s|²)``, ``s = −k2/k1``: reality forces ``κ = 1/s̄`` in eq. (X)).
    ``c = 2i Im η/|k|² = i·ci`` is imaginary; returns ``(m00, m01, m10, m11)``."""
    ci = (eta.imag + eta.imag) * (1.0 / nk)
    a2 = _abs2(k2)
    m01 = complex(ci * k1.imag, -ci * k1.real) * k2.conjugate()  # −c k1 conj(k2)
    m10 = complex(-ci * k1.imag, -ci * k1.real) * k2  # −c conj(k1) k2
    m00 = complex(-eta.real, ci * a2 - eta.imag)
    m11 = complex(-eta.real, eta.imag - ci * a2)
    return m00, m01, m10, m11


@njit(cache=True, error_model="numpy")
def _integrals(x, b, N, out):
    r"""``κ_1..κ_2N`` (``H_1..H_N, C_1..C_N``) of a real state with field ``b e_3`` (:func:`jetgaudin.integrals`):
    ``κ_m = Σ_{i+j=m} ⟨ξ_i, ξ_j⟩`` with ``ξ_0 = b e_3``, ``ξ_i = y_{i-1}``."""
    for m in range(2 * N):
        out[m] = 0.0
    for i in range(1, N + 1):
        p = 3 * (i - 1)
        out[i - 1] += 2.0 * b * x[p + 2]
        for j in range(1, N + 1):
            q = 3 * (j - 1)
            out[i + j - 1] += x[p] * x[q] + x[p + 1] * x[q + 1] + x[p + 2] * x[q + 2]


@njit(cache=True, error_model="numpy")
def _drift_pass(out, final, last, b, N, I0, Ibuf, drift):
    r"""``drift_k = max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over the saved rows ``out[1..last]`` and
    ``final`` (computed after the run, off the critical path of the steps)."""
    inv = np.empty(2 * N)
    for k in range(2 * N):
        inv[k] = 1.0 / max(1.0, abs(I0[k]))
    for j in range(1, last + 2):
        row = out[j] if j <= last else final
        _integrals(row, b, N, Ibuf)
        for k in range(2 * N):
            e = abs(Ibuf[k] - I0[k]) * inv[k]
            if not (e <= drift[k]):  # also propagates NaN
                drift[k] = e


# ---------------------------------------------------------------------------------------------
# building blocks shared by the generic route and the N = 3 route (so that the two agree bit for bit)
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always")
def _cr(c, r):
    """complex × real, as NumPy's product with ``r + 0i`` (identical for finite values)."""
    return complex(c.real * r, c.imag * r)


@njit(cache=True, error_model="numpy", inline="always")
def _horner_step_u(acc, z, u):
    """``acc·z + (u + 0i)`` with real ``u``."""
    p = acc * z
    return complex(p.real + u, p.imag)


@njit(cache=True, error_model="numpy", inline="always")
def _products(m00, m01, m10, m11, u, v, w):
    r"""``T1 = M0 ℓ_m + ℓ_m adj M0`` and ``T2 = M0 ℓ_m adj M0`` (entries 00, 01, 10) for
    ``ℓ_m = [[u, v], [w, −u]]``, ``u`` real (``m ≥ 1``)."""
    a00 = m11
    a01 = -m01
    a10 = -m10
    lx = -u
    p00 = _cr(m00, u) + m01 * w
    p01 = m00 * v + _cr(m01, lx)
    p10 = _cr(m10, u) + m11 * w
    p11 = m10 * v + _cr(m11, lx)
    t1u = p00 + (_cr(a00, u) + v * a10)
    t1v = p01 + (_cr(a01, u) + v * m00)
    t1w = p10 + (w * a00 + _cr(a10, lx))
    t2u = p00 * a00 + p01 * a10
    t2v = p00 * a01 + p01 * m00
    t2w = p10 * a00 + p11 * a10
    return t1u, t1v, t1w, t2u, t2v, t2w


@njit(cache=True, error_model="numpy", inline="always")
def _products0(m00, m01, m10, m11, b):
    r""":func:`_products` for ``ℓ_0 = diag(b, −b)`` (the zero entries dropped: ``x + 0·y = x``)."""
    a00 = m11
    a01 = -m01
    a10 = -m10
    p00 = _cr(m00, b)
    p01 = _cr(m01, -b)
    p10 = _cr(m10, b)
    p11 = _cr(m11, -b)
    t1u = p00 + _cr(a00, b)
    t1v = p01 + _cr(a01, b)
    t1w = p10 + _cr(a10, -b)
    t2u = p00 * a00 + p01 * a10
    t2v = p00 * a01 + p01 * m00
    t2w = p10 * a00 + p11 * a10
    return t1u, t1v, t1w, t2u, t2v, t2w


# ---------------------------------------------------------------------------------------------
# generic route, any N
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
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
    # ---- R_k = (ℓ_k + T1_{k-1}) + T2_{k-2}, k = 0..N+2 (NumPy's order of summation)
    t1u, t1v, t1w, Qu[0], Qv[0], Qw[0] = _products0(m00, m01, m10, m11, b)
    Ru[0] = b
    Rv[0] = 0.0
    Rw[0] = 0.0
    Ru[1] = complex(eu[1], 0.0) + t1u if N >= 1 else t1u
    Rv[1] = ev[1] + t1v
    Rw[1] = ew[1] + t1w
    for m in range(1, N + 1):
        t1u, t1v, t1w, Qu[m], Qv[m], Qw[m] = _products(m00, m01, m10, m11, eu[m], ev[m], ew[m])
        if m + 1 <= N:
            Ru[m + 1] = complex(eu[m + 1], 0.0) + t1u
            Rv[m + 1] = ev[m + 1] + t1v
            Rw[m + 1] = ew[m + 1] + t1w
        else:
            Ru[m + 1] = t1u
            Rv[m + 1] = t1v
            Rw[m + 1] = t1w
    for m in range(N + 1):  # T2_m was parked in Q
        if m + 2 <= N + 1:
            Ru[m + 2] = Ru[m + 2] + Qu[m]
            Rv[m + 2] = Rv[m + 2] + Qv[m]
            Rw[m + 2] = Rw[m + 2] + Qw[m]
        else:
            Ru[m + 2] = Qu[m]
            Rv[m + 2] = Qv[m]
            Rw[m + 2] = Qw[m]
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
    # ---- new state (state_from_ell, real part)
    acc = 0.0
    for m in range(1, N + 1):
        y1 = 0.5 * (Qv[m].real + Qw[m].real)
        y2 = 0.5 * (Qw[m].imag - Qv[m].imag)
        y3 = Qu[m].real
        xnew[3 * (m - 1)] = y1
        xnew[3 * (m - 1) + 1] = y2
        xnew[3 * (m - 1) + 2] = y3
        acc += y1 + y2 + y3
    if not (acc - acc == 0.0):  # NaN or inf somewhere
        return STATUS_NONFINITE, nu
    return STATUS_OK, nu


@njit(cache=True, error_model="numpy")
def run_orbit(x0, b, eta, nu0, cont, steps, save_every, out, final, drift, want_drift=True):
    r"""Iterate the map ``steps`` times from ``x0`` (shape ``(3N,)``), generic route.

    ``nu0``: ``ν1`` for the first step (``cont = False``) or the value to continue from
    (``cont = True``).  Saves ``x_{j·save_every}`` in ``out[j]`` (``j = 0..steps//save_every``),
    the last state in ``final``, and ``max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over
    the saved states and the last one in ``drift`` (shape ``(2N,)``; zeros if ``want_drift`` is false).
    Returns ``(status, step, nu)``: the status code, the failing step (or ``steps``) and the
    last ``ν1`` used (``nu0`` if ``steps == 0``).
    """
    n3 = x0.shape[0]
    N = n3 // 3
    eu = np.empty(N + 1)
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
    d1 = -(eta.real + eta.real)
    d2 = eta.real * eta.real + eta.imag * eta.imag
    inv_d2 = 1.0 / d2
    bottom_up = d2 >= 1.0
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
    if want_drift:
        _drift_pass(out, final, n // save_every, b, N, I0, Ib, drift)
    return status, n, nu


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
def run_orbit3(x0, b, eta, nu0, cont, steps, save_every, out, final, drift, want_drift=True):
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
    d1 = -(eta.real + eta.real)
    d2 = eta.real * eta.real + eta.imag * eta.imag
    inv_d2 = 1.0 / d2
    bottom_up = d2 >= 1.0
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


# ---------------------------------------------------------------------------------------------
# N = 3 ensembles: W orbits in lock-step (structure of arrays), branch-free, for SIMD across orbits
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always")
def _sel(c, a, b):
    return a if c else b


@njit(cache=True, error_model="numpy", inline="always")
def _selc(c, a, b):
    """complex select by components (a select of a complex struct keeps LLVM from vectorising)."""
    return complex(_sel(c, a.real, b.real), _sel(c, a.imag, b.imag))


@njit(cache=True, error_model="numpy", inline="always")
def _lane3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, eta, z1, z2, z3, d1, d2, inv_d2, bottom_up, nu, nu_sq,
           inv_2nu, newton):
    """:func:`_step3` without data-dependent branches: both sides of every choice are computed and the
    same value is selected, so each lane gives the bits of :func:`_step3`.  Returns
    ``(status, ν1, y0, …, y8, need_root)``; on a failed step the old state is returned (as :func:`_step3`
    does); ``need_root``: the Newton update of ``ν1`` was refused, the lane must be redone by :func:`_step3`."""
    u1, v1, w1, u2, v2, w2, u3, v3, w3 = _uvw3(x0, x1, x2, x3, x4, x5, x6, x7, x8)
    u, v, w = _ell3(b, z1, z2, z3, u1, v1, w1, u2, v2, w2, u3, v3, w3)
    nu2 = u * u + v * w
    c = nu2 - nu_sq
    # the closest-root fallback of _step3 is rare: flag the lane (it is redone by _step3) instead of computing it
    newton_ok = _abs2(c) <= 1e-16 * _abs2(nu2)
    need_root = _sel(newton, not newton_ok, False)  # selects, no short-circuit control flow (vectorisation)
    nu = _selc(newton, nu + c * inv_2nu, nu)
    k1, k2, nk, bad_scale, branch = _eigvec_flags(u, v, w, nu)  # eigenvector, statuses kept as flags
    m00, m01, m10, m11 = _m0_from_k(eta, k1, k2, nk)
    (Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5,
     Rw5) = _R3(m00, m01, m10, m11, b, u1, v1, w1, u2, v2, w2, u3, v3, w3)
    # bottom-up
    Bu1, Bv1, Bw1, Bu2, Bv2, Bw2, Bu3, Bv3, Bw3, resB = _bottom_up3(
        Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, inv_d2)
    # top-down
    Tu1, Tv1, Tw1, Tu2, Tv2, Tw2, Tu3, Tv3, Tw3, resT = _top_down3(
        Ru0, Ru1, Rv1, Rw1, Ru2, Rv2, Rw2, Ru3, Rv3, Rw3, Ru4, Rv4, Rw4, Ru5, Rv5, Rw5, d1, d2)
    Qu1 = _selc(bottom_up, Bu1, Tu1)
    Qv1 = _selc(bottom_up, Bv1, Tv1)
    Qw1 = _selc(bottom_up, Bw1, Tw1)
    Qu2 = _selc(bottom_up, Bu2, Tu2)
    Qv2 = _selc(bottom_up, Bv2, Tv2)
    Qw2 = _selc(bottom_up, Bw2, Tw2)
    Qu3 = _selc(bottom_up, Bu3, Tu3)
    Qv3 = _selc(bottom_up, Bv3, Tv3)
    Qw3 = _selc(bottom_up, Bw3, Tw3)
    res2 = _sel(bottom_up, resB, resT)
    e2 = max(b * b, u1 * u1, _abs2(v1), u2 * u2, _abs2(v2), u3 * u3, _abs2(v3))
    sc = 1.0 + math.sqrt(e2)
    residual = not (res2 <= _RESIDUAL_TOL2 * sc * sc)
    y0 = 0.5 * (Qv1.real + Qw1.real)
    y1 = 0.5 * (Qw1.imag - Qv1.imag)
    y2 = Qu1.real
    y3 = 0.5 * (Qv2.real + Qw2.real)
    y4 = 0.5 * (Qw2.imag - Qv2.imag)
    y5 = Qu2.real
    y6 = 0.5 * (Qv3.real + Qw3.real)
    y7 = 0.5 * (Qw3.imag - Qv3.imag)
    y8 = Qu3.real
    acc = ((y0 + y1) + (y2 + y3)) + ((y4 + y5) + (y6 + y7)) + y8
    nonfinite = not (acc - acc == 0.0)
    st = _sel(bad_scale, STATUS_NONFINITE,
              _sel(branch, STATUS_BRANCH, _sel(residual, STATUS_RESIDUAL, _sel(nonfinite, STATUS_NONFINITE, 0))))
    ok = st == 0
    return (st, nu, _sel(ok, y0, x0), _sel(ok, y1, x1), _sel(ok, y2, x2), _sel(ok, y3, x3), _sel(ok, y4, x4),
            _sel(ok, y5, x5), _sel(ok, y6, x6), _sel(ok, y7, x7), _sel(ok, y8, x8), need_root)


#: orbits per lock-stepped block.  A compile-time constant: with the rows of the block at constant offsets
#: of one buffer, LLVM proves that the rows do not overlap and vectorises the loop over the lanes without
#: run-time alias checks (with run-time strides it does not vectorise this loop body at all).
LANES = 64
# rows: 0-8 state, 9-10 ν, 11 b, 12-13 η, 14-19 z^1..z^3, 20 δ1, 21 δ2, 22 1/δ2, 23 bottom-up, 24 alive,
# 25 status, 26 redo (the lane needs the closest-root fallback)
_ROWS = 27


@njit(cache=True, error_model="numpy", inline="always")
def _lane_values(x0, x1, x2, x3, x4, x5, x6, x7, x8, nur, nui, b, er, ei, z1r, z1i, z2r, z2i, z3r, z3i, d1, d2,
                 inv_d2, bu, alive, newton):
    """New values of the rows 0-10, 25, 26 of one lane (the array is not passed in: an array argument would
    bring reference counting into the loop and stop its vectorisation)."""
    nu = complex(nur, nui)
    r = _lane3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, complex(er, ei), complex(z1r, z1i), complex(z2r, z2i),
               complex(z3r, z3i), d1, d2, inv_d2, bu, nu, nu * nu, _cdiv(complex(1.0, 0.0), nu + nu), newton)
    redo = _sel(alive, r[11], False)
    a = _sel(redo, False, alive)
    return (_sel(a, r[2], x0), _sel(a, r[3], x1), _sel(a, r[4], x2), _sel(a, r[5], x3), _sel(a, r[6], x4),
            _sel(a, r[7], x5), _sel(a, r[8], x6), _sel(a, r[9], x7), _sel(a, r[10], x8), _sel(a, r[1].real, nur),
            _sel(a, r[1].imag, nui), _sel(a, float(r[0]), 0.0), _sel(redo, 1.0, 0.0))


@njit(cache=True, error_model="numpy")
def _lanes3_step(buf, newton, mode):
    """One step of ``LANES`` lock-stepped N = 3 orbits stored by rows in ``buf`` (``_ROWS × LANES``).

    ``mode``: 1 all lanes divide bottom-up, 2 all top-down, 0 mixed (both computed, then selected); the
    uniform modes let LLVM drop the unused direction.  Lanes flagged ``redo`` are then stepped by
    :func:`_step3` itself (closest-root continuation of ``ν1``), one by one."""
    L = LANES
    for l in range(L):
        bu = _sel(mode == 1, True, _sel(mode == 2, False, buf[23 * L + l] != 0.0))
        v = _lane_values(buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l], buf[5 * L + l],
                         buf[6 * L + l], buf[7 * L + l], buf[8 * L + l], buf[9 * L + l], buf[10 * L + l],
                         buf[11 * L + l], buf[12 * L + l], buf[13 * L + l], buf[14 * L + l], buf[15 * L + l],
                         buf[16 * L + l], buf[17 * L + l], buf[18 * L + l], buf[19 * L + l], buf[20 * L + l],
                         buf[21 * L + l], buf[22 * L + l], bu, buf[24 * L + l] != 0.0, newton)
        buf[l] = v[0]
        buf[L + l] = v[1]
        buf[2 * L + l] = v[2]
        buf[3 * L + l] = v[3]
        buf[4 * L + l] = v[4]
        buf[5 * L + l] = v[5]
        buf[6 * L + l] = v[6]
        buf[7 * L + l] = v[7]
        buf[8 * L + l] = v[8]
        buf[9 * L + l] = v[9]
        buf[10 * L + l] = v[10]
        buf[25 * L + l] = v[11]
        buf[26 * L + l] = v[12]
    for l in range(L):
        if buf[26 * L + l] != 0.0:
            nu = complex(buf[9 * L + l], buf[10 * L + l])
            x = (buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l], buf[5 * L + l],
                 buf[6 * L + l], buf[7 * L + l], buf[8 * L + l])
            st, nu, xn = _step3(x, buf[11 * L + l], complex(buf[12 * L + l], buf[13 * L + l]),
                                complex(buf[14 * L + l], buf[15 * L + l]), complex(buf[16 * L + l], buf[17 * L + l]),
                                complex(buf[18 * L + l], buf[19 * L + l]), buf[20 * L + l], buf[21 * L + l],
                                buf[22 * L + l], buf[23 * L + l] != 0.0, nu, nu * nu,
                                _cdiv(complex(1.0, 0.0), nu + nu), newton)
            buf[25 * L + l] = float(st)
            buf[9 * L + l] = nu.real
            buf[10 * L + l] = nu.imag
            for i in range(9):
                buf[i * L + l] = xn[i]


@njit(cache=True, error_model="numpy")
def _run_block3(X0, b, eta, nu0, cont, steps, save_every, out, final, drift, status, fail, nu_last, want_drift):
    """Up to ``LANES`` orbits ``X0`` (W, 9) in lock-step; outputs as in :func:`run_ensemble`.  Each orbit gives
    the bits of :func:`run_orbit3` (same operations per lane; a failed orbit is frozen at its last good
    state).  Unused lanes repeat orbit 0 and are discarded."""
    W = X0.shape[0]
    L = LANES
    buf = np.empty(_ROWS * L)
    for l in range(L):
        src = l if l < W else 0
        for i in range(9):
            buf[i * L + l] = X0[src, i]
        buf[9 * L + l] = nu0[src].real
        buf[10 * L + l] = nu0[src].imag
        e = eta[src]
        z1 = _cdiv(complex(1.0, 0.0), e)
        z2 = z1 * z1
        z3 = z2 * z1
        d2 = e.real * e.real + e.imag * e.imag
        buf[11 * L + l] = b[src]
        buf[12 * L + l] = e.real
        buf[13 * L + l] = e.imag
        buf[14 * L + l] = z1.real
        buf[15 * L + l] = z1.imag
        buf[16 * L + l] = z2.real
        buf[17 * L + l] = z2.imag
        buf[18 * L + l] = z3.real
        buf[19 * L + l] = z3.imag
        buf[20 * L + l] = -(e.real + e.real)
        buf[21 * L + l] = d2
        buf[22 * L + l] = 1.0 / d2
        buf[23 * L + l] = 1.0 if d2 >= 1.0 else 0.0
        buf[24 * L + l] = 1.0
        buf[25 * L + l] = 0.0
        buf[26 * L + l] = 0.0
    for l in range(W):
        for i in range(9):
            out[l, 0, i] = X0[l, i]
        status[l] = STATUS_OK
        fail[l] = steps
    nbu = 0
    for l in range(L):
        if buf[23 * L + l] != 0.0:
            nbu += 1
    mode = 1 if nbu == L else (2 if nbu == 0 else 0)
    for n in range(steps):
        _lanes3_step(buf, n > 0 or cont, mode)
        for l in range(L):
            if buf[25 * L + l] != 0.0 and buf[24 * L + l] != 0.0:
                buf[24 * L + l] = 0.0
                if l < W:
                    status[l] = int(buf[25 * L + l])
                    fail[l] = n
        if (n + 1) % save_every == 0:
            j = (n + 1) // save_every
            for l in range(W):
                for i in range(9):
                    out[l, j, i] = buf[i * L + l]
    I0 = np.empty(6)
    Ib = np.empty(6)
    for l in range(W):
        for i in range(9):
            final[l, i] = buf[i * L + l]
        nu_last[l] = complex(buf[9 * L + l], buf[10 * L + l])
        for k in range(6):
            drift[l, k] = 0.0
        if want_drift:
            _integrals(X0[l], b[l], 3, I0)
            last = (fail[l] if status[l] != STATUS_OK else steps) // save_every
            _drift_pass(out[l], final[l], last, b[l], 3, I0, Ib, drift[l])


@njit(cache=True, error_model="numpy", parallel=True)
def run_ensemble(X0, b, eta, nu0, cont, steps, save_every, specialise, out, final, drift, status, fail, nu_last,
                 want_drift=True):
    r"""A batch of independent orbits: ``X0`` (B, 3N), per-orbit ``b``, ``eta``, ``nu0`` (B,);
    ``out`` (B, S, 3N), ``final`` (B, 3N), ``drift`` (B, 2N), ``status``/``fail`` (B,) int64,
    ``nu_last`` (B,) complex.  N = 3 (with ``specialise``): blocks of ``LANES`` orbits in lock-step
    (:func:`_run_block3`, SIMD across orbits), in a ``prange`` loop over blocks; other N: :func:`run_orbit`
    per orbit in a ``prange`` loop.  Either way every orbit gets the bits of its single-orbit run."""
    B = X0.shape[0]
    n3 = X0.shape[1]
    if specialise and n3 == 9:
        nblocks = (B + LANES - 1) // LANES
        for k in prange(nblocks):
            i0 = k * LANES
            i1 = min(i0 + LANES, B)
            _run_block3(X0[i0:i1], b[i0:i1], eta[i0:i1], nu0[i0:i1], cont, steps, save_every, out[i0:i1],
                        final[i0:i1], drift[i0:i1], status[i0:i1], fail[i0:i1], nu_last[i0:i1], want_drift)
    else:
        for i in prange(B):
            st, n, nu = run_orbit(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[i], final[i], drift[i],
                                  want_drift)
            status[i] = st
            fail[i] = n
            nu_last[i] = nu


# ---------------------------------------------------------------------------------------------
# N = 3 by the Appendix 1 closed form (jetgaudin.backlund.closed_form), compiled, for comparison
# ---------------------------------------------------------------------------------------------

_closed_form_core = None


def closed_form_orbit(x0, b, eta, nu0, steps):
    r"""Orbit (steps + 1, 9) of the N = 3 map by the corrected Appendix 1 closed form
    ``X̆ = Φ(s, t) X + X0(s, t)`` (:func:`jetgaudin.backlund.closed_form._two_point_core`, compiled with
    ``numba.njit``), with ``ℓ(η)``, ``ν1`` and the eigenvector as in :func:`_step3`,
    ``s = −k2/k1`` and ``t = 2i Im(η) s̄/(1 + |s|²)``.  For benchmarks and cross-checks only: ``s`` is
    infinite where ``k1 = 0`` (the dressing kernels work projectively there).  Raises on a singular step."""
    global _closed_form_core
    if _closed_form_core is None:
        from .closed_form import _two_point_core

        core = njit(cache=False, error_model="numpy", inline="always")(_two_point_core)

        @njit(cache=False, error_model="numpy")
        def orbit(x0, b, eta, nu0, steps, out):
            z1 = _cdiv(complex(1.0, 0.0), eta)
            z2 = z1 * z1
            z3 = z2 * z1
            x = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8])
            for i in range(9):
                out[0, i] = x0[i]
            nu = nu0
            for n in range(steps):
                nu_sq = nu * nu
                inv_2nu = _cdiv(complex(1.0, 0.0), nu + nu)
                v1 = complex(x[0], -x[1])
                w1 = complex(x[0], x[1])
                v2 = complex(x[3], -x[4])
                w2 = complex(x[3], x[4])
                v3 = complex(x[6], -x[7])
                w3 = complex(x[6], x[7])
                u = (complex(b, 0.0) + _cr(z1, x[2])) + (_cr(z2, x[5]) + _cr(z3, x[8]))
                v = (v1 * z1 + v2 * z2) + v3 * z3
                w = (w1 * z1 + w2 * z2) + w3 * z3
                if n > 0:
                    c = u * u + v * w - nu_sq
                    nu = nu + c * inv_2nu
                k1, k2, nk, st = _eigvec(u, v, w, nu)
                if st != STATUS_OK or _abs2(k1) == 0.0:
                    return n
                s = -_cdiv(k2, k1)
                t = complex(0.0, eta.imag + eta.imag) * s.conjugate() * (1.0 / (1.0 + _abs2(s)))
                r = core(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], b, eta.real, eta.imag, s, t)
                x = (r[0].real, r[1].real, r[2].real, r[3].real, r[4].real, r[5].real, r[6].real, r[7].real,
                     r[8].real)
                for i in range(9):
                    out[n + 1, i] = x[i]
            return steps

        _closed_form_core = orbit
    out = np.empty((steps + 1, 9))
    n = _closed_form_core(np.ascontiguousarray(x0, dtype=np.float64), float(b), complex(eta), complex(nu0), int(steps),
                          out)
    if n != steps:
        raise status_error(STATUS_BRANCH, n)
    return out


# ---------------------------------------------------------------------------------------------
# the default branch of ν(η) (the branch rule of jetgaudin.nu), compiled, for the first step
# ---------------------------------------------------------------------------------------------


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


def nu_default(X, b, eta, sheet=1):
    r"""Compiled :func:`jetgaudin.nu` (default branch times ``sheet``) for states ``X`` (B, 3N) with per-orbit
    ``b``, ``eta`` (B,); equal to the NumPy branch rule to round-off.  Raises :class:`jetgaudin.BranchPointError`
    where the rule is undefined."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    B = X.shape[0]
    nu = np.empty(B, np.complex128)
    ok = np.zeros(B, np.bool_)
    fn = _nu_default_batch if B >= 256 else _nu_default_serial
    fn(X, np.ascontiguousarray(b, dtype=np.float64), np.ascontiguousarray(eta, dtype=np.complex128), float(sheet), nu,
       ok)
    if not np.all(ok):
        from .._errors import BranchPointError

        i = int(np.flatnonzero(~ok)[0])
        raise BranchPointError(
            f"orbit {i}: nu has a branch point on the vertical segment from Re(eta) to eta (or Re(eta) = 0); "
            "move eta or the state off the branch point"
        )
    return nu


def flops_per_step(N: int, route: str = "auto") -> dict:
    r"""Floating-point operations of one step, counted by hand from the kernel source (:func:`_step3` for
    ``route="n3"``, :func:`_step_generic` for ``route="generic"``; ``"auto"``: ``n3`` when ``N = 3``).

    Counting rules: one real ``+ − × ÷ √`` = 1 flop (comparisons, ``max``, negations and
    conjugations = 0); complex ``±`` = 2, complex × complex = 6, real × complex (:func:`_cr`) = 2,
    ``|z|²`` = 3, complex ÷ (:func:`_cdiv`) = 14.  Returns the parts and the ``total``.
    """
    if route == "auto":
        route = "n3" if N == 3 else "generic"
    if route == "n3":
        if N != 3:
            raise ValueError("route 'n3' is the N = 3 kernel")
        parts = {
            "ell_at_eta": 12 + 22 + 22,  # u: 3 real×complex + 3 adds; v, w: 3 complex products + 2 adds each
            "nu": 14 + 17 + 22,  # u² + vw; Newton update; ν_prev², 1/(2ν_prev) (previous step's ν)
            "eigenvector": 35,  # two |k|², the scale of the branch-point test
            "M0": 26,
            "R_products": 62 + 3 * 118 + 36,  # T1, T2 for ℓ_0 (b real) and ℓ_1..ℓ_3; sums into R_k
            "division": 72 + 38,  # Q_3..Q_0 bottom-up; residual of the two unused equations
            "checks_and_state": 17 + 12 + 9,  # |ℓ| scale of the residual test; new state; finiteness
        }
    elif route == "generic":
        parts = {
            "ell_at_eta": 7 * N + 2 * (8 * (N - 1) + 6),  # Horner (u real parts added as reals)
            "nu": 14 + 9 + 3,  # u² + vw; square root; closest-root test
            "eigenvector": 35,
            "M0": 26,
            "R_products": 62 + 118 * N + 12 * N,
            "division": 24 * N + 38,
            "checks_and_state": 4 * N + 5 + 4 * N + 3 * N + 1,
        }
    else:
        raise ValueError(f"route must be 'auto', 'n3' or 'generic', got {route!r}")
    parts["total"] = sum(parts.values())
    return parts


# ---------------------------------------------------------------------------------------------
# Python drivers (raise typed errors; no mathematics)
# ---------------------------------------------------------------------------------------------


def status_error(status, fail, orbit=None):
    """The exception for a kernel status: :class:`BranchPointError` or :class:`SingularStepError`."""
    from .._errors import BranchPointError, SingularStepError

    where = f" at step {int(fail)}" + ("" if orbit is None else f" of orbit {int(orbit)}")
    cls = BranchPointError if int(status) == STATUS_BRANCH else SingularStepError
    return cls(f"singular Bäcklund step{where} (compiled route): {STATUS_MESSAGES[int(status)]}")


def _raise_status(status, fail, orbit=None):
    raise status_error(status, fail, orbit)


def saved_count(steps: int, save_every: int) -> int:
    """Number of saved states ``x_0, x_k, x_2k, …`` (``k = save_every``)."""
    return steps // save_every + 1


def run_batch(X, b, eta, nu0, cont, steps, save_every, specialise=True):
    r"""Run :func:`run_ensemble` on a batch ``X`` (B, 3N) with per-orbit ``b``, ``eta``, ``nu0`` (B,); never raises.

    Returns ``(out (B, S, 3N), final (B, 3N), drift (B, 2N), nu_last (B,), status (B,), fail (B,))``
    (``status`` and ``fail``: the ``STATUS_*`` code and the failing step of each orbit).
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    B, n3 = X.shape
    out = np.empty((B, saved_count(steps, save_every), n3))
    final = np.empty((B, n3))
    drift = np.empty((B, 2 * (n3 // 3)))
    status = np.zeros(B, np.int64)
    fail = np.zeros(B, np.int64)
    nu_last = np.empty(B, np.complex128)
    run_ensemble(
        X,
        np.ascontiguousarray(b, dtype=np.float64),
        np.ascontiguousarray(eta, dtype=np.complex128),
        np.ascontiguousarray(nu0, dtype=np.complex128),
        bool(cont),
        int(steps),
        int(save_every),
        bool(specialise),
        out,
        final,
        drift,
        status,
        fail,
        nu_last,
    )
    return out, final, drift, nu_last, status, fail


def iterate_batch(X, b, eta, nu0, cont, steps, save_every, *, specialise=True):
    r"""Run the compiled map on a batch ``X`` (B, 3N) with per-orbit ``b``, ``eta``, ``nu0`` (B,).

    Returns ``(out (B, S, 3N), final (B, 3N), drift (B, 2N), nu_last (B,))``; raises
    :class:`jetgaudin.SingularStepError` naming the first failing orbit and step.
    """
    out, final, drift, nu_last, status, fail = run_batch(X, b, eta, nu0, cont, steps, save_every, specialise)
    bad = np.flatnonzero(status)
    if bad.size:
        i = bad[0]
        _raise_status(status[i], fail[i], i)
    return out, final, drift, nu_last


def iterate_single(x, b, eta, nu0, cont, steps, save_every, *, specialise=True, want_drift=True):
    """One orbit ``x`` (3N,): returns ``(out (S, 3N), final (3N,), drift (2N,), nu_last)``."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    n3 = x.shape[0]
    out = np.empty((saved_count(steps, save_every), n3))
    final = np.empty(n3)
    drift = np.empty(2 * (n3 // 3))
    fn = run_orbit3 if (specialise and n3 == 9) else run_orbit
    status, fail, nu = fn(x, float(b), complex(eta), complex(nu0), bool(cont), int(steps), int(save_every),
                          out, final, drift, bool(want_drift))
    if status != STATUS_OK:
        _raise_status(status, fail)
    return out, final, drift, nu
