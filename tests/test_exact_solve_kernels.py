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
    needs one root of the two and continues the sign itself) and scales 1e-300..1e300 (past 1e±150 the modulus is
    taken by ``hypot``)."""
    rng = np.random.default_rng(7)
    vals = [complex(a, b) for a, b in rng.normal(size=(2000, 2)) * 10.0 ** rng.integers(-300, 300, size=(2000, 1))]
    vals += [4.0, -4.0 + 0j, 1j, -1j, complex(-4.0, 1e-300), complex(-4.0, -1e-300), 0j]
    for v in vals:
        got = complex(*_csqrt(v.real, v.imag))
        ref = cmath.sqrt(v)
        assert abs(got - ref) <= 4.5e-16 * abs(ref)


@pytest.mark.parametrize("substeps,save_every", [(1, 1), (3, 1), (1, 5), (2, 7)])
def test_rows_are_the_unrotated_orbit_rotated_through_the_accumulated_angle(substeps, save_every):
    """The N = 3 loop's rows (cos/sin from an anchor every 16 sub-steps and a table between) equal the unrotated
    orbit ``Z_m`` (the same loop at θ = 0: cos 0 = 1, sin 0 = 0 leave it exact) rotated through ``(m s) θ`` with
    ``cos``/``sin`` in long double, to 8e-16 of the row's size (the addition theorem costs a few ulps; a wrong
    table entry or anchor is off by O(θ)), for 203 steps (13 anchors); the final state equals its row bit for bit.
    """
    import jetgaudin as jg
    from jetgaudin._exact_loop import rows_single
    from jetgaudin.exact import _accepted

    H = jg.physical_hamiltonian(3, 1.0)
    x0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
    dt = 0.12 / substeps
    eta, theta, _, _, nu = _accepted(H, dt, x0[None], 1.5, None)
    steps = 203
    out = []
    for th in (float(theta[0]), 0.0):
        rows = np.empty((steps // save_every, 9))
        final = np.empty(9)
        info = np.zeros(2, dtype=np.int64)
        rows_single(x0, 1.0, eta[0], nu[0], th, steps, save_every, substeps, rows, final, info)
        assert info[0] == 0
        out.append((rows, final))
    (rows, final), (Z, zfinal) = out
    m = (np.arange(1, len(rows) + 1) * save_every * substeps).astype(np.longdouble)
    a = m * np.longdouble(float(theta[0]))
    c, s = np.cos(a)[:, None], np.sin(a)[:, None]
    Zl = Z.astype(np.longdouble).reshape(-1, 3, 3)
    ref = np.stack([c * Zl[..., 0] - s * Zl[..., 1], s * Zl[..., 0] + c * Zl[..., 1], Zl[..., 2]], axis=-1)
    err = np.abs(rows.reshape(-1, 3, 3) - ref).max(axis=(1, 2)) / np.abs(Z).max(axis=1)
    assert float(err.max()) <= 8e-16
    if steps % save_every == 0:
        assert np.array_equal(final, rows[-1])


def test_two_segments_in_one_loop_are_each_segments_own_bits():
    """``_weights_two`` (the N = 3 flow's two segments in one node loop) gives each segment's weights, derivatives
    and end-point ``ν`` bit for bit as ``_weights_one`` (its docstring: the same operations per segment)."""
    from jetgaudin._exact_kernels import _weights_one, _weights_two
    from jetgaudin.exact import _gauss_legendre

    x0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0])
    kappa = np.empty(7)
    _kappa(x0, 1.0, kappa)
    x, w = _gauss_legendre(64)
    a, h = (5.17, -5.17), (-1.55, -2.8)
    om, dom, nu = np.zeros((2, 6)), np.zeros((2, 6)), np.zeros(2, complex)
    _weights_two(kappa, a[0], h[0], a[1], h[1], x, w, om[0], dom[0], om[1], dom[1], nu)
    for j in range(2):
        o, d, n = np.zeros(6), np.zeros(6), np.zeros(1, complex)
        _weights_one(kappa, a[j], h[j], x, w, o, d, n)
        assert np.array_equal(o, om[j]) and np.array_equal(d, dom[j]) and n[0] == nu[j]
