r"""The trigonometric (XXZ) Gaudin family (issue 23; ``docs/families.md``).

Basis functions, anisotropy ``γ > 0``: ``w_1 = w_2 = γ/sin(γx)``, ``w_3 = γ cot(γx)``, so for order-1 sites

.. math:: u = b + \sum_j \gamma\cot(\gamma(\lambda-\lambda_j))\, s_j^3, \qquad
          v = \sum_j \frac{\gamma\, s_j^-}{\sin(\gamma(\lambda-\lambda_j))}, \qquad
          w = \sum_j \frac{\gamma\, s_j^+}{\sin(\gamma(\lambda-\lambda_j))},

``ℓ_γ(λ) = γ ℓ_1(γλ; γλ_j, b/γ)``, which tends to the rational chain with the same sites, ``b`` and spins as
``γ → 0``.  A jet site carries ``y_k`` multiplying ``φ_{a,k}(x) = (−1)^k w_a^{(k)}(x)/k!``.

**Integrals.**  ``ν² = u² + vw`` is ``π/γ``-periodic (``v, w`` change sign under ``λ → λ + π/γ``), has poles of
order ``≤ 2N_j`` at the sites and tends to ``(b ∓ iγJ)²`` as ``Im λ → ±∞`` (``J = Σ_j y^{(j)3}_0``; the
derivative terms vanish there).  Hence, exactly,

.. math:: \nu^2(\lambda) = b^2 - \gamma^2 J^2 + \sum_j \sum_{m=1}^{2N_j} h_{j,m}\, \psi_m(\lambda-\lambda_j),
          \qquad \psi_m(x) = \frac{(-1)^{m-1}}{(m-1)!} \frac{d^{m-1}}{dx^{m-1}}\, \gamma\cot(\gamma x),

(``ψ_m = x^{−m} + regular``; the difference is bounded, periodic and tends to 0 at ``±i∞`` after the constant is
removed), and comparing the limits at ``+i∞``: ``Σ_j h_{j,1} = 2bJ``.  For order-1 sites and ``γ = 1``:
``ψ_1 = cot``, ``ψ_2 = 1/sin²``, ``h_{j,2} = C_j = |s_j|²`` and ``h_{j,1} = 2H_j`` with
``H_j = b s_j^3 + Σ_{k≠j} [cot(λ_j − λ_k) s_j^3 s_k^3 + (s_j^1 s_k^1 + s_j^2 s_k^2)/sin(λ_j − λ_k)]``, so
``Σ_j H_j = bJ``.  The integrals are the ``h_{j,m}`` (as for rational chains) and ``J`` last.

**Dressing** (``z = e^{2iγλ}``): ``D(λ) = [[α e^{iγλ} + α_0 e^{−iγλ}, β], [γ', δ e^{iγλ} + δ_0 e^{−iγλ}]]``
satisfies ``D(λ + π/γ) = −σ_3 D(λ) σ_3`` like ``ℓ(λ + π/γ) = σ_3 ℓ(λ) σ_3``, is diagonal at ``±i∞`` and
``det D`` is ``e^{−2iγλ}`` times a quadratic in ``z``: with spectrality at ``ξ, ξ̄`` the only poles of
``ℓ̃ = D ℓ D^{-1}`` are at the sites, it is bounded at ``±i∞`` with the same limits ``b ∓ iγJ``, hence of the
same form.  Spectrality fixes each row up to a factor (a 3-vector cross product per row); the two factors are
the overall scale (irrelevant) and the rotation gauge ``diag(ρ, 1)``, fixed by the gauge rule of
:func:`gauge_rule`.

**One-point dressing** (``docs/families.md`` §3.1): ``D = [[s(λ−η)/γ + pq e^{−iγ(λ−η)}, p], [q, e^{−iγ(λ−η)}]]``,
``s(x) = sin γx``, whose determinant vanishes at ``η`` only (modulo ``π/γ``); ``q`` by spectrality, ``p`` by the
normalisation at ``Im λ → −∞`` (needs ``b + iγJ ≠ 0``): :meth:`TrigonometricFamily.one_point_normalisation`,
:meth:`TrigonometricFamily.one_point_dressing`.
"""

from __future__ import annotations

from functools import lru_cache
from math import factorial

import numpy as np

