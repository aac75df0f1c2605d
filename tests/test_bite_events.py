"""Events (``jetgaudin.find_events``): what counts as a crossing, for the mutants of issue 33's sample.

A crossing of ``{g = 0}`` between two saved states is a change of sign of ``g`` or an arrival at exactly 0 from a
non-zero value; a stretch where ``g`` stays 0 is not crossed again and again.  No tolerances: the counts and
directions are exact.
"""

from __future__ import annotations

import numpy as np
import pytest

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


# --- the seed-35 sample (issue 33, item 5) --------------------------------------------------------------------------

def test_events_backwards_in_time_are_the_forward_events_of_the_end_state_in_reverse():
    """``t_span = (0, −T)``: the events come in the order of the orbit (time decreasing), each a root of ``g``
    (``|g| < 1e-10``: brentq to 1e-15 in time, ``|dg/dt| ~ 1``), not terminated, and they are the forward events of
    the state at ``−T`` over ``(0, T)`` shifted by ``−T`` (1e-9: two orbits of the exact flow, one from each end, agree
    to ~1e-13 per step over 75 steps; the crossing times inherit that).  Written for the mutants ``s != 0`` → ``s > 0``
    in the function Brent's method sees (it then saw ``g`` constant backwards in time), the sense of a backward orbit
    ``−1`` → ``+1`` (events sorted forwards) and ``terminated = False`` → ``True``."""
    T = 15.0
    g = lambda X: X[0] - 0.5  # noqa: E731
    back = jg.find_events(H3, X3, g, (0.0, -T), 0.2)
    assert len(back.t) >= 2 and not back.terminated
    assert np.all(np.diff(back.t) < 0) and np.all((back.t < 0) & (back.t > -T))
    assert max(abs(g(x)) for x in back.X) < 1e-10
    start = jg.solve(H3, X3, (0.0, -T), dt=0.2).X[-1]
    fwd = jg.find_events(H3, start, g, (0.0, T), 0.2)
    assert len(fwd.t) == len(back.t)
    assert np.max(np.abs((fwd.t - T)[::-1] - back.t)) < 1e-9
    assert np.array_equal(fwd.direction[::-1], -back.direction)  # time reversed: increasing becomes decreasing


def test_a_terminal_event_ends_the_search_at_the_first_crossing():
    """``terminal=True``: exactly the first crossing of the non-terminal search, and ``terminated``.  Written for the
    mutant ``found[:j + 1]`` → ``found[:j / 1]`` (a TypeError: no selected test had a terminal event)."""
    g = lambda X: X[0] - 0.5  # noqa: E731
    every = jg.find_events(H3, X3, g, (0.0, 15.0), 0.2)
    first = jg.find_events(H3, X3, g, (0.0, 15.0), 0.2, terminal=True)
    assert len(every.t) >= 2 and not every.terminated
    assert first.terminated and len(first.t) == 1 and first.t[0] == every.t[0]


def test_a_batch_of_batches_is_refused_naming_its_shape():
    """``X0`` of shape ``(1, 2, 9)``: one line naming the shape (one state or a batch ``(m, n)``).  Written for the
    mutant ``X0.ndim != 1`` → ``X0.ndim < 1`` (a 3-d ``X0`` then reached the solver)."""
    with pytest.raises(jg.InvalidParameterError, match=r"X0 must be one state \(n,\) or a batch \(m, n\), got shape "
                                                        r"\(1, 2, 9\)"):
        jg.find_events(H3, X3[None, None].repeat(2, axis=1), lambda X: X[0], (0.0, 1.0), 0.2)
