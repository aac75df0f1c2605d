"""The chain maps' integral drift is round-off, not a bias repeated at every step (issue 33; docs/reliability.md,
"Drift like round-off").  Found: the rational chain's dressing divided by the rounded per-orbit constant
``(λ_i − η)(λ_i − η̄)`` instead of ``det K`` of the step's own ``M0``; the constant's rounding error (a fixed
relative ~1e-17..3e-16) multiplied each site's Casimir by the same factor at every step."""

from __future__ import annotations

import numpy as np
import pytest

from jetgaudin.gaudin import GaudinModel
from jetgaudin.gaudin.maps import monic_series

MODEL = GaudinModel(1.0, [(-0.5, 1), (0.4, 2)])
ETA = 1.5 + 0.2j
X0 = 0.5 * np.random.default_rng(2026).normal(size=(64, 9))


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_the_order_one_sites_casimir_has_no_drift_on_average(backend):
    """Mean over 64 orbits of the relative change of the first site's Casimir ``h1,2 = |y_0|²`` after 3000 steps.
    With the rounded constant it was −4.8e-14 on both routes: 3000 × 2 × (−8e-18), the constant's
    measured per-step factor, and of one sign on every orbit; with ``1/det K`` of the step it is 1.8e-15 (a random
    walk of ~2e-16 per step over 64 orbits gives ~1e-15).  The bound 1e-14 lies between the two."""
    B = MODEL.two_point_backlund(ETA, kernel=backend)
    X = B.advance(X0, None, 3000, 3000).X
    I0 = MODEL.integrals(X0)[:, 1]
    change = (MODEL.integrals(X)[:, 1] - I0) / I0
    assert abs(change.mean()) < 1e-14, change.mean()


def test_scaled_two_point_K0_is_n2_times_the_normalised_M0(rng):
    """``scaled_two_point_K0`` returns ``n2 M0`` and ``n2``: ``M0`` the normalised ``real_two_point_M0`` of the same
    eigenvector, ``n2 = |k|²`` after ``k`` is scaled by a power of two into ``[1/4, 1)``, so that ``det(λ n2 +
    n2 M0) = n2² (λ − η)(λ − η̄)``.  Tolerance 1e-14 relative: a few roundings of O(1) numbers (each ~1.1e-16);
    a wrong sign, conjugate or factor 2 is O(1)."""
    from jetgaudin.backlund._dressing import real_two_point_M0
    from jetgaudin.gaudin._compensated import scaled_two_point_K0

    eta = 1.5 + 0.2j
    k1 = rng.normal(size=50) + 1j * rng.normal(size=50)
    k2 = (rng.normal(size=50) + 1j * rng.normal(size=50)) * 10.0 ** rng.integers(-8, 8, size=50)
    K0, n2 = scaled_two_point_K0(eta, k1, k2)
    assert np.all((n2 >= 0.25 * (1 - 1e-15)) & (n2 < 1.0))
    M0 = real_two_point_M0(eta, k1, k2)
    assert np.allclose(K0, n2[:, None, None] * M0, rtol=0, atol=1e-14 * np.max(np.abs(M0)))
    for lam in (-0.5, 0.4, 3.0):
        K = K0 + (n2 * lam)[:, None, None] * np.eye(2)
        det = K[:, 0, 0] * K[:, 1, 1] - K[:, 0, 1] * K[:, 1, 0]
        assert np.allclose(det / n2**2, (lam - eta) * (lam - np.conj(eta)), rtol=1e-14, atol=0)


def test_the_numpy_rational_chain_has_no_mean_drift():
    """Fast form of the next test: after 3000 steps of the NumPy rational chain, the mean over 64 orbits of each
    integral's relative change is below 2e-14 in size.  Measured: at most 7.4e-15, 3.6e-15 since the products with
    the decimal ``η`` and site are split (``times_split``; the standard error of the mean is
    ~2e-15: a random walk of ~1e-16 per step, sd ~1.7e-14 over the orbits); with the normalised ``M0`` (next test)
    −3.9e-14 on ``h2,1`` and −3.4e-14 on ``h2,2``, of one sign: the bound lies between the two."""
    B = MODEL.two_point_backlund(ETA, kernel="numpy")
    I0 = B.integrals(X0)
    change = (B.integrals(B.advance(X0, None, 3000, 3000).X) - I0) / np.maximum(1.0, np.abs(I0))
    assert np.max(np.abs(change.mean(axis=0))) < 2e-14, dict(zip(B.integral_names(), change.mean(axis=0),
                                                                 strict=True))


