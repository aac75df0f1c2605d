"""The command line's --algebra (issue 32): info, orbit, ensemble, flow, resume and plot of an su(n) chain; one line
and exit 2 for every refusal."""

from __future__ import annotations

import json

import numpy as np
import pytest

import jetgaudin as jg
from test_cli_chains import one_line_error
from test_run import run_cli

SITES = "0:1,1:1"
MODEL = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
X0 = np.round(np.random.default_rng(1).normal(size=16) * 0.5, 3)
INIT = ",".join(repr(float(v)) for v in X0)
BASE = ["--sites", SITES, "--algebra", "su3", "--b", "0.5", "--eta", "0.4+0.1i", "--init", INIT]


def test_info_json_is_the_library(capsys):
    code, out, err = run_cli(capsys, "info", *BASE, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["algebra"] == "su(3)" and d["M"] == 2
    assert [r["name"] for r in d["integrals"]] == MODEL.integral_labels()
    assert np.array_equal([r["value"] for r in d["integrals"]], MODEL.integrals(X0))
    assert [r["kind"] == "Casimir" for r in d["integrals"]] == MODEL.casimir_mask().tolist()
    for r in range(3):
        row = d["branches"][r]
        assert complex(*row["mu"]) == MODEL.eigenvalue(X0, 0.4 + 0.1j, r)
        assert row["G"] == MODEL.interpolating_hamiltonian(X0, 0.4 + 0.1j, r)


def test_info_table(capsys):
    code, out, err = run_cli(capsys, "info", *BASE)
    assert code == 0, err
    assert "su(3) chain" in out and "t3_h2,3" in out and "μ_2" in out


@pytest.mark.parametrize("args, words", [
    (["--algebra", "so3"], ["--algebra", "unknown algebra"]),
    (["--algebra", "su3", "--family", "trigonometric"], ["--algebra", "rational only"]),
    (["--init", "1,2,3"], ["--sites", "8M = 16"]),
    (["--eta", "1+0.1i"], None),  # info: a site at Re eta is reported per branch, not refused
])
def test_info_refusals(capsys, args, words):
    argv = list(BASE)
    for i in range(0, len(args), 2):
        if args[i] in argv:
            argv[argv.index(args[i]) + 1] = args[i + 1]
        else:
            argv += [args[i], args[i + 1]]
    code, out, err = run_cli(capsys, "info", *argv, "--json")
    if words is None:
        assert code == 0 and all(r["mu"] is None and "is a site" in r["note"] for r in json.loads(out)["branches"])
    else:
        assert one_line_error(code, err, *words), err


def test_algebra_needs_sites(capsys):
    code, _, err = run_cli(capsys, "info", "--algebra", "su3")
    assert one_line_error(code, err, "--algebra", "give --sites"), err


def test_orbit_branch_r_is_the_library_map_bit_for_bit(capsys, tmp_path):
    """`orbit --algebra su3 --branch 2` writes the library's B^(2)_eta orbit (the CSV's %.17g round-trips), its
    header names the 8 components of each site, and `plot` draws the chain figures of the run."""
    code, _, err = run_cli(capsys, "orbit", *BASE, "--steps", "12", "--branch", "2", "--out", tmp_path / "r")
    assert code == 0, err
    ref = jg.SunTwoPointBacklund(MODEL, 0.4 + 0.1j, 2).iterate(X0, 12)
    lines = (tmp_path / "r" / "orbit.csv").read_text().splitlines()
    assert lines[0].split(",") == ["n"] + [f"s{s}_y0^{a}" for s in (1, 2) for a in range(1, 9)]
    assert np.array_equal(np.array([[float(v) for v in ln.split(",")[1:]] for ln in lines[1:]]), ref)
    assert json.loads((tmp_path / "r" / "run.json").read_text())["map"]["branch"] == 2
    for f in ("chain_y0.png", "chain_integrals.png"):
        (tmp_path / "r" / f).unlink()
    code, out, err = run_cli(capsys, "plot", tmp_path / "r")
    assert code == 0 and (tmp_path / "r" / "chain_y0.png").stat().st_size > 0, err


def test_interrupted_orbit_resumes_through_the_cli(capsys, tmp_path):
    """An su(3) orbit stopped early (a SIGINT through the run layer) finishes with `orbit --resume` to the bits of
    one uninterrupted run."""
    from jetgaudin import run as rl
    from test_gaudin_run import interrupt

    m = jg.SunTwoPointBacklund(MODEL, 0.4 + 0.1j, 1)
    spec = rl.RunSpec(m, X0, 20, 3, checkpoint_seconds=0.0, program="jetgaudin orbit")
    assert interrupt(spec, tmp_path / "r", 5).last_safe_step < 20
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "r", "--no-plots")
    assert code == 0, err
    d = rl.load(tmp_path / "r")
    assert np.array_equal(d.X, m.iterate(X0, 20)[d.n])


