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
