r"""Compiled (Numba) kernels for the real two-point Bäcklund map (Section 6.2, Appendix 1).

Modules (each one concern):

- :mod:`._target`: Numba's code-generation target, applied by an explicit call (:func:`configure`) at the
  kernels' first use, never at import;
- :mod:`._status`: the status codes kernels return instead of raising, and the typed error of each;
- :mod:`._scalar`: scalar building blocks (complex arithmetic, eigenvector, ``M0``, products of ``R(λ)``,
  selects, integrals, drift);
- :mod:`._generic`: the generic route (any N), one orbit and a batch in a ``prange`` loop;
- :mod:`._n3`: the N = 3 route, unrolled in scalars (shorter dependency chain);
- :mod:`._lanes`: N = 3 ensembles, ``LANES`` orbits in lock-step (SIMD across orbits), ranges of blocks run on
  threads by the driver (:func:`._drivers.in_threads`);
- :mod:`._closed`: the Appendix 1 closed form, compiled, for benchmarks and cross-checks;
- :mod:`._branch`: the default branch of ``ν(η)`` (the branch rule of :func:`jetgaudin.nu`) for the first step;
- :mod:`._flops`: hand-counted operations per step;
- :mod:`._drivers`: the Python drivers (validate counts, allocate, call, split large batches across threads,
  raise typed errors);
- :mod:`._select`: which kernels a run needs, loaded / cached / cold, the ``kernel="auto"`` choice, and
  visible compilation (:func:`prepare`, :func:`warmup`).

Importing this package imports neither Numba nor a kernel module; the drivers do at their first call.

**Reproducibility.** Arithmetic is IEEE without ``fastmath`` (no reassociation, no automatic FMA contraction);
the N = 3 blocks write their fused multiply-adds explicitly (:func:`._scalar._fma`, LLVM's ``llvm.fma``, rounded
once on every target: an FMA instruction, or the C library's correctly rounded ``fma`` where the processor has
none), so a kernel gives the same bits in a single-orbit run and as a member of a parallel ensemble
(:func:`run_ensemble`), and the same bits whether or not the processor has FMA instructions
(``tests/test_kernels.py``).
Kernels never raise: they return a status code (``STATUS_*``) and the failing step; the drivers raise
:class:`jetgaudin.SingularStepError` / :class:`jetgaudin.BranchPointError`.  The claims each route makes about
the others (bitwise equal, or equal to a stated tolerance per step) are listed and checked in
``tests/test_routes.py``.
"""

from __future__ import annotations

from typing import Any

from ._drivers import (
    INT64_MAX,
    batch_kernel,
    check_counts,
    closed_form_orbit,
    iterate_batch,
    iterate_single,
    kernel_module,
    nu_default,
    run_batch,
    run_ensemble,
    saved_count,
    single_kernel,
)
from ._flops import flops_per_step
from ._select import (
    KERNEL_MODULES,
    CompileReport,
    auto_kernel,
    kernel_names,
    kernels_state,
    prepare,
    prepare_call,
    remote_notice,
    warmup,
)
from ._status import STATUS_BRANCH, STATUS_MESSAGES, STATUS_NONFINITE, STATUS_OK, STATUS_RESIDUAL, status_error
from ._target import configure

__all__ = [
    "STATUS_OK",
    "STATUS_BRANCH",
    "STATUS_RESIDUAL",
    "STATUS_NONFINITE",
    "STATUS_MESSAGES",
    "INT64_MAX",
    "KERNEL_MODULES",
    "CompileReport",
    "auto_kernel",
    "batch_kernel",
    "check_counts",
    "closed_form_orbit",
    "configure",
    "flops_per_step",
    "iterate_batch",
    "iterate_single",
    "kernel_module",
    "kernel_names",
    "kernels_state",
    "nu_default",
    "prepare",
    "prepare_call",
    "remote_notice",
    "run_batch",
    "run_ensemble",
    "saved_count",
    "single_kernel",
    "status_error",
    "warmup",
]

#: compiled objects reachable as attributes (imported on first access, after :func:`configure`)
_LAZY = {
    "run_orbit": "_generic",
    "run_batch_generic": "_generic",
    "run_orbit3": "_n3",
    "run_lanes3": "_lanes",
    "LANES": "_lanes",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(kernel_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
