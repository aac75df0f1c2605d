"""Python-side constants of :class:`jetgaudin.ChainExactFlow`'s compiled solve (private): the family constants of the
compiled basis (per family parameter), the model-only constants of a flow (per flow, weak keys: nothing outlives its
flow), the trigonometric branch points from the compiled polynomial, the real parts of a periodic family's
parameters and the linear identities among the matched integrals.  Split from :mod:`jetgaudin.exact_chain`
(its size); Numba is imported on first use only."""

from __future__ import annotations

import importlib
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


def _integrals_row(flow, x: np.ndarray) -> np.ndarray:
    """``model.integrals(x)`` of one orbit ``x`` (3M,) by the compiled pass of :mod:`jetgaudin.gaudin._record` (the
    model's quadratic forms, cached per flow: ~1 µs against ~16 µs of NumPy for the Clebsch top; equal to
    ``model.integrals`` to ``n ε Σ|terms|``, not bit for bit); ``model.integrals`` itself where the pass is not finite
    (which refuses an overflow)."""
    model = flow.model
    f = _FORMS.get(flow)
    if f is None and np.ndim(model.b) == 0:
        q, lin = model._forms
        lin = np.ascontiguousarray(lin, dtype=float)
        forms = np.ascontiguousarray(np.asarray(model.family.extra_integrals(model.sites)[1], dtype=float)
                                     .reshape(-1, model.n_state))
        f = (np.ascontiguousarray(q, dtype=float), lin, float(model.b), forms,
             (q.shape[0] if q.ndim == 3 else q.shape[1]) + forms.shape[0])
        _FORMS[flow] = f
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


def _periodic_real_parts(lc: float, P: float, k: int, points: np.ndarray) -> np.ndarray:
    """``k`` real parts in one period ``[lc, lc + P)`` (a periodic family): greedily the points of a 256-point grid
    farthest from every site and branch point (``points``, with their images at ``± P``), at least ``P/(4k)`` apart
    from each other (the rational rule ``λ_c + cR/t_j`` could wrap onto a site)."""
    grid = lc + P * np.arange(256) / 256
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
