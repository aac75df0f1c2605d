"""Writing run directories (private): rows appended to HDF5 (and CSV), durable checkpoints, ``run.json``.

One rule for every checkpoint (``docs/reliability.md``): the rows are flushed and ``fsync``-ed, then the
checkpoint (an ``.npz`` slot for ensembles; inside ``run.json`` for orbits) is written durably, then ``run.json``
is replaced atomically; the in-memory record is updated only once ``run.json`` is on disk.  Any ``OSError`` or
HDF5 error on the way raises :class:`jetgaudin.RunIOError` and leaves the last durable checkpoint in force.
Every file is opened through :mod:`jetgaudin._fs` (no symlink followed, no stray ``.tmp``).

**Overlap** (ensembles, :attr:`Store.overlap`): an append (the HDF5 write and the rows' digest) and a checkpoint (the
fsync, the slot's serialisation, digest and write, ``run.json``) run in a writer thread while the caller goes on
stepping; one at a time, in the order given, each started only once the previous one has ended (its error, if any,
raised then, in the caller's thread: the next append, checkpoint, :meth:`Store.wait`).  The files see the same
operations in the same order as without it, so every rule above holds as it did; what a checkpoint records (the
state, ``ν1``, the anchor, the drift, the summary, the rows' count and digest) is taken when it is asked for.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import os
import signal
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from .. import _fs, _space
from .._errors import RecordingError, RunIOError
from .files import (
    ENSEMBLE_H5,
    ORBIT_H5,
    RowDigest,
    csv_header,
    file_sha256,
    format_rows,
    hex_floats,
    open_h5_read,
    write_run,
)

#: errors that mean "writing failed" (h5py raises RuntimeError or OSError subclasses for HDF5 failures)
WRITE_ERRORS = (OSError, RuntimeError)
#: bytes of HDF5 metadata (chunk index, object headers, superblock) one append or flush may add, reserved with the
#: data: measured below 20 kB for an append of up to 4096 chunks (``tests/test_data_safety.py``)
H5_META_BYTES = 64 << 10
#: bytes kept free for the last ``run.json`` of a session (plus twice the record's size)
RESERVE_BYTES = 64 << 10
#: HDF5 objects of a file whose write failed: never closed (HDF5 crashes closing them after a real ENOSPC)
_ABANDONED: list = []


def now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


class Store:
    """Rows ``(k, ..., n)`` appended to ``<h5_name>`` (datasets ``n`` and ``<data>``), checkpoints, ``run.json``."""

    h5_name = ORBIT_H5
    data = "X"
    _COPY_BLOCK_BYTES = 64 << 20
    #: appends and checkpoints overlap the caller's next steps (module doc; the ensembles': their rows are large)
    overlap = False

    def __init__(self, out_dir: Path, run: dict, shape: tuple[int, ...], *, fresh: bool,
                 extra: dict[str, np.ndarray] | None = None, check_only: bool = False):
        self.out_dir, self.run, self.shape = Path(out_dir), run, tuple(shape)
        self.h_rows = RowDigest()
        self.rows = 0 if fresh else int(run["checkpoint"]["rows"])
        #: ``(step, X, carry)`` where the kernel call that made the last saved row started: recorded with every
        #: checkpoint, replayed by a resume (:mod:`jetgaudin.run.replay`)
        self.anchor: tuple[int, np.ndarray, Any] | None = None
        self.f: Any = None
        self._job: threading.Thread | None = None  # the append or checkpoint running in the writer thread
        self._job_error: BaseException | None = None
        #: a read-only view of a run to resume (:meth:`checked`): every check of a resume, nothing written
        self.check_only = check_only
        if check_only:
            self._check_h5()
            return
        self._build_h5(fresh, extra or {})
        import h5py

        try:
            self.f = h5py.File(self.out_dir / self.h5_name, "a", libver="latest")
            self.dn, self.dS = self.f["n"], self.f[self.data]
            self.f.swmr_mode = True
        except WRITE_ERRORS as exc:
            raise RunIOError(f"{_fs.io_failure(exc)} while opening {self.out_dir / self.h5_name}") from exc

    @classmethod
    def checked(cls, *args: Any, **kwargs: Any) -> Store:
        """The stored run opened read-only (``check_only``): the rows ``run.json`` declares are verified (count,
        shape, digest; an orbit's CSV too) and ``dn``/``dS`` read from the file as it is, for the replay.  A resume
        makes every check through this view *before* it writes anything (a refusal changes nothing); ``close()``
        it before opening the writing store."""
        return cls(*args, check_only=True, **kwargs)

    def _check_h5(self) -> None:
        """:meth:`_build_h5`'s checks of the old file, read-only (no temporary file, nothing replaced)."""
        path = self.out_dir / self.h5_name
        try:
            self.f = open_h5_read(path)
            self.dn, self.dS = self.f["n"], self.f[self.data]
            if self.dn.shape[0] < self.rows or self.dS.shape[0] < self.rows:
                raise RecordingError(f"{path} is truncated: it holds fewer rows than run.json records; cannot resume")
            if self.dS.shape[1:] != self.shape:
                raise ValueError("the stored states do not match the recorded run")
            block = max(1, self._COPY_BLOCK_BYTES // (8 * max(1, int(np.prod(self.shape)))))
            for a in range(0, self.rows, block):
                e = min(self.rows, a + block)
                self.h_rows.update(self.dn[a:e], self.dS[a:e])
        except RecordingError:
            self.close()
            raise
        except (OSError, KeyError, ValueError, TypeError) as exc:
            self.close()
            raise RecordingError(f"{path} is unreadable or corrupted ({exc}); cannot resume") from None
        if self.h_rows.hexdigest() != self.run["checkpoint"].get("rows_sha256"):
            self.close()
            raise RecordingError(f"{path} does not match the digest in run.json (corrupted); cannot resume")

    # ------------------------------------------------------------------------------------------- HDF5
    def _build_h5(self, fresh: bool, extra: dict[str, np.ndarray]) -> None:
        """A new HDF5 file with the inputs and (on resume) exactly the checkpointed rows of the old one, verified
        against their digest (drops rows written after the last checkpoint and clears a killed writer's SWMR
        flag)."""
        import h5py

        tmp = self.h5_name + ".tmp"
        path, tmp_path = self.out_dir / self.h5_name, self.out_dir / tmp
        _fs.remove_file(self.out_dir, tmp)  # a stale file or a planted symlink: removed, never followed
        old = None
        try:
            if not fresh:
                try:
                    old = open_h5_read(path)
                    if old["n"].shape[0] < self.rows or old[self.data].shape[0] < self.rows:
                        raise RecordingError(f"{path} is truncated: it holds fewer rows than run.json records; "
                                             "cannot resume")
                    if old[self.data].shape[1:] != self.shape:
                        raise ValueError("the stored states do not match the recorded run")
                    extra = {k: np.array(old[k]) for k in self._extra_names()}
                except (OSError, KeyError, ValueError, TypeError) as exc:
                    raise RecordingError(f"{path} is unreadable or corrupted ({exc}); cannot resume") from None
            try:
                self._write_h5(h5py, tmp_path, old, extra)
            except WRITE_ERRORS as exc:
                raise RunIOError(f"{_fs.io_failure(exc)} while writing {tmp_path}") from exc
        except BaseException:
            _fs.remove_file(self.out_dir, tmp)
            raise
        finally:
            if old is not None:
                old.close()
        if not fresh and self.h_rows.hexdigest() != self.run["checkpoint"].get("rows_sha256"):
            _fs.remove_file(self.out_dir, tmp)
            raise RecordingError(f"{path} does not match the digest in run.json (corrupted); cannot resume")
        _space.release_space(self.out_dir, tmp)
        try:
            _fs.check_regular_or_absent(self.out_dir, self.h5_name)
            os.replace(tmp_path, path)
            _fs.fsync_dir(self.out_dir)
        except OSError as exc:
            _fs.remove_file(self.out_dir, tmp)
            raise RunIOError(f"{_fs.io_failure(exc)} while writing {path}") from exc

    def _extra_names(self) -> tuple[str, ...]:
        return ()

    def _write_h5(self, h5py: Any, path: Path, old: Any, extra: dict[str, np.ndarray]) -> None:
        rows = self.rows if old is not None else 0
        row_values = int(np.prod(self.shape))
        with h5py.File(path, "w", libver="latest") as f:
            extra_bytes = sum(int(np.asarray(v).nbytes) for v in extra.values())
            _space.reserve_space(path.parent, path.name, extra_bytes + self._h5_bytes(0, rows), what="writing")
            for k, v in extra.items():
                f.create_dataset(k, data=v)
            per_chunk = self._h5_chunks()
            dn = f.create_dataset("n", shape=(rows,), maxshape=(None,), chunks=(4096,), dtype="i8")
            dS = f.create_dataset(self.data, shape=(rows,) + self.shape, maxshape=(None,) + self.shape,
                                  chunks=per_chunk, dtype="f8")
            block = max(1, self._COPY_BLOCK_BYTES // (8 * max(1, row_values)))
            for a in range(0, rows, block):
                e = min(rows, a + block)
                bn, bS = old["n"][a:e], old[self.data][a:e]
                dn[a:e], dS[a:e] = bn, bS
                self.h_rows.update(bn, bS)
            self._attrs(f)

    def _h5_chunks(self) -> tuple[int, ...]:
        return (4096,) + self.shape

    def _attrs(self, f: Any) -> None:
        f.attrs["note"] = "rows beyond run.json checkpoint.rows are not data (see docs/reliability.md)"

    # ------------------------------------------------------------------------------------------ the writer
    def _submit(self, fn: Any, *args: Any) -> None:
        """Run ``fn(*args)`` once the previous job has ended: in the writer thread (:attr:`overlap`), else here."""
        self.wait()
        if not self.overlap:
            fn(*args)
            return

        def job() -> None:
            try:
                fn(*args)
            except BaseException as exc:  # raised in the caller's thread by the next wait()
                self._job_error = exc

        self._job = threading.Thread(target=job, name="jetgaudin-store", daemon=True)
        self._job.start()

    def wait(self) -> None:
        """Wait for the append or checkpoint in the writer thread to end; raise its error (once)."""
        if self._job is not None:
            self._job.join()
            self._job = None
        err, self._job_error = self._job_error, None
        if err is not None:
            raise err

    def _settle(self) -> None:
        """:meth:`wait`, its error dropped (it has been raised already, or the caller is failing anyway)."""
        with contextlib.suppress(BaseException):
            self.wait()

    # ------------------------------------------------------------------------------------------ writes
    def append(self, n_idx: np.ndarray, S: np.ndarray) -> None:
        """Append rows ``S`` ``(k,) + shape`` at steps ``n_idx`` (not yet durable: see :meth:`checkpoint`).  With
        :attr:`overlap` the write runs in the writer thread: ``S`` must not be changed afterwards (the run layer
        hands fresh arrays)."""
        self._submit(self._append, n_idx, S)

    def _append(self, n_idx: np.ndarray, S: np.ndarray) -> None:
        k = len(n_idx)
        if k == 0:
            return
        r = self.rows
        _space.reserve_space(self.out_dir, self.h5_name, self._h5_bytes(r, k), what="appending rows to")
        try:
            self.dn.resize((r + k,))
            self.dS.resize((r + k,) + self.shape)
            self.dn[r : r + k] = n_idx
            self.dS[r : r + k] = S
        except WRITE_ERRORS as exc:
            self._abandon()
            raise RunIOError(f"{_fs.io_failure(exc)} while appending rows") from exc
        try:
            self._append_more(n_idx, S)
        except WRITE_ERRORS as exc:
            raise RunIOError(f"{_fs.io_failure(exc)} while appending rows") from exc
        self.h_rows.update(n_idx, S)
        self.rows = r + k

    def _append_more(self, n_idx: np.ndarray, S: np.ndarray) -> None:
        pass

    def _h5_bytes(self, r: int, k: int) -> int:
        """An upper bound of the bytes HDF5 writes to append ``k`` rows after row ``r`` (every chunk the rows touch,
        of ``n`` and of the data, in full, and :data:`H5_META_BYTES`), reserved before the rows are handed to it."""
        if k <= 0:
            return H5_META_BYTES
        chunks = self._h5_chunks()
        per_row = 1
        for size, c in zip(self.shape, chunks[1:], strict=True):
            per_row *= -(-size // c)
        touched = (r + k - 1) // chunks[0] - r // chunks[0] + 1
        n_touched = (r + k - 1) // 4096 - r // 4096 + 1
        return touched * per_row * 8 * int(np.prod(chunks)) + n_touched * 8 * 4096 + H5_META_BYTES

    def _sync_data(self) -> None:
        _space.reserve_space(self.out_dir, self.h5_name, H5_META_BYTES, what="flushing")
        try:
            self.dn.flush()
            self.dS.flush()
            self.f.flush()
        except WRITE_ERRORS as exc:
            self._abandon()
            raise RunIOError(f"{_fs.io_failure(exc)} while flushing {self.out_dir / self.h5_name}") from exc
        _fs.fsync_file(self.out_dir, self.h5_name)
        _space.release_space(self.out_dir, self.h5_name)

    def _abandon(self) -> None:
        """After a failed HDF5 write, never touch the file's objects again: HDF5 may crash closing them (a real
        ENOSPC: SIGSEGV in ``H5D_close``); they are kept referenced and the file is left as the last durable
        checkpoint declared it (the rows after it are not data)."""
        if self.f is not None:
            _ABANDONED.append((self.f, self.dn, self.dS))
            self.f = None

    def checkpoint(self, step: int, X: np.ndarray, carry: Any, summary: dict) -> None:
        """Make everything appended durable and record ``(step, X, carry)`` as the checkpoint: data → fsync →
        checkpoint → fsync → ``run.json``; ``self.run`` changes only after ``run.json`` is on disk.  With
        :attr:`overlap` this runs in the writer thread (what it records is taken now)."""
        self._submit(self._checkpoint, int(step), X, carry, summary, self.anchor, self._checkpoint_extra())

    def _checkpoint_extra(self) -> Any:
        """What a checkpoint records besides the state and the anchor, taken when it is asked for."""
        return None

    def _checkpoint(self, step: int, X: np.ndarray, carry: Any, summary: dict, anchor: Any, extra: Any) -> None:
        try:
            self._sync_data()
            new = copy.deepcopy(self.run)
            self._write_checkpoint(new, int(step), X, carry, anchor, extra)
            new["checkpoint"].update(step=int(step), rows=self.rows, rows_sha256=self.h_rows.hexdigest())
            new.update(summary)
            new["last_safe_step"] = int(step)
            new["updated"] = now()
            write_run(self.out_dir, new)
        except RunIOError:
            raise
        except WRITE_ERRORS as exc:
            raise RunIOError(f"{_fs.io_failure(exc)} while writing a checkpoint") from exc
        self._committed()
        self.run = new

    def _write_checkpoint(self, new: dict, step: int, X: np.ndarray, carry: Any, anchor: Any, extra: Any) -> None:
        raise NotImplementedError

    def _committed(self) -> None:
        pass

    def begin(self, fresh: bool) -> None:
        """Start a session of writing: a new run's first ``run.json`` (no row yet: a failure at the first append
        leaves a run that resumes from ``X0``), then the reserve (:func:`jetgaudin._space.make_reserve`) that
        :meth:`mark` frees to record a full disk."""
        self.wait()
        if fresh:
            write_run(self.out_dir, copy.deepcopy(self.run))
        _space.make_reserve(self.out_dir, RESERVE_BYTES + 2 * len(json.dumps(self.run)))

    def mark(self, status: str, **fields: Any) -> None:
        """Best effort: record ``status`` (and ``fields``) over the last durable checkpoint (the disk may be what
        failed: the reserve is freed first; a job in the writer thread ends first)."""
        self._settle()
        _space.release_reserve(self.out_dir)
        with contextlib.suppress(Exception):
            new = copy.deepcopy(self.run)
            new.update(fields, status=status, updated=now())
            write_run(self.out_dir, new)
            self.run = new

    def close(self) -> None:
        with ignoring_sigxfsz():
            self._settle()
            if not self.check_only:
                _space.release_reserve(self.out_dir)
            with contextlib.suppress(Exception):
                if self.f is not None:
                    self.f.close()


class OrbitStore(Store):
    """``orbit.h5`` (datasets ``n``, ``X`` rows × n) and ``orbit.csv``; the checkpoint (exact state and ``ν1`` as
    ``float.hex``, row and CSV digests) lives in ``run.json``.  A map with a time step (``time_step``) also gets the
    dataset ``t = n · dt``; its CSV is indexed by ``t`` (``stem="flow"``) or has both ``n`` and ``t``
    (``stem="orbit"``: ``jetgaudin orbit --dt``)."""

    def __init__(self, out_dir: Path, run: dict, n_state: int, *, fresh: bool, csv: bool, stem: str = "orbit",
                 time_step: float | None = None, columns: list[str] | None = None, check_only: bool = False):
        self.csv = csv
        self.columns = columns  # names of the n_state columns (default y{i}^{a}; the chains name them by site)
        self.h5_name, self.csv_name = f"{stem}.h5", f"{stem}.csv"
        self.time_step = time_step  # a flow: the CSV's index column is the time t = n dt
        self.h_csv: Any = None
        self.csv_bytes = 0
        self.csv_fh: Any = None
        super().__init__(out_dir, run, (n_state,), fresh=fresh, check_only=check_only)
        self.dt_ds = None if time_step is None or check_only else self.f["t"]
        try:
            self._open_csv(fresh)
        except BaseException:
            self.close()
            raise

    def _h5_chunks(self) -> tuple[int, ...]:
        return (4096,) + self.shape

    def _attrs(self, f: Any) -> None:
        f.attrs["inputs"] = json.dumps(self.run["inputs"])
        f.attrs["columns"] = self._header().strip()
        if self.time_step is not None:
            f.attrs["dt"] = self.time_step
        super()._attrs(f)

    def _write_h5(self, h5py: Any, path: Path, old: Any, extra: dict[str, np.ndarray]) -> None:
        super()._write_h5(h5py, path, old, extra)
        if self.time_step is not None:  # t = n dt (derived from the verified n: rebuilt the same on resume)
            with h5py.File(path, "a", libver="latest") as f:
                f.create_dataset("t", data=self._times(f["n"][()]), maxshape=(None,), chunks=(4096,), dtype="f8")

    def _times(self, n_idx: np.ndarray) -> np.ndarray:
        return np.asarray(n_idx, dtype=float) * float(self.time_step or 0.0)

    def _index(self) -> str:
        return "n" if self.time_step is None else "t" if self.h5_name.startswith("flow") else "n,t"

    def _header(self) -> str:
        index = self._index()
        if self.columns is not None:
            return ",".join([index, *self.columns]) + "\n"
        return csv_header(self.shape[0] // 3, index)

    def _open_csv(self, fresh: bool) -> None:
        import hashlib

        if not self.csv:
            return
        self.h_csv = hashlib.sha256()
        ck = self.run["checkpoint"]
        path = self.out_dir / self.csv_name
        if fresh or (int(ck.get("csv_bytes", 0)) == 0 and self.rows == 0):  # nothing durable yet: start again
            if self.check_only:
                return
            head = self._header().encode()
            self.csv_fh = _fs.open_write(self.out_dir, self.csv_name)
            self.csv_fh.write(head)
            self.h_csv.update(head)
            self.csv_bytes = len(head)
            return
        self.csv_bytes = int(ck["csv_bytes"])
        lines, tail = 0, b""
        try:
            _fs.check_regular_or_absent(self.out_dir, self.csv_name)
            size = os.lstat(path).st_size
            with open(path, "rb") as fh:
                left = self.csv_bytes
                while left > 0:
                    block = fh.read(min(left, 1 << 22))
                    if not block:
                        break
                    self.h_csv.update(block)
                    lines += block.count(b"\n")
                    tail = (tail + block)[-(1 << 16):]
                    left -= len(block)
        except OSError:
            raise RecordingError(f"{path} is missing or unreadable; cannot resume") from None
        if size < self.csv_bytes:
            raise RecordingError(f"{path} is truncated (shorter than run.json records); cannot resume")
        if self.h_csv.hexdigest() != ck.get("csv_sha256"):
            raise RecordingError(f"{path} does not match the digest in run.json (corrupted); cannot resume")
        if lines != self.rows + 1 or (self.rows and not tail.endswith(self._row_text(self.rows - 1))):
            # the declared CSV must hold the header and exactly the declared rows (a resume never cuts a durable row)
            raise RecordingError(f"{path}: run.json's csv_bytes does not cover exactly the {self.rows} saved rows "
                                 "(edited or corrupted); cannot resume")
        if self.check_only:
            return
        self.csv_fh = _fs.open_write(self.out_dir, self.csv_name, append=True)
        os.ftruncate(self.csv_fh.fileno(), self.csv_bytes)

    def _row_text(self, i: int) -> bytes:
        """The CSV line of saved row ``i``."""
        return self._csv_text(np.array([self.dn[i]]), np.array(self.dS[i : i + 1]))

    def _csv_text(self, n_idx: np.ndarray, S: np.ndarray) -> bytes:
        index = n_idx.tolist() if self.time_step is None else self._times(n_idx).tolist()
        if self._index() == "n,t":
            index = [f"{n},{t:.17g}" for n, t in zip(n_idx.tolist(), index, strict=True)]
        return format_rows(index, S).encode()

    def _append_more(self, n_idx: np.ndarray, S: np.ndarray) -> None:
        if self.dt_ds is not None:
            r = self.dn.shape[0]
            self.dt_ds.resize((r,))
            self.dt_ds[r - len(n_idx):r] = self._times(n_idx)
        if self.csv_fh is not None:
            text = self._csv_text(n_idx, S)
            self.csv_fh.write(text)
            self.h_csv.update(text)

    def _sync_data(self) -> None:
        super()._sync_data()
        if self.csv_fh is not None:
            self.csv_fh.flush()
            os.fsync(self.csv_fh.fileno())

    def _write_checkpoint(self, new: dict, step: int, X: np.ndarray, carry: Any, anchor: Any, extra: Any) -> None:
        ck = new["checkpoint"]
        ck["X_hex"] = hex_floats(X)
        ck["nu1_hex"] = _hex_carry(carry)
        if anchor is not None:
            a_n, a_X, a_c = anchor
            ck["anchor"] = {"step": int(a_n), "X_hex": hex_floats(a_X), "nu1_hex": _hex_carry(a_c)}
        if self.csv_fh is not None:
            ck["csv_bytes"] = self.csv_fh.tell()
            ck["csv_sha256"] = self.h_csv.hexdigest()

    def close(self) -> None:
        super().close()
        if self.csv_fh is not None:
            with ignoring_sigxfsz(), contextlib.suppress(Exception):
                self.csv_fh.close()  # flushes the buffered CSV: past RLIMIT_FSIZE, EFBIG (suppressed), not SIGXFSZ


@contextlib.contextmanager
def ignoring_sigxfsz():
    """SIGXFSZ ignored while a store closes (in the main thread; restored after): its buffered CSV and HDF5 file are
    flushed then, after the driver's loop (which ignores SIGXFSZ while it runs) has restored the handler, and a write
    past ``RLIMIT_FSIZE`` must fail with EFBIG (suppressed: the run has already failed or its rows are declared by
    the checkpoint) instead of killing a host process whose SIGXFSZ is at its default action."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGXFSZ"):
        yield
        return
    old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGXFSZ, old)


def _hex_carry(carry: Any) -> list[str] | None:
    c = None if carry is None else complex(np.asarray(carry).reshape(-1)[0])
    return None if c is None else [c.real.hex(), c.imag.hex()]


class EnsembleStore(Store):
    """``ensemble.h5`` (inputs ``X0``, ``b``, ``eta``; rows ``n``, ``states`` (rows, B, n)) and two checkpoint slots
    ``checkpoint-0.npz`` / ``checkpoint-1.npz`` (state, ``ν1``, relative drift) written alternately; ``run.json``
    names the valid slot and its SHA-256."""

    h5_name = ENSEMBLE_H5
    data = "states"
    overlap = True

    def __init__(self, out_dir: Path, run: dict, shape: tuple[int, int], *, fresh: bool,
                 extra: dict[str, np.ndarray] | None = None, check_only: bool = False):
        super().__init__(out_dir, run, shape, fresh=fresh, extra=extra, check_only=check_only)
        self.slot = int(run["checkpoint"].get("slot", 1)) ^ 1  # the next checkpoint goes to the other slot
        self.drift_rel: np.ndarray = np.zeros(0)

    def _extra_names(self) -> tuple[str, ...]:
        return ("X0", "b", "eta")

    def _h5_chunks(self) -> tuple[int, ...]:
        B, n3 = self.shape
        return (1, max(1, min(B, (1 << 20) // (8 * n3))), n3)  # HDF5 chunks of at most 1 MiB

    def _attrs(self, f: Any) -> None:
        f.attrs["inputs"] = json.dumps(self.run["inputs"], sort_keys=True)
        f.attrs["layout"] = "states[r, i, :] is orbit i at step n[r]; components y_0, y_1, ... (3N)"
        super()._attrs(f)

    def _checkpoint_extra(self) -> Any:
        return self.drift_rel  # the relative drift (set by the run layer before each checkpoint)

    def _write_checkpoint(self, new: dict, step: int, X: np.ndarray, carry: Any, anchor: Any, extra: Any) -> None:
        name = f"checkpoint-{self.slot}.npz"
        buf = io.BytesIO()
        a_n, a_X, a_c = anchor if anchor is not None else (-1, np.zeros((0,) + X.shape[1:]), None)
        np.savez(buf, step=np.int64(step), X=X, nu1=np.zeros(0, complex) if carry is None else carry,
                 drift=extra, anchor_step=np.int64(a_n), anchor_X=a_X,
                 anchor_nu1=np.zeros(0, complex) if a_c is None else a_c)
        data = buf.getbuffer()  # the file's bytes in place (getvalue() would copy them once more)
        _fs.atomic_write_bytes(self.out_dir, name, data)
        import hashlib

        new["checkpoint"].update(slot=self.slot, file=name, sha256=hashlib.sha256(data).hexdigest())

    def _committed(self) -> None:
        self.slot ^= 1


def read_checkpoint_npz(out_dir: Path, ck: dict, shape: tuple[int, int]) -> dict[str, np.ndarray]:
    """The arrays of the checkpoint slot ``run.json`` names (a plain file name inside the directory, a regular
    file of bounded size, matching its digest)."""
    name = _fs.plain_name(ck["file"])
    B, n = shape
    cap = 2 * (8 * B * n + 16 * B) + 8 * B * n + (1 << 16)  # X, nu1 and the anchor's, the drift, the zip's own
    if file_sha256(out_dir, name, cap) != ck["sha256"]:
        raise ValueError(f"{name} does not match its digest")
    with np.load(io.BytesIO(_fs.read_bytes(out_dir, name, cap)), allow_pickle=False) as d:
        out = {k: np.array(d[k]) for k in ("step", "X", "nu1", "drift")}
        for k in ("anchor_step", "anchor_X", "anchor_nu1"):
            if k in d:
                out[k] = np.array(d[k])
        return out
