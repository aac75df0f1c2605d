r"""Event location on the exact flow: the times at which ``g(X(t))`` crosses zero, and Poincaré sections.

The orbit is sampled with the exact flow at step ``dt`` (:func:`jetgaudin.solve`, ``method="exact"``: a top's
:class:`jetgaudin.ExactFlow`, a chain's :class:`jetgaudin.ChainExactFlow`, or a physical top of
:mod:`jetgaudin.physical`); on every step where ``g`` changes sign the crossing time ``t_n + s*`` is found by Brent's
method (:func:`scipy.optimize.brentq`) on the trajectory's exact dense output (:meth:`jetgaudin.Trajectory.at`: one
exact step from the nearest saved state, no interpolant), so the event time is limited only by round-off and by ``g``
(``brentq`` to ``xtol = 1e-15``, ``rtol = 4ε``).  Several event functions at once (``g`` a sequence; each event
records which, :attr:`Events.index`), a ``direction`` and a ``terminal`` flag per function (the first terminal event
ends the search: later events are dropped, as in SciPy's ``solve_ivp``), and a batch ``X0`` ``(m, n)`` (one
:class:`Events` per orbit, a list).  A crossing inside one step that returns to the same sign (two roots) is not seen:
choose ``dt`` below half the shortest time between two crossings.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._errors import InvalidParameterError
from .solve import solve

__all__ = ["Events", "find_events", "poincare_section"]


@dataclass(frozen=True)
class Events:
    """The crossings, in the order of time along the orbit: ``t`` ``(k,)``, the states ``X`` ``(k, n)`` there (a
    physical top: its variables ``P``), the ``direction`` ``(k,)`` (+1: ``g`` increasing, −1: decreasing), the
    ``index`` ``(k,)`` of the event function (0 for a single ``g``), and ``terminated``: whether a terminal event
    ended the search."""

    t: np.ndarray
    X: np.ndarray
    direction: np.ndarray
    index: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    terminated: bool = False


def _scalar(g: Callable, X: np.ndarray) -> float:
    val = np.asarray(g(X), dtype=float)
    if val.shape != () or not np.isfinite(val):
        raise InvalidParameterError(f"the event function g must return one finite number per state, got {val!r}")
    return float(val)


def _per_function(value: Any, k: int, name: str, allowed: tuple) -> list:
    vals = list(value) if isinstance(value, Sequence) and not isinstance(value, str) else [value] * k
    if len(vals) != k:
        raise InvalidParameterError(f"{name} must be one value or one per event function ({k}), got {len(vals)}")
    for v in vals:
        if (isinstance(v, bool) and name == "direction") or v not in allowed:
            raise InvalidParameterError(f"{name} must be one of {allowed}, got {v!r}")
    return vals


def _one_orbit(H: Any, X0: np.ndarray, gs: list, t_span, dt: float, dirs: list, terms: list,
               substeps: int | str) -> Events:
    from scipy.optimize import brentq  # lazy: keeps `import jetgaudin` light

    tr = solve(H, X0, t_span, dt=dt, method="exact", substeps=substeps)
    physical = tr.physical is not None
    states: np.ndarray = tr.physical if tr.physical is not None else tr.X

    def at(t: float) -> np.ndarray:
        x = tr.at(t)
        return H.from_state(x) if physical else x

    found = []
    for i, g in enumerate(gs):
        gv = np.array([_scalar(g, x) for x in states])
        for n in range(len(gv) - 1):
            a, b = gv[n], gv[n + 1]
            if not (a * b < 0 or (b == 0 and a != 0)):
                continue
            d = 1 if b > a else -1
            if dirs[i] and d != dirs[i]:
                continue
            t0, t1 = float(tr.t[n]), float(tr.t[n + 1])

            def f(s: float, t0=t0, x=states[n], g=g) -> float:
                return _scalar(g, at(t0 + s)) if s != 0 else _scalar(g, x)

            root = t0 + brentq(f, 0.0, t1 - t0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
            found.append((root, i, d))
    sense = 1.0 if tr.t[-1] >= tr.t[0] else -1.0
    found.sort(key=lambda e: (sense * e[0], e[1]))
    terminated = False
    for j, (_, i, _) in enumerate(found):
        if terms[i]:
            found, terminated = found[:j + 1], True
            break
    n3 = states.shape[-1]
    X = np.array([at(t) for t, _, _ in found]).reshape(-1, n3)
    return Events(np.array([e[0] for e in found]), X, np.array([e[2] for e in found], dtype=int),
                  np.array([e[1] for e in found], dtype=int), terminated)


def find_events(H: Any, X0, g: Callable | Sequence[Callable], t_span, dt: float, *, direction: Any = 0,
                terminal: Any = False, substeps: int | str = "auto") -> Events | list[Events]:
    r"""The times ``t`` in ``t_span`` where ``g(X(t)) = 0`` along the exact flow of ``H`` from ``X0`` (module doc).

    ``H``: a top's :class:`~jetgaudin.IntegralHamiltonian`, a chain's ``model.hamiltonian(weights)`` or a physical top
    (:func:`jetgaudin.heavy_top`, :func:`jetgaudin.kirchhoff_clebsch`; then ``X0`` and the states ``g`` sees are its
    variables ``P``).  ``g``: one function or a sequence; ``direction`` (``+1`` only crossings with ``g`` increasing,
    ``−1`` decreasing, ``0`` both) and ``terminal`` (stop at the first such event): one value or one per function.
    ``X0`` ``(n,)``: one :class:`Events`; ``(m, n)``: a list of ``m``, one per orbit."""
    gs = list(g) if isinstance(g, Sequence) else [g]
    if not gs or not all(callable(f) for f in gs):
        raise InvalidParameterError("g must be a callable g(X) -> float or a non-empty sequence of them")
    dirs = _per_function(direction, len(gs), "direction", (-1, 0, 1))
    terms = [bool(v) for v in _per_function(terminal, len(gs), "terminal", (True, False))]
    if np.iscomplexobj(X0):
        raise InvalidParameterError("X0 must be real")
    X0 = np.asarray(X0, dtype=float)
    if X0.ndim == 2:
        return [_one_orbit(H, x, gs, t_span, dt, dirs, terms, substeps) for x in X0]
    if X0.ndim != 1:
        raise InvalidParameterError(f"X0 must be one state (n,) or a batch (m, n), got shape {X0.shape}")
    return _one_orbit(H, X0, gs, t_span, dt, dirs, terms, substeps)


def poincare_section(H: Any, X0, g: Callable, t_span, dt: float, *, direction: int = 1,
                     substeps: int | str = "auto") -> Events | list[Events]:
    r"""The Poincaré section ``{g = 0}`` crossed in ``direction`` (default ``+1``): :func:`find_events` with that
    direction.

    >>> import jetgaudin as jg
    >>> H = jg.physical_hamiltonian(3, 1.0)
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> ev = jg.poincare_section(H, X0, lambda X: X[0], (0, 20), 0.2)
    >>> bool(len(ev.t) > 0 and abs(ev.X[:, 0]).max() < 1e-12)
    True
    """
    if direction not in (-1, 1):
        raise InvalidParameterError(f"a Poincaré section needs direction +1 or -1, got {direction!r}")
    return find_events(H, X0, g, t_span, dt, direction=direction, substeps=substeps)
