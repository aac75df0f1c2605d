r"""Compiled parameter solve of :class:`jetgaudin.ChainExactFlow` (private): Newton's method for the imaginary parts
``h_j`` of the maps and the free multiples ``u_{k:}`` (rotation, identities) in one Numba call
(:func:`newton`), the twin of the NumPy route ``exact_chain._Weights`` / ``ChainExactFlow._newton_numpy`` (the
tests compare the two to round-off).

``ν²`` along a vertical segment ``λ = ρ + i s`` from the integrals: ``ν²(λ) = c + Σ_{i,m} h_{i,m} ψ_m(λ − λ_i)``
(``c`` the family's constant ``nu2_constant(b, extra)``; ``docs/families.md``), with the basis ``ψ_m`` compiled
per family (:mod:`jetgaudin._exact_chain_basis`): rational ``ψ_m(z) = z^{−m}``; trigonometric
``ψ_m = (−1)^{m−1} [x^{m−1}] w_3(z + x)``, ``w_3 = γ cot(γ ·)``, from the Taylor series of ``sin`` and ``cos`` at
``γz`` (series inverse and product, as :meth:`jetgaudin.families.TrigonometricFamily.taylor`); elliptic
``ψ_m = (−1)^{m−1} [x^{m−1}] F(z + x)``, ``F = cs dn + Z`` (:mod:`jetgaudin._exact_elliptic`).  Family ids:
``exact_chain.COMPILED_FAMILIES``.

The weights ``ω_I(ρ_j + i h_j) = −h_j Σ_q w_q Re[∂ν²/∂I(λ_q)/ν(λ_q)]`` by the Gauss–Legendre rule, ``ν`` continued
node by node from ``+√ν²(ρ)`` in the order of ``|s|`` (the root nearer to the previous one; a step that moves ``ν``
by more than a quarter of its size, or ``ν = 0``: a branch point near the segment, the solve fails), the derivative
``∂ω_I/∂h = −Re[∂ν²/∂I(η)/ν(η)]`` at the end point; the extras' column ``∂ν²/∂I`` is the constant ``dconst``.

Newton's ``cond₂(J) ≤ 1e12`` test and its steps are small dense linear algebra done here (:func:`_cond_at_most`:
one-sided Jacobi; :func:`_lu_solve`: partial pivoting; both in :mod:`jetgaudin._small_linalg`), not LAPACK through
Numba (~2 µs an iteration, as much as ten nodes); the elliptic family's whole solve (Newton, the residual test, the
branch check) is one call, :func:`solve_numerical`.

Numba's cache keys this module by its own source: after an edit of :mod:`jetgaudin._exact_chain_basis`,
:mod:`jetgaudin._exact_elliptic`, :mod:`jetgaudin._small_linalg` or :mod:`jetgaudin.gaudin._record`, clear
``jetgaudin/__pycache__/_exact_chain_kernels.*`` (the compiled callers keep the old elliptic code otherwise).
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from numba import njit

from ._exact_chain_basis import _psi_point, _psi_point_inline, _psi_scratch, psi_values
from ._exact_kernels import _csqrt
from ._small_linalg import _cond_at_most, _lu_solve
from .gaudin._record import chain_integrals

__all__ = ["all_finite", "branch_numerical", "branch_uniformized", "newton", "nu_numerical", "psi_values",
           "solve_numerical", "solve_orbit_numerical", "trig_polynomial"]


@njit(cache=True, error_model="numpy")
def _segment(fid, fp, site_pos, site_n, hI, const, dconst, kidx, a, h, xs, perm, f, psi, s, c, r, d, xcache, slot,
             root_a):
    """``f[q, i] = Re[∂ν²/∂I_{kidx[i]}(λ_q)/ν(λ_q)]`` at ``λ_q = a + i h xs[q]``, ``ν`` continued from ``+√ν²(a)``
    along ``perm`` (the nodes by increasing ``xs``); returns ``(ok, ν at the end point xs = 1)`` (``ok`` false: a step
    moved ``ν`` by more than a quarter of its size, or ``ν = 0``; the rest of the segment is then not evaluated: the
    callers discard it).  ``root_a = cmath.sqrt(ν²(a))``, ``ν²(a)`` summed as here (:func:`newton` evaluates it once
    per segment and solve, not once per pass: the same bits)."""
    n2 = hI.shape[0]
    v = root_a
    if v.real < 0:
        v = -v
    nu_last = v
    for t in range(perm.shape[0]):
        q = perm[t]
        lam = complex(a, h * xs[q])
        _psi_point_inline(fid, fp, lam, site_pos, site_n, psi, s, c, r, d, xcache, slot)
        acc = complex(const, 0.0)
        for cI in range(n2):
            acc += hI[cI] * psi[cI]
        qr, qi = _csqrt(acc.real, acc.imag)  # a root in real arithmetic (which one: the continuation's test)
        rq = complex(qr, qi)
        if (rq.real * v.real + rq.imag * v.imag) < 0.0:  # |rq − v| > |rq + v|: the root nearer to v
            rq = -rq
        # |rq − v| ≤ |rq|/4 or |v|/4, in squares (no hypot), and ν ≠ 0
        dr = rq.real - v.real
        di = rq.imag - v.imag
        a2 = rq.real * rq.real + rq.imag * rq.imag
        if not (dr * dr + di * di <= 0.0625 * max(a2, v.real * v.real + v.imag * v.imag) and a2 > 0.0):
            return False, nu_last
        v = rq
        ia2 = 1.0 / a2  # Re(F/ν) = Re(F ν̄)/|ν|²: one real division, no complex one
        for i in range(kidx.shape[0]):
            col = kidx[i]
            F = psi[col] if col < n2 else complex(dconst[col - n2], 0.0)
            f[q, i] = (F.real * rq.real + F.imag * rq.imag) * ia2
        if xs[q] == 1.0:
            nu_last = rq
    return True, nu_last


@njit(cache=True, error_model="numpy")
def _weights(fid, fp, site_pos, site_n, hI, const, dconst, kidx, rho, h, xs, perm, w1, w2, n1, xsf, permf, wf, om,
             dom, om2, nu_end, f, psi, s, c, r, d, xcache, roots_a):
    """For every segment ``j``: ``om[j] = ω`` by the rule ``w1`` (nodes ``xs[:n1]``, end node ``xs[n1] = 1``),
    ``dom[j] = ∂ω/∂h``, and, when ``w2`` is not empty, ``om2[j]`` by the rule ``w2`` (nodes ``xs[n1 + 1:-1]``);
    ``roots_a[j] = cmath.sqrt(ν²(ρ_j))`` (:func:`_segment`);
    ``nu_end[j]`` the continued ``ν`` at ``η_j``.  A segment where ``ν`` cannot be continued over ``xs`` takes the
    rule ``(xsf, permf, wf)`` when that is not empty (nodes ``xsf[:len(wf)]``, end node 1; no ``om2``).  Returns
    ``False`` where ``ν`` cannot be continued."""
    n2r = w2.shape[0]
    for j in range(rho.shape[0]):
        ok, nv = _segment(fid, fp, site_pos, site_n, hI, const, dconst, kidx, rho[j], h[j], xs, perm, f, psi, s,
                          c, r, d, xcache, j, roots_a[j])
        w = w1
        m = n1
        m2 = n2r
        if not ok and wf.shape[0]:  # this segment on the fallback rule (the others keep theirs)
            ok, nv = _segment(fid, fp, site_pos, site_n, hI, const, dconst, kidx, rho[j], h[j], xsf, permf, f, psi,
                              s, c, r, d, xcache, j, roots_a[j])
            w = wf
            m = wf.shape[0]
            m2 = 0
        if not ok:
            return False
        nu_end[j] = nv
        for i in range(kidx.shape[0]):
            acc = 0.0
            for q in range(m):
                acc += w[q] * f[q, i]
            om[j, i] = -h[j] * acc
            dom[j, i] = -f[m, i]
            if m2:
                acc = 0.0
                for q in range(m2):
                    acc += w2[q] * f[n1 + 1 + q, i]
                om2[j, i] = -h[j] * acc
    return True


#: the step (relative to ``|u|``) from which Newton on the fine rule alone continues with the estimate pass (``xs2``)
_FINE_FROM = 1e-9
#: the step (relative to ``|u|``) at which Newton leaves the very coarse rule for the coarse one
_VERY_COARSE_TO = 1e-3
#: the fast path's coarse phase ends at a step of ``_FAST_COARSE_TO |u|`` (the next error ``~ C·1e-16 |u|``: one pass of
#: the fine rule then converges) and its quadrature estimate must be at most ``_FAST_QUAD_TOL`` (``exact_chain``'s
#: ``_QUAD_TOL``), else the orbit takes the path of the rules alone
_FAST_COARSE_TO, _FAST_QUAD_TOL = 1e-8, 1e-13


@njit(cache=True, error_model="numpy")
def _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs, perm, w, w2, xsf, permf,
             wf, step_tol, iterations, u, om, dom, om2, nu_end, f, psi, s, c, r, d, xcache, J, res, JS, du, roots_a):
    """Newton's steps on the rule ``(xs, perm, w)`` from ``u`` until every ``|Δu| ≤ step_tol |u|``; returns 0
    (converged: ``om``, ``dom``, ``nu_end`` and, with a half rule ``w2`` (nodes ``xs[len(w) + 1:]``), ``om2`` are
    those of the last point evaluated, ``u`` + the last step), 1 (no solution: diverged, left the bound, ill
    conditioned, ``ν`` not continued).  A segment where ``ν`` cannot be continued over the nodes ``xs`` is evaluated
    on the rule ``(xsf, permf, wf)`` when that is not empty (a coarse rule's nodes can be too few for the
    quarter-size rule where the fine rule's are not; the other segments keep the coarse rule).  (A damped step,
    halving towards the previous iterate where the coarse continuation fails, saved one evaluation of the fine rule
    but made steps feasible that are not on the undamped iteration: the Clebsch top's ``dt_max`` 1.07 → 1.79, so
    the undamped path is kept.)"""
    k = rho.shape[0]
    nk = kidx.shape[0]
    ne = E.shape[1]
    for _ in range(iterations):
        for j in range(k):
            if not (abs(u[j]) <= bound[j]):
                return 1
        if not np.all(np.isfinite(u)):
            return 1
        if not _weights(fid, fp, site_pos, site_n, hI, const, dconst, kidx, rho, u[:k], xs, perm, w, w2, w.shape[0],
                        xsf, permf, wf, om, dom, om2, nu_end, f, psi, s, c, r, d, xcache, roots_a):
            return 1
        for i in range(nk):
            acc = -target[i]
            for j in range(k):
                acc += om[j, i]
                J[i, j] = dom[j, i]
            for e in range(ne):
                acc -= E[i, e] * u[k + e]
                J[i, k + e] = -E[i, e]
            res[i] = acc
        if not (np.all(np.isfinite(J)) and np.all(np.isfinite(om)) and _cond_at_most(J, 1e12, JS)):
            return 1
        _lu_solve(J, res, JS, du)
        done = True
        for i in range(k + ne):
            u[i] -= du[i]
            if not abs(du[i]) <= step_tol * abs(u[i]):
                done = False
        for j in range(k):
            if not (abs(u[j]) <= bound[j]):
                return 1
        if not np.all(np.isfinite(u)):
            return 1
        if done:
            return 0
    return 1


@njit(cache=True, error_model="numpy")
def newton(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1, perm1, w1, xs2, perm2,
           w2, xsc, permc, wc, xsv, permv, wv, step_tol, coarse_tol, iterations, u, om, nu_end):
    """Newton's method of ``ChainExactFlow._newton_numpy`` compiled: ``u = (h_1..h_k, extra unknowns)`` with
    ``Σ_j ω(ρ_j + i h_j) − E u_{k:} = target`` on the matched integrals ``kidx``.  The start from the linearisation
    at ``h = 0`` (``∂ω/∂h = −Re[∂ν²/∂I(ρ)/ν(ρ)]``), then steps with the exact Jacobian while ``|h_j| ≤ bound_j``,
    the Jacobian finite with condition number at most 1e12.  The solution is the fine rule's (``w1``): the coarser
    rules only find the start of its iterations, so the result is that of Newton on the fine rule alone to round-off.

    * **The fast path** (with both ``wv`` and ``wc``): steps on the very coarse rule ``(xsv, permv, wv)`` to
      ``|Δu| ≤ _VERY_COARSE_TO |u|``, on the coarse rule ``(xsc, permc, wc)`` to ``_FAST_COARSE_TO |u|`` (a segment
      whose nodes are too few to continue ``ν`` takes the rule ``w1`` in that pass), then on the rule ``w1`` until
      every ``|Δu| ≤ step_tol |u|`` (one pass where the coarse rule has converged, else two); the estimate is
      ``|Q_w1 − Q_wc|``, the coarse rule's weights carried from its last point ``h_c`` to the fine rule's ``h_f`` to
      first order (``ω_c + ∂ω/∂h (h_f − h_c)``, an error ``~|ω''| |h_f − h_c|² ≲ 1e-16 |u|²|ω''|``): accepted at
      most ``_FAST_QUAD_TOL``.  Any failure (and an estimate above it) leaves it for the path below, from the same
      start, whose result is then the same bits: the orbits solved are those the path below solves, and a few more
      (none among the 22 states of ``benchmarks/exact_chain_roundoff.py`` at 60 step sizes each; on a chain with two
      close sites, 5 steps inside the feasible range where the path below fails; ``tests/test_exact_chain_fast_solve``).
    * **The path of the rules alone**: on the coarse rule to ``|Δu| ≤ coarse_tol |u|`` (a step whose nodes are too
      few to continue ``ν`` takes the rule ``w1``), else (the coarse phase fails, or ``wc`` is empty) from the
      linear start on the rule ``w1`` to ``|Δu| ≤ _FINE_FROM |u|``; then steps on the rule ``w1`` with the half rule
      ``w2`` in the same pass (nodes ``xs2``, their continuation order ``perm2``) until every
      ``|Δu| ≤ step_tol |u|``; the estimate ``|Q_w1 − Q_w2|``.

    Returns ``(status, quadrature estimate, fast)``: status 0 converged (``u``; ``om`` (k, n_keep) by the rule ``w1``
    and ``nu_end`` (k,) at the last point evaluated, ``u`` + the last step: the residual there is ``O(|Δu|)``, and
    ``ν`` there only chooses the maps' root), 1 no solution; ``fast`` 1 where the fast path gave the solution."""
    k = rho.shape[0]
    nk = kidx.shape[0]
    ne = E.shape[1]
    n2 = hI.shape[0]
    psi = np.empty(n2, dtype=np.complex128)
    s, c, r, d, xcache = _psi_scratch(site_pos, site_n, k)  # one cache slot per segment
    f = np.empty((xs2.shape[0], nk))
    dom = np.empty((k, nk))
    om2 = np.empty((k, nk))
    J = np.empty((nk, k + ne))
    res = np.empty(nk)
    # the start: the linearisation at h = 0 (and √ν²(ρ_j), where every pass's continuation starts)
    roots_a = np.empty(k, dtype=np.complex128)
    for j in range(k):
        _psi_point(fid, fp, complex(rho[j], 0.0), site_pos, site_n, psi, s, c, r, d, xcache, j)
        acc = complex(const, 0.0)
        for cI in range(n2):
            acc += hI[cI] * psi[cI]
        roots_a[j] = cmath.sqrt(acc)
        nus = roots_a[j].real
        for i in range(nk):
            col = kidx[i]
            F = psi[col] if col < n2 else complex(dconst[col - n2], 0.0)
            J[i, j] = -(F / nus).real
    for i in range(nk):
        for e in range(ne):
            J[i, k + e] = -E[i, e]
    JS = np.empty_like(J)
    du = np.empty(k + ne)
    if not (np.all(np.isfinite(J)) and _cond_at_most(J, 1e12, JS)):
        return 1, 0.0, 0
    _lu_solve(J, target, JS, u)
    u0 = u.copy()
    none = w1[:0]
    status = 1
    if wv.shape[0] and wc.shape[0]:
        # the fast path: the very coarse rule while the steps are large, the coarse rule to a step of 1e-8 |u|, one
        # or two passes of the fine rule (a segment whose nodes are too few to continue ν takes the fine rule, as the
        # coarse phase of the path below does)
        status = _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xsv, permv, wv,
                          none, xs1, perm1, w1, _VERY_COARSE_TO, iterations, u, om, dom, om2, nu_end, f, psi,
                          s, c, r, d, xcache, J, res, JS, du, roots_a)
        if not status:
            status = _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xsc, permc,
                              wc, none, xs1, perm1, w1, _FAST_COARSE_TO, iterations, u, om, dom, om2, nu_end, f,
                              psi, s, c, r, d, xcache, J, res, JS, du, roots_a)
        if not status:  # the coarse rule's ω and ∂ω/∂h at its last point h_c (u + the last step)
            omc = om.copy()
            domc = dom.copy()
            hc = u[:k] + du[:k]
            status = _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1, perm1,
                              w1, none, none, perm1[:0], none, step_tol, iterations, u, om, dom, om2, nu_end, f, psi,
                              s, c, r, d, xcache, J, res, JS, du, roots_a)
            if not status:  # the estimate: the coarse rule carried to the fine rule's last point h_f to first order
                for j in range(k):
                    dh = (u[j] + du[j]) - hc[j]
                    for i in range(nk):
                        om2[j, i] = omc[j, i] + domc[j, i] * dh
                if _estimate(om, om2) > _FAST_QUAD_TOL:
                    status = 1
    if status:  # else the path of the rules alone, from the linear start: every orbit it solves is solved
        u[:] = u0
        if wc.shape[0]:
            status = _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xsc, permc,
                              wc, none, xs1, perm1, w1, coarse_tol, iterations, u, om, dom, om2, nu_end, f, psi, s, c,
                              r, d, xcache, J, res, JS, du, roots_a)
        if status:  # the coarse phase failed (or none): from the linear start on the fine rule
            u[:] = u0
            status = _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1, perm1,
                              w1, none, none, perm1[:0], none, _FINE_FROM, iterations, u, om, dom, om2, nu_end, f,
                              psi, s, c, r, d, xcache, J, res, JS, du, roots_a)
        if status:
            return 1, 0.0, 0
        # the last steps on the fine rule with the half rule's estimate in the same pass (xs2): om, om2, nu_end at
        # the last point evaluated, u = that point + the last step (|Δu| ≤ step_tol |u|)
        if _iterate(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs2, perm2, w1, w2,
                    none, perm1[:0], none, step_tol, iterations, u, om, dom, om2, nu_end, f, psi, s, c, r, d, xcache,
                    J, res, JS, du, roots_a):
            return 1, 0.0, 0
        return 0, _estimate(om, om2), 0
    return 0, _estimate(om, om2), 1


