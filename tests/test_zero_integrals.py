"""The relative drift of an integral that is zero at the start (``RunResult.max_drift_rel``, ``run.json``
``max_drift_rel``, the command's integrals table).

The Clebsch top's Casimir ``h1,3 = 2 M·p`` at ``M = (0.72, 0.24, -0.54)``, ``p = (0.6, 0, 0.8)`` is zero, computed
as ``-1.1e-16``; ``|ΔI| / |I(0)|`` read 1115 for a round-off drift of 1e-13.  Now the relative drift is ``nan``
(``null``, ``n/a (I(0) at round-off)``) where ``|I(0)| ≤ 64 ε s`` with ``s`` the integral's scale at ``X0``
(:func:`jetgaudin.run.api.integral_scales`), and ``|ΔI| / |I(0)|`` unchanged everywhere else.
"""

from __future__ import annotations

import json

import numpy as np

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.cli._common import ROUNDOFF_ZERO
from jetgaudin.gaudin import sun_exact
from jetgaudin.run.api import ROUNDOFF_ULPS, integral_scales, relative_drift
from test_run import run_cli

EPS = np.finfo(float).eps
CLEBSCH = jg.ChainTwoPointBacklund(jg.clebsch_top(0.6), 0.3 + 0.2j, backend="numpy")
CLEBSCH_X0 = np.array([0.72, 0.24, -0.54, 0.6, 0.0, 0.8])  # M ⟂ p: h1,3 = 2 M·p = 0 (-1.1e-16 computed)
# a top (N = 3, b = 0.7) whose C_2 = 2 y_1·y_2 is zero in the same way, and one whose integrals are all far from 0
TOP = jg.TwoPointBacklund(0.7, 0.3 + 0.2j)
TOP_ZERO = np.array([0.3, -0.2, 0.5, 0.72, 0.24, -0.54, 0.6, 0.0, 0.8])
TOP_PLAIN = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])


def _run(m, X0, out, steps=200):
    return rl.start(rl.RunSpec(m, X0, steps, checkpoint_seconds=0), out, handle_signals=False)


def test_the_clebsch_casimir_at_round_off_has_no_relative_drift(tmp_path):
    res = _run(CLEBSCH, CLEBSCH_X0, tmp_path / "c")
    names = res.record["integral_names"]
    k = names.index("h1,3")
    assert res.integrals0[k] != 0 and abs(res.integrals0[k]) < 1e-15  # the case of the report: -1.1e-16
    rel = res.max_drift_rel
    assert np.isnan(rel[k])  # the old divisor |I(0)| gave ~1e3 here
    assert res.record["max_drift_rel"][k] is None  # null in run.json (strict JSON)
    assert json.loads((tmp_path / "c" / "run.json").read_text())["max_drift_rel"][k] is None
    # the absolute drift, the number to read, is round-off: 200 steps of ~ε s each at most
    s = integral_scales(CLEBSCH, CLEBSCH_X0)
    assert 0 < res.drift_abs[k] <= 200 * EPS * s[k]
    # every integral that is not zero keeps |ΔI| / |I(0)| exactly (the same division)
    live = np.abs(res.integrals0) > ROUNDOFF_ULPS * EPS * s
    assert live.sum() == 3  # h1,2, h1,4, c0 (h1,1 = 2 b M_3 is exactly 0 at b = 0: n/a too)
    assert np.array_equal(rel[live], res.drift_abs[live] / np.abs(res.integrals0[live]))
    assert np.all(np.isnan(rel[~live]))
    assert np.array_equal(np.isnan(rel), [r is None for r in res.record["max_drift_rel"]])


def test_a_top_with_a_zero_casimir_and_one_without(tmp_path):
    res = _run(TOP, TOP_ZERO, tmp_path / "z")
    k = res.record["integral_names"].index("C_2")
    assert abs(res.integrals0[k]) < 1e-15 and np.isnan(res.max_drift_rel[k])
    assert np.sum(np.isnan(res.max_drift_rel)) == 1
    res = _run(TOP, TOP_PLAIN, tmp_path / "p")  # nothing at round-off: the meaning is unchanged, bit for bit
    assert np.array_equal(res.max_drift_rel, res.drift_abs / np.abs(res.integrals0))
    assert res.record["max_drift_rel"] == res.max_drift_rel.tolist()