@pytest.mark.slow
def test_the_numpy_rational_chain_has_no_bias_per_step():
    """The NumPy rational chain (``kernel="numpy"``): after 10^4 steps, the mean over 64 orbits of each integral's
    relative change, in units of its standard error (sd over the orbits / 8), is below 5 in size: a random walk
    gives |z| ~ 1 (measured: at most 2.3 over the six integrals; 1.4 since the products with the decimal ``η`` and
    site are split), a rounding error of one sign at every step
    grows the mean like ``n`` and the standard error like ``√n``.  With the normalised ``M0`` (``K = |k|²(λ_i +
    M0)``, whose real diagonal part is ``|k|²`` times ``λ_i − Re η`` rounded once, the same error at every step) it
    was z = −11.5 on ``h2,1`` and −7.4 on ``h2,2`` (mean −1.3e-13 and −1.0e-13); with the second site moved to
    0.5, where ``λ_i − Re η = −1`` is exact, the old code gave |z| ≤ 0.85: the rounded constant is the cause."""
    B = MODEL.two_point_backlund(ETA, kernel="numpy")
    I0 = B.integrals(X0)
    change = (B.integrals(B.advance(X0, None, 10_000, 10_000).X) - I0) / np.maximum(1.0, np.abs(I0))
    z = change.mean(axis=0) / (change.std(axis=0) / np.sqrt(len(X0)))
    assert np.max(np.abs(z)) < 5, dict(zip(B.integral_names(), z.round(1), strict=True))


def test_monic_series_is_the_series_of_one_over_det_K(rng):
    """``monic_series``' ``g`` are the Taylor coefficients of ``1/det(λ + M0)`` at each site: ``(d_0 + d_1 z + z²)
    Σ g_m z^m = 1`` to round-off (1e-13 relative: a few operations per coefficient on O(1) numbers)."""
    m = GaudinModel(0.7, [(-1.0, 3), (0.5, 4)])
    M0 = rng.normal(size=(5, 2, 2)) + 1j * rng.normal(size=(5, 2, 2))
    A0 = np.stack([np.array([[a[1, 1], -a[0, 1]], [-a[1, 0], a[0, 0]]]) for a in M0])
    for (lam, N), (Ka, Aa, g) in zip(m.sites, monic_series(m, M0, A0), strict=True):
        K = M0 + lam * np.eye(2)
        d0 = K[:, 0, 0] * K[:, 1, 1] - K[:, 0, 1] * K[:, 1, 0]
        d1 = 2 * lam + M0[:, 0, 0] + M0[:, 1, 1]
        poly = np.zeros((N, 5), dtype=complex)
        for k in range(N):  # the coefficient of z^k of (d0 + d1 z + z^2) * g(z)
            poly[k] = d0 * g[k] + (d1 * g[k - 1] if k >= 1 else 0) + (g[k - 2] if k >= 2 else 0)
        assert np.allclose(poly[0], 1, rtol=0, atol=1e-13) and np.allclose(poly[1:], 0, rtol=0, atol=1e-13)
        assert np.array_equal(Ka[0], K) and np.array_equal(Aa[0], A0 + lam * np.eye(2))


@pytest.mark.parametrize("family, kw, b", [("rational", {}, 1.0), ("trigonometric", {"gamma": 1.0}, 1.0),
                                          ("elliptic", {"modulus": 0.6}, 0.0)])
def test_the_unnormalised_dressing_keeps_large_states_finite(family, kw, b):
    """The dressing matrix is left unnormalised (above) but scaled by a power of two to size 1: states of size 1e60
    (each product of the dressing would be ~|X|^5 ~ 1e300 unscaled) step to finite states on both routes, with the
    integrals kept to 1e-12 relative over 5 steps (round-off: ~1e-15 per step) and the routes agreeing to 1e-10."""
    m = GaudinModel(b, [(-0.5, 1), (0.4, 2)], family=family, **kw)
    X = 1e60 * np.random.default_rng(8).normal(size=(2, 9))
    rows = {r: m.two_point_backlund(ETA, kernel=r).iterate(X, 5) for r in ("numpy", "compiled")}
    for r, orbit in rows.items():
        assert np.all(np.isfinite(orbit)), r
        I = m.integrals(orbit)
        assert np.max(np.abs(I - I[0]) / np.abs(I[0])) < 1e-12, r
    assert np.max(np.abs(rows["numpy"] - rows["compiled"])) <= 1e-10 * np.abs(rows["numpy"]).max()


FAMILIES = {"rational": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)]),
            "trigonometric": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)], family="trigonometric", gamma=1.0),
            "elliptic": GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6)}


#: a site of order 2 at λ = 0: the rational basis entry λ vanishes there but its derivative does not (the mpmath
#: tables kept only the entries nonzero at the site, and lost it: the GPU chain route, which takes the family kernel
#: for the rational family too, stepped such a chain wrongly, 0.39 off after 3 steps)
AT_ZERO = {"rational": GaudinModel(1.0, [(0.0, 2), (0.7, 1)]),
           "trigonometric": GaudinModel(1.0, [(0.0, 2), (0.7, 1)], family="trigonometric", gamma=1.0),
           "elliptic": GaudinModel(0.0, [(0.0, 2), (0.7, 1)], family="elliptic", modulus=0.6)}


