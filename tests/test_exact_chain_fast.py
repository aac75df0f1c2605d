"""The elliptic family's fast path of the exact chain flow (issue 33 item 2: the Python around the compiled calls):
``advance`` of one orbit by one compiled solve (integrals, Newton, acceptance, the checks of ``η``) and one compiled
loop, with the plan of constants cached per flow.  It must give the general path's bits, make every refusal the
general path makes, and never serve a plan or a state that is not the caller's."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import _exact_chain_prep as prep
from jetgaudin.maps import with_resolved_backend

_CLEBSCH_X = np.array([0.3, -0.5, 0.4, 0.8, 0.2, -0.3])
_CHAIN_X = np.array([0.3, -0.2, 0.4, 0.1, 0.5, -0.3, -0.2, 0.1, 0.6])


def _clebsch(modulus=0.6, weights=(0, 0.7, 0, 0, 1.0)):
    return jg.clebsch_top(modulus).hamiltonian(list(weights))


def _chain():
    ell = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.5)
    return ell.hamiltonian([0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4])


def _general(flow, X, steps, save_every):
    """``flow.advance`` on the general path: the flow's plan set to "none" for the call (the cache's own slot)."""
    impl = flow._r()
    saved = prep._FAST.get(impl)
    prep._FAST[impl] = False
    try:
        assert impl._fast() is None
        return flow.advance(np.array(X), None, steps, save_every)
    finally:
        if saved is None:
            del prep._FAST[impl]
        else:
            prep._FAST[impl] = saved


def _same(a, b):
    assert np.array_equal(a.rows, b.rows) and np.array_equal(a.X, b.X)
    assert a.rows.shape == b.rows.shape and a.X.shape == b.X.shape
    assert a.carry.shape == b.carry.shape == () and a.carry.dtype == b.carry.dtype == complex
    assert a.imag_max.shape == b.imag_max.shape == () and a.imag_max.dtype == b.imag_max.dtype


CASES = {
    "Clebsch top": (_clebsch, _CLEBSCH_X, 0.5),
    "Clebsch top, k = 0.3": (lambda: _clebsch(0.3, (0.2, 0.5, 0, 0, 1.0)), _CLEBSCH_X, 0.25),
    "elliptic, 3 sites": (_chain, _CHAIN_X, 0.05),
}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("substeps, sign, steps, save_every", [(1, 1, 12, 1), (2, -1, 9, 4), (1, 1, 3, 5)])
def test_the_fast_path_gives_the_general_path_s_bits(name, substeps, sign, steps, save_every):
    make, X0, dt = CASES[name]
    flow = jg.ExactFlow(make(), sign * dt, substeps=substeps)
    assert flow._r()._fast() is not None  # the fast path applies to these flows
    rng = np.random.default_rng(7)
    for X in (X0, X0 * (1 + 0.05 * rng.standard_normal(X0.size))):
        fast = flow.advance(X, None, steps, save_every)
        _same(fast, _general(flow, X, steps, save_every))  # bit for bit: the same compiled arithmetic
        # the iterate call (the start row, then every saved row) and a batch (each orbit by the fast orbit, its rows
        # into the batch's buffer)
        it = flow.iterate(X, steps, save_every=save_every)
        assert np.array_equal(it[0], X) and np.array_equal(it[1:], fast.rows)
        batch = flow.advance(np.stack([X, X]), None, steps, save_every)
        assert np.array_equal(batch.rows[:, 1], fast.rows) and np.array_equal(batch.X[0], fast.X)


def test_the_plan_is_per_flow_and_per_route():
    X = _CLEBSCH_X
    H6, H3 = _clebsch(0.6), _clebsch(0.3, (0.2, 0.5, 0, 0, 1.0))
    flows = [jg.ExactFlow(H6, 0.5), jg.ExactFlow(H6, 0.3), jg.ExactFlow(H6, 0.5, substeps=2), jg.ExactFlow(H3, 0.25),
             jg.ExactFlow(_clebsch(0.6, (0, 0.9, 0, 0, 1.0)), 0.5)]
    results = [f.advance(X, None, 5, 1) for f in flows]  # every plan built, then each flow called again below
    for f, r in zip(flows, results, strict=True):
        again = f.advance(X, None, 5, 1)
        _same(again, r)
        _same(again, _general(f, X, 5, 1))  # a plan of another dt, model or weights would give other bits
    assert len({r.X.tobytes() for r in results}) == len(flows)
    # a copy on another route is a new key: the NumPy route, not the copied flow's plan
    numpy_copy = with_resolved_backend(flows[0]._r(), "numpy")
    assert numpy_copy._fast() is None
    assert not np.array_equal(numpy_copy.advance(X, None, 5, 1).X, results[0].X)  # NumPy's round-off, not ours
    assert np.allclose(numpy_copy.advance(X, None, 5, 1).X, results[0].X, rtol=0, atol=1e-12)  # ~1e-15 apart
    assert jg.ExactFlow(H6, 0.5, backend="numpy")._r()._fast() is None


def test_a_mutated_state_is_not_served_stale():
    flow = jg.ExactFlow(_clebsch(), 0.5)
    X = _CLEBSCH_X.copy()
    first = flow.advance(X, None, 4, 1)
    X[0] += 0.01  # the same array object, new values
    second = flow.advance(X, None, 4, 1)
    _same(second, _general(flow, X, 4, 1))
    assert not np.array_equal(first.X, second.X)
    # the stepping loop's ν1 is the solve's (not a previous call's, which the loop overwrote)
    _same(flow.advance(X, None, 4, 1), second)


def test_the_fast_path_makes_the_general_path_s_refusals():
    flow = jg.ExactFlow(_clebsch(), 0.5)
    for bad in (np.array([np.nan, 0, 0, 0.8, 0.2, -0.3]), np.array([np.inf, 0, 0, 0.8, 0.2, -0.3])):
        with pytest.raises(jg.InvalidStateError, match="non-finite"):
            flow.advance(bad, None, 3, 1)
    with pytest.raises(jg.InvalidStateError, match="3M = 6 components"):
        flow.advance(np.zeros(9), None, 3, 1)
    for steps, save_every in ((-1, 1), (True, 1), (3.0, 1), (3, 0), (2**63, 1)):
        with pytest.raises(jg.InvalidParameterError):
            flow.advance(_CLEBSCH_X, None, steps, save_every)
    zero = flow.advance(_CLEBSCH_X, None, 0, 1)  # no step: no solve (the general path's rule)
    assert zero.rows.shape == (0, 6) and np.array_equal(zero.X, _CLEBSCH_X)
    # too large a step: the general path's StepTooLargeError with its dt_max
    big = jg.ExactFlow(_clebsch(), 3.0)
    with pytest.raises(jg.StepTooLargeError) as fast_err:
        big.advance(_CLEBSCH_X, None, 2, 1)
    impl = big._r()
    prep._FAST[impl] = False
    with pytest.raises(jg.StepTooLargeError) as general_err:
        big.advance(_CLEBSCH_X, None, 2, 1)
    assert fast_err.value.dt_max == general_err.value.dt_max and 0 < fast_err.value.dt_max < 3.0


def test_the_kernel_refuses_an_eta_the_maps_refuse():
    """The plan checks the real parts once; ``|Im η| < 0.9 K'`` (``EllipticFamily.check_xi``) is the kernel's, per
    orbit: with the limit set just below this orbit's largest ``|Im η|`` the fast path must decline (the general path
    then makes the maps' check), and just above it must not."""
    flow = jg.ExactFlow(_clebsch(), 0.5)._r()
    plan = flow._fast()
    eta, _ = flow.parameters(_CLEBSCH_X)
    top = float(np.max(np.abs(eta.imag)))

    def with_post(post):
        return plan[:4] + (post,) + plan[5:9] + ({},)  # a fresh cache of stacked constants

    post = plan[4]
    assert post[-1] == 0.9 * flow.model.family.Kp  # EllipticFamily's _IM_FRACTION K'
    assert prep._orbit_fast(flow, _CLEBSCH_X, 3, 1, with_post(post[:-1] + (np.nextafter(top, 0),))) is None
    got = prep._orbit_fast(flow, _CLEBSCH_X, 3, 1, with_post(post[:-1] + (np.nextafter(top, np.inf),)))
    assert got is not None and np.array_equal(got[1], flow.advance(_CLEBSCH_X, None, 3, 1).X)


