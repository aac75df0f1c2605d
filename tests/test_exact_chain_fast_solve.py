"""The compiled parameter solve's fast path (``_exact_chain_kernels.newton``; issue 33 item 2, the Clebsch top's
every-row call ≥ 2× heyoka): Newton's early steps on the 8-point rule, the 16-point rule to a step of 1e-8 |u|, one
pass of the 64-point rule, and the quadrature estimate from the 16-point rule carried to the last point.  It must give
the solution of the path of the rules alone (the 64-point rule's, to round-off), take the path of the rules alone
wherever it fails, and solve exactly the orbits that path solves (no step size made feasible or infeasible)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import _exact_chain_kernels as K
from jetgaudin.exact_chain import (
    _COARSE_TOL,
    _ITERATIONS,
    _QUAD_TOL,
    _STEP_TOL,
    COMPILED_FAMILIES,
    _family_constants,
    _orbit_roots,
    _rules,
    _static,
)

X9 = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])


def _cases():
    ell = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.5)
    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    rat = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)])
    return {
        "Clebsch top": (jg.clebsch_top(0.6).hamiltonian([0, 0.7, 0, 0, 1.0]),
                        np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])),
        "elliptic, 3 sites": (ell.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4]), X9),
        "trigonometric": (trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]), X9),
        "rational": (rat.hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2]), X9),
    }


def _problem(H, x, dt):
    """The arguments of ``newton`` before the rules for the orbit ``x`` and the step ``dt`` (as
    ``ChainExactFlow._newton_compiled`` builds them)."""
    flow = jg.ChainExactFlow(H, abs(dt))
    model, fam = H.model, H.model.family
    keep, E, _, k, wkeep, kidx, pos, orders, lc, P, Kp = _static(flow)
    I = np.asarray(model.integrals(x), dtype=float)
    hI = np.ascontiguousarray(I[:2 * model.M])
    const = float(np.real(fam.nu2_constant(float(model.b), I[2 * model.M:])))
    dconst = np.ascontiguousarray(fam.nu2_constant_gradient(float(model.b), I[2 * model.M:]), dtype=float)
    rho = flow._real_parts(x, k, _orbit_roots(model, x)[1])
    bound = np.minimum(2 * np.abs(rho - lc) + (P or 0.0), 0.9 * Kp)
    args = (COMPILED_FAMILIES[fam.name], _family_constants(fam), pos, orders, hI, const, dconst, kidx, E,
            dt * wkeep, rho, bound)
    return args, k, E.shape[0]


def _newton(problem, fast: bool):
    args, k, n = problem
    rules = _rules()
    if not fast:  # no very coarse rule: the path of the rules alone
        rules = rules[:9] + tuple(a[:0] for a in rules[9:])
    u, om, nu = np.empty(n), np.empty((k, n)), np.empty(k, dtype=complex)
    status, quad, took = K.newton(*args, *rules, _STEP_TOL, _COARSE_TOL, _ITERATIONS, u, om, nu)
    return status, quad, took, u, om, nu


@pytest.mark.parametrize("name", list(_cases()))
def test_the_fast_path_gives_the_solution_of_the_rules(name):
    H, x = _cases()[name]
    dmax = float(jg.ChainExactFlow(H, 1.0).max_dt(x))
    for f in (-0.9, 0.05, 0.3, 0.6, 0.9):
        problem = _problem(H, x, f * dmax)
        st, quad, took, u, om, nu = _newton(problem, True)
        st0, quad0, took0, u0, om0, nu0 = _newton(problem, False)
        assert st == st0 == 0 and took0 == 0
        assert took == 1, (name, f)  # these orbits are the fast path's (else it would not be faster)
        # both are Newton on the 64-point rule to a step of 1e-13 |u|: the same solution to round-off (measured
        # ≤ 1.5e-14 relative on these states, whose Jacobians are well conditioned: 1e-13 leaves 7×), the same
        # weights (1e-12 of their scale) and the same ν at the maps' parameters
        assert np.max(np.abs(u - u0) / np.abs(u0)) < 1e-13, (name, f)
        assert np.max(np.abs(om - om0)) < 1e-12 * np.abs(om0).max()
        assert np.max(np.abs(nu - nu0) / np.abs(nu0)) < 1e-12
        # the estimates: both the round-off of a converged rule here, below the acceptance of 1e-13
        assert 0 <= quad <= _QUAD_TOL and 0 <= quad0 <= _QUAD_TOL


@pytest.mark.parametrize("name", ["Clebsch top", "elliptic, 3 sites", "trigonometric"])
def test_the_fast_path_solves_exactly_the_orbits_the_rules_solve(name):
    """Feasibility is decided as before: a step the rules alone cannot take is not taken by the fast path either,
    and the reverse (over a grid of step sizes up to 2.5 × dt_max, infeasible steps and holes included: the
    3-site elliptic chain is feasible again beyond its first failure).  A continuation that refines the grid where
    two coarse nodes are too far apart made the 3-site chain's dt_max 0.249 → 0.321 with infeasible steps below it;
    it was not kept."""
    H, x = _cases()[name]
    dmax = float(jg.ChainExactFlow(H, 1.0).max_dt(x))
    seen = set()
    for f in np.linspace(0.05, 2.5, 50):
        problem = _problem(H, x, f * dmax)
        st, *_ = _newton(problem, True)
        st0, *_ = _newton(problem, False)
        assert st == st0, (name, f)
        seen.add(st)
    assert seen == {0, 1}  # both outcomes are on the grid


def test_where_the_fast_path_fails_the_rules_start_afresh():
    """Where the fast path finds no solution (the 8-point rule's continuation or iterates fail, or its estimate is
    above the acceptance) the path of the rules alone runs from the linear start: its solution bit for bit, as if the
    fast path had not run (a chain with two close sites, where the fast path fails at several step sizes).  On this
    chain the rules alone fail at some steps inside the feasible range (holes; at the smallest steps too) and the fast
    path solves some of them: never beyond the range (checked to 3 dt_max when this was written: 5 holes filled in 4
    orbits, no step feasible past the last one the rules reach)."""
    rat = jg.GaudinModel(1.0, [(0.0, 2), (0.05, 1)])
    H = rat.hamiltonian([0.3, 0.1, -0.2, 0.4, 0.5, 0.2])
    rng = np.random.default_rng(1)
    failed = 0
    for s in range(4):
        x = X9 if s == 0 else X9 * (1 + 0.2 * rng.standard_normal(X9.shape))
        dmax = float(jg.ChainExactFlow(H, 1.0).max_dt(x))
        for f in np.linspace(0.05, 1.0, 40):
            problem = _problem(H, x, f * dmax)
            st, quad, took, u, om, nu = _newton(problem, True)
            st0, quad0, _, u0, om0, nu0 = _newton(problem, False)
            assert st <= st0  # every orbit the rules solve is solved (some more: below)
            if st == 0 and took == 0:
                failed += 1
                assert np.array_equal(u, u0) and np.array_equal(om, om0) and np.array_equal(nu, nu0)
                assert quad == quad0
    assert failed >= 3  # the fallback was exercised (14 of 240 solves on the tree that added it)
