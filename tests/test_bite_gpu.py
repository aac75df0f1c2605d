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
from jetgaudin.gpu import _kernels

pytestmark = pytest.mark.skipif(REAL, reason="plants a failure through the simulator's Python kernels")


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
