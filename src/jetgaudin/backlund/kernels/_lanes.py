r"""N = 3 ensembles: ``LANES`` orbits in lock-step (structure of arrays), branch-free, for SIMD across orbits.

:func:`_lane3` is :func:`._n3._step3` with both sides of every choice computed and the same value selected, so
each lane gives the bits of the single-orbit route; lanes whose Newton update of ``ν1`` is refused are redone by
:func:`._n3._step3` itself.  Import only after :func:`._target.configure`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._n3 import _R3, _bottom_up3, _ell3, _step3, _top_down3, _uvw3
from ._scalar import (
    _RESIDUAL_TOL2,
    _abs2,
    _cdiv,
    _drift_pass,
    _eigvec_flags,
    _integrals,
    _m0_from_k,
    _sel,
    _selc,
)
from ._status import STATUS_BRANCH, STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL


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
            out[0, l, i] = X0[l, i]
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
                    out[j, l, i] = buf[i * L + l]
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
            _drift_pass(out[:, l], final[l], last, b[l], 3, I0, Ib, drift[l])


@njit(cache=True, error_model="numpy", parallel=True)
def run_lanes3(X0, b, eta, nu0, cont, steps, save_every, out, final, drift, status, fail, nu_last, want_drift):
    r"""A batch of independent N = 3 orbits: ``X0`` (B, 9), per-orbit ``b``, ``eta``, ``nu0`` (B,); ``out``
    (S, B, 9) (step-major: the layout of ``iterate()``'s result, no transposed copy), ``final`` (B, 9), ``drift``
    (B, 6), ``status``/``fail`` (B,) int64, ``nu_last`` (B,) complex.  Blocks of ``LANES`` orbits in lock-step
    (:func:`_run_block3`, SIMD across orbits), in a ``prange`` loop over blocks; every orbit gets the bits of its
    single-orbit run (:func:`._n3.run_orbit3`)."""
    B = X0.shape[0]
    nblocks = (B + LANES - 1) // LANES
    for k in prange(nblocks):
        i0 = k * LANES
        i1 = min(i0 + LANES, B)
        _run_block3(X0[i0:i1], b[i0:i1], eta[i0:i1], nu0[i0:i1], cont, steps, save_every, out[:, i0:i1],
                    final[i0:i1], drift[i0:i1], status[i0:i1], fail[i0:i1], nu_last[i0:i1], want_drift)
