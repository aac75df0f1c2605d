"""Ensembles on a Dask cluster (worker processes) equal the local run bit for bit."""

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

import jetgaudin as jg  # noqa: E402
from jetgaudin.ensemble import iterate_ensemble, sample_on_leaf  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=40) as cl:
        yield cl


def _same(a, b):
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("states", "final", "drift", "nu"))


def test_dask_equals_local_bit_for_bit(cluster, rng):
    X0 = sample_on_leaf(3, [0.4, -0.3, 1.5], 37, seed=int(rng.integers(1 << 30)))
    b = rng.uniform(0.5, 2.0, 37)
    eta = rng.uniform(2, 6, 37) + 0.15j
    local = iterate_ensemble(X0, b, eta, 80, save_every=8)
    # uneven chunks (37 = 3 * 10 + 7), by address and by client; generic route too
    remote = iterate_ensemble(X0, b, eta, 80, save_every=8, scheduler=cluster.scheduler_address, chunk_size=10)
    assert _same(local, remote)
    with distributed.Client(cluster) as client:
        remote2 = iterate_ensemble(X0, b, eta, 80, save_every=8, scheduler=client)
        assert _same(local, remote2)
        X2 = sample_on_leaf(2, [0.3, 1.0], 9, seed=2)
        assert _same(iterate_ensemble(X2, 1.0, 3 + 0.2j, 20), iterate_ensemble(X2, 1.0, 3 + 0.2j, 20, scheduler=client,
                                                                                 chunk_size=4))


def test_dask_failure_names_global_orbit(cluster):
    X = np.stack([sample_on_leaf(3, [0.4, -0.3, 1.5], 1, seed=1)[0]] * 5)
    X[3] *= 1e200
    with pytest.raises(jg.SingularStepError, match="orbit 3"):
        iterate_ensemble(X, 1.0, 5 + 0.1j, 3, nu1=np.ones(5, complex), scheduler=cluster.scheduler_address,
                         chunk_size=2)


def test_bad_scheduler_address():
    X = sample_on_leaf(3, [0.4, -0.3, 1.5], 2, seed=1)
    with pytest.raises(jg.InvalidParameterError, match="scheduler"):
        iterate_ensemble(X, 1.0, 5 + 0.1j, 3, scheduler="tcp://127.0.0.1:1", connect_timeout=2)
