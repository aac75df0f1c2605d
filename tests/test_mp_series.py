"""The families' Taylor series in mpmath (the compiled kernels' two-word constants, ``gaudin._compensated
.exact_tables``): each family's closed form (``mp_w_taylor``, ``mp_dressing_taylor``) against the generic definition
of :class:`jetgaudin.families.Family` — :func:`mpmath.taylor`'s numerical derivatives of ``mp_w`` and
``mp_dressing_basis`` at raised precision.  At 40 digits both are accurate to ~1e-38 relative; the tolerance 1e-32
relative to ``max(1, |coefficient|)`` is far below a double's 1e-16 (what the tables keep of them: two words, ~1e-32)
and far above the two's round-off, and a wrong recursion (a sign, a factor m, a missing 1/(k + 1)) is O(1) off."""

from __future__ import annotations

import mpmath
import pytest

from jetgaudin.families import Family
from jetgaudin.gaudin import GaudinModel

MODELS = {"rational": GaudinModel(1.0, [(0.0, 2), (0.7, 1)]),
          "trigonometric": GaudinModel(1.0, [(0.0, 2), (0.7, 1)], family="trigonometric", gamma=1.3),
          "elliptic": GaudinModel(0.0, [(0.0, 2), (0.7, 1)], family="elliptic", modulus=0.6),
          "elliptic, k = 0.95": GaudinModel(0.0, [(0.0, 2), (0.7, 1)], family="elliptic", modulus=0.95),
          "elliptic, k = 0.05": GaudinModel(0.0, [(0.0, 2), (0.7, 1)], family="elliptic", modulus=0.05)}


def close(a, b) -> bool:
    return abs(a - b) <= mpmath.mpf("1e-32") * max(1, abs(b))


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("n", [1, 2, 4])
def test_the_closed_form_series_are_the_numerical_taylor_series(name, n):
    fam = MODELS[name].family
    with mpmath.workdps(40):
        xi = mpmath.mpc("1.5", "0.2")
        for lam in (mpmath.mpf(0), mpmath.mpf("0.7"), mpmath.mpf("-0.35")):
            got, want = fam.mp_dressing_taylor(lam, xi, n), Family.mp_dressing_taylor(fam, lam, xi, n)
            assert len(got) == len(want) == fam.n_dressing
            for q in range(fam.n_dressing):
                for e in range(4):
                    assert len(got[q][e]) == n
                    assert all(close(g, w) for g, w in zip(got[q][e], want[q][e], strict=True)), (lam, q, e)
            got, want = fam.mp_w_taylor(xi - lam, n), Family.mp_w_taylor(fam, xi - lam, n)
            for a in range(3):
                assert all(close(g, w) for g, w in zip(got[a], want[a], strict=True)), (lam, a)
