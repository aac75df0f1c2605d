r"""Figures of an ensemble: the distribution of the orbits' integral drift, and several orbits side by side
(private).

``drift_hist`` answers "how do the orbits drift?" (one histogram per integral of the per-orbit relative drift
``max_n |I_m(X_n) − I_m(X_0)| / max(1, |I_m(X_0)|)``, with the quantiles of
:func:`jetgaudin.ensemble.drift_quantiles` marked); ``ensemble_orbits`` shows up to nine orbits spread over the
ensemble (orbits ``0, B/8, …, B − 1``), each as the e₁–e₂ projection of figure 2.  No mathematics here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..ensemble import DRIFT_QUANTILES, drift_quantiles
from ._orbit import POINT_COLORS, count_text, integral_labels, mark_dimensionless, new_figure, point_sets

__all__ = ["figure_drift_histogram", "figure_ensemble_orbits", "spread_orbits", "save_drift_histogram",
           "save_ensemble_figures"]

#: most orbits drawn side by side by :func:`figure_ensemble_orbits`
MAX_PANELS = 9


def figure_drift_histogram(drift, names=None, *, title: str = "", q=DRIFT_QUANTILES):
    """One histogram per integral of the orbits' relative drift ``drift[:, m]`` (``drift``: ``(B, 2N)``), on
    logarithmic bins, with the quantiles ``q`` drawn as vertical lines (labelled in the legend with their values).

    Orbits whose drift is exactly 0 cannot sit on a log axis: each panel states how many there are.

    Returns
    -------
    matplotlib.figure.Figure
    """
    d = np.asarray(drift, dtype=float)
    B, K = d.shape
    names = list(names) if names is not None else integral_labels(K // 2)
    quant = drift_quantiles(d, q)
    cols = max(1, (K + 1) // 2) if K > 1 else 1
    rows = -(-K // cols)
    fig = new_figure(figsize=(3.1 * cols + 0.8, 2.7 * rows + 0.9))
    axes = np.asarray(fig.subplots(rows, cols, squeeze=False))
    pos = d[d > 0]
    lo, hi = (np.log10(pos.min()), np.log10(pos.max())) if pos.size else (-17.0, -15.0)
    edges = np.logspace(np.floor(lo), np.ceil(hi) + (hi == lo), 31)
    styles = ("--", "-.", ":", "-")
    for m in range(rows * cols):
        ax = axes[m // cols, m % cols]
        if m >= K:
            ax.set_visible(False)
            continue
        col = d[:, m]
        ax.hist(col[col > 0], bins=edges, color="tab:blue", alpha=0.75)
        ax.set_xscale("log")
        for j, (qq, val) in enumerate(zip(np.atleast_1d(q), quant[:, m], strict=True)):
            if val > 0:
                lab = "max" if qq == 1 else f"{100 * qq:g} %"
                ax.axvline(val, color="0.15", linestyle=styles[j % len(styles)], linewidth=0.9,
                           label=f"{lab}: {val:.1e}")
        zeros = int(np.sum(col == 0))
        ax.set_title(names[m] + (f" ({zeros} orbits with drift 0)" if zeros else ""), fontsize=9)
        if ax.lines:
            ax.legend(fontsize=6.5, loc="upper left", frameon=False)
        if m % cols == 0:
            ax.set_ylabel("orbits")
        if m // cols == rows - 1 or m + cols >= K:
            ax.set_xlabel("relative drift")
    fig.suptitle((title + "\n" if title else "") + f"relative drift of the integrals over {count_text(B)} orbits: "
                 "max_n |I(X_n) − I(X_0)| / max(1, |I(X_0)|)", fontsize=8)
    fig.tight_layout()
    mark_dimensionless(fig)
    return fig


def spread_orbits(B: int, k: int = MAX_PANELS) -> list[int]:
    """Up to ``k`` orbit indices spread evenly over ``0..B−1`` (always the first and the last)."""
    if B <= 0:
        return []
    return sorted({int(i) for i in np.linspace(0, B - 1, min(k, B)).round()})


def figure_ensemble_orbits(orbits, *, title: str = "", drift=None):
    """Several orbits of an ensemble side by side: panel ``i`` is the e₁–e₂ projection of the point sets of
    orbit ``i`` (figure 2's material point and centre of mass for N = 3).

    Parameters
    ----------
    orbits : list of (int, ndarray of shape (T, 3N))
        The orbit's index in the ensemble and its states.
    drift : array_like, shape (B,), optional
        Each orbit's largest relative drift, named in its panel's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(orbits)
    cols = min(3, max(1, n))
    rows = -(-n // cols)
    fig = new_figure(figsize=(3.3 * cols, 3.3 * rows + 0.8))
    axes = np.asarray(fig.subplots(rows, cols, squeeze=False))
    for p in range(rows * cols):
        ax = axes[p // cols, p % cols]
        if p >= n:
            ax.set_visible(False)
            continue
        i, X = orbits[p]
        for (label, P), c in zip(point_sets(np.asarray(X, dtype=float)), POINT_COLORS, strict=False):
            ax.scatter(P[:, 0], P[:, 1], s=max(0.3, min(6.0, 600.0 / len(P))), color=c, linewidths=0,
                       label=label if p == 0 else None)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=7)
        extra = f", drift {np.asarray(drift)[i]:.1e}" if drift is not None else ""
        ax.set_title(f"orbit {i}{extra}", fontsize=8)
        if p % cols == 0:
            ax.set_ylabel("e₂")
        if p // cols == rows - 1:
            ax.set_xlabel("e₁")
    fig.legend(loc="lower center", ncol=2, fontsize=8, markerscale=4, frameon=False)
    fig.suptitle((title + "\n" if title else "") + f"{n} orbits of the ensemble, e₁–e₂ projection", fontsize=8)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    mark_dimensionless(fig)
    return fig


def save_drift_histogram(out_dir, drift, names=None, *, title: str = "", dpi: int = 130, fmt: str = "png") -> Path:
    """Write ``drift_hist.<fmt>`` (:func:`figure_drift_histogram`) into ``out_dir``; return its path."""
    from ._save import save_figure

    return save_figure(figure_drift_histogram(drift, names, title=title), Path(out_dir) / f"drift_hist.{fmt}", dpi)


def _ensemble_drift(run) -> np.ndarray:
    """Each orbit's relative drift over the saved rows of the ensemble ``run`` (a :class:`RunRows` of kind
    ``"ensemble"``), ``(B, 2N)``, read in blocks of rows (constant memory); the run's own table (``run.json``'s
    summary) also counts chunk ends between saved rows, so this one can only be smaller or equal."""
    import h5py

    from .._errors import RecordingError
    from ..ensemble import per_orbit_integrals

    B, n = int(run.inputs["B"]), 3 * run.N
    block = max(1, (1 << 23) // max(1, B * n))  # ~64 MB of states per block
    try:
        with h5py.File(run.path, "r", swmr=True) as f:
            b = np.asarray(f["b"][:], dtype=float)
            I0 = per_orbit_integrals(np.asarray(f["states"][0], dtype=float), b)
            scale = np.maximum(1.0, np.abs(I0))
            drift = np.zeros_like(I0)
            for a in range(0, run.rows, block):
                X = np.asarray(f["states"][a:min(a + block, run.rows)], dtype=float)
                drift = np.maximum(drift, np.max(np.abs(per_orbit_integrals(X, b) - I0) / scale, axis=0))
    except (OSError, KeyError) as exc:
        raise RecordingError(f"cannot read {run.path}: {exc}") from None
    return drift


def save_ensemble_figures(run, out_dir, *, max_points: int, dpi: int, fmt: str, title: str) -> list[Path]:
    """``plot`` of an ensemble: ``ensemble_orbits`` (up to nine orbits spread over the ensemble) and
    ``drift_hist`` (the per-orbit drift over the saved rows) into ``out_dir``."""
    from ._runs import open_run, thinned_rows
    from ._save import save_figure

    drift = _ensemble_drift(run)
    picks = spread_orbits(int(run.inputs["B"]))
    orbits = [(i, thinned_rows(open_run(run.run_dir, orbit=i), max_points)[1]) for i in picks]
    fig = figure_ensemble_orbits(orbits, title=title, drift=drift.max(axis=-1))
    return [save_figure(fig, Path(out_dir) / f"ensemble_orbits.{fmt}", dpi),
            save_drift_histogram(out_dir, drift, title=title + "\n(over the saved rows)", dpi=dpi, fmt=fmt)]
