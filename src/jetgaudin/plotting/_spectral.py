r"""The spectral curve seen from the λ-plane: ``|ν²(λ)|`` and ``arg ν(λ)`` with the branch points (private).

``ν(λ)² = u² + v w = Σ_m κ_m λ^{-m}`` (:func:`jetgaudin.nu_squared`), single-valued with a pole of order ``2N``
at the site ``λ = 0``; its ``2N`` zeros are the branch points (:func:`jetgaudin.branch_points`).  ``ν(λ)`` is
drawn on the default branch of :func:`jetgaudin.nu`: the root positive at ``Re λ``, continued along the vertical
segment ``[Re λ, λ]`` — so the picture shows where that rule jumps (on the vertical half-lines from the branch
points away from the real axis).  Points where the rule is undefined (``Re λ = 0``, a branch point on the
segment) are left blank.  All quantities are dimensionless.
"""

from __future__ import annotations

import numpy as np

import jetgaudin as jg

from ._orbit import mark_dimensionless, new_figure

__all__ = ["nu_on_grid", "figure_spectral_plane", "default_region"]


def default_region(X, b, eta, sites=(0.0,)) -> tuple[float, float, float, float]:
    """``(re_min, re_max, im_min, im_max)``: a box holding the branch points, the sites, ``η`` and ``η̄``, with a
    margin of 25% of its size on each side."""
    bp = np.ravel(jg.branch_points(X, b))
    pts = np.concatenate([bp[np.isfinite(bp)], np.asarray(sites, dtype=complex), [eta, np.conj(eta)]])
    lo_r, hi_r, lo_i, hi_i = pts.real.min(), pts.real.max(), pts.imag.min(), pts.imag.max()
    size = max(hi_r - lo_r, hi_i - lo_i, 1e-3)
    m = 0.25 * size
    return lo_r - m, hi_r + m, lo_i - m, hi_i + m


def nu_on_grid(lam, X, b) -> np.ndarray:
    r"""``ν(λ)`` on the default branch at every point of the array ``lam``, ``NaN`` where the branch rule is
    undefined (``Re λ = 0`` or a branch point on ``[Re λ, λ]``).

    Parameters
    ----------
    lam : array_like of complex, shape (R, C)
        A grid whose columns share ``Re λ`` (as from ``np.meshgrid``); each column is evaluated in one call.
    X : array_like, shape (3N,)
    b : float

    Returns
    -------
    ndarray of complex, shape (R, C)
    """
    lam = np.asarray(lam, dtype=complex)
    out = np.full(lam.shape, np.nan + 0j)
    for j in range(lam.shape[1]):
        col = lam[:, j]
        try:
            out[:, j] = jg.nu(col, X, b)
            continue
        except jg.JetGaudinError:
            pass
        for i, z in enumerate(col):  # only the few columns through a branch point (or Re λ = 0) get here
            try:
                out[i, j] = jg.nu(z, X, b)
            except jg.JetGaudinError:
                pass
    return out


