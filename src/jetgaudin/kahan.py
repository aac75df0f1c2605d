r"""Kahan's map (Kahan; Hirota–Kimura; Petrera–Pfadler–Suris) for ``Ẋ = f(X) = Π(X) ∇H`` with ``H`` quadratic.

Every model of the library has a quadratic Hamiltonian (the integrals ``κ_m`` / ``h_{i,m}`` are quadratic in ``X``)
and a linear Poisson tensor, so ``f`` is quadratic (plus a linear part from the linear terms of ``H``):
``f(X) = Q(X, X) + B X`` with ``Q`` symmetric bilinear.  Kahan's discretisation replaces ``Q(X, X)`` by
``Q(X, X')``, ``B X`` by ``B (X + X')/2``:

.. math:: \frac{X' - X}{h} = Q(X, X') + \tfrac12 B (X + X'),

linear in ``X'``.  With ``Δ = X' − X`` and ``f'(X)Δ = 2Q(X, Δ) + BΔ`` the right-hand side is
``Q(X, X) + BX + Q(X, Δ) + ½BΔ = f(X) + ½ f'(X)Δ``, so

.. math:: \big(I - \tfrac h2 f'(X)\big)\, Δ = h\, f(X), \qquad X' = X + Δ,

one linear solve per step (no Newton iteration).  Properties (each tested in ``tests/test_kahan.py``):

* order 2, **time-reversible** (``Φ_{−h} = Φ_h^{−1}``), real, birational;
* it keeps every **linear** integral ``ℓ·X`` exactly (``ℓ·f ≡ 0`` implies ``ℓ·f' ≡ 0``, so ``ℓ·Δ = 0``): for the
  top this is ``H_1 = 2b y_0^3``, an integral of every ``H = Σ w_m κ_m``;
* it is **not** integral-preserving in general and **not** a Poisson map of the Lie–Poisson bracket: the energy and
  the Casimirs oscillate at ``O(h²)`` (Petrera–Pfadler–Suris found modified integrals, deformations of the
  continuous ones by ``O(h²)``, for the Euler, Lagrange and Clebsch tops; measured in ``docs/integrators.md`` §6b).

Routes: NumPy (batched ``np.linalg.solve``) and compiled (Numba, :mod:`jetgaudin._kahan_kernels`: Gaussian
elimination with partial pivoting, one orbit or a batch over the cores, the same bits per orbit); they agree to
round-off.  ``H``: a top's :class:`~jetgaudin.IntegralHamiltonian` (one set of weights) or a chain's
:class:`~jetgaudin.ChainHamiltonian` (e.g. the Clebsch top).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._errors import IntegrationError, InvalidParameterError
from ._validate import as_state
from .exact import nonzero_step
from .hamiltonians import IntegralHamiltonian
from .maps import Advance, Backend, Map, MapProperties, register_map
from .spectral import integrals

__all__ = ["KahanMap", "kahan_step"]

#: from this many orbits the compiled route spreads them over the cores (same bits per orbit either way)
_PARALLEL_ORBITS = 64

_KAHAN_PROPERTIES = MapProperties(
    preserves_integrals=False, poisson=False, real=True, order=2, symmetric=True, interpolates_flow=False
)


def _is_chain(H: Any) -> bool:
    return getattr(H, "model", None) is not None and callable(getattr(H, "record_integrals", None))


def quadratic_field(H: Any, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""``(c, A, g0)``: ``f(X) = Π(X)(A X + g0)`` with ``Π(X)_{iJ} = Σ_k c[i, J, k] X_k`` (eq. (LP), or a chain's
    block structure) and ``∇H(X) = A X + g0`` (exact: ``H`` is quadratic)."""
    from .flows import _structure

    g0 = np.asarray(H.gradient(np.zeros(n)), dtype=float)
    A = np.stack([np.asarray(H.gradient(np.eye(n)[j]), dtype=float) - g0 for j in range(n)], axis=1)
    return np.ascontiguousarray(_structure(H, n), dtype=float), np.ascontiguousarray(A), np.ascontiguousarray(g0)


def kahan_step(X: np.ndarray, c: np.ndarray, A: np.ndarray, g0: np.ndarray, h: float) -> np.ndarray:
    r"""One step of Kahan's map from states ``X`` ``(..., n)``: ``X + (I − (h/2) f'(X))^{−1} h f(X)`` (module doc)."""
    n = X.shape[-1]
    g = X @ A.T + g0
    P = np.einsum("iJk,...k->...iJ", c, X)
    f = np.einsum("...iJ,...J->...i", P, g)
    Jf = np.einsum("iJk,...J->...ik", c, g) + P @ A
    D = np.linalg.solve(np.eye(n) - 0.5 * h * Jf, h * f[..., None])[..., 0]
    return X + D


