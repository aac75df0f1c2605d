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
