"""The GPU route (``backend="gpu"``, :mod:`jetgaudin.gpu`), tested without a GPU through Numba's CUDA simulator.

The simulator runs the kernels' logic as Python (thread indexing, thread-local scratch, the rows a thread writes, the
status and failing step, the copies back) around the same compiled orbit loop the CPU route runs, so there the GPU
route must give the CPU route's bits exactly.  On a real GPU (``JETGAUDIN_TEST_REAL_GPU=1``, as run on a lent H200)
NVVM contracts products and sums into fused operations, so the tolerance is then round-off per step: measured
1.4e-16 relative after one step and 7.5e-16 after 50 (``docs/performance.md``, the GPU section); the tests allow
1e-14 per step (the issue's bound) times the number of steps.
"""

from __future__ import annotations

import os

REAL = os.environ.get("JETGAUDIN_TEST_REAL_GPU", "0") == "1"
if not REAL:
    os.environ["NUMBA_ENABLE_CUDASIM"] = "1"  # before numba.cuda is imported (jetgaudin imports it only here)

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import jetgaudin as jg  # noqa: E402
from jetgaudin.ensemble import iterate_ensemble, sample_on_leaf  # noqa: E402

pytest.importorskip("numba_cuda", reason="the GPU route's tests need numba-cuda (pip install 'jetgaudin[gpu]')")

from jetgaudin import gpu  # noqa: E402
from jetgaudin.backlund.kernels import _drivers as C  # noqa: E402
from jetgaudin.maps import Backend  # noqa: E402

if not gpu.available():  # pragma: no cover - numba.cuda imported earlier in this process without the simulator
    pytest.skip(f"no GPU route here: {gpu.probe()[1]}", allow_module_level=True)


def same(a, b, steps: int = 1) -> None:
    """Equal bit for bit under the simulator; on a real GPU to 1e-14 relative per step (module docstring)."""
    a, b = np.asarray(a), np.asarray(b)
    if not REAL:
        np.testing.assert_array_equal(a, b)
    else:  # pragma: no cover - run on a lent GPU
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-14 * max(1, steps) * (1 + np.max(np.abs(b))))


def batch(B=5, N=3, seed=1):
    X = sample_on_leaf(N, list(np.linspace(0.5, 1.0, N)), B, seed=seed)
    b = np.linspace(0.8, 1.3, B)  # per-orbit parameters
    eta = (5 + 0.1j) + 0.05 * np.arange(B)
    return X, b, eta, C.nu_default(X, b, eta, 1)


@pytest.mark.parametrize("N, specialise", [(3, True), (3, False), (2, True), (4, True)])
def test_run_batch_equals_the_cpu_route(N, specialise):
    """Every output of the CPU batch driver (rows, final, drift, ν1, status, failing step), per-orbit b and η, the
    N = 3 real form and the generic route."""
    X, b, eta, nu0 = batch(N=N)
    g = gpu.run_batch(X, b, eta, nu0, False, 12, 4, specialise)
    c = C.run_batch(X, b, eta, nu0, False, 12, 4, specialise)
    for k in (0, 1, 3, 4, 5):
        same(g[k], c[k], 12)
    # the drift pass is NumPy's on the GPU route, compiled on the CPU: the same sums (simulator: the same states, at
    # most an ulp of the drift); on a GPU the states differ by ~1e-16 relative per step, so the integrals (quadratic,
    # of size ~10 here) by ~1e-14 over 12 steps: 1e-13
    np.testing.assert_allclose(g[2], c[2], rtol=0, atol=1e-13 if REAL else 1e-15)


def test_save_every_rows_are_the_subsampled_orbit():
    X, b, eta, nu0 = batch()
    full = gpu.run_batch(X, b, eta, nu0, False, 12, 1)[0]
    every3 = gpu.run_batch(X, b, eta, nu0, False, 12, 3)[0]
    assert every3.shape == (5, 5, 9)
    np.testing.assert_array_equal(every3, full[:, ::3])
    # a last step that is not saved still reaches the final state
    out, final = gpu.run_batch(X, b, eta, nu0, False, 11, 3)[:2]
    assert out.shape[1] == 4
    np.testing.assert_array_equal(final, full[:, 11])


