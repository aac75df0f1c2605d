r"""Hamiltonians built from the spectral invariants: the physical H = H_2/2 of eq. (H), any
linear combination of the integrals ``κ_m`` (``H_k``, ``C_k``), and the interpolating
Hamiltonian ``G_η = i ∫_{η̄}^{η} ν(λ) dλ`` of the real two-point Bäcklund map.

``G_η`` depends on the state only through the integrals, so its Hamiltonian vector field at
``X`` is ``Σ_m ω_m X_{κ_m}`` with ``ω_m = ∂G_η/∂κ_m`` constant along its own flow: the flow of
``G_η`` for time ``T`` is the flow of the quadratic Hamiltonian ``Σ_m ω_m(X_0) κ_m`` for time ``T``.

Which is which:

* :func:`interpolating_hamiltonian` ``(X, b, η)`` -- the **value** ``G_η(X)`` (a number per state; the quadrature
  of ``ν`` along the segment);
* :func:`interpolating_weights` ``(X, b, η)`` -- its gradient coordinates ``ω_m = ∂G_η/∂κ_m`` at ``X``;
* :func:`interpolating_flow_hamiltonian` ``(X0, b, η)`` -- an :class:`IntegralHamiltonian` ``Σ_m ω_m(X0) κ_m``
  (weights frozen at ``X0``) to **integrate**: its flow from ``X0`` is the flow of ``G_η`` (time 1: the two-point
  map), not from another state;
* :func:`interpolating_vector_field` ``(X, b, η)`` -- the vector field of ``G_η`` itself, each state with its own
  weights.
"""

from __future__ import annotations

import importlib
import numbers
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from ._errors import InvalidParameterError, InvalidStateError
from ._validate import as_state, check_N, field_vector, real_array, spectral_parameter
from .algebra import hamiltonian_vector_field
from .spectral import _nu_from_kappa, _roots, curve_coefficients, integral_gradients, integrals

__all__ = [
    "SolveHamiltonian",
    "IntegralHamiltonian",
    "physical_hamiltonian",
    "interpolating_hamiltonian",
    "interpolating_weights",
    "interpolating_flow_hamiltonian",
    "interpolating_vector_field",
]


@runtime_checkable
class SolveHamiltonian(Protocol):
    r"""What :func:`jetgaudin.solve` needs of a Hamiltonian ``H`` of any model (issue 33: one protocol, no top/chain
    branch): the top's :class:`IntegralHamiltonian`, a chain's :class:`jetgaudin.ChainHamiltonian`
    (``model.hamiltonian(weights)``, every family) and an su(n) chain's :class:`jetgaudin.gaudin.sun.SunHamiltonian`.

    * ``route_kind`` -- the key of the Hamiltonian's rows in the route table :data:`jetgaudin.methods.ROUTES`
      (``"top"``, ``"chain"``, ``"sun"``): which map each method of ``solve`` builds (``docs/architecture.md``);
    * ``n_state`` -- the length of a state;
    * ``check_state(X)`` -- ``X`` as a float array ``(..., n_state)``, or :class:`jetgaudin.InvalidStateError`;
    * ``record_integrals(X)`` -- the integrals a trajectory records (and its ``drift`` compares);
    * ``gradient(X)``, ``vector_field(X)`` -- ``∇H`` and ``Ẋ = Π(X)∇H`` (eq. (LP); a chain: its block bracket).
    """

    @property
    def route_kind(self) -> str: ...

    @property
    def n_state(self) -> int: ...

    def check_state(self, X) -> np.ndarray: ...

    def record_integrals(self, X) -> np.ndarray: ...

    def gradient(self, X) -> np.ndarray: ...

    def vector_field(self, X) -> np.ndarray: ...


