"""Python-side constants of :class:`jetgaudin.ChainExactFlow`'s compiled solve (private): the family constants of the
compiled basis (per family parameter), the model-only constants of a flow (per flow, weak keys: nothing outlives its
flow), the trigonometric branch points from the compiled polynomial, the real parts of a periodic family's
parameters and the linear identities among the matched integrals; and the elliptic family's fast path of
``advance`` (:func:`_fast_plan`, :func:`_orbit_fast`: one orbit in two compiled calls, every constant of the calls
cached per flow and per model, the same bits as the general path, which makes every refusal).  Split from
:mod:`jetgaudin.exact_chain` (its size); Numba is imported on first use only."""

from __future__ import annotations

import importlib
import math
import weakref
from functools import lru_cache
from typing import Any

import numpy as np

from ._errors import BranchPointError

__all__: list[str] = []


def _family_constants(fam) -> np.ndarray:
    """The constants of the compiled basis: trigonometric ``(γ,)``, elliptic ``_exact_elliptic.elliptic_constants``
    (read-only, computed once per family parameter)."""
    return _family_constants_of(fam.name, float(fam.modulus) if fam.name == "elliptic"
                                else float(getattr(fam, "gamma", 0.0)))


@lru_cache(maxsize=64)
def _family_constants_of(name: str, param: float) -> np.ndarray:
    if name == "elliptic":
        from ._exact_elliptic import elliptic_constants

        out = elliptic_constants(param)
    else:
        out = np.array([param])
    out.setflags(write=False)
    return out


#: per flow and per model (the flows of one model share one dictionary), by ``(k, rho_factor)``, the real parts of a
#: model without computed branch points (:meth:`ChainExactFlow._real_parts`)
_NO_ROOTS_RHO: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_NO_ROOTS_RHO_MODEL: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: per flow, the compiled solve's constants that depend on the model and weights only (:func:`_static`)
_STATIC: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


#: per model (weak keys), the model-only part of :func:`_static` (``jg.solve`` builds a new flow at every call: the
#: linear identities alone, an SVD of the integrals at random states, took ~0.4 ms of a Clebsch top's call)
_MODEL_STATIC: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _static(flow) -> tuple:
    """``(keep, E, rate, k, weights_keep, kidx, positions, orders, λ_c, P, K')`` of a flow (cached per flow: the
    Python around the compiled solve was ~1/3 of a Clebsch top's solve; all but the weights per model too; shared:
    the callers only read them — not flagged read-only, which would give the kernels another Numba signature)."""
    out = _STATIC.get(flow)
    if out is None:
        model = flow.model
        part = _MODEL_STATIC.get(model)
        if part is None:
            keep, E, rate = flow._design
            part = (keep, np.ascontiguousarray(E, dtype=float), rate, int(keep.sum()) - E.shape[1],
                    np.flatnonzero(keep).astype(np.int64), np.ascontiguousarray(model.positions, dtype=float),
                    np.array(model.orders, dtype=np.int64), float(np.mean(model.positions)), model.family.period,
                    getattr(model.family, "Kp", np.inf))
            _MODEL_STATIC[model] = part
        keep, E, rate, k = part[:4]
        out = (keep, E, rate, k, np.asarray(flow.H.weights, dtype=float)[keep]) + part[4:]
        _STATIC[flow] = out
    return out


#: per flow, the quadratic forms of its model's integrals for the compiled pass (:func:`_integrals_row`)
_FORMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _forms(flow) -> tuple | None:
    """``(q, lin, b, forms, number of integrals)``: the quadratic forms of the flow's model for the compiled pass of
    :mod:`jetgaudin.gaudin._record` (cached per flow), ``None`` for a field per site (not a scalar ``b``)."""
    f = _FORMS.get(flow)
    model = flow.model
    if f is None and np.ndim(model.b) == 0:
        q, lin = model._forms
        lin = np.ascontiguousarray(lin, dtype=float)
        forms = np.ascontiguousarray(np.asarray(model.family.extra_integrals(model.sites)[1], dtype=float)
                                     .reshape(-1, model.n_state))
        f = (np.ascontiguousarray(q, dtype=float), lin, float(model.b), forms,
             (q.shape[0] if q.ndim == 3 else q.shape[1]) + forms.shape[0])
        _FORMS[flow] = f
    return f


