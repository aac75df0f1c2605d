"""Translating every site (issue 33): the families' maps and exact steps do not see where the chain sits.

Every family's Lax matrix depends on ``λ`` only through ``λ − λ_i`` (rational ``1/(λ − λ_i)^m``, trigonometric and
elliptic ``r(λ − λ_i)``), so moving every site by ``c`` and the map's parameter ``η`` with them maps the model onto
itself: the two-point map with ``η + c`` is the map with ``η``, and the exact step of the same weights is the same
step (the weights are coefficients of the integrals, which are residues and values of the same functions of
``λ − λ_i``).  ``tests/test_exact_first_class.py`` checks the exact step for the rational and trigonometric families
and ``tests/test_gaudin_maps.py`` the rational maps; here the elliptic family's exact step and the trigonometric and
elliptic maps.

Tolerances: the translated model evaluates its functions at arguments that differ by round-off of ``c``
(~1e-16 relative), and the exact step solves a Newton system: 1e-12 for one exact step and for 10 maps of a state of
size ~1 (measured differences 1e-16 to 1e-14).
"""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.exact_chain import ChainExactFlow

FAMILIES = {"trigonometric": (0.8, {"family": "trigonometric", "gamma": 0.5}),
            "elliptic": (0.0, {"family": "elliptic", "modulus": 0.5})}
SITES = ((0.0, 1), (0.4, 1), (0.9, 1))


def _model(name: str, c: float, sites=SITES) -> jg.GaudinModel:
    b, kw = FAMILIES[name]
    return jg.GaudinModel(b, [(p + c, k) for p, k in sites], **kw)


# found by this test (issue 33 round): with every site moved by -0.5 the NumPy Newton solve of the exact step failed
# at dt = 0.02 exactly (0.0199 and 0.0201 solved; the periodic real parts of the elliptic family are not moved with the
# sites, so the translated solve starts elsewhere).  The compiled solve of the same round (_exact_chain_kernels,
# _exact_elliptic) solves it; the case stays here so that a return of the failure shows.
@pytest.mark.parametrize("c", [0.37, 1.3, -0.5])
def test_the_elliptic_exact_step_does_not_see_a_translation(c):
    """Three sites of order 1 (the XYZ magnet of tests/test_exact_chain.py), one exact step of dt = 0.02."""
    X = np.random.default_rng(4).standard_normal(9) * 0.5
    steps = []
    for shift in (0.0, c):
        m = _model("elliptic", shift)
        w = np.zeros(m.n_integrals)
        w[~m.casimir_mask()] = [0.5, 0.2, 0.3, 0.1]
        steps.append(ChainExactFlow(m.hamiltonian(w), 0.02)(X))
    assert np.max(np.abs(steps[0] - X)) > 1e-3  # it moves
    assert np.max(np.abs(steps[0] - steps[1])) < 1e-12


@pytest.mark.parametrize(("name", "sites"), [("trigonometric", SITES), ("trigonometric", ((0.0, 1), (0.9, 2))),
                                             ("elliptic", SITES)])
def test_the_maps_do_not_see_a_translation(name, sites):
    """The two-point map of the translated chain with ``η + c`` is the map with ``η`` (10 steps); the trigonometric
    family with a site of order 2 too (the elliptic family's sites are of order 1)."""
    eta, c = 0.2 + 0.3j, 0.61
    m0, m1 = _model(name, 0.0, sites), _model(name, c, sites)
    X = np.random.default_rng(5).standard_normal(m0.n_state) * 0.5
    a = m0.two_point_backlund(eta).iterate(X, 10)
    assert np.max(np.abs(a[-1] - X)) > 1e-2
    assert np.max(np.abs(m1.two_point_backlund(eta + c).iterate(X, 10) - a)) < 1e-12


