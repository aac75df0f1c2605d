"""Reading a run directory for plotting, in slices (constant memory) (private).

All reading of run directories by the plotting code goes through :func:`open_run`: it reads ``run.json``
with :func:`jetgaudin.recording.read_run` and returns a :class:`RunRows` whose :meth:`RunRows.read` takes
row slices of the HDF5 file with h5py, so that no figure ever holds a whole run in memory.

**Thinning rule** (:func:`thin_step`): a run of ``R`` saved rows drawn with at most ``M`` points uses every
``k``-th saved row, ``k = ceil(R / M)``, i.e. rows ``0, k, 2k, …`` and always the last row.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import RecordingError

__all__ = ["RunRows", "open_run", "thin_step", "thinned_rows"]


@dataclass(frozen=True)
class RunRows:
    """The safe rows of one orbit of a run directory (an orbit run, one orbit of an ensemble, or a flow run).

    ``kind`` is ``"orbit"``, ``"ensemble"`` or ``"flow"``; ``rows`` the number of rows ``run.json`` declares
    safe; ``index_name`` ``"n"`` (step) or ``"t"`` (time); ``b`` the field, ``eta`` the Bäcklund parameter
    (``None`` for the physical flow); ``orbit`` the chosen orbit of an ensemble (else ``None``)."""

    run_dir: Path
    kind: str
    path: Path
    dataset: str
    index_name: str
    rows: int
    N: int
    b: float
    eta: complex | None
    orbit: int | None
    status: str
    inputs: dict
    #: the map description of a chain run (``run.json`` ``"map"``, kind ``chain_*``: ``b``, ``sites``, ``family``,
    #: ``gamma``), else ``None``; :meth:`model` builds its :class:`jetgaudin.GaudinModel`
    chain: dict | None = None
    #: the time step of an exact-flow orbit run (``orbit --dt``: ``run.json`` ``"map"`` ``"dt"``), else ``None``
    dt: float | None = None

    def model(self):
        """The :class:`jetgaudin.GaudinModel` of a chain run (``None`` for a run of the top)."""
        if self.chain is None:
            return None
        from ..gaudin import GaudinModel

        return GaudinModel.from_description(self.chain)

    def read(self, start: int, stop: int, step: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """``(index, X)`` of the rows ``start:stop:step`` (clipped to the safe rows); ``X`` of shape ``(k, 3N)``."""
        from ..run.files import open_h5_read

        stop = min(stop, self.rows)
        try:
            # a regular file only (a FIFO or a link is refused, never waited on), complete; SWMR after a kill
            with open_h5_read(self.path) as f:
                idx = np.asarray(f[self.index_name][start:stop:step])
                ds = f[self.dataset]
                X = ds[start:stop:step] if self.orbit is None else ds[start:stop:step, self.orbit, :]
        except (OSError, KeyError) as exc:
            raise RecordingError(f"cannot read {self.path}: {exc}") from None
        return idx, np.asarray(X, dtype=float)

    def blocks(self, block_rows: int) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """``(start, index, X)`` for consecutive blocks of ``block_rows`` rows covering every safe row."""
        for start in range(0, self.rows, block_rows):
            idx, X = self.read(start, start + block_rows)
            yield start, idx, X


def thin_step(rows: int, max_points: int) -> int:
    """``k = ceil(rows / max_points)`` (at least 1): draw every ``k``-th saved row (and the last)."""
    if max_points < 2:
        raise RecordingError(f"max_points must be >= 2, got {max_points}")
    return max(1, math.ceil(rows / max_points))


def thinned_rows(run: RunRows, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """The rows ``0, k, 2k, …`` and the last one (:func:`thin_step`), read in one strided slice."""
    k = thin_step(run.rows, max_points)
    idx, X = run.read(0, run.rows, k)
    if run.rows and (run.rows - 1) % k:
        i_last, X_last = run.read(run.rows - 1, run.rows)
        idx, X = np.concatenate([idx, i_last]), np.concatenate([X, X_last])
    return idx, X


def _field(b) -> float:
    """The recorded field ``b`` as a number: itself, or for an su(n) field of ``n² − 1`` components its ``λ_3``
    component (the whole field stays in the map's description)."""
    return float(b[2]) if isinstance(b, list) and len(b) >= 3 else float(b)


def open_run(run_dir, *, orbit: int | None = None, map_of_flow: bool = False) -> RunRows:
    """Open the run in ``run_dir`` for reading in slices: an orbit, ensemble or flow run (the one place that reads
    run directories for plotting; the run layer's file names and ``run.json`` fields are used here only).

    Parameters
    ----------
    run_dir : path
        A directory written by ``jetgaudin orbit``, ``ensemble`` or ``flow`` (finished or interrupted).
    orbit : int, optional
        The orbit of an ensemble to read (default 0); must be ``None`` or 0 for an orbit or flow run.
    map_of_flow : bool
        For a ``flow --compare`` run: the map's orbit (``orbit.h5``) instead of the flow (``flow.h5``).

    Returns
    -------
    RunRows

    Raises
    ------
    RecordingError
        No ``run.json``, an unknown program, a missing data file or an orbit number out of range.
    """
    from .. import recording as rec

    run_dir = Path(run_dir)
    if not (run_dir / rec.RUN_JSON).is_file():
        raise RecordingError(f"{run_dir} holds no run.json: not a jetgaudin run directory")
    run = rec.read_run(run_dir)
    program, inp = run.get("program", ""), run.get("inputs", {})
    status = str(run.get("status", "unknown"))
    safe = int(run.get("checkpoint", {}).get("rows", 0))
    # the map's own description (run layer) names b and eta; runs written before it keep them in "inputs"
    described: dict = run["map"] if isinstance(run.get("map"), dict) else {}
    sun = described.get("algebra", "su(2)") != "su(2)"  # an su(n) chain (issue 32): always the chain figures
    chain = described if str(described.get("kind", "")).startswith("chain_") or sun else None
    if chain is not None and len(chain["sites"]) == 1 and chain["sites"][0][1] == 3 and "family" not in chain \
            and not sun:
        chain = None  # one rational site of order 3 is the paper's top: its figures (as `orbit --sites` draws it)
    common = dict(run_dir=run_dir, status=status, inputs=inp, chain=chain)
    if program == "jetgaudin orbit":
        if orbit not in (None, 0):
            raise RecordingError(f"{run_dir} is an orbit run: --orbit must be 0 or omitted, got {orbit}")
        try:
            b_run = _field(described.get("b", inp.get("b")))
            # an exact-flow run (orbit --dt) has a time step and no eta
            eta = None if "dt" in described else complex(*described.get("eta", inp.get("eta")))
        except (TypeError, ValueError):
            raise RecordingError(f"{run_dir}/run.json names no field b and parameter eta; cannot draw it") from None
        return RunRows(kind="orbit", path=run_dir / rec.ORBIT_H5, dataset="X", index_name="n", rows=safe,
                       N=int(inp["N"]), b=b_run, eta=eta, orbit=None,
                       dt=float(described["dt"]) if "dt" in described else None, **common)
    if program == "jetgaudin ensemble":
        from ..ensemble_recording import ENSEMBLE_H5

        k = 0 if orbit is None else int(orbit)
        B = int(inp["B"])
        if not 0 <= k < B:
            raise RecordingError(f"--orbit: the ensemble in {run_dir} has orbits 0..{B - 1}, got {orbit}")
        from ..run.files import open_h5_read

        try:
            with open_h5_read(run_dir / ENSEMBLE_H5) as f:
                b, eta = float(f["b"][k]), complex(f["eta"][k])
        except (OSError, KeyError) as exc:
            raise RecordingError(f"cannot read {run_dir / ENSEMBLE_H5}: {exc}") from None
        return RunRows(kind="ensemble", path=run_dir / ENSEMBLE_H5, dataset="states", index_name="n", rows=safe,
                       N=int(inp["N"]), b=b, eta=eta, orbit=k, **common)
    if program == "jetgaudin flow":
        if orbit not in (None, 0):
            raise RecordingError(f"{run_dir} is a flow run: --orbit must be 0 or omitted, got {orbit}")
        from ..run.files import open_h5_read

        path = run_dir / ("orbit.h5" if map_of_flow else "flow.h5")
        index_name = "n" if map_of_flow else "t"
        try:
            with open_h5_read(path) as f:
                rows = int(f["X"].shape[0])
        except (OSError, KeyError) as exc:
            raise RecordingError(f"cannot read {path}: {exc}") from None
        eta_flow = complex(*inp["eta"]) if inp.get("hamiltonian") == "interpolating" else None
        try:  # a chain flow records its field in the map's description only
            b_flow = _field(described.get("b", inp.get("b")))
        except (TypeError, ValueError):
            raise RecordingError(f"{run_dir}/run.json names no field b; cannot draw it") from None
        return RunRows(kind="map" if map_of_flow else "flow", path=path, dataset="X", index_name=index_name,
                       rows=rows, N=int(inp["N"]), b=b_flow, eta=eta_flow, orbit=None, **common)
    raise RecordingError(f"{run_dir}/run.json was written by {program!r}, not by jetgaudin orbit, ensemble or flow")
