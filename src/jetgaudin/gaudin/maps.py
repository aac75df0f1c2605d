r"""Bäcklund maps of a chain (Section 6 of the paper, for any sites and orders).

The dressing ``ℓ̆ = K ℓ adj(K) / det K`` (``ℓ = −2iL = [[u, v], [w, −u]]``) with ``K(λ) = λE + K_0`` is
computed **site by site on the principal parts**: ``K``, ``adj K`` and ``1/det K`` are analytic at every
site ``λ_i``, so the principal part of ``ℓ̆`` at ``λ_i`` is that of ``K ℓ^{(i)}_{sing} adj(K)/det K`` with
``ℓ^{(i)}_{sing} = Σ_k ℓ^{(i)}_k (λ − λ_i)^{-(k+1)}``:

.. math:: \breve\ell^{(i)}_k = \sum_{j=k}^{N_i-1} \sum_{a+c+d=j-k} K_a\, \ell^{(i)}_j\, A_c\, g_d,
          \qquad K(\lambda_i+z) = K_0' + zE,\ \operatorname{adj}K(\lambda_i+z) = A_0' + zE',\
          \frac{1}{\det K(\lambda_i+z)} = \sum_d g_d z^d.

The poles at the zeros of ``det K`` cancel by spectrality (their would-be residues ``K ℓ adj K`` at ``η`` are
returned as the step's residual) and ``ℓ̆(∞) = ℓ(∞) = b σ_3``-part by the choice of ``K`` (automatic for
the two-point map, ``p = S^-/(2b)`` with ``S = Σ_i y^{(i)}_0`` for the one-point map).  So ``ℓ̆`` is
``ℓ(∞)`` plus these principal parts: no polynomial division, for any sites.

* **Real two-point map** (eqs. (128), (mm), (x), (X) with ``η_1 = η``, ``η_2 = η̄``, ``ν_2 = conj ν_1``;
  ``docs/backlund.md`` §4): ``K = λ + M_0``, ``M_0`` from the eigenvector of ``ℓ(η)`` for ``ν_1``
  (:func:`jetgaudin.backlund._dressing.real_two_point_M0`).  ``branch="opposite"`` (``−ν_1``) is the inverse.
* **One-point map** (eqs. (rr), (ansatz), (hh), (hhh)): ``K = [[λ − η + pq, p], [q, 1]]``,
  ``p = S^-/(2b)``, ``q = (u(η) − ν)/v(η)``; the inverse map uses ``adj K`` with ``q = S̃^+/(2b)``,
  ``p = (ũ(η) − ν)/w̃(η)``.  Needs ``b ≠ 0``.  Trigonometric family: ``λ − η → sin(γ(λ−η))/γ``,
  ``1 → e^{−iγ(λ−η)}`` (:mod:`jetgaudin.gaudin._one_point`, where the class lives; re-exported here).
"""

from __future__ import annotations

import glob
import os
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np

from .._errors import InvalidParameterError, SingularStepError
from .._system_maps import TwoPointBacklund
from .._validate import spectral_parameter
from ..backlund._dressing import adj, eigenvector, mm, real_two_point_M0
from ..lax import ell_coefficients, state_from_ell
from ..lax import ell_from_xi as _matrix
from ..maps import Advance, Backend, Branch, Map, MapProperties, check_count, check_gpu, register_map, step_loop
from ._backend import AUTO_MIN_WORK, CHAIN_COMPILE_S, resolve_backend
from ._compensated import acc, family_lax, family_site_series, scaled_two_point_K0
from ._curve import nu_with_roots
from ._dressing import dress_sites, dressing_at, monic_series, real_coefficients, site_series
from ._model_map import register_model_map
from .model import GaudinModel

__all__ = ["ChainTwoPointBacklund", "monic_series"]  # ChainOnePointBacklund: module __getattr__ (gaudin._one_point)

#: relative size of the would-be residue at eta above which a step is refused (as backlund.maps: round-off
#: level in exact arithmetic zero; larger means eta is numerically at a branch point)
_RESIDUAL_TOL = 1e-8
_ID = np.eye(2, dtype=complex)


@lru_cache(maxsize=64)
def _orbit_constants(model: GaudinModel, eta: complex) -> tuple:
    """The compiled kernels' per-orbit constants, computed once per ``(model, η)`` (a run calls ``advance`` chunk by
    chunk; the kernels only read them)."""
    if model.family.uniform:
        from ._kernels import orbit_constants
    else:
        from ._family_kernel import orbit_constants
    return orbit_constants(model, eta)