@pytest.mark.parametrize("family, m", [(f, m) for models in (FAMILIES, AT_ZERO) for f, m in models.items()])
def test_the_family_kernels_two_word_constants_are_the_familys_functions(family, m):
    """The family kernel's constants as two words ``hi + lo`` (``gaudin._family_kernel.orbit_constants``, from the
    family's mpmath functions) are the double constants of the family's own NumPy functions (``phi``,
    ``kernel_constants``, ``dressing_taylor``) to 1e-14 relative (those are accurate to a few 1e-16; the elliptic
    ones, assembled from SciPy's real Jacobi functions, to ~1e-15 — ``tests/test_jacobi.py``), and each low word is
    below 2^-52 of its high word (``hi`` the nearest double): a wrong mpmath formula (a sign, a factor ``γ``, the
    wrong Jacobi function) fails the first check.  Every entry of the dressing's Taylor tables is compared, an
    entry the tables leave at zero too."""
    from jetgaudin.gaudin._family_kernel import orbit_constants

    xi = ETA
    fam = m.family
    f, _, gk, T, pidx, P, _, _ = orbit_constants(m, xi)
    f_np = np.zeros((3, m.M), dtype=complex)
    full = np.zeros((len(m.sites), max(m.orders), P, 4), dtype=complex)
    for i, (p, N) in enumerate(m.sites):
        for a in range(3):
            f_np[a, m.offsets[i]:m.offsets[i] + N] = fam.phi(a + 1, xi - p, N)
        Ti = fam.dressing_taylor(p, N, xi) if fam.dressing_needs_xi else fam.dressing_taylor(p, N)
        full[i, :N] = Ti.reshape(N, P, 4)
    gk_np = fam.kernel_constants(xi)
    G = len(gk) // 2
    assert np.allclose(f[:3], f_np, rtol=1e-14, atol=0) and np.allclose(gk[:G], gk_np, rtol=1e-14, atol=0)
    for e in range(4):
        for t in range(0, T.shape[-1], 2):  # interleaved: high word at t, low word at t + 1
            assert pidx[e, t] == pidx[e, t + 1]
            want = full[:, :, pidx[e, t], e] if np.any(T[:, :, e, t]) else 0 * T[:, :, e, t]
            assert np.allclose(T[:, :, e, t], want, rtol=1e-14, atol=1e-300)
    for e in range(4):  # and every basis matrix that feeds entry e is in the tables, with its values
        for p in range(P):
            if np.any(full[:, :, p, e]):
                t = [t for t in range(0, T.shape[-1], 2) if pidx[e, t] == p]
                assert t and np.allclose(T[:, :, e, t[0]], full[:, :, p, e], rtol=1e-14, atol=1e-300), (p, e)
    for hi, lo in ((f[:3], f[3:]), (gk[:G], gk[G:]), (T[..., 0::2], T[..., 1::2])):
        assert np.all(np.abs(lo) <= 2.0**-52 * np.abs(hi))


def _largest_drift(m, X0, ns):
    """The running largest relative drift over the orbits and integrals at each ``n`` in ``ns`` (compiled route)."""
    B = m.two_point_backlund(ETA, kernel="compiled")
    I0 = m.integrals(X0)
    X, carry, done, worst, out = X0, None, 0, 0.0, []
    for n in ns:
        adv = B.advance(X, carry, n - done, n - done)
        X, carry, done = adv.X, adv.carry, n
        worst = max(worst, float(np.max(np.abs(m.integrals(X) - I0) / np.maximum(1.0, np.abs(I0)))))
        out.append(worst)
    return out


def _exponent(ns, d):
    return float(np.polyfit(np.log(ns), np.log(d), 1)[0])


@pytest.mark.slow
@pytest.mark.parametrize("family", ["trigonometric", "elliptic"])
def test_the_family_kernels_drift_grows_like_a_random_walk(family, monkeypatch):
    """The exponent ``p`` of ``largest drift ~ n^p`` over 64 orbits, ``n = 10³ … 10⁵`` (the fit of
    ``benchmarks/chain_drift.py``): measured 0.54 (trigonometric) and 0.51 (elliptic) with the two-word constants
    and compensated sums, 0.97 and 0.89 with the constants rounded once and summed plainly (before; a random walk
    gives 1/2, a bias 1).  The bound 0.65 is the issue's; the fit over 5 points of a running maximum scatters by
    ~0.05 (seeds tried by hand).  The planted bug (the low words set to zero: the constants rounded once) is run
    here too and must fit above 0.65."""
    from jetgaudin.gaudin import _family_kernel as F
    from jetgaudin.gaudin import maps

    ns = [1000, 3162, 10000, 31623, 100000]
    m = FAMILIES[family]
    maps._orbit_constants.cache_clear()
    assert _exponent(ns, _largest_drift(m, X0, ns)) <= 0.65
    real = F.orbit_constants

    def rounded_once(model, xi):  # the planted bug: the constants as the nearest doubles only
        f, rule, gk, T, pidx, P, so, sn = real(model, xi)
        G = len(gk) // 2
        f, gk, T = f.copy(), gk.copy(), T.copy()
        f[3:], gk[G:], T[..., 1::2] = 0, 0, 0
        return f, rule, gk, T, pidx, P, so, sn

    monkeypatch.setattr(F, "orbit_constants", rounded_once)
    maps._orbit_constants.cache_clear()
    try:
        assert _exponent(ns, _largest_drift(m, X0, ns)) > 0.65
    finally:
        maps._orbit_constants.cache_clear()


