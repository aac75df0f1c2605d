"""The run layer's host-side work per row and per checkpoint made cheaper (issue 36) without changing what is written:
the row digest hashes the arrays' buffers (no bytes copy), the checkpoint is hashed and written from the zip's buffer
in place, ``BatchBacklund.describe`` builds its lists without a Python loop, the first row of a new run is not
integrated again, and the end state of a call off the save grid has its own entry (:meth:`Health.check_end`) that
the GPU route answers on the device (``tests/test_gpu.py``)."""

from __future__ import annotations

import hashlib
import json
import struct

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.ensemble import BatchBacklund, sample_on_leaf
from jetgaudin.run.files import RowDigest
from jetgaudin.run.health import Health


def test_row_digest_is_the_sha256_of_the_little_endian_bytes():
    """The format's definition (two SHA-256 streams: the ``n`` column as ``<i8``, the rows as ``<f8``, chunking
    free), computed here from the bytes themselves; inputs of other dtypes, orders and layouts included."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(5, 4, 9))
    parts = [(np.arange(2), X[:2]), (np.array([7], dtype=np.int32), X[2:3].astype(np.float32).astype(np.float64)),
             (np.array([9, 11]), np.asfortranarray(X[3:]))]
    d = RowDigest()
    hn, hX = hashlib.sha256(), hashlib.sha256()
    for n, S in parts:
        d.update(n, S)
        hn.update(b"".join(struct.pack("<q", int(v)) for v in np.ravel(n)))
        hX.update(b"".join(struct.pack("<d", float(v)) for v in np.ravel(S, order="C")))
    assert d.hexdigest() == hn.hexdigest() + ":" + hX.hexdigest()
    e = RowDigest()
    e.update(np.zeros(0, dtype=np.int64), np.zeros((0, 4, 9)))
    assert e.hexdigest() == RowDigest().hexdigest()


def _ensemble(tmp_path, B=40, steps=12, every=4, **kw):
    X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=2)
    m = BatchBacklund(np.linspace(0.9, 1.1, B), (5 + 0.1j) + 0.01 * np.arange(B), backend="compiled")
    spec = rl.RunSpec(m, X0, steps, every, rl.HealthLimits(max_drift=1e-6), csv=False, program="jetgaudin ensemble",
                      **kw)
    return spec, rl.start(spec, tmp_path / "e")


def test_ensemble_checkpoint_file_matches_its_recorded_digest_and_loads(tmp_path):
    """The checkpoint slot written from the zip's buffer: ``run.json``'s SHA-256 is the file's (hashed here from the
    file read back), and it loads with the state of the last step (the final state of the run's own rows)."""
    from jetgaudin.run.store import read_checkpoint_npz

    spec, res = _ensemble(tmp_path)
    run = json.loads((tmp_path / "e" / "run.json").read_text())
    ck = run["checkpoint"]
    data = (tmp_path / "e" / ck["file"]).read_bytes()
    assert hashlib.sha256(data).hexdigest() == ck["sha256"]
    got = read_checkpoint_npz(tmp_path / "e", ck, spec.X0.shape)
    assert int(got["step"]) == 12
    np.testing.assert_array_equal(got["X"], rl.load(tmp_path / "e").X[-1])


def test_describe_gives_the_same_values_and_json():
    """``describe`` of a batch: the same floats (and the same JSON text) as the orbit-by-orbit lists it replaced."""
    B = 7
    m = BatchBacklund(np.linspace(0.5, 2, B), np.exp(1j * np.linspace(0.1, 3, B)) * 3.3 + 0.01j)
    d = m.describe()
    assert d["eta"] == [[e.real, e.imag] for e in m.eta] and d["b"] == [float(v) for v in m.b]
    assert json.dumps(d["eta"]) == json.dumps([[float(e.real), float(e.imag)] for e in m.eta])
    assert BatchBacklund(np.ones(0), np.ones(0) * 1j).describe()["eta"] == []


class _Counting:
    """A map's ``integrals`` counted (the work :meth:`Health.check_start` saves)."""

    def __init__(self, m):
        self.m, self.calls = m, 0

    def __getattr__(self, name):
        return getattr(self.m, name)

    def integrals(self, X):
        self.calls += 1
        return self.m.integrals(X)


@pytest.mark.parametrize("kind", ["ensemble", "orbit"])
def test_check_start_is_the_full_check_of_the_first_row(kind):
    """``check_start(X0)`` where ``I0`` was computed from ``X0``: no integrals computed, and the result is the full
    check's -- no breach, the drift maxima and the radius deviation exactly 0, as :meth:`Health.check` of the row
    gives (checked here on a second ``Health``).  Where the states differ (one orbit's state changed) or ``I0`` was
    given, the full check runs and finds the breach."""
    if kind == "ensemble":
        X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], 50, seed=4)
        m = BatchBacklund(np.linspace(0.9, 1.1, 50), 5 + 0.1j)
    else:
        X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
        m = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    lim = rl.HealthLimits(max_drift=1e-6)
    c = _Counting(m)
    h = Health(c, X0, lim)
    assert c.calls == 1
    assert h.check_start(X0.copy()) is None and c.calls == 1  # nothing computed
    assert np.all(h.drift == 0) and h.sphere == 0
    full = Health(m, X0, lim)
    assert full.check([0], X0[None]) is None
    np.testing.assert_array_equal(full.drift, h.drift)  # the full check leaves exactly 0 too
    assert full.sphere == h.sphere == 0
    Y = X0.copy()
    Y[..., 0] += 0.5  # another state: the full check runs and sees the drift
    bad = h.check_start(Y)
    assert bad is not None and "integral drift" in bad.reason and c.calls == 2
    given = Health(c, X0, lim, I0=h.I0 + 1.0)  # I0 given (a resume): checked in full
    calls = c.calls
    assert given.check_start(X0) is not None and c.calls == calls + 1


