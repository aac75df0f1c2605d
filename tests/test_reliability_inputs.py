"""Issue 35, item 4: input the command line accepted and now refuses with one line (exit 2), or handles.

Each test failed before the change (checked against ``main`` 4744594), but three controls (the Devanagari digit,
refused before for another reason; ``--save-every 2.5``; counts in scientific notation, which must stay accepted):
``--sites`` read Unicode digits (``١:3`` was
site 1.0); ``flow`` wrote ``Infinity`` into ``run.json``; ``--steps 1e-99999`` ran 0 steps and
``--steps 3.0000000000000001`` ran 3; ``--show 2**63`` was accepted; ``--init`` with ``--init-from`` ignored one;
``ensemble --init-from`` a rational chain with ``--gamma`` became trigonometric, and an elliptic ensemble demanded
``--b 0``; a kernel edited from compiled to NumPy took minutes to be refused; ``ulimit -v`` 300 MB gave exit 2 and
llvmlite's "Could not find/load shared object" message."""

from __future__ import annotations

import copy
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.run.files import write_run
from test_run import one_line_error, run_cli

from conftest import APPENDIX2_X0

SRC = str(Path(jg.__file__).resolve().parents[1])  # the package under test


@pytest.mark.parametrize("args", [
    ["orbit", "--sites", "\u0661:3", "--steps", "3"],  # ARABIC-INDIC DIGIT ONE
    ["orbit", "--sites", "0:3,\u0967:3", "--steps", "3"],  # DEVANAGARI DIGIT ONE
    ["orbit", "--steps", "1e-99999"],
    ["orbit", "--steps", "3.0000000000000001"],
    ["orbit", "--save-every", "2.5"],
    ["ensemble", "--show", str(2**63), "--orbits", "2", "--steps", "2", "--no-progress"],
    ["ensemble", "--sites", ",".join(f"{i + 0.5}:1" for i in range(2000)), "--orbits", "2", "--steps", "2",
     "--no-progress"],  # before: a MemoryError for an array of 4000 x 2000 x 2000 doubles (128 GiB)
    ["orbit", "--init-from", "SOURCE", "--init", ",".join(map(str, APPENDIX2_X0)), "--steps", "3"],
    ["flow", "--init-from", "SOURCE", "--init", ",".join(map(str, APPENDIX2_X0)), "--steps", "3"],
], ids=["sites arabic digit", "sites devanagari digit", "steps 1e-99999", "steps 3.0000000000000001",
        "save-every 2.5", "show 2**63", "ensemble 2000 sites", "orbit init and init-from", "flow init and init-from"])
def test_refused_with_one_line_and_nothing_created(tmp_path, capsys, args):
    src = tmp_path / "src"
    if "SOURCE" in args:
        assert run_cli(capsys, "orbit", "--steps", 5, "--no-plots", "--out", src)[0] == 0
    args = [str(src) if a == "SOURCE" else a for a in args]
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "out", *(["--no-plots"] if args[0] != "ensemble"
                                                                        else []))
    assert one_line_error(code, err), (code, err)
    assert not (tmp_path / "out").exists()


def test_counts_in_scientific_notation_stay_exact(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--steps", "2.5e1", "--save-every", "1e1", "--kernel", "numpy",
                           "--no-plots", "--out", tmp_path / "o")
    assert code == 0, err
    assert rl.load(tmp_path / "o").n.tolist() == [0, 10, 20, 25]


def _no_constants(name):
    raise ValueError(f"not JSON: {name}")


def test_flow_run_json_is_strict_json_and_resumable_fields_read_back(tmp_path, capsys):
    out = tmp_path / "f"
    assert run_cli(capsys, "flow", "--steps", 20, "--no-plots", "--out", out)[0] == 0
    text = (out / "run.json").read_text()
    run = json.loads(text, parse_constant=_no_constants)  # before: "max_drift": Infinity
    assert run["inputs"]["max_drift"] is None and run["inputs"]["max_imag"] is None
    assert rl.read_run(out, verify=True)["status"] == "completed"


def test_a_non_finite_summary_is_recorded_as_null():
    from jetgaudin.run.files import run_digest, run_json_text

    run = {"inputs": {}, "status": "x", "a": [1.0, float("nan"), float("-inf")], "b": {"c": float("inf")}}
    back = json.loads(run_json_text(run), parse_constant=_no_constants)
    assert back["a"] == [1.0, None, None] and back["b"]["c"] is None and back["sha256"] == run_digest(back)