def _integrals_row(flow, x: np.ndarray) -> np.ndarray:
    """``model.integrals(x)`` of one orbit ``x`` (3M,) by the compiled pass of :mod:`jetgaudin.gaudin._record` (the
    model's quadratic forms, cached per flow: ~1 µs against ~16 µs of NumPy for the Clebsch top; equal to
    ``model.integrals`` to ``n ε Σ|terms|``, not bit for bit); ``model.integrals`` itself where the pass is not finite
    (which refuses an overflow)."""
    model = flow.model
    f = _forms(flow)
    if f is None:  # a field per site (not a scalar b): NumPy
        return np.asarray(model.integrals(x), dtype=float)
    q, lin, b, forms, n = f
    from .gaudin._record import chain_integrals, chain_integrals_gram

    out = np.empty((1, n))
    X = np.ascontiguousarray(x, dtype=float).reshape(1, -1)
    if q.ndim == 3:  # the rational forms (one q for the three components)
        chain_integrals_gram(X, q, lin, b, out)
    else:
        chain_integrals(X, q, lin, b, forms, out)
    if not np.isfinite(out).all():
        return np.asarray(model.integrals(x), dtype=float)
    return out[0]


def _trig_roots(model, hI: np.ndarray, const: float, pos: np.ndarray, orders: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """``_orbit_roots`` for the trigonometric family with the polynomial compiled
    (:func:`jetgaudin._exact_chain_kernels.trig_polynomial`, ``ν²`` from the expansion: the roots equal
    ``gaudin._curve.branch_points``' to round-off), the roots by the same companion matrix."""
    from .spectral import _roots

    K: Any = importlib.import_module("jetgaudin._exact_chain_kernels")
    coef = np.empty(hI.size + 1, dtype=complex)
    K.trig_polynomial(_family_constants(model.family), pos, orders, hI, const, coef)
    Q = coef[::-1]
    if abs(Q[0]) <= 1e-13 * np.max(np.abs(Q)):
        raise BranchPointError(
            "nu^2 vanishes at Im(lambda) -> -infinity (b + i gamma J = 0: b = 0 and J = sum of the y_0^3 = 0); the "
            "branch rule of nu needs b != 0 or J != 0")
    raw = _roots(Q)
    return raw, model.family.uniformizer_inverse(raw)


#: the offset of the real parts' grid, in grid cells (the golden ratio's fraction: no grid point is a dyadic
#: fraction of the period)
_GRID_OFFSET = (math.sqrt(5.0) - 1.0) / 2.0


def _periodic_real_parts(lc: float, P: float, k: int, points: np.ndarray) -> np.ndarray:
    """``k`` real parts in one period ``[lc, lc + P)`` (a periodic family): greedily the points of a 256-point grid
    farthest from every site and branch point (``points``, with their images at ``± P``), at least ``P/(4k)`` apart
    from each other (the rational rule ``λ_c + cR/t_j`` could wrap onto a site).  The grid is offset by
    :data:`_GRID_OFFSET` of a cell: on the grid ``lc + P j/256`` the point farthest from one site was the half
    period (the Clebsch top: ``Re η = K`` exactly), a point of symmetry of the elliptic functions where some quantity
    of the map's step has the same exact value at every step and rounds alike each time: the Casimir ``h_{1,3}``
    drifted linearly (per-step bias z = −15 over 4·10⁴ steps of the map at ``Re η = K``, none at ``K(1 + 1e-9)``;
    drift exponent 0.97 over 2·10⁵ steps of the exact flow)."""
    grid = lc + P * (np.arange(256) + _GRID_OFFSET) / 256
    imgs = np.concatenate([points - P, points, points + P])
    score = np.min(np.abs(grid[:, None] - imgs[None, :]), axis=1)
    order = np.argsort(-score, kind="stable")
    free = np.ones(len(grid), dtype=bool)  # at least P/(4k) from every chosen point (the same test, vectorised)
    chosen: list[float] = []
    while len(chosen) < k and free.any():
        c = grid[order[np.argmax(free[order])]]  # the best-scored free point
        chosen.append(float(c))
        d = np.abs(grid - c)
        free &= np.minimum(d, P - d) >= P / (4 * k)
    return np.array(sorted(chosen))


@lru_cache(maxsize=64)
def _periodic_real_parts_of_sites(lc: float, P: float, k: int, sites: tuple[float, ...]) -> np.ndarray:
    """:func:`_periodic_real_parts` for points that are the sites only (a read-only array, cached)."""
    out = _periodic_real_parts(lc, P, k, np.array(sites, dtype=complex))
    out.setflags(write=False)
    return out


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


def _orbit_roots(model, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(raw, bp)``: the orbit's branch points as the branch rule takes them (``gaudin._curve.branch_points``: in the
    uniformizer ``z`` for a family that has one, e.g. ``z = e^{2iγλ}``) and in ``λ`` (``model.branch_points``)."""
    from .gaudin._curve import branch_points

    raw = branch_points(model, x)
    fam = model.family
    return raw, (raw if fam.uniform or fam.uniformizer(0.0) is None else fam.uniformizer_inverse(raw))


def _branch_ok(model, x: np.ndarray, eta: np.ndarray, nu_end: np.ndarray, raw: np.ndarray) -> bool:
    """Whether the continued end values ``nu_end`` are ``model.nu``'s default branch at ``η_j`` (to 1e-8 relative:
    the maps take that branch); ``raw`` the orbit's branch points as the rule takes them (:func:`_orbit_roots`)."""
    from .gaudin._curve import nu_with_roots

    ref = np.asarray(nu_with_roots(model, np.broadcast_to(x, eta.shape + x.shape), eta, raw))
    return bool(np.all(np.abs(ref - nu_end) <= 1e-8 * np.abs(ref)))


