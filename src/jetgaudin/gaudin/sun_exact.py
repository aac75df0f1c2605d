r"""Exact time steps of an su(n) chain (issue 32): the time-``dt`` flow of ``H = Σ_I w_I h_I`` as a composition of
commuting two-point maps ``B^{(r_k)}_{η_k}``.

**Derivation.**  ``B^{(r)}_η`` is the time-1 flow of ``G^{(r)}_η`` (:mod:`jetgaudin.gaudin.sun_maps`, tested), and
``G^{(r)}_η`` is a function of the integrals only, so along any flow of the integrals its differential is
``dG = Σ_I ω_I dh_I`` with ``ω_I = ∂G/∂h_I`` constant on the common level set: the flow of ``G`` from ``X`` is the
flow of ``Σ_I ω_I(X) h_I``.  The integrals Poisson-commute, so these flows commute and compose by adding their
Hamiltonians:

.. math:: B^{(r_K)}_{η_K} \circ \dots \circ B^{(r_1)}_{η_1} = \exp\Big(\sum_k \sum_I ω^{(r_k)}_I(η_k) h_I\Big),

the time-1 flow of ``Σ_I Ω_I h_I``, ``Ω = Σ_k ω^{(r_k)}(η_k)`` (evaluated at the orbit's integrals, the same at every
step).  The Casimirs generate no flow, so this is the time-``dt`` flow of ``H`` exactly when

.. math:: \sum_k ω^{(r_k)}_I(η_k) = dt\, w_I \quad \text{for every non-Casimir } I

(``I`` with ``casimir_mask`` false: ``½ n(n−1) M`` equations).  **Reachable Hamiltonians**: with ``K`` maps the
left side is a map of ``2K`` real parameters ``(Re η_k, Im η_k)`` and the branches; ``K = ¼ n(n−1) M`` maps give
as many unknowns as equations (su(3), two order-1 sites: 6 equations, 3 maps).  An su(n) exact step reaches the
weights ``w`` in the image of that map divided by ``dt``, and :func:`match_weights` finds the ``η_k`` by Newton's
method from a starting guess (a finite-difference Jacobian).  A constant rotation (the flow of a linear Hamiltonian,
``h^{(2)}_{j,1}`` for a field along a Cartan direction) would enlarge the image as ``ChainExactFlow`` does for
su(2); not built here, nor the starting guess for arbitrary ``w`` (docs/sun.md §5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import InvalidParameterError, StepTooLargeError
from .sun import SunGaudinModel

__all__ = ["SunExactStep", "match_weights", "step_weights"]


def step_weights(model: SunGaudinModel, X, etas, branches) -> np.ndarray:
    """``Ω = Σ_k ω^{(r_k)}(η_k)`` at ``X``: the weights of the Hamiltonian whose time-1 flow is the composition."""
    return np.sum([model.interpolating_weights(X, e, r) for e, r in zip(etas, branches, strict=True)], axis=0)


@dataclass(frozen=True)
class SunExactStep:
    """One step: ``B^{(r_K)}_{η_K} ∘ … ∘ B^{(r_1)}_{η_1}`` (module docstring), the time-1 flow of
    ``Σ_I Ω_I h_I``, :meth:`weights`; with ``η_k`` from :func:`match_weights` the time-``dt`` flow of ``H``."""

    model: SunGaudinModel
    etas: tuple
    branches: tuple

    def __post_init__(self):
        if not isinstance(self.model, SunGaudinModel):
            raise InvalidParameterError("model must be an su(n) GaudinModel (algebra='su(n)')")
        if len(self.etas) != len(self.branches) or not self.etas:
            raise InvalidParameterError("give as many branches as etas (at least one map)")
        maps = tuple(self.model.two_point_backlund(complex(e), r, backend="numpy")
                     for e, r in zip(self.etas, self.branches, strict=True))
        object.__setattr__(self, "_maps", maps)

    def weights(self, X) -> np.ndarray:
        return step_weights(self.model, X, self.etas, self.branches)

    def iterate(self, X, steps: int) -> np.ndarray:
        """``steps + 1`` states ``X, S(X), S²(X), …``."""
        out = [np.asarray(X, dtype=float)]
        cur = out[0]
        carries = [None] * len(self._maps)  # type: ignore[attr-defined]
        for _ in range(int(steps)):
            for i, m in enumerate(self._maps):  # type: ignore[attr-defined]
                cur, carries[i], _ = m.step(cur, carries[i])
            out.append(cur)
        return np.array(out)


def match_weights(model: SunGaudinModel, X, weights, dt: float, etas0, branches, *, tol: float = 1e-12,
                  max_iter: int = 30) -> tuple[complex, ...]:
    """The ``η_k`` (from the guess ``etas0``) with ``Σ_k ω^{(r_k)}(η_k) = dt·w`` on the non-Casimir integrals at
    ``X`` (module docstring), by Newton's method with a central-difference Jacobian (step ``1e-6``).

    Raises
    ------
    InvalidParameterError
        Not as many real unknowns (``2K``) as non-Casimir integrals.
    StepTooLargeError
        No convergence to ``tol`` (relative) in ``max_iter`` iterations: ``dt·w`` is not reached from this guess.
    """
    mask = ~np.asarray(model.casimir_mask())
    target = float(dt) * np.asarray(weights, dtype=float)[mask]
    p = np.array([[complex(e).real, complex(e).imag] for e in etas0], dtype=float).ravel()
    if p.size != target.size:
        raise InvalidParameterError(f"{p.size // 2} maps give {p.size} real parameters; the {model.algebra.name} "
                                    f"chain has {target.size} non-Casimir integrals: give {target.size // 2} etas")

    def F(q):
        return step_weights(model, X, [complex(a, b) for a, b in q.reshape(-1, 2)], branches)[mask] - target

    scale = 1.0 + np.max(np.abs(target))
    for _ in range(max_iter):
        f = F(p)
        if np.max(np.abs(f)) <= tol * scale:
            return tuple(complex(a, b) for a, b in p.reshape(-1, 2))
        h = 1e-6
        J = np.stack([(F(p + h * e) - F(p - h * e)) / (2 * h) for e in np.eye(p.size)], axis=1)
        try:
            p = p - np.linalg.solve(J, f)
        except np.linalg.LinAlgError:
            raise StepTooLargeError("the weights of the maps are dependent at these etas (singular Jacobian); give "
                                    "another guess (distinct Re eta, other branches)") from None
    raise StepTooLargeError(f"the weights dt*w are not reached from the guess etas0 (Newton: residual "
                            f"{np.max(np.abs(F(p))):.2e}); give a closer guess or a smaller dt")
