r"""Recording of ensembles (compatibility layer over :mod:`jetgaudin.run`).

An ensemble run is the run layer's case of a batch ``(B, 3N)``: :func:`run_ensemble` builds a
:class:`jetgaudin.run.RunSpec` for :class:`jetgaudin.ensemble.BatchBacklund` (per-orbit ``b``, ``η``) and calls
:func:`jetgaudin.run.start` / :func:`jetgaudin.run.resume`.  The run directory::

    DIR/ensemble.h5      HDF5 (SWMR mode): the inputs ``X0`` (B × 3N), ``b`` (B), ``eta`` (B, complex), and,
                         growing along the first axis, ``n`` (int64, rows) and ``states`` (rows × B × 3N)
    DIR/checkpoint-0.npz, DIR/checkpoint-1.npz
                         the state ``X`` (B × 3N), ``ν1`` (B) and the running drift (B × 2N) after the last
                         safe step, written alternately (``run.json`` names the valid one and its SHA-256)
    DIR/run.json         inputs, version, status, last safe step, checkpoint, drift summary

Guarantees: ``docs/reliability.md`` (the same as orbit runs: durable checkpoints, resume bit for bit, one writer,
signals honoured within a fraction of a second, health checks).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._errors import InvalidParameterError, RecordingError
from ._validate import as_state
from .ensemble import BatchBacklund, per_orbit_integrals
from .maps import Branch, check_count
from .run import api as _api
from .run.files import ENSEMBLE_H5
from .run.load import load
from .run.spec import DEFAULT_MAX_DRIFT, HealthLimits, RunSpec

__all__ = ["EnsembleSpec", "EnsembleRunResult", "EnsembleData", "run_ensemble", "load_ensemble", "ENSEMBLE_H5"]

COMMAND = "jetgaudin ensemble"
EnsembleRunResult = _api.RunResult
_integrals = per_orbit_integrals


@dataclass(frozen=True, eq=False)
class EnsembleSpec:
    """The inputs that determine an ensemble run: ``X0`` (B, 3N), per-orbit ``b`` and ``eta`` (B,) (scalars are
    broadcast), ``steps``, ``save_every`` and ``branch``; validated by :class:`jetgaudin.ensemble.BatchBacklund`
    and :class:`jetgaudin.run.RunSpec` (``b ≠ 0``, ``Im η ≠ 0``, finite states, ``ν(η)`` defined at ``X0``)."""

    X0: np.ndarray
    b: Any
    eta: Any
    steps: int
    save_every: int = 1
    branch: str = "default"

    def __post_init__(self) -> None:
        X, _ = as_state(np.asarray(self.X0, dtype=float), name="the initial states")
        if X.ndim != 2:
            raise InvalidParameterError(f"X0 must have shape (B, 3N) (a batch of states), got shape {X.shape}")
        B = X.shape[0]
        object.__setattr__(self, "X0", np.ascontiguousarray(X))
        b = np.asarray(self.b)
        eta = np.asarray(self.eta)
        m = BatchBacklund(np.broadcast_to(b, (B,)) if b.ndim == 0 else b,
                          np.broadcast_to(eta, (B,)) if eta.ndim == 0 else eta, Branch.parse(self.branch))
        object.__setattr__(self, "b", m.b)
        object.__setattr__(self, "eta", m.eta)
        object.__setattr__(self, "branch", m.branch.value)
        object.__setattr__(self, "steps", check_count(self.steps, "steps"))
        object.__setattr__(self, "save_every", check_count(self.save_every, "save_every", 1))
        self.run_spec(m)  # the run's rules (state scale, nu(eta) at X0)

    def run_spec(self, m: BatchBacklund | None = None, max_drift: float = DEFAULT_MAX_DRIFT,
                 checkpoint_seconds: float = 2.0) -> RunSpec:
        m = m or BatchBacklund(self.b, self.eta, Branch.parse(self.branch))
        return RunSpec(m, self.X0, self.steps, self.save_every, HealthLimits(max_drift, float("inf")),
                       program=COMMAND, checkpoint_seconds=checkpoint_seconds)

    @property
    def B(self) -> int:
        return self.X0.shape[0]

    @property
    def N(self) -> int:
        return self.X0.shape[1] // 3

    def digest(self) -> str:
        """SHA-256 of ``X0``, ``b``, ``eta`` (little-endian), recorded in ``run.json``."""
        return _api.inputs_digest(self.X0, self.b, self.eta)


@dataclass(frozen=True)
class EnsembleData:
    """What :func:`load_ensemble` reads: step indices ``n`` (rows,), ``states`` (rows, B, 3N) and the inputs."""

    n: np.ndarray
    states: np.ndarray
    X0: np.ndarray
    b: np.ndarray
    eta: np.ndarray


def load_ensemble(out_dir: str | Path) -> EnsembleData:
    """The rows of a run directory that ``run.json`` declares safe (all in memory: for very large runs use
    :func:`jetgaudin.run.load` with ``rows=slice(...)``)."""
    d = load(out_dir)
    if d.X0 is None or d.b is None or d.eta is None:
        raise RecordingError(f"{out_dir} holds no ensemble run")
    return EnsembleData(n=d.n, states=d.X, X0=d.X0, b=d.b, eta=d.eta)


def run_ensemble(spec: EnsembleSpec | None, out_dir: str | Path, *, resume: bool = False,
                 max_drift: float = DEFAULT_MAX_DRIFT, checkpoint_seconds: float = 2.0,
                 max_chunk_bytes: int = 64 << 20, max_chunk_steps: int | None = None, scheduler: Any = None,
                 chunk_size: int | None = None, expect: dict | None = None,
                 progress: Callable[[int, int], None] | None = None, handle_signals: bool = True,
                 overwrite: bool = False, notify: Callable[[str], None] | None = None,
                 backend: str | None = None) -> _api.RunResult:
    """Iterate an ensemble and stream it into ``out_dir`` (see the module doc).

    ``resume=True`` continues the run recorded in ``out_dir`` (``expect``: names of ``run.json["inputs"]`` mapped
    to the values the user gave; a difference is refused).  ``scheduler``: a Dask scheduler address or
    ``distributed.Client`` (each kernel call is split over the cluster by orbits; same bits).  A kernel call holds
    at most ``max_chunk_bytes`` of saved states and at most ``max_chunk_steps`` steps; how the run is cut never
    changes the result.  ``notify(message)``: where the compile messages go (:func:`jetgaudin.run.start`).
    ``backend``: the map's route for a new run (:class:`jetgaudin.maps.Backend`; ``"gpu"``: :mod:`jetgaudin.gpu`);
    ``run.json`` records the route taken, which a resume keeps (give ``expect={"backend": ...}`` to check it).

    >>> import tempfile, numpy as np
    >>> from jetgaudin.ensemble import sample_on_leaf
    >>> spec = EnsembleSpec(sample_on_leaf(3, [0.5, 0.2, 1.0], 8, seed=1), 1.0, 5 + 0.1j, steps=100, save_every=10)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     res = run_ensemble(spec, d)
    ...     data = load_ensemble(d)
    >>> res.status, data.states.shape, bool(res.max_drift.max() < 1e-11)
    ('completed', (11, 8, 9), True)
    """
    if max_chunk_steps is not None:
        check_count(max_chunk_steps, "max_chunk_steps", 1)
    if chunk_size is not None:
        check_count(chunk_size, "chunk_size", 1)
    if isinstance(checkpoint_seconds, bool) or not (0 <= checkpoint_seconds < float("inf")):
        raise InvalidParameterError("checkpoint_seconds must be a finite number >= 0")
    opts: dict[str, Any] = dict(progress=progress, handle_signals=handle_signals, max_chunk_steps=max_chunk_steps,
                max_chunk_bytes=max_chunk_bytes, notify=notify)
    if not resume and spec is None:
        raise InvalidParameterError("spec is required for a new run")
    HealthLimits(max_drift, float("inf"))  # a bad limit refused before a cluster is contacted
    client, own = scheduler, False
    try:
        if scheduler is not None:
            from .ensemble import dask_client

            client = dask_client(scheduler)
            own = client is not scheduler
        mo = {"scheduler": client, "chunk_size": chunk_size}
        if resume:
            return _api.resume(out_dir, expect=expect, checkpoint_seconds=checkpoint_seconds, map_options=mo,
                               program=COMMAND, **opts)
        assert spec is not None
        # the run's map as it will run (route, cluster), then its RunSpec: one validation of the whole ensemble
        # (integrals and the branch rule at X0; seconds at 10^7 orbits) instead of two
        route: Any = backend or "auto"  # a name: parsed (and refused with the map's message) by the map
        m = BatchBacklund(spec.b, spec.eta, Branch.parse(spec.branch), scheduler=client, chunk_size=chunk_size,
                          backend=route)
        return _api.start(spec.run_spec(m, max_drift=max_drift, checkpoint_seconds=checkpoint_seconds), out_dir,
                          overwrite=overwrite, **opts)
    finally:
        if own:
            with contextlib.suppress(Exception):
                client.close()
