"""The compiled parameter solve of ChainExactFlow (jetgaudin._exact_chain_kernels) against the NumPy route, and the
compiled chain loop against the chain maps' own route (issue 33 item 2)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin._errors import StepTooLargeError
from jetgaudin._exact_chain_kernels import psi_values
from jetgaudin.exact_chain import COMPILED_FAMILIES, _family_constants


def _models():
    rat = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)])
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    trig2 = jg.GaudinModel(0.7, [(-0.4, 2), (0.9, 1)], family="trigonometric", gamma=0.8)
    ell = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.5)
    return {
        "rational": (rat.hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2]),
                     np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])),
        "trigonometric": (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]),
                          np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])),
        "trigonometric, a site of order 2": (trig2.hamiltonian([0.2, 0.1, -0.3, 0.05, 0.4, 0.0, 0.3]),
                                             np.array([0.2, -0.5, 0.3, 0.1, 0.2, -0.1, -0.4, 0.3, 0.5])),
        "Clebsch top (elliptic, one site)": (jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0]),
                                             np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])),
        "elliptic, 3 sites": (ell.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4]),
                              np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])),
    }


@pytest.mark.parametrize("family, kw", [("rational", {}), ("trigonometric", {"gamma": 0.5}),
                                        ("trigonometric", {"gamma": 1.7}), ("elliptic", {"modulus": 0.6}),
                                        ("elliptic", {"modulus": 0.05}), ("elliptic", {"modulus": 0.95})])
def test_the_compiled_basis_is_the_family_s_nu2_basis(family, kw):
    model = jg.GaudinModel(0.0 if family == "elliptic" else 1.0, [(0.0, 2), (1.3, 3)], family=family, **kw)
    rng = np.random.default_rng(5)
    lam = rng.uniform(-1, 3, 40) + 1j * rng.uniform(-2, 2, 40)  # elliptic: across the pole rows Im = ±K' too
    lam = np.concatenate([lam, 2.2 + 1j * np.linspace(-4, 4, 41)])  # a vertical line (the elliptic cache of Re λ)
    got = psi_values(COMPILED_FAMILIES[family], _family_constants(model.family), lam, model.positions.astype(float),
                     np.array(model.orders, dtype=np.int64))
    ref = np.stack([model.family.nu2_basis(m, lam - p) for p, N in model.sites for m in range(1, 2 * N + 1)], -1)
    # the same series (sin, cos, inverse, product; elliptic: the same reductions and addition theorems, the real
    # Jacobi functions by the AGM instead of SciPy's Cephes) in another order of operations: round-off of the
    # largest term, ~1e-15 of |ψ| + 1 (the points are O(1) from the poles); 1e-12 leaves room for the orders 6
    assert np.max(np.abs(got - ref) / (np.abs(ref) + 1)) < 1e-12


@pytest.mark.parametrize("name", list(_models()))
@pytest.mark.parametrize("dt", [0.05, -0.08, 0.01])
def test_compiled_solve_agrees_with_the_numpy_route(name, dt):
    H, x = _models()[name]
    flow = jg.ChainExactFlow(H, dt)
    a = flow._solve(x, dt, compiled=True)
    b = flow._solve(x, dt, compiled=False)
    assert a is not None and b is not None
    # both converge to a Newton step of 1e-13 |h| on the same 64-point rule, summed in another order: the
    # parameters agree to a few 1e-15 (tolerance 1e-12 relative to |η|, ~1e4 ulps)
    assert np.max(np.abs(a[0] - b[0])) <= 1e-12 * np.max(np.abs(b[0]))
    assert abs(a[1] - b[1]) <= 1e-12 * max(1.0, abs(b[1]))
    assert np.max(np.abs(a[2] - b[2])) <= 1e-12 * np.max(np.abs(b[2]))


@pytest.mark.parametrize("name", list(_models()))
def test_compiled_solve_refuses_the_same_steps(name):
    H, x = _models()[name]
    flow = jg.ChainExactFlow(H, 1.0)
    dmax = float(flow.max_dt(x))  # searched up to 10
    assert 0 < dmax < 9.9
    for dt in (0.95 * dmax, 1.05 * dmax, 3 * dmax):
        a = flow._solve(x, dt, compiled=True)
        b = flow._solve(x, dt, compiled=False)
        assert (a is None) == (b is None), dt
    with pytest.raises(StepTooLargeError) as err:
        jg.ChainExactFlow(H, 3 * dmax).advance(x, None, 2)
    # dt_max of the message is the bisection's below the step (feasibility need not be monotone in dt, so it may
    # differ from max_dt's, searched from 10): a feasible step, smaller than the refused one
    d = err.value.dt_max
    assert 0 < d < 3 * dmax and flow._solve(x, 0.999 * d) is not None


def test_a_batch_with_one_infeasible_orbit_names_it():
    H, x = _models()["trigonometric"]
    flow = jg.ChainExactFlow(H, 0.1)
    big = 6.0 * x  # a larger state: larger branch points, a smaller dt_max
    assert float(flow.max_dt(big)) < 0.1 < float(flow.max_dt(x))
    with pytest.raises(StepTooLargeError, match="orbit 1"):
        flow.advance(np.stack([x, big]), None, 3)


@pytest.mark.parametrize("name", list(_models()))
def test_the_exact_step_is_the_flow(name):
    """The compiled solve's maps are the time-dt flow of H: 20 steps against DOP853 at tight tolerances."""
    H, x = _models()[name]
    dt = 0.05
    rows = jg.ChainExactFlow(H, dt).iterate(x, 20)
    ref = jg.solve(H, x, (0.0, 20 * dt), dt=dt, method="dop853", rtol=1e-13, atol=1e-13).X
    # DOP853 at 1e-13 over t = 1: its own error ~1e-12; the exact steps are round-off (~1e-14)
    assert np.max(np.abs(rows[-1] - ref[-1])) < 1e-10


