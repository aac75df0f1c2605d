"""Start, resume and describe runs: the public entry points of the run layer (:func:`start`, :func:`resume`) and
the layouts' records in ``run.json`` (private helpers)."""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import _fs
from .._errors import InvalidParameterError, JetGaudinError, RecordingError, RunDirectoryError
from ..maps import Backend, Map, map_from_description, with_resolved_backend
from .driver import CompileInterrupted, Driver, Position, RaiseOnSignal, RunInterrupted
from .files import (
    ENSEMBLE_H5,
    ORBIT_CSV,
    ORBIT_H5,
    RUN_JSON,
    RowDigest,
    hex_floats,
    one_line,
    open_h5_read,
    read_run,
    unhex,
)
from .health import Health
from .replay import replay
from .spec import HealthLimits, Layout, RunSpec, RunStatus, block_size, model_of
from .store import EnsembleStore, OrbitStore, Store, now, read_checkpoint_npz

__all__ = ["RunResult", "start", "resume"]


@dataclass(frozen=True)
class RunResult:
    """Everything a finished (or failed) run reports; also in ``run.json``.

    ``status``: the text recorded (``completed``, ``failed: <reason>``), ``state``: the :class:`RunStatus`;
    ``drift_abs`` ``(..., k)``: ``max |I_k(n) − I_k(0)|`` over the checked states (saved rows and chunk ends);
    ``drift`` ``(..., k)`` the same relative to ``max(1, |I_k(0)|)``; ``max_drift_rel``: relative to ``|I_k(0)|``,
    ``nan`` where ``I_k(0)`` is zero to round-off (:func:`relative_drift`).  ``spec``: the run's :class:`RunSpec`;
    ``record``: the final ``run.json``.
    ``elapsed``: wall seconds of stepping over all sessions of the run (compile/load time excluded).  This
    session (the call that returned it): ``compile_seconds`` compiling or loading the kernels before the loop
    (0 when they were loaded), ``session_steps`` steps done in ``session_seconds`` of stepping, and
    :attr:`step_rate` (orbit-steps per second, compile/load excluded).
    """

    out_dir: Path
    status: str
    state: RunStatus
    last_safe_step: int
    rows: int
    integrals0: np.ndarray
    drift_abs: np.ndarray
    drift: np.ndarray
    max_imag_residue: float
    sphere_radius0: Any
    sphere_max_deviation: float
    elapsed: float
    files: tuple
    kernel: str
    spec: RunSpec
    record: dict
    compile_seconds: float = 0.0
    session_steps: int = 0
    session_seconds: float = 0.0

    @property
    def step_rate(self) -> float:
        """Orbit-steps per second of this session's stepping (orbits × steps / ``session_seconds``; compile and
        load time excluded); ``nan`` when no step was done."""
        if self.session_steps <= 0 or self.session_seconds <= 0:
            return float("nan")
        return self.session_steps * self.spec.B / self.session_seconds

    @property
    def max_drift_abs(self) -> np.ndarray:
        return self.drift_abs

    @property
    def max_drift_rel(self) -> np.ndarray:
        """``drift_abs / |I_k(0)|``, ``nan`` where ``I_k(0)`` is zero to round-off (:func:`relative_drift`)."""
        return relative_drift(self.drift_abs, self.integrals0, integral_scales(self.spec.map, self.spec.X0))

    @property
    def max_drift(self) -> np.ndarray:
        """Largest relative integral drift of each orbit, shape ``(B,)`` (ensembles) or ``()`` (orbits)."""
        return np.max(self.drift, axis=-1)

    @property
    def failed(self) -> bool:
        return self.state in (RunStatus.FAILED, RunStatus.FAILED_IO)


# ------------------------------------------------------------------------------------- relative drift
#: ``I_k(0)`` within this many ulps of its scale ``s_k`` (:func:`integral_scales`) is zero to round-off: its
#: relative drift is undefined (the Clebsch top's Casimir ``2 M·p`` computed as ``-1.1e-16`` at a state with
#: ``M ⟂ p`` made ``|ΔI| / |I(0)|`` read 1115 for a drift of 1e-13)
ROUNDOFF_ULPS = 64
#: the fixed directions of :func:`integral_scales` (unit vectors, one draw per state length, seed 0)
_SCALE_DIRECTIONS = 8


