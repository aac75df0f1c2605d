r"""N = 3 ensembles: ``LANES`` orbits in lock-step (structure of arrays), branch-free, for SIMD across orbits.

:func:`_lane_axis` and :func:`_lane_dress` are the two halves of :func:`._n3._step3` with both sides of every
choice computed and the same value selected, so each lane gives the bits of the single-orbit route (the same
operations, fused multiply-adds included, in the same order); lanes whose Newton update of ``ν1`` is refused are
redone by a second pass with ``ν1`` continued by the closest root (:func:`run_lanes3`).  Import only after
:func:`._target.configure`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import _scalar as S
from ._n3 import (
    _CARRY_TOL2,
    _NEWTON_TOL2,
    NCONST,
    _axis,
    _constants3,
    _ell3,
    _finite9,
    _newton_nu,
    _nu2,
    _scale3,
    _solve3,
    _tol3,
    _zed3,
)
from ._scalar import block
from ._status import STATUS_BRANCH, STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL


@block(inline="always")
def _lane_axis(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, z1r, z1i, z2r, z2i, z3r, z3i, q, nu, newton):
    """First half of :func:`._n3._step3` without data-dependent branches: ``ℓ(η)``, the Newton update of ``ν1``
    (carried to the next step, or applied first: the selects of ``_step3``'s cases), the eigenvector and the
    unnormalised axis ``n'`` with ``r = 1/(q|k|²)`` (:func:`._n3._axis`; ``q`` the power of two of
    :func:`._n3._scale3`).  Returns ``(ν1 for the next step, n'_1, n'_2, n'_3, r, need_root, bad, code)``
    (``bad``: the eigenvector failed, ``code``: then its status, :func:`._scalar._eigvec_flags`);
    ``need_root``: the Newton update of ``ν1`` was refused, the lane must be redone with the closest root."""
    u, v, w = _ell3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, z1r, z1i, z2r, z2i, z3r, z3i)
    nu2 = _nu2(u, v, w)
    c = nu2 - nu * nu
    a2 = S._abs2(c)
    s2 = S._abs2(nu2)
    # the closest-root fallback of _step3 is rare: flag the lane (redone by a second pass) instead of computing it
    need_root = S._sel(newton, not (a2 <= _NEWTON_TOL2 * s2), False)  # selects, no short-circuit control flow
    nn = _newton_nu(nu, c, S._cdiv(complex(1.0, 0.0), nu + nu))
    carry = a2 <= _CARRY_TOL2 * s2  # ν1 used as is, its update carried (as _step3)
    nu_next = S._selc(newton, nn, nu)
    nu = S._selc(S._sel(newton, not carry, False), nn, nu)
    k1, k2, nk, bad, code = S._eigvec_flags(u, v, w, nu)  # eigenvector, its status as a flag and a value
    n1, n2, n3, r = _axis(k1, k2, nk, q)
    return nu_next, n1, n2, n3, r, need_root, bad, code


@block(inline="always")
def _lane_dress(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, rk, Z, cst, t, bad_scale, branch):
    """Second half of :func:`._n3._step3` without data-dependent branches: the dressing (:func:`._n3._solve3`) from
    the axis ``n'``, ``r`` and ``Z'`` of :func:`._n3._zed3`.  Returns ``(status, y0, …, y8)``, the new state
    whatever the status (the caller keeps the old state on a failed step, as :func:`._n3._step3` does), and whether
    the step succeeded (``status == 0``, from the flags: no comparison of the status)."""
    r = _solve3(x0, x1, x2, x3, x4, x5, x6, x7, x8, b, n1, n2, rk, Z, cst, t)
    nonfinite = not _finite9(r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9])
    st = S._sel(nonfinite, STATUS_NONFINITE, 0)
    st = S._sel(bad_scale, STATUS_NONFINITE, S._sel(branch, STATUS_BRANCH, S._sel(not r[0], STATUS_RESIDUAL, st)))
    good = S._sel(bad_scale | branch, False, S._sel(r[0], not nonfinite, False))
    return (st, r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], good)


#: orbits per lock-stepped block.  A compile-time constant: with the rows of the block at constant offsets
#: of one buffer, LLVM proves that the rows do not overlap and vectorises the loop over the lanes without
#: run-time alias checks (with run-time strides it does not vectorise this loop body at all).
LANES = 32
# rows: 0-8 state, 9-10 ν, 11 b, 12-28 the constants of _n3._constants3, then the status (0: the lane is alive;
# a failure's code + 8 × its step: the lane is frozen; −1 during a second pass: not redone) and redo (the lane needs
# the closest-root fallback)
_C0 = 12
_STATUS = _C0 + NCONST
assert NCONST == 17  # _fill_constants writes them one by one
_REDO = _STATUS + 1
# the power of two q of _n3._scale3 (per orbit and call), b²
_Q = _STATUS + 2
_BB = _STATUS + 3
# scratch rows between the two halves of a step: n' (3), r (its sign: whether the lane steps), the residual tolerance
_MID = _STATUS + 4
_ROWS = _MID + 5


@block(inline="always")
def _lanes_pass(buf, newton, n8):
    """One step of the alive lanes of ``buf`` (``_ROWS × LANES``), vectorised across the lanes, in two loops over
    the lanes (the axis ``n'``, then the dressing) joined by scratch rows; the dressing loop writes the new values
    in place.  Two shorter loop bodies ran faster than one (docs/performance.md); the operations, hence the bits,
    are those of :func:`._n3._step3`.  A lane that is not alive, or is to be redone, keeps its values and status,
    and so does the state of a lane whose step failed (selects of the old values: on Zen 4 a blend, masked move or
    masked store costs no FMA-pipe cycle, a comparison one, a 512-bit store ~1.6, ``benchmarks/fp_ports.py``;
    writing the new values elsewhere and copying them back cost 13 stores per 8 lanes more).  Inlined by Numba
    into the step loop: as a call it cost an NRT incref/decref of ``buf`` per step (docs/performance.md, issue 36,
    "a third session")."""
    L = LANES
    M = _MID * L
    for l in range(L):
        r = _lane_axis(buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l], buf[5 * L + l],
                       buf[6 * L + l], buf[7 * L + l], buf[8 * L + l], buf[11 * L + l], buf[12 * L + l],
                       buf[13 * L + l], buf[14 * L + l], buf[15 * L + l], buf[16 * L + l], buf[17 * L + l],
                       buf[_Q * L + l], complex(buf[9 * L + l], buf[10 * L + l]), newton)
        # a lane alive and not to be redone takes its new ν1 (in place) and, if its eigenvector failed, the status;
        # the others keep their values.  Whether the lane steps (alive, not to be redone, its eigenvector valid)
        # goes to the dressing in the sign of the row of r (a row of its own cost a 512-bit store, ~1.6 FMA-pipe
        # cycles on Zen 4): r = 1/(q|k|²) > 0 where the lane steps (|k|² > 0 finite there, q > 0 a power of two, or
        # 0 with r = +inf beyond ~1e162, where |ℓ(η)|² has overflowed and the eigenvector failed), −1.0 where not;
        # the dressing steps where ``not (r < 0)`` (a NaN would step, and fail, as on the single-orbit route)
        alive = buf[_STATUS * L + l] == 0.0
        take = S._sel(alive, not r[5], False)
        buf[9 * L + l] = S._sel(take, r[0].real, buf[9 * L + l])
        buf[10 * L + l] = S._sel(take, r[0].imag, buf[10 * L + l])
        buf[_STATUS * L + l] = S._sel(S._sel(take, r[6], False), r[7] + n8, buf[_STATUS * L + l])
        buf[_REDO * L + l] = S._sel(S._sel(alive, r[5], False), 1.0, 0.0)
        buf[M + l] = r[1]
        buf[M + L + l] = r[2]
        buf[M + 2 * L + l] = r[3]
        buf[M + 3 * L + l] = S._sel(S._sel(take, not r[6], False), r[4], -1.0)
        # the residual tolerance (from the state alone) here, where the loop has idle issue slots
        buf[M + 4 * L + l] = _tol3(buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l],
                                   buf[5 * L + l], buf[6 * L + l], buf[7 * L + l], buf[8 * L + l], buf[_BB * L + l])
    for l in range(L):
        cst = (buf[12 * L + l], buf[13 * L + l], buf[14 * L + l], buf[15 * L + l], buf[16 * L + l],
               buf[17 * L + l], buf[18 * L + l], buf[19 * L + l], buf[20 * L + l], buf[21 * L + l],
               buf[22 * L + l], buf[23 * L + l], buf[24 * L + l], buf[25 * L + l], buf[26 * L + l],
               buf[27 * L + l], buf[28 * L + l])
        x0, x1, x2, x3, x4, x5, x6, x7, x8 = (buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l],
                                              buf[5 * L + l], buf[6 * L + l], buf[7 * L + l], buf[8 * L + l])
        go = not (buf[M + 3 * L + l] < 0.0)
        Z = _zed3(x0, x1, x2, x3, x4, x5, x6, x7, x8, buf[11 * L + l], buf[M + l], buf[M + L + l],
                  buf[M + 2 * L + l], buf[M + 3 * L + l], cst)
        r = _lane_dress(x0, x1, x2, x3, x4, x5, x6, x7, x8, buf[11 * L + l], buf[M + l],
                        buf[M + L + l], buf[M + 3 * L + l], Z, cst, buf[M + 4 * L + l], False, False)
        # in place: the state of a lane that steps (``go``: alive, not to be redone, its eigenvector valid) without
        # failure, and the status of a lane that steps; any other lane keeps its values (selects of the old values,
        # stored whole: AVX-512 masked stores where LLVM makes them, as cheap as plain ones on Zen 4)
        new = S._sel(go, r[10], False)
        buf[l] = S._sel(new, r[1], x0)
        buf[L + l] = S._sel(new, r[2], x1)
        buf[2 * L + l] = S._sel(new, r[3], x2)
        buf[3 * L + l] = S._sel(new, r[4], x3)
        buf[4 * L + l] = S._sel(new, r[5], x4)
        buf[5 * L + l] = S._sel(new, r[6], x5)
        buf[6 * L + l] = S._sel(new, r[7], x6)
        buf[7 * L + l] = S._sel(new, r[8], x7)
        buf[8 * L + l] = S._sel(new, r[9], x8)
        buf[_STATUS * L + l] = S._sel(go, float(r[0]) + S._sel(r[10], 0.0, n8), buf[_STATUS * L + l])


@block(inline="always")
def _any_row(buf, start):
    """Whether the row ``buf[start : start + LANES]`` (holding 0.0 or a positive flag/status) has a nonzero entry:
    an OR of the bits, which vectorises (a floating-point reduction would not), in place of a scalar loop with a
    branch per lane."""
    bits = buf.view(np.int64)
    acc = 0
    for l in range(start, start + LANES):
        acc |= bits[l]
    return acc != 0


@block(inline="always")
def _fill_constants(buf, M):
    """The rows of the constants of :func:`._n3._constants3` of every lane from its ``η`` in the scratch rows ``M``,
    ``M + LANES``: a loop over the lanes that LLVM vectorises (the constants of an ensemble whose orbits each have
    their own ``η``, one by one, were ~0.4 ms of a call of 2·10⁴ orbits)."""
    L = LANES
    for l in range(L):
        c = _constants3(complex(buf[M + l], buf[M + L + l]))
        buf[_C0 * L + l] = c[0]
        buf[(_C0 + 1) * L + l] = c[1]
        buf[(_C0 + 2) * L + l] = c[2]
        buf[(_C0 + 3) * L + l] = c[3]
        buf[(_C0 + 4) * L + l] = c[4]
        buf[(_C0 + 5) * L + l] = c[5]
        buf[(_C0 + 6) * L + l] = c[6]
        buf[(_C0 + 7) * L + l] = c[7]
        buf[(_C0 + 8) * L + l] = c[8]
        buf[(_C0 + 9) * L + l] = c[9]
        buf[(_C0 + 10) * L + l] = c[10]
        buf[(_C0 + 11) * L + l] = c[11]
        buf[(_C0 + 12) * L + l] = c[12]
        buf[(_C0 + 13) * L + l] = c[13]
        buf[(_C0 + 14) * L + l] = c[14]
        buf[(_C0 + 15) * L + l] = c[15]
        buf[(_C0 + 16) * L + l] = c[16]


@njit(cache=True, error_model="numpy", nogil=True)
def run_lanes3(X0, b, eta, nu0, cont, steps, save_every, out, final, drift, status, fail, nu_last, want_drift, k0,
               k1):
    r"""The blocks ``k0 <= k < k1`` (of ``LANES`` orbits each) of a batch of independent N = 3 orbits: ``X0`` (B, 9),
    per-orbit ``b``, ``eta``, ``nu0`` (B,); ``out`` (S, B, 9) (step-major: the layout of ``iterate()``'s result, no
    transposed copy), ``final`` (B, 9), ``drift`` (B, 6), ``status``/``fail`` (B,) int64, ``nu_last`` (B,) complex.

    Each block runs in lock-step, SIMD across its orbits (a partial last block repeats its first orbit in the
    unused lanes, whose results are discarded); every orbit gets the bits of its single-orbit run
    (:func:`._n3.run_orbit3`), and a failed orbit is frozen at its last good state.  A step is one pass of
    :func:`_lanes_pass` over the block; lanes whose Newton update of ``ν1`` was refused are left unchanged by it,
    their ``ν1`` continued by the closest root, and they alone are stepped by a second pass without the Newton
    update: the operations of :func:`._n3._step3`'s fallback, hence the same bits.

    One function from the blocks to the step loop (no intermediate compiled functions): Numba links the code of
    every callee into each caller's module and optimises it again there, so each level above the lanes' pass
    cost a full optimisation of it (merging two levels took ~2 s off the first-use compile, docs/performance.md).
    Serial and without the GIL: the driver runs ranges of blocks on threads of its own
    (:func:`._drivers.in_threads`, pieces taken by whichever thread is free).  Against Numba's ``prange`` over
    the blocks (a static split): as fast when the two vCPUs run at the same speed, faster when one is slowed by
    other jobs, and ~2 s less first-use compile (no parallel region; docs/performance.md)."""
    B = X0.shape[0]
    L = LANES
    M = _MID * L
    buf = np.empty(_ROWS * L)
    for k in range(k0, k1):
        i0 = k * L
        W = min(L, B - i0)  # orbits of this block
        # the block's buffer: lane l holds orbit i0 + l (the first orbit again in unused lanes)
        for l in range(L):
            o = i0 + (l if l < W else 0)
            for i in range(9):
                buf[i * L + l] = X0[o, i]
            buf[9 * L + l] = nu0[o].real
            buf[10 * L + l] = nu0[o].imag
            buf[M + l] = eta[o].real  # (the scratch rows hold η until the constants are computed)
            buf[M + L + l] = eta[o].imag
            buf[11 * L + l] = b[o]
            buf[_BB * L + l] = b[o] * b[o]
            buf[_Q * L + l] = _scale3(X0[o, 0], X0[o, 1], X0[o, 2], X0[o, 3], X0[o, 4], X0[o, 5], X0[o, 6],
                                      X0[o, 7], X0[o, 8], b[o])
            buf[_STATUS * L + l] = 0.0
            buf[_REDO * L + l] = 0.0
        _fill_constants(buf, M)
        for o in range(i0, i0 + W):
            for i in range(9):
                out[0, o, i] = X0[o, i]
            status[o] = STATUS_OK
            fail[o] = steps
        for n in range(steps):
            newton = n > 0 or cont
            n8 = 8.0 * n  # a failure at step n writes its code + 8n to the status row
            redo = False
            for second in (False, True):  # one call site of the pass (LLVM inlines it once)
                if second:
                    if not _any_row(buf, _REDO * L):
                        break
                    redo = True
                    for l in range(L):  # ν1 of the lanes to redo continued by the closest root
                        if buf[_REDO * L + l] != 0.0:
                            u, v, w = _ell3(buf[l], buf[L + l], buf[2 * L + l], buf[3 * L + l], buf[4 * L + l],
                                            buf[5 * L + l], buf[6 * L + l], buf[7 * L + l], buf[8 * L + l],
                                            buf[11 * L + l], buf[12 * L + l], buf[13 * L + l], buf[14 * L + l],
                                            buf[15 * L + l], buf[16 * L + l], buf[17 * L + l])
                            nu = S._continue_nu(u, v, w, complex(buf[9 * L + l], buf[10 * L + l]))
                            buf[9 * L + l] = nu.real
                            buf[10 * L + l] = nu.imag
                        elif buf[_STATUS * L + l] == 0.0:  # alive, not redone: out of the second pass
                            buf[_STATUS * L + l] = -1.0
                _lanes_pass(buf, newton and not second, n8)
            if redo:
                for l in range(L):
                    if buf[_STATUS * L + l] == -1.0:
                        buf[_STATUS * L + l] = 0.0
            if (n + 1) % save_every == 0:
                j = (n + 1) // save_every
                for l in range(W):
                    for i in range(9):
                        out[j, i0 + l, i] = buf[i * L + l]
        for l in range(W):
            o = i0 + l
            st = buf[_STATUS * L + l]
            if st != 0.0:  # failed: code + 8 × its step (no row of the block is read right after the pass that
                at = math.floor(st / 8.0)  # wrote it: a load of a lane's masked store in flight waits for it)
                status[o] = int(st - 8.0 * at)
                fail[o] = int(at)
            for i in range(9):
                final[o, i] = buf[i * L + l]
            nu_last[o] = complex(buf[9 * L + l], buf[10 * L + l])
            if want_drift:  # else ``drift`` is left as given (zeros: run_batch)
                last = (fail[o] if status[o] != STATUS_OK else steps) // save_every
                S._drift_pass3(out, o, final, last, b[o], X0[o], drift[o])
