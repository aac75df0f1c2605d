"""Safe file primitives of run directories (``jetgaudin._fs``), each tested with the fault it guards against:
a second writer, a planted symlink, a FIFO or device, an oversized file, an I/O error or a full disk."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from jetgaudin import RecordingError
from jetgaudin import _fs as fs
from jetgaudin._errors import RunDirectoryError, RunIOError, RunLockedError


# ------------------------------------------------------------------------------------------------ lock
def test_second_lock_in_same_process_is_refused_with_pid(tmp_path):
    with fs.RunDirLock(tmp_path):
        with pytest.raises(RunLockedError, match=f"process {os.getpid()}"):
            fs.RunDirLock(tmp_path).acquire()
    # released: a new writer gets it
    with fs.RunDirLock(tmp_path) as lock:
        assert lock.held


_HOLD = """
import sys, time
from jetgaudin._fs import RunDirLock
lock = RunDirLock(sys.argv[1]).acquire()
print("locked", flush=True)
time.sleep(60)
"""


def _holder(path):
    proc = subprocess.Popen([sys.executable, "-c", _HOLD, str(path)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "locked"
    return proc


def test_lock_held_by_other_process_then_released_by_sigkill(tmp_path):
    proc = _holder(tmp_path)
    try:
        with pytest.raises(RunLockedError, match=f"process {proc.pid}"):
            fs.RunDirLock(tmp_path).acquire()
        with pytest.raises(RunLockedError):
            fs.check_new_run_dir(tmp_path, overwrite=True)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    # the kernel released the dead holder's lock: no stale lock
    with fs.RunDirLock(tmp_path):
        pass


def _planted(tmp_path, name):
    """A file ``victim`` ("precious") and an empty run directory whose ``name`` is a symlink to it."""
    victim = tmp_path / "victim"
    victim.write_text("precious")
    run = tmp_path / "run"
    run.mkdir()
    (run / name).symlink_to(victim)
    return victim, run


def test_lock_file_symlink_is_not_followed(tmp_path):
    victim, run = _planted(tmp_path, fs.LOCK_NAME)
    with pytest.raises(RunDirectoryError, match="symbolic link"):
        fs.RunDirLock(run).acquire()
    assert victim.read_text() == "precious"


# ----------------------------------------------------------------------------------------- new runs
def test_a_new_directory_that_cannot_be_created_is_refused_by_the_check(tmp_path):
    """Refused by the check itself (before a run compiles anything), leaving nothing behind: under /proc no
    directory can be made; under a read-only directory neither (as non-root); a new path deep below tmp_path is
    accepted and not created."""
    with pytest.raises(RunDirectoryError, match="--out: cannot create"):
        fs.check_new_run_dir("/proc/jetgaudin-x/run")
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        with pytest.raises(RunDirectoryError, match="cannot create"):
            fs.check_new_run_dir(ro / "a" / "b")
        ro.chmod(0o700)
    assert fs.check_new_run_dir(tmp_path / "x" / "y") == tmp_path / "x" / "y"
    assert sorted(p.name for p in tmp_path.iterdir()) == (["ro"] if os.geteuid() != 0 else [])


def test_check_new_run_dir_rules(tmp_path):
    assert fs.check_new_run_dir(tmp_path / "new") == tmp_path / "new"
    assert not (tmp_path / "new").exists()  # creates nothing
    empty = tmp_path / "empty"
    empty.mkdir()
    fs.check_new_run_dir(empty)
    with pytest.raises(RunDirectoryError, match="empty path"):
        fs.check_new_run_dir("  ")
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(RunDirectoryError, match="not a directory"):
        fs.check_new_run_dir(f, overwrite=True)
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("x")
    with pytest.raises(RunDirectoryError, match="not empty .*thesis.tex.*--overwrite"):
        fs.check_new_run_dir(foreign)
    fs.check_new_run_dir(foreign, overwrite=True)
    for status, hint in (("completed", False), ("failed: drift", False), ("interrupted", True)):
        run = tmp_path / status.split(":")[0]
        run.mkdir()
        (run / "run.json").write_text(json.dumps({"status": status}))
        with pytest.raises(RunDirectoryError, match=f"holds a run \\(status {status}\\)") as info:
            fs.check_new_run_dir(run, option="--out")
        assert ("--resume" in str(info.value)) == hint
        assert str(info.value).startswith("--out: ")
        fs.check_new_run_dir(run, overwrite=True)


def test_check_new_run_dir_unreadable_run_json_is_still_a_run(tmp_path):
    (tmp_path / "run.json").symlink_to("/dev/zero")
    with pytest.raises(RunDirectoryError, match="status unreadable"):
        fs.check_new_run_dir(tmp_path)


# -------------------------------------------------------------------------------------------- reads
def test_read_refuses_symlink_fifo_device_and_oversize(tmp_path):
    (tmp_path / "ok.json").write_text('{"a": 1}')
    assert fs.read_json(tmp_path, "ok.json") == {"a": 1}
    (tmp_path / "link").symlink_to(tmp_path / "ok.json")
    with pytest.raises(RunDirectoryError, match="symbolic link"):
        fs.read_bytes(tmp_path, "link", 100)
    os.mkfifo(tmp_path / "fifo")
    t0 = time.monotonic()
    with pytest.raises(RunDirectoryError, match="not a regular file"):
        fs.read_bytes(tmp_path, "fifo", 100)
    assert time.monotonic() - t0 < 5  # returns at once (O_NONBLOCK); a blocking open would hang here forever
    (tmp_path / "big").write_bytes(b"x" * 101)
    with pytest.raises(RunDirectoryError, match="101 bytes"):
        fs.read_bytes(tmp_path, "big", 100)
    assert fs.read_bytes(tmp_path, "big", 101) == b"x" * 101
    with pytest.raises(FileNotFoundError):
        fs.read_bytes(tmp_path, "absent", 100)
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(RecordingError, match="not valid JSON"):
        fs.read_json(tmp_path, "bad.json")


def test_read_user_file_follows_links_but_refuses_devices_and_fifos(tmp_path):
    (tmp_path / "in.txt").write_text("1 2 3")
    (tmp_path / "link").symlink_to(tmp_path / "in.txt")
    assert fs.read_user_file(tmp_path / "link", 100) == b"1 2 3"
    with pytest.raises(RunDirectoryError, match="--input: /dev/zero is not a regular file"):
        fs.read_user_file("/dev/zero", 100, option="--input")
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(RunDirectoryError, match="not a regular file"):
        fs.read_user_file(tmp_path / "fifo", 100)
    with pytest.raises(RunDirectoryError, match="does not exist"):
        fs.read_user_file(tmp_path / "nope", 100)


@pytest.mark.parametrize("name", ["../x", "a/b", "", ".", "..", "/etc/passwd", "x\0y"])
def test_names_must_stay_inside_the_directory(tmp_path, name):
    with pytest.raises(RecordingError, match="plain file name"):
        fs.read_bytes(tmp_path, name, 10)
    with pytest.raises(RecordingError, match="plain file name"):
        fs.atomic_write_text(tmp_path, name, "x")


# ------------------------------------------------------------------------------------------- writes
def test_atomic_write_replaces_and_removes_planted_tmp_link(tmp_path):
    victim, run = _planted(tmp_path, "run.json.tmp")
    fs.atomic_write_text(run, "run.json", "new")
    assert (run / "run.json").read_text() == "new"
    assert victim.read_text() == "precious"
    assert not os.path.lexists(run / "run.json.tmp")


def test_atomic_write_over_a_symlink_replaces_the_link_not_its_target(tmp_path):
    victim, run = _planted(tmp_path, "run.json")
    fs.atomic_write_text(run, "run.json", "new")
    assert not (run / "run.json").is_symlink() and (run / "run.json").read_text() == "new"
    assert victim.read_text() == "precious"


def test_open_write_refuses_symlink(tmp_path):
    victim, run = _planted(tmp_path, "orbit.csv")
    for append in (False, True):
        with pytest.raises(RunDirectoryError, match="symbolic link"):
            fs.open_write(run, "orbit.csv", append=append)
    assert victim.read_text() == "precious"
    with fs.open_write(run, "new.csv") as fh:
        fh.write(b"a\n")
    with fs.open_write(run, "new.csv", append=True) as fh:
        fh.write(b"b\n")
    assert (run / "new.csv").read_text() == "a\nb\n"
    with fs.open_write(run, "new.csv") as fh:  # truncates
        fh.write(b"c\n")
    assert (run / "new.csv").read_text() == "c\n"


def test_check_regular_or_absent(tmp_path):
    assert fs.check_regular_or_absent(tmp_path, "orbit.h5") is False
    (tmp_path / "orbit.h5").write_bytes(b"")
    assert fs.check_regular_or_absent(tmp_path, "orbit.h5") is True
    (tmp_path / "x.h5").symlink_to(tmp_path / "orbit.h5")
    with pytest.raises(RunDirectoryError, match="symbolic link"):
        fs.check_regular_or_absent(tmp_path, "x.h5")
    (tmp_path / "d.h5").mkdir()
    with pytest.raises(RunDirectoryError, match="not a regular file"):
        fs.check_regular_or_absent(tmp_path, "d.h5")


@pytest.mark.parametrize(("where", "err", "said"), [
    ("write", errno.ENOSPC, "disk full"),
    ("write", errno.EIO, "I/O error"),
    ("fsync", errno.EIO, "I/O error"),
    ("fsync", errno.EDQUOT, "disk full"),
    ("replace", errno.EIO, "I/O error"),
])
def test_atomic_write_fault_keeps_old_file_and_leaves_no_tmp(tmp_path, monkeypatch, where, err, said):
    fs.atomic_write_text(tmp_path, "run.json", "old")
    real = {"write": os.write, "fsync": os.fsync, "replace": os.replace}[where]

    def boom(*args, **kwargs):
        raise OSError(err, os.strerror(err))

    monkeypatch.setattr(os, where, boom)
    with pytest.raises(RunIOError, match=said):
        fs.atomic_write_text(tmp_path, "run.json", "new")
    monkeypatch.setattr(os, where, real)
    assert (tmp_path / "run.json").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]


def test_io_failure_messages():
    assert fs.io_failure(OSError(errno.ENOSPC, "No space left on device")) == "disk full"
    assert fs.io_failure(RuntimeError("Can't write data (no space left on device)")) == "disk full"
    assert fs.io_failure(OSError(errno.EIO, "Input/output error", "x.h5")) == "I/O error (Input/output error: x.h5)"
    try:
        try:
            raise OSError(errno.ENOSPC, "full")
        except OSError as inner:
            raise RuntimeError("HDF5 write failed") from inner
    except RuntimeError as outer:
        assert fs.is_disk_full(outer)
    assert fs.io_failure(RuntimeError("HDF5\n  write\tfailed")) == "I/O error (HDF5 write failed)"


def test_real_full_disk_is_reported_as_disk_full(tmp_path):
    """A real ENOSPC (``/dev/full`` fails every write with it), not only a simulated one."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    with open("/dev/full", "wb", buffering=0) as fh, pytest.raises(OSError) as info:
        fh.write(b"x")
    assert fs.io_failure(info.value) == "disk full"