@dataclass(frozen=True)
class _TopHamiltonian:
    r"""The top's route of :class:`IntegralHamiltonian` (its system a field ``b``):
    ``H(X) = Σ_{m=1}^{2N} w_m κ_m(X)``, a linear combination of ``(H_1..H_N, C_1..C_N)``.

    ``weights`` has shape ``(2N,)`` or ``(..., 2N)`` (one combination per ensemble member);
    ``b`` is a float (field ``b e_3``) or a 3-vector; ``c`` the constants of eq. (lax).
    """

    b: object
    weights: np.ndarray
    c: object = None

    def __post_init__(self):
        w = real_array(self.weights, "weights")
        if w.ndim == 0 or w.shape[-1] % 2 or w.shape[-1] == 0:
            raise InvalidParameterError("weights must have a trailing axis of length 2N")
        if not np.all(np.isfinite(w)):
            raise InvalidParameterError("weights must be finite")
        object.__setattr__(self, "weights", w)
        field_vector(self.b)

    #: its rows of the route table of :func:`jetgaudin.solve` (:class:`SolveHamiltonian`)
    route_kind: ClassVar[str] = "top"

    @property
    def N(self) -> int:
        return self.weights.shape[-1] // 2

    @property
    def n_state(self) -> int:
        """``3N``, the length of a state."""
        return 3 * self.N

    def check_state(self, X) -> np.ndarray:
        """``X`` as a float array ``(..., 3N)`` (:class:`InvalidStateError` for another length; the protocol of
        :class:`SolveHamiltonian`)."""
        return self._check(X)

    def record_integrals(self, X) -> np.ndarray:
        """The integrals ``(H_1..H_N, C_1..C_N)`` at ``X`` (with this Hamiltonian's ``b`` and ``c``), ``(..., 2N)``."""
        return np.asarray(integrals(self._check(X), self.b, self.c), dtype=float)

    def as_model(self):
        """The same Hamiltonian on the one-site model ``GaudinModel(b, [(0, N, c)])`` (a
        :class:`jetgaudin.ChainHamiltonian` with the same weights: ``h_m = H_m``, ``h_{N+k} = C_k``; integrals,
        vector field and maps equal to round-off, ``tests/test_top_as_model.py``; with the jet constants ``c`` of eq.
        (lax) as the site's option, ``tests/test_site_constants.py``).  Needs a field along ``e_3`` and real ``c``
        with ``c_1 ≠ 0``; otherwise :class:`InvalidParameterError` naming which."""
        bv = field_vector(self.b)
        if bv[0] != 0.0 or bv[1] != 0.0:
            raise InvalidParameterError(f"as_model: a model's field is b e_3; this Hamiltonian's is {bv.tolist()}")
        # by name, as the map registry does (jetgaudin.maps): the system layer imports no method-layer module
        GaudinModel = importlib.import_module("jetgaudin.gaudin.model").GaudinModel  # noqa: N806
        return GaudinModel(float(bv[2]), [(0.0, self.N)], constants=[self.c]).hamiltonian(self.weights)

    def _check(self, X):
        X, N = as_state(X)
        if N != self.N:
            raise InvalidStateError(
                f"this Hamiltonian has {2 * self.N} weights (N = {self.N}): states need {3 * self.N} "
                f"components, got {3 * N}"
            )
        return X

    def __call__(self, X):
        return np.sum(self.weights * integrals(self._check(X), self.b, self.c), axis=-1)

    def gradient(self, X):
        return np.einsum("...m,...mi->...i", self.weights, integral_gradients(self._check(X), self.b, self.c))

    def vector_field(self, X):
        r"""``Ẋ = Π(X) ∇H`` (eq. (LP)), shape ``(..., 3N)``."""
        return hamiltonian_vector_field(self.gradient(X), X)


#: the route table of the Hamiltonian: system -> (module, implementation class), imported on use (the chain's lives in
#: the method layer's gaudin package: this system-layer module imports it by name only)
HAMILTONIAN_ROUTES: dict[str, tuple[str, str]] = {
    "top": ("jetgaudin.hamiltonians", "_TopHamiltonian"),
    "chain": ("jetgaudin.gaudin.hamiltonian", "_ChainHamiltonian"),
}
_MISSING: Any = object()


