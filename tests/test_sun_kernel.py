"""The compiled route of the su(3) two-point map (jetgaudin.gaudin._sun_kernel) against the NumPy route."""

import numpy as np
import pytest

import jetgaudin as jg


def _model(sites):
    return jg.GaudinModel([0.3, -0.1, 0.5, 0.2, 0.0, -0.2, 0.1, 0.4], sites, algebra="su3")


@pytest.mark.parametrize("sites, eta", [([(0.0, 1), (1.0, 1)], 0.4 + 0.1j), ([(0.0, 3)], -0.3 + 0.2j),
                                        ([(-1.0, 2), (0.7, 1)], 0.3 - 0.25j)])
def test_compiled_equals_numpy(sites, eta):
    """Every branch, 50 steps: the two routes differ by round-off only (1e-11 on O(1) states: they take the same
    eigenvector, normalised differently, and μ polished by Newton instead of an eigen-solver)."""
    m = _model(sites)
    X = 0.5 * np.random.default_rng(len(sites)).normal(size=m.n_state)
    for r in range(3):
        B = m.two_point_backlund(eta, branch=r)
        c = B.iterate(X, 50, backend="compiled", save_every=5)
        assert np.allclose(c, B.iterate(X, 50, backend="numpy", save_every=5), atol=1e-11)


def test_batch_split_and_auto():
    m = _model([(0.0, 1), (1.0, 1)])
    B = m.two_point_backlund(0.4 + 0.1j, branch=1, backend="compiled")
    X = 0.5 * np.random.default_rng(3).normal(size=(4, m.n_state))
    batch = B.iterate(X, 30)
    assert np.array_equal(batch, np.stack([B.iterate(x, 30) for x in X], axis=1))  # members = single runs
    orbit, carry = B.iterate(X[0], 10, return_carry=True)
    assert np.array_equal(B.iterate(orbit[-1], 20, carry=carry)[-1], batch[-1, 0])  # split = unsplit
    auto = m.two_point_backlund(0.4 + 0.1j)
    assert auto.resolved_backend(X, 10) is jg.Backend.NUMPY
    assert auto.resolved_backend(X, 10**6) is jg.Backend.COMPILED
    with pytest.raises(jg.InvalidParameterError, match="no compiled route"):
        jg.GaudinModel(0.5, [(0.0, 1)], algebra="su4").two_point_backlund(0.5 + 0.1j, backend="compiled")
