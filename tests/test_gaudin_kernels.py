"""The compiled (Numba) route of the chain two-point map against the NumPy route (issue 12, speed): the same orbits
to round-off, any sites and orders; batch members and split runs equal bit for bit."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import jetgaudin as jg
from test_gaudin import random_chain
from test_gaudin_maps import random_eta

pytest.importorskip("numba")


@pytest.fixture
def rng(request):
    return np.random.default_rng([20261123, zlib.crc32(request.node.nodeid.encode())])


@pytest.mark.parametrize("seed", range(5))
def test_compiled_equals_numpy_route(rng, seed):
    """100 steps of a batch of 2, both branches: <= 1e-10 relative to 1 + |X| (the routes round differently, the
    difference grows along the orbit; measured <= 4e-12 after 300 steps of a twisted chain with M = 9)."""
    m = random_chain(rng)
    eta = random_eta(rng, m)
    X = rng.normal(size=(2, m.n_state))
    for branch in ("default", "opposite"):
        a = m.two_point_backlund(eta, branch).iterate(X, 100)
        c = jg.ChainTwoPointBacklund(m, eta, branch, backend="compiled").iterate(X, 100)
        assert c.shape == a.shape and np.isrealobj(c)
        assert np.abs(a - c).max() <= 1e-10 * (1 + np.abs(a).max())


def test_compiled_batch_and_split_runs_bit_for_bit(rng):
    m = jg.twisted_chain(-0.9, [-1.0, 0.4, 1.5])
    B = jg.ChainTwoPointBacklund(m, 0.9 + 0.05j, backend="compiled")
    X = rng.normal(size=(3, 27))
    batch = B.iterate(X, 40, save_every=3)
    for k in range(3):
        assert np.array_equal(batch[:, k], B.iterate(X[k], 40, save_every=3))
    full, nu = B.iterate(X, 40, return_carry=True)
    first, carry = B.iterate(X, 15, return_carry=True)
    second, nu2 = B.iterate(first[-1], 25, carry=carry, return_carry=True)
    assert np.array_equal(np.concatenate([first, second[1:]]), full) and np.array_equal(nu, nu2)
    assert B.inverse().backend is jg.Backend.COMPILED
    back = B.inverse().iterate(full[-1], 40)[-1]
    assert np.abs(back - X).max() <= 1e-10 * (1 + np.abs(X).max())


def test_compiled_one_site_equals_todays_compiled_map(rng):
    """One site at 0 (N = 3, Appendix 2's eta): the chain kernel gives the orbit of jetgaudin's one-site map (NumPy
    route) to round-off (1e-10 relative over 200 steps: different operation orders)."""
    X = rng.normal(size=9)
    a = jg.ChainTwoPointBacklund(jg.GaudinModel(1.0, [(0.0, 3)]), 5 + 0.1j, backend="compiled").iterate(X, 200)
    o = jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(X, 200, kernel="numpy")
    assert np.abs(a - o).max() <= 1e-10 * (1 + np.abs(o).max())
