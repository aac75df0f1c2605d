"""Input validation shared by all modules (private)."""

from __future__ import annotations

from enum import Enum
from typing import TypeVar

import numpy as np

from ._errors import InvalidParameterError, InvalidStateError

E = TypeVar("E", bound=Enum)


def as_state(X, *, allow_complex: bool = False, name: str = "X", block: int = 3) -> tuple[np.ndarray, int]:
    """Return ``(X, N)`` with ``X`` a float (or complex) array of shape ``(..., block·N)`` (``block``: components
    per site and order, 3; an su(n) chain's ``n² − 1``).

    Raises :class:`InvalidStateError` if the trailing axis is not a positive
    multiple of ``block`` or if any entry is not finite.
    """
    try:
        arr = np.asarray(X)
    except Exception as exc:  # pragma: no cover - numpy raises many types
        raise InvalidStateError(f"{name} must be an array of numbers: {exc}") from None
    if arr.dtype == object or arr.dtype.kind not in "biufc":
        raise InvalidStateError(f"{name} must be numeric, got dtype {arr.dtype}")
    if arr.dtype.kind == "c" and not allow_complex:
        if np.any(arr.imag != 0):
            raise InvalidStateError(f"{name} must be real; pass a real state (complex given)")
        arr = arr.real
    arr = arr.astype(np.complex128 if arr.dtype.kind == "c" else np.float64, copy=False)
    if arr.ndim == 0 or arr.shape[-1] == 0 or arr.shape[-1] % block != 0:
        n = "scalar" if arr.ndim == 0 else arr.shape[-1]
        raise InvalidStateError(
            f"{name} must have shape (..., {block}N) with N >= 1 (components y_0, ..., y_(N-1)); "
            f"its last axis has length {n}, not a positive multiple of {block}"
        )
    if not np.isfinite(arr).all():
        raise InvalidStateError(f"{name} has non-finite entries (NaN or inf); give finite numbers")
    return arr, arr.shape[-1] // block


def check_N(N) -> int:
    """Validate the jet order N (a positive integer)."""
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise InvalidParameterError(f"the jet order N must be an integer >= 1, got {N!r}")
    return int(N)


def _refuse_text_and_bool(value, name: str) -> None:
    """A number is given as a number: a string (``"1"``) or a bool (``True``) is refused, not converted."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or (
            isinstance(value, np.ndarray) and value.dtype.kind in "bSUO"):
        raise InvalidParameterError(f"{name} must be a real number, got {value!r} ({type(value).__name__}); pass a "
                                    "float")


def field_vector(b) -> np.ndarray:
    """Return the external field as a 3-vector; a scalar ``b`` means ``(0, 0, b)``."""
    _refuse_text_and_bool(b, "the field b")
    if np.iscomplexobj(b):
        raise InvalidParameterError("the field b must be real")
    try:
        arr = np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"the field b must be a float or a 3-vector of floats, got {b!r}") from None
    if arr.ndim == 0:
        arr = np.array([0.0, 0.0, float(arr)])
    if arr.shape != (3,):
        raise InvalidParameterError(f"the field b must be a float or a 3-vector, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InvalidParameterError("the field b must be finite")
    return arr


def real_number(value, name: str) -> float:
    """Validate a finite real number (not a string or a bool); the messages call it ``name``."""
    _refuse_text_and_bool(value, name)
    try:
        val = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(val):
        raise InvalidParameterError(f"{name} must be finite, got {val}")
    return val


def real_array(value, name: str) -> np.ndarray:
    """Validate an array of real numbers (complex refused, not silently truncated); returns it as floats."""
    if np.iscomplexobj(value):
        raise InvalidParameterError(f"{name} must be real (complex given)")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be real numbers, got {value!r}") from None


def parse_choice(cls: type[E], value, name: str) -> E:
    """``cls(value)`` for an enum ``cls`` of options; otherwise an error naming ``name`` and the choices."""
    try:
        return cls(value)
    except ValueError:
        choices = [repr(member.value) for member in cls]
        listed = " or ".join([", ".join(choices[:-1]), choices[-1]] if len(choices) > 1 else choices)
        raise InvalidParameterError(f"{name} must be {listed}, got {value!r}") from None


def nonzero_field(b) -> float:
    """Validate a scalar field strength b (b e_3), which must be finite and nonzero."""
    val = real_number(b, "the field strength b")
    if val == 0.0:
        raise InvalidParameterError(
            "the field strength b must be nonzero (the formulas divide by b and the "
            "default branch of nu is normalised by nu -> |b| at infinity); give b != 0"
        )
    return val


def spectral_parameter(eta, *, name: str = "eta") -> complex:
    """Validate a complex spectral parameter."""
    try:
        val = complex(eta)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a complex number, got {eta!r}") from None
    if not (np.isfinite(val.real) and np.isfinite(val.imag)):
        raise InvalidParameterError(f"{name} must be finite, got {val}")
    return val


def complex_points(lam, *, name: str = "lambda") -> np.ndarray:
    """Validate an array of finite complex numbers (e.g. points of the spectral plane)."""
    try:
        arr = np.asarray(lam, dtype=complex)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a (complex) number or array, got {lam!r}") from None
    if not np.isfinite(arr).all():
        raise InvalidParameterError(f"{name} must be finite (NaN or inf given)")
    return arr


def spectral_points(lam, *, name: str = "lambda") -> np.ndarray:
    """Validate an array of spectral parameters: finite and nonzero (λ = 0 is the pole of L)."""
    arr = complex_points(lam, name=name)
    if np.any(arr == 0):
        raise InvalidParameterError(f"{name} must be nonzero: lambda = 0 is the pole of the Lax matrix")
    return arr


def check_gradient(grad, n: int, *, name: str = "gradient") -> np.ndarray:
    """Validate a gradient array whose trailing axis must have length ``n = 3N``."""
    arr = np.asarray(grad)
    if arr.ndim == 0 or arr.shape[-1] != n:
        got = "a scalar" if arr.ndim == 0 else f"trailing length {arr.shape[-1]}"
        raise InvalidStateError(f"{name} must have shape (..., {n}) like the state, got {got}")
    return arr


def finite_result(arr, what: str):
    """Raise :class:`InvalidStateError` if a computed quantity overflowed (never return a silent inf/NaN)."""
    if not np.isfinite(arr).all():
        raise InvalidStateError(
            f"{what} overflow for this input (products of components exceed the float range, |X| or |b| "
            "above ~1e154); rescale the state and the field"
        )
    return arr


def jet_constants(c, N: int) -> np.ndarray:
    """The constants ``c_1, …, c_(N-1)`` of the jet (Section 2) as a complex array: exactly ``N - 1`` finite numbers
    (more are refused, not ignored: ``c_k`` for ``k >= N`` do not enter the order-``N`` jet, so extra values are a
    mistake about ``N``)."""
    c = np.atleast_1d(np.asarray(c, dtype=complex))
    if c.ndim != 1 or len(c) != N - 1:
        raise InvalidParameterError(
            f"the constants c_1..c_(N-1) must be a sequence of exactly N-1 = {N - 1} numbers for N = {N}, got "
            f"{len(c) if c.ndim == 1 else c.shape}"
        )
    if not np.all(np.isfinite(c)):
        raise InvalidParameterError("the constants c_k must be finite")
    return c
