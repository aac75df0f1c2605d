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