def test_ensemble_and_flow_run(capsys, tmp_path):
    """`ensemble --algebra su3` draws 0.5 N(0, 1) states (--seed) and runs B^(r); `flow` runs the flow of G_eta and
    `plot` redraws it."""
    base = [a for a in BASE if a not in ("--init", INIT)]
    code, _, err = run_cli(capsys, "ensemble", *base, "--orbits", "3", "--seed", "4", "--steps", "5", "--branch", "1",
                           "--out", tmp_path / "e")
    assert code == 0, err
    from jetgaudin import run as rl

    d = rl.load(tmp_path / "e")
    S = 0.5 * np.random.default_rng(4).normal(size=(3, 16))
    for k in range(3):
        assert np.array_equal(d.X[:, k], jg.SunTwoPointBacklund(MODEL, 0.4 + 0.1j, 1).iterate(S[k], 5))
    code, _, err = run_cli(capsys, "flow", *BASE, "--hamiltonian", "interpolating", "--dt", "1", "--steps", "2",
                           "--out", tmp_path / "f", "--no-plots")
    assert code == 0, err
    X = rl.load(tmp_path / "f").X
    ref = jg.SunTwoPointBacklund(MODEL, 0.4 + 0.1j, 0).iterate(X0, 2)
    assert np.abs(X - ref).max() <= 1e-9  # DOP853 at 1e-12 over 2 units against the map (the time-1 flow of G)
    code, _, err = run_cli(capsys, "plot", tmp_path / "f")  # a chain flow records b in its map description only
    assert code == 0 and (tmp_path / "f" / "chain_integrals.png").is_file(), err


@pytest.mark.parametrize("args, words", [
    (["--branch", "3"], ["--branch", "0..2"]),
    (["--eta", "0+0.1i"], ["is a site"]),
    (["--eta", "0.4"], ["--eta"]),
])
def test_run_refusals_in_one_line(capsys, tmp_path, args, words):
    argv = list(BASE)
    if args[0] in argv:
        argv[argv.index(args[0]) + 1] = args[1]
    else:
        argv += args
    code, _, err = run_cli(capsys, "orbit", *argv, "--steps", "3", "--out", tmp_path / "r")
    assert one_line_error(code, err, *words), err
    assert not (tmp_path / "r").exists()


def test_su2_branch_numbers(capsys, tmp_path):
    """su(2): --branch 0 / 1 are default / opposite (the same bits); 2 is refused in one line."""
    init = ",".join(["0.1", "0.2", "0.3", "-0.2", "0.4", "0.1"])
    base = ["orbit", "--sites", SITES, "--b", "0.5", "--eta", "0.4+0.1i", "--init", init, "--steps", "4", "--no-plots"]
    for a, b in (("1", "opposite"), ("0", "default")):
        assert run_cli(capsys, *base, "--branch", a, "--out", tmp_path / a)[0] == 0
        assert run_cli(capsys, *base, "--branch", b, "--out", tmp_path / b)[0] == 0
        assert (tmp_path / a / "orbit.csv").read_text() == (tmp_path / b / "orbit.csv").read_text()
    code, _, err = run_cli(capsys, *base, "--branch", "2", "--out", tmp_path / "x")
    assert one_line_error(code, err, "--branch", "--algebra"), err
    code, _, err = run_cli(capsys, "ensemble", *BASE[:-2], "--casimirs", "1,1", "--out", tmp_path / "y")
    assert one_line_error(code, err, "--casimirs"), err


