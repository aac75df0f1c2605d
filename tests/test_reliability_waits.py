"""Issue 35, item 5: every wait can be interrupted or is bounded.

* an adaptive integrator's tolerance has a floor (``jetgaudin.flows.RTOL_FLOOR``): ``flow --method heyoka --rtol
  1e-300`` ran for ever past 1.2 GB, deaf to SIGINT; now it is refused at once (one line, exit 2);
* a SIGINT that comes as the last step is saved (during the last checkpoint or progress call) is not lost: the run
  is complete, and the command stops there with 130 (before: it went on to draw the figures and exited 0)."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from test_run import one_line_error, run_cli

from conftest import APPENDIX2_X0


@pytest.mark.parametrize("method", ["heyoka", "DOP853"])
def test_a_tolerance_below_the_floor_is_refused_at_once(tmp_path, capsys, method):
    code, _, err = run_cli(capsys, "flow", "--method", method, "--rtol", "1e-300", "--steps", 5, "--no-plots",
                           "--out", tmp_path / "f")
    assert one_line_error(code, err) and "--rtol" in err
    assert not (tmp_path / "f").exists()
    H = jg.physical_hamiltonian(3, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="rtol"):
        jg.integrate(H, np.array(APPENDIX2_X0), 1.0, method=method, rtol=1e-300)
    with pytest.raises(jg.InvalidParameterError, match="rtol"):
        jg.FlowMap(H, 0.1, method, rtol=1e-300)


def _kill_at_end(n, total):
    if n >= total:
        os.kill(os.getpid(), signal.SIGINT)


def test_a_signal_as_the_run_completes_is_reported(tmp_path):
    spec = rl.RunSpec(jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="numpy"), np.array(APPENDIX2_X0), 20, 1)
    with pytest.raises(rl.RunInterrupted, match="as the run completed") as exc:
        rl.start(spec, tmp_path / "r", progress=_kill_at_end)
    assert exc.value.exit_code == 130 and exc.value.result.status == "completed"
    assert rl.read_run(tmp_path / "r", verify=True)["status"] == "completed"


def test_the_command_exits_130_and_draws_nothing_after_such_a_signal(tmp_path, capsys, monkeypatch):
    from jetgaudin.cli import _common

    monkeypatch.setattr(_common.LazyProgress, "__call__", lambda self, n, total: _kill_at_end(n, total))
    code, _, err = run_cli(capsys, "orbit", "--steps", 20, "--kernel", "numpy", "--out", tmp_path / "o")
    assert code == 130 and "as the run completed" in err, err
    assert not (tmp_path / "o" / "figure1.png").exists()
    assert rl.read_run(tmp_path / "o")["status"] == "completed"