def test_the_compiled_real_jacobi_functions_are_scipy_s():
    from scipy import special

    from jetgaudin._exact_elliptic import sncndn, zeta_real

    rng = np.random.default_rng(2)
    for k in (0.05, 0.6, 0.95):
        m = k * k
        K, E = special.ellipk(m), special.ellipe(m)
        for x in rng.uniform(-K, K, 50):
            s, c, d, ph = special.ellipj(x, m)
            # the AGM (A&S 16.4) against Cephes' AGM: cn = cos(am) near K has absolute accuracy ~1e-15 on both
            assert np.max(np.abs(np.array(sncndn(x, m)) - [s, c, d])) < 5e-14
            # Z = E(am x) − (E/K) x (A&S 17.4) against the AGM sum Σ c_n sin φ_n: ~1e-16 absolute
            assert abs(zeta_real(x, m) - (special.ellipeinc(ph, m) - E / K * x)) < 1e-14


@pytest.mark.parametrize("k", [0.002, 0.05, 0.3, 0.6, 0.95, 0.999])
def test_the_theta_series_of_the_imaginary_parts_are_scipy_s(k):
    from scipy import special

    from jetgaudin._exact_elliptic import _theta_im, elliptic_constants, zeta_real

    ell = elliptic_constants(k)
    m1 = 1.0 - k * k  # the imaginary parts' parameter
    assert ell[7] >= 1  # a theta series (nome q' ≤ 0.6) for every modulus of the compiled route (k ≥ 1e-3)
    K1, E1 = special.ellipk(m1), special.ellipe(m1)
    y = np.linspace(-ell[3] / 2, ell[3] / 2, 201)  # |Im| ≤ K'/2 after the reductions
    got = np.array([_theta_im(v, ell) for v in y])
    s, c, d, ph = special.ellipj(y, m1)
    # truncated where q'^{n²} < 1e-18; the multiples' round-off enters damped by q'^{n(n+1)}: a few ulps of the
    # O(1) values (2e-15 allows ~10 ulps; the largest seen 3.4e-15 at k = 0.002: 5e-15 there)
    tol = 5e-15 if k < 0.01 else 2e-15
    assert np.max(np.abs(got[:, :3] - np.stack([s, c, d], -1))) < tol
    # Z = E(am y) − (E/K) y (A&S 17.4) and the AGM sum; |Z| grows like ln(1/k) as k → 0: 1e-14 absolute there
    z_ref = special.ellipeinc(ph, m1) - E1 / K1 * y
    assert np.max(np.abs(got[:, 3] - z_ref)) < (5e-14 if k < 0.01 else 2e-15 * max(1.0, np.abs(z_ref).max()))
    assert np.max(np.abs(got[:, 3] - np.array([zeta_real(v, m1) for v in y]))) < 5e-14


