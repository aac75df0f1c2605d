"""The figures show what they claim, checked on their content (the plotted data, the labels), not on file existence.

The paper's Figure 1 shows the N + N points x - z (material point) and z (centre of mass) in 3D with the sphere
|z| = const; Figure 2 its x-y projection.  Run directories are read in slices; a long run is thinned by the stated
rule (every k-th saved row, k = ceil(rows / max_points), and the last) and drawn in bounded memory.
"""

import tracemalloc

import matplotlib

matplotlib.use("Agg")

import h5py  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import jetgaudin as jg  # noqa: E402
from jetgaudin import plotting  # noqa: E402
from jetgaudin.plotting import _files  # noqa: E402
from jetgaudin.recording import OrbitSpec, RecordOptions, load_orbit, run_orbit  # noqa: E402

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0  # noqa: E402


def _says_dimensionless_once(fig):
    """'dimensionless' is said once per figure (a figure text), on no axis label or title."""
    texts = [t.get_text() for t in fig.texts]
    assert sum("dimensionless" in t for t in texts) == 1, texts
    for ax in fig.axes:
        labels = [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()] + ([ax.get_zlabel()] if ax.name == "3d" else [])
        assert not any("dimensionless" in lab for lab in labels), labels


@pytest.fixture(scope="module")
def orbit():
    return jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 1000)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """The Appendix 2 run (1000 steps, every row saved) written by the run layer."""
    d = tmp_path_factory.mktemp("runs") / "appendix2"
    spec = OrbitSpec(b=APPENDIX2_B, eta=APPENDIX2_ETA, steps=1000, X0=tuple(APPENDIX2_X0))
    assert run_orbit(spec, d, options=RecordOptions(csv=False)).status == "completed"
    return d


def _scatter_points(ax):
    """{label: (n, dim) array of the plotted points} of the scatter collections of an axes."""
    out = {}
    for c in ax.collections:
        lab = c.get_label()
        if not lab or lab.startswith("_"):
            continue
        if hasattr(c, "_offsets3d"):
            out[lab] = np.column_stack([np.asarray(a, dtype=float) for a in c._offsets3d])
        elif len(c.get_offsets()):
            out[lab] = np.asarray(c.get_offsets(), dtype=float)
    return out


def _capture(monkeypatch):
    """Record every figure that the plotting package writes (its content is checked, then it is saved)."""
    seen = {}
    real = _files.save_figure

    def spy(fig, path, dpi):
        seen[path.name] = fig
        fig_copy = {"axes": fig.axes, "texts": [t.get_text() for t in fig.texts]}
        seen[path.name + ":content"] = fig_copy
        return real(fig, path, dpi)

    monkeypatch.setattr(_files, "save_figure", spy)
    import jetgaudin.plotting._compare as cmp
    import jetgaudin.plotting._save as sv  # where the ensemble figures import it from, on use

    monkeypatch.setattr(sv, "save_figure", spy)

    monkeypatch.setattr(cmp, "save_figure", spy)
    return seen


# ------------------------------------------------------------------------------------------------ figure 1 and 2
def test_figure1_shows_material_point_and_centre_of_mass_with_the_sphere_on_top(orbit):
    fig = plotting.figure_points_3d(orbit)
    try:
        (ax,) = fig.axes
        pts = _scatter_points(ax)
        # 1000 + 1000 points (and the initial one): exactly the orbit's x - z and z
        np.testing.assert_array_equal(pts["material point x − z"], orbit[:, 3:6] - orbit[:, 6:9])
        np.testing.assert_array_equal(pts["centre of mass z"], orbit[:, 6:9])
        # the sphere: a wireframe of radius |z(0)| = 1 (every vertex at distance 1 from the origin, to rounding),
        # drawn after and above the points in a visible (not faint) style
        (wire,) = [c for c in ax.collections if c.get_label().startswith("sphere")]
        seg = np.concatenate([np.asarray(s) for s in wire._segments3d])
        np.testing.assert_allclose(np.linalg.norm(seg, axis=1), 1.0, rtol=1e-12)
        assert wire.get_label() == "sphere |z| = 1 (invariant)"
        assert wire.get_alpha() >= 0.5 and ax.computed_zorder is False
        point_sets = [c for c in ax.collections if c.get_label() in ("material point x − z", "centre of mass z")]
        assert len(point_sets) == 2 and wire.get_zorder() > max(c.get_zorder() for c in point_sets)
        assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == plotting._orbit.AXIS_LABELS
        _says_dimensionless_once(fig)
        # the legend is outside the axes (below them): it cannot cover a point
        (leg,) = fig.legends
        assert fig.transFigure.inverted().transform(leg.get_window_extent(fig.canvas.get_renderer()))[1, 1] < 0.12
    finally:
        plt.close(fig)


