"""Every method of ``jg.solve`` for every model (issue 33 item 1): one Hamiltonian protocol and one route table
(``jetgaudin.methods.ROUTES``), no top/chain branch in ``solve``.  Models: a rational and a trigonometric chain (two
sites), an elliptic chain (three sites), the Clebsch top (one elliptic site of order 2), the twisted top (N = 3), and
an su(3) chain for the midpoint rule.  The reference is DOP853 at rtol = atol = 1e-13 (global error ~1e-13 on these
O(1) states over t ≤ 0.2)."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.hamiltonians import SolveHamiltonian
from jetgaudin.methods import ROUTES, chain_maps_per_step
from jetgaudin.solve import SolveMethod

X6 = np.array([0.72, 0.24, -0.54, 0.6, 0.0, 0.8])


def _weights(model, matched=None):
    if matched is None:
        return np.linspace(0.3, 0.9, model.n_integrals)
    w = np.zeros(model.n_integrals)
    w[~model.casimir_mask()] = matched
    return w


def _case(name):
    """``(H, X0, dt)``."""
    if name == "twisted top":
        return jg.physical_hamiltonian(3, 1.0), 0.3 * np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]), 0.05
    if name == "elliptic chain":  # the case of tests/test_exact_chain.py::FAMILIES (its exact step is feasible)
        m = jg.GaudinModel(0.0, ((0.0, 1), (0.4, 1), (0.9, 1)), family="elliptic", modulus=0.5)
        return m.hamiltonian(_weights(m, [0.5, 0.2, 0.3, 0.1])), np.random.default_rng(3).standard_normal(9) * 0.5, 0.02
    m = {"rational chain": jg.GaudinModel(1.0, [(-0.5, 1), (0.4, 1)]),
         "trigonometric chain": jg.GaudinModel(1.0, [(-0.5, 1), (0.4, 1)], family="trigonometric", gamma=1.0),
         "Clebsch top": jg.clebsch_top(0.6)}[name]
    return m.hamiltonian(_weights(m)), X6, 0.05


CASES = ["rational chain", "trigonometric chain", "elliptic chain", "Clebsch top", "twisted top"]
T = 0.2


def _reference(H, X, t_span, dt):
    return jg.solve(H, X, t_span, dt=dt, method="dop853", rtol=1e-13, atol=1e-13)


def test_every_method_has_a_route_for_every_kind_of_hamiltonian():
    """The table has a row (a map, the adaptive integrator or a typed refusal) for every (model kind, method), and
    the three Hamiltonian classes follow the protocol solve needs."""
    kinds = {k for k, _ in ROUTES}
    assert kinds == {"top", "chain", "sun"}
    assert {(k, m.value) for k in kinds for m in SolveMethod} == set(ROUTES)
    sun = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
    for H in (jg.physical_hamiltonian(3, 1.0), jg.clebsch_top(0.6).hamiltonian(np.ones(5)),
              sun.hamiltonian(np.ones(10))):
        assert isinstance(H, SolveHamiltonian)
    assert [H.route_kind for H in (jg.physical_hamiltonian(2, 1.0), jg.clebsch_top(0.6).hamiltonian(np.ones(5)),
                                   sun.hamiltonian(np.ones(10)))] == ["top", "chain", "sun"]


@pytest.mark.parametrize("method", ["exact", "heyoka"])
@pytest.mark.parametrize("case", CASES)
def test_exact_and_heyoka_agree_with_dop853(case, method):
    """The exact flow (its step is the flow: round-off) and heyoka (rtol 1e-15) equal DOP853 on the whole grid to
    1e-11 (the reference's own global error ~1e-13; a wrong weight, rotation or structure constant is >= 1e-4 here),
    and keep every integral to 1e-12 (both claim it: exact by construction, heyoka at its tolerance)."""
    if method == "heyoka":
        pytest.importorskip("heyoka")
    H, X, dt = _case(case)
    ref = _reference(H, X, (0.0, T), dt)
    tr = jg.solve(H, X, (0.0, T), dt=dt, method=method, rtol=1e-15)
    assert tr.X.shape == ref.X.shape and np.array_equal(tr.t, ref.t)
    assert np.abs(tr.X[-1] - X).max() > 1e-3  # it moved
    assert np.abs(tr.X - ref.X).max() < 1e-11
    assert tr.drift.max() < 1e-12


@pytest.mark.parametrize("method", ["midpoint", "kahan"])
@pytest.mark.parametrize("case", CASES)
def test_midpoint_and_kahan_are_of_order_2_on_every_model(case, method):
    """Both rules are of order 2 on every model: halving dt divides the end-point error against DOP853 by 4 (within
    [3.5, 4.5]: the ratio of two O(dt²) errors at dt = 0.02, 0.01 differs from 4 by O(dt)), and the error is below
    1e-3 (a wrong structure constant or gradient gives an O(1) error that does not shrink).  The midpoint rule keeps
    every integral (all quadratic here, Cooper's theorem) to 1e-12 (Newton stops at round-off) -- its declared
    property; Kahan's map does not claim it."""
    H, X, _ = _case(case)
    ref = _reference(H, X, (0.0, T), 0.1).X[-1]
    errs = []
    for dt in (0.02, 0.01):
        tr = jg.solve(H, X, (0.0, T), dt=dt, method=method)
        errs.append(np.abs(tr.X[-1] - ref).max())
        if method == "midpoint":
            assert tr.drift.max() < 1e-12
    assert errs[0] < 1e-3
    assert 3.5 < errs[0] / errs[1] < 4.5, errs


@pytest.mark.parametrize("case", ["rational chain", "trigonometric chain"])
def test_bt_of_a_chain_with_one_map_is_its_exact_step(case):
    """Where the chain's exact step is one two-point map and a rotation (k = 1: two sites of order 1), "bt" is that
    map: the trajectory equals the exact one bit for bit, and DOP853 to 1e-11."""
    H, X, dt = _case(case)
    assert chain_maps_per_step(H) == 1
    bt = jg.solve(H, X, (0.0, T), dt=dt, method="bt")
    assert np.array_equal(bt.X, jg.solve(H, X, (0.0, T), dt=dt, method="exact").X)
    assert np.abs(bt.X - _reference(H, X, (0.0, T), dt).X).max() < 1e-11


@pytest.mark.parametrize("case, k", [("elliptic chain", 3), ("Clebsch top", 2)])
def test_bt_is_refused_where_no_matched_map_exists(case, k):
    H, X, dt = _case(case)
    with pytest.raises(jg.InvalidParameterError, match=rf"'bt'.*no matched two-point map.*k = {k}.*'exact'"):
        jg.solve(H, X, (0.0, T), dt=dt, method="bt")
    magnet = jg.gaudin_magnet(1.0, [0.0, 1.0, 2.5])  # three rational sites: k = 2
    with pytest.raises(jg.InvalidParameterError, match="k = 2"):
        jg.solve(magnet.hamiltonian(np.ones(6)), np.full(9, 0.3), (0.0, 0.1), dt=0.05, method="bt")


def test_bt_of_the_top_keeps_its_integrals():
    """The top's matched map (one map per step; for N = 3 the exact flow of a modified Hamiltonian) keeps every
    integral to 1e-13 (a Bäcklund map: round-off)."""
    H, X, dt = _case("twisted top")
    tr = jg.solve(H, X, (0.0, T), dt=dt, method="bt")
    assert tr.drift.max() < 1e-13 and np.abs(tr.X[-1] - X).max() > 1e-3


def test_midpoint_on_an_su3_chain():
    """The su(3) chain's field is cubic (h^(3)): the Jacobian is by central differences, the rule still of order 2
    (ratio in [3.5, 4.5]), it keeps the quadratic integrals h_(i,m) to 1e-12 (Cooper) and declares
    preserves_integrals = False (the cubic t3_h are not kept: their drift is above 1e-9 here)."""
    m = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
    H = m.hamiltonian(np.linspace(0.2, 1.0, 10))
    X = 0.5 * np.random.default_rng(0).normal(size=m.n_state)
    ref = _reference(H, X, (0.0, 0.5), 0.5).X[-1]
    quad = np.array([not lb.startswith("t3_") for lb in m.integral_labels()])
    errs = []
    for dt in (0.05, 0.025):
        tr = jg.solve(H, X, (0.0, 0.5), dt=dt, method="midpoint")
        errs.append(np.abs(tr.X[-1] - ref).max())
        assert tr.drift[quad].max() < 1e-12
        assert tr.drift[~quad].max() > 1e-9
    assert 3.5 < errs[0] / errs[1] < 4.5, errs
    assert not jg.midpoint.ImplicitMidpoint(H, 0.1).properties.preserves_integrals
    assert jg.midpoint.ImplicitMidpoint(_case("Clebsch top")[0], 0.1).properties.preserves_integrals


def test_a_chains_midpoint_map_travels_with_its_description():
    H, X, dt = _case("trigonometric chain")
    mp = jg.midpoint.ImplicitMidpoint(H, dt)
    again = jg.map_from_description(mp.describe())
    assert again.describe() == mp.describe() and np.array_equal(again(X), mp(X))


def test_heyoka_compiles_once_per_chain_hamiltonian(monkeypatch):
    """The compiled heyoka integrator is cached per Hamiltonian (its equations' coefficients) for chains as for the
    top: a second solve of the same chain Hamiltonian builds no new integrator."""
    hy = pytest.importorskip("heyoka")
    H, X, dt = _case("Clebsch top")
    first = jg.solve(H, X, (0.0, T), dt=dt, method="heyoka")
    built = []
    real = hy.taylor_adaptive
    monkeypatch.setattr(hy, "taylor_adaptive", lambda *a, **k: built.append(1) or real(*a, **k))
    again = jg.solve(H, X, (0.0, T), dt=dt, method="heyoka")
    assert built == [] and np.array_equal(first.X, again.X)
    jg.solve(H.model.hamiltonian(H.weights * 2), X, (0.0, T), dt=dt, method="heyoka")  # another H: compiled
    assert built == [1]


def test_a_hamiltonian_of_no_model_is_refused():
    for H in ("physical", np.ones(4), object()):
        with pytest.raises(jg.InvalidParameterError, match="H must be a Hamiltonian of a model"):
            jg.solve(H, X6, (0.0, 0.1), dt=0.05)


def test_exact_dense_output_of_a_chain_batch():
    """The exact dense output (one exact step from the nearest grid state) now serves a chain's batch as the top's:
    each orbit's ``at(t)`` equals DOP853 at ``t`` to 1e-11 (the exact step is the flow: round-off)."""
    H, X, dt = _case("Clebsch top")
    Xb = np.stack([X, X * 0.9])
    tr = jg.solve(H, Xb, (0.0, T), dt=dt)
    t = np.array([0.013, 0.121])
    got = tr.at(t)
    for k in range(2):
        ref = jg.solve(H, Xb[k], (0.0, T), method="dop853", rtol=1e-13, atol=1e-13, t_eval=t).X
        assert np.abs(got[:, k] - ref).max() < 1e-11


def test_the_protocol_check_remembered_per_type_still_refuses_other_types():
    """``methods._is_hamiltonian`` remembers the types that passed the runtime protocol check (issue 33: the check
    cost 11 µs, twice per solve): after a top and a chain were solved, objects of other types are still refused
    and only Hamiltonian types are remembered."""
    from jetgaudin import methods

    H, X, dt = _case("Clebsch top")
    jg.solve(H, X, (0.0, 0.1), dt=0.05)
    jg.solve(jg.physical_hamiltonian(3, 1.0), [-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0], (0.0, 0.1), dt=0.05)
    assert {jg.IntegralHamiltonian, type(H)} <= methods._HAMILTONIAN_TYPES
    for bad in (object(), np.ones(4), "physical"):
        with pytest.raises(jg.InvalidParameterError, match="H must be a Hamiltonian of a model"):
            jg.solve(bad, X6, (0.0, 0.1), dt=0.05)
        assert type(bad) not in methods._HAMILTONIAN_TYPES


@pytest.mark.parametrize("family", ["rational", "trigonometric", "elliptic"])
def test_a_chains_recorded_integrals_are_its_integrals(family):
    """``ChainHamiltonian.record_integrals`` (one compiled pass for every family, issue 33) equals ``model.integrals``
    on rows ``(T, 3M)`` and batches ``(T, B, 3M)``, to ``n ε Σ|terms|`` per entry (``n = 3M² + 2M + 2`` additions in
    another order than ``np.einsum``'s; ``Σ|terms|`` the same sums of absolute values; the elliptic ``c0`` is one more
    form), at unit size and at 1e3."""
    sites = [(0.0, 1), (1.0, 2), (2.5, 1)]
    kw = {"trigonometric": {"gamma": 0.5}, "elliptic": {"modulus": 0.6}}.get(family, {})
    b = 0.0 if family == "elliptic" else 0.8  # the elliptic family has no field
    model = jg.GaudinModel(b, sites, family=family, **kw)
    H = model.hamiltonian(np.linspace(0.2, 1.0, model.integrals(np.ones(3 * model.M)).shape[-1]))
    rng = np.random.default_rng(3)
    for scale in (1.0, 1e3):
        for shape in ((50, 3 * model.M), (7, 4, 3 * model.M)):
            X = rng.normal(size=shape) * scale
            got, ref = H.record_integrals(X), model.integrals(X)
            assert got.shape == ref.shape
            q, lin = model._forms
            q3 = np.broadcast_to(q, (3,) + q.shape) if q.ndim == 3 else q
            y = np.abs(X.reshape(X.shape[:-1] + (model.M, 3)))
            terms = np.einsum("aIcd,...ca,...da->...I", np.abs(q3), y, y) + 2 * b * np.einsum(
                "Ic,...c->...I", np.abs(lin), y[..., 2])
            if ref.shape[-1] > terms.shape[-1]:  # the linear extras
                forms = np.abs(model.family.extra_integrals(model.sites)[1])
                terms = np.concatenate([terms, np.einsum("Ei,...i->...E", forms, np.abs(X))], axis=-1)
            n = 3 * model.M ** 2 + 2 * model.M + 2
            assert np.all(np.abs(got - ref) <= n * 2.3e-16 * terms)
