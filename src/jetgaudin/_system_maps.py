r"""One class per kind of map, for every system (issue 33, "What to build" 1).

A map's first field is its **system**: a field strength ``b`` (a real number: the top of any ``N``, ``N`` read from
the state, eq. (lax2)) or a :class:`~jetgaudin.GaudinModel` (a chain of any family, the top's one-site model
``GaudinModel(b, [(0, N)])`` included).  ``TwoPointBacklund(1.0, eta)`` and ``TwoPointBacklund(model, eta)`` are the
same class; ``ChainTwoPointBacklund`` is that class under its old name (``isinstance`` holds both ways, and
``ChainTwoPointBacklund(model, eta, branch, backend, kernel)`` keeps its signature).  Likewise ``OnePointBacklund`` /
``ChainOnePointBacklund``.

What runs is picked by one route table, :data:`ROUTES` — ``(kind of map, system) → implementation`` — whose entries
are the existing implementations, unchanged (every orbit bit for bit what it was):

============== ============================================== ==================================================
kind           top (``b``)                                    chain (``GaudinModel``)
============== ============================================== ==================================================
two-point      ``backlund.maps._TopTwoPoint`` (NumPy; the      ``gaudin.maps._ChainTwoPoint`` (NumPy; compiled: the
               top's kernels ``backlund/kernels``; GPU)        top's kernels where ``model.is_top``, else
                                                               ``gaudin._kernels`` (rational) or
                                                               ``gaudin._family_kernel``; GPU)
one-point      ``backlund.maps._TopOnePoint`` (NumPy)          ``gaudin._one_point._ChainOnePoint`` (NumPy)
============== ============================================== ==================================================

The public object keeps, per system, everything the old classes answered: ``b``, ``model`` (``None`` for the top, whose
``N`` is the state's), ``kind`` (``"two_point"`` / ``"chain_two_point"``, …), :meth:`describe` (so the map registry
and every existing ``run.json`` load and resume bit for bit), equality and hashing on ``(system, η, branch, …)``.  The
methods of one system only (the top's ``nu1``, ``parameters``; a chain's ``dressing_matrix``, ``integral_names``,
``route_notice``) are its implementation's.
"""

from __future__ import annotations

import importlib
import numbers
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ._errors import InvalidParameterError
from .maps import Advance, Backend, Branch, Map, MapProperties

__all__ = ["ExactFlow", "OnePointBacklund", "TwoPointBacklund", "ROUTES", "system_kind"]

_TWO_POINT_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=True, real=True, order=2, symmetric=True, interpolates_flow=True
)
_ONE_POINT_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=True, real=False, order=None, symmetric=True, interpolates_flow=False
)
_EXACT_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=True, real=True, order=None, symmetric=True, interpolates_flow=False
)

#: the route table of the Bäcklund maps: ``(kind, system) -> (module, implementation class)`` (module docstring);
#: the modules are imported on first use (this module imports none of its implementations: no import circle)
ROUTES: dict[tuple[str, str], tuple[str, str]] = {
    ("two_point", "top"): ("jetgaudin.backlund.maps", "_TopTwoPoint"),
    ("two_point", "chain"): ("jetgaudin.gaudin.maps", "_ChainTwoPoint"),
    ("one_point", "top"): ("jetgaudin.backlund.maps", "_TopOnePoint"),
    ("one_point", "chain"): ("jetgaudin.gaudin._one_point", "_ChainOnePoint"),
    ("exact", "top"): ("jetgaudin.exact", "_TopExactFlow"),
    ("exact", "chain"): ("jetgaudin.exact_chain", "_ChainExactFlow"),
}
_IMPL: dict[tuple[str, str], type] = {}
_MISSING: Any = object()


def _implementation(kind: str, system: str) -> type:
    key = (kind, system)
    cls = _IMPL.get(key)
    if cls is None:
        module, name = ROUTES[key]
        cls = _IMPL[key] = getattr(importlib.import_module(module), name)
    return cls


