"""Which compiled kernels a run needs, whether they are loaded, cached on disk or cold, the ``kernel="auto"``
choice, and compilation made visible: :func:`prepare` (the kernels of one run) and :func:`warmup` (all).

Numba caches a kernel next to its source, in ``kernels/__pycache__``, as ``<module>.<function>-<line>.py3X.nbi``
(index) and ``.nbc`` (code) files, or under ``NUMBA_CACHE_DIR`` / the user-wide cache directory when that is
not writable; :data:`KERNEL_MODULES` names the module of each kernel, hence its cache files.
"""

from __future__ import annotations

import glob
import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "KERNEL_MODULES",
    "CompileReport",
    "kernel_names",
    "kernels_state",
    "auto_kernel",
    "prepare",
    "prepare_call",
    "remote_notice",
    "warmup",
]

#: every cached kernel and the module (file stem) defining it; Numba's cache files start with ``<stem>.<name>-``
KERNEL_MODULES = {
    "run_orbit3": "_n3",
    "run_orbit": "_generic",
    "run_batch_generic": "_generic",
    "run_lanes3": "_lanes",
    "nu_default_kernel": "_branch",
}

#: "auto" uses the compiled kernels once they are loaded, and otherwise from this many orbit-steps on.
#: Measured (benchmarks/, part f): in a fresh process, importing Numba and loading the cached kernels costs
#: ~0.3 s, the time of ~1000 steps of the NumPy route (~3500 steps/s); once loaded, the compiled route is
#: faster from the first step (~0.1 µs per step against ~300 µs).
_AUTO_MIN_WORK = 2000
#: The same threshold when Numba's cache does not hold the kernels yet (first use after an install): compiling
#: them takes ~6 s here (measured: 5.9 s for the N = 3 orbit kernel and the branch rule), ~20000 NumPy steps.
_AUTO_MIN_WORK_COLD = 20000

#: expected first-use compile time of each kernel in seconds on an idle core of the AMD EPYC of docs/performance.md
#: (benchmarks/setup_parts.py measures them, each in a fresh process with an empty cache; a loaded machine takes
#: 2-3 times longer)
EXPECTED_COMPILE_S = {
    "run_orbit3": 4.0,
    "run_orbit": 6.0,
    "run_batch_generic": 5.0,
    "run_lanes3": 7.0,
    "nu_default_kernel": 2.5,
}
#: expected time to load one cached kernel (seconds)
EXPECTED_LOAD_S = 0.1


def kernel_names(n_state: int, batch: bool, batch_size: int = 1, specialise: bool = True) -> tuple[str, ...]:
    """The compiled functions a run calls: the stepping kernel for ``n_state`` = 3N components (a batch or one
    orbit) and the branch rule for ``ν1`` (one kernel for every batch size, large batches on the driver's threads;
    ``batch_size`` is kept for callers that name it)."""
    n3 = specialise and int(n_state) == 9
    step = ("run_lanes3" if n3 else "run_batch_generic") if batch else ("run_orbit3" if n3 else "run_orbit")
    return (step, "nu_default_kernel")