@pytest.fixture
def rational_chain(tmp_path, capsys):
    src = tmp_path / "chain"
    code, _, err = run_cli(capsys, "ensemble", "--sites", "0:1,1:1", "--orbits", 2, "--steps", 4, "--no-progress",
                           "--out", src)
    assert code == 0, err
    return src


def test_init_from_a_rational_chain_with_gamma_is_refused(rational_chain, tmp_path, capsys):
    code, _, err = run_cli(capsys, "ensemble", "--init-from", rational_chain, "--gamma", "0.5", "--steps", 3,
                           "--no-progress", "--out", tmp_path / "o")
    assert one_line_error(code, err) and "rational" in err and "--family trigonometric" in err
    assert not (tmp_path / "o").exists()
    code, _, err = run_cli(capsys, "ensemble", "--init-from", rational_chain, "--family", "trigonometric",
                           "--gamma", "0.5", "--steps", 3, "--no-progress", "--out", tmp_path / "o2")
    assert code == 0, err  # an explicit change of family is the user's choice
    assert rl.read_run(tmp_path / "o2")["map"]["family"] == "trigonometric"


def test_init_from_an_elliptic_ensemble_takes_its_b(tmp_path, capsys):
    src = tmp_path / "ell"
    code, _, err = run_cli(capsys, "ensemble", "--sites", "0:1,1:1", "--family", "elliptic", "--modulus", "0.5",
                           "--b", "0", "--orbits", 2, "--steps", 4, "--no-progress", "--out", src)
    assert code == 0, err
    code, _, err = run_cli(capsys, "ensemble", "--init-from", src, "--steps", 3, "--no-progress",
                           "--out", tmp_path / "o")
    assert code == 0, err  # before: "--b: ... has no field; give --b 0"
    m = rl.read_run(tmp_path / "o")["map"]
    assert m["b"] == 0.0 and m["family"] == "elliptic"


@pytest.mark.slow
def test_a_kernel_edited_from_compiled_to_numpy_is_refused_quickly(tmp_path):
    """A compiled run stopped after ~1 s of 0.1 s kernel calls (save_every 10^6): its replay with the NumPy kernel
    would take minutes (about 100 times slower); the replay's time budget (20 times the recorded rate, at least
    3 s) refuses it.  The bound 40 s leaves room for a loaded machine; before: 3 minutes."""
    m = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="compiled")
    m.prepare_kernels(np.array(APPENDIX2_X0), 10**8, lambda _m: None)
    t0 = time.monotonic()

    def progress(n, _total):
        if time.monotonic() - t0 > 1.5:
            os.kill(os.getpid(), signal.SIGINT)

    spec = rl.RunSpec(m, np.array(APPENDIX2_X0), 10**9, 10**6, checkpoint_seconds=0.0)
    with pytest.raises(rl.RunInterrupted):
        rl.start(spec, tmp_path / "r", progress=progress)
    run = rl.read_run(tmp_path / "r")
    assert run["checkpoint"]["step"] - run["checkpoint"]["anchor"]["step"] > 10**5  # a real kernel call replayed
    edited = copy.deepcopy(run)
    edited["map"]["backend"] = edited["inputs"]["kernel"] = "numpy"
    write_run(tmp_path / "r", edited)
    t1 = time.monotonic()
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(tmp_path / "r")
    assert time.monotonic() - t1 < 40


def _limit_as(nbytes):
    def apply():
        resource.setrlimit(resource.RLIMIT_AS, (nbytes, nbytes))
    return apply


@pytest.mark.slow
@pytest.mark.parametrize("mb", [200, 300])
def test_an_address_space_limit_is_one_clear_line(tmp_path, mb):
    env = dict(os.environ, PYTHONPATH=SRC)
    p = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--steps", "1000", "--kernel", "compiled",
                        "--no-plots", "--out", str(tmp_path / "o")], env=env, capture_output=True, text=True,
                       timeout=120, preexec_fn=_limit_as(mb << 20))
    if p.returncode == 0:
        pytest.skip(f"the command ran within {mb} MB here")
    assert one_line_error(p.returncode, p.stderr, expected=1), p.stderr
    assert "out of memory under the address-space limit" in p.stderr
