r"""The compiled stepping loop of :class:`jetgaudin.ExactFlow` for runs that save often (private): every step
``B_{η_1} ∘ … ∘ B_{η_k}`` of one orbit in one compiled call, each map's step the two-point map's own kernel
(:func:`jetgaudin.backlund.kernels._n3.orbit3` for N = 3, :func:`~jetgaudin.backlund.kernels._generic.orbit_generic`
otherwise; the same arithmetic as the map's single-orbit route), and each saved row the unrotated map orbit ``Z_n``
rotated **once** through its accumulated angle ``n s θ`` (the maps commute with the rotation about the field, so
``X_n = R_{nsθ} Z_n``).  Applying ``R_θ`` at every step instead multiplies ``|y|`` by ``√(c² + s²)`` at every step,
a fixed factor ``1 + O(ε)`` for a fixed ``θ``: a drift linear in the number of steps (``docs/integrators.md`` §6).

Before this loop, ``iterate`` (every row) made two kernel calls and a rotation call from Python per step: 100× the
end-state call's time (``benchmarks/exact_rows.py``).  Numba's cache keys this module by its own source: after an
edit of the map kernels, clear ``jetgaudin/__pycache__/_exact_loop.*`` (the kernels' own stale-cache check does not
see this module).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._exact_kernels import solve_states
from .backlund.kernels._drivers import kernel_module

_n3 = kernel_module("_n3")
_orbit3 = _n3.orbit3
_step3 = _n3._step3
_constants3 = _n3._constants3
_scale3 = _n3._scale3
_cdiv = _n3.S._cdiv
_orbit_generic = kernel_module("_generic").orbit_generic

__all__ = ["rows_single", "rows_batch", "rows_serial", "solve_rows"]


@njit(cache=True, error_model="numpy")
def _rotate_into(z, angle, out):
    c = np.cos(angle)
    s = np.sin(angle)
    for n in range(z.shape[0] // 3):
        out[3 * n] = c * z[3 * n] - s * z[3 * n + 1]
        out[3 * n + 1] = s * z[3 * n] + c * z[3 * n + 1]
        out[3 * n + 2] = z[3 * n + 2]


@njit(cache=True, error_model="numpy")
def _rotate3_into(x, angle, out):
    """:func:`_rotate_into` of the N = 3 state as a tuple of 9 floats."""
    c = np.cos(angle)
    s = np.sin(angle)
    for n in range(3):
        out[3 * n] = c * x[3 * n] - s * x[3 * n + 1]
        out[3 * n + 1] = s * x[3 * n] + c * x[3 * n + 1]
        out[3 * n + 2] = x[3 * n + 2]


#: rows of the N = 3 loop whose rotation angle is a multiple of this many sub-steps take ``cos``/``sin`` directly;
#: the rows between them combine that with a table (:func:`_angle_cs`)
_ANCHOR = 16


@njit(cache=True, error_model="numpy")
def _angle_table(theta, substeps, ct, st):
    """``ct[k], st[k] = cos, sin((k s) θ)`` for ``k < _ANCHOR`` (``s`` the sub-steps)."""
    for k in range(ct.shape[0]):
        a = (k * substeps) * theta
        ct[k] = np.cos(a)
        st[k] = np.sin(a)


@njit(cache=True, error_model="numpy")
def _anchor_cs(j, theta, substeps):
    """``cos, sin((_ANCHOR j s) θ)``: the anchor of rows ``_ANCHOR j … _ANCHOR j + _ANCHOR − 1``."""
    a = ((_ANCHOR * j) * substeps) * theta
    return np.cos(a), np.sin(a)


@njit(cache=True, error_model="numpy")
def _rotate3_cs(x, c, s, out):
    """:func:`_rotate3_into` with ``cos``, ``sin`` of the angle given."""
    for n in range(3):
        out[3 * n] = c * x[3 * n] - s * x[3 * n + 1]
        out[3 * n + 1] = s * x[3 * n] + c * x[3 * n + 1]
        out[3 * n + 2] = x[3 * n + 2]


@njit(cache=True, error_model="numpy")
def _angle_cs(cb, sb, k, ct, st):
    """``cos, sin`` of the angle ``(m s) θ``, ``m = _ANCHOR j + k``, from the anchor's ``(cb, sb)`` and the table
    (the addition theorem: a few ulps, not accumulated, ``c² + s² − 1 = O(ε)`` at every row); ``k = 0``: the
    anchor itself (``cos``/``sin`` of the angle)."""
    if k == 0:
        return cb, sb
    return cb * ct[k] - sb * st[k], sb * ct[k] + cb * st[k]


@njit(cache=True, error_model="numpy")
def _rows3(x0, b, eta, nu, theta, steps, save_every, substeps, rows, final, info):
    """:func:`rows_single` for ``N = 3`` and ``k ≤ 2`` maps (the exact flow's two, the matched map's one): the N = 3
    kernel's step (:func:`jetgaudin.backlund.kernels._n3._step3`, inlined) on the state as a tuple, with each map's
    per-run constants (``_constants3``) and scale (``_scale3``: a power of two from the state's size, which the step's
    bits do not depend on) computed once per call instead of once per step (``orbit3`` with one step did both at
    every step).  The same arithmetic as :func:`~jetgaudin.backlund.kernels._n3.orbit3` step by step: the same bits
    of the unrotated orbit ``Z_n``.  Row ``m`` is ``Z_m`` rotated through ``(m s) θ`` with ``cos``/``sin`` by
    :func:`_angle_cs` (the anchor ``(16 j s) θ``, ``j = ⌊m/16⌋``, and a table of ``(k s) θ``, ``k < 16``: two
    trigonometric calls per 16 rows instead of two per row, ~5 µs of 417 rows); the final state as its row."""
    k = eta.shape[0]
    c0 = _constants3(eta[0])
    c1 = _constants3(eta[k - 1])
    x = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8])
    q = _scale3(x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8], b)
    n0 = nu[0]
    n1 = nu[k - 1]
    info[0] = 0
    info[1] = 0
    left = save_every
    r = 0
    ctab = np.empty(_ANCHOR)
    stab = np.empty(_ANCHOR)
    _angle_table(theta, substeps, ctab, stab)
    jb = -1  # the anchor (cb, sb) held
    cb = 1.0
    sb = 0.0
    for n in range(steps):
        for p in range(substeps):
            newton = n > 0 or p > 0
            st, n0, xn = _step3(x, b, c0, q, n0, n0 * n0, _cdiv(complex(1.0, 0.0), n0 + n0), newton)
            if st != 0:
                info[0] = st
                info[1] = n
                return
            x = xn
            if k == 2:
                st, n1, xn = _step3(x, b, c1, q, n1, n1 * n1, _cdiv(complex(1.0, 0.0), n1 + n1), newton)
                if st != 0:
                    info[0] = st
                    info[1] = n
                    return
                x = xn
        left -= 1
        if left == 0:
            left = save_every
            j = (n + 1) // _ANCHOR
            if j != jb:
                cb, sb = _anchor_cs(j, theta, substeps)
                jb = j
            cr, sr = _angle_cs(cb, sb, (n + 1) - _ANCHOR * j, ctab, stab)
            _rotate3_cs(x, cr, sr, rows[r])
            r += 1
    j = steps // _ANCHOR
    if j != jb:
        cb, sb = _anchor_cs(j, theta, substeps)
    cr, sr = _angle_cs(cb, sb, steps - _ANCHOR * j, ctab, stab)
    _rotate3_cs(x, cr, sr, final)


@njit(cache=True, error_model="numpy")
def rows_single(x0, b, eta, nu, theta, steps, save_every, substeps, rows, final, info):
    """One orbit ``x0`` (3N,): ``steps`` steps, each ``substeps`` times every map ``η_j`` (``eta`` (k,), first ``ν1``
    ``nu`` (k,), then continued) and the rotation ``θ`` per sub-step; ``rows[r] = X_{(r+1) save_every}``,
    ``final = X_steps``; ``info = (status, failing step)`` (status 0: fine, else the map kernel's status)."""
    n3 = x0.shape[0]
    N = n3 // 3
    k = eta.shape[0]
    if N == 3 and k <= 2:
        _rows3(x0, b, eta, nu, theta, steps, save_every, substeps, rows, final, info)
        return
    z = x0.copy()
    out = np.empty((2, n3))
    fin = np.empty(n3)
    nus = nu.copy()
    eu = np.empty(N + 1)
    ev = np.empty(N + 1, np.complex128)
    ew = np.empty(N + 1, np.complex128)
    Ru = np.empty(N + 3, np.complex128)
    Rv = np.empty(N + 3, np.complex128)
    Rw = np.empty(N + 3, np.complex128)
    Qu = np.zeros(N + 1, np.complex128)
    Qv = np.zeros(N + 1, np.complex128)
    Qw = np.zeros(N + 1, np.complex128)
    xs = np.empty(n3)
    xn = np.empty(n3)
    info[0] = 0
    info[1] = 0
    left = save_every
    r = 0
    for n in range(steps):
        for q in range(substeps):
            cont = n > 0 or q > 0
            for j in range(k):
                if N == 3:
                    st, _, nv = _orbit3(z, b, eta[j], nus[j], cont, 1, 1, out, fin)
                else:
                    st, _, nv = _orbit_generic(z, b, eta[j], nus[j], cont, 1, 1, out, fin, eu, ev, ew, Ru, Rv, Rw,
                                               Qu, Qv, Qw, xs, xn)
                if st != 0:
                    info[0] = st
                    info[1] = n
                    return
                nus[j] = nv
                for i in range(n3):
                    z[i] = fin[i]
        left -= 1
        if left == 0:
            left = save_every
            _rotate_into(z, ((n + 1) * substeps) * theta, rows[r])
            r += 1
    _rotate_into(z, (steps * substeps) * theta, final)


@njit(cache=True, error_model="numpy", parallel=True)
def rows_batch(X0, b, eta, nu, theta, steps, save_every, substeps, rows, final, info):
    """:func:`rows_single` for every orbit of ``X0`` (B, 3N) on all threads (``eta``, ``nu`` (B, k), ``theta`` (B,),
    ``rows`` (S, B, 3N), ``info`` (B, 2)): every orbit the bits of its single run."""
    for i in prange(X0.shape[0]):
        rows_single(X0[i], b, eta[i], nu[i], theta[i], steps, save_every, substeps, rows[:, i], final[i], info[i])


@njit(cache=True, error_model="numpy")
def rows_serial(X0, b, eta, nu, theta, steps, save_every, substeps, rows, final, info):
    """:func:`rows_batch` on this thread (one orbit, or a few: no thread start-up, and the per-orbit views taken
    here rather than in Python, where each costs a dispatch's type check): every orbit the bits of its single run."""
    for i in range(X0.shape[0]):
        rows_single(X0[i], b, eta[i], nu[i], theta[i], steps, save_every, substeps, rows[:, i], final[i], info[i])


@njit(cache=True, error_model="numpy")
def solve_rows(X0, b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, steps, save_every, substeps,
               eta, nu, out, rows, final, info):
    """The parameter solve (:func:`jetgaudin._exact_kernels.solve_states`) and, where every orbit's solve is
    accepted (``out[i, 0] == 1``), the run (:func:`rows_serial` with ``θ = out[:, 3]``) in one call from Python
    (the every-row call of one orbit: no Python between them); returns whether the run was made.  The same kernels
    as the two calls made one after the other: the same bits."""
    solve_states(X0, b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta, nu, out)
    for i in range(X0.shape[0]):
        if out[i, 0] != 1.0:
            return False
    rows_serial(X0, b, eta, nu, out[:, 3].copy(), steps, save_every, substeps, rows, final, info)
    return True
