"""One class per kind of map, for every system (issue 33, "What to build" 1; ``jetgaudin._system_maps``).

``TwoPointBacklund(b, η)`` (the top of any N) and ``TwoPointBacklund(model, η)`` (a chain) are one class, and
``ChainTwoPointBacklund`` is that class under its old name; likewise the one-point map.  The route table hands every
call to the implementation that ran before (``backlund.maps._TopTwoPoint``, ``gaudin.maps._ChainTwoPoint``, …), so
the orbits are the old ones bit for bit; ``kind``, ``describe()`` and the map registry answer as before for each
system, so old ``run.json`` descriptions load into the new class.
"""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import Backend, Branch, InvalidParameterError
from jetgaudin.backlund.closed_form import two_point_closed_form
from jetgaudin.backlund.maps import _TopOnePoint, _TopTwoPoint
from jetgaudin.gaudin._one_point import _ChainOnePoint
from jetgaudin.gaudin.maps import _ChainTwoPoint
from jetgaudin.maps import map_from_description, with_resolved_backend

X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])  # Appendix 2's state (N = 3)
ETA = 5 + 0.1j
TOP3 = jg.GaudinModel(1.0, [(0, 3)])  # the top of order 3 as a one-site model
CHAIN = jg.GaudinModel(0.7, [(0.0, 2), (1.5, 1)])  # a rational chain of two sites
XC = np.array([0.3, -0.2, 0.5, 0.1, 0.4, -0.3, -0.6, 0.2, 0.8])  # a state of CHAIN (3M = 9)
TRIG = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 1)], family="trigonometric", gamma=0.7)
XT = np.array([0.3, -0.2, 0.5, 0.1, 0.4, -0.3])


def test_both_systems_build_the_one_class_and_the_old_names_are_it():
    top, chain = jg.TwoPointBacklund(1.0, ETA), jg.TwoPointBacklund(CHAIN, ETA)
    assert type(top) is type(chain) is jg.TwoPointBacklund
    assert jg.ChainTwoPointBacklund is jg.TwoPointBacklund and jg.ChainOnePointBacklund is jg.OnePointBacklund
    assert jg.gaudin.ChainTwoPointBacklund is jg.TwoPointBacklund is jg.backlund.TwoPointBacklund
    # isinstance both ways, for both systems
    for m in (top, chain, jg.ChainTwoPointBacklund(TOP3, ETA)):
        assert isinstance(m, jg.TwoPointBacklund) and isinstance(m, jg.ChainTwoPointBacklund)
        assert isinstance(m, jg.Map)
    for m in (jg.OnePointBacklund(1.0, 2 + 0.3j), jg.ChainOnePointBacklund(CHAIN, 3 + 0.2j)):
        assert isinstance(m, jg.OnePointBacklund) and isinstance(m, jg.ChainOnePointBacklund)


def test_old_signatures_and_keywords_keep_working():
    # the chain's old positional signature (model, eta, branch, backend, kernel), as GaudinModel.two_point_backlund
    m = jg.ChainTwoPointBacklund(CHAIN, ETA, Branch.OPPOSITE, Backend.NUMPY, None)
    assert m.branch is Branch.OPPOSITE and m.backend is Backend.NUMPY and m.model == CHAIN
    assert CHAIN.two_point_backlund(ETA, branch="opposite") == m
    assert jg.ChainTwoPointBacklund(CHAIN, ETA, kernel="numpy").backend is Backend.NUMPY  # the alias
    assert jg.ChainOnePointBacklund(CHAIN, 3 + 0.2j, "default", True, "numpy", None).inverse_map is True
    # the old keyword names of the system
    assert jg.TwoPointBacklund(b=1.0, eta=ETA) == jg.TwoPointBacklund(1.0, ETA)
    assert jg.ChainTwoPointBacklund(model=CHAIN, eta=ETA) == jg.TwoPointBacklund(CHAIN, ETA)
    assert jg.OnePointBacklund(b=1.0, eta=2 + 0.3j, inverse_map=True).inverse_map is True
    # the top's old iterate keywords nu1= / return_nu=
    orbit, nu = jg.TwoPointBacklund(1.0, ETA).iterate(X0, 5, return_nu=True, backend="numpy")
    again = jg.TwoPointBacklund(1.0, ETA).iterate(orbit[-1], 5, nu1=nu, backend="numpy")
    whole = jg.TwoPointBacklund(1.0, ETA).iterate(X0, 10, backend="numpy")
    assert np.array_equal(again[-1], whole[-1])  # a split run is the unsplit one bit for bit (the carry rule)


