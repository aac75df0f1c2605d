"""The figures show what the caption of the paper's Figure 1 describes: the N + N points x - z (material point) and
z (centre of mass) in 3D with the sphere |z| = const, their x-y projection, and the integral drift."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import jetgaudin as jg  # noqa: E402
from jetgaudin import plotting  # noqa: E402

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0  # noqa: E402


@pytest.fixture(scope="module")
def orbit():
    return jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 1000)


def _scatter_points(ax):
    """{label: (n, dim) array of the plotted points} of the scatter collections of an axes."""
    out = {}
    for c in ax.collections:
        if c.get_label() and not c.get_label().startswith("_") and hasattr(c, "_offsets3d"):
            out[c.get_label()] = np.column_stack([np.asarray(a, dtype=float) for a in c._offsets3d])
        elif c.get_label() and not c.get_label().startswith("_") and len(c.get_offsets()):
            out[c.get_label()] = np.asarray(c.get_offsets(), dtype=float)
    return out


def test_figure1_shows_material_point_and_centre_of_mass_on_the_sphere(orbit):
    fig = plotting.figure_points_3d(orbit)
    try:
        (ax,) = fig.axes
        pts = _scatter_points(ax)
        assert set(pts) == {"material point x − z", "centre of mass z"}
        # 1000 + 1000 points (and the initial one): exactly the orbit's x - z and z
        np.testing.assert_array_equal(pts["material point x − z"], orbit[:, 3:6] - orbit[:, 6:9])
        np.testing.assert_array_equal(pts["centre of mass z"], orbit[:, 6:9])
        # the faint sphere: a wireframe of radius |z(0)| = 1 (every vertex at distance 1 from the origin)
        (wire,) = [c for c in ax.collections if not hasattr(c, "_offsets3d")]
        seg = np.concatenate([np.asarray(s) for s in wire._segments3d])
        np.testing.assert_allclose(np.linalg.norm(seg, axis=1), 1.0, rtol=1e-12)
        assert wire.get_alpha() < 0.5
    finally:
        plt.close(fig)


def test_figure2_is_the_xy_projection(orbit):
    fig = plotting.figure_projection(orbit)
    try:
        (ax,) = fig.axes
        pts = _scatter_points(ax)
        np.testing.assert_array_equal(pts["material point x − z"], orbit[:, 3:5] - orbit[:, 6:8])
        np.testing.assert_array_equal(pts["centre of mass z"], orbit[:, 6:8])
        (circle,) = ax.lines
        np.testing.assert_allclose(np.hypot(*circle.get_data()), 1.0, rtol=1e-12)
    finally:
        plt.close(fig)


def test_integral_drift_figure_has_the_2N_curves(orbit):
    n = np.arange(len(orbit))
    fig = plotting.figure_integral_drift(n, orbit, APPENDIX2_B)
    try:
        (ax,) = fig.axes
        assert ax.get_yscale() == "log"
        labels = [ln.get_label() for ln in ax.lines]
        assert labels == ["H_1", "H_2", "H_3", "C_1", "C_2", "C_3"]
        d = np.abs(jg.integrals(orbit, APPENDIX2_B) - jg.integrals(orbit[0], APPENDIX2_B))
        for k, ln in enumerate(ax.lines):  # each curve is |I_k(n) - I_k(0)| where it is nonzero
            x, y = ln.get_data()
            np.testing.assert_array_equal(y, d[d[:, k] > 0, k])
            np.testing.assert_array_equal(x, n[d[:, k] > 0])
    finally:
        plt.close(fig)


@pytest.mark.parametrize("N", [2, 4])
def test_other_N_plot_y0_and_the_last_block(N):
    rng = np.random.default_rng(N)
    X = rng.normal(size=(20, 3 * N))
    labels = [lab for lab, _ in plotting.point_sets(X)]
    assert labels == ["y_0", f"y_{N - 1}"]
    fig = plotting.figure_points_3d(X)
    try:
        pts = _scatter_points(fig.axes[0])
        np.testing.assert_array_equal(pts[f"y_{N - 1}"], X[:, 3 * N - 3 :])
    finally:
        plt.close(fig)