@pytest.mark.parametrize("name", ["Clebsch top (elliptic, one site)", "elliptic, 3 sites"])
def test_the_compiled_numerical_branch_rule_is_model_nu(name):
    H, x = _models()[name]
    flow = jg.ChainExactFlow(H, 0.2)
    eta, _, nu = flow._solve(x, 0.2, compiled=True)
    ref = np.asarray(H.model.nu(x, eta))
    # both continue ±√ν² over 65 equally spaced points; ν² summed in another order: round-off (1e-12 relative)
    assert np.max(np.abs(nu - ref) / np.abs(ref)) < 1e-12
    assert flow._branch_numerical(x, eta, nu)
    assert not flow._branch_numerical(x, eta, -nu)  # the other sheet is refused


@pytest.mark.parametrize("name", ["rational", "trigonometric", "trigonometric, a site of order 2"])
def test_the_branch_check_takes_model_nu_s_rule(name):
    """The solve computes the branch points once and checks ν(η_j) by the rule with them: it must be model.nu's
    (the trigonometric rule takes the roots in z = e^{2iγλ}, not in λ: with the λ-roots ~20 % of the signs differ)."""
    from jetgaudin.exact_chain import _branch_ok, _orbit_roots

    H, x0 = _models()[name]
    model = H.model
    rng = np.random.default_rng(11)
    for _ in range(20):
        x = x0 + 0.5 * rng.standard_normal(x0.size)
        eta = rng.uniform(-2, 5, 4) + 1j * rng.uniform(-2, 2, 4)
        raw, bp = _orbit_roots(model, x)
        assert np.allclose(np.sort_complex(bp), np.sort_complex(np.ravel(model.branch_points(x))), atol=1e-12)
        try:
            ref = np.asarray(model.nu(x, eta))
        except jg.JetGaudinError:  # a branch point on a segment: no rule to compare
            continue
        assert _branch_ok(model, x, eta, ref, raw)
        flipped = ref * np.where(np.arange(4) == rng.integers(4), -1, 1)
        assert not _branch_ok(model, x, eta, flipped, raw)


def test_the_recorded_integrals_are_jg_integrals_bit_for_bit():
    """jg.solve records the integrals of every row of a top by one compiled pass (exact.record_integrals): the same
    bits as jg.integrals (the same sums in the same order), and its checks where it cannot."""
    from jetgaudin.exact import record_integrals

    rng = np.random.default_rng(4)
    for N in (2, 3, 5):
        H = jg.physical_hamiltonian(N, 1.3)
        for shape in ((7, 3 * N), (4, 3, 3 * N), (3 * N,)):
            X = rng.standard_normal(shape) * 10.0 ** rng.uniform(-3, 3, shape)
            assert np.array_equal(record_integrals(H, X), np.asarray(jg.integrals(X, 1.3)))
    H = jg.physical_hamiltonian(3, 1.0)
    with np.errstate(over="ignore"), pytest.raises(jg.JetGaudinError, match="overflow"):  # the NumPy route's
        record_integrals(H, np.full((2, 9), 1e200))  # refusal, not a silent inf
    tr = jg.solve(H, [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0], (0.0, 2.0), dt=0.1)
    assert np.array_equal(tr.integrals, np.asarray(jg.integrals(tr.X, 1.0)))


