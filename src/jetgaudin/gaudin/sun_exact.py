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
:class:`SunExactFlow` is a :class:`jetgaudin.maps.Map` (runs, the CLI's ``orbit --dt`` and ``flow --method exact``):
its compiled route is the su(3) kernel's own loop with the ``K`` maps (:func:`jetgaudin.gaudin._sun_kernel.orbit_loop`
composes ``k`` maps; the single map is ``k = 1``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from .._errors import BranchPointError, InvalidParameterError, SingularStepError, StepTooLargeError
from .._validate import real_number
from ..maps import Advance, Backend, Map, MapProperties, StepByAdvance, check_count, per_orbit_buffers, register_map
from ._model_map import ModelMap, register_model_map
from .sun import SunGaudinModel
from .sun_maps import SunTwoPointBacklund

__all__ = ["SunExactFlow", "SunExactStep", "compose", "exact_parameters", "match_weights", "step_weights"]


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
        x = np.asarray(X, dtype=float)
        rows = np.empty((int(steps),) + x.shape)
        compose(self._maps, x, int(steps), 1, 1, rows)  # type: ignore[attr-defined]
        return np.concatenate([x[None], rows])


def compose(maps, x: np.ndarray, steps: int, substeps: int, save_every: int, rows: np.ndarray) -> np.ndarray:
    """``steps`` steps from ``x``, each ``substeps`` times ``maps`` in turn by their NumPy route (each map's ``μ_r``
    carried from its branch rule at ``x``), ``rows[j − 1]`` the state after ``j · save_every`` steps; returns the
    last state."""
    cur, carries = x, [None] * len(maps)
    for k in range(1, steps + 1):
        for _ in range(substeps):
            for j, m in enumerate(maps):
                cur, carries[j], _ = m.step(cur, carries[j])
        if k % save_every == 0:
            rows[k // save_every - 1] = cur
    return cur


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
                     max_iter: int = 20) -> tuple[tuple[complex, ...], tuple[int, ...]]:
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


#: a map whose ``|Im η|`` is at round-off of its ``Re η`` has weights ~1e-17: the identity, left out of the step
_IDENTITY_IM = 1e-13
#: the splits ``k`` :meth:`SunExactFlow._largest_dt` tries, in turn, for a solvable step ``dt/k`` (each trial is one
#: solve, ~0.2 s where it converges and a few s where Newton fails; solvability is not monotone in ``dt``: on the
#: orbit of ``tests/test_sun_exact.py`` 1/3 solves and 3/16 does not, so no bisection)
_SPLITS = (2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 256, 512, 1024)


@dataclass(frozen=True, eq=False)
class SunExactFlow(ModelMap, StepByAdvance, Map):
    r"""The exact time-``dt`` flow of ``H = Σ_I w_I h_I`` on an su(3) chain (a :class:`jetgaudin.maps.Map`: runs,
    the CLI's ``flow --method exact`` and ``orbit --dt``, :func:`jetgaudin.solve`'s ``method="exact"``).

    One step is ``substeps`` exact sub-steps of ``dt/substeps``, each the composition of the ``K = 3M`` maps
    :class:`SunExactStep` of :func:`exact_parameters`, solved once per orbit at the start of every :meth:`advance`
    call (the weights ``ω`` are functions of the integrals: constant along the orbit).  ``backend="compiled"``
    runs every step of one orbit in one compiled call, the su(3) kernel's loop with the ``K`` maps
    (:func:`jetgaudin.gaudin._sun_kernel.orbit_loop`: the loop of the single map, ``k = K``), a batch on all cores,
    each orbit its own parameters and its single run bit for bit; ``"numpy"`` the maps' NumPy route; ``"auto"`` the
    compiled one from ``AUTO_MIN_WORK`` map steps on.  The run layer cuts it in fixed chunks
    (``chunk_invariant = False``: each call starts every map's ``μ_r`` by its branch rule), so a resumed run meets
    the same cuts and the same bits.  A run solves the parameters once (:meth:`bind_run`: at the run's initial
    states, which a resume reads back from ``run.json``, so a resume solves them once more and gets the same bits);
    before, every chunk solved them again (~5 % of an orbit's time at ``--save-every 100``, issue 33 follow-up)."""

    H: Any
    dt: float
    substeps: int = 1
    backend: Backend = field(default=Backend.AUTO, compare=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)
    properties: MapProperties = field(
        default=MapProperties(preserves_integrals=True, poisson=True, real=True, order=None, symmetric=True,
                              interpolates_flow=False), init=False, repr=False, compare=False)
    chunk_invariant: ClassVar[bool] = False
    #: :meth:`bind_run`'s ``(X0 (B, 8M), maps per orbit)``; ``None``: solved at every :meth:`advance`
    _bound: ClassVar[Any] = None

    def __post_init__(self):
        model = getattr(self.H, "model", None)
        if not isinstance(model, SunGaudinModel) or np.ndim(self.H.weights) != 1:
            raise InvalidParameterError("H must be an su(n) chain's model.hamiltonian(weights) with one set of weights")
        if model.n != 3:
            raise InvalidParameterError(f"exact steps are built for su(3), not {model.algebra.name}; use "
                                        "method='dop853'")
        dt = real_number(self.dt, "dt")
        if dt == 0:
            raise InvalidParameterError("dt must be nonzero (dt = 0 is the identity); give e.g. dt = 0.1")
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "substeps", check_count(self.substeps, "substeps", 1))
        self._init_backend()

    @property
    def model(self) -> SunGaudinModel:
        return self.H.model

    @property
    def time_step(self) -> float:
        return self.dt

    @property
    def has_compiled(self) -> bool:
        return True

    def parameters(self, x) -> tuple[tuple[complex, ...], tuple[int, ...]]:
        """``(etas, branches)`` of one sub-step (``dt/substeps``) on the orbit ``x`` ``(8M,)``
        (:func:`exact_parameters`); :class:`~jetgaudin.StepTooLargeError` with ``dt_max`` the largest sub-step
        ``dt/k`` of the first ``k = 2, 3, 4, 6, …`` that solves (:meth:`_largest_dt`) where there are none."""
        x = np.asarray(self.model.check_state(x), dtype=float)
        if x.ndim != 1:
            raise InvalidParameterError(f"parameters take one orbit (shape ({self.n_state},)), got {x.shape}")
        h = self.dt / self.substeps
        try:
            return exact_parameters(self.model, x, self.H.weights, h)
        except StepTooLargeError:
            dmax = self._largest_dt(x, h)
        if dmax == 0.0:
            raise StepTooLargeError(f"dt = {h:g}: no exact step's parameters on this orbit even at dt/{_SPLITS[-1]}; "
                                    "use method='dop853'", dt_max=0.0)
        raise StepTooLargeError(
            f"dt = {h:g} is too large for this orbit: the exact step's parameters (Newton from the small-Im(eta) "
            f"guess) do not converge; dt = {dmax:.4g} (dt/{round(h / dmax)}) does: give |dt| <= {abs(dmax):.4g} or "
            f"substeps >= {math.ceil(abs(self.dt) / abs(dmax) * 1.01)}", dt_max=dmax)

    def _solvable(self, x, h: float) -> bool:
        try:
            exact_parameters(self.model, x, self.H.weights, h)
        except (StepTooLargeError, InvalidParameterError):
            return False
        return True

    def _largest_dt(self, x, h: float) -> float:
        """The first solvable step ``h/k``, ``k`` in :data:`_SPLITS` (0 when none is)."""
        return next((h / k for k in _SPLITS if self._solvable(x, h / k)), 0.0)

    def max_dt(self, X) -> np.ndarray:
        """A solvable sub-step for each orbit of ``X`` ``(..., 8M)``: ``10 |dt|/k`` of the first ``k`` in
        :data:`_SPLITS` that solves (solvability is not monotone: a lower bound of the largest, not the largest)."""
        X = np.asarray(self.model.check_state(X), dtype=float)
        return np.array([abs(self._largest_dt(x, 10 * self.dt)) for x in X.reshape(-1, X.shape[-1])]
                        ).reshape(X.shape[:-1])

    def _maps(self, x) -> list[SunTwoPointBacklund]:
        """The sub-step's maps on the orbit ``x`` (those with ``|Im η|`` at round-off left out: the identity)."""
        etas, branches = self.parameters(x)
        return [SunTwoPointBacklund(self.model, e, r, Backend.NUMPY) for e, r in zip(etas, branches, strict=True)
                if abs(e.imag) > _IDENTITY_IM * max(abs(e.real), 1.0)]

    def bind_run(self, X0) -> SunExactFlow:
        """This map with each orbit's sub-step maps solved once, at the run's initial states ``X0`` ``(8M,)`` or
        ``(B, 8M)`` (the run layer's :func:`jetgaudin.run.spec.run_map`): its :meth:`advance` of the run's orbits,
        in order, uses them instead of solving at every call (the parameters are functions of the integrals,
        constant along each orbit).  Only for the run's own orbits: a batch of ``b ≤ B`` orbits is taken as the
        run's first ``b`` (the driver's reference step on the first 64), so a map bound here must not be given
        other states.  The same map (``self``) when already bound at these ``X0``.  Raises what
        :meth:`parameters` raises (``StepTooLargeError`` with ``dt_max``; ``orbit i:`` named in a batch)."""
        X0 = np.asarray(self.model.check_state(X0), dtype=float)
        flat = X0.reshape(-1, X0.shape[-1])
        if self._bound is not None and np.array_equal(self._bound[0], flat):
            return self
        bound = SunExactFlow(self.H, self.dt, self.substeps, self.backend)
        object.__setattr__(bound, "_bound", (flat.copy(), self._solve(flat)))
        return bound

    def unbound(self) -> SunExactFlow:
        """This map solving the parameters at the start of every :meth:`advance` call (the run layer's way before
        :meth:`bind_run`; a run directory written that way is resumed that way: :mod:`jetgaudin.run.replay`)."""
        return self if self._bound is None else SunExactFlow(self.H, self.dt, self.substeps, self.backend)

    def _solve(self, flat: np.ndarray) -> list[list[SunTwoPointBacklund]]:
        """The sub-step's maps of each orbit of ``flat`` ``(B, 8M)``."""
        maps = []
        for i, x in enumerate(flat):
            try:
                maps.append(self._maps(x))
            except StepTooLargeError as exc:
                raise StepTooLargeError(f"orbit {i}: {exc}" if len(flat) > 1 else str(exc), dt_max=exc.dt_max) from None
        return maps

    def _auto_backend(self, X, steps) -> Backend:
        from ._backend import AUTO_MIN_WORK

        work = int(steps) * self.substeps * 3 * self.model.M * max(1, int(np.prod(np.shape(X)[:-1])))
        return Backend.COMPILED if work >= AUTO_MIN_WORK else Backend.NUMPY

    def advance(self, X, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """``steps`` exact steps from ``X`` ``(..., 8M)`` (parameters solved at ``X``, per orbit, or those of
        :meth:`bind_run`), rows every ``save_every`` (class doc); ``carry`` is not used (zeros back)."""
        steps, save_every, X, flat, rows, final = per_orbit_buffers(self.model, X, steps, save_every)
        if not steps:
            maps: list[list[SunTwoPointBacklund]] = [[] for _ in flat]
        elif self._bound is not None and len(flat) <= len(self._bound[1]):
            maps = self._bound[1][:len(flat)]
        else:
            maps = self._solve(flat)
        if (steps and self.resolved_backend(X, steps) is Backend.COMPILED and len(maps[0])
                and all(len(m) == len(maps[0]) for m in maps)):
            rows, final = self._compiled(flat, maps, steps, save_every)
        elif steps:
            for i, (x, ms) in enumerate(zip(flat, maps, strict=True)):
                final[i] = compose(ms, x, steps, self.substeps, save_every, rows[:, i])
        zeros = np.zeros(X.shape[:-1])
        return Advance(rows=rows.reshape((-1,) + X.shape), X=final.reshape(X.shape), carry=zeros.astype(complex),
                       imag_max=zeros)

    def _compiled(self, flat, maps, steps: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """The su(3) kernel's loop with the ``K`` maps of each orbit (a batch on all cores); ``μ_r`` of each map at
        the orbit's start by the NumPy branch rule, as the map's own compiled route."""
        from . import _sun_kernel as K

        B, k = len(flat), len(maps[0])
        mu0 = np.array([[m.start(x) for m in ms] for x, ms in zip(flat, maps, strict=True)], dtype=complex)
        eta = np.array([[m.eta for m in ms] for ms in maps], dtype=complex).reshape(B, k)
        consts = [[K.orbit_constants(self.model, m.eta) for m in ms] for ms in maps]
        fb, _, pos, off, orders = consts[0][0]
        F = np.array([[c[1] for c in cs] for cs in consts], dtype=complex).reshape(B, k, -1)
        run_orbit: Any = K.run_orbit  # Numba dispatchers
        run_batch: Any = K.run_batch
        x = np.ascontiguousarray(flat)
        if B == 1:
            r, xf, _ = run_orbit(x[0], fb, mu0[0], F[0], pos, off, orders, eta[0], steps, save_every, self.substeps)
            rows, final = r[:, None], xf[None]
        else:
            rows, final, _ = run_batch(x, fb, mu0, F, pos, off, orders, eta, steps, save_every, self.substeps)
        if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(final))):
            raise SingularStepError("the compiled su(3) exact step produced non-finite values (a map's eta at a branch "
                                    "point?); give a smaller dt")
        return rows, final

    def inverse(self) -> SunExactFlow:
        return SunExactFlow(self.H, -self.dt, self.substeps, self.backend)

    def describe(self) -> dict:
        return {"kind": "sun_exact", **self.model.describe(), "weights": np.asarray(self.H.weights).tolist(),
                "dt": self.dt, "substeps": self.substeps, "backend": self.backend.value}


def _from(d: dict) -> SunExactFlow:
    from .model import GaudinModel

    model = GaudinModel.from_description(d)
    if not isinstance(model, SunGaudinModel):
        raise InvalidParameterError("a sun_exact description needs an su(n) model ('algebra': 'su(n)')")
    return SunExactFlow(model.hamiltonian(np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                        int(d.get("substeps", 1)), Backend.parse(d.get("backend", "numpy")))


register_map("sun_exact", _from)
register_model_map("sun_exact", SunExactFlow)  # model.exact_flow (gaudin._model_map)
