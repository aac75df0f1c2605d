r"""The contract between a Gaudin *family* and the one model core (``docs/families.md``, issue 23).

A model of any family is the Lax matrix ``ℓ = −2iL = Σ_a ξ^a(λ) σ_a = [[u, v], [w, −u]]`` (``u = ξ^3``,
``v = ξ^1 − iξ^2``, ``w = ξ^1 + iξ^2``) with

.. math:: \xi^a(\lambda) = b\,\delta_{a3} + \sum_j \sum_{k<N_j} y^{(j)a}_k\, \varphi_{a,k}(\lambda-\lambda_j),
          \qquad \varphi_{a,k}(x) = \frac{(-1)^k}{k!}\, w_a^{(k)}(x),

one function ``w_a`` per Pauli component whose Laurent expansion at 0 is ``1/x + regular``, so that
``φ_{a,k}(x) = x^{−(k+1)} + regular`` and a site of order ``N`` carries ``y_0..y_{N−1}`` exactly as for the
rational chains (state ``(..., 3M)``, per site the Lie–Poisson bracket of ``g^(N)``).  A family is

1. **its basis functions** ``w_a`` (rational ``1/x``; trigonometric ``γ/sin(γx)``, ``γ/sin(γx)``,
   ``γ cot(γx)``; elliptic ``ns, ds, cs``), given as Taylor coefficients (:meth:`Family.taylor`,
   :meth:`Family.regular`) computed with :mod:`jetgaudin.families._series`;
2. **the expansion of** ``ν² = Σ_a (ξ^a)²``: ``ν² = constant + Σ_{j,m} h_{j,m} ψ_m(λ − λ_j)``
   (:meth:`Family.nu2_basis` ``ψ_m``, :meth:`Family.nu2_constant`), the ``h_{j,m}`` (principal-part
   coefficients of ``ν²`` at ``λ_j``) being computed by the core for every family, plus any *extra* integrals
   the family has (trigonometric: ``J = Σ_j y^{(j)3}_0``, :meth:`Family.extra_integrals`);
3. **the dressing form** ``D(λ) = Σ_p c_p B_p(λ)`` (:meth:`Family.dressing_basis`,
   :meth:`Family.dressing_taylor`) for which ``ℓ̃ = D ℓ D^{-1}`` keeps the form of ``ℓ`` (same ``b``, same
   ``w_a``);
4. **the gauge rule**: :meth:`Family.real_dressing` returns the coefficients ``c`` of the real two-point map
   from the eigenvectors at ``ξ, ξ̄`` (spectrality ``D(ξ_i) k_i = 0`` leaves a null space; the rule picks the
   member that makes the map real, Poisson and equal to the time-1 flow of ``G_ξ``);
5. optionally **the one-point dressing** (:attr:`Family.one_point_refusal` ``None``,
   :meth:`Family.one_point_normalisation`, :meth:`Family.one_point_dressing`): a dressing whose determinant vanishes
   at one point ``η`` modulo the periods (trigonometric; the rational family keeps its closed-form route).

Everything else — ``ℓ(λ)``, the integrals as quadratic forms, ``ν`` and its branch rule, ``G_ξ`` and its weights,
the dressing of the principal parts site by site, the maps, flows, compiled kernels, run layer and CLI — is
written once in :mod:`jetgaudin.gaudin` and uses only the methods below.

Writing a new family (the elliptic one, say): subclass :class:`Family`, set :attr:`name`, define the abstract
methods, optionally :attr:`period`, :meth:`check`, :meth:`extra_integrals`, :meth:`uniformizer`; register it with
:func:`jetgaudin.families.register_family`.  Arrays are NumPy arrays with the series index FIRST (``(order, ...)``)
and any batch shape after; ``a`` is the Pauli component ``1, 2, 3``.
"""

from __future__ import annotations

import abc
from typing import Any

import numpy as np

from .._errors import InvalidParameterError

__all__ = ["Family"]


