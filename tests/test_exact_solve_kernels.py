"""The compiled parameter solve's building blocks (issue 33 item 2, speed): the branch points by Aberth–Ehrlich
against NumPy's companion-matrix roots, its fallback at a double root, and the real-arithmetic square root of the
weights' loop against ``cmath.sqrt``."""

import cmath

import numpy as np
import pytest

from jetgaudin._exact_kernels import _aberth, _branch_points, _csqrt, _kappa


def _match(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance from a root of either set to the nearest of the other (set distance)."""
    return max(np.abs(a[:, None] - b[None]).min(1).max(), np.abs(b[:, None] - a[None]).min(1).max())


@pytest.mark.parametrize("N", [2, 3, 4, 5])
def test_branch_points_are_numpys_roots(N):
    """For 300 random states per N (scales 1e-3..1e3, three fields) the branch points equal ``np.roots`` of the same
    coefficients to 1e-12 of the largest modulus (both round-off: the companion eigenvalues of a polynomial with
    simple roots have errors ~1e-15 × their condition number; the worst seen is 3e-14), and so does ``R``."""
    rng = np.random.default_rng(N)
    for _ in range(300):
        x = rng.normal(size=3 * N) * rng.choice([1e-3, 1.0, 10.0, 1e3])
        b = float(rng.choice([1.0, 0.3, -2.0]))
        kappa = np.empty(2 * N + 1)
        _kappa(x, b, kappa)
        ref = np.roots(kappa)
        got = _branch_points(kappa)
        scale = np.abs(ref).max()
        assert _match(got, ref) <= 1e-12 * scale
        assert abs(np.abs(got).max() - scale) <= 1e-12 * scale


def test_aberth_converges_on_the_benchmark_state_and_refuses_a_double_root():
    """On the twisted top's benchmark state Aberth converges (no LAPACK call); for ``P = (λ² + 1)²(λ − 2)²`` (two
    double roots) its corrections stall at ~√ε and it answers False, so :func:`_branch_points` takes the companion
    eigenvalues, which find the roots to ~1e-8 (√ε: a double root's conditioning)."""
    x = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
    kappa = np.empty(7)
    _kappa(x, 1.0, kappa)
    z = np.empty(6, dtype=complex)
    assert _aberth(kappa, z)
    double = np.poly([1j, 1j, -1j, -1j, 2.0, 2.0]).real
    assert not _aberth(double, np.empty(6, dtype=complex))
    roots = _branch_points(double)
    assert _match(roots, np.array([1j, 1j, -1j, -1j, 2.0, 2.0])) <= 1e-6


def test_real_square_root_is_cmath_sqrt():
    """The principal root in real arithmetic equals ``cmath.sqrt`` to 2 ulps of the modulus, on every quadrant, the
    axes (±0 imaginary parts on the negative axis: ``cmath`` follows the sign of the zero, the weights' loop only
    needs one root of the two and continues the sign itself) and scales 1e-300..1e300 (past 1e±150 the modulus is taken by ``hypot``)."""
    rng = np.random.default_rng(7)
    vals = [complex(a, b) for a, b in rng.normal(size=(2000, 2)) * 10.0 ** rng.integers(-300, 300, size=(2000, 1))]
    vals += [4.0, -4.0 + 0j, 1j, -1j, complex(-4.0, 1e-300), complex(-4.0, -1e-300), 0j]
    for v in vals:
        got = complex(*_csqrt(v.real, v.imag))
        ref = cmath.sqrt(v)
        assert abs(got - ref) <= 4.5e-16 * abs(ref)