def system_kind(system: Any, what: str) -> str:
    """``"top"`` for a real number (the field ``b``), ``"chain"`` for a :class:`~jetgaudin.GaudinModel`; anything
    else is an :class:`InvalidParameterError` naming what ``what`` (the class) accepts."""
    from .gaudin.model import GaudinModel  # on use: the system layer below this one

    if isinstance(system, GaudinModel):
        return "chain"
    if isinstance(system, numbers.Real) or (isinstance(system, np.ndarray) and system.ndim == 0
                                            and system.dtype.kind in "biuf"):
        return "top"
    raise InvalidParameterError(
        f"the first argument of {what} is its system: a field strength b (a real number: the top of any N) or a "
        f"GaudinModel (a chain, e.g. jg.GaudinModel(1.0, [(0, 3)]) for the top of order 3); got "
        f"{type(system).__name__}"
    )


def _pick_system(cls_name: str, system: Any, b: Any, model: Any) -> Any:
    """The one system given positionally or as ``b=`` (a top) / ``model=`` (a chain), the old keyword names."""
    given = [(n, v) for n, v in (("system", system), ("b", b), ("model", model)) if v is not _MISSING]
    if len(given) != 1:
        raise InvalidParameterError(
            f"{cls_name} takes its system once: a field strength b (the top) or a GaudinModel (a chain), as the first "
            f"argument or as b= / model=; got {', '.join(n for n, _ in given) or 'none'}"
        )
    name, value = given[0]
    if name != "system":
        expected = "top" if name == "b" else "chain"
        if system_kind(value, cls_name) != expected:
            raise InvalidParameterError(
                f"{cls_name}: {name}= must be " + ("a real field strength (the top)" if name == "b" else
                                                  "a GaudinModel (a chain)") +
                f", got {type(value).__name__}; pass the system as the first argument"
            )
    return value


