r"""su(n) Gaudin models with jet sites (issue 32): the model core of :class:`GaudinModel` with the algebra as a
parameter.

Sites ``[(λ_1, N_1), …]`` (real, distinct; rational family), basis ``λ_a`` of :mod:`jetgaudin.lie`
(``tr λ_a λ_b = 2δ_ab``, ``[λ_a, λ_b] = 2i f_abc λ_c``), state ``(..., d M)``, ``d = n² − 1``, ``M = Σ N_j``: site
by site ``y_0 … y_{N_j−1}``, each ``d`` components.

.. math:: \ell(\lambda) = \sum_a \lambda_a \xi^a(\lambda), \qquad
          \xi^a = b^a + \sum_j \sum_{k<N_j} y^{(j)a}_k (\lambda-\lambda_j)^{-(k+1)},

Hermitian on the real axis (``ℓ(λ̄) = ℓ(λ)^†`` for a real state); ``n = 2``: the su(2) chain's
``lax_matrix``.  Bracket: sites commute, ``{y^a_j, y^b_k} = f_abc y^c_{j+k}`` (``j + k < N``, else 0), so that
(``Π = ½Σ_a λ_a⊗λ_a + 1/n``, the permutation of ``ℂⁿ⊗ℂⁿ``)

.. math:: \{\ell(\lambda) \otimes \ell(\mu)\} = [r(\lambda-\mu), \ell(\lambda)\otimes 1 + 1\otimes\ell(\mu)],
          \qquad r(\lambda) = \frac{i\,\Pi}{\lambda}

(one site of order 1: ``[Π, Y⊗1] = i Σ f_abc y^c λ_a⊗λ_b`` and ``[Π, 1⊗Y] = −[Π, Y⊗1]``; jet sites: the same
sum over the Taylor orders; tested in ``tests/test_sun_model.py``).

**Integrals.**  ``τ_k(λ) = tr ℓ(λ)^k / k`` (``k = 2..n``; ``τ_2 = Σ_a (ξ^a)² = ν²``) is rational, ``→ tr b^k/k`` at
infinity, with poles of order ``k N_j`` at the sites; ``h^{(k)}_{j,m}`` (``m = 1..kN_j``) are its principal-part
coefficients, computed from the Laurent series ``ℓ(λ_j + z) = z^{−N_j} Σ_p A_p z^p`` (``A_p = y_{N_j−1−p}`` for
``p < N_j``, then the Taylor coefficients of ``b`` plus the other sites), ``h^{(k)}_{j,m} = tr (A^k)_{kN_j−m}/k``
(a truncated series power).  Order: ``k`` first, then the site, then ``m``; for ``m > (k−1)N_j`` only the site's own
``y`` enter and ``h^{(k)}_{j,m}`` is a Casimir of ``g^{(N_j)}``.  Gradients by ``dτ_k = tr(ℓ^{k−1} dℓ)``, exactly.
The involution follows from the r-matrix relation; ``Σ_k Σ_j (k−1)N_j = ½ n(n−1) M`` non-Casimir integrals against
leaves of dimension ``n(n−1) M`` (``tests/test_sun_model.py`` counts both).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from .._errors import InvalidParameterError, InvalidStateError
from .._validate import as_state, check_gradient, finite_result
from ..families import make_family
from ..lie import SU, parse_algebra
from ._model_map import model_map, register_model_map
from .hamiltonian import _ChainHamiltonian
from .model import GaudinModel, _check_sites, _taylor_coefficient

__all__ = ["SunGaudinModel", "SunHamiltonian", "field_components"]


def field_components(b, alg: SU) -> float | tuple[float, ...]:
    """The field as stored: a float (along ``λ_3``), or the ``n² − 1`` real components of a vector or of a traceless
    Hermitian ``n × n`` matrix (as a tuple).  :class:`InvalidParameterError` otherwise."""
    if isinstance(b, bool):
        raise InvalidParameterError(f"the field b must be a real number, {alg.dim} components or a traceless "
                                    f"Hermitian {alg.n}x{alg.n} matrix, got {b!r}")
    try:
        arr = np.asarray(b)
        arr = arr.astype(complex) if np.iscomplexobj(arr) else arr.astype(float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"the field b must be real numbers, got {b!r}") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError("the field b must be finite")
    if arr.ndim == 0:
        if np.iscomplexobj(arr):
            raise InvalidParameterError(f"the field strength b must be real, got {b!r}")
        return float(arr)
    if arr.shape == (alg.n, alg.n):
        if np.max(np.abs(arr - np.conj(arr.T))) > 1e-12 * (1 + np.max(np.abs(arr))) or \
                abs(np.trace(arr)) > 1e-12 * (1 + np.max(np.abs(arr))):
            raise InvalidParameterError(f"a matrix field b must be traceless and Hermitian ({alg.name})")
        arr = alg.components(arr.astype(complex)).real
    if arr.shape != (alg.dim,) or np.iscomplexobj(arr):
        raise InvalidParameterError(f"the field b of an {alg.name} model: a real number (along lambda_3), "
                                    f"{alg.dim} real components or a {alg.n}x{alg.n} matrix; got shape {arr.shape}")
    return tuple(float(x) for x in arr)


def _not_here(what: str):
    raise InvalidParameterError(f"{what} is defined for the su(2) chains only; an su(n) model has the eigenvalue "
                                "branches mu_r instead (SunGaudinModel.eigenvalue, two_point_backlund(eta, branch=r))")


@dataclass(frozen=True)
class SunGaudinModel(GaudinModel):
    """The su(n) chain (module docstring); built by ``GaudinModel(b, sites, algebra="su(3)")``.  Built directly it
    also takes ``algebra="su(2)"``: then it is the su(2) chain through the general code (the tests compare it with
    :class:`GaudinModel`).

    Raises
    ------
    InvalidParameterError
        An unknown algebra, a family other than the rational one (or ``gamma`` / ``modulus``), a bad field, bad
        sites (as :class:`GaudinModel`).
    """

    def __post_init__(self):
        alg = parse_algebra(self.algebra)
        object.__setattr__(self, "algebra", alg)
        fam = self.family
        if (fam if isinstance(fam, str) else getattr(fam, "name", None)) != "rational" or \
                self.gamma is not None or self.modulus is not None:
            raise InvalidParameterError(
                f"{alg.name} models are rational only (family='rational', no gamma/modulus); the trigonometric and "
                "elliptic su(n) families are not implemented (docs/sun.md says what they need)")
        if self.constants is not None:  # (a field of GaudinModel: the su(2) sites' jet constants, issue 33)
            raise InvalidParameterError(f"{alg.name} models take no jet constants (su(2) sites only: docs/chains.md)")
        object.__setattr__(self, "family", make_family("rational"))
        object.__setattr__(self, "sites", _check_sites(self.sites))
        object.__setattr__(self, "b", field_components(self.b, alg))

    # ---- layout ------------------------------------------------------------------------------

    @property
    def n(self) -> int:
        return self.algebra.n

    @property
    def dim(self) -> int:
        return self.algebra.dim

    @property
    def n_state(self) -> int:
        """``(n² − 1) M``."""
        return self.dim * self.M

    @cached_property
    def field_vector(self) -> np.ndarray:
        """``b^a``, ``(n² − 1,)`` (a float ``b`` is ``b`` along ``λ_3``)."""
        if isinstance(self.b, float):
            v = np.zeros(self.dim)
            v[2] = self.b
        else:
            v = np.array(self.b)
        v.setflags(write=False)
        return v

    @cached_property
    def field_matrix(self) -> np.ndarray:
        return self.algebra.matrix(self.field_vector.astype(complex))

    def labels(self) -> list[str]:
        return [f"s{i + 1}_y{k}^{a}" for i, (_, N) in enumerate(self.sites) for k in range(N)
                for a in range(1, self.dim + 1)]

    def check_state(self, X, *, allow_complex: bool = False) -> np.ndarray:
        arr = np.asarray(X)
        block = self.dim if arr.ndim and arr.shape[-1] and arr.shape[-1] % self.dim == 0 else 1
        X = as_state(arr, allow_complex=allow_complex, block=block)[0]  # dtype, reality, finiteness
        if X.shape[-1] != self.n_state:
            raise InvalidStateError(
                f"a state of the {self.algebra.name} chain with sites {list(self.sites)} has (n^2-1) M = "
                f"{self.n_state} components (M = {self.M}), got {X.shape[-1]}; give {self.dim} components per site "
                "and order")
        return X

    def describe(self) -> dict:
        b = self.b if isinstance(self.b, float) else list(self.b)
        return {"b": b, "sites": [[p, N] for p, N in self.sites], "algebra": self.algebra.name}

    def matrices(self, X) -> np.ndarray:
        """The coefficient matrices ``Y_c = Σ_a y_c^a λ_a``, ``(..., M, n, n)``."""
        X = self.check_state(X, allow_complex=True)
        return self.algebra.matrix(X.reshape(X.shape[:-1] + (self.M, self.dim)))

    def state_from_matrices(self, Y) -> np.ndarray:
        """Inverse of :meth:`matrices` (complex components), ``(..., d M)``."""
        c = self.algebra.components(Y)
        return c.reshape(c.shape[:-2] + (self.n_state,))

    # ---- Lax matrix ----------------------------------------------------------------------------

    def xi(self, X, lam) -> np.ndarray:
        """``ξ^a(λ)``, shape ``(..., n² − 1)`` (``lam`` broadcast against ``X[..., 0]``)."""
        from ._curve import _component_poles, _points

        X = self.check_state(X, allow_complex=True)
        lam = _points(self, lam)
        pos, power = _component_poles(self.sites)
        f = (lam[..., None] - pos) ** (-power)
        return np.einsum("...c,...ca->...a", f, X.reshape(X.shape[:-1] + (self.M, self.dim))) + self.field_vector

    def lax_matrix(self, X, lam) -> np.ndarray:
        r"""``ℓ(λ) = Σ_a λ_a ξ^a(λ)``, shape ``(..., n, n)``."""
        return self.algebra.matrix(self.xi(X, lam))

    # ---- integrals -------------------------------------------------------------------------------

    @cached_property
    def _tables(self):
        """Per site: ``(Lmat, bvec, conv, W)``; ``A = Lmat @ Y + bvec B`` (the Laurent coefficients, module
        docstring), ``conv[a, c, p] = [a + c = p]`` and ``W[k][m−1, c, p]``: the weight of ``tr(λ_a (ℓ^{k−1})_p)`` in
        ``∂h^{(k)}_{j,m}/∂y_c^a``."""
        n, M = self.n, self.M
        out = []
        for j, (lam_j, N) in enumerate(self.sites):
            P = n * N
            Lmat = np.zeros((P, M))
            for p in range(N):
                Lmat[p, self.offsets[j] + N - 1 - p] = 1.0
            for q in range(P - N):
                for i, (lam_i, Ni) in enumerate(self.sites):
                    if i != j:
                        for k in range(Ni):
                            Lmat[N + q, self.offsets[i] + k] = _taylor_coefficient(k, q, lam_j - lam_i)
            bvec = np.zeros(P)
            if P > N:
                bvec[N] = 1.0
            idx = np.arange(P)
            conv = (idx[:, None, None] + idx[None, :, None] == idx[None, None, :]).astype(float)
            W = {}
            for k in range(2, n + 1):
                w = np.zeros((k * N, M, P))
                for m in range(1, k * N + 1):
                    for i, (lam_i, Ni) in enumerate(self.sites):
                        for q in range(Ni):
                            c = self.offsets[i] + q
                            if i == j:
                                p = (k - 1) * N + q + 1 - m
                                if 0 <= p < P:
                                    w[m - 1, c, p] = 1.0
                            else:
                                for p in range((k - 1) * N - m + 1):
                                    w[m - 1, c, p] = _taylor_coefficient(q, (k - 1) * N - m - p, lam_j - lam_i)
                W[k] = w
            out.append((Lmat, bvec, conv, W))
        return out

    def _powers(self, Y, j):
        """``[S_0, …, S_n]``, ``S_k = (A^k)`` truncated to ``n N_j`` terms, each ``(..., P, n, n)``."""
        Lmat, bvec, conv, _ = self._tables[j]
        A = np.einsum("pc,...cij->...pij", Lmat, Y) + bvec[:, None, None] * self.field_matrix
        S0 = np.zeros_like(A)
        S0[..., 0, :, :] = np.eye(self.n)
        S = [S0, A]
        for _ in range(2, self.n + 1):
            S.append(np.einsum("...aij,...cjk,acp->...pik", S[-1], A, conv, optimize=True))
        return S

    @property
    def n_integrals(self) -> int:
        """``Σ_{k=2}^n k M``."""
        return sum(k for k in range(2, self.n + 1)) * self.M

    def integral_labels(self) -> list[str]:
        """``h{j},{m}`` for ``k = 2`` (the su(2) names), ``t{k}_h{j},{m}`` for ``k ≥ 3`` (site ``j`` from 1)."""
        return [(f"h{j + 1},{m}" if k == 2 else f"t{k}_h{j + 1},{m}") for k in range(2, self.n + 1)
                for j, (_, N) in enumerate(self.sites) for m in range(1, k * N + 1)]

    def casimir_mask(self) -> np.ndarray:
        """``True`` for the Casimirs ``h^{(k)}_{j,m}``, ``m > (k−1) N_j``."""
        return np.array([m > (k - 1) * N for k in range(2, self.n + 1) for _, N in self.sites
                         for m in range(1, k * N + 1)])

    def integrals(self, X) -> np.ndarray:
        r"""``h^{(k)}_{j,m}``, shape ``(..., n_integrals)`` (module docstring); real for a real state."""
        X = self.check_state(X, allow_complex=True)
        Y = self.matrices(X)
        cols: dict[int, list] = {k: [] for k in range(2, self.n + 1)}
        for j, (_, N) in enumerate(self.sites):
            S = self._powers(Y, j)
            for k in range(2, self.n + 1):
                tr = np.trace(S[k], axis1=-2, axis2=-1)[..., : k * N]
                cols[k].append(tr[..., ::-1] / k)  # m = 1..kN  <->  p = kN − m
        out = np.concatenate([c for k in cols for c in cols[k]], axis=-1)
        out = out if np.iscomplexobj(X) else out.real
        return finite_result(out, "the su(n) chain integrals")

    def integral_gradients(self, X) -> np.ndarray:
        """``∂h_I/∂X``, shape ``(..., n_integrals, d M)``, exact (module docstring)."""
        X = self.check_state(X, allow_complex=True)
        Y = self.matrices(X)
        blocks: dict[int, list] = {k: [] for k in range(2, self.n + 1)}
        for j in range(len(self.sites)):
            S = self._powers(Y, j)
            W = self._tables[j][3]
            for k in range(2, self.n + 1):
                T = 2.0 * self.algebra.components(S[k - 1])  # tr(λ_a S_p), (..., P, d)
                blocks[k].append(np.einsum("mcp,...pa->...mca", W[k], T))
        g = np.concatenate([b for k in blocks for b in blocks[k]], axis=-3)
        g = g.reshape(g.shape[:-2] + (self.n_state,))
        return g if np.iscomplexobj(X) else g.real

    # ---- Poisson structure -------------------------------------------------------------------------

    def _site_constants(self, N: int) -> np.ndarray:
        d, f = self.dim, self.algebra.structure_constants
        c = np.zeros((d * N, d * N, d * N))
        for i in range(N):
            for j in range(N - i):
                c[d * i:d * i + d, d * j:d * j + d, d * (i + j):d * (i + j) + d] = f
        return c

    @cached_property
    def structure_constants(self) -> np.ndarray:
        r"""``c[I, J, K]``, ``{X_I, X_J} = Σ_K c[I, J, K] X_K``: block diagonal over sites, ``g^{(N)}`` with ``f``."""
        n, d = self.n_state, self.dim
        c = np.zeros((n, n, n))
        for i, (_, N) in enumerate(self.sites):
            s = slice(d * self.offsets[i], d * (self.offsets[i] + N))
            c[s, s, s] = self._site_constants(N)
        c.setflags(write=False)
        return c

    def vector_field(self, grad_H, X) -> np.ndarray:
        """``Ẋ = Π(X) ∇H``, shape ``(..., d M)``."""
        X = self.check_state(X, allow_complex=True)
        grad_H = check_gradient(grad_H, self.n_state, name="grad_H")
        out = np.empty(np.broadcast_shapes(X.shape, grad_H.shape), dtype=np.result_type(X, grad_H))
        d = self.dim
        for i, (_, N) in enumerate(self.sites):
            s = slice(d * self.offsets[i], d * (self.offsets[i] + N))
            out[..., s] = np.einsum("ijk,...k,...j->...i", self._site_constants(N), X[..., s], grad_H[..., s])
        return out

    # ---- spectral: eigenvalue branches, G^{(r)} -------------------------------------------------------

    def eigenvalue(self, X, eta, branch: int = 0) -> np.ndarray:
        """``μ_r(η)``: the ``r``-th largest eigenvalue of ``ℓ(Re η)`` continued along the vertical segment to ``η``
        (:func:`jetgaudin.gaudin.sun_spectral.eigenvalue_branch`), shape ``(...)``."""
        from .sun_spectral import eigenvalue_branch

        return eigenvalue_branch(self, X, eta, branch)

    def interpolating_hamiltonian(self, X, eta, branch: int = 0) -> np.ndarray:
        r"""``G^{(r)}_η = i∫_{η̄}^{η} μ_r dλ = −2∫_0^{Im η} Re μ_r(Re η + is) ds``, shape ``(...)``."""
        from .sun_spectral import interpolating

        return interpolating(self, X, eta, branch)[0]

    def interpolating_weights(self, X, eta, branch: int = 0) -> np.ndarray:
        r"""``ω_I = ∂G^{(r)}_η/∂h_I``, shape ``(..., n_integrals)`` (:mod:`jetgaudin.gaudin.sun_spectral`)."""
        from .sun_spectral import interpolating

        return interpolating(self, X, eta, branch)[1]

    def interpolating_flow_hamiltonian(self, X, eta, branch: int = 0):
        """``Σ ω_I(X) h_I``: its flow from ``X`` is the flow of ``G^{(r)}_η`` (the ``ω`` are constant on it)."""
        return SunHamiltonian(self, self.interpolating_weights(X, eta, branch))

    def solve_methods(self, method: str) -> None:
        """Refuse a method of :func:`jetgaudin.solve` that does not apply here, naming those that do
        (:mod:`jetgaudin.gaudin.sun_solve`)."""
        from .sun_solve import check_solve_method

        check_solve_method(self, method)

    def exact_flow(self, H, dt: float, substeps: int = 1, backend="auto"):
        """The exact time-``dt`` flow of ``H`` (``n = 3``; :class:`jetgaudin.gaudin.sun_exact.SunExactFlow`)."""
        return model_map("sun_exact")(H, dt, substeps, backend)  # SunExactFlow (registered: no import circle)

    def hamiltonian(self, weights) -> SunHamiltonian:  # type: ignore[override]  # another algebra: its own type
        """``H = Σ_I w_I h_I`` (weights in the order of :meth:`integrals`) for :func:`jetgaudin.integrate`."""
        return SunHamiltonian(self, weights)

    def two_point_backlund(self, eta, branch=0, backend="auto", kernel=None):  # type: ignore[override]
        """The real two-point map ``B^{(r)}_η`` (:class:`jetgaudin.gaudin.sun_maps.SunTwoPointBacklund`)."""
        return model_map("sun_two_point")(self, eta, branch, backend, kernel=kernel)  # SunTwoPointBacklund

    # ---- su(2)-only surface ------------------------------------------------------------------------------

    def nu_squared(self, X, lam):
        _not_here("nu^2")

    def nu(self, X, eta, *, sheet: int = 1):
        _not_here("nu")

    def branch_points(self, X):
        _not_here("branch_points")

    def physical_hamiltonian(self):
        _not_here("physical_hamiltonian")

    def one_point_backlund(self, *args, **kwargs):
        _not_here("the one-point map")


@dataclass(frozen=True)
class SunHamiltonian(_ChainHamiltonian):  # the chain Hamiltonian's implementation (another algebra: its own type)
    """``H = Σ_I w_I h_I`` on an su(n) chain.  For ``n ≥ 3`` the integrals are not quadratic, so it declares no
    structure constants (:func:`jetgaudin.integrate` then takes the generic right-hand side :meth:`vector_field`,
    not the affine-gradient one; heyoka's symbolic route refuses it), and it checks states of length ``(n²−1)M``."""

    route_kind: ClassVar[str] = "sun"  # its rows of the route table of jetgaudin.solve (jetgaudin.methods.ROUTES)

    @property
    def structure_constants(self):  # type: ignore[override]
        return self.model.structure_constants if self.model.n == 2 else None

    def check_state(self, X) -> np.ndarray:
        return self.model.check_state(X)

    def heyoka_integrator(self, rtol: float):
        """heyoka's integrator of the flow (``n ≤ 3``; :mod:`jetgaudin.gaudin.sun_solve`)."""
        from .sun_solve import heyoka_integrator

        return heyoka_integrator(self, rtol)


register_model_map("sun_model", SunGaudinModel)  # GaudinModel(..., algebra="su(n)") builds it
