r"""One entry point for the flow of any model's Hamiltonian: ``jg.solve(H, X0, t_span, dt=…, method=…)``.

``H`` follows the protocol :class:`jetgaudin.hamiltonians.SolveHamiltonian` (a top's ``IntegralHamiltonian``, a
chain's ``model.hamiltonian(w)`` of every family, an su(n) chain's); which map each method builds for it is one
route table, :data:`jetgaudin.methods.ROUTES` (no top/chain branch here).  Methods (``docs/integrators.md``):

* ``"exact"`` -- the exact time-``dt`` flow (:class:`jetgaudin.ExactFlow`, :class:`jetgaudin.ChainExactFlow`, the
  su(3) ``SunExactFlow``: commuting Bäcklund maps and a rotation); ``substeps="auto"`` splits a step the leaf cannot
  take in one into exact sub-steps, recorded in ``Trajectory.info["substeps"]`` (an exact composition, not an
  approximation);
* ``"bt"`` -- the matched two-point map: a top's :class:`jetgaudin.exact.MatchedBacklund` (one map per step, H_2
  weight and rotation matched; exact for N = 2, the exact flow of a *modified* Hamiltonian for N ≥ 3); a chain's
  exact step where that is one map and a rotation; refused, naming why, where no such map exists;
* ``"dop853"`` -- SciPy's DOP853 (adaptive; ``dt`` only sets the output grid), tolerances ``rtol``/``atol``;
* ``"heyoka"`` -- heyoka's Taylor method (adaptive; tolerance ``rtol``), extra ``jetgaudin[heyoka]``;
* ``"midpoint"`` -- :class:`jetgaudin.midpoint.ImplicitMidpoint`, order 2, fixed step (every model);
* ``"kahan"`` -- :class:`jetgaudin.kahan.KahanMap`, Kahan's map: order 2, one linear solve per step (tops and su(2)
  chains: quadratic fields).

The fixed-step methods take ``n = ⌈|t1 − t0|/|dt|⌉`` steps of ``(t1 − t0)/n`` (so the grid ends at ``t1``; the step
used is ``info["dt"]``).  The result is a :class:`jetgaudin.Trajectory` (``t``, ``X``, the integrals and their drift).
"""

from __future__ import annotations

import math
from dataclasses import replace
from enum import StrEnum
from typing import Any

import numpy as np

from ._errors import InvalidParameterError, StepTooLargeError
from ._validate import parse_choice, real_number
from .exact import record_integrals
from .flows import Method, Trajectory, integrate
from .maps import backend_option, check_count, check_output_size
from .methods import check_method, method_map

__all__ = ["SolveMethod", "solve", "time_grid"]


class SolveMethod(StrEnum):
    """The methods of :func:`solve`."""

    EXACT = "exact"
    BT = "bt"
    DOP853 = "dop853"
    HEYOKA = "heyoka"
    MIDPOINT = "midpoint"
    KAHAN = "kahan"

    @classmethod
    def parse(cls, value: SolveMethod | str) -> SolveMethod:
        return parse_choice(cls, value.lower() if isinstance(value, str) else value, "method")


def time_grid(t_span, dt) -> tuple[float, float, int]:
    """``(t0, step, n)``: ``n = ⌈|t1 − t0|/|dt|⌉`` steps of ``(t1 − t0)/n`` (the grid ends at ``t1``)."""
    try:
        t0, t1 = (real_number(v, "t_span") for v in t_span)
    except TypeError:
        raise InvalidParameterError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
    if t1 == t0:
        raise InvalidParameterError("t_span must have t1 != t0")
    dt = real_number(dt, "dt")
    if dt == 0:
        raise InvalidParameterError("dt must be nonzero")
    T = t1 - t0
    n = max(1, math.ceil(abs(T) / abs(dt) * (1 - 1e-12)))
    return t0, T / n, n


def _orbit(m, X0: np.ndarray, n: int, every: int) -> tuple[np.ndarray, np.ndarray]:
    """``(steps, states)``: the states after ``0, every, 2 every, …`` steps and after ``n``."""
    adv = m.advance(X0, None, n, every)
    idx = np.arange(0, n + 1, every)
    rows = [X0[None], adv.rows]
    if n % every:
        idx = np.append(idx, n)
        rows.append(adv.X[None])
    return idx, np.concatenate(rows, axis=0)


