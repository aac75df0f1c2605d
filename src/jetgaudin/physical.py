r"""Tops in the mechanician's own variables (issue 34; every correspondence derived in ``docs/physical.md``).

The library's bracket (LP) gives ``ẋ = ∇H × x`` (``{y_i^α, y_j^β} = ε^{αβγ} y_{i+j}^γ``), the reverse of the
textbook convention ``Π̇ = Π × Ω``; the maps below absorb that sign.

* :func:`heavy_top` ``(I1, I3, mgl)`` -- the Lagrange top ``I = diag(I1, I1, I3)`` in the body-frame variables of
  Marsden–Ratiu, ``P = (Π, Γ)``: ``Π̇ = Π × Ω + mgl Γ × χ``, ``Γ̇ = Γ × Ω``, ``Ω = I^{−1}Π``, ``χ = e_3``.
  State ``y_0 = −Π/I1``, ``y_1 = Γ`` (N = 2), field ``b = mgl/I1``, model time = physical time; model Hamiltonian
  ``½H_2 + w_1 H_1`` with the **orbit-dependent** weight ``w_1 = (I1/I3 − 1) y_0^3/(2b)`` (``y_0^3 = −Π_3/I1`` is
  conserved): ``H_phys/I1 = ½H_2 + (I1/I3 − 1)(y_0^3)²/2`` and the gradient of ``(y_0^3)²/2 = H_1²/(8b²)`` is
  ``(H_1/(4b²)) ∇H_1``, constant on the orbit.
* :func:`kirchhoff_clebsch` ``(a, theta, c)`` -- Kirchhoff's equations ``Ṁ = M × ∂H/∂M + p × ∂H/∂p``,
  ``ṗ = p × ∂H/∂M``, ``H = ½Σ a_i M_i² + ½Σ b_i p_i²``, ``b_i = θ a_j a_k + c`` (Clebsch's case), ``a_1 ≥ a_2 > a_3``,
  ``θ > 0``: the state of :func:`jetgaudin.clebsch_top` ``(k)``, ``k² = (a_1 − a_2)/(a_1 − a_3)``, is
  ``(M, p)_lib = −(M, p/λ)``, ``λ = √(s/θ)``, ``s = 1/(a_1 − a_3)``; model time ``τ = t/(2s)``; model Hamiltonian
  ``c_0 + μ h_{1,2}``, ``μ = s a_3 + E(k)/K(k)``.  Extra integral ``F = ½(|M|² − θ Σ a_i p_i²)``.

The twisted top of Thiffeault–Morrison is **not** mapped: their bracket and Hamiltonian were not accessible
(``docs/physical.md`` §3).  :func:`jetgaudin.solve` takes a physical top and ``P0`` (:func:`solve_physical`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._errors import InvalidParameterError, InvalidStateError
from ._validate import real_number

__all__ = ["HeavyTop", "KirchhoffClebsch", "heavy_top", "kirchhoff_clebsch", "solve_physical"]


def _physical(P, what: str) -> np.ndarray:
    if np.iscomplexobj(P):
        raise InvalidStateError(f"{what}: P must be real (complex given)")
    try:
        P = np.asarray(P, dtype=float)
    except (TypeError, ValueError):
        raise InvalidStateError(f"{what}: P must be an array of real numbers of shape (..., 6)") from None
    if P.ndim == 0 or P.shape[-1] != 6:
        raise InvalidStateError(f"{what}: P has shape {P.shape}; give (..., 6) = the two 3-vectors side by side")
    if not np.all(np.isfinite(P)):
        raise InvalidStateError(f"{what}: P must be finite")
    return P


def _state(X, what: str) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim == 0 or X.shape[-1] != 6:
        raise InvalidStateError(f"{what}: the model state has 6 components (y_0, y_1), got shape {X.shape}")
    return X


def _positive(v, name: str) -> float:
    v = real_number(v, name)
    if v <= 0:
        raise InvalidParameterError(f"{name} must be > 0 (a moment of inertia / a ratio), got {v}")
    return v


@dataclass(frozen=True)
class HeavyTop:
    """The Lagrange (symmetric heavy) top ``I1 = I2``, ``I3``, ``mgl`` (module doc; :func:`heavy_top`)."""

    I1: float
    I3: float
    mgl: float

    is_physical_top = True

    def __post_init__(self):
        object.__setattr__(self, "I1", _positive(self.I1, "I1"))
        object.__setattr__(self, "I3", _positive(self.I3, "I3"))
        mgl = real_number(self.mgl, "mgl")
        if mgl == 0:
            raise InvalidParameterError("mgl must be nonzero (mgl = 0 is the free symmetric top: the model needs a "
                                        "field b = mgl/I1 != 0); give e.g. mgl = 1e-3")
        object.__setattr__(self, "mgl", mgl)

    @property
    def b(self) -> float:
        """The model's field ``b = mgl/I1``."""
        return self.mgl / self.I1

    @property
    def time_scale(self) -> float:
        """Model time per unit of physical time (1: the heavy top's model runs in physical time)."""
        return 1.0

    def to_state(self, P) -> np.ndarray:
        """``(Π, Γ) ↦ (y_0, y_1) = (−Π/I1, Γ)``, shape ``(..., 6)``."""
        P = _physical(P, "heavy_top.to_state")
        return np.concatenate([-P[..., :3] / self.I1, P[..., 3:]], axis=-1)

    def from_state(self, X) -> np.ndarray:
        """``(y_0, y_1) ↦ (Π, Γ) = (−I1 y_0, y_1)``."""
        X = _state(X, "heavy_top.from_state")
        return np.concatenate([-self.I1 * X[..., :3], X[..., 3:]], axis=-1)

    def hamiltonian(self, P0):
        """The model Hamiltonian of the orbit from ``P0`` ``(6,)``: ``½H_2 + w_1 H_1``, ``w_1 = (I1/I3 − 1)
        y_0^3/(2b)`` (module doc), an :class:`~jetgaudin.IntegralHamiltonian` (batch ``P0``: weights ``(..., 4)``)."""
        from .hamiltonians import IntegralHamiltonian

        y03 = self.to_state(P0)[..., 2]
        w1 = (self.I1 / self.I3 - 1.0) * y03 / (2.0 * self.b)
        w = np.zeros(np.shape(y03) + (4,))
        w[..., 0], w[..., 1] = w1, 0.5
        return IntegralHamiltonian(self.b, w)

    def energy(self, P) -> np.ndarray:
        """``H = Π_1²/(2I1) + Π_2²/(2I1) + Π_3²/(2I3) + mgl Γ_3``."""
        P = _physical(P, "heavy_top.energy")
        Pi = P[..., :3]
        return (Pi[..., 0] ** 2 + Pi[..., 1] ** 2) / (2 * self.I1) + Pi[..., 2] ** 2 / (2 * self.I3) \
            + self.mgl * P[..., 5]

    def integrals(self, P) -> np.ndarray:
        """``(H, Π·Γ, |Γ|², Π_3)``, shape ``(..., 4)``: the energy, the two Casimirs and Lagrange's integral."""
        P = _physical(P, "heavy_top.integrals")
        Pi, G = P[..., :3], P[..., 3:]
        return np.stack([self.energy(P), np.sum(Pi * G, axis=-1), np.sum(G * G, axis=-1), Pi[..., 2]], axis=-1)


