"""`jetgaudin orbit --dt H`: the run's map is the exact time-H flow (jg.ExactFlow / jg.ChainExactFlow), shared with
`jetgaudin flow --method exact`; orbit.csv / orbit.h5 gain the time column t = n dt (issue 25)."""

from __future__ import annotations

import json
import os
import re
import signal

import h5py
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.cli import main

X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])  # Appendix 2's initial state
INIT = ",".join(f"{v:g}" for v in X3)


def run_cli(capsys, *args):
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out = capsys.readouterr()
    return (0 if exc.value.code is None else exc.value.code), out.out, out.err


def one_line_error(code, err, *words):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return code == 2 and "Traceback" not in err and len(lines) == 1 and all(w in err for w in words)


def table(path):
    """``(header, rows)`` of a CSV written by the run layer."""
    text = path.read_text()
    return text.splitlines()[0].split(","), np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def reference(H, X0, T):
    """DOP853 at rtol = atol = 1e-13: an integrator independent of the maps."""
    return jg.integrate(H, X0, T, rtol=1e-13, atol=1e-13).X[-1]


def test_orbit_dt_is_the_exact_flow_with_a_t_column(capsys, tmp_path):
    code, out, err = run_cli(capsys, "orbit", "--dt", 0.05, "--steps", 40, "--no-plots", "--out", tmp_path)
    assert code == 0, err
    head, rows = table(tmp_path / "orbit.csv")
    from jetgaudin.run.files import csv_header

    assert head == ["n", "t", *csv_header(3).strip().split(",")[1:]] and rows.shape == (41, 11)
    # t = n dt: the CSV's %.17g round-trips the double n * dt exactly
    assert np.array_equal(rows[:, 0], np.arange(41)) and np.array_equal(rows[:, 1], np.arange(41) * 0.05)
    with h5py.File(tmp_path / "orbit.h5") as f:
        assert np.array_equal(f["t"][()], np.arange(41) * 0.05) and np.array_equal(f["X"][()], rows[:, 2:])
    # 40 exact steps = the flow of H_2/2 to t = 2; DOP853 at 1e-13 leaves ~1e-12 over t = 2 (|X| ~ 3)
    H = jg.physical_hamiltonian(3, 1.0)
    assert np.max(np.abs(rows[-1, 2:] - reference(H, X3, 2.0))) < 1e-11
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["map"]["kind"] == "exact" and run["map"]["dt"] == 0.05 and run["inputs"]["stem"] == "orbit"
    assert jg.run.load(tmp_path).X.shape == (41, 9)


def test_orbit_dt_hamiltonian_weights_and_figures(capsys, tmp_path):
    """--hamiltonian w_1,...: the flow of Σ w_m κ_m (here H_2/2 + 0.3 H_3 − 0.2 H_1); figures are drawn."""
    w = np.array([-0.2, 0.5, 0.3, 0.0, 0.0, 0.0])
    code, _, err = run_cli(capsys, "orbit", "--dt", -0.05, "--steps", 20, "--hamiltonian", ",".join(map(str, w)),
                           "--out", tmp_path)
    assert code == 0, err
    _, rows = table(tmp_path / "orbit.csv")
    assert np.allclose(rows[-1, 1], -1.0, rtol=1e-15)
    # 10 exact steps backwards to t = -1 vs DOP853 at 1e-13 (~1e-12 over |t| = 1)
    assert np.max(np.abs(rows[-1, 2:] - reference(jg.IntegralHamiltonian(1.0, w), X3, -1.0))) < 1e-11
    assert (tmp_path / "figure1.png").is_file() and (tmp_path / "integrals.png").is_file()


