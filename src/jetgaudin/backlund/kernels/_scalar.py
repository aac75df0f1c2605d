"""Scalar building blocks of the kernels (complex arithmetic written out, the eigenvector and ``M0`` of the
dressing, the products of ``R(λ)``, selects for the lock-step lanes, the integrals and the drift pass).

The blocks are ``inline="always"`` (inlined by Numba, so that the loop bodies have no calls and LLVM vectorises
the lanes), except the two selects ``_sel`` and ``_selc``, used only by the lanes and left to LLVM's inliner:
inlining their hundreds of call sites at Numba's IR level doubled the compile time of the lanes kernel
(docs/performance.md, part i); the fused multiply-add :func:`_fma` is an LLVM intrinsic (no call at all).
Either way the single-orbit routes and the lanes perform the same IEEE operations in the same order (no fastmath,
no automatic contraction, explicit fused multiply-adds) and give the same bits (tests/test_routes.py).
Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import math

from llvmlite import ir
from numba import njit
from numba.core import types
from numba.extending import intrinsic

from ._status import STATUS_BRANCH, STATUS_NONFINITE, STATUS_OK

#: (1e-15)^2: squared form of the eigenvector test max(|k_a|², |k_b|²) <= (1e-15 * scale)² of the NumPy route
_EIG_TOL2 = 1e-30
#: squared relative residual tolerance (maps._RESIDUAL_TOL = 1e-8)
_RESIDUAL_TOL2 = 1e-16


def block(**options):
    """``numba.njit`` for a kernel block, a function called only from compiled code: cached, NumPy's error model
    (division by zero gives inf/NaN, caught by the status tests), and without the CPython and C-function wrappers
    that Numba otherwise compiles with every function, for calls from Python (about 10 % of the first-use compile
    time of the three kernels, docs/performance.md).  The entry points called by the drivers keep ``njit``."""
    return njit(cache=True, error_model="numpy", no_cpython_wrapper=True, no_cfunc_wrapper=True, **options)




@intrinsic
def _fma(typingctx, a, b, c):
    r"""``a·b + c`` rounded once (IEEE 754 fusedMultiplyAdd): LLVM's ``llvm.fma.f64``, an FMA instruction where the
    target has one, else the C library's correctly rounded ``fma`` (the same bits either way).  Written
    explicitly where the N = 3 blocks use it, so that the single-orbit route and the vectorised lanes perform the
    same fused operations (LLVM's own contraction, ``fastmath={"contract"}``, fuses differently in scalar and
    vector code).  An intrinsic, not a Numba function: no call for Numba's inliner to expand (hundreds of call
    sites made the lanes kernel's compile twice as long)."""
    if not all(isinstance(t, (types.Float, types.Integer)) for t in (a, b, c)):
        return None
    sig = types.float64(a, b, c)

    def codegen(context, builder, signature, args):
        vals = [context.cast(builder, v, t, types.float64) for v, t in zip(args, signature.args, strict=True)]
        fn = builder.module.declare_intrinsic("llvm.fma", [ir.DoubleType()] * 3)
        return builder.call(fn, vals)

    return sig, codegen


@intrinsic
def _bits(typingctx, x):
    """The IEEE 754 bits of a float64 as an int64 (LLVM ``bitcast``: no call, no memory)."""
    if not isinstance(x, types.Float):
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(context.cast(builder, args[0], signature.args[0], types.float64), ir.IntType(64))

    return types.int64(x), codegen