def test_reserved_space_cannot_be_taken_by_another_writer(tmp_path):
    """Issue 26: ``_space.reserve_space`` allocates the blocks past the end of a file (``FALLOC_FL_KEEP_SIZE``), so
    that a library that crashes on ENOSPC (HDF5) can write them even after the disk filled up; a reservation that
    does not fit is a ``RunIOError`` saying ``disk full`` before anything is written; the file size limit too."""
    import resource
    import subprocess

    from jetgaudin import _space

    m = tmp_path / "M"
    m.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", str(m)],
                                           capture_output=True).returncode != 0:
        pytest.skip("mount -t tmpfs is not permitted here")
    try:
        (m / "data").write_bytes(b"head")
        _space.reserve_space(m, "data", 200 << 10)
        assert (m / "data").stat().st_size == 4  # the size is unchanged
        with open(m / "filler", "wb", buffering=0) as fh, pytest.raises(OSError) as info:  # another writer fills it
            while True:
                fh.write(b"\0" * 4096)

        assert info.value.errno == errno.ENOSPC
        with open(m / "data", "ab") as fh:  # the reserved bytes are still there
            fh.write(b"x" * (200 << 10))
        with pytest.raises(RunIOError, match="^disk full"):
            _space.reserve_space(m, "data", 1 << 20)
        os.unlink(m / "filler")
        soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        resource.setrlimit(resource.RLIMIT_FSIZE, (100 << 10, hard))
        try:
            with pytest.raises(RunIOError, match="file size limit"):
                _space.reserve_space(m, "data", 1)
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    finally:
        subprocess.run(["umount", "-l", str(m)], check=False)
