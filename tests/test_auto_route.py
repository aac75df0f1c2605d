"""``backend="auto"`` never picks a route 3x slower than the other one (issue 33): the decision rule of the chain
maps (every family) and of the top's maps, tested as a rule on the cost model (no timings: the constants are
measured by ``benchmarks/auto_route.py``), with the kernels' state (loaded, cached, cold) given explicitly."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel
from jetgaudin.gaudin import _backend as rule
from jetgaudin.maps import Backend

MODELS = {
    "rational": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)]),
    "trigonometric": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)], family="trigonometric", gamma=1.0),
    "elliptic": GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6),
}
ETA = 1.5 + 0.2j


def _choice(name, batch, steps, state, monkeypatch):
    monkeypatch.setattr(rule, "kernel_state", lambda family, b=1: state)
    X = np.zeros((batch, 9)) if batch > 1 else np.zeros(9)
    return MODELS[name].two_point_backlund(ETA).resolved_backend(X, steps)


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("batch", [1, 50])
def test_loaded_kernels_are_always_taken(name, batch, monkeypatch):
    """Once the kernels are loaded the compiled route is ~1000x cheaper per step (the NumPy step costs >= 0.4 ms,
    the compiled one ~1 us per orbit) after a call's set-up of ~2 ms: AUTO takes it from ten steps on."""
    assert _choice(name, batch, 10, "loaded", monkeypatch) is Backend.COMPILED


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("batch", [1, 50])
@pytest.mark.parametrize("state", ["cached", "cold"])
def test_the_choice_switches_where_the_estimates_cross(name, batch, state, monkeypatch):
    """NumPy for a few steps (compiling or loading would cost more), compiled from where the NumPy estimate passes
    the compiled one on: the chosen route's estimate is never above the other's."""
    fam = MODELS[name].family
    assert _choice(name, batch, 1, state, monkeypatch) is Backend.NUMPY
    for steps in (10, 100, 1000, 10**4, 10**5, 10**6):
        cost = rule.route_costs(fam, 3, batch, steps, state)
        chosen = _choice(name, batch, steps, state, monkeypatch)
        assert (cost.compiled <= cost.numpy) == (chosen is Backend.COMPILED), (steps, cost)
    assert _choice(name, batch, 10**6, state, monkeypatch) is Backend.COMPILED


@pytest.mark.parametrize("name, batch, steps, state", [
    ("elliptic", 1, 10**4, "cold"),        # the elliptic orbit (27 steps/s on NumPy; today: NumPy)
    ("elliptic", 1, 3000, "cold"),         # 3000 NumPy steps (~8 s) against a 7 s compile (today: NumPy)
    ("elliptic", 1, 1000, "cached"),       # ~2.7 s of NumPy against a 0.3 s load (today: NumPy)
    ("elliptic", 50, 200, "loaded"),       # the ensemble: 597 orbit-steps/s against 9.3e3 (today: NumPy)
    ("trigonometric", 1, 5000, "cached"),  # ~3.5 s of NumPy against a load (today: NumPy)
    ("rational", 1, 5000, "cached"),       # ~2.5 s of NumPy against a load (today: NumPy)
])
def test_the_cases_where_the_old_threshold_took_a_much_slower_route(name, batch, steps, state, monkeypatch):
    """The fixed threshold of 20 000 orbit-steps took NumPy for each of these, > 3x slower than compiling (or
    loading) and running the kernel (measured rates in the comments, docs/performance.md's machine)."""
    assert _choice(name, batch, steps, state, monkeypatch) is Backend.COMPILED


