r"""Exact time steps: the exact time-``dt`` flow of an integral Hamiltonian from commuting Bäcklund maps.

**Construction** (``docs/integrators.md``; ``docs/backlund.md`` §6).  The real two-point map ``B_η`` is exactly
the time-1 flow of ``G_η = Σ_m ω_m(η) κ_m`` with ``ω_m(η) = −2 ∫_0^{Im η} Re[λ^{-m}/(2ν(λ))] ds``,
``λ = Re η + i s`` (:func:`jetgaudin.interpolating_weights`), and the weights depend on the state only through the
integrals ``κ_m = (H_1..H_N, C_1..C_N)``, so they are constant along the orbit.  The maps commute, so a composite
``B_{η_1} ∘ … ∘ B_{η_k}`` is the time-1 flow of ``Σ_j G_{η_j}``: its weights add.  For a target
``H = Σ_m w_m κ_m`` (:class:`jetgaudin.IntegralHamiltonian`) and a time step ``dt`` we take ``k = N − 1`` maps
with fixed real parts ``ρ_j`` and solve their imaginary parts ``h_j`` (per orbit, from its integrals, once) from
the ``N − 1`` real equations

.. math:: \sum_{j=1}^{N-1} ω_m(ρ_j + i h_j) = dt\, w_m, \qquad m = 2, …, N.

The remaining weights need no map: ``C_1..C_N`` (``m > N``) are Casimirs (trivial flows), and the flow of
``H_1 = 2 b y_0^3`` is the rigid rotation ``ẏ_i = 2 b e_3 × y_i`` (all ``i``, eq. (LP)), so the ``H_1`` weight is
matched exactly by a rotation about the field through ``θ = 2 b (dt w_1 − Σ_j ω_1(η_j))``.  One step is
``R_θ ∘ B_{η_1} ∘ … ∘ B_{η_{N−1}}``: **the exact time-dt flow of H**, for any ``dt`` the equations can be solved for.

**The free parameters.**  With ``R = max_k |r_k|`` the largest modulus of the branch points (roots of
``λ^{2N} ν²``, from the integrals), ``ρ_j = c R / t_j``, ``t = (1, −1, 1/2, −1/2, 1/3, …)`` (first ``N − 1``;
N = 2: one map at ``cR``; N = 3: ``±cR``), ``c = rho_factor = 1.5``.  Every vertical segment ``[ρ_j, η_j]`` then stays
at distance ``≥ (c − 1) R`` from every branch point and at distance ``|ρ_j|`` from the pole ``λ = 0``: ``ν(η_j)``
is bounded away from zero (the map is well conditioned, ``docs/backlund.md`` §5), and the Gauss–Legendre rule of
the weights converges geometrically.  For small ``h/ρ``, ``ω_m ≈ −h ρ^{-m}/ν(ρ)``: the linear system in ``h`` is a
Vandermonde system in ``1/ρ_j`` (nodes ``±1, ±1/2, …``: well conditioned for the N of interest), which gives
Newton's starting point.

**Where no solution exists.**  ``|ω_m(ρ + i h)|`` is bounded in ``h`` (for ``ν ≈ |b|``: ``ω_2 = −h/(ρ² + h²)``, at
most ``1/(2ρ)``), so on each leaf only ``|dt|`` up to some ``dt_max ≈ 1/(c R)`` is reachable with well-conditioned
maps.  We accept a solution only when Newton converges with ``|h_j| ≤ 2|ρ_j|`` (before the fold of ``ω(h)``) and
the quadrature error estimate is at round-off; otherwise :class:`jetgaudin.StepTooLargeError` names the orbit and
its largest feasible ``dt`` (bisection).  ``substeps = s`` makes one step ``s`` exact sub-steps of ``dt/s``
(an exact composition, not an approximation; recorded in :meth:`ExactFlow.describe`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache
from typing import Any, ClassVar

import numpy as np

from ._errors import InvalidParameterError, StepTooLargeError
from ._system_maps import _EXACT_PROPERTIES, ExactFlow
from ._validate import as_state, field_vector, real_number
from .hamiltonians import IntegralHamiltonian
from .maps import Advance, Backend, Map, MapProperties, check_count, map_name, register_map
from .spectral import _nu_from_kappa, integrals

__all__ = ["ExactFlow", "MatchedBacklund", "ExactParameters", "exact_parameters", "rotate_about_field", "RHO_FACTOR",
           "record_integrals"]

#: ``c`` of ``ρ_j = c R / t_j`` (module doc): the segments stay ``(c − 1) R`` away from the branch points
RHO_FACTOR = 1.5
#: Gauss–Legendre nodes of the weights' quadrature (the estimate with half as many is checked, see below)
_NODES = 64
#: nodes of the rule Newton's method starts with (to a step of 1e-9 |h|; the 64-point rule then converges in one
#: or two iterations)
_COARSE_NODES = 16
#: accepted quadrature error estimate ``|Q_64 − Q_32|`` relative to the weights' scale (round-off level: the rule
#: converges geometrically on segments a distance ``≥ (c − 1) R`` from every singularity)
_QUAD_TOL = 1e-13
#: Newton stops when every step ``|Δh_j| ≤ _STEP_TOL |h_j|`` (the next residual is then at round-off)
_STEP_TOL = 1e-14
#: accepted residual ``|Σ_j ω_m − dt w_m|`` relative to ``Σ_j |ω_m| + |dt w_m|`` (a few hundred ulps)
_RES_TOL = 1e-12
#: ``|h_j| ≤ _FOLD |ρ_j|``: stay on the monotone branch of ``ω(h)`` (the fold is at ``h ≈ ρ`` for ``R ≪ ρ``)
_FOLD = 2.0
_NEWTON_ITERATIONS = 40
_CONTINUATION_STAGES = (1, 4, 16)
_STAGES = np.array(_CONTINUATION_STAGES, dtype=np.int64)
#: the continued ``ν(η_j)`` must equal the branch rule's to this relative tolerance (a branch point near a segment
#: flips the sign: a difference of order 1)
_BRANCH_TOL = 1e-8
#: rows at most this many (sub-)steps apart run in the one compiled loop of :mod:`jetgaudin._exact_loop` (a map
#: kernel call per step); farther apart, ``k s`` steps of each map per kernel call
_FUSED_ROWS = 16
#: batches of at least this many orbits solve on all threads (below, a thread start costs more than the work)
_PARALLEL_FROM = 256


@cache
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the ``n``-point Gauss–Legendre rule on ``[0, 1]``."""
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1.0) / 2.0, w / 2.0


