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
method from a starting guess (a finite-difference Jacobian).

**Any weights, su(3)** (:func:`exact_parameters`, :class:`SunExactFlow`, ``jg.solve(..., method="exact")``): fix
the real parts of ``K = 3M`` maps at ``2M`` real points and solve for the imaginary parts, starting from the
``Im η → 0`` limit ``ω^{(r)}(a + iε) = −2ε ∂μ_r/∂h(a) + O(ε³)`` (a linear solve) — the eigenvalue gradients at
``2M`` points span all ``3M`` non-Casimir directions, so no constant rotation is needed (docs/sun.md §5).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._errors import BranchPointError, InvalidParameterError, StepTooLargeError
from .sun import SunGaudinModel

__all__ = ["SunExactFlow", "SunExactStep", "exact_parameters", "match_weights", "step_weights"]


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


# ---- jg.solve(..., method="exact") for su(3): fixed real points, Newton on the imaginary parts -----------------

def _dmu_dh(model: SunGaudinModel, X, eta: complex, r: int) -> np.ndarray:
    r"""``∂μ_r(η)/∂h_I`` (complex), ``n = 3``: ``μ³ − τ₂μ − τ₃ = 0`` (the characteristic polynomial of a traceless
    3 × 3 matrix: ``tr ℓ²/2 = τ₂``, ``det ℓ = tr ℓ³/3 = τ₃``) gives ``∂μ/∂τ₂ = μ/p'``, ``∂μ/∂τ₃ = 1/p'``,
    ``p' = 3μ² − τ₂``; and ``∂τ_k(η)/∂h^{(k)}_{j,m} = (η − λ_j)^{−m}``."""
    mu = complex(model.eigenvalue(X, eta, r))
    L = model.lax_matrix(X, eta)
    tau2 = complex(np.trace(L @ L)) / 2
    dp = 3 * mu * mu - tau2
    d = {2: mu / dp, 3: 1.0 / dp}
    return np.array([d[k] * (eta - lam) ** (-m) for k in range(2, 4) for lam, N in model.sites
                     for m in range(1, k * N + 1)])


def _points(model: SunGaudinModel, count: int) -> list[float]:
    """``count`` real points off the sites: outside the sites and between them, then further out."""
    lam = sorted(p for p, _ in model.sites)
    s = max(1.0, lam[-1] - lam[0])
    pts = [lam[0] - s / 2] + [(u + v) / 2 for u, v in zip(lam, lam[1:], strict=False)] + [lam[-1] + s / 2]
    k = 1
    while len(pts) < count:
        pts += [lam[-1] + s / 2 + k * s, lam[0] - s / 2 - k * s]
        k += 1
    return pts[:count]


