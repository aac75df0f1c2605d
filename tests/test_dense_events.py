"""Exact dense output (Trajectory.at, solve(t_eval=...)) and events on the exact flow (issue 34)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jetgaudin as jg
from jetgaudin.flows import _fast_rhs

H3 = jg.physical_hamiltonian(3, 1.0)
X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2
T = 20.0


@pytest.fixture(scope="module")
def reference():
    """DOP853 at rtol = atol = 1e-13 with dense output and the events of the tests below."""
    def e0(t, y):
        return y[0] - 0.5

    def e1(t, y):
        return y[4]

    return solve_ivp(_fast_rhs(H3, X3), (0, T), X3, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True,
                     events=[e0, e1])


def test_at_any_time_is_the_flow(reference):
    # 60 random times over T = 20 against DOP853's dense output (rtol 1e-13; its interpolant's error ~1e-12):
    # 1e-10; at grid times at() returns the saved state itself
    tr = jg.solve(H3, X3, (0.0, T), dt=0.2)
    ts = np.sort(np.random.default_rng(3).uniform(0, T, 60))
    assert np.abs(tr.at(ts) - reference.sol(ts).T).max() < 1e-10
    assert np.array_equal(tr.at(tr.t[7]), tr.X[7])
    assert tr.at(ts).shape == (60, 9) and tr.at(1.0).shape == (9,)


def test_at_equals_steps_that_land_on_t():
    # t = 1.37 reached by one exact step from the nearest grid state vs a grid that ends on t (7 steps of
    # 1.37/7): the same exact flow by two compositions, 1e-13 (round-off of a few 2 × 2 maps)
    tr = jg.solve(H3, X3, (0.0, 3.0), dt=0.25)
    landed = jg.solve(H3, X3, (0.0, 1.37), dt=1.37 / 7).X[-1]
    assert np.abs(tr.at(1.37) - landed).max() < 1e-13
    back = jg.solve(H3, X3, (0.0, -3.0), dt=0.25)  # backwards in time
    assert np.abs(back.at(-1.37) - jg.solve(H3, X3, (0.0, -1.37), dt=1.37 / 7).X[-1]).max() < 1e-13


def test_solve_t_eval(reference):
    # exact: the states at t_eval are the dense output (bit for bit) and the flow (1e-10 vs DOP853);
    # dop853 samples there itself
    t_eval = np.array([0.05, 3.3, 7.77, 19.9])
    tr = jg.solve(H3, X3, (0.0, T), dt=0.2, t_eval=t_eval)
    assert np.array_equal(tr.t, t_eval) and tr.X.shape == (4, 9) and tr.integrals.shape == (4, 6)
    assert np.abs(tr.X - reference.sol(t_eval).T).max() < 1e-10
    d = jg.solve(H3, X3, (0.0, T), method="dop853", t_eval=t_eval, rtol=1e-13, atol=1e-13)
    assert np.abs(d.X - tr.X).max() < 1e-10


def test_at_refuses_other_methods_and_times_outside():
    tr = jg.solve(H3, X3, (0.0, 1.0), dt=0.01, method="midpoint")
    with pytest.raises(jg.InvalidParameterError, match="exact"):
        tr.at(0.5)
    with pytest.raises(jg.InvalidParameterError, match="t_eval needs dense output"):
        jg.solve(H3, X3, (0.0, 1.0), dt=0.01, method="kahan", t_eval=[0.5])
    ex = jg.solve(H3, X3, (0.0, 1.0), dt=0.25)
    with pytest.raises(jg.InvalidParameterError, match="span"):
        ex.at(1.5)


def test_several_event_functions_and_directions(reference):
    # two functions, both directions: the times agree with solve_ivp's event location (1e-10, as in test_solve)
    ev = jg.find_events(H3, X3, [lambda X: X[0] - 0.5, lambda X: X[4]], (0.0, T), 0.2)
    for i in (0, 1):
        assert np.abs(ev.t[ev.index == i] - reference.t_events[i]).max() < 1e-10
        assert len(ev.t[ev.index == i]) == len(reference.t_events[i]) >= 2
    assert np.all(np.diff(ev.t) > 0)
    assert np.abs(ev.X[ev.index == 0, 0] - 0.5).max() < 1e-12 and np.abs(ev.X[ev.index == 1, 4]).max() < 1e-12
    up = jg.find_events(H3, X3, [lambda X: X[0] - 0.5, lambda X: X[4]], (0.0, T), 0.2, direction=[1, -1])
    keep = ((ev.index == 0) & (ev.direction == 1)) | ((ev.index == 1) & (ev.direction == -1))
    assert np.array_equal(up.t, ev.t[keep])


def test_terminal_event(reference):
    # terminal on the second function: the search ends at its first crossing (the events before it are kept)
    ev = jg.find_events(H3, X3, [lambda X: X[0] - 0.5, lambda X: X[4]], (0.0, T), 0.2, terminal=[False, True])
    first = reference.t_events[1][0]
    assert ev.terminated and ev.index[-1] == 1 and abs(ev.t[-1] - first) < 1e-10
    assert np.all(ev.t <= ev.t[-1]) and np.array_equal(ev.t[:-1], np.sort(ev.t[:-1]))


def test_events_for_an_ensemble_and_a_chain():
    # a batch: one Events per orbit, equal to the single-orbit searches; a chain (Gaudin magnet, two spins):
    # g vanishes at the located states (1e-12) and the times agree with DOP853 events (1e-10)
    X2 = np.stack([X3, X3 * [1, 1, 1, 0.9, 0.9, 0.9, 1, 1, 1]])
    evs = jg.find_events(H3, X2, lambda X: X[0] - 0.5, (0.0, 10.0), 0.2)
    assert isinstance(evs, list) and len(evs) == 2
    for i in range(2):
        assert np.array_equal(evs[i].t, jg.find_events(H3, X2[i], lambda X: X[0] - 0.5, (0.0, 10.0), 0.2).t)
    m = jg.gaudin_magnet(1.0, [-1.0, 0.5])
    H = m.physical_hamiltonian()
    X0 = np.array([0.3, -0.5, 0.8, 0.6, 0.1, -0.4])
    ev = jg.find_events(H, X0, lambda X: X[0], (0.0, 3.0), 0.25)
    sol = solve_ivp(lambda t, y: H.vector_field(y), (0, 3), X0, method="DOP853", rtol=1e-13, atol=1e-13,
                    events=lambda t, y: y[0])
    assert len(ev.t) == len(sol.t_events[0]) >= 1
    assert np.abs(ev.t - sol.t_events[0]).max() < 1e-10 and np.abs(ev.X[:, 0]).max() < 1e-12


def test_events_of_a_physical_top():
    # the heavy top's Π_1 = 0 crossings, located on the exact flow in physical variables, against the textbook
    # equations with solve_ivp's events (1e-10)
    I1, I3, mgl = 1.0, 2.0, 0.7
    top = jg.heavy_top(I1, I3, mgl)
    P0 = np.array([0.3, -0.2, 1.5, 0.6, 0.0, 0.8])
    inv = 1 / np.array([I1, I1, I3])

    def rhs(t, P):
        Om = inv * P[:3]
        return np.concatenate([np.cross(P[:3], Om) + mgl * np.cross(P[3:], [0, 0, 1.0]), np.cross(P[3:], Om)])

    sol = solve_ivp(rhs, (0, 30), P0, method="DOP853", rtol=1e-13, atol=1e-13, events=lambda t, y: y[0])
    ev = jg.find_events(top, P0, lambda P: P[0], (0.0, 30.0), 0.1)
    assert len(ev.t) == len(sol.t_events[0]) >= 2
    assert np.abs(ev.t - sol.t_events[0]).max() < 1e-10 and np.abs(ev.X[:, 0]).max() < 1e-12


def test_event_input_is_checked():
    with pytest.raises(jg.InvalidParameterError, match="direction"):
        jg.find_events(H3, X3, [lambda X: X[0]] * 2, (0, 1), 0.1, direction=[1])
    with pytest.raises(jg.InvalidParameterError, match="callable"):
        jg.find_events(H3, X3, [], (0, 1), 0.1)
    with pytest.raises(jg.InvalidParameterError, match="direction"):
        jg.find_events(H3, X3, lambda X: X[0], (0, 1), 0.1, direction=2)
