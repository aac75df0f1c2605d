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
``−2bα`` undoes the extra part exactly.

**Families** (``docs/families.md``).  The same construction for the trigonometric (XXZ) and elliptic (XYZ) families:
``∂ν²/∂h_{i,m} = ψ_m(λ − λ_i)`` (:meth:`jetgaudin.families.Family.nu2_basis`) in the Jacobian, and the family's extra
integrals (trigonometric ``J``, elliptic ``c0``) are matched too.  Linear identities among the matched integrals
(elliptic: ``Σ_i h_{i,1} = 0``, the residue theorem; trigonometric: one relation between the ``h_{i,1}`` and ``J``)
make their weights free along the identity: each identity is one more free unknown (found numerically,
:func:`_identities`).  The rotation generator is ``Σ_i h_{i,1}`` (rational, rate ``2b``) or ``J`` (trigonometric,
rate 1); the elliptic family has none.  A family with a real period ``P`` (trigonometric ``π/γ``, elliptic
``2K``) keeps that rule while every ``ρ_j`` is within ``P/2`` of every site, and otherwise takes the real parts
farthest from the sites and branch points within one period (:func:`_periodic_real_parts`: ``c R`` would wrap onto
a site modulo the period).  So ``k = (matched integrals) − (rotation) − (identities)`` maps: ``M − 1``
(rational, trigonometric), ``M`` (elliptic).  Only :class:`~jetgaudin.GaudinModel`'s public methods are used.  The NumPy
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


def _periodic_real_parts(lc: float, P: float, k: int, points: np.ndarray) -> np.ndarray:
    """``k`` real parts in one period ``[lc, lc + P)`` (a periodic family): greedily the points of a 256-point grid
    farthest from every site and branch point (``points``, with their images at ``± P``), at least ``P/(4k)`` apart
    from each other (the rational rule ``λ_c + cR/t_j`` could wrap onto a site)."""
    grid = lc + P * np.arange(256) / 256
    imgs = np.concatenate([points - P, points, points + P])
    score = np.min(np.abs(grid[:, None] - imgs[None, :]), axis=1)
    chosen: list[float] = []
    for i in np.argsort(-score, kind="stable"):
        if all(min(abs(grid[i] - c), P - abs(grid[i] - c)) >= P / (4 * k) for c in chosen):
            chosen.append(float(grid[i]))
        if len(chosen) == k:
            break
    return np.array(sorted(chosen))