@dataclass(frozen=True)
class KirchhoffClebsch:
    """Clebsch's case of Kirchhoff's equations (module doc; :func:`kirchhoff_clebsch`)."""

    a: tuple
    theta: float = 1.0
    c: float = 0.0

    is_physical_top = True

    def __post_init__(self):
        try:
            a = tuple(real_number(v, "a") for v in self.a)
        except TypeError:
            raise InvalidParameterError(f"a must be three real numbers (a_1, a_2, a_3), got {self.a!r}") from None
        if len(a) != 3:
            raise InvalidParameterError(f"a must be three real numbers (a_1, a_2, a_3), got {len(a)}")
        if not (a[0] >= a[1] > a[2]):
            raise InvalidParameterError(f"a = {a}: need a_1 >= a_2 > a_3 (the modulus k^2 = (a_1 - a_2)/(a_1 - a_3) "
                                        "must lie in [0, 1)); number the axes so that a decreases")
        object.__setattr__(self, "a", a)
        theta = real_number(self.theta, "theta")
        if theta <= 0:
            raise InvalidParameterError(f"theta must be > 0 (p is rescaled by sqrt(s/theta)), got {theta}")
        object.__setattr__(self, "theta", theta)
        object.__setattr__(self, "c", real_number(self.c, "c"))

    @property
    def b(self) -> np.ndarray:
        """``b_i = θ a_j a_k + c``, ``(i, j, k)`` cyclic."""
        a = self.a
        return self.theta * np.array([a[1] * a[2], a[2] * a[0], a[0] * a[1]]) + self.c

    @property
    def s(self) -> float:
        return 1.0 / (self.a[0] - self.a[2])

    @property
    def lam(self) -> float:
        """``λ = √(s/θ)``: ``p_lib = −p/λ``."""
        return float(np.sqrt(self.s / self.theta))

    @property
    def modulus(self) -> float:
        return float(np.sqrt((self.a[0] - self.a[1]) / (self.a[0] - self.a[2])))

    @property
    def time_scale(self) -> float:
        """Model time per unit of physical time: ``τ = t/(2s) = t (a_1 − a_3)/2``."""
        return 1.0 / (2.0 * self.s)

    @property
    def model(self):
        """:func:`jetgaudin.clebsch_top` ``(k)``."""
        from .gaudin import clebsch_top

        return clebsch_top(self.modulus)

    @property
    def mu(self) -> float:
        """``μ = s a_3 + E(k)/K(k)`` (the pencil ``c_0 + μ h_{1,2}`` whose ``a`` is ``s a``)."""
        from scipy.special import ellipe, ellipk

        m = self.modulus ** 2
        return self.s * self.a[2] + float(ellipe(m) / ellipk(m))

    def to_state(self, P) -> np.ndarray:
        """``(M, p) ↦ (−M, −p/λ)``."""
        P = _physical(P, "kirchhoff_clebsch.to_state")
        return np.concatenate([-P[..., :3], -P[..., 3:] / self.lam], axis=-1)

    def from_state(self, X) -> np.ndarray:
        """``(M, p)_lib ↦ (−M, −λ p)``."""
        X = _state(X, "kirchhoff_clebsch.from_state")
        return np.concatenate([-X[..., :3], -self.lam * X[..., 3:]], axis=-1)

    def hamiltonian(self, P0=None):
        """The model Hamiltonian ``c_0 + μ h_{1,2}`` (weights ``(0, μ, 0, 0, 1)`` over ``h_{1,1..4}, c_0``), the same
        for every orbit (``P0`` is ignored)."""
        return self.model.hamiltonian(np.array([0.0, self.mu, 0.0, 0.0, 1.0]))

    def energy(self, P) -> np.ndarray:
        """``H = ½Σ a_i M_i² + ½Σ b_i p_i²``."""
        P = _physical(P, "kirchhoff_clebsch.energy")
        return 0.5 * (P[..., :3] ** 2 @ np.asarray(self.a) + P[..., 3:] ** 2 @ self.b)

    def integrals(self, P) -> np.ndarray:
        """``(H, M·p, |p|², F)``, ``F = ½(|M|² − θ Σ a_i p_i²)`` (Clebsch's extra integral), shape ``(..., 4)``."""
        P = _physical(P, "kirchhoff_clebsch.integrals")
        M, p = P[..., :3], P[..., 3:]
        F = 0.5 * (np.sum(M * M, axis=-1) - self.theta * (p * p) @ np.asarray(self.a))
        return np.stack([self.energy(P), np.sum(M * p, axis=-1), np.sum(p * p, axis=-1), F], axis=-1)


