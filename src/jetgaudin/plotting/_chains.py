r"""Figures of chain orbits (issue 12): each site's ``y_0`` (its e₁–e₂ projection coloured by the step, and its
components against the step) and the drift of the ``2M`` integrals ``h_{i,m}`` on a log scale.

Uses the Agg backend (no display needed).  No mathematics here: the site layout comes from
:meth:`jetgaudin.gaudin.GaudinModel.labels` / ``offsets``, the integrals from
:meth:`jetgaudin.gaudin.GaudinModel.integrals`.  (To move into the ``plotting`` package with the other figures.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.ticker import FuncFormatter

from ._orbit import AXIS_LABELS, count_text, mark_dimensionless, new_figure, step_axis
from ._save import save_figure

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
    y = X.reshape(X.shape[:-1] + (model.M, getattr(model, "dim", 3)))  # su(n): n² − 1 components
    return y[..., list(model.offsets), :]


#: most sites drawn by :func:`figure_chain_y0` (one row of panels each)
MAX_SITES = 6


def figure_chain_y0(model, X, *, title: str = "", n=None, overlay=None, overlay_label: str = "map"):
    """Each site's ``y_0`` along the orbit, one row of panels per site (at most :data:`MAX_SITES`): left, its
    projection on the e₁–e₂ plane (su(n): the components along λ₁, λ₂) coloured by the step (colour bar), the start
    ringed; right, its three (su(n): n² − 1) components ``y_0^1, y_0^2, …`` against the step.  (A 3D cloud of all
    sites hides both the order of the points and which site moves how.)

    Parameters
    ----------
    model : GaudinModel
    X : array_like, shape (T, 3M)
    title : str
    n : array_like, shape (T,), optional
        The step of each row (default ``0, 1, …``).
    overlay : array_like, shape (T, 3M), optional
        Another orbit at the same steps (``flow --compare``: the map against the flow ``X``), drawn as black dots
        over the projection and as dots over each component's line.
    overlay_label : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    X = np.asarray(X, dtype=float)
    n = np.arange(len(X)) if n is None else np.asarray(n)
    w = X.shape[-1]
    if overlay is not None:  # thinned with the same rows as X
        X = np.concatenate([X, np.asarray(overlay, dtype=float)], axis=-1)
    n, X = _thin(n, X)
    Y = site_y0(model, X[:, :w])
    Z = None if overlay is None else site_y0(model, X[:, w:])
    S = min(Y.shape[1], MAX_SITES)
    fig = new_figure(figsize=(10, 2.9 * S + 0.9))
    axes = np.asarray(fig.subplots(S, 2, squeeze=False, gridspec_kw={"width_ratios": (1, 1.6)}))
    comp_colors = ("tab:blue", "tab:orange", "tab:green")
    for i in range(S):
        P = Y[:, i]
        ax, ax_t = axes[i]
        sc = ax.scatter(P[:, 0], P[:, 1], c=n, cmap="viridis", s=max(0.5, min(8.0, 1500.0 / len(P))), linewidths=0)
        if Z is not None:
            ax.plot(Z[:, i, 0], Z[:, i, 1], ".", color="black", markersize=2, label=overlay_label)
        ax.scatter(*P[0, :2], s=60, facecolors="none", edgecolors="red", linewidths=1.2, label="start")
        ax.set_aspect("equal", adjustable="datalim")
        su2 = P.shape[-1] == 3  # su(n), n ≥ 3: the components along the Gell-Mann λ₁, λ₂, not e₁, e₂
        ax.set_xlabel(AXIS_LABELS[0] if su2 else "y_0^1 (along λ₁)", fontsize=8)
        ax.set_ylabel(AXIS_LABELS[1] if su2 else "y_0^2 (along λ₂)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(f"y_0 of {_site_name(model, i)}", fontsize=8)
        cb = fig.colorbar(sc, ax=ax, shrink=0.85)
        cb.set_label("step n", fontsize=7)
        cb.ax.tick_params(labelsize=6)
        cb.formatter = FuncFormatter(lambda v, _pos: count_text(v))
        cb.update_ticks()
        for a in range(P.shape[-1]):  # su(n): all n² − 1 components
            color = comp_colors[a] if a < 3 else colormaps["tab10"](a % 10)
            ax_t.plot(n, P[:, a], linewidth=0.9, color=color, label=f"y_0^{a + 1}")
            if Z is not None:
                ax_t.plot(n, Z[:, i, a], ".", color=color, markersize=3)
        ax_t.set_ylabel("component", fontsize=8)
        ax_t.tick_params(labelsize=7)
        ax_t.grid(True, alpha=0.3)
        step_axis(ax_t)
        if i == 0:
            if Z is not None:
                ax_t.plot([], [], ".", color="0.3", markersize=5, label=f"{overlay_label} (dots)")
            ax_t.legend(fontsize=7, ncol=min(P.shape[-1], 4), loc="upper right")
            ax.legend(fontsize=7, loc="upper left")
    axes[-1, 1].set_xlabel("step n", fontsize=8)
    more = f" (first {S} of {Y.shape[1]} sites)" if Y.shape[1] > S else ""
    fig.suptitle((title + "\n" if title else "") + f"chain: y_0 of each site{more}", fontsize=8)
    fig.tight_layout()
    mark_dimensionless(fig)
    return fig


def _integral_label(name: str) -> str:
    """``h1,2`` → ``$h_{1,2}$``; an su(n) integral ``t3_h1,2`` (of ``tr ℓ³/3``) → ``$h^{(3)}_{1,2}$``."""
    if name.startswith("t") and "_h" in name:
        k, rest = name[1:].split("_h", 1)
        return f"$h^{{({k})}}_{{{rest}}}$"
    return f"$h_{{{name[1:]}}}$"


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
                    label=_integral_label(name) + (" (Casimir)" if cas[k] else ""))
    ax.set_xlabel(xlabel)
    step_axis(ax)
    ax.set_ylabel(r"$|h_{i,m}(n) - h_{i,m}(0)|$")
    ax.legend(ncol=1 + len(names) // 13, fontsize=7, markerscale=3, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title((title + "\n" if title else "") + "drift of the chain integrals", fontsize=8)
    mark_dimensionless(fig)
    return fig


def save_chain_figures(out_dir, n, X, model, *, title: str = "", xlabel: str = "step n", dpi: int = 130,
                       fmt: str = "png", overlay=None, overlay_label: str = "map") -> list[Path]:
    """Write ``chain_y0.<fmt>`` and ``chain_integrals.<fmt>`` into ``out_dir``; return their paths (``orbit``,
    ``flow`` and ``plot`` of a chain run; ``overlay``: another orbit drawn over ``chain_y0``, as
    :func:`figure_chain_y0`)."""
    out_dir = Path(out_dir)
    paths = []
    for name, fig in (("chain_y0", figure_chain_y0(model, X, title=title, n=n, overlay=overlay,
                                                   overlay_label=overlay_label)),
                      ("chain_integrals", figure_chain_integral_drift(n, model, X, title=title, xlabel=xlabel))):
        paths.append(save_figure(fig, out_dir / f"{name}.{fmt}", dpi))  # atomic, never through a symlink
    return paths