def _exact_dense(H: Any, substeps: int, t_grid: np.ndarray, X_grid: np.ndarray):
    """``dense(t)``: the state at times ``t`` by one exact step from the nearest saved state (issue 34)."""
    up = t_grid[-1] >= t_grid[0]
    ts, Xs = (t_grid, X_grid) if up else (t_grid[::-1], X_grid[::-1])
    span = abs(ts[-1] - ts[0])

    def dense(t) -> np.ndarray:
        try:
            t = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"t must be real times, got {t!r}") from None
        flat = t.reshape(-1)
        slack = 1e-12 * max(1.0, span)
        if not np.all(np.isfinite(flat)) or np.any(flat < ts[0] - slack) or np.any(flat > ts[-1] + slack):
            raise InvalidParameterError(f"t must lie in the trajectory's span [{ts[0]}, {ts[-1]}]; solve over a "
                                        "longer t_span")
        j = np.clip(np.searchsorted(ts, flat), 1, len(ts) - 1)
        k = np.where(flat - ts[j - 1] <= ts[j] - flat, j - 1, j) if len(ts) > 1 else np.zeros(len(flat), int)
        out = np.empty((len(flat),) + Xs.shape[1:])
        for r, (kk, tt) in enumerate(zip(k, flat, strict=True)):
            ds = float(tt - ts[kk])
            out[r] = Xs[kk] if ds == 0.0 else method_map(H, "exact", ds, substeps)(Xs[kk])
        return out.reshape(t.shape + Xs.shape[1:])

    return dense