from .._errors import InvalidParameterError
from . import _series
from ._base import Family

__all__ = ["TrigonometricFamily", "gauge_rule"]


def _check_gamma(gamma) -> float:
    if isinstance(gamma, bool) or np.iscomplexobj(gamma):
        raise InvalidParameterError(f"the anisotropy gamma must be a real number > 0, got {gamma!r}")
    try:
        g = float(gamma)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"the anisotropy gamma must be a real number > 0, got {gamma!r}") from None
    if not np.isfinite(g) or g <= 0:
        raise InvalidParameterError(f"the anisotropy gamma must be finite and > 0 (gamma -> 0 is the rational "
                                    f"family: use family='rational'), got {g}")
    return g


class TrigonometricFamily(Family):
    """The XXZ family with anisotropy ``gamma`` (module docstring)."""

    name = "trigonometric"
    uniform = False
    n_dressing = 6  # E11 e^{iγλ}, E11 e^{−iγλ}, E12, E21, E22 e^{iγλ}, E22 e^{−iγλ}
    kernel_rule = 1

    def __init__(self, gamma: float = 1.0):
        self.gamma = _check_gamma(gamma)

    @property
    def period(self) -> float:
        return float(np.pi / self.gamma)

    def describe(self) -> dict:
        return {"gamma": self.gamma}

    # ---- basis functions -------------------------------------------------------------------------------------

    def taylor(self, a, x0, order):
        g = self.gamma
        s, c = _series.sin_cos(x0, g, order)
        r = g * _series.inv(s, order)
        return r if a in (1, 2) else _series.mul(c, r, order)

    def regular(self, a, order):
        g = self.gamma
        n = order + 1
        # sin(γx)/(γx) and cos(γx) as series in x; w_a = (1/x)·[1 or cos]/(sin(γx)/(γx))
        s1 = np.array([(-1) ** (k // 2) * g**k / factorial(k + 1) if k % 2 == 0 else 0.0 for k in range(n)])
        c = np.array([(-1) ** (k // 2) * g**k / factorial(k) if k % 2 == 0 else 0.0 for k in range(n)])
        t = _series.inv(s1, n) if a in (1, 2) else _series.mul(c, _series.inv(s1, n), n)
        return t[1:].astype(complex)  # t_0 = 1 is the pole 1/x

    # ---- ν² ----------------------------------------------------------------------------------------------

    def nu2_basis(self, m, x):
        return self.phi(3, x, m)[m - 1]

    def nu2_constant(self, b, extra):
        J = extra[..., 0]
        return b * b - self.gamma**2 * J * J

    def nu2_constant_gradient(self, b, extra):
        return -2.0 * self.gamma**2 * extra

    def extra_integrals(self, sites):
        M = sum(N for _, N in sites)
        form = np.zeros((1, 3 * M))
        o = 0
        for _, N in sites:
            form[0, 3 * o + 2] = 1.0
            o += N
        return ["J"], form

    def uniformizer(self, lam):
        return np.exp(2j * self.gamma * np.asarray(lam, dtype=complex))

    def uniformizer_inverse(self, z):
        return np.log(np.asarray(z, dtype=complex)) / (2j * self.gamma)

    # ---- dressing -------------------------------------------------------------------------------------------

    def dressing_basis(self, lam):
        lam = np.asarray(lam, dtype=complex)
        ep, em = np.exp(1j * self.gamma * lam), np.exp(-1j * self.gamma * lam)
        out = np.zeros(lam.shape + (6, 2, 2), dtype=complex)
        out[..., 0, 0, 0] = ep
        out[..., 1, 0, 0] = em
        out[..., 2, 0, 1] = 1.0
        out[..., 3, 1, 0] = 1.0
        out[..., 4, 1, 1] = ep
        out[..., 5, 1, 1] = em
        return out

    def dressing_taylor(self, lam0, order):
        g = self.gamma
        ep = np.array([np.exp(1j * g * lam0) * (1j * g) ** n / factorial(n) for n in range(order)])
        em = np.array([np.exp(-1j * g * lam0) * (-1j * g) ** n / factorial(n) for n in range(order)])
        out = np.zeros((order, 6, 2, 2), dtype=complex)
        out[:, 0, 0, 0] = ep
        out[:, 1, 0, 0] = em
        out[0, 2, 0, 1] = 1.0
        out[0, 3, 1, 0] = 1.0
        out[:, 4, 1, 1] = ep
        out[:, 5, 1, 1] = em
        return out

    def mp_w(self, a, x):
        import mpmath

        g = mpmath.mpf(self.gamma)
        return g / mpmath.sin(g * x) if a in (1, 2) else g * mpmath.cot(g * x)

    def mp_dressing_basis(self, lam, xi=None):
        import mpmath

        ep, em = mpmath.expj(self.gamma * lam), mpmath.expj(-self.gamma * lam)
        return [[ep, 0, 0, 0], [em, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, ep], [0, 0, 0, em]]

    def mp_dressing_taylor(self, lam, xi, n: int) -> list:
        """:meth:`mp_dressing_basis`'s Taylor coefficients at ``λ``: ``e^{±iγ(λ + t)} = e^{±iγλ} Σ (±iγt)^k/k!``."""
        import mpmath

        g = mpmath.mpf(self.gamma)
        ep = [mpmath.expj(g * lam) * (1j * g) ** k / mpmath.factorial(k) for k in range(n)]
        em = [mpmath.expj(-g * lam) * (-1j * g) ** k / mpmath.factorial(k) for k in range(n)]
        z = [mpmath.mpf(0)] * n
        one = [mpmath.mpf(1)] + z[1:]
        return [[ep, z, z, z], [em, z, z, z], [z, one, z, z], [z, z, one, z], [z, z, z, ep], [z, z, z, em]]

    def mp_kernel_constants(self, xi):
        import mpmath

        g, xb = mpmath.mpf(self.gamma), mpmath.conj(xi)
        return [mpmath.expj(-g * xi), mpmath.expj(-g * xb), mpmath.expj(g * xi), mpmath.expj(g * xb),
                mpmath.sin(g * (xi - xb))]

    def real_dressing(self, xi, k1, k2):
        return gauge_rule(self.gamma, xi, k1, k2)

    # ---- one-point dressing (docs/families.md §3.1) ------------------------------------------------------------

    one_point_refusal = None

    def one_point_normalisation(self, b, sites, X, eta, inverse):
        r"""``p = S_γ^-(η)/(2(b + iγJ))`` (``q = S_γ^+(η)/(2(b + iγJ))`` for the inverse map) with
        ``S_γ^∓(η) = Σ_j Σ_k e^{iγ(λ_j − η)} (iγ)^k/k! y^{(j)∓}_k``: ``2iγ e^{iγη} S_γ^∓`` is the coefficient of
        ``e^{−iγλ}`` of ``v`` (``w``) as ``Im λ → −∞``, where ``u → b + iγJ`` (``φ_k(x) → (iγ)^k/k!·2iγ e^{−iγx}``
        for ``w = γ/sin γx``); ``S_γ → S = Σ_j y^{(j)}_0`` as ``γ → 0``.  Refuses ``b + iγJ = 0``."""
        from .._errors import InvalidStateError

        g = self.gamma
        y = X.reshape(X.shape[:-1] + (-1, 3))
        ys = y[..., 0] + (1j if inverse else -1j) * y[..., 1]  # y^+ or y^-
        weights = [np.exp(1j * g * (lam_j - eta)) * (1j * g) ** k / factorial(k) for lam_j, N in sites
                   for k in range(N)]
        S = sum(wc * ys[..., c] for c, wc in enumerate(weights))  # term by term: a batch member = its single run
        y0 = y[..., [sum(N for _, N in sites[:j]) for j in range(len(sites))], 2]
        uinf = b + 1j * g * np.sum(y0, axis=-1)
        if np.any(np.abs(uinf) <= 1e-12 * (abs(b) + g * np.sum(np.abs(y0), axis=-1))):
            raise InvalidStateError(
                "the one-point map of the trigonometric family needs b + i gamma J != 0 (J = sum of the sites' "
                "y_0^3): its dressing is normalised at Im(lambda) -> -infinity, where L tends to (b + i gamma J) "
                "sigma_3; give b != 0 (a real state then always qualifies) or a state with J != -i b / gamma")
        return S / (2.0 * uinf)

    def one_point_dressing(self, eta, norm, spec, inverse):
        r"""``D = [[s(λ−η)/γ + pq e^{−iγ(λ−η)}, p], [q, e^{−iγ(λ−η)}]]`` (``s = sin γx``; ``adj D`` with the
        inverse map's ``p``, ``q``): the rational ``K`` with ``λ − η → sin(γ(λ−η))/γ`` and ``1 → e^{−iγ(λ−η)}``;
        ``det D = e^{−iγ(λ−η)} sin(γ(λ−η)) (1 − 2iγpq)/γ`` (a :class:`SingularStepError` where ``1 − 2iγpq``
        vanishes: ``det D ≡ 0``)."""
        from .._errors import SingularStepError

        g = self.gamma
        p, q = (spec, norm) if inverse else (norm, spec)
        pq = p * q
        if np.any(np.abs(1 - 2j * g * pq) <= 1e-12 * (1 + np.abs(2 * g * pq))):
            raise SingularStepError("one-point step of the trigonometric chain: 1 - 2i gamma p q = 0, the dressing "
                                    "is degenerate (det D = 0 for every lambda); change eta")
        e, z = np.exp(1j * g * eta), np.zeros_like(pq)
        lead, sub = np.full_like(pq, 1 / (2j * g * e)), e * (pq - 1 / (2j * g))  # e^{iγλ}, e^{−iγλ} of s/γ + pq e
        if inverse:
            return np.stack([z, np.full_like(pq, e), -p, -q, lead, sub], axis=-1)
        return np.stack([lead, sub, p, q, z, np.full_like(pq, e)], axis=-1)

    def kernel_constants(self, xi):
        g, xb = self.gamma, np.conj(xi)
        return np.array([np.exp(-1j * g * xi), np.exp(-1j * g * xb), np.exp(1j * g * xi), np.exp(1j * g * xb),
                         np.sin(g * (xi - xb))])


@lru_cache(maxsize=64)
def _two_word_constants(gamma: float, xi: complex) -> tuple:
    """``(hi, lo)`` of ``e^{−iγξ}, e^{−iγξ̄}, e^{iγξ}, e^{iγξ̄}, sin(γ(ξ − ξ̄))`` (40-digit :mod:`mpmath`; the
    compiled kernel's ``gk``, :meth:`TrigonometricFamily.mp_kernel_constants`)."""
    import mpmath

    from ..gaudin._compensated import split

    with mpmath.workdps(40):
        words = [split(z) for z in TrigonometricFamily(gamma).mp_kernel_constants(mpmath.mpc(xi.real, xi.imag))]
    return tuple(np.array(w) for w in zip(*words, strict=True))


def spectral_rows(gamma, xi, k1, k2):
    r"""The two rows' null vectors ``(α, α_0, β)`` and ``(γ', δ, δ_0)`` of spectrality (cross products), shape
    ``(B, 3)`` each: row 1 of ``D(ξ_i) k_i = 0`` reads ``(e^{iγξ_i} k_{i1}, e^{−iγξ_i} k_{i1}, k_{i2})·(α, α_0, β) = 0``
    for ``ξ_1 = ξ``, ``ξ_2 = ξ̄``, row 2 ``(k_{i1}, e^{iγξ_i} k_{i2}, e^{−iγξ_i} k_{i2})·(γ', δ, δ_0) = 0``.  With
    ``k2 = (−k̄_{12}, k̄_{11})`` they give ``αα_0 = δδ_0`` identically and ``α/δ → −1`` as ``Im ξ → 0``."""
    e1p, e1m = np.exp(1j * gamma * xi), np.exp(-1j * gamma * xi)
    e2p, e2m = np.exp(1j * gamma * np.conj(xi)), np.exp(-1j * gamma * np.conj(xi))
    a1, a2 = k1[..., 0], k1[..., 1]
    b1, b2 = k2[..., 0], k2[..., 1]
    r1 = np.cross(np.stack([e1p * a1, e1m * a1, a2], -1), np.stack([e2p * b1, e2m * b1, b2], -1))
    r2 = np.cross(np.stack([a1, e1p * a2, e1m * a2], -1), np.stack([b1, e2p * b2, e2m * b2], -1))
    return r1, r2


def gauge_rule(gamma, xi, k1, k2, rule: str = "symmetric"):
    r"""Coefficients ``(α, α_0, β, γ', δ, δ_0)`` ``(B, 6)`` of the real two-point map's dressing.

    ``rule="symmetric"`` (the map's; ``docs/families.md`` §gauge): with ``p = |k_{11}|²``, ``q = |k_{12}|²``,
    ``s(x) = sin(γx)``,

    .. math:: D(\lambda) = \frac{1}{p+q}\begin{pmatrix} p\,s(\lambda-\xi) + q\,s(\lambda-\bar\xi) &
              -k_{11}\bar k_{12}\, s(\xi-\bar\xi) \\ -\bar k_{11} k_{12}\, s(\xi-\bar\xi) &
              q\,s(\lambda-\xi) + p\,s(\lambda-\bar\xi)\end{pmatrix},

    the rational ``K = λ + M_0`` of eq. (mm) (:func:`jetgaudin.backlund._dressing.real_two_point_M0`, times
    ``|k|²``) with every difference ``x`` replaced by ``sin(γx)``: it kills ``k1`` at ``ξ`` and
    ``k2 = (−k̄_{12}, k̄_{11})`` at ``ξ̄``, satisfies the symmetric gauge ``αα_0 = δδ_0`` (invariant under
    ``λ → −λ``, which swaps ``e^{±iγλ}``), is real (``|ρ| = 1``) and tends to ``sin(γ(λ − ξ))·1`` (the identity
    map) as ``Im ξ → 0`` — which fixes the sign ``ρ = ±1`` left by ``αα_0 = δδ_0``.  It is the time-1 flow of
    ``G_ξ`` (``tests/test_trigonometric_maps.py``).  Other values exist only to test that a wrong rule fails:
    ``"alpha"`` (``α = δ``: not real) and ``"sign"`` (``ρ = −1``, the other root of ``αα_0 = δδ_0``, e.g. the raw
    cross products of :func:`spectral_rows`: real, Poisson, but the flow composed with the rotation by ``π`` about
    ``e_3``, not the identity at ``Im ξ → 0``)."""
    from ..gaudin._compensated import acc, cacc

    a1, a2 = k1[..., 0], k1[..., 1]
    p, q = np.abs(a1) ** 2, np.abs(a2) ** 2
    n = p + q
    # the constants e^{−iγξ}, e^{−iγξ̄}, e^{iγξ}, e^{iγξ̄}, sin(γ(ξ − ξ̄)) as two words, every sum of products with them
    # compensated and rounded once (a constant rounded once puts the same error into every step: a linear drift of
    # the integrals; gaudin._compensated, docs/reliability.md "Drift like round-off")
    (e1m, e2m, e1p, e2p, sn), lo = _two_word_constants(float(gamma), complex(xi))
    z = np.zeros(np.shape(p))

    def pq(x, y, i, j):  # x·K_i + y·K_j, compensated
        sr, er = acc(z, z, x, K[i].real, lo[i].real)
        sr, er = acc(sr, er, y, K[j].real, lo[j].real)
        si, ei = acc(z, z, x, K[i].imag, lo[i].imag)
        si, ei = acc(si, ei, y, K[j].imag, lo[j].imag)
        return (sr + er) + 1j * (si + ei)

    def times_sin(t):  # t·sin(γ(ξ − ξ̄)), compensated
        sr, si, er, ei = cacc(z, z, z, z, t, K[4], lo[4])
        return (sr + er) + 1j * (si + ei)

    K = (e1m, e2m, e1p, e2p, sn)
    # s(λ − ξ) = (e^{−iγξ} e^{iγλ} − e^{iγξ} e^{−iγλ})/(2i)
    c = np.stack([pq(p, q, 0, 1) / (2j * n), -pq(p, q, 2, 3) / (2j * n), -times_sin(a1 * np.conj(a2)) / n,
                  -times_sin(np.conj(a1) * a2) / n, pq(q, p, 0, 1) / (2j * n), -pq(q, p, 2, 3) / (2j * n)], -1)
    if rule == "symmetric":
        return c
    if rule == "alpha":
        rho = c[..., 4] / c[..., 0]
    elif rule == "sign":
        rho = -np.ones_like(c[..., 0])
    else:  # pragma: no cover - a programming error
        raise ValueError(rule)
    c[..., :3] = c[..., :3] * rho[..., None]
    return c
