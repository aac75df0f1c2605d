r"""The real two-point Bäcklund maps ``B^{(r)}_η`` of an su(n) chain (issue 32).

**Derivation.**  For a real state ``ℓ(λ̄) = ℓ(λ)^†``.  Let ``v`` be the eigenvector of ``ℓ(η)`` for the branch
``μ_r(η)`` (:mod:`jetgaudin.gaudin.sun_spectral`), ``P = v v^†/(v^†v)`` (orthogonal, rank one) and

.. math:: D(\lambda) = (\lambda-\bar\eta)(1-P) + (\lambda-\eta)P,\qquad
          D^{-1} = \frac{1-P}{\lambda-\bar\eta} + \frac{P}{\lambda-\eta},\qquad \tilde\ell = D\,\ell\,D^{-1}.

* no pole at ``η``: the residue is ``D(η) ℓ(η) P = (η − η̄)(1 − P) ℓ(η) P = (η − η̄) μ_r (1 − P) P = 0``;
* no pole at ``η̄``: the residue is ``(η̄ − η) P ℓ(η̄)(1 − P)`` and ``P ℓ(η)^† = (ℓ(η) P)^† = μ̄_r P``, so it is 0;
* Hermitian on the real axis (the new state is real): there ``D^† = |λ − η|² D^{−1}``, so
  ``ℓ̃^† = D^{−†} ℓ D^† = D ℓ D^{−1}``;
* ``ℓ̃ → b`` at infinity (``D ~ λ``) and the poles stay at the sites with their orders: ``D``, ``D^{−1}`` are
  analytic there, ``D(λ_i + z) = D_0 + z``, ``D^{−1}(λ_i + z) = Σ_c (−z)^c [(1−P)(λ_i−η̄)^{−c−1} + P(λ_i−η)^{−c−1}]``,
  and the new coefficients are those of the principal part of ``D ℓ D^{−1}``:
  ``Ỹ_k = Σ_{j ≥ k} (D_0 Y_j D^{−1}_{j−k} + Y_j D^{−1}_{j−k−1})``.

The spectrum of ``ℓ̃(λ)`` is that of ``ℓ(λ)`` (a similarity), so every ``τ_k`` and every integral is kept, and
``μ_r(η)`` is an integral of the map (the carry: each step takes the eigenvalue of ``ℓ(η)`` nearest to it).
**Spectrality** fixes ``v``: any other eigenvector (another ``μ_{r'}``) gives the map of branch ``r'``; a vector
that is no eigenvector leaves a pole at ``η`` (``tests/test_sun_maps.py`` plants one).  ``n = 2``: ``D = λ + M_0``
is the su(2) map's ``K`` (``r = 0`` the default branch, ``r = 1`` ``"opposite"``).  Consequences (tested): the
map is the time-1 flow of ``G^{(r)}_η = i∫_{η̄}^{η} μ_r dλ``; ``B^{(r)}_{η̄} ∘ B^{(r)}_η = 1`` (``v`` is the
eigenvector of ``ℓ̃(η̄)`` for ``μ̄_r``, so ``D' ∝ D^{−1}``), which is :meth:`SunTwoPointBacklund.inverse`;
``B^{(n−1)}_η ∘ … ∘ B^{(0)}_η = 1`` (``Σ_r G^{(r)} = i∫ tr ℓ = 0``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._errors import InvalidParameterError, SingularStepError
from .._validate import spectral_parameter
from ..maps import Advance, Backend, Map, MapProperties, check_count, register_map
from ._model_map import ModelMap, register_model_map
from .sun import SunGaudinModel
from .sun_spectral import _GAP_TOL, branch_index, check_start, eigenvalue_branch

__all__ = ["SunTwoPointBacklund", "dress"]


def dress(model: SunGaudinModel, Y: np.ndarray, P: np.ndarray, eta: complex) -> np.ndarray:
    """The new coefficient matrices ``Ỹ`` ``(B, M, n, n)`` from ``Y`` and the projector ``P`` ``(B, n, n)``
    (module docstring)."""
    one = np.eye(model.n)
    Q = one - P
    out = np.empty_like(Y)
    eb = np.conj(eta)
    for i, (lam_i, N) in enumerate(model.sites):
        o = model.offsets[i]
        D0 = (lam_i - eb) * Q + (lam_i - eta) * P
        Dinv = [(-1) ** c * (Q * (lam_i - eb) ** (-(c + 1)) + P * (lam_i - eta) ** (-(c + 1))) for c in range(N)]
        for k in range(N):
            acc = np.zeros_like(Y[:, 0])
            for j in range(k, N):
                Yj = Y[:, o + j]
                acc = acc + D0 @ Yj @ Dinv[j - k]
                if j > k:
                    acc = acc + Yj @ Dinv[j - k - 1]
            out[:, o + k] = acc
    return out


@dataclass(frozen=True)
class SunTwoPointBacklund(ModelMap, Map):
    r"""``B^{(r)}_η`` of an su(n) chain (module docstring): real, keeps every integral, Poisson, the time-1 flow of
    ``G^{(r)}_η``; carry ``μ_r(η)``.

    Parameters
    ----------
    model : SunGaudinModel
    eta : complex
        ``Im η ≠ 0``, ``Re η`` off the sites.
    branch : int
        ``r = 0..n−1``: the ``r``-th largest eigenvalue of ``ℓ(Re η)`` continued to ``η`` (``"default"`` = 0; for
        ``n = 2`` ``"opposite"`` = 1).
    backend, kernel : {"auto", "numpy", "compiled", "gpu"}
        ``"compiled"``: the Numba kernel of :mod:`jetgaudin.gaudin._sun_kernel` (``n = 3`` only); ``"auto"`` takes
        it from ``AUTO_MIN_WORK`` orbit-steps on.  ``"gpu"`` (``n = 3``): the same orbit loop, one thread per orbit
        (:mod:`jetgaudin.gpu`; a :class:`jetgaudin.gpu.GPUUnavailableError` where no GPU can run); ``"auto"`` takes
        it only where :func:`jetgaudin.gpu.auto_uses_gpu` says so.

    Raises
    ------
    InvalidParameterError
        ``Im η = 0``, ``Re η`` at a site, a bad branch, a model that is not an su(n) chain.
    """

    model: SunGaudinModel
    eta: complex
    branch: Any = 0
    backend: Backend = field(default=Backend.AUTO, compare=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)
    kind = "sun_two_point"
    properties: MapProperties = field(
        default=MapProperties(preserves_integrals=True, poisson=True, real=True, order=2, symmetric=True,
                              interpolates_flow=True),
        init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.model, SunGaudinModel):
            raise InvalidParameterError(f"model must be an su(n) GaudinModel, got {type(self.model).__name__}")
        eta = spectral_parameter(self.eta)
        if eta.imag == 0:
            raise InvalidParameterError(
                f"Im(eta) = 0 (eta = {eta.real}): the real two-point map needs eta != conj(eta) (at Im eta = 0 it "
                "is the identity); give Im(eta) != 0")
        check_start(self.model, eta)
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "branch", branch_index(self.model, self.branch))
        self._init_backend()

    @property
    def b(self) -> float:
        """The field's ``λ_3`` component ``b³`` (a float field is all of it; the whole field is in
        :meth:`describe`): the number an ensemble run records per orbit next to ``η``."""
        return float(self.model.field_vector[2])

    def start(self, X: np.ndarray) -> np.ndarray:
        """``μ_r(η)`` by the branch rule, shape ``(...)``."""
        return eigenvalue_branch(self.model, X, self.eta, self.branch)

    def projector(self, X, carry=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(P, μ_r, ℓ(η))`` at the states ``X`` ``(B, d M)``: ``P`` the orthogonal projector on the eigenvector of
        ``ℓ(η)`` for the eigenvalue nearest ``carry`` (``None``: the branch rule)."""
        L = self.model.lax_matrix(X, np.full(X.shape[:-1], self.eta))
        ref = self.start(X) if carry is None else np.broadcast_to(np.asarray(carry, dtype=complex), X.shape[:-1])
        ev, V = np.linalg.eig(L)
        d = np.abs(ev - ref[:, None])
        k = np.argmin(d, axis=-1)
        mu = ev[np.arange(X.shape[0]), k]
        gap = np.abs(ev - mu[:, None])
        gap[np.arange(X.shape[0]), k] = np.inf
        if np.any(np.min(gap, axis=-1) <= _GAP_TOL * (1.0 + np.max(np.abs(ev), axis=-1))):
            raise SingularStepError(
                f"the eigenvalue mu_{self.branch}(eta) of ell(eta) is degenerate (eta at a branch point of the "
                "spectral curve): the map needs a simple one; change eta")
        v = V[np.arange(X.shape[0]), :, k]
        P = v[:, :, None] * np.conj(v[:, None, :]) / np.sum(np.abs(v) ** 2, axis=-1)[:, None, None]
        return P, mu, L

    def step(self, X, carry=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One step: ``(X̃, μ_r, imag_residue)`` (``X̃`` real: the imaginary part, relative to ``1 + |X̃|``, is
        returned and dropped)."""
        X = self.model.check_state(X)
        shape = X.shape
        Xb = X.reshape(-1, shape[-1])
        P, mu, _ = self.projector(Xb, None if carry is None else np.reshape(carry, -1))
        new = dress(self.model, self.model.matrices(Xb), P, self.eta)
        Xc = self.model.state_from_matrices(new)
        Xr = Xc.real
        if not np.all(np.isfinite(Xr)):
            raise SingularStepError("the su(n) two-point step produced non-finite values; change eta")
        imag = np.max(np.abs(Xc.imag), axis=-1) / (1.0 + np.max(np.abs(Xr), axis=-1))
        return Xr.reshape(shape), mu.reshape(shape[:-1]), imag.reshape(shape[:-1])

    @property
    def has_compiled(self) -> bool:
        """su(3) has a compiled route (:mod:`jetgaudin.gaudin._sun_kernel`); other ``n`` the NumPy one."""
        return self.model.n == 3

    @property
    def has_gpu(self) -> bool:
        """su(3) has a GPU route: the compiled route's orbit loop, one thread per orbit (:mod:`jetgaudin.gpu`)."""
        return self.model.n == 3

    def advance(self, X, carry, steps: int, save_every: int = 1) -> Advance:
        """:meth:`jetgaudin.maps.Map.advance`, with the GPU route where :meth:`resolved_backend` says so."""
        X = np.asarray(X)
        if X.size and self.has_gpu and self.resolved_backend(X, steps) is Backend.GPU:
            return self._compiled_advance(X, carry, check_count(steps, "steps"),
                                          check_count(save_every, "save_every", 1), gpu=True)
        return super().advance(X, carry, steps, save_every)

    def _auto_backend(self, X, steps) -> Backend:
        """Compiled from :data:`jetgaudin.gaudin._backend.AUTO_MIN_WORK` orbit-steps on (compiling costs seconds)."""
        from ._backend import AUTO_MIN_WORK

        work = int(steps) * max(1, int(np.prod(np.shape(X)[:-1])))
        return Backend.COMPILED if work >= AUTO_MIN_WORK else Backend.NUMPY

    def _compiled_advance(self, X, carry, steps, save_every, gpu: bool = False) -> Advance:
        """The Numba kernel (one orbit, or a batch on all cores; ``gpu``: its orbit loop on the GPU, one thread per
        orbit, :func:`jetgaudin.gpu.run_sun_batch`); ``μ_r`` at ``X`` by the NumPy branch rule; no imaginary
        residue (zeros).  :class:`SingularStepError` for an orbit that went non-finite (the GPU route names the
        first such orbit)."""
        from . import _sun_kernel as K

        X = self.model.check_state(X)
        shape = X.shape
        Xb = np.ascontiguousarray(X.reshape(-1, shape[-1]))
        mu = (self.start(Xb) if carry is None else np.broadcast_to(np.asarray(carry, dtype=complex),
                                                                    shape[:-1]).reshape(-1)).astype(complex)
        c = K.orbit_constants(self.model, self.eta)
        run_orbit: Any = K.run_orbit  # Numba dispatchers
        run_batch: Any = K.run_batch
        if gpu:
            from ..gpu import run_sun_batch

            fb, f, pos, off, orders = c
            rows, final, last, status = run_sun_batch(Xb, fb, mu, f, pos, off, orders, self.eta, steps, save_every)
            if np.any(status):
                raise SingularStepError(
                    f"orbit {int(np.flatnonzero(status)[0])} of the su(3) GPU route went non-finite (eta at a branch "
                    "point?); change eta")
        elif Xb.shape[0] == 1:  # one map: k = 1 of the kernel's composed loop
            r, xf, m = run_orbit(Xb[0], c[0], mu[:1], c[1][None], *c[2:], np.array([self.eta]), steps, save_every, 1)
            rows, final, last = r[:, None], xf[None], m
        else:
            B = Xb.shape[0]
            rows, final, last = run_batch(Xb, c[0], mu[:, None], np.repeat(c[1][None, None], B, axis=0), *c[2:],
                                          np.full((B, 1), self.eta), steps, save_every, 1)
            last = last[:, 0]
        if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(final))):
            raise SingularStepError("the compiled su(3) orbit produced non-finite values (eta at a branch point?); "
                                    "change eta")
        return Advance(rows=rows.reshape((rows.shape[0],) + shape), X=final.reshape(shape),
                       carry=last.reshape(shape[:-1]), imag_max=np.zeros(shape[:-1]))

    def inverse(self) -> SunTwoPointBacklund:
        """``B^{(r)}_{η̄}`` (module docstring)."""
        return SunTwoPointBacklund(self.model, np.conj(self.eta), self.branch, self.backend)

    def describe(self) -> dict:
        return {"kind": self.kind, **self.model.describe(), "eta": [self.eta.real, self.eta.imag],
                "branch": self.branch, "backend": self.backend.value}


def _from(d: dict) -> SunTwoPointBacklund:
    from .model import GaudinModel

    model = GaudinModel.from_description(d)
    if not isinstance(model, SunGaudinModel):
        raise InvalidParameterError("a sun_two_point description needs an su(n) model ('algebra': 'su(n)')")
    return SunTwoPointBacklund(model, complex(*d["eta"]), int(d["branch"]),
                               Backend.parse(d.get("backend", "numpy")))


register_map("sun_two_point", _from)
register_model_map("sun_two_point", SunTwoPointBacklund)  # model.two_point_backlund (gaudin._model_map)
