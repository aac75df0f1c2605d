r"""Jet constants ``c`` as a site option of :class:`~jetgaudin.GaudinModel` (issue 33, item 1).

A site at ``λ_s`` of order ``N`` with the constants ``c = (c_1, …, c_{N−1})`` of eq. (lax) carries the functions
``f_i(λ − λ_s) = Σ_n T[i, n] φ_n(λ − λ_s)`` (rational: ``φ_n(x) = x^{−(n+1)}``; :func:`jetgaudin.lax.jet_coefficients`,
``T[i, n] = (−1)^n [ε^i] c(ε)^n``), so its part of ``ξ(λ)`` is ``Σ_n Y_n φ_n(λ − λ_s)`` with

.. math:: Y_n = \sum_i T_{in}\, y_i \qquad (Y = T^{\mathsf T} y):

**the site with constants is the reduced site (lax2) in the variables** ``Y``.  The bracket of the ``y`` is (LP) for
every ``c`` (the paper's Prop. 1), and ``y ↦ Y`` is a Poisson map of ``g^(N)``: the ``y_i`` are the elements
``e_a ε^i`` of ``su(2) ⊗ C[ε]/(ε^N)`` (``{y_i, y_j} = y_{i+j}``, zero for ``i + j ≥ N``), and ``Y_n`` is
``e_a u(ε)^n`` with ``u(ε) = −c(ε)``; ``ε ↦ u(ε)`` is an endomorphism of the algebra ``C[ε]/(ε^N)`` (``u`` has no
constant term), so ``{Y_n, Y_m} = Y_{n+m}`` and ``0`` for ``n + m ≥ N`` (``u^{n+m} = O(ε^{n+m})``).  ``T`` is lower
triangular with the diagonal ``T[n, n] = (−c_1)^n``: an **isomorphism** exactly when ``c_1 ≠ 0`` (``c_1 = 0``
makes ``Y_{N−1}`` vanish for ``N ≥ 3``: the site is then not ``g^(N)`` in ``Y``; refused here).  Checked numerically
(the pulled-back bracket against (LP) at random points) and symbolically (SymPy, the paper's partition formula) in
``tests/test_site_constants.py``.

Hence, for a model with constants (``P = ⊕_s T_s^T ⊗ 1_3``, :func:`jet_matrix`): its integrals are the reduced
model's at ``P X`` (quadratic forms ``q ↦ S^T q S``), its Hamiltonian vector fields those of the reduced model
conjugated by ``P``, and every map of the reduced model ``B`` gives the map ``X ↦ P^{-1} B(P X)``
(:class:`SiteConstantsMap`): it preserves the integrals, is Poisson, and is the time-1 flow of the same ``G_η``
where ``B`` is.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from .._errors import InvalidParameterError
from .._validate import jet_constants
from ..lax import jet_coefficients
from ..maps import Advance, Backend, Map, MapProperties
from ._model_map import ModelMap

__all__ = ["split_sites", "jet_matrix", "SiteConstantsMap", "conjugated"]


def _site_constants(c, lam: float, N: int) -> tuple[float, ...] | None:
    """``c`` of the site at ``lam`` of order ``N`` as a tuple of ``N − 1`` real floats, ``None`` for the reduction
    (lax2) (``c = None``, ``N = 1``, or ``c = (−1, 0, …)``)."""
    if c is None or N == 1 and np.size(c) == 0:
        return None
    try:
        cc = jet_constants(c, N)
    except InvalidParameterError as exc:  # (a ValueError: first)
        raise InvalidParameterError(f"the site at {lam} (order {N}): {exc}") from None
    except (TypeError, ValueError):
        raise InvalidParameterError(f"the jet constants of the site at {lam} must be numbers, got {c!r}") from None
    if np.any(cc.imag != 0):
        raise InvalidParameterError(
            f"the jet constants of the site at {lam} must be real (a model's states and maps are real), got {c!r}; "
            "complex constants: the top's functions jg.lax_matrix / jg.integrals with c=")
    out = tuple(float(x) for x in cc.real)
    if out[0] == 0.0:
        raise InvalidParameterError(
            f"the site at {lam}: c_1 = 0 makes the jet matrix T singular (T[n, n] = (-c_1)^n): the site is then not "
            "the jet algebra g^(N) in Y = T^T y (its Lax matrix has fewer than N independent jets); give c_1 != 0")
    return None if out == (-1.0,) + (0.0,) * (N - 2) else out


def split_sites(sites, constants) -> tuple[Any, list | None]:
    """``(pairs, constants)``: the sites as ``(position, order)`` pairs and the normalised constants (a tuple with one
    entry per site, ``None`` or ``N − 1`` real floats; ``None`` overall when no site has constants).  A site may be
    given as ``(position, order, c)``; ``constants`` (one entry per site) is the keyword form.  Both at once is
    refused."""
    try:
        items = list(sites)
    except TypeError:
        return sites, None  # the caller's own check names the mistake
    triples = [s for s in items if isinstance(s, (tuple, list)) and len(s) == 3]
    pairs = [tuple(s[:2]) if isinstance(s, (tuple, list)) and len(s) == 3 else s for s in items]
    if triples and constants is not None:
        raise InvalidParameterError("give the jet constants either in the sites, (position, order, c), or as "
                                    "constants=, not both")
    if triples:
        constants = [s[2] if isinstance(s, (tuple, list)) and len(s) == 3 else None for s in items]
    if constants is None:
        return pairs, None
    try:
        cs = list(constants)
    except TypeError:
        raise InvalidParameterError(f"constants must be a sequence with one entry (None or c_1..c_(N-1)) per site, "
                                    f"got {constants!r}") from None
    if len(cs) != len(pairs):
        raise InvalidParameterError(f"constants must have one entry per site ({len(pairs)} sites), got {len(cs)}")
    return pairs, cs


def normalise(checked_sites, cs) -> tuple | None:
    """The constants of the validated ``(position, order)`` sites, normalised (see :func:`split_sites`)."""
    if cs is None:
        return None
    out = tuple(_site_constants(c, lam, N) for c, (lam, N) in zip(cs, checked_sites, strict=True))
    return None if all(c is None for c in out) else out


def jet_matrix(model) -> np.ndarray:
    """``S`` ``(M, M)``, block diagonal over the sites: ``S = T_s^T`` on the site ``s`` (the identity where it has no
    constants), so that ``Y_c = Σ_e S[c, e] y_e`` (``P = S ⊗ 1_3`` on states)."""
    S = np.eye(model.M)
    if model.constants is not None:
        for o, (_, N), c in zip(model.offsets, model.sites, model.constants, strict=True):
            if c is not None:
                S[o:o + N, o:o + N] = jet_coefficients(N, c).T
    S.setflags(write=False)
    return S


def apply(S: np.ndarray, X) -> np.ndarray:
    """``(S ⊗ 1_3) X`` for states ``X`` ``(..., 3M)``."""
    X = np.asarray(X)
    y = X.reshape(X.shape[:-1] + (S.shape[0], 3))
    return np.einsum("ce,...ea->...ca", S, y).reshape(X.shape)


def forms(S: np.ndarray, q: np.ndarray, lin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The forms of the reduced model's integrals in the variables ``y`` (``Y = S y``): ``q ↦ S^T q S`` (over the last
    two axes), ``lin ↦ lin S``; read-only."""
    q2 = np.einsum("ce,...cd,df->...ef", S, q, S)
    lin2 = lin @ S
    q2.setflags(write=False)
    lin2.setflags(write=False)
    return q2, lin2


