"""Disk space for libraries that cannot survive a failed write (private; ``docs/reliability.md``).

HDF5 crashes the process (SIGSEGV/SIGBUS in ``H5D_close``) after a real ``ENOSPC`` or ``EFBIG``; a replaced
``fsync`` never shows it.  So the run layer reserves, before HDF5 writes, the bytes it may write
(:func:`reserve_space`: the file size limit checked, the blocks allocated past the end of the file with
``fallocate(FALLOC_FL_KEEP_SIZE)``), gives back what was not used (:func:`release_space`), and keeps a reserve file
(:func:`make_reserve`) that it removes first on a full disk so that the last ``run.json`` can be written
(:func:`release_reserve`).
"""

from __future__ import annotations

import contextlib
import errno
import os
from pathlib import Path
from typing import Any

from ._errors import RunDirectoryError, RunIOError
from ._fs import FILE_SIZE_LIMIT, io_failure, open_dir, open_nofollow, plain_name, remove_file

__all__ = ["RESERVE_NAME", "reserve_space", "release_space", "make_reserve", "release_reserve"]

#: the space a writer keeps in its run directory for the ``run.json`` that records a full disk (removed first then)
RESERVE_NAME = ".jetgaudin-reserve"
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_FALLOC_FL_KEEP_SIZE = 1
_fallocate: Any = None


def _fallocate_keep_size(fd: int, offset: int, length: int) -> None:
    """Linux ``fallocate(fd, FALLOC_FL_KEEP_SIZE, offset, length)``: give the file the disk blocks of
    ``[offset, offset + length)`` without changing its size (``OSError`` with ``EOPNOTSUPP`` where unsupported)."""
    global _fallocate
    if _fallocate is None:
        import ctypes
        import ctypes.util
        import sys

        fn: Any = False
        if sys.platform.startswith("linux"):
            with contextlib.suppress(OSError, AttributeError):
                libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
                fn = libc.fallocate
                fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int64, ctypes.c_int64]
                fn.restype = ctypes.c_int
        _fallocate = fn
    if not _fallocate:
        raise OSError(errno.EOPNOTSUPP, "fallocate is not available")
    import ctypes

    if _fallocate(fd, _FALLOC_FL_KEEP_SIZE, offset, length) != 0:
        e = ctypes.get_errno()
        raise OSError(e, os.strerror(e))


def reserve_space(dirpath: str | os.PathLike[str], name: str, nbytes: int, *, what: str = "writing") -> None:
    """Make the next ``nbytes`` bytes written past the end of ``dirpath/name`` safe from a full disk and from the
    file size limit, *before* a library that cannot survive a failed write (HDF5 crashes the process on a real
    ``ENOSPC``/``EFBIG``: ``docs/reliability.md``) writes them.

    The file's size plus ``nbytes`` must fit the process's ``RLIMIT_FSIZE`` (``ulimit -f``), and the blocks of
    ``[size, size + nbytes)`` are allocated to the file without changing its size (``fallocate`` with
    ``FALLOC_FL_KEEP_SIZE``; where unsupported, the free space of the file system is checked instead, which a
    concurrent writer of the same file system can still race).  Raises :class:`~jetgaudin.RunIOError` saying
    ``disk full`` or ``file size limit reached (ulimit -f)``; nothing is written to the file."""
    import resource

    dirpath = Path(dirpath)
    nbytes = max(0, int(nbytes))
    with open_dir(dirpath) as dfd:
        fd = open_nofollow(dfd, dirpath, plain_name(name), os.O_WRONLY)
        try:
            size = os.fstat(fd).st_size
            soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
            if soft != resource.RLIM_INFINITY and size + nbytes > soft:
                raise RunIOError(f"{FILE_SIZE_LIMIT} while {what} {dirpath / name}")
            try:
                _fallocate_keep_size(fd, size, nbytes)
            except OSError as exc:
                if exc.errno in (errno.ENOSPC, errno.EDQUOT):
                    raise RunIOError(f"disk full while {what} {dirpath / name}") from exc
                if exc.errno == errno.EFBIG:
                    raise RunIOError(f"{FILE_SIZE_LIMIT} while {what} {dirpath / name}") from exc
                st = os.fstatvfs(fd)  # no fallocate here: the free space, checked
                if st.f_bavail * st.f_frsize < nbytes:
                    raise RunIOError(f"disk full while {what} {dirpath / name}") from None
        finally:
            os.close(fd)


def release_space(dirpath: str | os.PathLike[str], name: str) -> None:
    """Give back the blocks :func:`reserve_space` allocated past the end of ``dirpath/name`` and the writer did not
    use (``ftruncate`` to the file's own size frees them on Linux file systems; the content is untouched)."""
    dirpath = Path(dirpath)
    with contextlib.suppress(OSError, RunDirectoryError), open_dir(dirpath) as dfd:
        fd = open_nofollow(dfd, dirpath, plain_name(name), os.O_WRONLY)
        try:
            os.ftruncate(fd, os.fstat(fd).st_size)
        finally:
            os.close(fd)


def make_reserve(dirpath: str | os.PathLike[str], nbytes: int) -> None:
    """Create :data:`RESERVE_NAME` in ``dirpath`` holding ``nbytes`` allocated bytes (removed by
    :func:`release_reserve` when the disk is full, so that ``run.json`` can still record it)."""
    dirpath = Path(dirpath)
    with open_dir(dirpath) as dfd:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(RESERVE_NAME, dir_fd=dfd)
        try:
            fd = os.open(RESERVE_NAME, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC, 0o644,
                         dir_fd=dfd)
        except OSError as exc:
            raise RunIOError(f"{io_failure(exc)} while writing {dirpath / RESERVE_NAME}") from exc
        try:
            try:
                _fallocate_keep_size(fd, 0, nbytes)
            except OSError as exc:
                if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
                    raise
                os.write(fd, bytes(nbytes))  # no fallocate: real zeros hold the blocks
        except OSError as exc:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(RESERVE_NAME, dir_fd=dfd)
            raise RunIOError(f"{io_failure(exc)} while writing {dirpath / RESERVE_NAME}") from exc
        os.close(fd)


def release_reserve(dirpath: str | os.PathLike[str]) -> None:
    """Remove :data:`RESERVE_NAME` (best effort: frees its space for the last ``run.json``)."""
    with contextlib.suppress(OSError, RunDirectoryError):
        remove_file(dirpath, RESERVE_NAME)