def _check_model(model) -> None:
    if not isinstance(model, GaudinModel):
        raise InvalidParameterError(f"model must be a GaudinModel, got {type(model).__name__}")
    if model.algebra != "su(2)":  # an su(n) model: its own maps (jetgaudin.gaudin.sun_maps)
        raise InvalidParameterError(f"the su(2) chain maps take su(2) models; an {model.algebra} model has "
                                    "model.two_point_backlund(eta, branch=r)")
    if model.constants is not None:  # issue 33: the reduced model's map conjugated (gaudin._site_constants)
        raise InvalidParameterError("this model's sites carry jet constants: build its maps with "
                                    "model.two_point_backlund(eta) / model.one_point_backlund(eta)")


def _check_eta(model: GaudinModel, eta) -> complex:
    eta = spectral_parameter(eta)
    T = model.family.period
    for p, _ in model.sites:
        if (eta.real == p if T is None else abs((r := (eta.real - p) / T) - round(r)) < 1e-14):
            raise InvalidParameterError(
                f"Re(eta) = {eta.real} is a site" + ("" if T is None else f" ({p} modulo the period {T:.6g})") +
                ": the branch rule of nu starts at the real point Re(eta), a pole of the Lax matrix there; choose "
                "Re(eta) off the sites"
            )
    model.family.check_xi(eta)
    return eta


def _ell_at(model, parts, lam):
    """``ℓ(λ) = ℓ(∞) + Σ_c P_c (λ − λ_c)^{-(k_c+1)}`` for scalar ``λ``; ``parts`` ``(B, M, 2, 2)``.  The weights as
    two words and the sums compensated, rounded once (:func:`jetgaudin.gaudin._compensated.acc`;
    ``docs/reliability.md``, "Drift like round-off": a weight rounded once would put the same relative error into
    ``ℓ(η)`` at every step, a linear drift)."""
    from ._curve import rational_weights

    f, flo = rational_weights(model.sites, complex(lam))
    z = np.zeros(parts.shape[:-3] + (2, 2))
    sr, si, er, ei = z.copy(), z.copy(), z.copy(), z.copy()
    sr[..., 0, 0] += model.b
    sr[..., 1, 1] -= model.b
    for c in range(len(f)):
        P = parts[..., c, :, :]
        sr, er = acc(sr, er, P.real, f[c].real, flo[c].real)
        sr, er = acc(sr, er, -P.imag, f[c].imag, flo[c].imag)
        si, ei = acc(si, ei, P.real, f[c].imag, flo[c].imag)
        si, ei = acc(si, ei, P.imag, f[c].real, flo[c].real)
    return (sr + er) + 1j * (si + ei)


def _residual(K, L, A, scale):
    """``max |K ℓ adj K|`` at a zero of ``det K``, relative to ``1 + max|ℓ coefficients|`` (zero if exact)."""
    R = mm(mm(K, L), A)
    return np.max(np.abs(R), axis=(-2, -1)) / scale


def _continue(nu2, nu_prev):
    r = np.sqrt(nu2)
    return np.where((np.conj(r) * nu_prev).real >= 0, r, -r)


