"""The run layer's health checks (``jetgaudin.run.health``): what a breach reports, for the mutants of issue 33's
sample.  The checks are driven directly with planted rows (the states a run would append), so the breach, its
integral, orbit and size are known exactly.  Tolerances: the relative drifts are compared to 1e-6 relative (a
difference of two integrals of size ~10, each exact to ~1e-15, is ~1e-14 absolute beside the planted 1e-6)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.run.health import Health
from jetgaudin.run.spec import HealthLimits

MAP = jg.TwoPointBacklund(1.0, 5 + 0.1j)
X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2: H_1 = 2b y_0^3 = -2.4, C_3 = |z|^2 = 1


def _drift_in_h1(X: np.ndarray, d: float) -> np.ndarray:
    """``X`` with ``H_1 = 2 b y_0^3`` moved by ``d`` (``y_0^3 += d/2``; b = 1): the other integrals move too."""
    Y = X.copy()
    Y[..., 2] += d / 2
    return Y


def test_a_breach_in_an_ensemble_names_its_orbit_and_integral():
    """Three orbits, the second drifts: the reason names ``H_1`` (the top's integrals are named as
    ``jg.integrals`` orders them), ``orbit 1`` and the planted relative size.  Written for the mutants
    ``rel_row.ndim == 2`` → ``> 2`` (the orbit left out) and ``k % 2 == 0`` → ``== 1`` (``I_1`` for ``H_1``)."""
    X0 = np.stack([X3, 0.9 * X3, 1.1 * X3])
    h = Health(MAP, X0, HealthLimits(max_drift=1e-8))
    S = np.stack([X0, X0.copy()])  # two checked rows (steps 5 and 10), orbit 1 breaks in the second
    S[1, 1] = _drift_in_h1(X0[1], 2e-6 * 2.4 * 0.9)  # H_1 = -2.16 there: relative 2e-6 of max(1, |H_1|)
    fail = h.check([5, 10], S)
    assert fail is not None and fail.index == 1
    assert re.match(r"integral drift: H_1 of orbit 1 drifted by (\S+) \(relative to max\(1, \|I\(0\)\|\)\) at step "
                    r"10 > max_drift 1e-08$", fail.reason), fail.reason
    size = float(re.search(r"drifted by (\S+) ", fail.reason).group(1))
    assert abs(size - 2e-6) < 2e-12
    one = Health(MAP, X3, HealthLimits(max_drift=1e-8)).check([3], _drift_in_h1(X3, 1e-5)[None])
    assert one is not None and one.reason.startswith("integral drift: H_1 drifted by")  # one orbit: no orbit named


def test_drift_is_relative_to_one_for_small_integrals():
    """An integral whose value is below 1 (here ``H_1 = 0``: ``y_0^3 = 0``) is checked by its absolute drift (relative
    to ``max(1, |I(0)|)``, not to ``|I(0)|``): a drift of 1e-9 passes ``max_drift = 1e-8``.  Written for the mutant
    ``max(1.0, |I0|)`` → ``max(0.0, |I0|)`` (a division by 0: the row non-finite)."""
    X0 = X3.copy()
    X0[2] = 0.0
    h = Health(MAP, X0, HealthLimits(max_drift=1e-8))
    assert h.check([1], _drift_in_h1(X0, 1e-9)[None]) is None
    assert abs(h.relative[0] - 1e-9) < 1e-15 and np.all(np.isfinite(h.relative))


# ---- the store: reservations and a failed flush ----------------------------------------------------------------
def _run(tmp_path, monkeypatch=None, steps=200):
    from jetgaudin import run as rl

    spec = rl.RunSpec(jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy"), X3, steps, 1, checkpoint_seconds=0.0)
    return rl, rl.start(spec, tmp_path / "r")


def test_the_reserve_holds_a_record_beyond_its_margin(tmp_path, monkeypatch):
    """The reserve made at the start of a session (freed to record a full disk) holds ``RESERVE_BYTES`` and the
    run's record beyond it (the last ``run.json`` is written to a temporary copy, then renamed).  Written for
    the mutant ``+ 2 * len`` → ``+ 2 - len``
    (a reserve smaller than its margin)."""
    import json

    from jetgaudin import _space
    from jetgaudin.run import store

    seen: list[tuple[int, int]] = []  # (the reserve's bytes, the record's compact size then)
    real = _space.make_reserve

    def spy(d, n):
        seen.append((n, len(json.dumps(json.loads((Path(d) / "run.json").read_text())))))
        return real(d, n)

    monkeypatch.setattr(_space, "make_reserve", spy)
    rl, res = _run(tmp_path)
    assert res.state is rl.RunStatus.COMPLETED and seen
    for n, record in seen:
        # the margin and a record as written beyond it (the reserve counts twice the in-memory record, 1607 bytes
        # here; write_run's file, 1685 bytes compact, adds fields: so not twice the file's size)
        assert n >= store.RESERVE_BYTES + record, (n, record)


def test_the_reservation_for_an_append_covers_every_chunk_it_touches_and_the_metadata(tmp_path):
    """``_h5_bytes(r, k)``, the bytes reserved before ``k`` rows are appended after row ``r``: ``H5_META_BYTES`` for
    nothing appended, and for one row at least that plus one full chunk of the data and one of the step numbers
    (HDF5 writes whole chunks); the rows of a second chunk add a data chunk more.  Written for the mutant
    ``+ H5_META_BYTES`` → ``/ H5_META_BYTES`` (the metadata's margin lost)."""
    from jetgaudin.run import store

    rl, res = _run(tmp_path, steps=10)
    s = store.OrbitStore.__new__(store.OrbitStore)  # the arithmetic only: a store's shape and chunking
    s.shape = (9,)
    chunks = s._h5_chunks()
    data_chunk, n_chunk = 8 * int(np.prod(chunks)), 8 * 4096
    assert s._h5_bytes(0, 0) == store.H5_META_BYTES
    assert s._h5_bytes(0, 1) >= store.H5_META_BYTES + data_chunk + n_chunk
    assert s._h5_bytes(chunks[0] - 1, 2) >= store.H5_META_BYTES + 2 * data_chunk + n_chunk


def test_a_failed_flush_is_one_line_naming_the_file(tmp_path, monkeypatch):
    """HDF5's flush failing (EIO, injected): the run ends ``failed: I/O error (...) while flushing <dir>/orbit.h5``,
    one line, not a TypeError.  Written for the mutant ``out_dir / h5_name`` → ``out_dir ** h5_name`` in that
    message (a TypeError raised while handling the I/O error)."""
    import errno

    import h5py

    def flush(self):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(h5py.File, "flush", flush)
    rl, res = _run(tmp_path)
    assert res.state is rl.RunStatus.FAILED_IO
    assert "while flushing" in res.status and str(tmp_path / "r" / "orbit.h5") in res.status
    assert "\n" not in res.status and "I/O error" in res.status


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_a_checkpoint_file_beyond_its_bound_is_refused_before_it_is_read(tmp_path):
    """``read_checkpoint_npz`` reads a checkpoint of ``B`` orbits of ``n`` components only up to its bound (its
    arrays: ``X``, ``ν1`` and the anchor's, the drift, and 64 KiB for the zip's own bytes): a checkpoint at its
    largest (every array, 4 orbits of 9) is read; one that matches its digest but carries 1 MiB more (a planted
    extra array) is refused naming its size, never read into memory.  Exact (byte counts).  Written for the mutant
    ``8 B n + (1 << 16)`` → ``8 B n ** (1 << 16)`` (no bound)."""
    import hashlib
    import io

    from jetgaudin.run.store import read_checkpoint_npz

    B, n = 4, 9
    rng = np.random.default_rng(0)
    arrays = {"step": np.int64(10), "X": rng.normal(size=(B, n)), "nu1": rng.normal(size=B) + 1j,
              "drift": rng.normal(size=(B, 6)), "anchor_step": np.int64(8), "anchor_X": rng.normal(size=(B, n)),
              "anchor_nu1": rng.normal(size=B) + 1j}

    def write(name: str, **extra) -> dict:
        buf = io.BytesIO()
        np.savez(buf, **arrays, **extra)
        data = buf.getvalue()
        (tmp_path / name).write_bytes(data)
        return {"file": name, "sha256": hashlib.sha256(data).hexdigest()}

    got = read_checkpoint_npz(tmp_path, write("ck0.npz"), (B, n))
    assert np.array_equal(got["X"], arrays["X"]) and np.array_equal(got["anchor_nu1"], arrays["anchor_nu1"])
    with pytest.raises(jg.RunDirectoryError, match="more than the"):
        read_checkpoint_npz(tmp_path, write("ck1.npz", pad=np.zeros(1 << 17)), (B, n))


def test_a_checkpoint_before_the_first_durable_row_must_be_the_start():
    """``replay`` of a run with no durable row yet (``store.rows == 0``: the run starts again from ``X0``): only the
    start itself is accepted -- step 0 at ``X0``, bit for bit; a checkpoint at step 5 still at ``X0``, or at step 0
    with another state (edited), is refused (``RecordingError``, "does not match").  Written for the mutant
    ``pos.n != 0 or not array_equal(pos.X, X0)`` → ``and`` (either edit alone passed)."""
    import types

    from jetgaudin import run as rl
    from jetgaudin.run.driver import Position
    from jetgaudin.run.replay import replay

    spec = rl.RunSpec(MAP, X3, 100, 10)
    store = types.SimpleNamespace(rows=0, dn=np.zeros(0, dtype=np.int64), dS=np.zeros((0, 9)))
    assert replay(store, spec, Position(0, X3.copy(), None), None, "run.json") is spec
    for pos in (Position(5, X3.copy(), None), Position(0, X3 + 1e-9, None)):
        with pytest.raises(jg.RecordingError, match="does not match"):
            replay(store, spec, pos, None, "run.json")


def test_an_ensembles_calls_fill_the_chunk_memory_cap_and_no_more(tmp_path):
    """An ensemble of 4 orbits (compiled route): the driver's calls grow until their saved rows reach
    ``max_chunk_bytes`` (7 rows of 4 orbits of 9 doubles), never past it, and the run equals the one-call orbit bit
    for bit.  ``tests/test_reliability_runlayer.py`` checks one orbit, where a row is ``8 n`` bytes either way.
    Written for the mutant ``row_bytes = 8 * B * n`` → ``8 ** B * n`` (a batch's rows overcounted 128-fold: every
    call one row)."""
    from jetgaudin import run as rl

    X0 = np.stack([X3 * s for s in (1.0, 0.9, 1.1, 0.8)])
    sizes: list[int] = []

    class Spy(type(jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="compiled"))):
        def advance(self, X, carry, steps, save_every=1):
            adv = super().advance(X, carry, steps, save_every)
            sizes.append(int(np.asarray(adv.rows).nbytes))
            return adv

    spy = Spy(1.0, 5 + 0.1j, backend="compiled")
    cap = 7 * 4 * 72  # seven rows of 4 orbits of 9 doubles
    rl.start(rl.RunSpec(spy, X0, 600, 2, checkpoint_seconds=0.0), tmp_path / "r", max_chunk_bytes=cap)
    assert max(sizes) == cap
    d = rl.load(tmp_path / "r")
    ref = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="compiled").iterate(X0, 600)
    assert d.X.shape == (301, 4, 9) and np.array_equal(d.X, ref[d.n])
