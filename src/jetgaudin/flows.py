r"""Continuous Hamiltonian flows ``Ẋ = Π(X) ∇H`` on :math:`\mathfrak g^{(N)}`.

One driver, :func:`integrate`, for any :class:`~jetgaudin.hamiltonians.IntegralHamiltonian`
(or any object with ``vector_field(X)``); methods: SciPy's DOP853 (default) or heyoka's
Taylor integrator (``method="heyoka"``, extra ``jetgaudin[heyoka]``).  Returns a
:class:`Trajectory` with the drift of every integral.  :class:`FlowMap` is the flow over a fixed time step
``dt`` as a :class:`~jetgaudin.maps.Map`, so that the run layer records a flow like an orbit.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from ._errors import IntegrationError, InvalidParameterError
from ._validate import as_state, parse_choice, real_number
from .algebra import structure_constants
from .hamiltonians import IntegralHamiltonian
from .maps import Advance, Backend, Map, MapProperties, check_count, register_map
from .spectral import integrals

__all__ = ["Trajectory", "integrate", "Method", "FlowMap"]


class Method(StrEnum):
    """Integration method of :func:`integrate`: SciPy's DOP853 or heyoka's Taylor integrator."""

    DOP853 = "DOP853"
    HEYOKA = "heyoka"

    @classmethod
    def parse(cls, value: Method | str) -> Method:
        return parse_choice(cls, value, "method")


@dataclass(frozen=True)
class Trajectory:
    """Samples of a flow or of a map's orbit: ``t`` (shape ``(T,)``), ``X`` (``(T, ..., 3N)``), ``integrals``
    (``(T, ..., 2N)``), the ``method`` and ``info`` (what the method did: e.g. the time step used and the exact
    flow's sub-steps, see :func:`jetgaudin.solve`).  :meth:`to_xarray` (needs ``xarray``), :meth:`to_hdf5` /
    :meth:`from_hdf5` (datasets ``t``, ``X``, ``integrals``, as the run layer's files)."""

    t: np.ndarray
    X: np.ndarray
    integrals: np.ndarray
    method: str
    info: dict = field(default_factory=dict)
    #: a physical top's variables ``top.from_state(X)`` beside the model states (:func:`jetgaudin.solve` of a
    #: :mod:`jetgaudin.physical` top), else ``None``
    physical: np.ndarray | None = None
    #: model time per unit of ``t`` (a physical top's ``time_scale``; 1 otherwise)
    time_scale: float = 1.0
    #: ``dense(t) -> X(t)`` for the exact method (:meth:`at`), else ``None``
    dense: Any = field(default=None, repr=False, compare=False)

    def at(self, t) -> np.ndarray:
        """The model state at any time(s) ``t`` within the trajectory's span, shape ``np.shape(t) + X.shape[1:]``:
        for ``method="exact"`` one exact step from the nearest saved state (no interpolation error; a physical
        top's variables: ``top.from_state(tr.at(t))``).  Other methods: :class:`InvalidParameterError`."""
        if self.dense is None:
            raise InvalidParameterError(f"at(t) is the exact flow's dense output: this trajectory's method is "
                                        f"{self.method!r} (solve one orbit with method='exact', or use t_eval with "
                                        "'dop853'/'heyoka')")
        return self.dense(t)

    def to_xarray(self):
        """An ``xarray.Dataset`` with ``X`` (time, ..., component) and ``integrals`` (time, ..., integral);
        :class:`InvalidParameterError` when xarray is not installed (an optional dependency)."""
        try:
            import xarray as xr
        except ImportError:
            raise InvalidParameterError("to_xarray() needs the optional package xarray: pip install xarray") from None
        lead = [f"orbit{k}" for k in range(self.X.ndim - 2)]
        return xr.Dataset(
            {"X": (["t", *lead, "component"], self.X), "integrals": (["t", *lead, "integral"], self.integrals)},
            coords={"t": self.t}, attrs={"method": self.method, **{k: str(v) for k, v in self.info.items()}})

    def to_hdf5(self, path, *, overwrite: bool = False) -> None:
        """Write ``t``, ``X``, ``integrals`` and the attributes ``method``, ``info`` (JSON) to an HDF5 file.  An
        existing file is refused unless ``overwrite`` (then replaced atomically); a symlink, FIFO or device always
        (:class:`jetgaudin.RecordingError`, :func:`jetgaudin._fs.check_library_file`)."""
        import json
        import os

        import h5py

        from . import _fs

        path = _fs.check_library_file(path, write=True, overwrite=overwrite)
        tmp = path.with_name(path.name + ".tmp") if overwrite else path
        if overwrite:
            _fs.check_library_file(tmp, write=True, overwrite=True)
            tmp.unlink(missing_ok=True)
        try:
            with h5py.File(tmp, "x") as f:  # O_EXCL: never through a link planted meanwhile
                for name in ("t", "X", "integrals"):
                    f.create_dataset(name, data=getattr(self, name))
                f.attrs["method"] = self.method
                f.attrs["info"] = json.dumps(self.info)
            if overwrite:
                os.replace(tmp, path)
        except BaseException:
            if overwrite:
                tmp.unlink(missing_ok=True)
            raise

    @classmethod
    def from_hdf5(cls, path) -> Trajectory:
        """The trajectory :meth:`to_hdf5` wrote."""
        import json

        import h5py

        from . import _fs

        with h5py.File(_fs.check_library_file(path), "r") as f:  # a FIFO, device or link refused before opening
            return cls(np.asarray(f["t"]), np.asarray(f["X"]), np.asarray(f["integrals"]), str(f.attrs["method"]),
                       json.loads(f.attrs["info"]))

    @property
    def drift(self) -> np.ndarray:
        """``max_t |I_k(t) − I_k(0)| / max(1, |I_k(0)|)`` for each integral, shape ``(..., 2N)``."""
        I0 = self.integrals[0]
        return np.max(np.abs(self.integrals - I0), axis=0) / np.maximum(1.0, np.abs(I0))


def _heyoka_system(H: IntegralHamiltonian, n: int):
    if np.ndim(H.weights) != 1:
        raise InvalidParameterError("the heyoka backend integrates one orbit at a time (1-D weights)")
    # ∇H is affine in X: ∇H = A X + g0 (A constant), so Π(X)∇H is quadratic
    g0 = H.gradient(np.zeros(n))
    A = np.stack([H.gradient(np.eye(n)[j]) - g0 for j in range(n)], axis=1)
    return _heyoka_equations(n, g0, A, _structure(H, n))


def _heyoka_equations(n: int, g0: np.ndarray, A: np.ndarray, c: np.ndarray):
    """heyoka's equations ``dx_i/dt = Σ c[i, J, K] x_K (A x + g0)_J`` (:func:`_heyoka_system`)."""
    import heyoka as hy

    xs = hy.make_vars(*[f"x{i}" for i in range(n)])
    grads = []
    for J in range(n):
        terms = [float(A[J, K]) * xs[K] for K in range(n) if A[J, K] != 0.0]
        if g0[J] != 0.0:
            terms.append(hy.expression(float(g0[J])))
        grads.append(hy.sum(terms) if terms else hy.expression(0.0))
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


#: largest |T| of one :func:`integrate` call (issue 11, item 8: ``integrate(H, X0, 1e300)`` never ended)
MAX_INTEGRATION_TIME = 1e9


def _check_times(T, t_eval):
    T = real_number(T, "T")
    if abs(T) > MAX_INTEGRATION_TIME:
        raise InvalidParameterError(
            f"T = {T:g} is too long for one call: an adaptive integrator takes at least one step per unit of the "
            f"orbit's time scale (O(1) for states of size O(1)), so this would run for days or without end; give "
            f"|T| <= {MAX_INTEGRATION_TIME:g} (split a longer integration into several calls)"
        )
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


#: the smallest relative tolerance of the adaptive integrators (``dop853``, ``heyoka``): 1e-18, a hundredth of the
#: machine epsilon (no double-precision step gains anything below it; heyoka's own default is the epsilon).  Far
#: below it heyoka's Taylor order and step count grew without bound (``flow --method heyoka --rtol 1e-300`` ran for
#: ever past 1.2 GB, deaf to SIGINT); it is refused instead
RTOL_FLOOR = 1e-18


def _check_tol(name, val, positive, floor: float = 0.0):
    val = real_number(val, name)
    if val < 0 or (positive and val == 0):
        raise InvalidParameterError(f"{name} must be finite and {'> 0' if positive else '>= 0'}, got {val}")
    if val < floor:
        raise InvalidParameterError(f"{name} = {val:g} is below {floor:.3g} (a hundredth of the machine epsilon), "
                                    f"which no double-precision step can meet; give {name} >= {floor:.3g}")
    return val


def integrate(H, X0, T: float, *, t_eval=None, method: Method | str = Method.DOP853, rtol: float = 1e-12,
              atol: float = 1e-12, b=None) -> Trajectory:
    r"""Integrate ``Ẋ = Π(X) ∇H`` from ``X0`` over ``[0, T]`` (``T < 0``: backwards).

    ``H`` is an :class:`IntegralHamiltonian` (e.g. :func:`jetgaudin.physical_hamiltonian` or
    :func:`jetgaudin.interpolating_flow_hamiltonian` ``(X0, b, η)``, the Hamiltonian whose flow from ``X0`` is that of
    ``G_η``; the value ``G_η(X)`` itself is :func:`jetgaudin.interpolating_hamiltonian`, a number, not something to
    integrate), or any object with ``vector_field(X)``
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
    check = getattr(H, "check_state", None)  # the protocol of jetgaudin.hamiltonians.SolveHamiltonian
    X0 = np.asarray(check(X0), dtype=float) if callable(check) else as_state(X0)[0]
    T, t_eval = _check_times(T, t_eval)
    rtol = _check_tol("rtol", rtol, True, RTOL_FLOOR)
    atol = _check_tol("atol", atol, False)
    method = Method.parse(method)
    is_integral = getattr(H, "route_kind", None) == "top"  # the top's (one Hamiltonian type: the system decides)
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
    elif method is Method.DOP853:
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
        own = getattr(H, "heyoka_integrator", None)  # a Hamiltonian that builds its own equations (su(3) chains)
        if not affine and not callable(own):
            raise InvalidParameterError(
                "method='heyoka' needs an IntegralHamiltonian (its vector field is built symbolically)"
            )
        grid = t_eval if t_eval[0] == 0.0 else np.concatenate([[0.0], t_eval])  # heyoka's grid starts at t = 0
        try:
            ta = own(rtol) if callable(own) else _heyoka_integrator(H, X0.shape[-1], rtol)
            ta.state[:] = X0
            ta.time = 0.0
            res = ta.propagate_grid(grid)
        except (ValueError, RuntimeError) as exc:
            raise IntegrationError(f"heyoka failed: {exc}") from None
        if res[0] != hy.taylor_outcome.time_limit:
            raise IntegrationError(f"heyoka failed: {res[0]}")
        Xs = np.asarray(res[-1])[len(grid) - len(t_eval):]
    if not np.all(np.isfinite(Xs)):
        raise IntegrationError(f"{method} produced non-finite states (the orbit blew up); reduce T or the tolerances")
    recorded = record(Xs) if callable(record) else integrals(Xs, bb, cc)
    return Trajectory(t=t_eval, X=Xs, integrals=recorded, method=method.value)


def _heyoka_integrator(H: IntegralHamiltonian, n: int, rtol: float):
    """A fresh copy of heyoka's integrator of ``H`` on ``n`` components at tolerance ``rtol``: compiled once per
    Hamiltonian (its equations' coefficients) and tolerance, then copied (~1 ms against 30-150 ms of JIT
    compilation per call; issue 33)."""
    if np.ndim(H.weights) != 1:
        raise InvalidParameterError("the heyoka backend integrates one orbit at a time (1-D weights)")
    g0 = np.asarray(H.gradient(np.zeros(n)), dtype=float)
    A = np.stack([np.asarray(H.gradient(np.eye(n)[j]), dtype=float) - g0 for j in range(n)], axis=1)
    c = np.asarray(_structure(H, n), dtype=float)
    key = (n, float(rtol), g0.tobytes(), A.tobytes(), c.tobytes())
    template = _HEYOKA_CACHE.get(key)
    if template is None:
        import heyoka as hy

        template = hy.taylor_adaptive(_heyoka_equations(n, g0, A, c), np.zeros(n), tol=rtol)
        if len(_HEYOKA_CACHE) >= _HEYOKA_CACHE_SIZE:
            _HEYOKA_CACHE.pop(next(iter(_HEYOKA_CACHE)))  # the oldest
        _HEYOKA_CACHE[key] = template
    return copy.copy(template)


#: compiled heyoka integrators by (n, rtol, the equations' coefficients) (:func:`_heyoka_integrator`)
_HEYOKA_CACHE: dict = {}
_HEYOKA_CACHE_SIZE = 16


#: largest time step of a FlowMap: an adaptive integrator takes at least one step per unit of the orbit's own time
#: scale (O(1) for states of size O(1)); a step of 1e6 time units already means millions of integrator steps per
#: map step.  Larger steps are refused rather than left running without end (issue 11, item 8).
MAX_FLOW_DT = 1e6

_FLOW_PROPERTIES = MapProperties(
    preserves_integrals=True, poisson=True, real=True, order=None, symmetric=True, interpolates_flow=False
)


@dataclass(frozen=True, eq=False)
class FlowMap(Map):
    r"""The flow of ``Ẋ = Π(X) ∇H`` (eq. (LP)) over a fixed time step ``dt``, as a :class:`~jetgaudin.maps.Map`.

    ``H``: an :class:`IntegralHamiltonian` (e.g. :func:`jetgaudin.physical_hamiltonian`, or
    :func:`jetgaudin.interpolating_flow_hamiltonian` ``(X0, b, η)``, whose time-1 flow from its ``X0`` is the two-point
    map; not :func:`jetgaudin.interpolating_hamiltonian`, which is the value ``G_η(X)``);
    ``method``, ``rtol``, ``atol`` as in :func:`integrate`.  :meth:`advance` integrates ``steps * dt`` in one
    call sampled every ``save_every * dt`` (an adaptive integrator restarted at other times gives other
    round-off: a flow is reproducible for a given chunking, not bit for bit across chunkings; the run layer
    therefore cuts flows into fixed chunks, ``chunk_invariant = False``).  No carry (zeros).  ``backend`` (alias
    ``kernel``; the rule of :mod:`jetgaudin.maps`): the NumPy/SciPy route only (``"auto"``, the default, is
    ``"numpy"``; ``"compiled"`` is refused with :class:`~jetgaudin.InvalidParameterError`).
    """

    H: IntegralHamiltonian
    dt: float
    method: Method = Method.DOP853
    rtol: float = 1e-12
    atol: float = 1e-12
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_FLOW_PROPERTIES, init=False, repr=False, compare=False)
    chunk_invariant = False
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias

    def __post_init__(self) -> None:
        if getattr(self.H, "route_kind", None) != "top":
            raise InvalidParameterError("H must be an IntegralHamiltonian of the top (a field b: physical_hamiltonian, "
                                        "...); a chain's flow map is jetgaudin.gaudin.flow.ChainFlowMap")
        dt = _check_tol("dt", self.dt, True)
        if dt > MAX_FLOW_DT:
            raise InvalidParameterError(f"dt = {dt:g} is too large: one map step would integrate over {dt:g} time "
                                        f"units (hours to forever); give dt <= {MAX_FLOW_DT:g} and more steps")
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "method", Method.parse(self.method))
        object.__setattr__(self, "rtol", _check_tol("rtol", self.rtol, True, RTOL_FLOOR))
        object.__setattr__(self, "atol", _check_tol("atol", self.atol, False))
        self._init_backend()

    @property
    def n_state(self) -> int:
        return 3 * self.H.N

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(integrals(X, self.H.b, self.H.c), dtype=float)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        tr = integrate(self.H, X, self.dt, method=self.method, rtol=self.rtol, atol=self.atol)
        X1 = tr.X[-1]
        return X1, np.zeros(X1.shape[:-1], dtype=complex), np.zeros(X1.shape[:-1])

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        check = getattr(self.H, "check_state", None)  # a Hamiltonian on its own state space (an su(n) chain)
        X = check(X) if callable(check) else as_state(X)[0]
        zeros = np.zeros(X.shape[:-1], dtype=complex)
        if steps == 0:
            return Advance(rows=np.empty((0,) + X.shape), X=X.copy(), carry=zeros, imag_max=zeros.real)
        k = steps // save_every
        t = np.arange(1, k + 1) * (save_every * self.dt)
        T = steps * self.dt
        t_eval = t if (k and steps % save_every == 0) else np.concatenate([t, [T]])
        tr = integrate(self.H, X, T, t_eval=t_eval, method=self.method, rtol=self.rtol, atol=self.atol)
        return Advance(rows=tr.X[:k], X=tr.X[-1], carry=zeros, imag_max=zeros.real)

    def inverse(self) -> FlowMap:
        """The flow backwards in time (``dt → −dt``)."""
        return _flow_map(self.H, -self.dt, self.method, self.rtol, self.atol, self.backend)

    def describe(self) -> dict:
        b = np.asarray(self.H.b, dtype=float)
        return {"kind": "flow", "b": b.tolist(), "weights": np.asarray(self.H.weights).tolist(),
                "c": None if self.H.c is None else np.asarray(self.H.c).tolist(), "dt": self.dt,
                "method": self.method.value, "rtol": self.rtol, "atol": self.atol, "backend": self.backend.value}


def _flow_map(H: IntegralHamiltonian, dt: float, method: Method, rtol: float, atol: float,
              backend: Backend | str = Backend.AUTO) -> FlowMap:
    """A flow map with any nonzero ``dt`` (the constructor takes ``dt > 0``; the inverse runs backwards)."""
    m = FlowMap(H, abs(dt), method, rtol, atol, Backend.parse(backend))
    object.__setattr__(m, "dt", float(dt))
    return m


def _flow_from(d: dict) -> FlowMap:
    H = IntegralHamiltonian(d["b"], np.asarray(d["weights"], dtype=float), d.get("c"))
    return _flow_map(H, float(d["dt"]), Method.parse(d["method"]), float(d["rtol"]), float(d["atol"]),
                     d.get("backend", "auto"))


register_map("flow", _flow_from)
