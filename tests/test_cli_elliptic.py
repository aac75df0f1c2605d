"""`--family elliptic --modulus k` on orbit, ensemble, flow and info (issue 24), through the real entry point
in-process; references are the library's model and map called directly (bit for bit for orbit.h5 / ensemble.h5)."""

from __future__ import annotations

import numpy as np
import pytest

from jetgaudin import run as rl
from jetgaudin.gaudin import GaudinModel
from test_cli_chains import one_line_error, with_options
from test_run import run_cli

SITES = "-0.5:1,0.4:2"
MODEL = GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6)
ETA = 1.5 + 0.2j
X0 = np.round(np.random.default_rng(7).normal(size=9), 3)
INIT = ",".join(repr(float(v)) for v in X0)
COMMON = ("--sites", SITES, "--family", "elliptic", "--modulus", "0.6", "--b", "0", "--eta", "1.5+0.2i")


@pytest.mark.parametrize("args, words", [
    (("--b", "0.5"), ["--b", "no field"]),
    (("--modulus", "1"), ["--modulus", "[0, 1)"]),
    (("--modulus", "-0.2"), ["--modulus", "[0, 1)"]),
    (("--modulus", "abc"), ["--modulus"]),
    (("--gamma", "0.5"), ["--gamma", "anisotropy"]),
    (("--eta", f"{2 * 1.9953027776647296!r}+0.3i"), ["is a site", "modulo"]),  # Re eta = 2K, K(0.8) = 1.9953
    (("--eta", "0.5+1.7i"), ["too close to K'"]),  # 1.7 > 0.9 K'(0.8) = 1.576
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, args, words):
    base = ["orbit", "--sites", "0:1,1:1", "--family", "elliptic", "--modulus", "0.8", "--b", "0", "--eta",
            "0.5+0.3i", "--init", "1,0,0.3,0.2,0.1,-0.5", "--steps", "3", "--out", tmp_path / "x"]
    code, _, err = run_cli(capsys, *with_options(base, args))
    assert one_line_error(code, err, *words), err


def test_family_needs_modulus_and_modulus_needs_elliptic(tmp_path, capsys):
    code, _, err = run_cli(capsys, "info", "--sites", "0:1,1:1", "--family", "elliptic", "--b", "0", "--init",
                           "1,0,0.3,0.2,0.1,-0.5")
    assert one_line_error(code, err, "--modulus"), err
    code, _, err = run_cli(capsys, "info", "--sites", "0:1,1:1", "--family", "trigonometric", "--modulus", "0.3",
                           "--b", "1", "--init", "1,0,0.3,0.2,0.1,-0.5")
    assert one_line_error(code, err, "--modulus", "elliptic"), err


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_resume_and_plot(tmp_path, capsys, backend):
    """An interrupted elliptic run (SIGINT after step 6, chunks of 3) resumed from run.json (the map rebuilt from its
    description: family and modulus) equals the uninterrupted orbit bit for bit; `plot` draws the finished run."""
    from test_gaudin_run import interrupt

    B = MODEL.two_point_backlund(ETA, kernel=backend)
    interrupt(rl.RunSpec(B, X0, 24, 2, checkpoint_seconds=0.0, program="jetgaudin orbit"), tmp_path / "i", 6)
    assert rl.resume(tmp_path / "i").state is rl.RunStatus.COMPLETED
    assert np.array_equal(rl.load(tmp_path / "i").X, B.iterate(X0, 24, save_every=2))
    code, out, err = run_cli(capsys, "plot", tmp_path / "i")
    assert code == 0 and "wrote" in out, err
