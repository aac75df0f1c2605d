r"""The map interface: anything that advances states ``(..., n)`` by one step.

A :class:`Map` is the *method* layer of the package (see ``docs/architecture.md``): the Bäcklund maps of
Section 6 (:class:`jetgaudin.TwoPointBacklund`, :class:`jetgaudin.OnePointBacklund`), the flow of a
Hamiltonian over a fixed time step (:class:`jetgaudin.flows.FlowMap`) and the chain maps subclass it.
The run layer (:mod:`jetgaudin.run`) drives any map through this surface only:

* ``start(X)`` -- per-orbit set-up carried along the orbit (``ν1`` for the Bäcklund maps), shape ``(...)``;
* ``step(X, carry) -> (X_new, carry_new, imag_residue)``;
* ``advance(X, carry, steps, save_every) -> Advance`` -- ``steps`` steps keeping every ``save_every``-th
  state (compiled maps override the default loop over :meth:`Map.step`); ``carry=None`` starts the orbit;
* ``integrals(X)`` -- the quantities the map preserves (the health checks compare them);
* ``describe()`` / :func:`map_from_description` -- a JSON-able description and its inverse, so that a run
  can be resumed from ``run.json``.

**The backend rule** (one for every map, written here once):

* every map takes ``backend=`` (alias ``kernel=``; a :class:`Backend` or its value ``"auto"``, ``"numpy"``,
  ``"compiled"``, ``"gpu"``) in its constructor and in :meth:`Map.iterate`; the default is ``Backend.AUTO`` everywhere
  (:func:`backend_option`: ``"auto"`` yields to the other name, two different concrete choices are refused);
* a map *declares* a compiled route by overriding :meth:`Map._compiled_advance` (then :attr:`Map.has_compiled` is
  true) and, optionally, its cost rule :meth:`Map._auto_backend` for ``AUTO`` (default: compiled) and
  :meth:`Map.prepare_kernels`; everything else is shared: :meth:`Map.resolved_backend` ``(X, steps)`` (``AUTO``
  is the NumPy route for a map without a compiled one), :meth:`Map.advance` (the compiled hook or the loop over
  :meth:`Map.step`), :meth:`Map.with_backend`, :meth:`Map.iterate`;
* ``backend="compiled"`` for a map without a compiled route is an :class:`InvalidParameterError` at construction
  (:meth:`Map._init_backend`, called by the maps' ``__post_init__``) and in :meth:`Map.iterate`;
* a map *declares* a GPU route by :attr:`Map.has_gpu` (the top's two-point maps and the chains' two-point map);
  ``backend="gpu"`` on another map is an :class:`InvalidParameterError`, and where no GPU can run (no
  ``numba-cuda``, no driver, no GPU) a :class:`jetgaudin.gpu.GPUUnavailableError` naming what is missing;
  ``AUTO`` takes the GPU only where :func:`jetgaudin.gpu.auto_uses_gpu` says so (:func:`auto_gpu`);
* the argument order is ``(X, steps)`` everywhere: ``resolved_backend(X, steps)``, ``prepare_kernels(X, steps,
  notify)``; ``prepare_kernels()`` without arguments compiles every kernel the map could need.

Both routes of the two-point map keep the integrals at round-off (a random walk; ``docs/backlund.md``, section 7),
so the ``AUTO`` choice is a matter of cost only.  The same rule in words, with the template of a map that follows
it: ``docs/architecture.md``, "The backend rule".

Concrete maps are frozen dataclasses.  The selection enums :class:`Backend` and :class:`Branch` live here.
"""

from __future__ import annotations

import abc
import copy
import dataclasses
import importlib
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Self

import numpy as np

from ._errors import InvalidParameterError, JetGaudinError, MapDescriptionError, OutputTooLargeError

__all__ = [
    "Advance",
    "Backend",
    "Branch",
    "Map",
    "MapProperties",
    "auto_gpu",
    "backend_option",
    "check_count",
    "check_output_size",
    "MAX_OUTPUT_BYTES",
    "output_cap",
    "check_gpu",
    "map_from_description",
    "with_resolved_backend",
    "register_map",
    "step_loop",
]


