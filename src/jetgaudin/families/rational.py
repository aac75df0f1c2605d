r"""The rational (XXX) family: ``w_a(x) = 1/x`` for every component (the paper's chains, issue 12).

``ν² = b² + Σ_{j,m} h_{j,m} (λ − λ_j)^{−m}`` (``ψ_m(x) = x^{−m}``, no extra integrals), the dressing
``K(λ) = λE + K_0`` in the basis ``{E11 λ, E11, E12, E21, E22 λ, E22}`` with the gauge rule ``E = 1`` (the
real two-point map of eq. (mm), :func:`jetgaudin.backlund._dressing.real_two_point_M0`).  The model core keeps
its closed-form routes for this family (``uniform``: the integrals use the Gram matrix of the ``y``'s; the
dressing's ``1/det K`` is the product of ``1/(λ − ξ)`` and ``1/(λ − ξ̄)``), so the chains' results are today's.
"""

from __future__ import annotations

import numpy as np

from ..backlund._dressing import real_two_point_M0
from ._base import Family

__all__ = ["RationalFamily"]


class RationalFamily(Family):
    """``w_a(x) = 1/x`` (module docstring)."""

    name = "rational"
    uniform = True
    n_dressing = 6
    kernel_rule = 0

    def taylor(self, a, x0, order):
        x0 = np.asarray(x0, dtype=complex)
        return np.stack([(-1) ** n * x0 ** (-(n + 1)) for n in range(order)])

    def regular(self, a, order):
        return np.zeros(order, dtype=complex)

    def phi(self, a, x, order):
        x = np.asarray(x, dtype=complex)
        return np.stack([x ** (-(k + 1)) for k in range(order)])

    def nu2_basis(self, m, x):
        return np.asarray(x, dtype=complex) ** (-m)

    def nu2_constant(self, b, extra):
        return np.full(np.shape(extra)[:-1], b * b)

    def uniformizer(self, lam):
        return np.asarray(lam, dtype=complex)

    def dressing_basis(self, lam):
        lam = np.asarray(lam, dtype=complex)
        out = np.zeros(lam.shape + (6, 2, 2), dtype=complex)
        out[..., 0, 0, 0] = lam
        out[..., 1, 0, 0] = 1.0
        out[..., 2, 0, 1] = 1.0
        out[..., 3, 1, 0] = 1.0
        out[..., 4, 1, 1] = lam
        out[..., 5, 1, 1] = 1.0
        return out

    def dressing_taylor(self, lam0, order):
        out = np.zeros((order, 6, 2, 2), dtype=complex)
        out[0] = self.dressing_basis(lam0)
        if order > 1:
            out[1, 0, 0, 0] = out[1, 4, 1, 1] = 1.0
        return out

    def mp_w(self, a, x):
        return 1 / x

    def mp_dressing_basis(self, lam, xi=None):
        return [[lam, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, lam], [0, 0, 0, 1]]

    def mp_dressing_taylor(self, lam, xi, n: int) -> list:
        """:meth:`mp_dressing_basis`'s Taylor coefficients at ``λ``: ``λ + t`` and ``1``."""
        import mpmath

        z = [mpmath.mpf(0)] * n
        one = [mpmath.mpf(1)] + z[1:]
        lin = [mpmath.mpmathify(lam)] + ([mpmath.mpf(1)] if n > 1 else []) + z[2:]
        return [[lin, z, z, z], [one, z, z, z], [z, one, z, z], [z, z, one, z], [z, z, z, lin], [z, z, z, one]]

    def mp_kernel_constants(self, xi):
        return [xi]

    def real_dressing(self, xi, k1, k2):
        # K = λ + M0 (gauge rule E = 1); k2 is implied by k1 for the real reduction (eq. (X))
        M0 = real_two_point_M0(xi, k1[..., 0], k1[..., 1])
        one = np.ones(M0.shape[:-2], dtype=complex)
        return np.stack([one, M0[..., 0, 0], M0[..., 0, 1], M0[..., 1, 0], one, M0[..., 1, 1]], axis=-1)
