r"""Compiled (Numba) route of the su(3) two-point map ``B^{(r)}_η`` (issue 32), any sites and orders.

The arithmetic of :func:`jetgaudin.gaudin.sun_maps.dress` with what is constant along an orbit hoisted out:
``f_c = (η − λ_c)^{−(k_c+1)}`` (the weights of ``ℓ(η)``).  Per step:

* ``ℓ(η) = Σ_a λ_a ξ^a(η)`` from ``ξ = b + Σ_c f_c y_c`` (the Gell-Mann matrices written out);
* ``μ_r(η)`` is an integral of the map: the carry, Newton-polished (two steps) on the characteristic polynomial
  ``μ³ − ½ tr(ℓ²) μ − det ℓ`` of the current ``ℓ(η)`` (no eigen-solver);
* the eigenvector ``v`` (``(ℓ(η) − μ) v = 0``) is the cross product of two rows of ``ℓ(η) − μ`` (no conjugation: each
  row annihilates ``v``); of the three pairs the one with the largest product;
* ``u = v/|v|``, ``P = u u^†``, ``D_0 = d_0 + d_1 P`` (``d_0 = λ_i − η̄``, ``d_1 = η̄ − η``),
  ``D^{−1}_c = a_c + g_c P`` (``a_c = (−α)^c α``, ``g_c = (−1)^c (β^{c+1} − α^{c+1})``, ``α = 1/(λ_i − η̄)``,
  ``β = 1/(λ_i − η)``); with ``w = Y u``, ``s = u^† w`` and ``Y`` Hermitian (``YP = w u^†``, ``PY = u w^†``,
  ``PYP = s u u^†``) every term of ``Ỹ_k = Σ_{j≥k} D_0 Y_j D^{−1}_{j−k} + Y_j D^{−1}_{j−k−1}`` is
  ``(d_0 a_c + a_{c−1}) Y + (d_0 g_c + g_{c−1}) w u^† + d_1 a_c u w^† + d_1 g_c s u u^†`` (``c = j − k``,
  ``a_{−1} = g_{−1} = 0``): no 3×3 product; and ``y^a = Re tr(λ_a Ỹ)/2``.

The branch rule at the first state is applied by the caller (NumPy); the orbits agree with the NumPy route to
round-off (``tests/test_sun_kernel.py``).  ``run_batch`` runs orbits on all cores (``prange``), each its single run.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..backlund.kernels._target import configure

configure()

_S3 = 1.0 / np.sqrt(3.0)


@njit(cache=True, inline="always")
def _mat(v, o, Y):
    """``Y = Σ_a v[o + a] λ_a`` (3×3)."""
    Y[0, 0] = v[o + 2] + v[o + 7] * _S3
    Y[1, 1] = -v[o + 2] + v[o + 7] * _S3
    Y[2, 2] = -2.0 * v[o + 7] * _S3
    Y[0, 1] = v[o] - 1j * v[o + 1]
    Y[1, 0] = v[o] + 1j * v[o + 1]
    Y[0, 2] = v[o + 3] - 1j * v[o + 4]
    Y[2, 0] = v[o + 3] + 1j * v[o + 4]
    Y[1, 2] = v[o + 5] - 1j * v[o + 6]
    Y[2, 1] = v[o + 5] + 1j * v[o + 6]


@njit(cache=True, inline="always")
def _put(Y, out, o):
    """``out[o + a] = Re tr(λ_a Y)/2``."""
    out[o] = 0.5 * (Y[1, 0].real + Y[0, 1].real)
    out[o + 1] = 0.5 * (Y[1, 0].imag - Y[0, 1].imag)
    out[o + 2] = 0.5 * (Y[0, 0].real - Y[1, 1].real)
    out[o + 3] = 0.5 * (Y[2, 0].real + Y[0, 2].real)
    out[o + 4] = 0.5 * (Y[2, 0].imag - Y[0, 2].imag)
    out[o + 5] = 0.5 * (Y[2, 1].real + Y[1, 2].real)
    out[o + 6] = 0.5 * (Y[2, 1].imag - Y[1, 2].imag)
    out[o + 7] = 0.5 * _S3 * (Y[0, 0].real + Y[1, 1].real - 2.0 * Y[2, 2].real)


@njit(cache=True, inline="always")
def _mm(A, B, C):
    for i in range(3):
        for k in range(3):
            C[i, k] = A[i, 0] * B[0, k] + A[i, 1] * B[1, k] + A[i, 2] * B[2, k]


@njit(cache=True)
def _step(x, out, b, mu, f, site_pos, site_off, site_n, eta, xi, L, u, w, Y, acc, ac, gc):
    """One step from ``x`` into ``out``; returns the polished ``μ_r(η)``."""
    for a in range(8):
        xi[a] = b[a]
    for c in range(f.shape[0]):
        for a in range(8):
            xi[a] += f[c] * x[8 * c + a]
    _mat(xi, 0, L)
    t2 = 0j
    for i in range(3):
        for j in range(3):
            t2 += L[i, j] * L[j, i]
    det = (L[0, 0] * (L[1, 1] * L[2, 2] - L[1, 2] * L[2, 1]) - L[0, 1] * (L[1, 0] * L[2, 2] - L[1, 2] * L[2, 0])
           + L[0, 2] * (L[1, 0] * L[2, 1] - L[1, 1] * L[2, 0]))
    p = -0.5 * t2
    for _ in range(2):
        mu = mu - (mu * mu * mu + p * mu - det) / (3.0 * mu * mu + p)
    for i in range(3):
        L[i, i] -= mu
    best = -1.0
    v0 = v1 = v2 = 0j
    for r0, r1 in ((0, 1), (0, 2), (1, 2)):
        c0 = L[r0, 1] * L[r1, 2] - L[r0, 2] * L[r1, 1]
        c1 = L[r0, 2] * L[r1, 0] - L[r0, 0] * L[r1, 2]
        c2 = L[r0, 0] * L[r1, 1] - L[r0, 1] * L[r1, 0]
        nrm = c0.real**2 + c0.imag**2 + c1.real**2 + c1.imag**2 + c2.real**2 + c2.imag**2
        if nrm > best:
            best, v0, v1, v2 = nrm, c0, c1, c2
    nv = math.sqrt(best)  # math, not np: NumPy ufuncs do not compile for the CUDA target
    u[0], u[1], u[2] = v0 / nv, v1 / nv, v2 / nv
    eb = eta.conjugate()
    d0, d1 = 0j, eb - eta
    for s in range(site_pos.shape[0]):
        lam, o, N = site_pos[s], site_off[s], site_n[s]
        alpha, beta = 1.0 / (lam - eb), 1.0 / (lam - eta)
        d0 = lam - eb
        ap, bp = alpha, beta
        for c in range(N):  # D^{-1}_c = a_c + g_c P
            sg = 1.0 if c % 2 == 0 else -1.0
            ac[c], gc[c] = sg * ap, sg * (bp - ap)
            ap, bp = ap * alpha, bp * beta
        for k in range(N):
            for i in range(3):
                for j in range(3):
                    acc[i, j] = 0j
            for j in range(k, N):
                c = j - k
                A, Bc, C, E = d0 * ac[c], d0 * gc[c], d1 * ac[c], d1 * gc[c]
                if c > 0:
                    A += ac[c - 1]
                    Bc += gc[c - 1]
                _mat(x, 8 * (o + j), Y)
                sw = 0j
                for i in range(3):
                    w[i] = Y[i, 0] * u[0] + Y[i, 1] * u[1] + Y[i, 2] * u[2]
                    sw += u[i].conjugate() * w[i]
                for i in range(3):
                    bi, ci, ei = Bc * w[i], C * u[i], E * sw * u[i]
                    for m in range(3):
                        acc[i, m] += A * Y[i, m] + bi * u[m].conjugate() + ci * w[m].conjugate() + \
                            ei * u[m].conjugate()
            _put(acc, out, 8 * (o + k))
    return mu


@njit(cache=True)
def orbit_loop(x, out, rows, final, b, mu, f, site_pos, site_off, site_n, eta, xi, L, u, w, Y, acc, ac, gc, steps,
               save_every, substeps):
    """The stepping loop of :func:`run_orbit` on caller-given scratch, without allocations (the GPU kernel of
    :mod:`jetgaudin.gpu` calls it for one orbit per thread, compiled for the device, with thread-local scratch).
    One step is ``substeps`` times the composition of the ``k`` maps ``η_j`` (``eta`` (k,), their weights ``f``
    (k, C), carries ``mu`` (k,), updated in place) in turn: ``k = substeps = 1`` is the map ``B^{(r)}_η``, ``k``
    maps the exact step of :class:`jetgaudin.gaudin.sun_exact.SunExactFlow` (``B_{η_k} ∘ … ∘ B_{η_1}``).
    ``x`` (8M,) holds the start state and ``out`` (8M,) is scratch (both overwritten), ``rows[j − 1] =
    x_{j·save_every}``, ``final`` the last state; ``xi`` (8,), ``u, w`` (3,), ``L, Y, acc`` (3, 3), ``ac, gc``
    (at least the largest site order,) complex."""
    n = x.shape[0]
    for t in range(steps):
        for _ in range(substeps):
            for j in range(eta.shape[0]):
                mu[j] = _step(x, out, b, mu[j], f[j], site_pos, site_off, site_n, eta[j], xi, L, u, w, Y, acc, ac, gc)
                x, out = out, x
        if (t + 1) % save_every == 0:
            for i in range(n):
                rows[(t + 1) // save_every - 1, i] = x[i]
    for i in range(n):
        final[i] = x[i]


@njit(cache=True)
def run_orbit(x0, b, mu0, f, site_pos, site_off, site_n, eta, steps, save_every, substeps):
    """``steps`` steps from ``x0`` (8M,) of the maps ``eta`` (k,) with ``f`` (k, C) and first carries ``mu0`` (k,)
    (:func:`orbit_loop`): ``(rows (steps // save_every, 8M), final, μ (k,))``."""
    n = x0.shape[0]
    rows = np.empty((steps // save_every, n))
    final = np.empty(n)
    m = max(1, np.max(site_n))
    mu = mu0.copy()
    orbit_loop(x0.copy(), np.empty(n), rows, final, b, mu, f, site_pos, site_off, site_n, eta,
               np.empty(8, dtype=np.complex128), np.empty((3, 3), dtype=np.complex128),
               np.empty(3, dtype=np.complex128), np.empty(3, dtype=np.complex128),
               np.empty((3, 3), dtype=np.complex128), np.empty((3, 3), dtype=np.complex128),
               np.empty(m, dtype=np.complex128), np.empty(m, dtype=np.complex128), steps, save_every, substeps)
    return rows, final, mu


@njit(cache=True, parallel=True)
def run_batch(X0, b, mu0, f, site_pos, site_off, site_n, eta, steps, save_every, substeps):
    """:func:`run_orbit` for each row of ``X0`` (B, 8M) on all cores, orbit ``i`` with its own maps ``eta[i]`` (k,),
    ``f[i]`` (k, C), ``mu0[i]`` (k,): ``(rows (S, B, 8M), final (B, 8M), μ (B, k))``."""
    B, n = X0.shape
    rows = np.empty((steps // save_every, B, n))
    final = np.empty((B, n))
    mus = np.empty(mu0.shape, dtype=np.complex128)
    for i in prange(B):
        r, xf, m = run_orbit(X0[i], b, mu0[i], f[i], site_pos, site_off, site_n, eta[i], steps, save_every, substeps)
        rows[:, i, :] = r
        final[i] = xf
        mus[i] = m
    return rows, final, mus


def orbit_constants(model, eta: complex) -> tuple:
    """``(b, f, site_pos, site_off, site_n)`` of :func:`run_orbit` for the su(3) ``model`` and ``η``."""
    from ._curve import _component_poles

    pos, power = _component_poles(model.sites)
    f = (eta - pos) ** (-power.astype(float))
    return (np.ascontiguousarray(model.field_vector, dtype=float), f.astype(np.complex128),
            model.positions.astype(float), np.array(model.offsets, dtype=np.int64),
            np.array(model.orders, dtype=np.int64))