class _SystemMap(Map):
    """A map of either system (module docstring): the public fields and the route table's implementation, to which
    every method delegates (``self._r()``, rebuilt if the ``backend`` field was set on a copy, as
    :func:`jetgaudin.maps.with_resolved_backend` does)."""

    _MAP_KIND: ClassVar[str]  # the kind of map: the first key of ROUTES
    _KINDS: ClassVar[dict[str, str]]  # system -> describe()'s "kind"
    _ARGS: ClassVar[tuple[str, ...]]  # the implementation's positional fields after the system, in order
    _SYSTEM: ClassVar[str] = "system"  # the name of the first field (the exact flows: "H")
    backend: Backend

    @classmethod
    def _system_kind(cls, system: Any) -> str:
        return system_kind(system, cls.__name__)

    @staticmethod
    def _system_of(impl: Any, sk: str) -> Any:
        """The public first field from a validated implementation (the Bäcklund maps: ``b`` or the model)."""
        return impl.b if sk == "top" else impl.model

    def _build(self, system: Any, values: tuple, kernel: Any) -> None:
        sk = self._system_kind(system)
        impl = _implementation(self._MAP_KIND, sk)(system, *values, kernel=kernel)
        self._adopt(impl, sk)

    def _adopt(self, impl: Any, sk: str) -> None:
        object.__setattr__(self, self._SYSTEM, self._system_of(impl, sk))
        for a in self._ARGS:
            object.__setattr__(self, a, getattr(impl, a))
        object.__setattr__(self, "kernel", None)
        object.__setattr__(self, "_impl", impl)
        object.__setattr__(self, "_system", sk)

    @classmethod
    def _wrap(cls, impl: Any) -> Any:
        """The public map running ``impl`` (an implementation of the route table, already validated)."""
        out = object.__new__(cls)
        sk = next(s for (k, s), c in _IMPL.items() if k == cls._MAP_KIND and isinstance(impl, c))
        out._adopt(impl, sk)
        return out

    @property
    def _sys(self) -> Any:
        return getattr(self, self._SYSTEM)

    def _r(self) -> Any:
        impl = self.__dict__["_impl"]
        if impl.backend is not self.backend:  # the backend field was set on a copy (with_resolved_backend)
            from .maps import with_resolved_backend

            impl = with_resolved_backend(impl, self.backend)
            object.__setattr__(self, "_impl", impl)
        return impl

    def __getattr__(self, name: str) -> Any:
        """The methods of one system only (the top's ``nu1``, a chain's ``dressing_matrix``…): its implementation's."""
        impl = self.__dict__.get("_impl") if not name.startswith("__") else None
        if impl is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        try:
            return getattr(self._r(), name)
        except AttributeError:
            raise AttributeError(f"{type(self).__name__!r} object of the {self.__dict__['_system']} has no attribute "
                                 f"{name!r}") from None

    def __repr__(self) -> str:
        first = (f"{self._SYSTEM}={self._sys!r}" if self._SYSTEM != "system" else
                 f"b={self._sys!r}" if self.__dict__.get("_system") == "top" else f"model={self._sys!r}")
        rest = ", ".join(f"{a}={getattr(self, a)!r}" for a in self._ARGS)
        return f"{type(self).__name__}({first}, {rest})"

    # -- what every system answers --------------------------------------------------------------------------------
    @property
    def kind(self) -> str:
        """The kind of :meth:`describe` (as before for each system: ``"two_point"`` for the top,
        ``"chain_two_point"`` for a chain, …)."""
        return self._KINDS[self.__dict__["_system"]]

    @property
    def is_chain(self) -> bool:
        """Whether the system is a :class:`~jetgaudin.GaudinModel` (else the field ``b`` of the top of any N)."""
        return self.__dict__["_system"] == "chain"

    @property
    def b(self) -> float:
        """The field strength (the model's ``b`` for a chain)."""
        return float(self._r().b) if not self.is_chain else float(self.model.b)

    @property
    def model(self) -> Any:
        """The :class:`~jetgaudin.GaudinModel` of a chain; ``None`` for the top (its ``N`` is the state's)."""
        return self._r().model if self.is_chain else None

    @property
    def n_state(self) -> int | None:
        return self._r().n_state  # type: ignore[no-any-return]

    @property
    def has_compiled(self) -> bool:
        return self._r().has_compiled  # type: ignore[no-any-return]

    @property
    def has_gpu(self) -> bool:
        return self._r().has_gpu  # type: ignore[no-any-return]

    def resolved_backend(self, X: Any, steps: Any) -> Backend:
        return self._r().resolved_backend(X, steps)  # type: ignore[no-any-return]

    def _auto_backend(self, X: Any, steps: Any) -> Backend:
        return self._r()._auto_backend(X, steps)  # type: ignore[no-any-return]

    def with_backend(self, backend: Backend | str, kernel: Backend | str | None = None) -> Any:
        """This map on another route (the same object when it is unchanged)."""
        impl = self._r()
        new = impl.with_backend(backend) if kernel is None else impl.with_backend(backend, kernel)
        return self if new is impl else self._wrap(new)

    def prepare_kernels(self, *args: Any, **kwargs: Any) -> Any:
        return self._r().prepare_kernels(*args, **kwargs)

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return self._r().integrals(X)  # type: ignore[no-any-return]

    def start(self, X: np.ndarray) -> np.ndarray:
        return self._r().start(X)  # type: ignore[no-any-return]

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        return self._r().step(X, carry)  # type: ignore[no-any-return]

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1, **route: Any) -> Advance:
        return self._r().advance(X, carry, steps, save_every, **route)  # type: ignore[no-any-return]

    def iterate(self, X0: Any, steps: int, *, save_every: int = 1, carry: Any = None, return_carry: bool = False,
                backend: Backend | str | None = None, kernel: Backend | str | None = None, **top: Any) -> Any:
        """:meth:`jetgaudin.maps.Map.iterate` on the route ``backend`` (alias ``kernel``; default the map's), by the
        system's implementation (the top also takes its old names ``nu1=`` / ``return_nu=`` for ``carry`` /
        ``return_carry``)."""
        return self._r().iterate(X0, steps, save_every=save_every, carry=carry, return_carry=return_carry,
                                 backend=backend, kernel=kernel, **top)

    def __call__(self, X: np.ndarray) -> np.ndarray:
        return self._r()(X)  # type: ignore[no-any-return]

    def inverse(self) -> Any:
        return self._wrap(self._r().inverse())

    def describe(self) -> dict:
        return self._r().describe()  # type: ignore[no-any-return]