def _xxz():
    """The XXZ magnet of tests/test_exact_chain.py (three order-1 sites, trigonometric, γ = 0.5) and a state."""
    m = jg.GaudinModel(1.0, ((0.0, 1), (0.4, 1), (0.9, 1)), family="trigonometric", gamma=0.5)
    w = np.zeros(m.n_integrals)
    w[~m.casimir_mask()] = [0.5, 0.2, 0.3, 0.1]
    return m, m.hamiltonian(w), np.random.default_rng(3).standard_normal(m.n_state) * 0.5


def test_the_adaptive_quadrature_is_only_a_fallback(monkeypatch):
    """The weights of the exact step's Newton solve come from the 64-point Gauss–Legendre rule; the adaptive
    quadrature (``model.interpolating_weights``) runs only where the rule's estimate ``|Q_64 − Q_32|`` says it has not
    converged: never on this ordinary step; forced (a tolerance of 0), the fallback gives the same step (1e-13: both
    are the weights to ~1e-15, and Newton's solution moves by the same relative amount).  Written for the mutant that
    made the estimate ``|Q_64 · Q_32|`` (then every solve took the slow fallback)."""
    import jetgaudin.exact_chain as ec

    m, H, X = _xxz()
    calls = {"n": 0}
    real = type(m).interpolating_weights

    def spy(self, *args, **kwargs):
        calls["n"] += 1
        return real(self, *args, **kwargs)

    monkeypatch.setattr(type(m), "interpolating_weights", spy)
    rule = ChainExactFlow(H, 0.02)(X)
    assert calls["n"] == 0
    monkeypatch.setattr(ec, "_QUAD_TOL", 0.0)
    fallback = ChainExactFlow(H, 0.02)(X)
    assert calls["n"] > 0
    assert np.max(np.abs(fallback - rule)) < 1e-13 and np.max(np.abs(rule - X)) > 1e-3


def test_the_numpy_loop_of_maps_without_a_compiled_route(monkeypatch):
    """Every family's chain map has a compiled route today, so the exact step's NumPy loop (``k s`` steps of each map
    per call, rows rotated once) runs only for a map without one: made so here, its rows every 2 of 6 steps equal the
    compiled loop's (1e-12: the two routes of the same maps differ by round-off, ~1e-15 a step).  Written for the
    mutant ``save_every - done % save_every`` → ``save_every / done % save_every`` (the loop was never run)."""
    m, H, X = _xxz()
    E = ChainExactFlow(H, 0.02)
    compiled = E.advance(X, None, 6, 2)
    map_type = type(m.two_point_backlund(0.3 + 0.1j))
    monkeypatch.setattr(map_type, "has_compiled", property(lambda self: False))
    numpy_loop = E.advance(X, None, 6, 2)
    assert compiled.rows.shape == numpy_loop.rows.shape == (3, 9)
    assert np.max(np.abs(numpy_loop.rows - compiled.rows)) < 1e-12
    assert np.max(np.abs(numpy_loop.X - compiled.X)) < 1e-12


# --- the seed-35 sample (issue 33, item 5): exact.py's compiled top route -----------------------------------------

_X3 = np.array([0.3, -0.2, 0.9, 0.1, 0.4, -0.3, 0.2, 0.1, 0.5])  # a top of order 3 of size ~1


