r"""Multi-site jet-extended rational su(2) Gaudin models ("chains"), issue 12.

Sites ``[(λ_1, N_1), …, (λ_n, N_n)]`` (distinct real ``λ_i``, integer orders ``N_i ≥ 1``), field ``b e_3``:

.. math:: L(\lambda) = b\,\sigma^3 + \sum_i \sum_{k<N_i} \sum_a \sigma^a\,
          \frac{y^{(i)a}_k}{(\lambda-\lambda_i)^{k+1}},

the Lax matrix (lax2) of the paper with ``λ^{-(k+1)}`` replaced by ``(λ − λ_i)^{-(k+1)}`` and summed over
sites.  State ``(..., 3M)``, ``M = Σ N_i``: site by site, inside a site ``y_0, …, y_{N_i−1}``, each
``(y^1, y^2, y^3)`` (one site ``[(0, N)]`` is the one-site layout of :mod:`jetgaudin.algebra`).
Sites commute; inside a site the bracket is that of ``g^(N_i)``, eq. (LP).

``ν²(λ) = ⟨ξ(λ), ξ(λ)⟩ = b² + Σ_i Σ_{m=1}^{2N_i} h_{i,m} (λ − λ_i)^{-m}`` exactly (``ν² − b²`` is rational,
vanishes at infinity and has poles only at the sites, so it is the sum of its principal parts).  With
``R_i(λ) = b e_3 + Σ_{j≠i} ξ_j(λ) = Σ_n r^{(i)}_n (λ − λ_i)^n`` (Taylor at ``λ_i``):

.. math:: h_{i,m} = \sum_{k+l=m-2} \langle y^{(i)}_k, y^{(i)}_l\rangle
          + 2 \sum_{n \ge 0} \langle y^{(i)}_{m-1+n}, r^{(i)}_n\rangle,\qquad
          r^{(i)}_n = b e_3 \delta_{n0} + \sum_{j\ne i}\sum_k (-1)^n \binom{k+n}{n}
          \frac{y^{(j)}_k}{(\lambda_i-\lambda_j)^{k+n+1}}.

For ``m > N_i`` the second sum is empty and ``h_{i,m}`` is the Casimir ``C_{m−N_i}`` of ``g^(N_i)`` at site
``i`` (Prop. 2); the ``h_{i,m}``, ``m ≤ N_i``, are ``M`` Poisson-commuting Hamiltonians (the r-matrix
structure (er) of the sum).  One site at 0 gives ``h_m = H_m`` and ``h_{N+k} = C_k`` of Prop. 2.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from functools import cached_property
from math import comb
from typing import TYPE_CHECKING, Any

import numpy as np

from .._errors import InvalidParameterError, InvalidStateError
from .._validate import as_state, check_gradient, finite_result
from ..algebra import structure_constants
from ..families import make_family
from ..maps import Backend, Branch, map_from_description, register_map
from . import _site_constants as _jc
from ._model_map import model_map
from .hamiltonian import ChainHamiltonian

if TYPE_CHECKING:  # pragma: no cover
    from ._one_point import ChainOnePointBacklund
    from .maps import ChainTwoPointBacklund

__all__ = [
    "GaudinModel",
    "ChainHamiltonian",
    "parse_sites",
    "gaudin_magnet",
    "lagrange_chain",
    "twisted_chain",
    "clebsch_top",
]


def _check_sites(sites) -> tuple[tuple[float, int], ...]:
    try:
        items = list(sites)
    except TypeError:
        raise InvalidParameterError(
            f"sites must be a sequence of (position, order) pairs, e.g. [(-1.0, 2), (0.5, 3)]; got {sites!r}"
        ) from None
    if not items:
        raise InvalidParameterError("sites must contain at least one (position, order) pair")
    out = []
    for s in items:
        try:
            lam, N = s
        except (TypeError, ValueError):
            raise InvalidParameterError(f"each site must be a pair (position, order) or (position, order, c), "
                                        f"got {s!r}") from None
        if isinstance(lam, (complex, np.complexfloating)) and complex(lam).imag != 0:
            raise InvalidParameterError(f"site positions must be real (the poles of L lie on the real axis), "
                                        f"got {lam!r}")
        try:
            lamf = float(np.real(lam))
        except (TypeError, ValueError):
            raise InvalidParameterError(f"a site position must be a real number, got {lam!r}") from None
        if not np.isfinite(lamf):
            raise InvalidParameterError(f"site positions must be finite, got {lamf}")
        if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
            raise InvalidParameterError(f"the order N_i of the site at {lamf} must be an integer >= 1, got {N!r}")
        out.append((lamf, int(N)))
    pos = [p for p, _ in out]
    if len(set(pos)) != len(pos):
        dup = sorted({p for p in pos if pos.count(p) > 1})
        raise InvalidParameterError(
            f"site positions must be distinct, got {dup} more than once; merge them into one site of higher order"
        )
    return tuple(out)


def parse_sites(text: str) -> list[tuple[float, int]]:
    """Parse ``"λ1:N1,λ2:N2,…"`` (e.g. ``"-1:2,0.5:3,2:1"``) into ``[(λ1, N1), …]``.

    Raises
    ------
    InvalidParameterError
        On any malformed item, a non-integer or non-positive order, or repeated positions.

    >>> parse_sites("-1:2, 0.5:3,2:1")
    [(-1.0, 2), (0.5, 3), (2.0, 1)]
    """
    if not isinstance(text, str) or not text.strip():
        raise InvalidParameterError('sites: give "position:order" pairs separated by commas, e.g. "-1:2,0.5:3"')
    out = []
    for item in text.split(","):
        item = item.strip()
        m = re.fullmatch(r"([^:]+):([^:]+)", item)
        if m is None:
            raise InvalidParameterError(f'sites: "{item}" is not of the form position:order (e.g. "0.5:3")')
        try:
            lam = float(m.group(1))
        except ValueError:
            raise InvalidParameterError(f'sites: the position "{m.group(1).strip()}" in "{item}" is not a real '
                                        "number") from None
        order = m.group(2).strip()
        if not re.fullmatch(r"\+?\d+", order):
            raise InvalidParameterError(f'sites: the order "{order}" in "{item}" must be an integer >= 1')
        out.append((lam, int(order)))
    return list(_check_sites(out))


def _taylor_coefficient(k: int, n: int, d: float) -> float:
    """``[z^n] (z + d)^{-(k+1)} = (−1)^n C(k+n, n) d^{−(k+n+1)}``."""
    return (-1) ** n * comb(k + n, n) * d ** (-(k + n + 1))


@dataclass(frozen=True)
class GaudinModel:
    r"""The chain with ``sites = [(λ_i, N_i), …]`` in the field ``b e_3`` (see the module docstring), of the
    Gaudin family ``family`` (``docs/families.md``: the formulas above are the rational family's; the
    trigonometric one replaces ``(λ − λ_i)^{−(k+1)}`` by ``φ_{a,k}(λ − λ_i)`` built on ``γ/sin(γx)``,
    ``γ cot(γx)``, :mod:`jetgaudin.families.trigonometric`).

    Parameters
    ----------
    b : float
        Field strength (any real; ``b = 0`` is the magnet without field, see ``docs/chains.md``).
    sites : sequence of (float, int)
        Distinct real positions (modulo the family's period, ``π/γ`` for the trigonometric family) and integer
        orders ``N_i ≥ 1`` (default: one site at 0 of order 1, a single spin in the field).
    family : {"rational", "trigonometric", "elliptic"} or jetgaudin.families.Family
        The family (default rational: the paper's chains).
    gamma : float, optional
        The anisotropy ``γ > 0`` of the trigonometric family (default 1); the rational family has none.
    modulus : float, optional
        The modulus ``k ∈ [0, 1)`` of the elliptic (XYZ) family (required by it; ``b`` must be 0 there,
        :mod:`jetgaudin.families.elliptic`).
    constants : sequence, optional
        The jet constants of eq. (lax) per site: ``None`` (the reduction (lax2)) or the real ``c_1, …, c_{N_s−1}``
        (``c_1 ≠ 0``); a site may also be given as ``(λ_s, N_s, c)``.  A site with constants is the reduced site in
        ``Y = T^T y`` (:mod:`jetgaudin.gaudin._site_constants`, ``docs/chains.md``): :meth:`to_reduced`,
        :attr:`reduced`.
    algebra : str or jetgaudin.lie.SU, optional
        ``"su(2)"`` (default: this class) or ``"su(n)"`` / ``"sun"`` / ``jg.su(n)``, ``n ≥ 3``: the su(n) chain of
        :class:`jetgaudin.gaudin.sun.SunGaudinModel` (rational family; ``b`` a float along ``λ_3``, ``n² − 1``
        components or a traceless Hermitian matrix), which the constructor returns.

    Raises
    ------
    InvalidParameterError
        Non-real, non-finite or repeated positions; orders not integers ``≥ 1``; ``b`` not a finite real; an
        unknown family; ``gamma`` not a finite real ``> 0``, or given to the rational family; sites equal modulo
        the period.
    """

    b: float
    sites: tuple = field(default=((0.0, 1),))
    family: Any = "rational"
    gamma: float | None = None
    modulus: float | None = None
    algebra: Any = "su(2)"
    constants: tuple | None = None

    def __new__(cls, *args, **kwargs):
        """``algebra`` other than su(2): a :class:`jetgaudin.gaudin.sun.SunGaudinModel` (issue 32)."""
        if cls is GaudinModel:
            from ..lie import parse_algebra

            if parse_algebra(kwargs.get("algebra", args[5] if len(args) > 5 else "su(2)")).n != 2:
                cls = model_map("sun_model")  # jetgaudin.gaudin.sun.SunGaudinModel (registered: no import circle)
        return object.__new__(cls)

    def __post_init__(self):
        from ..lie import parse_algebra

        if parse_algebra(self.algebra).n != 2:
            raise InvalidParameterError(f"{self.algebra}: use GaudinModel(..., algebra=...) for su(n), n >= 3")
        object.__setattr__(self, "algebra", "su(2)")
        if np.iscomplexobj(self.b) or isinstance(self.b, bool):
            raise InvalidParameterError(f"the field strength b must be a real number, got {self.b!r}")
        try:
            b = float(self.b)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"the field strength b must be a real number, got {self.b!r}") from None
        if not np.isfinite(b):
            raise InvalidParameterError(f"the field strength b must be finite, got {b}")
        object.__setattr__(self, "b", b)
        sites, constants = _jc.split_sites(self.sites, self.constants)
        object.__setattr__(self, "sites", _check_sites(sites))
        object.__setattr__(self, "constants", _jc.normalise(self.sites, constants))
        fam = make_family(self.family, gamma=self.gamma, modulus=self.modulus)
        fam.check(b, self.sites)
        object.__setattr__(self, "family", fam)
        object.__setattr__(self, "gamma", fam.describe().get("gamma"))
        object.__setattr__(self, "modulus", fam.describe().get("modulus"))

    # ---- layout ---------------------------------------------------------------------------

    @property
    def M(self) -> int:
        """``M = Σ N_i`` (number of 3-vectors in a state)."""
        return sum(N for _, N in self.sites)

    @property
    def n_state(self) -> int:
        """Length ``3M`` of a state."""
        return 3 * self.M

    @property
    def positions(self) -> np.ndarray:
        return np.array([p for p, _ in self.sites])

    @property
    def orders(self) -> tuple[int, ...]:
        return tuple(N for _, N in self.sites)

    @cached_property
    def offsets(self) -> tuple[int, ...]:
        """Index of ``y_0`` of each site among the ``M`` 3-vectors."""
        return tuple(int(x) for x in np.concatenate([[0], np.cumsum(self.orders)[:-1]]))

    def labels(self) -> list[str]:
        """Column names ``s{i}_y{k}^{a}`` of the ``3M`` state components (site ``i`` from 1)."""
        return [f"s{i + 1}_y{k}^{a}" for i, (_, N) in enumerate(self.sites) for k in range(N) for a in (1, 2, 3)]

    def check_state(self, X, *, allow_complex: bool = False) -> np.ndarray:
        """``X`` as a float (or complex) array ``(..., 3M)``; :class:`InvalidStateError` otherwise."""
        X, _ = as_state(X, allow_complex=allow_complex)
        if X.shape[-1] != self.n_state:
            raise InvalidStateError(
                f"a state of the chain with sites {list(self.sites)} has 3M = {self.n_state} components "
                f"(M = sum of the orders = {self.M}), got {X.shape[-1]}; give one 3-vector per site and order"
            )
        return X

    def describe(self) -> dict:
        """``{"b", "sites"}`` and, for a family other than the rational one, ``"family"`` and its parameters; a model
        with jet constants: ``"constants"`` (one ``null`` or list per site)."""
        d: dict = {"b": self.b, "sites": [[p, N] for p, N in self.sites]}
        if self.constants is not None:
            d["constants"] = [None if c is None else list(c) for c in self.constants]
        if self.family.name != "rational":
            d.update({"family": self.family.name, **self.family.describe()})
        return d

    @classmethod
    def from_description(cls, d: dict) -> GaudinModel:
        """The model :meth:`describe` (or a map's description) describes."""
        extra = {k: d[k] for k in ("gamma", "modulus", "algebra", "constants") if k in d}
        return cls(d["b"], tuple((float(p), int(N)) for p, N in d["sites"]), d.get("family", "rational"), **extra)

    # ---- jet constants: the reduced model in Y = T^T y (jetgaudin.gaudin._site_constants) ----------------

    @cached_property
    def reduced(self) -> GaudinModel:
        """This model without its jet constants (itself when it has none): the model in the variables ``Y``."""
        return self if self.constants is None else replace(self, constants=None, gamma=None, modulus=None)

    @cached_property
    def jet_matrix(self) -> np.ndarray:
        """``S`` ``(M, M)``: ``Y = S y`` per component (block diagonal, ``T_s^T`` at a site with constants, else the
        identity; :func:`jetgaudin.gaudin._site_constants.jet_matrix`), read-only."""
        return _jc.jet_matrix(self)

    def to_reduced(self, X) -> np.ndarray:
        """The state of :attr:`reduced` for ``X`` ``(..., 3M)``: every site's ``Y_n = Σ_i T[i, n] y_i`` (a Poisson
        isomorphism: the module doc of :mod:`jetgaudin.gaudin._site_constants`)."""
        X = self.check_state(X, allow_complex=True)
        return X if self.constants is None else _jc.apply(self.jet_matrix, X)

    def from_reduced(self, X) -> np.ndarray:
        """The inverse of :meth:`to_reduced` (``S^{-1}``, block triangular: ``T_s`` has the diagonal ``(−c_1)^n``)."""
        X = self.check_state(X, allow_complex=True)
        return X if self.constants is None else _jc.apply(self._inverse_jet_matrix, X)

    @cached_property
    def _inverse_jet_matrix(self) -> np.ndarray:
        S = np.linalg.inv(self.jet_matrix)
        S.setflags(write=False)
        return S

    # ---- integrals as quadratic forms --------------------------------------------------------

    @cached_property
    def _forms(self):
        """The integrals as forms in the ``y``'s: today's closed formula for the rational family, the generic
        Laurent tables of :mod:`jetgaudin.gaudin._forms` for the others; with jet constants the reduced model's
        forms in ``Y = S y`` (``q → S^T q S``; the family's linear extras involve only the ``y_0 = Y_0``)."""
        if self.constants is not None:
            return _jc.forms(self.jet_matrix, *self.reduced._forms)
        if self.family.uniform:
            return self._rational_forms
        from ._forms import generic_forms

        return generic_forms(self)

    @cached_property
    def _rational_forms(self):
        """``(q, l)``: ``h_{i,m}(X) = Σ_{c,d} q[I, c, d] ⟨y_c, y_d⟩ + 2 b Σ_c l[I, c] y_c^3`` over the ``M``
        3-vectors ``y_c`` (``I`` runs over ``(i, m)`` in the order of :meth:`integrals`)."""
        M = self.M
        q = np.zeros((2 * M, M, M))
        lin = np.zeros((2 * M, M))
        row = 0
        for i, (lam_i, N_i) in enumerate(self.sites):
            oi = self.offsets[i]
            for m in range(1, 2 * N_i + 1):
                for k in range(N_i):
                    l_ = m - 2 - k
                    if 0 <= l_ < N_i:
                        q[row, oi + k, oi + l_] += 1.0
                if m <= N_i:
                    lin[row, oi + m - 1] = 1.0
                    for n in range(N_i - m + 1):
                        c_i = oi + m - 1 + n
                        for j, (lam_j, N_j) in enumerate(self.sites):
                            if j == i:
                                continue
                            for k in range(N_j):
                                c = _taylor_coefficient(k, n, lam_i - lam_j)
                                q[row, c_i, self.offsets[j] + k] += c
                                q[row, self.offsets[j] + k, c_i] += c
                row += 1
        q.setflags(write=False)
        lin.setflags(write=False)
        return q, lin

    def _extra_labels(self) -> list[str]:
        """The integrals after the ``h_{j,m}``: the constant term of ``ν²`` when it is one (elliptic ``c0``), then
        the family's linear extras (trigonometric ``J``)."""
        c = self.family.constant_integral
        return ([c] if c else []) + self.family.extra_integrals(self.sites)[0]

    @property
    def n_integrals(self) -> int:
        """``2M`` plus the family's extra integrals (trigonometric: ``J``; elliptic: ``c0``)."""
        return 2 * self.M + len(self._extra_labels())

    def integral_labels(self) -> list[str]:
        """Names ``h{i},{m}`` of the ``2M`` integrals (site ``i`` from 1), then the family's extras (``J``,
        ``c0``)."""
        return [f"h{i + 1},{m}" for i, (_, N) in enumerate(self.sites) for m in range(1, 2 * N + 1)] + \
            self._extra_labels()

    def casimir_mask(self) -> np.ndarray:
        """Boolean ``(n_integrals,)``: ``True`` for the Casimirs ``h_{i,m}``, ``m > N_i``; ``False`` for the ``M``
        commuting Hamiltonians ``h_{i,m}``, ``m ≤ N_i`` and the extras (``J`` generates the rotations about
        ``e_3``)."""
        n_extra = self.n_integrals - 2 * self.M
        return np.array([m > N for _, N in self.sites for m in range(1, 2 * N + 1)] + [False] * n_extra)

    def integrals(self, X) -> np.ndarray:
        r"""``(h_{1,1}, …, h_{1,2N_1}, h_{2,1}, …)``, shape ``(..., 2M)``: the exact partial-fraction
        coefficients of ``ν²(λ) − b²`` (module docstring).  One site at 0: ``(H_1..H_N, C_1..C_N)``.

        Parameters
        ----------
        X : array_like, shape (..., 3M)

        Returns
        -------
        ndarray, shape (..., 2M)
        """
        X = self.check_state(X, allow_complex=True)
        y = X.reshape(X.shape[:-1] + (self.M, 3))
        q, lin = self._forms
        if self.family.uniform:
            gram = np.einsum("...ca,...da->...cd", y, y)
            out = np.einsum("Icd,...cd->...I", q, gram) + 2.0 * self.b * np.einsum("Ic,...c->...I", lin, y[..., 2])
        else:
            from ._forms import evaluate

            out = evaluate(self, q, lin, X)
        return finite_result(out, "the chain integrals h_{i,m}")

    def integral_gradients(self, X) -> np.ndarray:
        """Gradients of the ``2M`` integrals, shape ``(..., 2M, 3M)`` (exact: the ``h`` are quadratic)."""
        X = self.check_state(X, allow_complex=True)
        y = X.reshape(X.shape[:-1] + (self.M, 3))
        q, lin = self._forms
        if not self.family.uniform:
            from ._forms import gradients

            return gradients(self, q, lin, X)
        g = 2.0 * np.einsum("Icd,...da->...Ica", q, y)
        g[..., 2] += 2.0 * self.b * lin
        return g.reshape(X.shape[:-1] + (2 * self.M, 3 * self.M))

    # ---- Poisson structure -----------------------------------------------------------------

    @cached_property
    def structure_constants(self) -> np.ndarray:
        r"""``c[I, J, K]`` with ``{X_I, X_J} = Σ_K c[I, J, K] X_K``: block diagonal, ``g^(N_i)`` (LP) per site,
        shape ``(3M, 3M, 3M)``, read-only."""
        n = self.n_state
        c = np.zeros((n, n, n))
        for i, (_, N) in enumerate(self.sites):
            s = slice(3 * self.offsets[i], 3 * (self.offsets[i] + N))
            c[s, s, s] = structure_constants(N)
        c.setflags(write=False)
        return c

    def poisson_tensor(self, X) -> np.ndarray:
        r"""``Π(X)_{IJ} = {X_I, X_J}``, shape ``(..., 3M, 3M)`` (block diagonal over sites)."""
        X = self.check_state(X, allow_complex=True)
        return np.einsum("ijk,...k->...ij", self.structure_constants, X)

    def vector_field(self, grad_H, X) -> np.ndarray:
        """``Ẋ = Π(X) ∇H``, shape ``(..., 3M)``."""
        X = self.check_state(X, allow_complex=True)
        grad_H = check_gradient(grad_H, self.n_state, name="grad_H")
        out = np.empty(np.broadcast_shapes(X.shape, grad_H.shape), dtype=np.result_type(X, grad_H))
        for i, (_, N) in enumerate(self.sites):
            s = slice(3 * self.offsets[i], 3 * (self.offsets[i] + N))
            out[..., s] = np.einsum("ijk,...k,...j->...i", structure_constants(N), X[..., s], grad_H[..., s])
        return out

    # ---- Lax matrix, spectral curve, Hamiltonians -------------------------------------------

    def lax_matrix(self, X, lam) -> np.ndarray:
        r"""``L(λ) = Σ_a σ^a ξ^a(λ)``, ``ξ(λ) = b e_3 + Σ_i Σ_k y^{(i)}_k (λ − λ_i)^{-(k+1)}``, shape
        ``(..., 2, 2)`` (``lam`` broadcast against ``X[..., 0]``)."""
        from ..lax import SIGMA

        return np.einsum("...a,aij->...ij", self.xi(X, lam), SIGMA)

    def xi(self, X, lam) -> np.ndarray:
        """``ξ(λ)`` (the coefficient vector of ``L``), shape ``(..., 3)``."""
        from ._curve import lax_vector

        return lax_vector(*self._curve_args(X), lam)

    def _curve_args(self, X) -> tuple[GaudinModel, Any]:
        """``(model, X)`` for the spectral-curve functions: the reduced model at ``P X`` where the sites carry jet
        constants (the Lax matrix is the reduced one's in ``Y``), else ``(self, X)``."""
        return (self, X) if self.constants is None else (self.reduced, self.to_reduced(X))

    def nu_squared(self, X, lam) -> np.ndarray:
        """``ν²(λ) = u² + vw = ⟨ξ(λ), ξ(λ)⟩`` evaluated directly, shape ``(...)``."""
        xi = self.xi(X, lam)
        return np.sum(xi * xi, axis=-1)

    def nu(self, X, eta, *, sheet: int = 1) -> np.ndarray:
        """``ν(η)`` on the default branch (positive at ``Re η``, continued vertically); see
        :func:`jetgaudin.gaudin._curve.nu`."""
        from ._curve import nu

        return nu(*self._curve_args(X), eta, sheet=sheet)

    def branch_points(self, X) -> np.ndarray:
        """The zeros of ``ν²``: roots of ``D(λ)² ν²(λ)``, ``D = Π (λ − λ_i)^{N_i}``, shape ``(..., 2M)``
        (``(..., 2M − 2)`` for ``b = 0``).  Trigonometric: the ``2M`` zeros in one period, ``λ = log(z_k)/(2iγ)``
        with ``Re λ`` in ``(−π/(2γ), π/(2γ)]``, ``z_k`` the roots in ``z = e^{2iγλ}``; a family without a
        uniformizer: none (``(..., 0)``; its branch rule is numerical)."""
        from ._curve import branch_points

        r = branch_points(*self._curve_args(X))
        return r if self.family.uniform else self.family.uniformizer_inverse(r)

    def hamiltonian(self, weights) -> ChainHamiltonian:
        """``H = Σ w_{i,m} h_{i,m}`` as an object for :func:`jetgaudin.integrate`."""
        return ChainHamiltonian(self, weights)

    def physical_hamiltonian(self) -> ChainHamiltonian:
        """The chain's physical Hamiltonian: ``ν²/2``'s first non-trivial coefficient at the family's infinity
        (rational: ``½Σ_i (λ_i h_{i,1} + h_{i,2})``, the top's ``H_2/2`` for one site at 0;
        :mod:`jetgaudin.gaudin.physical`)."""
        from .physical import physical_weights

        return ChainHamiltonian(self, physical_weights(self))

    def interpolating_hamiltonian(self, X, eta) -> np.ndarray:
        r"""``G_η(X) = i∫_{η̄}^{η} ν dλ = −2∫_0^{Im η} Re ν(Re η + is) ds``, shape ``(...)``."""
        from ._curve import interpolating_hamiltonian

        return interpolating_hamiltonian(*self._curve_args(X), eta)

    def interpolating_weights(self, X, eta) -> np.ndarray:
        r"""``ω_{i,m} = ∂G_η/∂h_{i,m} = −2∫_0^{Im η} Re[(λ − λ_i)^{-m} / (2ν(λ))] ds``, shape ``(..., 2M)``."""
        from ._curve import interpolating_weights

        return interpolating_weights(*self._curve_args(X), eta)

    def interpolating_flow_hamiltonian(self, X, eta) -> ChainHamiltonian:
        """``Σ ω_{i,m}(X) h_{i,m}``: its flow from ``X`` is the flow of ``G_η`` (the ``ω`` are constant on it)."""
        return ChainHamiltonian(self, self.interpolating_weights(X, eta))

    # ---- the top as a one-site model (issue 33) ------------------------------------------------

    @property
    def is_top(self) -> bool:
        """One rational site at ``λ = 0`` in a nonzero field: the ``N``-th top of the paper
        (:class:`jetgaudin.GaudinTop` ``(N, b)``, Lax matrix (lax2)), whose integrals, bracket and maps this model's
        equal to round-off, and whose hand-tuned kernels are a route of its maps (``docs/architecture.md``)."""
        return (self.family.name == "rational" and len(self.sites) == 1 and self.sites[0][0] == 0.0 and self.b != 0.0
                and self.constants is None)

    def as_top(self):
        """The top this one-site model is (:class:`jetgaudin.GaudinTop`); :class:`InvalidParameterError` for any
        other model (naming why: the top is one rational site at 0 with ``b ≠ 0``)."""
        if not self.is_top:
            raise InvalidParameterError(
                f"this model is not a top: a top is one rational site at 0 in a nonzero field b, this one has "
                f"{self.family.name} sites {list(self.sites)} and b = {self.b:g}"
                + ("" if self.constants is None else " with jet constants (the top's kernels take none: its maps are "
                   "the reduced model's, conjugated)"))
        from ..systems import GaudinTop

        return GaudinTop(self.orders[0], self.b)

    # ---- maps ---------------------------------------------------------------------------------

    def two_point_backlund(self, eta, branch: Branch | str = "default", backend: Backend | str = "auto",
                           kernel: Backend | str | None = None) -> ChainTwoPointBacklund:
        """The real two-point Bäcklund map of the chain (:class:`~jetgaudin.gaudin.maps.ChainTwoPointBacklund`;
        ``backend`` / its alias ``kernel``: the route of ``advance`` / ``iterate``, default ``"auto"``)."""
        if self.constants is not None:  # the reduced model's map conjugated by P (jetgaudin.gaudin._site_constants)
            return _jc.conjugated(self, self.reduced.two_point_backlund(eta, branch, backend, kernel))  # type: ignore
        return model_map("chain_two_point")(self, eta, Branch.parse(branch), Backend.parse(backend), kernel)

    def one_point_backlund(
        self, eta, branch: Branch | str = "default", inverse_map: bool = False, backend: Backend | str = "auto",
        kernel: Backend | str | None = None,
    ) -> ChainOnePointBacklund:
        """The complex one-point map (:class:`~jetgaudin.gaudin.ChainOnePointBacklund`): rational family with
        ``b ≠ 0``, trigonometric with ``b + iγJ ≠ 0`` (``docs/families.md`` §3.1); the elliptic family has none."""
        if self.constants is not None:  # the reduced model's map conjugated by P
            return _jc.conjugated(self, self.reduced.one_point_backlund(  # type: ignore[return-value]
                eta, branch, inverse_map, backend, kernel))
        return model_map("chain_one_point")(self, eta, Branch.parse(branch), inverse_map, Backend.parse(backend),
                                            kernel)


def _site_constants_map(d: dict) -> _jc.SiteConstantsMap:
    return _jc.SiteConstantsMap(GaudinModel.from_description(d["model"]), map_from_description(d["map"]))


register_map("site_constants", _site_constants_map)


def _uniform(b, positions, N, name):
    try:
        pos = list(positions)
    except TypeError:
        raise InvalidParameterError(f"{name}: positions must be a sequence of real numbers, got {positions!r}") \
            from None
    return GaudinModel(b, [(p, N) for p in pos])


def gaudin_magnet(b: float, positions) -> GaudinModel:
    """The rational su(2) Gaudin magnet: one spin (``N_i = 1``) at each position."""
    return _uniform(b, positions, 1, "gaudin_magnet")


def lagrange_chain(b: float, positions) -> GaudinModel:
    """The Lagrange chain of ``⊕ e(3)``: ``N_i = 2`` at each position."""
    return _uniform(b, positions, 2, "lagrange_chain")


def twisted_chain(b: float, positions) -> GaudinModel:
    """The twisted (generalised Lagrange) chain: ``N_i = 3`` at each position."""
    return _uniform(b, positions, 3, "twisted_chain")


def clebsch_top(modulus: float, position: float = 0.0) -> GaudinModel:
    r"""The Clebsch top: one elliptic (XYZ) jet site of order 2 at ``position`` (modulus ``k``), the coalescence of two
    order-1 sites (``docs/tutorials/xyz.md``).  State ``(M, p) = (y_0, y_1)`` with the bracket of ``e(3)`` (``g^(2)``):
    ``{M_a, M_b} = ε_{abc} M_c``, ``{M_a, p_b} = ε_{abc} p_c``, ``{p_a, p_b} = 0``.  Integrals (``integrals(X)``):
    ``h_{1,1} = 0``, ``h_{1,2} = |M|² − 2 Σ_a r_a p_a²``, the Casimirs ``h_{1,3} = 2 M·p``, ``h_{1,4} = |p|²``, and
    ``c0 = Σ_a A_a M_a² + Σ_a B_a p_a²`` with ``A = (1, k'², 0) − E/K``, ``r_a`` the ``x`` coefficients of ``w_a − 1/x``
    (``(1+k²)/6``, ``(1−2k²)/6``, ``−(2−k²)/6``).  Every ``H_μ = c0 + μ h_{1,2} = Σ a_i M_i² + Σ b_i p_i²``
    (``a_i = A_i + μ``) is a Kirchhoff Hamiltonian (a rigid body in an ideal fluid) in **Clebsch's case**
    ``b_i = a_j a_k + const`` (``(i, j, k)`` cyclic; equivalently ``Σ_cyc (b_j − b_k)/a_i = 0``), with
    ``k² = (a_1 − a_2)/(a_1 − a_3)``.  Conversely a Clebsch Hamiltonian ``Σ a_i M_i² + Σ (θ a_j a_k + c) p_i²`` with
    ``a_1 > a_2 > a_3`` and ``θ > 0`` is ``s^{-1}`` times a member of this pencil plus Casimirs (``s = 1/(a_1 − a_3)``)
    after ``p → λp`` (``λ² = s/θ``, an automorphism of ``e(3)``), with that ``k`` (the pencil's Clebsch form and ``k``
    are tested in ``tests/test_elliptic.py``).  As a motion, Kirchhoff's equations for ``½Σ a_i M_i² + ½Σ b_i p_i²``
    are the flow of ``c0 + μ h_{1,2}`` (``μ = s a_3 + E/K``) at time ``t/(2s)`` in the variables ``−(M, p/λ)``:
    :func:`jetgaudin.kirchhoff_clebsch` (``docs/physical.md`` §2)."""
    return GaudinModel(0.0, ((position, 2),), family="elliptic", modulus=modulus)
