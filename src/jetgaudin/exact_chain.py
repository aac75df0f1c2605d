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
a site modulo the period), and so does a family whose ``R`` is at its floor (one site and no computed branch points:
the Clebsch top, whose ``λ_c ± cR`` sat on the site).  So ``k = (matched integrals) − (rotation) − (identities)`` maps:
``M − 1`` (rational, trigonometric), ``M`` (elliptic).  Only :class:`~jetgaudin.GaudinModel`'s public methods are used.

**Solve and steps** (``docs/integrators.md`` §7).  The weights by a 64-point Gauss–Legendre rule with ``ν`` continued
node by node, Newton's method in one compiled call for every family (:mod:`jetgaudin._exact_chain_kernels`, the
family's basis ``ψ_m`` compiled; :data:`COMPILED_FAMILIES`) or on the NumPy route (:class:`_Weights`, the reference
the tests compare with; the adaptive quadrature only where the rule's estimate is above round-off); an orbit
without a solution raises :class:`~jetgaudin.StepTooLargeError` with its ``dt_max`` (bisection); ``substeps`` splits a
step exactly.  The steps of every map run in one compiled loop (:mod:`jetgaudin._exact_chain_loop`), each row the
unrotated orbit rotated once through its accumulated angle.  The largest feasible step is smaller than a top's when the
sites are close compared with ``R`` (the maps must then separate the sites' weights at a higher order in ``1/ρ``):
~0.1 for the Lagrange chain of the benchmark.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

from ._errors import BranchPointError, InvalidParameterError, SingularStepError, StepTooLargeError
from ._exact_chain_prep import (
    _NO_ROOTS_RHO,
    _NO_ROOTS_RHO_MODEL,
    _advance_fast,
    _branch_ok,
    _family_constants,
    _fast_plan,
    _identities,
    _integrals_row,
    _kernel_module,
    _orbit_fast,
    _orbit_roots,
    _periodic_real_parts,
    _periodic_real_parts_of_sites,
    _rules_of,
    _stacked_constants,
    _static,
    _trig_roots,
)
from ._system_maps import ExactFlow
from ._validate import real_number
from .exact import _EXACT_PROPERTIES, RHO_FACTOR, _gauss_legendre, _node_scales, nonzero_step, rotate_about_field
from .maps import Advance, Backend, Map, MapProperties, StepByAdvance, check_count, per_orbit_buffers, register_map

__all__ = ["ChainExactFlow"]


#: Newton: step tolerance (relative to |h|), largest number of iterations, residual accepted (relative to the scale
#: of the weights)
_STEP_TOL, _ITERATIONS, _RES_TOL = 1e-13, 30, 1e-11
#: the Gauss–Legendre rule of the weights and the accepted estimate ``|Q_64 − Q_32|`` (relative to the weights'
#: scale); an orbit whose rule does not converge to it falls back to the adaptive quadrature
#: (``model.interpolating_weights``, epsrel 1e-13)
_NODES, _QUAD_TOL = 64, 1e-13
#: the compiled solve's coarse rule and the step (relative to |u|) at which Newton leaves it for the 64-point rule
#: (the coarse rule only finds the start of the fine rule's Newton iterations: the solution is the fine rule's)
_COARSE_NODES, _COARSE_TOL = 16, 1e-9
#: the compiled solve's very coarse rule, which its fast path takes while Newton's steps are large
#: (``_exact_chain_kernels.newton``)
_VERY_COARSE_NODES = 8
#: the smallest ``R`` of the real-part rule: below it (one site and no branch points: the elliptic family, whose
#: branch points are not computed) ``ρ_j = λ_c ± c R`` would sit on the site, so a periodic family takes
#: :func:`_periodic_real_parts` (the Clebsch top) and any other one refuses the orbit
_R_FLOOR = 1e-6
#: the families whose basis ``ψ_m`` the compiled solve has (their ids in :mod:`jetgaudin._exact_chain_kernels`); any
#: other family solves on the NumPy route
COMPILED_FAMILIES = {"rational": 0, "trigonometric": 1, "elliptic": 2}
#: the elliptic family's branch points as ``gaudin._curve.branch_points`` gives them (none: its branch rule is the
#: numerical continuation), read-only
_NO_ROOTS = np.zeros(0, dtype=complex)
_NO_ROOTS.setflags(write=False)
#: the elliptic family's ``∂c_0/∂extra`` (``EllipticFamily.nu2_constant_gradient``: ones; its extra is ``c_0``)
_ONES = np.ones(4)


class _Weights:
    """The weights ``ω_I(ρ_j + i h_j)`` of the matched integrals ``I`` (``keep``) of one orbit ``x`` and their
    derivatives ``∂ω_I/∂h = −Re[∂ν²/∂I(η)/ν(η)]`` (the integrand at the end point), by the 64-point
    Gauss–Legendre rule on ``s ∈ [0, h]`` of ``−Re[∂ν²/∂I(ρ + is)/ν(ρ + is)]``, with the estimate
    ``|Q_64 − Q_32|``.  ``ν`` at the nodes: ``ν²`` evaluated directly (one call of ``model.nu_squared``) and its
    root continued node by node from ``+√ν²(ρ) > 0`` (the nodes sorted along the segment; each time the root
    nearer to the previous one, and no step may move ``ν`` by more than a quarter of its size, else
    :class:`~jetgaudin.BranchPointError`: a branch point near the segment).  That is the default branch of
    ``model.nu`` while no branch point is near the segment; the solve checks the end values against
    ``model.nu`` itself (:func:`_branch_ok`)."""

    def __init__(self, flow: _ChainExactFlow, x: np.ndarray, keep: np.ndarray):
        self.flow, self.x, self.keep = flow, x, keep

    def _nu(self, lam: np.ndarray) -> np.ndarray:
        """``ν`` continued along each row of ``lam`` ``(k, n)`` (points ``ρ_j + i s``, ``s`` in any order)."""
        s = lam.imag
        pts = np.concatenate([lam[:, :1].real + 0j, lam], axis=1)  # the start ρ_j first
        order = np.argsort(np.abs(np.concatenate([np.zeros((len(lam), 1)), s], axis=1)), axis=1, kind="stable")
        r = np.sqrt(np.asarray(self.flow.model.nu_squared(self.x, pts), dtype=complex))
        rs = np.take_along_axis(r, order, axis=1)
        v = np.where(rs[:, 0].real < 0, -rs[:, 0], rs[:, 0])
        out = np.empty_like(rs)
        out[:, 0] = v
        ok = np.ones(len(lam), dtype=bool)
        for q in range(1, rs.shape[1]):
            rq = np.where(np.abs(rs[:, q] - v) <= np.abs(rs[:, q] + v), rs[:, q], -rs[:, q])
            ok &= np.abs(rq - v) <= 0.25 * np.maximum(np.abs(rq), np.abs(v))
            out[:, q] = v = rq
        if not (ok.all() and np.all(np.abs(out) > 0)):
            raise BranchPointError("nu cannot be continued along an exact step's segment (a branch point near it)")
        nu = np.empty_like(out)
        np.put_along_axis(nu, order, out, axis=1)
        return nu[:, 1:]

    def __call__(self, rho: np.ndarray, h: np.ndarray, estimate: bool = False):
        """``(ω (k, n_keep), ∂ω/∂h (k, n_keep), relative quadrature estimate)`` (the estimate only with ``estimate``,
        else 0)."""
        rules = [_gauss_legendre(_NODES)] + ([_gauss_legendre(_NODES // 2)] if estimate else [])
        nodes = np.concatenate([np.concatenate([xg, [1.0]]) for xg, _ in rules])
        lam = rho[:, None] + 1j * h[:, None] * nodes
        nu = self._nu(lam)
        self.nu_end = nu[:, _NODES]
        F = self.flow._basis_values(self.x, lam.ravel(), self.keep).reshape(lam.shape + (-1,))
        f = (F / nu[..., None]).real
        n = _NODES
        om = -h[:, None] * np.einsum("q,jqi->ji", rules[0][1], f[:, :n])
        if not estimate:
            return om, -f[:, n], 0.0
        om2 = -h[:, None] * np.einsum("q,jqi->ji", rules[1][1], f[:, n + 1:-1])
        return om, -f[:, n], float(np.max(np.abs(om - om2)) / (np.abs(om).sum(axis=0).max() + 1e-300))


def _rules() -> tuple[np.ndarray, ...]:  # the compiled solve's nodes (_exact_chain_prep._rules_of of the rules above)
    return _rules_of(_NODES, _COARSE_NODES, _VERY_COARSE_NODES)


@dataclass(frozen=True, eq=False)
class _ChainExactFlow(StepByAdvance, Map):
    r"""The chain's route of :class:`jetgaudin.ExactFlow` (the route table of :mod:`jetgaudin._system_maps`): the exact
    time-``dt`` flow of a chain Hamiltonian ``H = model.hamiltonian(weights)`` (module doc), one orbit
    ``(3M,)`` or a batch (each orbit its own parameters, solved at the start of every :meth:`step` /
    :meth:`advance` call, from its integrals: constant along the orbit).

    ``substeps = s``: one step is ``s`` exact sub-steps of ``dt/s`` (an exact composition).  Between two saved rows
    the ``k s`` steps of each map run in one call of the map's own route (its compiled kernel where it has one:
    the maps commute), and every row is the unrotated map orbit rotated once through its accumulated angle: the
    rotation's round-off does not accumulate (``docs/integrators.md`` §7).  Each orbit is stepped on its own, so a
    batch member equals its single run bit for bit, and an orbit without parameters raises
    :class:`~jetgaudin.StepTooLargeError` naming it and its ``dt_max`` (:meth:`max_dt`).

    ``backend`` (alias ``kernel``, the maps' rule): ``"auto"`` (default) the compiled solve and loop where the family
    has them (:data:`COMPILED_FAMILIES`; an elliptic modulus below 1e-3 solves on NumPy), ``"compiled"`` those
    (:class:`~jetgaudin.InvalidParameterError` for a family without), ``"numpy"`` the NumPy solve and the maps' NumPy
    route (the reference; the same parameters to ~1e-15)."""

    H: Any  # a jetgaudin.ChainHamiltonian
    dt: float
    rho_factor: float = RHO_FACTOR
    substeps: int = 1
    properties: MapProperties = field(default=_EXACT_PROPERTIES, init=False, repr=False)
    backend: Any = "auto"
    kernel: Any = None  # the alias of backend (None once parsed into backend)
    chunk_invariant: ClassVar[bool] = False
    public_name: ClassVar[str] = "ExactFlow"  # the class its messages name (jetgaudin.maps.map_name)
    #: ``(X0 (B, 3M), [(η, θ, ν) per orbit])`` of :meth:`bind_run` (set on the bound copy only)
    _bound: ClassVar[Any] = None

    def __post_init__(self) -> None:
        model = getattr(self.H, "model", None)
        if model is None or not callable(getattr(model, "two_point_backlund", None)) or np.ndim(self.H.weights) != 1:
            raise InvalidParameterError("H must be a chain Hamiltonian model.hamiltonian(weights) with one set of "
                                        "weights (shape (2M,))")
        if getattr(model, "constants", None) is not None:  # issue 33: conjugated by the route table (methods.py)
            raise InvalidParameterError("ChainExactFlow: this model's sites carry jet constants; use jg.solve(H, X0, "
                                        "t_span, dt=..., method='exact') (the reduced model's flow conjugated by T)")
        object.__setattr__(self, "dt", nonzero_step(self.dt))
        rf = real_number(self.rho_factor, "rho_factor")
        if rf <= 1:
            raise InvalidParameterError(f"rho_factor must be > 1, got {rf}")
        object.__setattr__(self, "rho_factor", rf)
        object.__setattr__(self, "substeps", check_count(self.substeps, "substeps", 1))
        backend = Backend.parse(self.backend if self.kernel is None else self.kernel)
        if backend is Backend.GPU:
            raise InvalidParameterError("ChainExactFlow has no GPU route: give backend='auto', 'compiled' or 'numpy'")
        if backend is Backend.COMPILED and (COMPILED_FAMILIES.get(model.family.name) is None or (
                model.family.name == "elliptic" and not float(model.family.modulus) >= 1e-3)):
            raise InvalidParameterError(f"the {model.family.name} family has no compiled exact-step solve here "
                                        "(elliptic: modulus >= 1e-3): give backend='numpy' or 'auto'")
        object.__setattr__(self, "backend", backend)
        object.__setattr__(self, "kernel", None)

    @property
    def model(self):
        return self.H.model

    @property
    def has_compiled(self) -> bool:  # type: ignore[override]
        """Whether the compiled route exists: the family's compiled solve (:data:`COMPILED_FAMILIES`; elliptic:
        modulus ``≥ 1e-3``), with the compiled loop of the maps (without this property the run layer recorded the
        NumPy route for every ``AUTO`` run: ``jetgaudin orbit --sites … --dt`` ran the Clebsch top at ~160 steps/s,
        the compiled route at ~2·10⁴ with the run layer's chunks)."""
        fam = self.model.family
        return COMPILED_FAMILIES.get(fam.name) is not None and not (
            fam.name == "elliptic" and not float(fam.modulus) >= 1e-3)

    def route_costs(self, X: Any, steps: Any):
        """The estimated seconds of a run of ``steps`` steps of the states ``X`` on each route
        (``jetgaudin.gaudin._backend.exact_route_costs``: the parameters solved once, :meth:`bind_run`; the compiled
        route's compile or load included)."""
        from .gaudin._backend import exact_route_costs

        keep, E, _ = self._design
        shape = np.shape(X)
        return exact_route_costs(self.model.family, self.model.M, int(np.prod(shape[:-1])) if shape else 1,
                                 0 if steps is None else int(steps), int(keep.sum()) - int(E.shape[1]), self.substeps)

    def _auto_backend(self, X: Any, steps: Any) -> Backend:
        """``AUTO`` as the run layer resolves it (``Map.resolved_backend``, recorded before the first call): the route
        of the smaller estimated time (:meth:`route_costs`; estimates within √3 of the true times never pick a route
        3× slower).  The library's own :meth:`advance` of an ``AUTO`` flow takes the compiled route."""
        cost = self.route_costs(X, steps)
        return Backend.COMPILED if cost.compiled <= cost.numpy else Backend.NUMPY

    def prepare_kernels(self, X: Any = None, steps: Any = None, notify: Any = None):
        """Compile (or load) the kernels of the compiled route visibly before a run of ``steps`` steps from ``X`` that
        takes it (:meth:`resolved_backend`): a message with the expected time first and one when done where they
        must be compiled, quietly and timed where Numba's cache holds them, nothing where they are loaded or the
        NumPy route is taken (the run layer calls it before its loop, so that the rate excludes the compile).  The
        compile is one call of the flow on the first state (solve and one step: the kernels of the route).  Returns
        a ``CompileReport`` or ``None``."""
        from .backlund.kernels._select import prepare_call
        from .gaudin._backend import _EXACT_KERNELS, EXACT_COMPILE_S, _module_state

        if X is None:  # no state: nothing to solve the parameters on (the compile is one call of the flow)
            return None
        if not np.size(X) or self.resolved_backend(X, 10**6 if steps is None else steps) is not Backend.COMPILED:
            return None
        name = self.model.family.name
        need = _EXACT_KERNELS.get(name, _EXACT_KERNELS["elliptic"])
        state = _module_state(need)
        x0 = np.reshape(np.asarray(X, dtype=float), (-1, np.shape(X)[-1]))[0].copy()
        flow = self if self.backend is Backend.COMPILED else dataclasses.replace(self, backend=Backend.COMPILED)

        def call() -> None:
            try:
                flow.advance(x0, None, 1, 1)
            except StepTooLargeError:  # the run itself reports it (with its dt_max) at its first call
                pass

        return prepare_call(tuple(f"{m.rsplit('.', 1)[-1]}.{f}" for m, f in need), state == "loaded",
                            EXACT_COMPILE_S.get(name, EXACT_COMPILE_S["elliptic"]), call, notify, state == "cached")

    def route_notice(self, X: Any, steps: Any) -> str | None:
        """One line naming the route ``AUTO`` takes where it matters (the NumPy route, with both estimates;
        ``jetgaudin.gaudin._backend.auto_notice``), else ``None``."""
        from .gaudin._backend import auto_notice

        return auto_notice(self, X, steps)

    @property
    def n_state(self) -> int:
        return int(self.model.n_state)

    @property
    def time_step(self) -> float:
        return self.dt

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.model.integrals(X), dtype=float)

    @cached_property
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

    def _real_parts(self, x: np.ndarray, k: int, bp: np.ndarray | None = None) -> np.ndarray | None:
        """``ρ_1..ρ_k`` (module doc); ``None`` where no rule applies (one site, no branch points, no period).
        ``bp``: the orbit's branch points when the caller has them (``model.branch_points(x)``)."""
        model = self.model
        bp = np.ravel(model.branch_points(x) if bp is None else bp)
        if not bp.size:  # no computed branch points (elliptic): the same real parts for every orbit of the model
            per_k = _NO_ROOTS_RHO.get(self)
            if per_k is None:  # a new flow: the model's (jg.solve builds a flow at every call)
                per_k = _NO_ROOTS_RHO[self] = _NO_ROOTS_RHO_MODEL.setdefault(self.model, {})
            if (k, self.rho_factor) not in per_k:
                per_k[k, self.rho_factor] = self._real_parts_of(k, bp)
            rho = per_k[k, self.rho_factor]
            return None if rho is None else rho.copy()
        return self._real_parts_of(k, bp)

    def _real_parts_of(self, k: int, bp: np.ndarray) -> np.ndarray | None:
        """:meth:`_real_parts` from the orbit's branch points ``bp`` (1-D)."""
        model = self.model
        lc = float(np.mean(model.positions))
        R = max(float(np.max(np.abs(bp - lc))) if bp.size else 0.0, float(np.max(np.abs(model.positions - lc))),
                _R_FLOOR)
        P = model.family.period
        rho = lc + self.rho_factor * R / _node_scales(k)
        if P is not None and (R <= _R_FLOOR or np.max(np.abs(rho[:, None] - model.positions[None, :])) >= P / 2):
            pts = np.concatenate([bp, model.positions.astype(complex)])
            if not bp.size:  # no computed branch points (elliptic): the same real parts for every orbit of the model
                return _periodic_real_parts_of_sites(lc, P, k, tuple(pts.real)).copy()
            return _periodic_real_parts(lc, P, k, pts)
        return None if R <= _R_FLOOR else rho

    def _solve(self, x: np.ndarray, dt: float, compiled: bool | None = None
               ) -> tuple[np.ndarray, float, np.ndarray] | None:
        """``(η_1..η_k, θ)`` of the exact time-``dt`` step on the orbit ``x``, or ``None`` (no accepted solution:
        Newton's method diverges, leaves the monotone branch, meets a branch point or a period's edge); the third
        entry is ``ν(η_j)`` on the maps' branch (checked against ``model.nu``), the maps' first ``ν1``."""
        try:
            return self._newton(x, dt, compiled)
        except (BranchPointError, InvalidParameterError, np.linalg.LinAlgError):
            return None

    def _newton(self, x: np.ndarray, dt: float, compiled: bool | None = None
                ) -> tuple[np.ndarray, float, np.ndarray] | None:
        """The solve of :meth:`_solve`: Newton's method by the compiled route (:mod:`jetgaudin._exact_chain_kernels`,
        the families of its ``COMPILED_FAMILIES``) or the NumPy route (:meth:`_newton_numpy`; ``compiled=False``
        forces it: the tests compare the two), then the acceptance (quadrature estimate, residual, branch)."""
        model = self.model
        keep, E, rate, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(self)
        target = dt * wkeep
        fam = model.family
        fid = COMPILED_FAMILIES.get(fam.name)
        if fid == 2 and not float(fam.modulus) >= 1e-3:  # the AGM of 1 − m = 1 − k² → 1: NumPy (SciPy)
            fid = None
        if compiled is None:
            compiled = fid is not None and self.backend is not Backend.NUMPY
        if compiled and fid is None:
            raise InvalidParameterError(f"the {fam.name} family has no compiled exact-step solve")
        if compiled:
            I = _integrals_row(self, x)  # once (compiled forms): the roots, the solve's ν², the branch check
            extra = I[2 * model.M:]
            const = float(np.real(fam.nu2_constant(float(model.b), extra)))
            hI = np.ascontiguousarray(I[:2 * model.M])
        # once per orbit: the real parts and the branch check
        if compiled and fid == 1:
            raw, bp = _trig_roots(model, hI, const, pos, orders)
        elif compiled and fid == 2:  # no computed branch points (gaudin._curve.branch_points: the numerical rule)
            raw = bp = _NO_ROOTS
        else:
            raw, bp = _orbit_roots(model, x)
        rho = self._real_parts(x, k, bp)
        if rho is None:
            return None
        # the monotone branch of ω(h) (the fold is at h ~ ρ − λ_c); an elliptic segment stays below 0.9 K' (at K' the
        # points η, η̄ coincide modulo the period 2iK')
        bound = np.minimum(2 * np.abs(rho - lc) + (P or 0.0), 0.9 * Kp)
        if compiled and fid == 2:  # the whole solve in one call (Newton, residual, branch check)
            u = np.empty(E.shape[0])
            om = np.empty((k, E.shape[0]))
            nu_end = np.empty(k, dtype=complex)
            status, quad = _kernel_module("jetgaudin._exact_chain_kernels").solve_numerical(
                2, _family_constants(fam), pos, orders, hI, const, _ONES[:len(extra)], kidx, E, target, rho, bound,
                *_rules(), _STEP_TOL, _COARSE_TOL, _ITERATIONS, u, om, nu_end, _QUAD_TOL, _RES_TOL, float(P), 64,
                2**16, 1e-8)
            if status == 1:
                return None
            if status == 0:
                return rho + 1j * u[:k], 0.0, nu_end  # elliptic: no rotation (rate 0)
            sol = (u, om, quad, nu_end)  # the rule's estimate above _QUAD_TOL: the adaptive quadrature below
        elif compiled:
            sol = self._newton_compiled(x, int(fid), keep, E, target, rho, bound,  # type: ignore[arg-type]
                                        (hI, const, extra, kidx, pos, orders))
        else:
            sol = self._newton_numpy(x, keep, E, target, rho, bound)
        if sol is None:
            return None
        u, om, quad, nu_end = sol
        if quad > _QUAD_TOL:  # the rule has not converged on some segment: the adaptive quadrature
            om = np.array([model.interpolating_weights(x, e) for e in rho + 1j * u[:k]])[:, keep]
        Eu = E @ u[k:]
        scale = np.abs(om).sum(axis=0) + np.abs(target) + np.abs(Eu)
        eta = rho + 1j * u[:k]
        if np.max(np.abs(om.sum(axis=0) - Eu - target) / scale) > _RES_TOL:
            return None
        if compiled and fam.uniformizer(0.0) is None:  # the numerical branch rule, compiled
            ok = self._branch_numerical(x, eta, nu_end, (hI, const, pos, orders))
        elif compiled and fid == 1:  # the trigonometric family's uniformized rule, compiled (the same raw roots)
            K: Any = _kernel_module("jetgaudin._exact_chain_kernels")
            ok = bool(K.branch_uniformized(1, _family_constants(fam), pos, orders, hI, const, float(P),
                                           np.ascontiguousarray(eta, dtype=complex),
                                           np.ascontiguousarray(nu_end, dtype=complex),
                                           np.ascontiguousarray(np.ravel(raw), dtype=complex), 1e-8))
        else:
            ok = _branch_ok(model, x, eta, nu_end, raw)
        return (eta, -rate * u[k] if rate else 0.0, nu_end) if ok else None

    def _branch_numerical(self, x: np.ndarray, eta: np.ndarray, nu_end: np.ndarray, pre: tuple | None = None
                          ) -> bool:
        """:func:`_branch_ok` for a family without a uniformizer (elliptic), by the compiled twin of its branch rule
        (``gaudin._curve._nu_numerical``: ``ν`` continued over equally spaced points of ``[Re η_j, η_j]``), every
        segment in one call; ``pre``: ``(h_I, ν²'s constant, positions, orders)`` where the caller has them."""
        model = self.model
        fam = model.family
        K: Any = _kernel_module("jetgaudin._exact_chain_kernels")
        if pre is None:
            I = np.asarray(model.integrals(x), dtype=float)
            pre = (np.ascontiguousarray(I[:2 * model.M]), float(np.real(fam.nu2_constant(float(model.b),
                                                                                          I[2 * model.M:]))),
                   model.positions.astype(float), np.array(model.orders, dtype=np.int64))
        hI, const, pos, orders = pre
        return bool(K.branch_numerical(COMPILED_FAMILIES[fam.name], _family_constants(fam), pos, orders, hI, const,
                                       float(fam.period or np.inf), np.ascontiguousarray(eta, dtype=complex),
                                       np.ascontiguousarray(nu_end, dtype=complex), 64, 2**16, 1e-8))

    def _newton_compiled(self, x, fid: int, keep, E, target, rho, bound, pre: tuple | None = None):
        """:meth:`_newton_numpy` in one compiled call: ``(u, ω (k, n_keep), quadrature estimate, ν(η_j))`` or
        ``None``; ``pre``: ``(h_I, ν²'s constant, extra integrals, kidx, positions, orders)`` where the caller has
        them."""
        model = self.model
        fam = model.family
        if pre is None:
            I = np.asarray(model.integrals(x), dtype=float)
            pre = (np.ascontiguousarray(I[:2 * model.M]), float(np.real(fam.nu2_constant(float(model.b),
                                                                                          I[2 * model.M:]))),
                   I[2 * model.M:], np.flatnonzero(keep).astype(np.int64), model.positions.astype(float),
                   np.array(model.orders, dtype=np.int64))
        hI, const, extra, kidx, pos, orders = pre
        dconst = np.ascontiguousarray(fam.nu2_constant_gradient(float(model.b), extra), dtype=float)
        k = len(rho)
        u = np.empty(E.shape[0])
        om = np.empty((k, E.shape[0]))
        nu_end = np.empty(k, dtype=complex)
        K: Any = _kernel_module("jetgaudin._exact_chain_kernels")  # Numba (imported on first use)
        status, quad, _ = K.newton(fid, _family_constants(fam), pos, orders, hI, const, dconst, kidx,
                                   np.ascontiguousarray(E, dtype=float), np.ascontiguousarray(target),
                                   np.ascontiguousarray(rho, dtype=float), np.ascontiguousarray(bound, dtype=float),
                                   *_rules(), _STEP_TOL, _COARSE_TOL, _ITERATIONS, u, om, nu_end)
        return None if status else (u, om, quad, nu_end)

    def _newton_numpy(self, x, keep, E, target, rho, bound):
        """Newton's method on the NumPy route (:class:`_Weights`): ``(u, ω (k, n_keep), quadrature estimate,
        ν(η_j))`` or ``None``."""
        model = self.model
        k = len(rho)
        weights = _Weights(self, x, keep)

        def jac(dom):
            return np.concatenate([dom.T, -E], axis=1)

        nus = np.asarray(model.nu(x, rho.astype(complex))).real
        J0 = jac(-(self._basis_values(x, rho.astype(complex), keep) / nus[:, None]).real)
        if not np.all(np.isfinite(J0)) or np.linalg.cond(J0) > 1e12:
            return None
        u = np.linalg.solve(J0, target)
        for _ in range(_ITERATIONS):
            if np.any(np.abs(u[:k]) > bound) or not np.all(np.isfinite(u)):
                return None
            om, dom, _ = weights(rho, u[:k])
            J = jac(dom)
            if not (np.all(np.isfinite(J)) and np.all(np.isfinite(om))) or np.linalg.cond(J) > 1e12:
                return None
            du = np.linalg.solve(J, om.sum(axis=0) - E @ u[k:] - target)
            u = u - du
            if np.any(np.abs(u[:k]) > bound) or not np.all(np.isfinite(u)):
                return None
            if np.all(np.abs(du) <= _STEP_TOL * np.abs(u)):
                om, _, quad = weights(rho, u[:k], estimate=True)
                return u, om, quad, weights.nu_end
        return None

    def parameters(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """``(η_1..η_k, θ)`` of one sub-step (``dt/substeps``) for the orbit ``x`` ``(3M,)``: the maps and the
        rotation angle; :class:`~jetgaudin.StepTooLargeError` (with ``dt_max``) where Newton's method finds none."""
        eta, theta, _ = self._parameters(x)
        return eta, theta

    def _parameters(self, x: np.ndarray, checked: bool = False) -> tuple[np.ndarray, float, np.ndarray]:
        """:meth:`parameters` and the maps' first ``ν1``; ``checked``: ``x`` is one orbit already checked by
        ``model.check_state`` as floats (:meth:`advance`'s)."""
        if not checked:
            x = np.asarray(self.model.check_state(x), dtype=float)
        if x.ndim != 1:
            raise InvalidParameterError(f"parameters take one orbit (shape ({self.n_state},)), got {x.shape}")
        dt = self.dt / self.substeps
        sol = self._solve(x, dt)
        if sol is None:
            dmax = self._largest_dt(x, dt)
            if dmax == 0.0:
                raise StepTooLargeError(
                    f"dt = {dt:g}: no well-conditioned chain Bäcklund parameters give the exact time-dt step on this "
                    "orbit at any step size (no real parts off the sites and branch points); give a smaller dt or "
                    "use method='dop853'", dt_max=0.0)
            raise StepTooLargeError(
                f"dt = {dt:g} is too large for this orbit's leaf: no well-conditioned chain Bäcklund parameters give "
                f"the exact time-dt step; the largest feasible time step is dt = {dmax:.4g}: give a smaller dt "
                f"(|dt| <= {abs(dmax):.4g}) or substeps >= "
                f"{math.ceil(abs(self.dt) / abs(dmax) * 1.01)}", dt_max=dmax)
        return sol

    def _largest_dt(self, x: np.ndarray, dt: float, rel: float = 1e-3) -> float:
        """The largest ``|dt'| ≤ |dt|`` (sign of ``dt``) solvable on the orbit ``x``, by bisection to ``rel``
        (0 when even ``|dt| · 1e-6`` fails)."""
        if self._solve(x, dt * 1e-6) is None:
            return 0.0
        lo, hi = abs(dt) * 1e-6, abs(dt)
        while hi - lo > rel * hi:
            mid = 0.5 * (lo + hi)
            if self._solve(x, math.copysign(mid, dt)) is not None:
                lo = mid
            else:
                hi = mid
        return math.copysign(lo, dt)

    def max_dt(self, X) -> np.ndarray:
        """The largest feasible ``|dt|`` of one sub-step for each orbit of ``X`` ``(..., 3M)`` (bisection to 1e-3,
        searched up to ``10 |dt|``), so one step of this map is feasible iff ``|dt|/substeps`` is below it."""
        X = np.asarray(self.model.check_state(X), dtype=float)
        flat = X.reshape(-1, X.shape[-1])
        return np.array([abs(self._largest_dt(x, 10 * self.dt)) for x in flat]).reshape(X.shape[:-1])

    def _orbit(self, x: np.ndarray, steps: int, save_every: int, rows: np.ndarray,
               params: tuple | None = None) -> np.ndarray:
        """``steps`` steps of one orbit ``x``: the saved rows into ``rows`` ``(steps // save_every, 3M)``; returns
        the last state.  The maps run unrotated (they commute with the rotation), and each row is rotated once
        through its accumulated angle ``n s θ``: no rotation's round-off carries over to the next row.  Maps with
        a compiled kernel (every family's): every step in one compiled loop (:mod:`jetgaudin._exact_chain_loop`),
        each map's ``ν1`` the solve's ``ν(η_j)`` (checked against ``model.nu``) and then continued; else ``k s``
        steps of each map per call of its NumPy route (the maps commute).  ``params``: the orbit's ``(η, θ, ν)``
        (:meth:`bind_run`), else solved here."""
        if params is None:
            fast = _orbit_fast(self, x, steps, save_every, self._fast())  # the elliptic fast path (same bits)
            if fast is not None:
                rows[...] = fast[0]
                return fast[1]
            eta, theta, nu = self._parameters(x, checked=True)  # advance checked X (per_orbit_buffers)
        else:
            eta, theta, nu = params
        s = self.substeps
        # |Im η| at round-off: weights ~1e-17, the map is the identity (left out)
        used = [j for j, e in enumerate(eta) if abs(e.imag) > 1e-13 * max(abs(e.real), 1.0)]
        model = self.model
        fam = model.family
        if (used and self.backend is not Backend.NUMPY and (fam.uniform or fam.kernel_rule is not None)
                and model.algebra == "su(2)"):
            # the maps' compiled route (ChainTwoPointBacklund.has_compiled) without building the maps: the same
            # checks of η (gaudin.maps._check_eta; the models the maps take: su(2), no jet constants, which the
            # constructor refuses) and the same kernel constants (per (model, η), cached)
            from .gaudin.maps import _check_eta

            return self._orbit_compiled(x, [_check_eta(model, eta[j]) for j in used], nu[used], theta, steps,
                                        save_every, rows)
        maps = [self.model.two_point_backlund(eta[j]) for j in used]
        if self.backend is Backend.NUMPY:
            maps = [mp.with_backend(Backend.NUMPY) for mp in maps]
        elif maps and all(mp.has_compiled for mp in maps):
            return self._orbit_compiled(x, [mp.eta for mp in maps], nu[used], theta, steps, save_every, rows)
        z, done = x, 0
        while done < steps:
            n = min(save_every - done % save_every, steps - done)
            for mp in maps:
                z = mp.advance(z, None, n * s, n * s).X
            done += n
            if done % save_every == 0:
                rows[done // save_every - 1] = rotate_about_field(z, (done * s) * theta)
        return rotate_about_field(z, (steps * s) * theta)

    def _orbit_compiled(self, x: np.ndarray, etas: list, nu: np.ndarray, theta: float, steps: int, save_every: int,
                        rows: np.ndarray) -> np.ndarray:
        """The compiled loop of :meth:`_orbit` for the maps ``etas`` (their kernel constants stacked, cached per
        ``(model, η…)``)."""
        L: Any = _kernel_module("jetgaudin._exact_chain_loop")  # Numba dispatchers (untyped for mypy)

        x = np.ascontiguousarray(x, dtype=float)
        nu = np.array(nu, dtype=complex)  # the solve's ν(η_j) on the maps' branch (the kernels continue from it)
        consts = _stacked_constants(self, tuple(complex(e) for e in etas))
        out = np.empty((steps // save_every, x.size))
        final = np.empty(x.size)
        tail = (float(theta), steps, save_every, self.substeps, out, final)
        if len(consts) == 5:
            L.rows_rational(x, float(self.model.b), np.array(etas, dtype=complex), nu, *consts, *tail)
        else:
            L.rows_family(x, float(self.model.b), nu, *consts, *tail)
        if not _kernel_module("jetgaudin._exact_chain_kernels").all_finite(out, final):
            raise SingularStepError("the compiled exact chain step produced non-finite values; give a smaller dt")
        rows[...] = out
        return final

    def bind_run(self, X0) -> _ChainExactFlow:
        """This flow with each orbit's parameters ``(η_j, θ, ν(η_j))`` solved once, at the run's initial states ``X0``
        ``(3M,)`` or ``(B, 3M)`` (the run layer's :func:`jetgaudin.run.spec.run_map`): its :meth:`advance` of the
        run's orbits, in order, uses them instead of solving at every call (they are functions of the integrals,
        constant along each orbit; solving them again at every chunk of the run moved them by round-off and paid
        the maps' 40-digit constants, ~5–10 ms, at every chunk: the Clebsch top's ``orbit --dt`` ran at ~2·10⁴
        steps/s).  Only for the run's own orbits: a batch of ``b ≤ B`` orbits is taken as the run's first ``b`` (the
        driver's reference step), so a flow bound here must not be given other states.  The same flow when already
        bound at these ``X0``; raises what :meth:`parameters` raises (``orbit i:`` named in a batch)."""
        X0 = np.asarray(self.model.check_state(X0), dtype=float)
        flat = np.ascontiguousarray(X0.reshape(-1, X0.shape[-1]))
        if self._bound is not None and np.array_equal(self._bound[0], flat):
            return self
        params = []
        for i, x in enumerate(flat):
            try:
                params.append(self._parameters(np.ascontiguousarray(x), checked=True))
            except StepTooLargeError as exc:
                raise StepTooLargeError(f"orbit {i}: {exc}" if len(flat) > 1 else str(exc),
                                        dt_max=exc.dt_max) from None
        bound = copy.copy(self)
        object.__setattr__(bound, "_bound", (flat.copy(), params))
        return bound

    def unbound(self) -> _ChainExactFlow:
        """This flow solving the parameters at the start of every :meth:`advance` call (the run layer's way before
        :meth:`bind_run`; a run directory written that way is resumed that way: :mod:`jetgaudin.run.replay`)."""
        if self._bound is None:
            return self
        out = copy.copy(self)
        object.__setattr__(out, "_bound", None)
        return out

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """``steps`` exact steps from ``X`` ``(..., 3M)`` (parameters solved at ``X``, per orbit, or those of
        :meth:`bind_run`), rows every ``save_every`` (class doc)."""
        bound = self._bound
        if bound is None:
            fast = _advance_fast(self, self._fast(), X, steps, save_every)  # one orbit, elliptic: the fast path
            if fast is not None:
                return fast
        steps, save_every, X, flat, rows, final = per_orbit_buffers(self.model, X, steps, save_every)
        params = bound[1] if bound is not None and len(flat) <= len(bound[1]) else None
        if steps:
            for i, x in enumerate(flat):
                try:
                    final[i] = self._orbit(x, steps, save_every, rows[:, i], None if params is None else params[i])
                except StepTooLargeError as exc:
                    raise StepTooLargeError(f"orbit {i}: {exc}", dt_max=exc.dt_max) from None
        zeros = np.zeros(X.shape[:-1])
        return Advance(rows=rows.reshape((-1,) + X.shape), X=final.reshape(X.shape), carry=zeros.astype(complex),
                       imag_max=zeros)

    def _fast(self) -> tuple | None:  # the plan of the elliptic family's fast path (_exact_chain_prep._fast_plan)
        return _fast_plan(self, (_STEP_TOL, _COARSE_TOL, _ITERATIONS), (_QUAD_TOL, _RES_TOL), _rules())

    def inverse(self) -> _ChainExactFlow:
        return _ChainExactFlow(self.H, -self.dt, self.rho_factor, self.substeps, backend=self.backend)

    def describe(self) -> dict:
        return {"kind": "chain_exact", **self.model.describe(), "weights": np.asarray(self.H.weights).tolist(),
                "dt": self.dt, "rho_factor": self.rho_factor, "substeps": self.substeps, "backend": str(self.backend)}


#: the old name of :class:`jetgaudin.ExactFlow` for chains: the same class (``isinstance`` holds both ways)
ChainExactFlow = ExactFlow


def _chain_exact_from(d: dict) -> ExactFlow:
    from .gaudin import GaudinModel

    model = GaudinModel.from_description(d)
    return ExactFlow(model.hamiltonian(np.asarray(d["weights"], dtype=float)), float(d["dt"]),
                     rho_factor=float(d.get("rho_factor", RHO_FACTOR)), substeps=int(d.get("substeps", 1)),
                     backend=d.get("backend", "auto"))


register_map("chain_exact", _chain_exact_from)