@intrinsic
def _from_bits(typingctx, n):
    """The float64 whose IEEE 754 bits are the int64 ``n`` (LLVM ``bitcast``)."""
    if not isinstance(n, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(context.cast(builder, args[0], signature.args[0], types.int64), ir.DoubleType())

    return types.float64(n), codegen


@block(inline="always")
def _abs2(z):
    return z.real * z.real + z.imag * z.imag


@block(inline="always")
def _cdiv(a, b):
    r"""``a/b = a·conj(b)·(1/|b|²)``: one real division (shorter latency than Smith's algorithm, which
    the NumPy route uses; the two agree to a few ulp for ``1e-150 < |b| < 1e150``); never raises
    (``b = 0`` gives inf/NaN, caught by the callers' singularity tests and the final finiteness test)."""
    br = b.real
    bi = b.imag
    r = 1.0 / (br * br + bi * bi)
    return complex((a.real * br + a.imag * bi) * r, (a.imag * br - a.real * bi) * r)


@block(inline="always")
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


@block(inline="always")
def _continue_nu(u, v, w, nu_prev):
    r"""Root of ``u² + vw`` closest to ``nu_prev`` (``maps._continue_nu``)."""
    r = _csqrt(u * u + v * w)
    if r.real * nu_prev.real + r.imag * nu_prev.imag >= 0.0:
        return r
    return -r


@block(inline="always")
def _division_constants(eta):
    """``d1 = −2 Re η``, ``d2 = |η|²`` of ``(λ − η)(λ − η̄) = λ² + d1 λ + d2`` (the divisor of the real two-point
    dressing), ``1/d2``, and ``bottom_up = d2 >= 1`` (the direction of the exact division)."""
    d1 = -(eta.real + eta.real)
    d2 = eta.real * eta.real + eta.imag * eta.imag
    return d1, d2, 1.0 / d2, d2 >= 1.0


@block(inline="always")
def _eig_candidates(u, v, w, nu):
    """The two candidate eigenvectors of :func:`_eigvec`, ``a = (v, ν − u)`` and ``b = (u + ν, w)``, with their
    ``|a|²``, ``|b|²``."""
    a1 = v
    a2 = nu - u
    b1 = u + nu
    b2 = w
    return a1, a2, b1, b2, _abs2(a1) + _abs2(a2), _abs2(b1) + _abs2(b2)


@block(inline="always")
def _eigvec(u, v, w, nu):
    r"""Eigenvector ``k`` of ``ℓ(η) = [[u, v], [w, −u]]`` for ``ν`` (:func:`jetgaudin.backlund._dressing.eigenvector`):
    ``(v, ν − u)`` or ``(u + ν, w)``, the one with the larger ``|k|²``; ``s = −k_2/k_1`` may be infinite.
    Returns ``(k1, k2, |k|², status)``: ``STATUS_BRANCH`` when both vanish (``ℓ(η) = 0``, a double branch
    point), ``STATUS_NONFINITE`` on overflow."""
    # the same values as _eigvec_flags, with an if instead of selects: ~5 % faster on the single-orbit chain
    a1, a2, b1, b2, na, nb = _eig_candidates(u, v, w, nu)
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


@block(inline="always")
def _eigvec_flags(u, v, w, nu):
    """:func:`_eigvec` without data-dependent branches (both candidates formed, one selected; for the
    lock-step lanes): returns ``(k1, k2, |k|², bad, code)``, ``bad``: the status of :func:`_eigvec` is not
    ``STATUS_OK``, ``code``: that status if ``bad`` (a float).

    One comparison for both tests (a comparison into a mask costs an FMA-pipe cycle on Zen 4, an add or ``maxpd``
    none, ``benchmarks/fp_ports.py``): ``bad = not (|k|² > _EIG_TOL2 scale2)``.  With ``scale2`` finite,
    ``u, v, w, ν`` are finite, so ``|k|²`` is finite or ``+inf``, never NaN, and ``bad`` is
    ``|k|² <= _EIG_TOL2 scale2`` (``_eigvec``'s ``or |k|² == 0`` is implied: the bound is ``>= 0``); with
    ``scale2`` infinite or NaN the bound is too, nothing exceeds it, and ``bad`` holds.  With
    ``x = scale2 − scale2`` (0, or NaN exactly when ``_eigvec`` says ``STATUS_NONFINITE``),
    ``code = 1 − max(x, −4)`` (``x if x > −4 else −4``: ``maxpd``, NaN gives −4) is ``STATUS_BRANCH`` (1) or
    ``STATUS_NONFINITE`` (5) without a second comparison."""
    a1, a2, b1, b2, na, nb = _eig_candidates(u, v, w, nu)
    use_a = na >= nb
    k1 = _selc(use_a, a1, b1)
    k2 = _selc(use_a, a2, b2)
    nk = _sel(use_a, na, nb)
    # NumPy: max(na, nb) <= (1e-15 (|u| + |v| + |w| + |ν|))²; here the bound (Σ|·|)² <= 4 Σ|·|² (no
    # square roots): the compiled route refuses whenever the NumPy route does, and in a band twice as wide
    scale2 = 4.0 * (_abs2(u) + _abs2(v) + _abs2(w) + _abs2(nu))
    x = scale2 - scale2
    bad = not (nk > _EIG_TOL2 * scale2)
    m = x if x > -4.0 else -4.0
    code = 1.0 - m
    return k1, k2, nk, bad, code


@block(inline="always")
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


@block()
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


@block()
def _integrals3v(x0, x1, x2, x3, x4, x5, x6, x7, x8, b):
    """:func:`_integrals` for ``N = 3``, unrolled, of the state's nine floats: the same sums in the same order (the
    same bits), as a tuple, without the loops over ``N`` or an array (the drift pass of an ensemble computes them
    for every saved row of every orbit)."""
    tb = 2.0 * b
    d11 = x0 * x0 + x1 * x1 + x2 * x2
    d12 = x0 * x3 + x1 * x4 + x2 * x5
    d13 = x0 * x6 + x1 * x7 + x2 * x8
    d21 = x3 * x0 + x4 * x1 + x5 * x2
    d22 = x3 * x3 + x4 * x4 + x5 * x5
    d23 = x3 * x6 + x4 * x7 + x5 * x8
    d31 = x6 * x0 + x7 * x1 + x8 * x2
    d32 = x6 * x3 + x7 * x4 + x8 * x5
    d33 = x6 * x6 + x7 * x7 + x8 * x8
    # the accumulation order of _integrals' loops (i outer, j inner; 2b y_i^3 first in each i)
    return (0.0 + tb * x2, (0.0 + d11) + tb * x5, ((0.0 + d12) + d21) + tb * x8, ((0.0 + d13) + d22) + d31,
            (0.0 + d23) + d32, 0.0 + d33)


@block()
def _integrals3(x, b, out):
    """:func:`_integrals3v` of the array ``x`` into ``out``."""
    v = _integrals3v(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], b)
    for k in range(6):
        out[k] = v[k]