@njit(cache=True, error_model="numpy")
def _estimate(om, om2):
    """The quadrature estimate ``max_{j,i} |om − om2| / max_i Σ_j |om_{j,i}|``."""
    quad = 0.0
    scale = 0.0
    for i in range(om.shape[1]):
        tot = 0.0
        for j in range(om.shape[0]):
            quad = max(quad, abs(om[j, i] - om2[j, i]))
            tot += abs(om[j, i])
        scale = max(scale, tot)
    return quad / (scale + 1e-300)


@njit(cache=True, error_model="numpy")
def solve_numerical(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1, perm1, w1, xs2,
                    perm2, w2, xsc, permc, wc, xsv, permv, wv, step_tol, coarse_tol, iterations, u, om, nu_end,
                    quad_tol, res_tol, period, n0, n_max, branch_tol):
    """The whole solve of a family without a uniformizer (elliptic) in one call: :func:`newton`, then the acceptance
    of ``ChainExactFlow._newton`` — the residual ``max_i |Σ_j ω_{j,i} − (E u_{k:})_i − target_i| / scale_i ≤ res_tol``
    (``scale_i = Σ_j |ω_{j,i}| + |target_i| + |(E u_{k:})_i|``, NumPy's sums in the same order) and the branch check
    :func:`branch_numerical` at ``η_j = ρ_j + i u_j`` to ``branch_tol``.  Returns ``(status, quadrature estimate)``:
    0 accepted, 1 no accepted solution, 2 the estimate is above ``quad_tol`` (``u``, ``om``, ``nu_end`` of
    :func:`newton`; the caller takes the adaptive quadrature and checks the rest itself)."""
    status, quad, _ = newton(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1, perm1,
                             w1, xs2, perm2, w2, xsc, permc, wc, xsv, permv, wv, step_tol, coarse_tol, iterations, u,
                             om, nu_end)
    if status:
        return 1, quad
    if quad > quad_tol:
        return 2, quad
    k = rho.shape[0]
    nk = kidx.shape[0]
    ne = E.shape[1]
    worst = 0.0
    nan = False
    for i in range(nk):
        Eu = 0.0
        for e in range(ne):
            Eu += E[i, e] * u[k + e]
        tot = 0.0
        sabs = 0.0
        for j in range(k):
            tot += om[j, i]
            sabs += abs(om[j, i])
        ri = abs(tot - Eu - target[i]) / (sabs + abs(target[i]) + abs(Eu))
        if ri != ri:
            nan = True
        elif ri > worst:
            worst = ri
    if not nan and worst > res_tol:  # NumPy's test: max(...) > res_tol, False when a ratio is NaN
        return 1, quad
    eta = np.empty(k, dtype=np.complex128)
    for j in range(k):
        eta[j] = complex(rho[j], u[j])
    if not branch_numerical(fid, fp, site_pos, site_n, hI, const, period, eta, nu_end, n0, n_max, branch_tol):
        return 1, quad
    return 0, quad


