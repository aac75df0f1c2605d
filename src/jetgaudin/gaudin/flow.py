"""The flow of a chain Hamiltonian over a fixed time step as a :class:`jetgaudin.maps.Map` (issue 12): the run layer
records it like the one-site :class:`jetgaudin.flows.FlowMap` (``flow.h5`` / ``flow.csv``, fixed chunks)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._errors import InvalidParameterError
from ..flows import FlowMap, Method
from ..hamiltonians import physical_hamiltonian
from ..maps import register_map
from .model import GaudinModel

__all__ = ["ChainFlowMap"]


@dataclass(frozen=True)
class ChainFlowMap(FlowMap):
    r"""The flow of ``Ẋ = Π(X) ∇H`` for a :class:`~jetgaudin.gaudin.ChainHamiltonian` ``H = Σ w_{i,m} h_{i,m}`` over
    the time step ``dt`` (e.g. ``H = model.interpolating_flow_hamiltonian(X0, η)``, whose time-1 flow from ``X0`` is
    the chain's two-point map).  ``dt``, ``method``, ``rtol``, ``atol`` as for :class:`jetgaudin.flows.FlowMap`
    (validated by the same rule); the preserved integrals are the chain's ``h_{i,m}``.

    Raises
    ------
    InvalidParameterError
        ``H`` not a ``ChainHamiltonian``; ``dt``, ``method`` or tolerances invalid (as ``FlowMap``).
    """

    H: Any  # ChainHamiltonian (FlowMap's field, here the chain's Hamiltonian)

    def __post_init__(self) -> None:
        if getattr(self.H, "route_kind", None) not in ("chain", "sun"):  # a chain's Hamiltonian (the su(n) ones too)
            raise InvalidParameterError("H must be a ChainHamiltonian (model.hamiltonian(weights), "
                                        "model.interpolating_flow_hamiltonian(X, eta))")
        probe = FlowMap(physical_hamiltonian(1, 1.0), abs(self.dt) if isinstance(self.dt, int | float) else self.dt,
                        self.method, self.rtol, self.atol)  # FlowMap's own rules for dt, method and tolerances
        for name in ("method", "rtol", "atol"):
            object.__setattr__(self, name, getattr(probe, name))
        object.__setattr__(self, "dt", float(np.copysign(probe.dt, self.dt)))

    @property
    def model(self) -> GaudinModel:
        return self.H.model

    @property
    def n_state(self) -> int:
        return self.H.model.n_state

    def integrals(self, X: np.ndarray) -> np.ndarray:
        """The chain's ``2M`` integrals ``h_{i,m}``, shape ``(..., 2M)``."""
        return self.H.model.integrals(X)

    def integral_names(self) -> list[str]:
        return self.H.model.integral_labels()

    def state_labels(self) -> list[str]:
        return self.H.model.labels()

    def inverse(self) -> ChainFlowMap:
        """The flow backwards in time (``dt → −dt``)."""
        return ChainFlowMap(self.H, -self.dt, self.method, self.rtol, self.atol)

    def describe(self) -> dict:
        return {"kind": "chain_flow", **self.H.model.describe(),
                "weights": np.asarray(self.H.weights).tolist(), "dt": self.dt, "method": self.method.value,
                "rtol": self.rtol, "atol": self.atol}


def _chain_flow_from(d: dict) -> ChainFlowMap:
    model = GaudinModel.from_description(d)
    return ChainFlowMap(model.hamiltonian(np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                        Method.parse(d["method"]), float(d["rtol"]), float(d["atol"]))


register_map("chain_flow", _chain_flow_from)
