"""su(n) chains through the run layer (issue 32): an orbit, an ensemble and a flow of an su(3) chain are recorded
like any map's, with states of (n² − 1) M components.  References are the map's own `iterate` in one call (no
chunks, no files), so `np.array_equal` checks the chunking, the files, the checkpoints and the resume bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.gaudin import ChainFlowMap
from jetgaudin.run.spec import block_size
from test_gaudin_run import interrupt

MODEL = jg.GaudinModel(0.5, [(-1.0, 2), (0.7, 1)], algebra="su3")  # M = 3, 24 components
ETA = 0.3 + 0.25j
BACKENDS = ["numpy", "compiled"]


def states(B: int, seed: int = 3) -> np.ndarray:
    return 0.5 * np.random.default_rng(seed).normal(size=(B, MODEL.n_state))


def sun_map(backend: str, branch: int = 1) -> jg.SunTwoPointBacklund:
    return jg.SunTwoPointBacklund(MODEL, ETA, branch, backend)


def spec(X0, steps, backend, every=1, branch=1):
    return rl.RunSpec(sun_map(backend, branch), X0, steps, every, checkpoint_seconds=0.0,
                      program="jetgaudin ensemble" if np.ndim(X0) == 2 else "jetgaudin orbit")


def test_the_layout_is_the_models():
    """Components per site and order: 8 for su(3), 3 for the su(2) chain and for the top's map."""
    assert block_size(sun_map("numpy")) == 8 and MODEL.n_state == 24
    assert block_size(jg.ChainTwoPointBacklund(jg.GaudinModel(0.5, [(0.0, 1)]), 0.3 + 0.1j)) == 3
    assert block_size(jg.TwoPointBacklund(1.0, 0.3 + 0.1j)) == 3
    with pytest.raises(jg.InvalidParameterError, match="the map acts on 24"):
        rl.RunSpec(sun_map("numpy"), np.zeros(16) + 0.1, 3)


@pytest.mark.parametrize("backend", BACKENDS)
def test_orbit_run_equals_the_single_orbit_bit_for_bit(tmp_path, backend):
    X0 = states(1)[0]
    res = rl.start(spec(X0, 20, backend, every=3, branch=2), tmp_path / "o", max_chunk_steps=5)
    assert res.state is rl.RunStatus.COMPLETED and res.kernel == backend
    d = rl.load(tmp_path / "o")
    ref = sun_map(backend, 2).iterate(X0, 20)
    np.testing.assert_array_equal(d.n, list(range(0, 20, 3)) + [20])
    assert np.array_equal(d.X, ref[d.n])
    assert np.array_equal(rl.read_csv(tmp_path / "o" / "orbit.csv")[1], d.X)
    # the CSV header names the 8 components of each jet order of each site (written out, not from the code)
    header = (tmp_path / "o" / "orbit.csv").read_text().splitlines()[0].split(",")
    assert header == ["n"] + [f"s{s}_y{k}^{a}" for s, k in ((1, 0), (1, 1), (2, 0)) for a in range(1, 9)]
    run = rl.read_run(tmp_path / "o")
    assert run["map"] == sun_map(backend, 2).describe() and run["inputs"]["N"] == 3
    assert run["integral_names"] == MODEL.integral_labels()
    # the radius checked is |y_{N-1}| of the last site: its 8 components (a Casimir of su(3))
    assert run["sphere"]["radius0"] == np.linalg.norm(X0[-8:])
    assert run["sphere"]["max_deviation"] <= 1e-12  # round-off over 20 steps of O(1) states
    I = MODEL.integrals(ref[d.n])
    assert np.array_equal(res.drift_abs, np.abs(I - I[0]).max(axis=0))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("B", [None, 2])
def test_interrupted_run_resumes_bit_for_bit(tmp_path, backend, B):
    X0 = states(1)[0] if B is None else states(B)
    out = tmp_path / "i"
    assert 0 < interrupt(spec(X0, 30, backend, every=4), out, 7).last_safe_step < 30
    assert rl.read_run(out)["status"] == "interrupted"
    res = rl.resume(out)
    assert res.state is rl.RunStatus.COMPLETED
    d = rl.load(out)
    ref = sun_map(backend).iterate(X0, 30)
    np.testing.assert_array_equal(d.n, list(range(0, 30, 4)) + [30])
    assert np.array_equal(d.X, ref[d.n])
    if B is not None:
        assert rl.read_run(out)["inputs"]["N"] == 3 and rl.read_run(out)["map"]["kind"] == "sun_two_point"


def test_flow_run(tmp_path):
    """The flow of G^(1)_η (ChainFlowMap of the su(3) Hamiltonian): one unit of time is one map step (DOP853 at
    rtol = atol = 1e-12 over 4 units: 1e-9 relative, as for the su(2) chains)."""
    X = states(1)[0]
    F = ChainFlowMap(MODEL.interpolating_flow_hamiltonian(X, ETA, branch=1), 0.5)
    rl.start(rl.RunSpec(F, X, 8, program="jetgaudin flow"), tmp_path / "f")
    d = rl.load(tmp_path / "f")
    ref = sun_map("numpy").iterate(X, 4)
    assert np.abs(d.X[::2] - ref).max() <= 1e-9 * (1 + np.abs(ref).max())