@pytest.mark.parametrize("name", ["trigonometric", "trigonometric, a site of order 2"])
def test_the_compiled_uniformized_branch_rule_is_model_nu(name):
    from jetgaudin._exact_chain_kernels import branch_uniformized
    from jetgaudin.exact_chain import _branch_ok, _orbit_roots

    H, x0 = _models()[name]
    model = H.model
    rng = np.random.default_rng(11)
    P = float(model.family.period)
    flips = 0
    for trial in range(6):
        x = x0 if trial == 0 else x0 + 0.3 * rng.standard_normal(x0.shape)
        raw, _ = _orbit_roots(model, x)
        I = np.asarray(model.integrals(x), dtype=float)
        const = float(np.real(model.family.nu2_constant(float(model.b), I[2 * model.M:])))
        args = (1, _family_constants(model.family), model.positions.astype(float),
                np.array(model.orders, dtype=np.int64), np.ascontiguousarray(I[:2 * model.M]), const, P)
        # points over a period and both half planes (not only the solve's η: there ν is mostly the principal root)
        etas = rng.uniform(0, P, 40) + 1j * rng.uniform(-1.5, 1.5, 40)
        for e in etas:
            try:
                nu = complex(np.asarray(model.nu(x, np.array([e])))[0])
            except jg.BranchPointError:
                continue
            flips += (nu / np.sqrt(nu * nu)).real < 0  # the rule's ν is minus the principal root
            one = np.array([e])
            # both decide the sign of ±√ν²(η) by the same root product; ν² by the expansion against the Lax
            # vector (round-off ~1e-15 relative): the decisions agree, tol 1e-8 is the solve's own
            assert branch_uniformized(*args, one, np.array([nu]), raw.astype(complex), 1e-8)
            assert not branch_uniformized(*args, one, np.array([-nu]), raw.astype(complex), 1e-8)
            assert _branch_ok(model, x, one, np.array([nu]), raw)
    assert flips >= 20  # the sign is not the principal root's at many points: the test sees the rule's choice
    # the solve's own η on the benchmark state, through the flow
    flow = jg.ChainExactFlow(H, 0.05)
    eta, _, nu_end = flow._solve(x0, 0.05, compiled=False)
    raw, _ = _orbit_roots(model, x0)
    I = np.asarray(model.integrals(x0), dtype=float)
    const = float(np.real(model.family.nu2_constant(float(model.b), I[2 * model.M:])))
    args = (1, _family_constants(model.family), model.positions.astype(float), np.array(model.orders, dtype=np.int64),
            np.ascontiguousarray(I[:2 * model.M]), const, P, eta.astype(complex))
    assert branch_uniformized(*args, nu_end.astype(complex), raw.astype(complex), 1e-8)
    assert not branch_uniformized(*args, np.array([nu_end[0], -nu_end[1]]), raw.astype(complex), 1e-8)


def test_the_backend_picks_the_solve_and_the_stepping_route():
    from jetgaudin.maps import Backend

    H, x = _models()["Clebsch top (elliptic, one site)"]
    dt = 0.05
    auto, comp = jg.ChainExactFlow(H, dt), jg.ChainExactFlow(H, dt, backend="compiled")
    nump, alias = jg.ChainExactFlow(H, dt, backend="numpy"), jg.ChainExactFlow(H, dt, kernel="numpy")
    assert (auto.backend, comp.backend, nump.backend, alias.backend) == (Backend.AUTO, Backend.COMPILED,
                                                                          Backend.NUMPY, Backend.NUMPY)
    assert alias.kernel is None and nump.inverse().backend is Backend.NUMPY
    from jetgaudin.maps import map_from_description

    assert map_from_description(nump.describe()).backend is Backend.NUMPY  # a saved run keeps its route
    old = {k: v for k, v in auto.describe().items() if k != "backend"}  # a description from before the option
    assert map_from_description(old).backend is Backend.AUTO
    # each route's parameters are bit for bit its own solve's (the two differ by ~1e-15: another order of sums)
    for flow, compiled in ((auto, True), (comp, True), (nump, False)):
        eta, theta = flow.parameters(x)
        ref = flow._solve(x, dt, compiled=compiled)
        assert ref is not None and np.array_equal(eta, ref[0]) and theta == ref[1]
    from jetgaudin.exact import rotate_about_field

    a = np.asarray(comp.iterate(x, 6))
    b = np.asarray(nump.iterate(x, 6))
    # the NumPy maps and solve against the compiled ones: round-off of 6 steps (1e-12, as the routes' own tests)
    assert np.max(np.abs(a - b)) < 1e-12
    # backend="numpy" steps on the maps' NumPy route: its rows are those of that route, bit for bit, and not the
    # compiled loop's (which differ at round-off)
    eta, theta = nump.parameters(x)
    maps = [H.model.two_point_backlund(e).with_backend("numpy") for e in eta]
    z, rows = x, []
    for i in range(6):
        for mp in maps:
            z = mp.advance(z, None, 1, 1).X
        rows.append(rotate_about_field(z, (i + 1) * theta))
    assert np.array_equal(b[-6:], np.array(rows)) and not np.array_equal(a[-6:], b[-6:])


