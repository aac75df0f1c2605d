r"""The map against the flow it interpolates: drifts on one figure, and the map-flow distance (private).

The real two-point map is the time-1 flow of ``G_η`` (docs/backlund.md): ``flow --compare`` samples the flow at
``t = n`` and iterates the map ``n`` times from the same state.  All quantities are dimensionless.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
import numpy as np

import jetgaudin as jg

from ._orbit import integral_labels, mark_dimensionless, new_figure, step_axis
from ._save import save_figure

__all__ = ["figure_compare_drift", "figure_map_flow_distance", "save_compare_figures"]


def _drift(X, b, model=None):
    X = np.asarray(X, dtype=float)
    I = np.asarray(jg.integrals(X, b) if model is None else model.integrals(X), dtype=float)
    return np.abs(I - I[0])


def _names(model, K: int) -> list[str]:
    """The panel titles: a top's ``H_1..H_N, C_1..C_N``; a chain's integral labels, its Casimirs marked."""
    if model is None:
        return integral_labels(K // 2)
    cas = np.asarray(model.casimir_mask(), dtype=bool)
    return [name + (" (Casimir)" if c else "") for name, c in zip(model.integral_labels(), cas, strict=True)]


def figure_compare_drift(t_flow, X_flow, n_map, X_map, b, *, title: str = "", model=None):
    """The integral drifts ``|I_k − I_k(0)|`` of the flow of ``G_η`` (grey line) and of the map (coloured
    points), one panel per integral (a top: ``H_1..H_N`` on the top row, ``C_1..C_N`` below; a chain ``model``:
    its integrals in the order of ``model.integral_labels()``, at most 4 panels a row), log scale, shared axes.

    One panel per integral keeps the 2N pairs of series apart (on one axis their 4N curves overlap).

    Parameters
    ----------
    t_flow : array_like, shape (T,)
        Times of the flow samples.
    X_flow : array_like, shape (T, 3N)
    n_map : array_like, shape (M,)
        Steps of the map (step ``n`` is compared with time ``t = n``).
    X_map : array_like, shape (M, 3N)
    b : float
        The top's field (not used with ``model``).
    title : str
    model : GaudinModel, optional
        A chain: its integrals (``model.integrals``) instead of the top's.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    Exact zeros cannot be drawn on a log scale and are left out; a panel says so when a series is all zeros.
    """
    df, dm = _drift(X_flow, b, model), _drift(X_map, b, model)
    t_flow, n_map = np.asarray(t_flow, dtype=float), np.asarray(n_map, dtype=float)
    K = df.shape[-1]
    rows = 2 if model is None else -(-K // 4)  # a chain: at most 4 panels a row, the rows filled evenly
    N = -(-K // rows)
    fig = new_figure(figsize=(3.2 * N + 1.0, 5.6 if model is None else 2.8 * rows))
    axes = np.asarray(fig.subplots(rows, N, sharex=True, sharey=True, squeeze=False))
    for ax in axes.flat[K:]:
        ax.set_visible(False)
    colors = mpl.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, name in enumerate(_names(model, K)):
        ax = axes[k // N, k % N]
        mf, mm = df[:, k] > 0, dm[:, k] > 0
        ax.semilogy(t_flow[mf], df[mf, k], "-", color="0.55", linewidth=0.8, label="flow of G_η (line)")
        ax.semilogy(n_map[mm], dm[mm, k], ".", color=colors[k % len(colors)], markersize=3, label="map (points)")
        zero = [w for w, m in (("flow", mf), ("map", mm)) if not m.any()]
        ax.set_title(name + (f" ({' and '.join(zero)}: exactly conserved)" if zero else ""), fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        step_axis(ax)
    for k in range(K - N, K):  # the lowest panel of each column
        axes[k // N, k % N].set_xlabel("step n = time t")
        axes[k // N, k % N].xaxis.set_tick_params(labelbottom=True)
    for ax in axes[:, 0]:
        ax.set_ylabel("|I − I(0)|")
    handles = [mpl.lines.Line2D([], [], color="0.55", linewidth=1.0),
               mpl.lines.Line2D([], [], color=colors[0], marker=".", linestyle="none", markersize=6)]
    fig.legend(handles, ["flow of G_η at t = n (line)", "map, step n (points)"], loc="lower left", ncol=2,
               fontsize=8, frameon=False)
    what = "2N" if model is None else K
    fig.suptitle((title + "\n" if title else "") + f"drift of the {what} integrals: the map against the flow it "
                 "interpolates", fontsize=8)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    mark_dimensionless(fig)
    return fig


def figure_map_flow_distance(n, distance, *, title: str = ""):
    """The distance ``|X_map(n) − X_flow(n)|`` (Euclidean norm of the states) over the steps, log scale.

    Parameters
    ----------
    n : array_like, shape (T,)
    distance : array_like, shape (T,)
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    n, distance = np.asarray(n, dtype=float), np.asarray(distance, dtype=float)
    fig = new_figure(figsize=(8, 4.5))
    ax = fig.subplots()
    m = distance > 0
    ax.semilogy(
        n[m], distance[m], ".-", markersize=2.5, linewidth=0.6, color="tab:purple", label="|X_map(n) − X_flow(n)|"
    )
    if m.any():
        ax.axhline(distance.max(), color="0.4", linestyle=":", linewidth=0.8, label=f"maximum {distance.max():.2e}")
    ax.set_xlabel("step n")
    step_axis(ax)
    ax.set_ylabel("Euclidean distance of the states")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.set_title((title + "\n" if title else "") + "distance between the map and the time-n flow of G_η", fontsize=8)
    fig.tight_layout()
    mark_dimensionless(fig)
    return fig


def save_compare_figures(
    out_dir, t_flow, X_flow, n_map, X_map, b, *, title: str = "", dpi: int = 130, fmt: str = "png", model=None
) -> list[Path]:
    """Write ``compare_drift.<fmt>`` and ``compare_distance.<fmt>``; the flow samples at ``t = n`` are matched
    with the map's step ``n`` for the distance (rows of equal index).

    Parameters
    ----------
    out_dir : path
    t_flow, X_flow, n_map, X_map, b, title, model
        As in :func:`figure_compare_drift` (``model``: a chain's run); ``X_flow[i]`` and ``X_map[i]`` must be the
        same time.
    dpi : int
    fmt : str

    Returns
    -------
    list of Path
    """
    out_dir = Path(out_dir)
    X_flow, X_map = np.asarray(X_flow, dtype=float), np.asarray(X_map, dtype=float)
    m = min(len(X_flow), len(X_map))
    dist = np.linalg.norm(X_map[:m] - X_flow[:m], axis=-1)
    paths = []
    for name, fig in (
        ("compare_drift", figure_compare_drift(t_flow, X_flow, n_map, X_map, b, title=title, model=model)),
        ("compare_distance", figure_map_flow_distance(np.asarray(n_map)[:m], dist, title=title)),
    ):
        paths.append(save_figure(fig, out_dir / f"{name}.{fmt}", dpi))
    return paths
