"""Python-side constants of :class:`jetgaudin.ChainExactFlow`'s compiled solve (private): the family constants of the
compiled basis (per family parameter), the model-only constants of a flow (per flow, weak keys: nothing outlives its
flow), and the trigonometric branch points from the compiled polynomial.  Split from :mod:`jetgaudin.exact_chain`
(its size); Numba is imported on first use only."""

from __future__ import annotations

import importlib
import weakref
from functools import lru_cache
from typing import Any

import numpy as np

from ._errors import BranchPointError

__all__: list[str] = []


def _family_constants(fam) -> np.ndarray:
    """The constants of the compiled basis: trigonometric ``(γ,)``, elliptic ``_exact_elliptic.elliptic_constants``
    (read-only, computed once per family parameter)."""
    return _family_constants_of(fam.name, float(fam.modulus) if fam.name == "elliptic"
                                else float(getattr(fam, "gamma", 0.0)))


@lru_cache(maxsize=64)
def _family_constants_of(name: str, param: float) -> np.ndarray:
    if name == "elliptic":
        from ._exact_elliptic import elliptic_constants

        out = elliptic_constants(param)
    else:
        out = np.array([param])
    out.setflags(write=False)
    return out


#: per flow and ``k``, the real parts of a model without computed branch points (:meth:`ChainExactFlow._real_parts`)
_NO_ROOTS_RHO: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: per flow, the compiled solve's constants that depend on the model and weights only (:func:`_static`)
_STATIC: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _static(flow) -> tuple:
    """``(keep, E, rate, k, weights_keep, kidx, positions, orders, λ_c, P, K')`` of a flow (cached per flow: the
    Python around the compiled solve was ~1/3 of a Clebsch top's solve)."""
    out = _STATIC.get(flow)
    if out is None:
        model = flow.model
        keep, E, rate = flow._design
        out = (keep, np.ascontiguousarray(E, dtype=float), rate, int(keep.sum()) - E.shape[1],
               np.asarray(flow.H.weights, dtype=float)[keep], np.flatnonzero(keep).astype(np.int64),
               np.ascontiguousarray(model.positions, dtype=float), np.array(model.orders, dtype=np.int64),
               float(np.mean(model.positions)), model.family.period, getattr(model.family, "Kp", np.inf))
        _STATIC[flow] = out
    return out


def _trig_roots(model, hI: np.ndarray, const: float, pos: np.ndarray, orders: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """``exact_chain._orbit_roots`` for the trigonometric family with the polynomial compiled
    (:func:`jetgaudin._exact_chain_kernels.trig_polynomial`, ``ν²`` from the expansion: the roots equal
    ``gaudin._curve.branch_points``' to round-off), the roots by the same companion matrix."""
    from .spectral import _roots

    K: Any = importlib.import_module("jetgaudin._exact_chain_kernels")
    coef = np.empty(hI.size + 1, dtype=complex)
    K.trig_polynomial(_family_constants(model.family), pos, orders, hI, const, coef)
    Q = coef[::-1]
    if abs(Q[0]) <= 1e-13 * np.max(np.abs(Q)):
        raise BranchPointError(
            "nu^2 vanishes at Im(lambda) -> -infinity (b + i gamma J = 0: b = 0 and J = sum of the y_0^3 = 0); the "
            "branch rule of nu needs b != 0 or J != 0")
    raw = _roots(Q)
    return raw, model.family.uniformizer_inverse(raw)
