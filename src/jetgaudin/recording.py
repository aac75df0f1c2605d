r"""Recording of long Bäcklund orbits (compatibility layer over :mod:`jetgaudin.run`).

An orbit run is the run layer's case of one state: :func:`run_orbit` builds a :class:`jetgaudin.run.RunSpec` for
:class:`jetgaudin.TwoPointBacklund` and calls :func:`jetgaudin.run.start` / :func:`jetgaudin.run.resume`.  The run
directory::

    DIR/orbit.h5     HDF5 (SWMR mode): datasets ``n`` (int64, rows) and ``X`` (float64, rows × 3N)
    DIR/orbit.csv    header ``n,y0^1,y0^2,y0^3,y1^1,...``; one row per saved step, 17 significant digits
    DIR/run.json     inputs, map, version, kernel, status, last safe step, checkpoint, integrals at n = 0, drifts

Guarantees: ``docs/reliability.md`` (rows at ``n ≡ 0 (mod save_every)`` and the last step; durable checkpoints;
resume bit for bit; one writer; SIGINT/SIGTERM honoured within a fraction of a second; health checks).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import _fs
from ._errors import InvalidParameterError, RecordingError
from ._validate import as_state
from .backlund.maps import _TWO_POINT_PROPERTIES, TwoPointBacklund
from .maps import Advance, Backend, Branch, Map, MapProperties, check_count, step_loop
from .run import api as _api
from .run.driver import RunInterrupted
from .run.files import (
    ORBIT_CSV,
    ORBIT_H5,
    RUN_JSON,
    csv_header,
    format_rows,
    one_line,
    read_csv,
    read_run,
    write_run,
)
from .run.load import load
from .run.spec import DEFAULT_MAX_DRIFT, DEFAULT_MAX_IMAG, HealthLimits, RunSpec, integral_names

__all__ = [
    "RecordingError",
    "RunInterrupted",
    "OrbitSpec",
    "RecordOptions",
    "HealthLimits",
    "RunResult",
    "run_orbit",
    "load_orbit",
    "read_run",
    "csv_header",
    "format_rows",
    "read_csv",
    "write_table",
    "integral_names",
    "DEFAULT_MAX_DRIFT",
    "DEFAULT_MAX_IMAG",
    "ORBIT_CSV",
    "ORBIT_H5",
    "RUN_JSON",
    "one_line",
    "update_run",
]

RunResult = _api.RunResult
_write_run = write_run


@dataclass(frozen=True)
class OrbitSpec:
    """The inputs that determine an orbit of the two-point map: field ``b``, ``η``, steps, ``X0`` (3N), branch
    (validated by the map and :class:`jetgaudin.run.RunSpec`: ``b ≠ 0``, ``Im η ≠ 0``, ``ν(η)`` defined at ``X0``)."""

    b: float
    eta: complex
    steps: int
    X0: tuple
    branch: str = "default"

    def __post_init__(self) -> None:
        X0, _ = as_state(np.asarray(self.X0, dtype=float), name="the initial state")
        if X0.ndim != 1:
            raise InvalidParameterError("the initial state must be one state of 3N numbers")
        object.__setattr__(self, "X0", tuple(float(v) for v in X0))
        object.__setattr__(self, "steps", check_count(self.steps, "steps"))
        B = TwoPointBacklund(self.b, self.eta, Branch.parse(self.branch))
        object.__setattr__(self, "b", B.b)
        object.__setattr__(self, "eta", B.eta)
        object.__setattr__(self, "branch", B.branch.value)
        RunSpec(B, X0, self.steps)  # the run's rules: state scale, nu(eta) at X0 (BranchPointError)

    @property
    def N(self) -> int:
        return len(self.X0) // 3

    def backlund(self, backend: Backend | str = Backend.AUTO) -> TwoPointBacklund:
        return TwoPointBacklund(self.b, self.eta, Branch.parse(self.branch), Backend.parse(backend))

    def to_json(self) -> dict:
        return {"b": self.b, "eta": [self.eta.real, self.eta.imag], "steps": self.steps, "init": list(self.X0),
                "branch": self.branch, "N": self.N}

    @classmethod
    def from_json(cls, d: dict) -> OrbitSpec:
        return cls(b=d["b"], eta=complex(*d["eta"]), steps=d["steps"], X0=tuple(d["init"]), branch=d["branch"])


@dataclass(frozen=True)
class RecordOptions:
    """How the orbit is recorded: every ``save_every``-th step, CSV or not, checkpoint cadence, kernel
    (a :class:`~jetgaudin.maps.Backend` or its value), rows per chunk."""

    save_every: int = 1
    csv: bool = True
    checkpoint_seconds: float = 1.0
    chunk_rows: int = 4096
    kernel: Backend | str = Backend.AUTO

    def __post_init__(self) -> None:
        object.__setattr__(self, "save_every", check_count(self.save_every, "save_every", 1))
        if not (self.checkpoint_seconds >= 0) or not math.isfinite(self.checkpoint_seconds):
            raise InvalidParameterError("checkpoint_seconds must be a finite number >= 0")
        object.__setattr__(self, "chunk_rows", check_count(self.chunk_rows, "chunk_rows", 1))
        object.__setattr__(self, "kernel", Backend.parse(self.kernel))


@dataclass(frozen=True, eq=False)
class _StepHook(Map):
    """Testing hook: any object with ``step(X, ν1) -> (X̆, ν1, imag)`` driven as the NumPy route."""

    inner: Any
    reference: TwoPointBacklund
    properties: MapProperties = _TWO_POINT_PROPERTIES

    def integrals(self, X: np.ndarray) -> np.ndarray:
        return self.reference.integrals(X)

    def start(self, X: np.ndarray) -> np.ndarray:
        return self.reference.start(X)

    def step(self, X: np.ndarray, carry: Any = None) -> tuple[np.ndarray, Any, np.ndarray]:
        return self.inner.step(X, carry)

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        return step_loop(self, np.asarray(X, dtype=float), carry, steps, save_every)

    def inverse(self) -> Map:
        raise NotImplementedError

    def describe(self) -> dict:
        return self.reference.describe()


def resolve_kernel(kernel: Backend | str, steps: int = 0, n_state: int = 9) -> str:
    """``"auto"`` -> the kernel :func:`jetgaudin.backlund.auto_kernel` picks for ``steps`` steps of one orbit."""
    from .backlund import auto_kernel

    k = Backend.parse(kernel)
    return auto_kernel(steps, n_state) if k is Backend.AUTO else k.value


def run_orbit(spec: OrbitSpec | None, out_dir: str | Path, *, options: RecordOptions | None = None,
              limits: HealthLimits | None = None, resume: bool = False, expect: dict | None = None,
              progress: Callable[[int, int], None] | None = None, handle_signals: bool = True,
              backlund: Any = None, overwrite: bool = False) -> _api.RunResult:
    """Iterate the real two-point map and stream the orbit into ``out_dir`` (see the module doc).

    ``resume=True`` continues the run recorded in ``out_dir`` (``spec`` and ``limits`` ignored; ``options`` gives
    only the checkpoint cadence and the chunk size; ``expect``: input names of ``run.json["inputs"]`` mapped to the
    values the user gave, a difference is refused).  ``backlund`` (testing hook): an object with
    ``step(X, ν1) -> (X̆, ν1, imag_residue)`` used instead of the map (NumPy route).

    Returns a :class:`jetgaudin.run.RunResult`; raises :class:`RunInterrupted` on SIGINT/SIGTERM and
    :class:`RecordingError` (or its subclasses) for unusable directories.
    """
    options = options or RecordOptions()
    run_opts: dict[str, Any] = dict(progress=progress, handle_signals=handle_signals, chunk_rows=options.chunk_rows)
    if resume:
        return _api.resume(out_dir, expect=expect, checkpoint_seconds=options.checkpoint_seconds,
                           program="jetgaudin orbit", **run_opts)
    if spec is None:
        raise InvalidParameterError("spec is required for a new run")
    m: Map = spec.backlund(Backend.parse(options.kernel))
    if backlund is not None:
        m = _StepHook(backlund, spec.backlund(Backend.NUMPY))
    rs = RunSpec(m, np.array(spec.X0), spec.steps, options.save_every, limits or HealthLimits(), csv=options.csv,
                 program="jetgaudin orbit", checkpoint_seconds=options.checkpoint_seconds)
    return _api.start(rs, out_dir, overwrite=overwrite, **run_opts)


def load_orbit(out_dir: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """``(n, X)`` of a run directory: only the rows safely on disk (``run.json``'s checkpoint)."""
    d = load(out_dir)
    return d.n, d.X


def write_table(out_dir: str | Path, stem: str, index: Any, X: Any, *, index_name: str = "n",
                attrs: dict | None = None) -> list[Path]:
    """Write ``stem.csv`` and ``stem.h5`` (datasets ``index_name`` and ``X``) atomically (no link followed)."""
    import h5py

    out_dir = Path(out_dir)
    X = np.asarray(X, dtype=float)
    index = np.asarray(index)
    N = X.shape[-1] // 3
    _fs.atomic_write_text(out_dir, f"{stem}.csv", csv_header(N, index_name) + format_rows(index.tolist(), X))
    tmp = f"{stem}.h5.tmp"
    _fs.remove_file(out_dir, tmp)
    try:
        with h5py.File(out_dir / tmp, "w") as f:
            f.create_dataset(index_name, data=index)
            f.create_dataset("X", data=X)
            for k, v in (attrs or {}).items():
                f.attrs[k] = v
        os.replace(out_dir / tmp, out_dir / f"{stem}.h5")
        _fs.fsync_dir(out_dir)
    finally:
        _fs.remove_file(out_dir, tmp)
    return [out_dir / f"{stem}.csv", out_dir / f"{stem}.h5"]


def update_run(out_dir: str | Path, **fields: Any) -> None:
    """Add top-level fields to ``run.json`` atomically (e.g. the list of figures written)."""
    run = read_run(out_dir)
    run.update(fields)
    write_run(out_dir, run)

