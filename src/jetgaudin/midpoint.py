r"""The implicit midpoint rule for ``Ẋ = f(X) = Π(X) ∇H`` (eq. (LP)), a baseline of ``docs/integrators.md``.

.. math:: X_{n+1} = X_n + dt\, f\big((X_n + X_{n+1})/2\big),

solved by Newton's method with the exact Jacobian: ``∇H = A X + g0`` is affine (every integral ``κ_m`` is
quadratic in ``X``), so ``f`` is quadratic and ``∂f_i/∂X_k = Σ_J c_{iJk} (A X + g0)_J + (Π(X) A)_{ik}``.  Symmetric,
order 2, and it preserves every quadratic first integral exactly (Cooper's theorem): ``H`` itself and all the
``κ_m`` (``H_k``, ``C_k``), which are quadratic in ``X``; it is not a Poisson map of the Lie–Poisson bracket.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._errors import IntegrationError, InvalidParameterError
from ._validate import as_state
from .exact import FixedStep, nonzero_step
from .hamiltonians import IntegralHamiltonian
from .maps import Backend, Map, MapProperties, register_map
from .spectral import integrals

__all__ = ["ImplicitMidpoint"]

#: Newton stops when ``max|ΔX| ≤ _NEWTON_TOL (1 + max|X|)`` (the update is then at round-off)
_NEWTON_TOL = 4e-16
_NEWTON_ITERATIONS = 30

_MIDPOINT_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=False, real=True, order=2, symmetric=True, interpolates_flow=False
)


@dataclass(frozen=True, eq=False)
class ImplicitMidpoint(FixedStep, Map):
    """One step of the implicit midpoint rule for ``H`` (an :class:`~jetgaudin.IntegralHamiltonian`) with time step
    ``dt`` (either sign; ``−dt`` is :meth:`inverse`).  States ``(3N,)`` or ``(..., 3N)``; no carry.  ``backend``
    (alias ``kernel``; the rule of :mod:`jetgaudin.maps`): the NumPy route only (``"compiled"`` is refused)."""

    H: IntegralHamiltonian
    dt: float
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_MIDPOINT_PROPERTIES, init=False, repr=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias of backend

    def __post_init__(self) -> None:
        if not isinstance(self.H, IntegralHamiltonian) or np.ndim(self.H.weights) != 1:
            raise InvalidParameterError("H must be an IntegralHamiltonian with one set of weights (shape (2N,))")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        self._init_backend()

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(integrals(X, self.H.b, self.H.c), dtype=float)

    def _affine(self):
        from .algebra import structure_constants

        n = 3 * self.H.N
        g0 = self.H.gradient(np.zeros(n))
        A = np.stack([self.H.gradient(np.eye(n)[j]) - g0 for j in range(n)], axis=1)
        return A, g0, structure_constants(self.H.N)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        X, N = as_state(X)
        if N != self.H.N:
            raise InvalidParameterError(f"states need 3N = {3 * self.H.N} components, got {3 * N}")
        A, g0, c = self._affine()
        n, h = 3 * N, self.dt
        Y = X.copy()
        for _ in range(_NEWTON_ITERATIONS):
            M = 0.5 * (X + Y)
            g = M @ A.T + g0
            P = np.einsum("iJk,...k->...iJ", c, M)
            F = Y - X - h * np.einsum("...iJ,...J->...i", P, g)
            Jf = np.einsum("iJk,...J->...ik", c, g) + P @ A
            dY = np.linalg.solve(np.eye(n) - 0.5 * h * Jf, F[..., None])[..., 0]
            Y = Y - dY
            if np.max(np.abs(dY)) <= _NEWTON_TOL * (1.0 + np.max(np.abs(Y))):
                break
        else:
            raise IntegrationError(f"implicit midpoint: Newton did not converge in {_NEWTON_ITERATIONS} iterations "
                                   f"(dt = {h:g} too large for this state); give a smaller dt")
        zeros = np.zeros(X.shape[:-1])
        return Y, zeros.astype(complex), zeros

    def inverse(self) -> ImplicitMidpoint:
        return ImplicitMidpoint(self.H, -self.dt, self.backend)

    def describe(self) -> dict:
        return {"kind": "midpoint", "b": np.asarray(self.H.b, dtype=float).tolist(),
                "weights": np.asarray(self.H.weights).tolist(), "dt": self.dt, "backend": self.backend.value}


def _midpoint_from(d: dict) -> ImplicitMidpoint:
    return ImplicitMidpoint(IntegralHamiltonian(d["b"], np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                            d.get("backend", "auto"))


register_map("midpoint", _midpoint_from)