def test_split_run_continues_the_branch_bit_for_bit():
    """ν1 carried between calls (``cont``: the root of ν² nearest to it, Newton-carried) gives the unsplit run's
    bits on the same device: what a resumed run relies on."""
    X, b, eta, nu0 = batch()
    whole = gpu.run_batch(X, b, eta, nu0, False, 10, 1)
    first = gpu.run_batch(X, b, eta, nu0, False, 4, 1)
    second = gpu.run_batch(first[1], b, eta, first[3], True, 6, 1)
    np.testing.assert_array_equal(second[1], whole[1])
    np.testing.assert_array_equal(second[3], whole[3])
    np.testing.assert_array_equal(second[0][:, 1:], whole[0][:, 5:])


def test_status_and_failing_step_of_failed_orbits():
    """A ν1 that is not the eigenvalue, used as given, fails the residual check; a state of size 1e155 overflows:
    the CPU route's status and failing step, the other orbits run on, and a failed orbit's later rows hold its last
    good state (as the CPU lanes)."""
    X, b, eta, nu0 = batch(B=4)
    nu0[1] *= 1 + 1e-3
    X[2] *= 1e155
    nu0[2] = 1.0
    g = gpu.run_batch(X, b, eta, nu0, False, 6, 2)
    c = C.run_batch(X, b, eta, nu0, False, 6, 2)
    np.testing.assert_array_equal(g[4], c[4])  # status
    np.testing.assert_array_equal(g[5], c[5])  # failing step
    assert set(np.flatnonzero(g[4])) == {1, 2}
    for i in (1, 2):
        np.testing.assert_array_equal(g[0][i], np.broadcast_to(X[i], (4, 9)))  # failed at step 0: frozen at X_0
    same(g[0][[0, 3]], c[0][[0, 3]], 6)
    with pytest.raises(jg.JetGaudinError, match="orbit 1"):
        gpu.iterate_batch(X, b, eta, nu0, False, 6, 2)


def test_maps_take_backend_gpu():
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 4, seed=2)
    B = jg.TwoPointBacklund(1.0, 5 + 0.1j)
    same(B.iterate(X, 9, save_every=3, backend="gpu"), B.iterate(X, 9, save_every=3, backend="compiled"), 9)
    Bg = jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="gpu")
    assert Bg.resolved_backend(X, 9) is Backend.GPU
    adv = Bg.advance(X, None, 9)
    same(adv.X, B.iterate(X, 9, backend="compiled")[-1], 9)
    r_gpu = iterate_ensemble(X, 1.0, 5 + 0.1j, 9, save_every=3, gpu=True)
    r_cpu = iterate_ensemble(X, 1.0, 5 + 0.1j, 9, save_every=3)
    same(r_gpu.states, r_cpu.states, 9)
    bb = jg.ensemble.BatchBacklund(np.ones(4), np.full(4, 5 + 0.1j), backend="gpu")
    same(bb.advance(X, None, 9).X, r_cpu.final, 9)


@pytest.mark.parametrize("family, kw", [("rational", {}), ("trigonometric", {"gamma": 0.7}),
                                        ("elliptic", {"modulus": 0.5})])