class _ChainMap(Map):
    """Shared surface of the chain maps: a :class:`jetgaudin.maps.Map` on states ``(..., 3M)`` whose carry is
    ``ν1 = ±ν(η)`` (the branch rule at the first state, then the root of ``ν(η)²`` closest to the previous one)."""

    model: GaudinModel
    eta: complex
    branch: Branch
    properties: MapProperties
    kind: str
    kernel: Any  # the alias of backend given to the constructor (None once parsed into backend)

    def _setup(self, X: np.ndarray, carry: Any) -> tuple:  # pragma: no cover - every concrete map defines it
        raise NotImplementedError

    def _init_common(self) -> None:
        _check_model(self.model)
        object.__setattr__(self, "eta", _check_eta(self.model, self.eta))
        object.__setattr__(self, "branch", Branch.parse(self.branch))
        backend = Backend.parse(self.backend if self.kernel is None else self.kernel)  # kernel=: an alias
        object.__setattr__(self, "backend", backend)
        check_gpu(backend, self.has_gpu, f"the {self.kind} map of this family")  # 'gpu': a route and a GPU
        # the alias is consumed: ``dataclasses.replace(m, backend=...)`` (the run layer's resolution of AUTO) must
        # not be overridden by the constructor's old alias (it was: every chunk resolved AUTO again on its steps)
        object.__setattr__(self, "kernel", None)

    @property
    def has_compiled(self) -> bool:
        """Whether the map has a compiled route (the one backend rule, :func:`resolve_backend`, reads it)."""
        return False

    def resolved_backend(self, X: Any, steps: Any) -> Backend:
        """The backend :meth:`advance` uses for ``steps`` steps of the states ``X`` ``(..., 3M)``
        (:func:`resolve_backend`; the argument order of :meth:`jetgaudin.maps.Map.resolved_backend`)."""
        return resolve_backend(self.backend, self.has_compiled, X, steps, self.kind, self.has_gpu, self.model.family)

    def route_notice(self, X: Any, steps: Any) -> str | None:
        """One line naming the route ``AUTO`` takes for ``steps`` steps of ``X`` where it matters (the NumPy route
        of a map that has a compiled one, with both estimated times; :func:`jetgaudin.gaudin._backend.auto_notice`);
        ``None`` otherwise (a compile is announced by :meth:`prepare_kernels`)."""
        from ._backend import auto_notice

        return auto_notice(self, X, steps)

    def with_backend(self, backend=None, kernel=None):
        """This map on another route (``kernel`` an alias of ``backend``; both ``None``: itself)."""
        pick = backend if kernel is None else kernel
        return self if pick is None else replace(self, backend=Backend.parse(pick), kernel=None)

    def iterate(self, X0, steps: int, *, save_every: int = 1, carry: Any = None, return_carry: bool = False,
                backend: Backend | str | None = None, kernel: Backend | str | None = None):
        """:meth:`jetgaudin.maps.Map.iterate`, on the route ``backend`` (alias ``kernel``; default the map's)."""
        m = self.with_backend(backend, kernel)
        return Map.iterate(m, X0, steps, save_every=save_every, carry=carry, return_carry=return_carry)

    @property
    def b(self) -> float:
        return self.model.b

    @property
    def sheet(self) -> int:
        return self.branch.sheet

    @property
    def n_state(self) -> int:
        return self.model.n_state

    def integrals(self, X: np.ndarray) -> np.ndarray:
        """The ``2M`` preserved integrals ``h_{i,m}``, shape ``(..., 2M)``."""
        return self.model.integrals(X)

    def integral_names(self) -> list[str]:
        """``h{i},{m}`` (site ``i`` from 1), the order of :meth:`integrals` (used by the run layer's reports)."""
        return self.model.integral_labels()

    def state_labels(self) -> list[str]:
        """``s{i}_y{k}^{a}``, the names of the ``3M`` state components (:meth:`GaudinModel.labels`; the run layer's
        ``orbit.csv`` columns)."""
        return self.model.labels()

    def _nu_rule(self, X):
        """``±ν(η)`` by the branch rule at each state of the batch ``X`` ``(B, 3M)``."""
        from ._curve import branch_points

        lam = np.full(X.shape[:-1], self.eta, dtype=complex)
        return nu_with_roots(self.model, X, lam, branch_points(self.model, X), self.sheet)

    def start(self, X: np.ndarray) -> np.ndarray:
        """``ν1 = ±ν(η)`` at ``X`` by the branch rule (the carry of an orbit), shape ``(...)``."""
        X = self.model.check_state(X, allow_complex=not self.properties.real)
        shape = X.shape[:-1]
        return self._setup(X.reshape(-1, X.shape[-1]), None)[2].reshape(shape)

    def _checked(self, X: np.ndarray, carry: Any, steps: int, save_every: int) -> tuple:
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        X = self.model.check_state(X, allow_complex=not self.properties.real)
        if not self.properties.real:
            X = X.astype(complex)
        if carry is not None:
            try:
                carry = np.broadcast_to(np.asarray(carry, dtype=complex), X.shape[:-1])
            except (TypeError, ValueError):
                raise InvalidParameterError(f"carry (nu1) must be a complex number or an array of shape "
                                            f"{X.shape[:-1]}") from None
            if not np.all(np.isfinite(carry)):
                raise InvalidParameterError("carry (nu1) must be finite")
        return X, carry, steps, save_every

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1, *,
                backend: Backend | str | None = None, kernel: Backend | str | None = None) -> Advance:
        """``steps`` steps from ``X`` ``(..., 3M)`` continuing from ``carry = ν1`` (``None``: the branch rule at
        ``X``), rows every ``save_every`` steps: a loop over :meth:`step` (:func:`jetgaudin.maps.step_loop`);
        ``backend`` / ``kernel``: checked by the backend rule (NumPy is this map's only route)."""
        self.with_backend(backend, kernel).resolved_backend(X, steps)
        X, carry, steps, save_every = self._checked(X, carry, steps, save_every)
        return step_loop(self, X, carry, steps, save_every)

    def describe(self) -> dict:
        return {"kind": self.kind, **self.model.describe(), "eta": [self.eta.real, self.eta.imag],
                "branch": self.branch.value}


