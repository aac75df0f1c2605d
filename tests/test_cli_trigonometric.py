"""`--family trigonometric` and `--gamma` on orbit, ensemble, flow and info (issue 23), through the real entry point
in-process.  References are the library's model and map called directly (the CLI only converts text): bit for bit
for orbit.h5 / ensemble.h5, the flow's comparison with the map at the flow's tolerance."""

from __future__ import annotations

import numpy as np
import pytest

from jetgaudin import run as rl
from jetgaudin.gaudin import GaudinModel
from test_cli_chains import one_line_error, with_options
from test_run import run_cli

SITES = "-0.5:1,0.4:2"
MODEL = GaudinModel(0.8, [(-0.5, 1), (0.4, 2)], family="trigonometric", gamma=0.7)
ETA = 1.5 + 0.2j
X0 = np.round(np.random.default_rng(7).normal(size=9), 3)
INIT = ",".join(repr(float(v)) for v in X0)
COMMON = ("--sites", SITES, "--family", "trigonometric", "--gamma", "0.7", "--b", "0.8", "--eta", "1.5+0.2i")


@pytest.mark.parametrize("args, words", [
    (("--gamma", "-1"), ["--gamma", "> 0"]),
    (("--gamma", "abc"), ["--gamma"]),
    (("--family", "elliptical"), ["--family", "unknown"]),
    (("--family", "rational", "--gamma", "0.5"), ["--gamma", "anisotropy"]),
    (("--gamma", "1.5707963267948966", "--eta", "2+0.3i"), ["--sites", "is a site", "modulo"]),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, args, words):
    base = ["orbit", "--sites", "0:1,1:1", "--family", "trigonometric", "--b", "0.8", "--eta", "0.5+0.3i",
            "--init", "1,0,0.3,0.2,0.1,-0.5", "--steps", "3", "--out", tmp_path / "x"]
    code, _, err = run_cli(capsys, *with_options(base, args))
    assert one_line_error(code, err, *words), err


def test_zero_b_and_J_refused_and_family_needs_sites(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", "--sites", "0:1,1:1", "--family", "trigonometric", "--b", "0", "--eta",
                           "0.5+0.3i", "--init", "1,0,0.5,0.2,0.1,-0.5", "--out", tmp_path / "z")
    assert one_line_error(code, err, "J"), err
    for cmd in ("orbit", "info", "flow"):
        code, _, err = run_cli(capsys, cmd, "--family", "trigonometric", "--out", tmp_path / cmd) if cmd != "info" \
            else run_cli(capsys, cmd, "--family", "trigonometric")
        assert one_line_error(code, err, "--family", "--sites"), (cmd, err)


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_run_layer_interrupt_and_resume_bit_for_bit(tmp_path, backend):
    """The run layer drives the trigonometric map like any map: an interrupted run (SIGINT after step 9, chunks of 3)
    resumed from its run.json (the map rebuilt from its description, family and gamma included) equals the
    uninterrupted orbit bit for bit."""
    from test_gaudin_run import interrupt

    B = MODEL.two_point_backlund(ETA, kernel=backend)
    interrupt(rl.RunSpec(B, X0, 60, 4, checkpoint_seconds=0.0, program="jetgaudin orbit"), tmp_path / "i", 9)
    res = rl.resume(tmp_path / "i")
    assert res.state is rl.RunStatus.COMPLETED
    assert np.array_equal(rl.load(tmp_path / "i").X, B.iterate(X0, 60, save_every=4))


def test_plot_of_a_trigonometric_run(tmp_path, capsys):
    code, _, err = run_cli(capsys, "orbit", *COMMON, "--init", INIT, "--steps", "5", "--kernel", "numpy",
                           "--no-plots", "--out", tmp_path / "o")
    assert code == 0, err
    code, out, err = run_cli(capsys, "plot", tmp_path / "o")
    assert code == 0 and "wrote" in out, err


def test_warmup_compiles_the_family_kernel(capsys):
    code, out, err = run_cli(capsys, "warmup")
    assert code == 0 and "the family kernel (trigonometric chains)" in out, err
