"""Python drivers of the compiled kernels: validate the counts, allocate, call a kernel, turn its status into a
typed error.  No mathematics here.  The kernel modules are imported at the first call, after
:func:`._target.configure` (never at import of the package)."""

from __future__ import annotations

import importlib
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from types import ModuleType
from typing import Any

import numpy as np

from ..._errors import BranchPointError, InvalidParameterError
from . import _target
from ._status import STATUS_BRANCH, STATUS_OK, status_error

__all__ = [
    "kernel_module",
    "check_counts",
    "saved_count",
    "run_batch",
    "run_ensemble",
    "iterate_batch",
    "iterate_single",
    "nu_default",
    "closed_form_orbit",
]

#: largest count the kernels take (their loop counters are int64)
INT64_MAX = 2**63 - 1


_modules: dict[str, ModuleType] = {}


def kernel_module(name: str) -> ModuleType:
    """The kernel module ``name`` (``"_n3"``, ``"_generic"``, ``"_lanes"``, ``"_branch"``, ``"_closed"``),
    imported after the target configuration (:func:`._target.configure`)."""
    mod = _modules.get(name)
    if mod is None:
        _target.configure()
        mod = importlib.import_module(f"{__package__}.{name}")
        for dep in ("_scalar", "_n3", "_generic", "_branch"):  # the modules it inlines from, and itself
            _target.refresh_stale_cache(importlib.import_module(f"{__package__}.{dep}"))
        _target.refresh_stale_cache(mod)
        _modules[name] = mod
    return mod


_memory: list[int | None] = []


