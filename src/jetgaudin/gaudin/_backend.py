r"""The backend rule of the chain maps (every family), on top of :mod:`jetgaudin.maps`' one rule (private).

``AUTO`` is a choice of cost (both routes keep the integrals at round-off): the route whose *estimated* time is
smaller, with

* NumPy: ``steps · (F + B·G) · s(M)`` — a fixed cost per step (one vectorised step of the batch) and a cost per
  orbit, per family (:data:`NUMPY_STEP_S`), ``s(M) = (M + 1)/4`` for a chain of ``M`` components;
* compiled: the kernels' set-up (nothing when loaded in this process, :data:`LOAD_S` when Numba's cache holds them,
  :data:`COMPILE_S` when they must be compiled; importing Numba first, :data:`NUMBA_IMPORT_S`, when it is not
  imported yet) plus :data:`CALL_S` per call and ``B · steps · C · s(M)`` (:data:`COMPILED_STEP_S`).

The constants were measured by ``benchmarks/auto_route.py`` (which also prints, per family, orbit and ensemble, the
time of the route ``AUTO`` picks against the fastest one); a route is chosen only when its estimate is the smaller,
so that estimates within a factor √3 of the true times never pick a route 3× slower than the other
(``tests/test_auto_route.py`` checks the rule, family by family).
"""

from __future__ import annotations

import glob
import os
import sys
from dataclasses import dataclass

import numpy as np

from .._errors import InvalidParameterError
from ..maps import Backend, auto_gpu, check_gpu

__all__ = ["AUTO_MIN_WORK", "CHAIN_COMPILE_S", "RouteCost", "auto_notice", "exact_route_costs", "kernel_state",
           "resolve_backend", "route_costs"]

#: the work (orbit-steps) :meth:`ChainTwoPointBacklund.prepare_kernels` compiles for when called without arguments
AUTO_MIN_WORK = 20000
#: expected first-use compile time of the chain kernel (seconds, idle core of docs/performance.md's machine)
CHAIN_COMPILE_S = 10.0

#: NumPy route: seconds per step, ``(fixed per step, per orbit)`` at ``M = 3`` (×``(M + 1)/4`` for ``M``
#: components), measured by ``benchmarks/auto_route.py`` on the project's shared 2-vCPU machine (1.5x the quiet
#: values: a loaded machine slows the NumPy route more than the estimates of the compile)
NUMPY_STEP_S = {"rational": (7e-4, 3e-6), "trigonometric": (1e-3, 4e-6), "elliptic": (4e-3, 3e-5)}
#: a family without an entry here (a new one) is costed as the elliptic one, the slowest
_DEFAULT_NUMPY = NUMPY_STEP_S["elliptic"]
#: compiled route: seconds per orbit-step at ``M = 3`` (×``(M + 1)/4``), and per call (the branch rule at the first
#: state, the constants, the copies)
COMPILED_STEP_S = 1e-6
CALL_S = 2e-3
#: compile time of the kernels a call needs in a fresh cache (seconds): the rational chain kernel (one orbit or a loop
#: over the batch's orbits), the family kernel for one orbit, and its batch kernel (``prange``: slower to compile);
#: each includes the compiled branch rule
COMPILE_S = {"rational": 5.5, "orbit": 7.0, "batch": 27.0}
#: time to load the same kernels from Numba's cache (seconds), and to import Numba when it is not imported yet
LOAD_S = {"rational": 0.3, "orbit": 0.3, "batch": 0.6}
NUMBA_IMPORT_S = 0.5

#: the compiled functions each group of kernels consists of, as ``(module stem, function)``
_KERNELS = {
    "rational": (("_kernels", "run_orbit"), ("_family_kernel", "branch_rule")),
    "orbit": (("_family_kernel", "run_orbit"), ("_family_kernel", "branch_rule")),
    "batch": (("_family_kernel", "run_batch"), ("_family_kernel", "branch_rule")),
}


def _group(family, batch: int) -> str:
    if getattr(family, "uniform", False):
        return "rational"
    return "batch" if batch > 1 else "orbit"


def _module(name: str) -> str:
    """The full module name of ``name``: a module of this package by its stem (``_family_kernel``), else as given
    (``jetgaudin._exact_chain_kernels``)."""
    return name if name.startswith("jetgaudin.") else f"{__package__}.{name}"


def _loaded(name: str, func: str) -> bool:
    """The compiled function ``func`` of the module ``name`` (:func:`_module`) is compiled or loaded in this
    process."""
    return bool(getattr(getattr(sys.modules.get(_module(name)), func, None), "signatures", None))


