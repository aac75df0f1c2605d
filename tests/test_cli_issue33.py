"""The smaller items of issue 33 on the command line: a chain's weights are not a state (any count, not 3N), the
route notice of ``--backend auto``, and ``--backend`` on every command that has a route (``--kernel`` its alias)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jetgaudin.cli._flow import parse_hamiltonian
from jetgaudin.gaudin import GaudinModel
from test_cli_chains import one_line_error
from test_run import run_cli

INIT = "0.72,0.24,-0.54,0.6,0,0.8"


@pytest.mark.parametrize("sites, kw", [
    ([(0.0, 2)], {"family": "elliptic", "modulus": 0.6}),            # the Clebsch top: 2M + 1 = 5 weights
    ([(-0.5, 1), (0.4, 1)], {"family": "trigonometric", "gamma": 1.0}),  # 2M + J = 5
])
def test_a_chain_takes_as_many_weights_as_it_has_integrals(sites, kw):
    """The weights were parsed as a state (3N numbers), so 5 weights were refused for a model with 5 integrals."""
    model = GaudinModel(0.0 if kw["family"] == "elliptic" else 1.0, sites, **kw)
    X0 = np.array([float(v) for v in INIT.split(",")])
    assert model.n_integrals == 5
    kind, w = parse_hamiltonian("0.0,0.7,0.0,0.0,1.0", X0, model.b, model)
    assert kind == "weights" and np.array_equal(w, [0.0, 0.7, 0.0, 0.0, 1.0])


def test_flow_with_five_weights_runs_and_records_them(tmp_path, capsys):
    out = tmp_path / "f"
    code, _, err = run_cli(capsys, "flow", "--sites", "-0.5:1,0.4:1", "--family", "trigonometric", "--b", "1",
                           "--hamiltonian", "0.0,0.7,0.0,0.0,1.0", "--init", INIT, "--steps", "2", "--no-plots",
                           "--out", out)
    assert code == 0, err
    assert json.loads((out / "run.json").read_text())["map"]["weights"] == [0.0, 0.7, 0.0, 0.0, 1.0]


@pytest.mark.parametrize("text, words", [("0.1,abc,0,0,1", ["--hamiltonian", "5 comma-separated"]),
                                         ("0.1,inf,0,0,1", ["--hamiltonian", "finite"]),
                                         ("0.1,0.2", ["--hamiltonian", "give 5 weights"])])
def test_bad_weights_are_one_line(tmp_path, capsys, text, words):
    code, _, err = run_cli(capsys, "flow", "--sites", "-0.5:1,0.4:1", "--family", "trigonometric", "--b", "1",
                           "--hamiltonian", text, "--init", INIT, "--steps", "2", "--no-plots", "--out", tmp_path / "f")
    assert one_line_error(code, err, *words), err


@pytest.mark.parametrize("command", ["orbit", "ensemble"])
def test_backend_is_the_option_name_on_every_command_and_kernel_its_alias(tmp_path, capsys, command):
    """``orbit --kernel`` but ``ensemble --backend`` (issue 33): both commands take both names, with the same effect
    (the route recorded in run.json)."""
    base = [command, "--steps", "3", "--no-plots" if command == "orbit" else "--orbits", *([] if command == "orbit"
                                                                                      else ["2"])]
    routes = []
    for name in ("--backend", "--kernel"):
        out = tmp_path / name.strip("-")
        code, _, err = run_cli(capsys, *base, name, "numpy", "--out", out)
        assert code == 0, err
        routes.append(json.loads((out / "run.json").read_text())["map" if command == "orbit" else "inputs"])
    assert routes[0] == routes[1]
    assert "numpy" in json.dumps(routes[0])
    code, out, _ = run_cli(capsys, command, "--help")
    assert "--backend" in out and "--kernel" in out


def test_auto_names_the_slow_route_on_stderr(tmp_path, capsys, monkeypatch):
    """``--backend auto`` on a chain says in one line when it takes the NumPy route (here: kernels to be compiled,
    a run too short to pay for it)."""
    from jetgaudin.gaudin import _backend

    monkeypatch.setattr(_backend, "kernel_state", lambda family, batch=1: "cold")
    code, _, err = run_cli(capsys, "orbit", "--sites", "-0.5:1,0.4:1", "--family", "elliptic", "--modulus", "0.6",
                           "--b", "0", "--eta", "1.5+0.2i", "--init", INIT, "--steps", "3", "--no-plots",
                           "--out", tmp_path / "o")
    assert code == 0, err
    notes = [ln for ln in err.splitlines() if "backend auto" in ln]
    assert len(notes) == 1 and "NumPy route" in notes[0] and "--backend compiled" in notes[0]


def test_the_clebsch_orbit_of_the_issue_accepts_its_five_weights_and_draws_its_figures(tmp_path, capsys):
    """The command of issue 33 (``orbit --sites 0:2 --modulus 0.6 --b 0 --dt 0.05 --hamiltonian`` with 5 weights):
    the weights are accepted (they were parsed as a 3N-state), the run completes, and the figures are drawn (the
    chain figures' title read the map's ``eta``, which an exact time step has not: a KeyError, exit code 1)."""
    out = tmp_path / "o"
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:2", "--modulus", "0.6", "--b", "0", "--dt", "0.05",
                           "--hamiltonian", "0.0,0.7,0.0,0.0,1.0", "--init", INIT, "--steps", "3", "--out", out)
    assert code == 0, err
    run = json.loads((out / "run.json").read_text())
    assert run["map"]["weights"] == [0.0, 0.7, 0.0, 0.0, 1.0] and run["map"]["dt"] == 0.05
    assert (out / "chain_y0.png").stat().st_size > 0 and (out / "chain_integrals.png").stat().st_size > 0


def test_flow_takes_backend_and_its_alias_kernel(tmp_path, capsys):
    """``flow`` has a route too (``--method exact`` on a top): ``--backend`` and ``--kernel`` name it with the same
    effect (the map recorded in run.json), and an adaptive method refuses ``compiled`` in one line."""
    maps = []
    for name in ("--backend", "--kernel"):
        out = tmp_path / name.strip("-")
        code, _, err = run_cli(capsys, "flow", "--hamiltonian", "physical", "--method", "exact", "--dt", "0.1",
                               "--steps", "2", name, "numpy", "--no-plots", "--out", out)
        assert code == 0, err
        maps.append(json.loads((out / "run.json").read_text())["map"])
    assert maps[0] == maps[1] and maps[0]["backend"] == "numpy"
    code, _, err = run_cli(capsys, "flow", "--backend", "compiled", "--steps", "2", "--no-plots",
                           "--out", tmp_path / "d")
    assert one_line_error(code, err, "--backend", "no compiled route"), err
    code, out, _ = run_cli(capsys, "flow", "--help")
    assert "--backend" in out and "--kernel" in out


def test_flow_midpoint_runs_on_a_chain(tmp_path, capsys):
    """``flow --method midpoint`` was the tops' only; through the route table it runs on a chain (the Clebsch top),
    keeping its integrals (all quadratic: 1e-12, Newton at round-off)."""
    out = tmp_path / "m"
    code, _, err = run_cli(capsys, "flow", "--sites", "0:2", "--modulus", "0.6", "--b", "0", "--method", "midpoint",
                           "--dt", "0.05", "--hamiltonian", "0.0,0.7,0.0,0.0,1.0", "--init", INIT, "--steps", "4",
                           "--no-plots", "--out", out)
    assert code == 0, err
    run = json.loads((out / "run.json").read_text())
    assert run["map"]["kind"] == "midpoint" and run["map"]["model"]["family"] == "elliptic"
    assert max(run["max_drift_abs"]) < 1e-12


def test_every_command_with_a_route_names_it_backend_with_kernel_its_alias():
    """One option name on every command: where a command has ``--kernel`` it has ``--backend`` (the same option)
    and vice versa, and the commands that run a map with a route (orbit, ensemble, flow) have both."""
    import typer.main

    from jetgaudin.cli import app

    group = typer.main.get_command(app)
    names = {}
    for cmd_name, cmd in group.commands.items():  # type: ignore[attr-defined]
        opts = {o for p in cmd.params for o in getattr(p, "opts", [])}
        names[cmd_name] = opts
        same = [p for p in cmd.params if "--backend" in getattr(p, "opts", []) or "--kernel" in getattr(p, "opts", [])]
        assert len(same) <= 1 and all({"--backend", "--kernel"} <= set(p.opts) for p in same), cmd_name
    routed = {c for c, o in names.items() if "--backend" in o}
    assert {"orbit", "ensemble", "flow"} <= routed
    assert routed == {c for c, o in names.items() if "--kernel" in o}
