"""The backend rule of the chain maps (every family), on top of :mod:`jetgaudin.maps`' one rule (private)."""

from __future__ import annotations

import numpy as np

from .._errors import InvalidParameterError
from ..maps import Backend, auto_gpu, check_gpu

__all__ = ["AUTO_MIN_WORK", "CHAIN_COMPILE_S", "resolve_backend"]

#: ``Backend.AUTO`` runs the compiled kernel from this many orbit-steps on (compiling it costs a few seconds
#: the first time, ~10^4 NumPy steps of a small chain; Numba caches it on disk afterwards)
AUTO_MIN_WORK = 20000
#: expected first-use compile time of the chain kernel (seconds, idle core of docs/performance.md's machine)
CHAIN_COMPILE_S = 10.0


def resolve_backend(backend: Backend, has_compiled: bool, X, steps: int, kind: str = "map",
                    has_gpu: bool = False) -> Backend:
    """The one rule of the chain maps (every family): ``NUMPY`` as given; ``COMPILED`` needs a compiled route
    (:class:`InvalidParameterError` otherwise); ``GPU`` a GPU route and a usable GPU (:func:`jetgaudin.maps.check_gpu`);
    ``AUTO`` is the GPU where :func:`jetgaudin.maps.auto_gpu` says so, else the compiled route from
    :data:`AUTO_MIN_WORK` orbit-steps on where the map has one, NumPy otherwise."""
    if backend is Backend.COMPILED and not has_compiled:
        raise InvalidParameterError(f"the {kind} map of this family has no compiled route; use backend='numpy' or "
                                    "'auto'")
    check_gpu(backend, has_gpu, f"the {kind} map of this family")
    if backend is not Backend.AUTO:
        return backend
    if auto_gpu(has_gpu, X, steps):
        return Backend.GPU
    work = int(steps) * max(1, int(np.prod(np.shape(X)[:-1])))
    return Backend.COMPILED if has_compiled and work >= AUTO_MIN_WORK else Backend.NUMPY