def test_a_small_but_genuine_integral_keeps_its_relative_drift(tmp_path):
    """C_2 = 2 y_1·y_2 = 2e-8 (y_2 tilted by 1e-8): far above 64 ε s (~1e-13), so relative, however large."""
    X0 = TOP_ZERO.copy()
    X0[7] = 1e-8 / 0.24
    res = _run(TOP, X0, tmp_path / "s")
    k = res.record["integral_names"].index("C_2")
    assert 1e-9 < abs(res.integrals0[k]) < 1e-7
    assert res.max_drift_rel[k] == res.drift_abs[k] / abs(res.integrals0[k])


def test_the_threshold_is_64_ulps_of_the_scale():
    s = np.array([2.0, 2.0, 2.0, 0.0, 0.0])
    I0 = np.array([64 * EPS * 2.0, -65 * EPS * 2.0, 0.0, 0.0, 1e-300])
    rel = relative_drift(np.full(5, 1e-20), I0, s)
    assert np.isnan(rel[0]) and np.isnan(rel[2]) and np.isnan(rel[3])
    assert rel[1] == 1e-20 / (65 * EPS * 2.0) and rel[4] == 1e-20 / 1e-300


def test_the_scale_is_the_integrals_own_degree():
    """``s_k ∝ ‖X0‖^q``: doubling the state multiplies ``s`` by 4 for the quadratic integrals and 8 for su(3)'s
    cubic ones (b = 0: homogeneous), as it multiplies the integrals themselves (rtol 1e-12: round-off of the
    differences of sums of O(1) terms)."""
    model = jg.GaudinModel(0.0, [(0.0, 1), (1.0, 1)], algebra="su3")
    m = sun_exact.SunExactFlow(model.hamiltonian(np.ones(model.n_integrals)), 0.05, backend="numpy")
    X = np.round(np.random.default_rng(1).normal(size=16) * 0.5, 3)
    q = np.where([name.startswith("t3_") for name in model.integral_labels()], 3, 2)
    np.testing.assert_allclose(integral_scales(m, 2 * X), 2.0 ** q * integral_scales(m, X), rtol=1e-12)
    np.testing.assert_allclose(m.integrals(2 * X), 2.0 ** q * m.integrals(X), rtol=1e-12)


def test_the_scale_is_not_the_sum_of_the_terms():
    """At M = e_1, p = e_2 every term of 2 M·p is exactly 0 (so is their sum of absolute values), yet the orbit's
    h1,3 drifts by round-off: the scale is that of the state, s ~ ‖X0‖², and the relative drift n/a."""
    X0 = np.array([1.0, 0.0, 0.0, 0.0, 1.0, 0.0])
    k = CLEBSCH.integral_names().index("h1,3")
    s = integral_scales(CLEBSCH, X0)[k]
    assert CLEBSCH.integrals(X0)[k] == 0.0 and 0.5 < s < 8  # ‖X0‖² = 2
    X = CLEBSCH.iterate(X0, 200)
    drift = np.max(np.abs(CLEBSCH.integrals(X)[:, k]))
    assert 0 < drift <= 200 * EPS * s


def test_the_command_prints_n_a(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")  # the table's columns whole on one line each
    code, out, err = run_cli(capsys, "orbit", "--sites", "0:2", "--family", "elliptic", "--modulus", "0.6", "--b",
                             "0", "--init", ",".join(repr(float(v)) for v in CLEBSCH_X0), "--eta", "0.3+0.2i",
                             "--steps", "200", "--backend", "numpy", "--no-plots", "--no-progress",
                             "--out", tmp_path / "cli")
    assert code == 0, err
    rows = {line.split()[1]: line for line in out.splitlines() if line.strip().startswith(("│ h1,", "│ c0"))}
    assert ROUNDOFF_ZERO in rows["h1,3"] and ROUNDOFF_ZERO in rows["h1,1"]
    assert ROUNDOFF_ZERO not in rows["h1,2"] and ROUNDOFF_ZERO not in rows["c0"]
    assert json.loads((tmp_path / "cli" / "run.json").read_text())["max_drift_rel"][2] is None
