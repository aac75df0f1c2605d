"""The one driver loop of every run (orbit, ensemble, flow): chunking, signals, health, checkpoints, progress.

The loop advances ``spec.map`` through :meth:`jetgaudin.maps.Map.advance` only.  Kernel calls are bounded in
time, not in saved rows: a call lasts about :data:`CALL_SECONDS` (its length adapts to the measured step rate,
independently of ``save_every``), so SIGINT/SIGTERM are honoured within a fraction of a second.  Maps whose
``advance`` gives the same bits however a run is split (``chunk_invariant``, the Bäcklund maps) are cut anywhere;
other maps (flows) in fixed chunks on the save grid, so that a resumed run meets the same cuts.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _fs
from .._errors import JetGaudinError, RunIOError
from ..maps import Backend
from .files import one_line
from .health import Health
from .spec import RunSpec, RunStatus, run_map
from .store import Store

#: target duration of one kernel call (signals are handled between calls)
CALL_SECONDS = 0.1
#: at most this long between two health checks / appends of the accumulated rows, or longer where the check and the
#: append themselves take longer than :data:`FLUSH_SHARE` of it (large ensembles), at most :data:`FLUSH_MAX_SECONDS`
FLUSH_SECONDS = 0.1
#: the share of the time a health check and append may take (the interval grows to keep it)
FLUSH_SHARE = 0.1
#: the longest interval between two health checks (signals are still handled after every kernel call)
FLUSH_MAX_SECONDS = 2.0


class RunInterrupted(Exception):  # noqa: N818 - a normal outcome (not bad input), hence not a JetGaudinError
    """The run stopped on SIGINT / SIGTERM after writing a checkpoint (``signum``, ``last_safe_step``)."""

    def __init__(self, signum: int, last_safe_step: int, out_dir: Path, command: str = "jetgaudin orbit",
                 result: Any = None, message: str | None = None, compile_running: bool = False):
        self.signum = int(signum)
        #: the signal came during a compile that is still running in its worker thread (see
        #: :meth:`RaiseOnSignal.call`): a command line tool should exit at once (``os._exit`` once its message is
        #: out) instead of letting the interpreter shut down around the compiler, which takes up to a second
        self.compile_running = compile_running
        self.last_safe_step = int(last_safe_step)
        self.out_dir = Path(out_dir)
        self.result = result
        name = signal.Signals(self.signum).name
        super().__init__(
            f"interrupted by {name} {message}" if message is not None else
            f"interrupted by {name} at step {last_safe_step} (saved); resume with: {command} --resume {out_dir}"
        )

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


class CompileInterrupted(Exception):  # noqa: N818 - a normal outcome, turned into RunInterrupted by the run layer
    """SIGINT / SIGTERM arrived while the kernels were being compiled (before anything of the run was written)."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = int(signum)


class SignalFlag:
    """Install SIGINT/SIGTERM handlers that only set a flag (main thread only; a no-op elsewhere)."""

    def __init__(self, enabled: bool):
        self.signum = 0
        self._old: dict[int, Any] = {}
        self.enabled = enabled and threading.current_thread() is threading.main_thread()

    def _handler(self, signum: int, _frame: Any) -> None:
        self.signum = signum

    def __enter__(self) -> SignalFlag:
        if self.enabled:
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc: Any) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)
        if self._xfsz is not None:
            signal.signal(signal.SIGXFSZ, self._xfsz)
            self._xfsz = None

    #: SIGXFSZ's handler before the run: while a run writes, SIGXFSZ is ignored (whatever ``enabled`` says), so that
    #: a write past ``RLIMIT_FSIZE`` fails with EFBIG (``failed: file size limit ...``) instead of killing the process
    #: (its default action; the interpreter ignores it, a host process may not: the CSV is not covered by the HDF5
    #: reservation)
    _xfsz: Any = None

    def ignore_sigxfsz(self) -> None:
        if threading.current_thread() is threading.main_thread() and hasattr(signal, "SIGXFSZ"):
            self._xfsz = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


