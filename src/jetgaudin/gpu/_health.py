"""The GPU run layer's health kernels (:mod:`._resident`): ``flag``, ``fold``, ``failed``, one thread per orbit, and
:func:`warm`, their compile ahead of a run (:func:`jetgaudin.gpu.prepare`).  A module of their own, importing only
the device probe and the kernels' constants, so that ``prepare`` (:mod:`._drivers`) can compile them without
importing the resident route (which imports the map interface: an import circle)."""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ._device import cuda as _import_cuda
from ._device import require
from ._kernels import THREADS

#: ``numba.cuda``, bound by :func:`_health_kernels` (a module global: the CUDA simulator swaps the kernels' global
#: ``cuda`` for its own, as in :mod:`._kernels`)
cuda: Any = None

__all__ = ["warm"]


@functools.cache
def _health_kernels() -> tuple[Any, Any, Any]:
    """``(flag, fold, failed)``: CUDA kernels, one thread per orbit.

    ``flag(rows, j0, j1, b, I0, scale, max_drift, first)``: ``first[0] = min(first[0], j)`` over the rows ``j0 <= j <
    j1`` of ``rows (S, B, 3N)`` where an orbit's relative drift ``|κ(x) − I0| / scale`` is non-finite or above
    ``max_drift``.  ``fold(rows, j0, j1, b, I0, r0, drift, sphere)``: the running maxima ``drift (B, 2N)`` of
    ``|κ(x) − I0|`` (non-finite taken as 0) and ``sphere (B,)`` of ``||y_{N−1}| − r0|`` (NaN as 0, infinity as the
    largest double) over those rows.  ``failed(status, out)``: ``out[0] = min i`` with ``status[i] != 0``,
    ``out[1] = their count``.  ``κ_t = [t < N] 2 b y_t³ + Σ_{i+j+1=t} ⟨y_i, y_j⟩`` (``H_1..H_N, C_1..C_N``, the
    integrals of :func:`jetgaudin.integrals`)."""
    global cuda
    require()
    if cuda is None:
        cuda = _import_cuda()
    big = float(np.finfo(np.float64).max)

    @cuda.jit(device=True)
    def kappa(rows, j, o, b, N, t):  # pragma: no cover  (compiled for the device; the simulator runs it)
        s = 0.0
        if t < N:
            s = 2.0 * b * rows[j, o, 3 * t + 2]
        for i in range(N):
            k = t - 1 - i
            if 0 <= k < N:
                s += (rows[j, o, 3 * i] * rows[j, o, 3 * k] + rows[j, o, 3 * i + 1] * rows[j, o, 3 * k + 1]
                      + rows[j, o, 3 * i + 2] * rows[j, o, 3 * k + 2])
        return s

    @cuda.jit
    def flag(rows, j0, j1, b, I0, scale, max_drift, first):  # pragma: no cover
        o = cuda.grid(1)
        if o < rows.shape[1]:
            N = rows.shape[2] // 3
            for j in range(j0, j1):
                for t in range(2 * N):
                    rel = abs(kappa(rows, j, o, b[o], N, t) - I0[o, t]) / scale[o, t]
                    if not (rel < math.inf) or rel > max_drift:
                        cuda.atomic.min(first, 0, j)
                        return

    @cuda.jit
    def fold(rows, j0, j1, b, I0, r0, drift, sphere):  # pragma: no cover
        o = cuda.grid(1)
        if o < rows.shape[1]:
            N = rows.shape[2] // 3
            for j in range(j0, j1):
                for t in range(2 * N):
                    d = abs(kappa(rows, j, o, b[o], N, t) - I0[o, t])
                    if d < math.inf and d > drift[o, t]:
                        drift[o, t] = d
                y1, y2, y3 = rows[j, o, 3 * N - 3], rows[j, o, 3 * N - 2], rows[j, o, 3 * N - 1]
                e = abs(math.sqrt(y1 * y1 + y2 * y2 + y3 * y3) - r0[o])  # math's: NumPy ufuncs do not compile for CUDA
                if e != e:
                    e = 0.0
                elif e > big:
                    e = big
                if e > sphere[o]:
                    sphere[o] = e

    @cuda.jit
    def failed(status, out):  # pragma: no cover
        i = cuda.grid(1)
        if i < status.shape[0] and status[i] != 0:
            cuda.atomic.min(out, 0, i)
            cuda.atomic.add(out, 1, 1)

    return flag, fold, failed


def warm(n_state: int) -> None:
    """Compile the resident route's own kernels (``flag``, ``fold``, ``failed`` of :func:`_health_kernels`) for runs
    on states of ``n_state`` components: each is launched once on one orbit with the argument types a run gives it
    (the same dtypes, dimensions and layouts; Python ``int`` step bounds, ``float`` limit), so that Numba compiles it
    here -- in :func:`jetgaudin.gpu.prepare`, beside the stepping kernel and outside the stepping rate -- and not at
    its first call inside the run's loop (~1.4 s on an H200, issue 36)."""
    c = require()
    flag, fold, failed = _health_kernels()
    s = c.stream()
    k = 2 * (int(n_state) // 3)
    rows = c.device_array((2, 1, int(n_state)), stream=s)  # as a call's rows: device_array((S, B, n))
    rows.copy_to_device(np.zeros((2, 1, int(n_state))), stream=s)
    b = c.to_device(np.ones(1), stream=s)
    I0 = c.to_device(np.zeros((1, k)), stream=s)
    scale = c.to_device(np.ones((1, k)), stream=s)
    first = c.to_device(np.array([2], dtype=np.int64), stream=s)
    flag[1, THREADS, s](rows, 1, 2, b, I0, scale, 1.0, first)
    drift, r0, sphere = c.to_device(np.zeros((1, k)), stream=s), c.to_device(np.zeros(1), stream=s), \
        c.to_device(np.zeros(1), stream=s)
    fold[1, THREADS, s](rows, 1, 2, b, I0, r0, drift, sphere)
    status = c.device_array(1, np.int64, stream=s)
    status.copy_to_device(np.zeros(1, dtype=np.int64), stream=s)
    failed[1, THREADS, s](status, c.to_device(np.array([1, 0], dtype=np.int64), stream=s))
    s.synchronize()