@njit(cache=True, error_model="numpy")
def solve_orbit_numerical(x, q3, lin, b, forms, fid, fp, site_pos, site_n, dconst, kidx, E, target, rho, bound, xs1,
                          perm1, w1, xs2, perm2, w2, xsc, permc, wc, xsv, permv, wv, step_tol, coarse_tol, iterations,
                          u, om, nu_end,
                          quad_tol, res_tol, period, n0, n_max, branch_tol, im_limit, eta):
    """One orbit's whole solve for the elliptic family in one call (``ChainExactFlow``'s fast path: the Python around
    the compiled calls was ~1/4 of a Clebsch top's every-row call): ``x`` checked finite; its integrals by
    :func:`jetgaudin.gaudin._record.chain_integrals` with the forms ``q3, lin, b, forms`` of
    ``_exact_chain_prep._integrals_row`` (the function that one calls: the same bits), ``h_I`` their first ``2M``
    entries and ``ν²``'s constant ``c_0`` the next one (``EllipticFamily.nu2_constant``: the extra integral itself);
    then :func:`solve_numerical`; on acceptance the checks of ``η_j = ρ_j + i u_j`` that depend on ``u`` —
    ``|Im η_j| < im_limit`` (``EllipticFamily.check_xi``, which the maps' constructor makes) and every map used
    (``|Im η_j| > 1e-13 max(|ρ_j|, 1)``, ``ChainExactFlow._orbit``'s rule) — and ``eta`` written.  Returns 0
    (accepted, every check passed) or 1 (anything else: the caller takes the general path, which raises the right
    error or takes the adaptive quadrature); the real parts' checks (off the sites) are the caller's, once per
    flow."""
    n = x.shape[0]
    for i in range(n):
        if not np.isfinite(x[i]):
            return 1
    nI = q3.shape[1] + forms.shape[0]
    out = np.empty((1, nI))
    chain_integrals(x.reshape(1, n), q3, lin, b, forms, out)
    n2 = 0
    for i in range(site_n.shape[0]):
        n2 += 2 * site_n[i]
    for i in range(nI):
        if not np.isfinite(out[0, i]):
            return 1
    hI = np.empty(n2)
    for i in range(n2):
        hI[i] = out[0, i]
    const = out[0, n2]
    status, _ = solve_numerical(fid, fp, site_pos, site_n, hI, const, dconst, kidx, E, target, rho, bound, xs1,
                                perm1, w1, xs2, perm2, w2, xsc, permc, wc, xsv, permv, wv, step_tol, coarse_tol,
                                iterations, u, om,
                                nu_end, quad_tol, res_tol, period, n0, n_max, branch_tol)
    if status:
        return 1
    for j in range(rho.shape[0]):
        h = u[j]
        if not (abs(h) < im_limit and abs(h) > 1e-13 * max(abs(rho[j]), 1.0)):
            return 1
        eta[j] = complex(rho[j], h)
    return 0