def test_figure2_is_the_e1_e2_projection(orbit):
    fig = plotting.figure_projection(orbit)
    try:
        (ax,) = fig.axes
        pts = _scatter_points(ax)
        np.testing.assert_array_equal(pts["material point x − z"], orbit[:, 3:5] - orbit[:, 6:8])
        np.testing.assert_array_equal(pts["centre of mass z"], orbit[:, 6:8])
        (circle,) = ax.lines
        np.testing.assert_allclose(np.hypot(*circle.get_data()), 1.0, rtol=1e-12)
        assert circle.get_zorder() > 1 and "|z| = 1" in circle.get_label()
        assert ax.get_legend().get_bbox_to_anchor().x0 > ax.get_window_extent().x1 - 1  # legend right of the axes
    finally:
        plt.close(fig)


def test_integral_drift_figure_has_the_2N_curves(orbit):
    n = np.arange(len(orbit))
    fig = plotting.figure_integral_drift(n, orbit, APPENDIX2_B)
    try:
        (ax,) = fig.axes
        assert ax.get_yscale() == "log"
        labels = [ln.get_label() for ln in ax.lines]
        d = np.abs(jg.integrals(orbit, APPENDIX2_B) - jg.integrals(orbit[0], APPENDIX2_B))
        # an integral the orbit keeps bit for bit (H_1 = 2b y^3 on the compiled N = 3 route) is named so
        names = ["H_1", "H_2", "H_3", "C_1", "C_2", "C_3"]
        assert labels == [nm if d[:, k].any() else f"{nm} (exactly conserved)" for k, nm in enumerate(names)]
        for k, ln in enumerate(ax.lines):  # each curve is |I_k(n) - I_k(0)| where it is nonzero
            x, y = ln.get_data()
            np.testing.assert_array_equal(y, d[d[:, k] > 0, k])
            np.testing.assert_array_equal(x, n[d[:, k] > 0])
        _says_dimensionless_once(fig)
    finally:
        plt.close(fig)


@pytest.mark.parametrize("N", [2, 4])
def test_other_N_plot_y0_and_the_last_block_with_labels_that_fit(N):
    rng = np.random.default_rng(N)
    X = rng.normal(size=(20, 3 * N))
    labels = [lab for lab, _ in plotting.point_sets(X)]
    assert labels == ["y₀", f"y_{N - 1}"]
    r = np.linalg.norm(X[0, 3 * N - 3 :])
    for make in (plotting.figure_points_3d, plotting.figure_projection):
        fig = make(X)
        try:
            ax = fig.axes[0]
            pts = _scatter_points(ax)
            np.testing.assert_array_equal(pts[f"y_{N - 1}"][:, :2], X[:, 3 * N - 3 : 3 * N - 1])
            legend_text = " ".join(
                t.get_text() for leg in [*fig.legends, ax.get_legend()] if leg is not None for t in leg.get_texts()
            )
            assert "|z|" not in legend_text and f"|y_{N - 1}| = {r:.6g}" in legend_text
        finally:
            plt.close(fig)


# ------------------------------------------------------------------------------------------------ run directories
def test_thinning_rule_every_kth_row_and_the_last(run_dir):
    run = plotting.open_run(run_dir)
    assert (run.kind, run.rows, run.N) == ("orbit", 1001, 3)
    k = plotting.thin_step(1001, 100)
    assert k == 11  # ceil(1001 / 100)
    idx, X = plotting._runs.thinned_rows(run, 100)
    n_all, X_all = load_orbit(run_dir)  # the run layer's own loader: an independent route to the same rows
    expect = np.r_[np.arange(0, 1001, 11), 1000]
    np.testing.assert_array_equal(idx, n_all[expect])
    np.testing.assert_array_equal(X, X_all[expect])