@dataclass(frozen=True)
class SiteConstantsMap(ModelMap, Map):
    r"""``X ↦ P^{-1} B(P X)``: the map ``inner`` of ``model.reduced`` on the model ``model`` with jet constants (module
    doc; ``P = model.to_reduced``); ``n_state``, ``integrals``, the integral and state labels are the model's
    (:class:`~jetgaudin.gaudin._model_map.ModelMap`).  The same properties as ``inner`` (a Poisson isomorphism
    conjugates a Poisson, integral-preserving map into one); ``carry`` is ``inner``'s (``ν(η)`` is the same on both
    sides)."""

    model: Any
    inner: Map
    backend: Backend = field(default=Backend.AUTO)
    #: one conversion each way per ``advance`` call: a run cut into other chunks differs in the last bits
    chunk_invariant: ClassVar[bool] = False

    def __post_init__(self):
        if self.model.constants is None or self.inner.n_state not in (None, self.model.n_state):
            raise InvalidParameterError("SiteConstantsMap needs a model with jet constants and a map of its "
                                        "reduced model (model.two_point_backlund(eta) builds one)")
        object.__setattr__(self, "backend", self.inner.backend if self.backend is Backend.AUTO
                           else Backend.parse(self.backend))

    @property
    def properties(self) -> MapProperties:  # type: ignore[override]
        return self.inner.properties


    @property
    def has_compiled(self) -> bool:
        return self.inner.has_compiled

    @property
    def has_gpu(self) -> bool:
        return self.inner.has_gpu

    def __getattr__(self, name: str):
        """The inner map's parameters (``eta``, ``branch``, ``dt``, …); not its methods, which take the reduced
        model's states (call them on :attr:`inner` with ``model.to_reduced(X)``)."""
        if name.startswith("_") or name in ("model", "inner", "backend"):
            raise AttributeError(name)
        value = getattr(self.inner, name)
        if callable(value):
            raise AttributeError(f"{name}: a method of the reduced model's map; call map.inner.{name} with "
                                 "map.model.to_reduced(X)")
        return value

    def _inner(self) -> Map:
        return self.inner if self.backend is self.inner.backend else self.inner.with_backend(self.backend)

    def with_backend(self, backend=None, kernel=None):  # type: ignore[override]
        pick = backend if kernel is None else kernel
        return self if pick is None else replace(self, inner=self.inner.with_backend(pick), backend=Backend.AUTO)

    def resolved_backend(self, X: Any, steps: Any) -> Backend:
        return self._inner().resolved_backend(self.model.to_reduced(X), steps)

    def prepare_kernels(self, X=None, steps=None, notify=None):
        return self._inner().prepare_kernels(None if X is None else self.model.to_reduced(X), steps, notify)




    def start(self, X) -> np.ndarray:
        return self._inner().start(self.model.to_reduced(X))

    def step(self, X, carry=None):
        Xn, carry, im = self._inner().step(self.model.to_reduced(X), carry)
        return self.model.from_reduced(Xn), carry, im

    def advance(self, X, carry, steps: int, save_every: int = 1) -> Advance:
        """The inner map's ``advance`` on ``P X``, its rows and end state mapped back (one conversion each way: the
        reduced orbit itself carries no extra rounding)."""
        adv = self._inner().advance(self.model.to_reduced(X), carry, steps, save_every)
        return Advance(rows=self.model.from_reduced(adv.rows), X=self.model.from_reduced(adv.X), carry=adv.carry,
                       imag_max=adv.imag_max)

    def inverse(self) -> SiteConstantsMap:
        return SiteConstantsMap(self.model, self.inner.inverse())

    def describe(self) -> dict:
        return {"kind": "site_constants", "model": self.model.describe(), "map": self._inner().describe()}


def conjugated(model, inner: Map) -> SiteConstantsMap:
    """The map ``inner`` of ``model.reduced`` carried to ``model`` (a model with jet constants)."""
    return SiteConstantsMap(model, inner)