@njit(cache=True)
def all_finite(rows, final):
    """Whether every entry of ``rows`` (R, n) and ``final`` (n,) is finite (``np.isfinite(...).all()`` of both
    without two NumPy calls: ~0.5 µs against ~3.4 µs after a Clebsch top's every-row call)."""
    for r in range(rows.shape[0]):
        for i in range(rows.shape[1]):
            if not math.isfinite(rows[r, i]):
                return False
    for i in range(final.shape[0]):
        if not math.isfinite(final[i]):
            return False
    return True


@njit(cache=True, error_model="numpy")
def nu_numerical(fid, fp, site_pos, site_n, hI, const, period, eta, n0, n_max):
    """The branch rule of ``gaudin._curve._nu_numerical`` (families without a uniformizer) compiled, with ``ν²`` from
    the expansion: ``±√ν²`` at ``n + 1`` equally spaced points of ``[Re η, η]``, each time the root nearer to the
    previous one, ``n`` doubling from ``n0`` to ``n_max`` until no step moves ``ν`` by more than a quarter of its size.
    Returns ``(ok, ν(η))`` (``ok`` false: no such ``n``, or ``Re η`` a site modulo ``period``)."""
    a = eta.real
    for i in range(site_pos.shape[0]):
        r = (a - site_pos[i]) / period
        if abs(r - np.rint(r)) < 1e-14:
            return False, 0j
    n2 = hI.shape[0]
    psi = np.empty(n2, dtype=np.complex128)
    s, c, r, d, xcache = _psi_scratch(site_pos, site_n, 1)
    n = n0
    while n <= n_max:
        ok = True
        v = 0j
        for q in range(n + 1):
            lam = complex(a, eta.imag * (q / n))
            _psi_point_inline(fid, fp, lam, site_pos, site_n, psi, s, c, r, d, xcache, 0)
            acc = complex(const, 0.0)
            for cI in range(n2):
                acc += hI[cI] * psi[cI]
            if q == 0:
                rq = cmath.sqrt(acc)  # the start: the principal root (the rule's ν(Re η))
            else:  # a root in real arithmetic (which one: the continuation's test)
                qr, qi = _csqrt(acc.real, acc.imag)
                rq = complex(qr, qi)
            if q > 0:
                if (rq.real * v.real + rq.imag * v.imag) < 0.0:  # |rq − v| > |rq + v|
                    rq = -rq
                dr = rq.real - v.real
                di = rq.imag - v.imag
                # |rq − v| ≤ max(|rq|, |v|)/4, in squares (no hypot)
                if not dr * dr + di * di <= 0.0625 * max(rq.real * rq.real + rq.imag * rq.imag,
                                                         v.real * v.real + v.imag * v.imag):
                    ok = False
                    break
            v = rq
        if ok and v != 0:
            return True, v
        n *= 2
    return False, 0j


