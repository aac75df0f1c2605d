"""Numba's code-generation target for the kernels, set by an explicit call (:func:`configure`) before the first
kernel module is imported (the drivers do it at the kernels' first use; importing the package does not)."""

from __future__ import annotations

__all__ = ["configure", "prefer_256_bit"]

_state: dict[str, bool] = {}


def _prefer_256_bit_vectors() -> bool:
    """Ask LLVM for 256-bit vectors on AVX-512 hosts (the target feature ``prefer-256-bit``, a tuning hint).

    Measured on an AMD EPYC (znver4) host: the lock-step ensemble kernel runs 3.7e7-3.8e7 orbit-steps/s per thread
    with it against 2.1e7-2.3e7 with LLVM's default 512-bit choice there (on the Intel Xeon of
    docs/performance.md LLVM already picks 256 bits).  The arithmetic is unchanged (IEEE operations, no
    contraction), so the bits are the same.  Applied only when Numba has not created its CPU target yet in this
    process and the user has set neither NUMBA_CPU_NAME nor NUMBA_CPU_FEATURES; it then holds for the process's
    Numba code (Numba reads the features once, when its CPU target context is created).
    """
    import numba.core.config as config
    from numba.core import registry

    if config.CPU_FEATURES is not None or config.CPU_NAME is not None or "target_context" in vars(registry.cpu_target):
        return False
    try:
        import llvmlite.binding as ll

        features = ll.get_host_cpu_features()
    except (ImportError, RuntimeError):
        return False
    if not features.get("avx512f", False):
        return False
    config.CPU_FEATURES = features.flatten() + ",+prefer-256-bit"
    return True


def configure() -> bool:
    """Apply the target configuration once per process (idempotent); returns whether 256-bit vectors were
    requested.  Must run before any kernel module (``_scalar``, ``_generic``, ``_n3``, ``_lanes``, ``_branch``)
    is imported: creating their dispatchers creates Numba's CPU target."""
    if "prefer_256_bit" not in _state:
        _state["prefer_256_bit"] = _prefer_256_bit_vectors()
    return _state["prefer_256_bit"]


def prefer_256_bit() -> bool | None:
    """Whether :func:`configure` requested 256-bit vectors (``None``: not configured yet in this process)."""
    return _state.get("prefer_256_bit")