def test_the_backend_refuses_what_it_cannot_run():
    H, _ = _models()["Clebsch top (elliptic, one site)"]
    with pytest.raises(jg.InvalidParameterError, match="GPU"):
        jg.ChainExactFlow(H, 0.05, backend="gpu")
    with pytest.raises(jg.InvalidParameterError):
        jg.ChainExactFlow(H, 0.05, backend="fortran")
    tiny = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1)], family="elliptic", modulus=1e-4)
    with pytest.raises(jg.InvalidParameterError, match="modulus"):
        jg.ChainExactFlow(tiny.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3]), 0.05, backend="compiled")


@pytest.mark.parametrize("name", ["trigonometric", "trigonometric, a site of order 2"])
def test_the_compiled_trigonometric_branch_points_are_the_model_s(name):
    from jetgaudin.exact_chain import _orbit_roots, _trig_roots

    H, x0 = _models()[name]
    model = H.model
    rng = np.random.default_rng(4)
    for trial in range(20):
        x = x0 if trial == 0 else rng.standard_normal(x0.shape) * rng.uniform(0.2, 2.0)
        I = np.asarray(model.integrals(x), dtype=float)
        const = float(np.real(model.family.nu2_constant(float(model.b), I[2 * model.M:])))
        raw, bp = _trig_roots(model, np.ascontiguousarray(I[:2 * model.M]), const, model.positions.astype(float),
                              np.array(model.orders, dtype=np.int64))
        raw0, bp0 = _orbit_roots(model, x)
        # the same samples, DFT and companion matrix; ν² by the expansion instead of the Lax vector (round-off of
        # the samples, ~1e-15 relative): simple roots agree to ~1e-13 of the largest (tolerance 1e-10, room for
        # the conditioning of nearby roots); matched as sets (the eigenvalue order may differ)
        d = np.abs(raw[:, None] - raw0[None, :])
        assert np.max(np.min(d, axis=1)) < 1e-10 * np.max(np.abs(raw0))
        assert np.max(np.min(d, axis=0)) < 1e-10 * np.max(np.abs(raw0))
        assert np.max(np.min(np.abs(bp[:, None] - bp0[None, :]), axis=1)) < 1e-9


@pytest.mark.parametrize("name", list(_models()))
def test_the_coarse_rule_only_starts_newton_on_the_fine_rule(name):
    from jetgaudin import _exact_chain_kernels as K
    from jetgaudin.exact_chain import _COARSE_TOL, _ITERATIONS, _STEP_TOL, _orbit_roots, _rules, _static

    H, x = _models()[name]
    flow = jg.ChainExactFlow(H, 0.05)
    model, fam = H.model, H.model.family
    keep, E, _, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(flow)
    I = np.asarray(model.integrals(x), dtype=float)
    hI = np.ascontiguousarray(I[:2 * model.M])
    const = float(np.real(fam.nu2_constant(float(model.b), I[2 * model.M:])))
    dconst = np.ascontiguousarray(fam.nu2_constant_gradient(float(model.b), I[2 * model.M:]), dtype=float)
    rho = flow._real_parts(x, k, _orbit_roots(model, x)[1])
    bound = np.minimum(2 * np.abs(rho - lc) + (P or 0.0), 0.9 * Kp)
    rules = _rules()
    out = []
    no = (rules[6][:0], rules[7][:0], rules[8][:0])
    for coarse in (rules[6:], rules[6:9] + no, no + no):  # with both coarse phases, the 16-point one only, neither
        u, om, nu = np.empty(E.shape[0]), np.empty((k, E.shape[0])), np.empty(k, dtype=complex)
        status, quad, _ = K.newton(COMPILED_FAMILIES[fam.name], _family_constants(fam), pos, orders, hI, const, dconst,
                                kidx, E, 0.05 * wkeep, rho, bound, *rules[:6], *coarse, _STEP_TOL, _COARSE_TOL,
                                _ITERATIONS, u, om, nu)
        assert status == 0
        out.append((u.copy(), om.copy(), quad))
    # all end with Newton on the 64-point rule to a step of 1e-13 |u|: the same solution to round-off (1e-13
    # relative, the step tolerance), the same weights and quadrature estimate (1e-12 of their scale)
    for a in out[:2]:
        assert np.max(np.abs(a[0] - out[2][0]) / np.abs(out[2][0])) < 1e-13
        assert np.max(np.abs(a[1] - out[2][1])) < 1e-12 * np.abs(out[2][1]).max()
        assert abs(a[2] - out[2][2]) < 1e-12