@pytest.mark.parametrize("sites", [[(0.0, 1), (0.9, 2)], [(0.0, 2), (0.9, 1)]])
def test_chain_maps_on_the_gpu(family, kw, sites):
    """Every family through the one family kernel: the compiled route's bits (its own kernel for trigonometric and
    elliptic chains) or, for rational chains (whose CPU route is the rational chain kernel, other sums), the NumPy
    route to 1e-13 (10 steps of states of size ~1; measured 5e-15).  A site of order 2 at λ = 0 too: the rational
    family's tables lost the derivative of its basis entry λ there (0.39 off after 3 steps)."""
    m = jg.GaudinModel(0.0 if family == "elliptic" else 0.8, sites, family=family, **kw)
    X = np.random.default_rng(0).normal(size=(3, m.n_state))
    T = m.two_point_backlund(0.4 + 0.05j)
    g = T.iterate(X, 10, save_every=2, backend="gpu")
    np.testing.assert_allclose(g, T.iterate(X, 10, save_every=2, backend="numpy"), rtol=0, atol=1e-13)
    if family != "rational":
        same(g, T.iterate(X, 10, save_every=2, backend="compiled"), 10)
    a = T.with_backend("gpu").advance(X, None, 4)
    b = T.with_backend("gpu").advance(a.X, a.carry, 6)
    same(b.X, g[-1], 10)  # a split run is the unsplit one


def test_no_gpu_is_one_typed_error_and_auto_never_picks_it(monkeypatch):
    import jetgaudin.gpu._device as dev

    monkeypatch.setattr(dev, "probe", lambda: (False, "the GPU backend found no NVIDIA GPU with a working CUDA "
                                                      "driver on this machine"))
    with pytest.raises(gpu.GPUUnavailableError, match="backend 'gpu': the GPU backend found no NVIDIA GPU") as e:
        jg.TwoPointBacklund(1.0, 5 + 0.1j, backend="gpu")
    assert "\n" not in str(e.value)
    assert isinstance(e.value, jg.InvalidParameterError)
    m = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 1)], family="trigonometric")
    with pytest.raises(gpu.GPUUnavailableError):
        m.two_point_backlund(0.4 + 0.05j, backend="gpu")
    X = np.zeros((2**17, 9))
    assert not gpu.auto_uses_gpu(2**17, 10**6)
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j).resolved_backend(X, 10**6) is Backend.COMPILED


def test_auto_rule_sizes(monkeypatch):
    """``auto`` takes the GPU only with a usable GPU (never the simulator), from GPU_MIN_ORBITS orbits and
    GPU_MIN_WORK orbit-steps on."""
    import jetgaudin.gpu._device as dev

    if not REAL:
        assert not gpu.auto_uses_gpu(2**20, 10**6)  # the simulator is never chosen
    monkeypatch.setattr(dev, "simulator", lambda: False)
    monkeypatch.setattr(gpu, "available", lambda: True)
    big = gpu.GPU_MIN_WORK // gpu.GPU_MIN_ORBITS + 1
    assert gpu.auto_uses_gpu(gpu.GPU_MIN_ORBITS, big)
    assert not gpu.auto_uses_gpu(gpu.GPU_MIN_ORBITS - 1, 10**12)  # one thread per orbit: too few orbits
    assert not gpu.auto_uses_gpu(gpu.GPU_MIN_ORBITS, big // 10)
    X = np.zeros((gpu.GPU_MIN_ORBITS, 9))
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j).resolved_backend(X, big) is Backend.GPU
    assert jg.OnePointBacklund(1.0, 5 + 0.1j).resolved_backend(X, big) is Backend.NUMPY  # no GPU route


def test_maps_without_a_gpu_route_refuse_it():
    with pytest.raises(jg.InvalidParameterError, match="has no GPU route"):
        jg.OnePointBacklund(1.0, 5 + 0.1j, backend="gpu")
    with pytest.raises(jg.InvalidParameterError, match="'gpu'"):
        jg.Backend.parse("cuda")


def test_cli_ensemble_backend_gpu(tmp_path, monkeypatch):
    """``ensemble --backend gpu`` runs (simulator) and records the route; a resume keeps it; without a GPU: one line
    and exit 2."""
    from typer.testing import CliRunner

    from jetgaudin.cli import app

    r = CliRunner().invoke(app, ["ensemble", "--orbits", "3", "--steps", "6", "--backend", "gpu", "--out",
                                 str(tmp_path / "e")])
    assert r.exit_code == 0, r.output
    run = jg.run.read_run(tmp_path / "e")
    assert run["inputs"]["backend"] == "gpu"
    import jetgaudin.gpu._device as dev

    monkeypatch.setattr(dev, "probe", lambda: (False, "the GPU backend needs the optional package numba-cuda"))
    r = CliRunner().invoke(app, ["ensemble", "--orbits", "3", "--steps", "6", "--backend", "gpu", "--out",
                                 str(tmp_path / "f")])
    assert r.exit_code == 2
    assert "--backend gpu: the GPU backend needs the optional package numba-cuda" in r.output
    assert not (tmp_path / "f").exists()


