"""The N = 3 kernels' tests written with fewer comparisons (issue 36, docs/performance.md "a fourth session"):
each against the plain comparisons it replaces, on every special value (0, subnormal, inf, NaN)."""

import itertools

import numba
import numpy as np
import pytest

from jetgaudin.backlund import kernels

_n3 = kernels.kernel_module("_n3")
_scalar = kernels.kernel_module("_scalar")

# non-negative quantities (squares and sums of squares) as the residual test sees them, NaN included
_Q = [0.0, 5e-324, 1e-300, 0.25, 1.0, 1.0 + 2.0**-52, 2.0, 1e300, np.inf, np.nan]
_T = [0.0, 5e-324, 1.0, 1e300, np.inf, np.nan]


@numba.njit
def _max2_all(q1, q2, t, out):
    for i in range(q1.shape[0]):  # a loop LLVM vectorises (maxpd/minpd on 8 lanes) with a scalar remainder
        out[i] = _n3._max2_ok(q1[i], q2[i], t[i])


def test_one_comparison_residual_test_equals_the_two_comparisons():
    # exact: a boolean for every pair of special values and tolerance, in vector lanes and in the scalar tail
    # (the array is 3 lanes longer than a multiple of 8); NaN must fail as in q <= t
    rows = np.array(list(itertools.product(_Q, _Q, _T)))
    for shift in range(3):  # each triple in a different lane position
        r = np.roll(rows, shift, axis=0)
        q1, q2, t = (np.ascontiguousarray(r[:, i]) for i in range(3))
        out = np.zeros(len(r), dtype=np.bool_)
        _max2_all(q1, q2, t, out)
        with np.errstate(invalid="ignore"):
            expected = (q1 <= t) & (q2 <= t)
        assert np.array_equal(out, expected)


@numba.njit
def _eig_statuses(u, v, w, nu, out):
    for i in range(u.shape[0]):
        _, _, _, s = _scalar._eigvec(u[i], v[i], w[i], nu[i])
        _, _, _, bad, code = _scalar._eigvec_flags(u[i], v[i], w[i], nu[i])
        out[i, 0] = s
        out[i, 1] = code if bad else 0.0  # as _lanes._lanes_pass takes it


@pytest.mark.parametrize("seed", [0, 1])
def test_eigenvector_flags_give_the_statuses_of_the_eigenvector(seed):
    # _eigvec_flags: one comparison for _eigvec's two tests, the status by arithmetic (maxpd): the statuses must
    # be equal, exactly, on zeros (a double branch point), tiny, huge, inf and NaN entries
    rng = np.random.default_rng(seed)
    vals = [0.0, 5e-324, 1e-170, 1.0, -2.5, 1e170, 1e300, np.inf, -np.inf, np.nan]
    n = 4000
    parts = []
    for _ in range(4):
        z = np.empty(n, dtype=complex)
        z.real, z.imag = rng.choice(vals, n), rng.choice(vals, n)  # (no inf * 1j: its NaN real part)
        parts.append(z)
    parts = [np.where(rng.random(n) < 0.3, 0.0, p) for p in parts]  # many exact zeros
    parts[0][:8] = parts[1][:8] = parts[2][:8] = 0.0  # ℓ(η) = 0
    parts[3][:4] = 0.0
    out = np.empty((n, 2))
    with np.errstate(invalid="ignore", over="ignore"):
        _eig_statuses(*parts, out)
    assert np.array_equal(out[:, 0], out[:, 1])
    assert {0, 1, 5} <= set(out[:, 0])  # every status occurs
