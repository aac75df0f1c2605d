r"""The physical Hamiltonian of a chain: the first non-trivial coefficient of ``ν²/2`` at the family's infinity.

For the top (one rational site at 0, order ``N``) the physical Hamiltonian is ``H = H_2/2`` of eq. (H), and
``H_2`` is the coefficient of ``λ^{−2}`` in ``ν²(λ) = b² + Σ_m H_m λ^{−m} + …`` at ``λ = ∞``.  The chain's
definition keeps exactly that reading, for every family that has a point at infinity:

* **rational**: ``ν² = b² + Σ_{i,m} h_{i,m} (λ − λ_i)^{−m} = b² + 2bJ/λ + 2H/λ² + O(λ^{−3})`` with
  ``(λ − λ_i)^{−1} = λ^{−1} + λ_i λ^{−2} + …`` and ``(λ − λ_i)^{−2} = λ^{−2} + …``, so

  .. math:: H = \tfrac12 \sum_i \left(\lambda_i\, h_{i,1} + h_{i,2}\right).

  One site at 0: ``H = h_2/2 = H_2/2`` (the top's).  A magnet (order-1 sites, ``h_{i,1} = 2H_i`` the Gaudin
  Hamiltonians, ``h_{i,2} = |s_i|²``): ``H = Σ_i λ_i H_i + ½ Σ_i |s_i|² = ½|S|² + b Σ_i λ_i s_i^3``
  (``S = Σ_i s_i``), the classical reduced-BCS (Richardson–Gaudin) Hamiltonian up to the conserved ``J²/2``.
* **trigonometric** (``z = e^{2iγλ} → 0`` as ``Im λ → +∞``): ``ν² = (b − iγJ)² + c_1 z + O(z²)`` with
  ``ψ_m(x)``'s coefficient of ``e^{2iγx}`` equal to ``(−2iγ)^m/(m−1)!`` (from ``γ cot γx = −iγ(1 + 2Σ_n
  e^{2inγx})``), so ``c_1 = Σ_{i,m} e^{−2iγλ_i} (−2iγ)^m h_{i,m}/(m−1)!``, and

  .. math:: H = -\frac{\operatorname{Re} c_1}{8\gamma^2}, \qquad
            w_{i,m} = -\frac{\operatorname{Re}\big[(-2i\gamma)^m e^{-2i\gamma\lambda_i}\big]}{8\gamma^2 (m-1)!}
            \quad (w_{i,1} = \tfrac{\sin 2\gamma\lambda_i}{4\gamma},\ w_{i,2} = \tfrac{\cos 2\gamma\lambda_i}{2}),

  the same real part at ``−i∞`` (``ν²(λ̄) = conj ν²(λ)``), periodic in every ``λ_i`` with the family's period
  ``π/γ``, and the rational ``H`` as ``γ → 0`` (``w_{i,1} → λ_i/2``, ``w_{i,2} → 1/2``, ``w_{i,m≥3} → 0``).  For
  a magnet: ``H = ½Σ_{a=1,2}[(Σ_i cos(γλ_i) s_i^a)² − (Σ_i sin(γλ_i) s_i^a)²] + Σ_i [b sin(2γλ_i)/(2γ)
  + (J/2) cos(2γλ_i)] s_i^3``.

A family without a point at infinity (the elliptic one: ``ν²`` is doubly periodic) has no such coefficient; it
registers no rule here (:func:`register_physical`), and its chains take explicit weights
(:meth:`jetgaudin.GaudinModel.hamiltonian`).  The weights of the extra integrals (``J``) are 0.
"""

from __future__ import annotations

from collections.abc import Callable
from math import factorial

import numpy as np

from .._errors import InvalidParameterError

__all__ = ["physical_weights", "register_physical"]

_RULES: dict[str, Callable] = {}


def register_physical(family_name: str, rule: Callable) -> None:
    """Register ``rule(family, sites) -> weights over the h_{i,m}`` (site by site, ``m = 1..2N_i``)."""
    _RULES[family_name] = rule


def physical_weights(model) -> np.ndarray:
    """The weights ``w`` (``(n_integrals,)``) of the physical Hamiltonian ``H = Σ w_I I`` of ``model`` (module
    docstring); :class:`InvalidParameterError` for a family without one."""
    rule = _RULES.get(model.family.name)
    if rule is None:
        raise InvalidParameterError(
            f"the {model.family.name} family has no physical Hamiltonian (no point at infinity to expand nu^2 at); "
            "give the Hamiltonian's weights over the integrals explicitly (GaudinModel.hamiltonian(weights))")
    w = np.zeros(model.n_integrals)
    w[:2 * model.M] = rule(model.family, model.sites)
    return w


def _rational(family, sites) -> list[float]:
    return [lam / 2 if m == 1 else 0.5 if m == 2 else 0.0 for lam, N in sites for m in range(1, 2 * N + 1)]


def _trigonometric(family, sites) -> list[float]:
    g = family.gamma
    return [-((-2j * g) ** m * np.exp(-2j * g * lam)).real / (8 * g * g * factorial(m - 1))
            for lam, N in sites for m in range(1, 2 * N + 1)]


register_physical("rational", _rational)
register_physical("trigonometric", _trigonometric)