def _cached(name: str, func: str) -> bool:
    """Numba's cache holds an index file of ``func`` of the module ``name`` (:func:`_module`; next to the sources,
    under ``NUMBA_CACHE_DIR`` when set, or the user-wide cache); a wrong guess costs time, never correctness."""
    parts = _module(name).split(".")
    user = os.environ.get("NUMBA_CACHE_DIR")
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # jetgaudin/
    dirs = [user] if user else [os.path.join(package, *parts[1:-1], "__pycache__"),
                                os.path.expanduser("~/.cache/numba")]
    pattern = f"{parts[-1]}.{func}-*.nbi"
    return any(glob.glob(os.path.join(d, pattern)) or glob.glob(os.path.join(d, "**", pattern), recursive=True)
               for d in dirs)


def _module_state(need) -> str:
    """``"loaded"``, ``"cached"`` or ``"cold"`` (:func:`kernel_state`) of the compiled functions ``need``, pairs
    ``(module, function)`` (:func:`_module`)."""
    if all(_loaded(*k) for k in need):
        return "loaded"
    return "cached" if all(_loaded(*k) or _cached(*k) for k in need) else "cold"


#: the exact chain step (:class:`jetgaudin.ChainExactFlow`): the compiled functions of its route per family (the
#: solve and the loop of the maps), their first-use compile time in a fresh cache (seconds: 44.6, 39.6, 18.4 measured
#: on the project's 2-vCPU AMD EPYC, ``NUMBA_CACHE_DIR`` empty, each family in a new process) and their load time
#: from the cache (0.4–0.5 s measured)
_EXACT_KERNELS = {
    "elliptic": (("jetgaudin._exact_chain_kernels", "solve_orbit_numerical"),
                 ("jetgaudin._exact_chain_loop", "rows_family")),
    "trigonometric": (("jetgaudin._exact_chain_kernels", "newton"),
                      ("jetgaudin._exact_chain_kernels", "branch_uniformized"),
                      ("jetgaudin._exact_chain_loop", "rows_family")),
    "rational": (("jetgaudin._exact_chain_kernels", "newton"), ("jetgaudin._exact_chain_loop", "rows_rational")),
}
EXACT_COMPILE_S = {"elliptic": 45.0, "trigonometric": 40.0, "rational": 18.0}
EXACT_LOAD_S = 0.6
#: the exact step's set-up per orbit and run (the parameter solve and the maps' 40-digit constants, once: the run
#: layer binds the flow at X0, ``ChainExactFlow.bind_run``; seconds): the NumPy route's and the compiled route's
#: (measured as above, ~1.5× the quiet values); its steps cost ``k`` map steps each (:data:`NUMPY_STEP_S`,
#: :data:`COMPILED_STEP_S`)
EXACT_SETUP_S = {"elliptic": (7e-2, 7e-3), "trigonometric": (2e-2, 5e-3), "rational": (1e-2, 2e-3)}


def exact_route_costs(family, M: int, batch: int, steps: int, maps: int, substeps: int = 1,
                      state: str | None = None) -> RouteCost:
    """:class:`RouteCost` of a run of ``steps`` exact steps (``substeps`` sub-steps of ``maps`` two-point maps each)
    of ``batch`` orbits of a chain of ``M`` components: per orbit the set-up :data:`EXACT_SETUP_S` (once: the run
    binds the flow), per map step the maps' costs (:data:`NUMPY_STEP_S` per orbit: the exact step runs its orbits
    one by one; :data:`COMPILED_STEP_S`), and the compiled route's compile or load (:data:`EXACT_COMPILE_S`,
    :data:`EXACT_LOAD_S`; ``state`` as found now by default).  The run layer's own cost per call is the same on
    both routes (left out).  A family without measured constants is costed as the elliptic one."""
    name = getattr(family, "name", "")
    name = name if name in _EXACT_KERNELS else "elliptic"
    batch, steps = max(1, int(batch)), max(0, int(steps))
    state = _module_state(_EXACT_KERNELS[name]) if state is None else state
    scale = (int(M) + 1) / 4
    map_steps = steps * max(1, int(substeps)) * max(1, int(maps))
    fixed, per_orbit = NUMPY_STEP_S.get(name, _DEFAULT_NUMPY)
    np_setup, c_setup = EXACT_SETUP_S[name]
    numpy_s = batch * (np_setup + map_steps * (fixed + per_orbit) * scale)
    setup = 0.0 if state == "loaded" else (EXACT_LOAD_S if state == "cached" else EXACT_COMPILE_S[name])
    if state != "loaded" and "numba" not in sys.modules:
        setup += NUMBA_IMPORT_S
    compiled_s = setup + batch * (c_setup + map_steps * COMPILED_STEP_S * scale)
    return RouteCost(numpy_s, compiled_s, setup, state)


