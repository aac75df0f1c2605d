"""Issue 35, item 3: the library validates as the command line does.

* ``map_from_description`` with a missing key: :class:`jetgaudin.MapDescriptionError` naming it (before: a bare
  ``KeyError``);
* ``solve`` and every ``iterate`` refuse an output past ``jetgaudin.maps.output_cap()`` (``MAX_OUTPUT_BYTES``, by
  default half the physical memory) before allocating it
  (before: ``jg.solve(H, X0, (0, 1e9), dt=0.25)`` asked NumPy for hundreds of GiB), naming the size, the cap and
  the fix; the cap can be overridden;
* ``Trajectory.from_hdf5`` / ``to_hdf5`` refuse FIFOs, devices and symlinks without opening them (before: a FIFO
  hung the reader; a symlink was written through) and never replace a file without ``overwrite=True``."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

import jetgaudin as jg
import jetgaudin.maps as jmaps

from conftest import APPENDIX2_X0

X0 = np.array(APPENDIX2_X0)
H = jg.physical_hamiltonian(3, 1.0)


@pytest.mark.parametrize("key", ["b", "eta"])
def test_a_description_without_a_key_names_it(key):
    d = jg.TwoPointBacklund(1.0, 5 + 0.1j).describe()
    del d[key]
    with pytest.raises(jg.MapDescriptionError, match=repr(key)) as exc:
        jg.map_from_description(d)
    assert exc.value.key == key


def test_an_unknown_or_unhashable_kind_is_typed():
    with pytest.raises(jg.MapDescriptionError, match="unknown map kind"):
        jg.map_from_description({"kind": ["two_point"]})  # before: TypeError (unhashable)


@pytest.mark.parametrize("call", [
    lambda: jg.solve(H, X0, (0, 1e9), dt=0.25),
    lambda: jg.solve(H, X0, (0, 1e9), dt=0.25, method="dop853"),
    lambda: jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(X0, 10**12),
    lambda: jg.ExactFlow(H, 0.05).iterate(X0, 10**12),
    lambda: __import__("jetgaudin.ensemble").ensemble.iterate_ensemble(np.tile(X0, (4, 1)), 1.0, 5 + 0.1j, 10**12),
], ids=["solve exact", "solve dop853", "TwoPointBacklund.iterate", "Map.iterate", "iterate_ensemble"])
def test_outputs_past_the_cap_are_refused_before_allocation(call):
    with pytest.raises(jg.OutputTooLargeError, match="save_every") as exc:
        call()
    assert exc.value.nbytes > exc.value.cap == jmaps.output_cap() >= 1 << 30
    assert f"{exc.value.cap:,}" in str(exc.value)


def test_the_cap_is_overridable_and_counts_bytes(monkeypatch):
    m = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy")
    monkeypatch.setattr(jmaps, "MAX_OUTPUT_BYTES", 11 * 72)  # 11 rows of 9 doubles: exactly 10 steps
    assert m.iterate(X0, 10).shape == (11, 9)
    with pytest.raises(jg.OutputTooLargeError):
        m.iterate(X0, 11)
    assert m.iterate(X0, 20, save_every=2).shape == (11, 9)


# ------------------------------------------------------------------------------------------ Trajectory files
@pytest.fixture
def traj():
    return jg.solve(H, X0, (0.0, 0.5), dt=0.25)


def test_from_hdf5_refuses_a_fifo_without_opening_it(tmp_path):
    fifo = tmp_path / "t.h5"
    os.mkfifo(fifo)
    done = []
    t = threading.Thread(target=lambda: done.append(pytest.raises(jg.RecordingError, jg.Trajectory.from_hdf5, fifo)),
                         daemon=True)
    t.start()
    t.join(10)
    if t.is_alive():  # before: open() of the FIFO blocked for ever; unblock the thread, then fail
        with open(fifo, "wb"):
            pass
        pytest.fail("Trajectory.from_hdf5 blocked on a FIFO")
    assert done


@pytest.mark.parametrize("what", ["device", "symlink"])
def test_from_hdf5_refuses_devices_and_links(tmp_path, traj, what):
    if what == "device":
        path = "/dev/null"
    else:
        traj.to_hdf5(tmp_path / "real.h5")
        path = tmp_path / "link.h5"
        path.symlink_to(tmp_path / "real.h5")
    with pytest.raises(jg.RecordingError, match="symbolic link|not a regular file"):
        jg.Trajectory.from_hdf5(path)


def test_to_hdf5_never_replaces_without_overwrite_and_never_writes_through_a_link(tmp_path, traj):
    path = tmp_path / "t.h5"
    traj.to_hdf5(path)
    back = jg.Trajectory.from_hdf5(path)
    assert np.array_equal(back.X, traj.X) and np.array_equal(back.t, traj.t)
    kept = path.read_bytes()
    with pytest.raises(jg.RecordingError, match="overwrite=True"):
        traj.to_hdf5(path)
    assert path.read_bytes() == kept
    target = tmp_path / "precious"
    target.write_bytes(b"keep me")
    link = tmp_path / "link.h5"
    link.symlink_to(target)
    for ow in (False, True):
        with pytest.raises(jg.RecordingError, match="symbolic link"):
            traj.to_hdf5(link, overwrite=ow)
    assert target.read_bytes() == b"keep me"
    with pytest.raises(jg.RecordingError, match="not a regular file"):
        traj.to_hdf5("/dev/null", overwrite=True)
    jg.solve(H, X0, (0.0, 1.0), dt=0.25).to_hdf5(path, overwrite=True)
    assert len(jg.Trajectory.from_hdf5(path).t) == 5 and not (tmp_path / "t.h5.tmp").exists()