def _memory_bytes() -> int | None:
    """Physical memory of the machine in bytes (read once), ``None`` where unknown."""
    if not _memory:
        try:
            _memory.append(int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES")))
        except (AttributeError, OSError, ValueError):
            _memory.append(None)
    return _memory[0]


def _count(name: str, value: Any, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InvalidParameterError(f"{name} must be an integer, got {value!r}")
    if not minimum <= int(value) <= INT64_MAX:
        raise InvalidParameterError(f"{name} must be in [{minimum}, 2**63 - 1], got {int(value)}")
    return int(value)


def check_counts(steps: Any, save_every: Any, batch: int = 1, n_state: int = 9) -> int:
    """Validate ``steps`` (0 ≤ steps < 2⁶³) and ``save_every`` (1 ≤ save_every < 2⁶³) and check that the saved
    rows of ``batch`` orbits of ``n_state`` components fit in the machine's memory, before anything is allocated.

    Returns the number of saved rows ``steps // save_every + 1``; raises
    :class:`jetgaudin.InvalidParameterError` naming the count and the fix."""
    steps = _count("steps", steps, 0)
    save_every = _count("save_every", save_every, 1)
    rows = steps // save_every + 1
    need = rows * max(int(batch), 1) * max(int(n_state), 1) * 8
    mem = _memory_bytes()
    if mem is not None and need > mem:
        raise InvalidParameterError(
            f"steps = {steps} saving every {save_every}: the {rows} saved rows of {batch} orbit(s) need "
            f"{need / 2**30:.3g} GiB, more than this machine's {mem / 2**30:.3g} GiB; raise save_every or run "
            "in chunks (the run layer streams rows to disk)"
        )
    return rows


def saved_count(steps: int, save_every: int) -> int:
    """Number of saved states ``x_0, x_k, x_2k, …`` (``k = save_every``)."""
    return steps // save_every + 1


def _batch_args(X: Any, b: Any, eta: Any, nu0: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return (np.ascontiguousarray(X, dtype=np.float64), np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(eta, dtype=np.complex128), np.ascontiguousarray(nu0, dtype=np.complex128))


def _n3_route(n_state: int, specialise: bool) -> bool:
    """Whether states of ``n_state`` components run the N = 3 kernels (``specialise``) rather than the generic ones."""
    return bool(specialise) and n_state == 9


def batch_kernel(n_state: int, specialise: bool = True) -> Any:
    """The compiled batch kernel for states of ``n_state`` components: the lock-step lanes for N = 3
    (``specialise``), else the ``prange`` loop over the generic single-orbit route."""
    if _n3_route(n_state, specialise):
        return kernel_module("_lanes").run_lanes3
    return kernel_module("_generic").run_batch_generic


def single_kernel(n_state: int, specialise: bool = True) -> Any:
    """The compiled single-orbit kernel: the N = 3 route (``specialise``) or the generic route."""
    if _n3_route(n_state, specialise):
        return kernel_module("_n3").run_orbit3
    return kernel_module("_generic").run_orbit


def run_ensemble(X0, b, eta, nu0, cont, steps, save_every, specialise, out, final, drift, status, fail, nu_last,
                 want_drift=True) -> None:
    r"""A batch of independent orbits into preallocated outputs: ``X0`` (B, 3N), per-orbit ``b``, ``eta``,
    ``nu0`` (B,); ``out`` (S, B, 3N) (step-major, C order), ``final`` (B, 3N), ``drift`` (B, 2N),
    ``status``/``fail`` (B,) int64, ``nu_last`` (B,) complex.  N = 3 (with ``specialise``): blocks of lock-stepped lanes
    (:func:`._lanes.run_lanes3`); other N: :func:`._generic.run_batch_generic`.  Either way every orbit gets the
    bits of its single-orbit run.  Never raises on a singular step (see ``status``).  ``final`` may be the view
    ``out[S - 1]`` when the last step is saved (the kernels write the same values to both); with
    ``want_drift=False`` the N = 3 kernel does not touch ``drift`` (it may have no rows), the generic kernel takes
    a view of each row and leaves it as given."""
    kernel = batch_kernel(X0.shape[1], specialise)
    args = (X0, b, eta, nu0, bool(cont), int(steps), int(save_every), out, final, drift, status, fail, nu_last,
            bool(want_drift))
    if not _n3_route(X0.shape[1], specialise):
        kernel(*args)
        return
    nblocks = -(-X0.shape[0] // kernel_module("_lanes").LANES)
    cost = min(int(steps), LANES_WORK_PER_PIECE) + 4  # a block's set-up costs about 4 of its steps
    in_threads(lambda k0, k1: kernel(*args, k0, k1), nblocks, _threads(nblocks, -(-LANES_WORK_PER_THREAD // cost)),
               -(-LANES_WORK_PER_PIECE // cost))


def run_batch(X, b, eta, nu0, cont, steps, save_every, specialise=True, want_drift=True):
    r"""Run the compiled map on a batch ``X`` (B, 3N) with per-orbit ``b``, ``eta``, ``nu0`` (B,); never raises on a
    singular step.  ``want_drift=False``: the drift pass is skipped (``drift`` is then ``None``).

    Returns ``(out (B, S, 3N), final (B, 3N), drift (B, 2N) or None, nu_last (B,), status (B,), fail (B,))``
    (``status`` and ``fail``: the ``STATUS_*`` code and the failing step of each orbit); ``out`` is a transposed
    view of a C-ordered ``(S, B, 3N)`` array (``np.moveaxis(out, 0, 1)`` is contiguous, no copy).  Raises
    :class:`jetgaudin.InvalidParameterError` for counts out of range (:func:`check_counts`).
    """
    X, b, eta, nu0 = _batch_args(X, b, eta, nu0)
    B, n3 = X.shape
    S = check_counts(steps, save_every, B, n3)
    out = np.empty((S, B, n3))
    # the last saved row is the final state when the last step is saved: one array less to allocate and fault in
    # (the kernels write the same values to both).  Without the drift pass no ``drift`` rows for the lanes, which
    # then never index it: 48 bytes of scratch per orbit less.  Scratch that glibc returns to the system at free
    # (its trim threshold) is faulted in again by the next call: for 10^5 orbits, iterate(X, 0) re-faulted ~8 MB
    # per call, half its fixed cost (docs/performance.md).  The generic kernel takes a view of each row: zeros
    # from calloc, untouched without the pass
    final = out[S - 1] if steps % save_every == 0 else np.empty((B, n3))
    drift = np.zeros((B if want_drift or not _n3_route(n3, specialise) else 0, 2 * (n3 // 3)))
    status = np.empty(B, np.int64)  # every entry is written by the kernel
    fail = np.empty(B, np.int64)
    nu_last = np.empty(B, np.complex128)
    run_ensemble(X, b, eta, nu0, cont, steps, save_every, specialise, out, final, drift, status, fail, nu_last,
                 want_drift)
    return out.transpose(1, 0, 2), final, drift if want_drift else None, nu_last, status, fail


def iterate_batch(X, b, eta, nu0, cont, steps, save_every, *, specialise=True, want_drift=True, runner=None):
    r"""Run the compiled map on a batch ``X`` (B, 3N) with per-orbit ``b``, ``eta``, ``nu0`` (B,)
    (``want_drift=False``: no drift pass, ``drift`` is ``None``; ``runner``: another driver with the arguments and
    returns of :func:`run_batch`, the GPU's :func:`jetgaudin.gpu.run_batch`).

    Returns ``(out (B, S, 3N), final (B, 3N), drift (B, 2N) or None, nu_last (B,))``; raises
    :class:`jetgaudin.SingularStepError` naming the first failing orbit and step.
    """
    out, final, drift, nu_last, status, fail = (runner or run_batch)(X, b, eta, nu0, cont, steps, save_every,
                                                                     specialise, want_drift)
    if status.any():
        i = int(np.flatnonzero(status)[0])
        raise status_error(status[i], fail[i], i)
    return out, final, drift, nu_last


def iterate_single(x, b, eta, nu0, cont, steps, save_every, *, specialise=True, want_drift=True):
    """One orbit ``x`` (3N,): returns ``(out (S, 3N), final (3N,), drift (2N,), nu_last)``; raises
    :class:`jetgaudin.SingularStepError` / :class:`jetgaudin.BranchPointError` at a singular step and
    :class:`jetgaudin.InvalidParameterError` for counts out of range."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    n3 = x.shape[0]
    S = check_counts(steps, save_every, 1, n3)
    out = np.empty((S, n3))
    final = np.empty(n3)
    drift = np.empty(2 * (n3 // 3))
    fn = single_kernel(n3, specialise)
    status, fail, nu = fn(x, float(b), complex(eta), complex(nu0), bool(cont), int(steps), int(save_every),
                          out, final, drift, bool(want_drift))
    if status != STATUS_OK:
        raise status_error(status, fail)
    return out, final, drift, nu


#: orbits per thread below which the branch rule stays on fewer threads (a thread costs ~10^4 orbits of the rule,
#: ~0.1 µs each, to start)
BRANCH_ORBITS_PER_THREAD = 16384

#: block-steps (``LANES`` orbits × one step, ~0.5 µs) per thread below which the lanes stay on fewer threads
LANES_WORK_PER_THREAD = 256

#: block-steps of the smallest piece of work a thread takes (~1 ms)
LANES_WORK_PER_PIECE = 2048

_pool: list[tuple[int, ThreadPoolExecutor]] = []


def _executor() -> ThreadPoolExecutor:
    """The process's pool of helper threads, one fewer than Numba's largest thread count (``NUMBA_NUM_THREADS``:
    the calling thread is the other), made anew in a forked child, where the parent's threads do not run."""
    if not _pool or _pool[0][0] != os.getpid():
        import numba

        helpers = max(1, int(numba.config.NUMBA_NUM_THREADS) - 1)
        _pool[:] = [(os.getpid(), ThreadPoolExecutor(max_workers=helpers, thread_name_prefix="jetgaudin"))]
    return _pool[0][1]


def _threads(n: int, per_thread: int) -> int:
    """How many threads share ``n`` items of work: Numba's thread count (``numba.set_num_threads``, so a run
    limited to one thread stays on one), at most one per ``per_thread`` items."""
    most = n // max(1, per_thread)
    if most < 2:  # one thread, without asking Numba (a few µs: this is on the path of every short call)
        return 1
    import numba

    return max(1, min(numba.get_num_threads(), most))


def guided_edges(n: int, threads: int, min_piece: int = 1) -> list[int]:
    """The edges ``0 = e_0 < e_1 < … = n`` of :func:`in_threads`' pieces: each ``⌈left/(2 threads)⌉`` items, at least
    ``min_piece`` (and at least one piece per thread where ``n`` allows)."""
    least = max(1, min(int(min_piece), n // max(1, threads)))
    edges = [0]
    while edges[-1] < n:
        left = n - edges[-1]
        edges.append(edges[-1] + min(left, max(least, -(-left // (2 * threads)))))
    return edges


def in_threads(part: Callable[[int, int], None], n: int, threads: int, min_piece: int = 1) -> None:
    """``part(i0, i1)`` over the ranges of a split of ``[0, n)``, on the calling thread and ``threads − 1`` helper
    threads (``part`` is a compiled kernel that releases the GIL, writing disjoint parts of its outputs).  The
    range is cut in pieces of decreasing size (guided: each ``1/(2 threads)`` of what is left, at least
    ``min_piece`` items: a piece should last ~1 ms, so that the calls' Python overhead stays small), taken in turn
    by whichever thread is free (a thread slowed by other jobs of the machine takes fewer), so that the threads
    finish within about a smallest piece of each other (equal pieces left up to one large piece to the last
    thread); an exception on the calling thread (``KeyboardInterrupt``) stops the helpers after their current
    piece."""
    if threads <= 1 or n <= 1:
        part(0, n)
        return
    edges = guided_edges(n, threads, min_piece)
    pieces = len(edges) - 1
    todo = list(range(pieces - 1, -1, -1))
    lock = threading.Lock()

    def work() -> None:
        while True:
            with lock:
                if not todo:
                    return
                k = todo.pop()
            part(edges[k], edges[k + 1])

    futures = [_executor().submit(work) for _ in range(threads - 1)]
    try:
        work()
    finally:
        with lock:
            todo.clear()
        for f in futures:
            f.result()


def nu_default(X, b, eta, sheet=1):
    r"""Compiled :func:`jetgaudin.nu` (default branch times ``sheet``) for states ``X`` (B, 3N) with per-orbit
    ``b``, ``eta`` (B,) (:func:`._branch.nu_default_kernel`); equal to the NumPy branch rule to round-off.  Raises
    :class:`jetgaudin.BranchPointError` where the rule is undefined.  Large batches run in pieces on Numba's
    number of threads (:func:`in_threads`; the kernel releases the GIL; each orbit's value does not depend on the
    split)."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    eta = np.ascontiguousarray(eta, dtype=np.complex128)
    B = X.shape[0]
    nu = np.empty(B, np.complex128)
    ok = np.empty(B, np.bool_)
    kernel = kernel_module("_branch").nu_default_kernel
    work = 2 * (X.shape[1] // 3) + 1
    threads = _threads(B, BRANCH_ORBITS_PER_THREAD)
    if threads == 1:  # no slices (this is on the path of every short call)
        kernel(X, b, eta, float(sheet), np.empty(work), nu, ok)
    else:

        def part(i0: int, i1: int) -> None:
            kernel(X[i0:i1], b[i0:i1], eta[i0:i1], float(sheet), np.empty(work), nu[i0:i1], ok[i0:i1])

        in_threads(part, B, threads, BRANCH_ORBITS_PER_THREAD // 2)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise BranchPointError(
            f"orbit {i}: nu has a branch point on the vertical segment from Re(eta) to eta (or Re(eta) = 0); "
            "move eta or the state off the branch point"
        )
    return nu


def closed_form_orbit(x0, b, eta, nu0, steps):
    r"""Orbit (steps + 1, 9) of the N = 3 map by the corrected Appendix 1 closed form
    ``X̆ = Φ(s, t) X + X0(s, t)`` (:func:`jetgaudin.backlund.closed_form._two_point_core`, compiled with
    ``numba.njit``), with ``ℓ(η)``, ``ν1`` and the eigenvector as in the N = 3 route,
    ``s = −k2/k1`` and ``t = 2i Im(η) s̄/(1 + |s|²)``.  For benchmarks and cross-checks only: ``s`` is
    infinite where ``k1 = 0`` (the dressing kernels work projectively there).  Raises on a singular step."""
    S = check_counts(steps, 1, 1, 9)
    out = np.empty((S, 9))
    orbit = kernel_module("_closed").orbit_kernel()
    n = orbit(np.ascontiguousarray(x0, dtype=np.float64), float(b), complex(eta), complex(nu0), int(steps), out)
    if n != steps:
        raise status_error(STATUS_BRANCH, n)
    return out