@pytest.mark.parametrize("kind", ["top", "trigonometric chain"])
def test_run_layer_interrupt_and_resume_on_the_gpu_bit_for_bit(tmp_path, kind):
    """A run on the GPU route interrupted by SIGINT resumes (replaying its anchor on the GPU route, as ``run.json``
    records it) to the uninterrupted GPU orbit bit for bit."""
    from jetgaudin import run as rl
    from test_gaudin_run import interrupt

    if kind == "top":
        X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], 3, seed=7)
        m = jg.ensemble.BatchBacklund(np.ones(3), np.full(3, 5 + 0.1j), backend="gpu")
    else:
        model = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 2)], family="trigonometric", gamma=0.7)
        X0 = np.random.default_rng(3).normal(size=(3, model.n_state))
        m = model.two_point_backlund(0.4 + 0.05j, backend="gpu")
    spec = rl.RunSpec(m, X0, 40, 4, rl.HealthLimits(max_drift=1e-6), csv=False, program="jetgaudin ensemble")
    assert 0 < interrupt(spec, tmp_path / "i", 9).last_safe_step < 40
    run = rl.read_run(tmp_path / "i")
    assert run["status"] == "interrupted"
    # the route is recorded, and a resume rebuilds the map on it (under the simulator the CPU route would give the
    # same bits: the record is what a resume on a GPU relies on)
    assert (run["inputs"]["backend"] if kind == "top" else run["map"]["backend"]) == "gpu"
    assert rl.resume(tmp_path / "i").state is rl.RunStatus.COMPLETED
    ref = m.iterate(X0, 40, save_every=4)
    np.testing.assert_array_equal(rl.load(tmp_path / "i").X, ref)


def test_a_call_that_does_not_fit_the_gpu_is_refused_before_allocating(monkeypatch):
    """The device arrays of a call are checked against the GPU's free memory first: one typed line naming the size,
    not CUDA's out-of-memory error (the simulator reports infinite memory: a GPU with 1 MiB free is faked)."""
    import jetgaudin.gpu._drivers as drv

    monkeypatch.setattr(drv, "_free_bytes", lambda c: float(2**20))
    X, b, eta, nu0 = batch(B=200)
    with pytest.raises(jg.InvalidParameterError, match=r"needs .* GiB on the GPU, which has 0.000977 GiB free"):
        gpu.run_batch(X, b, eta, nu0, False, 100, 1)
    gpu.run_batch(X[:2], b[:2], eta[:2], nu0[:2], False, 3, 3)  # a small call fits
    m = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 2)], family="trigonometric")
    T = m.two_point_backlund(0.4 + 0.05j, backend="gpu")
    with pytest.raises(jg.InvalidParameterError, match="on the GPU"):
        T.advance(np.random.default_rng(0).normal(size=(500, m.n_state)), None, 100)


@pytest.mark.parametrize("on_gpu", [True, False])
def test_ensemble_without_the_drift_pass(on_gpu):
    """``want_drift=False`` (what BatchBacklund.advance, hence the run layer, asks for: on the GPU route the pass runs
    on the host, ~1.5 s per 10⁶ orbits and row) gives the same orbits and no drift; asking a result without drift for
    it is one typed error."""
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], 4, seed=2)
    a = iterate_ensemble(X, 1.0, 5 + 0.1j, 9, save_every=3, gpu=on_gpu, want_drift=False)
    b = iterate_ensemble(X, 1.0, 5 + 0.1j, 9, save_every=3, gpu=on_gpu)
    np.testing.assert_array_equal(a.states, b.states)
    assert a.drift is None and b.drift is not None
    with pytest.raises(jg.InvalidParameterError, match="want_drift=False"):
        a.max_drift  # noqa: B018