def _identities(model, keep: np.ndarray) -> np.ndarray:
    """Orthonormal rows ``c`` with ``Σ_I c_I I(X)`` constant on every state: the linear identities among the matched
    integrals (elliptic: ``Σ_i h_{i,1} = 0``, the residue theorem; trigonometric: one between the ``h_{i,1}`` and
    ``J``; rational with ``b = 0``: ``Σ_i h_{i,1} = 0``), from the integrals at ``4 n`` random states (singular values
    below ``1e-10`` of the largest).  Weights along them do not change the flow: each is a free unknown."""
    rng = np.random.default_rng(20251125)
    V = np.asarray(model.integrals(rng.standard_normal((4 * model.n_integrals + 8, model.n_state))))[:, keep]
    _, sv, vt = np.linalg.svd(V - V.mean(axis=0))
    sv = np.concatenate([sv, np.zeros(vt.shape[0] - len(sv))])
    return vt[sv <= 1e-10 * sv[0]]

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

    def _design(self) -> tuple[np.ndarray, np.ndarray, float]:
        """``(keep, E, rate)``: the integrals matched (``keep``: the non-Casimirs, with the family's extras), the extra
        unknowns' columns ``E`` (the rotation generator first, when the family has one, then the linear identities)
        and the rotation's rate (module doc)."""
        model = self.model
        keep = ~model.casimir_mask()
        labels = [str(lb) for lb, k in zip(model.integral_labels(), keep, strict=True) if k]
        null = _identities(model, keep)
        if model.family.name == "rational":  # Σ_i h_{i,1} = 2b J: the rotation at rate 2b
            g, rate = np.array([lb.endswith(",1") for lb in labels], dtype=float), 2.0 * float(model.b)
        elif "J" in labels:  # the trigonometric family's J = Σ_j y^{(j)3}_0: the rotation at rate 1
            g, rate = np.array([lb == "J" for lb in labels], dtype=float), 1.0
        else:
            g, rate = None, 0.0
        if g is not None and (rate == 0.0 or (len(null) and np.linalg.norm(g - null.T @ (null @ g)) < 1e-8)):
            g, rate = None, 0.0  # no rotation (b = 0): Σ_i h_{i,1} is then an identity, found in null
        cols = ([g] if g is not None else []) + list(null)
        E = np.array(cols).T if cols else np.zeros((len(labels), 0))
        return keep, E, rate

    def _basis_values(self, x: np.ndarray, lam: np.ndarray, keep: np.ndarray) -> np.ndarray:
        """``∂ν²/∂I (λ)`` for the matched integrals ``I``, shape ``(len(lam), n_keep)``:
        ``ψ_m(λ − λ_i)`` for ``h_{i,m}`` (:meth:`jetgaudin.families.Family.nu2_basis`; rational ``(λ − λ_i)^{-m}``)
        and the derivative of ``ν²``'s constant term for the extras (as ``GaudinModel.interpolating_weights``)."""
        model = self.model
        fam = model.family
        cols = [fam.nu2_basis(m, lam - p) for p, N in model.sites for m in range(1, 2 * N + 1)]
        extra = np.asarray(model.integrals(x))[2 * model.M:]
        dconst = np.asarray(fam.nu2_constant_gradient(model.b, extra), dtype=float)
        F = np.concatenate([np.stack(cols, -1), np.broadcast_to(dconst, lam.shape + dconst.shape)], -1)
        return F[:, keep]

    def parameters(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """``(η_1..η_k, θ)`` of one step for the orbit ``x`` ``(3M,)``: the maps and the rotation angle;
        :class:`~jetgaudin.StepTooLargeError` where Newton's method finds none (give a smaller ``dt``)."""
        model = self.model
        keep, E, rate = self._design()
        lc = float(np.mean(model.positions))
        target = self.dt * np.asarray(self.H.weights, dtype=float)[keep]
        k = int(keep.sum()) - E.shape[1]
        bp = np.ravel(model.branch_points(x))
        R = max(float(np.max(np.abs(bp - lc))) if bp.size else 0.0, float(np.max(np.abs(model.positions - lc))),
                1e-6)
        P = model.family.period
        rho = lc + self.rho_factor * R / _node_scales(k)
        if not bp.size and len(model.sites) == 1 and P is not None:
            # one site of a family without computed branch points (the elliptic Clebsch top, issue 34): R would be
            # the 1e-6 floor (real parts on the site) and ±ρ make ν²'s even basis functions coincide (a singular
            # Jacobian); take one-sided real parts P/4, P/8, … (a quarter period off the site)
            rho = lc + P / 4 / np.arange(1, k + 1)
        if P is not None and np.max(np.abs(rho[:, None] - model.positions[None, :])) >= P / 2:  # it would wrap
            rho = _periodic_real_parts(lc, P, k, np.concatenate([bp, model.positions.astype(complex)]))

        def jac(eta, nus):
            J = -(self._basis_values(x, eta, keep) / nus[:, None]).real.T
            return np.concatenate([J, -E], axis=1)

        u = np.linalg.solve(jac(rho.astype(complex), np.array([model.nu(x, r).real for r in rho])), target)
        for _ in range(_ITERATIONS):
            eta = rho + 1j * u[:k]
            om = np.array([model.interpolating_weights(x, e) for e in eta])[:, keep]
            du = np.linalg.solve(jac(eta, np.array([model.nu(x, e) for e in eta])), om.sum(axis=0) - E @ u[k:] - target)
            u = u - du
            if np.any(np.abs(u[:k]) > 2 * np.abs(rho - lc) + (P or 0.0)) or not np.all(np.isfinite(u)):
                break
            if np.all(np.abs(du) <= _STEP_TOL * np.abs(u)):
                om = np.array([model.interpolating_weights(x, e) for e in rho + 1j * u[:k]])[:, keep]
                scale = np.abs(om).sum(axis=0) + np.abs(target) + np.abs(E @ u[k:])
                if np.max(np.abs(om.sum(axis=0) - E @ u[k:] - target) / scale) <= _RES_TOL:
                    return rho + 1j * u[:k], -rate * u[k] if rate else 0.0
                break
        raise StepTooLargeError(f"dt = {self.dt:g}: no well-conditioned chain Bäcklund parameters give the exact "
                                f"time-dt step on this orbit (Newton's method failed); give a smaller dt")

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        X = np.asarray(self.model.check_state(X), dtype=float)
        flat = X.reshape(-1, X.shape[-1]).copy()
        for i, x in enumerate(flat):
            eta, theta = self.parameters(x)
            for e in eta:
                if abs(e.imag) > 1e-13 * abs(e.real):  # |Im η| at round-off: weights ~1e-17, the map is the identity
                    x = self.model.two_point_backlund(e)(x)
            flat[i] = rotate_about_field(x, theta)
        zeros = np.zeros(X.shape[:-1])
        return flat.reshape(X.shape), zeros.astype(complex), zeros

    def inverse(self) -> ChainExactFlow:
        return ChainExactFlow(self.H, -self.dt, self.rho_factor)

    def describe(self) -> dict:
        return {"kind": "chain_exact", **self.model.describe(), "weights": np.asarray(self.H.weights).tolist(),
                "dt": self.dt, "rho_factor": self.rho_factor}


def _chain_exact_from(d: dict) -> ChainExactFlow:
    from .gaudin import GaudinModel

    model = GaudinModel.from_description(d)
    return ChainExactFlow(model.hamiltonian(np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                          float(d.get("rho_factor", RHO_FACTOR)))


register_map("chain_exact", _chain_exact_from)
