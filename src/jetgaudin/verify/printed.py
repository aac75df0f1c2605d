"""The paper's formulas **as printed**, misprints included: one transcription of each, and nowhere else in
jetgaudin (the runtime modules hold only the corrected formulas, each with its equation label).

Every function is plain arithmetic, so it runs on NumPy arrays, mpmath numbers and SymPy symbols alike; the
trigonometric ones take the module (``numpy``, ``mpmath`` or ``sympy``) that supplies ``sin``, ``cos``, ``sqrt``.
Their failures are established by the checks of :mod:`jetgaudin.verify` (``docs/errata.md``); the tests use them
for the second, numerical route.  Do not use them for anything else.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "one_point_map",
    "one_point_map_array",
    "appendix1",
    "appendix1_arrays",
    "appendix1_map",
    "generating_function",
    "psi",
    "casimir_elimination",
    "realisation",
    "hamiltonian",
    "integral_I2",
    "symbolic_realisation",
]


# ----------------------------------------------------------------------------------------------- (mp)
def one_point_map(s: dict, corrected: bool = False) -> dict:
    """Section 6.1, eq. (mp), as printed: the nine components ``y~3, y~-, y~+, x~3, ...`` from the dict ``s`` with
    keys ``p, q, eta, b, y3, yp, ym, x3, xp, xm, z3, zp, zm`` (complex generators ``a^pm = a^1 pm i a^2``).

    ``corrected=True`` applies the erratum of the check ``mp`` to this transcription (``+z^-`` in ``x~-``, the
    sign of the ``eta q (pq - eta) y^-`` terms of ``z~3, z~+, z~-``)."""
    p, q, eta, b = s["p"], s["q"], s["eta"], s["b"]
    y3, yp, ym, x3, xp, xm, z3, zp, zm = (s[k] for k in ("y3", "yp", "ym", "x3", "xp", "xm", "z3", "zp", "zm"))
    sg = -1 if corrected else 1  # the sign of the eta q (pq - eta) y^- terms of z~
    return {
        "y~3": y3,
        "y~-": xm + (p * q - eta) * ym - 2 * p * y3,
        "y~+": 2 * q * b,
        "x~3": x3 + p * yp - q * xm - q * (p * q - eta) * ym + 2 * p * q * y3,
        "x~-": (zm if corrected else 0) + (2 * p * q - eta) * xm - 2 * p * x3 - p**2 * yp + p * q * (p * q - eta) * ym
        - 2 * p**2 * q * y3,
        "x~+": yp - q / p * (p * q - eta) * ym + 2 * q * y3,
        "z~3": z3 - q * zm + 2 * p * q * x3 - p * q**2 * xm + p * xp + sg * eta * q * (p * q - eta) * ym + p * eta * yp
        + 2 * eta * p * q * y3,
        "z~+": 2 * q * x3 - q**2 * xm + xp + sg * eta * q / p * (p * q - eta) * ym + eta * yp + 2 * eta * q * y3,
        "z~-": (2 * p * q - eta) * zm - 2 * p * z3 - 2 * p**2 * q * x3 + p**2 * q**2 * xm - p**2 * xp
        - sg * eta * p * q * (p * q - eta) * ym - p**2 * eta * yp - 2 * eta * p**2 * q * y3,
    }


def one_point_map_array(X: Any, b: float, eta: complex, p: Any, q: Any) -> Any:
    """(mp) as printed on NumPy states ``X`` of shape ``(..., 9)``; returns complex ``(..., 9)`` in the real basis."""
    import numpy as np

    X = np.asarray(X, dtype=complex)
    s = {"p": p, "q": q, "eta": eta, "b": b}
    for n, name in enumerate("yxz"):
        a1, a2, a3 = X[..., 3 * n], X[..., 3 * n + 1], X[..., 3 * n + 2]
        s[name + "3"], s[name + "p"], s[name + "m"] = a3, a1 + 1j * a2, a1 - 1j * a2
    o = one_point_map(s)
    out = []
    for name in "yxz":
        ap, am, a3 = o[name + "~+"], o[name + "~-"], o[name + "~3"]
        out += [0.5 * (ap + am), -0.5j * (ap - am), a3 + 0 * p]
    return np.stack(np.broadcast_arrays(*out), axis=-1).astype(complex)


# ----------------------------------------------------------------------------------------------- Appendix 1
def appendix1(b: Any, R: Any, Im: Any, s: Any, t: Any, alpha_fix: bool = False) -> tuple[list, list, list]:
    """Appendix 1 as printed: ``(A, B, X0)`` as nested lists (3x3, 3x3, 9), ``alpha_1 = 2 Im(eta) - s t``,
    ``alpha_2 = alpha_1 - s t``, ``R = Re eta``.  ``alpha_fix=True`` reads ``alpha_1 = 2i Im(eta) - s t`` and changes
    nothing else (to tell the remaining misprints entry by entry)."""
    a1 = (2j * Im if alpha_fix else 2 * Im) - s * t
    a2 = a1 - s * t
    i = 1j
    X0 = [b * (s * a1 - t), -b * (s * a1 + t), 0 * s,
          b * (s * a1 / 2 * (a2 + R) + t * (a2 - 2 * R)),
          i * b * (s * a1 / 2 * (a2 + R) - t * (a2 - 2 * R)),
          2 * b * t * s * a1,
          -i * b / 4 * ((Im + R) ** 2 * (t + a1) + 8 * s * t * R * (t - a1)),
          -b / 4 * ((Im + R) ** 2 * (t - a1) + 8 * s * t * R * (t + a1)),
          2 * (2 * b * t * s * a1) * R]
    A = [[0 * s, i * a2, s * a1 - t], [-i * a2, 0 * s, -i * (s * a1 + t)], [-(s * a1 - t), i * (s * a1 + t), 0 * s]]
    B = [[(1 - s**2) * (a1**2 - t**2) / 2, -i / 2 * ((t**2 - s**2 * a1**2) - 2 * a2 * R), s * a1 * (a2 + R) / 2],
         [-i / 2 * ((t**2 - s**2 * a1**2) + 2 * a2 * R), (1 + s**2) * (a1**2 - t**2) / 2, -i / 2 * s * a1 * (a2 + R)],
         [(t * (a2 + 2 * R) + s * a1 * (a2 - 2 * R)) / 2, (t * (a2 + 2 * R) - s * a1 * (a2 - 2 * R)) / 2,
          4 * s * t * a1]]
    return A, B, X0


def appendix1_arrays(b: float, eta: complex, s: Any, t: Any, *, restore_i: bool = False) -> tuple[Any, Any, Any]:
    """Appendix 1 as printed on NumPy arrays: ``A``, ``B`` of shape ``(..., 3, 3)``, ``X0`` of shape ``(..., 9)``."""
    import numpy as np

    eta = complex(eta)
    s, t = np.broadcast_arrays(np.asarray(s, dtype=complex), np.asarray(t, dtype=complex))
    A_rows, B_rows, X0 = appendix1(b, eta.real, eta.imag, s, t, alpha_fix=restore_i)
    A = np.stack([np.stack(row, -1) for row in A_rows], -2)
    B = np.stack([np.stack(row, -1) for row in B_rows], -2)
    return A, B, np.stack(np.broadcast_arrays(*X0), -1)


def appendix1_map(X: Any, b: float, eta: complex, s: Any, t: Any) -> Any:
    """Appendix 1 as printed, ``X^ = Phi X + X0`` on NumPy states ``(..., 9)`` (complex)."""
    import numpy as np

    X = np.asarray(X, dtype=float)
    A, B, X0 = appendix1_arrays(b, eta, s, t)
    y, x, z = X[..., 0:3], X[..., 3:6], X[..., 6:9]
    yn = y + X0[..., 0:3]
    xn = np.einsum("...ij,...j->...i", A, y) + x + X0[..., 3:6]
    zn = np.einsum("...ij,...j->...i", B, y) + np.einsum("...ij,...j->...i", A, x) + z + X0[..., 6:9]
    return np.concatenate([yn, xn, zn], axis=-1)


# ----------------------------------------------------------------------------------------------- Prop. 6
def generating_function(ym: Any, xm: Any, zm: Any, ypt: Any, xpt: Any, zpt: Any, eta: Any, b: Any, g1: Any,
                        g2: Any, k: Any, log: Any) -> Any:
    """(fu) as printed: ``F_eta(chi^- | chi~^+)`` with ``gamma_1, gamma_2 = g1, g2`` and ``k^2 = 1 + eta z^- z~^+``
    (``log`` the logarithm of the caller's number type)."""
    bracket = (zpt * xm + zm * xpt - eta * xpt * xm + (xm / zm) * (xm / zm + eta / 2 * xm * zpt - g2)
               + (xpt / zpt) * (xpt / zpt + eta / 2 * xpt * zm - g2))
    return (ym * ypt / (2 * b) + k * (ym / zm + ypt / zpt) - (1 + eta * g2) ** 2 / (4 * k * eta * eta)
            + (g2 * g2 / 4 - g1) / 2 * log((k + 1) / (k - 1)) - bracket / (2 * k))


def psi(ym: Any, xm: Any, zm: Any, ypt: Any, xpt: Any, zpt: Any, eta: Any, b: Any, g1: Any, g2: Any, k: Any,
        yp_old: Any) -> tuple:
    """The displayed ``Psi, Psi~`` of the proof of Prop. 6 as printed, ``(y3, x3, z3, y~3, x~3, z~3)``, with the
    undefined ``w`` of ``z^3, z~^3`` read as ``b``; ``yp_old`` is the old ``y^+`` that the printed ``y^3`` contains."""
    P = zm * zpt
    S = zm * xpt + xm * zpt
    br = ((eta * S - P) ** 2 / 2 + eta * eta * (zm * zm * zpt * ypt + zpt * zpt * zm * ym) + (1 + eta * g2 / 2) * S
          - (g2 + 2 * eta * g1) * P - eta * (xm * xpt + zm * ypt + zpt * ym) + (g2 * g2 - 4 * g1) / 4)
    y3 = ym * yp_old / (2 * b) - br / (2 * k * k * k)
    x3 = (ypt * xm + eta * S - P + g2) / (2 * k)
    z3 = ypt * zm / (2 * b) + k
    x3t = (xpt * ym + eta * S - P + g2) / (2 * k)
    z3t = zpt * ym / (2 * b) + k
    return y3, x3, z3, y3, x3t, z3t


def casimir_elimination(a3: Any, b3: Any, c3: Any, am: Any, bm: Any, cm: Any, g1: Any, g2: Any) -> tuple:
    """Proof of Prop. 6 as printed: ``(y^+, x^+, z^+)`` from ``(y^3, x^3, z^3)`` and ``(y^-, x^-, z^-)`` on the leaf
    (the same formulas give ``(y~^-, x~^-, z~^-)`` from the tilde variables); ``2 gamma_1 - 1`` is the misprint."""
    cp = (1 - c3 * c3) / cm
    bp = (2 * g2 - 2 * b3 * c3 - (bm / cm) * (1 - c3 * c3)) / cm
    ap = (2 * g1 - 1 - 2 * a3 * c3 - (am / cm) * (1 - c3 * c3)) / cm
    return ap, bp, cp


# ----------------------------------------------------------------------------------------------- Section 5
def realisation(lib: Any, th: Any, ph: Any, ps: Any, pth: Any, pph: Any, pps: Any) -> tuple:
    """Prop. 5 as printed: ``(y^1, y^2, y^3, x^1, x^2, x^3, z^1, z^2, z^3)`` in Euler angles (``lib`` supplies
    ``sin, cos, sqrt``)."""
    S, C = lib.sin, lib.cos
    r = lib.sqrt(2 * pps)
    y = (S(ph) * pth + C(th) / S(th) * C(ph) * pph - C(ph) / S(th) * pps,
         -C(ph) * pth + C(th) / S(th) * S(ph) * pph - S(ph) / S(th) * pps,
         pph)
    x = (r * (S(ps) * S(ph) - C(th) * C(ps) * C(ph)),
         r * (-S(ps) * C(ph) - C(th) * C(ps) * S(ph)),
         -r * S(th) * C(ps))
    z = (S(th) * C(ph), S(th) * S(ph), C(th))
    return y + x + z


def hamiltonian(lib: Any, th: Any, ps: Any, pth: Any, pph: Any, pps: Any, b: Any) -> Any:
    """Section 5's canonical Hamiltonian as printed (``- 2 p_psi p_phi cos theta``)."""
    S, C = lib.sin, lib.cos
    return (pth**2 / 2 + (pps**2 + pph**2 - 2 * pps * pph * C(th)) / (2 * S(th) ** 2)
            - b * lib.sqrt(2 * pps) * S(th) * C(ps))


def integral_I2(lib: Any, th: Any, ps: Any, pth: Any, pph: Any, pps: Any, b: Any) -> Any:
    """Section 5's ``I_2 = H_3/2`` as printed."""
    S, C = lib.sin, lib.cos
    return (lib.sqrt(2 * pps) * (pth * S(ps) + (pps - pph * C(th)) * C(th) / S(th) * C(ps) - pph * S(th) * C(ps))
            + b * C(th))


def symbolic_realisation() -> tuple:
    """``(q, p, X)``: Prop. 5 as printed in SymPy, with the real symbols ``theta, phi, psi, p_theta, p_phi, p_psi``
    (the names used by :func:`jetgaudin.canonical.symbolic_realisation`, so the expressions can be compared)."""
    import sympy as sp

    q = sp.symbols("theta phi psi", real=True)
    p = sp.symbols("p_theta p_phi p_psi", real=True)
    return q, p, realisation(sp, *q, *p)