def test_drift_envelope_is_the_bin_maximum(run_dir, monkeypatch):
    n_all, X_all = load_orbit(run_dir)
    I = jg.integrals(X_all, APPENDIX2_B)
    d = np.abs(I - I[0])
    monkeypatch.setattr(_files, "_BLOCK_ROWS", 64)  # several blocks, so that bins meet block ends
    run = plotting.open_run(run_dir)
    for k in (1, 7, 64):
        idx, env = _files.drift_envelope(run, k)
        bins = [slice(i, min(i + k, len(d))) for i in range(0, len(d), k)]
        np.testing.assert_array_equal(idx, n_all[[b.start for b in bins]])
        np.testing.assert_array_equal(env, np.array([d[b].max(axis=0) for b in bins]))


def test_redraw_of_a_run_draws_its_rows(run_dir, tmp_path, monkeypatch):
    seen = _capture(monkeypatch)
    paths = plotting.save_run_figures(run_dir, tmp_path, max_points=300, fmt="pdf", dpi=50)
    assert [p.name for p in paths] == ["figure1.pdf", "figure2.pdf", "integrals.pdf"]
    assert all(p.read_bytes()[:4] == b"%PDF" for p in paths)
    _, X_all = load_orbit(run_dir)
    k = plotting.thin_step(1001, 300)
    rows = np.unique(np.r_[np.arange(0, 1001, k), 1000])  # the last row is included once
    pts = _scatter_points(seen["figure1.pdf"].axes[0])
    # after drawing, a 3D scatter holds its points in depth order: compare them as sets of rows
    np.testing.assert_array_equal(np.unique(pts["centre of mass z"], axis=0), np.unique(X_all[rows, 6:9], axis=0))
    assert len(pts["centre of mass z"]) == len(rows)
    title = seen["figure1.pdf"]._suptitle.get_text()
    assert "b = 1" in title and "η = 5 + 0.1i" in title and "1,000 steps" in title  # thousands separator
    assert f"one saved row in {k} drawn" in seen["figure1.pdf"].axes[0].get_title()


def test_redraw_of_an_interrupted_run_uses_only_the_safe_rows(run_dir, tmp_path):
    """Only the rows run.json declares safe are drawn (a killed run may have more rows in its HDF5 file)."""
    import json
    import shutil

    from jetgaudin.recording import read_run

    d = tmp_path / "cut"
    shutil.copytree(run_dir, d)
    run = read_run(d)
    run["checkpoint"]["rows"] = 500
    run["status"] = "interrupted"
    run.pop("sha256", None)
    (d / "run.json").write_text(json.dumps(run))
    rr = plotting.open_run(d)
    assert rr.rows == 500
    idx, X = plotting._runs.thinned_rows(rr, 10_000)
    assert idx[-1] == 499 and len(X) == 500


@pytest.mark.slow
def test_constant_memory_for_longer_runs(tmp_path):
    """Drawing a 400001-row run takes about the memory of a 100001-row one: their data differ by 21.6 MB, their
    peaks by less than 5 MB (the allowance covers matplotlib's and the garbage collector's noise; loading the
    rows whole would add the 21.6 MB).  The rows are read in slices of 16384 and thinned."""
    import gc

    peaks = []
    for steps in (100_000, 400_000):
        d = tmp_path / f"r{steps}"
        spec = OrbitSpec(b=APPENDIX2_B, eta=APPENDIX2_ETA, steps=steps, X0=tuple(APPENDIX2_X0))
        run_orbit(spec, d, options=RecordOptions(csv=False, kernel="compiled"))
        plotting.save_run_figures(d, tmp_path / f"warm{steps}", max_points=500, dpi=40)  # imports, caches
        gc.collect()
        tracemalloc.start()
        plotting.save_run_figures(d, tmp_path / f"f{steps}", max_points=500, dpi=40)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] - peaks[0] < 5e6, peaks


