"""A chain map whose residue at η does not cancel is refused (issue 33: no test checked it; a mutant that dropped the
check survived).  The residue cancels by spectrality: ``K`` is built from the eigenvector of ``ℓ(η)`` for ``ν1``.  A
``ν1`` off the spectrum by 10 % (the square root of ``ν(η)²`` multiplied by 1.1, planted through the continuation
helper the maps share) leaves a residue of relative size ~0.1, far above the tolerance ``1e-8``: the step must raise
:class:`jetgaudin.SingularStepError` naming the pole at η, on every family and for both maps."""

from __future__ import annotations

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.gaudin import GaudinModel, _one_point
from jetgaudin.gaudin import maps as gm

MODELS = {
    "rational": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)]),
    "trigonometric": GaudinModel(1.0, [(-0.5, 1), (0.4, 2)], family="trigonometric", gamma=1.0),
    "elliptic": GaudinModel(0.0, [(-0.5, 1), (0.4, 2)], family="elliptic", modulus=0.6),
}
X = 0.5 * np.random.default_rng(4).normal(size=9)


_ROOT = gm._continue  # the unplanted continuation (the planted one calls it)


def _off_spectrum(nu2, nu_prev):
    return 1.1 * _ROOT(nu2, nu_prev)


@pytest.mark.parametrize("name", list(MODELS))
def test_two_point_map_refuses_a_residue_that_does_not_cancel(name, monkeypatch):
    B = MODELS[name].two_point_backlund(1.5 + 0.2j, kernel="numpy")
    B.step(X)  # the unplanted step is accepted
    monkeypatch.setattr(gm, "_continue", _off_spectrum)
    with pytest.raises(jg.SingularStepError, match="does not cancel"):
        B.step(X)


@pytest.mark.parametrize("name", ["rational", "trigonometric"])
def test_one_point_map_refuses_a_residue_that_does_not_cancel(name, monkeypatch):
    P = MODELS[name].one_point_backlund(0.3 + 0.7j)
    P.step(X)
    monkeypatch.setattr(_one_point, "_continue", _off_spectrum)
    with pytest.raises(jg.SingularStepError, match="does not cancel"):
        P.step(X)


def test_the_default_model_is_one_spin_at_zero():
    """``GaudinModel(b)`` without sites: one site at 0 of order 1 (its docstring; a mutant moving the default site to
    1 survived the sampled tests): the same integrals as the model written out."""
    m = GaudinModel(0.5)
    assert m.sites == ((0.0, 1),) and m.M == 1
    Y = np.array([0.3, -0.2, 0.9])
    assert np.array_equal(m.integrals(Y), GaudinModel(0.5, [(0.0, 1)]).integrals(Y))
