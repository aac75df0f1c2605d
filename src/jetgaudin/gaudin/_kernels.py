r"""Compiled (Numba) kernel of the real two-point map of a chain, any sites and orders.

The same arithmetic as :class:`jetgaudin.gaudin.maps.ChainTwoPointBacklund.step` (the site-wise dressing of the
principal parts, module docstring of :mod:`jetgaudin.gaudin.maps`), with the weights of ``ℓ(η)``,
``f_c = (η − λ_c)^{−(k_c+1)}``, hoisted out of the loop (as two words, ``f + flo``, each product with them rounded
once: :func:`_tw`) and ``K`` taken as
``|k|² (λ + M0)``, with the Taylor coefficients ``g_d`` of ``1/det K`` at each site from the step's own ``K``
(:func:`jetgaudin.gaudin.maps.monic_series`: the determinant of a normalised ``K`` is the same at every step and its
rounding, the same at every step, made the sites' Casimirs drift linearly; ``docs/reliability.md``).
With ``K' = K(λ_i)``, ``A' = adj K(λ_i)``, ``s = |k|²``, the four terms of the dressing sum collapse to

.. math:: \breve\ell_k = \sum_{j \ge k} g_{j-k} K' \ell_j A' + g_{j-k-1}\, s (K' \ell_j + \ell_j A')
          + g_{j-k-2}\, s^2 \ell_j .

``ν1`` is continued along the orbit as the root of ``ν(η)² = u² + vw`` closest to the previous one (the branch rule
at the first state is applied by the caller, on the NumPy route).  The residual check and the imaginary residue
of the NumPy route are not computed here; the orbits agree with the NumPy route to round-off
(``tests/test_gaudin_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..backlund.kernels._target import configure

# Numba's CPU target as for the Bäcklund kernels, chosen before this module's first dispatcher creates it: a process
# that imports the chains' kernels first (``ensemble --sites``) then loads the cache entries ``jetgaudin warmup``
# wrote instead of compiling for another target (``tests/test_cli_interface.py``).
configure()

from ..backlund.kernels._scalar import _fma  # noqa: E402  (after configure: the Bäcklund kernels' target)
from ._compensated import KAPPA  # noqa: E402


@njit(cache=True, inline="always")
def _acc(s, e, a, bh, bl):
    """One term ``a·(bh + bl)`` (reals; ``bh + bl`` a constant as two words) of a compensated sum: ``s`` the rounded
    running sum, ``e`` the sum of every rounding error so far (the product's, exact by a fused multiply-add; the
    addition's, exact by TwoSum) and of the ``a·bl``; the sum is ``s + e`` (the Dot2 of Ogita, Rump and Oishi, 2005).

    Why (issue 33; ``docs/reliability.md``, "Drift like round-off"): ``fl(a·bh)`` misses ``a·b`` by the constant's
    own relative error at every step, a bias; adding ``a·bl`` to a rounded double changes nothing (it is below half
    an ulp), so the low word counts only together with the exact rounding errors, and ``s + e`` is then the exact
    sum rounded once: an error that varies from step to step.  The compiled kernels now use the cheaper :func:`_tw`
    (``docs/reliability.md``, "Compensated sums: the cost"); this Dot2 term stays as the compiled twin of the NumPy
    route's :func:`jetgaudin.gaudin._compensated.acc` (``tests/test_chain_drift.py``)."""
    p = a * bh
    ep = _fma(a, bh, -p)
    t = s + p
    z = t - s
    return t, e + (ep + ((s - (t - z)) + (p - z)) + a * bl)


@njit(cache=True, inline="always")
def _tw(a, bh, bl):
    """``a·(bh + bl)`` (reals; ``bh + bl`` a constant as two words) rounded once: ``fma(a, bh, fl(a·bl))``, the
    exact ``a·bh`` plus the low word's product, one rounding.  The cheap form of :func:`_acc` the chain kernels use
    (``docs/reliability.md``, "Compensated sums: the cost"): the bias of a rounded constant (``fl(a·bh)`` misses
    ``a·b`` by ``bh``'s own relative error, the same at every step) is gone, and the one rounding left is of a
    product that varies from step to step (a random walk, unbiased), as are the roundings of the plain sum the
    terms then go into.  2 flops a term, against 11 for the Dot2 term of :func:`_acc`."""
    return _fma(a, bh, a * bl)


@njit(cache=True, inline="always")
def _ctw(a, h, lo):
    """``a·(h + lo)`` (``a``, ``h``, ``lo`` complex) with each of the real and imaginary parts rounded twice, both
    times a quantity that varies with ``a`` (:func:`_tw`): the low words' products first (plain), then the two
    high products each added exactly by a fused multiply-add."""
    ar, ai = a.real, a.imag
    re = _fma(ar, h.real, _fma(-ai, h.imag, ar * lo.real - ai * lo.imag))
    im = _fma(ar, h.imag, _fma(ai, h.real, ar * lo.imag + ai * lo.real))
    return complex(re, im)


#: the generic factor of :func:`_split` (the fixed point of cos: a mantissa with no short period), shared with the
#: NumPy route's :func:`jetgaudin.gaudin._compensated.split_constant` (the two routes split alike; Numba freezes it
#: into this module's cached kernels, whose cache is keyed on this file: a change of ``KAPPA`` needs a fresh cache)
_KAPPA = KAPPA


@njit(cache=True, inline="always")
def _split(c):
    """``c = a + b`` exactly, ``a = fl(κ c)`` with the generic ``κ`` = :data:`_KAPPA` (``b = c − a`` is exact:
    ``a`` is within a factor 2 of ``c``).

    Why (issue 33; ``docs/reliability.md``, "Drift like round-off"): the rounding of ``c·x`` is biased when ``c``'s
    binary mantissa has a short period, as the site and ``η`` constants typed as decimals do (``0.2``, ``0.4`` are
    the doubles nearest ``1/5``, ``2/5``: over uniformly random mantissas of ``x``, ``fl(0.2 x)`` is low by 0.006 ulp
    on average, 30 standard errors, because the bits it drops are those of ``x·4/5 mod 1``, five clusters rather than a
    uniform spread).  ``_tw(x, a, b) = fma(x, a, fl(x·b))`` is ``c·x`` rounded once after the generic product
    ``x·b``'s own rounding error: the final rounding is dithered and unbiased.  The NumPy route's twins:
    :func:`jetgaudin.gaudin._compensated.split_constant`, ``times_split``."""
    a = c * _KAPPA
    return a, c - a


@njit(cache=True, inline="always")
def _mm(a00, a01, a10, a11, b00, b01, b10, b11):
    return (a00 * b00 + a01 * b10, a00 * b01 + a01 * b11, a10 * b00 + a11 * b10, a10 * b01 + a11 * b11)


@njit(cache=True, inline="always")
def _abs2(z):
    return z.real * z.real + z.imag * z.imag


@njit(cache=True, inline="always")
def _add_scaled(s00, s01, s10, s11, gd, w, j):
    """``(s00, s01, s10, s11) + gd * w[j, :]``: one term of the dressing sum added to the 2x2 accumulator."""
    return s00 + gd * w[j, 0], s01 + gd * w[j, 1], s10 + gd * w[j, 2], s11 + gd * w[j, 3]


@njit(cache=True, inline="always")
def _put_site(out, c, s00, s01, s10):
    """Coordinate ``c`` of the new state from ``ℓ̃_c = [[s00, s01], [s10, −s00]]`` (``state_from_ell``, real part):
    ``y¹ = Re(s01 + s10)/2``, ``y² = Im(s10 − s01)/2``, ``y³ = Re s00``; every chain kernel stores its steps so."""
    out[3 * c] = 0.5 * (s01.real + s10.real)
    out[3 * c + 1] = 0.5 * (s10.imag - s01.imag)
    out[3 * c + 2] = s00.real


@njit(cache=True)
def _step(x, out, b, eta, nu_prev, f, flo, g, site_pos, site_off, site_n, M, w0, w1, wp):
    """One step from ``x`` (3M,) into ``out`` (3M,); returns the ``ν1`` used.  ``g`` (Nmax,) is scratch: the
    Taylor coefficients of ``1/det K`` at each site from this step's ``M0`` (``gaudin.maps.monic_series``)."""
    # ℓ(η) = diag(b, −b) + Σ_c f_c P_c,  P = [[y3, y1 − i y2], [y1 + i y2, −y3]]
    # f + flo: the weights to ~1e-32, each product with them rounded once (_tw: a rounded constant f alone repeats
    # its error at every step: ℓ(η), hence the eigenvector, off by the same relative ~1e-16 each time, whose dropped
    # residue at η drifts linearly; flo added to a rounded product would change nothing); the sums plain: their
    # roundings vary with the state
    ur, ui, vr, vi, wr, wi = b, 0.0, 0.0, 0.0, 0.0, 0.0
    for c in range(M):
        y1 = x[3 * c]
        y2 = x[3 * c + 1]
        y3 = x[3 * c + 2]
        fr, fi, lr, li = f[c].real, f[c].imag, flo[c].real, flo[c].imag
        ur += _tw(y3, fr, lr)
        ui += _tw(y3, fi, li)
        vr += _tw(y1, fr, lr) + _tw(y2, fi, li)  # v: f (y1 − i y2)
        vi += _tw(y1, fi, li) - _tw(y2, fr, lr)
        wr += _tw(y1, fr, lr) - _tw(y2, fi, li)  # w: f (y1 + i y2)
        wi += _tw(y1, fi, li) + _tw(y2, fr, lr)
    u = complex(ur, ui)
    v = complex(vr, vi)
    w = complex(wr, wi)
    r = np.sqrt(u * u + v * w)
    if (r.conjugate() * nu_prev).real < 0:
        r = -r
    nu = r
    # eigenvector of ℓ(η) for ν: (v, ν − u) or (u + ν, w), whichever is larger
    a1 = v
    a2 = nu - u
    c1 = u + nu
    c2 = w
    if _abs2(a1) + _abs2(a2) >= _abs2(c1) + _abs2(c2):
        k1 = a1
        k2 = a2
    else:
        k1 = c1
        k2 = c2
    n2 = _abs2(k1) + _abs2(k2)
    # k scaled by a power of two (exact: the mantissas, hence the rounding, are kept) to |k|² in [1/4, 1), so that K
    # below stays of the size of λ + M0 for states of any size
    p2 = math.ldexp(1.0, -((math.frexp(n2)[1] + 1) // 2))
    k1 = k1 * p2
    k2 = k2 * p2
    n2 = _abs2(k1) + _abs2(k2)
    # K = n2 (λ + M0) (eq. (mm) times |k|², no division): the dressing does not depend on the factor, and with a
    # factor varying along the orbit the rounding of K and of 1/det K changes from step to step (a normalised K has
    # a constant det whose reciprocal rounds alike at every step: a linear drift; gaudin.maps.monic_series, issue 33)
    # every product with η's parts and the sites as c·x = _tw(x, a, b), c = a + b split by _split: a decimal constant
    # (0.2 = the double nearest 1/5) rounds its products with a bias of its own (_split), which made each orbit's
    # integrals drift linearly, the sign depending on the orbit (benchmarks/chain_drift.py --persistence)
    ra, rb = _split(eta.real)
    ia, ib = _split(eta.imag)
    ak2 = _abs2(k2)
    er = _tw(n2, ra, rb)  # Re η · n2
    ei = _tw(n2, ia, ib) - _tw(ak2, 2.0 * ia, 2.0 * ib)  # Im η · (n2 − 2|k2|²)
    m00 = complex(-er, -ei)  # −η n2 + t |k2|², t = 2i Im η
    m11 = complex(-er, ei)  # −η̄ n2 − t |k2|²
    tk1 = complex(_tw(k1.imag, 2.0 * ia, 2.0 * ib), -_tw(k1.real, 2.0 * ia, 2.0 * ib))  # −t k1
    m01 = tk1 * k2.conjugate()
    m10 = complex(-tk1.real, tk1.imag) * k2  # −t k̄1 = −conj(−t k1)
    s2 = n2 * n2
    for i in range(site_pos.shape[0]):
        pa, pb = _split(site_pos[i])
        lam = _tw(n2, pa, pb)
        o = site_off[i]
        N = site_n[i]
        K00 = m00 + lam
        K11 = m11 + lam
        A00 = m11 + lam
        A11 = m00 + lam
        A01 = -m01
        A10 = -m10
        # 1/det K(λ_i + z) from this step's K (det = d0 + d1 z + n2² z²), each product of two factors that vary
        # with n2 (d1 g0 or n2² g0 are the same at every step: they would round alike; gaudin.maps.monic_series)
        g0 = 1.0 / (K00 * K11 - m01 * m10)
        d1 = n2 * (K00 + K11)
        g[0] = g0
        if N > 1:
            g[1] = -d1 * (g0 * g0)
        for d in range(2, N):
            g[d] = -(d1 * (g[d - 1] * g0) + s2 * (g[d - 2] * g0))
        # per component: P, K'P + PA', K'PA' (each once), then the O(N²) combination with the g's
        for j in range(N):
            c = o + j
            y1 = x[3 * c]
            y2 = x[3 * c + 1]
            y3 = x[3 * c + 2]
            p00 = complex(y3)
            p01 = complex(y1, -y2)
            p10 = complex(y1, y2)
            p11 = complex(-y3)
            kp = _mm(K00, m01, m10, K11, p00, p01, p10, p11)
            pa = _mm(p00, p01, p10, p11, A00, A01, A10, A11)
            kpa = _mm(kp[0], kp[1], kp[2], kp[3], A00, A01, A10, A11)
            wp[j, 0] = p00
            wp[j, 1] = p01
            wp[j, 2] = p10
            wp[j, 3] = p11
            for e in range(4):
                w1[j, e] = n2 * (kp[e] + pa[e])
                w0[j, e] = kpa[e]
                wp[j, e] = s2 * wp[j, e]
        for k in range(N):
            s00 = 0j
            s01 = 0j
            s11 = 0j
            s10 = 0j
            for j in range(k, N):
                # the three terms g_d K'ℓ_jA' + g_{d−1}(K'ℓ_j + ℓ_jA') + g_{d−2} ℓ_j, added in this order
                d = j - k
                s00, s01, s10, s11 = _add_scaled(s00, s01, s10, s11, g[d], w0, j)
                if d >= 1:
                    s00, s01, s10, s11 = _add_scaled(s00, s01, s10, s11, g[d - 1], w1, j)
                if d >= 2:
                    s00, s01, s10, s11 = _add_scaled(s00, s01, s10, s11, g[d - 2], wp, j)
            _put_site(out, o + k, s00, s01, s10)
    return nu


@njit(cache=True)
def step_scratch(site_n):
    """The scratch of :func:`_step` for sites of orders ``site_n``: ``w0, w1, wp`` (Nmax, 4) and ``gs`` (Nmax,)
    (complex), ``Nmax`` the largest order (shared with the exact chain loop, ``jetgaudin._exact_chain_loop``)."""
    Nmax = 1
    for i in range(site_n.shape[0]):
        Nmax = max(Nmax, site_n[i])
    return (np.empty((Nmax, 4), dtype=np.complex128), np.empty((Nmax, 4), dtype=np.complex128),
            np.empty((Nmax, 4), dtype=np.complex128), np.empty(Nmax, dtype=np.complex128))


@njit(cache=True)
def run_orbit(x0, b, eta, nu0, f, flo, site_pos, site_off, site_n, steps, save_every):
    """``steps`` steps from ``x0``; returns ``(rows (steps//save_every + 1, 3M), final state (3M,), last ν1)``."""
    n = x0.shape[0]
    M = n // 3
    rows = np.empty((steps // save_every + 1, n))
    rows[0] = x0
    x = x0.copy()
    y = np.empty(n)
    w0, w1, wp, gs = step_scratch(site_n)  # gs, per step: 1/det K at a site
    nu = nu0
    for s in range(steps):
        nu = _step(x, y, b, eta, nu, f, flo, gs, site_pos, site_off, site_n, M, w0, w1, wp)
        x, y = y, x
        if (s + 1) % save_every == 0:
            rows[(s + 1) // save_every] = x
    return rows, x, nu


def orbit_constants(model, eta):
    """``(f, flo, site_pos, site_off, site_n)``: the per-orbit constants of the kernel (module docstring); the weights
    of ``ℓ(η)``, ``f_c = (η − λ_c)^{−(k_c+1)}``, as two words ``f + flo`` (``flo`` the rounding error of ``f``,
    computed with mpmath at 40 digits: :func:`jetgaudin.gaudin._curve.rational_weights`)."""
    from ._curve import rational_weights

    f, flo = rational_weights(model.sites, complex(eta))
    return (f.copy(), flo.copy(), model.positions.astype(float), np.array(model.offsets, dtype=np.int64),
            np.array(model.orders, dtype=np.int64))
