"""The GPU drivers (``jetgaudin.gpu``) on Numba's CUDA simulator: an orbit that fails off the save grid (issue 33).

Until now the drivers' failure tests failed an orbit at step 0 (``tests/test_gpu.py``); the resident route had a
failure off the grid, the batch driver ``gpu.run_batch`` had none.  Here the orbit loop the kernel calls is wrapped
(under the simulator the kernels run as Python and call the CPU's compiled loops through a shim): for one orbit the
real loop runs to the failing step ``k`` and the wrapper returns what the loop returns at a refused step -- status
``STATUS_RESIDUAL``, step ``k``, the state of step ``k`` in ``final``, the rows up to ``k`` written -- and poisons the
rows after ``k`` with NaN (a real loop leaves them unwritten, whatever the device's memory held).  So the kernel's
own code (the status, failing step and ``ν1`` it stores) and the driver's handling of a failed orbit are what run.

Tolerances: none; under the simulator the GPU route gives the CPU route's bits (``tests/test_gpu.py``), so every
comparison is exact.
"""

from __future__ import annotations

from test_gpu import REAL, batch  # isort: skip  (sets NUMBA_ENABLE_CUDASIM=1 before numba.cuda is imported)

import types

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import gpu
from jetgaudin.backlund.kernels import _drivers as C
from jetgaudin.backlund.kernels._status import STATUS_RESIDUAL
from jetgaudin.ensemble import sample_on_leaf
from jetgaudin.gpu import _kernels


