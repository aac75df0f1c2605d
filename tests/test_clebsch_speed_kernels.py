"""The Clebsch top's faster exact step (issue 33 item 2, this round): the compiled small linear algebra of Newton's
method (the condition number by one-sided Jacobi, the solve by elimination) against LAPACK, the fused elliptic solve
(Newton, residual, branch check in one call) against the same steps taken one by one, and the orbit's integrals by
the compiled forms against ``model.integrals``."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import _exact_chain_kernels as K
from jetgaudin._exact_chain_prep import _integrals_row, _static


def _with_singular_values(rng, n, sv):
    """``U diag(sv) Vᵀ`` with random orthogonal ``U, V`` (QR of Gaussian matrices)."""
    U, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return (U * sv) @ V.T


@pytest.mark.parametrize("n", [2, 3, 4, 6])
def test_the_condition_test_is_lapack_s(n):
    rng = np.random.default_rng(n)
    U = np.empty((n, n))
    for _ in range(200):
        # condition numbers 1 … 1e16 (log-uniform) away from the limit 1e12 by at least 2 % (both SVDs resolve
        # σ_min to ~ε σ_max, i.e. the condition number to ~1e-4 relative at 1e12: the decision is the same outside
        # that band; 2 % leaves a margin of 200×)
        c = 10.0 ** rng.uniform(0, 16)
        if abs(np.log(c / 1e12)) < 0.02:
            continue
        sv = np.sort(np.exp(rng.uniform(0, np.log(c), n)))[::-1]
        sv[0], sv[-1] = c, 1.0
        J = _with_singular_values(rng, n, sv * 10.0 ** rng.uniform(-5, 5))
        assert K._cond_at_most(J, 1e12, U) == (np.linalg.cond(J) <= 1e12), c
    singular = rng.standard_normal((n, n))
    singular[:, -1] = singular[:, 0]  # two equal columns: σ_min = 0 to round-off (LAPACK: ~1e16 or inf)
    assert not K._cond_at_most(singular, 1e12, U)
    singular[:, -1] = 0.0  # a zero column: σ_min = 0 exactly
    assert not K._cond_at_most(singular, 1e12, U)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_the_small_solve_is_lapack_s(n):
    rng = np.random.default_rng(10 + n)
    A = np.empty((n, n))
    x = np.empty(n)
    for _ in range(200):
        J = _with_singular_values(rng, n, np.exp(rng.uniform(0, np.log(100.0), n)))  # condition ≤ 100
        b = rng.standard_normal(n)
        K._lu_solve(J, b, A, x)
        ref = np.linalg.solve(J, b)
        # both backward stable: forward errors ≤ cond · n ε each, ≤ 100 · 5 · 2.2e-16 ≈ 1.1e-13 of |x|; 1e-12
        assert np.max(np.abs(x - ref)) <= 1e-12 * np.max(np.abs(ref))
    J = np.array([[0.0, 1.0], [1.0, 0.0]]) if n == 2 else None  # a zero pivot without pivoting
    if J is not None:
        K._lu_solve(J, np.array([2.0, 3.0]), A, x)
        assert np.array_equal(x, [3.0, 2.0])


def _elliptic_cases():
    ell = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.5)
    return {
        "Clebsch top": (jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0]),
                        np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])),
        "Clebsch top, k = 0.3": (jg.clebsch_top(0.3).hamiltonian([0.1, 0.5, 0, 0.2, 1.0]),
                                 np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])),
        "elliptic, 3 sites": (ell.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4]),
                              np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])),
    }


def _solve_step_by_step(flow, x, dt):
    """``ChainExactFlow._newton``'s elliptic path before the fused call: the compiled Newton, then NumPy's residual
    test and the compiled branch check, each on its own."""
    from jetgaudin.exact_chain import _QUAD_TOL, _RES_TOL

    model = flow.model
    keep, E, rate, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(flow)
    target = dt * wkeep
    I = np.asarray(model.integrals(x), dtype=float)
    hI, extra = np.ascontiguousarray(I[:2 * model.M]), I[2 * model.M:]
    const = float(extra[0])
    rho = flow._real_parts(x, k, np.zeros(0, dtype=complex))
    bound = np.minimum(2 * np.abs(rho - lc) + P, 0.9 * Kp)
    sol = flow._newton_compiled(x, 2, keep, E, target, rho, bound, (hI, const, extra, kidx, pos, orders))
    if sol is None:
        return None
    u, om, quad, nu_end = sol
    assert quad <= _QUAD_TOL  # these states: the rule has converged (else the adaptive path, not compared here)
    Eu = E @ u[k:]
    if np.max(np.abs(om.sum(axis=0) - Eu - target) / (np.abs(om).sum(axis=0) + np.abs(target) + np.abs(Eu))) \
            > _RES_TOL:
        return None
    eta = rho + 1j * u[:k]
    return (eta, nu_end) if flow._branch_numerical(x, eta, nu_end, (hI, const, pos, orders)) else None


@pytest.mark.parametrize("name", list(_elliptic_cases()))
def test_the_fused_elliptic_solve_is_the_step_by_step_solve(name):
    H, x = _elliptic_cases()[name]
    flow = jg.ChainExactFlow(H, 1.0)
    dmax = float(flow.max_dt(x))
    for f in (-0.7, 0.1, 0.5, 0.9, 0.99, 1.01, 1.5, 3.0):
        dt = f * dmax
        got = flow._solve(x, dt)
        ref = _solve_step_by_step(flow, x, dt)
        assert (got is None) == (ref is None), f
        if ref is not None:
            # the same Newton call: the same bits up to the integrals (compiled forms in the fused path, NumPy's
            # einsum here: ~1e-16 relative) — η to 1e-14 relative (Newton's solution moves with the integrals)
            assert np.max(np.abs(got[0] - ref[0])) <= 1e-14 * np.max(np.abs(ref[0]))
            assert got[1] == 0.0  # the elliptic family has no rotation
            assert np.max(np.abs(got[2] - ref[1])) <= 1e-13 * np.max(np.abs(ref[1]))


@pytest.mark.parametrize("name", list(_elliptic_cases()) + ["rational", "trigonometric"])
def test_the_orbit_s_integrals_by_the_compiled_forms_are_model_integrals(name):
    cases = _elliptic_cases()
    cases["rational"] = (jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)]).hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2]),
                         np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6]))
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    cases["trigonometric"] = (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]),
                              np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6]))
    H, x0 = cases[name]
    flow = jg.ChainExactFlow(H, 0.1)
    model = flow.model
    rng = np.random.default_rng(4)
    for scale in (1.0, 1e3):
        x = x0 * scale * (1 + 0.3 * rng.standard_normal(x0.shape))
        got, ref = _integrals_row(flow, x), np.asarray(model.integrals(x))
        # the same quadratic forms summed in another order: ≤ n ε Σ|terms| per entry (n = 3M² + 2M + 2), with
        # Σ|terms| ≤ (Σ|q| over the forms + 2|b| Σ|l| + Σ|forms|) · max|x|² (a bound, so 1e-14 · that is safe)
        q, lin = model._forms
        qa = np.abs(q) if q.ndim == 4 else np.broadcast_to(np.abs(q), (3,) + q.shape)  # rational: one q for a = 1..3
        xm = np.max(np.abs(x))
        n = 3 * model.M ** 2 + 2 * model.M + 2
        tol = n * 2.3e-16 * (qa.sum(axis=(0, 2, 3)).max() * xm ** 2 + 2 * abs(float(model.b)) * np.abs(lin).sum()
                             * xm + np.sum(np.abs(x)))
        assert got.shape == ref.shape
        assert np.max(np.abs(got - ref)) <= tol


@pytest.mark.parametrize("name", list(_elliptic_cases()))
def test_the_fused_solve_applies_each_acceptance_test_at_its_threshold(name):
    """``solve_numerical`` refuses just below and accepts just above the solution's own residual (the residual
    test) and its own branch mismatch ``max_j |ν_rule(η_j) − ν_end,j| / |ν_rule(η_j)|`` (the branch check), and
    hands an estimate above ``quad_tol`` back (status 2): each test is applied, with its threshold."""
    from jetgaudin.exact_chain import _COARSE_TOL, _ITERATIONS, _STEP_TOL, _family_constants, _rules

    H, x = _elliptic_cases()[name]
    flow = jg.ChainExactFlow(H, 0.1)
    model = flow.model
    keep, E, rate, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(flow)
    dt = 0.5 * float(flow.max_dt(x))
    target = dt * wkeep
    I = _integrals_row(flow, x)
    hI, const = np.ascontiguousarray(I[:2 * model.M]), float(I[2 * model.M])
    rho = flow._real_parts(x, k, np.zeros(0, dtype=complex))
    bound = np.minimum(2 * np.abs(rho - lc) + P, 0.9 * Kp)
    fp = _family_constants(model.family)

    def run(quad_tol=1e-13, res_tol=1e-11, branch_tol=1e-8):
        u, om, nu = np.empty(E.shape[0]), np.empty((k, E.shape[0])), np.empty(k, dtype=complex)
        status, quad = K.solve_numerical(2, fp, pos, orders, hI, const, np.ones(1), kidx, E, target, rho, bound,
                                         *_rules(), _STEP_TOL, _COARSE_TOL, _ITERATIONS, u, om, nu, quad_tol,
                                         res_tol, float(P), 64, 2**16, branch_tol)
        return status, quad, u, om, nu

    status, quad, u, om, nu = run()
    assert status == 0
    Eu = E @ u[k:]
    res = np.max(np.abs(om.sum(axis=0) - Eu - target) / (np.abs(om).sum(axis=0) + np.abs(target) + np.abs(Eu)))
    assert 0 < res < 1e-11
    assert run(res_tol=res * (1 - 1e-9))[0] == 1 and run(res_tol=res * (1 + 1e-9))[0] == 0
    eta = rho + 1j * u[:k]
    ref = np.array([K.nu_numerical(2, fp, pos, orders, hI, const, float(P), e, 64, 2**16)[1] for e in eta])
    mismatch = np.max(np.abs(ref - nu) / np.abs(ref))
    assert 0 < mismatch < 1e-8
    assert run(branch_tol=mismatch * (1 - 1e-6))[0] == 1 and run(branch_tol=mismatch * (1 + 1e-6))[0] == 0
    assert quad > 0 and run(quad_tol=quad * (1 - 1e-9))[0] == 2 and run(quad_tol=quad)[0] == 0


@pytest.mark.parametrize("name", ["Clebsch top", "elliptic, 3 sites", "trigonometric"])
def test_the_loop_without_the_maps_is_the_loop_of_the_maps(name):
    """The every-row call takes the maps' kernel constants without building the maps: its rows are bit for bit
    those of the loop on the constants of ``model.two_point_backlund(η_j)`` (the route before), and ``η`` on a site
    is refused as the maps refuse it."""
    from jetgaudin import _exact_chain_loop as L
    from jetgaudin.gaudin.maps import _check_eta, _orbit_constants

    cases = _elliptic_cases()
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    cases["trigonometric"] = (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]),
                              np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6]))
    H, x = cases[name]
    flow = jg.ChainExactFlow(H, 0.05)
    model = flow.model
    steps = 7
    got = flow.advance(x, None, steps, 1)
    eta, theta, nu = flow._parameters(x)
    maps = [model.two_point_backlund(e) for e in eta]
    consts = L.stack_constants([_orbit_constants(model, mp.eta) for mp in maps])
    rows, final = np.empty((steps, x.size)), np.empty(x.size)
    L.rows_family(x, float(model.b), np.array(nu, dtype=complex), *consts, float(theta), steps, 1, 1, rows, final)
    assert np.array_equal(got.rows[:, ...], rows) and np.array_equal(got.X, final)
    with pytest.raises(jg.InvalidParameterError, match="is a site"):
        _check_eta(model, complex(model.positions[0], 0.3))
    with pytest.raises(jg.InvalidParameterError, match="is a site"):
        model.two_point_backlund(complex(model.positions[0], 0.3))
