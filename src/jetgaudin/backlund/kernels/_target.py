"""Numba's code-generation target for the kernels, set by an explicit call (:func:`configure`) before the first
kernel module is imported (the drivers do it at the kernels' first use; importing the package does not)."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from ..._errors import KernelSetupError

__all__ = ["configure", "prefer_256_bit", "refresh_stale_cache", "sources_digest", "clean_cache_dir"]

#: the modules holding compiled code; a kernel inlines blocks of the others
KERNEL_SOURCES = ("_status.py", "_scalar.py", "_generic.py", "_n3.py", "_lanes.py", "_branch.py")

_state: dict[str, Any] = {}


def _prefer_256_bit_vectors() -> bool:
    """Whether to ask LLVM for 256-bit vectors on AVX-512 hosts (the target feature ``prefer-256-bit``): no longer.

    It was requested on AMD EPYC (znver4) hosts, where LLVM otherwise picks 512-bit vectors, because the lanes
    kernel of that time ran 3.7e7 against 2.1e7 orbit-steps/s per thread with it.  The select-free lanes of issue 14
    reverse this: on a znver4 host (issue 36, docs/performance.md) one thread runs 8.2e7-8.6e7 with LLVM's own
    512-bit choice against 6.6e7-7.1e7 with 256-bit vectors (alternated processes).  On Intel AVX-512 hosts LLVM
    already prefers 256 bits.  So Numba's default target is kept everywhere (the arithmetic, hence the bits, does
    not depend on the vector width: IEEE operations, explicit fused multiply-adds, no contraction).
    """
    return False


def sources_digest() -> str:
    """SHA-256 of the kernel sources (:data:`KERNEL_SOURCES`) together."""
    here = Path(__file__).resolve().parent
    return hashlib.sha256(b"".join((here / f).read_bytes() for f in KERNEL_SOURCES)).hexdigest()


STAMP_NAME = "jetgaudin-kernel-sources.sha256"


def clean_cache_dir(path: str, digest: str) -> int:
    """Remove the kernels' cache files (``<module>.*.nbi``/``.nbc``) from the cache directory ``path`` unless its
    stamp file records ``digest``; then record it.  Returns the number of files removed (0 if unwritable)."""
    stamp = Path(path) / STAMP_NAME
    removed = 0
    try:
        if stamp.is_file() and stamp.read_text().strip() == digest:
            return 0
        for f in KERNEL_SOURCES:
            for p in Path(path).glob(f"{f[:-3]}.*.nb[ic]"):
                p.unlink()
                removed += 1
        Path(path).mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest + "\n")
    except OSError:
        pass
    return removed


def refresh_stale_cache(module: Any) -> int:
    """Drop cached kernels compiled from other kernel sources than the present ones, before the first call.

    Numba keys a cached function by the content of the file that defines it only, so after an edit of
    ``_scalar.py`` alone (or an upgrade that changes it) the cached ``_n3``/``_lanes``/... kernels, which inline its
    blocks, would still be loaded.  Each cache directory the just-imported kernel ``module`` uses holds a stamp with
    the digest of all kernel sources; on a mismatch the kernels' cache files there are removed (they are then
    recompiled).  Returns the number of files removed."""
    digest = _state.get("digest") or sources_digest()
    _state["digest"] = digest
    dirs = {getattr(getattr(v, "_cache", None), "_cache_path", None) for v in vars(module).values()}
    return sum(clean_cache_dir(d, digest) for d in dirs if isinstance(d, str))


def configure() -> bool:
    """Apply the target configuration once per process (idempotent); returns whether 256-bit vectors were
    requested.  Must run before any kernel module (``_scalar``, ``_generic``, ``_n3``, ``_lanes``, ``_branch``)
    is imported: creating their dispatchers creates Numba's CPU target."""
    if "prefer_256_bit" not in _state:
        try:
            import numba  # noqa: F401  (Numba validates its NUMBA_* settings at import)
        except ValueError as exc:  # e.g. NUMBA_NUM_THREADS=0: "Number of threads specified must be > 0."
            raise KernelSetupError(
                f"Numba cannot start: {exc} Check the NUMBA_* environment variables (NUMBA_NUM_THREADS: a positive "
                "integer, or unset)"
            ) from None
        _state["prefer_256_bit"] = _prefer_256_bit_vectors()
    return _state["prefer_256_bit"]


def prefer_256_bit() -> bool | None:
    """Whether :func:`configure` requested 256-bit vectors (``None``: not configured yet in this process)."""
    return _state.get("prefer_256_bit")
