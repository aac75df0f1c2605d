r"""The Lie algebra su(n): the generalised Gell-Mann basis and its structure constants (issue 32).

Basis ``λ_a``, ``a = 1..n²−1`` (Hermitian, traceless, ``tr λ_a λ_b = 2 δ_ab``), in the **nested order**: for
``k = 2..n``, the pairs ``(j, k−1)``, ``j < k−1`` (0-based), each symmetric ``E_{j,k−1} + E_{k−1,j}`` then
antisymmetric ``−i E_{j,k−1} + i E_{k−1,j}``, then the diagonal one of size ``k``,
``√(2/(k(k−1))) diag(1, …, 1, −(k−1), 0, …)``.  ``n = 2`` gives the Pauli matrices ``(σ_x, σ_y, σ_z)`` and
``n = 3`` Gell-Mann's ``λ_1 … λ_8`` in their usual order (``tests/test_lie.py``).  The structure constants are
real and totally antisymmetric:

.. math:: [\lambda_a, \lambda_b] = 2i f_{abc} \lambda_c, \qquad f_{abc} = \frac{1}{4i}\operatorname{tr}
          ([\lambda_a, \lambda_b] \lambda_c)

(``f = ε`` for ``n = 2``).  A Hermitian matrix ``H = Σ_a h^a λ_a + (tr H/n) 1`` has ``h^a = tr(λ_a H)/2``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache, cached_property

import numpy as np

from ._errors import InvalidParameterError

__all__ = ["SU", "su", "parse_algebra", "gell_mann_basis"]


@cache
def gell_mann_basis(n: int) -> np.ndarray:
    """The ``n² − 1`` generalised Gell-Mann matrices in the nested order (module docstring), ``(n²−1, n, n)``,
    read-only."""
    out = []
    for k in range(2, n + 1):
        for j in range(k - 1):
            s = np.zeros((n, n), dtype=complex)
            s[j, k - 1] = s[k - 1, j] = 1.0
            a = np.zeros((n, n), dtype=complex)
            a[j, k - 1], a[k - 1, j] = -1j, 1j
            out += [s, a]
        d = np.zeros((n, n), dtype=complex)
        d[np.arange(k - 1), np.arange(k - 1)] = 1.0
        d[k - 1, k - 1] = -(k - 1)
        out.append(np.sqrt(2.0 / (k * (k - 1))) * d)
    basis = np.array(out)
    basis.setflags(write=False)
    return basis


@cache
def _structure_constants(n: int) -> np.ndarray:
    lam = gell_mann_basis(n)
    comm = np.einsum("aij,bjk->abik", lam, lam) - np.einsum("bij,ajk->abik", lam, lam)
    f = np.einsum("abij,cji->abc", comm, lam) / 4j
    f = np.where(np.abs(f) < 1e-14, 0.0, f.real)  # exact zeros where the trace vanishes
    f.setflags(write=False)
    return f


@dataclass(frozen=True)
class SU:
    """The Lie algebra su(n), ``n ≥ 2`` (module docstring); ``jg.su(3)``.

    Raises
    ------
    InvalidParameterError
        ``n`` not an integer ``≥ 2``.
    """

    n: int

    def __post_init__(self):
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or self.n < 2:
            raise InvalidParameterError(f"su(n) needs an integer n >= 2, got {self.n!r}")
        object.__setattr__(self, "n", int(self.n))

    @property
    def name(self) -> str:
        return f"su({self.n})"

    def __str__(self) -> str:
        return self.name

    @property
    def dim(self) -> int:
        """``n² − 1``."""
        return self.n * self.n - 1

    @property
    def basis(self) -> np.ndarray:
        """The Gell-Mann matrices ``λ_a``, ``(dim, n, n)``, read-only."""
        return gell_mann_basis(self.n)

    @property
    def structure_constants(self) -> np.ndarray:
        """``f_abc`` with ``[λ_a, λ_b] = 2i f_abc λ_c``, ``(dim, dim, dim)``, read-only."""
        return _structure_constants(self.n)

    @cached_property
    def _dual(self) -> np.ndarray:
        # tr(λ_a H)/2 = Σ_ij (λ_a)_ji H_ij / 2
        d = np.transpose(self.basis, (0, 2, 1)) / 2.0
        d.setflags(write=False)
        return d

    def matrix(self, v) -> np.ndarray:
        """``Σ_a v^a λ_a``, ``(..., n, n)`` from ``(..., dim)`` (complex ``v`` allowed: the complexification)."""
        return np.einsum("...a,aij->...ij", v, self.basis)

    def components(self, H) -> np.ndarray:
        """``h^a = tr(λ_a H)/2``, ``(..., dim)`` (complex)."""
        return np.einsum("aij,...ij->...a", self._dual, H)


def su(n: int) -> SU:
    """The Lie algebra su(n) (:class:`SU`)."""
    return SU(n)


def parse_algebra(spec) -> SU:
    """``"su(3)"``, ``"su3"``, ``"SU(3)"`` or an :class:`SU` as an :class:`SU`.

    Raises
    ------
    InvalidParameterError
        Anything else (the message lists what is accepted).
    """
    if isinstance(spec, SU):
        return spec
    if isinstance(spec, str):
        m = re.fullmatch(r"\s*su\s*\(?\s*(\d+)\s*\)?\s*", spec, flags=re.IGNORECASE)
        if m is not None and int(m.group(1)) >= 2:
            return SU(int(m.group(1)))
    raise InvalidParameterError(
        f"unknown algebra {spec!r}: give su(n) with n >= 2 as 'su(3)', 'su3' or jetgaudin.su(3)"
    )
