r"""Runs on the GPU with the states kept on the device between calls (issue 36; private: :func:`attach`).

The run layer's loop (:class:`jetgaudin.run.driver.Driver`) calls ``map.advance(X, carry, k, save_every)`` and gets
the saved rows, the end state and ``ν1`` back as host arrays; on the GPU route that was two copies of every state per
call across PCIe, and the health checks (the integrals of every saved row, NumPy) on the host.  :func:`attach`
gives the loop a map whose ``advance`` keeps them on the device:

* **States and ``ν1`` stay on the device.**  ``Advance.X`` and ``Advance.carry`` are :class:`DeviceStates`, handles
  of device arrays, given back to the next call as they are (no copy); one becomes a host array only where the loop
  reads it -- the checkpoint (every ``checkpoint_seconds``: :func:`attach` wraps ``store.checkpoint``), the reference
  step of the imaginary residue (64 states), a state off the save grid at the end of a chunk that breaches (its
  health is checked on the device first: :meth:`ResidentMap.check_end`).  Each call writes new
  device arrays (the old ones are freed once no handle refers to them), so a handle never changes.
* **Only saved rows come back, their copy overlapping the next call.**  ``Advance.rows`` is a handle too.  A call
  that ends on the save grid (or at the run's last step: the loop takes its rows) starts the copy of its rows into a
  pinned host buffer at once, on a second CUDA stream after the call's kernel, and returns: the copy runs while the
  host goes on and the next call steps; the loop's first look at the rows waits for it.  The pinned buffers are a
  pool of :data:`POOL`, each reused once nothing refers to it any more (the loop copies the rows it appends); a call
  that finds none free, or whose rows the loop may not take (off the grid), copies what the loop takes when it takes
  it.
* **Health on the device.**  The health of the rows the loop took (integrals ``κ`` of every orbit against
  ``I(X_0)``, relative to ``max(1, |I(X_0)|)``; non-finite or above ``max_drift`` is a breach), the running maxima
  of the drift and of the radius deviation ``||y_{N−1}| − |y_{N−1}(0)||`` are computed by CUDA kernels, one thread
  per orbit (:func:`_health_kernels`); the host gets one integer per call (the first bad row).  Only a breach is
  worded on the host (its row is checked again there, to name the orbit and integral as the CPU route does).  The
  :class:`jetgaudin.run.health.Health` of the run keeps its interface: its ``drift`` and ``sphere`` read the device
  maxima when asked (the checkpoint's summary, the end of the run).
* **Status on the device.**  A failed orbit is found by a reduction kernel (first failing orbit, count): the call
  raises the same :class:`jetgaudin.SingularStepError` / :class:`jetgaudin.BranchPointError` as the CPU route.

The steps are the GPU route's own kernels (:func:`._kernels.top_kernels`), so a run split into calls equals the unsplit
run bit for bit on the same device, and a checkpoint resumes bit for bit, as before.  The integrals on the device
sum in another order than NumPy's: the drift values agree with the host's to round-off of ``max(1, |I|)``, not bit
for bit (``tests/test_gpu.py``).  The simulator runs streams in order, so the tests check the copies' content and
bookkeeping, not their overlap.

Ensembles of the top (``BatchBacklund``, N ≤ :data:`._kernels.MAX_N`) only; chains keep the host path.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from ._device import require
from ._health import _health_kernels, warm
from ._kernels import MAX_N, THREADS

#: at most this many pinned buffers for the rows' copies (a chunk of the loop holds a few calls' rows)
POOL = 4

__all__ = ["attach", "DeviceStates", "ResidentMap", "warm"]


class DeviceStates:
    """A device array ``(B, n)`` or ``(B,)`` (or a call's rows ``(r, B, n)``) seen as a host array on demand:
    ``np.asarray`` copies it (once; cached), a slice of the leading axis copies that slice only.  ``on_take``: called
    with the rows taken, for a call's rows (:class:`ResidentMap`)."""

    def __init__(self, dev: Any, owner: ResidentMap, on_take: Any = None):
        self.dev, self.owner, self._on_take = dev, owner, on_take
        self._host: np.ndarray | None = None
        self._copy: tuple[np.ndarray, Any] | None = None  # (pinned buffer, event): a copy on its way (copy_ahead)
        self.step: int | None = None  # the step a state handle is at (ResidentMap tracks the position)

    def copy_ahead(self, buf: np.ndarray, event: Any) -> None:
        """The copy into the pinned ``buf`` is on its way (done at ``event``): :meth:`host` waits for it."""
        self._copy = (buf, event)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.dev.shape)

    @property
    def ndim(self) -> int:
        return len(self.dev.shape)

    @property
    def size(self) -> int:
        return int(np.prod(self.dev.shape))

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(self.dev.dtype)

    def __len__(self) -> int:
        return int(self.dev.shape[0])

    def host(self) -> np.ndarray:
        if self._host is None:
            if self._copy is not None:
                buf, event = self._copy
                event.synchronize()
                self._host = buf
            else:
                self._host = self.owner.to_host(self.dev)
        return self._host

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        h = self.host()
        return h if dtype is None else h.astype(dtype)

    def __iter__(self) -> Any:
        if self._on_take is not None:
            self._on_take(0, len(self))
        return iter(self.host())

    def __getitem__(self, idx: Any) -> Any:
        if self._on_take is not None and isinstance(idx, int):  # a call's last row: the only one copied
            j = idx % len(self)
            self._on_take(j, j + 1)
            return self.owner.to_host(self.dev[j]) if self._host is None and self._copy is None else self.host()[j]
        if self._host is None and isinstance(idx, slice) and idx.step in (None, 1):
            return self.owner.to_host(self.dev[idx])
        return self.host()[idx]