class Backend(StrEnum):
    """How a map is evaluated: the NumPy reference route, the compiled (Numba) route on the CPU's cores, the GPU
    route (:mod:`jetgaudin.gpu`: Numba's CUDA target, one thread per orbit), or ``AUTO`` (compiled where it pays
    off, :func:`jetgaudin.backlund.auto_kernel`; the GPU only where one is present and the work is large,
    :func:`jetgaudin.gpu.auto_uses_gpu`)."""

    #: the NumPy reference route (every map)
    NUMPY = "numpy"
    #: the Numba kernels on the CPU's cores (maps with :attr:`Map.has_compiled`)
    COMPILED = "compiled"
    #: the cheapest route for the work at hand (:meth:`Map.resolved_backend`)
    AUTO = "auto"
    #: one orbit per thread of an NVIDIA GPU (maps with :attr:`Map.has_gpu`; :mod:`jetgaudin.gpu`)
    GPU = "gpu"

    @classmethod
    def parse(cls, value: Backend | str) -> Backend:
        """``Backend`` from an enum member or its value (``"numpy"``, ``"compiled"``, ``"gpu"``, ``"auto"``)."""
        try:
            return cls(value)
        except ValueError:
            raise InvalidParameterError(
                f"backend (kernel) must be 'auto', 'numpy', 'compiled' or 'gpu', got {value!r}"
            ) from None


def backend_option(backend: Backend | str | None = None, kernel: Backend | str | None = None) -> Backend | None:
    """The backend a caller asked for with ``backend=`` or its alias ``kernel=``: ``None`` when neither is given
    (keep the map's own); ``AUTO`` (no preference) yields to the other; two different concrete choices are an
    :class:`InvalidParameterError`."""
    chosen = [Backend.parse(v) for v in (backend, kernel) if v is not None]
    concrete = {c for c in chosen if c is not Backend.AUTO}
    if len(concrete) > 1:
        raise InvalidParameterError(f"backend={backend!r} and its alias kernel={kernel!r} disagree; give one of them")
    return concrete.pop() if concrete else (Backend.AUTO if chosen else None)


class Branch(StrEnum):
    """The root of ``ν(η)`` a Bäcklund map uses: ``DEFAULT`` (the branch rule of :func:`jetgaudin.nu`) or
    ``OPPOSITE`` (its negative; for the real two-point map this is the inverse map)."""

    DEFAULT = "default"
    OPPOSITE = "opposite"

    @property
    def sheet(self) -> int:
        """``+1`` (default) or ``-1`` (opposite)."""
        return 1 if self is Branch.DEFAULT else -1

    @classmethod
    def parse(cls, value: Branch | str | int) -> Branch:
        """``Branch`` from an enum member, ``"default"``/``"opposite"`` or the sheet ``+1``/``-1``."""
        if isinstance(value, str):
            try:
                return cls(value)
            except ValueError:
                pass
        elif not isinstance(value, bool) and value in (1, -1):
            return cls.DEFAULT if value == 1 else cls.OPPOSITE
        raise InvalidParameterError(f"branch must be 'default' or 'opposite' (or +1/-1), got {value!r}")


@dataclass(frozen=True)
class MapProperties:
    """Declared properties of a map; every ``True`` claim is asserted by the tests of that map.

    ``order`` is the order of the map as an integrator of the flow it discretises (for the two-point map: the
    flow of ``ν(Re η)`` with time step ``−2 Im η`` in the limit ``Im η → 0``; ``None``: not an integrator of a
    real flow).
    """

    preserves_integrals: bool
    poisson: bool
    real: bool
    order: int | None
    symmetric: bool  # the map with the other branch (or conj eta) is the inverse
    interpolates_flow: bool  # equals the time-1 flow of G_eta