def test_the_compensated_sums_are_the_exact_sums_rounded_once():
    """``s + e`` of the kernels' compensated sum (``gaudin._kernels._acc``, compiled) and of the NumPy route's
    (``gaudin._compensated.acc``) over 3 terms ``a_j (bh_j + bl_j)``, a two-word constant each, is the exact sum rounded
    once: within 1 ulp of the 40-digit value on every one of 2000 random draws, and unbiased — the mean signed error
    below 0.05 ulp (round-to-nearest: ~0.29 ulp spread / √2000 ≈ 0.006 ulp), where the plain sum of the rounded
    products ``Σ fl(a_j bh_j)`` misses by the constants' own relative error, the same at every draw (here the low
    words are drawn as a fixed +0.4 ulp of each constant, so the plain sum is biased by ~0.4 ulp)."""
    import mpmath
    from numba import njit

    from jetgaudin.gaudin import _compensated as C
    from jetgaudin.gaudin import _kernels as K

    @njit(cache=False)
    def compiled(a, bh, bl):
        s, e = 0.0, 0.0
        for j in range(a.shape[0]):
            s, e = K._acc(s, e, a[j], bh[j], bl[j])
        return s + e

    rng = np.random.default_rng(33)
    bh = rng.uniform(1, 2, 3)
    bl = 0.4 * np.spacing(bh)  # a fixed relative error: a constant rounded down by 0.4 ulp
    A = rng.uniform(0.5, 1, (2000, 3))
    errs = {"compiled": [], "numpy": [], "plain": []}
    with mpmath.workdps(40):
        for a in A:
            exact = sum(mpmath.mpf(x) * (mpmath.mpf(h) + mpmath.mpf(lo)) for x, h, lo in zip(a, bh, bl, strict=True))
            ulp = np.spacing(float(exact))
            s, e = 0.0, 0.0
            for j in range(3):
                s, e = C.acc(s, e, a[j], bh[j], bl[j])
            for name, v in (("compiled", compiled(a, bh, bl)), ("numpy", s + e), ("plain", float(np.sum(a * bh)))):
                errs[name].append(float((mpmath.mpf(v) - exact) / ulp))
    for name in ("compiled", "numpy"):
        err = np.array(errs[name])
        assert np.max(np.abs(err)) <= 1.0 and abs(err.mean()) < 0.05, (name, np.max(np.abs(err)), err.mean())
    assert np.mean(errs["plain"]) < -0.2  # the bias the two words remove (a check that the test can fail)


