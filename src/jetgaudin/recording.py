r"""Recording of long Bäcklund orbits: streamed, resumable, interrupt-safe, health-checked.

This is the *recording* layer of the package (the map knows nothing about saving; this driver knows
nothing about the mathematics).  One driver, :func:`run_orbit`, iterates
:class:`jetgaudin.TwoPointBacklund` through its public API in chunks -- ``iterate(X, k, save_every=...,
nu1=ν1, return_nu=True, kernel="compiled")`` or a loop over ``step(X, ν1)`` (``kernel="numpy"``) -- and
streams the orbit into a run directory::

    DIR/orbit.h5     HDF5 (SWMR mode): datasets ``n`` (int64, rows) and ``X`` (float64, rows × 3N)
    DIR/orbit.csv    header ``n,y0_1,y0_2,y0_3,y1_1,...``; one row per saved step, 17 significant digits
    DIR/run.json     inputs, version, kernel, status, last safe step, checkpoint, integrals at n = 0, drifts

Guarantees (tested in ``tests/test_recording.py`` and ``tests/test_fuzz.py``; see ``docs/reliability.md``):

* Rows are saved for ``n ≡ 0 (mod save_every)`` and for the last step.  Memory is constant: a chunk holds
  at most ``chunk_rows`` rows and lasts about 0.05-0.1 s.
* A *checkpoint* is written at most every ``checkpoint_seconds`` and at every stop: rows are appended to
  ``orbit.h5`` and ``orbit.csv``, both are flushed and ``fsync``-ed, then ``run.json`` is replaced
  atomically (temporary file, ``fsync``, ``os.replace``) with SHA-256 digests of the rows, of the CSV
  and of itself.  ``run.json`` is the authority: rows beyond ``checkpoint.rows`` are never read back
  (:func:`load_orbit` cuts them off, a resume drops them).
* The checkpoint stores the exact state (``float.hex``) and the eigenvalue ``ν1`` the next step continues
  from.  Every step is a deterministic function of ``(X, ν1)`` and the chunked ``iterate`` gives the same
  bits however a run is split, so a resumed run equals the uninterrupted one bit for bit (the kernel is
  recorded and reused: the compiled and NumPy kernels agree only to round-off).
* SIGINT / SIGTERM set a flag; the driver stops after the current chunk, writes a checkpoint, marks the
  run ``interrupted`` and raises :class:`RunInterrupted`.  After SIGKILL the HDF5 file (SWMR mode) still
  opens (as a SWMR reader; :func:`load_orbit` does this) and holds every checkpointed row.
* Health: every chunk checks the drift of the 2N integrals at the saved rows
  (``|I_k(n) − I_k(0)| / max(1, |I_k(0)|)`` against ``max_drift``) and the imaginary residue of the real
  map (every step with the NumPy kernel, one reference step per chunk with the compiled one, against
  ``max_imag``); a breach, non-finite integrals or a :class:`~jetgaudin.SingularStepError` /
  :class:`~jetgaudin.BranchPointError` along the orbit stop the run with status ``failed: <reason>`` and
  the data before it on disk.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import jetgaudin as jg

from ._errors import InvalidParameterError, JetGaudinError, RecordingError
from ._validate import as_state

__all__ = [
    "RecordingError",
    "RunInterrupted",
    "OrbitSpec",
    "RecordOptions",
    "HealthLimits",
    "RunResult",
    "run_orbit",
    "load_orbit",
    "read_run",
    "csv_header",
    "format_rows",
    "read_csv",
    "write_table",
    "integral_names",
    "DEFAULT_MAX_DRIFT",
    "DEFAULT_MAX_IMAG",
]

#: default health thresholds.  The map preserves the integrals up to round-off, which accumulates about
#: linearly: ~2e-13 (relative) after 10^3 steps and ~1e-8 after 5*10^7 steps for Appendix 2 (measured by
#: benchmarks/memory_long_run.py), i.e. ~2e-16 per step.  1e-6 leaves room for ~10^9 steps of round-off and
#: still flags a genuine loss of accuracy (a near-singular step jumps by far more).  The imaginary residue
#: of a real step is ~1e-18; 1e-8 flags a step that is no longer real.
DEFAULT_MAX_DRIFT = 1e-6
DEFAULT_MAX_IMAG = 1e-8

RUN_JSON = "run.json"
ORBIT_H5 = "orbit.h5"
ORBIT_CSV = "orbit.csv"


class RunInterrupted(Exception):  # noqa: N818 - a normal outcome (not bad input), hence not a JetGaudinError
    """The run stopped on SIGINT / SIGTERM after writing a checkpoint (``signum``, ``last_safe_step``)."""

    def __init__(self, signum: int, last_safe_step: int, out_dir: Path, command: str = "jetgaudin orbit"):
        self.signum = int(signum)
        self.last_safe_step = int(last_safe_step)
        self.out_dir = Path(out_dir)
        name = signal.Signals(self.signum).name
        super().__init__(
            f"interrupted by {name} at step {last_safe_step} (saved); resume with: {command} --resume {out_dir}"
        )

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


def integral_names(N: int) -> list[str]:
    """``["H_1", …, "H_N", "C_1", …, "C_N"]``, the order of :func:`jetgaudin.integrals`."""
    return [f"H_{k}" for k in range(1, N + 1)] + [f"C_{k}" for k in range(1, N + 1)]


@dataclass(frozen=True)
class OrbitSpec:
    """The inputs that determine an orbit: field ``b``, ``η``, number of steps, ``X0`` (3N), branch."""

    b: float
    eta: complex
    steps: int
    X0: tuple
    branch: str = "default"

    def __post_init__(self):
        if isinstance(self.steps, bool) or not isinstance(self.steps, (int, np.integer)) or self.steps < 0:
            raise InvalidParameterError(f"steps must be a non-negative integer, got {self.steps!r}")
        X0, _ = as_state(np.asarray(self.X0, dtype=float), name="the initial state")
        if X0.ndim != 1:
            raise InvalidParameterError("the initial state must be one state of 3N numbers")
        object.__setattr__(self, "X0", tuple(float(v) for v in X0))
        object.__setattr__(self, "steps", int(self.steps))
        # validates b != 0, finite eta and the branch name (raises InvalidParameterError)
        B = jg.TwoPointBacklund(self.b, self.eta, self.branch)
        object.__setattr__(self, "b", B.b)
        object.__setattr__(self, "eta", B.eta)
        if B.eta.imag == 0:
            raise InvalidParameterError(
                "Im(eta) = 0: the real two-point map is then the identity (its time step is Im eta); "
                "give eta with a nonzero imaginary part, e.g. 5+0.1i"
            )
        # nu(eta) must be defined on the chosen branch at X0 (raises BranchPointError otherwise)
        with np.errstate(all="ignore"):
            if not np.all(np.isfinite(jg.integrals(np.asarray(self.X0), B.b))):
                raise InvalidParameterError("the initial state is too large: its integrals overflow; scale it down")
            try:
                nu1 = complex(B.nu1(np.asarray(self.X0)))
            except (np.linalg.LinAlgError, FloatingPointError, OverflowError, ZeroDivisionError):
                nu1 = complex(math.nan)
        if not (math.isfinite(nu1.real) and math.isfinite(nu1.imag)):
            raise InvalidParameterError(
                f"nu(eta) cannot be computed at the initial state ({nu1}); b, eta or the state is too large"
            )

    @property
    def N(self) -> int:
        return len(self.X0) // 3

    def backlund(self) -> jg.TwoPointBacklund:
        return jg.TwoPointBacklund(self.b, self.eta, self.branch)

    def to_json(self) -> dict:
        return {
            "b": self.b,
            "eta": [self.eta.real, self.eta.imag],
            "steps": self.steps,
            "init": list(self.X0),
            "branch": self.branch,
            "N": self.N,
        }

    @classmethod
    def from_json(cls, d: dict) -> OrbitSpec:
        return cls(b=d["b"], eta=complex(*d["eta"]), steps=d["steps"], X0=tuple(d["init"]), branch=d["branch"])


@dataclass(frozen=True)
class RecordOptions:
    """How the orbit is recorded: every ``save_every``-th step, CSV or not, checkpoint cadence, kernel
    (``auto``, ``compiled`` or ``numpy``, see :func:`resolve_kernel`)."""

    save_every: int = 1
    csv: bool = True
    checkpoint_seconds: float = 1.0
    chunk_rows: int = 4096
    kernel: str = "auto"

    def __post_init__(self):
        if (
            isinstance(self.save_every, bool)
            or not isinstance(self.save_every, (int, np.integer))
            or self.save_every < 1
        ):
            raise InvalidParameterError(f"save_every must be an integer >= 1, got {self.save_every!r}")
        if not (self.checkpoint_seconds >= 0) or not math.isfinite(self.checkpoint_seconds):
            raise InvalidParameterError("checkpoint_seconds must be a finite number >= 0")
        if int(self.chunk_rows) < 1:
            raise InvalidParameterError("chunk_rows must be >= 1")


@dataclass(frozen=True)
class HealthLimits:
    """Thresholds of the numerical health checks (defaults :data:`DEFAULT_MAX_DRIFT`, :data:`DEFAULT_MAX_IMAG`)."""

    max_drift: float = DEFAULT_MAX_DRIFT
    max_imag: float = DEFAULT_MAX_IMAG

    def __post_init__(self):
        for name in ("max_drift", "max_imag"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or math.isnan(v) or v < 0:
                raise InvalidParameterError(f"{name} must be a number >= 0 (inf disables the check), got {v!r}")


@dataclass(frozen=True)
class RunResult:
    """Outcome of :func:`run_orbit` (also in ``run.json``)."""

    out_dir: Path
    status: str
    last_safe_step: int
    rows: int
    integrals0: np.ndarray
    max_drift_abs: np.ndarray
    max_drift_rel: np.ndarray
    max_imag_residue: float
    sphere_radius0: float
    sphere_max_deviation: float
    elapsed: float
    files: tuple = field(default_factory=tuple)
    kernel: str = "numpy"


# ----------------------------------------------------------------------------------------- tables
def csv_header(N: int, index: str = "n") -> str:
    """``n,y0_1,y0_2,y0_3,y1_1,…`` (``y{i}_{a}`` is the component ``a`` of ``y_i``)."""
    return ",".join([index] + [f"y{i}_{a}" for i in range(N) for a in (1, 2, 3)]) + "\n"


def format_rows(index, X) -> str:
    """CSV rows: the index, then the components with 17 significant digits (``%.17g``: every double
    round-trips exactly through ``float()``)."""
    lines = []
    for i, row in zip(index, X, strict=True):
        lines.append((f"{i:.17g}" if isinstance(i, float) else str(i)) + "," + ",".join(f"{v:.17g}" for v in row))
    return "\n".join(lines) + ("\n" if lines else "")


def read_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """``(index, X)`` from a CSV written by this module."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float)
    return data[:, 0], data[:, 1:]


