r"""Figures of one orbit (Appendix 2): the points in 3D with their sphere, the projection, the integral drift (private).

For ``N = 3`` the points are the material point ``x − z`` and the centre of mass ``z`` of the top (Section 4,
Appendix 2), and ``z`` lies on the sphere ``|z|² = C^(3)``; for other ``N`` they are ``y_0`` and the last block
``y_{N−1}``, which lies on the sphere ``|y_{N−1}|² = C_N``.  Every quantity is dimensionless (the paper's
variables carry no units).  No mathematics here: positions come from :func:`jetgaudin.material_point`,
integrals from :func:`jetgaudin.integrals`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import jetgaudin as jg

__all__ = [
    "point_sets",
    "sphere_label",
    "figure_points_3d",
    "figure_projection",
    "figure_integral_drift",
    "integral_labels",
    "AXIS_LABELS",
    "POINT_COLORS",
    "new_figure",
    "DIMENSIONLESS_NOTE",
    "mark_dimensionless",
    "count_text",
    "step_axis",
]

#: the axes' names; that every quantity is dimensionless is said once per figure (:func:`mark_dimensionless`)
AXIS_LABELS = ("e₁", "e₂", "e₃")
DIMENSIONLESS_NOTE = "all quantities are dimensionless"
POINT_COLORS = ("tab:blue", "tab:red")
SPHERE_STYLE: dict[str, Any] = {"color": "0.15", "linewidth": 0.6, "alpha": 0.55}


def new_figure(**kwargs) -> Figure:
    """A Matplotlib figure on the Agg canvas, outside pyplot: no global state, nothing to close, and any backend
    (a notebook's inline one included) can display it."""
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def mark_dimensionless(fig) -> None:
    """Say once, in the figure's bottom-right corner, that every quantity drawn is dimensionless (the paper's
    variables carry no units), instead of on every axis."""
    fig.text(0.995, 0.005, DIMENSIONLESS_NOTE, ha="right", va="bottom", fontsize=7, color="0.35")


def count_text(n) -> str:
    """A step count as people read it: thousands separators below 10⁶ (``12,345``), powers of ten from 10⁶ on
    (``10⁶``, ``2.5×10⁷``); non-integers as ``%g``."""
    x = float(n)
    if not np.isfinite(x) or x != round(x):
        return f"{x:g}"
    if abs(x) < 1e6:
        return f"{int(x):,}"
    e = int(np.floor(np.log10(abs(x))))
    m = x / 10.0**e
    sup = str(e).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return (f"10{sup}" if m == 1 else f"{m:.3g}×10{sup}").replace("-10", "−10")


def step_axis(ax, axis: str = "x") -> None:
    """Tick labels of a step (or time) axis formatted by :func:`count_text` (``1,000``, ``10⁶``) instead of
    Matplotlib's ``1e6`` offset text."""
    from matplotlib.ticker import FuncFormatter

    getattr(ax, f"{axis}axis").set_major_formatter(FuncFormatter(lambda v, _pos: count_text(v)))


def point_sets(X) -> list[tuple[str, np.ndarray]]:
    """The point sets to draw for states ``X`` of shape ``(T, 3N)``: for ``N = 3`` the material point
    ``x − z`` and the centre of mass ``z`` (Appendix 2); otherwise ``y_0`` and the last block ``y_{N−1}``
    (which lies on the sphere ``|y_{N−1}|² = C_N``); for ``N = 1`` only ``y_0``.

    Parameters
    ----------
    X : array_like, shape (T, 3N)

    Returns
    -------
    list of (str, ndarray of shape (T, 3))
        Label and points of each set.
    """
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    if N == 3:
        return [("material point x − z", jg.material_point(X)), ("centre of mass z", X[..., 6:9])]
    if N == 1:
        return [("y₀", X[..., 0:3])]
    return [("y₀", X[..., 0:3]), (f"y_{N - 1}", X[..., 3 * N - 3 :])]


def _sphere_block(X):
    N = X.shape[-1] // 3
    return X[..., 3 * N - 3 :]


def sphere_label(N: int, r: float) -> str:
    """Legend label of the invariant sphere: ``|z| = r`` for ``N = 3``, ``|y_{N−1}| = r`` otherwise."""
    block = "z" if N == 3 else ("y₀" if N == 1 else f"y_{N - 1}")
    return f"sphere |{block}| = {r:.6g} (invariant)"


def integral_labels(N: int) -> list[str]:
    """``["H_1", …, "H_N", "C_1", …, "C_N"]``: the names of the 2N integrals of Prop. 2."""
    return [f"H_{k}" for k in range(1, N + 1)] + [f"C_{k}" for k in range(1, N + 1)]


def _marker_size(T: int) -> float:
    """Scatter marker area ``3000 / T`` pt², clipped to [0.3, 10]: large for a few points, small for dense clouds."""
    return float(np.clip(3000.0 / max(T, 1), 0.3, 10.0))


def _equal_limits(ax, pts, r, dims=3):
    allp = np.concatenate([p[:, :dims] for p in pts] + [np.full((1, dims), r), np.full((1, dims), -r)])
    finite = allp[np.all(np.isfinite(allp), axis=1)]
    lo, hi = finite.min(axis=0), finite.max(axis=0)
    mid, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-12) * 1.05
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    if dims == 3:
        ax.set_zlim(mid[2] - half, mid[2] + half)


