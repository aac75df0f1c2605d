r"""Seeded, reproducible samplers of initial states for ensembles (re-exported by :mod:`jetgaudin.ensemble`).

:func:`sample_on_leaf` (states with the Casimirs ``C_1..C_N`` of Prop. 2 fixed), :func:`sample_on_energy_shell`
(states with ``H = H_2/2`` of eq. (H) fixed), and for Gaudin chains :func:`sample_chain_on_leaf` with
:func:`default_chain_casimirs`.
"""

from __future__ import annotations

import numpy as np

from ._errors import InvalidParameterError
from ._validate import check_N
from .maps import check_count

#: the leaf ``ensemble`` samples when given neither ``--input`` nor ``--sample`` (N = 3): the Casimirs of the
#: Appendix 2 initial state rounded, ``C = (0.4, -0.3, 1.5)`` (any leaf with ``C_N > 0`` works)
DEFAULT_CASIMIRS = (0.4, -0.3, 1.5)


def _unit(rng, shape):
    v = rng.standard_normal(shape + (3,))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sample_on_leaf(N: int, casimirs, size: int, *, seed=None, scale: float = 1.0) -> np.ndarray:
    r"""``size`` random states (shape ``(size, 3N)``) on the symplectic leaf ``C_k(X) = c_k`` (Prop. 2).

    ``C_k = Σ_{i=k-1}^{N-1} ⟨y_i, y_{N+k-i-2}⟩`` is triangular: ``C_N = |y_{N-1}|²`` and, for
    ``k < N``, ``C_k = 2⟨y_{k-1}, y_{N-1}⟩ + (terms in y_k..y_{N-2})``.  So ``y_{N-1}`` is drawn
    uniformly on the sphere of radius ``√c_N`` and, for ``k = N-1, …, 1``, ``y_{k-1}`` is a Gaussian
    (standard deviation ``scale``) whose component along ``y_{N-1}`` is then set to solve the ``C_k``
    equation.  ``c_N > 0`` is required.  ``seed``: anything :func:`numpy.random.default_rng` takes.
    """
    N = check_N(N)
    c = np.asarray(casimirs, dtype=float)
    if c.shape != (N,) or not np.all(np.isfinite(c)):
        raise InvalidParameterError(f"casimirs must be N = {N} finite numbers (C_1, ..., C_N), got {casimirs!r}")
    if c[-1] <= 0:
        raise InvalidParameterError(f"C_N = |y_(N-1)|^2 must be positive, got {c[-1]}")
    size = check_count(size, "size", 1)
    if not (np.isfinite(scale) and scale > 0):
        raise InvalidParameterError(f"scale must be positive, got {scale!r}")
    rng = np.random.default_rng(seed)
    y = np.empty((size, N, 3))
    y[:, N - 1] = np.sqrt(c[-1]) * _unit(rng, (size,))
    e = y[:, N - 1] / np.sqrt(c[-1])
    for k in range(N - 1, 0, -1):
        g = scale * rng.standard_normal((size, 3))
        g -= np.sum(g * e, axis=-1, keepdims=True) * e
        y[:, k - 1] = g
        rest = np.zeros(size)
        for i in range(k, N - 1):
            rest += np.sum(y[:, i] * y[:, N + k - i - 2], axis=-1)
        alpha = (c[k - 1] - rest) / (2.0 * np.sqrt(c[-1]))
        y[:, k - 1] += alpha[:, None] * e
    return y.reshape(size, 3 * N)