# ---------------------------------------------------------------------------------------------------------------
# The run layer on the GPU with the states on the device between calls (jetgaudin.gpu._resident; issue 36)


def _resident_calls(monkeypatch):
    """Count the calls of the device-resident layer (the run layer must take it for an ensemble on the GPU)."""
    from jetgaudin.gpu import _resident

    calls = []
    original = _resident.ResidentMap.advance

    def counted(self, X, carry, steps, save_every=1):
        calls.append((isinstance(X, _resident.DeviceStates), steps, save_every))
        return original(self, X, carry, steps, save_every)

    monkeypatch.setattr(_resident.ResidentMap, "advance", counted)
    return calls


def _ens_spec(backend, B=6, steps=40, every=4, max_drift=1e-6, seed=5):
    from jetgaudin import run as rl

    X0 = sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=seed)
    m = jg.ensemble.BatchBacklund(np.linspace(0.9, 1.2, B), (5 + 0.1j) + 0.03 * np.arange(B), backend=backend)
    return rl.RunSpec(m, X0, steps, every, rl.HealthLimits(max_drift=max_drift), csv=False,
                      program="jetgaudin ensemble")


@pytest.mark.parametrize("chunk", [1, 3, 7, None])
def test_resident_split_runs_equal_the_unsplit_run_bit_for_bit(tmp_path, monkeypatch, chunk):
    """Calls of 1, 3, 7 steps (off the save grid of 4 for 3 and 7) or as the driver chooses: the states stay on the
    device between calls (every call after the first is given a device handle) and the saved rows equal the one-call
    GPU run bit for bit (the same kernel continued from the carried ν1)."""
    from jetgaudin import run as rl
    from jetgaudin.gpu import _resident

    calls = _resident_calls(monkeypatch)
    ahead = []
    original = _resident.DeviceStates.copy_ahead
    monkeypatch.setattr(_resident.DeviceStates, "copy_ahead", lambda self, buf, ev: (ahead.append(1),
                                                                                      original(self, buf, ev)))
    asked = []
    pinned = _resident.ResidentMap._pinned_rows
    monkeypatch.setattr(_resident.ResidentMap, "_pinned_rows",
                        lambda self, shape, dtype: (asked.append(shape), pinned(self, shape, dtype))[1])
    spec = _ens_spec("gpu")
    res = rl.start(spec, tmp_path / "r", max_chunk_steps=chunk)
    assert res.state is rl.RunStatus.COMPLETED
    assert calls and not calls[0][0] and all(c[0] for c in calls[1:])
    if chunk is not None:
        assert len(calls) >= -(-40 // chunk)  # at most `chunk` steps a call
    # the rows of exactly the calls that end on the save grid (or at the end) are copied ahead, on the copy stream,
    # each into a free pinned buffer of the pool (at most POOL of them: a chunk holding more calls' rows copies the
    # others when the loop takes them)
    ends = np.cumsum([c[1] for c in calls])
    assert len(asked) == sum(1 for e in ends if e % 4 == 0 or e == 40) > 0
    assert 0 < len(ahead) <= len(asked)
    ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 40, save_every=4, gpu=True, want_drift=False)
    d = rl.load(tmp_path / "r")
    np.testing.assert_array_equal(d.X, np.moveaxis(ref.states, 0, 1) if d.X.shape[0] == spec.B else ref.states)


