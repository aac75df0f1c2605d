r"""Ready models: the N = 1, 2, 3 tops of the hierarchy (Sections 1, 4).

A :class:`GaudinTop` is a *system*: an algebra :math:`\mathfrak g^{(N)}`, a field ``b e_3``,
the Lax matrix (lax2)/(kkk), the physical Hamiltonian and the integrals.  It knows nothing
about stepping (see :mod:`jetgaudin.flows` and :mod:`jetgaudin.backlund`).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

from ._validate import as_state, check_N, field_vector, nonzero_field
from .hamiltonians import IntegralHamiltonian, physical_hamiltonian
from .lax import SIGMA, lax_matrix
from .spectral import integrals

__all__ = ["GaudinTop", "euler_top", "lagrange_top", "generalized_lagrange_top", "twisted_top_rhs",
           "material_point", "material_point_rhs"]


@dataclass(frozen=True)
class GaudinTop:
    r"""The N-th system of the hierarchy with field ``b e_3`` (``b ≠ 0``) and Lax matrix (lax2).

    ``N = 1``: a spin in a field; ``N = 2``: the Lagrange top; ``N = 3``: the generalised
    (twisted) Lagrange top of Section 4.
    """

    N: int
    b: float

    def __post_init__(self):
        object.__setattr__(self, "N", check_N(self.N))
        object.__setattr__(self, "b", nonzero_field(self.b))

    @property
    def model(self):
        """This top as the one-site model ``GaudinModel(b, [(0, N)])`` (rational; issue 33): the same integrals
        (``h_m = H_m``, ``h_{N+k} = C_k``), bracket, Hamiltonian vector fields and maps to round-off
        (``tests/test_top_as_model.py``); the model's maps take this top's hand-tuned kernels as a route
        (``model.is_top``, ``docs/architecture.md``).  ``GaudinTop`` stays as this thin view.  One difference of
        names: for ``N = 1`` :attr:`hamiltonian` is ``H_1/2`` while ``model.physical_hamiltonian()`` is the model's
        rule ``½ h_{1,2}`` (a Casimir there); for ``N ≥ 2`` both are ``H_2/2``."""
        return self.as_model()

    def as_model(self):
        """:attr:`model` (a fresh :class:`jetgaudin.GaudinModel`)."""
        # by name, as the map registry does (jetgaudin.maps): the system layer imports no method-layer module
        GaudinModel = importlib.import_module("jetgaudin.gaudin.model").GaudinModel  # noqa: N806
        return GaudinModel(self.b, [(0.0, self.N)])

    @property
    def hamiltonian(self) -> IntegralHamiltonian:
        """``H = H_2/2`` (eq. (H)); ``H_1/2`` for ``N = 1``."""
        return physical_hamiltonian(self.N, self.b)

    def energy(self, X):
        return self.hamiltonian(self._state(X))

    def integrals(self, X):
        """``(H_1..H_N, C_1..C_N)`` of Prop. 2, shape ``(..., 2N)``."""
        return integrals(self._state(X), self.b)

    def vector_field(self, X):
        r"""``Ẋ = Π(X)∇H``."""
        return self.hamiltonian.vector_field(self._state(X))

    def lax_matrix(self, lam, X):
        return lax_matrix(lam, self._state(X), self.b)

    def lax_pair(self, lam, X):
        r"""``(L(λ), M(λ))`` with ``dL/dt = [M, L]`` along the flow of ``H_2/2`` (``N ≥ 2``).

        ``M(λ) = Σ_{i=1}^{N-1} Y_i λ^{-i}`` with ``Y_i = Σ_α σ^α y_i^α``; for ``N = 3`` this is
        ``M = X/λ + Z/λ²`` of the Proposition in Section 4.1.  The paper prints ``dL/dt = [L, M]``;
        with its σ^α (for which ``[σ^α, σ^β] = −ε^{αβγ} σ^γ``) and the brackets (LP) the correct sign
        is ``[M, L]`` (``docs/errata.md``; checked in ``tests/test_systems.py``).
        """
        X = self._state(X)
        lam = np.asarray(lam, dtype=complex)
        y = X.reshape(X.shape[:-1] + (self.N, 3))
        M = 0
        for i in range(1, self.N):
            M = M + np.einsum("...a,aij->...ij", y[..., i, :], SIGMA) / lam[..., None, None] ** i
        return self.lax_matrix(lam, X), M

    def _state(self, X):
        X, N = as_state(X)
        if N != self.N:
            from ._errors import InvalidStateError

            raise InvalidStateError(f"this system has N = {self.N}: states need {3 * self.N} components, got {3 * N}")
        return X


def euler_top(b: float) -> GaudinTop:
    """N = 1."""
    return GaudinTop(1, b)


def lagrange_top(b: float) -> GaudinTop:
    """N = 2: the Lagrange top (y, x) with ``H = |y|²/2 + b x^3``."""
    return GaudinTop(2, b)


def generalized_lagrange_top(b: float) -> GaudinTop:
    """N = 3: the generalised (twisted) Lagrange top of Section 4, field (0, 0, b)."""
    return GaudinTop(3, b)


def twisted_top_rhs(X, b: float):
    r"""The equations of motion (em) written out, ``N = 3``, field ``b e_3`` (``b`` a float) or a 3-vector ``b``:

    .. math:: \dot y = b \wedge x, \quad \dot x = y \wedge x + b \wedge z, \quad \dot z = y \wedge z.
    """
    X, N = as_state(X)
    if N != 3:
        from ._errors import InvalidStateError

        raise InvalidStateError(f"(em) is for N = 3 (9 components), got {3 * N}")
    bv = field_vector(b)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    return np.concatenate(
        [np.cross(np.broadcast_to(bv, x.shape), x), np.cross(y, x) + np.cross(np.broadcast_to(bv, z.shape), z),
         np.cross(y, z)],
        axis=-1,
    )


def _state3(X, what):
    X, N = as_state(X)
    if N != 3:
        from ._errors import InvalidStateError

        raise InvalidStateError(f"{what} is defined for N = 3 (9 components (y, x, z)), got {3 * N}")
    return X


def material_point(X):
    r"""Position ``x − z`` of the material point (Section 4), shape ``(..., 3)``, ``N = 3``."""
    X = _state3(X, "the material point")
    return X[..., 3:6] - X[..., 6:9]


def material_point_rhs(X, b: float):
    r"""``d/dt (x − z) = y ∧ (x − z) + b ∧ z`` (Section 4)."""
    X = _state3(X, "the material point equation")
    bv = np.broadcast_to(field_vector(b), X[..., 6:9].shape)
    return np.cross(X[..., 0:3], X[..., 3:6] - X[..., 6:9]) + np.cross(bv, X[..., 6:9])