def test_every_system_answers_b_model_kind_as_before():
    top, chain, one_top, one_chain = (jg.TwoPointBacklund(1.5, ETA), jg.TwoPointBacklund(CHAIN, ETA),
                                      jg.OnePointBacklund(1.5, 2 + 0.3j), jg.OnePointBacklund(CHAIN, 3 + 0.2j))
    assert (top.kind, chain.kind, one_top.kind, one_chain.kind) == (
        "two_point", "chain_two_point", "one_point", "chain_one_point")
    assert top.b == 1.5 and top.model is None and not top.is_chain
    assert chain.b == 0.7 and chain.model is CHAIN and chain.is_chain
    assert one_top.model is None and one_chain.model is CHAIN
    assert top.n_state is None and chain.n_state == 9  # the top of any N; a chain's state length
    # one system's own methods stay reachable: the top's nu1 / parameters, a chain's names and dressing matrix
    assert np.isfinite(top.nu1(X0)) and len(top.parameters(X0)) == 3
    assert chain.integral_names() == CHAIN.integral_labels() and chain.dressing_matrix(XC, 0.3).shape == (2, 2)
    with pytest.raises(AttributeError, match="integral_names"):
        top.integral_names()
    assert not hasattr(top, "route_notice") and hasattr(chain, "route_notice")  # the run layer's probes


def _old_impl(m):
    """The implementation the old class was (the route table's entry), built directly."""
    if m.kind == "two_point":
        return _TopTwoPoint(m.b, m.eta, m.branch, m.backend)
    if m.kind == "chain_two_point":
        return _ChainTwoPoint(m.model, m.eta, m.branch, m.backend)
    if m.kind == "one_point":
        return _TopOnePoint(m.b, m.eta, m.branch, m.inverse_map, m.backend)
    return _ChainOnePoint(m.model, m.eta, m.branch, m.inverse_map, m.backend)


@pytest.mark.parametrize("make, X", [
    (lambda: jg.TwoPointBacklund(1.0, ETA, backend="numpy"), X0),
    (lambda: jg.TwoPointBacklund(1.0, ETA, "opposite", backend="numpy"), X0),
    (lambda: jg.TwoPointBacklund(1.0, ETA, backend="compiled"), X0),
    (lambda: jg.TwoPointBacklund(TOP3, ETA, backend="numpy"), X0),
    (lambda: jg.TwoPointBacklund(TOP3, ETA, backend="compiled"), X0),  # the top's kernels (route table)
    (lambda: jg.TwoPointBacklund(CHAIN, 0.8 + 0.15j, backend="numpy"), XC),
    (lambda: jg.TwoPointBacklund(CHAIN, 0.8 + 0.15j, backend="compiled"), XC),
    (lambda: jg.TwoPointBacklund(TRIG, 0.4 + 0.1j, backend="numpy"), XT),
    (lambda: jg.OnePointBacklund(1.0, 2 + 0.3j), X0),
    (lambda: jg.OnePointBacklund(CHAIN, 3 + 0.2j, inverse_map=True), XC),
])
def test_orbits_are_the_old_implementations_bit_for_bit(make, X):
    m = make()
    old = _old_impl(m)
    assert type(old) is not type(m)
    batch = np.stack([X, X * 0.97])
    for x in (X, batch):
        new_orbit, new_carry = m.iterate(x, 25, save_every=5, return_carry=True)
        old_orbit, old_carry = old.iterate(x, 25, save_every=5, return_carry=True)
        assert np.array_equal(new_orbit, old_orbit) and np.array_equal(new_carry, old_carry)  # bits, not tolerance
        a, b = m.advance(x, None, 7, 2), old.advance(x, None, 7, 2)
        assert np.array_equal(a.rows, b.rows) and np.array_equal(a.X, b.X) and np.array_equal(a.carry, b.carry)
        s, t = m.step(x), old.step(x)
        assert all(np.array_equal(p, q) for p, q in zip(s, t, strict=True))
        flip = -old.start(x)  # a carry on the other sheet: the step continues from it (not the branch rule)
        s, t = m.step(x, flip), old.step(x, flip)
        assert all(np.array_equal(p, q) for p, q in zip(s, t, strict=True))
        assert np.all((np.conj(s[1]) * m.start(x)).real < 0)  # it did continue on the other sheet
        assert np.array_equal(m.integrals(x), old.integrals(x)) and np.array_equal(m.start(x), old.start(x))
    assert m.describe() == old.describe()
    inv = m.inverse()
    assert type(inv) is type(m) and inv.describe() == old.inverse().describe()