def _cache_dirs() -> list[str]:
    """Where Numba looks, in its order: ``NUMBA_CACHE_DIR`` alone when set; else next to the source (when
    writable), then the user-wide cache directory."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        return [user]
    in_tree = os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__")
    return [in_tree, os.path.expanduser("~/.cache/numba")]


#: the kernels found loaded in this process (they stay loaded: a dispatcher's ``signatures`` is looked at once, not
#: on every ``auto`` call, where it cost ~10 µs of the Appendix 2 call's ~60; issue 36)
_LOADED: set[str] = set()


def _loaded(name: str) -> bool:
    if name in _LOADED:
        return True
    mod = sys.modules.get(f"{__package__}.{KERNEL_MODULES[name]}")
    if getattr(getattr(mod, name, None), "signatures", None):
        _LOADED.add(name)
        return True
    return False


def _cached(name: str) -> bool:
    """Numba's cache holds ``name`` compiled from the present kernel sources: an index file, next to a stamp that
    records the sources' digest (:func:`._target.refresh_stale_cache` drops the files of a stale directory at the
    first use, so a cache without the right stamp means a compile)."""
    from ._target import STAMP_NAME, _state, sources_digest

    digest = _state.get("digest") or sources_digest()
    _state["digest"] = digest
    pattern = f"{KERNEL_MODULES[name]}.{name}-*.nbi"
    for d in _cache_dirs():
        for f in glob.glob(os.path.join(d, pattern)) + glob.glob(os.path.join(d, "**", pattern), recursive=True):
            try:
                with open(os.path.join(os.path.dirname(f), STAMP_NAME)) as stamp:
                    if stamp.read().strip() == digest:
                        return True
            except OSError:
                continue
    return False


def kernels_state(names: Sequence[str]) -> str:
    """``"loaded"`` (compiled or loaded in this process), ``"cached"`` (index files in Numba's cache) or ``"cold"``
    (to be compiled), for all of ``names`` (unknown names are cold).

    Looks at the files only (no Numba import): a wrong guess costs time, never correctness.
    """
    if any(n not in KERNEL_MODULES for n in names):
        return "cold"
    if all(_loaded(n) for n in names):
        return "loaded"
    return "cached" if all(_loaded(n) or _cached(n) for n in names) else "cold"


def auto_kernel(steps: int, n_state: int, batch_shape: Sequence[int] = ()) -> str:
    """The kernel ``kernel="auto"`` picks for ``steps`` steps of ``prod(batch_shape)`` orbits of ``n_state`` = 3N
    components: ``"compiled"`` when it pays off (kernels loaded; or cached and at least ``_AUTO_MIN_WORK``
    orbit-steps; or at least ``_AUTO_MIN_WORK_COLD`` orbit-steps), else ``"numpy"``."""
    size = max(1, math.prod(int(s) for s in batch_shape))
    work = int(steps) * size
    state = kernels_state(kernel_names(int(n_state), len(batch_shape) > 0, size))
    if state == "loaded":
        return "compiled"
    threshold = _AUTO_MIN_WORK if state == "cached" else _AUTO_MIN_WORK_COLD
    return "compiled" if work >= threshold else "numpy"


@dataclass(frozen=True)
class CompileReport:
    """What :func:`prepare` / :func:`warmup` did: the kernels, their state before (``"loaded"``, ``"cached"``,
    ``"cold"``) and the seconds spent compiling or loading them (0 when already loaded)."""

    kernels: tuple[str, ...]
    state: str
    seconds: float


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _quiet(msg: str) -> None:
    """Says nothing (loading cached kernels when ``announce_load`` is false)."""


def _compile_one(name: str, n_state: int) -> None:
    """Call kernel ``name`` on a dummy input of 0 steps through the driver's argument types (the signature a
    run uses), which compiles it or loads it from the cache."""
    from . import _drivers

    N = max(1, int(n_state) // 3)
    x = np.zeros(3 * N)
    x[2] = 1.0
    if name in ("run_orbit3", "run_orbit"):
        _drivers.iterate_single(x, 1.0, 2 + 1j, 1 + 0j, False, 0, 1, specialise=name == "run_orbit3")
    elif name in ("run_lanes3", "run_batch_generic"):
        _drivers.run_batch(x[None], [1.0], [2 + 1j], [1 + 0j], False, 0, 1, specialise=name == "run_lanes3")
    else:
        _drivers.kernel_module("_branch").nu_default_kernel(x[None], np.ones(1), np.full(1, 2 + 1j), 1.0,
                                                            np.empty(2 * N + 1), np.empty(1, np.complex128),
                                                            np.empty(1, np.bool_))


def _expected(names: Sequence[str], state: str) -> float:
    if state == "cached":
        return EXPECTED_LOAD_S * len(names)
    return sum(EXPECTED_COMPILE_S[n] for n in names if not (_loaded(n) or _cached(n)))


def _prepare_names(names: Sequence[str], n_state: int, notify: Callable[[str], None] | None,
                   announce_load: bool = True) -> CompileReport:
    state = kernels_state(names)
    if state == "loaded":
        return CompileReport(tuple(names), state, 0.0)
    say = _stderr if notify is None else notify
    if state == "cached" and not announce_load:  # a fraction of a second: timed, not announced
        say = _quiet
    what = "compiling the" if state == "cold" else "loading the cached"
    say(f"jetgaudin: {what} Numba kernels {', '.join(names)} (about {_expected(names, state):.2g} s"
        + (", once per installation)" if state == "cold" else ")") + " ...")
    t0 = time.perf_counter()
    for n in names:
        if not _loaded(n):
            _compile_one(n, 9 if n in ("run_orbit3", "run_lanes3") else n_state)
    dt = time.perf_counter() - t0
    say(f"jetgaudin: kernels ready in {dt:.1f} s")
    return CompileReport(tuple(names), state, dt)


def prepare_call(kernels: tuple[str, ...], loaded: bool, expected: float, call: Callable[[], None],
                 notify: Callable[[str], None] | None = None, cached: bool = False) -> CompileReport:
    """Make one compile visible for kernels outside this package (the chains' kernel): unless ``loaded``, say
    that ``kernels`` are being compiled or loaded with the ``expected`` seconds, run ``call()`` (which compiles
    them), and say when they are ready; ``cached`` (Numba's cache holds them): load them without a message.
    Returns a :class:`CompileReport` (state ``"loaded"``, ``"cached"`` or ``"compiled"``)."""
    if loaded:
        return CompileReport(tuple(kernels), "loaded", 0.0)
    if cached:
        t0 = time.perf_counter()
        call()
        return CompileReport(tuple(kernels), "cached", time.perf_counter() - t0)
    say = _stderr if notify is None else notify
    say(f"jetgaudin: compiling (or loading from Numba's cache) the kernels {', '.join(kernels)} (about "
        f"{expected:.2g} s the first time, once per installation) ...")
    t0 = time.perf_counter()
    call()
    dt = time.perf_counter() - t0
    say(f"jetgaudin: kernels ready in {dt:.1f} s")
    return CompileReport(tuple(kernels), "compiled", dt)


def remote_notice(n_state: int = 9, batch_size: int = 2, *, specialise: bool = True) -> str:
    """What a run on a Dask cluster says before its first tasks: the workers load or compile the stepping kernel
    themselves, on their first task, each with its own Numba cache (``jetgaudin warmup`` on a worker compiles it
    ahead)."""
    step = kernel_names(n_state, True, batch_size, specialise)[0]
    return (f"jetgaudin: the Dask workers compile (or load from their Numba cache) the kernel {step} on their "
            f"first task: about {EXPECTED_COMPILE_S[step]:.2g} s on a worker where it is not cached (run "
            "`jetgaudin warmup` on the workers to compile it ahead)")


def prepare(n_state: int = 9, batch_size: int | None = None, *, specialise: bool = True,
            notify: Callable[[str], None] | None = None, step: bool = True,
            announce_load: bool = True) -> CompileReport:
    """Load or compile the kernels a compiled run of ``batch_size`` orbits (``None``: one orbit through
    ``iterate_single``) of ``n_state`` = 3N components needs, saying so first with the expected time
    (``notify(message)``; default: a line on stderr; nothing is said when they are already loaded).

    Call it before timing a run: the time it returns is the compile/load time, to be reported apart from the
    stepping rate.  ``step=False``: the branch rule only (a Dask run: the workers compile the stepping kernel,
    :func:`remote_notice`).  ``announce_load=False``: kernels found in Numba's cache are loaded without a message
    (a fraction of a second; the time is still returned); only a compile is announced.  Returns a
    :class:`CompileReport`.
    """
    names = kernel_names(n_state, batch_size is not None, batch_size or 1, specialise)
    return _prepare_names(names if step else names[1:], n_state, notify, announce_load)


def warmup(notify: Callable[[str], None] | None = None) -> CompileReport:
    """Compile (or load) every cached kernel once: the N = 3 and generic single-orbit routes, the lanes, the
    generic batch and both branch-rule kernels (the Appendix 1 closed form of the benchmarks is compiled on
    use and not cached).  Returns a :class:`CompileReport` (``state``: the state before, of all of them)."""
    return _prepare_names(tuple(KERNEL_MODULES), 3, notify)
