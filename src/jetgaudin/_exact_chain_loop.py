r"""The compiled stepping loop of :class:`jetgaudin.ChainExactFlow` (private): every step ``B_{η_1} ∘ … ∘ B_{η_k}`` of
one orbit in one compiled call, each map's step the chain map's own kernel (:func:`jetgaudin.gaudin._kernels.run_orbit`
for the rational family, :func:`jetgaudin.gaudin._family_kernel.run_orbit` for the others: the same arithmetic as
``ChainTwoPointBacklund(..., backend="compiled")``), each map's ``ν1`` continued from its previous step, and each saved
row the unrotated orbit rotated once through its accumulated angle (as :mod:`jetgaudin._exact_loop`).

The per-map constants (``gaudin.maps._orbit_constants``) are stacked along a leading axis of length ``k``; the shapes
agree for every ``η`` of one model except, for the family kernel, the number ``K`` of basis matrices per entry, which
:func:`stack_constants` pads with zeros (a zero coefficient adds nothing).  Numba's cache keys this module by its own
source: after an edit of the chain kernels, clear ``jetgaudin/__pycache__/_exact_chain_loop.*``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._exact_loop import _rotate_into
from .gaudin import _family_kernel as _fk
from .gaudin import _kernels as _rk

__all__ = ["rows_rational", "rows_family", "stack_constants"]


@njit(cache=True)
def rows_rational(x0, b, eta, nu, F, G, site_pos, site_off, site_n, theta, steps, save_every, substeps, rows, final):
    """One orbit ``x0`` (3M,) of the rational family: ``rows[r] = X_{(r+1) save_every}``, ``final = X_steps``; the
    maps ``eta`` (k,) with their kernel constants ``F`` (k, ...), ``G`` (k, ...), ``nu`` (k,) their first ``ν1``
    (overwritten by the last).  Each map step is the kernel's own step (:func:`jetgaudin.gaudin._kernels._step`,
    the arithmetic of its ``run_orbit``) on scratch allocated once per call."""
    n = x0.shape[0]
    M = n // 3
    x = x0.copy()
    y = np.empty(n)
    w0, w1, wp, gs = _rk.step_scratch(site_n)
    left = save_every
    r = 0
    for s in range(steps):
        for _ in range(substeps):
            for j in range(eta.shape[0]):
                nu[j] = _rk._step(x, y, b, eta[j], nu[j], F[j], G[j], gs, site_pos, site_off, site_n, M, w0, w1, wp)
                x, y = y, x
        left -= 1
        if left == 0:
            left = save_every
            _rotate_into(x, ((s + 1) * substeps) * theta, rows[r])
            r += 1
    _rotate_into(x, (steps * substeps) * theta, final)


@njit(cache=True)
def rows_family(x0, b, nu, F, rule, GK, T, PIDX, n_basis, site_off, site_n, theta, steps, save_every, substeps, rows,
                final):
    """:func:`rows_rational` for the family kernel (trigonometric, elliptic): the constants ``F, GK, T, PIDX``
    stacked over the ``k`` maps; each map step :func:`jetgaudin.gaudin._family_kernel._step` (the arithmetic of
    its ``run_orbit``; inlined here, with its unrolled sites of order 1 and 2) on scratch allocated once per call."""
    n = x0.shape[0]
    x = x0.copy()
    y = np.empty(n)
    Nmax = T.shape[2]
    c = np.zeros(n_basis, dtype=np.complex128)
    Dt = np.empty((Nmax, 4), dtype=np.complex128)
    At = np.empty((Nmax, 4), dtype=np.complex128)
    det = np.empty(Nmax, dtype=np.complex128)
    g = np.empty(Nmax, dtype=np.complex128)
    P = np.empty((Nmax, 4), dtype=np.complex128)
    left = save_every
    r = 0
    for s in range(steps):
        for _ in range(substeps):
            for j in range(nu.shape[0]):
                nu[j] = _fk._step(x, y, b, nu[j], F[j], rule, GK[j], T[j], PIDX[j], site_off, site_n, c, Dt, At, det,
                                  g, P)
                x, y = y, x
        left -= 1
        if left == 0:
            left = save_every
            _rotate_into(x, ((s + 1) * substeps) * theta, rows[r])
            r += 1
    _rotate_into(x, (steps * substeps) * theta, final)


def stack_constants(consts: list[tuple]) -> tuple:
    """The per-map kernel constants stacked over the maps: rational ``(F, G, site_pos, site_off, site_n)``, family
    ``(F, rule, GK, T, PIDX, n_basis, site_off, site_n)`` (``T``, ``PIDX`` zero-padded to the largest ``K``)."""
    if len(consts[0]) == 5:
        return (np.stack([c[0] for c in consts]), np.stack([c[1] for c in consts]), *consts[0][2:])
    K = max(c[3].shape[-1] for c in consts)
    T = np.zeros((len(consts),) + consts[0][3].shape[:-1] + (K,), dtype=complex)
    P = np.zeros((len(consts), 4, K), dtype=np.int64)
    for j, c in enumerate(consts):
        T[j, ..., :c[3].shape[-1]] = c[3]
        P[j, :, :c[4].shape[-1]] = c[4]
    return (np.stack([c[0] for c in consts]), consts[0][1], np.stack([c[2] for c in consts]), T, P, consts[0][5],
            *consts[0][6:])