def test_orbit_dt_bad_input_is_one_line(capsys, tmp_path):
    code, _, err = run_cli(capsys, "orbit", "--dt", 0.05, "--eta", "5+0.1i", "--out", tmp_path / "a")
    assert one_line_error(code, err, "--dt", "--eta")
    for args, words in ((["--dt", 0], ["--dt"]), (["--dt", "x"], ["--dt"]), (["--hamiltonian", "physical"], ["--dt"]),
                        (["--dt", 0.1, "--hamiltonian", "1,2,3"], ["--hamiltonian", "6"]),
                        (["--dt", 0.1, "--hamiltonian", "interpolating"], ["--eta"]),
                        (["--dt", 0.1, "--branch", "opposite"], ["--branch"]),
                        (["--dt", 0.1, "--substeps", 0], ["--substeps"])):
        code, _, err = run_cli(capsys, "orbit", *args, "--out", tmp_path / "b")
        assert one_line_error(code, err, *words), (args, err)
    # an infeasible dt names the leaf's largest step and the --substeps that makes it feasible; that one runs
    code, _, err = run_cli(capsys, "orbit", "--dt", 3, "--steps", 2, "--no-plots", "--out", tmp_path / "c")
    assert one_line_error(code, err, "--dt", "largest feasible", "--substeps")
    dmax = float(re.search(r"dt = ([0-9.e+-]+);", err).group(1))
    assert dmax == pytest.approx(jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), 1.0).max_dt(X3), rel=2e-3)
    k = re.search(r"--substeps (\d+)", err).group(1)
    code, _, err = run_cli(capsys, "orbit", "--dt", 3, "--substeps", k, "--steps", 2, "--no-plots", "--out",
                           tmp_path / "c")
    assert code == 0, err


def test_orbit_dt_resumes_bit_for_bit_and_init_from(capsys, tmp_path, monkeypatch):
    args = ("orbit", "--dt", 0.05, "--steps", 600, "--no-plots", "--checkpoint-seconds", 0)
    assert run_cli(capsys, *args, "--out", tmp_path / "full")[0] == 0
    calls = {"n": 0}
    advance = jg.ExactFlow.advance

    def interrupted(self, *a, **k):  # SIGINT during the 2nd chunk (256 steps each): the run stops at a checkpoint
        calls["n"] += 1
        if calls["n"] == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return advance(self, *a, **k)

    monkeypatch.setattr(jg.ExactFlow, "advance", interrupted)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "cut")
    assert code != 0 and json.loads((tmp_path / "cut" / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(jg.ExactFlow, "advance", advance)
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "cut")
    assert code == 0, err
    assert (tmp_path / "cut" / "orbit.csv").read_bytes() == (tmp_path / "full" / "orbit.csv").read_bytes()
    with h5py.File(tmp_path / "cut" / "orbit.h5") as f, h5py.File(tmp_path / "full" / "orbit.h5") as g:
        assert np.array_equal(f["t"][()], g["t"][()]) and np.array_equal(f["X"][()], g["X"][()])
    # --init-from the end, with -dt: back to the start (the exact flow of -dt inverts that of dt; the round-off of
    # 1200 exact steps on |X| ~ 3, a few 1e-13)
    code, _, err = run_cli(capsys, "orbit", "--init-from", tmp_path / "full", "--dt", -0.05, "--steps", 600,
                           "--no-plots", "--out", tmp_path / "back")
    assert code == 0, err
    _, rows = table(tmp_path / "back" / "orbit.csv")
    assert np.max(np.abs(rows[-1, 2:] - X3)) < 1e-11
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "cut", "--dt", 0.05)
    assert one_line_error(code, err, "--resume")


def test_orbit_dt_sites_is_the_chain_exact_flow(capsys, tmp_path):
    """--sites: ChainExactFlow of the given weights; one step vs DOP853 of the chain Hamiltonian."""
    model = jg.GaudinModel(1.0, ((0.0, 2), (1.0, 1)))
    X0 = np.array([0.3, -0.2, 0.5, 0.1, 0.2, -0.1, 0.4, 0.1, 0.6])
    w = np.zeros(2 * model.M)
    w[~model.casimir_mask()] = [0.5, 0.2, 0.3][: int((~model.casimir_mask()).sum())]
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2,1:1", "--init", ",".join(map(str, X0)), "--dt", 0.01,
                           "--steps", 2, "--hamiltonian", ",".join(map(str, w)), "--no-plots", "--out", tmp_path)
    assert code == 0, err
    _, rows = table(tmp_path / "orbit.csv")
    ref = jg.integrate(model.hamiltonian(w), X0, 0.02, rtol=1e-13, atol=1e-13).X[-1]
    # two exact steps vs DOP853 at 1e-13 (the chain weights by adaptive quadrature at epsrel 1e-13): 1e-11
    assert np.max(np.abs(rows[-1, 2:] - ref)) < 1e-11
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2,1:1", "--init", ",".join(map(str, X0)), "--dt", 0.01,
                           "--out", tmp_path / "p")
    assert one_line_error(code, err, "--hamiltonian", "chain")