def test_resident_health_and_drift_equal_the_cpu_route(tmp_path, monkeypatch):
    """The drift maxima, the radius deviation and the status computed on the device equal the host's (the CPU route
    through the same run layer) to round-off: |Δ drift| <= 4 ulp of max(1, |I(0)|) per integral (the device sums the
    integrals in another order than NumPy; under the simulator the states are the CPU's bits, so only that order
    differs).  Calls of 4 steps on the save grid of 4 for both (the driver's call length follows the measured rate,
    and a chunk ending off the grid has its end state checked: the states checked would depend on the timing)."""
    from jetgaudin import run as rl
    from jetgaudin.run import driver

    monkeypatch.setattr(driver.Driver, "_L", 4)
    monkeypatch.setattr(driver.Driver, "_adapt", lambda self, L, k, dt: 4)

    g = rl.start(_ens_spec("gpu"), tmp_path / "g")
    c = rl.start(_ens_spec("compiled"), tmp_path / "c")
    assert g.status == c.status == "completed"
    scale = np.maximum(1.0, np.abs(c.integrals0))
    # on a real GPU the states themselves differ by round-off per step (module docstring), and so do their integrals
    ulps = 4 if not REAL else 40 * 45  # 40 steps at 1e-14 ≈ 45 ulp each
    assert np.all(np.abs(g.drift_abs - c.drift_abs) <= ulps * np.spacing(scale))
    assert c.drift_abs.max() > 0  # round-off drift, not zeros: the comparison compares something
    r = 1.0 + np.abs(c.sphere_radius0).max()
    assert abs(g.sphere_max_deviation - c.sphere_max_deviation) <= ulps * np.spacing(r)
    same(rl.load(tmp_path / "g").X, rl.load(tmp_path / "c").X, 40)


def test_resident_orbit_failing_off_the_save_grid(tmp_path, monkeypatch):
    """An orbit whose step fails at step 13 (off the save grid of 4) on the device: the run fails with the CPU route's
    exception for that orbit, named in the status, at the start of the call that met it; the rows up to it are kept
    and equal the unfailed run (the failure is planted in the device's status arrays after the real kernel: the
    layer's handling of a device status is what is tested)."""
    from jetgaudin import run as rl
    from jetgaudin.backlund.kernels._status import STATUS_RESIDUAL
    from jetgaudin.gpu import _kernels

    real3, realg = _kernels.top_kernels()
    done = {"n": 0}

    class FailAt:
        def __getitem__(self, launch):
            def run(X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last):
                real3[launch](X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last)
                n0 = done["n"]
                done["n"] += int(steps)
                if n0 <= 13 < n0 + int(steps):
                    st, fl = status.copy_to_host(), fail.copy_to_host()
                    st[2], fl[2] = STATUS_RESIDUAL, 13 - n0
                    status.copy_to_device(st)
                    fail.copy_to_device(fl)
            return run

    monkeypatch.setattr(_kernels, "top_kernels", lambda: (FailAt(), realg))
    spec = _ens_spec("gpu")
    res = rl.start(spec, tmp_path / "f", max_chunk_steps=3)
    assert res.state is rl.RunStatus.FAILED
    # calls of 3 steps from 0: the call 12..15 meets step 13; its rows are discarded, the run stops at step 12
    assert res.status.startswith("failed: SingularStepError after step 12") and "orbit 2" in res.status
    assert res.last_safe_step == 12
    d = rl.load(tmp_path / "f")
    ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 12, save_every=4, gpu=True, want_drift=False)
    np.testing.assert_array_equal(d.X, np.moveaxis(ref.states, 0, 1) if d.X.shape[0] == spec.B else ref.states)


def test_resident_resume_bit_for_bit(tmp_path):
    """SIGINT at step 9 (calls of 3 steps), then resume: the checkpoint's states and ν1 come from the device; the
    resumed run equals the uninterrupted GPU run bit for bit."""
    from jetgaudin import run as rl
    from test_gaudin_run import interrupt

    spec = _ens_spec("gpu")
    assert 0 < interrupt(spec, tmp_path / "i", 9).last_safe_step < 40
    assert rl.resume(tmp_path / "i").state is rl.RunStatus.COMPLETED
    ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 40, save_every=4, gpu=True, want_drift=False)
    d = rl.load(tmp_path / "i")
    np.testing.assert_array_equal(d.X, np.moveaxis(ref.states, 0, 1) if d.X.shape[0] == spec.B else ref.states)


def _scaled(x, spin, f):
    """``x`` with the spin ``y_spin`` scaled by ``f``."""
    x = np.array(x)
    x[..., 3 * spin:3 * spin + 3] *= f
    return x