def test_check_end_is_the_unrecorded_check():
    """``check_end`` of a state is ``check`` of that one row with ``record=False``: a passing state moves no maximum,
    a breaching one is reported (and folded) as before."""
    X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], 20, seed=6)
    m = BatchBacklund(np.ones(20), 5 + 0.1j)
    h = Health(m, X0, rl.HealthLimits(max_drift=1e-3))
    X1 = m.advance(X0, None, 3).X
    assert h.check_end(3, X1) is None and np.all(h.drift == 0) and h.sphere == 0
    Y = X1.copy()
    Y[4, :3] *= 1.5
    bad = h.check_end(3, Y)
    assert bad is not None and "of orbit 4" in bad.reason and "at step 3 " in bad.reason and bad.index == 0
    assert h.drift[4].max() > 0


def test_run_ensemble_validates_the_ensemble_twice_not_three_times(tmp_path, monkeypatch):
    """``run_ensemble`` builds the run's map (route, cluster) first and its ``RunSpec`` once: the ensemble is
    validated (integrals and branch rule at ``X0``, seconds at 10⁷ orbits) by the ``EnsembleSpec`` and by that
    ``RunSpec`` -- two, where it was three; the run is the same (rows equal the compiled iteration), and a bad
    ``max_drift`` is still refused before anything runs."""
    from jetgaudin import ensemble_recording as er
    from jetgaudin.ensemble import iterate_ensemble
    from jetgaudin.run.spec import RunSpec

    seen = []
    post = RunSpec.__post_init__
    monkeypatch.setattr(RunSpec, "__post_init__", lambda self: (seen.append(1), post(self))[1])
    X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], 6, seed=1)
    spec = er.EnsembleSpec(X0, 1.0, 5 + 0.1j, steps=12, save_every=4)
    assert len(seen) == 1
    res = er.run_ensemble(spec, tmp_path / "e", backend="compiled")
    assert res.status == "completed" and len(seen) == 2
    assert rl.read_run(tmp_path / "e")["inputs"]["backend"] == "compiled"
    np.testing.assert_array_equal(er.load_ensemble(tmp_path / "e").states,
                                  iterate_ensemble(X0, 1.0, 5 + 0.1j, 12, save_every=4).states)
    with pytest.raises(jg.InvalidParameterError, match="max_drift"):
        er.run_ensemble(spec, tmp_path / "f", max_drift=-1.0, scheduler="tcp://127.0.0.1:9")
    assert not (tmp_path / "f").exists()


def test_a_new_ensemble_record_does_not_describe_a_batch(tmp_path, monkeypatch):
    """Starting an ensemble of ``BatchBacklund`` does not build its description (every orbit's ``b`` and ``η`` as
    lists: ~1 s per 10⁶ orbits) only to find its kind; ``run.json`` records no ``map`` for it, as before.  A map with
    another ``describe`` (a subclass here) is described and recorded."""
    calls = []
    original = BatchBacklund.describe
    monkeypatch.setattr(BatchBacklund, "describe", lambda self: (calls.append(1), original(self))[1])
    spec, res = _ensemble(tmp_path)
    assert res.status == "completed" and calls == [] and "map" not in rl.read_run(tmp_path / "e")

    class Described(BatchBacklund):
        def describe(self):
            return dict(original(self), kind="another")

    from jetgaudin.run import api

    m = Described(spec.map.b, spec.map.eta, backend="compiled")
    rec = api._new_record(rl.RunSpec(m, spec.X0, 4, 4, spec.limits, csv=False, program="jetgaudin ensemble"),
                          Health(m, spec.X0, spec.limits))
    assert rec["map"]["kind"] == "another"


def test_a_new_run_integrates_the_initial_ensemble_once(tmp_path, monkeypatch):
    """``start`` takes the run's ``I0`` from the run spec's own check (``RunSpec.integrals0``) instead of computing
    the integrals of the whole initial ensemble a second time: one call on ``X0``-shaped input where there were two,
    and the same ``I0`` bits as the map computes (so the first row's drift is still exactly 0)."""
    calls = []
    original = BatchBacklund.integrals
    monkeypatch.setattr(BatchBacklund, "integrals",
                        lambda self, X: (calls.append(np.shape(X)), original(self, X))[1])
    spec, res = _ensemble(tmp_path)
    assert res.status == "completed"
    assert calls.count(spec.X0.shape) == 1  # the spec's check; the health's I0 taken from it
    assert (1,) + spec.X0.shape not in calls  # nor the first row again (check_start: I0 is of X0; one chunk here)
    np.testing.assert_array_equal(res.integrals0, original(spec.map, spec.X0))
    assert spec.integrals0() is not spec.integrals0()  # a copy each time
    np.testing.assert_array_equal(spec.integrals0(), res.integrals0)
