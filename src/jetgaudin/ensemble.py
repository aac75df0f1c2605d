r"""Ensembles of orbits of the real two-point Bäcklund map (Section 6.2), local or on a Dask cluster.

A batch ``X0`` of shape ``(B, 3N)`` with per-orbit field ``b`` and Bäcklund parameter ``η`` (arrays of
shape ``(B,)`` or scalars) is iterated by the compiled kernels of :mod:`jetgaudin.backlund._kernels`
(:func:`~jetgaudin.backlund._kernels.run_ensemble`: a ``prange`` loop over orbits, all cores).  Every
orbit runs the very code of a single-orbit run, so **an ensemble member equals
``TwoPointBacklund(b_i, η_i).iterate(X0_i, steps, kernel="compiled")`` bit for bit**; with
``scheduler="tcp://…"`` the batch is split in chunks run on a Dask cluster, with the same result bit
for bit (needs ``pip install 'jetgaudin[distributed]'``).

Samplers (seeded, reproducible): :func:`sample_on_leaf` (states with the Casimirs ``C_1..C_N`` of
Prop. 2 fixed) and :func:`sample_on_energy_shell` (states with ``H = H_2/2`` of eq. (H) fixed).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ._errors import InvalidParameterError, InvalidStateError
from ._samplers import (  # noqa: F401  (re-exported: the samplers live in their own module)
    DEFAULT_CASIMIRS,
    default_chain_casimirs,
    sample_chain_on_leaf,
    sample_on_energy_shell,
    sample_on_leaf,
)
from ._validate import as_state
from .backlund.maps import _TWO_POINT_PROPERTIES, _sheet
from .maps import (
    Advance,
    Backend,
    Branch,
    Map,
    MapProperties,
    check_count,
    check_output_size,
    step_loop,
    with_resolved_backend,
)
from .spectral import integrals as _jg_integrals

__all__ = ["EnsembleResult", "BatchBacklund", "DaskBatch", "iterate_ensemble", "dask_client", "dask_chunks",
           "sample_on_leaf",
           "sample_on_energy_shell", "sample_chain_on_leaf", "default_chain_casimirs", "DEFAULT_CASIMIRS",
           "DRIFT_QUANTILES", "drift_quantiles"]


#: the quantiles of the drift that ``EnsembleResult.drift_quantiles`` and ``jetgaudin ensemble`` report
DRIFT_QUANTILES = (0.5, 0.9, 0.99, 1.0)


def drift_quantiles(drift, q=DRIFT_QUANTILES) -> np.ndarray:
    """Quantiles over the orbits (axis 0) of a drift table ``(B, 2N)``: shape ``(len(q), 2N)``.  ``q`` in [0, 1];
    an empty table (no orbit) gives NaN rows.  Shared by :class:`EnsembleResult` and the recorded ensembles."""
    qq = np.atleast_1d(np.asarray(q, dtype=float))
    if qq.ndim != 1 or qq.size == 0 or not np.all((qq >= 0) & (qq <= 1)):
        raise InvalidParameterError(f"q must be quantiles in [0, 1] (e.g. 0.5, 0.9, 0.99, 1), got {q!r}")
    d = np.asarray(drift, dtype=float)
    if d.ndim != 2:
        raise InvalidParameterError(f"drift must have shape (B, 2N), got shape {d.shape}")
    if d.shape[0] == 0:
        return np.full((qq.size, d.shape[1]), np.nan)
    return np.quantile(d, qq, axis=0)


@dataclass(frozen=True)
class EnsembleResult:
    r"""Orbits of an ensemble.

    ``states``: ``(S, B, 3N)``, the states ``X_0, X_k, …, X_{(S-1)k}`` (``k = save_every``,
    ``S = steps//k + 1``); ``final``: ``(B, 3N)`` the state after ``steps`` steps; ``drift``:
    ``(B, 2N)``, ``max_n |I_m(X_n) − I_m(X_0)| / max(1, |I_m(X_0)|)`` over the saved states and the
    final one, for the integrals ``(H_1..H_N, C_1..C_N)`` of :func:`jetgaudin.integrals` (``None`` from
    ``iterate_ensemble(..., want_drift=False)``); ``nu``:
    ``(B,)`` the last ``ν1`` used (pass it as ``nu1`` to continue the run bit for bit).
    """

    states: np.ndarray
    final: np.ndarray
    drift: np.ndarray | None
    nu: np.ndarray
    b: np.ndarray
    eta: np.ndarray
    steps: int
    save_every: int

    def _drift(self) -> np.ndarray:
        if self.drift is None:
            raise InvalidParameterError("this ensemble was run with want_drift=False: it has no drift; run it again "
                                        "with want_drift=True")
        return self.drift

    @property
    def max_drift_per_orbit(self) -> np.ndarray:
        """Largest relative drift of each orbit over its 2N integrals, ``max_m drift[:, m]``, shape ``(B,)``."""
        return np.max(self._drift(), axis=-1)

    @property
    def max_drift_per_integral(self) -> np.ndarray:
        """Largest relative drift of each integral ``(H_1..H_N, C_1..C_N)`` over the orbits, ``max_i drift[i, :]``,
        shape ``(2N,)``."""
        return np.max(self._drift(), axis=0)

    @property
    def max_drift(self) -> np.ndarray:
        """Per orbit, shape ``(B,)``: the same as :attr:`max_drift_per_orbit` (kept under its first name; the
        per-integral maximum is :attr:`max_drift_per_integral`, the table of both is :attr:`drift`)."""
        return self.max_drift_per_orbit

    def drift_quantiles(self, q=DRIFT_QUANTILES) -> np.ndarray:
        """Quantiles over the orbits of each integral's relative drift, shape ``(len(q), 2N)``: row ``j`` is the
        ``q[j]`` quantile of ``drift[:, m]`` for each integral ``m`` (``q = 1`` is the largest drift; default the
        median, 90 %, 99 % and the maximum).  Linear interpolation between orbits (:func:`numpy.quantile`)."""
        return drift_quantiles(self._drift(), q)


def _per_orbit(value, B, name, dtype):
    arr = np.asarray(value)
    if arr.dtype == object or arr.dtype.kind not in "biufc":
        raise InvalidParameterError(f"{name} must be numeric")
    if dtype is float and arr.dtype.kind == "c":
        raise InvalidParameterError(f"{name} must be real")
    if arr.ndim == 0:
        arr = np.full(B, arr.item())
    if arr.shape != (B,):
        raise InvalidParameterError(f"{name} must be a scalar or have shape (B,) = ({B},), got shape {arr.shape}")
    arr = arr.astype(np.complex128 if dtype is complex else np.float64)
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{name} must be finite")
    return np.ascontiguousarray(arr)


def _check_int(value, name, minimum):
    return check_count(value, name, minimum)


def per_orbit_integrals(X, b):
    """``jg.integrals`` with a per-orbit field ``b`` (shape ``(B,)``, broadcast over leading axes of ``X``).

    One field for all orbits (the usual case): exactly :func:`jetgaudin.integrals`.  Several: ``H_k`` is affine
    in ``b`` (``H_k = 2 b y_{k-1}^3 + …``, ``C_k`` does not depend on it), so ``I(b) = I(1) + 2 (b − 1) y^3``.
    """
    b = np.asarray(b, dtype=float)
    if b.size == 0 or np.all(b == b.flat[0]):
        return np.asarray(_jg_integrals(X, float(b.flat[0]) if b.size else 1.0), dtype=float)
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    I = np.array(_jg_integrals(X, 1.0), dtype=float)
    I[..., :N] += 2.0 * (b[..., None] - 1.0) * X[..., 2::3]
    return I


@dataclass(frozen=True, eq=False)
class BatchBacklund(Map):
    r"""The real two-point map on a batch ``(B, 3N)`` with a field ``b_i`` and a parameter ``η_i`` per orbit
    (arrays ``(B,)``; the carry is ``ν1`` ``(B,)``).  ``backend`` (alias ``kernel``; the rule of
    :mod:`jetgaudin.maps`): ``"auto"`` (the default) and ``"compiled"`` run the compiled kernels
    (:func:`iterate_ensemble`), orbit ``i`` equal to ``TwoPointBacklund(b_i, η_i, branch).iterate(X0_i, ...,
    backend="compiled")`` bit for bit; ``"gpu"`` the same loop per orbit on the GPU (:mod:`jetgaudin.gpu`; equal to
    the compiled route to round-off); ``"numpy"`` the NumPy reference step orbit by orbit (for checks, not
    speed), orbit ``i`` equal to ``TwoPointBacklund(b_i, η_i, branch).iterate(X0_i, ..., backend="numpy")``.
    ``scheduler`` / ``chunk_size``: run each compiled call on a Dask cluster (same bits; not with the GPU)."""

    b: np.ndarray
    eta: np.ndarray
    branch: Branch = Branch.DEFAULT
    scheduler: Any = field(default=None, repr=False)
    chunk_size: int | None = None
    backend: Backend = Backend.AUTO
    properties: MapProperties = field(default=_TWO_POINT_PROPERTIES, init=False, repr=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias

    def __post_init__(self) -> None:
        b = np.atleast_1d(np.asarray(self.b))
        B = b.shape[0] if b.ndim == 1 else -1
        bb = _per_orbit(self.b, B, "b", float)
        if np.any(bb == 0):
            raise InvalidParameterError("the field strength b must be nonzero for every orbit (the map divides by b)")
        ee = _per_orbit(self.eta, B, "eta", complex)
        if np.any(ee.imag == 0):
            raise InvalidParameterError(
                "eta must have a nonzero imaginary part for every orbit (Im eta = 0 is the identity map); "
                "give eta off the real axis"
            )
        object.__setattr__(self, "b", bb)
        object.__setattr__(self, "eta", ee)
        object.__setattr__(self, "branch", Branch.parse(self.branch))
        self._init_backend()
        if self.scheduler is not None and self.backend is Backend.GPU:
            raise InvalidParameterError("backend 'gpu' runs on this machine's GPU; it takes no Dask scheduler")

    @property
    def has_gpu(self) -> bool:
        """The GPU route (:mod:`jetgaudin.gpu`); not with a Dask scheduler (``AUTO`` then stays on the CPUs)."""
        return self.scheduler is None

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return per_orbit_integrals(X, self.b)

    def start(self, X: np.ndarray) -> np.ndarray:
        """``ν1`` by the branch rule, orbit by orbit: the compiled rule (NumPy's ``jg.nu`` for
        ``backend="numpy"``)."""
        X, _ = as_state(X)
        if self.backend is Backend.NUMPY:
            return np.array([self._orbit_map(i).nu1(X[i]) for i in range(len(X))], dtype=complex)
        from .backlund._compiled import kernels

        return kernels().nu_default(np.ascontiguousarray(X.reshape(-1, X.shape[-1])), self.b, self.eta,
                                    self.branch.sheet)

    def _orbit_map(self, i: int):
        from .backlund.maps import TwoPointBacklund

        return TwoPointBacklund(self.b[i], self.eta[i], self.branch, Backend.NUMPY)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        """One NumPy step per orbit (the reference route; for checks, not speed)."""
        out = [self._orbit_map(i).step(X[i], None if carry is None else carry[i]) for i in range(len(X))]
        return (np.array([o[0] for o in out]), np.array([o[1] for o in out], dtype=complex),
                np.array([o[2] for o in out], dtype=float))

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """The compiled kernels (:meth:`_compiled_advance`) or, for ``backend="numpy"``, the loop over :meth:`step`
        with the carry as given (``None``: each orbit's first step applies the branch rule, as the single-orbit
        map does, so that orbit ``i`` equals it bit for bit)."""
        X = np.asarray(X)
        if X.size and self.resolved_backend(X, steps) in (Backend.COMPILED, Backend.GPU):
            steps, save_every = check_count(steps, "steps"), check_count(save_every, "save_every", 1)
            return self._compiled_advance(X, carry, steps, save_every)
        return step_loop(self, X, carry, steps, save_every)

    def _compiled_advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int) -> Advance:
        res = iterate_ensemble(X, self.b, self.eta, steps, save_every=save_every, branch=self.branch, nu1=carry,
                               scheduler=self.scheduler, chunk_size=self.chunk_size,
                               gpu=self.resolved_backend(X, steps) is Backend.GPU, want_drift=False)
        return Advance(rows=res.states[1:], X=res.final, carry=res.nu, imag_max=np.zeros(len(res.final)))

    def inverse(self) -> BatchBacklund:
        other = Branch.OPPOSITE if self.branch is Branch.DEFAULT else Branch.DEFAULT
        return BatchBacklund(self.b, self.eta, other, self.scheduler, self.chunk_size, self.backend)

    def prepare_kernels(self, X: np.ndarray | None = None, steps: int | None = None, notify=None):
        """Compile (or load) the kernels of :meth:`advance` on ``X`` (B, 3N) visibly, as
        :meth:`jetgaudin.TwoPointBacklund.prepare_kernels` (``None`` for ``backend="numpy"``; no ``X``: every
        kernel, :func:`jetgaudin.backlund.kernels.warmup`); on a Dask cluster only the branch rule runs here, and
        what the workers compile is announced (:func:`jetgaudin.backlund.kernels.remote_notice`)."""
        import sys

        from .backlund._compiled import kernels

        if self.backend is Backend.NUMPY:
            return None
        if self.backend is Backend.GPU or (X is not None and steps is not None
                                           and self.resolved_backend(X, steps) is Backend.GPU):
            from .gpu import prepare

            return prepare(9 if X is None else X.shape[-1], notify)
        K = kernels()
        if X is None:
            return K.warmup(notify)
        n, B = X.shape[-1], max(1, len(X))
        if self.scheduler is not None:
            msg = K.remote_notice(n, B)
            notify(msg) if notify is not None else print(msg, file=sys.stderr, flush=True)
        return K.prepare(n, B, notify=notify, step=self.scheduler is None, announce_load=False)

    def describe(self) -> dict:
        # the same Python floats as [[e.real, e.imag] for e in eta], without a Python loop over the orbits
        return {"kind": "two_point_batch", "b": self.b.tolist(),
                "eta": np.stack([self.eta.real, self.eta.imag], axis=-1).tolist(),
                "branch": self.branch.value, "backend": self.backend.value}


def _run_chunk(X, b, eta, nu0, cont, steps, save_every, specialise, gpu=False, want_drift=True):
    """One chunk by the compiled kernels (the GPU's for ``gpu``): arrays and status, no exception (for Dask)."""
    if gpu:
        from .gpu import run_batch
    else:
        from .backlund._compiled import kernels

        run_batch = kernels().run_batch
    return run_batch(X, b, eta, nu0, cont, steps, save_every, specialise, want_drift)


def iterate_ensemble(X0, b, eta, steps: int, *, save_every: int = 1, branch="default", nu1=None,
                     scheduler=None, chunk_size: int | None = None, specialise: bool = True,
                     connect_timeout: float = 30.0, gpu: bool = False, want_drift: bool = True) -> EnsembleResult:
    r"""Iterate the real two-point map ``B_η`` (field ``b e_3``) on every orbit of a batch.

    ``X0``: ``(B, 3N)``; ``b``, ``eta``: scalars or arrays ``(B,)``; ``steps``: number of steps;
    ``save_every = k``: keep ``X_0, X_k, X_2k, …``; ``branch``: ``"default"`` or ``"opposite"`` (the
    inverse map); ``nu1``: ``(B,)`` values of ``ν1`` to continue from (see
    :meth:`jetgaudin.TwoPointBacklund.iterate`).  ``scheduler``: a Dask scheduler address
    (``"tcp://host:8786"``) or a ``distributed.Client``; the batch is then split in chunks of
    ``chunk_size`` orbits (default: ``B`` over twice the number of worker threads).
    ``connect_timeout``: seconds to wait for the scheduler.  ``specialise``: use the N = 3 kernel for
    N = 3 (``False`` forces the generic route; the two agree to round-off).  ``gpu``: run the steps on the GPU
    (:mod:`jetgaudin.gpu`, the same loop per orbit; not with a scheduler).  ``want_drift=False``: no drift pass
    (``drift`` is ``None``; on the GPU route the pass runs on the host, ~1.5 s per 10⁶ orbits and saved row here).

    Raises :class:`jetgaudin.SingularStepError` (or :class:`jetgaudin.BranchPointError`) naming the first
    orbit and step that fail.

    >>> import numpy as np, jetgaudin as jg
    >>> from jetgaudin.ensemble import iterate_ensemble, sample_on_leaf
    >>> X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], 4, seed=1)
    >>> res = iterate_ensemble(X0, 1.0, 5 + 0.1j, 100, save_every=10)
    >>> res.states.shape, bool(res.max_drift.max() < 1e-11)
    ((11, 4, 9), True)
    """
    X, N = as_state(X0)
    if X.ndim != 2:
        raise InvalidStateError(f"X0 must have shape (B, 3N) (a batch of states), got shape {X.shape}")
    B = X.shape[0]
    steps = _check_int(steps, "steps", 0)
    save_every = _check_int(save_every, "save_every", 1)
    check_output_size(steps // save_every + 1, X.size * 8, "iterate_ensemble")
    sheet = _sheet(branch)
    bb = _per_orbit(b, B, "b", float)
    if np.any(bb == 0):
        raise InvalidParameterError("the field strength b must be nonzero for every orbit (the map divides by b)")
    ee = _per_orbit(eta, B, "eta", complex)
    if np.any(ee.imag == 0):
        raise InvalidParameterError(
            "eta must have a nonzero imaginary part for every orbit (Im eta = 0 makes the map the identity); "
            "give eta off the real axis"
        )
    X = np.ascontiguousarray(X)
    if nu1 is None:
        cont = False
        from .backlund._compiled import kernels

        nu0 = kernels().nu_default(X, bb, ee, sheet)
    else:
        cont = True
        nu0 = _per_orbit(nu1, B, "nu1", complex)
    if gpu and scheduler is not None:
        raise InvalidParameterError("gpu=True runs on this machine's GPU; it takes no Dask scheduler")
    if scheduler is None:
        out, final, drift, nu_last, status, fail = _run_chunk(X, bb, ee, nu0, cont, steps, save_every, specialise,
                                                              gpu, want_drift)
    else:
        out, final, drift, nu_last, status, fail = _run_dask(
            scheduler, chunk_size, X, bb, ee, nu0, cont, steps, save_every, specialise, connect_timeout
        )
    bad = np.flatnonzero(status)
    if bad.size:
        from .backlund._compiled import kernels

        i = int(bad[0])
        exc = kernels().status_error(status[i], fail[i], i)
        raise type(exc)(f"{exc} ({bad.size} orbit(s) of {B} failed)")
    return EnsembleResult(states=np.moveaxis(out, 0, 1), final=final, drift=drift, nu=nu_last, b=bb, eta=ee,
                          steps=steps, save_every=save_every)


def dask_client(scheduler, timeout: float = 30.0):
    """A ``distributed.Client`` for a scheduler address (``"tcp://host:8786"``); a client is returned as it is.
    Raises :class:`InvalidParameterError` when ``distributed`` is missing or the scheduler cannot be reached."""
    try:
        from distributed import Client
    except ImportError:
        raise InvalidParameterError(
            "a Dask scheduler was given but the 'distributed' package is missing: pip install 'jetgaudin[distributed]'"
        ) from None
    if isinstance(scheduler, Client):
        return scheduler
    if not isinstance(scheduler, str):
        raise InvalidParameterError(f"scheduler must be an address 'tcp://host:port' or a distributed.Client, "
                                    f"got {scheduler!r}")
    try:
        return Client(scheduler, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InvalidParameterError(f"cannot connect to the Dask scheduler {scheduler!r}: {exc}") from None


def dask_chunks(scheduler, chunk_size, B: int, fn, per_orbit: tuple, shared: tuple, timeout: float = 30.0) -> list:
    """The one Dask path of the ensembles: ``fn(*chunk, *shared)`` for the chunks ``[i, j)`` of ``chunk_size``
    orbits (default: ``B`` over twice the number of worker threads) of the per-orbit arrays ``per_orbit`` (``None``
    entries passed as ``None``), on the cluster ``scheduler`` (an address or a ``distributed.Client``); the results
    in the order of the chunks.  Used by :func:`iterate_ensemble` (the top's kernels) and :class:`DaskBatch` (any
    map: the chains of every family)."""
    client = dask_client(scheduler, timeout)
    own = client is not scheduler
    try:
        if chunk_size is None:
            threads = sum(client.nthreads().values()) or 1
            chunk_size = max(1, -(-B // (2 * threads)))
        chunk_size = _check_int(chunk_size, "chunk_size", 1)
        futures = [client.submit(fn, *[None if a is None else a[i:min(i + chunk_size, B)] for a in per_orbit],
                                 *shared, pure=False) for i in range(0, B, chunk_size)]
        return client.gather(futures)
    finally:
        if own:
            client.close()


def _run_dask(scheduler, chunk_size, X, b, eta, nu0, cont, steps, save_every, specialise, timeout):
    parts = dask_chunks(scheduler, chunk_size, X.shape[0], _run_chunk, (X, b, eta, nu0),
                        (cont, steps, save_every, specialise), timeout)
    return tuple(np.concatenate([p[k] for p in parts], axis=0) for k in range(6))


def _advance_chunk(X, carry, m: Map, steps: int, save_every: int) -> Advance:
    return m.advance(X, carry, steps, save_every)


@dataclass(frozen=True, eq=False)
class DaskBatch(Map):
    r"""Any map's batch ``(B, n)`` split by orbits over a Dask cluster: each :meth:`advance` runs
    ``inner.advance`` on chunks of ``chunk_size`` orbits on the workers (:func:`dask_chunks`, the path of
    :func:`iterate_ensemble`) and joins them.  The maps of the chains advance every orbit independently, so the
    result is the local run's bit for bit; the ``auto`` route is resolved on the whole batch first (every chunk on
    the same route).  Everything else (``integrals``, ``start``, ``step``, ``describe``: the inner map's, so a run
    records and resumes the inner map) is the inner map's.  Needs ``pip install 'jetgaudin[distributed]'``."""

    inner: Map
    scheduler: Any = field(default=None, repr=False)
    chunk_size: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.inner, Map):
            raise InvalidParameterError(f"DaskBatch needs a map, got {type(self.inner).__name__}")
        if self.chunk_size is not None:
            _check_int(self.chunk_size, "chunk_size", 1)

    @property
    def properties(self) -> MapProperties:  # type: ignore[override]
        return self.inner.properties

    @property
    def n_state(self) -> int | None:
        return self.inner.n_state

    @property
    def backend(self) -> Backend:
        return self.inner.backend

    @property
    def chunk_invariant(self) -> bool:
        return bool(getattr(self.inner, "chunk_invariant", True))

    @property
    def has_compiled(self) -> bool:
        return self.inner.has_compiled

    def resolved_backend(self, X: Any, steps: Any) -> Backend:
        """The inner map's route for ``steps`` steps of the whole batch ``X``."""
        return self.inner.resolved_backend(X=X, steps=steps)

    def prepare_kernels(self, *args: Any, **kwargs: Any) -> Any:
        """The inner map's (compiled here; workers on this machine load Numba's cache, others compile their own)."""
        return self.inner.prepare_kernels(*args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        # the inner map's parameters and optional surface (b, eta, branch, model, integral_names, state_labels);
        # dunder and private names are not forwarded (pickling, copying)
        if name.startswith("_") or name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)

    def with_backend(self, backend: Backend | str) -> DaskBatch:  # type: ignore[override]
        """The same split with the inner map on another route."""
        return replace(self, inner=self.inner.with_backend(backend))

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return self.inner.integrals(X)

    def start(self, X: np.ndarray) -> np.ndarray:
        return self.inner.start(X)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        return self.inner.step(X, carry)

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        X = np.asarray(X)
        inner = self.inner
        if X.ndim != 2 or len(X) == 0:
            return inner.advance(X, carry, steps, save_every)
        if inner.backend is Backend.AUTO:  # every chunk on the route of the whole batch
            inner = with_resolved_backend(inner, inner.resolved_backend(X=X, steps=steps))
        c = None if carry is None else np.asarray(carry)
        parts = dask_chunks(self.scheduler, self.chunk_size, len(X), _advance_chunk, (X, c), (inner, steps, save_every))
        carries = [p.carry for p in parts]
        return Advance(rows=np.concatenate([p.rows for p in parts], axis=1), X=np.concatenate([p.X for p in parts]),
                       carry=None if any(x is None for x in carries) else np.concatenate(carries),
                       imag_max=np.concatenate([p.imag_max for p in parts]))

    def inverse(self) -> DaskBatch:
        return replace(self, inner=self.inner.inverse())

    def describe(self) -> dict:
        return self.inner.describe()