def figure_points_3d(X, *, title: str = "", overlay=None, overlay_label: str = "flow", note: str = ""):
    """Figure 1: the ``N + N`` points in 3D and, drawn on top in dark grey, the sphere ``|z| = |z(0)|``.

    Parameters
    ----------
    X : array_like, shape (T, 3N)
        The states to draw (already thinned by the caller if needed).
    title : str
        Figure title (a second line ``note`` may say how the points were thinned).
    overlay : array_like, shape (T', 3N), optional
        Drawn as lines in the colours of the points (e.g. the flow of ``G_η``).
    overlay_label : str
        Legend suffix of the overlay.
    note : str
        Smaller text under the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    fig = new_figure(figsize=(7.5, 7.8))
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    r = float(np.linalg.norm(_sphere_block(X[0])))
    sets = point_sets(X)
    for (label, P), c in zip(sets, POINT_COLORS, strict=False):
        ax.scatter(
            P[:, 0],
            P[:, 1],
            P[:, 2],
            s=_marker_size(len(P)),
            color=c,
            label=label,
            depthshade=False,
            zorder=1,
            linewidths=0,
        )
    if overlay is not None:
        for (label, P), c in zip(point_sets(overlay), POINT_COLORS, strict=False):
            ax.plot(
                P[:, 0],
                P[:, 1],
                P[:, 2],
                color=c,
                linewidth=0.8,
                alpha=0.7,
                label=f"{label} ({overlay_label})",
                zorder=2,
            )
    # the sphere on top of the points, so that a dense cloud cannot hide it
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(
        r * np.cos(u) * np.sin(v),
        r * np.sin(u) * np.sin(v),
        r * np.cos(v),
        zorder=3,
        label=sphere_label(N, r),
        **SPHERE_STYLE,
    )
    ax.scatter([0], [0], [0], s=25, color="black", marker="+", label="origin (fixed point)", zorder=4)
    _equal_limits(ax, [P for _, P in sets], r)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel(AXIS_LABELS[0])
    ax.set_ylabel(AXIS_LABELS[1])
    ax.set_zlabel(AXIS_LABELS[2])
    fig.legend(loc="lower center", ncol=2, fontsize=8, markerscale=3, frameon=False)
    fig.suptitle(title, fontsize=9)
    if note:
        ax.set_title(note, fontsize=7, color="0.3")
    fig.subplots_adjust(bottom=0.12, top=0.9)
    mark_dimensionless(fig)
    return fig


def figure_projection(X, *, title: str = "", overlay=None, overlay_label: str = "flow", note: str = ""):
    """Figure 2: the projection of figure 1 on the ``e₁–e₂`` plane, with the circle of radius ``|z(0)|``.

    Parameters and return value as :func:`figure_points_3d`.
    """
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    fig = new_figure(figsize=(8.8, 6.2))
    ax = fig.subplots()
    r = float(np.linalg.norm(_sphere_block(X[0])))
    sets = point_sets(X)
    for (label, P), c in zip(sets, POINT_COLORS, strict=False):
        ax.scatter(P[:, 0], P[:, 1], s=_marker_size(len(P)), color=c, label=label, zorder=1, linewidths=0)
    if overlay is not None:
        for (label, P), c in zip(point_sets(overlay), POINT_COLORS, strict=False):
            ax.plot(P[:, 0], P[:, 1], color=c, linewidth=0.8, alpha=0.7, label=f"{label} ({overlay_label})", zorder=2)
    th = np.linspace(0, 2 * np.pi, 400)
    ax.plot(
        r * np.cos(th),
        r * np.sin(th),
        zorder=3,
        label=sphere_label(N, r).replace("sphere", "equator of"),
        **SPHERE_STYLE,
    )
    ax.set_aspect("equal")
    _equal_limits(ax, [P for _, P in sets], r, dims=2)
    ax.set_xlabel(AXIS_LABELS[0])
    ax.set_ylabel(AXIS_LABELS[1])
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, markerscale=3)
    ax.set_title(title + (f"\n{note}" if note else ""), fontsize=8)
    fig.tight_layout()
    mark_dimensionless(fig)
    return fig


def figure_integral_drift(n, X=None, b=None, *, title: str = "", xlabel: str = "step n", drift=None, note: str = ""):
    r"""``|I_k(n) − I_k(0)|`` for the 2N integrals (``H_1..H_N, C_1..C_N``) on a log scale.

    Parameters
    ----------
    n : array_like, shape (T,)
        Step numbers (or times) of the rows.
    X : array_like, shape (T, 3N), optional
        States; the drift is computed from them with :func:`jetgaudin.integrals` (row 0 is the reference).
    b : float
        Field strength (needed with ``X``).
    drift : array_like, shape (T, 2N), optional
        Precomputed drifts (e.g. the per-bin maxima of a thinned long run) instead of ``X``.
    title, xlabel, note : str

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    Exact zeros (no drift at all) cannot be drawn on a log scale and are left out; an integral that never
    drifts is named in the legend as "exactly conserved".
    """
    n = np.asarray(n)
    if drift is None:
        X = np.asarray(X, dtype=float)
        I = np.asarray(jg.integrals(X, b), dtype=float)
        drift = np.abs(I - I[0])
    d = np.asarray(drift, dtype=float)
    N = d.shape[-1] // 2
    fig = new_figure(figsize=(9, 4.8))
    ax = fig.subplots()
    for k, name in enumerate(integral_labels(N)):
        mask = d[:, k] > 0
        label = name if mask.any() else f"{name} (exactly conserved)"
        ax.semilogy(n[mask], d[mask, k], ".", markersize=2.5, label=label)
    ax.set_xlabel(xlabel)
    step_axis(ax)
    ax.set_ylabel("|I_k(n) − I_k(0)|")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, markerscale=4)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(title + (f"\n{note}" if note else ""), fontsize=8)
    fig.tight_layout()
    mark_dimensionless(fig)
    return fig