@dataclass(frozen=True, eq=False)
class KahanMap(Map):
    """Kahan's map with time step ``dt`` (either sign; ``−dt`` is :meth:`inverse`) for ``H`` (module doc).  States
    ``(n,)`` or ``(..., n)``; no carry.  ``backend`` (alias ``kernel``; the rule of :mod:`jetgaudin.maps`):
    ``"numpy"``, ``"compiled"`` (Numba) or ``"auto"`` (compiled)."""

    H: Any
    dt: float
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_KAHAN_PROPERTIES, init=False, repr=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias
    chunk_invariant = True

    def __post_init__(self) -> None:
        if getattr(self.H, "route_kind", None) == "top":  # the one Hamiltonian type: its system decides
            if np.ndim(self.H.weights) != 1:
                raise InvalidParameterError("Kahan's map takes one set of weights (shape (2N,)); "
                                            "give one Hamiltonian per orbit")
        elif not _is_chain(self.H):
            raise InvalidParameterError("H must be an IntegralHamiltonian (jg.physical_hamiltonian(N, b), ...) or a "
                                        "chain Hamiltonian model.hamiltonian(weights)")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        self._init_backend()

    @property
    def n_state(self) -> int:
        return self.H.model.n_state if _is_chain(self.H) else 3 * self.H.N

    @property
    def time_step(self) -> float:
        """The time one step advances (``dt``)."""
        return self.dt

    def _field(self):
        return quadratic_field(self.H, self.n_state)

    def _check(self, X) -> np.ndarray:
        X = np.asarray(self.H.model.check_state(X), dtype=float) if _is_chain(self.H) else as_state(X)[0]
        if X.shape[-1] != self.n_state:
            raise InvalidParameterError(f"states need {self.n_state} components, got {X.shape[-1]}")
        return X

    def integrals(self, X: np.ndarray) -> np.ndarray:
        if _is_chain(self.H):
            return np.asarray(self.H.record_integrals(X), dtype=float)
        return np.asarray(integrals(X, self.H.b, self.H.c), dtype=float)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        X = self._check(X)
        c, A, g0 = self._field()
        try:
            Y = kahan_step(X, c, A, g0, self.dt)
        except np.linalg.LinAlgError:
            raise IntegrationError(f"Kahan's map: I - (h/2) f'(X) is singular at this state (dt = {self.dt:g}); "
                                   "give a smaller dt") from None
        if not np.all(np.isfinite(Y)):
            raise IntegrationError(f"Kahan's map produced non-finite states (dt = {self.dt:g}); give a smaller dt")
        zeros = np.zeros(X.shape[:-1])
        return Y, zeros.astype(complex), zeros

    def _compiled_advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int) -> Advance:
        from ._kahan_kernels import kahan_parallel, kahan_serial

        X = self._check(X)
        c, A, g0 = self._field()
        flat = np.ascontiguousarray(X.reshape(-1, X.shape[-1]))
        run = kahan_parallel if len(flat) >= _PARALLEL_ORBITS else kahan_serial
        rows, last, ok = run(flat, c, A, g0, float(self.dt), steps, save_every)
        if not ok:
            raise IntegrationError(f"Kahan's map: a singular or non-finite step (dt = {self.dt:g}); "
                                   "give a smaller dt")
        zeros = np.zeros(X.shape[:-1])
        return Advance(rows=rows.reshape((rows.shape[0],) + X.shape), X=last.reshape(X.shape),
                       carry=zeros.astype(complex), imag_max=zeros)

    def inverse(self) -> KahanMap:
        """Kahan's map with ``−dt``: its inverse (time reversibility, tested)."""
        return KahanMap(self.H, -self.dt, self.backend)

    def describe(self) -> dict:
        d: dict = {"kind": "kahan", "dt": self.dt, "weights": np.asarray(self.H.weights).tolist(),
                   "backend": self.backend.value}
        if _is_chain(self.H):
            d["model"] = self.H.model.describe()
        else:
            d["b"] = np.asarray(self.H.b, dtype=float).tolist()
            d["c"] = None if self.H.c is None else np.asarray(self.H.c).tolist()
        return d


def _kahan_from(d: dict) -> KahanMap:
    if "model" in d:
        from .gaudin import GaudinModel

        H: Any = GaudinModel.from_description(d["model"]).hamiltonian(np.asarray(d["weights"], dtype=float))
    else:
        H = IntegralHamiltonian(d["b"], np.asarray(d["weights"], dtype=float), d.get("c"))
    return KahanMap(H, float(d["dt"]), d.get("backend", "auto"))


register_map("kahan", _kahan_from)