@pytest.fixture
def failing_loop(monkeypatch):
    """``fail(b_value, k)``: the top's GPU kernels rebuilt with orbit loops that fail the orbit of parameter
    ``b == b_value`` at step ``k`` (see the module docstring); the kernels' cache is cleared before and after."""

    def install(b_fail: float, k: int) -> None:
        real = {name: getattr(C.kernel_module(mod), name) for mod, name in (("_n3", "orbit3"),
                                                                             ("_generic", "orbit_generic"))}

        def wrap(name):
            def loop(x0, b, eta, nu0, cont, steps, save_every, out, final, *scratch):
                if b != b_fail:
                    return real[name](x0, b, eta, nu0, cont, steps, save_every, out, final, *scratch)
                _, _, nu = real[name](x0, b, eta, nu0, cont, k, save_every, out[: k // save_every + 1], final,
                                      *scratch)
                out[k // save_every + 1:] = np.nan  # never written by a loop that stopped at step k
                return STATUS_RESIDUAL, k, nu
            return loop

        fake = {"_n3": types.SimpleNamespace(orbit3=wrap("orbit3")),
                "_generic": types.SimpleNamespace(orbit_generic=wrap("orbit_generic"))}
        real_module = C.kernel_module
        monkeypatch.setattr(C, "kernel_module", lambda name: fake.get(name) or real_module(name))
        _kernels.top_kernels.cache_clear()

    yield install
    _kernels.top_kernels.cache_clear()


@pytest.mark.skipif(REAL, reason="plants a failure through the simulator's Python kernels")
@pytest.mark.parametrize(("N", "specialise"), [(3, True), (4, True)])  # the real N = 3 kernel; the generic one
@pytest.mark.parametrize("k", [5, 6])  # off the save grid of 3, between rows 1 and 2; off it again
def test_an_orbit_failing_off_the_save_grid(failing_loop, N, specialise, k):
    """Orbit 2 fails at step k of 12 (rows every 3 steps): its rows up to step k are the unfailed orbit's, every
    later row and ``final`` hold the state of step k (its last good state, as on the CPU lanes), its status and
    failing step are stored, its drift covers what it ran; the other orbits are the unfailed run bit for bit; the
    raising driver names orbit 2 and step k."""
    X, b, eta, nu0 = batch(B=4, N=N)
    ref = C.run_batch(X, b, eta, nu0, False, 12, 3, specialise)
    at_k = C.run_batch(X[2:3], b[2:3], eta[2:3], nu0[2:3], False, k, 1, specialise)[1][0]
    failing_loop(float(b[2]), k)
    out, final, drift, nu_last, status, fail = gpu.run_batch(X, b, eta, nu0, False, 12, 3, specialise)
    assert list(status) == [0, 0, STATUS_RESIDUAL, 0] and fail[2] == k
    kept = k // 3 + 1  # rows of steps 0, 3, .., <= k
    np.testing.assert_array_equal(out[2, :kept], ref[0][2, :kept])
    np.testing.assert_array_equal(out[2, kept:], np.broadcast_to(at_k, (5 - kept, 3 * N)))
    np.testing.assert_array_equal(final[2], at_k)
    assert np.all(np.isfinite(drift[2]))
    # the drift of the failed orbit: over its rows up to step k and its last state, with the module's sums (the
    # definition is tested against the CPU pass in tests/test_gpu.py); here the rows it covers are what is tested
    from jetgaudin.gpu._drivers import _kappa

    rows = np.vstack([ref[0][2, :kept], at_k])
    I0 = _kappa(rows[0], b[2])
    want = np.max(np.abs(_kappa(rows, b[2]) - I0) / np.maximum(1, np.abs(I0)), 0)
    np.testing.assert_allclose(drift[2], want, rtol=1e-15, atol=0)  # the driver multiplies by 1/scale: an ulp
    for i in (0, 1, 3):
        for got, want in zip((out, final, drift, nu_last, status, fail), ref, strict=True):
            np.testing.assert_array_equal(got[i], want[i])
    with pytest.raises(jg.SingularStepError, match=f"at step {k} of orbit 2"):
        gpu.iterate_batch(X, b, eta, nu0, False, 12, 3, specialise=specialise)


def test_compute_capability_below_6_is_refused_and_6_is_taken(monkeypatch):
    """``probe`` (a fake CUDA module: not the simulator, one device) refuses compute capability 5.x in one line
    naming it and what is needed, and takes 6.0 (the double-precision atomics and the FMA the kernels rely on)."""
    from jetgaudin.gpu import _device

    def fake(cc):
        dev = types.SimpleNamespace(name=b"Fake GPU", compute_capability=cc)
        return types.SimpleNamespace(is_available=lambda: True, get_current_device=lambda: dev)

    monkeypatch.setattr(_device, "simulator", lambda: False)
    try:
        for cc, ok in (((5, 2), False), ((5, 0), False), ((6, 0), True), ((9, 0), True)):
            monkeypatch.setattr(_device, "cuda", lambda cc=cc: fake(cc))
            _device.probe.cache_clear()
            usable, what = _device.probe()
            assert usable is ok, (cc, what)
            assert ("needs 6.0 or newer" in what) is not ok and f"{cc[0]}.{cc[1]}" in what and "Fake GPU" in what
    finally:
        _device.probe.cache_clear()  # the next caller probes the simulator again


def test_a_top_beyond_the_kernels_scratch_is_refused():
    """N = 17 > MAX_N = 16 (the generic kernel's thread-local scratch is of fixed size): one typed line naming the
    bound and the CPU route, before anything is copied; N = 16 runs."""
    X = sample_on_leaf(17, list(np.linspace(0.5, 1.0, 17)), 2, seed=1)
    with pytest.raises(jg.InvalidStateError, match="N <= 16 .* got N = 17; use backend 'compiled'"):
        gpu.run_batch(X, 1.0, 5 + 0.1j, 1 + 0j, False, 1, 1)
    X16 = sample_on_leaf(16, list(np.linspace(0.5, 1.0, 16)), 1, seed=1)
    nu = C.nu_default(X16, np.ones(1), np.full(1, 5 + 0.1j), 1)
    assert gpu.run_batch(X16, 1.0, 5 + 0.1j, nu, False, 1, 1)[4][0] == 0


def test_the_refusal_of_a_call_too_large_for_the_gpu_names_its_size(monkeypatch):
    """The size named in the refusal is the call's device arrays in GiB: at least the saved rows (B S 3N doubles),
    at most 10 % more (the start and final states and per-orbit scalars); the free memory is the faked 1 MiB."""
    import re

    import jetgaudin.gpu._drivers as drv

    monkeypatch.setattr(drv, "_free_bytes", lambda c: float(2**20))
    X, b, eta, nu0 = batch(B=200)
    with pytest.raises(jg.InvalidParameterError) as e:
        gpu.run_batch(X, b, eta, nu0, False, 100, 1)
    need, free = map(float, re.search(r"needs (\S+) GiB on the GPU, which has (\S+) GiB free", str(e.value)).groups())
    rows = 200 * 101 * 9 * 8 / 2**30
    assert rows <= need <= 1.1 * rows and free == pytest.approx(2**20 / 2**30, rel=1e-3)  # printed to 3 digits


def test_the_timing_of_every_driver_is_a_duration_within_the_call():
    """``last_timing()`` after each driver (the top's, the chains', su(3)'s): ``0 <= kernel <= total <=`` the
    call's wall time (the kernel's own seconds only on a real GPU), and the orbits and steps of the call."""
    import time

    X, b, eta, nu0 = batch(B=3)
    m = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 1)], family="trigonometric")
    Xc = 0.5 * np.random.default_rng(2).normal(size=(3, m.n_state))
    ms = jg.GaudinModel([0.3, -0.1, 0.5, 0.2, 0.0, -0.2, 0.1, 0.4], [(0.0, 1), (1.0, 1)], algebra="su3")
    Xs = 0.5 * np.random.default_rng(1).normal(size=(3, ms.n_state))
    Ts = ms.two_point_backlund(0.4 + 0.1j, backend="gpu")
    calls = [lambda: gpu.run_batch(X, b, eta, nu0, False, 4, 2),
             lambda: m.two_point_backlund(0.4 + 0.05j, backend="gpu").advance(Xc, None, 4),
             lambda: Ts.advance(Xs, None, 4)]
    for call in calls:
        t0 = time.perf_counter()
        call()
        wall = time.perf_counter() - t0
        t = gpu.last_timing()
        assert 0.0 < t.total <= wall, (t, wall)
        if REAL:  # pragma: no cover - the simulator's CUDA events time nothing (elapsed_time gives -1 ms)
            assert 0.0 <= t.kernel <= t.total
        assert (t.orbits, t.steps) == (3, 4)


