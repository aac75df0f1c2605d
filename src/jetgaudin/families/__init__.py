"""Gaudin families on one model core (issue 23): the rational (XXX) and trigonometric (XXZ) families.

:class:`Family` is the contract (:mod:`jetgaudin.families._base`); :func:`make_family` builds one by name for
:class:`jetgaudin.GaudinModel` (``family="rational"`` is the default; ``family="trigonometric", gamma=γ``).
See ``docs/families.md``.
"""

from __future__ import annotations

from collections.abc import Callable

from .._errors import InvalidParameterError
from ._base import Family
from .elliptic import EllipticFamily
from .rational import RationalFamily
from .trigonometric import TrigonometricFamily

__all__ = ["Family", "RationalFamily", "TrigonometricFamily", "EllipticFamily", "make_family", "register_family",
           "family_names"]

_FAMILIES: dict[str, Callable[..., Family]] = {}


def register_family(name: str, factory: Callable[..., Family]) -> None:
    """Register ``factory(**parameters) -> Family`` under ``name``."""
    _FAMILIES[name] = factory


def family_names() -> list[str]:
    """The registered family names."""
    return list(_FAMILIES)


def make_family(family: str | Family = "rational", **params) -> Family:
    """The family ``family`` (a name or a :class:`Family`, returned as is) with its parameters (``gamma`` for the
    trigonometric family; ``None`` values mean the default).  :class:`InvalidParameterError` for an unknown name
    or a parameter the family does not have."""
    params = {k: v for k, v in params.items() if v is not None}
    if isinstance(family, Family):
        if params:
            raise InvalidParameterError(f"give the parameters {sorted(params)} to the family object, not beside it")
        return family
    if family not in _FAMILIES:
        raise InvalidParameterError(f"unknown family {family!r}; known: {', '.join(_FAMILIES)}")
    try:
        return _FAMILIES[family](**params)
    except TypeError:
        raise InvalidParameterError(f"the {family} family has no parameter(s) {sorted(params)}") from None


def _rational(gamma=None):
    if gamma is not None and gamma != 1.0:
        raise InvalidParameterError(f"gamma = {gamma} is the anisotropy of the trigonometric family; the rational "
                                    "family has none (give family='trigonometric' or drop gamma)")
    return RationalFamily()


register_family("rational", _rational)
register_family("trigonometric", TrigonometricFamily)


def _elliptic(modulus=None, half_period="0"):
    if modulus is None:
        raise InvalidParameterError("the elliptic family needs its modulus k in [0, 1): give modulus=k "
                                    "(--modulus k on the command line)")
    return EllipticFamily(modulus, half_period)


register_family("elliptic", _elliptic)