@block(inline="always")
def _worse(d, e):
    """``e`` where ``not (e <= d)`` (also NaN), else ``d``: the running maximum of :func:`_drift_pass`."""
    return e if not (e <= d) else d


@block(inline="always")
def _drift3_row(d, inv, i0, i):
    """One row's update of :func:`_drift_pass` for ``N = 3`` on tuples (the same operations)."""
    return (_worse(d[0], abs(i[0] - i0[0]) * inv[0]), _worse(d[1], abs(i[1] - i0[1]) * inv[1]),
            _worse(d[2], abs(i[2] - i0[2]) * inv[2]), _worse(d[3], abs(i[3] - i0[3]) * inv[3]),
            _worse(d[4], abs(i[4] - i0[4]) * inv[4]), _worse(d[5], abs(i[5] - i0[5]) * inv[5]))


@block()
def _drift_pass3(out, o, final, last, b, x0, drift):
    """:func:`_drift_pass` for ``N = 3`` of orbit ``o`` of a batch (``out`` (S, B, 9), ``final`` (B, 9), its
    initial state ``x0`` (9,), its ``drift`` row (6,)): the same values, with scalars and tuples instead of views
    and scratch arrays (no reference counting per orbit and row)."""
    i0 = _integrals3v(x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8], b)
    inv = (1.0 / max(1.0, abs(i0[0])), 1.0 / max(1.0, abs(i0[1])), 1.0 / max(1.0, abs(i0[2])),
           1.0 / max(1.0, abs(i0[3])), 1.0 / max(1.0, abs(i0[4])), 1.0 / max(1.0, abs(i0[5])))
    d = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for j in range(1, last + 1):
        d = _drift3_row(d, inv, i0, _integrals3v(out[j, o, 0], out[j, o, 1], out[j, o, 2], out[j, o, 3],
                                                 out[j, o, 4], out[j, o, 5], out[j, o, 6], out[j, o, 7],
                                                 out[j, o, 8], b))
    d = _drift3_row(d, inv, i0, _integrals3v(final[o, 0], final[o, 1], final[o, 2], final[o, 3], final[o, 4],
                                             final[o, 5], final[o, 6], final[o, 7], final[o, 8], b))
    for k in range(6):
        drift[k] = d[k]