@dataclass(frozen=True)
class _ChainTwoPoint(_ChainMap):
    r"""The chain's route of :class:`jetgaudin.TwoPointBacklund` (:mod:`jetgaudin._system_maps`): the real two-point
    Bäcklund map ``B_η`` of a chain (module docstring); the time-1 flow of ``G_η``.

    Parameters
    ----------
    model : GaudinModel
    eta : complex
        ``Re η`` off the sites, ``Im η ≠ 0``.
    branch : Branch or {"default", "opposite"}
        ``ν1 = ±ν(η)`` by the branch rule; ``"opposite"`` is the inverse map.
    backend, kernel : Backend or {"numpy", "compiled", "auto"}
        Route of :meth:`advance` / :meth:`iterate` (``kernel`` is an alias; default ``"auto"``, the rule of
        :func:`resolve_backend`).

    Raises
    ------
    InvalidParameterError
        ``Re η`` at a site, ``Im η = 0``, a non-finite ``η``, an unknown branch.
    """

    model: GaudinModel
    eta: complex
    branch: Branch = Branch.DEFAULT
    backend: Backend = field(default=Backend.AUTO, compare=False)
    kernel: Backend | str | None = field(default=None, compare=False, repr=False)
    kind = "chain_two_point"
    public_name = "TwoPointBacklund"  # the class its messages name (jetgaudin.maps.map_name)
    properties: MapProperties = field(
        default=MapProperties(
            preserves_integrals=True, poisson=True, real=True, order=2, symmetric=True, interpolates_flow=True
        ),
        init=False,
        repr=False,
        compare=False,
    )

    def __post_init__(self) -> None:
        self._init_common()
        if self.eta.imag == 0:
            raise InvalidParameterError(
                f"Im(eta) = 0 (eta = {self.eta.real}): the real two-point map needs eta1 = eta != eta2 = conj(eta) "
                "(at Im eta = 0 it degenerates to the identity); give Im(eta) != 0, its time step is -2 Im(eta)"
            )

    def inverse(self) -> _ChainTwoPoint:
        """The same ``η`` on the other branch (same backend)."""
        other = Branch.OPPOSITE if self.branch is Branch.DEFAULT else Branch.DEFAULT
        return _ChainTwoPoint(self.model, self.eta, other, self.backend)

    def describe(self) -> dict:
        return {**super().describe(), "backend": self.backend.value}

    @property
    def has_compiled(self) -> bool:
        """The rational family's map runs in :mod:`jetgaudin.gaudin._kernels`, the others' in the one family kernel
        of :mod:`jetgaudin.gaudin._family_kernel` (where the family declares its ``kernel_rule``)."""
        return self.model.family.uniform or self.model.family.kernel_rule is not None

    @property
    def has_gpu(self) -> bool:
        """The GPU route (:mod:`jetgaudin.gpu`): the one family kernel's loop, one thread per orbit, every family."""
        return self.has_compiled

    def _kernel(self):
        """``(module name, dispatcher, run(x, ν, steps, save_every))`` of the compiled route."""
        b = float(self.model.b)
        c = _orbit_constants(self.model, self.eta)
        if self.model.family.uniform:  # the rational chain kernel (its speed and bits kept)
            from . import _kernels as K

            return "_kernels", K.run_orbit, lambda x, nu, n, se: K.run_orbit(x, b, self.eta, nu, *c, n, se)
        from . import _family_kernel as F

        return "_family_kernel", F.run_orbit, lambda x, nu, n, se: F.run_orbit(x, b, nu, *c, n, se)

    def prepare_kernels(self, X: np.ndarray | None = None, steps: int | None = None, notify=None):
        """Compile (or load) the chain kernel visibly before a compiled run of ``steps`` steps from ``X`` (as
        :meth:`jetgaudin.TwoPointBacklund.prepare_kernels`: a message with the expected time first, one when done;
        nothing when it is loaded already, in Numba's cache (loaded quietly, timed) or the NumPy route is used).
        Returns a ``CompileReport`` or ``None``."""
        if X is None:  # everything it could need: the kernel on one state of the model
            X, steps = np.ones(self.model.n_state), AUTO_MIN_WORK
        route = self.resolved_backend(X, AUTO_MIN_WORK if steps is None else steps)
        if route is Backend.GPU and np.size(X):
            from ..gpu import prepare

            return prepare(self.model.n_state, notify, self)
        if route is not Backend.COMPILED or np.size(X) == 0:
            return None
        if self.model.is_top and self.model.M >= 2:  # the top's kernels (the route of advance)
            return self._top_map().prepare_kernels(X, steps, notify)
        from ..backlund._compiled import kernels

        x0 = np.reshape(np.asarray(X, dtype=float), (-1, np.shape(X)[-1]))[:1]
        name, disp, _ = self._kernel()
        loaded = bool(getattr(disp, "signatures", None))
        where = getattr(getattr(disp, "_cache", None), "_cache_path", None)  # Numba's cache directory
        cached = isinstance(where, str) and bool(glob.glob(os.path.join(where, f"{name}.run_orbit-*.nbi")))
        compiled = _ChainTwoPoint(self.model, self.eta, self.branch, Backend.COMPILED)
        return kernels().prepare_call((f"gaudin.{name}.run_orbit",), loaded, CHAIN_COMPILE_S,
                                      lambda: compiled.advance(x0, None, 0), notify, cached)

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1, *,
                backend: Backend | str | None = None, kernel: Backend | str | None = None) -> Advance:
        """As :meth:`_ChainMap.advance` (``backend`` / ``kernel``: this call's route); on the compiled route
        (``backend``, :meth:`resolved_backend`) the steps run in the Numba kernel of :mod:`jetgaudin.gaudin._kernels`
        (rational) or :mod:`jetgaudin.gaudin._family_kernel` (other families): the same orbits to round-off; ``ν1``
        at ``X`` by the NumPy branch rule; the residual check is not made and ``imag_max`` is zeros (the imaginary
        residue is not computed).  A batch member equals its single run, and a split run the unsplit one, bit for
        bit (both routes)."""
        if backend is not None or kernel is not None:
            return self.with_backend(backend, kernel).advance(X, carry, steps, save_every)
        X, carry, steps, save_every = self._checked(X, carry, steps, save_every)
        route = self.resolved_backend(X, steps)
        if route not in (Backend.COMPILED, Backend.GPU) or X.size == 0:
            return step_loop(self, X, carry, steps, save_every)
        if route is Backend.COMPILED and self.model.is_top and self.model.M >= 2:
            return self._top_map().advance(X, carry, steps, save_every)  # the top's kernels: a route-table entry
        shape = X.shape
        Xb = X.reshape(-1, shape[-1])
        nu = self._compiled_start(Xb) if carry is None else np.reshape(carry, -1)
        if route is Backend.GPU:  # the family kernel's loop, one thread per orbit (jetgaudin.gpu)
            from ..gpu import run_chain

            rows, final, last = run_chain(self.model, self.eta, Xb, nu, steps, save_every)
            return self._finish(rows, final, last, shape)
        name, _, run_orbit = self._kernel()
        if name == "_family_kernel" and Xb.shape[0] > 1:  # a batch on all cores, each orbit its single run's bits
            from . import _family_kernel

            run_batch: Any = _family_kernel.run_batch  # a Numba dispatcher
            rows, final, last = run_batch(np.ascontiguousarray(Xb), float(self.model.b), nu.astype(complex),
                                          *_orbit_constants(self.model, self.eta), steps, save_every)
            return self._finish(rows, final, last, shape)
        rows = np.empty((steps // save_every,) + Xb.shape)
        final = np.empty_like(Xb)
        last = np.empty(Xb.shape[0], dtype=complex)
        for n in range(Xb.shape[0]):
            out, final[n], last[n] = run_orbit(np.ascontiguousarray(Xb[n]), complex(nu[n]), steps, save_every)
            rows[:, n] = out[1:]
        return self._finish(rows, final, last, shape)

    def iterate(self, X0, steps: int, *, save_every: int = 1, carry: Any = None, return_carry: bool = False,
                backend: Backend | str | None = None, kernel: Backend | str | None = None):
        """:meth:`_ChainMap.iterate`; a top's compiled route (``model.is_top``) is the top map's own ``iterate`` (its
        orbit array written in place: the top's speed, ``benchmarks/top_as_model.py``)."""
        m = self.with_backend(backend, kernel)
        if self.model.is_top and self.model.M >= 2:
            X = self.model.check_state(X0)
            if m.resolved_backend(X, steps) is Backend.COMPILED:
                return m._top_map().iterate(X, steps, save_every=save_every, carry=carry, return_carry=return_carry)
        return super(_ChainTwoPoint, m).iterate(X0, steps, save_every=save_every, carry=carry,
                                                       return_carry=return_carry)

    def _top_map(self):
        """The top's compiled two-point map of this one-site model (``model.is_top``, order ``N ≥ 2``): the route
        table's entry that takes the top's hand-tuned kernels (``docs/architecture.md``; same orbits to round-off,
        ``tests/test_top_as_model.py``)."""
        from ..backlund.maps import _TopTwoPoint

        return _TopTwoPoint(self.model.b, self.eta, self.branch, Backend.COMPILED)

    def _compiled_start(self, Xb: np.ndarray) -> np.ndarray:
        """``ν1`` at the states ``Xb`` ``(B, 3M)`` by the compiled branch rule
        (:func:`jetgaudin.gaudin._family_kernel.branch_rule`, every family), the exact NumPy rule (:meth:`start`)
        for the states it flags; only the sign of ``ν1`` reaches the kernels (they take the root of ``ν²`` nearest
        to it), so the orbits are the NumPy-started ones bit for bit wherever the two rules agree
        (``tests/test_chain_compiled_start.py``)."""
        from ._family_kernel import branch_rule, segment_constants

        nu, ok = branch_rule(np.ascontiguousarray(Xb, dtype=float), float(self.model.b),
                             segment_constants(self.model, self.eta), self.sheet)
        if not np.all(ok):
            nu[~ok] = self.start(Xb[~ok])
        return nu

    @staticmethod
    def _finish(rows, final, last, shape) -> Advance:
        if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(final))):
            raise SingularStepError("the compiled chain orbit produced non-finite values; change eta")
        return Advance(rows=rows.reshape((rows.shape[0],) + shape), X=final.reshape(shape),
                       carry=last.reshape(shape[:-1]), imag_max=np.zeros(shape[:-1]))

    def _setup(self, X, carry):
        """``(ell, L(η), ν1, M0)`` for a 2-D batch ``X`` (other families: the dressing coefficients ``c``
        ``(B, P)`` of :mod:`jetgaudin.gaudin._dressing` in place of ``M0``)."""
        ell = ell_coefficients(X, self.model.b)
        if self.model.family.uniform:
            L = _ell_at(self.model, ell[..., 1:, :, :], self.eta)
        else:  # compensated with the two-word weights (gaudin._compensated; issue 33), else the plain sums
            L = family_lax(self.model, X, self.eta)
            L = _matrix(self.model.xi(X, self.eta)) if L is None else L
        # the root of ν(η)² (from ℓ(η)) closest to the carry, or to the branch rule's value: step(X) and
        # step(X, start(X)) are the same bits
        ref = self._nu_rule(X) if carry is None else np.asarray(carry).reshape(-1)
        nu1 = _continue(L[..., 0, 0] ** 2 + L[..., 0, 1] * L[..., 1, 0], ref)
        if not self.model.family.uniform:
            # D times |ℓ(ξ)|² scaled to [1/4, 1): unnormalised (a normalised D has the same det D at every step,
            # whose reciprocal rounds alike each time: a linear drift, as monic_series); the dressing does not
            # depend on D's scale
            m, e = np.frexp(np.sum(np.abs(L[..., :, :]) ** 2, axis=(-2, -1)))
            c = real_coefficients(self.model, self.eta, L, nu1)
            return ell, L, nu1, c * np.ldexp(m, e - 2 * ((e + 1) // 2))[..., None]
        k1, k2 = eigenvector(L[..., 0, 0], L[..., 0, 1], L[..., 1, 0], nu1)
        return ell, L, nu1, real_two_point_M0(self.eta, k1, k2)

    def dressing_matrix(self, X, lam, carry=None) -> np.ndarray:
        """``M(λ) = λ + M0`` of eq. (mm) at ``X`` (real reduction), shape ``(..., 2, 2)``; ``M ℓ(X) = ℓ(X̆) M``
        (other families: ``D(λ) = Σ_p c_p B_p(λ)``, scalar ``λ``)."""
        X = self.model.check_state(X)
        M0 = self._setup(X.reshape(-1, X.shape[-1]), carry)[3]
        if not self.model.family.uniform:
            return dressing_at(self.model, M0, lam, self.eta).reshape(X.shape[:-1] + (2, 2))
        M0 = M0.reshape(X.shape[:-1] + (2, 2))
        return M0 + np.asarray(lam, dtype=complex)[..., None, None] * _ID

    def step(self, X, carry=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One step: ``(X̆, ν1, imag_residue)``; ``carry=None``: ``ν1`` by the branch rule, else the root of
        ``ν(η)²`` closest to ``carry``.  ``X̆`` is real (imaginary part dropped, its size relative to
        ``1 + |X̆|`` returned)."""
        X = self.model.check_state(X)
        shape = X.shape
        X = X.reshape(-1, shape[-1])  # 2-D batch: a single orbit equals its ensemble member bit for bit
        ell, L, nu1, M0 = self._setup(X, carry)
        scale = 1.0 + np.max(np.abs(ell), axis=(-3, -2, -1))
        if self.model.family.uniform:
            A0 = adj(M0)
            res = _residual(M0 + self.eta * _ID, L, A0 + self.eta * _ID, scale) / abs(2 * self.eta.imag)
            series = None
        else:  # the family's dressing: residual relative to |D(η)|², principal parts from its Taylor series
            D1 = dressing_at(self.model, M0, self.eta, self.eta)
            res = _residual(D1, L, adj(D1), scale) / np.max(np.abs(D1), axis=(-2, -1)) ** 2
            series = family_site_series(self.model, M0, self.eta)  # compensated (gaudin._compensated)
            series = site_series(self.model, M0, self.eta) if series is None else series
        if np.any(res > _RESIDUAL_TOL):
            raise SingularStepError(
                f"two-point Bäcklund step of the chain: the pole at eta does not cancel (relative residue "
                f"{np.max(res):.2e}); eta is numerically at a branch point; change eta"
            )
        if series is None:  # K = n2 (λ + M0), formed without the normalised M0 (scaled_two_point_K0; issue 33)
            k1, k2 = eigenvector(L[..., 0, 0], L[..., 0, 1], L[..., 1, 0], nu1)
            K0, n2 = scaled_two_point_K0(self.eta, k1, k2)
            new = dress_sites(self.model, ell[..., 1:, :, :], monic_series(self.model, K0, adj(K0), n2, scaled=True))
        else:
            new = dress_sites(self.model, ell[..., 1:, :, :], series)
        Xc = state_from_ell(np.concatenate([ell[..., :1, :, :], new], axis=-3))
        Xr = Xc.real
        if not np.all(np.isfinite(Xr)):
            raise SingularStepError("two-point Bäcklund step of the chain produced non-finite values; change eta")
        imag = np.max(np.abs(Xc.imag), axis=-1) / (1.0 + np.max(np.abs(Xr), axis=-1))
        return Xr.reshape(shape), nu1.reshape(shape[:-1]), imag.reshape(shape[:-1])


def _sites(d: dict) -> GaudinModel:
    return GaudinModel.from_description(d)


ChainTwoPointBacklund = TwoPointBacklund  #: the old name for chains: the same class (isinstance both ways)


def _two_point_from(d: dict) -> TwoPointBacklund:
    return TwoPointBacklund(_sites(d), complex(*d["eta"]), Branch.parse(d.get("branch", "default")),
                            Backend.parse(d.get("backend", "numpy")))


register_map("chain_two_point", _two_point_from)
register_model_map("chain_two_point", ChainTwoPointBacklund)  # model.two_point_backlund (gaudin._model_map)


def __getattr__(name: str):
    """``ChainOnePointBacklund``, which lives in :mod:`jetgaudin.gaudin._one_point` (every family's one-point
    dressing; it imports this module's helpers), still importable from here (looked up on use: no import cycle)."""
    if name == "ChainOnePointBacklund":
        from ._one_point import ChainOnePointBacklund

        return ChainOnePointBacklund
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
