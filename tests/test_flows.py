"""Tests of jetgaudin.flows: integrate() with DOP853 and heyoka, Trajectory, conservation of the integrals."""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.flows import Trajectory, _fast_rhs

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

T_LONG = 1000.0
T_EVAL = np.linspace(0.0, T_LONG, 101)


@pytest.fixture(scope="module")
def long_runs():
    """The N = 3 top (H = H_2/2, b = 1) from the Appendix 2 data over t = 1000 with both backends.

    Measured (this machine): DOP853 ~3 s (22068 steps), heyoka ~0.4 s (9586 steps)."""
    H = jg.physical_hamiltonian(3, APPENDIX2_B)
    return {m: jg.integrate(H, APPENDIX2_X0, T_LONG, t_eval=T_EVAL, method=m) for m in ("DOP853", "heyoka")}


@pytest.mark.parametrize("method", ["DOP853", "heyoka"])
def test_six_integrals_conserved_over_t1000(long_runs, method):
    """Drift of (H_1, H_2, H_3, C_1, C_2, C_3), relative to max(1, |I(0)|), at rtol = atol = 1e-12.

    Bound asserted for DOP853: 2e-8 = (number of steps ~2e4) x (tolerance 1e-12), the worst case of a linear
    accumulation of local errors (measured max 5.3e-10, H_3).  For heyoka (Taylor, ~1e4 steps each with an error
    below 1e-12 of either sign): 1e-9, ten times the random-walk estimate sqrt(1e4) x 1e-12 = 1e-10 (measured
    1.6e-11); DOP853's drift would fail it."""
    tr = long_runs[method]
    assert tr.X.shape == (len(T_EVAL), 9) and tr.integrals.shape == (len(T_EVAL), 6)
    assert np.array_equal(tr.t, T_EVAL)
    assert np.all(tr.drift <= {"DOP853": 2e-8, "heyoka": 1e-9}[method]), tr.drift
    # H_1 = 2 b y^3: y^3' = (b ^ x)^3 = 0 identically (b = e_3), so only rounding can move it
    assert tr.drift[0] <= 1e-14
    # the orbit is non-trivial: the state moves by O(1)
    assert np.max(np.abs(tr.X - APPENDIX2_X0)) > 0.5


def test_backends_agree(long_runs):
    """The two backends follow the same orbit: each one's global error grows ~linearly, <= steps x tol ~ 2e-8
    per unit state size; the state is O(3): assert 1e-6 (measured 2.8e-8 at t = 1000)."""
    a, b = long_runs["DOP853"], long_runs["heyoka"]
    assert np.max(np.abs(a.X - b.X)) <= 1e-6
    assert np.max(np.abs(a.X[:11] - b.X[:11])) <= 1e-7  # t <= 100: errors ~10x smaller


def test_short_run_both_backends_and_em():
    """t = 5: the trajectory satisfies (em) (finite differences of the samples vs twisted_top_rhs)."""
    H = jg.physical_hamiltonian(3, APPENDIX2_B)
    t = np.linspace(0, 5, 501)
    for method in ("DOP853", "heyoka"):
        tr = jg.integrate(H, APPENDIX2_X0, 5.0, t_eval=t, method=method)
        dt = t[1] - t[0]
        Xs = tr.X
        fd = (-Xs[4:] + 8 * Xs[3:-1] - 8 * Xs[1:-3] + Xs[:-4]) / (12 * dt)
        rhs = jg.systems.twisted_top_rhs(Xs[2:-2], APPENDIX2_B)
        # five-point stencil: error dt^4 |X^(5)| / 30 with dt = 0.01; the 3-point stencil measured
        # dt^2 |X'''| / 6 ~ 3.5e-3, i.e. |X'''| ~ 200, so |X^(5)| ~ 1e4 and the error ~ 3e-5 at most
        # (measured 2.8e-6)
        assert np.max(np.abs(fd - rhs)) <= 1e-4
        assert tr.method == method