def test_resident_health_finds_the_planted_breach_and_folds_up_to_it(tmp_path, monkeypatch):
    """Rows of orbit 1 changed on the device after the real kernel, in one call of 20 steps: at step 8 its last spin
    ``y_2`` scaled by 1.004 (radius deviation 0.004, drifts below max_drift 1e-2), at step 12 its first spin ``y_0``
    by 1.5 (a breach, radius unchanged), at step 16 ``y_2`` by 1.3 (worse, after the breach).  The breach is the row
    of step 12 (worded as the CPU route words it), and the maxima fold the rows up to it and not the row after it in
    the same call: ``drift_abs`` of orbit 1 is the host's max |I(x) − I(0)| over the rows of steps 8 and 12, and the
    radius deviation that of step 8 (found on the device only: the host words the breach from row 12 alone).
    Tolerance 1e-12 relative: the device sums the integrals in another order."""
    from jetgaudin import run as rl
    from jetgaudin.gpu import _kernels

    real3, realg = _kernels.top_kernels()
    done = {"n": 0}
    change = {8: (2, 1.004), 12: (0, 1.5), 16: (2, 1.3)}

    class Change:
        def __getitem__(self, launch):
            def run(X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last):
                real3[launch](X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last)
                n0, se = done["n"], int(save_every)
                done["n"] += int(steps)
                rows = out.copy_to_host()
                for step, (spin, f) in change.items():
                    if n0 < step <= n0 + int(steps) and (step - n0) % se == 0:
                        rows[(step - n0) // se, 1] = _scaled(rows[(step - n0) // se, 1], spin, f)
                out.copy_to_device(rows)
            return run

    monkeypatch.setattr(_kernels, "top_kernels", lambda: (Change(), realg))
    spec = _ens_spec("gpu", max_drift=1e-2)
    res = rl.start(spec, tmp_path / "h", max_chunk_steps=20)
    assert res.status.startswith("failed: integral drift") and "of orbit 1" in res.status
    assert "at step 12 " in res.status and res.last_safe_step == 8
    ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 12, save_every=4, gpu=True, want_drift=False)
    x8, x12 = _scaled(ref.states[2, 1], *change[8]), _scaled(ref.states[3, 1], *change[12])
    I = jg.ensemble.per_orbit_integrals(np.array([x8, x12]), np.full(2, spec.map.b[1]))
    np.testing.assert_allclose(res.drift_abs[1], np.max(np.abs(I - res.integrals0[1]), axis=0), rtol=1e-12)
    r0 = np.linalg.norm(spec.X0[1, -3:])
    np.testing.assert_allclose(res.sphere_max_deviation, abs(np.linalg.norm(x8[-3:]) - r0), rtol=1e-12)


def test_prepare_compiles_the_resident_kernels_with_the_run_types(tmp_path, monkeypatch):
    """``gpu.prepare`` launches the resident route's kernels (``flag``, ``fold``, ``failed``) once, with the argument
    types the run's loop gives them, so that Numba compiles them there (outside the stepping rate) and not at their
    first call inside the timed loop (issue 36: ~1.4 s on an H200).  Every launch of the run has argument types (dtype,
    dimensions, layout; int or float scalars: ``numba.typeof``) that one of prepare's launches had; on a real GPU the
    run also adds no compiled overload."""
    import numba

    from jetgaudin import run as rl
    from jetgaudin.gpu import _drivers, _health, _resident

    real = _resident._health_kernels()
    seen: dict[str, dict[str, set]] = {"prepare": {}, "run": {}}
    phase = {"now": "prepare"}

    class Recorder:
        def __init__(self, name, kernel):
            self.name, self.kernel = name, kernel

        def __getitem__(self, launch):
            def run(*args):
                types = tuple(str(numba.typeof(a)) for a in args)
                seen[phase["now"]].setdefault(self.name, set()).add(types)
                return self.kernel[launch](*args)
            return run

    def recorded():
        return tuple(Recorder(n, k) for n, k in zip(("flag", "fold", "failed"), real, strict=True))

    monkeypatch.setattr(_resident, "_health_kernels", recorded)  # the run's launches
    monkeypatch.setattr(_health, "_health_kernels", recorded)  # prepare's (warm)
    monkeypatch.setattr(_drivers, "_prepared", set())
    gpu.prepare(9, notify=lambda m: None)
    assert set(seen["prepare"]) == {"flag", "fold", "failed"}
    overloads = {n: len(getattr(k, "overloads", {})) for n, k in zip(("flag", "fold", "failed"), real, strict=True)}
    phase["now"] = "run"
    res = rl.start(_ens_spec("gpu"), tmp_path / "w", notify=lambda m: None)
    assert res.status == "completed"
    assert set(seen["run"]) == {"flag", "fold", "failed"}  # the run launches all three: the comparison is not empty
    for name, types in seen["run"].items():
        assert types <= seen["prepare"][name], (name, types - seen["prepare"][name])
    assert overloads == {n: len(getattr(k, "overloads", {})) for n, k in zip(("flag", "fold", "failed"), real,
                                                                               strict=True)}


