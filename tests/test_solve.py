"""jg.solve (one entry point), the implicit midpoint rule, the Trajectory object and event location.

Tolerances are stated at each assert; the references are DOP853 at rtol = atol = 1e-13 (global error ~1e-12 over
T <= 20 for these O(1) orbits).
"""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.exact import MatchedBacklund
from jetgaudin.flows import _fast_rhs
from jetgaudin.midpoint import ImplicitMidpoint

from conftest import APPENDIX2_X0

X3 = np.array(APPENDIX2_X0)
X2 = np.array([0.3, -0.5, 0.8, 1.0, 0.2, 0.4])
H3 = jg.physical_hamiltonian(3, 1.0)
H2 = jg.physical_hamiltonian(2, 1.0)


def _ref(H, X0, T):
    return jg.integrate(H, X0, T, rtol=1e-13, atol=1e-13).X[-1]


@pytest.mark.parametrize("method", ["exact", "bt", "dop853", "heyoka", "midpoint"])
def test_every_method_returns_a_trajectory_on_the_grid(method, tmp_path):
    """Same Trajectory for every method: the grid t0 + k dt (ending at t1), the integrals and their drift, HDF5
    round trip bit for bit; the exact flow ends at the reference to 1e-11 over T = 2 (some hundred steps' round-off)."""
    if method == "heyoka":
        pytest.importorskip("heyoka")
    tr = jg.solve(H3, X3, (1.0, 3.0), dt=0.1, method=method, save_every=5)
    assert np.allclose(tr.t, 1.0 + 0.5 * np.arange(5), rtol=0, atol=1e-14)
    assert tr.X.shape == (5, 9) and tr.integrals.shape == (5, 6) and tr.drift.shape == (6,)
    if method in ("exact", "dop853", "heyoka"):
        assert np.max(np.abs(tr.X[-1] - _ref(H3, X3, 2.0))) < 1e-11
    tr.to_hdf5(tmp_path / "t.h5")
    back = jg.Trajectory.from_hdf5(tmp_path / "t.h5")
    assert np.array_equal(back.X, tr.X) and np.array_equal(back.t, tr.t) and back.info == tr.info


def test_to_xarray_is_optional():
    tr = jg.solve(H2, X2, (0.0, 0.2), dt=0.1)
    try:
        import xarray  # noqa: F401
    except ImportError:
        with pytest.raises(jg.InvalidParameterError, match="xarray"):
            tr.to_xarray()
    else:
        ds = tr.to_xarray()
        assert np.array_equal(ds["X"].values, tr.X)


def test_solve_substeps_are_recorded_and_exact():
    """A dt beyond the leaf's largest step: solve splits it into exact sub-steps and says so in info; with
    substeps=1 the StepTooLargeError reaches the caller.  End state vs DOP853: 1e-11 (T = 3)."""
    tr = jg.solve(H3, X3, (0.0, 3.0), dt=1.0)
    assert tr.info["substeps"] > 1 and tr.info["dt"] == 1.0
    assert np.max(np.abs(tr.X[-1] - _ref(H3, X3, 3.0))) < 1e-11
    with pytest.raises(jg.StepTooLargeError):
        jg.solve(H3, X3, (0.0, 3.0), dt=1.0, substeps=1)


def test_bt_is_exact_for_N2_and_a_modified_flow_for_N3():
    """The plain map (one map per step): exact for N = 2 (1e-12 vs DOP853, T = 1); for N = 3 its unmatched H_3 weight
    moves it O(0.1) away from the flow of H over T = 5 while it still keeps the integrals (1e-13)."""
    tr2 = jg.solve(H2, X2, (0.0, 1.0), dt=0.1, method="bt")
    assert np.max(np.abs(tr2.X[-1] - _ref(H2, X2, 1.0))) < 1e-12
    tr3 = jg.solve(H3, X3, (0.0, 5.0), dt=0.1, method="bt")
    assert np.max(np.abs(tr3.X[-1] - _ref(H3, X3, 5.0))) > 1e-2
    assert tr3.drift.max() < 1e-13
    assert MatchedBacklund(H3, 0.1).parameters(X3).eta.shape == (1,)


