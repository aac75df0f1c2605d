"""Jacobi elliptic functions of complex argument (jetgaudin.families._jacobi) against mpmath (30 digits)."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from jetgaudin._errors import InvalidParameterError
from jetgaudin.families import _jacobi as J

mp.mp.dps = 30  # the reference: 30 digits, so that its own error is far below the tolerances


def _mp_w(a, x, k):
    sn, cn, dn = (mp.ellipfun(f, mp.mpc(x), k=mp.mpf(k)) for f in ("sn", "cn", "dn"))
    return (1 / sn, dn / sn, cn / sn)[a]


def _rel(a, b):
    return abs(complex(a) - complex(b)) / (1 + abs(complex(b)))


# relative error (to 1 + |value|) at these 40 points, measured: 5e-16 (k = 0), 9e-16 (0.3), 1.1e-15 (0.8), 7e-15
# (0.99), 9e-14 (1e-4), 1.1e-11 (0.999999: Cephes' cos of the amplitude near K), 1.5e-11 (1e-6: near the pole rows,
# Cephes' first-order m -> 1 expansion for the complementary modulus).  Tolerances: a factor ~10 above these.
ACCURACY = [(0.0, 1e-14), (1e-4, 1e-12), (0.3, 1e-14), (0.8, 1e-14), (0.99, 1e-13), (0.999999, 2e-10), (1e-6, 2e-10)]


@pytest.mark.parametrize("k, tol", ACCURACY)
def test_sn_cn_dn_and_w_against_mpmath(k, tol):
    rng = np.random.default_rng([24, int(k * 1e6)])
    K, Kp = J.periods(k)
    ym = Kp if np.isfinite(Kp) else 4.0
    u = rng.uniform(-4 * K, 4 * K, 40) + 1j * rng.uniform(-2 * ym, 2 * ym, 40)
    s, c, d = J.ellipfun(u, k)
    w = J.w_values(u, k)
    for i, ui in enumerate(u):
        ref = [mp.ellipfun(f, mp.mpc(ui), k=mp.mpf(k)) for f in ("sn", "cn", "dn")]
        assert max(_rel(x, r) for x, r in zip((s[i], c[i], d[i]), ref, strict=True)) <= tol
        assert max(_rel(w[a, i], _mp_w(a, ui, k)) for a in range(3)) <= tol


@pytest.mark.parametrize("k", [0.3, 0.8])
def test_w_near_the_poles_and_zeros_of_sn(k):
    """w_a stay accurate within 1e-6 of a pole of sn (iK', K + iK': w finite there) and of a zero of sn (w ~ 1/x):
    relative error <= 1e-12 (the pole of sn is cancelled in the ratios N_d/N_s; 1e-6 offsets lose ~6 digits in
    the absolute position only).  Not near the zero 2K: there the rounding of 2K itself (~1e-16) is amplified by
    the condition number 1/|x - 2K| of the pole, which is no error of the functions."""
    K, Kp = J.periods(k)
    pts = np.array([1j * Kp + 1e-6, 1j * Kp + 1e-6j, K + 1j * Kp - 1e-6, 1e-6 + 1e-6j, 1j * Kp])
    w = J.w_values(pts, k)
    for i, x in enumerate(pts):
        for a in range(3):
            assert _rel(w[a, i], _mp_w(a, x, k)) <= 1e-12, (a, x)


def test_trigonometric_limit_k0():
    """k = 0: sn = sin, cn = cos, dn = 1 and w = (1/sin, 1/sin, cot) to round-off (1e-14 relative)."""
    u = np.array([0.3 + 0.4j, -2.0 + 1.5j, 5.0 - 3.0j])
    s, c, d = J.ellipfun(u, 0.0)
    assert np.allclose(s, np.sin(u), rtol=1e-14, atol=0) and np.allclose(c, np.cos(u), rtol=1e-14, atol=0)
    assert np.allclose(d, 1.0, rtol=0, atol=1e-15)
    w = J.w_values(u, 0.0)
    assert np.allclose(w, [1 / np.sin(u), 1 / np.sin(u), 1 / np.tan(u)], rtol=1e-14, atol=0)
    assert J.periods(0.0) == (np.pi / 2, np.inf)


@pytest.mark.parametrize("k", [0.0, 0.5, 0.9])
def test_w_taylor_against_mpmath(k):
    """Taylor coefficients (order 7) at points of both branches of w_taylor (near a pole row of sn: |Im| > K'/2):
    mpmath.taylor (numerical differentiation at 30 digits); 1e-13 relative to 1 + |c_n| (ODE recursion and series
    division in double precision)."""
    K, Kp = J.periods(k)
    Kp = Kp if np.isfinite(Kp) else 3.0
    pts = np.array([0.4 + 0.3j, -1.1 - 0.2j, 0.3 + 0.8 * Kp * 1j, -0.7 - 0.7 * Kp * 1j, 3 * K + 0.1 + 2.6j * Kp])
    T = J.w_taylor(pts, k, 7)
    for i, x in enumerate(pts):
        for a in range(3):
            ref = mp.taylor(lambda t, a=a: _mp_w(a, t, k), mp.mpc(x), 6)
            assert max(_rel(T[a, n, i], ref[n]) for n in range(7)) <= 1e-13


@pytest.mark.parametrize("k", [0.0, 0.6])
def test_regular_parts_at_zero(k):
    """w_a - 1/x at 0: the closed forms of the first coefficient, (1 + k^2)/6, (1 - 2k^2)/6, -(2 - k^2)/6 (DLMF
    22.20 / A&S 16.22 expansions), exactly to round-off, and the next ones against mpmath.taylor of x w_a(x)."""
    R = J.w_regular(k, 6)
    assert np.allclose(R[:, 1], [(1 + k * k) / 6, (1 - 2 * k * k) / 6, -(2 - k * k) / 6], rtol=0, atol=1e-16)
    assert np.all(R[:, ::2] == 0)  # odd functions
    for a in range(3):
        ref = mp.taylor(lambda t, a=a: t * _mp_w(a, t, k) if t != 0 else mp.mpf(1), 0, 7)
        assert max(abs(R[a, n] - float(mp.re(ref[n + 1]))) for n in range(6)) <= 1e-14


def _mp_zeta(u, k):
    """Z(u) = ∫_0^u dn^2 - (E/K) u on the straight path (no pole on it for the points used)."""
    u, m = mp.mpc(u), mp.mpf(k) ** 2
    return mp.quad(lambda t: mp.ellipfun("dn", t * u, m=m) ** 2 * u, [0, 1]) - mp.ellipe(m) / mp.ellipk(m) * u


@pytest.mark.parametrize("k", [0.3, 0.8])
def test_zeta_and_curve_function_against_mpmath(k):
    """Z at complex points (addition theorem + imaginary transformation) and F = cs dn + Z with its Taylor series
    against the quadrature definition, also in the pole rows' neighbourhood (|Im| > K'/2, the shifted form):
    1e-12 absolute (|Z| <= ~20 at these points)."""
    Kp = J.periods(k)[1]
    pts = np.array([0.3 + 0.4j, 1.5 - 1.0j, -2.0 + 0.7j, 3.7 + 0.2j, 0.4 + 0.8j * Kp, -0.5 - 0.95j * Kp])
    Z = J.jacobi_zeta(pts, k)
    for i, u in enumerate(pts):
        assert abs(Z[i] - complex(_mp_zeta(u, k))) <= 1e-12
    # Taylor series of F = cs dn + Z: that of cs dn by mpmath.taylor, that of Z from Z(u) and Z' = dn^2 - E/K
    T = J.curve_function_taylor(pts[:2], k, 4)
    m = mp.mpf(k) ** 2
    for i, u in enumerate(pts[:2]):
        u = mp.mpc(u)
        csdn = mp.taylor(lambda t: _mp_w(2, t, k) * mp.ellipfun("dn", t, k=k), u, 3)
        dz = mp.taylor(lambda t: mp.ellipfun("dn", t, k=k) ** 2, u, 2)
        ref = [csdn[0] + _mp_zeta(u, k)] + [csdn[n] + (dz[n - 1] - (mp.ellipe(m) / mp.ellipk(m) if n == 1 else 0)) / n
                                            for n in range(1, 4)]
        assert max(abs(T[n, i] - complex(ref[n])) for n in range(4)) <= 1e-12


@pytest.mark.parametrize("k", [0.0, 0.5, 0.9])
def test_curve_function_periods_and_regularity(k):
    """F(x + 2K) = F(x), F(x + 2iK') = F(x) - i pi/K, F regular at iK' (its poles cancel), and F - 1/x odd with the
    derivative 1 - E/K - ns^2: all to 1e-12 (round-off of values of size ~10)."""
    K, Kp = J.periods(k)
    x = np.array([0.3 + 0.2j, -0.9 + 0.5j])
    F = J.curve_function(x, k)
    assert np.allclose(J.curve_function(x + 2 * K, k), F, rtol=0, atol=1e-12)
    if np.isfinite(Kp):
        assert np.allclose(J.curve_function(x + 2j * Kp, k), F - 1j * np.pi / K, rtol=0, atol=1e-12)
        near = J.curve_function(np.array([1j * Kp + 1e-3, 1j * Kp - 1e-3]), k)
        assert np.all(np.abs(near) < 10) and abs(near[0] + near[1] - 2 * near.mean()) < 1e-12
    else:
        assert np.allclose(F, 1 / np.tan(x), rtol=1e-14, atol=0)
    f = J.curve_function_regular(k, 5)
    assert abs(f[0]) < 1e-300 and f[2] == 0


def test_modulus_refused():
    for bad in (-0.1, 1.0, 1.5, float("nan"), 0.5j, True, "x"):
        with pytest.raises(InvalidParameterError, match="modulus"):
            J.check_modulus(bad)
