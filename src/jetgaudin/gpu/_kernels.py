r"""The CUDA kernels of the GPU route: one thread per orbit, calling the CPU kernels' own orbit loops (private).

Nothing of the mathematics is written here.  Each kernel is a few lines that pick the thread's orbit and call the
allocation-free loop the CPU route runs for one orbit -- :func:`jetgaudin.backlund.kernels._n3.orbit3` (the real
N = 3 form, 345 flops a step), :func:`jetgaudin.backlund.kernels._generic.orbit_generic` (any N) and
:func:`jetgaudin.gaudin._family_kernel.orbit_loop` (chains of every family) and
:func:`jetgaudin.gaudin._sun_kernel.orbit_loop` (su(3) chains) -- which Numba's CUDA target compiles
as device functions, with the blocks they inline (complex arithmetic written out, explicit fused multiply-adds:
an LLVM intrinsic, which NVVM lowers to the GPU's ``fma.rn.f64``).  Scratch arrays are thread-local
(``cuda.local.array``), of a size fixed at compile time: :data:`MAX_N` for the top's generic route,
:data:`MAX_CHAIN_STATE`, :data:`MAX_ORDER` and :data:`MAX_BASIS` for chains, :data:`MAX_SUN_STATE` and
:data:`MAX_ORDER` for su(3) chains.

The state, the per-orbit constants and the carried ``ν1`` stay in registers (or local memory) for the whole run;
global memory is touched at the start, at every saved row and at the end.  The arithmetic differs from the CPU
route only where NVVM contracts a product and a sum into one fused operation (its default; the explicit fused
operations are the same on both), so the orbits agree with the CPU route to round-off, not bit for bit
(``docs/performance.md``, the GPU section, gives the measured difference per step).

Under Numba's CUDA simulator (the tests without a GPU) the kernels run as Python and the loops are the CPU's
compiled functions, called through :func:`_host`, which hands them the simulator's arrays as NumPy views.  (The
simulator swaps this module's global ``cuda`` for its own: the kernels must reach Numba's CUDA API through it.)
Call the kernel builders only after :func:`jetgaudin.gpu._device.require`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from ._device import cuda as _import_cuda
from ._device import simulator

__all__ = ["MAX_N", "MAX_CHAIN_STATE", "MAX_SUN_STATE", "MAX_ORDER", "MAX_BASIS", "THREADS", "top_kernels",
           "chain_kernel", "sun_kernel"]

#: largest N of the top's generic GPU kernel (thread-local scratch of fixed size)
MAX_N = 16
#: largest chain state (3M coordinates) of the chain GPU kernel
MAX_CHAIN_STATE = 96
#: largest su(3) chain state (8M coordinates) of the su(3) GPU kernel
MAX_SUN_STATE = 128
#: largest site order of the chain GPU kernels
MAX_ORDER = 8
#: largest number of dressing coefficients of a family (rational and trigonometric 6, elliptic 4)
MAX_BASIS = 8
#: threads per block (one orbit each)
THREADS = 128
# the sizes of the thread-local arrays, as literal constants (Numba's CUDA target needs them at compile time)
_N1, _N3, _S3 = MAX_N + 1, MAX_N + 3, 3 * MAX_N
_F8, _C16 = np.float64, np.complex128

#: ``numba.cuda``, bound by :func:`_bind` before the kernels are defined (importing this module imports nothing of
#: CUDA: the doctest collection and ``import jetgaudin`` stay free of it)
cuda: Any = None


def _bind() -> None:
    global cuda
    if cuda is None:
        cuda = _import_cuda()  # the NumPy alias numba-cuda needs, then numba.cuda



def _unwrap(a: Any) -> Any:
    """The NumPy array behind a CUDA simulator array (itself for anything else)."""
    while hasattr(a, "_item") or hasattr(a, "_ary"):
        a = getattr(a, "_item", None) if hasattr(a, "_item") else a._ary
    return a


def _host(fn: Callable) -> Callable:
    """``fn`` as the kernels call it: itself on a GPU (a device function); under the simulator a Python shim that
    passes the simulator's arrays as the NumPy arrays behind them (views: what ``fn`` writes lands in them)."""
    if not simulator():
        return fn

    def call(*args: Any) -> Any:
        return fn(*(_unwrap(a) for a in args))

    return call