@dataclass(frozen=True)
class Advance:
    """Result of :meth:`Map.advance`: ``rows`` ``(steps // save_every, ..., n)`` (the states after
    ``save_every``, ``2 save_every``, … steps; the start state is not included), the final state ``X``
    ``(..., n)``, the ``carry`` ``(...)`` to continue from, and ``imag_max`` ``(...)``, the largest imaginary
    residue of the steps (zeros where the route does not compute it)."""

    rows: np.ndarray
    X: np.ndarray
    carry: Any
    imag_max: np.ndarray


#: the largest count: int64, as the compiled kernels' loop counters and the HDF5 files
_INT64_MAX = 2**63 - 1


#: the largest array (bytes) that ``iterate``, ``iterate_ensemble`` and ``solve`` return, or ``None`` (the default):
#: half the machine's physical memory (:func:`output_cap`).  Past it they refuse with
#: :class:`jetgaudin.OutputTooLargeError` before allocating anything (before: ``jg.solve(H, X0, (0, 1e9), dt=0.25)``
#: asked NumPy for hundreds of GiB).  Override it (``jetgaudin.maps.MAX_OUTPUT_BYTES = ...``) to return more or
#: less; a long orbit is better saved sparsely (``save_every``) or streamed to disk by the run layer
#: (``jetgaudin.run``).
MAX_OUTPUT_BYTES: int | None = None


def output_cap() -> int:
    """The cap in force: :data:`MAX_OUTPUT_BYTES`, or half the physical memory (at least 1 GiB) when it is ``None``."""
    if MAX_OUTPUT_BYTES is not None:
        return int(MAX_OUTPUT_BYTES)
    try:
        physical = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        physical = 8 << 30
    return max(1 << 30, int(physical) // 2)


def check_output_size(rows: int, row_bytes: int, what: str) -> None:
    """Refuse (:class:`jetgaudin.OutputTooLargeError`, naming the size, the cap and the fix) an output of ``rows``
    rows of ``row_bytes`` bytes larger than :func:`output_cap` (read at each call: overridable)."""
    nbytes, cap = int(rows) * int(row_bytes), output_cap()
    if nbytes > cap:
        raise OutputTooLargeError(
            f"{what} would return {rows:,} rows, {nbytes:,} bytes ({nbytes / 2**30:.3g} GiB), more than the cap of "
            f"{cap:,} bytes (jetgaudin.maps.MAX_OUTPUT_BYTES; default: half the physical memory); save fewer rows (a "
            "larger save_every), take a shorter span, or stream the orbit to disk with the run layer (jetgaudin.run, "
            "`jetgaudin orbit`)", nbytes, cap)


def check_count(value: object, name: str, minimum: int = 0) -> int:
    """An integer count ``>= minimum`` that fits in int64 (the compiled kernels and the HDF5 files use int64);
    :class:`InvalidParameterError` naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InvalidParameterError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if int(value) > _INT64_MAX:
        raise InvalidParameterError(f"{name} = {value} does not fit in 64 bits; give at most 2**63 - 1")
    return int(value)


def check_gpu(backend: Backend, has_gpu: bool, name: str) -> None:
    """Refuse ``backend="gpu"`` for a map without a GPU route (:class:`InvalidParameterError`) or where no GPU can
    run (:class:`jetgaudin.gpu.GPUUnavailableError`, naming what is missing)."""
    if backend is not Backend.GPU:
        return
    if not has_gpu:
        raise InvalidParameterError(f"{name} has no GPU route: backend (kernel) must be 'auto', 'numpy' or "
                                    "'compiled', got 'gpu'")
    from .gpu import require

    require("backend 'gpu'")


def auto_gpu(has_gpu: bool, X: Any, steps: Any) -> bool:
    """Whether ``AUTO`` runs ``steps`` steps of the states ``X`` ``(..., n)`` on the GPU: the map has a GPU route and
    :func:`jetgaudin.gpu.auto_uses_gpu` says the work pays for it here (never without a GPU)."""
    if not has_gpu or steps is None:
        return False
    from .gpu import auto_uses_gpu

    return auto_uses_gpu(math.prod(np.shape(X)[:-1]), int(steps))  # math.prod: 5 µs less than np.prod a call


def map_name(m: Any) -> str:
    """The class name a map's messages give: its ``public_name`` (a route of a public class, e.g. the top's route of
    :class:`jetgaudin.OnePointBacklund`, :mod:`jetgaudin._system_maps`), else its class's name."""
    return str(getattr(type(m), "public_name", type(m).__name__))


