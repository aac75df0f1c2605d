r"""The chain Hamiltonian ``H = Σ_I w_I h_I``: a linear combination of a :class:`~jetgaudin.GaudinModel`'s integrals
(``model.hamiltonian(weights)``), what :func:`jetgaudin.solve` and :func:`jetgaudin.integrate` flow.  Split from
:mod:`jetgaudin.gaudin.model` (one concept per module); ``jetgaudin.gaudin.model.ChainHamiltonian`` is the same class.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._errors import InvalidParameterError
from ..hamiltonians import IntegralHamiltonian

if TYPE_CHECKING:
    from .model import GaudinModel

__all__ = ["ChainHamiltonian"]

#: the old name of the chain's Hamiltonian: :class:`jetgaudin.IntegralHamiltonian`, the one type (``isinstance`` holds
#: both ways; ``ChainHamiltonian(model, weights)`` builds it)
ChainHamiltonian = IntegralHamiltonian


@dataclass(frozen=True)
class _ChainHamiltonian:
    r"""The chain's route of :class:`jetgaudin.IntegralHamiltonian` (its system a :class:`~jetgaudin.GaudinModel`;
    :data:`jetgaudin.hamiltonians.HAMILTONIAN_ROUTES`): ``H(X) = Σ_I w_I h_I(X)``, a linear combination of the
    chain integrals (weights ``(2M,)`` or
    ``(..., 2M)``).  Usable with :func:`jetgaudin.integrate` (``vector_field`` and ``record_integrals``)."""

    model: GaudinModel
    weights: np.ndarray
    #: its rows of the route table of :func:`jetgaudin.solve` (:class:`jetgaudin.hamiltonians.SolveHamiltonian`)
    route_kind: ClassVar[str] = "chain"

    def __post_init__(self):
        if np.iscomplexobj(self.weights):
            raise InvalidParameterError("weights must be real (complex given)")
        try:
            w = np.asarray(self.weights, dtype=float)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"weights must be real numbers, got {self.weights!r}") from None
        n = self.model.n_integrals
        if w.ndim == 0 or w.shape[-1] != n:
            what = (f"2M = {2 * self.model.M} h_(i,m){' and J' if n > 2 * self.model.M else ''}"
                    if getattr(self.model, "dim", 3) == 3 else f"the h^(k)_(j,m) of tr l^k/k, k = 2..{self.model.n}")
            raise InvalidParameterError(
                f"weights must have a trailing axis of length {n} ({what}: one per integral "
                f"{', '.join(self.model.integral_labels()[:3])}, ...), got shape {w.shape}"
            )
        if not np.all(np.isfinite(w)):
            raise InvalidParameterError("weights must be finite")
        object.__setattr__(self, "weights", w)

    @property
    def b(self) -> float:
        return self.model.b

    @property
    def n_state(self) -> int:
        """``3M`` (the model's state length)."""
        return int(self.model.n_state)

    def check_state(self, X) -> np.ndarray:
        """``X`` as a float array ``(..., 3M)`` (``model.check_state``)."""
        return np.asarray(self.model.check_state(X), dtype=float)

    @property
    def structure_constants(self) -> np.ndarray:
        """The chain's structure constants (lets :func:`jetgaudin.integrate` use its fast and heyoka routes)."""
        return self.model.structure_constants

    def __call__(self, X) -> np.ndarray:
        return np.sum(self.weights * self.model.integrals(X), axis=-1)

    def gradient(self, X) -> np.ndarray:
        return np.einsum("...m,...mi->...i", self.weights, self.model.integral_gradients(X))

    def vector_field(self, X) -> np.ndarray:
        r"""``Ẋ = Π(X) ∇H``, shape ``(..., 3M)``."""
        return self.model.vector_field(self.gradient(X), X)

    def record_integrals(self, X) -> np.ndarray:
        """The integrals :func:`jetgaudin.integrate` records along the flow (the chain's ``h_{i,m}``): for real
        finite float rows of the rational, trigonometric and elliptic families one compiled pass over the rows
        (:mod:`jetgaudin.gaudin._record`, the model's quadratic forms; equal to
        :meth:`GaudinModel.integrals` to round-off), else :meth:`GaudinModel.integrals` (which also refuses an
        overflow)."""
        m = self.model
        X = np.asarray(X)
        if (X.dtype == np.float64 and X.ndim >= 1 and X.size and X.shape[-1] == 3 * m.M
                and getattr(m.family, "name", None) in ("rational", "trigonometric", "elliptic") and np.ndim(m.b) == 0
                and np.isfinite(X).all()):
            from ._record import chain_integrals, chain_integrals_gram

            q, lin = m._forms
            flat = np.ascontiguousarray(X.reshape(-1, X.shape[-1]))
            lin = np.ascontiguousarray(lin, dtype=float)
            if q.ndim == 3:  # the rational forms: one q for the three components (the Gram matrix once per row)
                out = np.empty((flat.shape[0], q.shape[0]))
                chain_integrals_gram(flat, np.ascontiguousarray(q, dtype=float), lin, float(m.b), out)
            else:
                forms = np.asarray(m.family.extra_integrals(m.sites)[1], dtype=float).reshape(-1, X.shape[-1])
                out = np.empty((flat.shape[0], q.shape[1] + forms.shape[0]))
                chain_integrals(flat, np.ascontiguousarray(q, dtype=float), lin, float(m.b),
                                np.ascontiguousarray(forms), out)
            if np.isfinite(out).all():
                return out.reshape(X.shape[:-1] + out.shape[-1:])
        return m.integrals(X)

    def as_top(self):
        """The top's :class:`jetgaudin.IntegralHamiltonian` ``Σ w_m κ_m`` (the same weights: one site at 0 has
        ``h_m = H_m``, ``h_{N+k} = C_k``) where :attr:`GaudinModel.is_top`; :class:`InvalidParameterError` otherwise."""
        self.model.as_top()
        from ..hamiltonians import IntegralHamiltonian

        return IntegralHamiltonian(self.model.b, self.weights)
