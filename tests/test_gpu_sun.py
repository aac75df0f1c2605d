"""The su(3) GPU route (``SunTwoPointBacklund(..., backend="gpu")``, issue 32) on Numba's CUDA simulator.

As in ``tests/test_gpu.py``: the simulator runs the kernel's logic as Python (thread indexing, thread-local scratch, the
rows a thread writes, the per-orbit status, the copies back) around the same compiled orbit loop the CPU route runs
(:func:`jetgaudin.gaudin._sun_kernel.orbit_loop`), so there the GPU route must give the compiled route's bits exactly.
With ``JETGAUDIN_TEST_REAL_GPU=1`` the tolerance is round-off per step (NVVM contracts products and sums into fused
operations): 1e-14 per step times the number of steps, that file's bound.  (Not yet run on a GPU.)  Sizes are tiny:
the simulator is slow.
"""

from __future__ import annotations

# the GPU tests' set-up (the simulator switched on before numba.cuda is imported; skipped without numba-cuda or a GPU
# route) and their tolerance rule ``same``: equal bits under the simulator, 1e-14 per step on a real GPU
from test_gpu import REAL, same  # isort: skip

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import gpu
from jetgaudin.gaudin import _sun_kernel
from jetgaudin.gpu import _kernels
from jetgaudin.maps import Backend

FIELD = [0.3, -0.1, 0.5, 0.2, 0.0, -0.2, 0.1, 0.4]
ETA = 0.4 + 0.1j


def model(sites=((0.0, 1), (1.0, 2))):
    return jg.GaudinModel(FIELD, list(sites), algebra="su3")


def states(m, B=3, seed=1):
    return 0.5 * np.random.default_rng(seed).normal(size=(B, m.n_state))


@pytest.mark.parametrize("branch", [0, 1, 2])
def test_gpu_equals_the_compiled_route(branch):
    """Every branch, a batch of 3 orbits and a single orbit, rows, final state and the carried ``μ_r``."""
    m = model()
    X = states(m)
    B = m.two_point_backlund(ETA, branch=branch)
    g, mg = B.iterate(X, 6, save_every=2, backend="gpu", return_carry=True)
    c, mc = B.iterate(X, 6, save_every=2, backend="compiled", return_carry=True)
    same(g, c, 6)
    same(mg, mc, 6)
    same(B.iterate(X[1], 4, backend="gpu"), B.iterate(X[1], 4, backend="compiled"), 4)


def test_save_every_and_split_runs():
    """``save_every`` rows are the subsampled orbit (a last step that is not saved still reaches the final state), and
    a run split in two with the carried ``μ_r`` is the unsplit run bit for bit (the same device: exact everywhere)."""
    m = model()
    X = states(m, B=2, seed=4)
    Bg = m.two_point_backlund(ETA, branch=1, backend="gpu")
    assert Bg.has_gpu and Bg.resolved_backend(X, 5) is Backend.GPU
    full = Bg.iterate(X, 5)
    np.testing.assert_array_equal(Bg.iterate(X, 5, save_every=2), full[::2])
    a = Bg.advance(X, None, 5, 2)
    assert a.rows.shape == (2, 2, m.n_state)
    np.testing.assert_array_equal(a.X, full[-1])
    first = Bg.advance(X, None, 2)
    second = Bg.advance(first.X, first.carry, 3)
    np.testing.assert_array_equal(second.X, full[-1])
    np.testing.assert_array_equal(second.carry, a.carry)