class Family(abc.ABC):
    """One family of Gaudin models (module docstring).  Instances are immutable and hashable by
    :meth:`describe` (two equal descriptions are the same family)."""

    #: the family's name (``GaudinModel(..., family=name)``, ``--family name``)
    name: str = ""
    #: ``True`` when ``w_1 = w_2 = w_3`` (rational): the core then uses the Gram matrix of the ``y``'s
    uniform: bool = False
    #: number ``P`` of dressing basis matrices ``B_p``
    n_dressing: int = 0
    #: the gauge rule's id in the compiled kernel (:mod:`jetgaudin.gaudin._family_kernel`; ``None``: the family
    #: has no compiled route yet — add a branch to its ``_coefficients`` and set the id)
    kernel_rule: int | None = None

    def kernel_constants(self, xi: complex) -> np.ndarray:
        """The constants ``gk`` of the gauge rule in the compiled kernel for the parameter ``ξ``."""
        return np.array([xi], dtype=complex)

    # ---- the same constants to many digits (the compiled kernel's two-word constants) -------------------------

    def mp_w(self, a: int, x):
        """``w_a(x)`` in :mod:`mpmath` arithmetic at the working precision (``x`` an ``mpc``), for the compiled
        kernel's constants as two words (:func:`jetgaudin.gaudin._family_kernel.orbit_constants`: constants rounded
        once repeat their error at every step, a linear drift of the integrals; ``docs/reliability.md``, "Drift like
        round-off").  ``NotImplementedError`` (default): the kernel takes the double constants alone."""
        raise NotImplementedError(f"the {self.name} family has no mpmath basis functions")

    def mp_dressing_basis(self, lam, xi) -> list:
        """The dressing basis ``B_p(λ)`` in :mod:`mpmath` arithmetic: ``P`` lists of the 4 entries ``00, 01, 10,
        11`` (``xi`` the map's parameter, used where :attr:`dressing_needs_xi`); see :meth:`mp_w`."""
        raise NotImplementedError(f"the {self.name} family has no mpmath dressing basis")

    def mp_kernel_constants(self, xi) -> list:
        """:meth:`kernel_constants` in :mod:`mpmath` arithmetic (``xi`` an ``mpc``); see :meth:`mp_w`."""
        raise NotImplementedError(f"the {self.name} family has no mpmath kernel constants")

    def mp_w_taylor(self, x, n: int) -> list:
        """``w_a(x + t) = Σ_k W[a − 1][k] t^k`` (``k < n``, ``a = 1, 2, 3``): three lists of ``n`` Taylor coefficients
        in :mod:`mpmath` arithmetic at the working precision (``x`` an ``mpc``).  Default: :func:`mpmath.taylor` of
        :meth:`mp_w` (numerical derivatives at raised precision; a family with the series in closed form overrides
        it: the elliptic one, 10× faster)."""
        import mpmath

        return [mpmath.taylor(lambda z, a=a: self.mp_w(a, z), x, n - 1) for a in (1, 2, 3)]

    def mp_dressing_taylor(self, lam, xi, n: int) -> list:
        """The dressing basis' Taylor coefficients at ``λ`` (``k < n``): ``P`` lists of the 4 entries ``00, 01, 10,
        11``, each a list of ``n`` coefficients (an entry that vanishes identically: zeros).  Default:
        :func:`mpmath.taylor` of :meth:`mp_dressing_basis`, entry by entry."""
        import mpmath

        P = len(self.mp_dressing_basis(lam, xi))
        return [[mpmath.taylor(lambda z, q=q, e=e: self.mp_dressing_basis(z, xi)[q][e], lam, n - 1) for e in range(4)]
                for q in range(P)]

    # ---- parameters -------------------------------------------------------------------------------------

    @property
    def period(self) -> float | None:
        """Sites must be distinct modulo this real period (``None``: distinct)."""
        return None

    def describe(self) -> dict[str, Any]:
        """The family's parameters besides its name, JSON-able (``{"gamma": γ}`` for the trigonometric one)."""
        return {}

    def check(self, b: float, sites: tuple) -> None:
        """Refuse a field or sites the family cannot have (:class:`InvalidParameterError`); the default checks
        that the sites are distinct modulo :attr:`period`."""
        T = self.period
        if T is None:
            return
        pos = [p for p, _ in sites]
        for i, p in enumerate(pos):
            for q in pos[:i]:
                r = (p - q) / T
                if abs(r - round(r)) < 1e-12:
                    raise InvalidParameterError(
                        f"the sites {q} and {p} of the {self.name} family coincide modulo its period {T} "
                        "(the Lax matrix is periodic): merge them into one site of higher order or move one")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Family) and (self.name, self.describe()) == (other.name, other.describe())

    def __hash__(self) -> int:
        return hash((self.name, tuple(sorted(self.describe().items()))))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in self.describe().items())})"

    # ---- basis functions -----------------------------------------------------------------------------------

    @abc.abstractmethod
    def taylor(self, a: int, x0, order: int) -> np.ndarray:
        """Taylor coefficients ``[x^n] w_a(x0 + x)``, ``n < order``, at points ``x0`` off the poles; shape
        ``(order,) + shape(x0)`` (complex)."""

    @abc.abstractmethod
    def regular(self, a: int, order: int) -> np.ndarray:
        """Taylor coefficients at 0 of ``w_a(x) − 1/x``, shape ``(order,)``."""

    def phi(self, a: int, x, order: int) -> np.ndarray:
        """``φ_{a,k}(x) = (−1)^k w_a^{(k)}(x)/k!`` for ``k < order``, shape ``(order,) + shape(x)``."""
        t = self.taylor(a, x, order)
        return np.stack([(-1) ** k * t[k] for k in range(order)])

    # ---- the expansion of ν² --------------------------------------------------------------------------------

    @abc.abstractmethod
    def nu2_basis(self, m: int, x) -> np.ndarray:
        """``ψ_m(x)``: the function multiplying ``h_{j,m}`` in ``ν²`` (principal part ``x^{−m}`` at 0, no other
        pole modulo the period), at complex ``x``."""

    @abc.abstractmethod
    def nu2_constant(self, b: float, extra: np.ndarray) -> np.ndarray:
        """The constant of ``ν² = constant + Σ h_{j,m} ψ_m(λ − λ_j)`` from ``b`` and the extra integrals
        ``extra`` ``(..., E)`` (:meth:`extra_integrals`), shape ``(...)``."""

    def nu2_constant_gradient(self, b: float, extra: np.ndarray) -> np.ndarray:
        """``∂(constant)/∂extra``, shape ``(..., E)`` (the weights of ``G_ξ`` on the extra integrals)."""
        return np.zeros(np.shape(extra))

    def extra_integrals(self, sites: tuple) -> tuple[list[str], np.ndarray]:
        """``(labels, forms)``: integrals linear in the state besides the ``h_{j,m}``, ``forms`` ``(E, 3M)`` (none
        by default; trigonometric: ``J = Σ_j y^{(j)3}_0``, the generator of the rotation gauge)."""
        M = sum(N for _, N in sites)
        return [], np.zeros((0, 3 * M))

    #: label of the constant term of ``ν²`` when it is itself an integral (a quadratic form in the state,
    #: appended after the ``h_{j,m}``; elliptic ``"c0"``), ``None`` when it is a function of ``b`` and the extras
    constant_integral: str | None = None

    def nu2_basis_constant(self, m: int) -> float:
        """``[x^0] (ψ_m(x) − x^{−m})`` at 0: needed by the core for the quadratic form of the constant term when
        :attr:`constant_integral` is set."""
        raise NotImplementedError(f"the {self.name} family has no constant-term integral")

    def check_xi(self, xi: complex) -> None:
        """Refuse a spectral parameter the family's maps cannot take (:class:`InvalidParameterError`); none by
        default (the elliptic family refuses ``|Im ξ|`` too close to ``K'``)."""
        return None

    #: ``True`` when the dressing basis depends on the map's ``ξ`` (elliptic: ``w_a(λ − Re ξ)``): the core then
    #: calls ``dressing_basis(lam, xi)`` and ``dressing_taylor(lam0, order, xi)``
    dressing_needs_xi: bool = False

    def uniformizer(self, lam) -> np.ndarray | None:
        """``z(λ)`` such that ``ν²`` is a rational function of ``z`` with poles only at the ``z(λ_j)``, of
        degree ``2M`` over ``Π (z − z_j)^{2N_j}``, and vertical segments map to straight segments (rational
        ``z = λ``; trigonometric ``z = e^{2iγλ}``).  ``None`` (default): the core continues ``ν`` numerically
        along the segment instead of by its exact root product."""
        return None

    def uniformizer_inverse(self, z) -> np.ndarray:
        """``λ(z)``, one preimage of :meth:`uniformizer` (for the branch points; needed when ``uniformizer`` is not
        ``None``); a family without a uniformizer has no exact branch points: ``z`` (empty) is returned."""
        return np.asarray(z, dtype=complex)

    # ---- the dressing -----------------------------------------------------------------------------------

    @abc.abstractmethod
    def dressing_basis(self, lam) -> np.ndarray:
        """``B_p(λ)``, shape ``shape(lam) + (P, 2, 2)``."""

    @abc.abstractmethod
    def dressing_taylor(self, lam0: float, order: int) -> np.ndarray:
        """Taylor coefficients of each ``B_p`` at the real point ``lam0``, shape ``(order, P, 2, 2)``."""

    # ---- the one-point dressing (optional) -----------------------------------------------------------------------

    #: ``None`` when the family has one-point Bäcklund maps (:meth:`one_point_normalisation`,
    #: :meth:`one_point_dressing`); otherwise the reason it has none, the refusal's message
    one_point_refusal: str | None = ("this family defines no one-point dressing (no one-point map); use the real "
                                     "two-point map")

    def one_point_normalisation(self, b: float, sites: tuple, X: np.ndarray, eta: complex,
                                inverse: bool) -> np.ndarray:
        """The entry of the one-point dressing fixed by keeping ``ℓ̃`` of the family's form (rational
        ``p = S^-/(2b)``; ``q = S^+/(2b)`` for the inverse map), for the states ``X`` ``(B, 3M)``, shape ``(B,)``."""
        raise NotImplementedError(self.one_point_refusal)

    def one_point_dressing(self, eta: complex, norm: np.ndarray, spec: np.ndarray, inverse: bool) -> np.ndarray:
        """The coefficients ``c`` ``(B, P)`` of the one-point dressing from :meth:`one_point_normalisation`'s entry
        ``norm`` and spectrality's ``spec`` (``q = (u(η) − ν)/v(η)``, or ``p = (u(η) − ν)/w(η)`` for the inverse
        map), as the rational ``K = [[λ − η + pq, p], [q, 1]]`` (``adj K`` for the inverse map)."""
        raise NotImplementedError(self.one_point_refusal)

    @abc.abstractmethod
    def real_dressing(self, xi: complex, k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
        """The coefficients ``c`` ``(B, P)`` of the real two-point map's dressing: ``D(ξ) k1 = 0`` and
        ``D(ξ̄) k2 = 0`` (``k1``, ``k2`` ``(B, 2)``: eigenvectors of ``ℓ(ξ)`` for ``ν1`` and of ``ℓ(ξ̄)`` for
        ``conj ν1``), the member of the null space picked by the family's gauge rule."""
