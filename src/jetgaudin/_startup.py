"""The command line's start-up guard (private): between the start of the process and :func:`jetgaudin.cli.entry`
(about 0.3 s of imports: NumPy, SciPy, h5py, Typer), a SIGINT/SIGTERM or an import that fails for lack of memory
(``ulimit -v``) would print a traceback.  When the process *is* the command line (``jetgaudin ...`` or
``python -m jetgaudin ...``, read from :data:`sys.orig_argv`), importing this module installs

* SIGINT/SIGTERM handlers that print ``jetgaudin: interrupted`` and end the process at once with 130/143 (nothing
  has been written yet), and
* a :data:`sys.excepthook` that prints one line for an exception escaping the imports (``MemoryError``, an
  ``ImportError`` "failed to map segment" under ``ulimit -v``), exit 1; under an address-space limit, one OpenBLAS
  thread (``OPENBLAS_NUM_THREADS=1`` unless set: OpenBLAS's start-up otherwise hangs in ``mmap`` retries);

:func:`release` (called by :func:`jetgaudin.cli.entry`) restores both.  In any other process (a library user, the
tests) it does nothing.  Standard library only: it must be importable first.
"""

from __future__ import annotations

import os
import signal
import sys

_old: dict = {}


def is_command_line() -> bool:
    """Whether this process was started as ``jetgaudin`` (the console script) or ``python -m jetgaudin``."""
    argv = list(getattr(sys, "orig_argv", sys.argv))
    for i, a in enumerate(argv[:-1]):
        if a == "-m" and argv[i + 1] in ("jetgaudin", "jetgaudin.cli"):
            return True
        if a.startswith("-") and not a.startswith("-m"):
            continue
        if a.startswith("-m") and a[2:] in ("jetgaudin", "jetgaudin.cli"):
            return True
    return len(argv) >= 2 and os.path.basename(argv[1]) == "jetgaudin"


def _interrupted(signum: int, _frame: object) -> None:
    try:
        os.write(2, b"jetgaudin: interrupted\n")
    finally:
        os._exit(128 + signum)


def address_space_limit() -> int | None:
    """The process's address-space limit in bytes (``ulimit -v``), or ``None`` when unlimited."""
    import resource

    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return None if soft == resource.RLIM_INFINITY else int(soft)


def out_of_memory(exc: BaseException) -> str | None:
    """One line for an exception that means "out of memory" (a ``MemoryError``, ``ENOMEM``, or a shared library —
    NumPy's, HDF5's, LLVM's (``libllvmlite.so``) — that could not be mapped under ``ulimit -v``), else ``None``."""
    import errno

    text = " ".join(str(exc).split())
    limit = address_space_limit()
    load = any(s in text for s in ("map segment", "shared object", "libllvmlite", "Cannot allocate memory"))
    if not (isinstance(exc, MemoryError) or getattr(exc, "errno", None) == errno.ENOMEM
            or (load and (limit is not None or isinstance(exc, (ImportError, OSError))))
            or (isinstance(exc, RuntimeError) and "can't start new thread" in text)
            or (limit is not None and isinstance(exc, SystemError))):
        return None
    where = (f"under the address-space limit ulimit -v {limit // 1024} kB" if limit is not None
             else "(check ulimit -v and the free memory)")
    return (f"out of memory {where}: {type(exc).__name__} ({text[:160]}); the command line needs about 0.5 GB of "
            "address space (the compiled kernels' LLVM more): raise the limit")


def _hook(exc_type: type[BaseException], exc: BaseException, tb: object) -> None:
    if issubclass(exc_type, KeyboardInterrupt):
        _interrupted(signal.SIGINT, None)
    text = " ".join(f"{exc_type.__name__}: {exc}".split())[:300]
    memory = out_of_memory(exc)
    line = f"cannot start: {memory}" if memory else f"cannot start: {text}"
    jit_off = os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")
    if jit_off and not memory:  # a setting, not a failure: refused as NUMBA_NUM_THREADS=0 is (exit 2)
        line = (f"NUMBA_DISABLE_JIT={os.environ['NUMBA_DISABLE_JIT']} is not supported: jetgaudin's kernels are "
                f"built with Numba's compiler ({text[:120]}); unset NUMBA_DISABLE_JIT")
    os.write(2, f"jetgaudin: error: {line}\n".encode(errors="replace"))
    os._exit(2 if jit_off and not memory else 1)


def install() -> None:
    if _old or not is_command_line():
        return
    import resource

    if resource.getrlimit(resource.RLIMIT_AS)[0] != resource.RLIM_INFINITY:
        # under an address-space limit (ulimit -v) OpenBLAS's thread start-up (loaded with NumPy/SciPy) retries its
        # per-thread 32 MB buffers in mmap without end once memory is short: measured, ulimit -v 200 MB hung the
        # command; with one BLAS thread it fails (one line) or runs.  The kernels' threads are Numba's, not BLAS's.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    _old["hook"] = sys.excepthook
    sys.excepthook = _hook
    for s in (signal.SIGINT, signal.SIGTERM):
        _old[s] = signal.signal(s, _interrupted)


def release() -> None:
    """Restore the exception hook and the signal handlers in place before :func:`install`."""
    if not _old:
        return
    sys.excepthook = _old.pop("hook")
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, _old.pop(s))


install()
