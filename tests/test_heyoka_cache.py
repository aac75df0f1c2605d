"""heyoka's integrator is compiled once per Hamiltonian and tolerance (issue 33: ``solve(method="heyoka")`` rebuilt
its JIT on every call, 80-157 ms against ~1 ms of propagation), and a cached integrator gives the bits of a fresh
one, whatever was integrated with it before."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import flows

hy = pytest.importorskip("heyoka")

X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])


@pytest.fixture
def builds(monkeypatch):
    """Counts heyoka's integrator constructions, starting from an empty cache."""
    monkeypatch.setattr(flows, "_HEYOKA_CACHE", {})
    count = [0]
    real = hy.taylor_adaptive

    def counting(*args, **kwargs):
        count[0] += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(hy, "taylor_adaptive", counting)
    return count


def test_one_compile_per_hamiltonian_and_tolerance(builds):
    H = jg.physical_hamiltonian(3, 1.0)
    a = jg.solve(H, X0, (0, 2), method="heyoka")
    b = jg.solve(H, X0, (0, 2), method="heyoka")
    assert builds[0] == 1 and np.array_equal(a.X, b.X)
    jg.solve(H, X0, (0, 2), method="heyoka", rtol=1e-10)  # another tolerance: another integrator
    jg.solve(jg.physical_hamiltonian(3, 0.5), X0, (0, 2), method="heyoka")  # another Hamiltonian
    assert builds[0] == 3


def test_a_cached_integrator_gives_the_bits_of_a_fresh_one(monkeypatch):
    """Other orbits integrated before (state and time left in the cached copy's template) change nothing."""
    H = jg.physical_hamiltonian(3, 1.0)
    monkeypatch.setattr(flows, "_HEYOKA_CACHE", {})
    fresh = jg.solve(H, X0, (0, 3), method="heyoka")
    jg.solve(H, 0.5 * X0, (0, 7), method="heyoka")
    again = jg.solve(H, X0, (0, 3), method="heyoka")
    assert np.array_equal(fresh.X, again.X) and np.array_equal(fresh.t, again.t)
    ta = hy.taylor_adaptive(flows._heyoka_system(H, 9), X0.copy(), tol=1e-12)  # solve's default rtol
    ref = np.asarray(ta.propagate_grid(np.asarray(fresh.t, dtype=float))[-1])
    assert np.array_equal(fresh.X, ref)  # the cached route is heyoka's integrator on the same equations: same bits