def integral_scales(m: Map, X0: np.ndarray) -> np.ndarray:
    """``s_k``, the natural scale of each integral at ``X0`` ``(..., n)``: the largest ``|I_k(X0 ± ‖X0‖ d) −
    I_k(X0)|`` over 8 fixed unit directions ``d`` (pseudo-random, seed 0), shape ``(..., k)``.

    Why this scale: round-off moves a state by ``~ε ‖X‖`` in every component (the steps mix them), which moves an
    integral of degree ``q`` by ``~ε ‖∇I‖ ‖X‖ ~ ε c ‖X‖^q`` (``c`` the size of its coefficients: ``b``, the site
    differences, the weights), whatever ``I(X0)`` is; ``s_k`` is ``c ‖X0‖^q`` up to a factor of order one for the
    quadratic integrals of the tops and chains and the cubic ones of su(3) (and mixed degrees, e.g. ``2b y + …``,
    without knowing ``q`` or ``c``).  The sum of the absolute values of ``I``'s terms at ``X0`` is the round-off of
    one evaluation only: it vanishes at states such as ``M = e_1``, ``p = e_2`` (``2 M·p``), where the orbit's
    integral still drifts by ``~ε ‖X‖²``, and is not available from a map's ``integrals``."""
    X0 = np.asarray(X0, dtype=float)
    n = X0.shape[-1]
    D = np.random.default_rng(0).normal(size=(_SCALE_DIRECTIONS, n))
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    h = np.linalg.norm(X0, axis=-1, keepdims=True)
    with np.errstate(all="ignore"):
        I0 = np.asarray(m.integrals(X0), dtype=float)
        s = np.zeros_like(I0)
        for d in np.concatenate([D, -D]):
            try:
                s = np.fmax(s, np.abs(np.asarray(m.integrals(X0 + h * d), dtype=float) - I0))
            except JetGaudinError:  # a map refusing such a state: that direction is left out
                continue
    return s


