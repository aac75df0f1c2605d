"""Safe file primitives for run directories: one writer, no symlink followed, nothing unbounded read.

The run layer writes and reads every file of a run directory through this module, so the rules of
``docs/reliability.md`` hold in one place:

* **One writer per directory**: :class:`RunDirLock` holds an exclusive ``flock`` on ``<dir>/.jetgaudin.lock``
  for the run's life; the kernel releases it when the process dies (even by SIGKILL).  A second writer, of any
  kind and in any process, gets :class:`~jetgaudin.RunLockedError` naming the holder's PID.
* **No symlink is followed** inside a run directory, and no file with more than one hard link is used: files are
  opened relative to a descriptor of the directory
  with ``O_NOFOLLOW``, temporary files are created with ``O_EXCL`` after removing a stale entry (``unlink``
  removes a link, never its target), and names must be plain file names (no ``/``, no ``..``).
* **Nothing is read without a bound**: reads open with ``O_NONBLOCK`` (a FIFO cannot block), accept regular files
  only, and refuse files larger than the caller's cap before reading them.
* **Durable before declared**: :func:`atomic_write_bytes` writes ``name.tmp``, fsyncs it, renames it over
  ``name`` and fsyncs the directory; an ``OSError`` on the way leaves ``name`` as it was, removes the ``.tmp``
  and raises :class:`~jetgaudin.RunIOError` whose message says ``disk full`` or ``I/O error``.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ._errors import RecordingError, RunDirectoryError, RunIOError, RunLockedError

__all__ = [
    "LOCK_NAME",
    "RunDirLock",
    "check_new_run_dir",
    "clearable",
    "make_run_dir",
    "plain_name",
    "open_dir",
    "open_write",
    "open_nofollow",
    "atomic_write_bytes",
    "atomic_write_text",
    "read_bytes",
    "read_text",
    "read_json",
    "read_user_file",
    "check_library_file",
    "check_regular_or_absent",
    "remove_file",
    "fsync_file",
    "fsync_dir",
    "io_failure",
    "is_disk_full",
    "FILE_SIZE_LIMIT",
]

#: the lock file every writer holds (never deleted: deleting a lock file races with its next holder)
LOCK_NAME = ".jetgaudin.lock"
#: ``run.json`` marks a directory as a jetgaudin run
_RUN_JSON = "run.json"
#: the cap for reading ``run.json`` when classifying a directory
_RUN_JSON_CAP = 1 << 20

_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)


# ------------------------------------------------------------------------------------------- names
def plain_name(name: str) -> str:
    """``name`` if it is a plain file name inside a directory (no separator, not ``.``/``..``, no NUL), else
    :class:`~jetgaudin.RecordingError` (e.g. a checkpoint path in ``run.json`` pointing outside the run)."""
    if (not isinstance(name, str) or name in ("", ".", "..") or "/" in name or "\0" in name
            or (os.altsep and os.altsep in name)):
        raise RecordingError(f"{name!r} is not a plain file name inside the run directory; refusing to use it")
    return name


@contextlib.contextmanager
def open_dir(path: str | os.PathLike[str]) -> Iterator[int]:
    """A descriptor of the directory ``path`` (the directory itself may be reached through a symlink the user
    chose; the files in it are then opened relative to it with ``O_NOFOLLOW``)."""
    try:
        fd = os.open(path, os.O_RDONLY | _DIRECTORY | _CLOEXEC)
    except FileNotFoundError:
        raise RunDirectoryError(f"{path} does not exist") from None
    except NotADirectoryError:
        raise RunDirectoryError(f"{path} is not a directory") from None
    except OSError as exc:
        raise RunDirectoryError(f"cannot open directory {path}: {exc.strerror or exc}") from None
    try:
        yield fd
    finally:
        os.close(fd)


def _refuse_special(path: Path, st: os.stat_result) -> None:
    if stat.S_ISLNK(st.st_mode):
        raise RunDirectoryError(f"{path} is a symbolic link; a run directory holds regular files only "
                                "(remove the link)")
    if not stat.S_ISREG(st.st_mode):
        raise RunDirectoryError(f"{path} is not a regular file (a FIFO, device or directory); remove it")
    if st.st_nlink > 1:  # a hard link: writing it (an append to orbit.csv) would write another name's file too
        raise RunDirectoryError(f"{path} has {st.st_nlink} hard links; a run directory holds files of its own only "
                                "(copy it instead of linking it: cp, not ln)")


def open_nofollow(dfd: int, dirpath: Path, name: str, flags: int, mode: int = 0o644) -> int:
    """``os.open`` of ``name`` relative to ``dfd`` with ``O_NOFOLLOW``, refusing links and non-regular files."""
    try:
        fd = os.open(name, flags | _NOFOLLOW | _CLOEXEC, mode, dir_fd=dfd)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise RunDirectoryError(f"{dirpath / name} is a symbolic link; a run directory holds regular files "
                                    "only (remove the link)") from None
        raise
    try:
        st = os.fstat(fd)
        _refuse_special(dirpath / name, st)
    except BaseException:
        os.close(fd)
        raise
    return fd


def check_regular_or_absent(dirpath: str | os.PathLike[str], name: str) -> bool:
    """``True`` if ``dirpath/name`` is a regular file, ``False`` if absent; :class:`~jetgaudin.RunDirectoryError`
    for a symlink, FIFO, device or directory (for files opened by libraries that take a path, e.g. HDF5)."""
    path = Path(dirpath) / plain_name(name)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return False
    _refuse_special(path, st)
    return True


def remove_file(dirpath: str | os.PathLike[str], name: str) -> None:
    """Remove ``dirpath/name`` if present (a symlink is removed itself, its target untouched)."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(Path(dirpath) / plain_name(name))