@dataclass(frozen=True, init=False, repr=False)
class IntegralHamiltonian:
    r"""``H(X) = Σ_I w_I κ_I(X)``, a linear combination of a system's integrals: one type for the top and every su(2)
    chain (issue 33; ``ChainHamiltonian`` is this class, and ``model.hamiltonian(weights)`` builds it).

    ``system``: a field ``b`` (a float, field ``b e_3``, or a 3-vector: the top of ``N = len(weights)/2``, integrals
    ``(H_1..H_N, C_1..C_N)`` of eq. (H); ``c`` the constants of eq. (lax); ``route_kind`` ``"top"``) or a
    :class:`~jetgaudin.GaudinModel` (a chain of any family: its integrals ``h_{i,m}`` (and ``J``), weights of length
    ``model.n_integrals``; ``c`` must be ``None``: a chain's constants are its model's; ``route_kind`` ``"chain"``).
    ``weights``: shape ``(n,)`` or ``(..., n)`` (one combination per ensemble member).  The old keywords ``b=`` /
    ``model=`` are accepted.  What it computes is its system's implementation (:data:`HAMILTONIAN_ROUTES`, unchanged:
    the top's :class:`_TopHamiltonian`, a chain's :class:`jetgaudin.gaudin.hamiltonian._ChainHamiltonian`); the
    methods of one system only (the top's ``N``, ``as_model``; a chain's ``structure_constants``, ``as_top``) are
    its.  ``b`` is the field (a chain's: its model's), ``model`` the chain's model (``None`` for the top).  The su(n)
    chains' :class:`jetgaudin.gaudin.sun.SunHamiltonian` stays its own type (another algebra: ``tr ℓ^k`` integrals).
    """

    system: object
    weights: np.ndarray
    c: object = None

    def __init__(self, system: Any = _MISSING, weights: Any = _MISSING, c: object = None, *, b: Any = _MISSING,
                 model: Any = _MISSING) -> None:
        given = [(n, v) for n, v in (("system", system), ("b", b), ("model", model)) if v is not _MISSING]
        if len(given) != 1:
            raise InvalidParameterError(
                "IntegralHamiltonian takes its system once: a field b (the top) or a GaudinModel (a chain), as the "
                f"first argument or as b= / model=; got {', '.join(n for n, _ in given) or 'none'}")
        if weights is _MISSING:
            raise TypeError("IntegralHamiltonian() missing required argument: 'weights'")
        name, system = given[0]
        model_cls = importlib.import_module("jetgaudin.gaudin.model").GaudinModel
        sk = "chain" if isinstance(system, model_cls) else "top"
        if sk == "top" and not isinstance(system, numbers.Real | np.ndarray | list | tuple):
            raise InvalidParameterError(
                "the first argument of IntegralHamiltonian is its system: a field b (a real number or a 3-vector: the "
                "top) or a GaudinModel (a chain, e.g. jg.GaudinModel(1.0, [(0, 3)])); got " + type(system).__name__)
        if name != "system" and (name == "model") != (sk == "chain"):
            raise InvalidParameterError(f"IntegralHamiltonian: {name}= must be "
                                        + ("a GaudinModel (a chain)" if name == "model" else "a field (the top)")
                                        + f", got {type(system).__name__}; pass the system as the first argument")
        if sk == "chain" and c is not None:
            raise InvalidParameterError("c (the jet constants of eq. (lax)) is the top's; a chain's constants are its "
                                        "model's: give c = None with a GaudinModel")
        module, cls = HAMILTONIAN_ROUTES[sk]
        impl_cls = getattr(importlib.import_module(module), cls)
        impl = impl_cls(system, weights, c) if sk == "top" else impl_cls(system, weights)
        object.__setattr__(self, "system", impl.b if sk == "top" else impl.model)
        object.__setattr__(self, "weights", impl.weights)
        object.__setattr__(self, "c", impl.c if sk == "top" else None)
        object.__setattr__(self, "_impl", impl)

    def __getattr__(self, name: str) -> Any:
        impl = self.__dict__.get("_impl") if not name.startswith("__") else None
        if impl is None:
            raise AttributeError(f"'IntegralHamiltonian' object has no attribute {name!r}")
        try:
            return getattr(impl, name)
        except AttributeError:
            raise AttributeError(f"'IntegralHamiltonian' object of the {impl.route_kind} has no attribute "
                                 f"{name!r}") from None

    def __repr__(self) -> str:
        if self.route_kind == "top":
            return f"IntegralHamiltonian(b={self.system!r}, weights={self.weights!r}, c={self.c!r})"
        return f"IntegralHamiltonian(model={self.system!r}, weights={self.weights!r})"

    @property
    def route_kind(self) -> str:
        """Its rows in the route table of :func:`jetgaudin.solve` (:class:`SolveHamiltonian`): "top" or "chain"."""
        return self.__dict__["_impl"].route_kind  # type: ignore[no-any-return]

    @property
    def b(self) -> Any:
        """The field: the top's ``b`` as given (a float or a 3-vector), a chain's model's ``b``."""
        return self.__dict__["_impl"].b

    @property
    def model(self) -> Any:
        """The chain's :class:`~jetgaudin.GaudinModel` (``None`` for the top)."""
        return None if self.route_kind == "top" else self.system

    @property
    def n_state(self) -> int:
        return int(self.__dict__["_impl"].n_state)

    def check_state(self, X) -> np.ndarray:
        return self.__dict__["_impl"].check_state(X)  # type: ignore[no-any-return]

    def record_integrals(self, X) -> np.ndarray:
        return self.__dict__["_impl"].record_integrals(X)  # type: ignore[no-any-return]

    def __call__(self, X):
        return self.__dict__["_impl"](X)

    def gradient(self, X) -> np.ndarray:
        return self.__dict__["_impl"].gradient(X)  # type: ignore[no-any-return]

    def vector_field(self, X) -> np.ndarray:
        r"""``Ẋ = Π(X) ∇H`` (eq. (LP); a chain: its block bracket), shape ``(..., n_state)``."""
        return self.__dict__["_impl"].vector_field(X)  # type: ignore[no-any-return]


