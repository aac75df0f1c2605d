"""Reading a run directory back: :func:`load` (any layout) and the rows ``run.json`` declares safe."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import RecordingError
from .files import ENSEMBLE_H5, ORBIT_H5, RowDigest, open_h5_read, read_run, unhex
from .spec import Layout, RunStatus

__all__ = ["RunData", "load"]


@dataclass(frozen=True)
class RunData:
    """A run directory's safe rows: ``n`` (rows,), ``X`` (rows, n) for an orbit or (rows, B, n) for an ensemble, the
    parsed ``run.json`` (``record``), its status and layout; ensembles also ``X0`` (B, n), ``b`` (B,), ``eta`` (B,)."""

    n: np.ndarray
    X: np.ndarray
    record: dict
    status: RunStatus
    layout: Layout
    X0: np.ndarray | None = None
    b: np.ndarray | None = None
    eta: np.ndarray | None = None

    @property
    def states(self) -> np.ndarray:
        """Alias of ``X`` (the name of ensemble runs)."""
        return self.X

    @property
    def last_state(self) -> np.ndarray:
        """The last safe saved state (``(n,)`` or ``(B, n)``), e.g. to start another run from it."""
        if len(self.n) == 0:
            raise RecordingError("the run holds no saved row")
        return self.X[-1]


def load(out_dir: str | Path, *, rows: slice | None = None, verify: bool = False) -> RunData:
    """The rows of a run directory that ``run.json`` declares safe (``rows``: a slice of them, to read part of a
    large run; rows beyond the checkpoint are never read).

    ``verify=True`` (a run to continue from, as ``--init-from`` does): ``run.json`` must match its digest, and every
    declared row its recorded SHA-256 (read in blocks, constant memory) -- the checks a resume makes before it
    trusts the rows (:class:`jetgaudin.RecordingError` otherwise)."""
    out_dir = Path(out_dir)
    run = read_run(out_dir, verify=verify)
    safe = int(run.get("checkpoint", {}).get("rows", 0))
    layout = Layout.ENSEMBLE if "B" in run.get("inputs", {}) else Layout.ORBIT
    name, data = (ENSEMBLE_H5, "states") if layout is Layout.ENSEMBLE else (ORBIT_H5, "X")
    if "dt" in run.get("map", {}):  # a flow map (its rows are indexed by time: flow.h5)
        name = "flow.h5"
    path = out_dir / name
    a, e, _ = (rows or slice(None)).indices(safe)
    try:
        with open_h5_read(path) as f:
            if f[data].shape[0] < safe or f["n"].shape[0] < safe:
                raise RecordingError(f"{path} holds fewer rows than run.json records: truncated")
            if verify:
                _verify_rows(f["n"], f[data], safe, run, path)
            n, X = f["n"][a:e], f[data][a:e]
            extra = {k: f[k][()] for k in ("X0", "b", "eta")} if layout is Layout.ENSEMBLE else {}
    except (OSError, KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, RecordingError):
            raise
        raise RecordingError(f"cannot read {path}: {exc}") from None
    return RunData(n=n, X=X, record=run, status=RunStatus.of(run), layout=layout, **extra)


def _verify_rows(dn, dS, safe: int, run: dict, path: Path) -> None:
    """The first ``safe`` rows must match ``run.json``'s ``rows_sha256`` (and an orbit's checkpoint, when it is on
    the last row, that row bit for bit)."""
    ck = run["checkpoint"]
    digest = RowDigest()
    block = max(1, (64 << 20) // max(1, 8 * int(np.prod(dS.shape[1:]))))
    for a in range(0, safe, block):
        e = min(safe, a + block)
        digest.update(dn[a:e], dS[a:e])
    if digest.hexdigest() != ck.get("rows_sha256"):
        raise RecordingError(f"{path} does not match the digest in run.json (corrupted or edited); cannot start "
                             "from it")
    if safe and "X_hex" in ck and int(ck["step"]) == int(dn[safe - 1]) and not np.array_equal(
            unhex(ck["X_hex"]), dS[safe - 1]):
        raise RecordingError(f"{path}: the checkpoint state is not the last saved row (corrupted or edited); cannot "
                             "start from it")
