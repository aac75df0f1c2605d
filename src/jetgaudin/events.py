r"""Event location on the exact flow: the times at which ``g(X(t))`` crosses zero, and Poincaré sections.

The orbit is sampled with :class:`jetgaudin.ExactFlow` at step ``dt``; on every step where ``g`` changes sign the
crossing time ``t_n + s*`` is found by Brent's method (:func:`scipy.optimize.brentq`) on the step length ``s`` of the
exact flow from ``X_n``: every trial ``X(t_n + s) = ExactFlow(H, s)(X_n)`` is the exact state (no interpolant), so
the event time is limited only by round-off and by ``g`` (``brentq`` to ``xtol = 1e-15``, ``rtol = 4ε``).
A crossing inside one step that returns to the same sign (two roots) is not seen: choose ``dt`` below half the
shortest time between two crossings.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ._errors import InvalidParameterError
from ._validate import as_state
from .hamiltonians import IntegralHamiltonian
from .solve import SolveMethod, _map, solve

__all__ = ["Events", "find_events", "poincare_section"]


@dataclass(frozen=True)
class Events:
    """The crossings: ``t`` ``(k,)``, the states ``X`` ``(k, 3N)`` there and the ``direction`` ``(k,)`` (+1: ``g``
    increasing, −1: decreasing)."""

    t: np.ndarray
    X: np.ndarray
    direction: np.ndarray


def _scalar(g: Callable, X: np.ndarray) -> float:
    val = np.asarray(g(X), dtype=float)
    if val.shape != () or not np.isfinite(val):
        raise InvalidParameterError(f"the event function g must return one finite number per state, got {val!r}")
    return float(val)


def find_events(H: IntegralHamiltonian, X0, g: Callable, t_span, dt: float, *, direction: int = 0,
                substeps: int | str = "auto") -> Events:
    r"""The times ``t`` in ``t_span`` where ``g(X(t)) = 0`` along the flow of ``H`` from ``X0`` ``(3N,)`` (module
    doc); ``direction``: ``+1`` only crossings with ``g`` increasing, ``−1`` decreasing, ``0`` both."""
    from scipy.optimize import brentq  # lazy: keeps `import jetgaudin` light

    X0, _ = as_state(X0)
    if X0.ndim != 1:
        raise InvalidParameterError("find_events follows one orbit: X0 must have shape (3N,)")
    if direction not in (-1, 0, 1):
        raise InvalidParameterError(f"direction must be -1, 0 or +1, got {direction!r}")
    tr = solve(H, X0, t_span, dt=dt, method="exact", substeps=substeps)
    h, s = tr.info["dt"], tr.info["substeps"]
    gv = np.array([_scalar(g, x) for x in tr.X])
    times, states, dirs = [], [], []
    for n in range(len(gv) - 1):
        a, b = gv[n], gv[n + 1]
        if not (a * b < 0 or (b == 0 and a != 0)):
            continue
        d = 1 if b > a else -1
        if direction and d != direction:
            continue
        x = tr.X[n]

        def f(sv: float, x=x) -> float:
            return _scalar(g, _map(SolveMethod.EXACT, H, sv, s, "auto")(x)) if sv != 0 else _scalar(g, x)

        root = brentq(f, 0.0, h, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        times.append(tr.t[n] + root)
        states.append(_map(SolveMethod.EXACT, H, root, s, "auto")(x) if root != 0 else x)
        dirs.append(d)
    n3 = X0.shape[-1]
    return Events(np.array(times), np.array(states).reshape(-1, n3), np.array(dirs, dtype=int))


def poincare_section(H: IntegralHamiltonian, X0, g: Callable, t_span, dt: float, *, direction: int = 1,
                     substeps: int | str = "auto") -> Events:
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
