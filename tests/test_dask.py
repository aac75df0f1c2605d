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


# ---- chains of every family (issue 23): any map's batch through jetgaudin.ensemble.DaskBatch -------------------
@pytest.mark.parametrize(("family", "kw", "backend"), [("rational", {}, "numpy"), ("rational", {}, "compiled"),
                                                       ("trigonometric", {"gamma": 0.7}, "numpy"),
                                                       ("trigonometric", {"gamma": 0.7}, "compiled"),
                                                       ("elliptic", {"modulus": 0.6}, "numpy"),
                                                       ("elliptic", {"modulus": 0.6}, "compiled")])
def test_chain_ensemble_on_dask_equals_local_bit_for_bit(cluster, family, kw, backend):
    from jetgaudin.ensemble import DaskBatch, sample_chain_on_leaf

    model = jg.GaudinModel(0.0 if family == "elliptic" else 0.8, [(-1.0, 1), (0.3, 2)], family=family, **kw)
    X0 = sample_chain_on_leaf(model, None, 7, seed=3)
    m = model.two_point_backlund(0.5 + 0.05j, backend=backend)
    local = m.advance(X0, None, 9, 3)
    remote = DaskBatch(m, cluster.scheduler_address, chunk_size=3).advance(X0, None, 9, 3)  # chunks 3, 3, 1
    for k in ("rows", "X", "carry", "imag_max"):
        assert np.array_equal(getattr(local, k), getattr(remote, k)), k
    # continuing from the carry: the same bits as the unsplit run
    more = DaskBatch(m, cluster.scheduler_address, chunk_size=2).advance(remote.X, remote.carry, 4, 4)
    assert np.array_equal(more.X, m.advance(X0, None, 13, 13).X)


def test_chain_ensemble_cli_scheduler(cluster, tmp_path, monkeypatch):
    """`ensemble --sites --scheduler`: the file holds the local run's bits (the orbits split over the workers)."""
    import json

    from jetgaudin import run as rl
    from jetgaudin.cli import main

    def cli(*args):
        try:
            return main([str(a) for a in args]) or 0
        except SystemExit as exc:
            return exc.code or 0

    common = ["--sites", "-1:1,0.3:2", "--family", "trigonometric", "--gamma", "0.7", "--b", "0.8", "--eta",
              "0.5+0.05i", "--orbits", "5", "--steps", "30", "--save-every", "5"]
    assert cli("ensemble", *common, "--out", tmp_path / "local") == 0
    calls = _count_dask_calls(monkeypatch)
    assert cli("ensemble", *common, "--scheduler", cluster.scheduler_address, "--chunk-size", "2",
               "--out", tmp_path / "dask") == 0
    a, b = rl.load(tmp_path / "local"), rl.load(tmp_path / "dask")
    assert np.array_equal(a.X, b.X) and a.X.shape == (7, 5, 9) and calls
    assert json.loads((tmp_path / "dask" / "run.json").read_text())["map"]["kind"] == "chain_two_point"


def _count_dask_calls(monkeypatch):
    """Count the calls of the one Dask path (jetgaudin.ensemble.dask_chunks): the runs below really use it."""
    from jetgaudin import ensemble as ens

    calls, real = [], ens.dask_chunks
    monkeypatch.setattr(ens, "dask_chunks", lambda *a, **k: calls.append(1) or real(*a, **k))
    return calls


def test_interrupted_chain_ensemble_resumes_on_dask_bit_for_bit(cluster, tmp_path, monkeypatch):
    from jetgaudin import ensemble_recording as er
    from jetgaudin import run as rl
    from jetgaudin.ensemble import DaskBatch, sample_chain_on_leaf
    from test_gaudin_run import interrupt

    model = jg.GaudinModel(0.8, [(-1.0, 1), (0.3, 2)], family="trigonometric", gamma=0.7)
    X0 = sample_chain_on_leaf(model, None, 5, seed=1)
    m = model.two_point_backlund(0.5 + 0.05j, backend="numpy")
    spec = rl.RunSpec(DaskBatch(m, cluster.scheduler_address, 2), X0, 24, 4, program="jetgaudin ensemble")
    interrupt(spec, tmp_path / "r", 9)
    assert rl.read_run(tmp_path / "r")["status"] == "interrupted"
    calls = _count_dask_calls(monkeypatch)
    res = er.run_ensemble(None, tmp_path / "r", resume=True, scheduler=cluster.scheduler_address, chunk_size=2)
    assert res.status == "completed" and calls
    assert np.array_equal(rl.load(tmp_path / "r").X, m.iterate(X0, 24, save_every=4))