def test_su2_algebra_is_todays_chain(capsys, tmp_path):
    """--algebra su2 is the default: the same info as without it."""
    init = ",".join(["0.1", "0.2", "0.3", "-0.2", "0.4", "0.1"])
    a = run_cli(capsys, "info", "--sites", SITES, "--b", "0.5", "--init", init, "--json")
    b = run_cli(capsys, "info", "--sites", SITES, "--b", "0.5", "--init", init, "--json", "--algebra", "su2")
    assert a == b and a[0] == 0


W = np.round(np.random.default_rng(3).normal(size=MODEL.n_integrals), 3)  # weights of the 10 h^(k)_(j,m)
WEIGHTS = ",".join(repr(float(v)) for v in W)
EXACT = [a for a in BASE if a not in ("--eta", "0.4+0.1i")] + ["--hamiltonian", WEIGHTS]


def test_exact_steps_round_trip(capsys, tmp_path):
    """`orbit --dt` and `flow --method exact` of an su(3) chain run the library's SunExactFlow: the same rows, bit
    for bit, as its `iterate` (one chunk: the run layer cuts a non-invariant map every 256 steps), and the flow of
    H = Σ w h against DOP853 at rtol = atol = 1e-13 over t = 2: measured 3e-13, asserted 1e-10 (DOP853's global
    error; the orbit moves by O(1)).  The run records the map ('sun_exact') and a t column."""
    from jetgaudin.gaudin import SunExactFlow

    code, _, err = run_cli(capsys, "orbit", *EXACT, "--dt", "0.2", "--steps", "10", "--out", tmp_path / "o")
    assert code == 0, err
    code, _, err = run_cli(capsys, "flow", *BASE, "--method", "exact", "--hamiltonian", WEIGHTS, "--dt", "0.2",
                           "--steps", "10", "--out", tmp_path / "f", "--no-plots")
    assert code == 0, err
    from jetgaudin import run as rl

    d, f = rl.load(tmp_path / "o"), rl.load(tmp_path / "f")
    H = MODEL.hamiltonian(W)
    assert np.array_equal(d.X, SunExactFlow(H, 0.2, backend="numpy").iterate(X0, 10))
    assert np.array_equal(f.X, d.X)
    ref = jg.solve(H, X0, (0.0, 2.0), dt=0.2, method="dop853", rtol=1e-13, atol=1e-13).X
    assert np.abs(d.X - ref).max() <= 1e-10 and np.abs(d.X[-1] - X0).max() > 0.1
    run = json.loads((tmp_path / "o" / "run.json").read_text())
    assert run["map"]["kind"] == "sun_exact" and run["map"]["weights"] == W.tolist() and run["map"]["dt"] == 0.2
    lines = (tmp_path / "o" / "orbit.csv").read_text().splitlines()
    assert lines[0].split(",")[:3] == ["n", "t", "s1_y0^1"] and float(lines[-1].split(",")[1]) == 10 * 0.2
    assert (tmp_path / "o" / "chain_y0.png").stat().st_size > 0  # the chain figures, titled by dt