@pytest.mark.slow
def test_a_million_row_run_is_drawn_in_bounded_memory(tmp_path):
    d = tmp_path / "big"
    spec = OrbitSpec(b=APPENDIX2_B, eta=APPENDIX2_ETA, steps=1_000_000, X0=tuple(APPENDIX2_X0))
    run_orbit(spec, d, options=RecordOptions(csv=False, kernel="compiled"))
    tracemalloc.start()
    plotting.save_run_figures(d, tmp_path / "f")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 40e6  # the run's rows are 72 MB


def test_bad_run_directories_are_refused(tmp_path):
    with pytest.raises(jg.RecordingError, match="run.json"):
        plotting.save_run_figures(tmp_path)
    with pytest.raises(jg.InvalidParameterError, match="max_points"):
        plotting.save_run_figures(tmp_path, max_points=1)


# ------------------------------------------------------------------------------------------------ animation
def test_animation_of_the_default_run(run_dir, tmp_path):
    from PIL import Image

    assert plotting._animate.frame_rows(1001, 100, None) == (10, 100)  # floor(1000 / 99) rows between frames
    assert plotting._animate.frame_rows(1001, 100, 50) == (50, 21)
    out = plotting.animate_run(run_dir, tmp_path / "top.gif", frames=12, dpi=40)
    with Image.open(out) as im:
        assert im.n_frames == 12
        frames = []
        for j in (0, 6, 11):
            im.seek(j)
            frames.append(np.asarray(im.convert("RGB"), dtype=int))
    # the body moves: successive frames differ (and not only in the step counter)
    assert np.count_nonzero(np.abs(frames[0] - frames[1]).sum(axis=-1)) > 100
    assert np.count_nonzero(np.abs(frames[1] - frames[2]).sum(axis=-1)) > 100


def test_animation_refuses_bad_input(run_dir, tmp_path):
    with pytest.raises(jg.InvalidParameterError, match=r"\.gif or \.mp4"):
        plotting.animate_run(run_dir, tmp_path / "x.avi")
    with pytest.raises(jg.InvalidParameterError, match="frames"):
        plotting.animate_run(run_dir, tmp_path / "x.gif", frames=1)
    with pytest.raises(jg.RecordingError, match="orbit"):
        plotting.animate_run(run_dir, tmp_path / "x.gif", orbit=3)


