r"""Recording of ensembles: streamed in time chunks, resumable, interrupt-safe, health-checked.

The ensemble counterpart of :mod:`jetgaudin.recording` (same guarantees, same building blocks).  One
driver, :func:`run_ensemble`, advances a batch of orbits with :func:`jetgaudin.ensemble.iterate_ensemble`
in time chunks (each chunk continues from the previous one's ``ν1``, so the chunks give the unsplit
run bit for bit) and streams the saved states into a run directory::

    DIR/ensemble.h5      HDF5 (SWMR mode): the inputs ``X0`` (B × 3N), ``b`` (B), ``eta`` (B, complex), and,
                         growing along the first axis, ``n`` (int64, rows) and ``states`` (rows × B × 3N)
    DIR/checkpoint-0.npz, DIR/checkpoint-1.npz
                         the state ``X`` (B × 3N), ``ν1`` (B) and the running drift (B × 2N) after the last
                         safe step, written alternately (``run.json`` names the valid one and its SHA-256)
    DIR/run.json         inputs, version, status, last safe step, checkpoint, drift summary

Guarantees (tested in ``tests/test_ensemble_recording.py``; ``docs/reliability.md``):

* Memory is constant: a chunk holds at most ``max_chunk_bytes`` of saved states (and at least one row)
  and lasts about 0.3-1.5 s (its length adapts), so signals are handled within about two seconds.
* A checkpoint (at most every ``checkpoint_seconds`` and at every stop) appends the rows to
  ``ensemble.h5`` and ``fsync``-s it, writes the other checkpoint slot (temporary file, ``fsync``,
  ``os.replace``), then replaces ``run.json`` atomically.  A kill at any moment leaves ``run.json``
  pointing to a complete slot and to rows that are on disk; rows beyond ``checkpoint.rows`` are never
  read back as data.
* SIGINT / SIGTERM stop the run after the current chunk with a checkpoint and status ``interrupted``
  (:class:`~jetgaudin.recording.RunInterrupted`); :func:`run_ensemble` with ``resume=True`` continues,
  and the resumed run equals the uninterrupted one bit for bit.
* Health: the drift ``|I_k(X_n) − I_k(X_0)| / max(1, |I_k(X_0)|)`` of every orbit is checked at the
  saved rows and at the end of every chunk against ``max_drift``; a breach, non-finite values or a
  singular step (:class:`~jetgaudin.SingularStepError`, :class:`~jetgaudin.BranchPointError`) stop the
  run with status ``failed: <reason>`` and the data before it on disk.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import jetgaudin as jg

from ._errors import InvalidParameterError, JetGaudinError, RecordingError
from ._validate import as_state
from .ensemble import iterate_ensemble
from .recording import (
    DEFAULT_MAX_DRIFT,
    RUN_JSON,
    RunInterrupted,
    _fsync_path,
    _mark_crashed,
    _open_h5_read,
    _prepare_dir,
    _RowDigest,
    _SignalFlag,
    _write_run,
    integral_names,
    one_line,
    read_run,
)

__all__ = ["EnsembleSpec", "EnsembleRunResult", "EnsembleData", "run_ensemble", "load_ensemble", "ENSEMBLE_H5"]

ENSEMBLE_H5 = "ensemble.h5"
COMMAND = "jetgaudin ensemble"


@dataclass(frozen=True, eq=False)
class EnsembleSpec:
    """The inputs that determine an ensemble run: ``X0`` (B, 3N), per-orbit ``b`` and ``eta`` (B,) (scalars are
    broadcast), ``steps``, ``save_every`` and ``branch``; validated as :func:`jetgaudin.ensemble.iterate_ensemble`
    does (``b ≠ 0``, ``Im η ≠ 0``, finite states)."""

    X0: np.ndarray
    b: np.ndarray
    eta: np.ndarray
    steps: int
    save_every: int = 1
    branch: str = "default"

    def __post_init__(self):
        from .ensemble import _check_int, _per_orbit

        X, _ = as_state(np.asarray(self.X0, dtype=float), name="the initial states")
        if X.ndim != 2:
            raise InvalidParameterError(f"X0 must have shape (B, 3N) (a batch of states), got shape {X.shape}")
        B = X.shape[0]
        object.__setattr__(self, "X0", np.ascontiguousarray(X))
        b = _per_orbit(self.b, B, "b", float)
        if np.any(b == 0):
            raise InvalidParameterError("the field strength b must be nonzero for every orbit (the map divides by b)")
        eta = _per_orbit(self.eta, B, "eta", complex)
        if np.any(eta.imag == 0):
            raise InvalidParameterError(
                "eta must have a nonzero imaginary part for every orbit (Im eta = 0 makes the map the identity)"
            )
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "steps", _check_int(self.steps, "steps", 0))
        object.__setattr__(self, "save_every", _check_int(self.save_every, "save_every", 1))
        if self.branch not in ("default", "opposite"):
            raise InvalidParameterError(f"branch must be 'default' or 'opposite', got {self.branch!r}")
        with np.errstate(all="ignore"):
            if not np.all(np.isfinite(_integrals(self.X0, b))):
                raise InvalidParameterError("an initial state is too large: its integrals overflow; scale it down")

    @property
    def B(self) -> int:
        return self.X0.shape[0]

    @property
    def N(self) -> int:
        return self.X0.shape[1] // 3

    def digest(self) -> str:
        """SHA-256 of ``X0``, ``b``, ``eta`` (little-endian), recorded in ``run.json``."""
        h = hashlib.sha256()
        for a, dt in ((self.X0, "<f8"), (self.b, "<f8"), (self.eta, "<c16")):
            h.update(np.ascontiguousarray(a, dtype=dt).tobytes())
        return h.hexdigest()

    def to_json(self) -> dict:
        return {
            "B": self.B,
            "N": self.N,
            "steps": self.steps,
            "save_every": self.save_every,
            "branch": self.branch,
            "inputs_sha256": self.digest(),
        }


@dataclass(frozen=True)
class EnsembleRunResult:
    """Outcome of :func:`run_ensemble` (also in ``run.json``): ``drift`` (B, 2N) is the largest relative drift of
    each integral of each orbit over the saved rows and the chunk ends."""

    out_dir: Path
    status: str
    last_safe_step: int
    rows: int
    drift: np.ndarray
    elapsed: float
    files: tuple

    @property
    def max_drift(self) -> np.ndarray:
        """Largest relative integral drift of each orbit, shape ``(B,)``."""
        return np.max(self.drift, axis=-1)


@dataclass(frozen=True)
class EnsembleData:
    """What :func:`load_ensemble` reads: step indices ``n`` (rows,), ``states`` (rows, B, 3N) and the inputs."""

    n: np.ndarray
    states: np.ndarray
    X0: np.ndarray
    b: np.ndarray
    eta: np.ndarray


def _integrals(X, b):
    """``jg.integrals`` with a per-orbit field ``b`` (shape ``(B,)``, broadcast over leading axes of ``X``).

    One field for all orbits (the usual case): exactly :func:`jetgaudin.integrals`.  Several: ``H_k`` is affine
    in ``b`` (``H_k = 2 b y_{k-1}^3 + …``, ``C_k`` does not depend on it), so ``I(b) = I(1) + 2 (b − 1) y^3``.
    """
    b = np.asarray(b, dtype=float)
    if np.all(b == b.flat[0]):
        return np.asarray(jg.integrals(X, float(b.flat[0])), dtype=float)
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    I = np.array(jg.integrals(X, 1.0), dtype=float)
    I[..., :N] += 2.0 * (b[..., None] - 1.0) * X[..., 2::3]
    return I


def _file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


class _EnsembleWriter:
    """Appends rows to ``ensemble.h5`` (SWMR) and writes the alternating checkpoint slots and ``run.json``."""

    _COPY_BLOCK_BYTES = 64 << 20

    def __init__(self, out_dir: Path, spec: EnsembleSpec, run: dict, fresh: bool):
        import h5py

        self.out_dir, self.spec, self.run = out_dir, spec, run
        self.path = out_dir / ENSEMBLE_H5
        self.h_rows = _RowDigest()
        tmp = out_dir / (ENSEMBLE_H5 + ".tmp")
        ck = run["checkpoint"]
        self.rows = 0 if fresh else int(ck["rows"])
        if fresh:
            self._create(h5py, tmp, None)
        else:
            try:
                with _open_h5_read(self.path) as old:
                    if old["states"].shape[0] < self.rows or old["n"].shape[0] < self.rows:
                        raise RecordingError(f"{self.path} holds fewer rows than run.json records (truncated)")
                    if old["states"].shape[1:] != spec.X0.shape:
                        raise ValueError("the states do not match the recorded ensemble")
                    self._create(h5py, tmp, old)
            except (OSError, KeyError, ValueError, TypeError) as exc:
                tmp.unlink(missing_ok=True)
                raise RecordingError(f"{self.path} is unreadable or corrupted ({exc}); cannot resume") from None
            if self.h_rows.hexdigest() != ck.get("rows_sha256"):
                tmp.unlink(missing_ok=True)
                raise RecordingError(f"{self.path} does not match the digest in run.json (corrupted); cannot resume")
        os.replace(tmp, self.path)
        self.f = h5py.File(self.path, "a", libver="latest")
        self.dn, self.dS = self.f["n"], self.f["states"]
        self.f.swmr_mode = True
        self.slot = int(ck.get("slot", 1)) ^ 1  # the next checkpoint goes to the other slot

    def _create(self, h5py, path, old):
        """A new file with the inputs and (on resume) exactly the checkpointed rows of ``old``."""
        spec = self.spec
        B, n3 = spec.X0.shape
        rows = self.rows if old is not None else 0
        with h5py.File(path, "w", libver="latest") as f:
            f.create_dataset("X0", data=spec.X0)
            f.create_dataset("b", data=spec.b)
            f.create_dataset("eta", data=spec.eta)
            per_chunk = max(1, min(B, (1 << 20) // (8 * n3)))  # HDF5 chunks of at most 1 MiB: one row, many orbits
            dn = f.create_dataset("n", shape=(rows,), maxshape=(None,), chunks=(4096,), dtype="i8")
            dS = f.create_dataset(
                "states", shape=(rows, B, n3), maxshape=(None, B, n3), chunks=(1, per_chunk, n3), dtype="f8"
            )
            step = max(1, self._COPY_BLOCK_BYTES // (8 * B * n3))
            for a in range(0, rows, step):
                e = min(rows, a + step)
                bn, bS = old["n"][a:e], old["states"][a:e]
                dn[a:e], dS[a:e] = bn, bS
                self.h_rows.update(bn, bS)
            f.attrs["inputs"] = json.dumps(self.run["inputs"], sort_keys=True)
            f.attrs["layout"] = "states[r, i, :] is orbit i at step n[r]; components y_0, y_1, ... (3N)"
            f.attrs["note"] = "rows beyond run.json checkpoint.rows are not data (see docs/reliability.md)"

    def append(self, n_idx: np.ndarray, S: np.ndarray) -> None:
        k = len(n_idx)
        if k == 0:
            return
        r = self.rows
        self.dn.resize((r + k,))
        self.dS.resize((r + k,) + self.dS.shape[1:])
        self.dn[r : r + k] = n_idx
        self.dS[r : r + k] = S
        self.h_rows.update(n_idx, S)
        self.rows = r + k

    def checkpoint(self, step: int, X, nu1, drift, **update) -> None:
        self.dn.flush()
        self.dS.flush()
        self.f.flush()
        _fsync_path(self.path)
        name = f"checkpoint-{self.slot}.npz"
        path = self.out_dir / name
        tmp = self.out_dir / (name + ".tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, step=np.int64(step), X=X, nu1=np.zeros(0, complex) if nu1 is None else nu1, drift=drift)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        ck = self.run["checkpoint"]
        ck.update(step=int(step), rows=self.rows, rows_sha256=self.h_rows.hexdigest(), slot=self.slot,
                  file=name, sha256=_file_sha256(path))
        self.run.update(update)
        self.run["last_safe_step"] = int(step)
        self.run["updated"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        _write_run(self.out_dir, self.run)
        self.slot ^= 1

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.f.close()


def _read_inputs(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    try:
        with _open_h5_read(path) as f:
            return np.array(f["X0"]), np.array(f["b"]), np.array(f["eta"])
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise RecordingError(f"cannot read the ensemble inputs from {path} ({exc})") from None


def load_ensemble(out_dir) -> EnsembleData:
    """The rows of a run directory that ``run.json`` declares safe (all in memory: for very large runs read
    ``ensemble.h5`` with h5py, dataset ``states`` of shape (rows, B, 3N), the first ``checkpoint.rows`` rows)."""
    out_dir = Path(out_dir)
    run = read_run(out_dir)
    rows = int(run.get("checkpoint", {}).get("rows", 0))
    path = out_dir / ENSEMBLE_H5
    try:
        with _open_h5_read(path) as f:
            if f["states"].shape[0] < rows or f["n"].shape[0] < rows:
                raise RecordingError(f"{path} holds fewer rows than run.json records: truncated")
            return EnsembleData(
                n=f["n"][:rows], states=f["states"][:rows], X0=f["X0"][()], b=f["b"][()], eta=f["eta"][()]
            )
    except (OSError, KeyError) as exc:
        raise RecordingError(f"cannot read {path}: {exc}") from None


def run_ensemble(
    spec: EnsembleSpec | None,
    out_dir,
    *,
    resume: bool = False,
    max_drift: float = DEFAULT_MAX_DRIFT,
    checkpoint_seconds: float = 2.0,
    max_chunk_bytes: int = 64 << 20,
    max_chunk_steps: int | None = None,
    scheduler=None,
    chunk_size: int | None = None,
    expect: dict | None = None,
    progress: Callable[[int, int], None] | None = None,
    handle_signals: bool = True,
) -> EnsembleRunResult:
    """Iterate an ensemble and stream it into ``out_dir`` (see the module doc).

    ``resume=True`` continues the run recorded in ``out_dir`` from its last safe step (``spec`` and
    ``max_drift`` are then the recorded ones; ``expect`` maps names of ``run.json["inputs"]`` (``steps``,
    ``save_every``, ``branch``, ``max_drift``) to values the user gave: a difference is refused).
    ``scheduler``: a Dask scheduler address or ``distributed.Client`` (each time chunk is split over the
    cluster by orbits; the result is the same bit for bit).  ``progress(n, steps)`` is called after each chunk.
    A time chunk holds at most ``max_chunk_bytes`` of saved states and at most ``max_chunk_steps`` steps (its
    length otherwise adapts to last 0.3-1.5 s); how the run is cut into chunks never changes the result.

    Returns an :class:`EnsembleRunResult` (status ``completed`` or ``failed: <reason>``); raises
    :class:`~jetgaudin.recording.RunInterrupted` on SIGINT/SIGTERM and :class:`RecordingError` for unusable
    directories.

    >>> import tempfile, numpy as np
    >>> from jetgaudin.ensemble import sample_on_leaf
    >>> spec = EnsembleSpec(sample_on_leaf(3, [0.5, 0.2, 1.0], 8, seed=1), 1.0, 5 + 0.1j, steps=100, save_every=10)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     res = run_ensemble(spec, d)
    ...     data = load_ensemble(d)
    >>> res.status, data.states.shape, bool(res.max_drift.max() < 1e-11)
    ('completed', (11, 8, 9), True)
    """
    out_dir = Path(out_dir)
    if not (checkpoint_seconds >= 0) or not math.isfinite(checkpoint_seconds):
        raise InvalidParameterError("checkpoint_seconds must be a finite number >= 0")
    if resume:
        run = read_run(out_dir, verify=True)
        status = str(run["status"])
        if status == "completed":
            raise RecordingError(f"the run in {out_dir} is already completed; nothing to resume")
        if status.startswith("failed"):
            raise RecordingError(f"the run in {out_dir} {status}; it cannot be resumed (it would fail again)")
        if run.get("program") != COMMAND:
            raise RecordingError(f"{out_dir} holds a run of {run.get('program')!r}, not an ensemble; cannot resume")
        try:
            rec = run["inputs"]
            X0, b, eta = _read_inputs(out_dir / ENSEMBLE_H5)
            spec = EnsembleSpec(X0, b, eta, rec["steps"], rec["save_every"], rec["branch"])
            if spec.digest() != rec["inputs_sha256"]:
                raise ValueError("the stored X0, b, eta do not match their digest in run.json")
            max_drift = float(rec["max_drift"])
            ck = run["checkpoint"]
            ck_path = out_dir / ck["file"]
            if _file_sha256(ck_path) != ck["sha256"]:
                raise ValueError(f"{ck['file']} does not match its digest")
            with np.load(ck_path) as d:
                n0 = int(d["step"])
                X = np.array(d["X"])
                nu1 = np.array(d["nu1"]) if d["nu1"].size else None
                drift = np.array(d["drift"])
            I0 = _integrals(spec.X0, spec.b)
            elapsed0 = float(run.get("elapsed_seconds", 0.0))
            if (n0 != int(ck["step"]) or X.shape != spec.X0.shape or drift.shape != I0.shape
                    or not (0 <= n0 <= spec.steps)):
                raise ValueError("inconsistent checkpoint")
        except (KeyError, TypeError, ValueError, IndexError, OSError, JetGaudinError) as exc:
            raise RecordingError(f"{out_dir} holds a corrupted ensemble run ({one_line(exc)}); cannot resume") from None
        mine = dict(spec.to_json(), max_drift=max_drift)
        diff = [k for k, v in (expect or {}).items() if mine.get(k) != v]
        if diff:
            raise RecordingError(
                f"cannot resume {out_dir} with different inputs ({', '.join(diff)}); "
                "drop those options or start a new run in another --out directory"
            )
        _prepare_dir(out_dir)
        writer = _EnsembleWriter(out_dir, spec, run, fresh=False)
    else:
        if spec is None:
            raise InvalidParameterError("spec is required for a new run")
        if not (isinstance(max_drift, (int, float)) and max_drift >= 0):
            raise InvalidParameterError(f"max_drift must be a number >= 0 (inf disables the check), got {max_drift!r}")
        _prepare_dir(out_dir)
        n0, X, nu1, elapsed0 = 0, spec.X0.copy(), None, 0.0
        I0 = _integrals(spec.X0, spec.b)
        drift = np.zeros_like(I0)
        run = {
            "program": COMMAND,
            "version": jg.__version__,
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "inputs": dict(spec.to_json(), max_drift=max_drift),
            "status": "running",
            "last_safe_step": 0,
            "integral_names": integral_names(spec.N),
            "checkpoint": {"step": 0, "rows": 0},
        }
        writer = _EnsembleWriter(out_dir, spec, run, fresh=True)

    steps, every, B, n3 = spec.steps, spec.save_every, spec.B, 3 * spec.N
    scale = np.maximum(1.0, np.abs(I0))
    names = integral_names(spec.N)
    row_bytes = 8 * B * n3
    max_rows = max(1, int(max_chunk_bytes) // row_bytes)
    L_max = max_rows * every
    if max_chunk_steps is not None:
        from .ensemble import _check_int

        L_max = min(L_max, _check_int(max_chunk_steps, "max_chunk_steps", 1))
    L = max(1, min(L_max, (1 << 18) // B))  # first chunk: ~2.6e5 orbit-steps (a few ms), then adapted
    t_start = time.monotonic()
    t_ck = t_start
    n = n0

    def health(rows_n, S):
        """Drift over the rows ``S`` (k, B, 3N) at steps ``rows_n``; a failure reason or None."""
        nonlocal drift
        with np.errstate(all="ignore"):
            d = np.abs(_integrals(S, spec.b) - I0) / scale
        if not np.all(np.isfinite(d)):
            r, i = np.argwhere(~np.all(np.isfinite(d), axis=-1))[0]
            return f"non-finite integrals of orbit {i} at step {rows_n[r]}"
        drift = np.maximum(drift, d.max(axis=0))
        bad = d > max_drift
        if np.any(bad):
            r, i, k = np.argwhere(bad)[0]
            return (
                f"integral drift: {names[k]} of orbit {i} drifted by {d[r, i, k]:.4e} (relative to max(1, |I(0)|)) "
                f"at step {rows_n[r]} > max_drift {max_drift:g}"
            )
        return None

    def summary(status_):
        md = drift.max(axis=1) if B else np.zeros(0)
        return dict(
            status=status_,
            max_drift_per_integral=drift.max(axis=0).tolist(),
            max_drift_note="max over orbits of |I_k(n) - I_k(0)| / max(1, |I_k(0)|) over the saved rows and chunk ends",
            worst_orbit=int(np.argmax(md)) if B else None,
            elapsed_seconds=elapsed0 + time.monotonic() - t_start,
        )

    client, own_client = scheduler, False
    failure, interrupted = None, 0
    try:
        if scheduler is not None:
            from .ensemble import dask_client

            client = dask_client(scheduler)
            own_client = client is not scheduler
        with _SignalFlag(handle_signals) as sig:
            if not resume:
                failure = health([0], X[None])
                writer.append(np.array([0]), X[None])
                writer.checkpoint(0, X, nu1, drift, **summary("running"))
            while failure is None and n < steps and not sig.signum:
                head = (-n) % every
                if head == 0 and L >= every and steps - n >= every:
                    k = min(L // every, (steps - n) // every) * every  # whole save intervals: rows n+every..n+k
                    ke = every
                else:  # a piece of one interval (long intervals, or a run resumed off the save grid)
                    k = min(L, head or every, steps - n)
                    ke = k
                t0 = time.monotonic()
                try:
                    res = iterate_ensemble(X, spec.b, spec.eta, k, save_every=ke, branch=spec.branch, nu1=nu1,
                                           scheduler=client, chunk_size=chunk_size)
                except (jg.SingularStepError, jg.BranchPointError) as exc:
                    failure = f"{type(exc).__name__} after step {n}: {one_line(exc)}"
                    break
                dt = time.monotonic() - t0
                n_new = n + k
                if ke == every and k >= every:
                    rows_n, S = list(range(n + every, n_new + 1, every)), res.states[1:]
                elif n_new % every == 0 or n_new == steps:
                    rows_n, S = [n_new], res.states[-1:]
                else:
                    rows_n, S = [], res.states[:0]
                failure = (health(rows_n, S) if rows_n else None) or health([n_new], res.final[None])
                writer.append(np.asarray(rows_n, dtype=np.int64), S)
                X, nu1, n = res.final, res.nu, n_new
                # ~0.3-1.5 s per chunk (a kernel call has a fixed cost of ~10 steps: set-up of the lanes, the
                # integrals at the start), at most max_rows saved rows
                if dt < 0.3:
                    L = min(L_max, L * 2)
                elif dt > 1.5:
                    L = max(1, L // 2)
                now = time.monotonic()
                if failure is None and now - t_ck >= checkpoint_seconds:
                    writer.checkpoint(n, X, nu1, drift, **summary("running"))
                    t_ck = now
                if progress is not None:
                    progress(n, steps)
            if sig.signum and failure is None and n < steps:
                interrupted, status = sig.signum, "interrupted"
            elif failure is not None:
                status = f"failed: {failure}"
            else:
                status = "completed"
            writer.checkpoint(n, X, nu1, drift, **summary(status))
    except BaseException as exc:
        _mark_crashed(out_dir, run, exc)
        raise
    finally:
        writer.close()
        if own_client:
            with contextlib.suppress(Exception):
                client.close()
    if interrupted:
        raise RunInterrupted(interrupted, n, out_dir, command=COMMAND)
    return EnsembleRunResult(
        out_dir=out_dir,
        status=status,
        last_safe_step=int(n),
        rows=writer.rows,
        drift=drift.copy(),
        elapsed=elapsed0 + time.monotonic() - t_start,
        files=(out_dir / ENSEMBLE_H5, out_dir / RUN_JSON),
    )