@pytest.mark.parametrize("name", list(MODELS))
def test_estimates_follow_the_family_and_size(name):
    """The NumPy estimate grows with the orbits, the steps and the chain's size; the elliptic step (Jacobi functions
    of complex argument) is the dearest; the set-up is nothing once loaded and a compile costs more than a load."""
    fam = MODELS[name].family
    one = rule.route_costs(fam, 3, 1, 1000, "loaded")
    assert rule.route_costs(fam, 3, 10, 1000, "loaded").numpy > one.numpy
    assert rule.route_costs(fam, 3, 1, 2000, "loaded").numpy == pytest.approx(2 * one.numpy)  # linear in steps
    assert rule.route_costs(fam, 12, 1, 1000, "loaded").numpy > one.numpy
    assert one.setup == 0 and rule.route_costs(fam, 3, 1, 1000, "cold").setup > \
        rule.route_costs(fam, 3, 1, 1000, "cached").setup
    if name != "elliptic":
        assert rule.route_costs(MODELS["elliptic"].family, 3, 1, 1000, "loaded").numpy > one.numpy


def test_explicit_routes_and_maps_without_a_compiled_route_are_untouched():
    m = MODELS["elliptic"]
    X = np.zeros(9)
    assert m.two_point_backlund(ETA, kernel="numpy").resolved_backend(X, 10**9) is Backend.NUMPY
    assert m.two_point_backlund(ETA, kernel="compiled").resolved_backend(X, 1) is Backend.COMPILED
    one = MODELS["rational"].one_point_backlund(ETA)
    assert one.resolved_backend(X, 10**9) is Backend.NUMPY


def test_the_notice_names_the_slow_route_only(monkeypatch):
    """One line when AUTO takes NumPy on a map that has a compiled route (both estimates and the option);
    nothing when it takes the compiled route or the backend was given."""
    B = MODELS["elliptic"].two_point_backlund(ETA)
    monkeypatch.setattr(rule, "kernel_state", lambda family, b=1: "cold")
    text = B.route_notice(np.zeros(9), 5)
    assert text is not None and "NumPy route" in text and "--backend compiled" in text and "\n" not in text
    assert B.route_notice(np.zeros(9), 10**6) is None
    assert B.with_backend("numpy").route_notice(np.zeros(9), 5) is None


@pytest.mark.parametrize("n_state", [9, 12])
def test_the_top_rule_stays_within_3x(n_state):
    """The top's maps (``backlund.auto_kernel``): compiled once loaded; the thresholds in orbit-steps correspond to
    the set-up they weigh: the NumPy step of the top costs ~300 us (docs/performance.md), so the cached threshold
    (2000) is ~0.6 s against a ~0.3 s load and the cold one (20 000) ~6 s against the kernels' compile time; each
    within a factor 3 of the set-up it stands for."""
    from jetgaudin.backlund.kernels import _select as sel

    numpy_step_s = 3e-4
    names = sel.kernel_names(n_state, False)
    cold = sum(sel.EXPECTED_COMPILE_S[n] for n in names)
    assert 1 / 3 <= sel._AUTO_MIN_WORK_COLD * numpy_step_s / cold <= 3
    assert 1 / 3 <= sel._AUTO_MIN_WORK * numpy_step_s / (0.3 + sel.EXPECTED_LOAD_S * len(names)) <= 3
    X = np.zeros(n_state)
    X[2] = 1.0
    assert jg.TwoPointBacklund(1.0, 5 + 0.1j).resolved_backend(X, 10**6) is Backend.COMPILED


def test_the_numpy_estimate_is_the_documented_formula():
    """``steps · (F + B·G) · (M + 1)/4`` with the family's ``(F, G)`` (module docstring of ``gaudin._backend``): at
    ``M = 3`` the factor is 1, at ``M = 7`` it is 2 (a mutant ``(M + 2)/4`` survived the decision tests)."""
    fam = MODELS["trigonometric"].family
    F, G = rule.NUMPY_STEP_S["trigonometric"]
    assert rule.route_costs(fam, 3, 10, 100, "loaded").numpy == pytest.approx(100 * (F + 10 * G), rel=1e-12)
    assert rule.route_costs(fam, 7, 10, 100, "loaded").numpy == pytest.approx(2 * 100 * (F + 10 * G), rel=1e-12)
