"""What a new user met in the second round after issues 32 and 33, each fixed and held here:

* su(3) exact runs (``orbit --algebra su3 --dt``, ``flow --algebra su3 --method exact``) solved the per-orbit
  parameters of the exact step again at every saved chunk (a Newton solve each time): now once per run, and once
  more on a resume (bit for bit: the parameters are solved at the run's initial state, read back from run.json);
"""

from __future__ import annotations

import json
import os
import signal

import numpy as np

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.gaudin import sun_exact
from test_run import run_cli

MODEL = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
X0 = np.round(np.random.default_rng(1).normal(size=16) * 0.5, 3)
INIT = ",".join(repr(float(v)) for v in X0)
W = np.round(np.random.default_rng(3).normal(size=MODEL.n_integrals), 3)  # as tests/test_cli_sun.py
WEIGHTS = ",".join(repr(float(v)) for v in W)
SU3 = ["--sites", "0:1,1:1", "--algebra", "su3", "--b", "0.5", "--init", INIT]


def _count_solves(monkeypatch) -> dict:
    """Counts the calls of ``exact_parameters`` (the Newton solve of one orbit's step parameters)."""
    calls = {"n": 0}
    solve = sun_exact.exact_parameters

    def counted(*a, **k):
        calls["n"] += 1
        return solve(*a, **k)

    monkeypatch.setattr(sun_exact, "exact_parameters", counted)
    return calls


# ---- 1. su(3) exact runs solve their parameters once per run ----------------------------------------------------

def test_orbit_dt_solves_once_per_run_and_once_per_resume(capsys, tmp_path, monkeypatch):
    """600 steps in chunks of 200 (save_every 100: the driver's fixed cuts of a non-invariant map) are 3 kernel
    calls and more reference steps; the parameters are solved once (the command's check at X0, kept for the run).
    Stopped by a SIGINT in its second call and resumed: one more solve (the replay's and the run's, shared), and
    the bytes of orbit.csv equal to one uninterrupted run's."""
    args = ("orbit", *SU3, "--hamiltonian", WEIGHTS, "--dt", "0.05", "--steps", "600", "--save-every", "100",
            "--no-plots", "--checkpoint-seconds", "0", "--backend", "compiled")
    calls = _count_solves(monkeypatch)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "full")
    assert code == 0, err
    assert calls["n"] == 1
    advance, seen = sun_exact.SunExactFlow.advance, {"n": 0}

    def interrupted(self, *a, **k):
        seen["n"] += 1
        if seen["n"] == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return advance(self, *a, **k)

    monkeypatch.setattr(sun_exact.SunExactFlow, "advance", interrupted)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "cut")
    assert code != 0 and json.loads((tmp_path / "cut" / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(sun_exact.SunExactFlow, "advance", advance)
    calls["n"] = 0
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "cut")
    assert code == 0, err
    assert calls["n"] == 1
    assert (tmp_path / "cut" / "orbit.csv").read_bytes() == (tmp_path / "full" / "orbit.csv").read_bytes()


def test_flow_exact_solves_once(capsys, tmp_path, monkeypatch):
    """600 samples: 3 kernel calls (256, 256, 88), one solve."""
    calls = _count_solves(monkeypatch)
    code, _, err = run_cli(capsys, "flow", *SU3, "--method", "exact", "--hamiltonian", WEIGHTS, "--dt", "0.05",
                           "--steps", "600", "--no-plots", "--no-progress",
                           "--out", tmp_path / "f")
    assert code == 0, err
    assert calls["n"] == 1


def test_library_run_solves_once_and_is_the_one_call_orbit(tmp_path, monkeypatch):
    """A run of an unbound SunExactFlow (the library's own, not the command's) solves once, at X0, and its rows
    are those of one `advance` call with the parameters of X0 on the NumPy route cut in the same chunks: equal bit
    for bit to two calls of the bound map (200 + 200 steps)."""
    H = MODEL.hamiltonian(W)
    fm = sun_exact.SunExactFlow(H, 0.05, backend="numpy")
    calls = _count_solves(monkeypatch)
    spec = rl.RunSpec(fm, X0, 400, save_every=100, csv=False, checkpoint_seconds=0)
    rl.start(spec, tmp_path / "lib", handle_signals=False)
    assert calls["n"] == 1
    bound = fm.bind_run(X0)
    assert calls["n"] == 2 and bound.bind_run(X0) is bound  # bound once: binding again at X0 is the same map
    a = bound.advance(X0, None, 200, 100)
    b = bound.advance(a.X, None, 200, 100)
    assert np.array_equal(rl.load(tmp_path / "lib").X, np.concatenate([X0[None], a.rows, b.rows]))