def test_the_kernels_products_with_two_word_constants_are_rounded_once_and_unbiased():
    """The chain kernels' cheap form (``gaudin._kernels._tw``, ``_ctw``; ``docs/reliability.md``, "Compensated sums:
    the cost"): ``_tw(a, bh, bl) = fma(a, bh, fl(a·bl))`` is ``a·(bh + bl)`` rounded once — within 0.5 ulp (plus
    ``fl(a·bl)``'s own ~2^-106 relative error: the bound 0.501) on every one of 2000 draws, and unbiased (mean signed
    error below 0.05 ulp: round-to-nearest spreads ~0.29 ulp, / √2000 ≈ 0.006); a sum of 3 such terms in plain
    double is within 2 ulp (two more roundings) and as unbiased.  ``_ctw`` (complex, each part two roundings of
    quantities that vary with ``a``) is within 1.5 ulp of ``|a_r h| + |a_i h|`` and unbiased.  The low words are a
    fixed ±0.4 ulp of each constant, so the plain ``fl(a·bh)`` is biased by ~0.4 ulp (checked: the test can fail)."""
    import mpmath
    from numba import njit

    from jetgaudin.gaudin import _kernels as K

    @njit(cache=False)
    def sum3(a, bh, bl):
        s = 0.0
        for j in range(a.shape[0]):
            s += K._tw(a[j], bh[j], bl[j])
        return s

    @njit(cache=False)
    def one(a, bh, bl):
        return K._tw(a, bh, bl)

    @njit(cache=False)
    def cone(a, h, lo):
        return K._ctw(a, h, lo)

    rng = np.random.default_rng(34)
    bh = rng.uniform(1, 2, 3)
    bl = 0.4 * np.spacing(bh)
    A = rng.uniform(0.5, 1, (2000, 3))
    h = complex(rng.uniform(1, 2), rng.uniform(1, 2))
    lo = complex(0.4 * np.spacing(h.real), -0.4 * np.spacing(h.imag))  # biases add up in the real part
    Z = rng.uniform(0.5, 1, (2000, 2)) @ np.array([1, 1j])
    e1, e3, ep, ec = [], [], [], []
    with mpmath.workdps(40):
        mh = mpmath.mpc(h.real, h.imag) + mpmath.mpc(lo.real, lo.imag)
        for a, z in zip(A, Z, strict=True):
            ex = [mpmath.mpf(x) * (mpmath.mpf(hh) + mpmath.mpf(ll)) for x, hh, ll in zip(a, bh, bl, strict=True)]
            e1.append(float((mpmath.mpf(one(a[0], bh[0], bl[0])) - ex[0]) / np.spacing(float(ex[0]))))
            ep.append(float((mpmath.mpf(a[0] * bh[0]) - ex[0]) / np.spacing(float(ex[0]))))
            e3.append(float((mpmath.mpf(sum3(a, bh, bl)) - sum(ex)) / np.spacing(float(sum(ex)))))
            exc = mpmath.mpc(z.real, z.imag) * mh
            got = cone(z, h, lo)
            for g, x, scale in ((got.real, exc.real, abs(z.real * h.real) + abs(z.imag * h.imag)),
                                (got.imag, exc.imag, abs(z.real * h.imag) + abs(z.imag * h.real))):
                ec.append(float((mpmath.mpf(g) - x) / np.spacing(scale)))
    for name, err, bound in (("_tw", e1, 0.501), ("sum of 3", e3, 2.0), ("_ctw", ec, 1.5)):
        err = np.array(err)
        assert np.max(np.abs(err)) <= bound and abs(err.mean()) < 0.05, (name, np.max(np.abs(err)), err.mean())
    assert np.mean(ep) < -0.2  # the bias the low word removes