def test_orbit_dt_sites_takes_substeps(capsys, tmp_path):
    """--substeps with --sites (refused before): a chain step of dt beyond the leaf's dt_max is refused naming the
    --substeps that fixes it, and with them it is the flow (two steps vs DOP853 at 1e-13: 1e-11, as above)."""
    model = jg.GaudinModel(1.0, ((0.0, 2), (1.0, 1)))
    X0 = np.array([0.3, -0.2, 0.5, 0.1, 0.2, -0.1, 0.4, 0.1, 0.6])
    w = np.zeros(2 * model.M)
    w[~model.casimir_mask()] = [0.5, 0.2, 0.3][: int((~model.casimir_mask()).sum())]
    common = ("orbit", "--sites", "0:2,1:1", "--init", ",".join(map(str, X0)), "--dt", 0.5, "--steps", 2,
              "--hamiltonian", ",".join(map(str, w)), "--no-plots")
    code, _, err = run_cli(capsys, *common, "--out", tmp_path / "a")
    assert one_line_error(code, err, "--dt", "--substeps")
    s = int(re.search(r"--substeps (\d+)", err).group(1))
    assert s >= 2
    code, _, err = run_cli(capsys, *common, "--substeps", s, "--out", tmp_path / "b")
    assert code == 0, err
    _, rows = table(tmp_path / "b" / "orbit.csv")
    ref = jg.integrate(model.hamiltonian(w), X0, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    assert np.max(np.abs(rows[-1, 2:] - ref)) < 1e-11


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_orbit_dt_sites_runs_the_route_asked_for(capsys, tmp_path, backend):
    """``--backend`` of a chain's exact run is honoured (it was ignored: a ChainExactFlow was built on ``auto``, which
    the run layer recorded as the NumPy route).  Both runs are the same exact flow: the compiled and NumPy routes
    agree to 1e-12 after 20 steps (each step's parameters from the integrals at its chunk's start, solved by each
    route to ~1e-15; the orbit's round-off grows with the steps)."""
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2", "--family", "elliptic", "--modulus", 0.6, "--b", 0,
                           "--hamiltonian", "0,0.7,0,0,1.0", "--init", "0.3,-0.5,0.4,0.8,0.2,-0.3", "--dt", 0.9,
                           "--steps", 20, "--no-plots", "--backend", backend, "--out", tmp_path / "run")
    assert code == 0, err
    rec = json.loads((tmp_path / "run" / "run.json").read_text())
    assert rec["map"]["kind"] == "chain_exact" and rec["map"]["backend"] == backend
    _, rows = table(tmp_path / "run" / "orbit.csv")
    H = jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0])
    ref = jg.ChainExactFlow(H, 0.9, backend="numpy").iterate(np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3]), 20)
    assert np.max(np.abs(rows[:, 2:] - ref)) < 1e-12


def test_orbit_dt_sites_auto_takes_the_compiled_route_for_a_long_run(capsys, tmp_path):
    """``auto`` on 20 000 steps: the compiled route whatever the state of Numba's cache (estimated NumPy ~110 s,
    compiled at most ~46 s with a compile), as run.json records it: the route of the run layer had been the NumPy one
    for every chain exact run (the Clebsch top at ~160 steps/s)."""
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2", "--family", "elliptic", "--modulus", 0.6, "--b", 0,
                           "--hamiltonian", "0,0.7,0,0,1.0", "--init", "0.3,-0.5,0.4,0.8,0.2,-0.3", "--dt", 0.9,
                           "--steps", 20000, "--save-every", 1000, "--no-plots", "--out", tmp_path / "run")
    assert code == 0, err
    rec = json.loads((tmp_path / "run" / "run.json").read_text())
    assert rec["map"]["backend"] == "compiled" and rec["status"] == "completed"