def sample_on_energy_shell(N: int, b: float, energy: float, size: int, *, seed=None, scale: float = 1.0,
                           max_tries: int = 1000) -> np.ndarray:
    r"""``size`` random states (``(size, 3N)``, ``N ≥ 2``) on the energy shell ``H = H_2/2 = E`` of
    eq. (H) with field ``b e_3``: ``H_2 = 2 b y_1^3 + |y_0|²`` (Prop. 2).

    ``y_1, …, y_{N-1}`` are Gaussian (standard deviation ``scale``), redrawn until
    ``2E − 2 b y_1^3 > 0``; then ``y_0`` is uniform on the sphere of radius ``√(2E − 2 b y_1^3)``.
    """
    N = check_N(N)
    if N < 2:
        raise InvalidParameterError("the energy shell H = H_2/2 needs N >= 2 (for N = 1 use sample_on_leaf)")
    size = check_count(size, "size", 1)
    b = float(b)
    energy = float(energy)
    if not (np.isfinite(b) and b != 0 and np.isfinite(energy)):
        raise InvalidParameterError("b must be finite and nonzero and the energy finite")
    if not (np.isfinite(scale) and scale > 0):
        raise InvalidParameterError(f"scale must be positive, got {scale!r}")
    rng = np.random.default_rng(seed)
    y = scale * rng.standard_normal((size, N, 3))
    r2 = 2.0 * energy - 2.0 * b * y[:, 1, 2]
    for _ in range(max_tries):
        bad = r2 <= 0
        if not np.any(bad):
            break
        y[bad] = scale * rng.standard_normal((int(bad.sum()), N, 3))
        r2 = 2.0 * energy - 2.0 * b * y[:, 1, 2]
    else:
        raise InvalidParameterError(
            f"could not reach the energy shell H = {energy} with scale {scale}: increase the energy or the scale"
        )
    y[:, 0] = np.sqrt(r2)[:, None] * _unit(rng, (size,))
    return y.reshape(size, 3 * N)


def default_chain_casimirs(orders) -> list[float]:
    r"""The leaf a chain ensemble samples by default: per site of order ``N``, the one-body default
    :data:`DEFAULT_CASIMIRS` ``(C_{N-2}, C_{N-1}, C_N) = (0.4, −0.3, 1.5)`` right-aligned (its last ``N`` entries for
    ``N < 3``, zeros before it for ``N > 3``); so a site of order 3 gets the one-body default and a spin
    (``N = 1``) ``|s|² = 1.5``.  Flat, site by site, in the order of the state (``M = Σ N_i`` numbers)."""
    out: list[float] = []
    for N in orders:
        N = check_N(N)
        out += [0.0] * max(0, N - 3) + list(DEFAULT_CASIMIRS[max(0, 3 - N):])
    return out


def sample_chain_on_leaf(model, casimirs=None, size: int = 1, *, seed=None, scale: float = 1.0) -> np.ndarray:
    r"""``size`` random states (``(size, 3M)``) of the chain ``model`` (a :class:`jetgaudin.GaudinModel` of any
    family) on the symplectic leaf given site by site.

    The Poisson structure of a chain is per site that of ``g^(N_i)`` (the same for every family), so its leaves are
    products of the sites' leaves: site ``i`` has the Casimirs ``C^{(i)}_1..C^{(i)}_{N_i}`` of Prop. 2, which are
    the integrals ``h_{i,N_i+k} = C^{(i)}_k`` the model marks in :meth:`~jetgaudin.GaudinModel.casimir_mask`.
    Each site is drawn by :func:`sample_on_leaf` (its rule and ``scale``), the sites one after the other from one
    generator (``seed``), so one site at 0 of order ``N`` gives exactly ``sample_on_leaf(N, casimirs, size,
    seed=seed)``.  ``casimirs``: ``M`` numbers, site by site ``C_1..C_{N_i}`` (each site's ``C_{N_i} > 0``);
    ``None``: :func:`default_chain_casimirs`.
    """
    orders = tuple(model.orders)
    c = np.asarray(default_chain_casimirs(orders) if casimirs is None else casimirs, dtype=float)
    M = sum(orders)
    if c.shape != (M,) or not np.all(np.isfinite(c)):
        raise InvalidParameterError(f"casimirs must be M = {M} finite numbers, site by site C_1..C_(N_i) (orders "
                                    f"{list(orders)}), got {casimirs!r}")
    size = check_count(size, "size", 1)
    rng = np.random.default_rng(seed)
    parts, o = [], 0
    for i, N in enumerate(orders):
        try:
            parts.append(sample_on_leaf(N, c[o:o + N], size, seed=rng, scale=scale))
        except InvalidParameterError as exc:
            raise InvalidParameterError(f"site {i + 1} (order {N}): {exc}") from None
        o += N
    return np.concatenate(parts, axis=-1)
