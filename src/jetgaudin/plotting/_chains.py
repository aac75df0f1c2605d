r"""Figures of chain orbits (issue 12): the trajectory of each site's ``y_0`` in 3D (one colour per site) and the
drift of the ``2M`` integrals ``h_{i,m}`` on a log scale.

Uses the Agg backend (no display needed).  No mathematics here: the site layout comes from
:meth:`jetgaudin.gaudin.GaudinModel.labels` / ``offsets``, the integrals from
:meth:`jetgaudin.gaudin.GaudinModel.integrals`.  (To move into the ``plotting`` package with the other figures.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps

from ._files import save_figure
from ._orbit import AXIS_LABELS, new_figure

__all__ = ["site_y0", "figure_chain_y0", "figure_chain_integral_drift", "save_chain_figures"]

_MAX_POINTS = 200_000  # larger orbits are thinned (evenly) for plotting only


def _thin(n: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(n) <= _MAX_POINTS:
        return n, X
    idx = np.linspace(0, len(n) - 1, _MAX_POINTS).astype(int)
    return n[idx], X[idx]


def _site_name(model, i: int) -> str:
    p, N = model.sites[i]
    return f"site {i + 1} (λ = {p:g}, N = {N})"


def site_y0(model, X) -> np.ndarray:
    """``y_0`` of every site along the orbit ``X`` ``(T, 3M)``: shape ``(T, n_sites, 3)``."""
    X = model.check_state(X)
    y = X.reshape(X.shape[:-1] + (model.M, 3))
    return y[..., list(model.offsets), :]


def figure_chain_y0(model, X, *, title: str = ""):
    """The trajectories of the sites' ``y_0`` in 3D (dimensionless components ``e_1, e_2, e_3``), one colour per
    site; the start of each trajectory is marked with a ring."""
    X = np.asarray(X, dtype=float)
    _, X = _thin(np.arange(len(X)), X)
    Y = site_y0(model, X)
    fig = new_figure(figsize=(7.5, 7))
    ax = fig.add_subplot(projection="3d")
    colors = colormaps["tab10"]
    for i in range(Y.shape[1]):
        P = Y[:, i]
        c = colors(i % 10)
        ax.plot(P[:, 0], P[:, 1], P[:, 2], ".", markersize=2, color=c, label=f"y_0 of {_site_name(model, i)}")
        ax.scatter(*P[0], s=40, facecolors="none", edgecolors=[c], linewidths=1.2)
    ax.set_xlabel(AXIS_LABELS[0])
    ax.set_ylabel(AXIS_LABELS[1])
    ax.set_zlabel(AXIS_LABELS[2])
    ax.legend(loc="upper left", fontsize=8, markerscale=4)
    ax.set_title((title + "\n" if title else "") + "chain: y_0 of each site (ring: start)", fontsize=8)
    return fig


def figure_chain_integral_drift(n, model, X, *, title: str = "", xlabel: str = "step n"):
    r"""``|h_{i,m}(n) − h_{i,m}(0)|`` of the ``2M`` integrals on a log scale (Hamiltonians ``m ≤ N_i`` as dots,
    Casimirs ``m > N_i`` as crosses).  Exact zeros (no drift at all) cannot be drawn on a log scale and are left
    out."""
    n, X = _thin(np.asarray(n), np.asarray(X, dtype=float))
    I = model.integrals(X)
    d = np.abs(I - I[0])
    names = model.integral_labels()
    cas = model.casimir_mask()
    fig = new_figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    colors = colormaps["tab20"]
    for k, name in enumerate(names):
        mask = d[:, k] > 0
        ax.semilogy(n[mask], d[mask, k], "x" if cas[k] else ".", markersize=3 if cas[k] else 2, color=colors(k % 20),
                    label=f"$h_{{{name[1:]}}}$" + (" (Casimir)" if cas[k] else ""))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(r"$|h_{i,m}(n) - h_{i,m}(0)|$ (dimensionless)")
    ax.legend(ncol=1 + len(names) // 13, fontsize=7, markerscale=3, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title((title + "\n" if title else "") + "drift of the chain integrals", fontsize=8)
    return fig


def save_chain_figures(out_dir, n, X, model, *, title: str = "", xlabel: str = "step n") -> list[Path]:
    """Write ``chain_y0.png`` and ``chain_integrals.png`` into ``out_dir``; return their paths."""
    out_dir = Path(out_dir)
    paths = []
    for name, fig in (("chain_y0.png", figure_chain_y0(model, X, title=title)),
                      ("chain_integrals.png", figure_chain_integral_drift(n, model, X, title=title, xlabel=xlabel))):
        paths.append(save_figure(fig, out_dir / name, 130))  # atomic, never through a symlink
    return paths
