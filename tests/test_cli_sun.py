"""The command line's --algebra (issue 32): info of an su(n) chain; one line and exit 2 for every refusal."""

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


@pytest.mark.parametrize("command", ["orbit", "flow", "ensemble"])
def test_runs_are_refused_in_one_line(capsys, tmp_path, command):
    """The run layer records 3N-component states: su(n) runs are refused, after the map's own rules for eta."""
    argv = [a for a in BASE if a not in ("--init", INIT)] if command == "ensemble" else BASE
    code, _, err = run_cli(capsys, command, *argv, "--steps", "3", "--out", tmp_path / "r")
    assert one_line_error(code, err, "--algebra", "not built yet"), err
    assert not (tmp_path / "r").exists()
    code, _, err = run_cli(capsys, "orbit", *BASE[:-4], "--eta", "0+0.1i", "--init", INIT, "--out", tmp_path / "s")
    assert one_line_error(code, err, "is a site"), err


def test_su2_algebra_is_todays_chain(capsys, tmp_path):
    """--algebra su2 is the default: the same info as without it."""
    init = ",".join(["0.1", "0.2", "0.3", "-0.2", "0.4", "0.1"])
    a = run_cli(capsys, "info", "--sites", SITES, "--b", "0.5", "--init", init, "--json")
    b = run_cli(capsys, "info", "--sites", SITES, "--b", "0.5", "--init", init, "--json", "--algebra", "su2")
    assert a == b and a[0] == 0