def exact_parameters(model: SunGaudinModel, X, weights, dt: float, *, tol: float = 1e-13,
                     max_iter: int = 40) -> tuple[tuple[complex, ...], tuple[int, ...]]:
    r"""``(etas, branches)`` with ``Σ_k ω^{(r_k)}(η_k) = dt·w`` on the non-Casimir integrals at ``X`` (``n = 3``).

    The real parts are fixed: ``K = 3M`` maps (``M = Σ N_j``, ``K`` the number of non-Casimir integrals) at
    ``2M`` real points ``a`` off the sites (:func:`_points`), branches ``0, 1`` at the first ``M``, ``0`` at the
    others.  Why: by :func:`_dmu_dh`, ``∂μ_r/∂h(a) = (μ_r/p'_r) (u(a), 0) + (1/p'_r) (0, v(a))`` with
    ``u = ((a − λ_j)^{−m})_{m ≤ N_j}`` (the ``M`` non-Casimir ``h^{(2)}``) and ``v`` the same for
    ``m ≤ 2N_j`` (the ``2M`` non-Casimir ``h^{(3)}``), so the branches at one point span only
    ``{(u(a), 0), (0, v(a))}`` (2 directions; the third branch is dependent, ``Σ_r μ_r = 0``) and the ``v(a)`` of
    ``2M`` distinct points (partial fractions) are needed to span the ``h^{(3)}`` directions.  Then
    ``ω^{(r)}_I(a + iε) = −2∫_0^ε Re ∂μ_r/∂h_I(a + is) ds`` (sun_spectral), so
    ``∂ω^{(r)}/∂ε = −2 Re ∂μ_r/∂h(a + iε)`` (:func:`_dmu_dh`): the starting guess is the linear solve
    ``dt·w = −2 Σ_k ε_k ∂μ_{r_k}/∂h(a_k)`` (the ``ε → 0`` limit) and Newton's method, with that exact Jacobian,
    solves for the ``ε_k``.

    Raises
    ------
    InvalidParameterError
        ``n ≠ 3``, or the gradients at these points are dependent (the weights are not reachable this way).
    StepTooLargeError
        Newton does not converge (``dt_max = dt/2``: :func:`jetgaudin.solve` then takes sub-steps).
    """
    if model.n != 3:
        raise InvalidParameterError(f"exact steps are built for su(3), not {model.algebra.name}; use "
                                    "method='dop853'")
    mask = ~np.asarray(model.casimir_mask())
    target = float(dt) * np.asarray(weights, dtype=float)[mask]
    K, M = int(mask.sum()), model.M  # K = 3M
    pts = _points(model, 2 * M)
    a = [p for p in pts[:M] for _ in range(2)] + pts[M:]
    branches = tuple([0, 1] * M + [0] * M)

    def jac(eps):
        return np.stack([-2 * _dmu_dh(model, X, complex(p, e), r).real[mask]
                         for p, e, r in zip(a, eps, branches, strict=True)], axis=1)

    J0 = jac(np.zeros(K))
    if np.linalg.cond(J0) > 1e10:
        raise InvalidParameterError("the eigenvalue gradients at the chosen real points are dependent on this orbit "
                                    "(the weights are not reachable by the exact step); use method='dop853'")
    eps = np.linalg.solve(J0, target)
    scale = 1.0 + np.max(np.abs(target))
    for _ in range(max_iter):
        if np.any(eps == 0.0):  # a real eta has omega = 0: nudge (Newton corrects it)
            eps = np.where(eps == 0.0, 1e-300, eps)
        try:
            f = step_weights(model, X, [complex(p, e) for p, e in zip(a, eps, strict=True)], branches)[mask] - target
            if np.max(np.abs(f)) <= tol * scale:
                return tuple(complex(p, e) for p, e in zip(a, eps, strict=True)), branches
            eps = eps - np.linalg.solve(jac(eps), f)
        except (np.linalg.LinAlgError, InvalidParameterError, BranchPointError):
            break
        if not np.all(np.isfinite(eps)):
            break
    raise StepTooLargeError(f"dt = {dt:g}: the exact step's parameters (Newton from the small-Im(eta) guess) do "
                            "not converge; give a smaller dt or substeps", dt_max=abs(float(dt)) / 2)


@dataclass(frozen=True)
class SunExactFlow:
    """The time-``dt`` flow of ``H = Σ_I w_I h_I`` on an su(3) chain, ``substeps`` exact sub-steps of ``dt/substeps``
    per step, each :class:`SunExactStep` with the parameters of :func:`exact_parameters` (solved once per orbit:
    the weights ``ω`` are functions of the integrals).  :func:`jetgaudin.solve`'s ``method="exact"``."""

    H: Any
    dt: float
    substeps: int = 1

    def __post_init__(self):
        if not isinstance(getattr(self.H, "model", None), SunGaudinModel):
            raise InvalidParameterError("H must be an su(n) chain's model.hamiltonian(weights)")
        if not (np.isfinite(self.dt) and self.dt != 0) or int(self.substeps) < 1:
            raise InvalidParameterError("dt must be finite and nonzero, substeps a positive integer")

    def _step(self, x: np.ndarray) -> SunExactStep:
        model = self.H.model
        etas, branches = exact_parameters(model, x, self.H.weights, self.dt / self.substeps)
        return SunExactStep(model, etas, branches)

    def __call__(self, X) -> np.ndarray:
        """One step of ``dt`` from ``X`` ``(n_state,)``."""
        x = np.asarray(self.H.model.check_state(X), dtype=float)
        return self._step(x).iterate(x, self.substeps)[-1]

    def advance(self, X, carry, steps: int, save_every: int = 1):
        """``steps`` steps from ``X`` ``(..., n_state)``, rows every ``save_every``
        (:class:`jetgaudin.maps.Advance`)."""
        from ..maps import Advance

        X = np.asarray(self.H.model.check_state(X), dtype=float)
        flat = X.reshape(-1, X.shape[-1])
        rows = np.empty((steps // save_every,) + flat.shape)
        final = flat.copy()
        for i, x in enumerate(flat):
            maps = self._step(x)._maps  # type: ignore[attr-defined]
            cur, carries = x, [None] * len(maps)
            for k in range(1, steps + 1):
                for _ in range(self.substeps):
                    for j, m in enumerate(maps):
                        cur, carries[j], _ = m.step(cur, carries[j])
                if k % save_every == 0:
                    rows[k // save_every - 1, i] = cur
            final[i] = cur
        zeros = np.zeros(X.shape[:-1])
        return Advance(rows=rows.reshape((-1,) + X.shape), X=final.reshape(X.shape), carry=zeros.astype(complex),
                       imag_max=zeros)