@functools.cache
def top_kernels() -> tuple[Any, Any]:
    """``(kernel3, kernel_generic)``: the top's real two-point map, one thread per orbit, compiled at first use.

    Both take ``(X0 (B, 3N), b (B,), eta (B,), nu0 (B,), cont, steps, save_every, out (S, B, 3N), final (B, 3N),
    status (B,), fail (B,), nu_last (B,))`` -- the arguments of the CPU batch kernels without the drift pass."""
    from ..backlund.kernels._drivers import kernel_module

    _bind()
    loop3 = _host(kernel_module("_n3").orbit3)
    loopg = _host(kernel_module("_generic").orbit_generic)
    @cuda.jit
    def kernel3(X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail, nu_last):  # pragma: no cover
        i = cuda.grid(1)
        if i < X0.shape[0]:
            st, n, nu = loop3(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[:, i], final[i])
            status[i] = st
            fail[i] = n
            nu_last[i] = nu

    @cuda.jit
    def kernel_generic(X0, b, eta, nu0, cont, steps, save_every, out, final, status, fail,
                       nu_last):  # pragma: no cover
        i = cuda.grid(1)
        if i < X0.shape[0]:
            eu = cuda.local.array(_N1, _F8)
            ev = cuda.local.array(_N1, _C16)
            ew = cuda.local.array(_N1, _C16)
            Ru = cuda.local.array(_N3, _C16)
            Rv = cuda.local.array(_N3, _C16)
            Rw = cuda.local.array(_N3, _C16)
            Qu = cuda.local.array(_N1, _C16)
            Qv = cuda.local.array(_N1, _C16)
            Qw = cuda.local.array(_N1, _C16)
            x = cuda.local.array(_S3, _F8)
            xn = cuda.local.array(_S3, _F8)
            for k in range(_N1):
                Qu[k] = 0j
                Qv[k] = 0j
                Qw[k] = 0j
            st, n, nu = loopg(X0[i], b[i], eta[i], nu0[i], cont, steps, save_every, out[:, i], final[i], eu, ev, ew,
                              Ru, Rv, Rw, Qu, Qv, Qw, x, xn)
            status[i] = st
            fail[i] = n
            nu_last[i] = nu

    return kernel3, kernel_generic


@functools.cache
def chain_kernel() -> Any:
    """The chains' real two-point map (every family), one thread per orbit, compiled at first use.

    Takes ``(X0 (B, 3M), b, nu0 (B,), f, rule, gk, T, pidx, site_off, site_n, steps, save_every, rows (S, B, 3M),
    final (B, 3M), last (B,))`` with the per-``(model, ξ)`` constants of
    :func:`jetgaudin.gaudin._family_kernel.orbit_constants`."""
    from ..gaudin import _family_kernel

    _bind()
    loop = _host(_family_kernel.orbit_loop)

    @cuda.jit
    def kernel(X0, b, nu0, f, rule, gk, T, pidx, site_off, site_n, steps, save_every, rows, final,
               last):  # pragma: no cover
        i = cuda.grid(1)
        if i < X0.shape[0]:
            n = X0.shape[1]
            x = cuda.local.array(MAX_CHAIN_STATE, _F8)
            y = cuda.local.array(MAX_CHAIN_STATE, _F8)
            cf = cuda.local.array(MAX_BASIS, _C16)
            Dt = cuda.local.array((MAX_ORDER, 4), _C16)
            At = cuda.local.array((MAX_ORDER, 4), _C16)
            P = cuda.local.array((MAX_ORDER, 4), _C16)
            det = cuda.local.array(MAX_ORDER, _C16)
            g = cuda.local.array(MAX_ORDER, _C16)
            for k in range(MAX_BASIS):
                cf[k] = 0j
            for k in range(n):
                x[k] = X0[i, k]
            last[i] = loop(x[:n], y[:n], rows[:, i], final[i], b, nu0[i], f, rule, gk, T, pidx, site_off, site_n,
                           cf, Dt, At, det, g, P, steps, save_every)

    return kernel


@functools.cache
def sun_kernel() -> Any:
    """The su(3) chains' real two-point map ``B^{(r)}_η``, one thread per orbit, compiled at first use.

    Takes ``(X0 (B, 8M), b (8,), mu0 (B,), f (1, C), site_pos, site_off, site_n, eta (1,), steps, save_every, rows
    (steps//save_every, B, 8M), final (B, 8M), mu_last (B,), status (B,))`` with the per-``(model, η)`` constants of
    :func:`jetgaudin.gaudin._sun_kernel.orbit_constants`; ``status[i] = 1`` where orbit ``i`` ended non-finite
    (``η`` at a branch point, an overflow: NaN stays NaN, so a failed step shows in the final state), else 0."""
    from ..gaudin import _sun_kernel

    _bind()
    loop = _host(_sun_kernel.orbit_loop)

    @cuda.jit
    def kernel(X0, b, mu0, f, site_pos, site_off, site_n, eta, steps, save_every, rows, final, mu_last,
               status):  # pragma: no cover
        i = cuda.grid(1)
        if i < X0.shape[0]:
            n = X0.shape[1]
            x = cuda.local.array(MAX_SUN_STATE, _F8)
            y = cuda.local.array(MAX_SUN_STATE, _F8)
            xi = cuda.local.array(8, _C16)
            L = cuda.local.array((3, 3), _C16)
            u = cuda.local.array(3, _C16)
            w = cuda.local.array(3, _C16)
            Y = cuda.local.array((3, 3), _C16)
            acc = cuda.local.array((3, 3), _C16)
            ac = cuda.local.array(MAX_ORDER, _C16)
            gc = cuda.local.array(MAX_ORDER, _C16)
            m = cuda.local.array(1, _C16)  # the carry of the kernel's one map (k = 1: f (1, C), eta (1,))
            m[0] = mu0[i]
            for k in range(n):
                x[k] = X0[i, k]
            loop(x[:n], y[:n], rows[:, i], final[i], b, m, f, site_pos, site_off, site_n, eta, xi, L, u, w, Y, acc,
                 ac, gc, steps, save_every, 1)
            mu = m[0]
            mu_last[i] = mu
            ok = 1 if (mu.real - mu.real == 0.0 and mu.imag - mu.imag == 0.0) else 0  # finite: x - x is 0, else NaN
            for k in range(n):
                if final[i, k] - final[i, k] != 0.0:
                    ok = 0
            status[i] = 1 - ok

    return kernel