# ------------------------------------------------------------------------------------------ errors
def is_disk_full(exc: BaseException) -> bool:
    """Whether ``exc`` (or the exception it was raised from) is a full disk or an exceeded quota."""
    seen = 0
    while exc is not None and seen < 8:
        if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
            return True
        text = str(exc).lower()
        if "no space left" in text or "disk quota" in text or text.startswith("disk full"):
            return True
        exc = exc.__cause__ or exc.__context__  # type: ignore[assignment]
        seen += 1
    return False


def _is_too_large(exc: BaseException) -> bool:
    seen = 0
    while exc is not None and seen < 8:
        if isinstance(exc, OSError) and exc.errno == errno.EFBIG:
            return True
        if "file too large" in str(exc).lower() or str(exc).startswith(FILE_SIZE_LIMIT):
            return True
        exc = exc.__cause__ or exc.__context__  # type: ignore[assignment]
        seen += 1
    return False


def io_failure(exc: BaseException) -> str:
    """One line for a failed write: ``"disk full"``, ``"file size limit reached (ulimit -f)"`` or
    ``"I/O error (...)"`` (HDF5 errors included)."""
    if is_disk_full(exc):
        return "disk full"
    if _is_too_large(exc):
        return FILE_SIZE_LIMIT
    if isinstance(exc, RunIOError):
        return str(exc)
    if isinstance(exc, OSError) and exc.strerror:
        what = exc.strerror + (f": {exc.filename}" if exc.filename else "")
    else:
        what = " ".join(str(exc).split())[:200] or type(exc).__name__
    return f"I/O error ({what})"


#: the failure of a write past the process's file size limit (``ulimit -f``, EFBIG)
FILE_SIZE_LIMIT = "file size limit reached (ulimit -f)"
# -------------------------------------------------------------------------------------------- sync
def fsync_dir(dirpath: str | os.PathLike[str]) -> None:
    """fsync the directory entry table (after a rename or a file creation)."""
    with open_dir(dirpath) as dfd:
        os.fsync(dfd)


