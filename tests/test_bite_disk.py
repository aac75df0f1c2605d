"""Disk handling (``jetgaudin._fs``): the properties the mutation sample of issue 33 found unchecked.

Each test names the mutant (``docs/mutation.md``) it was written for; each was run on its mutant, planted by hand, and
fails there.  No numerical tolerances: byte counts and classifications are exact.
"""

from __future__ import annotations

import errno
import os

import pytest

from jetgaudin import _fs as fs
from jetgaudin._errors import RunDirectoryError


def _chain(leaf: BaseException, depth: int, *, implicit: bool) -> BaseException:
    """``leaf`` wrapped ``depth`` times, each wrapper raised while handling the one below: ``__context__`` (implicit,
    a bare ``raise`` in an ``except`` block) or ``__cause__`` (``raise ... from``)."""
    exc = leaf
    for k in range(depth):
        outer = RuntimeError(f"wrapper {k}")
        if implicit:
            outer.__context__ = exc
        else:
            outer.__cause__ = exc
        exc = outer
    return exc


@pytest.mark.parametrize("implicit", [True, False])
def test_full_disk_and_size_limit_are_found_at_the_same_depth(implicit):
    """``io_failure`` follows an error's causes (explicit) and contexts (implicit) through the same 8 links for a full
    disk (ENOSPC) and for the file size limit (EFBIG), so an error gets one name however it was wrapped: found with 7
    wrappers above it, not with 8 (the bound that stops a cyclic chain).  Written for the mutant ``seen = 0`` →
    ``seen = -1`` in ``_is_too_large`` (9 links for EFBIG against 8 for ENOSPC)."""
    for depth, found in ((0, True), (7, True), (8, False)):
        full = _chain(OSError(errno.ENOSPC, "x"), depth, implicit=implicit)
        big = _chain(OSError(errno.EFBIG, "x"), depth, implicit=implicit)
        assert fs.is_disk_full(full) is found
        assert fs._is_too_large(big) is found
        assert fs.io_failure(full) == ("disk full" if found else "I/O error (wrapper 7)")
        assert fs.io_failure(big) == (fs.FILE_SIZE_LIMIT if found else "I/O error (wrapper 7)")


def test_a_cyclic_error_chain_ends():
    """An exception whose context chain is a cycle (a handler that re-raises an earlier error) is classified, not
    followed for ever."""
    a, b = RuntimeError("a"), RuntimeError("b")
    a.__context__, b.__context__ = b, a
    assert not fs.is_disk_full(a) and not fs._is_too_large(a)
    assert fs.io_failure(a) == "I/O error (a)"


def test_a_bounded_read_asks_for_at_most_one_byte_past_the_cap(tmp_path, monkeypatch):
    """``read_bytes(..., max_bytes)`` reads in bounded memory: the requests add up to at most ``max_bytes + 1`` bytes
    (the one byte more tells a file that grew past the cap while it was read), for a file at the cap and one that
    grows by a megabyte under it (the growth simulated by ``os.read``).  Written for the mutant ``max_bytes + 1`` →
    ``max_bytes + 2``."""
    cap = 1000
    (tmp_path / "f").write_bytes(b"x" * cap)
    asked: list[int] = []
    real = os.read

    def spy(fd, n):
        asked.append(n)
        return real(fd, n)

    monkeypatch.setattr(os, "read", spy)
    assert fs.read_bytes(tmp_path, "f", cap) == b"x" * cap
    assert asked == [cap + 1, 1]  # the whole file and one byte more; the second request finds the end

    asked.clear()

    def growing(fd, n):  # the file grew after the size check: every read returns all it is asked for
        asked.append(n)
        return b"y" * n

    monkeypatch.setattr(os, "read", growing)
    (tmp_path / "g").write_bytes(b"")
    with pytest.raises(RunDirectoryError, match="larger than the 1000 bytes"):
        fs.read_bytes(tmp_path, "g", cap)
    assert sum(asked) == cap + 1  # read one byte past the cap, then refused: no more is taken in


def test_the_file_size_limit_is_checked_on_the_size_plus_the_bytes_to_the_byte(tmp_path, monkeypatch):
    """``_space.reserve_space`` under a soft ``RLIMIT_FSIZE`` of 1000 bytes (faked; fallocate faked to succeed): a
    file of 100 bytes takes 900 more (``size + nbytes`` equal to the limit is allowed), not 901, and nothing is
    written.  Written for the mutants of that line (``docs/mutation.md``, issue 33 sample of ``_space.py``):
    ``size + nbytes`` → ``size × nbytes`` or ``size ÷ nbytes``, ``>`` → ``≤``, ``soft != RLIM_INFINITY`` →
    ``soft < RLIM_INFINITY`` (``RLIM_INFINITY`` is −1 on Linux: the check never fires)."""
    import resource

    from jetgaudin import _space
    from jetgaudin._errors import RunIOError

    (tmp_path / "f").write_bytes(b"x" * 100)
    real = resource.getrlimit
    monkeypatch.setattr(resource, "getrlimit",
                        lambda which: (1000, resource.RLIM_INFINITY) if which == resource.RLIMIT_FSIZE else real(which))
    monkeypatch.setattr(_space, "_fallocate_keep_size", lambda fd, offset, length: None)
    _space.reserve_space(tmp_path, "f", 900)
    with pytest.raises(RunIOError, match="file size limit"):
        _space.reserve_space(tmp_path, "f", 901)
    assert (tmp_path / "f").stat().st_size == 100