class Map(abc.ABC):
    """Abstract base of every map ``X ↦ X_new`` on states ``(..., n)`` (see the module doc).

    Subclasses define :attr:`properties`, :meth:`integrals`, :meth:`step`, :meth:`inverse` and
    :meth:`describe`; they may override :meth:`start` (default: no carry, zeros), :meth:`advance` (default: a
    loop over :meth:`step`) and :attr:`n_state` (default ``None``: any length the map accepts).
    """

    properties: MapProperties

    @property
    def n_state(self) -> int | None:
        """Length of the state vector the map acts on (``None``: any admissible length)."""
        return None

    @property
    def backend(self) -> Backend:
        """How the map is evaluated: the map's ``backend`` field (a map without the field: :attr:`Backend.NUMPY`)."""
        return Backend.NUMPY

    @property
    def has_compiled(self) -> bool:
        """Whether the map has a compiled route: it overrides :meth:`_compiled_advance`."""
        return type(self)._compiled_advance is not Map._compiled_advance

    @property
    def has_gpu(self) -> bool:
        """Whether the map has a GPU route (``backend="gpu"``; :mod:`jetgaudin.gpu`); none here."""
        return False

    def _compiled_advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int) -> Advance:
        """The compiled route of :meth:`advance` (maps with one override it; ``X`` non-empty, counts checked)."""
        raise NotImplementedError(f"{type(self).__name__} has no compiled route")

    def _auto_backend(self, X: Any, steps: Any) -> Backend:
        """What ``AUTO`` means for a map with a compiled route, for ``steps`` steps of ``X`` (here: compiled; the
        two-point maps weigh the compile or load time against the steps, :func:`jetgaudin.backlund.auto_kernel`)."""
        return Backend.COMPILED

    def resolved_backend(self, X: Any, steps: Any) -> Backend:
        """The route :meth:`advance` takes for ``steps`` steps of the states ``X``: the map's ``backend``, with
        ``AUTO`` resolved (:meth:`_auto_backend` for a map with a compiled route, the NumPy route otherwise)."""
        b = self.backend
        if b is not Backend.AUTO:
            return b
        if auto_gpu(self.has_gpu, X, steps):
            return Backend.GPU
        return self._auto_backend(np.asarray(X), steps) if self.has_compiled else Backend.NUMPY

    def _init_backend(self) -> None:
        """Set the ``backend`` field from it and its alias field ``kernel`` (:func:`backend_option`; the alias is
        then cleared), refusing ``COMPILED`` for a map without a compiled route.  Called by the ``__post_init__``
        of every map with the fields ``backend: Backend = Backend.AUTO`` and ``kernel: Backend | str | None =
        field(default=None, kw_only=True, repr=False, compare=False)``."""
        chosen = backend_option(self.backend, getattr(self, "kernel", None))
        object.__setattr__(self, "backend", Backend.AUTO if chosen is None else chosen)
        if hasattr(self, "kernel"):
            object.__setattr__(self, "kernel", None)
        if self.backend is Backend.COMPILED and not self.has_compiled:
            raise InvalidParameterError(
                f"{map_name(self)} has no compiled route: backend (kernel) must be 'auto' or 'numpy', "
                "got 'compiled'"
            )
        check_gpu(self.backend, self.has_gpu, map_name(self))

    def with_backend(self, backend: Backend | str) -> Self:
        """This map with another ``backend`` (the same map when it is unchanged; :class:`InvalidParameterError` for
        ``"compiled"`` on a map without a compiled route)."""
        backend = Backend.parse(backend)
        if backend is self.backend:
            return self
        check_gpu(backend, self.has_gpu, map_name(self))
        if not self.has_compiled:  # one route: "auto" and "numpy" are the same map
            if backend is Backend.COMPILED:
                raise InvalidParameterError(f"{map_name(self)} has no compiled route: backend (kernel) must be "
                                            "'auto' or 'numpy', got 'compiled'")
            return self
        return dataclasses.replace(self, backend=backend)  # type: ignore[type-var]

    def prepare_kernels(self, *args: Any, **kwargs: Any) -> Any:
        """``prepare_kernels(X=None, steps=None, notify=None)``: compile (or load) the kernels :meth:`advance` of
        ``steps`` steps from ``X`` will call, visibly (``notify(message)``; default stderr), and return a report of
        the time spent (``None``: nothing to compile, as here for a map without a compiled route).  Without
        arguments: every kernel the map could need.  (Declared with ``*args, **kwargs`` so that a map may spell its
        signature out; the order is ``(X, steps, notify)``.)"""
        return None

    @abc.abstractmethod
    def integrals(self, X: np.ndarray) -> np.ndarray:
        """The quantities the map preserves at ``X`` ``(..., n)``, shape ``(..., k)``."""

    def start(self, X: np.ndarray) -> np.ndarray:
        """Per-orbit set-up at ``X`` ``(..., n)`` carried along the orbit, shape ``(...)`` (complex); zeros here."""
        return np.zeros(np.shape(X)[:-1], dtype=complex)

    @abc.abstractmethod
    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        """One step from ``X`` with ``carry`` (``None``: start the orbit); returns ``(X_new, carry_new,
        imag_residue)``, the residue of shape ``(...)`` (zeros where not defined)."""

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """``steps`` steps from ``(X, carry)`` keeping every ``save_every``-th state: the compiled route
        (:meth:`_compiled_advance`) when :meth:`resolved_backend` says so, else a loop over :meth:`step`
        (``carry=None`` starts the orbit with :meth:`start`)."""
        X = np.asarray(X)
        if self.has_compiled and X.size and self.resolved_backend(X, steps) is Backend.COMPILED:
            return self._compiled_advance(X, carry, check_count(steps, "steps"),
                                          check_count(save_every, "save_every", 1))
        return step_loop(self, X, self.start(X) if carry is None else carry, steps, save_every)

    def iterate(self, X0: np.ndarray, steps: int, *, save_every: int = 1, carry: Any = None,
                return_carry: bool = False, backend: Backend | str | None = None,
                kernel: Backend | str | None = None) -> np.ndarray | tuple[np.ndarray, Any]:
        """Orbit ``X_0, X_k, …, X_{⌊steps/k⌋k}`` (``k = save_every``), shape ``(steps//k + 1, ..., n)``;
        ``return_carry=True`` also returns the carry after the last step (pass it back to continue).
        ``backend`` (alias ``kernel``): the route for this call (default: the map's ``backend``; the rule of the
        module doc)."""
        choice = backend_option(backend, kernel)
        m = self if choice is None else self.with_backend(choice)
        X0 = np.asarray(X0)
        rows = check_count(steps, "steps") // check_count(save_every, "save_every", 1) + 1
        check_output_size(rows, X0.size * max(8, X0.dtype.itemsize), "iterate")
        adv = m.advance(X0, carry, steps, save_every)
        orbit = np.concatenate([X0[None].astype(adv.rows.dtype, copy=False), adv.rows], axis=0)
        return (orbit, adv.carry) if return_carry else orbit

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """Apply the map once to states ``(..., n)``."""
        return self.step(X)[0]

    @abc.abstractmethod
    def inverse(self) -> Map:
        """The inverse map."""

    @abc.abstractmethod
    def describe(self) -> dict:
        """A JSON-able description with ``"kind"`` and every parameter (:func:`map_from_description` inverts it)."""