def test_mp4_when_imageio_ffmpeg_is_installed(run_dir, tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    out = plotting.animate_run(run_dir, tmp_path / "top.mp4", frames=10, dpi=40)
    head = out.read_bytes()[:12]
    assert head[4:8] == b"ftyp"  # an ISO base media (MP4) file


# ------------------------------------------------------------------------------------------------ λ-plane
def test_nu_on_grid_is_nu_where_the_branch_rule_is_defined():
    X, b = APPENDIX2_X0, APPENDIX2_B
    re = np.array([-1.0, 0.0, 0.31231881, 2.0])  # a column on Re λ = 0 and one near a branch point
    lam = re[None, :] + 1j * np.array([-2.0, -0.3, 0.05, 1.0])[:, None]
    got = plotting.nu_on_grid(lam, X, b)
    for i in range(lam.shape[0]):
        for j in range(lam.shape[1]):
            try:
                want = jg.nu(lam[i, j], X, b)
            except jg.JetGaudinError:
                assert np.isnan(got[i, j])
            else:
                assert got[i, j] == want
    assert np.all(np.isnan(got[:, 1]))  # Re λ = 0: the rule is undefined


def test_spectral_plane_marks_branch_points_site_eta_and_segment():
    X, b, eta = APPENDIX2_X0, APPENDIX2_B, 5 + 0.1j
    fig = plotting.figure_spectral_plane(X, b, eta, resolution=40)
    try:
        ax0, ax1 = fig.axes[0], fig.axes[1]  # the two panels (the colour bars come after)
        for ax in (ax0, ax1):
            lines = {ln.get_label(): ln for ln in ax.lines}
            bp = np.ravel(jg.branch_points(X, b))
            (bpl,) = [ln for lab, ln in lines.items() if "branch points" in lab]
            np.testing.assert_array_equal(bpl.get_xdata() + 1j * bpl.get_ydata(), bp)
            seg = lines["segment [η̄, η] of the branch rule"]
            np.testing.assert_array_equal(seg.get_xdata(), [5.0, 5.0])
            np.testing.assert_array_equal(seg.get_ydata(), [-0.1, 0.1])
            assert list(lines["site λ = 0 (pole)"].get_xdata()) == [0.0]
            assert list(lines["η = 5 + 0.1i"].get_ydata()) == [0.1] and list(lines["η̄"].get_ydata()) == [-0.1]
            x0, x1 = ax.get_xlim()
            y0, y1 = ax.get_ylim()
            assert x0 < bp.real.min() and x1 > 5 and y0 < bp.imag.min() and y1 > bp.imag.max()
        # the |ν²| panel shows log10 |ν²| of the grid
        _says_dimensionless_once(fig)
        img = ax0.images[0].get_array()
        assert img.shape[0] == 40 and np.isfinite(img).mean() > 0.99
    finally:
        plt.close(fig)


# ------------------------------------------------------------------------------------------------ map against flow
def test_compare_figures_show_the_flow_as_lines_and_the_map_as_points(tmp_path, monkeypatch):
    X0, b, eta, steps = APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA, 20
    H = jg.interpolating_flow_hamiltonian(X0, b, eta)
    t = np.arange(steps + 1.0)
    flow = jg.integrate(H, X0, float(steps), t_eval=t, rtol=1e-12, atol=1e-12).X
    orb = jg.TwoPointBacklund(b, eta).iterate(X0, steps)
    seen = _capture(monkeypatch)
    paths = plotting.save_compare_figures(tmp_path, t, flow, np.arange(steps + 1), orb, b)
    assert [p.name for p in paths] == ["compare_drift.png", "compare_distance.png"]
    fig = seen["compare_drift.png"]
    df = np.abs(jg.integrals(flow, b) - jg.integrals(flow[0], b))
    dm = np.abs(jg.integrals(orb, b) - jg.integrals(orb[0], b))
    # one panel per integral (H_k above, C_k below), each with exactly the flow's line and the map's points
    assert len(fig.axes) == 6
    assert [ax.get_title().split(" ")[0] for ax in fig.axes] == plotting.integral_labels(3)
    for k, ax in enumerate(fig.axes):
        fl, mp = ax.lines
        assert fl.get_label() == "flow of G_η (line)" and mp.get_label() == "map (points)"
        assert fl.get_linestyle() == "-" and mp.get_linestyle() == "None" and mp.get_marker() == "."
        np.testing.assert_array_equal(fl.get_ydata(), df[df[:, k] > 0, k])
        np.testing.assert_array_equal(mp.get_ydata(), dm[dm[:, k] > 0, k])
        assert ax.get_yscale() == "log"
    assert [ax.get_ylabel() for ax in fig.axes] == ["|I − I(0)|", "", "", "|I − I(0)|", "", ""]
    _says_dimensionless_once(fig)
    ax = seen["compare_distance.png"].axes[0]
    dist = np.linalg.norm(orb - flow, axis=-1)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), dist[dist > 0])
    assert dist.max() < 1e-9  # the map is the time-1 flow of G_eta (docs/backlund.md; 2.5e-11 over 1000 steps)


# ------------------------------------------------------------------------------------------------ command line
def _cli(*args):
    from jetgaudin.cli import main

    with pytest.raises(SystemExit) as exc:
        main(list(args))
    return exc.value.code