def test_fast_rhs_equals_vector_field(rng):
    """The DOP853 kernel (affine gradient + c.X) equals IntegralHamiltonian.vector_field (generic route)."""
    for N in range(1, 6):
        X = rng.normal(size=(3, 3 * N))
        for c in (None, rng.uniform(-1, 1, size=N - 1)):
            H = jg.IntegralHamiltonian(rng.normal(size=3), rng.normal(size=2 * N), c)
            rhs = _fast_rhs(H, X)
            # both are sums of O(N^2) products: rounding ~1e-15 relative to the size of the terms
            ref = H.vector_field(X)
            assert np.allclose(rhs(0.0, X.reshape(-1)).reshape(X.shape), ref, rtol=0,
                               atol=1e-12 * (1 + np.max(np.abs(ref))))
    W = rng.normal(size=(3, 6))
    X = rng.normal(size=(3, 9))
    H = jg.IntegralHamiltonian(1.0, W)
    assert np.allclose(_fast_rhs(H, X)(0.0, X.reshape(-1)).reshape(3, 9), H.vector_field(X), rtol=0, atol=1e-12)


def test_backward_integration_returns():
    H = jg.physical_hamiltonian(3, APPENDIX2_B)
    for method in ("DOP853", "heyoka"):
        fwd = jg.integrate(H, APPENDIX2_X0, 3.0, method=method)
        back = jg.integrate(H, fwd.X[-1], -3.0, method=method)
        # two runs of ~100 steps at tol 1e-12: error ~1e-10; assert 1e-9
        assert np.max(np.abs(back.X[-1] - APPENDIX2_X0)) <= 1e-9


def test_t_eval_variants():
    H = jg.physical_hamiltonian(3, APPENDIX2_B)
    ref = jg.integrate(H, APPENDIX2_X0, 2.0, t_eval=[0.0, 0.5, 2.0], method="heyoka")
    late = jg.integrate(H, APPENDIX2_X0, 2.0, t_eval=[0.5, 2.0], method="heyoka")  # grid not starting at 0
    assert np.array_equal(late.t, [0.5, 2.0])
    assert np.allclose(late.X, ref.X[1:], rtol=0, atol=1e-12)
    d = jg.integrate(H, APPENDIX2_X0, 2.0, t_eval=[0.5, 2.0])
    assert np.allclose(d.X, ref.X[1:], rtol=0, atol=1e-9)
    zero = jg.integrate(H, APPENDIX2_X0, 0.0)
    assert np.array_equal(zero.X, APPENDIX2_X0[None]) and np.all(zero.drift == 0)


def test_batch_dop853_matches_single_runs(rng):
    """A batch (..., 3N) is integrated as one system: members agree with single runs to the tolerance."""
    X0 = APPENDIX2_X0 + 0.1 * rng.normal(size=(3, 9))
    H = jg.physical_hamiltonian(3, APPENDIX2_B)
    batch = jg.integrate(H, X0, 2.0)
    for i in range(3):
        single = jg.integrate(H, X0[i], 2.0)
        assert np.allclose(batch.X[:, i], single.X, rtol=0, atol=1e-9)


def test_trajectory_drift_definition(rng):
    """drift_k = max_t |I_k(t) - I_k(0)| / max(1, |I_k(0)|), written out independently."""
    I = rng.normal(size=(7, 6)) * np.array([1e-3, 1, 10, 100, 0.5, 3])
    tr = Trajectory(t=np.arange(7.0), X=np.zeros((7, 9)), integrals=I, method="none")
    ref = [max(abs(I[t, k] - I[0, k]) for t in range(7)) / max(1.0, abs(I[0, k])) for k in range(6)]
    assert np.allclose(tr.drift, ref, rtol=1e-15, atol=0)
    real = jg.integrate(jg.physical_hamiltonian(3, 1.0), APPENDIX2_X0, 1.0, t_eval=np.linspace(0, 1, 5))
    assert np.array_equal(real.integrals, jg.integrals(real.X, 1.0))