class StepByAdvance:
    """For a map whose one step is its own :meth:`Map.advance` of one step (the exact flows: a step is a solve of the
    maps' parameters and their composition, so ``advance`` is the primitive and ``step`` follows from it)."""

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        adv = self.advance(X, carry, 1)  # type: ignore[attr-defined]
        return adv.X, adv.carry, adv.imag_max


def per_orbit_buffers(model: Any, X: Any, steps: int, save_every: int):
    """``(steps, save_every, X, flat, rows, final)`` for a map that solves per orbit (the exact flows): the counts
    checked, ``X`` checked by ``model.check_state`` as floats, its orbits ``flat`` ``(B, n)``, the saved rows
    ``(steps // save_every, B, n)`` to fill and the final states (a copy of ``flat``)."""
    steps = check_count(steps, "steps")
    save_every = check_count(save_every, "save_every", 1)
    X = np.asarray(model.check_state(X), dtype=float)
    flat = X.reshape(-1, X.shape[-1])
    return steps, save_every, X, flat, np.empty((steps // save_every,) + flat.shape), flat.copy()


def with_resolved_backend(m: Map, backend: Backend) -> Map:
    """A copy of ``m`` with its ``backend`` field set to ``backend`` (the run layer records the route ``AUTO`` chose);
    the copy is not validated again (``m`` was when it was built: a flow map run backwards, ``dt < 0``, which the
    constructor refuses, stays valid)."""
    out = copy.copy(m)
    object.__setattr__(out, "backend", Backend.parse(backend))
    return out


def step_loop(m: Map, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
    """The one stepping loop of the NumPy routes: ``steps`` calls of ``m.step`` from ``(X, carry)`` keeping every
    ``save_every``-th state and the largest imaginary residue (``carry`` passed as given, ``None`` included)."""
    steps = check_count(steps, "steps")
    save_every = check_count(save_every, "save_every", 1)
    rows = np.empty((steps // save_every,) + np.shape(X), dtype=np.asarray(X).dtype)
    imag = np.zeros(np.shape(X)[:-1])
    for n in range(steps):
        X, carry, im = m.step(X, carry)
        imag = np.maximum(imag, im)
        if (n + 1) % save_every == 0:
            rows[(n + 1) // save_every - 1] = X
    return Advance(rows=rows, X=X, carry=carry, imag_max=imag)


_REGISTRY: dict[str, Callable[[dict], Map]] = {}
#: the modules whose import registers the built-in map kinds (:func:`register_map`); imported by name in
#: :func:`map_from_description`, so that this interface module imports none of its implementations (issue 33: a
#: 13-module import circle ran through here)
_BUILTIN_MAP_MODULES = ("jetgaudin.backlund", "jetgaudin.exact", "jetgaudin.exact_chain",
                        "jetgaudin.flows", "jetgaudin.gaudin", "jetgaudin.kahan", "jetgaudin.midpoint")


def register_map(kind: str, factory: Callable[[dict], Map]) -> None:
    """Register ``factory(description) -> Map`` for descriptions with ``"kind": kind``."""
    _REGISTRY[kind] = factory


def map_from_description(d: dict) -> Map:
    """The map a :meth:`Map.describe` dictionary describes (:class:`InvalidParameterError` for unknown kinds)."""
    if not isinstance(d, dict) or "kind" not in d:
        raise InvalidParameterError(f"a map description must be a dict with a 'kind', got {d!r}")
    for module in _BUILTIN_MAP_MODULES:  # they register the built-in kinds when imported (by name: no import cycle)
        importlib.import_module(module)
    kind = d["kind"]
    if not isinstance(kind, str) or kind not in _REGISTRY:
        raise MapDescriptionError(f"unknown map kind {kind!r} (known: {', '.join(sorted(_REGISTRY))})", "kind")
    try:
        return _REGISTRY[kind](d)
    except KeyError as exc:
        key = exc.args[0] if exc.args else None
        raise MapDescriptionError(f"the description of a {kind!r} map has no key {key!r}; give it (as describe() "
                                  "writes it)", None if key is None else str(key)) from None
    except JetGaudinError:
        raise
    except (TypeError, ValueError, IndexError, AttributeError) as exc:
        bad = [k for k, v in d.items() if k != "kind" and not isinstance(v, (int, float, str, list, dict, bool))
               and v is not None]
        key = bad[0] if bad else None
        raise MapDescriptionError(f"the description of a {kind!r} map holds a value of the wrong kind"
                                  f"{f' (key {key!r})' if key else ''}: {type(exc).__name__}: {exc}", key) from None