def test_midpoint_declared_properties():
    """ImplicitMidpoint: order 2 (error ratio 4 ± 0.2 per halving of dt at T = 1), symmetric (−dt inverts it to
    1e-13), preserves every integral (quadratic: Cooper's theorem) to 1e-13 over 200 steps, real; not Poisson
    (declared False: the Poisson defect at one step is not at round-off, > 1e-8)."""
    m = ImplicitMidpoint(H3, 0.05)
    P = m.properties
    assert P.order == 2 and P.symmetric and P.preserves_integrals and P.real and not P.poisson
    ref = _ref(H3, X3, 1.0)
    errs = [np.max(np.abs(jg.solve(H3, X3, (0, 1), dt=h, method="midpoint").X[-1] - ref)) for h in (0.1, 0.05, 0.025)]
    for e1, e2 in zip(errs, errs[1:], strict=False):
        assert 3.8 < e1 / e2 < 4.2
    assert np.max(np.abs(m.inverse()(m(X3)) - X3)) < 1e-13
    orbit = m.iterate(X3, 200)
    I = jg.integrals(orbit, 1.0)
    assert np.max(np.abs(I - I[0]) / np.maximum(1, np.abs(I[0]))) < 1e-13
    e = 1e-6
    J = np.stack([(m(X3 + e * np.eye(9)[k]) - m(X3 - e * np.eye(9)[k])) / (2 * e) for k in range(9)], axis=1)
    defect = np.max(np.abs(J @ jg.poisson_tensor(X3) @ J.T - jg.poisson_tensor(m(X3))))
    assert defect > 1e-8
    assert jg.map_from_description(m.describe()).describe() == m.describe()


def test_events_agree_with_a_dense_output_integrator():
    """Crossing times of y_0^1 = 0 (both directions) over T = 20 agree with solve_ivp's DOP853 event location at
    rtol = atol = 1e-13 to 1e-10 (its dense output interpolates within its tolerance; our trials are exact states);
    g vanishes at the located states to 1e-12."""
    from scipy.integrate import solve_ivp

    def g(X):
        return X[0] - 0.5

    ev = jg.find_events(H3, X3, g, (0.0, 20.0), 0.2)
    e = lambda t, y: y[0] - 0.5  # noqa: E731
    sol = solve_ivp(_fast_rhs(H3, X3), (0, 20), X3, method="DOP853", rtol=1e-13, atol=1e-13, events=e)
    assert len(ev.t) == len(sol.t_events[0]) >= 2
    assert np.max(np.abs(ev.t - sol.t_events[0])) < 1e-10
    assert np.max(np.abs(ev.X[:, 0] - 0.5)) < 1e-12
    up = jg.poincare_section(H3, X3, g, (0.0, 20.0), 0.2)
    assert np.array_equal(up.t, ev.t[ev.direction == 1])


def test_solve_and_events_refuse_bad_input():
    with pytest.raises(jg.InvalidParameterError, match="method"):
        jg.solve(H3, X3, (0, 1), dt=0.1, method="rk4")
    with pytest.raises(jg.InvalidParameterError, match="give dt"):
        jg.solve(H3, X3, (0, 1), method="exact")
    with pytest.raises(jg.InvalidParameterError, match="t1 != t0"):
        jg.solve(H3, X3, (1, 1), dt=0.1)
    with pytest.raises(jg.InvalidParameterError, match="one finite number"):
        jg.find_events(H3, X3, lambda X: X, (0, 1), 0.1)
    with pytest.raises(jg.InvalidParameterError, match="direction"):
        jg.poincare_section(H3, X3, lambda X: X[0], (0, 1), 0.1, direction=0)


def _cli(capsys, *args):
    from jetgaudin.cli import main

    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out = capsys.readouterr()
    return (0 if exc.value.code is None else exc.value.code), out.out, out.err


def test_cli_flow_method_exact(capsys, tmp_path):
    """`jetgaudin flow --hamiltonian physical --method exact --dt H`: flow.csv has the t column t = n dt and the rows
    of ExactFlow (1e-12 vs DOP853 at t = 1: ten exact steps); a dt beyond the leaf's largest step is one line on
    stderr naming --dt and the largest feasible dt, exit 2; --substeps makes it run."""
    from jetgaudin import run as rl

    code, _, err = _cli(capsys, "flow", "--hamiltonian", "physical", "--method", "exact", "--dt", "0.1", "--steps",
                        10, "--no-plots", "--out", tmp_path / "a")
    assert code == 0, err
    t, X = rl.read_csv(tmp_path / "a" / "flow.csv")
    assert np.allclose(t, 0.1 * np.arange(11), rtol=1e-15, atol=0)
    assert np.max(np.abs(X[-1] - _ref(H3, X3, 1.0))) < 1e-12
    code, _, err = _cli(capsys, "flow", "--hamiltonian", "physical", "--method", "exact", "--dt", "2", "--steps", 2,
                        "--no-plots", "--out", tmp_path / "b")
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert "--dt" in err and "largest feasible time step" in err
    code, _, err = _cli(capsys, "flow", "--hamiltonian", "physical", "--method", "exact", "--dt", "2", "--steps", 2,
                        "--substeps", 10, "--no-plots", "--out", tmp_path / "c")
    assert code == 0, err
    code, _, err = _cli(capsys, "flow", "--hamiltonian", "physical", "--method", "midpoint", "--dt", "0.1",
                        "--steps", 3, "--no-plots", "--out", tmp_path / "d")
    assert code == 0, err