def test_the_top_map_against_the_closed_form_of_appendix_1():
    """An independent formula: the closed form ``X̆ = Φ(s, t; η) X + X0`` of Appendix 1 (corrected) from the map's
    ``(s, t)``, for both systems of the top (the field b and the one-site model) on the NumPy route."""
    for m in (jg.TwoPointBacklund(1.0, ETA, backend="numpy"), jg.TwoPointBacklund(TOP3, ETA, backend="numpy")):
        orbit = m.iterate(X0, 20)
        for x, y in zip(orbit[:-1], orbit[1:], strict=True):
            s, t, _ = jg.TwoPointBacklund(1.0, ETA).parameters(x)
            ref = two_point_closed_form(x, 1.0, ETA, s, t)
            # 1e-13 relative to |X| ~ 3: a different sequence of ~100 roundings of O(1) numbers (eps 2.2e-16)
            assert np.max(np.abs(y - ref)) <= 1e-13 * (1 + np.max(np.abs(x)))


OLD_DESCRIPTIONS = [  # as older versions wrote them in run.json (some without "backend", the key added later)
    {"kind": "two_point", "b": 1.0, "eta": [5.0, 0.1], "branch": "default", "backend": "auto"},
    {"kind": "two_point", "b": 1.0, "eta": [5.0, 0.1], "branch": "opposite"},
    {"kind": "one_point", "b": 1.0, "eta": [2.0, 0.3], "branch": "default", "inverse": True, "backend": "auto"},
    {"kind": "chain_two_point", "b": 0.7, "sites": [[0.0, 2], [1.5, 1]], "eta": [0.8, 0.15], "branch": "default",
     "backend": "compiled"},
    {"kind": "chain_two_point", "b": 1.0, "sites": [[0.0, 3]], "eta": [5.0, 0.1], "branch": "default"},
    {"kind": "chain_one_point", "b": 0.7, "sites": [[0.0, 2], [1.5, 1]], "eta": [3.0, 0.2], "branch": "default",
     "inverse_map": False},
]


@pytest.mark.parametrize("d", OLD_DESCRIPTIONS, ids=lambda d: d["kind"])
def test_old_descriptions_load_into_the_one_class_and_round_trip(d):
    m = map_from_description(dict(d))
    assert isinstance(m, jg.TwoPointBacklund | jg.OnePointBacklund) and m.kind == d["kind"]
    assert m.is_chain == d["kind"].startswith("chain_")
    out = m.describe()
    assert {k: v for k, v in out.items() if k in d} == d  # every key written before, with its value
    assert map_from_description(out) == m and map_from_description(out).describe() == out


def test_new_constructions_describe_as_the_old_classes_did():
    assert jg.TwoPointBacklund(1.0, ETA).describe() == OLD_DESCRIPTIONS[0]
    assert jg.TwoPointBacklund(TOP3, ETA).describe() == {**OLD_DESCRIPTIONS[4], "backend": "auto"}
    assert jg.OnePointBacklund(CHAIN, 3 + 0.2j).describe() == OLD_DESCRIPTIONS[5]


@pytest.mark.parametrize("m", [jg.TwoPointBacklund(1.0, ETA, backend="numpy"),
                               jg.TwoPointBacklund(CHAIN, 0.8 + 0.15j, "opposite", "compiled"),
                               jg.OnePointBacklund(1.0, 2 + 0.3j, inverse_map=True),
                               jg.OnePointBacklund(CHAIN, 3 + 0.2j)], ids=lambda m: m.kind)
def test_pickle_copy_replace_equality_hash(m):
    X = X0 if m.model is None else XC
    for other in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m), dataclasses.replace(m)):
        assert type(other) is type(m) and other == m and hash(other) == hash(m) and repr(other) == repr(m)
        assert other.backend is m.backend and other.kind == m.kind
        assert np.array_equal(other.iterate(X, 6), m.iterate(X, 6))
    other_branch = Branch.OPPOSITE if m.branch is Branch.DEFAULT else Branch.DEFAULT
    flipped = {"branch": other_branch} if m.kind.endswith("two_point") else {"inverse_map": not m.inverse_map}
    assert dataclasses.replace(m, **flipped) == m.inverse()
    assert m == m.with_backend("numpy")  # the backend is a route, not a parameter of the map
    assert len({m, pickle.loads(pickle.dumps(m))}) == 1


