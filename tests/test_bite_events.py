"""Events (``jetgaudin.find_events``): what counts as a crossing, for the mutants of issue 33's sample.

A crossing of ``{g = 0}`` between two saved states is a change of sign of ``g`` or an arrival at exactly 0 from a
non-zero value; a stretch where ``g`` stays 0 is not crossed again and again.  No tolerances: the counts and
directions are exact.
"""

from __future__ import annotations

import numpy as np

import jetgaudin as jg

H3 = jg.physical_hamiltonian(3, 1.0)
X3 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])  # Appendix 2


def test_a_function_that_stays_zero_is_not_crossed():
    """``g ≡ 0`` along the orbit: no event (not one per step).  Written for the mutant ``a != 0`` → ``a != 1`` in
    the crossing test (a stretch of zeros then counts at every step)."""
    ev = jg.find_events(H3, X3, lambda X: 0.0, (0, 2), 0.2)
    assert len(ev.t) == 0 and len(ev.direction) == 0


def test_arriving_at_zero_counts_once_and_leaving_it_not_at_all():
    """``g = max(x_0 − c, 0)`` is 0 wherever ``x_0 <= c``: it is crossed (arrives at 0, direction −1) once per
    descent of ``x_0`` through ``c`` and never on the way up, so its events are as many as the down-crossings of the
    smooth ``x_0 − c`` (all of direction −1, each at a saved state where the smooth one has crossed)."""
    c = 0.5
    smooth = jg.find_events(H3, X3, lambda X: X[0] - c, (0, 60), 0.2, direction=-1)
    clipped = jg.find_events(H3, X3, lambda X: max(X[0] - c, 0.0), (0, 60), 0.2)
    assert len(smooth.t) >= 2
    assert len(clipped.t) == len(smooth.t) and np.all(clipped.direction == -1)
    assert np.all(clipped.t >= smooth.t) and np.all(clipped.t - smooth.t <= 0.2 + 1e-12)  # within the step after it