_MODULES: dict[str, Any] = {}


def _kernel_module(name: str) -> Any:
    """The compiled module ``name`` (Numba imported on first use; then a dictionary look-up, ~1 µs less a call than
    ``importlib.import_module``)."""
    mod = _MODULES.get(name)
    if mod is None:
        mod = _MODULES[name] = importlib.import_module(name)
    return mod


#: per flow and per model (the flows of one model share one dictionary), the stacked kernel constants of its last
#: maps (:func:`_stacked_constants`)
_STACKED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_STACKED_MODEL: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _stacked_constants(flow, etas: tuple) -> tuple:
    """The stepping loop's kernel constants of the maps ``etas`` of the flow's model (``gaudin.maps._orbit_constants``
    per map, stacked by ``_exact_chain_loop.stack_constants``), cached per model and ``(η…)`` (up to 64), looked up
    through the flow (hashing the model costs ~3 µs a call); the loop only reads them."""
    per_flow = _STACKED.get(flow)
    if per_flow is None:  # a new flow: its model's (jg.solve builds a flow at every call)
        per_flow = _STACKED[flow] = _STACKED_MODEL.setdefault(flow.model, {})
    out = per_flow.get(etas)
    if out is None:
        from .gaudin.maps import _orbit_constants

        if len(per_flow) >= 64:
            per_flow.clear()
        out = per_flow[etas] = _kernel_module("jetgaudin._exact_chain_loop").stack_constants(
            [_orbit_constants(flow.model, e) for e in etas])
    return out