def test_non_finite_steps_are_refused_on_the_fast_path():
    """The loop's rows are checked as the general path checks them (``SingularStepError``): here a loop that
    returns a NaN in one row stands in for an overflow inside the compiled map step."""
    flow = jg.ExactFlow(_clebsch(), 0.5)._r()
    plan = flow._fast()

    def rows_with_nan(x, b, nu, *rest):
        rest[-2][...] = 1.0
        rest[-1][...] = 1.0
        rest[-2][1, 2] = np.nan

    with pytest.raises(jg.SingularStepError, match="non-finite"):
        prep._orbit_fast(flow, _CLEBSCH_X, 3, 1, plan[:1] + (rows_with_nan,) + plan[2:])


def test_the_model_s_plans_follow_the_weights_and_the_step():
    """``jg.solve`` builds a new flow at every call; the plans are also kept per model, by weights, ``dt``,
    ``substeps`` and ``rho_factor``: a Hamiltonian whose weights were changed in place, or another step, must get
    its own plan (the result of a fresh Hamiltonian), not the previous call's."""
    X = _CLEBSCH_X
    H = _clebsch()
    first = jg.solve(H, X, (0.0, 2.0), dt=0.5, method="exact", save_every=1)
    H.weights[1] = 0.9  # in place
    changed = jg.solve(H, X, (0.0, 2.0), dt=0.5, method="exact", save_every=1)
    fresh = jg.solve(_clebsch(0.6, (0, 0.9, 0, 0, 1.0)), X, (0.0, 2.0), dt=0.5, method="exact", save_every=1)
    assert np.array_equal(changed.X, fresh.X) and not np.array_equal(changed.X, first.X)
    for dt, substeps in ((0.25, 1), (0.5, 2)):  # the same model and weights, another step
        got = jg.ExactFlow(H, dt, substeps=substeps).advance(X, None, 4, 1)
        _same(got, _general(jg.ExactFlow(H, dt, substeps=substeps), X, 4, 1))
    # rho_factor: the real parts λ_c + c R/t_j of a chain whose period is long enough for that rule (the Clebsch
    # top's, and the 3-site chain's at k = 0.5, are the period's rule, which does not read c)
    Hc = jg.GaudinModel(0.0, [(0.0, 1), (0.4, 1), (0.9, 1)], family="elliptic", modulus=0.95).hamiltonian(
        [0.5, 0.1, 0.2, 0.0, 0.3, 0.05, 0.4])
    jg.ExactFlow(Hc, 0.05).advance(_CHAIN_X, None, 2, 1)
    other = jg.ExactFlow(Hc, 0.05, rho_factor=1.7)
    assert not np.array_equal(other._r()._fast()[3][12], jg.ExactFlow(Hc, 0.05)._r()._fast()[3][12])  # ρ differ
    _same(other.advance(_CHAIN_X, None, 4, 1), _general(jg.ExactFlow(Hc, 0.05, rho_factor=1.7), _CHAIN_X, 4, 1))


