"""What a run is: a validated :class:`RunSpec` (map, initial states, steps, save cadence, health limits) and the
run statuses (the *recording* layer; see ``docs/architecture.md``).  Every rule about a run's inputs is checked
here, once; the command line only converts text to values."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from .._errors import InvalidParameterError
from .._validate import as_state
from ..maps import Map, check_count

__all__ = [
    "DEFAULT_MAX_DRIFT",
    "DEFAULT_MAX_IMAG",
    "HealthLimits",
    "Layout",
    "RunSpec",
    "RunStatus",
    "integral_names",
    "binds_per_run",
    "run_map",
]

#: default health thresholds.  The map preserves the integrals up to round-off, which accumulates about
#: linearly: ~2e-13 (relative) after 10^3 steps and ~1e-8 after 5*10^7 steps for Appendix 2 (measured by
#: benchmarks/memory_long_run.py), i.e. ~2e-16 per step.  1e-6 leaves room for ~10^9 steps of round-off and
#: still flags a genuine loss of accuracy (a near-singular step jumps by far more).  The imaginary residue
#: of a real step is ~1e-18; 1e-8 flags a step that is no longer real.
DEFAULT_MAX_DRIFT = 1e-6
DEFAULT_MAX_IMAG = 1e-8

#: largest number of states one run may hold in memory per orbit batch (B * n doubles): 2**31 doubles = 16 GiB
_MAX_BATCH_VALUES = 1 << 31


class RunStatus(StrEnum):
    """The state of a run directory.  ``FAILED``: the run stopped on a health check or a singular step (not
    resumable: it would fail again); ``FAILED_IO``: writing failed (full disk, I/O error) after the last
    durable checkpoint (resumable once the cause is removed)."""

    RUNNING = "running"
    COMPLETED = "completed"
    INTERRUPTED = "interrupted"
    FAILED = "failed"
    FAILED_IO = "failed_io"

    @classmethod
    def of(cls, run: dict) -> RunStatus:
        """The status a ``run.json`` records (its ``status`` text is ``failed: <reason>`` for both failures)."""
        text = str(run.get("status", ""))
        if text.startswith("failed"):
            return cls.FAILED_IO if run.get("failure") == "io" else cls.FAILED
        try:
            return cls(text)
        except ValueError:
            return cls.FAILED

    @property
    def resumable(self) -> bool:
        return self in (RunStatus.RUNNING, RunStatus.INTERRUPTED, RunStatus.FAILED_IO)


class Layout(StrEnum):
    """Files of a run directory: ``ORBIT`` (one state: ``orbit.h5``, ``orbit.csv``, ``run.json``) or ``ENSEMBLE``
    (a batch ``(B, n)``: ``ensemble.h5``, ``checkpoint-0/1.npz``, ``run.json``)."""

    ORBIT = "orbit"
    ENSEMBLE = "ensemble"


def model_of(m: object) -> Any:
    """The chain model of the map ``m`` (or of the inner map of a wrapper, or of its Hamiltonian ``H``: a map of one
    Hamiltonian such as :class:`jetgaudin.midpoint.ImplicitMidpoint`), ``None`` for a top."""
    inner = getattr(m, "inner", None)
    base = inner if isinstance(inner, Map) else m
    model = getattr(base, "model", None)
    return model if model is not None else getattr(getattr(base, "H", None), "model", None)


def block_size(m: object) -> int:
    """Components per site and jet order of the states of the map ``m`` (or of the inner map of a wrapper): the
    model's ``dim`` (an su(n) chain: ``n² − 1``), else 3 (the tops and the su(2) chains).  The run layer's one
    source of the state layout: ``n_state // block_size(m)`` blocks ``y_k``."""
    d = getattr(model_of(m), "dim", None)
    return d if isinstance(d, int) and not isinstance(d, bool) and d > 0 else 3


def integral_names(N: int) -> list[str]:
    """``["H_1", …, "H_N", "C_1", …, "C_N"]``, the order of :func:`jetgaudin.integrals`."""
    return [f"H_{k}" for k in range(1, N + 1)] + [f"C_{k}" for k in range(1, N + 1)]


