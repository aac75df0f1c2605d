r"""Continuous Hamiltonian flows ``Ẋ = Π(X) ∇H`` on :math:`\mathfrak g^{(N)}`.

One driver, :func:`integrate`, for any :class:`~jetgaudin.hamiltonians.IntegralHamiltonian`
(or any object with ``vector_field(X)``); methods: SciPy's DOP853 (default) or heyoka's
Taylor integrator (``method="heyoka"``, extra ``jetgaudin[heyoka]``).  Returns a
:class:`Trajectory` with the drift of every integral.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ._errors import IntegrationError, InvalidParameterError
from ._validate import as_state
from .algebra import structure_constants
from .hamiltonians import IntegralHamiltonian
from .spectral import integrals

__all__ = ["Trajectory", "integrate"]


@dataclass(frozen=True)
class Trajectory:
    """Samples of a flow: ``t`` (shape ``(T,)``), ``X`` (``(T, ..., 3N)``), ``integrals`` (``(T, ..., 2N)``)."""

    t: np.ndarray
    X: np.ndarray
    integrals: np.ndarray
    method: str

    @property
    def drift(self) -> np.ndarray:
        """``max_t |I_k(t) − I_k(0)| / max(1, |I_k(0)|)`` for each integral, shape ``(..., 2N)``."""
        I0 = self.integrals[0]
        return np.max(np.abs(self.integrals - I0), axis=0) / np.maximum(1.0, np.abs(I0))


def _heyoka_system(H: IntegralHamiltonian, n: int):
    import heyoka as hy

    if np.ndim(H.weights) != 1:
        raise InvalidParameterError("the heyoka backend integrates one orbit at a time (1-D weights)")
    xs = hy.make_vars(*[f"x{i}" for i in range(n)])
    # ∇H is affine in X: ∇H = A X + g0 (A constant), so Π(X)∇H is quadratic
    g0 = H.gradient(np.zeros(n))
    A = np.stack([H.gradient(np.eye(n)[j]) - g0 for j in range(n)], axis=1)
    grads = []
    for J in range(n):
        terms = [float(A[J, K]) * xs[K] for K in range(n) if A[J, K] != 0.0]
        if g0[J] != 0.0:
            terms.append(hy.expression(float(g0[J])))
        grads.append(hy.sum(terms) if terms else hy.expression(0.0))
    c = structure_constants(n // 3)
    rhs = []
    for i in range(n):
        terms = []
        for J in range(n):
            for K in range(n):
                if c[i, J, K] != 0.0:
                    terms.append(float(c[i, J, K]) * xs[K] * grads[J])
        rhs.append(hy.sum(terms) if terms else hy.expression(0.0))
    return list(zip(xs, rhs, strict=True))


def integrate(H, X0, T: float, *, t_eval=None, method: str = "DOP853", rtol: float = 1e-12, atol: float = 1e-12,
              b=None) -> Trajectory:
    r"""Integrate ``Ẋ = Π(X) ∇H`` from ``X0`` over ``[0, T]``.

    ``H`` is an :class:`IntegralHamiltonian` (e.g. :func:`jetgaudin.physical_hamiltonian` or
    :func:`jetgaudin.interpolating_flow_hamiltonian`).  ``t_eval`` (default: ``0`` and ``T``)
    are the sample times.  ``method``: ``"DOP853"`` (SciPy, tolerances ``rtol``/``atol``) or
    ``"heyoka"`` (Taylor method, tolerance ``rtol``; needs ``pip install jetgaudin[heyoka]``).
    ``X0`` may be a batch ``(..., 3N)`` for DOP853 (integrated as one system).

    >>> import jetgaudin as jg
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> tr = jg.integrate(jg.physical_hamiltonian(3, 1.0), X0, 1.0)
    >>> bool(tr.drift.max() < 1e-11)
    True
    """
    X0, N = as_state(X0)
    try:
        T = float(T)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"T must be a number, got {T!r}") from None
    if not np.isfinite(T):
        raise InvalidParameterError("T must be finite")
    t_eval = np.array([0.0, T]) if t_eval is None else np.asarray(t_eval, dtype=float)
    if t_eval.ndim != 1 or len(t_eval) == 0 or not np.all(np.isfinite(t_eval)):
        raise InvalidParameterError("t_eval must be a non-empty 1-D array of finite times")
    if not (rtol > 0 and atol >= 0):
        raise InvalidParameterError("rtol must be > 0 and atol >= 0")
    bb = H.b if b is None else b
    shape = X0.shape
    if method == "DOP853":
        def rhs(_t, y):
            return H.vector_field(y.reshape(shape)).reshape(-1)

        sol = solve_ivp(rhs, (0.0, T), X0.reshape(-1), method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
        if not sol.success:
            raise IntegrationError(f"DOP853 failed: {sol.message}")
        Xs = sol.y.T.reshape((len(t_eval),) + shape)
    elif method == "heyoka":
        try:
            import heyoka as hy
        except ImportError:
            raise InvalidParameterError(
                "method='heyoka' needs the optional backend: pip install 'jetgaudin[heyoka]'"
            ) from None
        if X0.ndim != 1:
            raise InvalidParameterError("method='heyoka' integrates one orbit: X0 must have shape (3N,)")
        ta = hy.taylor_adaptive(_heyoka_system(H, 3 * N), X0.copy(), tol=rtol)
        res = ta.propagate_grid(t_eval)
        if res[0] not in (hy.taylor_outcome.time_limit,):
            raise IntegrationError(f"heyoka failed: {res[0]}")
        Xs = np.asarray(res[-1])
    else:
        raise InvalidParameterError(f"method must be 'DOP853' or 'heyoka', got {method!r}")
    return Trajectory(t=t_eval, X=Xs, integrals=integrals(Xs, bb, H.c), method=method)