def write_table(out_dir, stem: str, index, X, *, index_name: str = "n", attrs: dict | None = None) -> list[Path]:
    """Write ``stem.csv`` and ``stem.h5`` (datasets ``index_name`` and ``X``) atomically (temp + rename)."""
    out_dir = Path(out_dir)
    X = np.asarray(X, dtype=float)
    index = np.asarray(index)
    N = X.shape[-1] // 3
    csv_path, h5_path = out_dir / f"{stem}.csv", out_dir / f"{stem}.h5"
    _atomic_write_text(csv_path, csv_header(N, index_name) + format_rows(index.tolist(), X))
    import h5py

    tmp = h5_path.with_suffix(".h5.tmp")
    with h5py.File(tmp, "w") as f:
        f.create_dataset(index_name, data=index)
        f.create_dataset("X", data=X)
        for k, v in (attrs or {}).items():
            f.attrs[k] = v
    os.replace(tmp, h5_path)
    return [csv_path, h5_path]


# ----------------------------------------------------------------------------------------- files
def _atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def _fsync_path(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _hex(v) -> str:
    return float(v).hex()


def _unhex(s) -> float:
    return float.fromhex(s)


def _run_digest(run: dict) -> str:
    body = {k: v for k, v in run.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def _write_run(out_dir, run: dict) -> None:
    """Write ``run.json`` atomically with a SHA-256 digest of its content (field ``sha256``)."""
    run["sha256"] = _run_digest(run)
    _atomic_write_text(Path(out_dir) / RUN_JSON, json.dumps(run, indent=1) + "\n")


def read_run(out_dir, *, verify: bool = False) -> dict:
    """The parsed ``run.json`` of a run directory (:class:`RecordingError` if missing or corrupted;
    ``verify=True`` also checks its ``sha256`` digest, as a resume does)."""
    path = Path(out_dir) / RUN_JSON
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        raise RecordingError(f"{path} does not exist: not a jetgaudin run directory") from None
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        data = json.loads(text)
        if not isinstance(data, dict) or "inputs" not in data or "status" not in data:
            raise ValueError("missing keys")
    except (ValueError, RecursionError):
        raise RecordingError(f"{path} is corrupted (not a jetgaudin run.json); cannot use this run") from None
    if verify and data.get("sha256") != _run_digest(data):
        raise RecordingError(f"{path} does not match its own digest (corrupted or edited); cannot use this run")
    return data


_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _check_h5_eof(path: Path) -> None:
    """Refuse a truncated HDF5 file before a SWMR reader touches it (SWMR reads of missing bytes retry
    without end).  The version-2/3 superblock at offset 0 stores the end-of-file address."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
        size = os.path.getsize(path)
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


def _open_h5_read(path: Path):
    import h5py

    try:
        return h5py.File(path, "r")
    except OSError as exc:
        msg = str(exc)
        if "open for write" not in msg and "h5clear" not in msg:
            raise
    # a run killed while writing leaves the SWMR "open for write" flag set: open as a SWMR reader
    _check_h5_eof(path)
    return h5py.File(path, "r", swmr=True)


def load_orbit(out_dir) -> tuple[np.ndarray, np.ndarray]:
    """``(n, X)`` of a run directory: only the rows safely on disk (``run.json``'s checkpoint)."""
    out_dir = Path(out_dir)
    run = read_run(out_dir)
    rows = int(run.get("checkpoint", {}).get("rows", 0))
    try:
        with _open_h5_read(out_dir / ORBIT_H5) as f:
            if f["X"].shape[0] < rows or f["n"].shape[0] < rows:
                raise RecordingError(f"{out_dir / ORBIT_H5} holds fewer rows than run.json records: truncated")
            return f["n"][:rows], f["X"][:rows]
    except (OSError, KeyError) as exc:
        raise RecordingError(f"cannot read {out_dir / ORBIT_H5}: {exc}") from None


# ----------------------------------------------------------------------------------------- driver
class _SignalFlag:
    """Install SIGINT/SIGTERM handlers that only set a flag (main thread only; a no-op elsewhere)."""

    def __init__(self, enabled: bool):
        self.signum = 0
        self._old = {}
        self.enabled = enabled and threading.current_thread() is threading.main_thread()

    def _handler(self, signum, _frame):
        self.signum = signum

    def __enter__(self):
        if self.enabled:
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc):
        for s, h in self._old.items():
            signal.signal(s, h)
        return False


class _RowDigest:
    """SHA-256 of the ``n`` column and of the ``X`` rows as two streams (independent of how they are chunked)."""

    def __init__(self):
        self.hn, self.hX = hashlib.sha256(), hashlib.sha256()

    def update(self, n_idx, X) -> None:
        self.hn.update(np.ascontiguousarray(n_idx, dtype="<i8").tobytes())
        self.hX.update(np.ascontiguousarray(X, dtype="<f8").tobytes())

    def hexdigest(self) -> str:
        return self.hn.hexdigest() + ":" + self.hX.hexdigest()


class _Writer:
    """Appends rows to orbit.h5 (SWMR) and orbit.csv and writes checkpoints to run.json.

    SHA-256 digests of the rows (``n`` as int64 and ``X`` as float64, little-endian, see :class:`_RowDigest`) and of
    the CSV bytes are kept up to date and stored with each checkpoint; a resume recomputes them from the
    files and refuses data that do not match (corrupted or edited files)."""

    _COPY_BLOCK = 1 << 16  # rows copied at a time on resume (constant memory)

    def __init__(self, out_dir: Path, N: int, csv: bool, chunk_rows: int, run: dict, fresh: bool):
        import h5py

        self.out_dir, self.N, self.csv, self.run = out_dir, N, csv, run
        self.h5_path, self.csv_path = out_dir / ORBIT_H5, out_dir / ORBIT_CSV
        self.h_rows, self.h_csv = _RowDigest(), hashlib.sha256()
        ck = run["checkpoint"]
        tmp = out_dir / (ORBIT_H5 + ".tmp")
        if fresh:
            self.rows, self.csv_bytes = 0, 0
            self._create_h5(h5py, tmp, None, 0, chunk_rows)
            os.replace(tmp, self.h5_path)
            if csv:
                head = csv_header(N).encode()
                self.csv_path.write_bytes(head)
                self.h_csv.update(head)
                self.csv_bytes = len(head)
        else:
            self.rows, self.csv_bytes = int(ck["rows"]), int(ck["csv_bytes"])
            # rebuild orbit.h5 with exactly the checkpointed rows (drops rows written after the last
            # checkpoint and clears the SWMR flag a killed writer leaves behind), verifying their digest
            try:
                with _open_h5_read(self.h5_path) as old:
                    if old["X"].shape[0] < self.rows or old["n"].shape[0] < self.rows or old["X"].shape[1:] != (3 * N,):
                        raise RecordingError(
                            f"{self.h5_path} is truncated: it holds fewer rows than run.json records; cannot resume"
                        )
                    self._create_h5(h5py, tmp, old, self.rows, chunk_rows)
            except (OSError, KeyError, ValueError, TypeError) as exc:
                raise RecordingError(f"{self.h5_path} is unreadable or corrupted ({exc}); cannot resume") from None
            if self.h_rows.hexdigest() != ck.get("rows_sha256"):
                tmp.unlink(missing_ok=True)
                raise RecordingError(f"{self.h5_path} does not match the digest in run.json (corrupted); cannot resume")
            os.replace(tmp, self.h5_path)
            if csv:
                try:
                    size = self.csv_path.stat().st_size
                    with open(self.csv_path, "rb") as fh:
                        left = self.csv_bytes
                        while left > 0:
                            block = fh.read(min(left, 1 << 22))
                            if not block:
                                break
                            self.h_csv.update(block)
                            left -= len(block)
                except OSError:
                    raise RecordingError(f"{self.csv_path} is missing or unreadable; cannot resume") from None
                if size < self.csv_bytes:
                    raise RecordingError(f"{self.csv_path} is truncated (shorter than run.json records); cannot resume")
                if self.h_csv.hexdigest() != ck.get("csv_sha256"):
                    raise RecordingError(
                        f"{self.csv_path} does not match the digest in run.json (corrupted); cannot resume"
                    )
                os.truncate(self.csv_path, self.csv_bytes)
        self.f = h5py.File(self.h5_path, "a", libver="latest")
        self.dn, self.dX = self.f["n"], self.f["X"]
        self.f.swmr_mode = True
        self.csv_fh = open(self.csv_path, "ab") if csv else None  # noqa: SIM115

    def _create_h5(self, h5py, path, old, rows, chunk_rows):
        with h5py.File(path, "w", libver="latest") as f:
            n = 3 * self.N
            ch = max(1, min(int(chunk_rows), 4096))
            dn = f.create_dataset("n", shape=(rows,), maxshape=(None,), chunks=(ch,), dtype="i8")
            dX = f.create_dataset("X", shape=(rows, n), maxshape=(None, n), chunks=(ch, n), dtype="f8")
            for a in range(0, rows if old is not None else 0, self._COPY_BLOCK):
                e = min(rows, a + self._COPY_BLOCK)
                bn, bX = old["n"][a:e], old["X"][a:e]
                dn[a:e], dX[a:e] = bn, bX
                self.h_rows.update(bn, bX)
            f.attrs["inputs"] = json.dumps(self.run["inputs"])
            f.attrs["columns"] = csv_header(self.N).strip()
            f.attrs["note"] = "rows beyond run.json checkpoint.rows are not data (see docs/reliability.md)"

    def append(self, n_idx: np.ndarray, X: np.ndarray) -> None:
        k = len(n_idx)
        if k == 0:
            return
        r = self.rows
        self.dn.resize((r + k,))
        self.dX.resize((r + k, 3 * self.N))
        self.dn[r : r + k] = n_idx
        self.dX[r : r + k] = X
        self.h_rows.update(n_idx, X)
        if self.csv_fh is not None:
            text = format_rows(n_idx.tolist(), X).encode()
            self.csv_fh.write(text)
            self.h_csv.update(text)
        self.rows = r + k

    def checkpoint(self, **update) -> None:
        self.dn.flush()
        self.dX.flush()
        self.f.flush()
        _fsync_path(self.h5_path)
        ck = self.run["checkpoint"]
        if self.csv_fh is not None:
            self.csv_fh.flush()
            os.fsync(self.csv_fh.fileno())
            self.csv_bytes = self.csv_fh.tell()
            ck["csv_sha256"] = self.h_csv.hexdigest()
        ck.update(rows=self.rows, csv_bytes=self.csv_bytes, rows_sha256=self.h_rows.hexdigest())
        self.run.update(update)
        self.run["updated"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        _write_run(self.out_dir, self.run)

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.f.close()
        if self.csv_fh is not None:
            with contextlib.suppress(Exception):
                self.csv_fh.close()


def _mark_crashed(out_dir: Path, run: dict, exc: BaseException) -> None:
    """An unexpected error (a bug, a full disk) during a run: the checkpointed data stay valid and resumable, so
    ``run.json`` says ``interrupted`` and records the error (best effort: the disk may be what failed)."""
    with contextlib.suppress(Exception):
        run["status"] = "interrupted"
        run["error"] = one_line(f"{type(exc).__name__}: {exc}")
        _write_run(out_dir, run)


def _prepare_dir(out_dir: Path) -> None:
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        probe = out_dir / ".jetgaudin-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise RecordingError(f"cannot write to output directory {out_dir}: {exc.strerror or exc}") from None


def _inputs(spec: OrbitSpec, options: RecordOptions, limits: HealthLimits) -> dict:
    d = spec.to_json()
    d.update(
        save_every=int(options.save_every),
        csv=bool(options.csv),
        kernel=options.kernel,
        max_drift=limits.max_drift,
        max_imag=limits.max_imag,
    )
    return d


def resolve_kernel(kernel: str, steps: int = 0, n_state: int = 9) -> str:
    """``"auto"`` -> the kernel :func:`jetgaudin.backlund.auto_kernel` picks for ``steps`` steps of one orbit
    (``"numpy"`` for short runs such as Appendix 2 unless the compiled kernels are already loaded or cached);
    the resolved name is recorded so that a resumed run uses the same kernel (the two agree only to round-off,
    not bit for bit)."""
    if kernel not in ("auto", "compiled", "numpy"):
        raise InvalidParameterError(f"kernel must be 'auto', 'compiled' or 'numpy', got {kernel!r}")
    if kernel == "auto":
        from .backlund import auto_kernel

        return auto_kernel(steps, n_state)
    return kernel


class _Stepper:
    """Advance ``(X, ν1)`` by one chunk through the public API; return the saved rows and the imaginary residue.

    ``numpy``: a loop over :meth:`TwoPointBacklund.step` (the residue of every step is checked).
    ``compiled``: :meth:`TwoPointBacklund.iterate` with ``nu1``/``return_nu`` (chunks split anywhere give the
    same orbit bit for bit); the residue is sampled by one reference ``step`` at the start of each chunk.
    """

    def __init__(self, B, kernel: str, every: int, steps: int):
        self.B, self.kernel, self.every, self.steps = B, kernel, every, steps

    def advance(self, X, nu1, n, L, max_imag, stop):
        """Steps ``n -> n + L``; rows at multiples of ``every`` and at ``steps``.  Returns
        ``(rows_n, rows_X, X, nu1, n, imag_max, failure)``; stops early (numpy) on a residue breach or
        when ``stop()`` is true."""
        every, steps = self.every, self.steps
        rows_n, rows_X = [], []
        imag_max, failure = 0.0, None
        if self.kernel == "numpy":
            for _ in range(L):
                X, nu1, imag = self.B.step(X, nu1)
                n += 1
                im = float(np.max(imag))
                imag_max = max(imag_max, im)
                if n % every == 0 or n == steps:
                    rows_n.append(n)
                    rows_X.append(X)
                if im > max_imag:
                    failure = f"imaginary residue {im:.3e} of the real map at step {n} > max_imag {max_imag:g}"
                    break
                if stop():
                    break
            return rows_n, rows_X, X, nu1, n, imag_max, failure
        # compiled: sample the residue of the next step with the reference route
        _, _, imag = self.B.step(X, nu1)
        imag_max = float(np.max(imag))
        if imag_max > max_imag:
            failure = f"imaginary residue {imag_max:.3e} of the real map at step {n + 1} > max_imag {max_imag:g}"
            return rows_n, rows_X, X, nu1, n, imag_max, failure
        B = self.B

        def segment(X, nu1, k, every_k):
            out, nu1 = B.iterate(X, k, save_every=every_k, kernel="compiled", nu1=nu1, return_nu=True)
            return out, nu1

        head = min((-n) % every, L)  # up to the next multiple of every (a run resumed off the grid)
        if head:
            out, nu1 = segment(X, nu1, head, head)
            X, n = out[-1], n + head
            if n % every == 0 or n == steps:
                rows_n.append(n)
                rows_X.append(X)
        full = ((L - head) // every) * every
        if full:
            out, nu1 = segment(X, nu1, full, every)
            X = out[-1]
            rows_n.extend(range(n + every, n + full + 1, every))
            rows_X.extend(out[1:])
            n += full
        rest = L - head - full
        if rest:
            out, nu1 = segment(X, nu1, rest, rest)
            X, n = out[-1], n + rest
            if n == steps:
                rows_n.append(n)
                rows_X.append(X)
        return rows_n, rows_X, X, nu1, n, imag_max, failure


def run_orbit(
    spec: OrbitSpec | None,
    out_dir,
    *,
    options: RecordOptions | None = None,
    limits: HealthLimits | None = None,
    resume: bool = False,
    expect: dict | None = None,
    progress: Callable[[int, int], None] | None = None,
    handle_signals: bool = True,
    backlund=None,
) -> RunResult:
    """Iterate the real two-point map and stream the orbit into ``out_dir`` (see the module doc).

    ``resume=True`` continues the run recorded in ``out_dir`` from its last safe step; ``spec`` and
    ``limits`` are then ignored (the recorded ones are used; ``options`` gives only the checkpoint cadence)
    and ``expect`` maps input names of ``run.json["inputs"]`` (``b``, ``eta`` as ``[re, im]``, ``steps``,
    ``init``, ``branch``, ``save_every``, ``csv``, ``kernel``, ``max_drift``, ``max_imag``) to values the user
    gave: any difference is refused with :class:`RecordingError`.
    ``progress(n, steps)`` is called about ten times a second.  ``backlund`` (testing hook) replaces
    the map built from ``spec``: an object with ``step(X, ν1) -> (X̆, ν1, imag_residue)`` (kernel ``numpy``).

    Returns a :class:`RunResult` (status ``completed`` or ``failed: <reason>``); raises
    :class:`RunInterrupted` on SIGINT/SIGTERM and :class:`RecordingError` for unusable directories.
    """
    out_dir = Path(out_dir)
    options = options or RecordOptions()
    if resume:
        run = read_run(out_dir, verify=True)
        status = str(run["status"])
        if status == "completed":
            raise RecordingError(f"the run in {out_dir} is already completed; nothing to resume")
        if status.startswith("failed"):
            raise RecordingError(f"the run in {out_dir} {status}; it cannot be resumed (it would fail again)")
        try:
            rec = run["inputs"]
            spec = OrbitSpec.from_json(rec)
            kernel = rec["kernel"]
            if kernel not in ("compiled", "numpy"):
                raise ValueError(f"unknown kernel {kernel!r}")
            options = RecordOptions(
                save_every=rec["save_every"],
                csv=rec["csv"],
                kernel=kernel,
                checkpoint_seconds=options.checkpoint_seconds,
                chunk_rows=options.chunk_rows,
            )
            limits = HealthLimits(float(rec["max_drift"]), float(rec["max_imag"]))
            ck = run["checkpoint"]
            n0 = int(ck["step"])
            X = np.array([_unhex(s) for s in ck["X_hex"]])
            nu1 = None if ck["nu1_hex"] is None else complex(_unhex(ck["nu1_hex"][0]), _unhex(ck["nu1_hex"][1]))
            I0 = np.array([_unhex(s) for s in run["integrals0_hex"]])
            drift = np.array(run["max_drift_abs"], dtype=float)
            max_imag = float(run["max_imag_residue"])
            sph_dev = float(run["sphere"]["max_deviation"])
            elapsed0 = float(run.get("elapsed_seconds", 0.0))
            if (
                X.shape != (3 * spec.N,)
                or not (0 <= n0 <= spec.steps)
                or drift.shape != I0.shape
                or I0.shape != (2 * spec.N,)
                or not np.all(np.isfinite(X))
            ):
                raise ValueError("inconsistent checkpoint")
        except (KeyError, TypeError, ValueError, IndexError, JetGaudinError) as exc:
            raise RecordingError(f"{out_dir / RUN_JSON} is corrupted ({exc}); cannot resume") from None
        mine = _inputs(spec, options, limits)
        if expect:
            diff = [k for k, v in expect.items() if k not in mine or mine[k] != v]
            if diff:
                raise RecordingError(
                    f"cannot resume {out_dir} with different inputs ({', '.join(diff)}); "
                    "drop those options or start a new run in another --out directory"
                )
        _prepare_dir(out_dir)
        writer = _Writer(out_dir, spec.N, options.csv, options.chunk_rows, run, fresh=False)
    else:
        if spec is None:
            raise InvalidParameterError("spec is required for a new run")
        kernel = "numpy" if backlund is not None else resolve_kernel(options.kernel, spec.steps, 3 * spec.N)
        options = RecordOptions(
            save_every=options.save_every,
            csv=options.csv,
            kernel=kernel,
            checkpoint_seconds=options.checkpoint_seconds,
            chunk_rows=options.chunk_rows,
        )
        limits = limits or HealthLimits()
        _prepare_dir(out_dir)
        X = np.array(spec.X0, dtype=float)
        n0, nu1 = 0, None
        I0 = np.asarray(jg.integrals(X, spec.b), dtype=float)
        drift = np.zeros_like(I0)
        max_imag, sph_dev, elapsed0 = 0.0, 0.0, 0.0
        run = {
            "program": "jetgaudin orbit",
            "version": jg.__version__,
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "inputs": _inputs(spec, options, limits),
            "status": "running",
            "last_safe_step": 0,
            "integral_names": integral_names(spec.N),
            "integrals0": I0.tolist(),
            "integrals0_hex": [_hex(v) for v in I0],
            "checkpoint": {"step": 0, "X_hex": [_hex(v) for v in X], "nu1_hex": None, "rows": 0, "csv_bytes": 0},
        }
        writer = _Writer(out_dir, spec.N, options.csv, options.chunk_rows, run, fresh=True)
    B = backlund if backlund is not None else spec.backlund()
    N, steps, every = spec.N, spec.steps, options.save_every
    stepper = _Stepper(B, kernel, every, steps)
    r0 = float(np.linalg.norm(np.asarray(spec.X0)[3 * N - 3 :]))  # |y_{N-1}| is a Casimir: sqrt(C_N)
    scale = np.maximum(1.0, np.abs(I0))
    names = integral_names(N)
    t_start = time.monotonic()
    t_ck = t_prog = t_start
    n = n0

    def health(rows_n, rows_X):
        """Drift of the integrals over the rows (and |y_{N-1}|); a failure reason or None."""
        nonlocal drift, sph_dev
        if not rows_n:
            return None
        R = np.asarray(rows_X)
        with np.errstate(all="ignore"):
            I = np.asarray(jg.integrals(R, spec.b), dtype=float)
            d = np.abs(I - I0)
            sph = np.abs(np.linalg.norm(R[:, 3 * N - 3 :], axis=1) - r0)
        if not np.all(np.isfinite(d)):
            return f"non-finite integrals at step {rows_n[int(np.argmax(~np.all(np.isfinite(d), axis=1)))]}"
        drift = np.maximum(drift, d.max(axis=0))
        sph_dev = max(sph_dev, float(sph.max()))
        bad = d / scale > limits.max_drift
        if np.any(bad):
            i, k = np.argwhere(bad)[0]
            return (
                f"integral drift: {names[k]} drifted by {d[i, k] / scale[k]:.4e} (relative to max(1, |I(0)|)) "
                f"at step {rows_n[i]} > max_drift {limits.max_drift:g}"
            )
        return None

    def summary(status_):
        return dict(
            status=status_,
            last_safe_step=int(n),
            max_drift_abs=drift.tolist(),
            max_drift_rel=(drift / np.where(I0 != 0, np.abs(I0), 1.0)).tolist(),
            max_drift_rel_note="|I_k(n) - I_k(0)| / |I_k(0)| over the saved rows (absolute where I_k(0) = 0)",
            max_imag_residue=max_imag,
            sphere={"block": f"y_{N - 1}", "radius0": r0, "max_deviation": sph_dev},
            elapsed_seconds=elapsed0 + time.monotonic() - t_start,
        )

    def checkpoint(status_):
        ck = run["checkpoint"]
        ck["step"] = int(n)
        ck["X_hex"] = [_hex(v) for v in X]
        ck["nu1_hex"] = None if nu1 is None else [_hex(complex(nu1).real), _hex(complex(nu1).imag)]
        writer.checkpoint(**summary(status_))

    failure = None
    interrupted = 0
    # chunk length: a multiple of save_every, adapted so that one chunk takes ~0.1 s (signals are handled
    # between chunks) and holds at most chunk_rows rows (constant memory)
    max_L = max(every, (options.chunk_rows // 1) * every)
    L = every if kernel == "compiled" else min(max_L, max(1, 64 // every) * every)
    try:
        with _SignalFlag(handle_signals) as sig:
            if not resume:
                failure = health([0], [X])
                writer.append(np.array([0]), X[None, :])
                checkpoint("running")
            while failure is None and n < steps and not sig.signum:
                length = min(L, steps - n)
                t0 = time.monotonic()
                try:
                    rows_n, rows_X, X_new, nu_new, n_new, im, failure = stepper.advance(
                        X, nu1, n, length, limits.max_imag, lambda: bool(sig.signum)
                    )
                except JetGaudinError as exc:  # SingularStepError, BranchPointError met along the orbit
                    failure = f"{type(exc).__name__} after step {n}: {one_line(exc)}"
                    break
                dt = time.monotonic() - t0
                max_imag = max(max_imag, im)
                reason = health(rows_n, rows_X)
                failure = failure or reason
                if rows_n:
                    writer.append(np.asarray(rows_n, dtype=np.int64), np.asarray(rows_X))
                X, nu1, n = X_new, nu_new, n_new
                if kernel == "compiled" and length == L:
                    L = int(min(max_L, max(every, (L * 2 if dt < 0.05 else L) // every * every)))
                now = time.monotonic()
                if failure is None and now - t_ck >= options.checkpoint_seconds:
                    checkpoint("running")
                    t_ck = now
                if progress is not None and now - t_prog >= 0.1:
                    progress(n, steps)
                    t_prog = now
            if sig.signum and failure is None and n < steps:
                interrupted = sig.signum
                status = "interrupted"
            elif failure is not None:
                status = f"failed: {failure}"
            else:
                status = "completed"
            checkpoint(status)
            if progress is not None:
                progress(n, steps)
    except BaseException as exc:
        _mark_crashed(out_dir, run, exc)
        raise
    finally:
        writer.close()
    if interrupted:
        raise RunInterrupted(interrupted, n, out_dir)
    files = (out_dir / ORBIT_H5,) + ((out_dir / ORBIT_CSV,) if options.csv else ()) + (out_dir / RUN_JSON,)
    return RunResult(
        out_dir=out_dir,
        status=status,
        last_safe_step=int(n),
        rows=writer.rows,
        integrals0=I0,
        max_drift_abs=drift.copy(),
        max_drift_rel=drift / np.where(I0 != 0, np.abs(I0), 1.0),
        max_imag_residue=max_imag,
        sphere_radius0=r0,
        sphere_max_deviation=sph_dev,
        elapsed=elapsed0 + time.monotonic() - t_start,
        files=files,
        kernel=kernel,
    )


def one_line(msg) -> str:
    return " ".join(str(msg).split())


def update_run(out_dir, **fields) -> None:
    """Add top-level fields to ``run.json`` atomically (e.g. the list of figures written)."""
    run = read_run(out_dir)
    run.update(fields)
    _write_run(out_dir, run)
