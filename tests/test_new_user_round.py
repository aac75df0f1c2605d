"""What a new user met trying this round's features (issues 32 and 33) from the command line, each fixed and held here:

* ``flow --algebra su3 --method midpoint`` refused the su(3) state as "not a positive multiple of 3" (the run layer read
  the state layout from ``map.model``, which the midpoint map of a chain's Hamiltonian does not have), and an su(2)
  chain's midpoint run wrote a top's column names and integral names (H_k, C_k);
* ``flow --method midpoint`` with a dt too large for its Newton solve started a run that failed (exit 1) instead of
  one line and exit 2, as ``--method exact`` does;
* ``orbit --dt`` on a chain without weights asked for "2M weights" (an su(3) chain has 5M integrals);
* ``--dt`` on su(4) advised ``--method DOP853``, an option ``orbit`` does not have;
* ``orbit --resume DIR --algebra su2`` and ``ensemble --resume DIR --algebra/--sites/--family/--b`` silently resumed
  the recorded run with the other model ignored.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.methods import method_map
from jetgaudin.run.spec import block_size
from test_cli_chains import one_line_error
from test_run import run_cli

MODEL = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
X0 = np.round(np.random.default_rng(1).normal(size=16) * 0.5, 3)
INIT = ",".join(repr(float(v)) for v in X0)
W = [1.0, 0.0, 0.5, 0.0, 0.3, 0.2, 0.0, 0.1, 0.4, 0.0]  # the 10 integrals' weights (Casimir weights included)
WEIGHTS = ",".join(repr(v) for v in W)
SU3 = ["--sites", "0:1,1:1", "--algebra", "su3", "--b", "0.5", "--init", INIT]


def _rows(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def test_su3_midpoint_flow_runs_and_is_the_library_map(capsys, tmp_path):
    code, out, err = run_cli(capsys, "flow", *SU3, "--method", "midpoint", "--hamiltonian", WEIGHTS, "--dt", "0.1",
                             "--steps", 5, "--no-plots", "--no-progress", "--out", tmp_path / "mp")
    assert code == 0, err
    header, rows = _rows(tmp_path / "mp" / "flow.csv")
    assert header == ["t", *MODEL.labels()]  # 16 component names, s1_y0^1 ... s2_y0^8
    want = method_map(MODEL.hamiltonian(W), "midpoint", 0.1).iterate(X0, 5)
    # the same map and state through the run layer: equal to round-off of the CSV's 17 digits (1e-15 is generous)
    assert np.max(np.abs(rows[:, 1:] - want)) < 1e-15
    assert np.allclose(rows[:, 0], 0.1 * np.arange(6), rtol=0, atol=1e-15)
    assert "t3_h2,3" in out and "C_5" not in out  # the model's integral names, not a top's H_k/C_k


def test_su2_chain_midpoint_names_its_columns_and_integrals(capsys, tmp_path):
    model = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1)])
    code, out, err = run_cli(capsys, "flow", "--sites", "0:1,1:1", "--init", "1,0,0,0,1,0", "--method", "midpoint",
                             "--hamiltonian", "1,0,1,0", "--dt", "0.1", "--steps", 3, "--no-plots", "--no-progress",
                             "--out", tmp_path / "mp2")
    assert code == 0, err
    header, _ = _rows(tmp_path / "mp2" / "flow.csv")
    assert header == ["t", *model.labels()]
    assert "h2,2" in out and "C_2" not in out


def test_block_size_of_a_midpoint_map_is_the_models():
    assert block_size(method_map(MODEL.hamiltonian(W), "midpoint", 0.1)) == 8
    top = jg.IntegralHamiltonian(1.0, np.ones(6))
    assert block_size(method_map(top, "midpoint", 0.1)) == 3


def test_midpoint_dt_too_large_is_one_line_before_the_run(capsys, tmp_path):
    code, _, err = run_cli(capsys, "flow", *SU3, "--method", "midpoint", "--hamiltonian", WEIGHTS, "--dt", "50",
                           "--steps", 5, "--no-plots", "--out", tmp_path / "big")
    assert one_line_error(code, err, "--dt", "smaller dt"), err
    assert not (tmp_path / "big").exists()  # refused before the run: nothing written


def test_chain_dt_without_weights_names_the_model_count(capsys, tmp_path):
    code, _, err = run_cli(capsys, "orbit", *SU3, "--dt", "0.1", "--steps", 3, "--out", tmp_path / "o")
    assert one_line_error(code, err, "--hamiltonian", "10 weights"), err
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:1,1:2", "--init", "1,0,0,0,1,0,0,0,1", "--dt", "0.1",
                           "--steps", 3, "--out", tmp_path / "o2")
    assert one_line_error(code, err, "--hamiltonian", "6 weights"), err  # su(2): 2M = 6


def test_su4_exact_points_to_a_command_that_exists(capsys, tmp_path):
    init = ",".join(["0.1"] * 15)
    w = ",".join(["1"] * 9)
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:1", "--algebra", "su4", "--init", init, "--dt", "0.1",
                           "--hamiltonian", w, "--steps", 3, "--out", tmp_path / "o")
    assert one_line_error(code, err, "--dt", "jetgaudin flow --method DOP853"), err


@pytest.mark.parametrize("extra", [["--algebra", "su2"], ["--algebra", "su3"]])
def test_orbit_resume_refuses_another_algebra(capsys, tmp_path, extra):
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path, *extra)
    assert one_line_error(code, err, "--algebra", "drop --algebra"), err


@pytest.mark.parametrize("extra", [["--algebra", "su2"], ["--sites", "0:1"], ["--family", "trigonometric"],
                                   ["--b", "2"], ["--modulus", "0.5"]])
def test_ensemble_resume_refuses_another_model(capsys, tmp_path, extra):
    code, _, err = run_cli(capsys, "ensemble", "--resume", tmp_path, *extra)
    assert one_line_error(code, err, extra[0], "drop"), err


def test_su3_weight_count_error_names_su3_integrals():
    with pytest.raises(jg.InvalidParameterError) as ei:
        MODEL.hamiltonian([1.0, 2.0, 3.0])
    msg = str(ei.value)
    assert "length 10" in msg and "tr l^k/k" in msg and "and J" not in msg and "2M" not in msg
    with pytest.raises(jg.InvalidParameterError, match=r"length 4 \(2M = 4 h_\(i,m\):"):  # su(2): unchanged
        jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1)]).hamiltonian([1.0, 2.0, 3.0])


@pytest.mark.parametrize("method", ["exact", "midpoint"])
def test_solve_refuses_an_unknown_backend_on_a_chain(method):
    # ChainExactFlow has no backend choice: solve(..., backend="cuda") used to run silently
    H = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1)]).hamiltonian([1.0, 0.0, 1.0, 0.0])
    with pytest.raises(jg.InvalidParameterError, match="backend"):
        jg.solve(H, np.array([1.0, 0, 0, 0, 1.0, 0]), (0, 0.2), dt=0.1, method=method, backend="cuda")


def test_su3_chain_figure_names_its_projection_axes():
    # the left panels of an su(3) chain's y_0 figure project on the λ₁, λ₂ components: not labelled e₁, e₂ (su(2))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jetgaudin.plotting._chains import figure_chain_y0

    X = MODEL.two_point_backlund(0.4 + 0.1j).iterate(X0, 3)
    fig = figure_chain_y0(MODEL, X)
    left = fig.axes[0]
    assert "λ₁" in left.get_xlabel() and "λ₂" in left.get_ylabel()
    plt.close(fig)
    su2 = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1)])
    fig = figure_chain_y0(su2, su2.two_point_backlund(0.4 + 0.1j).iterate(np.array([1.0, 0, 0, 0, 1.0, 0]), 3))
    assert fig.axes[0].get_xlabel() == "e₁"
    plt.close(fig)


def test_plot_titles_an_exact_step_run_as_such(capsys, tmp_path):
    # `jetgaudin plot` of an `orbit --dt` run (su(3) chain or top) titled it "Real two-point Bäcklund map ...
    # η = (none)": an exact-step run has a time step and no η
    from jetgaudin.plotting._files import run_title
    from jetgaudin.plotting._runs import open_run

    code, _, err = run_cli(capsys, "orbit", *SU3, "--dt", "0.1", "--hamiltonian", WEIGHTS, "--steps", 2,
                           "--backend", "numpy", "--no-plots", "--no-progress", "--out", tmp_path / "sx")
    assert code == 0, err
    code, _, err = run_cli(capsys, "orbit", "--dt", "0.05", "--steps", 2, "--no-plots", "--no-progress",
                           "--out", tmp_path / "tx")
    assert code == 0, err
    for d, dt in (("sx", "0.1"), ("tx", "0.05")):
        title = run_title(open_run(tmp_path / d))
        assert "Exact time steps" in title and f"dt = {dt}" in title, title
        assert "Bäcklund" not in title and "η" not in title, title


def test_solve_takes_the_maps_alias_kernel():
    """``jg.solve(..., kernel=...)`` is the alias of ``backend=`` as on every map (a bare TypeError before): the same
    trajectory, bit for bit, and two different concrete choices refused with the typed error."""
    H = jg.physical_hamiltonian(3, 1.0)
    X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    a = jg.solve(H, X0, (0.0, 1.0), dt=0.25, method="bt", backend="numpy")
    b = jg.solve(H, X0, (0.0, 1.0), dt=0.25, method="bt", kernel="numpy")
    assert np.array_equal(a.X, b.X)
    with pytest.raises(jg.InvalidParameterError, match="kernel"):
        jg.solve(H, X0, (0.0, 1.0), dt=0.25, method="bt", backend="numpy", kernel="compiled")
