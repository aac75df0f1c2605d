"""Writing the figures of a run: from arrays in memory, or streamed from a run directory (private).

:func:`save_run_figures` never holds a whole run in memory: the points are every ``k``-th saved row
(``k = ceil(rows / max_points)``, and the last row), and each point of the drift figure is the largest
``|I_k(n) − I_k(0)|`` over the ``k`` consecutive saved rows it stands for (drawn at the bin's first row),
computed block by block.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import jetgaudin as jg

from .._errors import InvalidParameterError
from ._orbit import count_text, figure_integral_drift, figure_points_3d, figure_projection
from ._runs import RunRows, open_run, thin_step, thinned_rows
from ._save import FigureFormat, save_figure  # below the figure modules (no import circle): re-exported here

__all__ = ["FigureFormat", "save_orbit_figures", "save_run_figures", "run_title", "save_figure", "DEFAULT_MAX_POINTS"]

DEFAULT_MAX_POINTS = 20_000
_BLOCK_ROWS = 1 << 14  # rows read at a time for the drift envelope (9 columns: ~1.2 MB)


def _eta_text(eta: complex | None) -> str:
    if eta is None:
        return "(none)"
    return f"{eta.real:g} {'+' if eta.imag >= 0 else '−'} {abs(eta.imag):g}i"


def _steps_text(steps) -> str:
    return "?" if steps is None else count_text(steps)


def run_title(run: RunRows) -> str:
    """A title a reader understands: what was iterated, with which parameters, from which state."""
    inp = run.inputs
    x0 = inp.get("init")
    start = f"; start (y₀, y₁, …) = ({', '.join(f'{v:g}' for v in x0)})" if x0 is not None and len(x0) <= 12 else ""
    if run.kind == "orbit" and run.dt is not None:  # orbit --dt: exact time steps of H, no η
        what = f"Exact time steps of H (run.json: its weights), dt = {run.dt:g}"
        return f"{what} (N = {run.N}): b = {run.b:g}, {_steps_text(inp.get('steps'))} steps{start}"
    if run.kind in ("orbit", "ensemble", "map"):
        what = "Real two-point Bäcklund map"
        if run.kind == "ensemble":
            what += f", orbit {run.orbit} of an ensemble of {inp.get('B')}"
        steps = inp.get("steps")
        return f"{what} (N = {run.N}): b = {run.b:g}, η = {_eta_text(run.eta)}, {_steps_text(steps)} steps{start}"
    ham = "G_η" if run.eta is not None else "H₂/2"
    eta = f", η = {_eta_text(run.eta)}" if run.eta is not None else ""
    return (
        f"Flow of {ham} (N = {run.N}): b = {run.b:g}{eta}, dt = {inp.get('dt', 1):g}, {_steps_text(inp.get('steps'))} "
        f"samples{start}"
    )


def save_orbit_figures(
    out_dir,
    n,
    X,
    b,
    *,
    title: str = "",
    overlay=None,
    overlay_label: str = "flow",
    xlabel: str = "step n",
    dpi: int = 130,
    fmt: FigureFormat | str = FigureFormat.png,
    note: str = "",
) -> list[Path]:
    """Write ``figure1``, ``figure2`` and ``integrals`` (``.png`` by default) of arrays held in memory.

    Parameters
    ----------
    out_dir : path
    n : array_like, shape (T,)
        Step numbers (or times).
    X : array_like, shape (T, 3N)
    b : float
    title, overlay, overlay_label, xlabel, note
        As in :func:`figure_points_3d` and :func:`figure_integral_drift`.
    dpi : int
    fmt : FigureFormat

    Returns
    -------
    list of Path
    """
    out_dir, fmt = Path(out_dir), FigureFormat(fmt)
    kw = {"title": title, "overlay": overlay, "overlay_label": overlay_label, "note": note}
    return [
        save_figure(figure_points_3d(X, **kw), out_dir / f"figure1.{fmt}", dpi),
        save_figure(figure_projection(X, **kw), out_dir / f"figure2.{fmt}", dpi),
        save_figure(
            figure_integral_drift(n, X, b, title=title, xlabel=xlabel, note=note), out_dir / f"integrals.{fmt}", dpi
        ),
    ]


def drift_envelope(run: RunRows, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(index, drift)``: per bin of ``k`` consecutive saved rows, the largest ``|I_j(n) − I_j(0)|`` of each
    integral, drawn at the bin's first row; shape ``(bins,)`` and ``(bins, 2N)``.  Reads the run in
    blocks of a multiple of ``k`` rows (constant memory)."""
    block = max(k, (_BLOCK_ROWS // k) * k)
    I0 = None
    idx_out, d_out = [], []
    for _start, idx, X in run.blocks(block):
        I = np.asarray(jg.integrals(X, run.b), dtype=float)
        if I0 is None:
            I0 = I[0]
        d = np.abs(I - I0)
        nb = -(-len(d) // k)
        pad = nb * k - len(d)
        dp = np.concatenate([d, np.full((pad, d.shape[1]), -1.0)]).reshape(nb, k, -1)
        ip = np.concatenate([idx, np.full(pad, idx[-1])]).reshape(nb, k)
        d_out.append(dp.max(axis=1))
        idx_out.append(ip[:, 0])  # each bin is drawn at its first row
    if not d_out:
        return np.zeros(0), np.zeros((0, 2 * run.N))
    return np.concatenate(idx_out), np.concatenate(d_out)


def check_run_figures(run_dir, *, orbit: int | None = None, dpi: int = 130, max_points: int = DEFAULT_MAX_POINTS):
    """Every refusal of :func:`save_run_figures`, read-only (the run opened, nothing written): the opened run.
    ``jetgaudin plot`` calls it before it takes the run directory's lock, so that a refusal changes nothing."""
    if not 10 <= int(dpi) <= 2000:
        raise InvalidParameterError(f"dpi must be between 10 and 2000, got {dpi}")
    if int(max_points) < 2:
        raise InvalidParameterError(f"max_points must be >= 2, got {max_points}")
    run = open_run(run_dir, orbit=orbit)
    if run.rows == 0:
        from .._errors import RecordingError

        raise RecordingError(f"{run_dir}: no saved row is declared safe in run.json yet; nothing to draw")
    return run


def save_run_figures(
    run_dir,
    out_dir=None,
    *,
    orbit: int | None = None,
    dpi: int = 130,
    fmt: FigureFormat | str = FigureFormat.png,
    max_points: int = DEFAULT_MAX_POINTS,
) -> list[Path]:
    """Redraw the figures of a finished or interrupted run from its files, in constant memory.

    Writes ``figure1``, ``figure2`` and ``integrals`` for an orbit run, one orbit of an ensemble (``orbit``) or
    a flow run; for a ``flow --compare`` run also ``compare_drift`` and ``compare_distance``; for an ensemble
    without ``orbit`` also ``ensemble_orbits`` (up to nine orbits side by side) and ``drift_hist`` (the
    distribution of the orbits' drift over the saved rows).

    Parameters
    ----------
    run_dir : path
    out_dir : path, optional
        Where to write (default: ``run_dir``).
    orbit : int, optional
        The orbit of an ensemble run (default 0).
    dpi : int
    fmt : FigureFormat
    max_points : int
        At most this many rows are drawn: every ``k``-th saved row, ``k = ceil(rows / max_points)``, and the last;
        the drift figure shows each bin's maximum.

    Returns
    -------
    list of Path

    Raises
    ------
    RecordingError
        Not a run directory, unreadable files, no safe row.
    InvalidParameterError
        ``dpi`` or ``max_points`` out of range.
    """
    run = check_run_figures(run_dir, orbit=orbit, dpi=dpi, max_points=max_points)
    fmt = FigureFormat(fmt)
    out_dir = Path(run_dir) if out_dir is None else Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    k = thin_step(run.rows, max_points)
    idx, X = thinned_rows(run, max_points)
    title = run_title(run)
    unit = "time t" if run.index_name == "t" else "step n"
    note = (
        f"all {count_text(run.rows)} saved rows drawn"
        if k == 1
        else f"one saved row in {count_text(k)} drawn (rows 0, {count_text(k)}, {count_text(2 * k)}, … and the last "
        f"of {count_text(run.rows)}); status: {run.status}"
    )
    if k == 1:
        note += f"; status: {run.status}"
    if run.chain is not None:  # a chain: each site's y_0 and the drift of its integrals h_(i,m) (not the top's)
        from ._chains import save_chain_figures

        what = f"orbit {run.orbit} of {run.inputs.get('B')}, " if run.kind == "ensemble" else ""
        return save_chain_figures(out_dir, idx, X, run.model(), title=f"{title}\nchain run ({what}{note})",
                                  xlabel=unit, dpi=dpi, fmt=fmt)
    overlay = None
    if run.kind == "flow" and run.inputs.get("compare"):
        mrun = open_run(run_dir, map_of_flow=True)
        _, overlay = thinned_rows(mrun, max_points)
        overlay, X = X, overlay  # the map as points, the flow as lines (as `flow --compare` draws them)
        title += "\npoints: the map, n = 0, 1, …; lines: the flow of G_η at t = n"
    kw = {"title": title, "note": note}
    paths = [
        save_figure(
            figure_points_3d(X, overlay=overlay, overlay_label="flow of G_η", **kw), out_dir / f"figure1.{fmt}", dpi
        ),
        save_figure(
            figure_projection(X, overlay=overlay, overlay_label="flow of G_η", **kw), out_dir / f"figure2.{fmt}", dpi
        ),
    ]
    d_idx, drift = drift_envelope(run, k)
    dnote = note if k == 1 else note + f"; each point: the largest drift over a bin of {k} rows"
    paths.append(
        save_figure(
            figure_integral_drift(d_idx, drift=drift, title=title, xlabel=unit, note=dnote),
            out_dir / f"integrals.{fmt}",
            dpi,
        )
    )
    if run.kind == "ensemble" and orbit is None:  # several orbits and the drift of all of them
        from ._ensemble import save_ensemble_figures

        paths += save_ensemble_figures(run, out_dir, max_points=max_points, dpi=dpi, fmt=fmt, title=run_title(run)
                                       .split(", orbit")[0] + f" (N = {run.N})")
    if overlay is not None:
        from ._compare import save_compare_figures

        n_f, X_f = run.read(0, run.rows)  # a flow run is held in memory by `flow` itself (bounded by its --steps)
        n_m, X_m = mrun.read(0, mrun.rows)
        paths += save_compare_figures(out_dir, n_f, X_f, n_m, X_m, run.b, title=title, dpi=dpi, fmt=fmt)
    return paths