@block()
def _drift_pass(out, final, last, b, N, I0, Ibuf, drift):
    r"""``drift_k = max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over the saved rows ``out[1..last]`` and
    ``final`` (computed after the run, off the critical path of the steps).  ``Ibuf``: scratch of ``4N`` floats
    from the caller, allocated once per call (an allocation per orbit here was ~2 % of a 500-step ensemble call)."""
    inv = Ibuf[2 * N:]
    for k in range(2 * N):
        inv[k] = 1.0 / max(1.0, abs(I0[k]))
    for j in range(1, last + 2):
        row = out[j] if j <= last else final
        if N == 3:
            _integrals3(row, b, Ibuf)
        else:
            _integrals(row, b, N, Ibuf)
        for k in range(2 * N):
            e = abs(Ibuf[k] - I0[k]) * inv[k]
            if not (e <= drift[k]):  # also propagates NaN
                drift[k] = e


# ---------------------------------------------------------------------------------------------
# building blocks shared by the generic route and the N = 3 route (so that the two agree bit for bit)
# ---------------------------------------------------------------------------------------------


@block(inline="always")
def _cr(c, r):
    """complex × real, as NumPy's product with ``r + 0i`` (identical for finite values)."""
    return complex(c.real * r, c.imag * r)


@block(inline="always")
def _horner_step_u(acc, z, u):
    """``acc·z + (u + 0i)`` with real ``u``."""
    p = acc * z
    return complex(p.real + u, p.imag)


@block(inline="always")
def _commutator(p00, p01, p10, u, v, w):
    r"""``[P, ℓ_m]`` (entries 00, 01, 10; traceless) for the traceless ``P = [[p00, p01], [p10, −p00]]`` and
    ``ℓ_m = [[u, v], [w, −u]]``: ``(p01 w − v p10, 2 (p00 v − u p01), 2 (u p10 − p00 w))``."""
    return (p01 * w - v * p10, 2.0 * (p00 * v - u * p01), 2.0 * (u * p10 - p00 * w))


@block(inline="always")
def _m0_times(m00, m01, m10, m11, cu, cv, cw):
    r"""``M0 C`` (entries 00, 01, 10) for a traceless ``C = [[cu, cv], [cw, −cu]]`` (``M0 [P, ℓ]`` is traceless:
    ``tr(P [P, ℓ]) = 0``)."""
    return (m00 * cu + m01 * cw, m00 * cv - m01 * cu, m10 * cu + m11 * cw)


@block()
def _sel(c, a, b):
    return a if c else b


@block()
def _selc(c, a, b):
    """complex select by components (a select of a complex struct keeps LLVM from vectorising)."""
    return complex(_sel(c, a.real, b.real), _sel(c, a.imag, b.imag))


