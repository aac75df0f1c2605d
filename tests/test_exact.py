"""ExactFlow: one step is the exact time-dt flow of an integral Hamiltonian (jetgaudin.exact, docs/integrators.md).

Tolerances.  A step is a composition of N - 1 two-point maps and a rotation: its round-off is a few ulps of the
state times the conditioning |ℓ(η)|/|ν(η)| of the maps (docs/backlund.md §5; O(1)-O(10) for our choice of Re η),
so with states of size ~3 one step agrees with the exact flow to ~1e-14.  The references: DOP853 at
rtol = atol = 1e-13 over |T| <= 0.25 (global error a few 1e-14) and heyoka at tol = 1e-16 (Taylor, error at
round-off).  We assert 1e-12 absolute against either (a wrong weight, a sign or a missing rotation gives errors
>= 1e-4 at these dt: see the planted bugs noted in the tests).
"""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.ensemble import sample_on_leaf
from jetgaudin.exact import MatchedBacklund, _weights, rotate_about_field

from conftest import APPENDIX2_X0

X3 = np.array(APPENDIX2_X0)
X2 = np.array([0.3, -0.5, 0.8, 1.0, 0.2, 0.4])
X4 = np.array([0.3, -0.5, 0.8, 0.4, 0.1, -0.3, 0.2, 0.6, 0.1, 0.0, 0.3, 0.9])
STATES = {2: X2, 3: X3, 4: X4}


def _flow(H, X0, T, method="DOP853"):
    if method == "heyoka":
        return jg.integrate(H, X0, T, method="heyoka", rtol=1e-16).X[-1]
    return jg.integrate(H, X0, T, rtol=1e-13, atol=1e-13).X[-1]


@pytest.mark.parametrize("N", [2, 3, 4])
@pytest.mark.parametrize("dt", [1e-3, 0.05, -0.12])
def test_step_is_the_flow_dop853(N, dt):
    """One step of ExactFlow(physical H) equals the DOP853 flow to 1e-12 (module doc), NumPy and compiled routes.
    (Planted: dropping the rotation or the second map gives errors 1e-3..1e-1 here.)"""
    H = jg.physical_hamiltonian(N, 1.0)
    X0 = STATES[N]
    ref = _flow(H, X0, dt)
    for backend in ("numpy", "compiled"):
        X1 = jg.ExactFlow(H, dt, backend=backend)(X0)
        assert np.max(np.abs(X1 - ref)) < 1e-12


@pytest.mark.parametrize("N", [2, 3])
def test_step_is_the_flow_heyoka(N):
    """The second, independent reference: heyoka's Taylor method at tol 1e-16 (1e-12, module doc); also a general
    combination of all the integrals (H_1 and the Casimirs included) and b != 1."""
    pytest.importorskip("heyoka")
    rng = np.random.default_rng(7)
    # a general H weights H_3 like H_2: the two maps must nearly cancel on H_2, so its largest feasible dt is smaller
    # (about 0.017 here; module doc of jetgaudin.exact)
    for H, dts in ((jg.physical_hamiltonian(N, 1.0), (0.02, -0.1)),
                   (jg.IntegralHamiltonian(0.7, rng.uniform(-1, 1, 2 * N)), (0.01, -0.015))):
        for dt in dts:
            X1 = jg.ExactFlow(H, dt)(STATES[N])
            assert np.max(np.abs(X1 - _flow(H, STATES[N], dt, "heyoka"))) < 1e-12
            assert np.max(np.abs(X1 - _flow(H, STATES[N], dt))) < 1e-12


def test_rotation_is_the_H1_flow():
    """rotate_about_field(X, 2 b ω τ) is the time-τ flow of ω H_1 (ẏ_i = 2b e_3 × y_i, eq. (LP)); DOP853 at 1e-13 over
    τ = 0.7 (error ~1e-13; 1e-11 asserted).  (Planted: the opposite sense of rotation fails by ~1.)"""
    b, om, tau = 1.3, 0.4, 0.7
    w = np.zeros(6)
    w[0] = om
    H = jg.IntegralHamiltonian(b, w)
    ref = _flow(H, X3, tau)
    assert np.max(np.abs(rotate_about_field(X3, 2 * b * om * tau) - ref)) < 1e-11
    assert np.max(np.abs(rotate_about_field(X3, -2 * b * om * tau) - ref)) > 0.1