@pytest.mark.skipif(REAL, reason="the shim is the simulator's")
def test_unwrap_gives_the_numpy_array_behind_a_simulator_array():
    """``_unwrap`` (the simulator's shim around the CPU loops) gives the NumPy array behind a device array, the same
    memory (a loop's writes land in it), and anything else unchanged.  Written for the mutant that swapped its two
    branches: inside a kernel both reach the array, on a device array itself the swapped one gave ``None``."""
    from jetgaudin.gpu import _device

    c = _device.require()
    x = np.arange(6.0)
    d = c.to_device(x)
    a = _kernels._unwrap(d)
    assert isinstance(a, np.ndarray)
    a[0] = 7.0
    assert d.copy_to_host()[0] == 7.0
    assert _kernels._unwrap(x) is x and _kernels._unwrap(3) == 3


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_the_refusal_of_an_su3_call_too_large_for_the_gpu_names_its_size(monkeypatch):
    """``run_sun_batch`` (the su(3) chains' GPU driver): the size its refusal names covers at least the saved rows and
    the final states it allocates (``8 B (S + 1) n`` bytes), at most 10 % more (per-orbit scalars); printed to 3
    digits, so compared to 0.5 %.  200 orbits of 2 sites (n = 16), 100 saved rows, 1 MiB free (faked).  Written for
    the mutants ``8 B (n (S + 1) + 4)`` → ``8 B (n S^1 + 4)`` (1 % short: the final states forgotten), → ``7 B …``."""
    import re

    import jetgaudin.gpu._drivers as drv

    monkeypatch.setattr(drv, "_free_bytes", lambda c: float(2**20))
    ms = jg.GaudinModel([0.3, -0.1, 0.5, 0.2, 0.0, -0.2, 0.1, 0.4], [(0.0, 1), (1.0, 1)], algebra="su3")
    Xs = 0.5 * np.random.default_rng(1).normal(size=(200, ms.n_state))
    with pytest.raises(jg.InvalidParameterError) as e:
        ms.two_point_backlund(0.4 + 0.1j, backend="gpu").advance(Xs, None, 100)
    need, free = map(float, re.search(r"needs (\S+) GiB on the GPU, which has (\S+) GiB free", str(e.value)).groups())
    arrays = 8 * 200 * 101 * ms.n_state / 2**30
    assert ms.n_state == 16 and 0.995 * arrays <= need <= 1.1 * arrays, (need, arrays)
    assert free == pytest.approx(2**20 / 2**30, rel=1e-3)