@njit(cache=True, error_model="numpy")
def branch_numerical(fid, fp, site_pos, site_n, hI, const, period, eta, nu_end, n0, n_max, tol):
    """Whether every ``nu_end[j]`` is :func:`nu_numerical`'s ``ν(η_j)`` to ``tol`` relative (the solve's branch
    check, every segment in one call)."""
    for j in range(eta.shape[0]):
        ok, ref = nu_numerical(fid, fp, site_pos, site_n, hI, const, period, eta[j], n0, n_max)
        if not (ok and abs(ref - nu_end[j]) <= tol * abs(ref)):
            return False
    return True


@njit(cache=True, error_model="numpy")
def branch_uniformized(fid, fp, site_pos, site_n, hI, const, period, eta, nu_end, roots, tol):
    """Whether every ``nu_end[j]`` is the uniformized branch rule's ``ν(η_j)`` to ``tol`` relative: the compiled
    twin of ``gaudin._curve._nu_uniformized`` for the trigonometric family (``z = e^{2iγλ}``, ``roots`` the orbit's
    branch points in ``z``): ``ν(η) = ±√ν²(η)``, the sign of ``ν(a) Π_j [(z_a − z_j)/(z − z_j)]^{N_j}
    Π_k √((z − r_k)/(z_a − r_k))`` (``a = Re η``; ``ν(a) = +√ν²(a)``), ``ν²`` from the expansion.  False where the
    rule refuses (``Re η`` a site modulo the period, a root on the segment, ``ν`` zero or not finite)."""
    n2 = hI.shape[0]
    psi = np.empty(n2, dtype=np.complex128)
    s, c, r, d, xcache = _psi_scratch(site_pos, site_n, 1)
    g2 = 2.0 * fp[0]
    for j in range(eta.shape[0]):
        e = eta[j]
        a = e.real
        for i in range(site_pos.shape[0]):
            q = (a - site_pos[i]) / period
            if abs(q - np.round(q)) < 1e-14:
                return False
        _psi_point(fid, fp, e, site_pos, site_n, psi, s, c, r, d, xcache, 0)
        acc = complex(const, 0.0)
        for cI in range(n2):
            acc += hI[cI] * psi[cI]
        direct = cmath.sqrt(acc)
        _psi_point(fid, fp, complex(a, 0.0), site_pos, site_n, psi, s, c, r, d, xcache, 0)
        acc = complex(const, 0.0)
        for cI in range(n2):
            acc += hI[cI] * psi[cI]
        ref = cmath.sqrt(acc)
        z = cmath.exp(1j * g2 * e)
        za = cmath.exp(1j * g2 * complex(a, 0.0))
        for i in range(site_pos.shape[0]):
            zj = cmath.exp(1j * g2 * complex(site_pos[i], 0.0))
            ref = ref * ((za - zj) / (z - zj)) ** site_n[i]
        for kk in range(roots.shape[0]):
            ratio = (z - roots[kk]) / (za - roots[kk])
            if abs(ratio.imag) <= 1e-13 * abs(ratio) and ratio.real <= 0:
                return False
            ref = ref * cmath.sqrt(ratio)
        test = ((direct / abs(direct)).conjugate() * (ref / abs(ref))).real
        if not np.isfinite(test):
            return False
        nu = direct if test >= 0 else -direct
        if not abs(nu - nu_end[j]) <= tol * abs(nu):
            return False
    return True