@cache
def _node_scales(k: int) -> np.ndarray:
    """``t_1..t_k = 1, −1, 1/2, −1/2, …`` (``ρ_j = c R / t_j``)."""
    return np.array([(1.0 if j % 2 == 0 else -1.0) / (j // 2 + 1) for j in range(k)])


def _weights(kappa, roots, a, h, n=_NODES):
    r"""``ω_m(a + i h)`` for ``m = 1..2N`` by the ``n``-point Gauss–Legendre rule on ``s ∈ [0, h]`` of
    ``−2 Re[λ^{-m}/(2ν(λ))]``, ``λ = a + i s`` (default branch: continued from ``a`` along the segment), and
    ``∂ω_m/∂h = −Re[η^{-m}/ν(η)]`` (the integrand at the end point).  ``kappa`` ``(..., 2N+1)``, ``roots``
    ``(..., 2N)``, ``a``/``h`` ``(..., k)``; returns two arrays ``(..., k, 2N)``."""
    x, w = _gauss_legendre(n)
    M = kappa.shape[-1] - 1
    m = np.arange(1, M + 1)
    lam = a[..., None] + 1j * h[..., None] * np.concatenate([x, [1.0]])  # (..., k, n+1): nodes and the end point
    kap = np.broadcast_to(kappa[..., None, None, :], lam.shape + kappa.shape[-1:])
    rts = np.broadcast_to(roots[..., None, None, :], lam.shape + roots.shape[-1:])
    nu = _nu_from_kappa(kap, lam, 1, roots=rts)
    f = (lam[..., None] ** (-m) / nu[..., None]).real  # (..., k, n+1, 2N): Re[λ^{-m}/ν]
    f = np.moveaxis(f, -1, -2)  # (..., k, 2N, n+1): the node sum runs over the last (contiguous) axis
    omega = -h[..., None] * np.sum(f[..., :n] * w, axis=-1)
    return omega, -f[..., n]


@dataclass(frozen=True)
class ExactParameters:
    """The solved parameters of one exact (sub-)step for each orbit of a batch: ``eta`` ``(..., N−1)`` the maps'
    parameters, ``theta`` ``(...)`` the rotation angle about the field, ``dt`` the sub-step, ``residual`` ``(...)``
    the relative residual of the weight equations, ``quadrature_error`` ``(...)`` the relative estimate
    ``|Q_64 − Q_32|`` of the weights, ``nu`` ``(..., N−1)`` the maps' ``ν(η_j)`` (their first ``ν1``)."""

    eta: np.ndarray
    theta: np.ndarray
    dt: float
    residual: np.ndarray
    quadrature_error: np.ndarray
    nu: np.ndarray | None = None


def _field_strength(H: IntegralHamiltonian) -> float:
    if type(H.b) is float and H.b != 0 and math.isfinite(H.b):  # the common case, without building a vector
        return H.b
    bvec = field_vector(H.b)
    if bvec[0] != 0 or bvec[1] != 0 or bvec[2] == 0:
        raise InvalidParameterError(
            f"ExactFlow needs the field along e_3 (b = b e_3, b != 0; the Bäcklund maps are built for it), got b = "
            f"{bvec.tolist()}; rotate the state so that the field is b e_3"
        )
    return float(bvec[2])


@cache
def _solve_constants() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The solve's constants packed for :func:`jetgaudin._exact_kernels.solve_states`: the nodes and weights of the
    ``_NODES``-, ``_NODES // 2``- and ``_COARSE_NODES``-point rules one after the other, their sizes, the
    continuation stages and the tolerances."""
    sizes = np.array([_NODES, _NODES // 2, _COARSE_NODES], dtype=np.int64)
    rules = np.concatenate([a for n in sizes for a in _gauss_legendre(int(n))])
    tols = np.array([_STEP_TOL, _FOLD, _NEWTON_ITERATIONS, _RES_TOL, _QUAD_TOL, _BRANCH_TOL])
    return rules, sizes, _STAGES, tols


def _weights_of(H: IntegralHamiltonian) -> np.ndarray:
    """``H.weights`` as a contiguous float array (itself when it is one: the kernels only read it)."""
    w = H.weights
    if type(w) is np.ndarray and w.dtype == np.float64 and w.flags.c_contiguous:
        return w
    return np.ascontiguousarray(w, dtype=float)


def _solve_flat(H: IntegralHamiltonian, dt: float, X: np.ndarray, rho_factor: float, k: int | None = None):
    """The parameters for a flat batch ``X`` (B, 3N): ``(eta, theta, residual, quad_error, ok, nu)`` (``nu``: the
    maps' ``ν(η_j)`` on the checked branch, their first ``ν1``); ``k`` maps
    (default ``N − 1``) matching the weights of ``H_2..H_{k+1}`` (fewer than ``N − 1``: not the exact flow).  One
    compiled call (:func:`jetgaudin._exact_kernels.solve_states`): per orbit the integrals ``κ``, the branch points'
    largest modulus ``R`` (``≥ 1e-6``: ``X = 0`` has every branch point at 0), ``ρ_j``, Newton's method and the
    acceptance, including the check that the continued ``ν`` at each ``η_j`` is the branch rule's (the maps' own
    ``ν``: no branch point near a segment)."""
    from ._exact_kernels import solve_states, solve_states_batch

    k = H.N - 1 if k is None else k
    X = np.ascontiguousarray(X, dtype=float)
    eta = np.empty((X.shape[0], k), dtype=complex)
    nu = np.empty((X.shape[0], k), dtype=complex)
    out = np.empty((X.shape[0], 4))
    solve = solve_states_batch if len(X) >= _PARALLEL_FROM else solve_states  # small: this thread, no start-up
    solve(X, _field_strength(H), _weights_of(H), float(dt), k, float(rho_factor), _node_scales(k), *_solve_constants(),
          eta, nu, out)
    return eta, out[:, 3], out[:, 1], out[:, 2], out[:, 0] == 1.0, nu


def _largest_dt(H: IntegralHamiltonian, dt: float, x: np.ndarray, rho_factor: float, rel: float = 1e-3,
                k: int | None = None) -> float:
    """The largest ``|dt'| ≤ |dt|`` (sign of ``dt``) solvable on the orbit ``x`` (3N,), by bisection to ``rel``;
    0 where none above ``1e-12 |dt|`` is (at most ~40 halvings: without the floor an orbit where nothing is
    feasible halved ``hi`` to underflow, ~1000 failing solves)."""
    lo, hi = 0.0, abs(dt)
    while hi - lo > rel * hi and hi > 1e-12 * abs(dt):
        mid = 0.5 * (lo + hi)
        if _solve_flat(H, math.copysign(mid, dt), x[None], rho_factor, k)[4][0]:
            lo = mid
        else:
            hi = mid
    return math.copysign(lo, dt)


def exact_parameters(H: IntegralHamiltonian, dt: float, X, *, rho_factor: float = RHO_FACTOR,
                     maps: int | None = None) -> ExactParameters:
    r"""Solve the parameters of the exact time-``dt`` step of ``H`` for every orbit of ``X`` ``(..., 3N)`` (module
    doc).  Raises :class:`jetgaudin.StepTooLargeError` (with ``dt_max``) when an orbit has no solution.
    ``maps``: use fewer than ``N − 1`` maps (matching ``H_2..H_{maps+1}`` only: the plain map of
    :class:`MatchedBacklund`, not the exact flow)."""
    X, N = as_state(X)
    if getattr(H, "route_kind", None) != "top" or np.ndim(H.weights) != 1:
        raise InvalidParameterError("H must be an IntegralHamiltonian of the top (a field b, not a model: a chain's "
                                    "exact steps are jg.ExactFlow(H, dt)) with one set of weights (shape (2N,))")
    if H.N != N or N < 2:
        raise InvalidParameterError(f"ExactFlow needs N >= 2 and states of 3N = {3 * H.N} components, got {3 * N}")
    if H.c is not None:
        raise InvalidParameterError("ExactFlow supports the reduction (lax2) only (c = None)")
    dt = nonzero_step(dt)
    Xf = X.reshape(-1, 3 * N)
    eta, theta, res, quad, nu = _accepted(H, dt, Xf, rho_factor, maps)
    lead = X.shape[:-1]
    return ExactParameters(eta.reshape(lead + (eta.shape[-1],)), theta.reshape(lead), dt, res.reshape(lead),
                           quad.reshape(lead), nu.reshape(lead + (nu.shape[-1],)))


def _accepted(H: IntegralHamiltonian, dt: float, Xf: np.ndarray, rho_factor: float, maps: int | None):
    """:func:`_solve_flat` on checked inputs; :class:`StepTooLargeError` naming the first orbit without a
    solution and its largest feasible ``dt``."""
    eta, theta, res, quad, ok, nu = _solve_flat(H, dt, Xf, rho_factor, maps)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        dmax = _largest_dt(H, dt, Xf[i], rho_factor, k=maps)
        raise StepTooLargeError(
            f"dt = {dt:g} is too large for orbit {i} (its leaf): no well-conditioned Bäcklund parameters give the "
            f"exact time-dt step there; the largest feasible time step is dt = {dmax:.4g}. Give |dt| <= "
            f"{abs(dmax):.4g} or substeps >= {math.ceil(abs(dt) / max(abs(dmax), 1e-300) * 1.01)}",
            dt_max=dmax,
        )
    return eta, theta, res, quad, nu


def record_integrals(H: IntegralHamiltonian, X) -> np.ndarray:
    """``jg.integrals(X, H.b, H.c)`` of the rows ``X`` ``(..., 3N)`` that ``jg.solve`` records: one compiled pass
    (:func:`jetgaudin._exact_kernels.integrals_rows`, the same bits) for the reduction (lax2) with a field along
    ``e_3`` and real finite rows, else :func:`jetgaudin.spectral.integrals` (which also refuses an overflow)."""
    X = np.asarray(X)
    b = H.b
    if (H.c is None and type(b) is float and X.dtype == np.float64 and X.ndim >= 1 and X.shape[-1] % 3 == 0
            and X.size and np.isfinite(b)):
        from ._exact_kernels import integrals_rows

        flat = np.ascontiguousarray(X.reshape(-1, X.shape[-1]))
        out = np.empty((flat.shape[0], 2 * (X.shape[-1] // 3)))
        integrals_rows(flat, b, out)
        if np.isfinite(out).all():
            return out.reshape(X.shape[:-1] + out.shape[-1:])
    return np.asarray(integrals(X, b, H.c), dtype=float)


def rotate_about_field(X, theta):
    r"""Rotate every ``y_i`` of ``X`` ``(..., 3N)`` about ``e_3`` by the angles ``theta`` ``(...)``
    (counter-clockwise): the time-``τ`` flow of ``ω H_1`` with ``θ = 2 b ω τ`` (``ẏ_i = 2 b e_3 × y_i``)."""
    X = np.asarray(X, dtype=float)
    Y = X.reshape(X.shape[:-1] + (-1, 3))
    c = np.cos(theta)[..., None]
    s = np.sin(theta)[..., None]
    out = Y.copy()
    out[..., 0] = c * Y[..., 0] - s * Y[..., 1]
    out[..., 1] = s * Y[..., 0] + c * Y[..., 1]
    return out.reshape(X.shape)


def nonzero_step(dt) -> float:
    """A finite, nonzero time step ``dt`` (:class:`InvalidParameterError` otherwise)."""
    dt = real_number(dt, "dt")
    if dt == 0:
        raise InvalidParameterError("dt must be nonzero (dt = 0 is the identity); give e.g. dt = 0.1")
    return dt


class FixedStep:
    """What every fixed-step map of a Hamiltonian ``H`` (attributes ``H``, ``dt``) shares: the state length and the
    ``time_step`` (the run layer writes ``t = n · time_step``)."""

    H: IntegralHamiltonian
    dt: float

    @property
    def n_state(self) -> int:
        return 3 * self.H.N

    @property
    def time_step(self) -> float:
        """The time one step advances (``dt``)."""
        return self.dt




@dataclass(frozen=True, eq=False)
class _TopExactFlow(FixedStep, Map):
    r"""The top's route of :class:`jetgaudin.ExactFlow` (``H`` an ``IntegralHamiltonian``; the route table of
    :mod:`jetgaudin._system_maps`): the exact time-``dt`` flow of ``H`` as a :class:`~jetgaudin.maps.Map` (module
    doc): one step is ``substeps`` times ``R_θ ∘ B_{η_1} ∘ … ∘ B_{η_{N−1}}`` with the parameters of
    :func:`exact_parameters` for ``dt/substeps``.

    ``H``: an :class:`~jetgaudin.IntegralHamiltonian` with field ``b e_3`` (default use:
    ``jg.physical_hamiltonian(N, b)``), any ``N ≥ 2``; ``dt``: either sign (``−dt`` is :meth:`inverse`).  States
    ``(3N,)`` or a batch ``(..., 3N)``; **each orbit solves its own parameters** from its integrals at the start of
    every :meth:`advance` / :meth:`step` call (constant along the orbit: re-solving at a later state changes them
    by round-off only).  ``backend``: ``NUMPY`` (the reference route: every step ``B_{η_1}``, …, then the rotation)
    or ``COMPILED`` (the Numba kernels of the two-point map with a parameter per orbit: between two saved rows the
    ``k`` steps of each map run in one kernel call, then one rotation by ``kθ`` — the same flow, since the maps
    and the rotation commute, with other round-off; so ``chunk_invariant = False`` and the run layer cuts the run
    into fixed chunks, which keeps resume bit for bit); ``AUTO``: compiled.  No carry (zeros): each kernel call
    takes ``ν(η_j)`` by the branch rule.  Not an integrator with an order: the step *is* the flow
    (``order = None``); it preserves the integrals, is a Poisson map (a composition of Poisson maps and a rotation)
    and real.  (The example is the public class's, :class:`jetgaudin.ExactFlow`.)
    """

    H: IntegralHamiltonian
    dt: float
    substeps: int = 1
    backend: Backend = Backend.AUTO  # type: ignore[assignment]
    rho_factor: float = RHO_FACTOR
    properties: MapProperties = field(default=_EXACT_PROPERTIES, init=False, repr=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias of backend
    chunk_invariant: ClassVar[bool] = False
    #: the backend rule (jetgaudin.maps): advance runs the compiled kernels itself (AUTO: compiled)
    has_compiled: ClassVar[bool] = True  # type: ignore[misc]
    _maps: ClassVar[int | None] = None  # the number of two-point maps per (sub-)step; None: N − 1 (the exact flow)
    _kind: ClassVar[str] = "exact"
    public_name: ClassVar[str] = "ExactFlow"  # the class its messages name (jetgaudin.maps.map_name)

    def __post_init__(self) -> None:
        if getattr(self.H, "route_kind", None) != "top":
            raise InvalidParameterError("H must be an IntegralHamiltonian of the top (e.g. "
                                        "jg.physical_hamiltonian(N, b))")
        if self.H.N < 2 or np.ndim(self.H.weights) != 1:
            raise InvalidParameterError("ExactFlow needs N >= 2 and one set of weights (shape (2N,))")
        if self.H.c is not None:
            raise InvalidParameterError("ExactFlow supports the reduction (lax2) only (c = None)")
        _field_strength(self.H)
        k = self.H.N - 1 if self._maps is None else self._maps
        if not np.any(np.asarray(self.H.weights, dtype=float)[1:k + 1]):
            raise InvalidParameterError(
                f"{map_name(self)} matches the weights of H_2..H_{k + 1} with Bäcklund maps, and H has none "
                "(those weights are 0): its flow is the rotation about the field, which no such map gives. Use "
                "jetgaudin.exact.rotate_about_field(X, 2 * b * w_1 * t) (the exact flow of w_1 H_1) or "
                "method='dop853'")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        object.__setattr__(self, "substeps", check_count(self.substeps, "substeps", 1))
        self._init_backend()
        rf = real_number(self.rho_factor, "rho_factor")
        if rf <= 1:
            raise InvalidParameterError(f"rho_factor must be > 1 (Re eta beyond every branch point), got {rf}")
        object.__setattr__(self, "rho_factor", rf)

    @property
    def b(self) -> float:
        return _field_strength(self.H)

    def parameters(self, X) -> ExactParameters:
        """The parameters of one sub-step (``dt/substeps``) for the orbits ``X``."""
        return exact_parameters(self.H, self.dt / self.substeps, X, rho_factor=self.rho_factor, maps=self._maps)

    def max_dt(self, X) -> np.ndarray:
        """The largest feasible ``|dt|`` of one sub-step for each orbit of ``X`` ``(..., 3N)`` (bisection to 1e-3,
        searched up to 100), so one step of this map is feasible iff ``|dt|/substeps`` is below it."""
        X, _ = as_state(X)
        flat = X.reshape(-1, X.shape[-1])
        out = [abs(_largest_dt(self.H, 100.0, x, self.rho_factor, k=self._maps)) for x in flat]
        return np.array(out).reshape(X.shape[:-1])

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(integrals(X, self.b), dtype=float)

    def _maps_numpy(self, X: np.ndarray, eta: np.ndarray) -> np.ndarray:
        from .backlund.maps import TwoPointBacklund

        b = self.b
        for i in range(X.shape[0]):
            x = X[i]
            for e in eta[i]:
                x = TwoPointBacklund(b, e, backend=Backend.NUMPY).step(x)[0]
            X[i] = x
        return X

    def _maps_compiled(self, X: np.ndarray, eta: np.ndarray, nu: np.ndarray, k: int) -> np.ndarray:
        """``k`` steps of every map, one kernel call each (per-orbit ``η``: the ensemble kernels), each started
        from ``ν1 = ν(η_j)`` of the solve (``nu``; ``ν(η)`` depends on the integrals only, so it is the branch rule's
        ``ν`` at every state of the orbit)."""
        from .backlund._compiled import kernels

        K = kernels()
        b = _field_strength(self.H)
        bb = np.full(X.shape[0], b) if X.shape[0] > 1 else None
        for j in range(eta.shape[-1]):
            if X.shape[0] == 1:  # the single-orbit kernel (the same bits as a batch member, ~20x faster for one)
                X = K.iterate_single(X[0], b, eta[0, j], nu[0, j], False, k, k, want_drift=False)[1][None]
                continue
            ee = np.ascontiguousarray(eta[:, j])
            nu0 = np.ascontiguousarray(nu[:, j])
            X = np.ascontiguousarray(K.iterate_batch(X, bb, ee, nu0, False, k, k, want_drift=False)[1])
        return X

    def _run(self, X: np.ndarray, eta: np.ndarray, theta: np.ndarray, nu: np.ndarray, steps: int,
             save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, final)`` of ``steps`` steps on a flat batch ``X`` (B, 3N) with the maps' ``eta`` (B, k), their
        first ``ν1`` ``nu`` (B, k) and the rotation angles ``theta`` (B,) of one sub-step.  The maps run on the
        unrotated orbit ``Z`` (they commute with the rotation) and each row is ``R_{n s θ} Z_n``, one rotation
        through the accumulated angle: the rotation's round-off does not accumulate (a fixed ``R_θ`` applied at
        every step changes ``|y|`` by the same ``O(ε)`` factor every step, a drift linear in the steps).  Compiled,
        with rows at most :data:`_FUSED_ROWS` steps apart: every step in one compiled loop
        (:mod:`jetgaudin._exact_loop`); farther apart: ``k s`` steps of each map per kernel call."""
        s = self.substeps
        rows = np.empty((steps // save_every,) + X.shape)
        compiled = self.resolved_backend(X, steps) is Backend.COMPILED
        Z = np.ascontiguousarray(X, dtype=float)
        if compiled and save_every * s <= _FUSED_ROWS:
            return self._run_fused(Z, eta, theta, nu, steps, save_every, rows)
        rotate: Any = rotate_about_field
        if compiled:
            from ._exact_kernels import rotate
        done = 0
        while done < steps:
            k = min(save_every - done % save_every, steps - done)
            if compiled:
                Z = self._maps_compiled(Z, eta, nu, k * s)
            else:
                for _ in range(k * s):
                    Z = self._maps_numpy(Z.copy(), eta)
            done += k
            if done % save_every == 0:
                rows[done // save_every - 1] = rotate(Z, (done * s) * theta)
        return rows, rotate(Z, (steps * s) * theta)

    def _run_fused(self, Z: np.ndarray, eta: np.ndarray, theta: np.ndarray, nu: np.ndarray, steps: int,
                   save_every: int, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from ._exact_loop import rows_batch, rows_serial

        final = np.empty_like(Z)
        info = np.zeros((Z.shape[0], 2), dtype=np.int64)
        run = rows_serial if Z.shape[0] == 1 else rows_batch  # one orbit: this thread, no thread start-up
        run(Z, _field_strength(self.H), np.ascontiguousarray(eta), np.ascontiguousarray(nu),
            np.ascontiguousarray(theta, dtype=float), steps, save_every, self.substeps, rows, final, info)
        if info[0, 0] or (Z.shape[0] > 1 and info[:, 0].any()):
            from .backlund._compiled import kernels

            i = int(np.flatnonzero(info[:, 0])[0])
            raise kernels().status_error(info[i, 0], info[i, 1], i if Z.shape[0] > 1 else None)
        return rows, final

    def _solve_and_run(self, flat: np.ndarray, steps: int, save_every: int) -> tuple[np.ndarray, np.ndarray] | None:
        """One orbit's solve and every-row run in one compiled call (:func:`jetgaudin._exact_loop.solve_rows`; the
        same kernels, so the same bits, as :func:`_accepted` then :meth:`_run_fused`): ``(rows, final)``, or
        ``None`` where the route is not compiled or the solve is not accepted (the caller then takes the general
        path, which raises the error naming ``dt_max``)."""
        if self.resolved_backend(flat, steps) is not Backend.COMPILED:
            return None
        from ._exact_loop import solve_rows

        k = self.H.N - 1 if self._maps is None else self._maps
        Z = np.ascontiguousarray(flat, dtype=float)
        eta = np.empty((1, k), dtype=complex)
        nu = np.empty((1, k), dtype=complex)
        out = np.empty((1, 4))
        rows = np.empty((steps // save_every,) + Z.shape)
        final = np.empty_like(Z)
        info = np.zeros((1, 2), dtype=np.int64)
        if not solve_rows(Z, _field_strength(self.H), _weights_of(self.H), float(self.dt / self.substeps), k,
                          float(self.rho_factor), _node_scales(k), *_solve_constants(), steps, save_every,
                          self.substeps, eta, nu, out, rows, final, info):
            return None
        if info[0, 0]:
            from .backlund._compiled import kernels

            raise kernels().status_error(info[0, 0], info[0, 1], None)
        return rows, final

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        adv = self.advance(X, carry, 1)
        return adv.X, adv.carry, adv.imag_max

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """``steps`` exact steps from ``X`` ``(..., 3N)`` (parameters solved at ``X``), rows every ``save_every``."""
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        X, N = as_state(X)
        if N != self.H.N:
            raise InvalidParameterError(f"states need 3N = {3 * self.H.N} components, got {3 * N}")
        lead = X.shape[:-1]
        zeros = np.zeros(lead, dtype=complex)
        flat = X.reshape(-1, 3 * N)
        if steps == 0 or flat.shape[0] == 0:
            rows = np.empty((steps // save_every,) + X.shape)
            return Advance(rows=rows, X=X.copy(), carry=zeros, imag_max=zeros.real)
        if flat.shape[0] == 1 and save_every * self.substeps <= _FUSED_ROWS:
            fused = self._solve_and_run(flat, steps, save_every)
            if fused is not None:
                return Advance(rows=fused[0].reshape((-1,) + X.shape), X=fused[1].reshape(X.shape), carry=zeros,
                               imag_max=zeros.real)
        eta, theta, _, _, nu = _accepted(self.H, self.dt / self.substeps, flat, self.rho_factor, self._maps)
        rows, final = self._run(flat, eta, theta, nu, steps, save_every)
        return Advance(rows=rows.reshape((-1,) + X.shape), X=final.reshape(X.shape), carry=zeros,
                       imag_max=zeros.real)

    def inverse(self) -> _TopExactFlow:
        """The flow backwards: ``dt → −dt``."""
        return type(self)(self.H, -self.dt, self.substeps, self.backend, self.rho_factor)

    def describe(self) -> dict:
        return {"kind": self._kind, "b": self.b, "weights": np.asarray(self.H.weights).tolist(), "dt": self.dt,
                "substeps": self.substeps, "backend": self.backend.value, "rho_factor": self.rho_factor}


@dataclass(frozen=True, eq=False)
class MatchedBacklund(_TopExactFlow):
    r"""The plain Bäcklund map as a time step of ``H`` (the baseline of ``docs/integrators.md``): **one** two-point
    map per step, ``Re η = c R``, ``Im η`` solved so that its ``H_2`` weight is ``dt w_2``, and the ``H_1`` rotation
    undone exactly.  For N = 2 this is :class:`ExactFlow`; for N ≥ 3 it is the exact time-``dt`` flow of
    ``H + Σ_{m ≥ 3} (ω_m/dt − w_m) H_m`` (``ω_3/ω_2 ≈ 1/Re η``): not a consistent integrator of ``H`` at fixed
    ``Re η`` (its error per unit time does not shrink with ``dt``).  Same interface as :class:`ExactFlow`."""

    _maps = 1
    _kind = "matched_backlund"
    public_name = "MatchedBacklund"


def _exact_from(d: dict) -> Map:
    H = IntegralHamiltonian(float(d["b"]), np.asarray(d["weights"], dtype=float))
    cls = MatchedBacklund if d["kind"] == "matched_backlund" else ExactFlow
    return cls(H, float(d["dt"]), int(d.get("substeps", 1)), d.get("backend", "auto"),
               float(d.get("rho_factor", RHO_FACTOR)))


register_map("exact", _exact_from)
register_map("matched_backlund", _exact_from)