def test_equality_tells_the_systems_apart():
    top, one_site = jg.TwoPointBacklund(1.0, ETA), jg.TwoPointBacklund(TOP3, ETA)
    assert top != one_site and one_site != top  # the top of any N is not the model of one order
    assert top != jg.TwoPointBacklund(2.0, ETA) and top != jg.TwoPointBacklund(1.0, ETA, "opposite")
    assert one_site != jg.TwoPointBacklund(jg.GaudinModel(1.0, [(0, 2)]), ETA)
    assert jg.TwoPointBacklund(1.0, ETA) != jg.OnePointBacklund(1.0, ETA)


def test_reprs_name_the_system():
    assert repr(jg.TwoPointBacklund(1.0, ETA)).startswith("TwoPointBacklund(b=1.0, eta=(5+0.1j), branch=")
    r = repr(jg.TwoPointBacklund(CHAIN, ETA))
    assert r.startswith("TwoPointBacklund(model=GaudinModel(") and "_Chain" not in r
    assert repr(jg.OnePointBacklund(CHAIN, 3 + 0.2j, inverse_map=True)).startswith("OnePointBacklund(model=")


@pytest.mark.parametrize("cls", [jg.TwoPointBacklund, jg.OnePointBacklund])
@pytest.mark.parametrize("bad", ["1.0", None, [1.0], jg.IntegralHamiltonian(1.0, [1, 0, 0, 0, 0, 0]), 1 + 2j])
def test_a_wrong_system_is_one_typed_error_naming_what_is_accepted(cls, bad):
    with pytest.raises(InvalidParameterError, match="field strength b .*GaudinModel") as e:
        cls(bad, ETA)
    assert cls.__name__ in str(e.value)


def test_other_refusals_stay_the_system_s_own_and_name_the_public_class():
    with pytest.raises(InvalidParameterError, match="nonzero"):
        jg.TwoPointBacklund(0.0, ETA)  # the top's message about b
    with pytest.raises(InvalidParameterError, match="Im"):
        jg.TwoPointBacklund(CHAIN, 0.8)  # the chain's message about Im eta
    with pytest.raises(InvalidParameterError, match="is a site"):
        jg.TwoPointBacklund(CHAIN, 1.5 + 0.1j)
    with pytest.raises(InvalidParameterError, match=r"^OnePointBacklund has no compiled route"):
        jg.OnePointBacklund(1.0, ETA, backend="compiled")
    with pytest.raises(InvalidParameterError, match="su\\(3\\)"):
        jg.TwoPointBacklund(jg.GaudinModel(1.0, [(0, 1)], algebra="su(3)"), ETA)
    with pytest.raises(InvalidParameterError, match="once"):
        jg.TwoPointBacklund(1.0, ETA, b=1.0)
    with pytest.raises(InvalidParameterError, match="model= must be a GaudinModel"):
        jg.TwoPointBacklund(model=1.0, eta=ETA)
    with pytest.raises(TypeError, match="eta"):
        jg.TwoPointBacklund(1.0)


def test_a_route_set_on_a_copy_is_the_route_taken():
    """The run layer records AUTO's choice by setting the ``backend`` field on a copy
    (:func:`jetgaudin.maps.with_resolved_backend`); the copy must run on that route, not the original's."""
    for m, X in ((jg.TwoPointBacklund(1.0, ETA, backend="compiled"), X0),
                 (jg.TwoPointBacklund(CHAIN, 0.8 + 0.15j, backend="compiled"), XC)):
        c = with_resolved_backend(m, Backend.NUMPY)
        assert c.resolved_backend(X, 10**7) is Backend.NUMPY and m.resolved_backend(X, 10**7) is Backend.COMPILED
        numpy_route = _old_impl(m).with_backend(Backend.NUMPY).advance(X, None, 30)
        compiled_route = _old_impl(m).advance(X, None, 30)
        assert not np.array_equal(numpy_route.X, compiled_route.X)  # the two routes differ in the last bits
        got = c.advance(X, None, 30)
        assert np.array_equal(got.X, numpy_route.X) and np.array_equal(got.imag_max, numpy_route.imag_max)