def kernel_state(family, batch: int = 1) -> str:
    """``"loaded"`` (compiled or loaded in this process), ``"cached"`` (in Numba's cache) or ``"cold"`` (to be
    compiled): the chain kernels a compiled call of ``batch`` orbits of ``family`` needs.  Looks at modules and files
    only (imports nothing)."""
    return _module_state(_KERNELS[_group(family, batch)])


@dataclass(frozen=True)
class RouteCost:
    """The estimated seconds of ``steps`` steps of ``batch`` orbits on each route (module docstring): ``numpy``;
    ``compiled`` (set-up included); ``setup`` (the compiled route's compile or load, part of ``compiled``) and the
    kernels' ``state``."""

    numpy: float
    compiled: float
    setup: float
    state: str


def route_costs(family, M: int, batch: int, steps: int, state: str | None = None) -> RouteCost:
    """:class:`RouteCost` of ``steps`` steps of ``batch`` orbits of a chain of ``M`` components of ``family`` (a
    :class:`jetgaudin.families.Family`; ``None`` or a family without measured constants: costed as the slowest);
    ``state``: the kernels' state (default: :func:`kernel_state`, as found now)."""
    batch = max(1, int(batch))
    steps = max(0, int(steps))
    state = kernel_state(family, batch) if state is None else state
    scale = (int(M) + 1) / 4
    fixed, per_orbit = NUMPY_STEP_S.get(getattr(family, "name", ""), _DEFAULT_NUMPY)
    numpy_s = steps * (fixed + batch * per_orbit) * scale
    group = _group(family, batch)
    setup = 0.0 if state == "loaded" else (LOAD_S if state == "cached" else COMPILE_S)[group]
    if state != "loaded" and "numba" not in sys.modules:
        setup += NUMBA_IMPORT_S
    compiled_s = setup + (CALL_S if steps else 0.0) + batch * steps * COMPILED_STEP_S * scale
    return RouteCost(numpy_s, compiled_s, setup, state)


def resolve_backend(backend: Backend, has_compiled: bool, X, steps: int, kind: str = "map",
                    has_gpu: bool = False, family=None, state: str | None = None) -> Backend:
    """The one rule of the chain maps (every family): ``NUMPY`` as given; ``COMPILED`` needs a compiled route
    (:class:`InvalidParameterError` otherwise); ``GPU`` a GPU route and a usable GPU (:func:`jetgaudin.maps.check_gpu`);
    ``AUTO`` is the GPU where :func:`jetgaudin.maps.auto_gpu` says so, else, where the map has a compiled route, the
    route of the smaller estimated time (:func:`route_costs`: the compiled one once its kernels are loaded), NumPy
    otherwise.  ``family``: the chain's family (``None``: costed as the slowest); ``state``: the kernels' state
    (default: as found now, :func:`kernel_state`)."""
    if backend is Backend.COMPILED and not has_compiled:
        raise InvalidParameterError(f"the {kind} map of this family has no compiled route; use backend='numpy' or "
                                    "'auto'")
    check_gpu(backend, has_gpu, f"the {kind} map of this family")
    if backend is not Backend.AUTO:
        return backend
    if auto_gpu(has_gpu, X, steps):
        return Backend.GPU
    if not has_compiled:
        return Backend.NUMPY
    cost = _costs(X, steps, family, state)
    return Backend.COMPILED if cost.compiled <= cost.numpy else Backend.NUMPY


def _costs(X, steps, family, state) -> RouteCost:
    shape = np.shape(X)
    return route_costs(family, max(1, shape[-1] // 3) if shape else 1, int(np.prod(shape[:-1])) if shape else 1,
                       0 if steps is None else int(steps), state)


def auto_notice(m, X, steps) -> str | None:
    """One line naming the route ``AUTO`` takes for ``steps`` steps of ``X`` where it matters: the NumPy route of a
    map that has a compiled one (with both estimates, and the option that forces the other route); ``None`` when the
    map's backend is not ``AUTO``, has one route only, or takes the compiled route (a compile is announced by
    :meth:`prepare_kernels` itself)."""
    if getattr(m, "backend", None) is not Backend.AUTO or not getattr(m, "has_compiled", False):
        return None
    if m.resolved_backend(X, steps) is not Backend.NUMPY:
        return None
    fam = getattr(getattr(m, "model", None), "family", None)
    own = getattr(m, "route_costs", None)  # a map with its own estimates (the exact chain step)
    cost = own(X, steps) if callable(own) else _costs(np.asarray(X), steps, fam, None)
    why = {"cold": "compiling its kernel", "cached": "loading its kernel"}.get(cost.state, "its set-up")
    return (f"backend auto: the NumPy route (about {cost.numpy:.2g} s; the compiled route would take about "
            f"{cost.compiled:.2g} s, {why} included); give --backend compiled to take it")
