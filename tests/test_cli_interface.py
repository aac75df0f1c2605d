"""The command line's interface (issue 27): numeric options show a type in --help, a resumed run's summary gives
the rate of the stepping it did, and ``jetgaudin warmup`` leaves nothing to compile for the commands (slow)."""

import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("command", ["orbit", "ensemble", "flow"])
def test_numeric_options_show_their_type_in_help(command):
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    out = CliRunner().invoke(app, [command, "--help"], env={"COLUMNS": "150"}).output
    for option, kind in (("--b", "FLOAT"), ("--steps", "INTEGER"), ("--eta", "COMPLEX")):
        line = next(ln for ln in out.splitlines() if ln.strip().startswith(option + " "))
        assert line.split()[1] == kind, line
    if command == "ensemble":
        for option in ("--orbits", "--seed", "--save-every", "--chunk-size"):
            assert any(ln.split()[:2] == [option, "INTEGER"] for ln in out.splitlines()), option


def _result(session_steps, last_safe_step, session_seconds, elapsed, compile_seconds=0.0):
    """The fields of a run.RunResult that the summary reads (B = 1: one orbit)."""
    rate = session_steps / session_seconds if session_steps > 0 and session_seconds > 0 else float("nan")
    spec = SimpleNamespace(B=1, X0=np.zeros(9))
    return SimpleNamespace(spec=spec, step_rate=rate, elapsed=elapsed, session_steps=session_steps,
                           session_seconds=session_seconds, last_safe_step=last_safe_step,
                           compile_seconds=compile_seconds)


def test_a_resumed_run_reports_the_rate_and_time_of_its_own_stepping():
    from jetgaudin.cli._common import timing_text

    # a run of 1000 steps in one session: its time, and its rate 1000 / 4 s = 250 steps/s
    assert timing_text(_result(1000, 1000, 4.0, 4.0)) == "4 s stepping (250 steps/s)"
    # resumed at step 600: this session did 400 steps in 2 s (200 steps/s); 5 s over the whole run
    text = timing_text(_result(400, 1000, 2.0, 5.0, compile_seconds=0.3))
    assert text.startswith("2 s stepping 400 steps in this session (200 steps/s), 5 s over the whole run")
    assert text.endswith("kernels compiled or loaded in 0.3 s, not in the rate")


@pytest.mark.slow
def test_warmup_leaves_nothing_to_compile_for_a_chain_ensemble(tmp_path):
    """In a fresh Numba cache: ``warmup``, then an orbit and an ensemble of a rational and of a trigonometric chain on
    the compiled route; none announces a compile and none adds a compiled object to the cache (Numba writes one
    ``.nbc`` per compiled signature and target: the chain ensemble, importing the chains' kernel before the
    Bäcklund kernels chose Numba's target, compiled for another one for 5 s after a warmup in one process)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(ROOT / "src")}

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "jetgaudin", *args], env=env, capture_output=True, text=True,
                              cwd=tmp_path, timeout=600)

    assert cli("warmup").returncode == 0
    compiled = sorted(p.name for p in (tmp_path / "cache").rglob("*.nbc"))
    assert compiled  # the warmup wrote the cache the runs below must only read
    init = ("1.288,1.449,0.066,-0.765,-1.092,0.031,-1.022,-1.437,0.199,0.133,0.546,-0.914,0.005,-0.065,-1.506,"
            "0.538,0.321,2.389")
    chain = ["--sites", "-1:2,0.5:3,2:1", "--b", "0.8", "--eta", "0.9+0.05i", "--no-progress"]
    r = cli("orbit", *chain, "--steps", "300", "--out", "o", f"--init={init}")
    assert r.returncode == 0 and "compiling" not in r.stderr, r.stderr
    # the compiled route named: `auto` costs it against NumPy (301 x 100 orbit-steps are cheaper on NumPy than loading
    # the kernel), and this test is about the compiled route's cache
    r = cli("ensemble", *chain, "--steps", "100", "--input", "o/orbit.csv", "--out", "e", "--backend", "compiled")
    assert r.returncode == 0 and "compiling" not in r.stderr, r.stderr
    assert "kernels compiled or loaded" in r.stdout  # the compiled route was taken (and its kernel loaded)
    trig = ["--sites", "-1:1,0.5:1,2:1", "--family", "trigonometric", "--b", "0.8", "--eta", "0.9+0.05i",
            "--no-progress"]
    init3 = ",".join(init.split(",")[:9])
    r = cli("orbit", *trig, "--steps", "30000", "--save-every", "100", "--out", "t", f"--init={init3}")
    assert r.returncode == 0 and "compiling" not in r.stderr, r.stderr
    r = cli("ensemble", *trig, "--steps", "100", "--input", "t/orbit.csv", "--out", "te", "--backend", "compiled")
    assert r.returncode == 0 and "compiling" not in r.stderr, r.stderr
    assert sorted(p.name for p in (tmp_path / "cache").rglob("*.nbc")) == compiled