def test_the_exact_chain_route_rule():
    """``AUTO``'s rule for the exact chain step (``gaudin._backend.exact_route_costs``; the run layer resolves it
    before its first call): the NumPy route for a short run where the compiled one must first be compiled or loaded,
    the compiled route for a long one, the compiled route as soon as its kernels are loaded."""
    from jetgaudin.gaudin._backend import exact_route_costs

    fam = jg.clebsch_top(0.6).family
    pick = lambda steps, state: (lambda c: "compiled" if c.compiled <= c.numpy else "numpy")(  # noqa: E731
        exact_route_costs(fam, 2, 1, steps, 2, 1, state))
    assert [pick(n, "cold") for n in (10, 1000, 10**4, 10**5)] == ["numpy", "numpy", "compiled", "compiled"]
    assert [pick(n, "cached") for n in (10, 30, 1000)] == ["numpy", "numpy", "compiled"]
    assert pick(1, "loaded") == "compiled"
    # the orbits of a batch cost one by one on both routes; a sub-step costs its maps
    c1, c4 = exact_route_costs(fam, 2, 1, 500, 2, 1, "loaded"), exact_route_costs(fam, 2, 4, 500, 2, 1, "loaded")
    assert c4.numpy == pytest.approx(4 * c1.numpy) and c4.compiled == pytest.approx(4 * c1.compiled)
    assert exact_route_costs(fam, 2, 1, 500, 2, 3, "loaded").numpy > 2.5 * c1.numpy


def test_the_chain_exact_flow_s_auto_route_is_its_compiled_one():
    """``resolved_backend`` (what the run layer records) of an ``auto`` ChainExactFlow on a long run: compiled for
    every family with the compiled solve, NumPy for the elliptic family below modulus 1e-3 (whose solve has no
    compiled route; ``backend="compiled"`` is refused there)."""
    X9 = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    rat = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)])
    for H, x in ((jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0]), X9[:6]),
                 (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]), X9),
                 (rat.hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2]), X9)):
        flow = jg.ChainExactFlow(H, 0.05)
        assert flow.has_compiled and flow.resolved_backend(x, 10**5) is jg.Backend.COMPILED
        assert flow.with_backend("numpy").resolved_backend(x, 10**5) is jg.Backend.NUMPY
    low = jg.clebsch_top(1e-4).hamiltonian([0, 0.7, 0, 0, 1.0])
    flow = jg.ChainExactFlow(low, 0.05)
    assert not flow.has_compiled and flow.resolved_backend(X9[:6], 10**5) is jg.Backend.NUMPY
    with pytest.raises(jg.InvalidParameterError, match="compiled"):
        jg.ChainExactFlow(low, 0.05, backend="compiled")


def test_the_chain_exact_flow_prepares_its_compiled_route():
    """``prepare_kernels`` (the run layer calls it before its loop, so that a compile is announced and kept out of the
    rate): nothing for the NumPy route; for the compiled route the report of the kernels of the family's route, here
    already loaded in this process (no message), and a flow whose first state is infeasible is not an error there
    (the run reports it at its first call)."""
    H = jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0])
    x = np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])
    said = []
    flow = jg.ChainExactFlow(H, 0.9, backend="compiled")
    flow.advance(x, None, 1, 1)  # the kernels loaded in this process
    report = flow.prepare_kernels(x, 10, said.append)
    assert report.state == "loaded" and said == []
    assert "solve_orbit_numerical" in " ".join(report.kernels)
    assert jg.ChainExactFlow(H, 0.9, backend="numpy").prepare_kernels(x, 10**6, said.append) is None
    assert jg.ChainExactFlow(H, 5.0, backend="compiled").prepare_kernels(x, 10, said.append).state == "loaded"


def test_orbit_dt_sites_backend_compiled_without_the_compiled_solve_is_one_line(capsys, tmp_path):
    """An elliptic modulus below 1e-3 has no compiled exact solve: ``--backend compiled`` is refused in one line
    naming ``--backend`` (it named ``--dt``), and nothing is written."""
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2", "--family", "elliptic", "--modulus", 1e-4, "--b", 0,
                           "--hamiltonian", "0,0.7,0,0,1.0", "--init", "0.3,-0.5,0.4,0.8,0.2,-0.3", "--dt", 0.4,
                           "--steps", 5, "--no-plots", "--backend", "compiled", "--out", tmp_path / "run")
    assert one_line_error(code, err, "--backend", "compiled")
    assert not (tmp_path / "run").exists()