def fsync_file(dirpath: str | os.PathLike[str], name: str) -> None:
    """fsync ``dirpath/name`` (a regular file, opened without following links)."""
    dirpath = Path(dirpath)
    with open_dir(dirpath) as dfd:
        fd = open_nofollow(dfd, dirpath, plain_name(name), os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


# ------------------------------------------------------------------------------------------ writes
def open_write(dirpath: str | os.PathLike[str], name: str, *, append: bool = False):
    """A binary file object writing ``dirpath/name`` (created if absent; truncated unless ``append``), opened with
    ``O_NOFOLLOW``: a symlink in its place is refused, never followed."""
    dirpath = Path(dirpath)
    flags = os.O_WRONLY | os.O_CREAT | (os.O_APPEND if append else 0)
    with open_dir(dirpath) as dfd:
        fd = open_nofollow(dfd, dirpath, plain_name(name), flags)
    if not append:
        try:
            os.ftruncate(fd, 0)
        except BaseException:
            os.close(fd)
            raise
    return os.fdopen(fd, "ab" if append else "wb")


def atomic_write_bytes(dirpath: str | os.PathLike[str], name: str, data: bytes | memoryview) -> None:
    """Replace ``dirpath/name`` by ``data`` durably: write ``name.tmp`` (created with ``O_EXCL|O_NOFOLLOW``
    after removing any stale entry), fsync it, rename it over ``name``, fsync the directory.

    On an ``OSError`` the old ``name`` is untouched, the ``.tmp`` is removed (best effort) and
    :class:`~jetgaudin.RunIOError` says ``disk full`` or ``I/O error (...)``."""
    dirpath = Path(dirpath)
    name = plain_name(name)
    tmp = name + ".tmp"
    with open_dir(dirpath) as dfd:
        try:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp, dir_fd=dfd)  # a stale file or a planted symlink: removed, its target untouched
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC, 0o644, dir_fd=dfd)
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view):]
                os.fsync(fd)
            finally:
                os.close(fd)
            os.replace(tmp, name, src_dir_fd=dfd, dst_dir_fd=dfd)
            os.fsync(dfd)
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.unlink(tmp, dir_fd=dfd)
            raise RunIOError(f"{io_failure(exc)} while writing {dirpath / name}") from exc


