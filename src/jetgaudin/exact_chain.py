r"""Exact time steps of a Gaudin chain: the exact time-``dt`` flow of a :class:`~jetgaudin.ChainHamiltonian` from
commuting chain Bäcklund maps (``docs/integrators.md`` §7; the tops' construction of :mod:`jetgaudin.exact`).

The chain's real two-point map ``B_η`` (``model.two_point_backlund(η)``) is the time-1 flow of
``G_η = Σ_I ω_I(η) h_I`` with ``ω_{i,m} = −2∫_0^{Im η} Re[(λ − λ_i)^{-m}/(2ν)] ds`` (``model.interpolating_weights``),
constant along the orbit; the maps commute, so their weights add.  The Casimirs ``h_{i,m}``, ``m > N_i``
(``model.casimir_mask()``) need nothing; the ``M`` commuting Hamiltonians ``h_{i,m}``, ``m ≤ N_i``, are matched by
``M − 1`` maps with fixed real parts ``ρ_j = λ_c + c R/t_j`` (``λ_c`` the mean site, ``R`` the largest distance of a
branch point or a site from it, ``c = 1.5``, ``t = 1, −1, 1/2, −1/2, …``) and imaginary parts ``h_j`` solved by
Newton's method with the exact Jacobian ``∂ω_{i,m}/∂h = −Re[(η − λ_i)^{-m}/ν(η)]`` (``model.nu``), together with a
free multiple ``α`` of the weight vector of ``Σ_i h_{i,1}``, which generates the rotation of every spin about ``e_3``
at rate ``2b`` (as ``H_1`` of a top; tested): the maps give ``dt·w + α Σ_i h_{i,1}``, and a rotation through
``−2bα`` undoes the extra part exactly.  Only :class:`~jetgaudin.GaudinModel`'s public methods are used.  The NumPy
route only (adaptive quadrature of the weights, ~25 ms per evaluation: a solve costs 0.3–2 s per orbit).  The
largest feasible step is smaller than a top's when the sites are close compared with ``R`` (the maps must then
separate the sites' weights at a higher order in ``1/ρ``): ~0.02 for the Lagrange chain of the tests.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ._errors import InvalidParameterError, StepTooLargeError
from ._validate import real_number
from .exact import _EXACT_PROPERTIES, RHO_FACTOR, _node_scales, nonzero_step, rotate_about_field
from .maps import Map, MapProperties, register_map

__all__ = ["ChainExactFlow"]

#: Newton: step tolerance (relative to |h|), largest number of iterations, residual accepted (relative to the scale
#: of the weights; the adaptive quadrature's epsrel is 1e-13)
_STEP_TOL, _ITERATIONS, _RES_TOL = 1e-13, 30, 1e-11


@dataclass(frozen=True, eq=False)
class ChainExactFlow(Map):
    r"""The exact time-``dt`` flow of a chain Hamiltonian ``H = model.hamiltonian(weights)`` (module doc), one orbit
    ``(3M,)`` or a batch (each orbit its own parameters, solved at every :meth:`step` / :meth:`advance` call)."""

    H: Any  # a jetgaudin.ChainHamiltonian
    dt: float
    rho_factor: float = RHO_FACTOR
    properties: MapProperties = field(default=_EXACT_PROPERTIES, init=False, repr=False)
    chunk_invariant: ClassVar[bool] = True

    def __post_init__(self) -> None:
        model = getattr(self.H, "model", None)
        if model is None or not callable(getattr(model, "two_point_backlund", None)) or np.ndim(self.H.weights) != 1:
            raise InvalidParameterError("H must be a chain Hamiltonian model.hamiltonian(weights) with one set of "
                                        "weights (shape (2M,))")
        if getattr(getattr(model, "family", None), "name", "rational") != "rational":
            raise InvalidParameterError(
                f"the exact chain flow is built for the rational family (its weights use (lambda - lambda_i)^-m); the "
                f"{model.family.name} family is not supported: integrate its Hamiltonian with method 'dop853' or "
                "'heyoka'")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        rf = real_number(self.rho_factor, "rho_factor")
        if rf <= 1:
            raise InvalidParameterError(f"rho_factor must be > 1, got {rf}")
        object.__setattr__(self, "rho_factor", rf)

    @property
    def model(self):
        return self.H.model

    @property
    def n_state(self) -> int:
        return int(self.model.n_state)

    @property
    def time_step(self) -> float:
        return self.dt

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.model.integrals(X), dtype=float)

    def _basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        model = self.model
        pos = np.repeat(model.positions, [2 * n for n in model.orders]).astype(float)
        m = np.concatenate([np.arange(1, 2 * n + 1) for n in model.orders])
        return pos, m, ~model.casimir_mask()

    def parameters(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """``(η_1..η_{M−1}, θ)`` of one step for the orbit ``x`` ``(3M,)``: the maps and the rotation angle;
        :class:`~jetgaudin.StepTooLargeError` where Newton's method finds none (give a smaller ``dt``)."""
        model = self.model
        pos, m, keep = self._basis()
        target = self.dt * self.H.weights[keep]
        e1 = (m[keep] == 1).astype(float)  # Σ_i h_{i,1}: the rotation about e_3 at rate 2b (tested)
        k = int(keep.sum()) - 1
        lc = float(np.mean(model.positions))
        R = max(float(np.max(np.abs(model.branch_points(x) - lc))), float(np.max(np.abs(model.positions - lc))), 1e-6)
        rho = lc + self.rho_factor * R / _node_scales(k)

        def jac(eta, nus):
            J = -(((eta[None, :] - pos[keep][:, None]) ** -m[keep][:, None]) / nus[None, :]).real
            return np.concatenate([J, -e1[:, None]], axis=1)

        u = np.linalg.solve(jac(rho.astype(complex), np.array([model.nu(x, r).real for r in rho])), target)
        for _ in range(_ITERATIONS):
            eta = rho + 1j * u[:k]
            om = np.array([model.interpolating_weights(x, e) for e in eta])[:, keep]
            du = np.linalg.solve(jac(eta, np.array([model.nu(x, e) for e in eta])), om.sum(axis=0) - u[k] * e1 - target)
            u = u - du
            if np.any(np.abs(u[:k]) > 2 * np.abs(rho - lc)) or not np.all(np.isfinite(u)):
                break
            if np.all(np.abs(du) <= _STEP_TOL * np.abs(u)):
                om = np.array([model.interpolating_weights(x, e) for e in rho + 1j * u[:k]])[:, keep]
                scale = np.abs(om).sum(axis=0) + np.abs(target) + np.abs(u[k])
                if np.max(np.abs(om.sum(axis=0) - u[k] * e1 - target) / scale) <= _RES_TOL:
                    return rho + 1j * u[:k], -2.0 * model.b * u[k]
                break
        raise StepTooLargeError(f"dt = {self.dt:g}: no well-conditioned chain Bäcklund parameters give the exact "
                                f"time-dt step on this orbit (Newton's method failed); give a smaller dt")

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        X = np.asarray(self.model.check_state(X), dtype=float)
        flat = X.reshape(-1, X.shape[-1]).copy()
        for i, x in enumerate(flat):
            eta, theta = self.parameters(x)
            for e in eta:
                x = self.model.two_point_backlund(e)(x)
            flat[i] = rotate_about_field(x, theta)
        zeros = np.zeros(X.shape[:-1])
        return flat.reshape(X.shape), zeros.astype(complex), zeros

    def inverse(self) -> ChainExactFlow:
        return ChainExactFlow(self.H, -self.dt, self.rho_factor)

    def describe(self) -> dict:
        return {"kind": "chain_exact", "b": float(self.model.b), "sites": [[float(p), int(n)] for p, n in
                                                                           self.model.sites],
                "weights": np.asarray(self.H.weights).tolist(), "dt": self.dt, "rho_factor": self.rho_factor}


def _chain_exact_from(d: dict) -> ChainExactFlow:
    from .gaudin import GaudinModel

    model = GaudinModel(float(d["b"]), tuple((float(p), int(n)) for p, n in d["sites"]))
    return ChainExactFlow(model.hamiltonian(np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                          float(d.get("rho_factor", RHO_FACTOR)))


register_map("chain_exact", _chain_exact_from)