def test_flow_of_interpolating_hamiltonian_conserves_integrals():
    Hq = jg.interpolating_flow_hamiltonian(APPENDIX2_X0, APPENDIX2_B, APPENDIX2_ETA)
    for method in ("DOP853", "heyoka"):
        tr = jg.integrate(Hq, APPENDIX2_X0, 1.0, t_eval=np.linspace(0, 1, 11), method=method)
        assert np.all(tr.drift <= 1e-11)  # ~100 steps at tol 1e-12


def test_generic_vector_field_object():
    """Any object with vector_field(X) and b works with DOP853 (e.g. a GaudinTop)."""
    top = jg.generalized_lagrange_top(APPENDIX2_B)
    a = jg.integrate(top, APPENDIX2_X0, 1.0)
    b = jg.integrate(top.hamiltonian, APPENDIX2_X0, 1.0)
    assert np.allclose(a.X, b.X, rtol=0, atol=1e-10)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"T": np.nan}, jg.InvalidParameterError, "T must be finite"),
        ({"T": "x"}, jg.InvalidParameterError, "T must be a real number"),
        ({"t_eval": [0.0, 2.0]}, jg.InvalidParameterError, "between 0 and T"),
        ({"t_eval": [-0.1, 0.5]}, jg.InvalidParameterError, "between 0 and T"),
        ({"t_eval": [0.0, 0.7, 0.3]}, jg.InvalidParameterError, "monotone"),
        ({"t_eval": [0.0, 0.5, 0.5]}, jg.InvalidParameterError, "monotone"),
        ({"t_eval": [[0.0, 1.0]]}, jg.InvalidParameterError, "1-D"),
        ({"t_eval": []}, jg.InvalidParameterError, "non-empty"),
        ({"t_eval": [0.0, np.nan]}, jg.InvalidParameterError, "finite"),
        ({"T": -1.0, "t_eval": [0.0, 0.5]}, jg.InvalidParameterError, "between 0 and T"),
        ({"T": 0.0, "t_eval": [0.0, 1.0]}, jg.InvalidParameterError, "T = 0"),
        ({"method": "RK45"}, jg.InvalidParameterError, "method must be"),
        ({"rtol": 0.0}, jg.InvalidParameterError, "rtol"),
        ({"rtol": "a"}, jg.InvalidParameterError, "rtol must be a real number"),
        ({"atol": -1.0}, jg.InvalidParameterError, "atol"),
    ],
)
@pytest.mark.parametrize("method", ["DOP853", "heyoka"])
def test_integrate_bad_input(kwargs, exc, match, method):
    kw = {"T": 1.0, "method": method} | kwargs
    T = kw.pop("T")
    with pytest.raises(exc, match=match):
        jg.integrate(jg.physical_hamiltonian(3, 1.0), APPENDIX2_X0, T, **kw)


def test_integrate_bad_state_and_hamiltonian():
    H = jg.physical_hamiltonian(3, 1.0)
    with pytest.raises(jg.InvalidStateError, match="N = 3"):
        jg.integrate(H, APPENDIX2_X0[:6], 1.0)
    with pytest.raises(jg.InvalidStateError, match="non-finite"):
        jg.integrate(H, np.r_[APPENDIX2_X0[:8], np.inf], 1.0)
    with pytest.raises(jg.InvalidStateError, match="multiple of 3"):
        jg.integrate(H, APPENDIX2_X0[:8], 1.0)
    with pytest.raises(jg.InvalidParameterError, match="vector_field"):
        jg.integrate(object(), APPENDIX2_X0, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="one orbit"):
        jg.integrate(H, np.stack([APPENDIX2_X0] * 2), 1.0, method="heyoka")


@pytest.mark.parametrize("T", [1e300, -1e300, 2e9])
def test_huge_integration_time_is_refused_at_once(T):
    """Issue 11, item 8: ``integrate(H, X0, 1e300)`` ran without end; now refused before integrating."""
    from jetgaudin.flows import MAX_INTEGRATION_TIME

    assert abs(T) > MAX_INTEGRATION_TIME
    H = jg.physical_hamiltonian(3, 1.0)
    with pytest.raises(jg.InvalidParameterError, match="too long for one call"):  # before it ran without end
        jg.integrate(H, np.array(APPENDIX2_X0), T)
