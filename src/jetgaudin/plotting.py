r"""Figures of orbits (Appendix 2): the material point ``x − z`` and the centre of mass ``z`` in 3D with the
sphere ``|z| = const``, their ``x–y`` projection, and the drift of the 2N integrals.

Uses the Agg backend (no display needed).  No mathematics here: positions come from
:func:`jetgaudin.material_point`, integrals from :func:`jetgaudin.integrals`.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import jetgaudin as jg  # noqa: E402

__all__ = ["point_sets", "figure_points_3d", "figure_projection", "figure_integral_drift", "save_orbit_figures"]

_MAX_POINTS = 200_000  # larger orbits are thinned (evenly) for plotting only


def _thin(*arrays):
    n = len(arrays[0])
    if n <= _MAX_POINTS:
        return arrays
    idx = np.linspace(0, n - 1, _MAX_POINTS).astype(int)
    return tuple(a[idx] for a in arrays)


def point_sets(X) -> list[tuple[str, np.ndarray]]:
    """The point sets to draw for states ``X`` of shape ``(T, 3N)``: for ``N = 3`` the material point
    ``x − z`` and the centre of mass ``z`` (Appendix 2); otherwise ``y_0`` and the last block ``y_{N−1}``
    (which lies on the sphere ``|y_{N−1}|² = C_N``)."""
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    if N == 3:
        return [("material point x − z", jg.material_point(X)), ("centre of mass z", X[..., 6:9])]
    if N == 1:
        return [("y_0", X[..., 0:3])]
    return [("y_0", X[..., 0:3]), (f"y_{N - 1}", X[..., 3 * N - 3 :])]


def _sphere_block(X):
    N = X.shape[-1] // 3
    return X[..., 3 * N - 3 :]


def figure_points_3d(X, *, title: str = "", overlay=None, overlay_label: str = "flow"):
    """Figure 1: the ``N + N`` points in 3D and, faintly, the sphere ``|z| = |z(0)|``.

    ``overlay`` (optional, same shape as ``X``) is drawn as lines (e.g. the flow of ``G_η``)."""
    X = np.asarray(X, dtype=float)
    fig = plt.figure(figsize=(7.5, 7))
    ax = fig.add_subplot(projection="3d")
    r = float(np.linalg.norm(_sphere_block(X[0])))
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 48), np.linspace(0, np.pi, 24))
    ax.plot_wireframe(
        r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v), color="0.6", linewidth=0.3, alpha=0.35
    )
    colors = ["tab:blue", "tab:red"]
    for (label, P), c in zip(point_sets(X), colors, strict=False):
        (P,) = _thin(P)
        ax.scatter(P[:, 0], P[:, 1], P[:, 2], s=3, color=c, label=label, depthshade=False)
    if overlay is not None:
        for (label, P), c in zip(point_sets(overlay), colors, strict=False):
            (P,) = _thin(P)
            ax.plot(P[:, 0], P[:, 1], P[:, 2], color=c, linewidth=0.6, alpha=0.6, label=f"{label} ({overlay_label})")
    allp = np.concatenate([P for _, P in point_sets(X)] + [np.full((1, 3), r), np.full((1, 3), -r)])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    mid, half = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("component 1")
    ax.set_ylabel("component 2")
    ax.set_zlabel("component 3")
    ax.legend(loc="upper left", fontsize=8, markerscale=3)
    ax.set_title(title, fontsize=8)
    return fig


def figure_projection(X, *, title: str = "", overlay=None, overlay_label: str = "flow"):
    """Figure 2: the projection of figure 1 on the ``x–y`` (components 1–2) plane, with the circle ``|z| = r``."""
    X = np.asarray(X, dtype=float)
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    r = float(np.linalg.norm(_sphere_block(X[0])))
    th = np.linspace(0, 2 * np.pi, 200)
    ax.plot(r * np.cos(th), r * np.sin(th), color="0.6", linewidth=0.6, alpha=0.6, label=f"|z| = {r:.6g}")
    colors = ["tab:blue", "tab:red"]
    for (label, P), c in zip(point_sets(X), colors, strict=False):
        (P,) = _thin(P)
        ax.scatter(P[:, 0], P[:, 1], s=3, color=c, label=label)
    if overlay is not None:
        for (label, P), c in zip(point_sets(overlay), colors, strict=False):
            (P,) = _thin(P)
            ax.plot(P[:, 0], P[:, 1], color=c, linewidth=0.6, alpha=0.6, label=f"{label} ({overlay_label})")
    ax.set_aspect("equal")
    ax.set_xlabel("component 1")
    ax.set_ylabel("component 2")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, markerscale=3)
    ax.set_title(title, fontsize=8)
    return fig


def figure_integral_drift(n, X, b, *, title: str = "", xlabel: str = "step n"):
    r"""``|I_k(n) − I_k(0)|`` for the 2N integrals (``H_1..H_N, C_1..C_N``) on a log scale.

    Exact zeros (no drift at all) cannot be drawn on a log scale and are left out."""
    X = np.asarray(X, dtype=float)
    n, X = _thin(np.asarray(n), X)
    I = np.asarray(jg.integrals(X, b), dtype=float)
    d = np.abs(I - I[0])
    N = X.shape[-1] // 3
    names = [f"H_{k}" for k in range(1, N + 1)] + [f"C_{k}" for k in range(1, N + 1)]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, name in enumerate(names):
        mask = d[:, k] > 0
        ax.semilogy(n[mask], d[mask, k], ".", markersize=2, label=name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(r"$|I_k(n) - I_k(0)|$")
    ax.legend(ncol=min(2 * N, 6), fontsize=8, markerscale=4)
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(title, fontsize=8)
    return fig


def save_orbit_figures(
    out_dir, n, X, b, *, title: str = "", overlay=None, overlay_label: str = "flow", xlabel: str = "step n"
) -> list[Path]:
    """Write ``figure1.png``, ``figure2.png`` and ``integrals.png`` into ``out_dir``; return their paths."""
    out_dir = Path(out_dir)
    paths = []
    for name, fig in (
        ("figure1.png", figure_points_3d(X, title=title, overlay=overlay, overlay_label=overlay_label)),
        ("figure2.png", figure_projection(X, title=title, overlay=overlay, overlay_label=overlay_label)),
        ("integrals.png", figure_integral_drift(n, X, b, title=title, xlabel=xlabel)),
    ):
        path = out_dir / name
        fig.savefig(path, dpi=130, bbox_inches="tight")
        plt.close(fig)
        paths.append(path)
    return paths
