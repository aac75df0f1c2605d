r"""The implicit midpoint rule for ``Ẋ = f(X) = Π(X) ∇H`` (eq. (LP)), a baseline of ``docs/integrators.md``, for the
Hamiltonian of any model (:class:`jetgaudin.hamiltonians.SolveHamiltonian`: a top, a chain of any family, an su(n)
chain).

.. math:: X_{n+1} = X_n + dt\, f\big((X_n + X_{n+1})/2\big),

solved by Newton's method.  For a quadratic ``H`` on a linear bracket (the tops and the su(2) chains of every family:
every integral is quadratic in ``X``) ``∇H = A X + g0`` is affine, so ``f`` is quadratic and the Jacobian is exact:
``∂f_i/∂X_k = Σ_J c_{iJk} (A X + g0)_J + (Π(X) A)_{ik}`` (``c`` the structure constants: of ``g^(N)`` for a top, the
chain's block ones, ``H.structure_constants``).  Otherwise (an su(n) chain, ``n ≥ 3``: the integrals ``h^(k)`` are
of degree ``k``) the Jacobian is by central differences of ``H.vector_field``; Newton's residual is exact either
way, so it converges to the same midpoint state (an approximate Jacobian only slows the convergence).

Symmetric, order 2, and it preserves every quadratic first integral exactly (Cooper's theorem): for a quadratic
``H`` that is ``H`` itself and all the integrals (``κ_m``, ``h_{i,m}``, a family's extras); for an su(n) chain
only the quadratic ones.  It is not a Poisson map of the Lie–Poisson bracket.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from ._errors import IntegrationError, InvalidParameterError
from .exact import FixedStep, nonzero_step
from .hamiltonians import IntegralHamiltonian, SolveHamiltonian
from .maps import Backend, Map, MapProperties, register_map

__all__ = ["ImplicitMidpoint"]

#: Newton stops when ``max|ΔX| ≤ _NEWTON_TOL (1 + max|X|)`` (the update is then at round-off)
_NEWTON_TOL = 4e-16
_NEWTON_ITERATIONS = 30

_MIDPOINT_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=False, real=True, order=2, symmetric=True, interpolates_flow=False
)


#: relative step of the central differences of the Jacobian of a non-quadratic field (error ~1e-10 relative:
#: Newton then contracts by that factor per iteration)
_FD_STEP = 1e-5


def quadratic_field(H: Any, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    r"""``(A, g0, c)`` with ``∇H(X) = A X + g0`` and ``Π(X)_{iJ} = Σ_k c[i, J, k] X_k`` when ``H`` is quadratic on a
    linear bracket (a top: ``g^(N)``; a chain: ``H.structure_constants``), else ``None``."""
    from .algebra import structure_constants

    top = getattr(H, "route_kind", None) == "top"  # the one Hamiltonian type: its system decides
    c: Any = structure_constants(H.N) if top else getattr(H, "structure_constants", None)
    if c is None:
        return None
    g0 = np.asarray(H.gradient(np.zeros(n)), dtype=float)
    A = np.stack([np.asarray(H.gradient(np.eye(n)[j]), dtype=float) - g0 for j in range(n)], axis=1)
    return A, g0, np.asarray(c, dtype=float)


def _fd_jacobian(field_, M: np.ndarray) -> np.ndarray:
    """``∂f_i/∂X_k`` at ``M`` ``(..., n)`` by central differences, shape ``(..., n, n)``."""
    n = M.shape[-1]
    eps = _FD_STEP * (1.0 + np.max(np.abs(M)))
    cols = [(np.asarray(field_(M + eps * e)) - np.asarray(field_(M - eps * e))) / (2 * eps) for e in np.eye(n)]
    return np.stack(cols, axis=-1)


@dataclass(frozen=True, eq=False)
class ImplicitMidpoint(FixedStep, Map):
    """One step of the implicit midpoint rule for ``H`` (any model's Hamiltonian with one set of weights: the protocol
    :class:`~jetgaudin.hamiltonians.SolveHamiltonian`) with time step ``dt`` (either sign; ``−dt`` is
    :meth:`inverse`).  States ``(n_state,)`` or ``(..., n_state)``; no carry.  ``properties.preserves_integrals``:
    true for a quadratic ``H`` (every integral then quadratic; module doc), false for an su(n) chain, ``n ≥ 3``.
    ``backend`` (alias ``kernel``; the rule of :mod:`jetgaudin.maps`): the NumPy route only (``"compiled"`` is
    refused)."""

    H: Any
    dt: float
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_MIDPOINT_PROPERTIES, init=False, repr=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias of backend

    def __post_init__(self) -> None:
        if not isinstance(self.H, SolveHamiltonian) or np.ndim(getattr(self.H, "weights", ())) != 1:
            raise InvalidParameterError("H must be a Hamiltonian with one set of weights: jg.physical_hamiltonian(N, "
                                        "b), jg.IntegralHamiltonian(b, w) (w of shape (2N,)) or model.hamiltonian(w)")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        self._init_backend()
        if self._quadratic is None:
            object.__setattr__(self, "properties", replace(_MIDPOINT_PROPERTIES, preserves_integrals=False))

    @property
    def n_state(self) -> int:
        return int(self.H.n_state)

    @cached_property
    def _quadratic(self):
        return quadratic_field(self.H, self.n_state)

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.H.record_integrals(X), dtype=float)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        X = np.asarray(self.H.check_state(X), dtype=float)
        quad = self._quadratic
        n, h = X.shape[-1], self.dt
        Y = X.copy()
        prev = np.inf
        for _ in range(_NEWTON_ITERATIONS):
            M = 0.5 * (X + Y)
            if quad is not None:
                A, g0, c = quad
                g = M @ A.T + g0
                P = np.einsum("iJk,...k->...iJ", c, M)
                F = Y - X - h * np.einsum("...iJ,...J->...i", P, g)
                Jf = np.einsum("iJk,...J->...ik", c, g) + P @ A
            else:
                F = Y - X - h * np.asarray(self.H.vector_field(M))
                Jf = _fd_jacobian(self.H.vector_field, M)
            dY = np.linalg.solve(np.eye(n) - 0.5 * h * Jf, F[..., None])[..., 0]
            Y = Y - dY
            size = float(np.max(np.abs(dY))) if dY.size else 0.0
            tol = _NEWTON_TOL * (1.0 + float(np.max(np.abs(Y))) if Y.size else 1.0)
            # converged: the update at round-off, or (a field evaluated with more round-off) stalled near it
            if size <= tol or (quad is None and size <= 64 * tol and size >= 0.5 * prev):
                break
            prev = size
        else:
            raise IntegrationError(f"implicit midpoint: Newton did not converge in {_NEWTON_ITERATIONS} iterations "
                                   f"(dt = {h:g} too large for this state); give a smaller dt")
        zeros = np.zeros(X.shape[:-1])
        return Y, zeros.astype(complex), zeros

    def inverse(self) -> ImplicitMidpoint:
        return ImplicitMidpoint(self.H, -self.dt, self.backend)

    def describe(self) -> dict:
        d: dict = {"kind": "midpoint", "weights": np.asarray(self.H.weights).tolist(), "dt": self.dt,
                   "backend": self.backend.value}
        model = getattr(self.H, "model", None)
        if model is not None:
            d["model"] = model.describe()
        else:
            d["b"] = np.asarray(self.H.b, dtype=float).tolist()
            if self.H.c is not None:
                d["c"] = np.asarray(self.H.c).tolist()
        return d


def _midpoint_from(d: dict) -> ImplicitMidpoint:
    w = np.asarray(d["weights"], dtype=float)
    if "model" in d:
        from .gaudin import GaudinModel

        H: Any = GaudinModel.from_description(d["model"]).hamiltonian(w)
    else:
        H = IntegralHamiltonian(d["b"], w, d.get("c"))
    return ImplicitMidpoint(H, float(d["dt"]), d.get("backend", "auto"))


register_map("midpoint", _midpoint_from)