class RaiseOnSignal(SignalFlag):
    """While compiling kernels (before a run's loop): SIGINT/SIGTERM make :meth:`call` raise
    :class:`CompileInterrupted` within 0.05 s.  Main thread only, and only when ``enabled``; the previous handlers are
    restored on exit.  The handler only records the signal; the waiting thread raises it from its own code (a handler
    that raised landed, one run in ~50 under load, inside ``Thread.start``'s wait for the worker, in the middle of
    ``threading.Condition``'s lock restore: ``RuntimeError: release unlocked lock`` and a traceback instead of the one
    line and exit code 130)."""

    def __enter__(self) -> RaiseOnSignal:
        super().__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        super().__exit__(*exc)
        if self.signum and exc[0] is None:  # a signal after the compile, before the handlers were restored
            raise CompileInterrupted(self.signum)

    def call(self, fn: Callable[[], Any]) -> Any:
        """``fn()``, run in a daemon thread while this (main) thread waits in steps of 0.05 s, so that a signal is
        honoured within 0.05 s even while the compiler is inside one long LLVM pass (C code, during which the
        thread calling it cannot run a Python signal handler; llvmlite releases the GIL there).  On a signal
        :class:`CompileInterrupted` is raised here and the compile is abandoned: nothing of the run exists yet,
        and Numba writes its cache files by an atomic rename, so an abandoned compile leaves no partial file.
        Without signal handling (``enabled`` false: not the main thread, or the caller's choice) ``fn`` runs here.
        """
        if not self.enabled:
            return fn()
        box: dict[str, Any] = {}

        def target() -> None:
            try:
                box["value"] = fn()
            except BaseException as exc:  # handed to the waiting thread below
                box["error"] = exc

        worker = threading.Thread(target=target, name="jetgaudin-compile", daemon=True)
        worker.start()
        while worker.is_alive() and not self.signum:
            worker.join(0.05)
        if self.signum:  # the compile is abandoned (its thread is a daemon)
            raise CompileInterrupted(self.signum)
        if "error" in box:
            raise box["error"]
        return box.get("value")


@dataclass
class Position:
    """Where a run stands: step ``n``, state ``X`` and ``carry`` (``None``: not started)."""

    n: int
    X: np.ndarray
    carry: Any


@dataclass
class Outcome:
    """What the loop ends with: the status, its reason and the position of the last durable checkpoint."""

    status: RunStatus
    reason: str | None
    last_safe_step: int
    elapsed: float
    signum: int = 0
    extra: dict = field(default_factory=dict)


def piece(n: int, L: int, steps: int, every: int) -> tuple[int, int]:
    """The next kernel call from step ``n`` with at most ``L`` steps: ``(k, save_every)``; whole save intervals when
    on the save grid, else up to the grid (or to ``steps``)."""
    rem, off = steps - n, n % every
    if off:
        k = min(every - off, rem, L)
    elif rem < every:
        k = min(rem, L)
    elif L >= every:
        k = min(L, rem) // every * every
    else:
        k = L
    return k, (every if off == 0 and k % every == 0 else k)