def host(x: Any) -> Any:
    """``x`` as a host array where it is a :class:`DeviceStates` (else as it is)."""
    return np.asarray(x) if isinstance(x, DeviceStates) else x


class ResidentMap:
    """The map of a GPU run as the run layer's loop sees it (module docstring): ``advance`` on device-resident states;
    everything else is the wrapped :class:`jetgaudin.ensemble.BatchBacklund`'s."""

    def __init__(self, m: Any, health: Any, n0: int = 0, every: int = 1, steps: int = 0):
        self.m = m
        self.c = require()
        self.stream = self.c.stream()
        self.copy_stream = self.c.stream()  # the saved rows' copies, beside the next call's steps
        self.n0, self.every, self.steps = int(n0), int(every), int(steps)
        self._pool: list[np.ndarray] = []  # pinned buffers of the rows' copies, reused once nothing refers to them
        c, B = self.c, len(m.b)
        self.B = B
        self.d_b = c.to_device(np.ascontiguousarray(m.b, dtype=np.float64), stream=self.stream)
        self.d_eta = c.to_device(np.ascontiguousarray(m.eta, dtype=np.complex128), stream=self.stream)
        self.d_I0 = c.to_device(np.ascontiguousarray(np.broadcast_to(health.I0, (B, health.I0.shape[-1]))),
                                stream=self.stream)
        self.d_scale = c.to_device(np.ascontiguousarray(np.broadcast_to(health.scale, self.d_I0.shape)),
                                   stream=self.stream)
        self.d_r0 = c.to_device(np.ascontiguousarray(np.broadcast_to(health.r0, (B,)), dtype=np.float64),
                                stream=self.stream)
        self.d_drift = c.to_device(np.ascontiguousarray(np.broadcast_to(health.drift, self.d_I0.shape)),
                                   stream=self.stream)
        self.d_sphere = c.to_device(np.zeros(B), stream=self.stream)
        self.max_drift = float(health.limits.max_drift)
        self.taken: list[tuple[Any, int, int]] = []  # (device rows, j0, j1) the loop took, in order
        self._pinned: dict[tuple, np.ndarray] = {}

    def __getattr__(self, name: str) -> Any:
        return getattr(self.m, name)

    # ------------------------------------------------------------------ copies
    def to_host(self, dev: Any) -> np.ndarray:
        """A host copy of the device array ``dev``, through a pinned buffer of its shape (reused), on the stream."""
        key = (tuple(dev.shape), np.dtype(dev.dtype).str)
        buf = self._pinned.get(key)
        if buf is None:
            buf = self.c.pinned_array(dev.shape, dtype=dev.dtype)
            self._pinned = {key: buf}  # one buffer at a time: the shapes of a run repeat
        dev.copy_to_host(buf, stream=self.stream)
        self.stream.synchronize()
        return np.array(buf)

    def _pinned_rows(self, shape: tuple, dtype: Any) -> np.ndarray | None:
        """A pinned buffer of ``shape`` that nothing outside the pool refers to (the loop has copied the rows it held
        into its own arrays), or a new one (at most :data:`POOL` in all); ``None`` when all are in use."""
        for i in range(len(self._pool)):
            if self._pool[i].shape == shape and sys.getrefcount(self._pool[i]) <= 2:  # the pool's and the argument's
                return self._pool[i]
        if len(self._pool) >= POOL:
            self._pool = [b for b in self._pool if sys.getrefcount(b) > 2]  # drop free buffers of other shapes
            if len(self._pool) >= POOL:
                return None
        self._pool.append(self.c.pinned_array(shape, dtype=dtype))
        return self._pool[-1]

    def _device(self, x: Any, dtype: Any) -> Any:
        if isinstance(x, DeviceStates) and x.owner is self:
            return x.dev
        return self.c.to_device(np.ascontiguousarray(np.asarray(x), dtype=dtype), stream=self.stream)

    # ------------------------------------------------------------------ the step
    def advance(self, X: Any, carry: Any, steps: int, save_every: int = 1) -> Any:
        from ..backlund.kernels._drivers import check_counts
        from ..maps import Advance, check_count
        from ._drivers import _check_fits, _record
        from ._kernels import top_kernels

        steps, save_every = check_count(steps, "steps"), check_count(save_every, "save_every", 1)
        c, B, s = self.c, self.B, self.stream
        n = int(X.shape[-1])
        S = check_counts(steps, save_every, B, n)
        _check_fits(c, 8 * B * (n * (S + 1) + 4), f"a call of {B} orbits with {S} saved rows")
        import time

        t0 = time.perf_counter()
        dX = self._device(X, np.float64)
        if carry is None:  # the branch rule on the host, as the CPU route (its bits)
            from ..backlund._compiled import kernels

            Xh = np.ascontiguousarray(host(X), dtype=np.float64)
            d_nu0, cont = c.to_device(kernels().nu_default(Xh, self.m.b, self.m.eta, self.m.branch.sheet),
                                      stream=s), False
        else:
            d_nu0, cont = self._device(carry, np.complex128), True
        d_out = c.device_array((S, B, n), stream=s)
        d_final = c.device_array((B, n), stream=s)
        d_status = c.device_array(B, np.int64, stream=s)
        d_fail = c.device_array(B, np.int64, stream=s)
        d_nu = c.device_array(B, np.complex128, stream=s)
        kernel3, kernel_generic = top_kernels()
        kernel = kernel3 if n == 9 else kernel_generic
        grid = -(-B // THREADS)
        start, stop = c.event(), c.event()
        start.record(stream=s)
        kernel[grid, THREADS, s](dX, self.d_b, self.d_eta, d_nu0, cont, np.int64(steps), np.int64(save_every), d_out,
                                 d_final, d_status, d_fail, d_nu)
        stop.record(stream=s)
        at = X.step if isinstance(X, DeviceStates) and X.owner is self and X.step is not None else self.n0
        rows = DeviceStates(d_out[1:], self, on_take=lambda j0, j1: self.taken.append((d_out, j0 + 1, j1 + 1)))
        # the rows the loop will take (the call ends on the save grid, or the run ends) are copied at once, on the copy
        # stream, while the host goes on and the next call steps: their copy overlaps the next call
        if S > 1 and ((at + steps) % self.every == 0 or at + steps == self.steps):
            buf = self._pinned_rows((S - 1, B, n), np.float64)
            if buf is not None:
                stop.wait(stream=self.copy_stream)
                d_out[1:].copy_to_host(buf, stream=self.copy_stream)
                copied = c.event()
                copied.record(stream=self.copy_stream)
                rows.copy_ahead(buf, copied)
        _, _, failed = _health_kernels()
        d_bad = c.to_device(np.array([B, 0], dtype=np.int64), stream=s)
        failed[grid, THREADS, s](d_status, d_bad)
        bad = d_bad.copy_to_host(stream=s)
        s.synchronize()
        _record(start.elapsed_time(stop) / 1000.0, time.perf_counter() - t0, B, int(steps))
        if bad[1]:  # the CPU route's exception for the first failing orbit
            from ..backlund._compiled import kernels

            i = int(bad[0])
            st, fl = int(d_status[i:i + 1].copy_to_host()[0]), int(d_fail[i:i + 1].copy_to_host()[0])
            exc = kernels().status_error(st, fl, i)
            raise type(exc)(f"{exc} ({int(bad[1])} orbit(s) of {B} failed)")

        end = DeviceStates(d_final, self)
        end.step = at + steps
        return Advance(rows=rows, X=end, carry=DeviceStates(d_nu, self),  # type: ignore[arg-type]
                       imag_max=np.zeros(0))

    # ------------------------------------------------------------------ health
    def check_end(self, X: DeviceStates) -> bool:
        """Whether the end state ``X`` (a handle of this map's, ``(B, n)``) passes the health check, on the device
        (``flag`` on it as a one-row call; nothing copied to the host, no maxima moved)."""
        c, s = self.c, self.stream
        d_first = c.to_device(np.array([1], dtype=np.int64), stream=s)
        flag, _, _ = _health_kernels()
        flag[-(-self.B // THREADS), THREADS, s](X.dev.reshape((1,) + tuple(X.dev.shape)), 0, 1, self.d_b, self.d_I0,
                                                 self.d_scale, self.max_drift, d_first)
        first = int(d_first.copy_to_host(stream=s)[0])
        s.synchronize()
        return first == 1

    def check_taken(self, count: int) -> int | None:
        """The health of the ``count`` rows the loop took since the last check (in order), on the device: the index
        of the first bad one (``None``: all good), the running maxima folded over the rows up to it (included, as
        :meth:`jetgaudin.run.health.Health.check`).  ``-1``: the rows taken do not match ``count`` (the caller checks
        on the host)."""
        taken, self.taken = self.taken, []
        if sum(j1 - j0 for _, j0, j1 in taken) != count:
            return -1
        flag, fold, _ = _health_kernels()
        c, s, grid = self.c, self.stream, -(-self.B // THREADS)
        seen = 0
        for d_out, j0, j1 in taken:
            d_first = c.to_device(np.array([j1], dtype=np.int64), stream=s)
            flag[grid, THREADS, s](d_out, j0, j1, self.d_b, self.d_I0, self.d_scale, self.max_drift, d_first)
            first = int(d_first.copy_to_host(stream=s)[0])
            s.synchronize()
            fold[grid, THREADS, s](d_out, j0, min(first + 1, j1), self.d_b, self.d_I0, self.d_r0, self.d_drift,
                                   self.d_sphere)
            if first < j1:
                s.synchronize()
                return seen + first - j0
            seen += j1 - j0
        s.synchronize()
        return None


def _device_health_class(base: Any) -> type:
    """A subclass of the run's :class:`jetgaudin.run.health.Health` class whose ``check`` of the rows a
    :class:`ResidentMap` returned runs on the device, and whose ``drift`` and ``sphere`` are the device maxima."""

    class DeviceHealth(base):  # type: ignore[misc, valid-type]
        resident: ResidentMap

        @property  # type: ignore[override]
        def drift(self) -> np.ndarray:
            return self.resident.to_host(self.resident.d_drift)

        @drift.setter
        def drift(self, value: np.ndarray) -> None:
            r = self.resident
            r.d_drift = r.c.to_device(np.ascontiguousarray(np.broadcast_to(value, r.d_drift.shape)), stream=r.stream)

        @property  # type: ignore[override]
        def sphere(self) -> float:
            d = self.resident.to_host(self.resident.d_sphere)
            return max(self.__dict__.get("_sphere", 0.0), float(d.max()) if d.size else 0.0)

        @sphere.setter
        def sphere(self, value: float) -> None:
            self.__dict__["_sphere"] = float(value)

        def check_end(self, step: int, X: Any) -> Any:
            r = self.resident
            if isinstance(X, DeviceStates) and X.owner is r and X.ndim == 2 and r.check_end(X):
                return None  # passed on the device: not copied, not recorded (as the host's record=False)
            return base.check_end(self, step, X)  # a breach (or a host state): checked and worded on the host

        def check(self, steps: list[int], S: np.ndarray, *, record: bool = True) -> Any:
            r = self.resident
            if not r.taken:  # e.g. the end of a call off the save grid (record=False): on the host, as on the CPU
                return base.check(self, steps, S, record=record)
            first = r.check_taken(len(steps))
            if first is None:
                return None
            if first < 0:
                return base.check(self, steps, S, record=record)
            bad = base.check(self, [steps[first]], np.asarray(S)[first:first + 1])  # worded as on the CPU route
            if bad is not None:
                bad.index = first
            return bad

    return DeviceHealth


def attach(spec: Any, health: Any, store: Any, n0: int = 0) -> Any:
    """The map the run layer's loop advances for ``spec``: a :class:`ResidentMap` for an ensemble of the top on the
    GPU (``health`` then checks on the device, ``store``'s checkpoints copy the states they record), else
    ``spec.map`` (nothing changed)."""
    from ..ensemble import BatchBacklund
    from ..maps import Backend

    m = spec.map
    if (not isinstance(m, BatchBacklund) or m.backend is not Backend.GPU or spec.X0.ndim != 2 or spec.B == 0
            or spec.n_state > 3 * MAX_N):
        return m
    r = ResidentMap(m, health, n0, spec.save_every, spec.steps)
    sphere = health.sphere
    health.__dict__.pop("drift", None)
    health.__dict__.pop("sphere", None)
    health.__class__ = _device_health_class(type(health))
    health.resident = r
    health.sphere = sphere
    original = store.checkpoint

    def checkpoint(step: int, X: Any, carry: Any, summary: dict) -> None:
        if store.anchor is not None:
            a_n, a_X, a_c = store.anchor
            store.anchor = (a_n, host(a_X), host(a_c))
        original(step, host(X), host(carry), summary)

    store.checkpoint = checkpoint
    return r
