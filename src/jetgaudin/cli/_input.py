"""``ensemble --input``: initial states from a CSV or NPZ file, read with memory bounded by the declared shape
(private).

Nothing is read without a bound: the file must be a regular file of at most ``max_bytes``; a CSV is read line by
line (a line longer than :data:`MAX_LINE_BYTES` -- a binary file, a NUL-filled file -- is refused at once, and the
column count is fixed by the first row and checked against the command line's ``N <= MAX_N`` before any more is
read); an NPZ member's ``.npy`` header (shape and dtype) is read first and the shape checked against the same
rules and the machine's memory before one value is decompressed, which is then done in blocks (a SIGINT is
honoured between blocks).  A complex ``X`` is handed on as complex, so that the library refuses it if it is not
real (never a silent cast).  Every refusal is a :class:`CliInputError` (one line, exit 2).
"""

from __future__ import annotations

import io
import os
import stat
import zipfile
from pathlib import Path

import numpy as np

from ._common import MAX_N, CliInputError, one_line

#: longest CSV line: 3 * MAX_N values of at most ~32 characters each, with room for spaces
MAX_LINE_BYTES = 3 * MAX_N * 40 + 256
#: CSV lines parsed at a time
_BLOCK_LINES = 1 << 16
#: bytes decompressed at a time from an NPZ member
_BLOCK_BYTES = 1 << 24


def _memory_limit() -> int:
    """Bytes the states read from a file may take: 1/32 of the memory this process may use (:func:`_memory_bytes`,
    and the address-space limit ``ulimit -v``).  An ensemble run's peak memory is about 16 times its states
    (measured: 10^7 x 9 states, 0.72 GB, peaked at 11.6 GB on the 2-core AMD EPYC VM: integrals and drifts per
    orbit, the kernel's rows, the checkpoint built in memory), and half the memory is left to the rest."""
    import resource

    avail = _memory_bytes()
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft != resource.RLIM_INFINITY:
        avail = min(avail, soft)
    return avail // 32


def _memory_bytes() -> int:
    """The memory available now (``MemAvailable`` of ``/proc/meminfo``; else the physical memory)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 36


def _check_shape(shape: tuple[int, ...], path: Path) -> None:
    if len(shape) != 2 or shape[0] == 0 or shape[1] == 0 or shape[1] % 3:
        raise CliInputError(f"--input: the states must form a (B, 3N) table (one state y_0, y_1, ... per row, 3N "
                            f"numbers); {path} holds shape {shape}")
    if shape[1] > 3 * MAX_N:
        raise CliInputError(f"--input: {path} has {shape[1]} columns (N = {shape[1] // 3}); the command line accepts "
                            f"N <= {MAX_N} ({3 * MAX_N} columns)")
    need = 8 * shape[0] * shape[1]
    if need > _memory_limit():
        raise CliInputError(f"--input: {path} declares {shape[0]} states of {shape[1]} numbers "
                            f"({need / 2**30:.3g} GiB), more than this machine can run (about "
                            f"{_memory_limit() / 2**30:.3g} GiB of states); give fewer states")


def _open(path: Path, max_bytes: int):
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise CliInputError(f"--input: {path} does not exist") from None
    except OSError as exc:
        raise CliInputError(f"--input: cannot read {path}: {exc.strerror or exc}") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise CliInputError(f"--input: {path} is not a regular file (a FIFO, device or directory)")
    if st.st_size > max_bytes:
        os.close(fd)
        raise CliInputError(f"--input: {path} is {st.st_size} bytes, more than the {max_bytes} accepted")
    return os.fdopen(fd, "rb")


def read_input(path: Path, max_bytes: int) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``(X, b or None, eta or None)`` from a CSV or NPZ file (see the module doc)."""
    path = Path(path)
    with _open(path, max_bytes) as fh:
        if path.suffix.lower() == ".npz":
            return _read_npz(fh, path)
        return _read_csv(fh, path), None, None