@pytest.mark.parametrize("plant", [False, True])
def test_resident_end_state_off_the_grid_checked_on_the_device(tmp_path, monkeypatch, plant):
    """A chunk ending off the save grid has its end state health-checked (as the CPU route's ``record=False``
    check) on the device: no host check of a passing end state (issue 36: at 10⁷ orbits that was a 720 MB copy
    and the host integrals per chunk).  Planted (``plant``): orbit 1's end state after the call 12..15 (off the grid
    of 4) with ``y_0`` scaled by 1.5 on the device: the breach is found there and worded by the host as the CPU route
    words it (orbit 1, step 15), the run stops at the last row, step 12.  One call per chunk
    (``FLUSH_MAX_SECONDS = 0``), calls of 3 steps."""
    from jetgaudin import run as rl
    from jetgaudin.gpu import _kernels, _resident
    from jetgaudin.run import driver, health

    monkeypatch.setattr(driver, "FLUSH_MAX_SECONDS", 0.0)
    host_end = []
    original = health.Health.check

    def counted(self, steps, S, *, record=True):
        if not record:
            host_end.append(steps[0])
        return original(self, steps, S, record=record)

    monkeypatch.setattr(health.Health, "check", counted)
    ends = []
    original_end = _resident.ResidentMap.check_end
    monkeypatch.setattr(_resident.ResidentMap, "check_end", lambda self, X: (ends.append(X.step),
                                                                             original_end(self, X))[1])
    real3, realg = _kernels.top_kernels()
    done = {"n": 0}

    class Change:
        def __getitem__(self, launch):
            def run(X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last):
                real3[launch](X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last)
                done["n"] += int(steps)
                if plant and done["n"] == 15:
                    f = final.copy_to_host()
                    f[1] = _scaled(f[1], 0, 1.5)
                    final.copy_to_device(f)
            return run

    monkeypatch.setattr(_kernels, "top_kernels", lambda: (Change(), realg))
    spec = _ens_spec("gpu", max_drift=1e-2)
    res = rl.start(spec, tmp_path / "e", max_chunk_steps=3)
    if not plant:
        assert res.status == "completed"
        assert host_end == [] and any(e % 4 for e in ends)  # end states off the grid met, none checked on the host
        ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 40, save_every=4, gpu=True, want_drift=False)
    else:
        assert res.status.startswith("failed: integral drift") and "of orbit 1" in res.status, res.status
        assert "at step 15 " in res.status and res.last_safe_step == 12
        assert host_end == [15]  # the host words the breach the device found
        ref = iterate_ensemble(spec.X0, spec.map.b, spec.map.eta, 12, save_every=4, gpu=True, want_drift=False)
    d = rl.load(tmp_path / "e")
    np.testing.assert_array_equal(d.X, np.moveaxis(ref.states, 0, 1) if d.X.shape[0] == spec.B else ref.states)