def test_per_orbit_status():
    """An orbit of size 1e200 overflows (``tr ℓ²`` is inf, so ``μ`` is NaN): status 1 for it alone, the others run on
    and equal the compiled route; the map raises a :class:`SingularStepError` naming that orbit."""
    m = model()
    X = states(m)
    X[1] *= 1e200
    B = m.two_point_backlund(ETA, branch=0)
    mu = np.array([B.start(X[[0]])[0], 1.0 + 0j, B.start(X[[2]])[0]])
    c = _sun_kernel.orbit_constants(m, B.eta)
    rows, final, last, status = gpu.run_sun_batch(X, c[0], mu, *c[1:], B.eta, 3, 1)
    np.testing.assert_array_equal(status, [0, 1, 0])
    ref = _sun_kernel.run_batch(X[[0, 2]], c[0], mu[[0, 2], None], np.repeat(c[1][None, None], 2, axis=0), *c[2:],
                                np.full((2, 1), B.eta), 3, 1, 1)  # one map (k = 1) per orbit
    same(rows[:, [0, 2]], ref[0], 3)
    same(final[[0, 2]], ref[1], 3)
    with pytest.raises(jg.SingularStepError, match="orbit 1 of the su"):
        B.with_backend("gpu")._compiled_advance(X, mu, 3, 1, gpu=True)


def test_gpu_route_refusals(monkeypatch):
    """su(n), n != 3, has no GPU route; a model beyond the kernel's fixed scratch is refused before launching; no GPU
    is the one typed error of every map."""
    with pytest.raises(jg.InvalidParameterError, match="has no GPU route"):
        jg.GaudinModel(0.5, [(0.0, 1)], algebra="su4").two_point_backlund(0.5 + 0.1j, backend="gpu")
    big = model([(0.0, _kernels.MAX_ORDER + 1)])
    with pytest.raises(jg.InvalidParameterError, match="site orders up to"):
        big.two_point_backlund(ETA, backend="gpu").iterate(0.1 * np.ones(big.n_state), 1)
    import jetgaudin.gpu._device as dev

    monkeypatch.setattr(dev, "probe", lambda: (False, "the GPU backend found no NVIDIA GPU with a working CUDA "
                                                      "driver on this machine"))
    with pytest.raises(gpu.GPUUnavailableError, match="backend 'gpu': the GPU backend found no NVIDIA GPU"):
        model().two_point_backlund(ETA, backend="gpu")
    assert model().two_point_backlund(ETA).resolved_backend(np.zeros((2**17, 24)), 10**6) is Backend.COMPILED


@pytest.mark.skipif(REAL, reason="plants a Python loop, which only the simulator runs")
def test_a_planted_bug_is_caught(monkeypatch):
    """The comparison above sees one ulp: a kernel whose loop starts from ``μ_r`` one ulp off (what a mix-up of the
    orbits' carries, or a lossy copy to the device, would do) no longer gives the compiled route's bits."""
    m = model()
    X = states(m, B=2)
    B = m.two_point_backlund(ETA, branch=2)
    loop = _sun_kernel.orbit_loop

    def planted(*a):
        a = list(a)
        a[5] = a[5] * (1 + 2.0**-52)
        return loop(*a)

    _kernels.sun_kernel.cache_clear()
    monkeypatch.setattr(_sun_kernel, "orbit_loop", planted)
    try:
        g = B.iterate(X, 3, backend="gpu")
    finally:
        _kernels.sun_kernel.cache_clear()
    with pytest.raises(AssertionError):
        same(g, B.iterate(X, 3, backend="compiled"), 3)


def test_cli_su3_ensemble_on_the_gpu(tmp_path):
    """``ensemble --algebra su3 --backend gpu`` runs through the run layer, records the route, and saves the compiled
    route's states (bit for bit under the simulator)."""
    import h5py
    from typer.testing import CliRunner

    import jetgaudin.run
    from jetgaudin.cli import app

    base = ["ensemble", "--sites", "0:1,1:1", "--algebra", "su3", "--b", "0.5", "--eta", "0.4+0.1i", "--orbits", "2",
            "--steps", "4", "--save-every", "2"]
    states = {}
    for route in ("gpu", "compiled"):
        r = CliRunner().invoke(app, [*base, "--backend", route, "--out", str(tmp_path / route)])
        assert r.exit_code == 0, r.output
        assert jetgaudin.run.read_run(tmp_path / route)["inputs"]["backend"] == route
        with h5py.File(tmp_path / route / "ensemble.h5") as f:
            states[route] = f["states"][()]
    assert states["gpu"].shape == (3, 2, 16)
    same(states["gpu"], states["compiled"], 4)