def solve(H: Any, X0, t_span, *, dt=None, method: SolveMethod | str = SolveMethod.EXACT,
          rtol: float = 1e-12, atol: float = 1e-12, save_every: int = 1, substeps: int | str = "auto",
          backend: str = "auto", t_eval=None, kernel: str | None = None) -> Trajectory:
    r"""The flow of ``Ẋ = Π(X) ∇H`` (eq. (LP)) for ``H`` a top's :class:`~jetgaudin.IntegralHamiltonian` or a chain's
    ``model.hamiltonian(weights)`` of any family or algebra (every method for every model where the route table
    :data:`jetgaudin.methods.ROUTES` has a map; elsewhere :class:`jetgaudin.InvalidParameterError` naming why and the
    methods that apply: ``"bt"`` where no matched two-point map exists, ``"kahan"`` and ``"heyoka"`` past su(3),
    ``"exact"`` of su(n) for ``n ≠ 3``; ``docs/sun.md`` §5) from ``X0`` ``(n_state,)`` (or a batch
    ``(..., n_state)`` for the map methods)
    over ``t_span = (t0, t1)`` (either direction), sampled every ``save_every`` steps of ``dt`` (module doc).

    ``dt``: the time step (required by ``"exact"``, ``"bt"``, ``"midpoint"``; for ``"dop853"``/``"heyoka"`` the
    output spacing, default: the end points only).  ``substeps``: for ``"exact"``/``"bt"``, ``"auto"`` (split a step
    the leaf cannot take at once; :class:`jetgaudin.StepTooLargeError` never reaches you) or an integer (an
    infeasible step then raises).  ``backend`` (alias ``kernel``, as on the maps): ``"auto"``/``"compiled"``/``"numpy"``
    for the map methods.
    ``t_eval``: sample times (absolute) instead of the grid -- ``"dop853"``/``"heyoka"`` sample there, ``"exact"``
    steps on the ``dt`` grid and reaches each ``t`` by one exact step from the nearest grid state
    (:meth:`Trajectory.at`, kept on the result for ``"exact"``).  ``H`` may be a physical top
    (:func:`jetgaudin.heavy_top`, :func:`jetgaudin.kirchhoff_clebsch`; then ``X0`` is its ``P0`` and the result has
    physical times and ``Trajectory.physical``, :func:`jetgaudin.physical.solve_physical`).

    >>> import jetgaudin as jg
    >>> H = jg.physical_hamiltonian(3, 1.0)
    >>> X0 = [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]
    >>> tr = jg.solve(H, X0, (0.0, 1.0), dt=0.25)
    >>> tr.t.tolist(), bool(tr.drift.max() < 1e-13)
    ([0.0, 0.25, 0.5, 0.75, 1.0], True)
    """
    chosen = backend_option(backend, kernel)  # the maps' alias rule (two different concrete choices are refused)
    backend = "auto" if chosen is None else chosen.value
    if getattr(H, "is_physical_top", False):  # jg.heavy_top, jg.kirchhoff_clebsch (issue 34)
        from .physical import solve_physical

        return solve_physical(H, X0, t_span, dt=dt, method=method, rtol=rtol, atol=atol, save_every=save_every,
                              substeps=substeps, backend=backend, t_eval=t_eval)
    method = SolveMethod.parse(method)
    check_method(H, method.value)  # the route table (jetgaudin.methods): a typed refusal where no route exists
    X0 = np.asarray(H.check_state(X0), dtype=float)
    every = check_count(save_every, "save_every", 1)
    grid = None if dt is None else time_grid(t_span, dt)
    if grid is not None:  # the output's size, refused past the cap before anything is allocated (maps.MAX_OUTPUT_BYTES)
        n_out = grid[2] // every + 2
        check_output_size(n_out, 8 * (X0.size + 1 + 2 * (X0.shape[-1] // 3) * max(1, X0.size // X0.shape[-1])),
                          "solve")
    if method in (SolveMethod.DOP853, SolveMethod.HEYOKA):
        t0, t1 = (real_number(v, "t_span") for v in t_span)
        if t_eval is not None:
            t_eval = np.asarray(t_eval, dtype=float) - t0
        elif dt is None:
            t_eval = np.array([0.0, t1 - t0])
        else:
            _, h, n = time_grid(t_span, dt)
            k = np.arange(0, n + 1, every)
            t_eval = np.unique(np.concatenate([k, [n]])) * h
        mth = Method.DOP853 if method is SolveMethod.DOP853 else Method.HEYOKA
        tr = integrate(H, X0, t1 - t0, t_eval=t_eval, method=mth, rtol=rtol, atol=atol)
        return Trajectory(t0 + tr.t, tr.X, tr.integrals, method.value, {"rtol": rtol, "atol": atol})
    if grid is None:
        raise InvalidParameterError(f"method={method.value!r} is a fixed-step method: give dt")
    t0, h, n = grid
    auto = substeps == "auto"
    s = 1 if auto else check_count(substeps, "substeps", 1)
    info: dict = {"dt": h, "steps": n}
    while True:
        m = method_map(H, method.value, h, s, backend)
        try:
            idx, Xs = _orbit(m, X0, n, every)
            break
        except StepTooLargeError as exc:
            if not auto or exc.dt_max is None or exc.dt_max == 0:
                raise
            s = max(s + 1, math.ceil(abs(h) / abs(exc.dt_max) * 1.01))
    if method not in (SolveMethod.MIDPOINT, SolveMethod.KAHAN):
        info["substeps"] = s
    # the top's rows through one compiled pass (exact.record_integrals, the same bits as jg.integrals; issue 33)
    recorded = record_integrals(H, Xs) if H.route_kind == "top" else H.record_integrals(Xs)
    t = t0 + idx * h
    tr = Trajectory(t, Xs, np.asarray(recorded, dtype=float), method.value, info,
                    dense=_exact_dense(H, s, t, Xs) if method is SolveMethod.EXACT else None)
    if t_eval is not None:  # the exact flow's dense output at the requested times
        if tr.dense is None:
            raise InvalidParameterError(f"t_eval needs dense output: method='exact', 'dop853' or 'heyoka', not "
                                        f"{method.value!r} (a fixed-step map has states on its grid only)")
        Xe = tr.at(t_eval)
        tr = replace(tr, t=np.asarray(t_eval, dtype=float), X=Xe, integrals=np.asarray(H.record_integrals(Xe),
                                                                                        dtype=float))
    return tr
