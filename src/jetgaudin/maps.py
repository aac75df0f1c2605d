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

Concrete maps are frozen dataclasses.  The selection enums :class:`Backend` and :class:`Branch` live here.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from ._errors import InvalidParameterError

__all__ = [
    "Advance",
    "Backend",
    "Branch",
    "Map",
    "MapProperties",
    "check_count",
    "map_from_description",
    "register_map",
    "step_loop",
]


class Backend(StrEnum):
    """How a map is evaluated: the NumPy reference route, the compiled (Numba) route, or ``AUTO`` (compiled where
    it pays off; see :func:`jetgaudin.backlund.auto_kernel`)."""

    NUMPY = "numpy"
    COMPILED = "compiled"
    AUTO = "auto"

    @classmethod
    def parse(cls, value: Backend | str) -> Backend:
        """``Backend`` from an enum member or its value (``"numpy"``, ``"compiled"``, ``"auto"``)."""
        try:
            return cls(value)
        except ValueError:
            raise InvalidParameterError(
                f"backend (kernel) must be 'auto', 'numpy' or 'compiled', got {value!r}"
            ) from None


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


def check_count(value: object, name: str, minimum: int = 0) -> int:
    """An integer count ``>= minimum`` that fits in int64 (the compiled kernels and the HDF5 files use int64);
    :class:`InvalidParameterError` naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InvalidParameterError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if int(value) > _INT64_MAX:
        raise InvalidParameterError(f"{name} = {value} does not fit in 64 bits; give at most 2**63 - 1")
    return int(value)


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
        """How the map is evaluated (maps without a compiled route: :attr:`Backend.NUMPY`)."""
        return Backend.NUMPY

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
        """``steps`` steps from ``(X, carry)`` keeping every ``save_every``-th state (a loop over :meth:`step`;
        ``carry=None`` starts the orbit with :meth:`start`)."""
        X = np.asarray(X)
        return step_loop(self, X, self.start(X) if carry is None else carry, steps, save_every)

    def iterate(self, X0: np.ndarray, steps: int, *, save_every: int = 1, carry: Any = None,
                return_carry: bool = False) -> np.ndarray | tuple[np.ndarray, Any]:
        """Orbit ``X_0, X_k, …, X_{⌊steps/k⌋k}`` (``k = save_every``), shape ``(steps//k + 1, ..., n)``;
        ``return_carry=True`` also returns the carry after the last step (pass it back to continue)."""
        X0 = np.asarray(X0)
        adv = self.advance(X0, carry, steps, save_every)
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


def register_map(kind: str, factory: Callable[[dict], Map]) -> None:
    """Register ``factory(description) -> Map`` for descriptions with ``"kind": kind``."""
    _REGISTRY[kind] = factory


def map_from_description(d: dict) -> Map:
    """The map a :meth:`Map.describe` dictionary describes (:class:`InvalidParameterError` for unknown kinds)."""
    if not isinstance(d, dict) or "kind" not in d:
        raise InvalidParameterError(f"a map description must be a dict with a 'kind', got {d!r}")
    from . import backlund, exact, exact_chain, flows, gaudin, midpoint  # noqa: F401  (they register the built-in kinds)

    kind = d["kind"]
    if kind not in _REGISTRY:
        raise InvalidParameterError(f"unknown map kind {kind!r} (known: {', '.join(sorted(_REGISTRY))})")
    return _REGISTRY[kind](d)
