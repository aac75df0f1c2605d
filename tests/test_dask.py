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


def test_recorded_ensemble_on_dask_equals_local(cluster, tmp_path):
    """The streamed driver with --scheduler: each time chunk split over the workers; the file holds the bits of
    the local in-memory run (and the CLI path with an address works end to end)."""
    import subprocess
    import sys

    from jetgaudin import ensemble_recording as er

    X0 = sample_on_leaf(3, [0.4, -0.3, 1.5], 11, seed=9)
    spec = er.EnsembleSpec(X0, 1.0, 5 + 0.1j, 30, 4)
    er.run_ensemble(spec, tmp_path / "a", scheduler=cluster.scheduler_address, chunk_size=3, max_chunk_steps=7)
    ref = iterate_ensemble(X0, 1.0, 5 + 0.1j, 30)
    n = list(range(0, 31, 4)) + [30]
    assert np.array_equal(er.load_ensemble(tmp_path / "a").states, ref.states[n])
    r = subprocess.run([sys.executable, "-m", "jetgaudin", "ensemble", "--sample", "leaf", "--casimirs",
                        "0.4,-0.3,1.5", "--orbits", "11", "--seed", "9", "--steps", "30", "--save-every", "4",
                        "--scheduler", cluster.scheduler_address, "--chunk-size", "4", "--out", str(tmp_path / "b")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert np.array_equal(er.load_ensemble(tmp_path / "b").states, ref.states[n])
