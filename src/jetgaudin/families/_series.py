r"""Truncated power series: the one small series module every Gaudin family uses (``docs/families.md``).

A series is an array ``a`` of shape ``(order, ...)``: ``a[n]`` is the coefficient of ``x^n`` (any trailing batch
shape, real or complex).  Products are Cauchy products truncated to ``order`` terms; the inverse solves
``a · r = 1`` term by term (``r_0 = 1/a_0``, ``r_n = −a_0^{-1} Σ_{k=1}^{n} a_k r_{n−k}``), so it needs
``a_0 ≠ 0``.
"""

from __future__ import annotations

from math import factorial

import numpy as np

__all__ = ["mul", "inv", "div", "sin_cos", "shift_derivative"]


def mul(a: np.ndarray, b: np.ndarray, order: int | None = None) -> np.ndarray:
    """Cauchy product of two series, ``order`` terms (default: the shorter length)."""
    n = min(len(a), len(b)) if order is None else order
    out = np.zeros((n,) + np.broadcast_shapes(np.shape(a)[1:], np.shape(b)[1:]), dtype=np.result_type(a, b))
    for p in range(min(n, len(a))):
        for q in range(min(n - p, len(b))):
            out[p + q] = out[p + q] + a[p] * b[q]
    return out


def inv(a: np.ndarray, order: int | None = None) -> np.ndarray:
    """The series of ``1/a`` (``a[0] ≠ 0``), ``order`` terms (default ``len(a)``)."""
    n = len(a) if order is None else order
    r = np.zeros((n,) + np.shape(a)[1:], dtype=np.result_type(a, 1.0))
    r[0] = 1.0 / a[0]
    for m in range(1, n):
        acc = np.zeros_like(r[0])
        for k in range(1, min(m, len(a) - 1) + 1):
            acc = acc + a[k] * r[m - k]
        r[m] = -acc * r[0]
    return r


def div(a: np.ndarray, b: np.ndarray, order: int | None = None) -> np.ndarray:
    """The series of ``a/b`` (``b[0] ≠ 0``)."""
    n = min(len(a), len(b)) if order is None else order
    return mul(a, inv(b, n), n)


def sin_cos(x0, scale: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Taylor coefficients in ``x`` of ``sin(scale·(x0 + x))`` and ``cos(scale·(x0 + x))``, ``order`` terms each
    (``x0`` any complex array): ``[x^n] sin = scale^n sin(scale x0 + nπ/2)/n!``."""
    t = scale * np.asarray(x0, dtype=complex)
    s0, c0 = np.sin(t), np.cos(t)
    s = np.empty((order,) + t.shape, dtype=complex)
    c = np.empty_like(s)
    for n in range(order):
        f = scale**n / factorial(n)
        s[n] = f * (s0, c0, -s0, -c0)[n % 4]
        c[n] = f * (c0, -s0, -c0, s0)[n % 4]
    return s, c


def shift_derivative(t: np.ndarray, k: int, order: int) -> np.ndarray:
    r"""From the Taylor coefficients ``t`` of ``w`` at a point, those of ``(−1)^k w^{(k)}/k!`` there, ``order``
    terms: ``[x^p] = (−1)^k C(p+k, k) t_{p+k}`` (needs ``len(t) ≥ order + k``)."""
    from math import comb

    return np.stack([(-1) ** k * comb(p + k, k) * t[p + k] for p in range(order)]) if order else t[:0]
