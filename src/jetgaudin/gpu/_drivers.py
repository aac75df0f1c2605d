"""Host side of the GPU route: validate, copy to the device, launch, copy back (private; no mathematics here).

:func:`run_batch` has the arguments and returns of the CPU route's
:func:`jetgaudin.backlund.kernels._drivers.run_batch`, so the maps and the ensemble driver swap one for the other;
:func:`run_chain_batch` those of :func:`jetgaudin.gaudin._family_kernel.run_batch`, :func:`run_sun_batch` those of
:func:`jetgaudin.gaudin._sun_kernel.run_batch` (and a per-orbit status).  The branch rule (``ν1`` at
the start) stays on the host, compiled on all cores, and so gives the CPU route's bits; the drift pass runs on the
host too (NumPy, over the rows copied back).
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass

import numpy as np

from .._errors import InvalidParameterError, InvalidStateError
from ._device import require

__all__ = ["run_batch", "iterate_batch", "run_chain_batch", "run_chain", "run_sun_batch", "prepare", "GPUReport",
           "Timing", "last_timing"]


@dataclass
class Timing:
    """Seconds of the last GPU call: ``kernel`` (the launch to its end, CUDA events), ``total`` (the call, copies
    to and from the device included), ``orbits``, ``steps``."""

    kernel: float = 0.0
    total: float = 0.0
    orbits: int = 0
    steps: int = 0
    device: str = ""


_last = Timing()


def last_timing() -> Timing:
    """The :class:`Timing` of the last GPU call in this process (for the benchmarks)."""
    return _last


def _launch(kernel, B: int, args: tuple) -> float:
    """Launch ``kernel`` on ``B`` threads (blocks of :data:`THREADS`) and wait for it; returns its seconds."""
    c = require()
    from ._kernels import THREADS

    if B == 0:
        return 0.0
    start, stop = c.event(), c.event()
    start.record()
    kernel[-(-B // THREADS), THREADS](*args)
    stop.record()
    stop.synchronize()
    return start.elapsed_time(stop) / 1000.0


def _free_bytes(c) -> float:
    """Free memory on the current GPU (bytes; the simulator reports infinity)."""
    return float(c.current_context().get_memory_info()[0])


def _check_fits(c, nbytes: int, what: str) -> None:
    """:class:`InvalidParameterError` (one line, before anything is allocated) when ``nbytes`` of device arrays
    would not fit in 90 % of the GPU's free memory."""
    free = _free_bytes(c)
    if nbytes > 0.9 * free:
        raise InvalidParameterError(
            f"{what} needs {nbytes / 2**30:.3g} GiB on the GPU, which has {free / 2**30:.3g} GiB free: give fewer "
            "orbits, or save fewer rows per call (a larger save_every, fewer steps)")


