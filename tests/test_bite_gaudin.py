"""``jetgaudin.GaudinModel``: properties the mutation sample of issue 33 found unchecked (each test names its
mutant, planted by hand: the test fails on it).  No tolerances: names and counts are exact."""

from __future__ import annotations

import jetgaudin as jg


def test_integral_labels_name_sites_from_one_and_their_orders():
    """``h{i},{m}``: site ``i`` counted from 1, ``m = 1..2N_i`` for a site of order ``N_i``, in the order of the
    integrals (site by site), then the family's extras (the trigonometric ``J``).  Written for the mutant
    ``h{i + 1}`` → ``h{i + 2}``."""
    m = jg.GaudinModel(0.8, [(0.0, 2), (0.9, 1)])
    assert m.integral_labels() == ["h1,1", "h1,2", "h1,3", "h1,4", "h2,1", "h2,2"]
    t = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 1)], family="trigonometric", gamma=0.5)
    labels = t.integral_labels()
    assert labels[:4] == ["h1,1", "h1,2", "h2,1", "h2,2"] and len(labels) == t.n_integrals


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_a_model_describes_its_jet_constants_and_is_rebuilt_from_its_description():
    """``describe()`` names the jet constants of a model that has them (one ``None`` or list per site) and no
    ``"constants"`` otherwise; ``GaudinModel.from_description`` rebuilds the same model (the same integrals at a
    state, bit for bit).  Written for the mutant ``if self.constants is not None`` → ``if not …`` (a model without
    constants could not be described, one with them lost them)."""
    import numpy as np

    plain = jg.GaudinModel(1.0, [(0.0, 2), (1.0, 1)])
    with_c = jg.GaudinModel(1.0, [(0.0, 3, (0.5, 0.25)), (1.0, 1)])
    assert "constants" not in plain.describe()
    assert with_c.describe()["constants"] == [[0.5, 0.25], None]
    X = np.random.default_rng(1).normal(size=with_c.n_state)
    for m in (plain, with_c):
        again = jg.GaudinModel.from_description(m.describe())
        assert again.constants == m.constants
        Xm = X[: m.n_state]
        assert np.array_equal(again.integrals(Xm), m.integrals(Xm))


def test_kernel_state_looks_at_the_kernels_of_one_orbit_or_of_a_batch(monkeypatch):
    """``_backend.kernel_state(family, batch)``: a trigonometric call of one orbit needs ``run_orbit`` (and the branch
    rule), of several ``run_batch``.  With only the one-orbit kernels loaded (faked), one orbit is ``"loaded"`` and a
    batch of 2 is not; a kernel loaded in this process or one in Numba's cache counts as available, so one of each is
    ``"cached"``, neither is ``"cold"``.  Written for the mutants ``batch > 1`` → ``batch < 1`` (a batch looked at the
    one-orbit kernels) and ``_loaded(k) or _cached(k)`` → ``and``."""
    from jetgaudin.gaudin import _backend

    fam = jg.GaudinModel(0.8, [(0.0, 1), (0.9, 1)], family="trigonometric", gamma=0.5).family
    loaded = {("_family_kernel", "run_orbit"), ("_family_kernel", "branch_rule")}
    monkeypatch.setattr(_backend, "_loaded", lambda stem, func: (stem, func) in loaded)
    monkeypatch.setattr(_backend, "_cached", lambda stem, func: False)
    assert _backend.kernel_state(fam, 1) == "loaded"
    assert _backend.kernel_state(fam, 2) == "cold"
    loaded = {("_family_kernel", "branch_rule")}
    monkeypatch.setattr(_backend, "_loaded", lambda stem, func: (stem, func) in loaded)
    monkeypatch.setattr(_backend, "_cached", lambda stem, func: func == "run_batch")
    assert _backend.kernel_state(fam, 2) == "cached"
    monkeypatch.setattr(_backend, "_cached", lambda stem, func: False)
    assert _backend.kernel_state(fam, 2) == "cold"


def test_a_map_with_jet_constants_changes_its_backend():
    """``SiteConstantsMap.with_backend("numpy")`` (a model with jet constants): the map's backend is NumPy and its
    orbit is the compiled one's to round-off (1e-12 over 10 steps of a state of size ~1; the two routes differ by
    ~1e-16 a step).  Written for the mutant ``backend if kernel is None else kernel`` → ``backend if not kernel is
    None else kernel`` (the backend was then never changed)."""
    import numpy as np

    from jetgaudin.maps import Backend

    m = jg.GaudinModel(1.0, [(0.0, 3, (0.5, 0.25)), (1.0, 1)])
    T = m.two_point_backlund(0.4 + 0.3j)
    X = np.random.default_rng(2).normal(size=m.n_state) * 0.5
    Tn, Tc = T.with_backend("numpy"), T.with_backend("compiled")
    assert Tn.backend is Backend.NUMPY and Tc.backend is Backend.COMPILED
    a, b = Tn.iterate(X, 10), Tc.iterate(X, 10)
    assert np.max(np.abs(a - b)) < 1e-12 and np.max(np.abs(a[-1] - X)) > 1e-3


def test_the_one_point_map_declares_the_properties_of_its_implementations():
    """``jg.OnePointBacklund`` of a top and of a chain declares what its route's implementation declares
    (``gaudin._one_point._ChainOnePoint``, written out on its own there): integral-preserving, Poisson, symmetric,
    complex, of no order, and not the time-1 flow of ``G_η`` (``interpolates_flow=False``: only the real two-point map
    is, ``docs/architecture.md``).  Written for the mutant ``interpolates_flow=False`` → ``True`` in
    ``_system_maps._ONE_POINT_PROPERTIES`` (the public class then claimed a property its implementation does not)."""
    import dataclasses

    from jetgaudin.gaudin._one_point import _ChainOnePoint

    impl = {f.name: f for f in dataclasses.fields(_ChainOnePoint)}["properties"].default
    chain = jg.GaudinModel(1.0, [(0.0, 1), (1.0, 2)])
    for system in (1.0, chain):
        props = jg.OnePointBacklund(system, 0.5 + 0.3j).properties
        assert props == impl, (system, props, impl)
        assert props.interpolates_flow is False and props.real is False and props.preserves_integrals
