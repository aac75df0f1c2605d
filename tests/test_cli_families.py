"""`--family trigonometric --gamma` (issue 23) and `--family elliptic --modulus` (issue 24) on orbit, ensemble, flow and
info, through the real entry point in-process, one parametrised test per command.  References are the library's model
and map called directly (the CLI only converts text): bit for bit for orbit.h5 / ensemble.h5, the flow's comparison
with the map at the flow's tolerance.  Family-specific refusals live in test_cli_trigonometric.py and
test_cli_elliptic.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jetgaudin import run as rl
from jetgaudin.gaudin import GaudinModel
from test_run import run_cli

X0 = np.round(np.random.default_rng(7).normal(size=9), 3)
INIT = ",".join(repr(float(v)) for v in X0)
ETA = 1.5 + 0.2j
SITES = "-0.5:1,0.4:2"
CASES = {
    # family: (model, CLI options, recorded parameter, last integral, orbit steps, --init-from steps, ensemble size)
    "trigonometric": (GaudinModel(0.8, [(-0.5, 1), (0.4, 2)], family="trigonometric", gamma=0.7),
                      ("--family", "trigonometric", "--gamma", "0.7", "--b", "0.8"), ("gamma", 0.7), "J", 12, 3, 3),
    "elliptic": (GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6),
                 ("--family", "elliptic", "--modulus", "0.6", "--b", "0"), ("modulus", 0.6), "c0", 6, 2, 2),
}
FAMILIES = pytest.mark.parametrize("family", list(CASES))


def _common(family):
    return ("--sites", SITES, *CASES[family][1], "--eta", "1.5+0.2i")


@FAMILIES
def test_orbit_and_init_from(tmp_path, capsys, family):
    model, _, (key, value), last, n, n2, _ = CASES[family]
    code, _, err = run_cli(capsys, "orbit", *_common(family), "--init", INIT, "--steps", str(n), "--kernel", "numpy",
                           "--out", tmp_path / "o")
    assert code == 0, err
    ref = model.two_point_backlund(ETA).iterate(X0, n, kernel="numpy")
    assert np.array_equal(rl.load(tmp_path / "o").X, ref)
    run = json.loads((tmp_path / "o" / "run.json").read_text())
    assert run["map"]["family"] == family and run["map"][key] == value
    assert run["integral_names"][-1] == last
    # --init-from keeps the family of the recorded run
    code, _, err = run_cli(capsys, "orbit", "--init-from", tmp_path / "o", "--steps", str(n2), "--kernel", "numpy",
                           "--out", tmp_path / "o2")
    assert code == 0, err
    ref2 = model.two_point_backlund(ETA, kernel="numpy").iterate(ref[-1], n2)
    assert np.array_equal(rl.load(tmp_path / "o2").X, ref2)


@FAMILIES
def test_ensemble(tmp_path, capsys, family):
    model, size = CASES[family][0], CASES[family][6]
    X = np.random.default_rng(8).normal(size=(size, 9))
    np.savetxt(tmp_path / "in.csv", X, delimiter=",")
    code, _, err = run_cli(capsys, "ensemble", *_common(family), "--input", tmp_path / "in.csv", "--steps", "4",
                           "--out", tmp_path / "e")
    assert code == 0, err
    d = rl.load(tmp_path / "e")
    # bit for bit against the route the run took (recorded in run.json): `auto` chooses by the kernels' state in the
    # process (loaded, cached on disk or not compiled yet), so a fresh clone and a warm machine may differ
    route = json.loads((tmp_path / "e" / "run.json").read_text())["map"]["backend"]
    assert route in ("numpy", "compiled")
    B = model.two_point_backlund(ETA, backend=route)
    for k in range(size):
        assert np.array_equal(d.X[:, k], B.iterate(X[k], 4))


@FAMILIES
def test_flow_compare(tmp_path, capsys, family):
    """The flow of G_eta against the map: the CLI's compare.csv distance below 1e-9 (DOP853 at the default rtol)."""
    code, out, err = run_cli(capsys, "flow", *_common(family), "--init", INIT, "--steps", "2", "--compare",
                             "--out", tmp_path / "f")
    assert code == 0, err
    d = np.loadtxt(tmp_path / "f" / "compare.csv", delimiter=",", skiprows=1)
    assert np.abs(d[:, 1]).max() < 1e-9


@FAMILIES
def test_info_json(capsys, family):
    model, _, (key, value) = CASES[family][:3]
    code, out, err = run_cli(capsys, "info", *_common(family), "--init", INIT, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["family"] == family and d[key] == value
    assert [r["name"] for r in d["integrals"]] == model.integral_labels()
    assert np.allclose([r["value"] for r in d["integrals"]], model.integrals(X0), rtol=1e-15, atol=0)
    assert [r["kind"] for r in d["integrals"]].count("Casimir") == model.M