def test_other_inputs_take_the_general_path_with_the_same_result():
    """A read-only or strided array, float32, a list: not the fast path's input (another compiled signature, or a
    conversion the state check makes), so the general path, with the same result where the values are the same."""
    flow = jg.ExactFlow(_clebsch(), 0.5)
    ref = flow.advance(_CLEBSCH_X, None, 4, 2)
    ro = _CLEBSCH_X.copy()
    ro.setflags(write=False)
    strided = np.repeat(_CLEBSCH_X, 2)[::2]
    for X in (ro, strided, list(_CLEBSCH_X), _CLEBSCH_X.reshape(1, 6)[0]):
        got = flow.advance(X, None, 4, 2)
        _same(got, ref)
    x32 = _CLEBSCH_X.astype(np.float32)
    _same(flow.advance(x32, None, 4, 2), flow.advance(x32.astype(float), None, 4, 2))


def test_non_finite_steps_are_refused_on_the_general_path(monkeypatch):
    """The same check on the general path (a trigonometric chain: no fast path), its loop replaced by one that
    returns a NaN in the last row, as an overflow inside the compiled map step would."""
    import jetgaudin._exact_chain_loop as loop

    trig = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 1), (2.5, 1)], family="trigonometric", gamma=0.5)
    flow = jg.ExactFlow(trig.hamiltonian([0.3, 0, -0.2, 0, 0.5, 0, 0.4]), 0.05)
    assert flow._r()._fast() is None
    flow.advance(_CHAIN_X, None, 3, 1)  # fine before

    def rows_with_nan(*args):
        args[-2][...] = 1.0
        args[-1][...] = 1.0
        args[-2][-1, 0] = np.nan

    monkeypatch.setattr(loop, "rows_family", rows_with_nan)
    with pytest.raises(jg.SingularStepError, match="non-finite"):
        flow.advance(_CHAIN_X, None, 3, 1)


def test_maps_at_round_off_are_left_out_as_on_the_general_path():
    """``|Im η_j| ≤ 1e-13 max(|Re η_j|, 1)``: the map is the identity to round-off and ``_orbit`` leaves it out; the
    kernel declines such an orbit (here every map: ``dt = 1e-30``, ``|Im η| ~ 1e-30``), and the general path returns
    the state unchanged."""
    flow = jg.ExactFlow(_clebsch(), 1e-30)._r()
    eta, _ = flow.parameters(_CLEBSCH_X)
    assert np.all(np.abs(eta.imag) < 1e-29) and np.all(eta.imag != 0)  # solved, at round-off
    assert prep._orbit_fast(flow, _CLEBSCH_X, 2, 1, flow._fast()) is None
    got = flow.advance(_CLEBSCH_X, None, 2, 1)
    assert np.array_equal(got.X, _CLEBSCH_X) and np.array_equal(got.rows, [_CLEBSCH_X, _CLEBSCH_X])