#: per flow (weak keys), the plan of the fast path (:func:`_fast_plan`; ``False``: none); a copy of a flow
#: (``maps.with_resolved_backend``) is another key, so a plan never outlives the route it was made for
_FAST: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: per model (weak keys), the plans by ``(weights, dt, substeps, rho_factor)`` (``jg.solve`` builds a new flow at
#: every call: building the plan took ~40 µs of it), up to 16 per model
_FAST_MODEL: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _fast_plan(flow, tols: tuple, accept: tuple, rules: tuple) -> tuple | None:
    """The constants of :func:`_orbit_fast` for a flow (cached per flow), or ``None`` where it does not apply: every
    argument of the compiled solve ``_exact_chain_kernels.solve_orbit_numerical`` but the orbit and its outputs, which
    ``ChainExactFlow._newton`` rebuilt at every call (``tols``: Newton's step and coarse tolerances and iterations;
    ``accept``: the quadrature and residual tolerances; ``rules``: ``exact_chain._rules()``).  It applies to the
    elliptic family on the compiled route with a scalar field: there the real parts, the bounds and the target are
    the same for every orbit of the flow (no computed branch points, no rotation), and the real parts are checked
    once here as the maps' constructor checks ``η`` (``gaudin.maps._check_eta``: finite, off the sites modulo the
    period); the rest of that check, ``|Im η| < 0.9 K'``, is the kernel's, per orbit."""
    plan: tuple | bool | None = _FAST.get(flow)
    if plan is None:
        from .maps import Backend

        if flow.backend is Backend.NUMPY or np.ndim(flow.H.weights) != 1:
            plan = False
        else:  # the model's plan of these weights and steps (every constant of the plan is the model's or these)
            per_model = _FAST_MODEL.setdefault(flow.model, {})
            key = (np.asarray(flow.H.weights, dtype=float).tobytes(), flow.dt, flow.substeps, flow.rho_factor)
            plan = per_model.get(key)
            if plan is None:
                if len(per_model) >= 16:
                    per_model.clear()
                plan = per_model[key] = _make_fast_plan(flow, tols, accept, rules) or False
        _FAST[flow] = plan
    return plan if isinstance(plan, tuple) else None


def _make_fast_plan(flow, tols: tuple, accept: tuple, rules: tuple) -> tuple | None:
    from ._errors import InvalidParameterError
    from .families.elliptic import _IM_FRACTION
    from .gaudin.maps import _check_eta
    from .maps import Backend

    model = flow.model
    fam = model.family
    if (flow.backend is Backend.NUMPY or fam.name != "elliptic" or not float(fam.modulus) >= 1e-3
            or model.algebra != "su(2)" or fam.kernel_rule is None or np.ndim(model.b) != 0):
        return None
    forms = _forms(flow)
    keep, E, rate, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(flow)
    if forms is None or rate or forms[0].ndim != 4 or k < 1:
        return None
    q3, lin, b, fforms, n = forms
    n2 = 2 * model.M
    rho = flow._real_parts(np.zeros(model.n_state), k, np.zeros(0, dtype=complex))  # no branch points: no x used
    if rho is None or n - n2 != 1:
        return None
    try:
        for r in rho:
            _check_eta(model, complex(r, 0.0))
    except InvalidParameterError:
        return None  # the general path raises it, naming the orbit
    bound = np.minimum(2 * np.abs(rho - lc) + (P or 0.0), 0.9 * Kp)  # as ChainExactFlow._newton
    target = (flow.dt / flow.substeps) * wkeep  # as _parameters → _solve → _newton
    K: Any = _kernel_module("jetgaudin._exact_chain_kernels")
    L: Any = _kernel_module("jetgaudin._exact_chain_loop")
    pre = (q3, lin, b, fforms, 2, _family_constants(fam), pos, orders, np.ones(n - n2), kidx, E, target, rho, bound,
           *rules, *tols)
    post = (*accept, float(P), 64, 2**16, 1e-8, _IM_FRACTION * fam.Kp)
    return (K.solve_orbit_numerical, L.rows_family, K.all_finite, pre, post, k, E.shape[0], float(model.b),
            flow.substeps, {}, (model.n_state,))


_F64, _INT64_MAX = np.dtype(float), 2**63 - 1


@lru_cache(maxsize=4)
def _rules_of(nodes: int, coarse: int, very_coarse: int) -> tuple[np.ndarray, ...]:
    """The nodes of the compiled solve: ``(xs1, perm1, w1, xs2, perm2, w2, xsc, permc, wc)``, ``xs1`` the
    ``nodes``-point rule's nodes and the end point 1, ``xs2`` those and the ``nodes/2``-point rule's with its end point
    (the estimate pass), ``xsc`` the coarse rule's (``coarse`` points) with the end point, ``perm*`` the order of the
    continuation (increasing ``|s|``, stable: the NumPy route's order)."""
    from .exact import _gauss_legendre

    x1, w1 = _gauss_legendre(nodes)
    x2, w2 = _gauss_legendre(nodes // 2)
    xc, wc = _gauss_legendre(coarse)
    xv, wv = _gauss_legendre(very_coarse)
    xs1 = np.concatenate([x1, [1.0]])
    xs2 = np.concatenate([x1, [1.0], x2, [1.0]])
    xsc = np.concatenate([xc, [1.0]])
    xsv = np.concatenate([xv, [1.0]])
    return (xs1, np.argsort(xs1, kind="stable"), w1, xs2, np.argsort(xs2, kind="stable"), w2, xsc,
            np.argsort(xsc, kind="stable"), wc, xsv, np.argsort(xsv, kind="stable"), wv)


def _advance_fast(flow, plan: tuple | None, X, steps, save_every):
    """``ChainExactFlow.advance(X, None, steps, save_every)`` by :func:`_orbit_fast` for one orbit ``X`` given as a
    float64 array ``(3M,)`` and counts given as ints (its checks, ``maps.per_orbit_buffers``'s, made here without
    copies: ``X``'s finiteness in the kernel), or ``None`` (the general path)."""
    if not (plan is not None and type(X) is np.ndarray and X.dtype is _F64 and X.shape == plan[10]
            and type(steps) is int and type(save_every) is int and 0 < steps <= _INT64_MAX and save_every >= 1):
        return None
    fast = _orbit_fast(flow, X, steps, save_every, plan)
    if fast is None:
        return None
    from .maps import Advance

    zero = np.zeros(())
    return Advance(rows=fast[0], X=fast[1], carry=zero.astype(complex), imag_max=zero)


def _orbit_fast(flow, x: np.ndarray, steps: int, save_every: int, plan: tuple | None) -> tuple | None:
    """``(rows, final)`` of ``ChainExactFlow._orbit`` for one orbit ``x`` (float64 ``(3M,)``) and ``steps ≥ 1`` by
    the plan of :func:`_fast_plan`: the same compiled solve and loop, the same bits, with two compiled calls and a
    few µs of Python around them; ``None`` where the orbit needs the general path (no plan, ``x`` not C-contiguous
    and writeable (another compiled signature), ``x`` not finite, no accepted solution, the adaptive quadrature, a
    map not used or an ``η`` the maps refuse: that path raises the error or takes the fallback)."""
    if plan is None or not (x.flags.c_contiguous and x.flags.writeable):
        return None
    solve, rows_family, finite, pre, post, k, ne, b, s, cache = plan[:10]
    u = np.empty(ne)
    nu = np.empty(k, dtype=complex)
    eta = np.empty(k, dtype=complex)
    if solve(x, *pre, u, np.empty((k, ne)), nu, *post, eta):
        return None
    key = eta.tobytes()
    consts = cache.get(key)
    if consts is None:  # the model's stacked constants of these η (cached per model; hashing the tuple ~1 µs)
        if len(cache) >= 64:
            cache.clear()
        consts = cache[key] = _stacked_constants(flow, tuple(complex(e) for e in eta))
    out = np.empty((steps // save_every, x.size))
    final = np.empty(x.size)
    rows_family(x, b, nu, *consts, 0.0, steps, save_every, s, out, final)  # elliptic: no rotation (θ = 0)
    if not finite(out, final):
        from ._errors import SingularStepError

        raise SingularStepError("the compiled exact chain step produced non-finite values; give a smaller dt")
    return out, final
