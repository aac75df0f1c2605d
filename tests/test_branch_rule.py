"""The compiled branch rule of ``ν1`` (``backlund/kernels/_branch.py``): its exact no-stepping test and its
stepping both give the root of :func:`jetgaudin.nu`'s default rule."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.backlund import kernels as K
from jetgaudin.ensemble import sample_on_leaf


def _p_and_bound(X, b, a):
    """``P(a) = ν²(a)`` and ``D = Σ m |κ_m| |a|^{-m-1}`` from :func:`jetgaudin.integrals` (an independent sum)."""
    kappa = np.concatenate([np.full((len(X), 1), b**2), np.asarray(jg.integrals(X, b)).reshape(len(X), -1)], axis=1)
    m = np.arange(kappa.shape[1])
    return (kappa * float(a) ** -m).sum(axis=1), (m * np.abs(kappa) * abs(a) ** (-m - 1.0)).sum(axis=1)


def test_no_stepping_test_cases_agree_with_nu(rng):
    # states where |Im eta| D <= P(a)/2 (the exact test holds): the rule returns the principal sqrt of P(eta), which
    # is jg.nu's root; 1e-13 relative: the two sum nu^2 in different orders (Horner vs powers)
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 400, seed=2)
    eta = 5 + 0.1j
    p, d = _p_and_bound(X, 1.0, eta.real)
    fast = abs(eta.imag) * d <= 0.5 * p
    assert fast.mean() > 0.9  # the common case of a small time step
    got = K.nu_default(X, np.ones(len(X)), np.full(len(X), eta))
    ref = np.array([jg.nu(eta, x, 1.0) for x in X])
    assert np.all(np.abs(got - ref) <= 1e-13 * np.abs(ref))
    principal = np.sqrt(np.array([jg.nu_squared(eta, x, 1.0) for x in X]))
    assert np.all(np.abs(got[fast] - principal[fast]) <= 1e-13 * np.abs(principal[fast]))


def test_stepping_cases_where_the_principal_root_is_not_the_branch(rng):
    # N = 1, y = (1, 0, -2), b = 1: nu^2 = (l^2 - 4l + 5)/l^2 with branch points 2 +- i.  Along [a, a + iY] with
    # a < 2 and Y > 1 the segment passes left of the branch point 2 + i: nu^2 crosses the cut of the principal
    # sqrt and the continued root is minus the principal one at the end; the exact test fails and the rule steps
    x = np.array([[1.0, 0.0, -2.0]])
    for eta in (2.01 + 3j, 2.2 + 1.5j, 1.9 + 3j, 1.5 + 2j, 1.0 + 5j, -3 - 2j):
        p, d = _p_and_bound(x, 1.0, eta.real)
        assert abs(eta.imag) * d[0] > 0.5 * p[0]  # the exact test does not hold: stepping
        ref = jg.nu(eta, x[0], 1.0)
        got = K.nu_default(x, [1.0], [eta])[0]
        assert abs(got - ref) <= 1e-13 * abs(ref)
    for eta in (1.9 + 3j, 1.5 + 2j, 1.0 + 5j):  # the case the exact test must not take: -sqrt(nu^2)
        principal = np.sqrt(jg.nu_squared(eta, x[0], 1.0))
        assert abs(K.nu_default(x, [1.0], [eta])[0] + principal) <= 1e-13 * abs(principal)


def test_sheet_and_batches_of_any_size(rng):
    # one serial kernel for every batch size: orbit i of a batch equals its single-orbit value bit for bit
    X = sample_on_leaf(2, [0.3, 1.0], 300, seed=5)
    eta = rng.uniform(1, 6, 300) + 1j * rng.uniform(-2, 2, 300)
    b = rng.uniform(0.5, 2, 300)
    whole = K.nu_default(X, b, eta, -1)
    single = np.array([K.nu_default(X[i:i + 1], b[i:i + 1], eta[i:i + 1], -1)[0] for i in range(300)])
    assert np.array_equal(whole, single)
    assert np.array_equal(K.nu_default(X, b, eta, 1), -whole)


def test_a_batch_split_across_threads_gives_the_same_values(monkeypatch, rng):
    # large batches run in pieces on threads of the driver's own (the kernel releases the GIL): every split gives
    # the bits of one call, and a failing orbit in a later piece is named by its index in the batch.  The split is
    # forced (3 threads) so that it is exercised on a machine with one CPU too
    from jetgaudin.backlund.kernels import _drivers

    n = 3 * 1000 + 7
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], n, seed=6)
    b = rng.uniform(0.5, 2, n)
    eta = rng.uniform(1, 6, n) + 1j * rng.uniform(-2, 2, n)
    whole = K.nu_default(X, b, eta)
    monkeypatch.setattr(_drivers, "_threads", lambda n, per_thread: 3)
    assert np.array_equal(K.nu_default(X, b, eta), whole)
    eta[2500] = 1j  # Re(eta) = 0: the rule is undefined there
    with pytest.raises(jg.BranchPointError, match="orbit 2500:"):
        K.nu_default(X, b, eta)


def test_states_of_extreme_size_scale_exactly():
    # nu is homogeneous of degree 1 in (X, b): nu(cX, cb) = c nu(X, b).  For c a power of 2 every operation of the
    # rule (kappa, the Horner sums, the tests, the steps) scales exactly, and so does its square root, which takes
    # p scaled into (1e-150, 1e150) by a power of 4 where |p| is outside that range: exact equality, for |nu^2| from
    # ~1e-160 to ~1e160 (there sqrt(a^2 + b^2) of p under- or overflows: a root without the scaling gives inf/NaN)
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 50, seed=7)
    b, eta = np.ones(50), np.full(50, 5 + 0.1j)
    ref = K.nu_default(X, b, eta)
    for e in (-265, -200, 200, 265):
        c = 2.0**e
        assert np.array_equal(K.nu_default(X * c, b * c, eta), ref * c), e
    x = np.array([[1.0, 0.0, -2.0]])  # the stepping case of the test above (the exact test does not hold)
    for eta1 in (2.01 + 3j, 1.0 + 5j):
        ref1 = K.nu_default(x, [1.0], [eta1])
        for e in (-100, 100):
            c = 2.0**e
            assert np.array_equal(K.nu_default(x * c, [c], [eta1]), ref1 * c), (eta1, e)


def test_the_written_out_n3_kappa_equals_the_loops(rng):
    # N = 3 computes kappa written out (_kappa3), other N by loops (_kappa).  A fourth site y_4 = 0 adds exact
    # zeros to every kappa_m (and kappa_7 = kappa_8 = 0, leading zeros of the Horner sums): the padded N = 4 state
    # runs the loops on the same numbers, so nu is the same bits, in the common case and in the stepping
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 200, seed=8)
    X[:50] = rng.normal(size=(50, 9))
    b = rng.uniform(0.5, 2, 200)
    eta = rng.uniform(-3, 3, 200) + 1j * rng.uniform(-2, 2, 200)
    ok = np.abs(eta.real) > 1e-3
    X, b, eta = X[ok], b[ok], eta[ok]
    X4 = np.concatenate([X, np.zeros((len(X), 3))], axis=1)
    assert np.array_equal(K.nu_default(X4, b, eta), K.nu_default(X, b, eta))
