"""The N = 3 step's work cut for issue 36 ("a fifth session", docs/performance.md): the residual tolerance without
its square root, the residual ``e_A`` from the recurrence's own coefficients, and the unrolled integrals of the
drift pass.  Each against the form it replaces."""

import numba
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.backlund import kernels

_n3 = kernels.kernel_module("_n3")
_scalar = kernels.kernel_module("_scalar")


@numba.njit
def _tols(X, b, out):
    for i in range(X.shape[0]):
        x = X[i]
        out[i] = _n3._tol3(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], b[i] * b[i])


def _size(X, b):
    """``max_m |ℓ_m|`` in NumPy: ``|b|``, and per jet ``|y³|`` and ``|y¹ + i y²|``."""
    y = X.reshape(len(X), 3, 3)
    return np.maximum(np.abs(b), np.max(np.maximum(np.abs(y[:, :, 2]), np.hypot(y[:, :, 0], y[:, :, 1])), axis=1))


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3, 1e100])
def test_the_tolerance_bounds_the_complex_routes_from_above_by_at_most_twice(scale):
    # t = 2 (1e-8)² (1 + s²) against the complex route's (1e-8 (1 + s))²: (1 + s)² <= 2 (1 + s²) <= 2 (1 + s)²,
    # so old <= t <= 2 old; the computed t has a few roundings (relative 4 eps allowed) and equals the formula
    rng = np.random.default_rng(36)
    X = rng.normal(size=(4000, 9)) * scale * rng.uniform(0.01, 1, size=(4000, 1))
    b = rng.normal(size=4000) * scale
    t = np.empty(4000)
    _tols(X, b, t)
    s = _size(X, b)
    old = (1e-8 * (1.0 + s)) ** 2
    assert np.all(t >= old * (1 - 4e-16))
    assert np.all(t <= 2 * old * (1 + 4e-16))
    np.testing.assert_allclose(t, 2e-16 * (1.0 + s * s), rtol=4e-16 * 8)


@numba.njit
def _consts(eta, out):  # the blocks have no CPython wrapper: called from compiled code
    c = _n3._constants3(eta)
    for i in range(_n3.NCONST):
        out[i] = c[i]


@pytest.mark.parametrize("eta", [5.0 + 0.1j, 0.3 + 0.2j, -1.5 + 0.7j, 0.1 - 0.05j, 2.0 + 3.0j])
def test_the_recurrence_coefficients_are_the_residuals_scaled_by_s0(eta):
    # e_A = s0 ((−2c Z_d − s1 g) − δ1 h) = (α Z_d + ζ g) + γ h needs α = −2c s0, γ = −δ1 s0, ζ = −s1 s0 in both
    # directions of the division (|η| >= 1 bottom-up, else top-down): exact, the same products rounded once
    c = np.empty(_n3.NCONST)
    _consts(complex(eta), c)
    al, ga, ze, s0, s1, d1, m2c = c[9], c[10], c[11], c[12], c[13], c[14], c[16]
    assert al == m2c * s0
    assert ga == -(d1 * s0)
    assert ze == -(s1 * s0)
    assert (c[8] == 1.0) == (abs(eta) >= 1.0)


@numba.njit
def _both_integrals(X, b, a, u):
    for i in range(X.shape[0]):
        _scalar._integrals(X[i], b[i], 3, a[i])
        _scalar._integrals3(X[i], b[i], u[i])


def test_the_unrolled_integrals_are_the_loops_bits_and_jg_integrals():
    # bit for bit the loop form (the same sums in the same order), and jg.integrals to round-off (1e-13 relative:
    # a few roundings of O(1) sums)
    rng = np.random.default_rng(3)
    X = rng.normal(size=(500, 9))
    X[:7, 4] = [0.0, -0.0, 1e-310, 1e300, np.inf, np.nan, -1.0]  # special values: the same bits, NaN where NaN
    b = rng.normal(size=500)
    a, u = np.empty((500, 6)), np.empty((500, 6))
    _both_integrals(X, b, a, u)
    assert np.array_equal(a.view(np.int64), u.view(np.int64))
    for i in range(7, 20):
        ref = np.asarray(jg.integrals(X[i], b[i]))
        np.testing.assert_allclose(u[i], ref, rtol=1e-13, atol=1e-13)


