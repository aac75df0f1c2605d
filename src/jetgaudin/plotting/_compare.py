r"""The map against the flow it interpolates: drifts on one figure, and the map-flow distance (private).

The real two-point map is the time-1 flow of ``G_η`` (docs/backlund.md): ``flow --compare`` samples the flow at
``t = n`` and iterates the map ``n`` times from the same state.  All quantities are dimensionless.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
import numpy as np

import jetgaudin as jg

from ._files import save_figure
from ._orbit import integral_labels, new_figure

__all__ = ["figure_compare_drift", "figure_map_flow_distance", "save_compare_figures"]


def _drift(X, b):
    I = np.asarray(jg.integrals(np.asarray(X, dtype=float), b), dtype=float)
    return np.abs(I - I[0])


def figure_compare_drift(t_flow, X_flow, n_map, X_map, b, *, title: str = ""):
    """The integral drifts ``|I_k − I_k(0)|`` of the flow of ``G_η`` (lines) and of the map (points), one colour
    per integral, on a log scale.

    Parameters
    ----------
    t_flow : array_like, shape (T,)
        Times of the flow samples.
    X_flow : array_like, shape (T, 3N)
    n_map : array_like, shape (M,)
        Steps of the map (step ``n`` is compared with time ``t = n``).
    X_map : array_like, shape (M, 3N)
    b : float
    title : str

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    Exact zeros cannot be drawn on a log scale and are left out.
    """
    df, dm = _drift(X_flow, b), _drift(X_map, b)
    t_flow, n_map = np.asarray(t_flow, dtype=float), np.asarray(n_map, dtype=float)
    N = df.shape[-1] // 2
    fig = new_figure(figsize=(9.5, 5))
    ax = fig.subplots()
    colors = mpl.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, name in enumerate(integral_labels(N)):
        c = colors[k % len(colors)]
        mf, mm = df[:, k] > 0, dm[:, k] > 0
        ax.semilogy(t_flow[mf], df[mf, k], "-", color=c, linewidth=1.0, label=f"{name}: flow of G_η (line)")
        ax.semilogy(n_map[mm], dm[mm, k], ".", color=c, markersize=3, label=f"{name}: map (points)")
    ax.set_xlabel("step n of the map = time t of the flow (dimensionless)")
    ax.set_ylabel("|I_k − I_k(0)| (dimensionless)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, markerscale=2)
    ax.set_title(
        (title + "\n" if title else "") + "drift of the 2N integrals: flow of G_η (lines) and map (points)", fontsize=8
    )
    fig.tight_layout()
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
    ax.set_xlabel("step n (dimensionless)")
    ax.set_ylabel("Euclidean distance of the states (dimensionless)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.set_title((title + "\n" if title else "") + "distance between the map and the time-n flow of G_η", fontsize=8)
    fig.tight_layout()
    return fig


def save_compare_figures(
    out_dir, t_flow, X_flow, n_map, X_map, b, *, title: str = "", dpi: int = 130, fmt: str = "png"
) -> list[Path]:
    """Write ``compare_drift.<fmt>`` and ``compare_distance.<fmt>``; the flow samples at ``t = n`` are matched
    with the map's step ``n`` for the distance (rows of equal index).

    Parameters
    ----------
    out_dir : path
    t_flow, X_flow, n_map, X_map, b, title
        As in :func:`figure_compare_drift`; ``X_flow[i]`` and ``X_map[i]`` must be the same time.
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
        ("compare_drift", figure_compare_drift(t_flow, X_flow, n_map, X_map, b, title=title)),
        ("compare_distance", figure_map_flow_distance(np.asarray(n_map)[:m], dist, title=title)),
    ):
        paths.append(save_figure(fig, out_dir / f"{name}.{fmt}", dpi))
    return paths
