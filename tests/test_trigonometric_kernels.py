"""The one family kernel (jetgaudin.gaudin._family_kernel, issue 23): the trigonometric map's compiled route against
its NumPy route, batch and split runs bit for bit, the rational family through the same kernel against the rational
chain kernel, and the backend rule (auto, kernel= alias, no compiled route)."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel
from test_gaudin import random_chain
from test_gaudin_maps import random_eta
from test_trigonometric import random_trig
from test_trigonometric_maps import random_xi

pytest.importorskip("numba")


@pytest.fixture
def rng(request):
    return np.random.default_rng([20261125, zlib.crc32(request.node.nodeid.encode())])


@pytest.mark.parametrize("seed", range(5))
def test_compiled_equals_numpy_route(rng, seed):
    """100 steps of a batch of 2, both branches, jet sites included: <= 1e-10 relative to 1 + |X| (the routes round
    differently and the difference grows along the orbit, as for the rational chains; measured ~1e-13)."""
    m = random_trig(rng)
    xi = random_xi(rng, m)
    X = rng.normal(size=(2, m.n_state))
    for branch in ("default", "opposite"):
        B = m.two_point_backlund(xi, branch)
        a = B.iterate(X, 100, kernel="numpy")
        c = B.iterate(X, 100, backend="compiled")
        assert c.shape == a.shape and np.isrealobj(c)
        assert np.abs(a - c).max() <= 1e-10 * (1 + np.abs(a).max())


def test_batch_and_split_runs_bit_for_bit(rng):
    m = GaudinModel(-0.9, [(-1.0, 1), (0.4, 2), (1.5, 1)], family="trigonometric", gamma=0.8)
    B = m.two_point_backlund(0.9 + 0.1j, kernel="compiled")
    X = rng.normal(size=(3, m.n_state))
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


@pytest.mark.parametrize("seed", range(3))
def test_rational_family_through_the_family_kernel(rng, seed):
    """The one kernel serves every family: the rational family's constant tables (gauge rule 0, K = lam + M0) in the
    family kernel give the rational chain kernel's orbit to round-off (1e-10 relative over 100 steps)."""
    from jetgaudin.gaudin import _family_kernel as F

    m = random_chain(rng)
    B = m.two_point_backlund(random_eta(rng, m), kernel="compiled")
    X = rng.normal(size=m.n_state)
    ref = B.iterate(X, 100)
    rows, _, _ = F.run_orbit(X, m.b, complex(B.start(X)), *F.orbit_constants(m, B.eta), 100, 1)
    assert np.abs(rows - ref).max() <= 1e-10 * (1 + np.abs(ref).max())


def test_backend_rule(monkeypatch):
    from jetgaudin.gaudin import _backend

    m = GaudinModel(0.8, [(-0.4, 1), (0.9, 1)], family="trigonometric", gamma=0.7)
    B = m.two_point_backlund(0.5 + 0.2j)
    X = np.array([0.3, -0.2, 0.5, 0.1, 0.4, -0.3])
    assert B.backend is jg.Backend.AUTO and B.has_compiled
    monkeypatch.setattr(_backend, "kernel_state", lambda family, batch=1: "cold")  # AUTO's cost rule: test_auto_route
    assert B.resolved_backend(X, 10) is jg.Backend.NUMPY
    assert B.resolved_backend(X, 10**6) is jg.Backend.COMPILED
    assert m.two_point_backlund(0.5 + 0.2j, kernel="numpy").resolved_backend(X, 10**6) is jg.Backend.NUMPY
    with pytest.raises(jg.InvalidParameterError, match="backend"):
        m.two_point_backlund(0.5 + 0.2j, kernel="fast")
    report = m.two_point_backlund(0.5 + 0.2j, kernel="compiled").prepare_kernels(X, 5)
    assert report is not None
    r = GaudinModel(0.8, [(-0.4, 1), (0.9, 1)]).one_point_backlund(0.5 + 0.2j)
    with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
        r.iterate(X, 3, kernel="compiled")
    assert np.array_equal(r.iterate(X, 3, kernel="numpy"), r.iterate(X, 3))
