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