def _kappa(X: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``κ_1..κ_2N`` (``H_1..H_N, C_1..C_N``) of states ``X`` (..., 3N) with per-orbit ``b`` (...,): the sums of the
    CPU kernels' ``_integrals`` (``κ_m = Σ_{i+j=m} ⟨ξ_i, ξ_j⟩``, ``ξ_0 = b e_3``), in NumPy and without the range
    check of :func:`jetgaudin.integrals` (an overflowed orbit gets inf/NaN drift, as on the CPU route)."""
    N = X.shape[-1] // 3
    Y = X.reshape(X.shape[:-1] + (N, 3))
    out = np.zeros(X.shape[:-1] + (2 * N,))
    with np.errstate(all="ignore"):
        for i in range(N):
            out[..., i] += 2.0 * b * Y[..., i, 2]
            for j in range(N):
                out[..., i + j + 1] += Y[..., i, 0] * Y[..., j, 0] + Y[..., i, 1] * Y[..., j, 1] + Y[..., i, 2] * Y[
                    ..., j, 2]
    return out


def _drift(out: np.ndarray, final: np.ndarray, fail: np.ndarray, save_every: int, b: np.ndarray) -> np.ndarray:
    """``max_n |I_k(x_n) − I_k(x_0)| / max(1, |I_k(x_0)|)`` over each orbit's saved rows up to its last step and its
    final state (the CPU kernels' drift pass, in NumPy): ``(B, 2N)``."""
    I0 = _kappa(out[0], b)
    with np.errstate(all="ignore"):
        scale = 1.0 / np.maximum(1.0, np.abs(I0))
        drift = np.abs(_kappa(final, b) - I0) * scale
        last = fail // save_every
        for j in range(1, out.shape[0]):
            rows = np.flatnonzero(last >= j)
            if rows.size:
                e = np.abs(_kappa(out[j, rows], b[rows]) - I0[rows]) * scale[rows]
                drift[rows] = np.maximum(drift[rows], e)  # NaN propagates, as in the CPU pass
    return drift


def run_batch(X, b, eta, nu0, cont, steps, save_every, specialise=True, want_drift=True):
    r"""The top's real two-point map on a batch on the GPU: the arguments and returns of the CPU route's
    ``run_batch`` -- ``(out (B, S, 3N), final (B, 3N), drift (B, 2N) or None, nu_last (B,), status (B,), fail
    (B,))`` -- never raising on a singular step (``status``).  N = 3 (``specialise``) runs the real form of the
    step, other N (up to :data:`MAX_N`) the generic route."""
    from ..backlund.kernels._drivers import check_counts

    c = require()
    from ._kernels import MAX_N, top_kernels

    X = np.ascontiguousarray(X, dtype=np.float64)
    B, n3 = X.shape
    if n3 > 3 * MAX_N:
        raise InvalidStateError(f"the GPU route takes N <= {MAX_N} (states of up to {3 * MAX_N} components), got "
                                f"N = {n3 // 3}; use backend 'compiled'")
    S = check_counts(steps, save_every, B, n3)
    b = np.ascontiguousarray(np.broadcast_to(b, (B,)), dtype=np.float64)
    eta = np.ascontiguousarray(np.broadcast_to(eta, (B,)), dtype=np.complex128)
    nu0 = np.ascontiguousarray(np.broadcast_to(nu0, (B,)), dtype=np.complex128)
    _check_fits(c, 8 * B * (n3 * (S + 2) + 7), f"a call of {B} orbits with {S} saved rows")
    t0 = time.perf_counter()
    dX, db, de, dn = (c.to_device(a) for a in (X, b, eta, nu0))
    d_out = c.device_array((S, B, n3))
    d_final = c.device_array((B, n3))
    d_status = c.device_array(B, np.int64)
    d_fail = c.device_array(B, np.int64)
    d_nu = c.device_array(B, np.complex128)
    kernel3, kernel_generic = top_kernels()
    kernel = kernel3 if (specialise and n3 == 9) else kernel_generic
    tk = _launch(kernel, B, (dX, db, de, dn, bool(cont), np.int64(steps), np.int64(save_every), d_out, d_final,
                             d_status, d_fail, d_nu))
    out = d_out.copy_to_host()
    final, status, fail, nu_last = (a.copy_to_host() for a in (d_final, d_status, d_fail, d_nu))
    for i in np.flatnonzero(status):  # a failed orbit's later rows hold its last good state (as the CPU lanes)
        out[fail[i] // save_every + 1:, i] = final[i]
    _record(tk, time.perf_counter() - t0, B, int(steps))
    drift = _drift(out, final, fail, int(save_every), b) if want_drift else None
    return out.transpose(1, 0, 2), final, drift, nu_last, status, fail


def run_chain_batch(X0, b, nu0, f, rule, gk, T, pidx, n_basis, site_off, site_n, steps, save_every):
    """A chain's real two-point map on a batch on the GPU: the arguments and returns of
    :func:`jetgaudin.gaudin._family_kernel.run_batch` -- ``(rows (steps//save_every, B, 3M) without the start
    states, final (B, 3M), last ν1 (B,))``."""
    c = require()
    from ._kernels import MAX_BASIS, MAX_CHAIN_STATE, MAX_ORDER, chain_kernel

    X0 = np.ascontiguousarray(X0, dtype=np.float64)
    B, n = X0.shape
    if n > MAX_CHAIN_STATE or T.shape[1] > MAX_ORDER or n_basis > MAX_BASIS:
        raise InvalidParameterError(
            f"the GPU route takes chains of up to {MAX_CHAIN_STATE // 3} spins, site orders up to {MAX_ORDER} and "
            f"{MAX_BASIS} dressing coefficients; this model has {n // 3}, {T.shape[1]} and {n_basis}: use backend "
            "'compiled'")
    S = int(steps) // int(save_every) + 1
    _check_fits(c, 8 * B * (n * (S + 2) + 4) + T.nbytes + f.nbytes, f"a call of {B} orbits with {S} saved rows")
    t0 = time.perf_counter()
    args = [c.to_device(np.ascontiguousarray(a)) for a in (X0, np.asarray(nu0, dtype=np.complex128), f, gk, T, pidx,
                                                            site_off, site_n)]
    d_rows = c.device_array((S, B, n))
    d_final = c.device_array((B, n))
    d_last = c.device_array(B, np.complex128)
    tk = _launch(chain_kernel(), B, (args[0], float(b), args[1], args[2], int(rule), args[3], args[4], args[5],
                                     args[6], args[7], np.int64(steps), np.int64(save_every), d_rows, d_final, d_last))
    rows = d_rows.copy_to_host()[1:]
    final, last = d_final.copy_to_host(), d_last.copy_to_host()
    _record(tk, time.perf_counter() - t0, B, int(steps))
    return rows, final, last


def run_sun_batch(X0, b, mu0, f, site_pos, site_off, site_n, eta, steps, save_every):
    """The su(3) chains' map on a batch on the GPU: the arguments and returns of
    :func:`jetgaudin.gaudin._sun_kernel.run_batch` for one map (``k = 1``: ``mu0`` (B,), ``f`` (C,), ``eta`` a
    number) -- ``(rows (steps//save_every, B, 8M) without the start states,
    final (B, 8M), last μ_r (B,))`` -- and ``status (B,)`` (1 where the orbit ended non-finite, else 0)."""
    c = require()
    from ._kernels import MAX_ORDER, MAX_SUN_STATE, sun_kernel

    X0 = np.ascontiguousarray(X0, dtype=np.float64)
    B, n = X0.shape
    order = int(np.max(site_n)) if len(site_n) else 0
    if n > MAX_SUN_STATE or order > MAX_ORDER:
        raise InvalidParameterError(
            f"the su(3) GPU route takes states of up to {MAX_SUN_STATE} components and site orders up to "
            f"{MAX_ORDER}; this model has {n} and {order}: use backend 'compiled'")
    S = int(steps) // int(save_every)
    _check_fits(c, 8 * B * (n * (S + 1) + 4), f"a call of {B} orbits with {S} saved rows")
    t0 = time.perf_counter()
    args = [c.to_device(np.ascontiguousarray(a)) for a in (X0, np.asarray(b, dtype=np.float64),
                                                            np.asarray(mu0, dtype=np.complex128),
                                                            np.asarray(f, dtype=np.complex128)[None], site_pos,
                                                            site_off, site_n)]
    d_rows = c.device_array((S, B, n))
    d_final = c.device_array((B, n))
    d_mu = c.device_array(B, np.complex128)
    d_status = c.device_array(B, np.int64)
    d_eta = c.to_device(np.array([complex(eta)]))  # the kernel's one map: eta (1,), f (1, C)
    tk = _launch(sun_kernel(), B, (*args, d_eta, np.int64(steps), np.int64(save_every), d_rows, d_final, d_mu,
                                   d_status))
    rows, final, mu, status = (a.copy_to_host() for a in (d_rows, d_final, d_mu, d_status))
    _record(tk, time.perf_counter() - t0, B, int(steps))
    return rows, final, mu, status


def _record(kernel_s: float, total_s: float, orbits: int, steps: int) -> None:
    _last.kernel, _last.total, _last.orbits, _last.steps = kernel_s, total_s, orbits, steps
    _last.device = require_name()


def iterate_batch(X, b, eta, nu0, cont, steps, save_every, *, specialise=True, want_drift=True):
    """:func:`run_batch` raising :class:`jetgaudin.SingularStepError` (or :class:`jetgaudin.BranchPointError`) for
    the first failing orbit: the CPU route's ``iterate_batch`` with this driver."""
    from ..backlund.kernels._drivers import iterate_batch as cpu_iterate_batch

    return cpu_iterate_batch(X, b, eta, nu0, cont, steps, save_every, specialise=specialise, want_drift=want_drift,
                             runner=run_batch)


@functools.lru_cache(maxsize=64)
def _family_constants(model, eta: complex) -> tuple:
    """The one family kernel's per-``(model, ξ)`` constants, computed once (a run calls chunk by chunk)."""
    from ..gaudin._family_kernel import orbit_constants

    return orbit_constants(model, eta)


def run_chain(model, eta, X, nu0, steps: int, save_every: int):
    """A chain's map (``model``, ``η``) on the batch ``X`` (B, 3M) from ``ν1 = nu0`` on the GPU, with the constants
    of the one family kernel (every family, the rational one included): ``(rows, final, last ν1)`` as
    :func:`run_chain_batch`."""
    f, rule, gk, T, pidx, P, site_off, site_n = _family_constants(model, complex(eta))
    return run_chain_batch(X, float(model.b), np.asarray(nu0, dtype=complex), f, rule, gk, T, pidx, P, site_off,
                           site_n, steps, save_every)


@dataclass(frozen=True)
class GPUReport:
    """What :func:`prepare` did: the kernel it compiled for the GPU (``kernels``), ``state`` (``"loaded"``: it was
    compiled in this process already; ``"cold"``) and the seconds spent (compile and first launch)."""

    kernels: tuple[str, ...]
    state: str
    seconds: float


_prepared: set[str] = set()


def prepare(n_state: int, notify=None, chain_map=None) -> GPUReport:
    """Compile the GPU kernel a run on states of ``n_state`` components will launch (the top's N = 3 or generic
    kernel, or ``chain_map``'s), saying so first and when done (``notify(message)``; default stderr); nothing is
    said when it is compiled in this process already.  For the top, the run layer's resident kernels (health and
    status on the device: :func:`jetgaudin.gpu._health.warm`) are compiled here too, so that no compile falls
    inside a run's timed loop.  Numba's CUDA target keeps no on-disk cache of these kernels: a new process compiles
    them again (a few seconds)."""
    import sys

    say = notify if notify is not None else (lambda m: print(m, file=sys.stderr, flush=True))
    name = "chain" if chain_map is not None else ("top3" if n_state == 9 else "top_generic")
    if name in _prepared:
        return GPUReport((f"gpu.{name}",), "loaded", 0.0)
    say(f"compiling the GPU kernel gpu.{name} for {require_name()} (a few seconds, once per process)...")
    t0 = time.perf_counter()
    if chain_map is not None:
        x = np.ones((1, n_state))
        run_chain(chain_map.model, chain_map.eta, x, np.ones(1, dtype=complex), 0, 1)
    else:
        from ._health import warm

        run_batch(np.ones((1, n_state)), 1.0, 2 + 1j, 1 + 0j, False, 0, 1, want_drift=False)
        warm(n_state)  # the run layer's resident kernels (health, status) too: not compiled inside the timed loop
    dt = time.perf_counter() - t0
    _prepared.add(name)
    say(f"GPU kernel gpu.{name} compiled in {dt:.1f} s")
    return GPUReport((f"gpu.{name}",), "cold", dt)


def require_name() -> str:
    """The device the GPU route runs on, in words (:func:`jetgaudin.gpu._device.probe`)."""
    from ._device import probe

    return probe()[1]