def _read_csv(fh, path: Path) -> np.ndarray:
    blocks: list[np.ndarray] = []
    lines: list[str] = []
    cols = rows = 0
    first = True
    lineno = 0

    def flush() -> None:
        nonlocal rows
        if not lines:
            return
        try:
            a = np.loadtxt(lines, delimiter=",", ndmin=2, dtype=float)
        except ValueError as exc:
            raise CliInputError(f"--input: cannot read {path} as CSV of numbers: {one_line(exc)}") from None
        if a.shape[1] != cols:
            raise CliInputError(f"--input: {path}: the rows have different numbers of values ({cols} and "
                                f"{a.shape[1]})")
        rows += len(a)
        _check_shape((rows, cols), path)
        blocks.append(a)
        lines.clear()

    drop_index = False
    while True:
        raw = fh.readline(MAX_LINE_BYTES + 1)
        if not raw:
            break
        lineno += 1
        if len(raw) > MAX_LINE_BYTES:
            raise CliInputError(f"--input: line {lineno} of {path} is longer than {MAX_LINE_BYTES} bytes; not a CSV "
                                f"of states (at most {3 * MAX_N} numbers per line)")
        try:
            text = raw.decode("utf-8").split("#", 1)[0].strip()
        except UnicodeDecodeError:
            raise CliInputError(f"--input: line {lineno} of {path} is not text; not a CSV of numbers") from None
        if not text:
            continue
        if first:
            first = False
            if text[:1].isalpha():  # a header (orbit.csv: n,y0_1,...)
                drop_index = text.startswith("n,")
                continue
        values = text.split(",")
        if drop_index:
            values = values[1:]
        if cols == 0:
            cols = len(values)
            _check_shape((1, cols), path)
        lines.append(",".join(values))
        if len(lines) >= _BLOCK_LINES:
            flush()
    flush()
    if not blocks:
        raise CliInputError(f"--input: {path} holds no states")
    return np.concatenate(blocks)


def _npy_member(z: zipfile.ZipFile, name: str, path: Path, table: bool) -> np.ndarray:
    """The array of member ``name``: header first (shape, dtype checked), then the data in blocks."""
    from numpy.lib import format as npf

    with z.open(name + ".npy") as m:
        version = npf.read_magic(m)
        if version == (1, 0):
            shape, fortran, dtype = npf.read_array_header_1_0(m)
        elif version in ((2, 0), (3, 0)):
            shape, fortran, dtype = npf.read_array_header_2_0(m)
        else:
            raise ValueError(f"unsupported .npy version {version}")
        if dtype.hasobject or dtype.kind not in "biufc" or dtype.itemsize > 16:
            raise CliInputError(f"--input: {path}: {name} has dtype {dtype}; give numbers")
        if table:
            _check_shape(tuple(shape), path)
        elif len(shape) > 1 or (shape and shape[0] > (1 << 28)):
            raise CliInputError(f"--input: {path}: {name} must be a number or one value per orbit, got shape {shape}")
        count = int(np.prod(shape, dtype=np.int64))
        out = np.empty(count, dtype=dtype)
        buf = out.view(np.uint8)
        done = 0
        while done < buf.size:
            chunk = m.read(min(_BLOCK_BYTES, buf.size - done))
            if not chunk:
                raise ValueError(f"{name} is truncated")
            buf[done : done + len(chunk)] = np.frombuffer(chunk, dtype=np.uint8)
            done += len(chunk)
    out = out.reshape(shape, order="F" if fortran else "C")
    return out.astype(out.dtype.newbyteorder("="), copy=False)


def _read_npz(fh, path: Path) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    try:
        with zipfile.ZipFile(io.BufferedReader(fh)) as z:  # type: ignore[arg-type]
            names = {n[:-4] for n in z.namelist() if n.endswith(".npy")}
            if "X" not in names:
                raise CliInputError(f"--input: {path} has no array 'X' (the initial states, shape (B, 3N))")
            X = _npy_member(z, "X", path, table=True)
            b = _npy_member(z, "b", path, table=False) if "b" in names else None
            eta = _npy_member(z, "eta", path, table=False) if "eta" in names else None
    except CliInputError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError, EOFError, KeyError,
            NotImplementedError) as exc:
        raise CliInputError(f"--input: cannot read {path} as NPZ: {one_line(exc) or type(exc).__name__}") from None
    if X.dtype.kind == "c":
        if np.any(X.imag):
            raise CliInputError(f"--input: {path}: X holds complex states; the states must be real (a real orbit of "
                                "the real map)")
        X = X.real
    return X.astype(float), b, eta
