"""Whether a GPU route can run here, and Numba's CUDA target imported once (private; :mod:`jetgaudin.gpu`).

The GPU route needs the optional package ``numba-cuda`` (``pip install 'jetgaudin[gpu]'``), its CUDA bindings, and
an NVIDIA GPU with a CUDA driver -- or Numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, set before the first
import of ``numba.cuda``), on which the tests run the kernels' logic without a GPU.  Nothing here is imported
with :mod:`jetgaudin`; :func:`probe` is called only where a caller asks for the GPU (or ``AUTO`` weighs it).
"""

from __future__ import annotations

import functools
import os
from types import ModuleType
from typing import Any

import numpy as np

from .._errors import KernelSetupError

__all__ = ["GPUUnavailableError", "cuda", "probe", "available", "require", "simulator"]


class GPUUnavailableError(KernelSetupError):
    """``backend="gpu"`` was asked for where no GPU route can run (no ``numba-cuda``, no CUDA driver, no GPU)."""


def _asked() -> bool:
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def simulator() -> bool:
    """Whether Numba's CUDA simulator is on: ``NUMBA_ENABLE_CUDASIM`` set (and not ``0``) as Numba's configuration
    read it (numba-cuda's configuration is :mod:`numba.core.config`, read when ``numba`` is imported;
    :func:`cuda` re-reads it when the variable was set later, before ``numba.cuda`` is imported)."""
    import sys

    config = getattr(sys.modules.get("numba.core.config"), "ENABLE_CUDASIM", None)
    return _asked() if config is None else bool(config)


def cuda() -> ModuleType:
    """``numba.cuda``, imported on first use.  :class:`ImportError` when ``numba-cuda`` (or its CUDA bindings) is
    missing."""
    import sys

    if _asked() and "numba.cuda" not in sys.modules:
        from numba.core import config

        if not getattr(config, "ENABLE_CUDASIM", 0):  # set after ``import numba``: Numba re-reads its NUMBA_* variables
            config.reload_config()
    # numba-cuda (0.2x, on the lent H100/H200 image) still refers to ``np.row_stack``, which NumPy 2.5 removed: alias
    # it to ``np.vstack`` (the same function) before the import, until numba-cuda stops using it
    if not hasattr(np, "row_stack"):
        setattr(np, "row_stack", np.vstack)  # noqa: B010  (the name NumPy removed: a plain assignment trips NPY201)
    from numba import cuda as _cuda

    return _cuda


@functools.cache
def probe() -> tuple[bool, str]:
    """``(usable, what)``: whether the GPU route can run in this process and, in words, the device it runs on or
    why it cannot (one line).  Computed once per process (the CUDA driver is started on the first call)."""
    try:
        c = cuda()
    except ImportError as exc:
        return False, (f"the GPU backend needs the optional package numba-cuda and its CUDA bindings ({exc}); "
                       "install them with: pip install 'jetgaudin[gpu]'")
    if simulator():
        return True, "Numba's CUDA simulator (NUMBA_ENABLE_CUDASIM=1; for tests, not speed)"
    try:
        if not c.is_available():
            return False, ("the GPU backend found no NVIDIA GPU with a working CUDA driver on this machine; run on "
                           "a machine with one, or use backend 'compiled' (all CPU cores)")
        dev = c.get_current_device()
        name = dev.name.decode() if isinstance(dev.name, bytes) else str(dev.name)
        cc = dev.compute_capability
    except Exception as exc:  # the driver's own errors (CudaSupportError, CudaDriverError, ...)
        text = " ".join(str(exc).split())
        return False, f"the CUDA driver could not start ({text}); use backend 'compiled' (all CPU cores)"
    if tuple(cc) < (6, 0):
        return False, f"the GPU {name} has compute capability {cc[0]}.{cc[1]}; the GPU backend needs 6.0 or newer"
    return True, f"{name} (compute capability {cc[0]}.{cc[1]})"


def available() -> bool:
    """Whether the GPU route can run in this process (:func:`probe`)."""
    return probe()[0]


def require(what: str = "backend 'gpu'") -> Any:
    """``numba.cuda`` when the GPU route can run; :class:`GPUUnavailableError` (one line naming what is missing and
    the fix) otherwise."""
    ok, why = probe()
    if not ok:
        raise GPUUnavailableError(f"{what}: {why}")
    return cuda()
