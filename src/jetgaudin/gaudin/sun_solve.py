r"""Integrating the flows of an su(n) chain Hamiltonian ``H = Σ_I w_I h_I`` (issue 32): which methods of
:func:`jetgaudin.solve` apply, and heyoka's equations for ``n = 3``.

**Methods** (the rows ``"sun"`` of :data:`jetgaudin.methods.ROUTES`).  ``"dop853"`` and ``"midpoint"`` (any ``n``:
the generic right-hand side ``Π(X)∇H``); ``"heyoka"`` for ``n ≤ 3`` (its
equations are built symbolically, below); ``"exact"`` for ``n = 3``
(:class:`jetgaudin.gaudin.sun_exact.SunExactFlow`).  Refused with :class:`jetgaudin.InvalidParameterError`
naming those: ``"kahan"`` (Kahan–Hirota–Kimura is built for quadratic vector fields on 3-component blocks; for
``n ≥ 3`` the integrals ``h^{(k)}``, ``k ≥ 3``, are of degree ``k`` and the blocks have ``n² − 1``
components), ``"bt"`` (no two-point map ``B^(r)`` is matched to a time step), ``"exact"`` for ``n ≠ 3``.
``"midpoint"`` applies (:class:`jetgaudin.midpoint.ImplicitMidpoint` on the generic field; it keeps the quadratic
integrals only).

**heyoka's equations (n = 3).**  ``Ẋ_I = Σ_{J,K} c_{IJK} X_K g_J(X)`` with ``c`` the chain's structure constants
and ``g = ∇H``; the ``h^{(2)}`` are quadratic and the ``h^{(3)}`` cubic in ``X`` (``τ_k`` is a polynomial of degree
``k`` in the ``y``, with constant coefficients from ``b`` and the sites), so ``g`` is a polynomial of degree 2:

.. math:: g(x) = g_0 + \sum_j a_j x_j + \sum_{j \le k} q_{jk} x_j x_k,

read off exactly from values of the exact gradient: ``g_0 = g(0)``, ``a_j = (g(e_j) − g(−e_j))/2``,
``q_{jj} = (g(e_j) + g(−e_j))/2 − g_0`` and, for ``j < k``, ``q_{jk} = g(e_j + e_k) − g(e_j) − g(e_k) + g_0``
(identities for any polynomial of degree 2; round-off leaves coefficients of order 1e-16 where the exact one is 0:
those below ``1e-14 · max |q|`` are dropped, a change of the vector field far below heyoka's tolerance).
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from .._errors import InvalidParameterError

__all__ = ["SOLVE_METHODS", "check_solve_method", "gradient_polynomial", "heyoka_integrator"]

#: the methods of :func:`jetgaudin.solve` for an su(n) chain (``"heyoka"`` for ``n ≤ 3``)
SOLVE_METHODS = ("dop853", "heyoka", "midpoint")


def check_solve_method(model, method: str) -> None:
    """Refuse a method of :func:`jetgaudin.solve` that does not apply to the su(n) chain ``model`` (module
    docstring), naming those that do."""
    ok = [m for m in SOLVE_METHODS if m != "heyoka" or model.n <= 3] + (["exact"] if model.n == 3 else [])
    if method not in ok:
        why = {"kahan": "Kahan's map is built for quadratic vector fields on 3-component blocks",
               "exact": f"its exact time step is built for su(3) (docs/sun.md §5), not {model.algebra.name}",
               "heyoka": f"heyoka's equations are built for n <= 3 (the gradient of h^(k), k <= 3), not {model.n}",
               "bt": "no two-point map B^(r) of an su(n) chain is matched to a time step of H"}
        raise InvalidParameterError(
            f"method={method!r} does not apply to an {model.algebra.name} chain ("
            f"{why.get(method, 'a fixed-step method of the tops')}); use one of {', '.join(map(repr, ok))}")


def gradient_polynomial(H) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int, np.ndarray]]]:
    """``(g0, a, q)`` of ``∇H`` (module docstring): ``g0`` ``(n,)``, ``a`` ``(n, n)`` (``a[:, j]``), ``q`` the list
    of ``(j, k, q_jk)`` with a coefficient above the round-off floor."""
    n = H.model.n_state
    if H.model.n > 3:
        raise InvalidParameterError(f"the gradient of H is of degree {H.model.n - 1} > 2; built for n <= 3")
    E = np.eye(n)
    g0 = np.asarray(H.gradient(np.zeros(n)), dtype=float)
    gp = np.asarray(H.gradient(E), dtype=float)  # g(e_j), row j
    gm = np.asarray(H.gradient(-E), dtype=float)
    a = ((gp - gm) / 2).T
    j, k = np.triu_indices(n, 1)
    gjk = np.asarray(H.gradient(E[j] + E[k]), dtype=float)
    Q = np.concatenate([(gp + gm) / 2 - g0, gjk - gp[j] - gp[k] + g0])
    pairs = list(zip(np.arange(n), np.arange(n), strict=True)) + list(zip(j, k, strict=True))
    floor = 1e-14 * max(float(np.max(np.abs(Q))) if Q.size else 0.0, 1e-300)
    q = [(int(p), int(r), Q[i]) for i, (p, r) in enumerate(pairs) if np.max(np.abs(Q[i])) > floor]
    return g0, a, q


def heyoka_equations(H) -> list:
    """heyoka's ``(x_I, Ẋ_I)`` pairs of ``Ẋ = Π(X)∇H`` (module docstring)."""
    import heyoka as hy

    n = H.model.n_state
    g0, a, q = gradient_polynomial(H)
    floor = 1e-14 * max(float(np.max(np.abs(a))), float(np.max(np.abs(g0))), 1e-300)
    xs = hy.make_vars(*[f"x{i}" for i in range(n)])
    grads = []
    for J in range(n):
        terms: list[Any] = [float(a[J, K]) * xs[K] for K in range(n) if abs(a[J, K]) > floor]
        terms += [float(c[J]) * xs[p] * xs[r] for p, r, c in q if abs(c[J]) > floor]
        if abs(g0[J]) > floor:
            terms.append(hy.expression(float(g0[J])))
        grads.append(hy.sum(terms) if terms else hy.expression(0.0))
    c = H.model.structure_constants
    rhs = []
    for i in range(n):
        terms = [float(c[i, J, K]) * xs[K] * grads[J] for J in range(n) for K in range(n) if c[i, J, K] != 0.0]
        rhs.append(hy.sum(terms) if terms else hy.expression(0.0))
    return list(zip(xs, rhs, strict=True))


#: compiled integrators by (the Hamiltonian's model description and weights, rtol)
_CACHE: dict = {}


def heyoka_integrator(H, rtol: float):
    """A fresh copy of heyoka's integrator of ``Ẋ = Π∇H`` at tolerance ``rtol`` (compiled once per ``H``)."""
    import heyoka as hy

    key = (repr(H.model.describe()), np.asarray(H.weights).tobytes(), float(rtol))
    if key not in _CACHE:
        if len(_CACHE) >= 8:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = hy.taylor_adaptive(heyoka_equations(H), np.zeros(H.model.n_state), tol=rtol, compact_mode=True)
    return copy.copy(_CACHE[key])
