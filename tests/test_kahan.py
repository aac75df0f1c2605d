"""Kahan's map (issue 34): each declared property tested; what it does not keep, measured."""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.kahan import KahanMap

X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2
X2 = np.array([0.3, -0.5, 0.8, 1.0, 0.2, 0.4])


def test_one_step_solves_kahans_bilinear_equation():
    # the defining relation (X' − X)/h = f̃(X, X') with f̃ the polarisation of f (quadratic part) and the mean
    # of the linear part: f̃(X, Y) = [f((X+Y)/2)·4 − f(X) − f(Y)]/2 for f = Q + B (exact algebra), to 1e-14
    H = jg.physical_hamiltonian(3, 1.0)
    h = 0.1
    Y = KahanMap(H, h, backend="numpy")(X3)
    f = H.vector_field
    polar = 2.0 * f(0.5 * (X3 + Y)) - 0.5 * (f(X3) + f(Y))
    assert np.abs((Y - X3) / h - polar).max() < 1e-13


@pytest.mark.parametrize("H, X0", [(jg.physical_hamiltonian(3, 1.0), X3), (jg.physical_hamiltonian(2, 0.7), X2)])
def test_order_two_and_time_reversible(H, X0):
    # order 2: error at T = 1 against DOP853 (rtol 1e-13) falls by 4 within 10 % when dt halves;
    # Φ_{−h} ∘ Φ_h = id to 1e-14 (round-off of one linear solve)
    ref = jg.integrate(H, X0, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    err = [np.abs(KahanMap(H, h).iterate(X0, round(1 / h))[-1] - ref).max() for h in (0.02, 0.01)]
    assert 3.6 < err[0] / err[1] < 4.4
    m = KahanMap(H, 0.3)
    assert np.abs(m.inverse()(m(X0)) - X0).max() < 1e-14
    assert m.properties.symmetric and m.properties.order == 2 and m.properties.real


def test_compiled_route_equals_numpy_route_and_batches():
    # same arithmetic order per orbit: compiled and NumPy routes within 1e-13 over 200 steps; batch members equal
    # single runs of the compiled route bit for bit
    H = jg.physical_hamiltonian(3, 1.0)
    Xb = np.stack([X3, X3 * 0.9])
    a = KahanMap(H, 0.05, backend="numpy").iterate(Xb, 200)
    b = KahanMap(H, 0.05, backend="compiled").iterate(Xb, 200)
    assert np.abs(a - b).max() < 1e-12
    one = KahanMap(H, 0.05, backend="compiled").iterate(Xb[1], 200)
    assert np.array_equal(one, b[:, 1])
    assert KahanMap(H, 0.05, backend="compiled").has_compiled


def test_linear_integral_kept_quadratic_ones_not():
    # declared: H_1 = 2b y_0^3 (linear) is kept to round-off (1e-13 over 2000 steps); preserves_integrals is False
    # and the energy / Casimirs are indeed not kept (their error is O(h²), > 1e-6 at h = 0.1), bounded over the run
    H = jg.physical_hamiltonian(3, 1.0)
    m = KahanMap(H, 0.1)
    orb = m.iterate(X3, 2000)
    I = m.integrals(orb)
    assert np.abs(I[:, 0] - I[0, 0]).max() < 1e-12
    assert not m.properties.preserves_integrals and not m.properties.poisson
    assert np.abs(I[:, 1] - I[0, 1]).max() > 1e-6
    assert np.isfinite(orb).all()


def test_chain_hamiltonian_and_description_round_trip():
    # a chain (the Clebsch top) through solve(method="kahan"); describe() rebuilds the same map (bit for bit)
    top = jg.clebsch_top(0.6)
    Hc = top.hamiltonian(np.array([0.0, 0.4, 0.0, 0.0, 1.0]))
    X0 = np.array([0.72, 0.24, -0.54, 0.6, 0.0, 0.8])
    tr = jg.solve(Hc, X0, (0.0, 1.0), dt=0.05, method="kahan")
    ref = jg.integrate(Hc, X0, 1.0, rtol=1e-13, atol=1e-13).X[-1]
    assert np.abs(tr.X[-1] - ref).max() < 1e-2  # O(h²) at h = 0.05
    for H, X in [(Hc, X0), (jg.physical_hamiltonian(2, 0.7), X2)]:
        m = KahanMap(H, 0.05)
        m2 = jg.map_from_description(m.describe())
        assert np.array_equal(m2(X), m(X))


def test_bad_input():
    with pytest.raises(jg.InvalidParameterError):
        KahanMap(jg.physical_hamiltonian(2, 1.0), 0.0)
    with pytest.raises(jg.InvalidParameterError):
        KahanMap("not a Hamiltonian", 0.1)
    with pytest.raises(jg.InvalidParameterError, match="fixed-step"):
        jg.solve(jg.physical_hamiltonian(2, 1.0), X2, (0, 1), method="kahan")


def test_parallel_batch_equals_serial_runs():
    # a batch above the parallel threshold: every member equals its single (serial) run bit for bit
    from jetgaudin import kahan

    H = jg.physical_hamiltonian(2, 0.7)
    Xb = X2 * (1 + 0.01 * np.arange(kahan._PARALLEL_ORBITS + 3))[:, None]
    m = KahanMap(H, 0.05, backend="compiled")
    b = m.iterate(Xb, 50)
    for i in (0, len(Xb) - 1):
        assert np.array_equal(b[:, i], m.iterate(Xb[i], 50))


def test_energy_error_is_order_two_and_does_not_drift():
    # docstring claim: the energy oscillates at O(h²) — its largest error over T = 200 falls by 4 (within 15 %)
    # when h halves, and the oscillation in the last tenth of the run equals that in the first (within 5 %: no
    # drift; measured 2.49e-3 vs 2.48e-3 over T = 1000 at h = 0.05)
    H = jg.physical_hamiltonian(3, 1.0)
    spans = []
    for h in (0.05, 0.025):
        orb = KahanMap(H, h).iterate(X3, round(200 / h), save_every=round(0.5 / h))
        e = H(orb) - H(X3)
        spans.append((np.abs(e).max(), np.ptp(e[:40]), np.ptp(e[-40:])))
    assert 3.4 < spans[0][0] / spans[1][0] < 4.6
    for _, first, last in spans:
        assert abs(first - last) < 0.05 * first