class Driver:
    """Runs ``spec`` from ``pos`` into ``store`` (see the module doc); ``summary(health, elapsed)`` gives the
    layout's summary fields of ``run.json``."""

    def __init__(self, spec: RunSpec, store: Store, pos: Position, health: Health, *,
                 summary: Callable[[Health, float], dict], elapsed0: float = 0.0,
                 progress: Callable[[int, int], None] | None = None, handle_signals: bool = True,
                 max_chunk_steps: int | None = None, max_chunk_bytes: int = 64 << 20, chunk_rows: int = 4096,
                 first: bool = False, fresh: bool = False):
        self.spec, self.store, self.pos, self.health = spec, store, pos, health
        self.fresh = fresh
        self.summary_fn, self.elapsed0, self.progress = summary, elapsed0, progress
        self.handle_signals, self.first = handle_signals, first
        row_bytes = 8 * spec.B * spec.n_state
        self.max_rows = max(1, min(int(chunk_rows), int(max_chunk_bytes) // max(1, row_bytes)))
        self.max_steps = max_chunk_steps
        self.n_start = pos.n
        self.t_start = time.monotonic()
        #: the map the loop advances: on the GPU, one that keeps the states, health and drift on the device
        self.map = spec.map
        if spec.map.backend is Backend.GPU:
            from ..gpu._resident import attach

            self.map = attach(spec, health, store, pos.n)

    def summary(self, status: str) -> dict:
        """The layout's summary fields, ``status`` and the stepping rate of this session (orbit-steps per second of
        wall time since the loop started: compile/load time, spent before, is not in it)."""
        d = dict(self.summary_fn(self.health, self.elapsed()), status=status)
        dt = time.monotonic() - self.t_start
        if self.pos.n > self.n_start and dt > 0:
            d["orbit_steps_per_second"] = (self.pos.n - self.n_start) * self.spec.B / dt
        return d

    def elapsed(self) -> float:
        return self.elapsed0 + time.monotonic() - self.t_start

    def _limit(self, L: int) -> int:
        every = self.spec.save_every
        L = min(L, self.max_rows * every)
        return max(1, L if self.max_steps is None else min(L, self.max_steps))

    def run(self) -> Outcome:
        spec, store, pos, health = self.spec, self.store, self.pos, self.health
        steps, every, m = spec.steps, spec.save_every, self.map
        per_step = m.backend is Backend.NUMPY and getattr(m, "chunk_invariant", True)
        invariant = getattr(m, "chunk_invariant", True)
        sample_imag = m.backend in (Backend.COMPILED, Backend.GPU) and m.properties.real and np.isfinite(
            spec.limits.max_imag)  # the compiled and GPU routes do not compute the residue: sampled per chunk
        L = 1 if per_step else (every * max(1, 256 // every) if not invariant else max(1, (1 << 12) // spec.B))
        failure: str | None = None
        t_ck = time.monotonic()
        with SignalFlag(self.handle_signals) as sig:
            sig.ignore_sigxfsz()
            try:
                store.begin(self.fresh)
                if self.first:
                    bad = health.check_start(pos.X)
                    failure = bad.reason if bad else None
                    store.append(np.array([0]), pos.X[None])
                    store.anchor = (0, pos.X, None)
                    store.checkpoint(0, pos.X, pos.carry, self.summary("running"))
                if failure is None and self.map is spec.map and pos.n < steps:
                    try:  # a map set up once per run (su(3) exact steps: their parameters), inside the run
                        self.map = run_map(spec)
                    except JetGaudinError as exc:
                        failure = f"{type(exc).__name__} after step {pos.n}: {one_line(exc)}"
                while failure is None and pos.n < steps and not sig.signum:
                    failure = self._chunk(sig, L if not invariant else None, sample_imag, per_step)
                    if invariant and not per_step:
                        L = self._L
                    now = time.monotonic()
                    if failure is None and now - t_ck >= spec.checkpoint_seconds:
                        store.checkpoint(pos.n, pos.X, pos.carry, self.summary("running"))
                        t_ck = now
                if sig.signum and failure is None and pos.n < steps:
                    status, text = RunStatus.INTERRUPTED, "interrupted"
                elif failure is not None:
                    status, text = RunStatus.FAILED, f"failed: {failure}"
                else:
                    status, text = RunStatus.COMPLETED, "completed"
                store.checkpoint(pos.n, pos.X, pos.carry, self.summary(text))
                store.wait()  # the last checkpoint durable (an ensemble's writer thread: Store.overlap) before the end
            except RunIOError as exc:  # the status says what failed in one word: "disk full", ...
                reason = _fs.io_failure(exc)
                store.mark(f"failed: {reason}", failure="io", elapsed_seconds=self.elapsed())
                return Outcome(RunStatus.FAILED_IO, reason, int(store.run.get("last_safe_step", 0)), self.elapsed())
            except BaseException:
                store._settle()  # an ensemble's writer thread ends here, while SIGXFSZ is still ignored
                raise
            if self.progress is not None:
                self.progress(pos.n, steps)
        # a signal that came after the last step (during the last checkpoint or the last progress call) is still
        # reported: the run completed, and the caller stops there (no exit 0 after a SIGINT)
        return Outcome(status, failure, pos.n, self.elapsed(), signum=sig.signum)

    _L = 1
    _fixed = float("inf")  # the shortest call's seconds (:meth:`_adapt`)
    _overhead = 0.0  # seconds of the last chunk outside the kernel calls (health checks, append, reference step)

    def _chunk(self, sig: SignalFlag, fixed: int | None, sample_imag: bool, per_step: bool) -> str | None:
        """Advance by kernel calls for about :data:`FLUSH_SECONDS` (longer when the checks are slow: see
        :data:`FLUSH_SHARE`; or one fixed chunk), then check the health of the rows and the end state and append the
        rows that passed.  Returns a failure reason or ``None``."""
        spec, pos, health, m = self.spec, self.pos, self.health, self.map
        steps, every = spec.steps, spec.save_every
        rows_n: list[int] = []
        rows: list[np.ndarray] = []
        end: tuple[int, np.ndarray, Any] | None = None  # (step, X, carry) after the last call
        anchor: tuple[int, np.ndarray, Any] | None = None  # where the call that made the last row started
        failure: str | None = None
        t_enter = time.monotonic()
        if sample_imag:  # the compiled route does not compute the residue: one reference step per chunk
            Xs = pos.X if pos.X.ndim == 1 else pos.X[:64]
            cs = pos.carry if (pos.carry is None or pos.X.ndim == 1) else pos.carry[:64]
            try:
                imag = m.step(Xs, cs)[2]
            except JetGaudinError:
                imag = np.zeros(0)  # the kernel call below meets the same singularity and reports it
            failure = health.check_imag(pos.n + 1, imag)
            if failure:
                return failure
        t0 = time.monotonic()
        t_calls = 0.0  # time inside the kernel calls; the rest of the chunk is the checks' overhead
        flush = min(FLUSH_MAX_SECONDS, max(FLUSH_SECONDS, self._overhead / FLUSH_SHARE))
        n, X, carry = pos.n, pos.X, pos.carry
        while n < steps:
            L = fixed if fixed is not None else (1 if per_step else self._limit(self._L))
            k, se = piece(n, L, steps, every)
            tc = time.monotonic()
            start = (n, X, carry)
            try:
                adv = m.advance(X, carry, k, se)
            except JetGaudinError as exc:  # SingularStepError, BranchPointError met along the orbit
                failure = f"{type(exc).__name__} after step {n}: {one_line(exc)}"
                break
            dt = time.monotonic() - tc
            t_calls += dt
            if fixed is None and not per_step:
                self._L = self._adapt(self._L, k, dt)
            if se == every and k >= every:
                rows_n.extend(range(n + every, n + k + 1, every))
                rows.extend(adv.rows)
                anchor = start
            elif (n + k) % every == 0 or n + k == steps:
                rows_n.append(n + k)
                rows.append(adv.rows[-1])
                anchor = start
            n, X, carry = n + k, adv.X, adv.carry
            if per_step or not sample_imag:
                failure = health.check_imag(n, adv.imag_max)
                if failure:
                    if rows_n and rows_n[-1] == n:
                        rows_n.pop()
                        rows.pop()
                    n, X, carry = end if end is not None else (pos.n, pos.X, pos.carry)
                    break
            end = (n, X, carry)
            if self.progress is not None:  # after every kernel call (a display: the rows are checked below)
                self.progress(n, steps)
            if fixed is not None or sig.signum or time.monotonic() - t0 >= flush or len(rows_n) >= self.max_rows:
                break
        failure = self._commit(rows_n, rows, end, failure)
        if failure is None and anchor is not None:
            self.store.anchor = anchor  # the last saved row is the end of that call (a resume replays it)
        self._overhead = max(0.0, time.monotonic() - t_enter - t_calls)
        return failure

    def _commit(self, rows_n: list[int], rows: list[np.ndarray], end: tuple[int, np.ndarray, Any] | None,
                failure: str | None) -> str | None:
        """Health-check the rows and the last end state; append the rows that passed; move the position to the last
        state that passed (the last step that passed is what ``last_safe_step`` reports)."""
        health, pos = self.health, self.pos
        S = np.asarray(rows) if rows else np.empty((0,) + pos.X.shape)
        bad = health.check(rows_n, S)
        if bad is not None:
            keep = bad.index
            self.store.append(np.asarray(rows_n[:keep], dtype=np.int64), S[:keep])
            if keep:
                pos.n, pos.X, pos.carry = rows_n[keep - 1], S[keep - 1], None
            return bad.reason
        if end is not None:
            n_end, X_end, c_end = end
            if not rows_n or rows_n[-1] != n_end:
                bad = health.check_end(n_end, X_end)  # off the save grid: not in the maxima
                if bad is not None:
                    self.store.append(np.asarray(rows_n, dtype=np.int64), S)
                    if rows_n:
                        pos.n, pos.X, pos.carry = rows_n[-1], S[-1], None
                    return bad.reason
        self.store.append(np.asarray(rows_n, dtype=np.int64), S)
        if end is not None:
            pos.n, pos.X, pos.carry = end
        return failure

    def _adapt(self, L: int, k: int, dt: float) -> int:
        """The next call length: about :data:`CALL_SECONDS` of steps at the measured marginal rate (the shortest call's
        time taken as the fixed cost of a call, so a call lasts that cost plus about CALL_SECONDS), at most 4x the last
        one.  A short piece (``k < L``: up to the save grid, or whole save intervals below ``L``) may only make ``L``
        grow: its rate, with the call's fixed cost spread over fewer steps, underestimates the rate at length ``L``.
        (Ignoring short pieces, as before, stalled ``L`` at its first value above ``save_every`` whenever the pieces
        never reached it: calls of 14 steps for ``save_every = 7`` all run long.)"""
        # the marginal rate, the cheapest call so far taken as a call's fixed cost (copies to a GPU, allocations):
        # the rate k/dt shrank L to one step per call wherever that cost exceeded CALL_SECONDS (10^6 orbits on a GPU)
        self._fixed = min(self._fixed, dt)
        work = max(dt - self._fixed, 1e-6)
        new = int(max(1, min(4 * L, k / work * CALL_SECONDS)))
        return max(L, new) if k < L else new