def test_cli_plot_animate_and_info_plot(run_dir, tmp_path, capsys):
    assert _cli("plot", str(run_dir), "--out", str(tmp_path / "p"), "--format", "svg", "--max-points", "200") == 0
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == ["figure1.svg", "figure2.svg", "integrals.svg"]
    assert (tmp_path / "p" / "figure1.svg").read_text().lstrip().startswith("<?xml")
    assert _cli("animate", str(run_dir), "--out", str(tmp_path / "a.gif"), "--frames", "5", "--dpi", "30") == 0
    assert _cli("info", "--plot", str(tmp_path / "nu.png")) == 0
    assert (tmp_path / "nu.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert _cli("plot", str(tmp_path / "nothing")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "run.json" in err
    assert _cli("animate", str(run_dir), "--out", str(tmp_path / "a.avi")) == 2
    assert _cli("info", "--plot", str(tmp_path / "nu.jpg")) == 2


def test_hdf5_is_read_in_slices_not_loaded_whole(run_dir, monkeypatch):
    """Every read of the run's dataset asks for a slice of at most max(k-strided rows, one block)."""
    asked = []
    real = h5py.Dataset.__getitem__

    def spy(self, key):
        if self.name in ("/X", "/states"):
            asked.append(key)
        return real(self, key)

    monkeypatch.setattr(h5py.Dataset, "__getitem__", spy)
    monkeypatch.setattr(_files, "_BLOCK_ROWS", 128)
    run = plotting.open_run(run_dir)
    _files.drift_envelope(run, 4)
    plotting._runs.thinned_rows(run, 100)
    assert asked and all(isinstance(k, slice) and (k.stop - k.start) <= 128 or k.step >= 11 for k in asked)


@pytest.mark.parametrize("planted", ["figure1.png", "figure1.png.tmp"])
def test_figures_are_never_written_through_a_symlink(tmp_path, planted):
    """Issue 11, item 5: a symlink named like a figure (or its temporary file) used to get its target overwritten.
    Figures are rendered in memory and renamed into place: the link is replaced (or removed), the target kept."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "figs"
    out.mkdir()
    (out / planted).symlink_to(victim)
    X = jg.TwoPointBacklund(APPENDIX2_B, APPENDIX2_ETA).iterate(APPENDIX2_X0, 20)
    files = plotting.save_orbit_figures(out, np.arange(21), X, APPENDIX2_B)
    assert victim.read_text() == "precious"
    assert (out / "figure1.png").is_file() and not (out / "figure1.png").is_symlink()
    assert (out / "figure1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (out / "figure1.png.tmp").exists() and not (out / "figure1.png.tmp").is_symlink()
    assert {f.name for f in files} >= {"figure1.png", "figure2.png", "integrals.png"}


# ------------------------------------------------------------------------------------------------ formatting
def test_step_counts_are_written_as_people_read_them():
    from jetgaudin.plotting._orbit import count_text

    # expected strings written by hand: separators below 10^6, powers of ten from 10^6 on, non-integers as %g
    assert [count_text(v) for v in (0, 999, 1000, 12345, 999_999)] == ["0", "999", "1,000", "12,345", "999,999"]
    assert [count_text(v) for v in (1e6, 2.5e7, 10**8, 123_456_789)] == ["10⁶", "2.5×10⁷", "10⁸", "1.23×10⁸"]
    assert count_text(0.5) == "0.5"
    fig = plotting.figure_integral_drift(np.array([0, 500_000, 1_000_000]), drift=np.full((3, 6), 1e-15))
    fig.canvas.draw()
    ticks = [t.get_text() for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert "10⁶" in ticks and not any("e+" in t or "1e6" in t for t in ticks), ticks


# ------------------------------------------------------------------------------------------------ ensembles
def test_drift_quantiles_per_integral():
    from jetgaudin import InvalidParameterError
    from jetgaudin.ensemble import drift_quantiles, iterate_ensemble, sample_on_leaf

    # column m holds (1..5) * 10^-m: linear interpolation between orbits gives, by hand, median 3, 90 % 4.6,
    # 99 % 4.96 and the maximum 5 (times 10^-m); exact up to the rounding of the interpolation (rtol 1e-15)
    d = np.arange(1.0, 6.0)[:, None] * 10.0 ** -np.arange(6.0)
    want = np.array([3.0, 4.6, 4.96, 5.0])[:, None] * 10.0 ** -np.arange(6.0)
    np.testing.assert_allclose(drift_quantiles(d[::-1]), want, rtol=1e-15)
    res = iterate_ensemble(sample_on_leaf(3, [0.4, -0.3, 1.5], 6, seed=2), 1.0, 5 + 0.1j, 20)
    assert np.array_equal(res.drift_quantiles((0.5, 1.0))[1], res.drift.max(axis=0))
    assert np.array_equal(res.drift_quantiles()[0], np.median(res.drift, axis=0))
    for bad in ((0.5, 1.5), (), (-0.1,)):
        with pytest.raises(InvalidParameterError, match="quantiles in"):
            res.drift_quantiles(bad)


def test_drift_histogram_counts_every_orbit_and_marks_the_quantiles():
    from jetgaudin.ensemble import drift_quantiles
    from jetgaudin.plotting._ensemble import figure_drift_histogram

    rng = np.random.default_rng(3)
    d = 10.0 ** rng.uniform(-16, -12, size=(200, 6))
    d[:7, 0] = 0.0  # seven orbits keep H_1 exactly: not on a log axis, counted in the title
    fig = figure_drift_histogram(d)
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert len(axes) == 6 and [ax.get_title().split(" ")[0] for ax in axes] == plotting.integral_labels(3)
    q = drift_quantiles(d)
    for m, ax in enumerate(axes):
        heights = sum(p.get_height() for p in ax.patches)
        assert heights == 200 - (7 if m == 0 else 0)  # every orbit with a nonzero drift is in a bar
        np.testing.assert_array_equal(sorted(ln.get_xdata()[0] for ln in ax.lines), sorted(q[:, m]))
        assert ax.get_xscale() == "log"
    assert "7 orbits with drift 0" in axes[0].get_title()
    _says_dimensionless_once(fig)


@pytest.fixture(scope="module")
def ensemble_dir(tmp_path_factory):
    from jetgaudin.cli import main

    out = tmp_path_factory.mktemp("ens") / "e"
    with pytest.raises(SystemExit) as exc:
        main(["ensemble", "--orbits", "20", "--steps", "40", "--save-every", "4", "--out", str(out), "--no-progress"])
    assert exc.value.code in (0, None)
    return out


def test_ensemble_summary_reports_quantiles_and_writes_the_histogram(tmp_path, capsys):
    import json

    from jetgaudin.cli import main

    out = tmp_path / "e"
    with pytest.raises(SystemExit):
        main(["ensemble", "--orbits", "30", "--steps", "50", "--out", str(out), "--no-progress", "--show", "2"])
    text = capsys.readouterr().out
    assert "quantiles per integral" in text and (out / "drift_hist.png").read_bytes()[:4] == b"\x89PNG"
    rows = {ln.split("│")[1].strip(): ln.split("│")[2:-1] for ln in text.splitlines()
            if ln.startswith("│") and ln.split("│")[1].strip() in ("50 %", "90 %", "99 %", "max")}
    assert list(rows) == ["50 %", "90 %", "99 %", "max"]
    # the max row is the run layer's own per-integral maximum over the orbits (run.json), written independently
    rec = json.loads((out / "run.json").read_text())
    assert [float(v) for v in rows["max"]] == [float(f"{v:.2e}") for v in rec["max_drift_per_integral"]]


def test_plot_of_an_ensemble_shows_several_orbits_and_the_drift_histogram(ensemble_dir, tmp_path, monkeypatch):
    from jetgaudin.plotting._ensemble import spread_orbits
    from jetgaudin.run import load

    seen = _capture(monkeypatch)
    paths = plotting.save_run_figures(ensemble_dir, tmp_path)
    assert {p.name for p in paths} >= {"ensemble_orbits.png", "drift_hist.png", "figure1.png"}
    assert spread_orbits(20) == [0, 2, 5, 7, 10, 12, 14, 17, 19] and spread_orbits(3) == [0, 1, 2]
    fig = seen["ensemble_orbits.png"]
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert [int(ax.get_title().split(",")[0].split()[1]) for ax in panels] == spread_orbits(20)
    data = load(ensemble_dir)
    for ax, i in zip(panels, spread_orbits(20), strict=True):
        com = ax.collections[1].get_offsets()  # the centre of mass z of orbit i, every saved row
        np.testing.assert_array_equal(np.asarray(com), data.states[:, i, 6:8])
    # the histogram of the drift over the saved rows counts every orbit
    hist = seen["drift_hist.png"]
    assert sum(p.get_height() for p in hist.axes[1].patches) == 20
    _says_dimensionless_once(fig)
    # one orbit asked for: only that orbit's figures
    assert [p.name for p in plotting.save_run_figures(ensemble_dir, tmp_path / "k", orbit=3)] == [
        "figure1.png", "figure2.png", "integrals.png"]