# -- the exact flow: one class for the top's IntegralHamiltonian and every chain's Hamiltonian ----------------------
H_TOP = jg.physical_hamiltonian(3, 1.0)
H_CHAIN = CHAIN.hamiltonian([0.0, 1.0, 0.0, 0.5, 0.0, 0.0])


def test_exact_flow_is_one_class_for_both_systems():
    top, chain = jg.ExactFlow(H_TOP, 0.05), jg.ExactFlow(H_CHAIN, 0.02)
    assert jg.ChainExactFlow is jg.ExactFlow and type(top) is type(chain) is jg.ExactFlow
    assert isinstance(jg.ChainExactFlow(H_CHAIN, 0.02), jg.ExactFlow) and isinstance(top, jg.ChainExactFlow)
    assert (top.kind, chain.kind) == ("exact", "chain_exact")
    assert top.model is None and top.b == 1.0 and chain.model is CHAIN and chain.b == 0.7
    assert top.n_state == 9 and chain.n_state == 9 and top.time_step == 0.05 and chain.time_step == 0.02
    assert top.chunk_invariant is False and chain.chunk_invariant is False  # the run layer's fixed chunks
    assert repr(top).startswith("ExactFlow(H=IntegralHamiltonian(b=1.0")
    assert repr(chain).startswith("ExactFlow(H=IntegralHamiltonian(model=")
    # the old signatures: the top's positional (H, dt, substeps, backend, rho_factor), the chain's keywords
    old = jg.ExactFlow(H_TOP, 0.05, 2, "numpy", 1.7)
    assert (old.substeps, old.backend, old.rho_factor) == (2, Backend.NUMPY, 1.7)
    c = jg.ChainExactFlow(H_CHAIN, 0.02, rho_factor=1.8, substeps=3)
    assert (c.rho_factor, c.substeps) == (1.8, 3) and c.describe()["rho_factor"] == 1.8


def _old_exact(m):
    from jetgaudin.exact import _TopExactFlow
    from jetgaudin.exact_chain import _ChainExactFlow

    if m.kind == "exact":
        return _TopExactFlow(m.H, m.dt, m.substeps, m.backend, m.rho_factor)
    return _ChainExactFlow(m.H, m.dt, m.rho_factor, m.substeps)


@pytest.mark.parametrize("make, X", [
    (lambda: jg.ExactFlow(H_TOP, 0.05, backend="numpy"), X0),
    (lambda: jg.ExactFlow(H_TOP, -0.05, 2, backend="compiled"), X0),
    (lambda: jg.ExactFlow(H_CHAIN, 0.02), XC),
])
def test_exact_orbits_are_the_old_implementations_bit_for_bit(make, X):
    m = make()
    old = _old_exact(m)
    for x in (X, np.stack([X, X * 0.97])):
        assert np.array_equal(m.iterate(x, 6, save_every=2), old.iterate(x, 6, save_every=2))
        a, b = m.advance(x, None, 4, 1), old.advance(x, None, 4, 1)
        assert np.array_equal(a.rows, b.rows) and np.array_equal(a.X, b.X)
        assert np.array_equal(m.step(x)[0], old.step(x)[0]) and np.array_equal(m.integrals(x), old.integrals(x))
        assert np.array_equal(m.max_dt(x), old.max_dt(x))
    assert m.describe() == old.describe() and m.inverse().describe() == old.inverse().describe()
    assert type(m.inverse()) is jg.ExactFlow


@pytest.mark.parametrize("d", [
    {"kind": "exact", "b": 1.0, "weights": [0.0, 0.5, 0.0, 0.0, 0.0, 0.0], "dt": 0.05, "substeps": 1,
     "backend": "auto", "rho_factor": 1.5},
    {"kind": "exact", "b": 1.0, "weights": [0.0, 0.5, 0.0, 0.0, 0.0, 0.0], "dt": 0.05},  # the oldest keys only
    {"kind": "chain_exact", "b": 0.7, "sites": [[0.0, 2], [1.5, 1]], "weights": [0.0, 1.0, 0.0, 0.5, 0.0, 0.0],
     "dt": 0.02, "rho_factor": 1.5, "substeps": 1},
], ids=lambda d: d["kind"])
def test_old_exact_descriptions_load_into_the_one_class(d):
    m = map_from_description(dict(d))
    assert type(m) is jg.ExactFlow and m.kind == d["kind"]
    out = m.describe()
    assert {k: v for k, v in out.items() if k in d} == d
    X = X0 if m.kind == "exact" else XC
    again = map_from_description(out)
    assert again.describe() == out and np.array_equal(again.iterate(X, 3), m.iterate(X, 3))