def physical_hamiltonian(N: int, b) -> IntegralHamiltonian:
    r"""The physical Hamiltonian of the N-th system: ``H = H_2/2`` (eq. (H)) for ``N ≥ 2``
    (``N = 2``: the Lagrange top; ``N = 3``: the generalised Lagrange top of Section 4) and
    ``H = H_1/2 = ⟨b, y_0⟩`` for ``N = 1`` (a spin in the field, the only non-Casimir integral)."""
    N = check_N(N)
    w = np.zeros(2 * N)
    w[1 if N >= 2 else 0] = 0.5
    return IntegralHamiltonian(b, w)


def _segment_setup(X, b, eta):
    X, N = as_state(X)
    eta = spectral_parameter(eta)
    if eta.real == 0:
        from ._errors import BranchPointError

        raise BranchPointError("G_eta needs Re(eta) != 0 (the segment would start at the pole lambda = 0)")
    kappa = curve_coefficients(X, b)
    roots = _roots(kappa)
    return X, N, eta, kappa, roots


def _segment_integral(X, b, eta, integrand, epsabs=1e-15, epsrel=1e-13):
    """``∫_0^{Im η} f(a + i s) ds`` for ``f`` built from ν on the default branch; vectorised."""
    X, N, eta, kappa, roots = _segment_setup(X, b, eta)
    a, h = eta.real, eta.imag

    def f(sv):
        lam = np.full(X.shape[:-1], a + 1j * sv)
        nu = _nu_from_kappa(kappa, lam, 1, roots=roots)
        return integrand(lam, nu).real

    if h == 0:
        return np.zeros(np.shape(f(0.0)))
    from scipy.integrate import quad_vec  # lazy: keeps `import jetgaudin` light

    val, _err = quad_vec(f, 0.0, h, epsabs=epsabs, epsrel=epsrel, limit=2000)
    return val


def interpolating_hamiltonian(X, b, eta):
    r"""The value ``G_η(X) = i ∫_{η̄}^{η} ν(λ; X) dλ = −2 ∫_0^{Im η} Re ν(Re η + i s) ds`` (vertical segment,
    ``ν`` on the default branch; real since ``ν(λ̄) = conj ν(λ)``).  Shape ``(...)``.  To integrate its flow use
    :func:`interpolating_flow_hamiltonian` (an :class:`IntegralHamiltonian`), not this function.  Adaptive
    quadrature (SciPy ``quad_vec``) asked for ``epsrel = 1e-13``, ``epsabs = 1e-15``."""
    return -2.0 * _segment_integral(X, b, eta, lambda lam, nu: nu)


def interpolating_weights(X, b, eta):
    r"""``ω_m = ∂G_η/∂κ_m = −2 ∫_0^{Im η} Re[λ^{-m} / (2 ν(λ))] ds`` for ``m = 1..2N``, shape ``(..., 2N)``: the
    gradient of :func:`interpolating_hamiltonian` in the integrals, the weights of
    :func:`interpolating_flow_hamiltonian`."""
    X, N = as_state(X)
    m = np.arange(1, 2 * N + 1)
    return -2.0 * _segment_integral(X, b, eta, lambda lam, nu: lam[..., None] ** (-m) / (2.0 * nu[..., None]))


def interpolating_flow_hamiltonian(X0, b, eta) -> IntegralHamiltonian:
    r"""The quadratic Hamiltonian ``Σ_m ω_m(X0) κ_m`` (an :class:`IntegralHamiltonian`, weights
    :func:`interpolating_weights` frozen at ``X0``) whose flow from ``X0`` is the flow of ``G_η``: give it to
    :func:`jetgaudin.integrate` or :class:`jetgaudin.flows.FlowMap` with the same ``X0``.  Its value is not ``G_η``
    (that is :func:`interpolating_hamiltonian`)."""
    return IntegralHamiltonian(b, interpolating_weights(X0, b, eta))


def interpolating_vector_field(X, b, eta):
    r"""The Hamiltonian vector field of ``G_η`` (:func:`interpolating_hamiltonian`) at ``X``:
    ``Π(X)∇G_η = Σ_m ω_m(X) Π(X)∇κ_m``, shape ``(..., 3N)`` (vectorised: each state uses its own weights ``ω(X)``;
    along one orbit it equals the field of :func:`interpolating_flow_hamiltonian` from any of its states)."""
    w = interpolating_weights(X, b, eta)
    return IntegralHamiltonian(b, w).vector_field(X)