def figure_spectral_plane(X, b, eta, *, region=None, resolution: int = 241, sites=(0.0,), title: str = ""):
    r"""Two panels over a region of the λ-plane: ``log10 |ν²(λ)|`` and ``arg ν(λ)`` (default branch), with the
    branch points, the site(s), ``η`` and ``η̄`` and the vertical segment ``[η̄, η]`` through ``Re η`` of the
    branch rule marked.

    Parameters
    ----------
    X : array_like, shape (3N,)
        A real state.
    b : float
        Field strength.
    eta : complex
        The Bäcklund parameter.
    region : (float, float, float, float), optional
        ``(re_min, re_max, im_min, im_max)``; default :func:`default_region`.
    resolution : int
        Grid points per axis.
    sites : sequence of complex
        Poles of the Lax matrix (``λ = 0`` for the jet-extended models).
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    eta = complex(eta)
    X = np.asarray(X, dtype=float)
    N = X.shape[-1] // 3
    re0, re1, im0, im1 = default_region(X, b, eta, sites) if region is None else region
    # an even number of columns keeps the grid off Re λ = 0 when the region is symmetric
    re = np.linspace(re0, re1, resolution + (resolution % 2 == 1))
    im = np.linspace(im0, im1, resolution)
    lam = re[None, :] + 1j * im[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        pole = lam == 0  # the site itself: ν² has its pole there (left blank)
        nu2 = np.where(pole, np.nan, np.asarray(jg.nu_squared(np.where(pole, 1.0, lam), X, b)))
        logabs = np.log10(np.abs(nu2))
    nu = nu_on_grid(lam, X, b)
    bp = np.ravel(jg.branch_points(X, b))
    fig = new_figure(figsize=(13, 5.6))
    axes = fig.subplots(1, 2, sharey=True)
    ext = (re[0], re[-1], im[0], im[-1])
    finite = logabs[np.isfinite(logabs)]
    vmin, vmax = (np.percentile(finite, 1), np.percentile(finite, 99)) if finite.size else (None, None)
    im_a = axes[0].imshow(logabs, origin="lower", extent=ext, aspect="auto", cmap="viridis", vmin=vmin, vmax=vmax)
    fig.colorbar(im_a, ax=axes[0], label="log₁₀ |ν²(λ)|", shrink=0.85)
    axes[0].contour(re, im, logabs, levels=12, colors="white", linewidths=0.4, alpha=0.6)
    axes[0].set_title("log₁₀ |ν²(λ)|: zeros at the branch points, pole at the site", fontsize=9)
    im_b = axes[1].imshow(
        np.angle(nu),
        origin="lower",
        extent=ext,
        aspect="auto",
        cmap="twilight",
        vmin=-np.pi,
        vmax=np.pi,
        interpolation="nearest",
    )
    cb = fig.colorbar(im_b, ax=axes[1], label="arg ν(λ) (radians)", shrink=0.85)
    cb.set_ticks([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], labels=["−π", "−π/2", "0", "π/2", "π"])
    axes[1].set_title("arg ν(λ), default branch (positive at Re λ, continued vertically)", fontsize=9)
    for ax in axes:
        ax.plot([eta.real, eta.real], [-eta.imag, eta.imag], color="white", linewidth=2.2, zorder=3)
        ax.plot(
            [eta.real, eta.real],
            [-eta.imag, eta.imag],
            color="black",
            linewidth=1.0,
            zorder=4,
            label="segment [η̄, η] of the branch rule",
        )
        ax.plot(bp.real, bp.imag, "x", color="red", markersize=9, mew=2, zorder=5, label=f"{len(bp)} branch points")
        s = np.asarray(sites, dtype=complex)
        ax.plot(
            s.real,
            s.imag,
            "o",
            mfc="none",
            mec="orange",
            markersize=10,
            mew=2,
            zorder=5,
            label="site λ = 0 (pole)" if len(s) == 1 and s[0] == 0 else "sites (poles)",
        )
        ax.plot(
            [eta.real],
            [eta.imag],
            "^",
            color="magenta",
            markersize=8,
            zorder=6,
            label=f"η = {eta.real:g} {'+' if eta.imag >= 0 else '−'} {abs(eta.imag):g}i",
        )
        ax.plot([eta.real], [-eta.imag], "v", color="cyan", markersize=8, zorder=6, label="η̄")
        ax.set_xlabel("Re λ")
        ax.set_xlim(ext[0], ext[1])
        ax.set_ylim(ext[2], ext[3])
    axes[0].set_ylabel("Im λ")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.suptitle(title or f"Spectral curve in the λ-plane (N = {N}, b = {b:g}): ν² = u² + vw", fontsize=10)
    fig.subplots_adjust(bottom=0.17, top=0.88, wspace=0.12)
    mark_dimensionless(fig)
    return fig