def test_exact_orbit_resumes_bit_for_bit(capsys, tmp_path, monkeypatch):
    """An `orbit --dt` run of an su(3) chain (compiled route, 600 steps: three chunks of 256, 256, 88) stopped by a
    SIGINT in its second chunk ends, after `orbit --resume`, with the bytes of one uninterrupted run."""
    import os
    import signal

    from jetgaudin.gaudin import SunExactFlow

    args = ("orbit", *EXACT, "--dt", "0.05", "--steps", "600", "--no-plots", "--checkpoint-seconds", "0",
            "--backend", "compiled")
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "full")
    assert code == 0, err
    calls = {"n": 0}
    advance = SunExactFlow.advance

    def interrupted(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return advance(self, *a, **k)

    monkeypatch.setattr(SunExactFlow, "advance", interrupted)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "cut")
    assert code != 0 and json.loads((tmp_path / "cut" / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(SunExactFlow, "advance", advance)
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "cut")
    assert code == 0, err
    assert (tmp_path / "cut" / "orbit.csv").read_bytes() == (tmp_path / "full" / "orbit.csv").read_bytes()
    assert json.loads((tmp_path / "cut" / "run.json").read_text())["map"]["backend"] == "compiled"


def test_exact_substeps_hint_runs(capsys, tmp_path):
    """A --dt with no exact parameters names the --substeps that has them (the first dt/k that solves); with it
    the run completes and is the flow of H (DOP853 at 1e-13 over t = 2: 1e-10, as above)."""
    import re

    common = ("orbit", *EXACT, "--dt", "1", "--steps", "2", "--no-plots")
    code, _, err = run_cli(capsys, *common, "--out", tmp_path / "a")
    assert one_line_error(code, err, "--dt", "--substeps"), err
    k = re.search(r"--substeps (\d+)", err).group(1)
    assert int(k) >= 2
    code, _, err = run_cli(capsys, *common, "--substeps", k, "--out", tmp_path / "b")
    assert code == 0, err
    from jetgaudin import run as rl

    ref = jg.solve(MODEL.hamiltonian(W), X0, (0.0, 2.0), dt=1.0, method="dop853", rtol=1e-13, atol=1e-13).X
    assert np.abs(rl.load(tmp_path / "b").X - ref).max() <= 1e-10


@pytest.mark.parametrize("args, words", [
    (["--algebra", "su4", "--init", ",".join(["0.1"] * 30), "--hamiltonian", ",".join(["0.1"] * 18)],
     ["--dt", "su(3)"]),
    (["--dt", "1"], ["--dt", "--substeps"]),
    (["--hamiltonian", "physical"], ["--hamiltonian"]),
    (["--hamiltonian", "1,2,3"], ["--hamiltonian", "10 weights"]),
    (["--branch", "1"], ["--branch"]),
])
def test_exact_refusals_in_one_line(capsys, tmp_path, args, words):
    """Exact steps of an su(n) chain: n != 3, a dt past the orbit's largest solvable step (naming the --substeps that
    fix it), no weights, a wrong count, --branch: one line, exit 2, nothing written."""
    argv = list(EXACT) + ["--dt", "0.2"]
    for i in range(0, len(args), 2):
        if args[i] in argv:
            argv[argv.index(args[i]) + 1] = args[i + 1]
        else:
            argv += [args[i], args[i + 1]]
    code, _, err = run_cli(capsys, "orbit", *argv, "--steps", "2", "--out", tmp_path / "o")
    assert one_line_error(code, err, *words), err
    assert not (tmp_path / "o").exists()


def test_flow_heyoka(capsys, tmp_path):
    """flow --method heyoka of an su(3) chain = DOP853 (both at rtol 1e-12 over 2 units: 1e-9)."""
    pytest.importorskip("heyoka")
    for m in ("heyoka", "DOP853"):
        code, _, err = run_cli(capsys, "flow", *BASE, "--method", m, "--dt", "1", "--steps", "2", "--out",
                               tmp_path / m, "--no-plots")
        assert code == 0, err
    from jetgaudin import run as rl

    assert np.abs(rl.load(tmp_path / "heyoka").X - rl.load(tmp_path / "DOP853").X).max() <= 1e-9
