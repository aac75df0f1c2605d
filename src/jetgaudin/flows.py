r"""Continuous Hamiltonian flows ``Ẋ = Π(X) ∇H`` on :math:`\mathfrak g^{(N)}`.

One driver, :func:`integrate`, for any :class:`~jetgaudin.hamiltonians.IntegralHamiltonian`
(or any object with ``vector_field(X)``); methods: SciPy's DOP853 (default) or heyoka's
Taylor integrator (``method="heyoka"``, extra ``jetgaudin[heyoka]``).  Returns a
:class:`Trajectory` with the drift of every integral.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    c = _structure(H, n)
    rhs = []
    for i in range(n):
        terms = []
        for J in range(n):
            for K in range(n):
                if c[i, J, K] != 0.0:
                    terms.append(float(c[i, J, K]) * xs[K] * grads[J])
        rhs.append(hy.sum(terms) if terms else hy.expression(0.0))
    return list(zip(xs, rhs, strict=True))


def _structure(H, n: int) -> np.ndarray:
    """The structure constants of the Poisson bracket ``H`` lives on: ``H.structure_constants`` if it has them (a
    chain, :class:`jetgaudin.gaudin.ChainHamiltonian`), else those of g^(N), N = n/3 (eq. (LP))."""
    c = getattr(H, "structure_constants", None)
    return structure_constants(n // 3) if c is None else np.asarray(c)


def _affine_gradient(H: IntegralHamiltonian, X0: np.ndarray):
    """``(A, g0)`` with ``∇H(X) = A X + g0`` (exact: every κ_m is quadratic in X), batched like ``X0``."""
    n = X0.shape[-1]
    zero = np.zeros_like(X0)
    g0 = H.gradient(zero)
    cols = [H.gradient(zero + np.eye(n)[j]) - g0 for j in range(n)]
    return np.stack(cols, axis=-1), g0  # A[..., i, j] = ∂g_i/∂X_j


def _fast_rhs(H: IntegralHamiltonian, X0: np.ndarray):
    """``Ẋ = Π(X)(A X + g0)`` with ``Π(X) = c · X`` (eq. (LP)): two small matrix products per call.

    Same vector field as ``H.vector_field`` (checked in tests/test_flows.py), ~20x cheaper.
    """
    n = X0.shape[-1]
    A, g0 = _affine_gradient(H, X0)
    C = _structure(H, n).reshape(n * n, n)
    shape = X0.shape

    def rhs(_t, y):
        X = y.reshape(shape)
        g = np.einsum("...ij,...j->...i", A, X) + g0
        P = (X @ C.T).reshape(shape[:-1] + (n, n))
        return np.einsum("...ij,...j->...i", P, g).reshape(-1)

    return rhs


def _check_times(T, t_eval):
    try:
        T = float(T)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"T must be a number, got {T!r}") from None
    if not np.isfinite(T):
        raise InvalidParameterError(f"T must be finite, got {T}")
    if t_eval is None:
        t_eval = np.array([0.0, T]) if T != 0 else np.array([0.0])
    try:
        t_eval = np.asarray(t_eval, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"t_eval must be a 1-D array of times, got {t_eval!r}") from None
    if t_eval.ndim != 1 or len(t_eval) == 0 or not np.all(np.isfinite(t_eval)):
        raise InvalidParameterError("t_eval must be a non-empty 1-D array of finite times")
    if T == 0:
        if np.any(t_eval != 0):
            raise InvalidParameterError("with T = 0, t_eval may only contain 0; give T != 0 to integrate")
        return T, t_eval
    d = np.sign(T)
    s = d * t_eval
    if np.any(s < 0) or np.any(s > abs(T)):
        raise InvalidParameterError(f"t_eval must lie in the interval between 0 and T = {T}")
    if np.any(np.diff(s) <= 0):
        raise InvalidParameterError(
            "t_eval must be strictly monotone in the direction of integration (increasing for T > 0, "
            "decreasing for T < 0), without repeated times"
        )
    return T, t_eval


def _check_tol(name, val, positive):
    try:
        val = float(val)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number, got {val!r}") from None
    if not np.isfinite(val) or val < 0 or (positive and val == 0):
        raise InvalidParameterError(f"{name} must be finite and {'> 0' if positive else '>= 0'}, got {val}")
    return val


def integrate(H, X0, T: float, *, t_eval=None, method: str = "DOP853", rtol: float = 1e-12, atol: float = 1e-12,
              b=None) -> Trajectory:
    r"""Integrate ``Ẋ = Π(X) ∇H`` from ``X0`` over ``[0, T]`` (``T < 0``: backwards).

    ``H`` is an :class:`IntegralHamiltonian` (e.g. :func:`jetgaudin.physical_hamiltonian` or
    :func:`jetgaudin.interpolating_flow_hamiltonian`), or any object with ``vector_field(X)``
    (then give the field ``b`` for the recorded integrals, unless ``H.record_integrals(X)`` gives them, as for
    :class:`jetgaudin.gaudin.ChainHamiltonian`).  ``t_eval`` (default: ``0`` and ``T``)
    are the sample times, strictly monotone, between ``0`` and ``T``.  ``method``: ``"DOP853"``
    (SciPy, tolerances ``rtol``/``atol``) or ``"heyoka"`` (Taylor method, tolerance ``rtol``; needs
    ``pip install jetgaudin[heyoka]``).  ``X0`` may be a batch ``(..., 3N)`` for DOP853 (integrated
    as one system).

    >>> import jetgaudin as jg
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> tr = jg.integrate(jg.physical_hamiltonian(3, 1.0), X0, 1.0)
    >>> bool(tr.drift.max() < 1e-11)
    True
    """
    X0, N = as_state(X0)
    T, t_eval = _check_times(T, t_eval)
    rtol = _check_tol("rtol", rtol, True)
    atol = _check_tol("atol", atol, False)
    if method not in ("DOP853", "heyoka"):
        raise InvalidParameterError(f"method must be 'DOP853' or 'heyoka', got {method!r}")
    is_integral = isinstance(H, IntegralHamiltonian)
    # quadratic Hamiltonians on another Lie-Poisson space (a chain) declare their structure constants
    affine = is_integral or getattr(H, "structure_constants", None) is not None
    if not is_integral and not callable(getattr(H, "vector_field", None)):
        raise InvalidParameterError("H must be an IntegralHamiltonian or have a vector_field(X) method")
    if is_integral:
        H._check(X0)  # N of the Hamiltonian matches the state
    record = getattr(H, "record_integrals", None)  # a Hamiltonian of another model (e.g. a chain) records its own
    bb = getattr(H, "b", None) if b is None else b
    if bb is None and not callable(record):
        raise InvalidParameterError("give the field b (H has no attribute b) to record the integrals")
    cc = getattr(H, "c", None)
    shape = X0.shape
    if T == 0:
        Xs = np.broadcast_to(X0, (len(t_eval),) + shape).copy()
    elif method == "DOP853":
        if affine:
            rhs = _fast_rhs(H, X0)
        else:
            def rhs(_t, y):
                return np.asarray(H.vector_field(y.reshape(shape))).reshape(-1)

        from scipy.integrate import solve_ivp  # lazy: keeps `import jetgaudin` light

        sol = solve_ivp(rhs, (0.0, T), X0.reshape(-1), method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
        if not sol.success:
            raise IntegrationError(f"DOP853 failed: {sol.message}")
        Xs = sol.y.T.reshape((len(t_eval),) + shape)
    else:
        try:
            import heyoka as hy
        except ImportError:
            raise InvalidParameterError(
                "method='heyoka' needs the optional backend: pip install 'jetgaudin[heyoka]'"
            ) from None
        if X0.ndim != 1:
            raise InvalidParameterError("method='heyoka' integrates one orbit: X0 must have shape (3N,)")
        if not affine:
            raise InvalidParameterError(
                "method='heyoka' needs an IntegralHamiltonian (its vector field is built symbolically)"
            )
        grid = t_eval if t_eval[0] == 0.0 else np.concatenate([[0.0], t_eval])  # heyoka's grid starts at t = 0
        try:
            ta = hy.taylor_adaptive(_heyoka_system(H, 3 * N), X0.copy(), tol=rtol)
            res = ta.propagate_grid(grid)
        except (ValueError, RuntimeError) as exc:
            raise IntegrationError(f"heyoka failed: {exc}") from None
        if res[0] != hy.taylor_outcome.time_limit:
            raise IntegrationError(f"heyoka failed: {res[0]}")
        Xs = np.asarray(res[-1])[len(grid) - len(t_eval):]
    if not np.all(np.isfinite(Xs)):
        raise IntegrationError(f"{method} produced non-finite states (the orbit blew up); reduce T or the tolerances")
    recorded = record(Xs) if callable(record) else integrals(Xs, bb, cc)
    return Trajectory(t=t_eval, X=Xs, integrals=recorded, method=method)