def atomic_write_text(dirpath: str | os.PathLike[str], name: str, text: str) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text."""
    atomic_write_bytes(dirpath, name, text.encode("utf-8"))


# ------------------------------------------------------------------------------------------- reads
def _read_fd(fd: int, path: Path, max_bytes: int) -> bytes:
    size = os.fstat(fd).st_size
    if size > max_bytes:
        raise RunDirectoryError(f"{path} is {size} bytes, more than the {max_bytes} a valid file can have; "
                                "it is not a file of this run")
    chunks, total = [], 0
    while True:
        chunk = os.read(fd, min(1 << 20, max_bytes + 1 - total))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
        if total > max_bytes:  # grew while we read
            raise RunDirectoryError(f"{path} is larger than the {max_bytes} bytes a valid file can have")
    return b"".join(chunks)


def read_bytes(dirpath: str | os.PathLike[str], name: str, max_bytes: int) -> bytes:
    """The content of ``dirpath/name``: a regular file (not a link, FIFO or device) of at most ``max_bytes``
    bytes.  ``FileNotFoundError`` if absent; :class:`~jetgaudin.RunDirectoryError` otherwise."""
    dirpath = Path(dirpath)
    name = plain_name(name)
    with open_dir(dirpath) as dfd:
        fd = open_nofollow(dfd, dirpath, name, os.O_RDONLY | os.O_NONBLOCK)
        try:
            return _read_fd(fd, dirpath / name, max_bytes)
        finally:
            os.close(fd)


def read_text(dirpath: str | os.PathLike[str], name: str, max_bytes: int) -> str:
    """:func:`read_bytes` decoded as UTF-8 (undecodable bytes replaced)."""
    return read_bytes(dirpath, name, max_bytes).decode("utf-8", errors="replace")


def read_json(dirpath: str | os.PathLike[str], name: str, max_bytes: int = _RUN_JSON_CAP) -> Any:
    """The parsed JSON of ``dirpath/name`` (:func:`read_bytes` rules); :class:`~jetgaudin.RecordingError` if it
    is not valid JSON."""
    text = read_text(dirpath, name, max_bytes)
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        raise RecordingError(f"{Path(dirpath) / name} is not valid JSON (corrupted); cannot use it") from None


def read_user_file(path: str | os.PathLike[str], max_bytes: int, *, option: str = "file") -> bytes:
    """The content of a file the user names (e.g. ``--input``): symlinks allowed (the user chose the path), but
    only a regular file of at most ``max_bytes`` bytes; never blocks on a FIFO."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | _CLOEXEC)
    except FileNotFoundError:
        raise RunDirectoryError(f"{option}: {path} does not exist") from None
    except OSError as exc:
        raise RunDirectoryError(f"{option}: cannot read {path}: {exc.strerror or exc}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise RunDirectoryError(f"{option}: {path} is not a regular file (a FIFO, device or directory)")
        return _read_fd(fd, path, max_bytes)
    finally:
        os.close(fd)


def check_library_file(path: str | os.PathLike[str], *, write: bool = False, overwrite: bool = False) -> Path:
    """A file path a library call reads (``write=False``) or writes (:meth:`jetgaudin.Trajectory.from_hdf5`,
    ``to_hdf5``), checked with ``lstat`` before anything opens it (a FIFO is never opened: opening one blocks):
    a symbolic link, a FIFO, a device or a directory is refused (:class:`~jetgaudin.RecordingError`); reading needs
    an existing regular file; writing refuses an existing file unless ``overwrite``."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        if write:
            return path
        raise RecordingError(f"{path} does not exist") from None
    except OSError as exc:
        raise RecordingError(f"cannot use {path}: {exc.strerror or exc}") from None
    if stat.S_ISLNK(st.st_mode):
        raise RecordingError(f"{path} is a symbolic link; give the file itself (links are not followed)")
    if not stat.S_ISREG(st.st_mode):
        raise RecordingError(f"{path} is not a regular file (a FIFO, device or directory); give a file")
    if write and not overwrite:
        raise RecordingError(f"{path} exists; pass overwrite=True to replace it, or choose another file")
    return path


# ------------------------------------------------------------------------------------ directories
def _run_status(path: Path) -> str:
    try:
        data = read_json(path, _RUN_JSON)
        status = data.get("status") if isinstance(data, dict) else None
        return str(status) if status is not None else "unreadable"
    except (OSError, RecordingError):
        return "unreadable"


def check_new_run_dir(path: str | os.PathLike[str], *, overwrite: bool = False, option: str = "--out") -> Path:
    """Check that a new run may be written to ``path``; create nothing.

    Accepted: a path that does not exist (its parent must be a directory or creatable), an empty directory, or,
    with ``overwrite=True``, a directory holding a run or other files, unless a live process holds its lock.
    Refused (:class:`~jetgaudin.RunDirectoryError`, :class:`~jetgaudin.RunLockedError`): an empty path, a path
    that is not a directory, a directory holding a run (any status) or foreign files without ``overwrite``."""
    if str(path).strip() == "":
        raise RunDirectoryError(f"{option}: empty path; give a directory name (an empty one would write into the "
                                "current directory)")
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        _probe_creatable(path, option)
        return path
    except OSError as exc:
        raise RunDirectoryError(f"{option}: cannot use {path}: {exc.strerror or exc}") from None
    if not stat.S_ISDIR(st.st_mode):
        raise RunDirectoryError(f"{option}: {path} exists and is not a directory; choose another {option}")
    entries = sorted(e for e in os.listdir(path) if e != LOCK_NAME)
    if not entries:
        _probe_lock(path, option)
        return path
    if overwrite:
        clearable(path, entries, option)
    if not overwrite:
        if _RUN_JSON in entries:
            status = _run_status(path)
            hint = f"continue it with --resume {path}, " if status in ("running", "interrupted") else ""
            raise RunDirectoryError(f"{option}: {path} holds a run (status {status}); {hint}pass --overwrite to "
                                    "replace it, or choose another directory")
        shown = ", ".join(entries[:3]) + (", ..." if len(entries) > 3 else "")
        raise RunDirectoryError(f"{option}: {path} is not empty (it holds {shown}); choose an empty or new "
                                "directory, or pass --overwrite")
    _probe_lock(path, option)
    return path


def clearable(path: Path, entries: list[str], option: str = "--overwrite") -> list[str]:
    """The entries ``--overwrite`` removes from ``path`` (all but the lock), after checking that every one is a
    file or a link (removed itself, never followed): a directory inside is refused, before anything is removed
    (a refusal changes nothing)."""
    names = []
    for name in entries:
        if name == LOCK_NAME:
            continue
        try:
            st = os.lstat(path / name)
        except FileNotFoundError:
            continue
        if stat.S_ISDIR(st.st_mode):
            raise RunDirectoryError(f"{option}: {path} holds a directory {name!r}; not a run directory, refusing to "
                                    "clear it (nothing was removed); choose another directory")
        names.append(name)
    return names


def _probe_creatable(path: Path, option: str) -> None:
    """Refuse a new ``path`` that could not be created (its nearest existing ancestor not a directory, or one in
    which no directory can be made, as under ``/proc``), before a run spends time on anything (e.g. compiling):
    an empty directory is made there and removed at once, so nothing is left."""
    parent = path.parent
    while not os.path.lexists(parent) and parent != parent.parent:
        parent = parent.parent
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".jetgaudin-probe-", dir=parent))
    except OSError as exc:
        raise RunDirectoryError(f"{option}: cannot create {path}: {exc.strerror or exc}") from None


def _probe_lock(path: Path, option: str) -> None:
    """Refuse a directory whose lock a live process holds (without creating the lock file)."""
    lock = path / LOCK_NAME
    try:
        st = os.lstat(lock)
    except FileNotFoundError:
        return
    if not stat.S_ISREG(st.st_mode):
        raise RunDirectoryError(f"{option}: {lock} is not a regular file; remove it")
    with RunDirLock(path, claim=False):
        pass


def make_run_dir(path: str | os.PathLike[str], *, option: str = "--out") -> Path:
    """Create ``path`` (and parents) if needed: :class:`~jetgaudin.RunDirectoryError` if impossible."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunDirectoryError(f"{option}: cannot create {path}: {exc.strerror or exc}") from None
    if not path.is_dir():
        raise RunDirectoryError(f"{option}: {path} exists and is not a directory")
    return path


# -------------------------------------------------------------------------------------------- lock
class RunDirLock:
    """Exclusive lock of a run directory for one writer, held while the object is entered.

    ``flock(LOCK_EX | LOCK_NB)`` on ``<dir>/.jetgaudin.lock`` (opened with ``O_NOFOLLOW``); the file holds the
    holder's PID for the message a second writer gets.  The kernel drops the lock when the holder's descriptor
    closes, including when the process dies by a signal, so a crashed run never leaves a stale lock.  A second
    :class:`RunDirLock` of the same directory, in this process or another, raises
    :class:`~jetgaudin.RunLockedError`.
    """

    def __init__(self, path: str | os.PathLike[str], *, claim: bool = True, create: bool = True):
        self.path = Path(path)
        self._fd: int | None = None
        self._claim = claim
        #: ``create=False`` (a resume checking its run): an absent lock file is not created on entry (a refusal
        #: must leave the directory as it was); :meth:`claim` then creates and takes it
        self._create = create

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> RunDirLock:
        import fcntl

        if self._fd is not None:
            return self
        try:
            with open_dir(self.path) as dfd:
                fd = open_nofollow(dfd, self.path, LOCK_NAME, os.O_RDWR | (os.O_CREAT if self._create else 0))
        except RunDirectoryError:
            raise
        except FileNotFoundError:
            if self._create:
                raise RunDirectoryError(f"cannot write to run directory {self.path}: it disappeared") from None
            return self  # no lock file: taken (created) by claim()
        except OSError as exc:
            raise RunDirectoryError(f"cannot write to run directory {self.path}: {exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = ""
            with contextlib.suppress(OSError, ValueError):
                holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                who = f"process {holder}" if holder.isdigit() else "another process"
                raise RunLockedError(f"{self.path} is in use by {who} (one writer per run directory); wait for it "
                                     "to finish or stop it, then try again") from None
            raise RunDirectoryError(f"cannot lock run directory {self.path}: {exc.strerror or exc}") from None
        self._fd = fd
        if self._claim:
            self.claim()
        return self

    def claim(self) -> None:
        """Write this process's PID into the lock file (for the message a second writer gets).  A holder that may
        still refuse (a resume checking its run) takes the lock with ``claim=False`` and claims it once it writes:
        a refusal leaves the lock file as it was."""
        if self._fd is None:
            if self._create:
                return
            self._create, self._claim = True, True
            self.acquire()  # the lock file was absent: created and taken now
            return
        try:
            os.ftruncate(self._fd, 0)
            os.pwrite(self._fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:
            pass  # the PID is only for the message of a second writer

    def release(self) -> None:
        if self._fd is not None:
            import fcntl

            with contextlib.suppress(OSError):
                fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> RunDirLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()
