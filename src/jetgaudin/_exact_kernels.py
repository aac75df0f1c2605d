r"""Compiled parameter solve of :mod:`jetgaudin.exact` (private): from an orbit's state to its accepted parameters in
one call (:func:`_solve_state`: the integrals, the branch points' largest modulus, the weights ``ω_m(ρ + i h)`` by
Gauss–Legendre, Newton's method for ``h``, the branch check); a ``prange`` loop over a batch (every orbit gets the
bits of its single solve).

``ν`` along the vertical segment ``λ = ρ + i s``, ``s ∈ [0, h]``: the root of ``ν² = Σ_m κ_m λ^{-m}`` positive at
``s = 0`` (``ν(ρ)² = |ξ(ρ)|² > 0`` for a real state), continued node by node (the root closer to the previous
node's value; the nodes are sorted along the segment).  This is the default branch of :func:`jetgaudin.nu` as long
as no branch point lies near the segment; :func:`_branch_ok` checks the end value against the branch rule.
The NumPy twin is :func:`jetgaudin.exact._weights` (the tests compare the two).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy")
def _node(kappa, a, s, prr, pri):
    """At ``λ = a + i s``: ``z = 1/λ = λ̄/|λ|²`` (one real division, shared by ``ν² = Σ κ_m z^m`` and the powers
    ``z^m``), ``ν`` the root of ``ν²`` nearer the previous node's ``(prr, pri)`` and ``1/ν = ν̄/|ν|²``; returns
    ``(zr, zi, νr, νi, (1/ν)r, (1/ν)i)``.  The same quantities as ``1/lam``, ``cmath.sqrt`` and ``1/r`` to
    round-off (Numba's complex division scales and branches; this is the parameter solve's inner loop)."""
    M = kappa.shape[0] - 1
    d = 1.0 / (a * a + s * s)
    zr = a * d
    zi = -s * d
    pr = kappa[M]
    pi = 0.0
    for m in range(M - 1, -1, -1):  # Horner: ν² = Σ κ_m z^m
        t = pr * zr - pi * zi + kappa[m]
        pi = pr * zi + pi * zr
        pr = t
    rr, ri = _csqrt(pr, pi)
    if (rr * prr + ri * pri) < 0.0:
        rr = -rr
        ri = -ri
    e = 1.0 / (rr * rr + ri * ri)
    return zr, zi, rr, ri, rr * e, -ri * e


@njit(cache=True, error_model="numpy")
def _weights_one(kappa, a, h, x, w, om, dom, nu_end):
    """``om[m] = ω_{m+1}(a + i h)`` (``m = 0..2N−1``) by the rule ``(x, w)`` on ``[0, 1]``; ``dom[m] = ∂ω/∂h``;
    returns ``ν`` at the end point (continued from ``+√ν²(a)``), node by node (:func:`_node`); only the real part
    of ``z^m/ν`` is formed."""
    M = kappa.shape[0] - 1
    for m in range(M):
        om[m] = 0.0
    prr = np.sqrt(max(_nu2(kappa, complex(a, 0.0)).real, 0.0))
    pri = 0.0
    n = x.shape[0]
    for q in range(n + 1):
        s = h * x[q] if q < n else h
        zr, zi, prr, pri, ir, ii = _node(kappa, a, s, prr, pri)
        wr = zr
        wi = zi
        if q < n:
            hw = h * w[q]
            for m in range(M):
                om[m] -= hw * (wr * ir - wi * ii)
                t = wr * zr - wi * zi
                wi = wr * zi + wi * zr
                wr = t
        else:
            for m in range(M):
                dom[m] = -(wr * ir - wi * ii)
                t = wr * zr - wi * zi
                wi = wr * zi + wi * zr
                wr = t
    nu_end[0] = complex(prr, pri)


@njit(cache=True, error_model="numpy")
def _weights_two(kappa, a0, h0, a1, h1, x, w, om0, dom0, om1, dom1, NU):
    """:func:`_weights_one` of two segments in one loop over the nodes (two independent dependency chains the
    processor overlaps; the exact flow of N = 3 has two maps): the same operations per segment, so the same bits."""
    M = kappa.shape[0] - 1
    for m in range(M):
        om0[m] = 0.0
        om1[m] = 0.0
    p0r = np.sqrt(max(_nu2(kappa, complex(a0, 0.0)).real, 0.0))
    p1r = np.sqrt(max(_nu2(kappa, complex(a1, 0.0)).real, 0.0))
    p0i = 0.0
    p1i = 0.0
    n = x.shape[0]
    for q in range(n + 1):
        s0 = h0 * x[q] if q < n else h0
        s1 = h1 * x[q] if q < n else h1
        z0r, z0i, p0r, p0i, i0r, i0i = _node(kappa, a0, s0, p0r, p0i)
        z1r, z1i, p1r, p1i, i1r, i1i = _node(kappa, a1, s1, p1r, p1i)
        u0r = z0r
        u0i = z0i
        u1r = z1r
        u1i = z1i
        if q < n:
            hw0 = h0 * w[q]
            hw1 = h1 * w[q]
            for m in range(M):
                om0[m] -= hw0 * (u0r * i0r - u0i * i0i)
                om1[m] -= hw1 * (u1r * i1r - u1i * i1i)
                t0 = u0r * z0r - u0i * z0i
                u0i = u0r * z0i + u0i * z0r
                u0r = t0
                t1 = u1r * z1r - u1i * z1i
                u1i = u1r * z1i + u1i * z1r
                u1r = t1
        else:
            for m in range(M):
                dom0[m] = -(u0r * i0r - u0i * i0i)
                dom1[m] = -(u1r * i1r - u1i * i1i)
                t0 = u0r * z0r - u0i * z0i
                u0i = u0r * z0i + u0i * z0r
                u0r = t0
                t1 = u1r * z1r - u1i * z1i
                u1i = u1r * z1i + u1i * z1r
                u1r = t1
    NU[0] = complex(p0r, p0i)
    NU[1] = complex(p1r, p1i)


@njit(cache=True, error_model="numpy")
def _csqrt(pr, pi):
    """The principal square root of ``pr + i pi`` in real arithmetic (``t = √((|p| + |pr|)/2)``, the other part
    ``pi/(2t)``: no cancellation), as ``cmath.sqrt`` to round-off; ``|p| = √(pr² + pi²)``, by ``hypot`` only where
    the squares leave ``[1e-300, 1e300]``."""
    a2 = pr * pr + pi * pi
    mod = np.sqrt(a2) if 1e-300 < a2 < 1e300 else np.hypot(pr, pi)  # hypot (slow) only where a2 over/underflows
    t = np.sqrt(0.5 * (mod + abs(pr)))
    if t == 0.0:
        return 0.0, 0.0
    if pr >= 0.0:
        return t, 0.5 * pi / t
    return 0.5 * abs(pi) / t, (t if pi >= 0.0 else -t)


@njit(cache=True, error_model="numpy")
def _nu2(kappa, lam):
    z = 1.0 / lam
    acc = complex(kappa[kappa.shape[0] - 1], 0.0)
    for m in range(kappa.shape[0] - 2, -1, -1):
        acc = acc * z + kappa[m]
    return acc


@njit(cache=True, error_model="numpy")
def _gauss_solve(A, b):
    """``A y = b`` (small, partial pivoting) in place; returns ``False`` when singular."""
    k = b.shape[0]
    for c in range(k):
        p = c
        for r in range(c + 1, k):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if A[p, c] == 0.0 or not np.isfinite(A[p, c]):
            return False
        for j in range(k):
            A[c, j], A[p, j] = A[p, j], A[c, j]
        b[c], b[p] = b[p], b[c]
        for r in range(c + 1, k):
            f = A[r, c] / A[c, c]
            for j in range(c, k):
                A[r, j] -= f * A[c, j]
            b[r] -= f * b[c]
    for c in range(k - 1, -1, -1):
        acc = b[c]
        for j in range(c + 1, k):
            acc -= A[c, j] * b[j]
        b[c] = acc / A[c, c]
    return True


@njit(cache=True, error_model="numpy")
def _eval(kappa, rho, h, x, w, OM, DOM, NU):
    if rho.shape[0] == 2:
        _weights_two(kappa, rho[0], h[0], rho[1], h[1], x, w, OM[0], DOM[0], OM[1], DOM[1], NU)
        return
    for j in range(rho.shape[0]):
        _weights_one(kappa, rho[j], h[j], x, w, OM[j], DOM[j], NU[j:j + 1])


@njit(cache=True, error_model="numpy")
def _newton(kappa, rho, target, h, x, w, OM, DOM, NU, step_tol, fold, iterations, F, h_last):
    """Newton's method for ``Σ_j ω_m(ρ_j + i h_j) = target`` with the rule ``(x, w)``; stops when every step
    ``|Δh_j| ≤ step_tol |h_j|``.  On return ``h_last`` is the last point evaluated (``OM``, ``DOM``, ``NU`` there)
    and ``F`` the last step: ``h = h_last − F``."""
    k = rho.shape[0]
    A = np.empty((k, k))
    for _ in range(iterations):
        _eval(kappa, rho, h, x, w, OM, DOM, NU)
        for mi in range(k):
            acc = -target[mi]
            for j in range(k):
                acc += OM[j, mi + 1]
                A[mi, j] = DOM[j, mi + 1]
            F[mi] = acc
        if not _gauss_solve(A, F):
            return False
        done = True
        for j in range(k):
            hn = h[j] - F[j]
            if not np.isfinite(hn) or abs(hn) > fold * abs(rho[j]):
                return False
            if abs(F[j]) > step_tol * abs(hn):
                done = False
            h_last[j] = h[j]
            h[j] = hn
        if done:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _solve_one(kappa, rho, target, x, w, x2, w2, xc, wc, stages, step_tol, fold, iterations, h, nu_end, info):
    """Solve ``Σ_j ω_m(ρ_j + i h_j) = target_{m−2}`` (``m = 2..k+1``) into ``h``; ``info = (ok, residual,
    quadrature estimate, Σ_j ω_1)``, ``nu_end`` the end-point ``ν`` of each segment.

    Newton's method runs on the coarse rule ``(xc, wc)`` to a step of ``1e-9 |h|``, then on the ``x`` rule to
    ``step_tol`` (quadratic convergence: one or two iterations; from the linear start alone if the coarse phase
    fails).  The residual, the quadrature estimate ``|Q_x − Q_x2|`` and ``ν`` are taken at the last point Newton
    evaluated, ``h_last = h + Δ`` (``|Δ_j| ≤ step_tol |h_j|``), and ``Σ_j ω_1`` is carried to ``h`` by its derivative
    (an error ``O(Δ²)``, below round-off): no extra evaluation of the fine rule."""
    k = rho.shape[0]
    M = kappa.shape[0] - 1
    OM = np.zeros((k, M))
    DOM = np.zeros((k, M))
    OM2 = np.zeros((k, M))
    DOM2 = np.zeros((k, M))
    V = np.empty((k, k))
    F = np.zeros(k)
    h_last = np.zeros(k)
    h0 = np.empty(k)
    ok = False
    for S in stages:
        for s in range(1, S + 1):
            tg = target * (s / S)
            if s == 1:
                for mi in range(k):
                    h[mi] = tg[mi]
                    for j in range(k):
                        nr = np.sqrt(max(_nu2(kappa, complex(rho[j], 0.0)).real, 1e-300))
                        V[mi, j] = -(rho[j] ** -(mi + 2)) / nr
                if not _gauss_solve(V, h):
                    break
            h0[:] = h
            ok = _newton(kappa, rho, tg, h, xc, wc, OM, DOM, nu_end, 1e-9, fold, iterations, F, h_last)
            ok = ok and _newton(kappa, rho, tg, h, x, w, OM, DOM, nu_end, step_tol, fold, iterations, F, h_last)
            if not ok:  # the coarse rule can fail where the fine one converges: from the same start, fine only
                h[:] = h0
                ok = _newton(kappa, rho, tg, h, x, w, OM, DOM, nu_end, step_tol, fold, iterations, F, h_last)
            if not ok:
                break
        if ok:
            break
    if not ok:  # the values at the last h (for the caller's message only)
        h_last[:] = h
        F[:] = 0.0
        _eval(kappa, rho, h_last, x, w, OM, DOM, nu_end)
    _eval(kappa, rho, h_last, x2, w2, OM2, DOM2, nu_end[k:])
    res = 0.0
    quad = 0.0
    for mi in range(k):
        tot = -target[mi]
        scale = abs(target[mi]) + 1e-300
        for j in range(k):
            tot += OM[j, mi + 1]
            scale += abs(OM[j, mi + 1])
        res = max(res, abs(tot) / scale)
    om1 = 0.0
    for j in range(k):
        om1 += OM[j, 0] - DOM[j, 0] * F[j]
        for m in range(min(M, k + 1)):
            quad = max(quad, abs(OM[j, m] - OM2[j, m]) / (abs(OM[j, m]) + abs(OM[j, 0]) + 1e-300))
    info[0] = 1.0 if ok else 0.0
    info[1] = res
    info[2] = quad
    info[3] = om1


@njit(cache=True, error_model="numpy")
def _kappa(x, b, kappa):
    """``κ_0..κ_{2N}`` of ``ν² = Σ κ_m λ^{-m}`` from the state ``x`` (3N,) in the field ``b e_3``:
    ``κ_{i+j} += ⟨ξ_i, ξ_j⟩`` with ``ξ_0 = b e_3``, ``ξ_{n+1} = y_n`` (reduction (lax2)), summed in the order of
    :func:`jetgaudin.spectral.curve_coefficients` (the same bits)."""
    _kappa_into(x, b, kappa, np.empty((x.shape[0] // 3 + 1, 3)))


@njit(cache=True, error_model="numpy")
def _kappa_into(x, b, kappa, xi):
    """:func:`_kappa` with the scratch ``xi`` ``(N + 1, 3)`` given (no allocation per row)."""
    N = x.shape[0] // 3
    xi[0, 0] = 0.0
    xi[0, 1] = 0.0
    xi[0, 2] = b
    for n in range(N):
        for a in range(3):
            xi[n + 1, a] = x[3 * n + a]
    for m in range(2 * N + 1):
        kappa[m] = 0.0
    for i in range(N + 1):
        for j in range(N + 1):
            kappa[i + j] += (xi[i, 0] * xi[j, 0] + xi[i, 1] * xi[j, 1]) + xi[i, 2] * xi[j, 2]


@njit(cache=True, error_model="numpy")
def _branch_points(kappa):
    """The roots of ``P(λ) = Σ_m κ_m λ^{2N−m}`` (``κ_0 = b² ≠ 0``): :func:`_aberth` (simple roots: ~1 µs), else
    (a root it does not resolve to round-off, e.g. a double one) the eigenvalues of the companion matrix, as
    :func:`jetgaudin.spectral._roots` (LAPACK, ~12 µs for N = 3)."""
    deg = kappa.shape[0] - 1
    roots = np.empty(deg, dtype=np.complex128)
    if _aberth(kappa, roots):
        return roots
    comp = np.zeros((deg, deg), dtype=np.complex128)
    for j in range(deg):
        comp[0, j] = -kappa[j + 1] / kappa[0]
    for j in range(deg - 1):
        comp[j + 1, j] = 1.0
    return np.linalg.eigvals(comp)


@njit(cache=True, error_model="numpy")
def _aberth(kappa, z):
    """The roots ``z`` of ``P(λ) = Σ_m κ_m λ^{deg−m}`` by the Aberth–Ehrlich iteration
    ``z_i ← z_i − w_i/(1 − w_i Σ_{j≠i} 1/(z_i − z_j))``, ``w_i = P(z_i)/P'(z_i)``, from ``deg`` points on the circle
    of radius ``|κ_deg/κ_0|^{1/deg}`` (the geometric mean of the roots' moduli; ``B = max_j |κ_j/κ_0|^{1/j}``, half
    a bound on every root's modulus, where that is 0); converged when every correction is at
    most ``4e-16 B``, so the root is correct to round-off (quadratic convergence at a simple
    root: the last step's error is the square of the one before).  ``False`` when that does not happen within 60
    sweeps (a multiple or nearly multiple root: the caller takes the eigenvalues)."""
    deg = kappa.shape[0] - 1
    bound = 0.0
    for j in range(1, deg + 1):
        bound = max(bound, abs(kappa[j] / kappa[0]) ** (1.0 / j))
    if bound == 0.0 or not np.isfinite(bound):
        return False
    start = abs(kappa[deg] / kappa[0]) ** (1.0 / deg)  # the geometric mean of the roots' moduli
    if start == 0.0:
        start = bound
    for i in range(deg):
        z[i] = start * np.exp(complex(0.0, (2.0 * np.pi * i + 0.4) / deg))
    for _ in range(60):
        big = 0.0
        for i in range(deg):
            zi = z[i]
            p = complex(kappa[0], 0.0)
            dp = complex(0.0, 0.0)
            for m in range(1, deg + 1):
                dp = dp * zi + p
                p = p * zi + kappa[m]
            if dp == 0:
                return False
            w = p / dp
            ar = 0.0
            ai = 0.0
            for j in range(deg):  # Σ_{j≠i} 1/(z_i − z_j) = Σ conj(d)/|d|²
                if j != i:
                    d = zi - z[j]
                    e = 1.0 / (d.real * d.real + d.imag * d.imag)
                    ar += d.real * e
                    ai -= d.imag * e
            acc = complex(ar, ai)
            step = w / (1.0 - w * acc)
            if not np.isfinite(step.real) or not np.isfinite(step.imag):
                return False
            z[i] = zi - step
            big = max(big, abs(step))
        if big <= 4e-16 * bound:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _branch_ok(kappa, roots, rho, h, nu_end, tol):
    """Whether every continued ``ν(ρ_j + i h_j)`` (``nu_end``) is the branch rule's ``ν`` (the maps' own,
    :func:`jetgaudin.spectral._nu_from_kappa`: the root of ``ν²`` whose phase matches
    ``λ^{−N} √P(ρ) sgn(ρ)^N Π_k √((λ − r_k)/(ρ − r_k))``, ``P(λ) = λ^{2N} ν²``) to ``tol`` (relative): no branch point
    near a segment."""
    deg = kappa.shape[0] - 1
    N = deg // 2
    for j in range(rho.shape[0]):
        a = rho[j]
        lam = complex(a, h[j])
        Pa = complex(0.0, 0.0)
        for m in range(deg + 1):
            Pa += kappa[m] * complex(a, 0.0) ** (deg - m)
        ref = np.sqrt(Pa) * (1.0 if a > 0 else -1.0) ** N
        for r in roots:
            ratio = (lam - r) / (a - r)
            if abs(ratio.imag) <= 1e-13 * abs(ratio) and ratio.real <= 0.0:
                return False  # a branch point on the segment
            ref *= np.sqrt(ratio)
        direct = np.sqrt(_nu2(kappa, lam))
        if direct == 0 or ref == 0:
            return False
        ph = (lam.conjugate() / abs(lam)) ** N
        test = ((direct / abs(direct)).conjugate() * (ref / abs(ref)) * ph).real
        rule = direct if test >= 0 else -direct
        if not np.isfinite(test) or abs(rule - nu_end[j]) > tol * abs(rule):
            return False
    return True


@njit(cache=True, error_model="numpy")
def _solve_state(x, b, weights, dt, k, rho_factor, scales, x64, w64, x32, w32, xc, wc, stages, step_tol, fold,
                 iterations, res_tol, quad_tol, branch_tol, eta, nu, out):
    """One orbit from its state: ``κ`` (:func:`_kappa`), ``ρ_j = c R / t_j``, the solve (:func:`_solve_one`) and the
    acceptance (converged, residual, quadrature estimate, ``h_j ≠ 0``, branch check); ``eta`` (k,) complex,
    ``nu`` (k,) the maps' ``ν(η_j)`` (the root of ``ν²(η_j)`` on the continued, checked branch: the maps' first
    ``ν1``), ``out = (ok, residual, quadrature estimate, θ)`` with ``θ = 2b(dt w_1 − Σ_j ω_1)``."""
    M = x.shape[0] // 3 * 2
    kappa = np.empty(M + 1)
    _kappa(x, b, kappa)
    roots = _branch_points(kappa)
    R = 1e-6  # floor: X = 0 has every branch point at 0
    for r in roots:
        R = max(R, abs(r))
    rho = np.empty(k)
    h = np.zeros(k)
    target = np.empty(k)
    for j in range(k):
        rho[j] = rho_factor * R / scales[j]
        target[j] = dt * weights[j + 1]
    nu_end = np.zeros(2 * k, dtype=np.complex128)
    info = np.zeros(4)
    ok = kappa[0] > 0.0  # b != 0 (checked by the caller)
    if ok:
        _solve_one(kappa, rho, target, x64, w64, x32, w32, xc, wc, stages, step_tol, fold, iterations, h, nu_end,
                   info)
        ok = info[0] == 1.0 and info[1] <= res_tol and info[2] <= quad_tol
        for j in range(k):
            ok = ok and h[j] != 0.0
        ok = ok and _branch_ok(kappa, roots, rho, h, nu_end, branch_tol)
    for j in range(k):
        eta[j] = complex(rho[j], h[j])
        r = np.sqrt(_nu2(kappa, eta[j]))  # ν at η_j itself (nu_end is at Newton's last point, |Δh| ≤ step_tol |h|)
        nu[j] = r if (r.real * nu_end[j].real + r.imag * nu_end[j].imag) >= 0.0 else -r
    out[0] = 1.0 if ok else 0.0
    out[1] = info[1]
    out[2] = info[2]
    out[3] = 2.0 * b * (dt * weights[0] - info[3])


@njit(cache=True, error_model="numpy")
def _solve_packed(x, b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta, nu, out):
    """:func:`_solve_state` with the constants packed (fewer arguments: Numba's dispatch types each one):
    ``rules`` the nodes and weights of the fine, estimate and coarse rules one after the other (lengths
    ``sizes = (n, n₂, n_c)``), ``tols = (step_tol, fold, iterations, res_tol, quad_tol, branch_tol)``."""
    n, n2, nc = sizes[0], sizes[1], sizes[2]
    x64 = rules[0:n]
    w64 = rules[n:2 * n]
    o = 2 * n
    x32 = rules[o:o + n2]
    w32 = rules[o + n2:o + 2 * n2]
    o += 2 * n2
    xc = rules[o:o + nc]
    wc = rules[o + nc:o + 2 * nc]
    _solve_state(x, b, weights, dt, k, rho_factor, scales, x64, w64, x32, w32, xc, wc, stages, tols[0], tols[1],
                 int(tols[2]), tols[3], tols[4], tols[5], eta, nu, out)


@njit(cache=True, error_model="numpy")
def solve_states(X, b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta, nu, out):
    """:func:`_solve_packed` for every orbit of ``X`` (B, 3N) on this thread (one call from Python: no thread
    start-up, no per-orbit dispatch); ``eta``, ``nu`` (B, k), ``out`` (B, 4)."""
    for i in range(X.shape[0]):
        _solve_packed(X[i], b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta[i], nu[i], out[i])


@njit(cache=True, error_model="numpy", parallel=True)
def solve_states_batch(X, b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta, nu, out):
    """:func:`solve_states` on all threads (every orbit the bits of its own solve)."""
    for i in prange(X.shape[0]):
        _solve_packed(X[i], b, weights, dt, k, rho_factor, scales, rules, sizes, stages, tols, eta[i], nu[i], out[i])


@njit(cache=True, error_model="numpy")
def rotate(X, theta):
    """:func:`jetgaudin.exact.rotate_about_field` of a flat batch ``X`` (B, 3N) by ``theta`` (B,), compiled (one
    call for a short run: no NumPy temporaries); a new array."""
    out = np.empty_like(X)
    for i in range(X.shape[0]):
        c = np.cos(theta[i])
        s = np.sin(theta[i])
        for n in range(X.shape[1] // 3):
            y1 = X[i, 3 * n]
            y2 = X[i, 3 * n + 1]
            out[i, 3 * n] = c * y1 - s * y2
            out[i, 3 * n + 1] = s * y1 + c * y2
            out[i, 3 * n + 2] = X[i, 3 * n + 2]
    return out


@njit(cache=True, error_model="numpy")
def integrals_rows(X, b, out):
    """``out[r] = (H_1..H_N, C_1..C_N)`` of every row of ``X`` (R, 3N) in the field ``b e_3`` (reduction (lax2)):
    ``κ_1..κ_{2N}`` of :func:`_kappa`, summed in the order of :func:`jetgaudin.spectral.curve_coefficients` (the
    same bits as :func:`jetgaudin.spectral.integrals`; tested)."""
    N = X.shape[1] // 3
    xi = np.empty((N + 1, 3))
    xi[0, 0] = 0.0
    xi[0, 1] = 0.0
    xi[0, 2] = b
    for r in range(X.shape[0]):
        for n in range(N):
            xi[n + 1, 0] = X[r, 3 * n]
            xi[n + 1, 1] = X[r, 3 * n + 1]
            xi[n + 1, 2] = X[r, 3 * n + 2]
        # κ_m, m ≥ 1: the terms (i, m − i) in the order of i, as the double loop of _kappa_into adds them
        for m in range(1, 2 * N + 1):
            acc = 0.0
            for i in range(max(0, m - N), min(m, N) + 1):
                j = m - i
                acc += (xi[i, 0] * xi[j, 0] + xi[i, 1] * xi[j, 1]) + xi[i, 2] * xi[j, 2]
            out[r, m - 1] = acc
