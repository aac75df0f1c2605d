"""su(n) as a definition (issue 32): the nested generalised Gell-Mann basis and its structure constants."""

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin.lie import gell_mann_basis, parse_algebra

# every basis matrix is built from exact entries (0, ±1, ±i and one square root), so comparisons are at 1e-15


def test_su2_is_pauli():
    pauli = np.array([[[0, 1], [1, 0]], [[0, -1j], [1j, 0]], [[1, 0], [0, -1]]])
    assert np.allclose(jg.su(2).basis, pauli, atol=1e-15, rtol=0)


def test_su3_is_gell_mann():
    s3 = 1 / np.sqrt(3)
    lam = np.zeros((8, 3, 3), dtype=complex)
    lam[0][0, 1] = lam[0][1, 0] = 1
    lam[1][0, 1], lam[1][1, 0] = -1j, 1j
    lam[2][0, 0], lam[2][1, 1] = 1, -1
    lam[3][0, 2] = lam[3][2, 0] = 1
    lam[4][0, 2], lam[4][2, 0] = -1j, 1j
    lam[5][1, 2] = lam[5][2, 1] = 1
    lam[6][1, 2], lam[6][2, 1] = -1j, 1j
    lam[7] = s3 * np.diag([1, 1, -2])
    assert np.allclose(jg.su(3).basis, lam, atol=1e-15, rtol=0)


def test_su3_structure_constants_are_the_textbook_ones():
    f = jg.su(3).structure_constants
    h = np.sqrt(3) / 2
    for (a, b, c), v in {(1, 2, 3): 1, (1, 4, 7): .5, (1, 5, 6): -.5, (2, 4, 6): .5, (2, 5, 7): .5, (3, 4, 5): .5,
                         (3, 6, 7): -.5, (4, 5, 8): h, (6, 7, 8): h}.items():
        assert f[a - 1, b - 1, c - 1] == pytest.approx(v, abs=1e-15)
    assert np.count_nonzero(f) == 9 * 6  # the nine above, with their permutations; nothing else


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_basis_and_brackets(n):
    lam = gell_mann_basis(n)
    assert lam.shape == (n * n - 1, n, n)
    assert np.allclose(lam, np.conj(np.transpose(lam, (0, 2, 1))), atol=1e-15)  # Hermitian
    assert np.allclose(np.trace(lam, axis1=1, axis2=2), 0, atol=1e-14)  # traceless
    assert np.allclose(np.einsum("aij,bji->ab", lam, lam), 2 * np.eye(n * n - 1), atol=1e-14)
    f = jg.su(n).structure_constants
    comm = np.einsum("aij,bjk->abik", lam, lam) - np.einsum("bij,ajk->abik", lam, lam)
    assert np.allclose(comm, 2j * np.einsum("abc,cij->abij", f, lam), atol=1e-14)
    assert np.allclose(f, -np.transpose(f, (1, 0, 2)), atol=1e-15)  # totally antisymmetric
    assert np.allclose(f, np.transpose(f, (1, 2, 0)), atol=1e-15)
    jac = np.einsum("abe,ecd->abcd", f, f)
    assert np.allclose(jac + np.transpose(jac, (1, 2, 0, 3)) + np.transpose(jac, (2, 0, 1, 3)), 0, atol=1e-14)
    if n == 2:
        eps = np.zeros((3, 3, 3))
        eps[0, 1, 2] = eps[1, 2, 0] = eps[2, 0, 1] = 1
        eps[0, 2, 1] = eps[2, 1, 0] = eps[1, 0, 2] = -1
        assert np.array_equal(f, eps)


def test_components_invert_matrix():
    s = jg.su(4)
    v = np.random.default_rng(0).normal(size=(5, 15))
    assert np.allclose(s.components(s.matrix(v)), v, atol=1e-14)


@pytest.mark.parametrize("spec", ["su(3)", "su3", "SU(3)", " su ( 3 ) ", jg.su(3)])
def test_parse_algebra(spec):
    assert parse_algebra(spec) == jg.SU(3)


@pytest.mark.parametrize("spec", ["so(3)", "su(1)", "su", 3, None, "su(x)"])
def test_parse_algebra_refuses(spec):
    with pytest.raises(jg.InvalidParameterError, match="unknown algebra"):
        parse_algebra(spec)


@pytest.mark.parametrize("n", [1, 2.0, True, "3"])
def test_su_refuses_bad_n(n):
    with pytest.raises(jg.InvalidParameterError, match="integer n >= 2"):
        jg.su(n)