def test_without_fallocate_the_free_space_is_checked_to_the_byte(tmp_path, monkeypatch):
    """Where ``fallocate`` is unsupported (``EOPNOTSUPP``, faked) ``reserve_space`` compares the bytes with the file
    system's free space ``f_bavail × f_frsize`` (faked: 10 blocks of 4096 bytes): 40960 bytes fit, 40961 are a
    full disk, one line naming it.  Written for the mutants ``f_bavail × f_frsize`` → ``f_bavail + f_frsize`` and
    ``<`` → ``==`` (``docs/mutation.md``)."""
    from types import SimpleNamespace

    from jetgaudin import _space
    from jetgaudin._errors import RunIOError

    def unsupported(fd, offset, length):
        raise OSError(errno.EOPNOTSUPP, "fallocate is not available")

    (tmp_path / "f").write_bytes(b"")
    monkeypatch.setattr(_space, "_fallocate_keep_size", unsupported)
    monkeypatch.setattr(_space.os, "fstatvfs", lambda fd: SimpleNamespace(f_bavail=10, f_frsize=4096))
    _space.reserve_space(tmp_path, "f", 40960)
    with pytest.raises(RunIOError, match="disk full") as e:
        _space.reserve_space(tmp_path, "f", 40961)
    assert "\n" not in str(e.value)


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_a_resume_without_a_lock_file_takes_the_lock_when_it_claims(tmp_path):
    """``RunDirLock(create=False, claim=False)`` (a resume checking its run) on a directory without a lock file takes
    nothing on entry and leaves the directory as it was; ``claim()`` then creates the lock file, takes the lock (a
    second writer is refused naming this process) and writes this PID.  Written for the mutant
    ``self._create, self._claim = True, True`` → ``False, True`` in ``claim`` (the lock was then never taken)."""
    from jetgaudin._errors import RunLockedError

    lock = fs.RunDirLock(tmp_path, claim=False, create=False)
    with lock:
        assert not lock.held and not (tmp_path / fs.LOCK_NAME).exists()
        lock.claim()
        assert lock.held and (tmp_path / fs.LOCK_NAME).read_text() == f"{os.getpid()}\n"
        with pytest.raises(RunLockedError, match=f"process {os.getpid()}"):
            fs.RunDirLock(tmp_path).acquire()


def test_a_resume_with_a_lock_file_claims_it_with_its_pid(tmp_path):
    """A lock file left by an earlier writer (its PID, which has exited): ``RunDirLock(create=False, claim=False)``
    takes the lock on entry without writing; ``claim()`` replaces the old PID by this one.  Written for the mutant
    ``O_CREAT if self._create else 0`` → ``else 1`` (``O_RDWR | O_WRONLY``: a descriptor that can neither read nor
    write, so the PID was never written)."""
    (tmp_path / fs.LOCK_NAME).write_text("999999999\n")
    lock = fs.RunDirLock(tmp_path, claim=False, create=False)
    with lock:
        assert lock.held and (tmp_path / fs.LOCK_NAME).read_text() == "999999999\n"
        lock.claim()
        assert (tmp_path / fs.LOCK_NAME).read_text() == f"{os.getpid()}\n"


def test_files_are_created_rw_r__r__and_rewritten_from_empty(tmp_path):
    """``open_write`` creates a run file with mode ``0o644`` (under umask 0o022: readable by everyone, executable by
    none) and truncates an existing one: rewritten with nothing it is empty.  Written for the mutants
    ``mode=0o644`` → ``419`` (``0o643``) in ``open_nofollow`` and ``os.ftruncate(fd, 0)`` → ``(fd, 1)`` (a byte of
    the old content was left)."""
    old = os.umask(0o022)
    try:
        with fs.open_write(tmp_path, "a.txt") as f:
            f.write(b"hello")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
    with fs.open_write(tmp_path, "a.txt"):
        pass
    assert (tmp_path / "a.txt").read_bytes() == b""


def test_a_reserve_that_cannot_be_created_is_one_io_error_naming_it(tmp_path, monkeypatch):
    """``make_reserve`` where creating the reserve file fails (ENOSPC, planted in ``os.open``): a ``RunIOError``
    saying ``disk full`` and naming the reserve's path, no other exception.  Written for the mutant
    ``dirpath / RESERVE_NAME`` → ``dirpath * RESERVE_NAME`` in that message (a TypeError instead)."""
    from jetgaudin import _space
    from jetgaudin._errors import RunIOError

    real_open = os.open

    def full(name, *args, **kwargs):
        if name == _space.RESERVE_NAME:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_open(name, *args, **kwargs)

    monkeypatch.setattr(os, "open", full)
    with pytest.raises(RunIOError, match="disk full") as e:
        _space.make_reserve(tmp_path, 4096)
    assert str(tmp_path / _space.RESERVE_NAME) in str(e.value)