def _chain_drift_module():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "chain_drift.py"
    spec = importlib.util.spec_from_file_location("_test_chain_drift_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_persistence_score_tells_an_orbitwise_bias_from_a_random_walk(rng):
    """``benchmarks/chain_drift.py --persistence`` (docs/reliability.md, "Drift like round-off"): the mean
    correlation over the orbits of the changes in two quarters.  Synthetic changes ``(4, 64, 2)``: independent steps
    of a random walk give a score near 0 (the correlation of 64 pairs has sd ~1/√61 = 0.13; the mean of six pairs
    is within ±0.3 at > 3 sd), a drift per orbit of random sign twice the walk's size gives > 0.6 (the expected
    correlation is 4/(4 + 1) = 0.8, the sd again ~0.1).  Planted: the quarters' changes taken from different
    orbits (the orbits shuffled between quarters) give ~0 for the drift too and fail."""
    cd = _chain_drift_module()
    walk = rng.normal(size=(4, 64, 2))
    bias = 2.0 * rng.choice([-1.0, 1.0], size=(1, 64, 2)) * rng.uniform(0.5, 1.5, size=(1, 64, 2))
    assert np.all(np.abs(cd.persistence(walk)) < 0.3), cd.persistence(walk)
    assert np.all(cd.persistence(walk + bias) > 0.6), cd.persistence(walk + bias)


def test_quarter_changes_add_up_to_the_whole_change():
    """``quarter_changes`` returns each quarter's change (a difference of the cumulative changes), so that the four
    add up to the change over all ``n`` steps, relative to ``max(1, |I_0|)`` (100 steps of the NumPy rational chain,
    64 orbits; the cumulative changes evaluated here on the same rows, ``integrals`` of a different batch shape
    rounds differently at ~2e-16).  Tolerance 1e-29 absolute: the changes are ~1e-15 and the differences and their
    sum round at ~1e-31; a cumulative change returned in place of the quarter's is off by ~1e-15."""
    cd = _chain_drift_module()
    B = MODEL.two_point_backlund(ETA, kernel="numpy")
    q = cd.quarter_changes(B, X0, 100)
    I0 = B.integrals(X0)
    rows = B.advance(X0, None, 100, 25).rows
    cumulative = (B.integrals(rows) - I0) / np.maximum(1.0, np.abs(I0))
    assert q.shape == (4, 64, 6) and np.array_equal(rows[-1], B.advance(X0, None, 100, 100).X)
    assert np.mean(cumulative[-1] != 0) > 0.5  # changes to add up
    assert np.allclose(q.sum(axis=0), cumulative[-1], rtol=0, atol=1e-29)
    assert np.array_equal(q[0], cumulative[0])


@pytest.mark.parametrize("route", ["compiled", "numpy"])
def test_products_with_a_decimal_constant_are_unbiased_when_split(route):
    """``_split`` (gaudin/_kernels.py) and its NumPy twin ``split_constant`` / ``times_split``
    (gaudin/_compensated.py): ``fl(0.2·x)`` over 2·10⁶ uniformly random mantissas of ``x`` is low by
    0.006 ulp on average (measured −0.00617; the standard error is 0.0002 ulp: a bias of 30 standard errors, because
    ``0.2`` is the double nearest 1/5 and the dropped bits are those of ``x·4/5 mod 1``); ``_tw(x, *_split(0.2))``
    is unbiased, and so is ``times_split(x, *split_constant(0.2))`` (the same bits: ``fma`` emulated with Dekker's
    product and TwoSum).  Bounds: the plain product below −0.004 ulp (10 se from its value), the split one within
    ±0.0015 ulp (7 se).  The errors exact from Dekker's product (``c·x = p + e``; ``r − p`` is exact, ``r`` within an
    ulp of ``p``).  Planted: ``_split`` or ``split_constant`` returning ``(c, 0)`` (the plain product) fails."""
    from jetgaudin.gaudin._compensated import split_constant, times_split, two_prod

    if route == "compiled":
        from numba import njit

        from jetgaudin.gaudin import _kernels as K

        @njit(cache=False)
        def split_products(x, c):
            out = np.empty_like(x)
            a, b = K._split(c)
            for i in range(x.shape[0]):
                out[i] = K._tw(x[i], a, b)
            return out
    else:
        def split_products(x, c):
            return times_split(x, *split_constant(c))

    rng = np.random.default_rng(5)
    x = np.ldexp((2**52 + rng.integers(0, 2**52, 2_000_000, dtype=np.int64)).astype(float), -53)  # [1/2, 1)
    c = np.full_like(x, 0.2)
    p, e = two_prod(c, x)
    ulp = np.spacing(np.abs(p))
    plain = (-e / ulp).mean()
    split = (((split_products(x, 0.2) - p) - e) / ulp).mean()
    assert plain < -0.004, plain
    assert abs(split) < 0.0015, split


def test_the_numpy_split_product_is_the_kernels_bit_for_bit(rng):
    """``times_split(x, *split_constant(c))`` (NumPy: Dekker's product and TwoSum) is the compiled
    ``_tw(x, *_split(c))`` (a fused multiply-add) bit for bit: ``fma`` emulated, correctly rounded but where the low
    part's own rounding falls on a tie (none among these draws), and the same split (one ``KAPPA``).  2·10⁵ draws of
    ``x`` of both signs over 40 binades, five constants (decimals, an exact binary one, a negative one).  Exact
    comparison: the claim is the same bits.  Planted: ``times_split`` without the TwoSum error (``fl(p + y) + e``)
    differs on some draws."""
    from numba import njit

    from jetgaudin.gaudin import _kernels as K
    from jetgaudin.gaudin._compensated import split_constant, times_split

    @njit(cache=False)
    def compiled(x, c):
        out = np.empty_like(x)
        a, b = K._split(c)
        for i in range(x.shape[0]):
            out[i] = K._tw(x[i], a, b)
        return out

    x = rng.choice([-1.0, 1.0], 200_000) * np.ldexp(rng.uniform(0.5, 1.0, 200_000), rng.integers(-20, 20, 200_000))
    for c in (0.2, 0.4, 1.7, 1.5, -0.5):
        assert split_constant(c) == K._split(c)
        assert np.array_equal(times_split(x, *split_constant(c)), compiled(x, c)), c


def test_the_numpy_routes_products_with_eta_and_the_sites_are_unbiased(rng):
    """The NumPy rational route rounds each product with ``Im η``, ``2 Im η`` and a site as the compiled kernel does
    (``times_split``; ``docs/reliability.md``, "The rational chain's bias per orbit"): read off the route's own
    functions at inputs where an entry is exactly one such product — ``Im K0_00 = −Im η·n2`` at ``k2 = 0``,
    ``Im K0_01 / p2 = −2 Im η·k1`` at ``k1`` real and ``k2 = 1`` (scaled by the power of two ``p2``, exact), and
    ``K(λ_i) = s λ_i`` of ``monic_series(scaled=True)`` at ``M0 = 0`` — with ``η = 1.5 + 0.2i`` and the site 0.4
    (decimals) over 2·10⁶ draws each, the mean signed error (towards zero negative) is within ±0.003 ulp.  Measured
    (four seeds): 0.0002–0.0004, 0.0011–0.0014, −0.0007–−0.0010 ulp in the order above — the dither of ``fl(x·b)``
    spans less than an ulp, so a small bias remains on these non-uniform mantissas, 5–7 standard errors of 0.0002 —
    against −0.0135, −0.025, −0.006 for the plain products; the bound 0.003 lies between the two with ≥ 8 standard
    errors to spare on either side.  The plain product of the same inputs is checked to be below −0.004 ulp (the test
    can fail).  Planted: ``scaled_two_point_K0`` with ``-eta * n2`` and ``t * k1``
    (the plain products, as before the fix), ``monic_series`` with ``s * lam_i`` — each fails its case."""
    from jetgaudin.gaudin._compensated import scaled_two_point_K0, two_prod

    n = 2_000_000
    eta, site = 1.5 + 0.2j, 0.4
    k1 = rng.normal(size=n) + 1j * rng.normal(size=n)
    K0, n2 = scaled_two_point_K0(eta, k1, np.zeros(n))
    cases = {"Im η n2": (n2, 0.2, -K0[:, 0, 0].imag)}
    x = rng.uniform(-3, 3, n)
    K0, n2 = scaled_two_point_K0(eta, x.astype(complex), np.ones(n, dtype=complex))
    p2 = np.ldexp(1.0, -((np.frexp(x * x + 1)[1] + 1) // 2))  # the route's scaling of k (a power of two)
    assert np.array_equal(n2, (x * p2) ** 2 + p2 * p2)
    cases["2 Im η k1"] = (x * p2, 0.4, -K0[:, 0, 1].imag / p2)
    s = rng.uniform(0.25, 1.0, n)
    model = GaudinModel(1.0, [(site, 1)])
    z = np.zeros((n, 2, 2), dtype=complex)
    K = monic_series(model, z, z, s, scaled=True)[0][0][0]
    cases["site n2"] = (s, site, K[:, 0, 0].real)
    for name, (xs, c, got) in cases.items():
        p, e = two_prod(np.full_like(xs, c), xs)
        ulp = np.spacing(np.abs(p)) * np.sign(p)  # errors towards zero negative (the bias's sign at either sign of x)
        ok = p != 0
        plain = (-e[ok] / ulp[ok]).mean()
        bias = (((got[ok] - p[ok]) - e[ok]) / ulp[ok]).mean()
        assert plain < -0.004, (name, plain)
        assert abs(bias) < 0.003, (name, bias)


@pytest.mark.slow
def test_the_rational_chain_drifts_by_no_bias_per_orbit():
    """``benchmarks/chain_drift.py --persistence`` on the compiled rational chain (64 orbits, 10⁶ steps, ~30 s):
    the mean correlation over the orbits of the integrals' changes in two quarters is below 0.4 for every integral.
    Measured 0.22 at most (h2,1) with the products with ``η`` and the sites split (``_split``); with them rounded
    plainly 0.50 / 0.62 / 0.69 on h1,1 / h2,1 / h2,2: each orbit drifted linearly, the sign depending on the orbit
    (the ensemble mean, ``z``, stayed ≤ 3).  A random walk gives 0 ± ~0.1; the bound is between the two.  Planted:
    ``_split`` returning ``(c, 0)`` fails."""
    from jetgaudin.gaudin import GaudinModel as GM

    cd = _chain_drift_module()
    B = GM(1.0, [(-0.5, 1), (0.4, 2)]).two_point_backlund(1.5 + 0.2j, kernel="compiled")
    score = cd.persistence(cd.quarter_changes(B, cd.states(B, 64), 10**6))
    assert np.all(score < 0.4), score


@pytest.mark.parametrize("family, kw", [("trigonometric", {"gamma": 1.0}), ("elliptic", {"modulus": 0.6})])
def test_the_vectorised_compensated_sums_are_the_term_by_term_sums_bit_for_bit(family, kw):
    """``family_lax`` and ``family_site_series`` (``gaudin/_compensated.py``) sum all entries side by side, one NumPy
    call per term (the NumPy route's speed: issue 33, the NumPy drift runs to 10⁶); each entry must be the
    compensated sum of its own nonzero terms in increasing order, bit for bit (the arithmetic the drift fits measured).
    Reference: the sums entry by entry with :func:`acc` / :func:`cacc`, zero constants skipped.  Exact comparison:
    the same operations in the same order.  Planted: the low word dropped in either vectorised sum fails (the
    terms in reverse order do not: a compensated sum is the exact sum rounded once, whatever the order)."""
    from jetgaudin.gaudin._compensated import acc, cacc, exact_tables, family_lax, family_site_series

    model = GaudinModel(1.0 if family == "trigonometric" else 0.0, [(-0.5, 1), (0.4, 2)], family=family, **kw)
    X = 0.5 * np.random.default_rng(3).normal(size=(16, model.n_state))
    c = np.random.default_rng(4).normal(size=(16, model.family.n_dressing)) * (1 + 0.5j)
    f, T, _ = exact_tables(model, ETA)
    y = X.reshape(16, model.M, 3)
    L = family_lax(model, X, ETA)
    comp = []
    for a in range(3):
        z = np.zeros(16)
        sr, si, er, ei = z + (model.b if a == 2 else 0.0), z.copy(), z.copy(), z.copy()
        for k in range(model.M):
            sr, er = acc(sr, er, y[:, k, a], f[0, a, k].real, f[1, a, k].real)
            si, ei = acc(si, ei, y[:, k, a], f[0, a, k].imag, f[1, a, k].imag)
        comp.append((sr + er) + 1j * (si + ei))
    x1, x2, u = comp
    for got, ref in ((L[:, 0, 0], u), (L[:, 0, 1], x1 - 1j * x2), (L[:, 1, 0], x1 + 1j * x2), (L[:, 1, 1], -u)):
        assert np.array_equal(got, ref)
    series = family_site_series(model, c, ETA)
    for i, (_, N) in enumerate(model.sites):
        for n in range(N):
            for e in range(4):
                z = np.zeros(16)
                sr, si, er, ei = z, z.copy(), z.copy(), z.copy()
                for p in range(c.shape[-1]):
                    if T[0, i, n, p, e] != 0:
                        sr, si, er, ei = cacc(sr, si, er, ei, c[:, p], T[0, i, n, p, e], T[1, i, n, p, e])
                assert np.array_equal(series[i][0][n][:, e // 2, e % 2], (sr + er) + 1j * (si + ei)), (i, n, e)


def test_the_drift_runs_persistence_is_that_of_its_quarters_and_survives_a_restart(tmp_path):
    """``drift_curve`` (benchmarks/chain_drift.py, the long NumPy runs) stops at the quarters of its last ``n`` and
    returns their persistence score: the score of the quarters' changes of the same orbits computed here, a quarter
    per call (to 1e-12: the same integrals of the same states, the correlations' roundings aside; the integrals of
    the same states stored otherwise, as the rows of one call, round differently by ~1e-16, a tenth of the changes).
    A run killed after some chunks and started again with its checkpoint gives the same drift curve, ``z`` and score
    as an unkilled run, bit for bit (the quarters' changes are kept in the checkpoint).  Planted: the quarters'
    changes left out of the checkpoint (the restarted run has no score), the score taken from the cumulative changes
    instead of each quarter's — each fails."""
    cd = _chain_drift_module()
    B = MODEL.two_point_backlund(ETA, kernel="numpy")
    X0 = cd.states(B, 16)
    ns = [200, 400]
    d, z, pers = cd.drift_curve(B, X0, ns)
    I0 = B.integrals(X0)
    X, carry, cum = X0, None, []
    for _ in range(4):
        adv = B.advance(X, carry, 100, 100)
        X, carry = adv.X, adv.carry
        cum.append((B.integrals(X) - I0) / np.maximum(1.0, np.abs(I0)))
    ref = cd.persistence(np.diff(np.stack([0 * cum[0]] + cum), axis=0))
    assert pers is not None and np.allclose(pers, ref, rtol=0, atol=1e-12), (pers, ref)
    assert np.max(np.abs(pers)) > 0.01  # scores to compare (not all zero)

    class Killed(Exception):
        pass

    calls = [0]

    class Dying:  # the map, killed at its 5th chunk (after the first quarter's mark at 100 steps)
        def integrals(self, X):
            return B.integrals(X)

        def advance(self, X, carry, k, se):
            calls[0] += 1
            if calls[0] == 5:
                raise Killed
            return B.advance(X, carry, k, se)

    ck = str(tmp_path / "ck.npz")
    with pytest.raises(Killed):
        cd.drift_curve(Dying(), X0, ns, None, 30, ck)
    assert calls[0] == 5
    d2, z2, pers2 = cd.drift_curve(B, X0, ns, None, 30, ck)
    assert d2 == d and z2 == z and pers2 is not None and np.array_equal(pers2, pers)


@pytest.mark.slow
def test_the_numpy_elliptic_chain_has_no_bias_per_step():
    """The NumPy elliptic chain (``kernel="numpy"``, k = 0.6, the module's sites and ``η``): after 8000 steps of 2048
    orbits, the mean of each integral's relative change in units of its standard error is below 4.5 in size (a random
    walk: |z| ~ N(0, 1) per integral, max over 7 beyond 4.5 with probability ~5e-5).  The null vector of the
    spectrality system by the SVD (LAPACK's rounding) gave |z| = 5.0 at 4000 steps on two seeds and grew with ``n``
    (`docs/reliability.md`, issue 33 item 3); by the cofactors of three rows (``spectral_null_vector`` now, as the
    compiled kernel) ≤ 1.6 at 4000 steps on the same seeds.  This test: max |z| 1.7; with the SVD planted back 7.1."""
    model = GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6)
    B = model.two_point_backlund(ETA, kernel="numpy")
    X = 0.5 * np.random.default_rng(7).normal(size=(2048, model.n_state))
    I0 = B.integrals(X)
    change = (B.integrals(B.advance(X, None, 8000, 8000).X) - I0) / np.maximum(1.0, np.abs(I0))
    z = change.mean(axis=0) / (change.std(axis=0) / np.sqrt(len(X)))
    assert np.max(np.abs(z)) < 4.5, dict(zip(B.integral_names(), z.round(1), strict=True))
