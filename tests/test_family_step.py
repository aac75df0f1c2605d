"""The family kernel's fast paths (``jetgaudin.gaudin._family_kernel``, issue 33 item 2): each is the general
arithmetic rewritten with the same floating-point operations in the same order, so each must give the same bits.

* ``_site1``/``_site2`` (sites of order 1 and 2, unrolled) against ``_site`` (any order, the series recursions);
* ``_null_vector`` (the elliptic rule's cofactor vector, unrolled, shared 2 × 2 minors) against the loop over four
  3 × 3 determinants it replaces, written out here (the reference), on systems that take each of its four branches;
* ``_half_scale`` (bits) against ``math.ldexp(1, −⌊(frexp(x)[1] + 1)/2⌋)`` on every exponent and the special values.

"Same bits" is checked on the bytes (``view(np.int64)``): the sign of a zero counts too.  No tolerance anywhere.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("numba")

from numba import njit  # noqa: E402

from jetgaudin.gaudin import _family_kernel as F  # noqa: E402


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


@njit(cache=False)
def _general(x, c, T, pidx, i, o, N):
    out = np.zeros(x.shape[0])
    Nmax = T.shape[1]
    Dt = np.zeros((Nmax, 4), dtype=np.complex128)
    At = np.zeros((Nmax, 4), dtype=np.complex128)
    P = np.zeros((Nmax, 4), dtype=np.complex128)
    det = np.zeros(Nmax, dtype=np.complex128)
    g = np.zeros(Nmax, dtype=np.complex128)
    F._site(x, out, c, T, pidx, i, o, N, Dt, At, det, g, P)
    return out


@njit(cache=False)
def _special(x, c, T, pidx, i, o, N):
    out = np.zeros(x.shape[0])
    if N == 1:
        F._site1(x, out, c, T, pidx, i, o)
    else:
        F._site2(x, out, c, T, pidx, i, o)
    return out


def _tables(rng, S, Nmax, K, P):
    """Random two-word tables as ``orbit_constants`` lays them out: term ``t`` of entry ``e`` at ``2t`` (high word)
    and ``2t + 1`` (low word, ~1e-16 of it), some later terms zero (the padding of entries with fewer terms)."""
    hi = rng.normal(size=(S, Nmax, 4, K)) + 1j * rng.normal(size=(S, Nmax, 4, K))
    hi[..., 1:][rng.random(hi[..., 1:].shape) < 0.3] = 0  # the first term of each entry kept: det D_0 ≠ 0
    T = np.zeros((S, Nmax, 4, 2 * K), dtype=complex)
    T[..., 0::2] = hi
    T[..., 1::2] = hi * 1e-16 * (rng.normal(size=hi.shape) + 1j * rng.normal(size=hi.shape))
    pidx = np.repeat(rng.integers(0, P, size=(4, K)), 2, axis=1).astype(np.int64)
    return T, pidx


@pytest.mark.parametrize("N", [1, 2])
def test_unrolled_sites_are_the_general_site_bit_for_bit(N):
    """200 random sites of order ``N`` (the site in the middle of three, so its offset and index are not 0), random
    two-word tables with zero padding, coefficients and states of mixed scales."""
    rng = np.random.default_rng(3300 + N)
    for _ in range(200):
        P, K = int(rng.integers(4, 7)), int(rng.integers(1, 4))
        T, pidx = _tables(rng, 3, 3, K, P)
        c = (rng.normal(size=P) + 1j * rng.normal(size=P)) * 10.0 ** rng.uniform(-3, 3, P)
        x = rng.normal(size=3 * (2 + N)) * 10.0 ** rng.uniform(-2, 2)
        o = 1
        ref = _general(x, c, T, pidx, 1, o, N)
        got = _special(x, c, T, pidx, 1, o, N)
        assert _same_bits(got, ref)
        assert np.all(got[3 * o:3 * (o + N)] != 0)  # the site's coordinates were written (not the zeros left)


@njit(cache=False)
def _det3(A, r0, r1, r2, c0, c1, c2):
    return (A[r0, c0] * (A[r1, c1] * A[r2, c2] - A[r1, c2] * A[r2, c1])
            - A[r0, c1] * (A[r1, c0] * A[r2, c2] - A[r1, c2] * A[r2, c0])
            + A[r0, c2] * (A[r1, c0] * A[r2, c1] - A[r1, c1] * A[r2, c0]))


@njit(cache=False)
def _reference_null_vector(A, c):
    """The selection as the kernel wrote it before (a loop over the rows to skip, four determinants per try):
    returns ``(best, the try it stopped at)``."""
    rn = np.zeros(4)
    for r in range(4):
        rn[r] = F._abs2(A[r, 0]) + F._abs2(A[r, 1]) + F._abs2(A[r, 2]) + F._abs2(A[r, 3])
    best = -1.0
    last = 3
    for i in range(4):
        skip = 3 - i
        r0 = (skip + 1) % 4
        r1 = (skip + 2) % 4
        r2 = (skip + 3) % 4
        n0 = _det3(A, r0, r1, r2, 1, 2, 3)
        n1 = -_det3(A, r0, r1, r2, 0, 2, 3)
        n2 = _det3(A, r0, r1, r2, 0, 1, 3)
        n3 = -_det3(A, r0, r1, r2, 0, 1, 2)
        s = F._abs2(n0) + F._abs2(n1) + F._abs2(n2) + F._abs2(n3)
        if s > best:
            best = s
            c[0] = n0
            c[1] = n1
            c[2] = n2
            c[3] = n3
        if best > 1e-4 * rn[r0] * rn[r1] * rn[r2]:
            last = i
            break
    return best, last


@njit(cache=False)
def _unrolled_null_vector(A, c):
    return F._null_vector((A[0, 0], A[0, 1], A[0, 2], A[0, 3]), (A[1, 0], A[1, 1], A[1, 2], A[1, 3]),
                          (A[2, 0], A[2, 1], A[2, 2], A[2, 3]), (A[3, 0], A[3, 1], A[3, 2], A[3, 3]), c)


def test_elliptic_null_vector_is_the_determinant_loop_bit_for_bit():
    """Random rank-3 systems (a null vector exists), and systems whose first three rows, or more, are dependent (so
    the selection goes on to the second, third and fourth try), scaled from 1e-3 to 1e3; the same ``c`` and the
    same ``|n|²``, and every try of the loop is reached by some system (else the branches are not tested)."""
    rng = np.random.default_rng(33)
    reached = set()
    for k in range(2000):
        A = rng.normal(size=(4, 4)) + 1j * rng.normal(size=(4, 4))
        kind = k % 5
        if kind == 0:  # rank 3: row 3 a combination of the others
            A[3] = A[:3].T @ (rng.normal(size=3) + 1j * rng.normal(size=3))
        elif kind in (1, 2, 3):  # a row nearly a combination of two others: tries 2 and later
            a, b2, d = [(0, 1, 2), (3, 0, 1), (2, 3, 0)][kind - 1]
            A[d] = rng.normal() * A[a] + rng.normal() * A[b2] + 1e-9 * A[d]
            if kind == 3:  # and a second dependency
                A[1] = rng.normal() * A[2] + rng.normal() * A[3] + 1e-9 * A[1]
        A *= 10.0 ** rng.uniform(-3, 3)
        c_ref = np.full(4, 7 + 7j)
        c_new = c_ref.copy()
        best_ref, last = _reference_null_vector(A, c_ref)
        best_new = _unrolled_null_vector(A, c_new)
        reached.add(int(last))
        assert _same_bits(c_new, c_ref) and _same_bits(best_new, best_ref), (k, last)
    assert reached == {0, 1, 2, 3}, reached
    nan = np.full((4, 4), np.nan + 0j)  # nothing compares: c untouched, best −1 (as the loop)
    c_new = np.full(4, 7 + 7j)
    assert _unrolled_null_vector(nan, c_new) == -1.0 and np.all(c_new == 7 + 7j)


@njit(cache=False)
def _scales(a):
    out = np.empty_like(a)
    for i in range(a.shape[0]):
        out[i] = F._half_scale(a[i])
    return out


def test_half_scale_is_frexp_ldexp_for_every_double():
    """Every power of two and its predecessor (normal and subnormal), the extremes, zeros, infinities, NaN, negative
    values and 10⁴ random magnitudes over the whole range: the bits of the ``frexp``/``ldexp`` form."""
    rng = np.random.default_rng(36)
    p2 = np.ldexp(1.0, np.arange(-1074, 1024))
    x = np.concatenate([[0.0, -0.0, np.inf, -np.inf, np.nan, -1.0, 5e-324, np.finfo(float).tiny,
                         np.finfo(float).max], p2, np.nextafter(p2, 0), np.nextafter(p2, np.inf)[:-1],
                        rng.uniform(0, 1, 10000) * 10.0 ** rng.integers(-323, 308, 10000),
                        -rng.uniform(0, 1, 100) * 10.0 ** rng.integers(-300, 300, 100)])
    ref = np.array([math.ldexp(1.0, -((math.frexp(v)[1] + 1) // 2)) for v in x])
    assert _same_bits(_scales(x), ref)