@njit(cache=True, error_model="numpy")
def trig_polynomial(fp, site_pos, site_n, hI, const, out):
    """``gaudin._curve._uniform_polynomial`` for the trigonometric family with ``ν²`` from the expansion: the
    coefficients ``out[n]``, ``n = 0..2M`` (ascending), of ``Q(z) = ν²(λ(z)) Π_j (z − z_j)^{2N_j}``
    (``z = e^{2iγλ}``, ``z_j = e^{2iγλ_j}``), by the discrete Fourier transform of its ``2M + 1`` values at
    ``λ_q = qT/(2M + 1) + 0.15i/γ`` (``T = π/γ``: the circle ``|z| = e^{−0.3}``, off the sites' unit circle)."""
    n2 = hI.shape[0]
    D = n2 + 1
    psi = np.empty(n2, dtype=np.complex128)
    s, c, rr, d, xcache = _psi_scratch(site_pos, site_n, 1)
    gamma = fp[0]
    T = math.pi / gamma
    vals = np.empty(D, dtype=np.complex128)
    for q in range(D):
        lam = complex(q * T / D, 0.15 / gamma)
        z = cmath.exp(2j * gamma * lam)
        _psi_point(1, fp, lam, site_pos, site_n, psi, s, c, rr, d, xcache, 0)
        acc = complex(const, 0.0)
        for cI in range(n2):
            acc += hI[cI] * psi[cI]
        for i in range(site_pos.shape[0]):
            acc *= (z - cmath.exp(2j * gamma * complex(site_pos[i], 0.0))) ** (2 * site_n[i])
        vals[q] = acc
    r = math.exp(-0.3)
    for n in range(D):
        acc = 0j
        for q in range(D):
            acc += vals[q] * cmath.exp(-2j * math.pi * ((q * n) % D) / D)
        out[n] = acc / D / r ** n