@dataclass(frozen=True, init=False, repr=False)
class TwoPointBacklund(_SystemMap):
    r"""The real two-point Bäcklund map ``B_η: X ↦ X̆`` (Section 6.2, Appendix 1) of the top of any N or of a chain.

    ``X̆`` solves ``M(λ) L(λ) = L̆(λ) M(λ)`` (eq. (128)) with ``M = λ + M0(s, t)`` of (mm) (a chain of another family:
    the family's dressing ``D(λ)``), ``η1 = η``, ``η2 = η̄``, ``ν1 = ν(η)`` on the chosen branch and
    ``ν2 = conj ν1``.  Maps real states to real states; it preserves the integrals, is a Poisson map, commutes with
    itself for other ``η``, has the ``"opposite"`` branch as inverse, and equals the time-1 flow of ``G_η``
    (the value of ``G_η`` is :func:`jetgaudin.interpolating_hamiltonian`; the quadratic Hamiltonian with the same
    flow from a given ``X0``, for :func:`jetgaudin.integrate`, is :func:`jetgaudin.interpolating_flow_hamiltonian`).

    Parameters
    ----------
    system : float or GaudinModel
        ``b`` (``b ≠ 0``): the top of any N with field ``b e_3`` (states ``(..., 3N)``, N from the state; ``kind``
        ``"two_point"``); or a :class:`~jetgaudin.GaudinModel` (states ``(..., 3M)``; ``kind`` ``"chain_two_point"``;
        ``Re η`` off the sites).  The old keywords ``b=`` / ``model=`` are accepted.
    eta : complex
        ``Im η ≠ 0`` (``Im η`` is the time step: ``Im η = 0`` would be the identity map and is refused with
        :class:`InvalidParameterError`).
    branch : Branch or {"default", "opposite"}
        ``ν1 = ±ν(η)`` by the branch rule; ``"opposite"`` is the inverse map.
    backend, kernel : Backend or {"auto", "numpy", "compiled", "gpu"}
        The route of :meth:`advance` / :meth:`iterate` by the rule of :mod:`jetgaudin.maps` (the carry is ``ν1``);
        which compiled kernels run is the route table of :mod:`jetgaudin._system_maps`.

    ``ChainTwoPointBacklund`` is this class (its old name for chains).

    >>> import jetgaudin as jg
    >>> B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> orbit = B.iterate(X0, 10)
    >>> orbit.shape
    (11, 9)
    >>> import numpy as np
    >>> bool(np.allclose(jg.integrals(orbit, 1.0), jg.integrals(X0, 1.0), rtol=1e-12, atol=1e-12))
    True
    >>> C = jg.TwoPointBacklund(jg.GaudinModel(1.0, [(0, 3)]), 5 + 0.1j)
    >>> type(C) is jg.ChainTwoPointBacklund is jg.TwoPointBacklund, C.kind
    (True, 'chain_two_point')
    """

    system: Any
    eta: complex
    branch: Branch = Branch.DEFAULT
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_TWO_POINT_PROPERTIES, init=False, repr=False, compare=False)
    kernel: Backend | str | None = field(default=None, repr=False, compare=False)  # the alias of backend

    _MAP_KIND: ClassVar[str] = "two_point"
    _KINDS: ClassVar[dict[str, str]] = {"top": "two_point", "chain": "chain_two_point"}
    _ARGS: ClassVar[tuple[str, ...]] = ("eta", "branch", "backend")

    def __init__(self, system: Any = _MISSING, eta: Any = _MISSING, branch: Branch | str | int = Branch.DEFAULT,
                 backend: Backend | str = Backend.AUTO, kernel: Backend | str | None = None, *, b: Any = _MISSING,
                 model: Any = _MISSING) -> None:
        system = _pick_system(type(self).__name__, system, b, model)
        if eta is _MISSING:
            raise TypeError(f"{type(self).__name__}() missing required argument: 'eta'")
        self._build(system, (eta, branch, backend), kernel)