def test_quadrature_matches_adaptive_weights():
    """The 64-point Gauss–Legendre weights equal jg.interpolating_weights (adaptive Gauss–Kronrod, epsrel 1e-13)
    to 1e-12 relative, and ∂ω/∂h (the integrand at the end point) equals a central difference to 1e-7 (h = 1e-5:
    truncation ~1e-10, cancellation ~1e-11 relative)."""
    from jetgaudin.spectral import _roots, curve_coefficients

    kappa = curve_coefficients(X3, 1.0)
    roots = _roots(kappa)
    a, h = np.array([5.2, -5.2]), np.array([0.9, -0.4])
    om, dom = _weights(kappa, roots, a, h)
    for j in range(2):
        ref = jg.interpolating_weights(X3, 1.0, a[j] + 1j * h[j])
        assert np.max(np.abs(om[j] - ref)) <= 1e-12 * np.max(np.abs(ref))
        e = 1e-5
        fd = (_weights(kappa, roots, a, h + e)[0][j] - _weights(kappa, roots, a, h - e)[0][j]) / (2 * e)
        assert np.max(np.abs(fd - dom[j])) <= 1e-7 * np.max(np.abs(dom[j]))
        # the compiled twin (node-by-node continuation of ν) gives the same weights to round-off (1e-14 relative)
        from jetgaudin._exact_kernels import _weights_one
        from jetgaudin.exact import _gauss_legendre

        x, w = _gauss_legendre(64)
        omc, domc, nuc = np.zeros(6), np.zeros(6), np.zeros(1, complex)
        _weights_one(kappa, a[j], h[j], x, w, omc, domc, nuc)
        assert np.max(np.abs(omc - om[j])) <= 1e-14 * np.max(np.abs(om[j]))
        assert np.max(np.abs(domc - dom[j])) <= 1e-14 * np.max(np.abs(dom[j]))
        assert abs(nuc[0] - jg.nu(a[j] + 1j * h[j], X3, 1.0)) <= 1e-14 * abs(nuc[0])


def test_dt_and_minus_dt_invert_each_other():
    """E(−dt) ∘ E(dt) = id to 1e-13 (round-off of 2×2 maps), and inverse() is ExactFlow(H, −dt)."""
    H = jg.physical_hamiltonian(3, 1.0)
    E = jg.ExactFlow(H, 0.2)
    assert E.inverse().dt == -0.2
    back = E.inverse()(E(X3))
    assert np.max(np.abs(back - X3)) < 1e-13
    assert np.max(np.abs(E(X3) - X3)) > 0.1  # the step moves the state


def test_steps_commute_and_compose():
    """E(dt1) ∘ E(dt2) = E(dt2) ∘ E(dt1) = E(dt1 + dt2) to 1e-13 (each is the exact flow)."""
    H = jg.physical_hamiltonian(3, 1.0)
    E1, E2, E12 = jg.ExactFlow(H, 0.07), jg.ExactFlow(H, -0.16), jg.ExactFlow(H, -0.09)
    a, b, c = E1(E2(X3)), E2(E1(X3)), E12(X3)
    assert np.max(np.abs(a - b)) < 1e-13 and np.max(np.abs(a - c)) < 1e-13


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_batch_members_equal_single_runs(backend):
    """Each member of a batch solves its own parameters; it equals its single-orbit run bit for bit."""
    X0 = sample_on_leaf(3, [0.4, -0.3, 1.5], 5, seed=3)
    E = jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), 0.05, backend=backend)
    steps = 4 if backend == "numpy" else 40
    batch = E.iterate(X0, steps, save_every=2)
    for i in range(len(X0)):
        assert np.array_equal(batch[:, i], E.iterate(X0[i], steps, save_every=2))
    p = E.parameters(X0)
    assert len(set(np.round(p.eta[:, 0].imag, 12))) == len(X0)  # the members do have their own parameters


@pytest.mark.parametrize("cls", [jg.ExactFlow, MatchedBacklund])
def test_declared_properties(cls):
    """Every claim of the properties of ExactFlow and of the plain map: integrals preserved (drift over 2000 steps
    <= 1e-12 relative: the maps' round-off), real (float output), symmetric (−dt inverts to 1e-13), Poisson (the
    Jacobian J of one step satisfies J Π(X) Jᵀ = Π(E(X)) to 1e-7: central differences with h = 1e-6, error
    ~h² + ε/h ~ 1e-10 × |X|²)."""
    H = jg.physical_hamiltonian(3, 1.0)
    E = cls(H, 0.1)
    P = E.properties
    assert P.preserves_integrals and P.real and P.poisson and P.symmetric and P.order is None
    assert not P.interpolates_flow
    assert np.max(np.abs(E.inverse()(E(X3)) - X3)) < 1e-13
    orbit = E.iterate(X3, 2000, save_every=100)
    I = jg.integrals(orbit, 1.0)
    assert np.max(np.abs(I - I[0]) / np.maximum(1, np.abs(I[0]))) < 1e-12
    assert orbit.dtype == np.float64
    En = cls(H, 0.1, backend="numpy")
    p = En.parameters(X3)  # fixed parameters: the map of one orbit's leaf (the weights are functions of integrals)
    flat = np.array([p.eta])

    def step(x):
        return rotate_about_field(En._maps_numpy(x[None].copy(), flat), p.theta)[0]

    e = 1e-6
    J = np.stack([(step(X3 + e * np.eye(9)[k]) - step(X3 - e * np.eye(9)[k])) / (2 * e) for k in range(9)], axis=1)
    lhs = J @ jg.poisson_tensor(X3) @ J.T
    assert np.max(np.abs(lhs - jg.poisson_tensor(step(X3)))) < 1e-7


