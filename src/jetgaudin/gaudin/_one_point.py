r"""The one-point Bäcklund maps of a chain, every family with a one-point dressing (``docs/families.md`` §3.1).

**Rational** (eqs. (rr), (ansatz), (hh), (hhh); ``docs/backlund.md`` §2): ``K = [[λ − η + pq, p], [q, 1]]``,
``det K = λ − η``, ``q = (u(η) − ν)/v(η)`` (spectrality: ``K(η) = (p, 1)ᵀ(q, 1)`` kills the eigenvector of ``ℓ(η)``
for ``ν``), ``p = S^-/(2b)`` (``ℓ̃(∞) = ℓ(∞)`` to order ``1/λ``; needs ``b ≠ 0``); the inverse map uses ``adj K``
with ``q = S̃^+/(2b)``, ``p = (ũ(η) − ν)/w̃(η)``.  Its closed-form route is unchanged (bit for bit).

**Trigonometric** (``z = e^{2iγλ}``; the family's methods
:meth:`~jetgaudin.families.TrigonometricFamily.one_point_normalisation`,
:meth:`~jetgaudin.families.TrigonometricFamily.one_point_dressing`):

.. math:: D(\lambda) = \begin{pmatrix} \sin(\gamma(\lambda-\eta))/\gamma + pq\, e^{-i\gamma(\lambda-\eta)} & p \\
          q & e^{-i\gamma(\lambda-\eta)} \end{pmatrix}, \qquad
          \det D = e^{-i\gamma(\lambda-\eta)} \sin(\gamma(\lambda-\eta))\, \frac{1 - 2i\gamma pq}{\gamma},

the two-point form with ``δ = 0`` (``e^{iγλ} D`` is the rational ``K`` in ``z``): ``D(λ + π/γ) = −σ_3 D σ_3``,
``det D`` vanishes at ``η`` modulo ``π/γ`` only; spectrality ``q = (u(η) − ν)/v(η)`` as above.  At ``Im λ → +∞``
``D ≈ e^{−iγλ}·diag(·, ·)``: ``ℓ̃`` tends to ``ℓ``'s limit ``(b − iγJ)σ_3``.  At ``Im λ → −∞`` (``t = e^{iγλ} → ∞``)
``ℓ ≈ (b + iγJ)σ_3 + [[0, v_{−1}], [w_{−1}, 0]]/t`` and ``D ≈ [[αt, p], [q, δ_0/t]]`` (``α = e^{−iγη}/(2iγ)``,
``δ_0 = e^{iγη}``); the ``t`` coefficient of ``ṽ`` is ``α(αv_{−1} − 2p(b + iγJ))``, so ``ℓ̃`` keeps the form (``ṽ → 0``)
iff ``p = α v_{−1}/(2(b + iγJ)) = S_γ^-(η)/(2(b + iγJ))``: the condition **b + iγJ ≠ 0** (a real state with
``b = 0`` qualifies when ``J ≠ 0``, unlike the rational map).  Then ``ũ(∓i∞) = b ± iγJ``: ``b`` and ``J`` are kept.
The inverse map is ``adj D`` with ``q = S_γ^+(η)/(2(b + iγJ))`` and ``p = (u(η) − ν)/w(η)`` (the rational rule with
the indices 1 ↔ 2 swapped).  As ``γ → 0``, ``D → K``: the rational map, to first order (measured; its first-order
term is the flow of the rational physical Hamiltonian and of ``J``, ``docs/families.md`` §3.1).

**Factorisation.**  ``B̂_{ξ̄} ∘ B_ξ = R_ξ ∘ B_ξ^{(2)}``: the one-point map at ``ξ`` then the inverse one-point map at
``ξ̄`` (``ν`` by the branch rule at each state; it gives ``ν(ξ̄) = conj ν(ξ)``) is the real two-point map followed by
the constant complex rotation ``R_ξ: ℓ → diag(ρ, 1) ℓ diag(ρ, 1)^{-1}``, ``ρ = e^{2γ Im ξ}``
(``y^- → ρ y^-``, ``y^+ → y^+/ρ``; the identity in the rational limit, where the factorisation is exact).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._errors import InvalidParameterError, SingularStepError
from .._system_maps import OnePointBacklund
from ..backlund._dressing import adj, spectral_s
from ..lax import ell_coefficients, ell_from_xi, state_from_ell
from ..maps import Backend, Branch, MapProperties, register_map
from ._dressing import dress_parts, dress_sites, dressing_at, site_series
from ._model_map import register_model_map
from .maps import (
    _RESIDUAL_TOL,
    _ChainMap,
    _check_model,
    _continue,
    _ell_at,
    _residual,
    _sites,
)
from .model import GaudinModel

__all__ = ["ChainOnePointBacklund"]

_E11 = np.array([[1.0, 0.0], [0.0, 0.0]], dtype=complex)
_E22 = np.array([[0.0, 0.0], [0.0, 1.0]], dtype=complex)


@dataclass(frozen=True)
class _ChainOnePoint(_ChainMap):
    r"""The chain's route of :class:`jetgaudin.OnePointBacklund` (:mod:`jetgaudin._system_maps`): the complex
    one-point map ``B_(η, ν)`` of a chain (or its inverse, ``inverse_map=True``), module docstring: rational
    (needs ``b ≠ 0``) and trigonometric (needs ``b + iγJ ≠ 0``) families.  Preserves the integrals, is
    Poisson (holomorphically: ``J Π(X) Jᵀ = Π(X̃)``), ``inverse()`` undoes it; not real.

    Raises
    ------
    InvalidParameterError
        Rational ``b = 0`` (``p = S^-/(2b)``: the normalisation ``ℓ̃(∞) = ℓ(∞)`` has no solution), ``Re η`` at a site
        (modulo the period), a family without one-point maps (elliptic: the reason is in the message).
    InvalidStateError
        (at a step) trigonometric ``b + iγJ = 0``.
    """

    model: GaudinModel
    eta: complex
    branch: Branch = Branch.DEFAULT
    inverse_map: bool = False
    backend: Backend = field(default=Backend.AUTO, compare=False)
    kernel: Backend | str | None = field(default=None, compare=False, repr=False)
    kind = "chain_one_point"
    public_name = "OnePointBacklund"  # the class its messages name (jetgaudin.maps.map_name)
    properties: MapProperties = field(
        default=MapProperties(
            preserves_integrals=True, poisson=True, real=False, order=None, symmetric=True, interpolates_flow=False
        ),
        init=False,
        repr=False,
        compare=False,
    )

    def __post_init__(self) -> None:
        _check_model(self.model)
        fam = self.model.family
        if not fam.uniform and fam.one_point_refusal is not None:
            raise InvalidParameterError(fam.one_point_refusal)
        if fam.uniform and self.model.b == 0.0:
            raise InvalidParameterError(
                "the one-point map needs a nonzero field b (p = S^-/(2b) keeps L(infinity) = b sigma^3); the magnet "
                "without field (b = 0) has only the real two-point map; give b != 0"
            )
        self._init_common()
        object.__setattr__(self, "inverse_map", bool(self.inverse_map))

    def inverse(self) -> _ChainOnePoint:
        return _ChainOnePoint(self.model, self.eta, self.branch, not self.inverse_map)

    def describe(self) -> dict:
        return {**super().describe(), "inverse_map": self.inverse_map}

    def _setup(self, X, carry):
        """``(ell, L(η), ν, K0, E, A0, Ea)`` for a 2-D batch ``X`` (``K = λE + K0``, ``adj K = λEa + A0``); other
        families: ``(ell, L(η), ν, c)``, ``c`` the coefficients of the family's one-point dressing."""
        if not self.model.family.uniform:
            return self._family_setup(X, carry)
        b = self.model.b
        ell = ell_coefficients(X, b)
        parts = ell[..., 1:, :, :]
        L = _ell_at(self.model, parts, self.eta)
        u, v, w = L[..., 0, 0], L[..., 0, 1], L[..., 1, 0]
        nu = _continue(u * u + v * w, self._nu_rule(X) if carry is None else np.asarray(carry).reshape(-1))
        # ℓ's 1/λ coefficient at infinity, [[S3, S^-], [S^+, −S3]]: the y_0 of every site
        S = np.sum(parts[..., list(self.model.offsets), :, :], axis=-3)
        if self.inverse_map:
            q = S[..., 1, 0] / (2.0 * b)
            p = spectral_s(u, w, v, nu)  # (ũ − ν)/w̃ = −ṽ/(ũ + ν)
        else:
            p = S[..., 0, 1] / (2.0 * b)
            q = spectral_s(u, v, w, nu)
        M0 = np.empty(p.shape + (2, 2), dtype=complex)
        M0[..., 0, 0] = -self.eta + p * q
        M0[..., 0, 1] = p
        M0[..., 1, 0] = q
        M0[..., 1, 1] = 1.0
        if self.inverse_map:
            return ell, L, nu, adj(M0), _E22, M0, _E11
        return ell, L, nu, M0, _E11, adj(M0), _E22

    def _family_setup(self, X, carry):
        """``(ell, L(η), ν, c)``: the normalisation first (its refusal names ``b + iγJ``), then ``ν`` (root of
        ``ν(η)²`` nearest the carry or the branch rule) and spectrality, as the rational route."""
        fam, eta = self.model.family, self.eta
        norm = fam.one_point_normalisation(self.model.b, self.model.sites, X, eta, self.inverse_map)
        ell = ell_coefficients(X, self.model.b)
        L = ell_from_xi(self.model.xi(X, eta))
        u, v, w = L[..., 0, 0], L[..., 0, 1], L[..., 1, 0]
        nu = _continue(u * u + v * w, self._nu_rule(X) if carry is None else np.asarray(carry).reshape(-1))
        spec = spectral_s(u, w, v, nu) if self.inverse_map else spectral_s(u, v, w, nu)
        return ell, L, nu, fam.one_point_dressing(eta, norm, spec, self.inverse_map)

    def dressing_matrix(self, X, lam, carry=None) -> np.ndarray:
        """``K(λ)`` at ``X``: ``M = [[λ − η + pq, p], [q, 1]]`` of (ansatz), or ``adj M`` for the inverse map (whose
        image ``X̃`` has ``ℓ(X̃) = M^{-1} ℓ(X) M``), shape ``(..., 2, 2)``; ``K ℓ(X) = ℓ(X̃) K``.  Other families: the
        family's ``D(λ)`` (trigonometric: module docstring, ``adj`` of it for the inverse map), scalar ``λ``."""
        X = self.model.check_state(X, allow_complex=True)
        if not self.model.family.uniform:  # D(λ) = Σ_p c_p B_p(λ), scalar λ
            c = self._setup(X.reshape(-1, X.shape[-1]), carry)[3]
            return dressing_at(self.model, c, lam).reshape(X.shape[:-1] + (2, 2))
        _, _, _, K0, E, _, _ = self._setup(X.reshape(-1, X.shape[-1]), carry)
        return K0.reshape(X.shape[:-1] + (2, 2)) + np.asarray(lam, dtype=complex)[..., None, None] * E

    def step(self, X, carry=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One step: ``(X̃, ν, zeros)`` with ``X̃`` complex."""
        X = self.model.check_state(X, allow_complex=True)
        shape = X.shape
        X = X.reshape(-1, shape[-1])
        if not self.model.family.uniform:
            return self._family_step(X, carry, shape)
        ell, L, nu, K0, E, A0, Ea = self._setup(X, carry)
        scale = 1.0 + np.max(np.abs(ell), axis=(-3, -2, -1))
        res = _residual(K0 + self.eta * E, L, A0 + self.eta * Ea, scale)
        if np.any(res > _RESIDUAL_TOL):
            raise SingularStepError(
                f"one-point Bäcklund step of the chain: the pole at eta does not cancel (relative residue "
                f"{np.max(res):.2e}); change eta"
            )
        new = dress_parts(self.model, ell[..., 1:, :, :], K0, E, A0, Ea, (self.eta,))
        out = state_from_ell(np.concatenate([ell[..., :1, :, :], new], axis=-3))
        if not np.all(np.isfinite(out)):
            raise SingularStepError("one-point Bäcklund step of the chain produced non-finite values; change eta")
        return out.reshape(shape), nu.reshape(shape[:-1]), np.zeros(shape[:-1])

    def _family_step(self, X, carry, shape):
        """:meth:`step` of a non-rational family: the residual of spectrality relative to ``|D(η)|²`` (as the
        two-point map's), then the principal parts from the Taylor series of ``D`` at the sites."""
        ell, L, nu, c = self._setup(X, carry)
        scale = 1.0 + np.max(np.abs(ell), axis=(-3, -2, -1))
        D = dressing_at(self.model, c, self.eta)
        res = _residual(D, L, adj(D), scale) / np.max(np.abs(D), axis=(-2, -1)) ** 2
        if np.any(res > _RESIDUAL_TOL):
            raise SingularStepError(
                f"one-point Bäcklund step of the chain: the pole at eta does not cancel (relative residue "
                f"{np.max(res):.2e}); change eta")
        new = dress_sites(self.model, ell[..., 1:, :, :], site_series(self.model, c))
        out = state_from_ell(np.concatenate([ell[..., :1, :, :], new], axis=-3))
        if not np.all(np.isfinite(out)):
            raise SingularStepError("one-point Bäcklund step of the chain produced non-finite values; change eta")
        return out.reshape(shape), nu.reshape(shape[:-1]), np.zeros(shape[:-1])


#: the old name of :class:`jetgaudin.OnePointBacklund` for chains: the same class (``isinstance`` holds both ways)
ChainOnePointBacklund = OnePointBacklund


def _one_point_from(d: dict) -> OnePointBacklund:
    return OnePointBacklund(_sites(d), complex(*d["eta"]), Branch.parse(d.get("branch", "default")),
                            bool(d.get("inverse_map", False)))


register_map("chain_one_point", _one_point_from)
register_model_map("chain_one_point", ChainOnePointBacklund)  # model.one_point_backlund (gaudin._model_map)