@dataclass(frozen=True, init=False, repr=False)
class OnePointBacklund(_SystemMap):
    r"""The complex one-point Bäcklund map ``B_(η, ν)`` of Section 6.1 (or its inverse) of the top of any N or of a
    chain (rational family, ``b ≠ 0``; trigonometric, ``b + iγJ ≠ 0``).

    Forward: ``L̃ = M L M^{-1}`` with ``M = [[λ − η + pq, p], [q, 1]]`` (eq. (ansatz)), ``p = S^-/(2b)`` (hh; the
    top's ``y_0^-``, a chain's sum of every site's), ``q = (u(η) − ν)/v(η)`` (hhh, with the paper's ``μ`` read as
    ``ν``): ``[1, −q]`` is the eigenvector of ``ℓ(η)`` for ``ν``.  Inverse (``inverse_map=True``):
    ``L = M^{-1} L̃ M`` with ``q = S̃^+/(2b)`` and ``p = (ũ(η) − ν)/w̃(η)``; it is *not* the forward map on the other
    sheet.  ``ν = ±ν(η)`` by the branch rule (``branch="opposite"``: ``−ν(η)``).  Real input gives complex output;
    it preserves the integrals and is Poisson (holomorphically); the carry of :meth:`advance` is ``ν``, the
    imaginary residue zeros.  ``backend`` (alias ``kernel``): the NumPy route only (``"auto"`` is ``"numpy"``;
    ``"compiled"`` is refused).

    ``system``: ``b`` (the top of any N, ``kind`` ``"one_point"``) or a :class:`~jetgaudin.GaudinModel` (``kind``
    ``"chain_one_point"``; the elliptic family has no one-point map: refused, the reason in the message).
    ``ChainOnePointBacklund`` is this class.
    """

    system: Any
    eta: complex
    branch: Branch = Branch.DEFAULT
    inverse_map: bool = False
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_ONE_POINT_PROPERTIES, init=False, repr=False, compare=False)
    kernel: Backend | str | None = field(default=None, repr=False, compare=False)  # the alias of backend

    _MAP_KIND: ClassVar[str] = "one_point"
    _KINDS: ClassVar[dict[str, str]] = {"top": "one_point", "chain": "chain_one_point"}
    _ARGS: ClassVar[tuple[str, ...]] = ("eta", "branch", "inverse_map", "backend")

    def __init__(self, system: Any = _MISSING, eta: Any = _MISSING, branch: Branch | str | int = Branch.DEFAULT,
                 inverse_map: bool = False, backend: Backend | str = Backend.AUTO,
                 kernel: Backend | str | None = None, *, b: Any = _MISSING, model: Any = _MISSING) -> None:
        system = _pick_system(type(self).__name__, system, b, model)
        if eta is _MISSING:
            raise TypeError(f"{type(self).__name__}() missing required argument: 'eta'")
        self._build(system, (eta, branch, inverse_map, backend), kernel)