def test_step_too_large_names_the_largest_dt():
    """Beyond the largest feasible dt of a leaf: StepTooLargeError with dt_max; dt_max is feasible, 1.01 dt_max is
    not; substeps makes a long step exact (vs DOP853, 1e-11 over T = 1: ~10 sub-steps' round-off)."""
    H = jg.physical_hamiltonian(3, 1.0)
    with pytest.raises(jg.StepTooLargeError, match="largest feasible time step") as exc:
        jg.ExactFlow(H, 5.0)(X3)
    dmax = exc.value.dt_max
    assert 0.05 < dmax < 5.0
    jg.ExactFlow(H, 0.999 * dmax)(X3)
    with pytest.raises(jg.StepTooLargeError):
        jg.ExactFlow(H, 1.01 * dmax)(X3)
    assert jg.ExactFlow(H, 1.0).max_dt(X3) == pytest.approx(dmax, rel=2e-3)
    s = int(np.ceil(1.0 / dmax))
    X1 = jg.ExactFlow(H, 1.0, substeps=s)(X3)
    assert np.max(np.abs(X1 - _flow(H, X3, 1.0))) < 1e-11


@pytest.mark.parametrize("bad, match", [
    (dict(H=jg.physical_hamiltonian(1, 1.0)), "N >= 2"),
    (dict(dt=0.0), "dt must be nonzero"),
    (dict(H=jg.IntegralHamiltonian([0.0, 1.0, 1.0], np.ones(6))), "field along e_3"),
    (dict(H=jg.IntegralHamiltonian(1.0, np.ones((2, 6)))), "one set of weights"),
    (dict(substeps=0), "substeps"),
    (dict(rho_factor=0.5), "rho_factor"),
])
def test_bad_input_is_refused(bad, match):
    kw = dict(H=jg.physical_hamiltonian(3, 1.0), dt=0.1) | bad
    with pytest.raises(jg.InvalidParameterError, match=match):
        jg.ExactFlow(**kw)


def test_description_round_trip():
    E = jg.ExactFlow(jg.IntegralHamiltonian(0.8, np.arange(6.0) / 10), -0.03, substeps=2, backend="numpy")
    F = jg.map_from_description(E.describe())
    assert F.describe() == E.describe() and np.array_equal(F(X3), E(X3))


def test_run_layer_records_time_and_resumes_bit_for_bit(tmp_path):
    """The run layer records an ExactFlow run with a t column (t = n dt) and resumes it bit for bit after an
    interrupt at a chunk boundary (chunk_invariant = False: fixed chunks)."""
    E = jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), 0.05)
    spec = rl.RunSpec(E, X3, 600, 1, checkpoint_seconds=0.0)
    rl.start(spec, tmp_path / "full")
    full = rl.load(tmp_path / "full")

    def stop(n, _steps):
        if n >= 256:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(rl.RunInterrupted, match="at step 256"):
        rl.start(spec, tmp_path / "cut", progress=stop)
    rl.resume(tmp_path / "cut")
    cut = rl.load(tmp_path / "cut")
    assert np.array_equal(cut.X, full.X) and len(full.X) == 601
    t, rows = rl.read_csv(next((tmp_path / "full").glob("*.csv")))[:2]
    assert np.allclose(np.asarray(t, dtype=float), 0.05 * np.arange(601), rtol=1e-12, atol=0)


@pytest.mark.parametrize("N", [2, 3, 4])
def test_random_states_up_to_the_largest_step(N):
    """Seeded random states and fields (entries standard normal, b in [0.5, 2]): a step of 0.95 dt_max and of
    −0.7 dt_max equals the DOP853 flow (rtol = atol = 1e-13) to 2e-13 relative to max(1, |X|) (measured worst 5e-14
    over 15 states per N: the reference's own error at displacements O(1))."""
    rng = np.random.default_rng(5 + N)
    for _ in range(3):
        X = rng.standard_normal(3 * N)
        H = jg.physical_hamiltonian(N, rng.uniform(0.5, 2))
        dm = float(jg.ExactFlow(H, 1.0).max_dt(X))
        for f in (0.95, -0.7):
            ref = _flow(H, X, f * dm)
            assert np.max(np.abs(jg.ExactFlow(H, f * dm)(X) - ref)) < 2e-13 * max(1.0, np.max(np.abs(X)))
