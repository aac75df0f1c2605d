"""`--sites` on the command line (issue 12): orbit, ensemble, info, flow for chains, through the real entry point
`jetgaudin.cli.main` (in-process).  References are the library's chain map / model called directly (the CLI only
converts text), compared bit for bit where the CLI writes binary data (orbit.h5, ensemble.h5) and to the 17
significant digits of orbit.csv (a float printed with 17 digits reads back exactly)."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.cli import main
from jetgaudin.gaudin import GaudinModel, parse_sites
from test_run import run_cli

SITES = "-1:2,0.5:3,2:1"
MODEL = GaudinModel(0.8, parse_sites(SITES))
ETA = 0.9 + 0.05j
X0 = np.round(np.random.default_rng(3).normal(size=18), 3)
INIT = ",".join(repr(float(v)) for v in X0)


def one_line_error(code, err, *words):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return code == 2 and len(lines) == 1 and "Traceback" not in err and all(w in err for w in words)


def with_options(base, args):
    """The command line ``base`` with the option/value pairs of ``args`` set: a later value overrides an option
    already there, a new option is appended."""
    base = list(base)
    for i in range(0, len(args), 2):
        if args[i] in base:
            base[base.index(args[i]) + 1] = args[i + 1]
        else:
            base += [args[i], args[i + 1]]
    return base


@pytest.fixture(scope="module")
def orbit_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("chain") / "o"
    code = main_quiet("orbit", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--init", INIT, "--steps", "60",
                      "--kernel", "numpy", "--out", out)
    assert code == 0
    return out


def main_quiet(*args):
    try:
        return main([str(a) for a in args]) or 0
    except SystemExit as exc:
        return exc.code or 0


def test_orbit_sites_writes_the_chain_orbit(orbit_dir):
    ref = jg.ChainTwoPointBacklund(MODEL, ETA, backend="numpy").iterate(X0, 60)
    d = rl.load(orbit_dir)
    assert np.array_equal(d.X, ref)
    header = (orbit_dir / "orbit.csv").read_text().splitlines()[0].split(",")
    assert header == ["n", *MODEL.labels()] and header[1] == "s1_y0^1" and header[-1] == "s3_y0^3"
    n, X = rl.read_csv(orbit_dir / "orbit.csv")
    assert np.array_equal(n, np.arange(61)) and np.array_equal(X, ref)
    run = json.loads((orbit_dir / "run.json").read_text())
    assert run["map"]["kind"] == "chain_two_point" and run["map"]["sites"] == [[-1.0, 2], [0.5, 3], [2.0, 1]]
    assert run["integral_names"] == MODEL.integral_labels()
    assert {"chain_y0.png", "chain_integrals.png"} <= set(run["files"])
    assert not (orbit_dir / "figure1.png").exists()


def test_chain_y0_figure_plots_each_sites_y0(orbit_dir):
    """The 3D figure's point sets are the saved y_0 of each site (one set per site, in site order)."""
    from jetgaudin import plotting as pc

    d = rl.load(orbit_dir)
    fig = pc.figure_chain_y0(MODEL, d.X, n=d.n)
    # one row per site: the e1-e2 projection coloured by the step (a colour bar), and the three components
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 2 * 3 and sum(ax.get_label() == "<colorbar>" for ax in fig.axes) == 3
    for i in range(3):
        proj, comps = panels[2 * i], panels[2 * i + 1]
        o = 3 * MODEL.offsets[i]
        assert f"site {i + 1}" in proj.get_title()
        pts = proj.collections[0]
        assert np.array_equal(pts.get_offsets(), d.X[:, o:o + 2]) and np.array_equal(pts.get_array(), d.n)
        assert len(comps.lines) == 3
        for a, ln in enumerate(comps.lines):
            assert np.array_equal(ln.get_xdata(), d.n) and np.array_equal(ln.get_ydata(), d.X[:, o + a])
    assert sum("dimensionless" in t.get_text() for t in fig.texts) == 1
    fig2 = pc.figure_chain_integral_drift(d.n, MODEL, d.X)
    labels = [ln.get_label() for ln in fig2.axes[0].get_lines()]
    assert len(labels) == 2 * MODEL.M and sum("Casimir" in s for s in labels) == MODEL.M
    assert fig2.axes[0].get_yscale() == "log"