def test_the_lanes_drift_is_the_single_orbit_routes():
    # the ensemble's drift pass (unrolled integrals, scratch from the caller) against the single-orbit route's, bit
    # for bit, orbit by orbit, with saved rows in between
    rng = np.random.default_rng(11)
    B = 40
    X = 0.5 * rng.normal(size=(B, 9))
    b = np.full(B, 0.8)
    eta = 1.7 + rng.uniform(-0.3, 0.3, B) + 0.2j
    nu0 = kernels.nu_default(X, b, eta, 1)
    out, final, drift, nu_last, status, fail = kernels.run_batch(X, b, eta, nu0, False, 60, 20)
    assert not status.any()
    single = kernels.kernel_module("_n3").run_orbit3
    for i in range(B):
        o, f, d = np.empty((4, 9)), np.empty(9), np.empty(6)
        single(X[i], b[i], eta[i], nu0[i], False, 60, 20, o, f, d, True)
        assert np.array_equal(d, drift[i])
        assert np.all(d < 1e-12)  # a drift of round-off: 60 steps of a map that preserves these integrals


@pytest.mark.parametrize("size", [1e140, 1e165, 1e200, 1e300])
def test_huge_states_fail_in_the_lanes_as_on_the_single_orbit_route(size):
    # whether a lane steps reaches the dressing in the sign of r = 1/(q|k|²) (q = 0 beyond ~1e162): huge lanes must
    # step and fail as on the single-orbit route, never be left unstepped with status 0, beside ordinary lanes of
    # the same blocks; statuses, failing steps and final states equal exactly, lane by lane
    rng = np.random.default_rng(5)
    B = 19
    X = rng.normal(size=(B, 9))
    X[::3] *= size  # every third orbit huge, the others ordinary, in the same blocks
    b = np.full(B, 0.9)
    eta = np.full(B, 1.3 + 0.4j)
    small = X.copy()
    small[::3] /= size
    nu0 = kernels.nu_default(small, b, eta, 1)  # (the branch rule overflows on the huge states: any ν0 serves here,
    nu0[::3] *= size  # both routes start from the same one)
    out, final, drift, nu_last, status, fail = kernels.run_batch(X, b, eta, nu0, False, 12, 4)
    single = kernels.kernel_module("_n3").run_orbit3
    for i in range(B):
        o, f, d = np.empty((4, 9)), np.empty(9), np.empty(6)
        st, n, _ = single(X[i], b[i], eta[i], nu0[i], False, 12, 4, o, f, d, False)
        assert (st, n) == (status[i], fail[i])
        assert np.array_equal(f, final[i])


def test_failures_late_in_the_orbit_are_recorded_at_their_step():
    # a lane's failure goes to the status row as its code + 8 × its step, read when the block ends (no row is read
    # right after the pass that wrote it): orbits scaled to ~1e153.6 overflow at steps 45-125 of 200 (found by a
    # scan with the single-orbit route), beside ordinary orbits in the same block; statuses, failing steps, rows
    # and frozen final states equal the single-orbit route's exactly
    from jetgaudin.ensemble import sample_on_leaf

    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 30, seed=4)
    b = np.ones(30)
    eta = np.full(30, 5 + 0.1j)
    nu = kernels.nu_default(X, b, eta)
    for i, e in ((8, 153.7), (20, 153.65), (23, 153.6), (29, 153.65)):
        X[i] *= 10.0**e
        b[i] = 10.0**e
        nu[i] *= 10.0**e
    out, final, _, nu_last, status, fail = kernels.run_batch(X, b, eta, nu, False, 200, 1)
    single = kernels.kernel_module("_n3").run_orbit3
    late = 0
    for i in range(30):
        ref, ref_final = np.empty((201, 9)), np.empty(9)
        st, n, _ = single(X[i], b[i], eta[i], nu[i], False, 200, 1, ref, ref_final, np.empty(6), False)
        assert (status[i], fail[i]) == (st, n)
        assert np.array_equal(out[i, : n + 1], ref[: n + 1]) and np.array_equal(final[i], ref_final)
        late += bool(st) and n > 0
    assert late == 4