def test_prepare_compiles_once_per_process_and_says_so_once(monkeypatch):
    """``gpu.prepare`` (module doc of :func:`jetgaudin.gpu._drivers.prepare`): the first call for a kernel compiles
    it (state ``"cold"``, two messages: before and when done, naming the kernel); a second call for the same kernel
    says nothing and reports ``"loaded"`` in 0 s; another kernel is compiled on its own.  Written for the mutant
    ``if name in _prepared`` → ``if not name in _prepared`` (nothing compiled, every later call compiled again)."""
    import jetgaudin.gpu._drivers as drv

    monkeypatch.setattr(drv, "_prepared", set())
    said: list[str] = []
    first = drv.prepare(9, notify=said.append)
    assert (first.kernels, first.state) == (("gpu.top3",), "cold") and first.seconds > 0
    assert len(said) == 2 and all("gpu.top3" in m for m in said)
    again = drv.prepare(9, notify=said.append)
    assert (again.kernels, again.state, again.seconds) == (("gpu.top3",), "loaded", 0.0) and len(said) == 2
    other = drv.prepare(12, notify=said.append)
    assert (other.kernels, other.state) == (("gpu.top_generic",), "cold") and len(said) == 4


def test_the_refusal_of_a_resident_call_too_large_for_the_gpu_names_its_size(monkeypatch):
    """The device-resident route (``gpu._resident.ResidentMap.advance``, a GPU ensemble of the run layer) refuses a
    call whose device arrays do not fit before it launches anything, naming at least the saved rows and final states
    (``8 B (S + 1) n`` bytes) and at most 10 % more (printed to 3 digits: compared to 0.5 %).  20 orbits, N = 3,
    1000 saved rows, 1 MiB free (faked); the kernels are replaced by a trap, so that a call that passes the check
    fails at once instead of stepping on the simulator.  Written for the mutants ``8 * B * (…)`` → ``8 * B + (…)``
    (nothing refused) and → ``8 * B ** (…)``."""
    import re

    import jetgaudin.gpu._drivers as drv
    import jetgaudin.gpu._kernels as kern
    from jetgaudin.ensemble import BatchBacklund
    from jetgaudin.gpu._resident import ResidentMap

    def trap():
        raise AssertionError("launched: the call was not refused")

    monkeypatch.setattr(drv, "_free_bytes", lambda c: float(2**20))
    monkeypatch.setattr(kern, "top_kernels", trap)
    B = 20
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], B, seed=3)
    m = BatchBacklund(np.linspace(0.9, 1.2, B), (5 + 0.1j) + 0.03 * np.arange(B), backend="gpu")
    health = types.SimpleNamespace(I0=np.zeros((B, 6)), scale=np.ones((B, 6)), r0=np.ones(B), drift=np.zeros((B, 6)),
                                   limits=types.SimpleNamespace(max_drift=1e-6))
    with pytest.raises(jg.InvalidParameterError) as e:
        ResidentMap(m, health).advance(X, None, 1000, 1)
    need = float(re.search(r"needs (\S+) GiB on the GPU", str(e.value)).group(1))
    arrays = 8 * B * 1001 * 9 / 2**30
    assert 0.995 * arrays <= need <= 1.1 * arrays, (need, arrays)