def test_orbit_init_from_a_chain_run(tmp_path, capsys, orbit_dir):
    """--init-from a chain run takes its sites, b, eta; the run continues the orbit bit for bit."""
    out = tmp_path / "cont"
    code, _, err = run_cli(capsys, "orbit", "--init-from", orbit_dir, "--steps", "20", "--kernel", "numpy",
                           "--no-plots", "--out", out)
    assert code == 0, err
    ref = jg.ChainTwoPointBacklund(MODEL, ETA, backend="numpy").iterate(X0, 60)
    # a new run starts the branch rule again at its first state: equal to the map from that state
    assert np.array_equal(rl.load(out).X, jg.ChainTwoPointBacklund(MODEL, ETA, backend="numpy").iterate(ref[-1], 20))


def test_single_site_of_order_3_keeps_the_papers_figures(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:3", "--steps", "5", "--out", tmp_path / "p")
    assert code == 0, err
    assert (tmp_path / "p" / "figure1.png").exists() and not (tmp_path / "p" / "chain_y0.png").exists()
    # one site at 0 of order 3 is the paper's system: the same orbit as without --sites, to round-off
    code, _, err = run_cli(capsys, "orbit", "--steps", "5", "--kernel", "numpy", "--no-plots", "--out", tmp_path / "q")
    a, b = rl.load(tmp_path / "p").X, rl.load(tmp_path / "q").X
    assert np.abs(a - b).max() <= 1e-12 * (1 + np.abs(b).max())  # two routes, same formula: round-off only


def test_without_sites_nothing_changes(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--steps", "3", "--no-plots", "--out", tmp_path / "a")
    assert code == 0, err
    assert json.loads((tmp_path / "a" / "run.json").read_text())["map"]["kind"] == "two_point"
    assert (tmp_path / "a" / "orbit.csv").read_text().startswith("n,y0^1,y0^2,y0^3,y1^1")


@pytest.mark.parametrize(("args", "words"), [
    (["--sites", "-1:2,-1:3"], ["--sites", "distinct"]),
    (["--sites", "1+2i:2"], ["--sites", "not a real number"]),
    (["--sites", "0.5:0"], ["--sites", "integer >= 1"]),
    (["--sites", "0.5:x"], ["--sites", "integer >= 1"]),
    (["--sites", "-1:2,0.5:3,2:1", "--init", "1,2,3,4,5,6,7,8,9"], ["--sites", "3M = 18", "got 9"]),
    (["--sites", "-1:2,0.5:1", "--eta", "0.5+1i", "--init", "1,2,3,4,5,6,7,8,9"], ["--sites", "Re(eta) = 0.5"]),
    (["--sites", "-1:2,0.5:1", "--eta", "0.2", "--init", "1,2,3,4,5,6,7,8,9"], ["--eta", "Im(eta) = 0"]),
])
def test_bad_sites_are_one_line_errors(tmp_path, capsys, args, words):
    code, _, err = run_cli(capsys, "orbit", *args, "--out", tmp_path / "x")
    assert one_line_error(code, err, *words), err
    assert not (tmp_path / "x").exists()


def test_ensemble_sites_members_equal_single_orbits(tmp_path, capsys):
    X = np.round(np.random.default_rng(4).normal(size=(3, 18)), 3)
    path = tmp_path / "in.csv"
    path.write_text("\n".join(",".join(repr(float(v)) for v in row) for row in X) + "\n")
    code, out, err = run_cli(capsys, "ensemble", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--input", path,
                             "--steps", "20", "--out", tmp_path / "e")
    assert code == 0, err
    d = rl.load(tmp_path / "e")
    m = jg.ChainTwoPointBacklund(MODEL, ETA, backend=d.record["map"]["backend"])
    for k in range(3):
        assert np.array_equal(d.X[:, k], m.iterate(X[k], 20))
    # the chain's sampler is its leaf (tests/test_chain_capabilities.py); the top's energy shell is refused
    code, _, err = run_cli(capsys, "ensemble", "--sites", SITES, "--sample", "energy", "--energy", "1", "--out",
                           tmp_path / "s")
    assert one_line_error(code, err, "--sites", "leaf")


def test_info_sites_marks_casimirs_and_hamiltonians(capsys):
    code, out, err = run_cli(capsys, "info", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--init", INIT,
                             "--json")
    assert code == 0, err
    d = json.loads(out)
    h = MODEL.integrals(X0)
    assert [r["name"] for r in d["integrals"]] == MODEL.integral_labels()
    assert [r["kind"] == "Casimir" for r in d["integrals"]] == MODEL.casimir_mask().tolist()
    assert np.array_equal([r["value"] for r in d["integrals"]], h)
    assert np.isclose(complex(*d["nu_default"]), complex(MODEL.nu(X0, ETA)), rtol=1e-14)
    code, out, err = run_cli(capsys, "info", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--init", INIT)
    assert code == 0 and "Casimir" in out and "Hamiltonian" in out and "h2,6" in out


def test_flow_sites_integrates_the_chains_G_eta(tmp_path, capsys):
    """flow --sites --compare: the flow of the chain's G_eta sampled at t = n is the chain map's orbit (the map is the
    time-1 flow, docs/chains.md section 4); DOP853 at rtol = atol = 1e-12 over 20 time units: <= 1e-8 relative to
    1 + |X| (measured ~1e-11)."""
    out = tmp_path / "f"
    code, stdout, err = run_cli(capsys, "flow", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--init", INIT,
                                "--steps", "20", "--compare", "--out", out)
    assert code == 0, err
    d = rl.load(out)
    ref = jg.ChainTwoPointBacklund(MODEL, ETA).iterate(X0, 20)
    assert d.X.shape == ref.shape and np.abs(d.X - ref).max() <= 1e-8 * (1 + np.abs(ref).max())
    assert (out / "flow.csv").read_text().startswith("t," + ",".join(MODEL.labels()))
    run = json.loads((out / "run.json").read_text())
    assert run["map"]["kind"] == "chain_flow" and run["integral_names"] == MODEL.integral_labels()
    assert run["compare"]["max_distance"] <= 1e-8 * (1 + np.abs(ref).max())
    assert {"chain_y0.png", "chain_integrals.png"} <= set(run["files"])
    # the chain's physical Hamiltonian (tests/test_chain_capabilities.py); --compare stays G_η's
    code, _, err = run_cli(capsys, "flow", "--sites", SITES, "--init", INIT, "--hamiltonian", "physical",
                           "--compare", "--out", tmp_path / "g")
    assert one_line_error(code, err, "--compare", "interpolating")


def test_the_commands_of_docs_chains_run(tmp_path, capsys, monkeypatch):
    """Every `$ jetgaudin ...` line of docs/chains.md runs with exit code 0 (in a fresh directory, in order)."""
    import pathlib
    import re
    import shlex

    text = (pathlib.Path(__file__).resolve().parents[1] / "docs" / "chains.md").read_text()
    blocks = re.findall(r"```console\n(.*?)```", text, flags=re.S)
    lines = [ln[2:] for b in blocks for ln in b.splitlines() if ln.startswith("$ jetgaudin ")]
    assert len(lines) >= 3
    monkeypatch.chdir(tmp_path)
    for ln in lines:
        code, _, err = run_cli(capsys, *shlex.split(ln)[1:])
        assert code == 0, (ln, err)
    assert (tmp_path / "chain" / "chain_y0.png").exists()


def test_info_sites_prints_branch_points_with_17_digits(capsys):
    """The text summary's branch points round-trip exactly (17 significant digits, as the top's; issue 27): each
    printed root, parsed back, equals a root of the JSON record bit for bit (6 digits, as before, fails)."""
    args = ("info", "--sites", SITES, "--b", "0.8", "--eta", "0.9+0.05i", "--init", INIT)
    code, out, err = run_cli(capsys, *args, "--json")
    assert code == 0, err
    roots = {complex(*z) for z in json.loads(out)["branch_points"]}
    code, out, err = run_cli(capsys, *args)
    tail = " ".join(out.split("branch points (zeros of ν²):")[1].split())  # the console may wrap the line
    num = r"[-+]?\d\.?\d*(?:e[-+]?\d+)?"
    found = re.findall(rf"({num}) ([-+]) ({num}) i", tail)[: len(roots)]
    printed = [complex(float(a), float(c) if s == "+" else -float(c)) for a, s, c in found]
    assert len(printed) == len(roots) and all(z in roots for z in printed)
