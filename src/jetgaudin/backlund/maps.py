r"""Bäcklund transformations of Section 6: the one-point map and the real two-point map.

Conventions (see ``docs/backlund.md``, section 1):

* ``ν`` is an eigenvalue of ``ℓ(λ) = [[u, v], [w, −u]] = −2i L(λ)``, ``ν² = u² + vw``;
  the paper's ``μ`` in the spectrality formulas (hhh), (x), (X) is this ``ν``.
* One-point map ``B_(η, ν)`` (eqs. (rr), (ansatz), (hh), (hhh)): ``M = [[λ − η + pq, p], [q, 1]]``,
  ``p = y_0^-/(2b)``, ``q = (u(η) − ν)/v(η)``; ``[1, −q]`` is the eigenvector of ``ℓ(η)`` for ``ν``.
* Two-point map (eqs. (128), (mm), (x), (X)): ``M = λ + M0(s, t)``; ``[1, −s]`` is the eigenvector
  of ``ℓ(η1)`` for ``ν1`` and ``[1, κ]``, ``κ = (η1 − η2)/t − s``, the eigenvector of ``ℓ(η2)`` for
  ``−ν2`` (the point ``Q2 = (η2, −μ2)`` of the paper).
* Real reduction: ``η1 = η``, ``η2 = η̄`` **and** ``ν2 = conj(ν1)`` (so ``−ν2`` is the eigenvalue at
  ``η̄`` on the sheet opposite to ``ν(η̄) = conj ν(η)``); proof in ``docs/backlund.md``.
* Default branch: ``ν1 = ν(η)`` continued from the positive root at ``Re η`` along the vertical
  segment (:func:`jetgaudin.nu`); ``branch="opposite"`` uses ``−ν1`` and gives the inverse map.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._errors import InvalidParameterError, SingularStepError
from .._system_maps import _ONE_POINT_PROPERTIES, _TWO_POINT_PROPERTIES, OnePointBacklund, TwoPointBacklund
from .._validate import as_state, nonzero_field, spectral_parameter
from ..lax import ell_coefficients, state_from_ell
from ..maps import (
    Advance,
    Backend,
    Branch,
    Map,
    MapProperties,
    backend_option,
    check_count,
    check_output_size,
    register_map,
    step_loop,
)
from ..spectral import _nu_from_kappa, curve_coefficients, integrals
from . import _compiled
from ._dressing import (
    _safe_ratio,
    dress_one_point,
    dress_real_two_point,
    dress_two_point,
    eigenvector,
    horner,
    real_two_point_M0,
    spectral_kappa,
    spectral_s,
    two_point_M0,
)
from .kernels import auto_kernel  # the kernel choice of kernel="auto" lives with the kernels

__all__ = [  # what this module defines (Backend, Branch, MapProperties are jetgaudin.maps' own; the two public map
    # classes are jetgaudin._system_maps', one per kind of map for every system, re-exported here)
    "OnePointBacklund",
    "TwoPointBacklund",
    "two_point_parameters",
    "one_point_parameters",
    "two_point_general",
]

#: tolerance on the relative residual of the exact division (round-off level: the division
#: is exact in exact arithmetic; values above this mean the spectral data are inconsistent)
_RESIDUAL_TOL = 1e-8


def _sheet(branch: Branch | str | int) -> int:
    """``+1``/``-1`` for a branch (enum, name or sheet); :class:`InvalidParameterError` otherwise."""
    return Branch.parse(branch).sheet


def _nu_default(X, b, eta, sheet):
    kappa = curve_coefficients(X, b)
    return _nu_from_kappa(kappa, np.asarray(eta, dtype=complex) * np.ones(X.shape[:-1]), sheet)


def _continue_nu(ell, eta, nu_prev):
    """``ν(η)`` for the state with Laurent coefficients ``ell``, on the root closest to ``nu_prev``.

    Exact continuation along an orbit: ν(η) depends on the state only through the integrals,
    which the maps preserve, so consecutive values differ by round-off only.
    """
    L = horner(ell, eta)
    nu2 = L[..., 0, 0] ** 2 + L[..., 0, 1] * L[..., 1, 0]
    r = np.sqrt(nu2)
    return np.where((np.conj(r) * nu_prev).real >= 0, r, -r)


def two_point_parameters(ell, eta1, eta2, nu1, nu2):
    r"""``(s, t)`` of eqs. (x), (X) from ``ℓ`` at ``η1, η2`` and the eigenvalues ``ν1`` at ``η1``,
    ``−ν2`` at ``η2``.  Raises :class:`SingularStepError` at vanishing denominators."""
    L1 = horner(ell, eta1)
    L2 = horner(ell, eta2)
    s = spectral_s(L1[..., 0, 0], L1[..., 0, 1], L1[..., 1, 0], nu1)
    kappa = spectral_kappa(L2[..., 0, 0], L2[..., 0, 1], L2[..., 1, 0], -nu2)
    den = s + kappa
    if np.any(np.abs(den) <= 1e-13 * (np.abs(s) + np.abs(kappa))) or np.any(den == 0):
        raise SingularStepError(
            "singular Bäcklund step: the denominator s + kappa of t (eq. (X)) vanishes "
            "(the two eigenvectors at eta1 and eta2 coincide); change eta"
        )
    return s, (eta1 - eta2) / den


def two_point_general(X, b, eta1, eta2, nu1, nu2):
    r"""The general (complex) two-point map of eqs. (128), (mm), (x), (X) for any ``η1, η2`` and
    eigenvalues ``ν1`` of ``ℓ(η1)`` and ``−ν2`` of ``ℓ(η2)`` (``B_{Q2} ∘ B_{P1}`` with
    ``P1 = (η1, ν1)``, ``Q2 = (η2, −ν2)``); returns complex states ``(..., 3N)``."""
    X, _ = as_state(X, allow_complex=True)
    ell = ell_coefficients(X, b)
    s, t = two_point_parameters(ell, eta1, eta2, nu1, nu2)
    new_ell, res = dress_two_point(ell, eta1, eta2, two_point_M0(eta1, eta2, s, t))
    _check_residual(res, ell, "two-point Bäcklund step")
    return state_from_ell(new_ell)


def one_point_parameters(ell, eta, nu, b):
    r"""``(p, q)`` of eqs. (hh), (hhh): ``p = y_0^-/(2b)``, ``q = (u(η) − ν)/v(η)``."""
    L = horner(ell, eta)
    q = spectral_s(L[..., 0, 0], L[..., 0, 1], L[..., 1, 0], nu)
    p = ell[..., 1, 0, 1] / (2.0 * b)
    return p, q


def _check_residual(res, ell, what):
    scale = 1.0 + np.max(np.abs(ell), axis=(-3, -2, -1))
    rel = res / scale
    if np.any(rel > _RESIDUAL_TOL):
        raise SingularStepError(
            f"{what}: the dressing division left a remainder {np.max(rel):.2e} (relative); the step "
            "is numerically singular (eta close to a branch point or a vanishing denominator)"
        )


def _check_nu(nu: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    """``nu`` broadcast to ``shape`` (complex, finite); :class:`InvalidParameterError` otherwise."""
    try:
        arr = np.broadcast_to(np.asarray(nu, dtype=complex), shape)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a complex number or an array of shape {shape}") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{name} must be finite (NaN or inf given)")
    return arr


def _empty_advance(X: np.ndarray, steps: int, save_every: int, carry: Any) -> Advance:
    """The advance of a batch of zero orbits (both routes: nothing to compute)."""
    return Advance(rows=np.empty((steps // save_every,) + X.shape, dtype=X.dtype), X=X.copy(), carry=carry,
                   imag_max=np.zeros(X.shape[:-1]))




def _init_parameters(m) -> None:
    """Validate the parameters every Bäcklund map of the top shares (``b ≠ 0``, ``η``, the branch, the backend and
    its alias ``kernel``), in place on the frozen dataclass ``m``."""
    object.__setattr__(m, "b", nonzero_field(m.b))
    object.__setattr__(m, "eta", spectral_parameter(m.eta))
    object.__setattr__(m, "branch", Branch.parse(m.branch))
    m._init_backend()


@dataclass(frozen=True)
class _TopTwoPoint(Map):
    r"""The top's route of :class:`jetgaudin.TwoPointBacklund` (its system a field ``b``; the route table of
    :mod:`jetgaudin._system_maps`): the real two-point Bäcklund map ``B_η: X ↦ X̆`` (Section 6.2, Appendix 1), any N.

    ``X̆`` solves ``M(λ) L(λ) = L̆(λ) M(λ)`` (eq. (128)) with ``M = λ + M0(s, t)`` of (mm),
    ``η1 = η``, ``η2 = η̄``, ``ν1 = ν(η)`` on the chosen branch and ``ν2 = conj ν1``.
    Field ``b e_3`` (``b ≠ 0``); ``Im η ≠ 0`` (``Im η`` is the time step: ``Im η = 0`` would be the identity
    map and is refused with :class:`InvalidParameterError`).  Maps real states ``(..., 3N)`` to real states;
    it preserves the 2N integrals, is a Poisson map, commutes with itself for other ``η``, has the
    ``"opposite"`` branch as inverse, and equals the time-1 flow of ``G_η``
    (the value of ``G_η`` is :func:`jetgaudin.interpolating_hamiltonian`; the quadratic Hamiltonian with the same
    flow from a given ``X0``, for :func:`jetgaudin.integrate`, is :func:`jetgaudin.interpolating_flow_hamiltonian`).
    ``backend`` (alias ``kernel``; default ``"auto"``): the route of :meth:`advance` / :meth:`iterate`, by the rule
    of :mod:`jetgaudin.maps` (the carry is ``ν1``).

    """

    b: float
    eta: complex
    branch: Branch = Branch.DEFAULT
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_TWO_POINT_PROPERTIES, init=False, repr=False, compare=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias
    public_name = "TwoPointBacklund"  # the class its messages name (jetgaudin.maps.map_name)

    def __post_init__(self) -> None:
        _init_parameters(self)
        if self.eta.imag == 0:
            raise InvalidParameterError(
                "eta must have a nonzero imaginary part (Im eta = 0 is the identity map: the real two-point map is "
                "a step -2 Im eta of the flow of nu(Re eta)); give e.g. eta = 5+0.1i"
            )

    @property
    def sheet(self) -> int:
        return self.branch.sheet

    def inverse(self) -> _TopTwoPoint:
        """The inverse map: the same ``η`` on the other branch."""
        other = Branch.OPPOSITE if self.branch is Branch.DEFAULT else Branch.DEFAULT
        return _TopTwoPoint(self.b, self.eta, other, self.backend)

    def describe(self) -> dict:
        return {"kind": "two_point", "b": self.b, "eta": [self.eta.real, self.eta.imag],
                "branch": self.branch.value, "backend": self.backend.value}

    def integrals(self, X: np.ndarray) -> np.ndarray:
        """``(H_1..H_N, C_1..C_N)`` at ``X`` (:func:`jetgaudin.integrals` with this field), shape ``(..., 2N)``."""
        return np.asarray(integrals(X, self.b), dtype=float)

    def start(self, X: np.ndarray) -> np.ndarray:
        """``ν1`` by the branch rule at ``X`` (as :meth:`nu1`)."""
        return np.asarray(self.nu1(X), dtype=complex)

    def nu1(self, X):
        """``ν1 = ±ν(η)`` used by the map at ``X`` (default branch times the sheet)."""
        X, _ = as_state(X)
        return _nu_default(X, self.b, self.eta, self.sheet)

    def parameters(self, X, nu1=None):
        """``(s, t, ν1)`` of eqs. (x), (X) at ``X``."""
        X, _ = as_state(X)
        if nu1 is None:
            nu1 = self.nu1(X)
        ell = ell_coefficients(X, self.b)
        s, t = two_point_parameters(ell, self.eta, np.conj(self.eta), nu1, np.conj(nu1))
        return s, t, nu1

    def step(self, X, nu1=None):
        """One step; returns ``(X̆, ν1, imag_residue)`` with ``X̆`` real (imaginary part dropped,
        its size relative to ``1 + |X̆|`` returned as ``imag_residue``).

        ``nu1=None``: ``ν1`` from the branch rule; otherwise the root of ``ν(η)²`` closest to ``nu1``
        (continuation along an orbit)."""
        X, _ = as_state(X)
        # work on a 2-D batch: NumPy's scalar and 0-d paths round complex arithmetic differently from its
        # array loops, and a single orbit must equal its ensemble member bit for bit
        shape = X.shape
        X = X.reshape(-1, shape[-1])
        if nu1 is not None:
            nu1 = _check_nu(nu1, shape[:-1], "nu1").reshape(-1)
        ell = ell_coefficients(X, self.b)
        if nu1 is None:
            nu1 = _nu_default(X, self.b, self.eta, self.sheet)
        else:
            nu1 = _continue_nu(ell, self.eta, nu1)
        L1 = horner(ell, self.eta)
        k1, k2 = eigenvector(L1[..., 0, 0], L1[..., 0, 1], L1[..., 1, 0], nu1)
        M0 = real_two_point_M0(self.eta, k1, k2)
        new_ell, res = dress_real_two_point(ell, self.eta, M0)
        _check_residual(res, ell, "two-point Bäcklund step")
        Xc = state_from_ell(new_ell)
        Xr = Xc.real
        imag = np.max(np.abs(Xc.imag), axis=-1) / (1.0 + np.max(np.abs(Xr), axis=-1))
        if not np.all(np.isfinite(Xr)):
            raise SingularStepError("two-point Bäcklund step produced non-finite values; change eta")
        return Xr.reshape(shape), nu1.reshape(shape[:-1]), imag.reshape(shape[:-1])

    @property
    def has_gpu(self) -> bool:
        """The GPU route (:mod:`jetgaudin.gpu`): one thread per orbit, the compiled route's orbit loop."""
        return True

    def _auto_backend(self, X: np.ndarray, steps: int) -> Backend:
        """``AUTO``: :func:`auto_kernel` (compiled when its kernels are loaded, or from 2000 orbit-steps on when
        Numba's cache holds them, or from 20000 on when they must first be compiled; NumPy otherwise)."""
        return Backend(auto_kernel(steps, X.shape[-1], X.shape[:-1]))

    def prepare_kernels(self, X: np.ndarray | None = None, steps: int | None = None, notify=None):
        """Compile (or load) the kernels that :meth:`advance` of ``steps`` steps from ``X`` will call, saying so first
        with the expected time (``notify(message)``; default: stderr) and when done; nothing is said when they are
        loaded already, found in Numba's cache (loaded in a fraction of a second, timed) or the NumPy route is used.
        ``steps=None``: any number of steps (the kernels of the compiled route unless ``backend="numpy"``); no
        arguments: every kernel a two-point map could need (every N, one orbit and batches:
        :func:`jetgaudin.backlund.kernels.warmup`).  Returns a :class:`~jetgaudin.backlund.kernels.CompileReport`
        (``None`` on the NumPy route).  The run layer calls it before a run, so that compile time is visible and
        apart from the stepping rate; :meth:`iterate` and :meth:`advance` compile silently on first use."""
        if self.backend is Backend.NUMPY:
            return None
        K = _compiled.kernels()
        if X is None and self.backend is not Backend.GPU:
            return K.warmup(notify)
        X, _ = as_state(np.zeros(9) if X is None else X)
        if X.size and self.resolved_backend(X, 1 if steps is None else steps) is Backend.GPU:
            from ..gpu import prepare

            return prepare(X.shape[-1], notify)
        if X.size == 0 or (steps is not None and self.resolved_backend(X, steps) is not Backend.COMPILED):
            return None
        return K.prepare(X.shape[-1], None if X.ndim == 1 else int(np.prod(X.shape[:-1])), notify=notify,
                         announce_load=False)

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """``steps`` steps from ``X`` ``(..., 3N)`` continuing from ``carry = ν1`` (``None``: the branch rule at
        ``X``); rows every ``save_every`` steps.  NumPy route: a loop over :meth:`step` (imaginary residue of
        every step); compiled route: the Numba kernels (``ν1`` at ``X`` by the compiled branch rule, equal to
        the NumPy rule to round-off; ``imag_max`` zeros: the residue is not computed)."""
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        X, _ = as_state(X)
        if carry is not None:
            carry = _check_nu(carry, X.shape[:-1], "nu1")
        if X.size == 0:
            return _empty_advance(X, steps, save_every, carry)
        if self.resolved_backend(X, steps) in (Backend.COMPILED, Backend.GPU):
            return self._compiled_advance(X, carry, steps, save_every)
        return step_loop(self, X, carry, steps, save_every)

    def _compiled_advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int) -> Advance:
        orbit, final, nu = self._orbit_compiled(X, carry, steps, save_every)
        return Advance(rows=orbit[1:], X=final, carry=nu, imag_max=np.zeros(X.shape[:-1]))

    def _orbit_compiled(self, X: np.ndarray, carry: Any, steps: int, save_every: int,
                        route: Backend | None = None) -> tuple[Any, Any, Any]:
        """``(orbit (steps//save_every + 1, ..., 3N) including X, final state, ν1)`` by the compiled kernels (on the
        GPU for ``backend="gpu"``, or ``AUTO`` resolved to it: :mod:`jetgaudin.gpu`, the same loop per orbit).
        ``route``: :meth:`resolved_backend` when the caller has it (resolving ``AUTO`` again cost ~15 µs of the
        Appendix 2 call's ~60, issue 36)."""
        K = _compiled.kernels()
        cont = carry is not None
        lead = X.shape[:-1]
        Xb = X.reshape(-1, X.shape[-1])
        B = Xb.shape[0]
        bb = np.array([self.b]) if B == 1 else np.full(B, self.b)
        ee = np.array([self.eta], dtype=complex) if B == 1 else np.full(B, self.eta, dtype=complex)
        nu0 = np.reshape(carry, -1) if cont else K.nu_default(Xb, bb, ee, self.sheet)
        gpu = (self.resolved_backend(X, steps) if route is None else route) is Backend.GPU
        if X.ndim == 1 and not gpu:
            out, final, _, nu = K.iterate_single(X, self.b, self.eta, complex(nu0[0]), cont, steps, save_every,
                                                 want_drift=False)
            return out, final, np.complex128(nu)
        if gpu:
            from ..gpu import iterate_batch
        else:
            iterate_batch = K.iterate_batch
        out, final, _, nu = iterate_batch(Xb, bb, ee, nu0, cont, steps, save_every, want_drift=False)
        orbit = np.ascontiguousarray(np.moveaxis(out, 0, 1)).reshape((out.shape[1],) + X.shape)
        return orbit, final.reshape(X.shape), nu.reshape(lead)

    def _with_backend_cached(self, choice: Backend) -> _TopTwoPoint:
        """:meth:`with_backend`, kept per map and backend: building the map again (validation included) was ~20 µs of
        the ~60 of an Appendix 2 call with ``kernel="compiled"`` (issue 36).  The maps are frozen: the copy stays
        equal to a new one."""
        cache = self.__dict__.setdefault("_backend_variants", {})
        m = cache.get(choice)
        if m is None:
            m = cache[choice] = self.with_backend(choice)
        return m

    def iterate(self, X0, steps: int, *, save_every: int = 1, kernel: Backend | str | None = None, nu1=None,
                return_nu: bool = False, carry=None, return_carry: bool = False,
                backend: Backend | str | None = None):
        """Orbit ``X_0, X_k, X_2k, …, X_{⌊steps/k⌋k}`` (``k = save_every``), shape ``(steps//k + 1, ..., 3N)``.

        ``ν(η)`` is taken on the chosen branch at ``X_0`` and continued along the orbit (it depends on
        the state only through the preserved integrals).  ``nu1`` (alias ``carry``, shape ``(...)``): continue
        from this value instead (the ``ν1`` of the step before ``X_0``; a run split in chunks, each given
        the previous chunk's last ``ν1``, equals the unsplit run bit for bit).  ``return_nu=True`` (alias
        ``return_carry``) returns ``(orbit, ν1)`` with the last ``ν1`` used.

        ``backend`` (alias ``kernel``; a :class:`~jetgaudin.maps.Backend` or its value; default: the map's
        ``backend``): ``"numpy"`` (the reference route), ``"compiled"`` (Numba kernels, N = 3 with a specialised
        kernel; the same orbits to round-off, ``ν1`` at ``X_0`` by the compiled branch rule; the imaginary residue
        of the steps is not computed), ``"gpu"`` (:mod:`jetgaudin.gpu`: the compiled route's loop, one orbit per GPU
        thread; equal to it to round-off, ~1e-16 relative per step) or ``"auto"`` (:func:`auto_kernel`: compiled when
        its kernels are already loaded in the process, or from 2000 orbit-steps on when Numba's on-disk cache
        holds them (loading costs about 1000 NumPy steps), or from 20000 on when they must first be compiled (about
        6 s); NumPy otherwise; the GPU only where one is present and the call is large,
        :func:`jetgaudin.gpu.auto_uses_gpu`).  Both routes keep the integrals at round-off (``docs/reliability.md``).
        A batch
        ``(..., 3N)`` gives, orbit by orbit, the bits of the single-orbit runs (both routes).  The compiled route
        compiles its kernels silently at first use (a library call prints nothing); call :meth:`prepare_kernels`
        first to see it and time it apart (the run layer and the CLI do).
        """
        choice = backend_option(backend, kernel)
        m = self if choice is None else self._with_backend_cached(choice)
        X, _ = as_state(X0)
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        check_output_size(steps // save_every + 1, X.size * 8, "iterate")
        c = nu1 if carry is None else carry
        if c is not None:
            c = _check_nu(c, X.shape[:-1], "nu1")
        route = m.resolved_backend(X, steps) if X.size else None
        if route in (Backend.COMPILED, Backend.GPU):  # the kernels write X_0 too
            orbit, _, c = m._orbit_compiled(X, c, steps, save_every, route)
        else:
            adv = m.with_backend(Backend.NUMPY).advance(X, c, steps, save_every)
            orbit, c = np.concatenate([X[None], adv.rows], axis=0), adv.carry
        return (orbit, c) if (return_nu or return_carry) else orbit


@dataclass(frozen=True)
class _TopOnePoint(Map):
    r"""The top's route of :class:`jetgaudin.OnePointBacklund` (:mod:`jetgaudin._system_maps`): the complex
    one-point Bäcklund map ``B_(η, ν)`` of Section 6.1 (or its inverse), any N,
    field ``b e_3``.

    Forward: ``L̃ = M L M^{-1}`` with ``M = [[λ − η + pq, p], [q, 1]]`` (eq. (ansatz)),
    ``p = y_0^-/(2b)`` (hh), ``q = (u(η) − ν)/v(η)`` (hhh, with the paper's ``μ`` read as ``ν``):
    ``[1, −q]`` is the eigenvector of ``ℓ(η)`` for ``ν``.

    Inverse (``inverse=True``): ``L = M^{-1} L̃ M`` with ``q = ỹ_0^+/(2b)`` and ``p = (ũ(η) − ν)/w̃(η)``
    (``[p, 1]`` is the eigenvector of ``ℓ̃(η)`` for ``−ν``).  This is the map the paper writes
    ``B_(η, −μ)``; it is *not* the forward map on the other sheet.

    ``ν = ±ν(η)`` by the branch rule of :func:`jetgaudin.nu` (principal root at ``Re η`` for complex
    states), ``branch="opposite"`` taking ``−ν(η)``.  Real input gives complex output.  The carry of
    :meth:`advance` is ``ν``; the imaginary residue is not defined (zeros).  ``backend`` (alias ``kernel``):
    the rule of :mod:`jetgaudin.maps`; this map has the NumPy route only (``"auto"``, the default, is
    ``"numpy"``; ``"compiled"`` is refused).
    """

    b: float
    eta: complex
    branch: Branch = Branch.DEFAULT
    inverse_map: bool = False
    backend: Backend = field(default=Backend.AUTO, compare=False)
    properties: MapProperties = field(default=_ONE_POINT_PROPERTIES, init=False, repr=False, compare=False)
    kernel: Backend | str | None = field(default=None, kw_only=True, repr=False, compare=False)  # alias
    public_name = "OnePointBacklund"  # the class its messages name (jetgaudin.maps.map_name)

    def __post_init__(self) -> None:
        _init_parameters(self)

    @property
    def sheet(self) -> int:
        return self.branch.sheet

    def inverse(self) -> _TopOnePoint:
        """The inverse map (same ``η`` and branch)."""
        return _TopOnePoint(self.b, self.eta, self.branch, not self.inverse_map, self.backend)

    def describe(self) -> dict:
        return {"kind": "one_point", "b": self.b, "eta": [self.eta.real, self.eta.imag],
                "branch": self.branch.value, "inverse": bool(self.inverse_map), "backend": self.backend.value}

    def integrals(self, X: np.ndarray) -> np.ndarray:
        """``(H_1..H_N, C_1..C_N)`` at (complex) ``X``, shape ``(..., 2N)``."""
        X, _ = as_state(X, allow_complex=True)
        return np.asarray(integrals(X, self.b))

    def start(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.nu(X), dtype=complex)

    def nu(self, X):
        """``±ν(η)`` at ``X`` on the chosen branch."""
        X, _ = as_state(X, allow_complex=True)
        return _nu_default(X, self.b, self.eta, self.sheet)

    def parameters(self, X, nu=None):
        """``(p, q, ν)`` of eqs. (hh), (hhh) at ``X`` (``X`` is the image point for the inverse map).

        ``nu=None``: ``ν`` by the branch rule; otherwise the root of ``ν(η)²`` closest to ``nu``."""
        X, _ = as_state(X, allow_complex=True)
        ell = ell_coefficients(X, self.b)
        if nu is None:
            nu = _nu_default(X, self.b, self.eta, self.sheet)
        else:
            nu = _continue_nu(ell, self.eta, _check_nu(nu, X.shape[:-1], "nu"))
        L = horner(ell, self.eta)
        u, v, w = L[..., 0, 0], L[..., 0, 1], L[..., 1, 0]
        if self.inverse_map:
            q = ell[..., 1, 1, 0] / (2.0 * self.b)
            p = _safe_ratio(
                u - nu, w, -v, u + nu,
                "singular inverse one-point step: w(eta) and u(eta) + nu(eta) both vanish; change eta",
            )
        else:
            p = ell[..., 1, 0, 1] / (2.0 * self.b)
            q = spectral_s(u, v, w, nu)
        return p, q, nu

    def step(self, X, nu=None):
        """One step; returns ``(X̃, ν, imag_residue)`` (``X̃`` complex, the residue zeros: not defined for a
        complex map).  ``nu``: continue from this ``ν`` (the root of ``ν(η)²`` closest to it) instead of
        applying the branch rule."""
        X, _ = as_state(X, allow_complex=True)
        p, q, nu = self.parameters(X, nu)
        ell = ell_coefficients(X, self.b)
        new_ell, res = dress_one_point(ell, self.eta, p, q, inverse=self.inverse_map)
        _check_residual(res, ell, "one-point Bäcklund step")
        out = state_from_ell(new_ell)
        if not np.all(np.isfinite(out)):
            raise SingularStepError("one-point Bäcklund step produced non-finite values; change eta")
        return out, nu, np.zeros(X.shape[:-1])

    def __call__(self, X):
        """Apply the map to states of shape ``(..., 3N)`` (real or complex); complex output."""
        return self.step(X)[0]

    def iterate(self, X0, steps: int, *, save_every: int = 1, carry=None, return_carry: bool = False,
                backend: Backend | str | None = None, kernel: Backend | str | None = None):
        """Orbit ``X_0, …, X_steps`` (complex), shape ``(steps//save_every + 1, ..., 3N)``.

        ``ν`` is taken by the branch rule at ``X_0`` and continued along the orbit (the map preserves ``ν(η)²``).
        The states grow complex and, in general, large: the one-point map is not a physical (real) map.
        ``backend`` (alias ``kernel``): ``"auto"`` or ``"numpy"`` (the only route).
        """
        X, _ = as_state(X0, allow_complex=True)
        return Map.iterate(self, X.astype(complex), steps, save_every=save_every, carry=carry,
                           return_carry=return_carry, backend=backend, kernel=kernel)

    def advance(self, X: np.ndarray, carry: Any, steps: int, save_every: int = 1) -> Advance:
        """A loop over :meth:`step` (``carry=None``: the branch rule at the first step)."""
        steps = check_count(steps, "steps")
        save_every = check_count(save_every, "save_every", 1)
        X, _ = as_state(X, allow_complex=True)
        X = X.astype(complex)
        if X.size == 0:
            return _empty_advance(X, steps, save_every, carry)
        return step_loop(self, X, carry, steps, save_every)


def _two_point_from(d: dict) -> TwoPointBacklund:
    return TwoPointBacklund(d["b"], complex(*d["eta"]), d.get("branch", "default"), d.get("backend", "auto"))


def _one_point_from(d: dict) -> OnePointBacklund:
    return OnePointBacklund(d["b"], complex(*d["eta"]), d.get("branch", "default"), bool(d.get("inverse", False)),
                            d.get("backend", "auto"))


register_map("two_point", _two_point_from)
register_map("one_point", _one_point_from)