def heavy_top(I1: float, I3: float, mgl: float) -> HeavyTop:
    """The Lagrange top in Marsden–Ratiu's body-frame variables ``P = (Π, Γ)`` (module doc)."""
    return HeavyTop(I1, I3, mgl)


def kirchhoff_clebsch(a, theta: float = 1.0, c: float = 0.0) -> KirchhoffClebsch:
    """Clebsch's case of Kirchhoff's equations, ``P = (M, p)`` (module doc)."""
    return KirchhoffClebsch(tuple(a) if np.ndim(a) else a, theta, c)


def solve_physical(top: Any, P0, t_span, **kwargs):
    r"""``jg.solve(top, P0, t_span, dt=…, method=…)`` for a physical top: the model's orbit from ``top.to_state(P0)``
    under ``top.hamiltonian(P0)`` over the model times ``time_scale · t`` (``dt`` scaled alike), returned with the
    physical times ``t``, the model states ``X`` and ``physical = top.from_state(X)``; ``info["time_scale"]``.  A batch
    ``P0`` ``(..., 6)`` is solved orbit by orbit (each its own Hamiltonian)."""
    from dataclasses import replace

    from .flows import Trajectory
    from .solve import solve

    P0 = _physical(P0, "solve")
    sigma = top.time_scale
    if P0.ndim > 1:
        parts = [solve_physical(top, p, t_span, **kwargs) for p in P0.reshape(-1, 6)]
        lead = P0.shape[:-1]

        def stack(name):
            arr = np.stack([getattr(tr, name) for tr in parts], axis=1)
            return arr.reshape(arr.shape[:1] + lead + arr.shape[2:])

        return Trajectory(parts[0].t, stack("X"), stack("integrals"), parts[0].method, parts[0].info,
                          physical=stack("physical"))
    try:
        t0, t1 = (real_number(v, "t_span") for v in t_span)
    except TypeError:
        raise InvalidParameterError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
    if kwargs.get("dt") is not None:
        kwargs["dt"] = real_number(kwargs["dt"], "dt") * sigma
    if kwargs.get("t_eval") is not None:
        kwargs["t_eval"] = np.asarray(kwargs["t_eval"], dtype=float) * sigma
    tr = solve(top.hamiltonian(P0), top.to_state(P0), (t0 * sigma, t1 * sigma), **kwargs)
    info = {**tr.info, "time_scale": sigma}
    if "dt" in info:
        info["dt"] = info["dt"] / sigma
    model_dense = tr.dense
    dense = None if model_dense is None else (lambda t: model_dense(np.asarray(t, dtype=float) * sigma))
    return replace(tr, t=tr.t / sigma, info=info, physical=top.from_state(tr.X), time_scale=sigma, dense=dense)