def test_matched_backlund_stays_its_own_kind():
    from jetgaudin.exact import MatchedBacklund

    mb = MatchedBacklund(H_TOP, 0.05)
    assert mb.describe()["kind"] == "matched_backlund" and type(map_from_description(mb.describe())) is MatchedBacklund
    with pytest.raises(InvalidParameterError, match="^MatchedBacklund matches the weights"):  # its own name
        MatchedBacklund(jg.IntegralHamiltonian(1.0, [1.0, 0, 0, 0, 0, 0]), 0.1)


@pytest.mark.parametrize("m", [jg.ExactFlow(H_TOP, 0.05, backend="numpy"), jg.ExactFlow(H_CHAIN, 0.02)],
                         ids=["top", "chain"])
def test_exact_pickle_copy_and_identity_equality(m):
    X = X0 if m.model is None else XC
    for other in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        assert type(other) is jg.ExactFlow and other.describe() == m.describe() and repr(other) == repr(m)
        assert np.array_equal(other.iterate(X, 3), m.iterate(X, 3))
        assert other != m  # as before: an exact flow is equal to itself only (it holds H's weight array)
    assert m == m and len({m, m}) == 1


def test_exact_refusals_name_what_is_accepted():
    for bad in (1.0, CHAIN, None):
        with pytest.raises(InvalidParameterError, match="IntegralHamiltonian .*model.hamiltonian"):
            jg.ExactFlow(bad, 0.1)
    with pytest.raises(InvalidParameterError, match="no GPU route: give backend="):  # a chain's routes: numpy, compiled
        jg.ExactFlow(H_CHAIN, 0.02, backend="gpu")
    with pytest.raises(InvalidParameterError, match="dt must be nonzero"):
        jg.ExactFlow(H_CHAIN, 0.0)
    with pytest.raises(InvalidParameterError, match="^ExactFlow matches the weights"):
        jg.ExactFlow(jg.IntegralHamiltonian(1.0, [1.0, 0, 0, 0, 0, 0]), 0.1)


# -- one Hamiltonian type: IntegralHamiltonian for the top (a field b) and every su(2) chain (a GaudinModel) ---------
W_TOP = np.array([0.2, 0.5, -0.3, 0.1, 0.0, 0.4])
W_CHAIN = np.array([0.0, 1.0, 0.0, 0.5, 0.0, 0.0])


def test_one_hamiltonian_type_for_both_systems():
    from jetgaudin.hamiltonians import SolveHamiltonian

    top, chain = jg.IntegralHamiltonian(1.0, W_TOP), CHAIN.hamiltonian(W_CHAIN)
    assert jg.ChainHamiltonian is jg.IntegralHamiltonian and type(top) is type(chain) is jg.IntegralHamiltonian
    assert isinstance(top, jg.ChainHamiltonian) and isinstance(chain, jg.IntegralHamiltonian)
    assert isinstance(top, SolveHamiltonian) and isinstance(chain, SolveHamiltonian)
    assert (top.route_kind, chain.route_kind) == ("top", "chain")  # their rows of solve's route table
    assert top.b == 1.0 and top.model is None and top.c is None and top.N == 3 and top.n_state == 9
    assert chain.b == 0.7 and chain.model is CHAIN and chain.c is None and chain.n_state == 9
    assert chain.structure_constants.shape == (9, 9, 9) and not hasattr(top, "structure_constants")
    # every construction of a chain's Hamiltonian is the one type, with the same weights
    for H in (jg.IntegralHamiltonian(CHAIN, W_CHAIN), jg.ChainHamiltonian(CHAIN, W_CHAIN),
              jg.ChainHamiltonian(model=CHAIN, weights=W_CHAIN)):
        assert type(H) is jg.IntegralHamiltonian and H.model is CHAIN and np.array_equal(H.weights, W_CHAIN)
    assert jg.IntegralHamiltonian(b=1.0, weights=W_TOP).route_kind == "top"
    # the views both ways stay the one type
    assert TOP3.hamiltonian(W_TOP).as_top().route_kind == "top" and top.as_model().route_kind == "chain"
    assert repr(top).startswith("IntegralHamiltonian(b=1.0, weights=array(")
    assert repr(chain).startswith("IntegralHamiltonian(model=GaudinModel(")