@dataclass(frozen=True, init=False, repr=False, eq=False)  # eq=False as before: equal when the same object
class ExactFlow(_SystemMap):
    r"""The exact time-``dt`` flow of a Hamiltonian ``H`` as a :class:`~jetgaudin.maps.Map`, for the top and for every
    chain: one step is ``substeps`` times ``R_θ ∘ B_{η_1} ∘ … ∘ B_{η_k}`` (commuting two-point maps and a rotation
    about the field) with parameters solved per orbit from its integrals (``docs/integrators.md``).

    ``H``: an :class:`~jetgaudin.IntegralHamiltonian` (the top of any ``N ≥ 2``, field ``b e_3``: the route
    :class:`jetgaudin.exact._TopExactFlow`, ``kind`` ``"exact"``; ``backend`` ``NUMPY`` or ``COMPILED``, ``AUTO``:
    compiled) or a chain's Hamiltonian ``model.hamiltonian(weights)`` (:class:`~jetgaudin.ChainHamiltonian`, every
    family: the route :class:`jetgaudin.exact_chain._ChainExactFlow`, ``kind`` ``"chain_exact"``; ``backend``
    NUMPY, or COMPILED: the compiled solve and loop, ``AUTO``: compiled where the family has them).  ``dt``: either
    sign (``−dt`` is :meth:`inverse`).  It preserves the integrals, is a Poisson map
    and real; the step *is* the flow (``order = None``).  Not chunk-invariant (``chunk_invariant = False``: the run
    layer cuts runs into fixed chunks).  ``ChainExactFlow`` is this class (its old name for chains; its old third and
    fourth positional arguments were ``rho_factor, substeps``: pass them by keyword).
    :class:`jetgaudin.exact.MatchedBacklund` (one map per step, the top's baseline) stays its own class.

    >>> import jetgaudin as jg, numpy as np
    >>> H = jg.physical_hamiltonian(3, 1.0)
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> X1 = jg.ExactFlow(H, 0.05).iterate(X0, 2)[-1]
    >>> ref = jg.integrate(H, X0, 0.1, rtol=1e-13, atol=1e-13).X[-1]
    >>> bool(np.max(np.abs(X1 - ref)) < 1e-12)
    True
    """

    H: Any
    dt: float
    substeps: int = 1
    backend: Backend = field(default=Backend.AUTO, compare=False)
    rho_factor: float | None = None  # None: the implementation's default (jetgaudin.exact.RHO_FACTOR)
    properties: MapProperties = field(default=_EXACT_PROPERTIES, init=False, repr=False, compare=False)
    kernel: Backend | str | None = field(default=None, repr=False, compare=False)  # the alias of backend

    _MAP_KIND: ClassVar[str] = "exact"
    _KINDS: ClassVar[dict[str, str]] = {"top": "exact", "chain": "chain_exact"}
    _ARGS: ClassVar[tuple[str, ...]] = ("dt", "substeps", "backend", "rho_factor")
    _SYSTEM: ClassVar[str] = "H"

    def __init__(self, H: Any = _MISSING, dt: Any = _MISSING, substeps: int = 1, backend: Backend | str = Backend.AUTO,
                 rho_factor: float | None = None, *, kernel: Backend | str | None = None) -> None:
        if H is _MISSING or dt is _MISSING:
            raise TypeError(f"{type(self).__name__}() missing required argument: {'H' if H is _MISSING else 'dt'}")
        sk = self._system_kind(H)
        cls = _implementation("exact", sk)
        kw: dict[str, Any] = {"substeps": substeps}
        if rho_factor is not None:
            kw["rho_factor"] = rho_factor
        kw.update(backend=backend, kernel=kernel)  # both implementations take the maps' rule (numpy, compiled, auto)
        self._adopt(cls(H, dt, **kw), sk)

    @classmethod
    def _system_kind(cls, H: Any) -> str:
        if getattr(H, "route_kind", None) == "top":  # the one Hamiltonian type: its system decides
            return "top"
        if callable(getattr(getattr(H, "model", None), "two_point_backlund", None)):
            return "chain"
        raise InvalidParameterError(
            f"the first argument of {cls.__name__} is a Hamiltonian: an IntegralHamiltonian (the top, e.g. "
            "jg.physical_hamiltonian(N, b)) or a chain's model.hamiltonian(weights) (a ChainHamiltonian); got "
            f"{type(H).__name__}"
        )

    def bind_run(self, X0: Any) -> Any:
        """The implementation's :meth:`bind_run` (the run layer's per-run set-up, :func:`jetgaudin.run.spec.run_map`:
        the chain exact flow's parameters), wrapped; this map where the implementation has none."""
        impl = self._r()
        bind = getattr(type(impl), "bind_run", None)
        new = bind(impl, X0) if callable(bind) else impl
        return self if new is impl else self._wrap(new)

    def unbound(self) -> Any:
        """The implementation's :meth:`unbound`, wrapped; this map where the implementation has none."""
        impl = self._r()
        unbind = getattr(type(impl), "unbound", None)
        new = unbind(impl) if callable(unbind) else impl
        return self if new is impl else self._wrap(new)

    @staticmethod
    def _system_of(impl: Any, sk: str) -> Any:
        return impl.H
