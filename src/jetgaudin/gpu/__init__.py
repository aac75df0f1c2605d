r"""The GPU route of the maps: ``backend="gpu"`` (issue 28; ``docs/performance.md``, the GPU section).

One thread per orbit runs the CPU route's own orbit loop, compiled for the GPU by Numba's CUDA target
(:mod:`jetgaudin.gpu._kernels`): the top's real two-point map (the real N = 3 form and the generic route, any N <=
16), the chains' two-point map of every family and the su(3) chains' map ``B^{(r)}_η`` (issue 32). The same contract
as the compiled CPU route -- ``save_every``, the branch rule (``ν1`` at the start by the compiled rule on the host,
continued by Newton steps on the device), the status and failing step of every orbit, per-orbit ``b`` and ``η``, a
split run equal to the unsplit one bit for bit on the same device -- and the same orbits to round-off (NVVM's
contraction of products and sums into fused operations is the only difference; measured per step in
``docs/performance.md``).  The su(3) route reports a status per orbit (non-finite at the end) without the failing
step, and has run on the simulator only: its difference from the CPU route on a device is not measured.

Needs the optional ``numba-cuda`` (``pip install 'jetgaudin[gpu]'``) and an NVIDIA GPU; without them
``backend="gpu"`` is a :class:`GPUUnavailableError` naming what is missing, and ``backend="auto"`` never picks the GPU.
``auto`` picks it where one is present, for at least :data:`GPU_MIN_ORBITS` orbits and :data:`GPU_MIN_WORK` orbit-steps.

>>> import jetgaudin.gpu as gpu
>>> isinstance(gpu.available(), bool)
True
"""

from __future__ import annotations

from ._device import GPUUnavailableError, available, probe, require
from ._drivers import GPUReport, iterate_batch, last_timing, prepare, run_batch, run_chain, run_sun_batch

__all__ = ["GPUUnavailableError", "GPUReport", "available", "probe", "require", "iterate_batch", "run_batch",
           "run_chain", "run_sun_batch", "prepare", "last_timing", "GPU_MIN_WORK", "GPU_MIN_ORBITS", "auto_uses_gpu"]

#: ``backend="auto"`` takes the GPU (where one is present) from this many orbit-steps in one call on.  Measured on an
#: H200 beside its host's 16 Xeon cores (``docs/performance.md``, the GPU section): with the copies, the GPU is
#: faster from 65536 orbits × 100 steps on (1.2×; 13–20× at 1000 steps), but its kernel is compiled once per
#: process (2.7 s; Numba keeps no disk cache of it), which the 16 cores' lanes match at ~1.6·10⁹ orbit-steps
GPU_MIN_WORK = 2 * 10**9
#: ... and from this many orbits on (one thread per orbit: a few orbits leave the GPU idle, however long they run)
GPU_MIN_ORBITS = 2**16


def auto_uses_gpu(orbits: int, steps: int) -> bool:
    """Whether ``backend="auto"`` runs ``steps`` steps of ``orbits`` orbits on the GPU: a GPU is usable here
    (:func:`available`, never the simulator), at least :data:`GPU_MIN_ORBITS` orbits and :data:`GPU_MIN_WORK`
    orbit-steps.  Nothing is imported or started below those sizes."""
    from ._device import simulator

    if int(orbits) < GPU_MIN_ORBITS or int(orbits) * int(steps) < GPU_MIN_WORK or simulator():
        return False
    return available()
