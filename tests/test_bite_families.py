"""The Gaudin families (``jetgaudin.families``): properties the fresh mutation sample of issue 33 (seed 35) found
unchecked.

Each test names the mutant (``docs/mutation.md``) it was written for; each was run on it, planted by hand, and fails
there.  Tolerances are stated per test.
"""

from __future__ import annotations

import numpy as np
import pytest

from jetgaudin.families.trigonometric import spectral_rows


@pytest.mark.parametrize("gamma", [0.5, 1.3])
def test_spectral_rows_are_the_null_vectors_of_both_rows(gamma):
    """``spectral_rows(γ, ξ, k1, k2)`` (its docstring): ``r1 = (α, α_0, β)`` is orthogonal (bilinear dot) to
    ``(e^{iγξ_i} k_{i1}, e^{−iγξ_i} k_{i1}, k_{i2})`` and ``r2 = (γ', δ, δ_0)`` to ``(k_{i1}, e^{iγξ_i} k_{i2},
    e^{−iγξ_i} k_{i2})`` for ``ξ_1 = ξ``, ``ξ_2 = ξ̄`` (``k_1 = k1``, ``k_2 = k2``); with ``k2 = (−k̄_{12}, k̄_{11})``,
    ``αα_0 = δδ_0`` identically.  Random ``k1`` of size ~1 and ``ξ`` with ``|Im ξ| <= 1``; each entry of a cross
    product is a difference of two products (round-off ~ε times their size), so every identity holds to 1e-13
    relative to the sum of the moduli of its terms (a few ε expected; the mutant misses by O(1)).
    Written for the mutant ``e^{iγξ̄} k_{22}`` → ``e^{iγξ̄} − k_{22}`` in ``r2``
    (the function is public and used by no route today: no test called it)."""
    rng = np.random.default_rng(7)
    B = 16
    k1 = rng.normal(size=(B, 2)) + 1j * rng.normal(size=(B, 2))
    k2 = np.stack([-np.conj(k1[:, 1]), np.conj(k1[:, 0])], -1)
    xi = rng.uniform(-2, 2, B) + 1j * rng.uniform(-1, 1, B)
    r1, r2 = spectral_rows(gamma, xi, k1, k2)
    for x, k in ((xi, k1), (np.conj(xi), k2)):
        ep, em = np.exp(1j * gamma * x), np.exp(-1j * gamma * x)
        row1 = np.stack([ep * k[:, 0], em * k[:, 0], k[:, 1]], -1)
        row2 = np.stack([k[:, 0], ep * k[:, 1], em * k[:, 1]], -1)
        for row, r in ((row1, r1), (row2, r2)):
            scale = np.sum(np.abs(row) * np.abs(r), -1)
            assert np.max(np.abs(np.sum(row * r, -1)) / scale) < 1e-13
    gauge = np.abs(r1[:, 0] * r1[:, 1] - r2[:, 1] * r2[:, 2])
    assert np.max(gauge / (np.abs(r1[:, 0] * r1[:, 1]) + np.abs(r2[:, 1] * r2[:, 2]))) < 1e-13
    assert np.min(np.abs(r2[:, 1])) > 1e-3  # not the zero vector


def test_sites_that_coincide_modulo_the_period_are_refused_and_only_those():
    """A trigonometric chain's sites must differ modulo its period ``T`` (its Lax matrix is periodic in ``λ``):
    ``0.3`` and ``0.3 + T`` are refused naming both, ``0.2`` and ``T − 0.2`` (whose sum is a period) are a valid
    chain.  Written for the mutant ``(p − q)/T`` → ``(p + q)/T`` in ``Family.check`` (the sum tested, not the
    difference)."""
    import jetgaudin as jg

    fam = jg.GaudinModel(0.8, [(0.0, 1), (1.0, 1)], family="trigonometric", gamma=0.5).family
    T = fam.period
    with pytest.raises(jg.InvalidParameterError, match="coincide modulo its period"):
        jg.GaudinModel(0.8, [(0.3, 1), (0.3 + T, 1)], family="trigonometric", gamma=0.5)
    m = jg.GaudinModel(0.8, [(0.2, 1), (T - 0.2, 1)], family="trigonometric", gamma=0.5)
    assert m.M == 2