def test_the_top_flow_saves_rows_up_to_16_steps_apart_in_one_compiled_loop(monkeypatch):
    """``ExactFlow._run`` (module doc of :meth:`_run`): compiled, rows at most ``_FUSED_ROWS = 16`` (sub)steps apart
    run in the fused loop (``_run_fused``), farther apart ``k s`` steps per kernel call (``_maps_compiled``); the two
    routes give the same rows to round-off (1e-13: measured 5e-16 to 9e-16 over 51 steps of a state of size ~1).
    Batches of two orbits, so that ``advance`` takes ``_run`` (one orbit takes the fused solve-and-run call).
    Written for the mutant ``save_every * s <= _FUSED_ROWS`` → ``!=`` (the sparse saving took the fused loop)."""
    import jetgaudin.exact as ex

    H = jg.physical_hamiltonian(3, 1.0)
    XB = np.stack([_X3, 0.9 * _X3])
    seen: list[int] = []
    real = ex._TopExactFlow._run_fused

    def spy(self, Z, eta, theta, nu, steps, save_every, rows):
        seen.append(save_every)
        return real(self, Z, eta, theta, nu, steps, save_every, rows)

    monkeypatch.setattr(ex._TopExactFlow, "_run_fused", spy)
    for se, substeps, fused in ((16, 1, True), (17, 1, False), (8, 2, True), (9, 2, False)):
        Es = jg.ExactFlow(H, 0.05, substeps, backend="compiled")
        seen.clear()
        adv = Es.advance(XB, None, 3 * se, se)
        assert seen == ([se] if fused else []), (se, substeps, seen)
        monkeypatch.setattr(ex, "_FUSED_ROWS", 0 if fused else 10 ** 6)  # the other route
        other = Es.advance(XB, None, 3 * se, se)
        monkeypatch.setattr(ex, "_FUSED_ROWS", 16)
        assert np.max(np.abs(other.rows - adv.rows)) < 1e-13 and np.max(np.abs(other.X - adv.X)) < 1e-13
        assert np.max(np.abs(adv.X - XB)) > 1e-2  # it moves


def test_a_batch_whose_second_orbit_fails_in_the_compiled_loop_raises_naming_it(monkeypatch):
    """A batch of the top's exact flow (compiled, fused loop) in which orbit 1 fails mid-run raises the typed error
    naming orbit 1 (``SingularStepError``), never returns its rows with NaN.  The failure is planted: the solve's
    parameters of orbit 1 made NaN (``_accepted`` wrapped), so that its first step is non-finite; orbit 0 is fine.
    Written for the mutant ``Z.shape[0] > 1 and info[:, 0].any()`` → ``Z.shape[0] <= 1 and …`` (a batch's failures
    after its first orbit were dropped)."""
    import jetgaudin.exact as ex

    real = ex._accepted

    def planted(*args, **kwargs):
        eta, theta, res, quad, nu = real(*args, **kwargs)
        eta = eta.copy()
        eta[1] = np.nan
        return eta, theta, res, quad, nu

    monkeypatch.setattr(ex, "_accepted", planted)
    E = jg.ExactFlow(jg.physical_hamiltonian(3, 1.0), 0.05, backend="compiled")
    with pytest.raises(jg.SingularStepError, match="of orbit 1"):
        E.advance(np.stack([_X3, 0.9 * _X3]), None, 4, 1)


def test_the_compiled_solve_refuses_what_the_numpy_solve_refuses_without_a_branch_rule():
    """A trigonometric chain at ``b = 0`` with ``J = Σ y_0^3 = 0``: ``ν²`` vanishes as ``Im λ → −∞`` (``b + iγJ = 0``)
    and the family's branch rule of ``ν`` is undefined.  The NumPy solve refuses the step (no parameters "at any step
    size"); the compiled solve, a faster copy of it, must refuse the same state the same way, never step on a guessed
    branch.  Written for the mutant ``abs(Q[0])`` → ``abs(Q[1])`` in the compiled route's test of the polynomial's
    leading coefficient (the compiled solve then stepped)."""
    m = jg.GaudinModel(0.0, ((0.0, 1), (0.4, 1), (0.9, 1)), family="trigonometric", gamma=0.5)
    X = np.random.default_rng(3).standard_normal(m.n_state) * 0.5
    X[2::3] -= X[2::3].mean()  # J = 0
    w = np.zeros(m.n_integrals)
    w[~m.casimir_mask()] = [0.5, 0.2, 0.3, 0.1][: int((~m.casimir_mask()).sum())]
    H = m.hamiltonian(w)
    for backend in ("numpy", "compiled"):
        with pytest.raises(jg.StepTooLargeError, match="at any step size"):
            ChainExactFlow(H, 0.02, backend=backend)(X)


