"""Exact steps off the twisted top's path (issue 33, part 2): the Clebsch top, dt_max and substeps of a chain, the
drift of saving every step, the every-row route, batches with an infeasible orbit, event directions, translation of
the sites.

Tolerances: one exact step is a few two-point maps and a rotation, round-off ~1e-15 for states of size ~1; the
references are DOP853 at rtol = atol = 1e-13 (its error over |T| <= 2 is ~1e-13): 1e-12 asserted unless stated.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jetgaudin as jg
from jetgaudin.exact_chain import ChainExactFlow

CLEBSCH = jg.clebsch_top(0.6)
H_CLEBSCH = CLEBSCH.hamiltonian([0, 0.7, 0, 0, 1.0])
X_CLEBSCH = np.array([0.72, 0.24, -0.54, 0.6, 0, 0.8])  # the state of the issue
H3 = jg.physical_hamiltonian(3, 1.0)
X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2


def _dop(H, X, T):
    return jg.solve(H, X, (0.0, T), method="dop853", rtol=1e-13, atol=1e-13).X[-1]


def test_clebsch_top_exact_flow_is_the_flow():
    """The issue's call (a bare LinAlgError before: one site, no branch points, so R = 1e-6 put the maps' real parts
    on the site): every row agrees with DOP853 (1e-12) and the integrals are kept (1e-13 relative: 20 steps)."""
    tr = jg.solve(H_CLEBSCH, X_CLEBSCH, (0, 1), dt=0.05, method="exact")
    ref = jg.solve(H_CLEBSCH, X_CLEBSCH, (0, 1), dt=0.05, method="dop853", rtol=1e-13, atol=1e-13)
    assert tr.X.shape == (21, 6) and tr.info["substeps"] == 1
    assert np.max(np.abs(tr.X - ref.X)) < 1e-12
    assert tr.drift.max() < 1e-13
    assert np.max(np.abs(tr.X[-1] - X_CLEBSCH)) > 0.05  # it moves


def test_clebsch_top_dt_max_substeps_and_solve_never_raises():
    """dt = 2 is beyond this leaf's largest step: StepTooLargeError names dt_max (feasible at 0.999 dt_max, refused at
    1.01 dt_max: the bisection's 1e-3); solve's substeps='auto' splits the step (its docstring: StepTooLargeError never
    reaches the user) and the result is the flow (DOP853, 1e-12 over T = 4)."""
    with pytest.raises(jg.StepTooLargeError, match="largest feasible time step") as exc:
        ChainExactFlow(H_CLEBSCH, 2.0)(X_CLEBSCH)
    dmax = exc.value.dt_max
    assert 0.1 < dmax < 2.0
    ChainExactFlow(H_CLEBSCH, dmax)(X_CLEBSCH)  # the largest feasible step is feasible (the bisection's lower end)
    with pytest.raises(jg.StepTooLargeError):
        ChainExactFlow(H_CLEBSCH, 1.01 * dmax)(X_CLEBSCH)
    tr = jg.solve(H_CLEBSCH, X_CLEBSCH, (0, 4), dt=2.0)
    assert tr.info["substeps"] >= 2
    assert np.max(np.abs(tr.X[-1] - _dop(H_CLEBSCH, X_CLEBSCH, 4.0))) < 1e-12
    E = ChainExactFlow(H_CLEBSCH, 2.0, substeps=3)
    assert jg.map_from_description(E.describe()).substeps == 3
    assert np.max(np.abs(E(X_CLEBSCH) - _dop(H_CLEBSCH, X_CLEBSCH, 2.0))) < 1e-12


def _ivp_events(H, X0, g, T, direction):
    ev = lambda t, X: g(X)  # noqa: E731
    ev.direction = direction
    sol = solve_ivp(lambda t, X: H.vector_field(X), (0, T), X0, method="DOP853", rtol=1e-13, atol=1e-13,
                    events=ev)
    return sol.t_events[0]


@pytest.mark.parametrize("direction", [1, -1])
def test_event_directions_on_the_clebsch_top(direction):
    """find_events / poincare_section on the Clebsch top (a LinAlgError before): the crossing times of g = y_1^1
    in each direction equal DOP853's event times (1e-9: its dense output at 1e-13), and g increases (direction +1)
    or decreases (-1) through each: its sign 1e-3 before and after, by exact steps from the event state."""
    g = lambda X: X[3]  # noqa: E731
    ev = jg.poincare_section(H_CLEBSCH, X_CLEBSCH, g, (0, 6), 0.1, direction=direction)
    ref = _ivp_events(H_CLEBSCH, X_CLEBSCH, g, 6.0, direction)
    assert len(ev.t) == len(ref) >= 1
    assert np.max(np.abs(ev.t - ref)) < 1e-9
    assert np.all(ev.direction == direction)
    for X in ev.X:
        assert abs(g(X)) < 1e-12
        before, after = (g(ChainExactFlow(H_CLEBSCH, s)(X)) for s in (-1e-3, 1e-3))
        assert np.sign(after - before) == direction and np.sign(after) == direction
    both = jg.find_events(H_CLEBSCH, X_CLEBSCH, g, (0, 6), 0.1)
    assert len(both.t) == len(_ivp_events(H_CLEBSCH, X_CLEBSCH, g, 6.0, 0))
    assert set(np.round(ev.t, 9)) <= set(np.round(both.t, 9))


def test_event_directions_on_the_top():
    """The top's crossing directions: the +1 and -1 events partition the two-sided ones, and each is checked by the
    sign of g 1e-3 before and after (exact steps)."""
    g = lambda X: X[0]  # noqa: E731
    up = jg.poincare_section(H3, X3, g, (0, 60), 0.2, direction=1)
    down = jg.poincare_section(H3, X3, g, (0, 60), 0.2, direction=-1)
    both = jg.find_events(H3, X3, g, (0, 60), 0.2)
    assert len(up.t) >= 2 and len(down.t) >= 2
    assert np.array_equal(np.sort(np.concatenate([up.t, down.t])), both.t)
    for evs, d in ((up, 1), (down, -1)):
        for X in evs.X:
            assert np.sign(g(jg.ExactFlow(H3, 1e-3)(X))) == d and np.sign(g(jg.ExactFlow(H3, -1e-3)(X))) == -d


def test_a_one_site_model_without_real_parts_is_a_typed_error():
    """A one-site rational model at X = 0 has every branch point at 0 (R = 0): no real parts off the site exist, a
    StepTooLargeError (dt_max = 0) instead of a bare LinAlgError."""
    H = jg.twisted_chain(0.8, [0.0]).hamiltonian([0.1, 0.5, 0.2, 0, 0, 0])
    with pytest.raises(jg.StepTooLargeError, match="at any step size") as exc:
        ChainExactFlow(H, 0.05)(np.zeros(9))
    assert exc.value.dt_max == 0.0


def test_saving_every_step_drifts_like_round_off():
    """The issue's measurement: dt = 0.01, T = 1000 (10^5 steps), every row saved.  Before: every step applied R_θ,
    whose cos² + sin² − 1 = −1.1e-16 shrank |y| by the same factor each step: H_2 drift 6.7e-11 (linear).  Now each
    row is the unrotated orbit rotated once: 5e-12 asserted (10^5 steps of 1e-16 random round-off give
    ~3e-14–1e-13; the linear bias would exceed it tenfold)."""
    tr = jg.solve(H3, X3, (0, 1000), dt=0.01)
    assert tr.X.shape[0] == 100_001
    assert tr.drift.max() < 5e-12


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_every_row_route_equals_the_end_state_route(backend):
    """iterate (every row: the one compiled loop) and advance to the end state (k steps per kernel call) are the same
    flow with other round-off: 1e-12 after 400 steps (each ~1e-15); the numpy route's rows agree with the compiled
    ones to 1e-12; a batch member equals its single run bit for bit."""
    E = jg.ExactFlow(H3, 0.1, backend=backend)
    rows = E.iterate(X3, 400)
    assert rows.shape == (401, 9)
    assert np.max(np.abs(rows[-1] - E.advance(X3, None, 400, 400).X)) < 1e-12
    assert np.max(np.abs(rows[1:41] - jg.ExactFlow(H3, 0.1, backend="numpy").iterate(X3, 40)[1:])) < 1e-12
    B = np.stack([X3, 0.9 * X3])
    assert np.array_equal(E.advance(B, None, 30, 1).rows[:, 0], E.advance(X3, None, 30, 1).rows)


def test_batch_with_one_infeasible_orbit():
    """A batch whose orbit 1 cannot take the step (a leaf 3x larger: dt_max ~ 1/R): StepTooLargeError names orbit 1,
    not 0; solve splits the step for the batch, and the feasible orbit's rows equal its own run with the same
    substeps bit for bit."""
    B = np.stack([X3, 3.0 * X3])
    dmax = jg.ExactFlow(H3, 1.0).max_dt(B)
    dt = 0.5 * (dmax[0] + dmax[1])
    assert dmax[1] < dt < dmax[0]
    with pytest.raises(jg.StepTooLargeError, match="orbit 1"):
        jg.ExactFlow(H3, dt)(B)
    tr = jg.solve(H3, B, (0, 4 * dt), dt=dt)
    s = tr.info["substeps"]
    assert s >= 2
    one = jg.ExactFlow(H3, dt, substeps=s).advance(X3, None, 4).rows
    assert np.array_equal(tr.X[1:, 0], one)
    chain = jg.twisted_chain(1.0, [0.0]).hamiltonian(np.asarray(H3.weights))
    with pytest.raises(jg.StepTooLargeError, match="orbit 1"):
        ChainExactFlow(chain, dt)(B)


@pytest.mark.parametrize("family", [{}, {"family": "trigonometric", "gamma": 0.5}])
def test_translating_every_site_does_not_change_the_step(family):
    """L(λ) depends on λ − λ_i only: moving every site by c maps the model onto itself (same integrals, same
    Poisson structure), so the exact step of the same weights is the same map (1e-12: both are the flow)."""
    X = np.random.default_rng(4).standard_normal(9) * 0.5
    w = [0.3, 0.0, -0.2, 0.0, 0.5, 0.0] + ([0.4] if family else [])  # the trigonometric J
    steps = []
    for c in (0.0, 0.37):
        model = jg.GaudinModel(1.0, [(0.0 + c, 1), (1.0 + c, 1), (2.5 + c, 1)], **family)
        steps.append(ChainExactFlow(model.hamiltonian(w), 0.05)(X))
    assert np.max(np.abs(steps[0] - X)) > 1e-3
    assert np.max(np.abs(steps[0] - steps[1])) < 1e-12


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_substeps_of_the_top_on_every_route(backend):
    """substeps = 3 on both of the top's routes and both stepping paths (rows every step: the one compiled loop;
    rows 2 steps apart: k s steps per kernel call): every row is the flow (DOP853, 1e-12 over T <= 1)."""
    E = jg.ExactFlow(H3, 0.25, substeps=3, backend=backend)
    for every in (1, 2):
        rows = E.advance(X3, None, 4, every).rows
        for r, X in enumerate(rows):
            assert np.max(np.abs(X - _dop(H3, X3, 0.25 * every * (r + 1)))) < 1e-12


@pytest.mark.parametrize("case", ["lagrange", "trigonometric"])
def test_chain_substeps_on_the_compiled_loop(case):
    """A chain step beyond dt_max split into exact sub-steps (rational kernel; family kernel) is the flow: every row
    of 3 steps vs DOP853 (1e-11: 3 s maps' round-off, amplified by the chain's larger weights)."""
    if case == "lagrange":
        model = jg.GaudinModel(1.0, ((0.0, 2), (1.0, 1)))
        w = np.zeros(2 * model.M)
        w[~model.casimir_mask()] = [0.5, 0.2, 0.3]
        X0, dt = np.array([0.3, -0.2, 0.5, 0.1, 0.2, -0.1, 0.4, 0.1, 0.6]), 0.3
    else:
        model = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
        w = np.array([0.3, 0, -0.2, 0, 0.5, 0, 0.4])
        X0, dt = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6]), 0.4
    H = model.hamiltonian(w)
    dmax = float(ChainExactFlow(H, 1.0).max_dt(X0))
    s = int(np.ceil(dt / dmax * 1.01))
    assert s >= 2
    rows = ChainExactFlow(H, dt, substeps=s).advance(X0, None, 3, 1).rows
    for r, X in enumerate(rows):
        assert np.max(np.abs(X - _dop(H, X0, dt * (r + 1)))) < 1e-11
    B = np.stack([X0, 0.8 * X0])
    assert np.array_equal(ChainExactFlow(H, dt, substeps=s).advance(B, None, 3, 1).rows[:, 0], rows)


def test_a_hamiltonian_without_h2_to_hN_is_refused_at_once_with_the_rotation_named():
    """H = w_1 H_1 (the weights of H_2..H_N zero) has no Bäcklund parameters (the maps' η would be real): before,
    ExactFlow searched 32 s for a feasible dt and answered dt_max = 0; now the construction refuses it naming the
    rotation, and the rotation named is the flow (against DOP853 at rtol 1e-12: 1e-11 after t = 0.7)."""
    from jetgaudin.exact import MatchedBacklund, rotate_about_field

    X = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
    H = jg.IntegralHamiltonian(1.3, np.array([0.8, 0, 0, 0, 0.5, 0]))  # a Casimir weight changes nothing
    for cls in (jg.ExactFlow, MatchedBacklund):
        with pytest.raises(jg.InvalidParameterError, match="rotate_about_field"):
            cls(H, 0.1)
    ref = jg.integrate(H, X, 0.7, rtol=1e-12, atol=1e-12).X[-1]
    assert np.max(np.abs(rotate_about_field(X, 2 * 1.3 * 0.8 * 0.7) - ref)) < 1e-11


def test_the_largest_dt_search_stops_where_nothing_is_feasible(monkeypatch):
    """Where no dt is feasible the bisection for dt_max stops at 1e-12 |dt| (≤ 41 solves) and answers 0 (before:
    halving to underflow, ~1075 failing solves)."""
    from jetgaudin import exact

    calls = []

    def never(H, dt, X, rho_factor, k=None):
        calls.append(dt)
        return (None, None, None, None, np.array([False]), None)

    monkeypatch.setattr(exact, "_solve_flat", never)
    H = jg.physical_hamiltonian(3, 1.0)
    assert exact._largest_dt(H, 0.3, np.ones(9), 1.5) == 0.0
    assert len(calls) <= 41