@dataclass(frozen=True)
class HealthLimits:
    """Thresholds of the numerical health checks (defaults :data:`DEFAULT_MAX_DRIFT`, :data:`DEFAULT_MAX_IMAG`;
    ``inf`` disables a check)."""

    max_drift: float = DEFAULT_MAX_DRIFT
    max_imag: float = DEFAULT_MAX_IMAG

    def __post_init__(self) -> None:
        for name in ("max_drift", "max_imag"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or math.isnan(v) or v < 0:
                raise InvalidParameterError(f"{name} must be a number >= 0 (inf disables the check), got {v!r}")
            object.__setattr__(self, name, float(v))


@dataclass(frozen=True, eq=False)
class RunSpec:
    """A run: ``map`` advanced ``steps`` steps from ``X0`` keeping every ``save_every``-th state (and the last).

    ``X0``: one state ``(n,)`` (an *orbit* directory) or a batch ``(B, n)`` (an *ensemble* directory);
    ``limits``: health thresholds; ``csv``: also write ``orbit.csv`` (orbits only); ``program``: the command
    named in ``run.json`` and in resume hints; ``stem``: the files of one orbit of a map with a time step
    (``map.dt``): ``"flow"`` (the default: ``flow.h5`` / ``flow.csv``, rows indexed by ``t = n dt``) or
    ``"orbit"`` (``orbit.h5`` / ``orbit.csv`` with both ``n`` and ``t``: ``jetgaudin orbit --dt``).  Validated
    once, here: the counts (integers in int64), the state (finite, real, length ``map.n_state``, integrals
    representable) and the map's set-up at ``X0`` (``map.start``: a branch point of ``ν`` is refused with
    :class:`jetgaudin.BranchPointError` whatever the layout).
    """

    map: Map
    X0: np.ndarray
    steps: int
    save_every: int = 1
    limits: HealthLimits = field(default_factory=HealthLimits)
    csv: bool = True
    program: str = "jetgaudin orbit"
    checkpoint_seconds: float = 1.0
    stem: str = "flow"
    #: private: the map's per-orbit set-up is solved at the start of every kernel call, not once per run (see
    #: :func:`run_map`); set by a resume for the run directories written that way (``run.json`` ``map_setup``)
    _per_chunk_setup: bool = field(default=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.map, Map):
            raise InvalidParameterError(f"map must be a jetgaudin.maps.Map, got {type(self.map).__name__}")
        if not self.map.properties.real:
            raise InvalidParameterError(
                f"{type(self.map).__name__} maps real states to complex ones; a run directory records real orbits "
                "only (iterate a complex map in memory with its iterate() method)"
            )
        X0, _ = as_state(self.X0, name="the initial state", block=block_size(self.map))
        if X0.ndim not in (1, 2):
            raise InvalidParameterError(f"X0 must be one state (n,) or a batch (B, n), got shape {X0.shape}")
        if self.map.n_state is not None and X0.shape[-1] != self.map.n_state:
            raise InvalidParameterError(f"X0 has {X0.shape[-1]} components, the map acts on {self.map.n_state}")
        if X0.size > _MAX_BATCH_VALUES:
            raise InvalidParameterError(f"X0 holds {X0.size} numbers; a run holds at most {_MAX_BATCH_VALUES}")
        object.__setattr__(self, "X0", np.ascontiguousarray(X0))
        object.__setattr__(self, "steps", check_count(self.steps, "steps"))
        object.__setattr__(self, "save_every", check_count(self.save_every, "save_every", 1))
        if not isinstance(self.limits, HealthLimits):
            raise InvalidParameterError("limits must be a HealthLimits")
        object.__setattr__(self, "checkpoint_seconds", self.check_checkpoint_seconds(self.checkpoint_seconds))
        if self.stem not in ("flow", "orbit"):
            raise InvalidParameterError(f"stem must be 'flow' or 'orbit', got {self.stem!r}")
        with np.errstate(all="ignore"):
            I0 = self.map.integrals(self.X0)
            if not np.all(np.isfinite(I0)):
                raise InvalidParameterError(
                    "the initial state is too large: its integrals overflow double precision; scale it down")
            # kept for the run's health (:meth:`integrals0`): the ensemble's integrals once, not twice (10^7 orbits:
            # seconds); a private attribute, recomputed by every RunSpec (dataclasses.replace included)
            object.__setattr__(self, "_integrals0", I0)
            if self.X0.shape[0] > 0 or self.X0.ndim == 1:
                carry = np.asarray(self.map.start(self.X0))
                if not np.all(np.isfinite(carry)):
                    raise InvalidParameterError(
                        "the map cannot be set up at the initial state (non-finite nu); b, eta or the state is "
                        "too large")

    @staticmethod
    def check_checkpoint_seconds(cs: object) -> float:
        """The checkpoint cadence: a finite number of seconds >= 0."""
        if isinstance(cs, bool) or not isinstance(cs, int | float) or not (0 <= cs < math.inf):
            raise InvalidParameterError(f"checkpoint_seconds must be a finite number >= 0, got {cs!r}")
        return float(cs)

    def integrals0(self) -> np.ndarray:
        """``map.integrals(X0)``, as computed by this spec's check (a copy; computed now if the spec has none)."""
        I0 = self.__dict__.get("_integrals0")
        return np.array(self.map.integrals(self.X0) if I0 is None else I0, dtype=float)

    @property
    def layout(self) -> Layout:
        return Layout.ORBIT if self.X0.ndim == 1 else Layout.ENSEMBLE

    @property
    def n_state(self) -> int:
        return int(self.X0.shape[-1])

    @property
    def B(self) -> int:
        return 1 if self.X0.ndim == 1 else int(self.X0.shape[0])


def run_map(spec: RunSpec) -> Map:
    """The map a run advances (the driver and a resume's replay): ``spec.map``, or, where its class has
    ``bind_run`` (the su(3) exact step), ``spec.map.bind_run(spec.X0)``: the map with its per-orbit set-up solved
    once per run at the initial states, not at every chunk.  A resume rebuilds ``X0`` from ``run.json`` bit for bit,
    so it solves once more and meets the same bits.  Kept on ``spec`` (one solve for the replay and the run).

    With ``spec._per_chunk_setup`` (a run directory written before runs were bound: ``run.json`` ``map_setup`` is
    ``"per_chunk"``, or such a run found by the replay, :mod:`jetgaudin.run.replay`): the map's ``unbound()``, which
    solves its set-up at the start of every kernel call, as those runs were written."""
    m = spec.__dict__.get("_run_map")
    if m is None:
        cls = type(spec.map)  # the class's methods: a wrapper forwarding attributes is not bound
        bind, unbind = getattr(cls, "bind_run", None), getattr(cls, "unbound", None)
        if spec._per_chunk_setup:
            m = unbind(spec.map) if callable(unbind) else spec.map
        else:
            m = bind(spec.map, spec.X0) if callable(bind) else spec.map
        object.__setattr__(spec, "_run_map", m)
    return m


def binds_per_run(spec: RunSpec) -> bool:
    """Whether :func:`run_map` solves the map's set-up once per run (its class has ``bind_run`` and the spec is not
    ``_per_chunk_setup``): only such a run may have been written the other way, per kernel call."""
    return callable(getattr(type(spec.map), "bind_run", None)) and not spec._per_chunk_setup
