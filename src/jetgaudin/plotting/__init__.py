r"""Figures of runs, orbits, the λ-plane and the map against its flow; animations of the moving top.

Figures are made on Matplotlib's Agg canvas outside pyplot (no display needed, nothing to close; a notebook
shows them as they are).  No mathematics here: everything numerical comes from the public API
(:func:`jetgaudin.integrals`, :func:`jetgaudin.material_point`, :func:`jetgaudin.nu`, …).  Every quantity
drawn is dimensionless (the paper's variables carry no units); the axes are named ``e₁, e₂, e₃``.

Run directories are read in slices (constant memory) by one function, :func:`open_run`; long runs are thinned
by a stated rule: at most ``max_points`` rows drawn, every ``k``-th saved row with ``k = ceil(rows /
max_points)`` and the last row; the drift figure shows, per bin of ``k`` rows, the largest drift.
"""

from __future__ import annotations

from ._animate import AnimationFormat, animate_run
from ._chains import figure_chain_integral_drift, figure_chain_y0, save_chain_figures, site_y0
from ._compare import figure_compare_drift, figure_map_flow_distance, save_compare_figures
from ._files import (
    DEFAULT_MAX_POINTS,
    FigureFormat,
    check_run_figures,
    run_title,
    save_figure,
    save_orbit_figures,
    save_run_figures,
)
from ._orbit import (
    figure_integral_drift,
    figure_points_3d,
    figure_projection,
    integral_labels,
    point_sets,
    sphere_label,
)
from ._runs import RunRows, open_run, thin_step
from ._spectral import default_region, figure_spectral_plane, nu_on_grid

__all__ = [
    "AnimationFormat",
    "DEFAULT_MAX_POINTS",
    "FigureFormat",
    "RunRows",
    "animate_run",
    "default_region",
    "figure_chain_integral_drift",
    "figure_chain_y0",
    "figure_compare_drift",
    "figure_integral_drift",
    "figure_map_flow_distance",
    "figure_points_3d",
    "figure_projection",
    "figure_spectral_plane",
    "integral_labels",
    "nu_on_grid",
    "open_run",
    "point_sets",
    "run_title",
    "save_chain_figures",
    "save_compare_figures",
    "save_figure",
    "save_orbit_figures",
    "check_run_figures",
    "save_run_figures",
    "site_y0",
    "sphere_label",
    "thin_step",
]