def relative_drift(drift_abs: np.ndarray, I0: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """``drift_abs / |I0|``, and ``nan`` where ``|I0| ≤`` :data:`ROUNDOFF_ULPS` ``· ε · scale`` (``I0`` zero to
    round-off, e.g. exactly zero: no relative drift means anything there; ``null`` in ``run.json``, ``n/a`` in the
    command's table; the absolute drift is the number to read)."""
    I0 = np.abs(np.asarray(I0, dtype=float))
    zero = I0 <= ROUNDOFF_ULPS * np.finfo(float).eps * np.asarray(scale, dtype=float)
    with np.errstate(all="ignore"):
        return np.where(zero, np.nan, np.asarray(drift_abs, dtype=float) / np.where(zero, 1.0, I0))


# ------------------------------------------------------------------------------------------ records
def _orbit_inputs(spec: RunSpec) -> dict:
    d = spec.map.describe()
    inputs: dict[str, Any] = {}
    if d.get("kind") == "two_point":  # the format-1 keys of an orbit of the two-point map
        inputs.update(b=d["b"], eta=d["eta"])
    inputs.update(steps=spec.steps, init=spec.X0.tolist())
    if d.get("kind") == "two_point":
        inputs["branch"] = d["branch"]
    inputs.update(N=spec.n_state // block_size(spec.map),
                  save_every=spec.save_every, csv=bool(spec.csv), kernel=spec.map.backend.value,
                  max_drift=spec.limits.max_drift, max_imag=spec.limits.max_imag)
    if _time_step(spec.map) is not None and spec.stem != "flow":
        inputs["stem"] = spec.stem  # a timed map recorded as an orbit (orbit.h5 with n and t)
    return inputs


def _batch_params(m: Map, B: int) -> tuple[np.ndarray, np.ndarray, str]:
    try:
        params: Any = m
        b = np.broadcast_to(np.asarray(params.b, dtype=np.float64), (B,)).copy()
        eta = np.broadcast_to(np.asarray(params.eta, dtype=np.complex128), (B,)).copy()
        return b, eta, str(getattr(params.branch, "value", params.branch))
    except AttributeError:
        raise InvalidParameterError("an ensemble run needs a Bäcklund map (fields b, eta, branch)") from None


def inputs_digest(X0: np.ndarray, b: np.ndarray, eta: np.ndarray) -> str:
    """SHA-256 of ``X0``, ``b``, ``eta`` (little-endian), recorded in an ensemble's ``run.json``."""
    h = hashlib.sha256()
    for a, dt in ((X0, "<f8"), (b, "<f8"), (eta, "<c16")):
        h.update(np.ascontiguousarray(a, dtype=dt).tobytes())
    return h.hexdigest()


def _ensemble_inputs(spec: RunSpec) -> dict:
    b, eta, branch = _batch_params(spec.map, spec.B)
    return {"B": spec.B, "N": spec.n_state // block_size(spec.map), "steps": spec.steps, "save_every": spec.save_every,
            "branch": branch,
            "inputs_sha256": inputs_digest(spec.X0, b, eta), "max_drift": spec.limits.max_drift,
            "backend": _route(spec.map).value}


def _route(m: Any) -> Backend:
    """The map's backend (a wrapper's inner map's: :class:`jetgaudin.ensemble.DaskBatch`)."""
    inner = getattr(m, "inner", None)
    return (inner if isinstance(inner, Map) else m).backend


def _summary(spec: RunSpec) -> Callable[[Health, float], dict]:
    if spec.layout is Layout.ORBIT:
        N = spec.n_state // block_size(spec.map)
        scale = integral_scales(spec.map, spec.X0)

        def orbit(h: Health, elapsed: float) -> dict:
            return dict(
                max_drift_abs=h.drift.tolist(),
                max_drift_rel=relative_drift(h.drift, h.I0, scale).tolist(),  # nan: null in run.json
                max_drift_rel_note=f"|I_k(n) - I_k(0)| / |I_k(0)| over the saved rows and chunk ends; null where "
                                   f"|I_k(0)| <= {ROUNDOFF_ULPS} eps s_k (zero to round-off; s_k the integral's "
                                   "scale at X0, jetgaudin.run.api.integral_scales)",
                max_imag_residue=h.imag,
                sphere={"block": f"y_{N - 1}", "radius0": float(h.r0), "max_deviation": h.sphere},
                elapsed_seconds=elapsed,
            )

        return orbit

    def ensemble(h: Health, elapsed: float) -> dict:
        rel = h.relative
        md = rel.max(axis=1) if len(rel) else np.zeros(0)
        return dict(
            max_drift_per_integral=(rel.max(axis=0) if len(rel) else np.zeros(rel.shape[-1])).tolist(),
            max_drift_note="max over orbits of |I_k(n) - I_k(0)| / max(1, |I_k(0)|) over the saved rows and chunk "
                           "ends",
            worst_orbit=int(np.argmax(md)) if len(md) else None,
            max_imag_residue=h.imag,
            elapsed_seconds=elapsed,
        )

    return ensemble


def _new_record(spec: RunSpec, health: Health) -> dict:
    run: dict[str, Any] = {"program": spec.program, "version": _version(), "created": now()}
    if spec.layout is Layout.ORBIT:
        run.update(inputs=_orbit_inputs(spec), map=spec.map.describe(), status="running", last_safe_step=0,
                   integral_names=health.names, integrals0=health.I0.tolist(), integrals0_hex=hex_floats(health.I0),
                   checkpoint={"step": 0, "X_hex": hex_floats(spec.X0), "nu1_hex": None, "rows": 0, "csv_bytes": 0,
                               "rows_sha256": RowDigest().hexdigest(), "csv_sha256": hashlib.sha256().hexdigest()})
    else:
        run.update(inputs=_ensemble_inputs(spec), status="running", last_safe_step=0,
                   integral_names=health.names,
                   checkpoint={"step": 0, "rows": 0, "rows_sha256": RowDigest().hexdigest()})
        if not _two_point_batch(spec.map):
            d = spec.map.describe()
            if d.get("kind") != "two_point_batch":  # another map (a chain): rebuilt from its description on resume
                run["map"] = d
    run.update(_summary(spec)(health, 0.0))  # complete from the start: a failure at the first checkpoint resumes
    return run


def _two_point_batch(m: Map) -> bool:
    """Whether ``m`` (or the inner map of a wrapper, :class:`jetgaudin.ensemble.DaskBatch`) is a
    :class:`jetgaudin.ensemble.BatchBacklund` with its own ``describe`` (kind ``two_point_batch``, not recorded as a
    map): known without building its description (lists of every orbit's ``b`` and ``η``: ~1 s per 10⁶ orbits)."""
    from ..ensemble import BatchBacklund

    inner = getattr(m, "inner", None)
    m = inner if isinstance(inner, Map) else m
    return isinstance(m, BatchBacklund) and type(m).describe is BatchBacklund.describe


def _version() -> str:
    import jetgaudin

    return jetgaudin.__version__


def _open_store(spec: RunSpec, out_dir: Path, run: dict, fresh: bool, check_only: bool = False) -> Store:
    if spec.layout is Layout.ORBIT:
        labels = getattr(spec.map, "state_labels", None)  # a map may name the state's components (the chains)
        if labels is None and model_of(spec.map) is not None:  # a map of a chain's Hamiltonian (midpoint)
            labels = model_of(spec.map).labels
        return OrbitStore(out_dir, run, spec.n_state, fresh=fresh, csv=spec.csv, stem=_stem(spec),
                          time_step=_time_step(spec.map),
                          columns=list(labels()) if callable(labels) else None, check_only=check_only)
    b, eta, _ = _batch_params(spec.map, spec.B)
    extra = {"X0": spec.X0, "b": b, "eta": eta} if fresh else None
    store = EnsembleStore(out_dir, run, spec.X0.shape, fresh=fresh, extra=extra, check_only=check_only)
    return store


def _time_step(m: Map) -> float | None:
    """The time step of a flow map (its rows are indexed by time ``t = n dt`` in ``flow.csv``), else ``None``."""
    dt = getattr(m, "dt", None)
    return None if dt is None else float(dt)


def _stem(spec: RunSpec) -> str:
    """``orbit`` (``orbit.h5`` / ``orbit.csv``) or ``flow`` (a map with a time step, unless ``spec.stem``)."""
    return "orbit" if _time_step(spec.map) is None else spec.stem


def _files(spec: RunSpec, out_dir: Path) -> tuple[Path, ...]:
    if spec.layout is Layout.ORBIT:
        stem = _stem(spec)
        h5, csv = (ORBIT_H5, ORBIT_CSV) if stem == "orbit" else ("flow.h5", "flow.csv")
        return (out_dir / h5,) + ((out_dir / csv,) if spec.csv else ()) + (out_dir / RUN_JSON,)
    return (out_dir / ENSEMBLE_H5, out_dir / RUN_JSON)


def _resolved(spec: RunSpec) -> RunSpec:
    """The spec with the map's ``AUTO`` backend resolved (recorded, so that a resume uses the same route)."""
    resolve = getattr(spec.map, "resolved_backend", None)
    if spec.map.backend is Backend.AUTO and resolve is not None:
        backend = resolve(X=spec.X0, steps=spec.steps)
        inner = getattr(spec.map, "inner", None)  # a wrapper (jetgaudin.ensemble.DaskBatch): its inner map's route
        wrapper: Any = spec.map
        m = dataclasses.replace(wrapper, inner=with_resolved_backend(inner, backend)) if isinstance(inner, Map) \
            else with_resolved_backend(spec.map, backend)
        return dataclasses.replace(spec, map=m)
    return spec


# --------------------------------------------------------------------------------------- entry points
def start(spec: RunSpec, out_dir: str | Path, *, overwrite: bool = False, record: dict | None = None,
          notify: Callable[[str], None] | None = None, **options: Any) -> RunResult:
    """Run ``spec`` into the new run directory ``out_dir``.

    The directory is checked before anything is written (:func:`jetgaudin._fs.check_new_run_dir`: a directory
    holding a run or other files is refused unless ``overwrite``; a directory in use by another writer always) and
    locked for the run's life.  ``options``: ``progress(n, steps)``, ``handle_signals``, ``max_chunk_steps``,
    ``max_chunk_bytes``, ``chunk_rows`` (how a run is cut never changes its bits).  ``record``: extra top-level
    fields of ``run.json`` (e.g. the command line's ``plots`` choice, honoured by a resume).  ``notify(message)``:
    where the compile messages go (the map's kernels are compiled or loaded before the loop, with a message
    giving the expected time and one when done; default: stderr; nothing is said when they are loaded).

    Returns a :class:`RunResult`; raises :class:`RunInterrupted` on SIGINT/SIGTERM (checkpoint written; also when
    the signal came as the run completed: its ``result`` is then complete),
    :class:`jetgaudin.RunDirectoryError` / :class:`jetgaudin.RunLockedError` for a refused directory.
    """
    out_dir = Path(out_dir)
    _fs.check_new_run_dir(out_dir, overwrite=overwrite)
    spec = _resolved(spec)
    compile_s = _prepare(spec, spec.X0, out_dir, notify, options.get("handle_signals", True),
                         f"while compiling the kernels; nothing was written to {out_dir}")
    if compile_s:  # the directory may have changed during the compile: checked again, as just before it
        _fs.check_new_run_dir(out_dir, overwrite=overwrite)
    _fs.make_run_dir(out_dir)
    with _fs.RunDirLock(out_dir):
        if overwrite:
            _clear(out_dir)
        health = Health(spec.map, spec.X0, spec.limits, I0_of_X0=spec.integrals0())
        run = dict(_new_record(spec, health), **(record or {}))
        store = _open_store(spec, out_dir, run, fresh=True)
        pos = Position(0, spec.X0.copy(), None)
        return _drive(spec, out_dir, store, pos, health, 0.0, first=True, fresh=True, compile_s=compile_s,
                      **options)


def _prepare(spec: RunSpec, X: np.ndarray, out_dir: Path, notify: Callable[[str], None] | None,
             handle_signals: bool, interrupted: str) -> float:
    """Compile or load the kernels the run's map will call (its ``prepare_kernels``, when it has one), visibly:
    a message with the expected time first and one when done (``notify``; default: stderr), before the run's
    loop, so that the stepping rate excludes it.  SIGINT/SIGTERM during the compile stop the command with
    :class:`RunInterrupted` (message ``interrupted``; nothing of the run is written by then).  Returns the
    seconds spent (0 when the kernels were loaded or the map has no compiled route)."""
    prepare = getattr(spec.map, "prepare_kernels", None)
    if prepare is None:
        return 0.0
    try:
        with RaiseOnSignal(handle_signals) as guard:
            report = guard.call(lambda: prepare(X, spec.steps, notify))
    except CompileInterrupted as exc:
        raise RunInterrupted(exc.signum, 0, out_dir, command=spec.program, message=interrupted,
                             compile_running=handle_signals) from None
    return 0.0 if report is None else float(report.seconds)


def _clear(out_dir: Path) -> None:
    """Remove the files of an old run (``--overwrite``; the lock is held): every entry is checked first
    (:func:`jetgaudin._fs.clearable`: a directory inside refuses the whole clear, nothing removed), then the files
    and links are removed (links never followed)."""
    import os

    for name in _fs.clearable(out_dir, sorted(os.listdir(out_dir))):
        _fs.remove_file(out_dir, name)


def _drive(spec: RunSpec, out_dir: Path, store: Store, pos: Position, health: Health, elapsed0: float, *,
           first: bool, fresh: bool = False, compile_s: float = 0.0, progress: Callable[[int, int], None] | None = None,
           handle_signals: bool = True, max_chunk_steps: int | None = None, max_chunk_bytes: int = 64 << 20,
           chunk_rows: int = 4096) -> RunResult:
    if isinstance(store, EnsembleStore):
        store.drift_rel = health.relative
        original = store.checkpoint

        def checkpoint(step: int, X: np.ndarray, carry: Any, summary: dict) -> None:
            store.drift_rel = health.relative
            original(step, X, carry, summary)

        store.checkpoint = checkpoint  # type: ignore[method-assign]
    layout_summary = _summary(spec)
    compile_total = float(store.run.get("compile_seconds", 0.0)) + compile_s  # over the sessions of the run

    def summary(h: Health, elapsed: float) -> dict:
        return dict(layout_summary(h, elapsed), compile_seconds=compile_total)

    n0 = pos.n
    driver = Driver(spec, store, pos, health, summary=summary, elapsed0=elapsed0, progress=progress,
                    handle_signals=handle_signals, max_chunk_steps=max_chunk_steps, max_chunk_bytes=max_chunk_bytes,
                    chunk_rows=chunk_rows, first=first, fresh=fresh)
    try:
        out = driver.run()
    except BaseException as exc:  # a bug or an unexpected error: the checkpointed data stay valid and resumable
        store.mark("interrupted", error=one_line(f"{type(exc).__name__}: {exc}"))
        raise
    finally:
        store.close()
    result = RunResult(
        out_dir=out_dir, status=str(store.run["status"]), state=out.status, last_safe_step=out.last_safe_step,
        rows=int(store.run["checkpoint"]["rows"]), integrals0=health.I0, drift_abs=health.drift.copy(),
        drift=health.relative, max_imag_residue=health.imag, sphere_radius0=health.r0,
        sphere_max_deviation=health.sphere, elapsed=out.elapsed, files=_files(spec, out_dir),
        kernel=spec.map.backend.value, spec=spec, record=store.run, compile_seconds=compile_s,
        session_steps=out.last_safe_step - n0, session_seconds=out.elapsed - elapsed0)
    if out.status is RunStatus.INTERRUPTED:
        raise RunInterrupted(out.signum, out.last_safe_step, out_dir, command=spec.program, result=result)
    if out.signum and out.status is RunStatus.COMPLETED:  # the signal came as the last step was saved
        raise RunInterrupted(out.signum, out.last_safe_step, out_dir, command=spec.program, result=result,
                             message=f"as the run completed (all {out.last_safe_step} steps saved in {out_dir}); "
                                     f"nothing else was done (draw the figures with: jetgaudin plot {out_dir})")
    return result


def resume(out_dir: str | Path, *, expect: dict | None = None, checkpoint_seconds: float | None = None,
           map_options: dict | None = None, program: str | None = None,
           notify: Callable[[str], None] | None = None, **options: Any) -> RunResult:
    """Continue the run recorded in ``out_dir`` from its last durable checkpoint (bit for bit the uninterrupted run).

    ``expect`` maps names of ``run.json["inputs"]`` to the values the user gave: a difference is refused with
    :class:`jetgaudin.RecordingError`.  The checkpoint is cross-checked against the last saved row (step, state bits
    when the checkpoint is on a row, the integrals, and ``ν1`` against the branch rule at the checkpoint state).
    ``map_options``: extra fields of an ensemble's map (``scheduler``, ``chunk_size``).  Other ``options`` as in
    :func:`start` (``notify``: the compile messages).  ``program``: refuse a run of another command (e.g. an orbit
    given to ``ensemble --resume``).
    """
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise RecordingError(f"{out_dir} does not exist: not a jetgaudin run directory")
    with _fs.RunDirLock(out_dir, claim=False, create=False) as lock:
        run = read_run(out_dir, verify=True)
        if program is not None and run.get("program") != program:
            kind = "an ensemble" if program == "jetgaudin ensemble" else f"a {program!r} run"
            raise RecordingError(f"{out_dir} holds a run of {run.get('program')!r}, not {kind}; cannot resume it "
                                 "with this command")
        state = RunStatus.of(run)
        if state is RunStatus.COMPLETED:
            raise RecordingError(f"the run in {out_dir} is already completed; nothing to resume")
        if not state.resumable:
            raise RecordingError(f"the run in {out_dir} {run['status']}; it cannot be resumed (it would fail again)")
        try:
            spec, pos, health, elapsed0, anchor = _restore(out_dir, run, map_options or {})
        except (KeyError, TypeError, ValueError, IndexError, OSError, AttributeError, JetGaudinError) as exc:
            if isinstance(exc, RunDirectoryError):
                raise
            raise RecordingError(f"{out_dir} holds a corrupted run ({one_line(exc)}); cannot resume") from None
        if checkpoint_seconds is not None:
            spec = dataclasses.replace(spec, checkpoint_seconds=checkpoint_seconds)
        diff = [k for k, v in (expect or {}).items() if run["inputs"].get(k, object()) != v]
        if diff:
            raise RecordingError(f"cannot resume {out_dir} with different inputs ({', '.join(diff)}); drop those "
                                 "options or start a new run in another --out directory")
        # every check reads only: the stored rows, the CSV and the replay run on a read-only view of the files,
        # so that a refusal changes nothing (not a byte, not an mtime, not the lock's PID)
        view = _open_store(spec, out_dir, run, fresh=False, check_only=True)
        try:
            compile_s = _prepare(spec, pos.X, out_dir, notify, options.get("handle_signals", True),
                                 f"while compiling the kernels; the run in {out_dir} is unchanged; resume with: "
                                 f"{spec.program} --resume {out_dir}")
            spec = replay(view, spec, pos, anchor, str(out_dir / RUN_JSON), recorded_rate=_recorded_rate(run))
        finally:
            view.close()
        lock.claim()  # from here on the directory is written: the lock names this process
        if read_run(out_dir, verify=True) != run:  # only possible without a lock file (taken just now)
            raise RecordingError(f"{out_dir / RUN_JSON} changed while the resume checked it; try again")
        if spec._per_chunk_setup:  # written before runs were set up once (found by the replay): resumed that way
            run["map_setup"] = _PER_CHUNK
        store = _open_store(spec, out_dir, run, fresh=False)
        store.anchor = anchor
        return _drive(spec, out_dir, store, pos, health, elapsed0, first=store.rows == 0, compile_s=compile_s,
                      **options)


def _recorded_rate(run: dict) -> float | None:
    """The recorded run's steps per second (over all its sessions), or ``None`` when unknown: bounds the replay's
    time (a kernel edited from compiled to NumPy is refused in seconds, not minutes)."""
    try:
        steps, seconds = int(run["last_safe_step"]), float(run.get("elapsed_seconds", 0.0))
    except (KeyError, TypeError, ValueError):
        return None
    return steps / seconds if steps > 0 and seconds > 0 else None


#: ``run.json`` ``map_setup`` of a run whose map's set-up (the su(3) exact step's parameters) is solved at every
#: kernel call, as before it was solved once per run (:func:`jetgaudin.run.spec.run_map`); absent: once per run, or
#: a directory of that older code (the replay tells which: :func:`jetgaudin.run.replay.replay`)
_PER_CHUNK = "per_chunk"


def _restore(out_dir: Path, run: dict, map_options: dict) -> tuple[RunSpec, Position, Health, float, Any]:
    rec, ck = run["inputs"], run["checkpoint"]
    setup = run.get("map_setup")
    if setup not in (None, _PER_CHUNK):
        raise ValueError(f"map_setup {setup!r}")
    per_chunk = setup == _PER_CHUNK
    limits = HealthLimits(_limit(rec["max_drift"]), _limit(rec.get("max_imag")))  # null: no limit (strict JSON)
    program = str(run.get("program", "jetgaudin orbit"))
    elapsed0 = float(run.get("elapsed_seconds", 0.0))
    if "B" not in rec:  # an orbit directory
        m = map_from_description(run["map"]) if "map" in run else _legacy_two_point(rec)
        spec = RunSpec(m, np.array(rec["init"], dtype=float), rec["steps"], rec["save_every"], limits,
                       csv=bool(rec["csv"]), program=program, stem=str(rec.get("stem", "flow")),
                       _per_chunk_setup=per_chunk)
        I0 = unhex(run["integrals0_hex"])
        health = Health(spec.map, spec.X0, limits, I0=I0)
        health.drift = np.array(run["max_drift_abs"], dtype=float)
        health.imag = _limit(run["max_imag_residue"], np.nan)
        health.sphere = float(run["sphere"]["max_deviation"])
        X = unhex(ck["X_hex"])
        carry: Any = _unhex_carry(ck["nu1_hex"])
        n0 = int(ck["step"])
        a = ck.get("anchor")
        anchor = None if a is None else (int(a["step"]), unhex(a["X_hex"]), _unhex_carry(a["nu1_hex"]))
        if X.shape != spec.X0.shape or health.drift.shape != I0.shape or I0.shape != health.scale.shape:
            raise ValueError("inconsistent checkpoint")
    else:
        if program != "jetgaudin ensemble":
            raise RecordingError(f"{out_dir} holds a run of {program!r}, not an ensemble; cannot resume")
        from ..ensemble import BatchBacklund

        with open_h5_read(out_dir / ENSEMBLE_H5) as f:
            X0, b, eta = np.array(f["X0"]), np.array(f["b"]), np.array(f["eta"])
        if inputs_digest(X0, b, eta) != rec["inputs_sha256"]:
            raise ValueError("the stored X0, b, eta do not match their digest in run.json")
        m = map_from_description(run["map"]) if "map" in run else BatchBacklund(
            b, eta, rec["branch"], backend=rec.get("backend", "auto"), **map_options)  # the recorded route
        if "map" in run and map_options.get("scheduler") is not None:  # a chain ensemble resumed on a cluster
            from ..ensemble import DaskBatch

            m = DaskBatch(m, **map_options)
        spec = RunSpec(m, X0, rec["steps"], rec["save_every"], limits, program=program, _per_chunk_setup=per_chunk)
        if "file" not in ck and int(ck["rows"]) == 0 and int(ck["step"]) == 0:  # stopped before its first slot
            d: dict[str, np.ndarray] = {"step": np.array(0), "X": X0.copy(), "nu1": np.zeros(0, complex),
                 "drift": np.zeros((X0.shape[0], np.shape(spec.map.integrals(X0[:1]))[-1]))}
        else:
            d = read_checkpoint_npz(out_dir, ck, X0.shape)
        n0, X = int(d["step"]), d["X"]
        carry = d["nu1"] if d["nu1"].size else None
        health = Health(spec.map, spec.X0, limits)
        if d["drift"].shape != health.I0.shape or X.shape != X0.shape or n0 != int(ck["step"]):
            raise ValueError("inconsistent checkpoint")
        health.drift = d["drift"] * health.scale
        anchor = None
        if "anchor_step" in d and int(d["anchor_step"]) >= 0:
            anchor = (int(d["anchor_step"]), d["anchor_X"], d["anchor_nu1"] if d["anchor_nu1"].size else None)
    if not (0 <= n0 <= spec.steps) or not np.all(np.isfinite(X)):
        raise ValueError("inconsistent checkpoint")
    return spec, Position(n0, X, carry), health, elapsed0, anchor


def _limit(value: Any, missing: float = np.inf) -> float:
    """A number of ``run.json`` that JSON may hold as ``null`` (a non-finite value: :func:`files.run_json_text`)."""
    return missing if value is None else float(value)


def _unhex_carry(h: Any) -> Any:
    return None if h is None else np.complex128(complex(*unhex(h)))


def _legacy_two_point(rec: dict) -> Map:
    from ..backlund.maps import TwoPointBacklund

    return TwoPointBacklund(rec["b"], complex(*rec["eta"]), rec["branch"], Backend.parse(rec["kernel"]))