def test_the_real_parts_of_a_periodic_family_are_the_farthest_points_of_the_whole_grid():
    """``_periodic_real_parts(λ_c, P, k, points)``: greedily the points of the 256-point grid
    ``λ_c + (j + φ)P/256``, ``j = 0..255`` (``φ = (√5 − 1)/2``: no dyadic fraction of the period), farthest from every
    point and its images at ``± P``.  One point at ``P/2 − 3P/1024`` (period 1): the farthest grid point is the last
    one, ``(255 + φ)/256`` (distance 0.49856, against 0.49753 for ``j = 254`` and 0.49466 for ``j = 0``); for
    ``k = 2`` the second is at least ``P/8`` from it.  Exact (grid points).  Written for the mutant ``np.arange(256)``
    → ``np.arange(255)`` (the grid's last point dropped); the grid is offset (the half period is not a grid point,
    the next test)."""
    from jetgaudin._exact_chain_prep import _GRID_OFFSET, _periodic_real_parts

    pts = np.array([0.5 - 3 / 1024], dtype=complex)
    last = (255 + _GRID_OFFSET) / 256
    assert _periodic_real_parts(0.0, 1.0, 1, pts).tolist() == [last]
    two = _periodic_real_parts(0.0, 1.0, 2, pts)
    assert last in two.tolist() and len(two) == 2
    d = abs(two[0] - two[1])
    assert min(d, 1 - d) >= 1 / 8


def test_no_real_part_of_a_periodic_family_is_a_dyadic_fraction_of_the_period():
    """The real parts of one site (the Clebsch top) are not the half period, nor any ``jP/2^m``: at ``Re η = K`` (the
    half period of the elliptic functions from a site at 0) some quantity of the map's step has the same exact value at
    every step and rounds alike each time, and the Casimir ``h_{1,3}`` of the Clebsch top drifted linearly (next
    test).  Planted: the grid without its offset (this test and the next fail)."""
    from jetgaudin._exact_chain_prep import _periodic_real_parts

    for P in (1.0, 2 * 1.7507538029157526, np.pi / 0.5):
        for k in (1, 2, 3):
            rho = _periodic_real_parts(0.0, P, k, np.zeros(1, dtype=complex))
            frac = rho / P * 1024
            assert np.all(np.abs(frac - np.round(frac)) > 0.1), (P, k, rho)


@pytest.mark.parametrize("k", [0.6, 0.3])
def test_the_clebsch_top_s_casimir_has_no_bias_per_step(k):
    """The Casimir ``h_{1,3}`` of the Clebsch top under its exact flow (dt = 0.5: ``|Im η|`` up to ~0.4) changes by
    round-off of either sign: the mean of its per-step changes over 8 orbits × 2500 steps is within 4.5 standard
    errors of 0 (a random walk's ``|z|`` exceeds 4.5 with probability 7e-6; with the real part at the half period
    ``K``, ``z`` was −9 to −16 on such samples).  The other integrals likewise."""
    H = jg.clebsch_top(k).hamiltonian([0, 0.7, 0, 0, 1.0])
    m = H.model
    rng = np.random.default_rng(5)
    x0 = np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])
    inc = []
    for _ in range(8):
        rows = jg.ChainExactFlow(H, 0.5).iterate(x0 * (1 + 0.1 * rng.standard_normal(6)), 2500)
        inc.append(np.diff(np.asarray(m.integrals(rows)), axis=0))
    inc = np.concatenate(inc)
    for j, label in enumerate(m.integral_labels()):
        sd = inc[:, j].std()
        if sd == 0:
            continue
        z = inc[:, j].mean() / (sd / np.sqrt(len(inc)))
        assert abs(z) < 4.5, (label, z)
