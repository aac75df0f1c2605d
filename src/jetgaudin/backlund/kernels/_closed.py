r"""N = 3 by the corrected Appendix 1 closed form ``X̆ = Φ(s, t) X + X0(s, t)``
(:func:`jetgaudin.backlund.closed_form._two_point_core`), compiled with ``numba.njit`` when first asked for
(:func:`orbit_kernel`; not cached on disk: the core lives in another module).  For benchmarks and cross-checks
only (``tests/test_routes.py`` states its accuracy against the NumPy route).  Import only after
:func:`._target.configure`.
"""

from __future__ import annotations

from typing import Any

from numba import njit

from ._scalar import _abs2, _cdiv, _cr, _eigvec
from ._status import STATUS_OK

_cache: dict[str, Any] = {}


def orbit_kernel() -> Any:
    """The compiled ``orbit(x0, b, eta, nu0, steps, out) -> n`` (``n < steps``: the step where ``k1 = 0`` or the
    eigenvector test failed; ``out`` (steps + 1, 9) holds the states ``x_0..x_n``)."""
    if "orbit" in _cache:
        return _cache["orbit"]
    from ..closed_form import _two_point_core

    core = njit(cache=False, error_model="numpy", inline="always")(_two_point_core)

    @njit(cache=False, error_model="numpy")
    def orbit(x0, b, eta, nu0, steps, out):
        z1 = _cdiv(complex(1.0, 0.0), eta)
        z2 = z1 * z1
        z3 = z2 * z1
        x = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5], x0[6], x0[7], x0[8])
        for i in range(9):
            out[0, i] = x0[i]
        nu = nu0
        for n in range(steps):
            nu_sq = nu * nu
            inv_2nu = _cdiv(complex(1.0, 0.0), nu + nu)
            v1 = complex(x[0], -x[1])
            w1 = complex(x[0], x[1])
            v2 = complex(x[3], -x[4])
            w2 = complex(x[3], x[4])
            v3 = complex(x[6], -x[7])
            w3 = complex(x[6], x[7])
            u = (complex(b, 0.0) + _cr(z1, x[2])) + (_cr(z2, x[5]) + _cr(z3, x[8]))
            v = (v1 * z1 + v2 * z2) + v3 * z3
            w = (w1 * z1 + w2 * z2) + w3 * z3
            if n > 0:
                c = u * u + v * w - nu_sq
                nu = nu + c * inv_2nu
            k1, k2, nk, st = _eigvec(u, v, w, nu)
            if st != STATUS_OK or _abs2(k1) == 0.0:
                return n
            s = -_cdiv(k2, k1)
            t = complex(0.0, eta.imag + eta.imag) * s.conjugate() * (1.0 / (1.0 + _abs2(s)))
            r = core(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], b, eta.real, eta.imag, s, t)
            x = (r[0].real, r[1].real, r[2].real, r[3].real, r[4].real, r[5].real, r[6].real, r[7].real,
                 r[8].real)
            for i in range(9):
                out[n + 1, i] = x[i]
        return steps

    _cache["orbit"] = orbit
    return orbit
