"""Reading run directories: ``run.json`` (digest-checked), HDF5 files opened safely, CSV helpers (private; the
writers are in :mod:`jetgaudin.run.store`)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from .. import _fs
from .._errors import RecordingError, RunDirectoryError

RUN_JSON = "run.json"
ORBIT_H5 = "orbit.h5"
ORBIT_CSV = "orbit.csv"
ENSEMBLE_H5 = "ensemble.h5"
#: largest run.json read (a run.json is a few kB; a bigger file is not one)
RUN_JSON_CAP = 1 << 22
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def one_line(msg: object) -> str:
    return " ".join(str(msg).split())


def hex_floats(values: Any) -> list[str]:
    return [float(v).hex() for v in np.ravel(values)]


def unhex(values: Any) -> np.ndarray:
    return np.array([float.fromhex(s) for s in values], dtype=float)


def run_digest(run: dict) -> str:
    body = {k: v for k, v in run.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def _strict(value: Any) -> Any:
    """``value`` with every non-finite float replaced by ``None`` (JSON has no ``Infinity`` or ``NaN``)."""
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _strict(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_strict(v) for v in value]
    return value


def run_json_text(run: dict) -> str:
    """``run.json`` text with its SHA-256 digest (field ``sha256``) set in ``run``: strict JSON (a non-finite number,
    e.g. the infinite health limits of ``flow``, is recorded as ``null`` in ``run`` and in the file)."""
    for k in list(run):
        run[k] = _strict(run[k])
    run["sha256"] = run_digest(run)
    return json.dumps(run, indent=1, allow_nan=False) + "\n"


def write_run(out_dir: str | os.PathLike[str], run: dict) -> None:
    """Write ``run.json`` durably and atomically (``jetgaudin._fs.atomic_write_text``) with its digest."""
    _fs.atomic_write_text(out_dir, RUN_JSON, run_json_text(run))


def read_run(out_dir: str | os.PathLike[str], *, verify: bool = False) -> dict:
    """The parsed ``run.json`` of a run directory (:class:`RecordingError` if missing or corrupted; a link, FIFO
    or oversized file is refused without reading it; ``verify=True`` also checks its ``sha256`` digest, as a
    resume does)."""
    path = Path(out_dir) / RUN_JSON
    try:
        data = _fs.read_json(out_dir, RUN_JSON, RUN_JSON_CAP)
    except FileNotFoundError:
        raise RecordingError(f"{path} does not exist: not a jetgaudin run directory") from None
    except RunDirectoryError:
        raise
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    except RecordingError:
        raise RecordingError(f"{path} is corrupted (not a jetgaudin run.json); cannot use this run") from None
    if not isinstance(data, dict) or "inputs" not in data or "status" not in data:
        raise RecordingError(f"{path} is corrupted (not a jetgaudin run.json); cannot use this run")
    if verify and data.get("sha256") != run_digest(data):
        raise RecordingError(f"{path} does not match its own digest (corrupted or edited); cannot use this run")
    return data


def _check_h5_eof(path: Path) -> None:
    """Refuse a truncated HDF5 file before a SWMR reader touches it (SWMR reads of missing bytes retry
    without end).  The version-2/3 superblock at offset 0 stores the end-of-file address."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
        try:
            size = os.fstat(fd).st_size
            head = os.read(fd, 64)
        finally:
            os.close(fd)
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    if head[:8] != _HDF5_SIGNATURE or len(head) < 12:
        raise RecordingError(f"{path} is not an HDF5 file (corrupted)")
    if head[8] in (2, 3):
        so = head[9]
        if so not in (2, 4, 8) or len(head) < 12 + 3 * so:
            raise RecordingError(f"{path} has a corrupted superblock")
        eof = int.from_bytes(head[12 + 2 * so : 12 + 3 * so], "little")
        if size < eof:
            raise RecordingError(f"{path} is truncated ({size} bytes, the file records {eof})")


def open_h5_read(path: str | os.PathLike[str]):
    """Open an HDF5 file of a run for reading: a regular file (no link, FIFO or device), checked complete; a run
    killed while writing leaves the SWMR "open for write" flag set: it is then opened as a SWMR reader."""
    import h5py

    path = Path(path)
    if not _fs.check_regular_or_absent(path.parent, path.name):
        raise RecordingError(f"{path} is missing")
    _check_h5_eof(path)
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        msg = str(exc)
        if "open for write" not in msg and "h5clear" not in msg:
            raise
    return h5py.File(path, "r", swmr=True)


def csv_header(N: int, index: str = "n") -> str:
    """``n,y0^1,y0^2,y0^3,y1^1,…`` (``y{i}^{a}`` is the component ``a`` of ``y_i``: the chains' ``s{j}_y{i}^{a}``
    without the site; older files name them ``y{i}_{a}`` and load the same: nothing reads the names back)."""
    return ",".join([index] + [f"y{i}^{a}" for i in range(N) for a in (1, 2, 3)]) + "\n"


def format_rows(index: Any, X: Any) -> str:
    """CSV rows: the index, then the components with 17 significant digits (``%.17g``: every double
    round-trips exactly through ``float()``)."""
    lines = []
    for i, row in zip(index, X, strict=True):
        lines.append((f"{i:.17g}" if isinstance(i, float) else str(i)) + "," + ",".join(f"{v:.17g}" for v in row))
    return "\n".join(lines) + ("\n" if lines else "")


def read_csv(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(index, X)`` from a CSV written by this package."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float)
    return data[:, 0], data[:, 1:]


def file_sha256(out_dir: Path, name: str, max_bytes: int) -> str:
    return hashlib.sha256(_fs.read_bytes(out_dir, name, max_bytes)).hexdigest()


class RowDigest:
    """SHA-256 of the ``n`` column and of the rows as two streams (independent of how they are chunked)."""

    def __init__(self) -> None:
        self.hn, self.hX = hashlib.sha256(), hashlib.sha256()

    def update(self, n_idx: Any, X: Any) -> None:
        # the arrays' buffers as they are (hashlib reads a C-contiguous buffer): no bytes copy of the rows
        self.hn.update(np.ascontiguousarray(n_idx, dtype="<i8").data)
        self.hX.update(np.ascontiguousarray(X, dtype="<f8").data)

    def hexdigest(self) -> str:
        return self.hn.hexdigest() + ":" + self.hX.hexdigest()