@pytest.mark.parametrize("H, impl, X", [
    (jg.IntegralHamiltonian(1.0, W_TOP), ("jetgaudin.hamiltonians", "_TopHamiltonian", (1.0, W_TOP)), X0),
    (jg.IntegralHamiltonian([0.1, -0.2, 1.0], W_TOP, [0.3, 0.2]),
     ("jetgaudin.hamiltonians", "_TopHamiltonian", ([0.1, -0.2, 1.0], W_TOP, [0.3, 0.2])), X0),
    (CHAIN.hamiltonian(W_CHAIN), ("jetgaudin.gaudin.hamiltonian", "_ChainHamiltonian", (CHAIN, W_CHAIN)), XC),
    (TRIG.hamiltonian([0.3, 0.0, 1.0, 0.0, 0.2]),
     ("jetgaudin.gaudin.hamiltonian", "_ChainHamiltonian", (TRIG, [0.3, 0.0, 1.0, 0.0, 0.2])), XT),
], ids=["top", "top-vector-field-c", "chain", "trigonometric"])
def test_hamiltonian_values_are_the_old_implementations_bit_for_bit(H, impl, X):
    import importlib

    module, name, args = impl
    old = getattr(importlib.import_module(module), name)(*args)
    assert type(old) is not jg.IntegralHamiltonian
    batch = np.stack([X, 0.9 * X])
    for f in ("__call__", "gradient", "vector_field", "record_integrals", "check_state"):
        assert np.array_equal(getattr(H, f)(batch), getattr(old, f)(batch)), f
    assert H.n_state == old.n_state and H.route_kind == old.route_kind and np.array_equal(H.weights, old.weights)
    assert H.b == old.b and H.c == getattr(old, "c", None)  # the parameters as given (the top's c, its b as a vector)
    again = pickle.loads(pickle.dumps(H))
    assert type(again) is jg.IntegralHamiltonian and np.array_equal(again.vector_field(X), H.vector_field(X))
    assert repr(again) == repr(H)


def test_hamiltonian_refusals_name_what_is_accepted():
    for bad in ("1.0", None, jg.TwoPointBacklund(1.0, ETA)):
        with pytest.raises(InvalidParameterError, match="field b .*GaudinModel"):
            jg.IntegralHamiltonian(bad, W_TOP)
    with pytest.raises(InvalidParameterError, match="c .*is the top's"):
        jg.IntegralHamiltonian(CHAIN, W_CHAIN, [0.1, 0.2])
    with pytest.raises(InvalidParameterError, match="b= must be a field"):
        jg.IntegralHamiltonian(b=CHAIN, weights=W_CHAIN)
    with pytest.raises(InvalidParameterError, match="once"):
        jg.IntegralHamiltonian(1.0, W_TOP, b=1.0)
    with pytest.raises(InvalidParameterError, match="trailing axis of length 6"):
        jg.IntegralHamiltonian(CHAIN, W_CHAIN[:4])  # the chain's own message
    with pytest.raises(InvalidParameterError, match="trailing axis of length 2N"):
        jg.IntegralHamiltonian(1.0, W_TOP[:5])  # the top's own message


def test_maps_of_one_system_refuse_the_other_system_s_hamiltonian():
    """The one type's system decides (``route_kind``), where the code asked ``isinstance`` before."""
    from jetgaudin.exact import exact_parameters
    from jetgaudin.gaudin.flow import ChainFlowMap

    top, chain = jg.physical_hamiltonian(3, 1.0), CHAIN.hamiltonian(W_CHAIN)
    with pytest.raises(InvalidParameterError, match="ChainHamiltonian"):
        ChainFlowMap(top, 0.1)
    with pytest.raises(InvalidParameterError, match="IntegralHamiltonian of the top"):
        jg.FlowMap(chain, 0.1)
    with pytest.raises(InvalidParameterError, match="IntegralHamiltonian of the top"):
        exact_parameters(chain, 0.1, XC)
    assert jg.ExactFlow(chain, 0.02).kind == "chain_exact" and jg.ExactFlow(top, 0.02).kind == "exact"
    assert ChainFlowMap(chain, 0.1).H is chain and jg.FlowMap(top, 0.1).H is top
