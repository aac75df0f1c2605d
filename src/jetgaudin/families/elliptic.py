r"""The elliptic (XYZ) Gaudin family (issue 24; ``docs/families.md``, tutorial ``docs/tutorials/xyz.md``).

Modulus ``k ∈ [0, 1)``, ``K = K(k)``, ``K' = K(√(1−k²))``; **no field** (``b ≠ 0`` is refused: the XYZ r-matrix
has no continuous symmetry).  Basis functions (Jacobi functions of modulus ``k``, :mod:`._jacobi`):

.. math:: w_1 = \operatorname{ns},\quad w_2 = \operatorname{ds},\quad w_3 = \operatorname{cs},\qquad
          \xi^a(\lambda) = \sum_j \sum_{k<N_j} y^{(j)a}_k \frac{(-1)^k}{k!} w_a^{(k)}(\lambda-\lambda_j),

``ℓ = Σ_a ξ^a σ_a`` (Pauli), ``L = (i/2) ℓ``; at ``k = 0`` they are ``1/sin``, ``1/sin``, ``cot``: the
trigonometric family (``γ = 1``) with ``b = 0``.  ``w_a(x + 2K) = ε_a w_a(x)``, ``ε = (−1, −1, 1)``;
``w_a(x + 2iK') = ε'_a w_a(x)``, ``ε' = (1, −1, −1)``: sites must be distinct modulo ``2K``.

**r-matrix.**  With ``{y^a, y^b} = ε_{abc} y^c`` per site (``g^(N)``, as for every family), the identity
``w_a(x) w_b(y) = w_a(x−y) w_c(y) − w_b(x−y) w_c(x)`` (``(a, b, c)`` distinct; its ``k = 0`` and rational
limits are the partial fractions of ``1/(xy)``) gives

.. math:: \{\ell(\lambda) \otimes \ell(\mu)\} = [\, r(\lambda-\mu),\ \ell(\lambda)\otimes 1 + 1\otimes\ell(\mu)\,],
          \qquad r(x) = \tfrac{i}{2} \sum_a w_a(x)\, \sigma_a \otimes \sigma_a

(for ``L = (i/2)ℓ``: ``r_L = (i/2) r``), tested in ``tests/test_elliptic.py``.

**Integrals.**  ``ν² = Σ_a (ξ^a)²`` is elliptic (periods ``2K``, ``2iK'``: the signs ``ε_a`` cancel in the
squares) with poles only at the sites.  With ``F(x) = cs(x) dn(x) + Z(x)`` (``Z`` Jacobi's zeta; ``F = 1/x`` +
odd regular part, regular at ``iK'``, ``F(x + 2K) = F(x)``, ``F(x + 2iK') = F(x) − iπ/K``, ``F' = 1 − E/K − ns²``,
``cot x`` at ``k = 0``) and ``ψ_m = (−1)^{m−1} F^{(m−1)}/(m−1)!`` (principal part ``x^{−m}``; ``ψ_2 = ns² − 1 + E/K``,
``1/sin²`` at ``k = 0``):

.. math:: \nu^2(\lambda) = c_0 + \sum_j \sum_{m=1}^{2N_j} h_{j,m}\, \psi_m(\lambda-\lambda_j),
          \qquad \sum_j h_{j,1} = 0,

exactly: ``ν² − Σ h ψ`` has no pole and, since ``Σ_j h_{j,1} = 0`` (the residues of an elliptic function), is
doubly periodic, hence a constant ``c_0``.  For order-1 sites ``h_{j,2} = C_j = |s_j|²`` (Casimirs) and
``h_{j,1} = 2H_j``, ``H_j = Σ_{k≠j} Σ_a w_a(λ_j − λ_k) s^a_j s^a_k`` (the Gaudin Hamiltonians, ``Σ_j H_j = 0``);
``c_0`` is one more commuting quadratic integral (its form: :func:`jetgaudin.gaudin._forms.constant_form`; at
``k = 0`` it is ``−J²``).  ``integrals(X)`` = ``(h_{1,1} … h_{1,2N_1}, h_{2,1}, …, c0)``; the Casimirs are the
``h_{j,m}``, ``m > N_j`` (``casimir_mask``).

**Dressing** (Sklyanin's classical XYZ L-operator with a shifted spectral parameter):

.. math:: D(\lambda) = S_0\,\mathbb 1 + \sum_a S_a\, w_a(\lambda - \lambda_0)\, \sigma_a,
          \qquad \lambda_0 = \operatorname{Re}\xi + \omega,\ \omega \in \{0, K, iK', K + iK'\}.

``D(λ + 2K) = σ_3 D σ_3`` and ``D(λ + 2iK') = σ_1 D σ_1`` like ``ℓ``; ``det D = S_0² − S_1² − k'² S_2² −
|S|² cs²(λ − λ_0)`` (``ns² = 1 + cs²``, ``ds² = k'² + cs²``) vanishes at ``λ_0 ± x_*`` modulo the periods of
``cs²``; ``x_* = iIm ξ − ω`` puts the zeros at ``ξ`` and ``ξ̄`` for every half period ``ω``, and ``ℓ̃ = Dℓ adj D/det D``
is regular at ``λ_0`` (``det D ∼ −|S|²/x²`` there), so it has the form of ``ℓ``.  Spectrality ``D(ξ) k_1 = 0``,
``D(ξ̄) k_2 = 0`` (``k_2 ⊥ k_1``, the eigenvector of ``ℓ(ξ̄)`` for ``−conj ν_1``) is 4 linear equations of rank 3
in ``S``: ``S`` is fixed up to scale (:func:`spectral_null_vector`).  For a real state ``(S_0, iS_a)`` is real up
to a common factor, so ``D(λ̄)^† ∝ adj D(λ)`` and the map is real.  The four half periods give four real, Poisson,
integral-preserving maps: ``D_ω`` differs from ``D_0`` by the symmetry ``ℓ → σ_b ℓ σ_b`` (a π-rotation of every
spin about the axis ``b``; ``ω = K, iK', K + iK'`` ↔ ``b = 3, 1, 2``).  Only ``ω = 0`` tends to the identity as
``Im ξ → 0`` (``D → S_0 1``: ``det D`` then has its zeros near the pole of ``cs²``) and is the time-1 flow of
``G_ξ = i∫_{ξ̄}^{ξ} ν dλ``; the others are that flow composed with the π-rotation (tested).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import special

from .._errors import InvalidParameterError
from . import _jacobi
from ._base import Family

__all__ = ["EllipticFamily", "spectral_null_vector", "HALF_PERIODS", "PAULI"]

#: Pauli matrices σ_1, σ_2, σ_3
PAULI = np.array([[[0, 1], [1, 0]], [[0, -1j], [1j, 0]], [[1, 0], [0, -1]]], dtype=complex)
PAULI.setflags(write=False)
#: the half-period shifts ω of the dressing as multiples (of K, of iK'); the map's is (0, 0)
HALF_PERIODS = {"0": (0, 0), "K": (1, 0), "iK'": (0, 1), "K+iK'": (1, 1)}
#: |Im ξ| must stay below this fraction of K' (at K' the points ξ, ξ̄ coincide modulo the period 2iK')
_IM_FRACTION = 0.9


class EllipticFamily(Family):
    """The XYZ family of modulus ``modulus`` (module docstring).  ``half_period`` (a key of
    :data:`HALF_PERIODS`) chooses the dressing's shift; only ``"0"`` is the time-1 flow of ``G_ξ``: the others
    exist to test that."""

    name = "elliptic"
    uniform = False
    n_dressing = 4  # 1, w_1 σ_1, w_2 σ_2, w_3 σ_3
    constant_integral = "c0"
    dressing_needs_xi = True
    kernel_rule = 2  # jetgaudin.gaudin._family_kernel: the null vector of spectrality
    one_point_refusal = (
        "the elliptic (XYZ) family has no one-point map: the determinant of its dressing (Sklyanin's L-operator) is "
        "an elliptic function of order 2, so its zeros come in pairs (lambda_0 +- x*), and no elliptic function has a "
        "single zero; use the real two-point map two_point_backlund(eta)")

    def __init__(self, modulus: float = 0.5, half_period: str = "0"):
        self.modulus = _jacobi.check_modulus(modulus)
        if half_period not in HALF_PERIODS:
            raise InvalidParameterError(f"half_period must be one of {list(HALF_PERIODS)}, got {half_period!r}")
        self.half_period = half_period
        self.K, self.Kp = _jacobi.periods(self.modulus)
        m = self.modulus**2
        self._e_over_k = float(special.ellipe(m)) / self.K

    @property
    def period(self) -> float:
        return 2.0 * self.K

    def describe(self) -> dict:
        d: dict = {"modulus": self.modulus}
        if self.half_period != "0":
            d["half_period"] = self.half_period
        return d

    def check(self, b, sites):
        if b != 0.0:
            raise InvalidParameterError(
                f"the elliptic (XYZ) family has no field: b must be 0 (the XYZ r-matrix has no continuous symmetry "
                f"to align a field with), got b = {b}; use GaudinModel(0.0, sites, family='elliptic', ...)")
        super().check(b, sites)

    def check_xi(self, xi):
        if abs(xi.imag) >= _IM_FRACTION * self.Kp:
            raise InvalidParameterError(
                f"|Im(eta)| = {abs(xi.imag):.6g} is too close to K' = {self.Kp:.6g} (modulus {self.modulus}): at "
                f"|Im eta| = K' the points eta and conj(eta) coincide modulo the period 2iK'; give "
                f"|Im(eta)| < {_IM_FRACTION} K' = {_IM_FRACTION * self.Kp:.6g}")

    # ---- basis functions -------------------------------------------------------------------------------------

    def taylor(self, a, x0, order):
        return _jacobi.w_taylor(x0, self.modulus, order)[a - 1]

    def regular(self, a, order):
        return _jacobi.w_regular(self.modulus, order)[a - 1].astype(complex)

    # ---- ν² ----------------------------------------------------------------------------------------------

    def nu2_basis(self, m, x):
        return (-1) ** (m - 1) * _jacobi.curve_function_taylor(x, self.modulus, m)[m - 1]

    def nu2_basis_constant(self, m):
        # ψ_m = (−1)^{m−1} F^{(m−1)}/(m−1)!, F = 1/x + Σ f_n x^n: the constant of ψ_m − x^{−m} is (−1)^{m−1} f_{m−1}
        return (-1) ** (m - 1) * float(_jacobi.curve_function_regular(self.modulus, m)[m - 1])

    def nu2_constant(self, b, extra):
        return extra[..., 0]

    def nu2_constant_gradient(self, b, extra):
        return np.ones(np.shape(extra))

    # ---- dressing -------------------------------------------------------------------------------------------

    def _lam0(self, xi) -> complex:
        nK, nKp = HALF_PERIODS[self.half_period]
        if nKp and not np.isfinite(self.Kp):
            raise InvalidParameterError("the half periods iK', K + iK' do not exist at k = 0 (K' = inf)")
        return complex(np.real(xi)) + nK * self.K + (1j * self.Kp if nKp else 0.0)

    def dressing_basis(self, lam, xi):
        lam = np.asarray(lam, dtype=complex)
        W = _jacobi.w_values(lam - self._lam0(xi), self.modulus)  # (3,) + shape
        out = np.zeros(lam.shape + (4, 2, 2), dtype=complex)
        out[..., 0, :, :] = np.eye(2)
        for a in range(3):
            out[..., a + 1, :, :] = W[a][..., None, None] * PAULI[a]
        return out

    def dressing_taylor(self, lam0, order, xi):
        T = _jacobi.w_taylor(np.asarray(lam0 - self._lam0(xi), dtype=complex), self.modulus, order)  # (3, order)
        out = np.zeros((order, 4, 2, 2), dtype=complex)
        out[0, 0] = np.eye(2)
        for a in range(3):
            out[:, a + 1] = T[a][:, None, None] * PAULI[a]
        return out

    def mp_w(self, a, x):
        """``ns, ds, cs`` (``a = 1, 2, 3``) of parameter ``m = k²`` (the modulus as given, squared exactly)."""
        import mpmath

        m = mpmath.mpf(self.modulus) ** 2
        sn = mpmath.ellipfun("sn", x, m=m)
        return 1 / sn if a == 1 else mpmath.ellipfun("dn" if a == 2 else "cn", x, m=m) / sn

    def _mp_lam0(self, xi):
        import mpmath

        nK, nKp = HALF_PERIODS[self.half_period]
        m = mpmath.mpf(self.modulus) ** 2
        return (mpmath.re(xi) + (nK * mpmath.ellipk(m) if nK else 0)
                + (1j * mpmath.ellipk(1 - m) if nKp else 0))

    def mp_dressing_basis(self, lam, xi):
        w1, w2, w3 = (self.mp_w(a, lam - self._mp_lam0(xi)) for a in (1, 2, 3))
        return [[1, 0, 0, 1], [0, w1, w1, 0], [0, -1j * w2, 1j * w2, 0], [w3, 0, 0, -w3]]

    def mp_w_taylor(self, x, n: int) -> list:
        """The Taylor coefficients of ``ns, ds, cs`` at ``x`` in closed form: ``sn, cn, dn`` at ``x`` (three
        :func:`mpmath.ellipfun` calls), their series from ``sn' = cn dn``, ``cn' = −sn dn``, ``dn' = −m sn cn``
        (``(k + 1) s_{k+1} = Σ_j c_j d_{k−j}``, …), then ``ns = 1/sn`` by series inversion, ``ds = dn·ns``,
        ``cs = cn·ns`` (Cauchy products): exact to the working precision, where :func:`mpmath.taylor` evaluates
        ``mp_w`` at many points (~15 ms a coefficient).  ``sn, cn, dn`` by :func:`_mp_sn_cn_dn`."""
        import mpmath

        m = mpmath.mpf(self.modulus) ** 2
        s, c, d = ([v] for v in _mp_sn_cn_dn(self.modulus, mpmath.mp.prec, x))
        for k in range(n - 1):
            s.append(mpmath.fsum(c[j] * d[k - j] for j in range(k + 1)) / (k + 1))
            c.append(-mpmath.fsum(s[j] * d[k - j] for j in range(k + 1)) / (k + 1))
            d.append(-m * mpmath.fsum(s[j] * c[k - j] for j in range(k + 1)) / (k + 1))
        ns = [1 / s[0]]
        for k in range(1, n):
            ns.append(-mpmath.fsum(s[j] * ns[k - j] for j in range(1, k + 1)) / s[0])

        def times(u):
            return [mpmath.fsum(u[j] * ns[k - j] for j in range(k + 1)) for k in range(n)]

        return [ns, times(d), times(c)]

    def mp_dressing_taylor(self, lam, xi, n: int) -> list:
        """:meth:`mp_dressing_basis`'s Taylor coefficients at ``λ`` from :meth:`mp_w_taylor` at ``λ − λ_0``."""
        import mpmath

        w1, w2, w3 = self.mp_w_taylor(lam - self._mp_lam0(xi), n)
        zero, one = [mpmath.mpf(0)] * n, [mpmath.mpf(1)] + [mpmath.mpf(0)] * (n - 1)
        return [[one, zero, zero, one], [zero, w1, w1, zero], [zero, [-1j * t for t in w2], [1j * t for t in w2], zero],
                [w3, zero, zero, [-t for t in w3]]]

    def mp_kernel_constants(self, xi):
        import mpmath

        lam0 = self._mp_lam0(xi)
        return [w[0] for z in (xi, mpmath.conj(xi)) for w in self.mp_w_taylor(z - lam0, 1)]

    def real_dressing(self, xi, k1, k2):
        return spectral_null_vector(self, xi, k1, k2)

    def kernel_constants(self, xi):
        """``(w_a(ξ − λ_0), w_a(ξ̄ − λ_0))``, ``a = 1, 2, 3``: the dressing basis at the two spectral points."""
        xi = complex(xi)
        lam0 = self._lam0(xi)
        return _jacobi.w_values(np.array([xi - lam0, np.conj(xi) - lam0]), self.modulus).T.ravel()


@lru_cache(maxsize=16)
def _mp_theta_constants(modulus: float, prec: int) -> tuple:
    """``(K, q, θ2(0), θ3(0), θ4(0))`` of the parameter ``m = k²`` at the binary precision ``prec`` (cached: what
    :func:`mpmath.ellipfun` computes again at every call)."""
    import mpmath

    with mpmath.workprec(prec):
        m = mpmath.mpf(modulus) ** 2
        q = mpmath.qfrom(m=m)
        return mpmath.ellipk(m), q, mpmath.jtheta(2, 0, q), mpmath.jtheta(3, 0, q), mpmath.jtheta(4, 0, q)


def _mp_sn_cn_dn(modulus: float, prec: int, u) -> tuple:
    """``sn, cn, dn`` of ``u`` (an ``mpc``) and ``m = k²`` from the theta functions of the cached nome: with
    ``z = πu/(2K)``, ``sn = (θ3/θ2) θ1(z)/θ4(z)``, ``cn = (θ4/θ2) θ2(z)/θ4(z)``, ``dn = (θ4/θ3) θ3(z)/θ4(z)`` (DLMF
    22.2.4–22.2.6; the constants at 0).  Equal to :func:`mpmath.ellipfun` to ~1e-41 relative at 40 digits
    (``tests/test_mp_series.py`` compares the series built on them with ``mpmath.taylor`` of ``ellipfun``), four
    theta calls against ``ellipfun``'s three calls that each recompute the nome and ``K``.  At ``k = 0`` (nome 0,
    ``θ2(0) = 0``) ``ellipfun`` itself."""
    import mpmath

    K, q, t2, t3, t4 = _mp_theta_constants(modulus, prec)
    if q == 0:  # k = 0 (the trigonometric limit): θ2(0) = 0; sin, cos, 1 through ellipfun
        m = mpmath.mpf(modulus) ** 2
        return tuple(mpmath.ellipfun(f, u, m=m) for f in ("sn", "cn", "dn"))
    z = mpmath.pi * u / (2 * K)
    th1, th2, th3, th4 = (mpmath.jtheta(n, z, q) for n in (1, 2, 3, 4))
    return t3 / t2 * th1 / th4, t4 / t2 * th2 / th4, t4 / t3 * th3 / th4


@lru_cache(maxsize=64)
def _two_word_w(family: EllipticFamily, xi: complex) -> tuple:
    """``(hi, lo)`` of :meth:`EllipticFamily.mp_kernel_constants` (40-digit :mod:`mpmath`): ``w_a(ξ − λ_0)``,
    ``w_a(ξ̄ − λ_0)``, the dressing basis at the two spectral points."""
    import mpmath

    from ..gaudin._compensated import split

    with mpmath.workdps(40):
        words = [split(z) for z in family.mp_kernel_constants(mpmath.mpc(xi.real, xi.imag))]
    return tuple(np.array(w) for w in zip(*words, strict=True))


def _det3(r0, r1, r2, c0, c1, c2):
    """The 3 × 3 determinant of the columns ``c0, c1, c2`` of the rows ``r0, r1, r2`` (arrays ``(B, 4)``), expanded
    along ``r0`` as the compiled kernel's ``_det3`` (no LAPACK: its rounding is what the docstring below avoids)."""
    return (r0[..., c0] * (r1[..., c1] * r2[..., c2] - r1[..., c2] * r2[..., c1])
            - r0[..., c1] * (r1[..., c0] * r2[..., c2] - r1[..., c2] * r2[..., c0])
            + r0[..., c2] * (r1[..., c0] * r2[..., c1] - r1[..., c1] * r2[..., c0]))


def spectral_null_vector(family: EllipticFamily, xi, k1, k2) -> np.ndarray:
    r"""``S = (S_0, S_1, S_2, S_3)`` ``(B, 4)`` with ``D(ξ) k_1 = 0``, ``D(ξ̄) k_2 = 0`` (module docstring): the null
    vector of the ``4 × 4`` system ``A`` (rank 3) as the cofactor vector of three of its rows (the generalised cross
    product: ``A·n = 0`` exactly in exact arithmetic for the fourth row by rank 3, for the three by construction) —
    rows ``0, 1, 2`` unless their cofactors are small against the rows' norms (``|n|² ≤ 1e-4 Π|A_r|²``), then the
    choice of three with the largest cofactors, as the compiled kernel
    (:func:`jetgaudin.gaudin._family_kernel._elliptic_coefficients`); normalised to ``|S| = 1`` with its largest
    component real (if it is ``S_0``) or imaginary (an ``S_a``), so that ``(S_0, iS_a)`` is real for a real state.

    Not the SVD's singular vector: LAPACK's rounding of it leaves an error of one sign in the map's integrals at
    every step (the NumPy elliptic route's drift grew like a bias, ``z`` 5 at 4000 steps of 2048 orbits; with the
    cofactors ≤ 2, as the compiled route: ``docs/reliability.md``, issue 33 item 3)."""
    from ..gaudin._compensated import cacc

    xi = complex(xi)
    hi, lo = _two_word_w(family, xi)  # w_a(ξ − λ_0), then w_a(ξ̄ − λ_0), a = 1, 2, 3, as two words
    cols = []
    for j, k in enumerate((k1, k2)):
        # k scaled by a power of two (exact) to |k|² in [1/4, 1): the rows, hence the cofactors (cubes of them), are
        # of size 1 for states of any size; the null vector does not depend on the rows' scale
        e = np.frexp(np.sum(np.abs(k) ** 2, axis=-1))[1]
        k = k * np.ldexp(1.0, -((e + 1) // 2))[..., None]
        z = np.zeros(k.shape[:-1])

        def w_times(a, v, j=j, z=z):  # w_a(·) v, compensated and rounded once (docs/reliability.md, issue 33)
            sr, si, er, ei = cacc(z, z, z, z, v, hi[3 * j + a - 1], lo[3 * j + a - 1])
            return (sr + er) + 1j * (si + ei)

        a1, a2 = k[..., 0], k[..., 1]  # rows i of D(λ) k = Σ_p S_p (B_p k)_i: B_0 = 1, B_a = w_a σ_a
        cols.append(np.stack([np.stack([a1, w_times(1, a2), w_times(2, -1j * a2), w_times(3, a1)], -1),
                              np.stack([a2, w_times(1, a1), w_times(2, 1j * a1), w_times(3, -a2)], -1)], -2))
    A = np.concatenate(cols, axis=-2)  # (B, 4, 4)
    rn = np.sum(np.abs(A) ** 2, axis=-1)  # (B, 4): the rows' squared norms
    S = np.zeros(A.shape[:-2] + (4,), dtype=complex)
    best = np.full(A.shape[:-2], -1.0)
    done = np.zeros(A.shape[:-2], dtype=bool)
    for i in range(4):  # leave out row 3, 2, 1, 0 in turn (the compiled kernel's order)
        rows = [(3 - i + d) % 4 for d in (1, 2, 3)]
        r0, r1, r2 = (A[..., r, :] for r in rows)
        n = np.stack([_det3(r0, r1, r2, 1, 2, 3), -_det3(r0, r1, r2, 0, 2, 3), _det3(r0, r1, r2, 0, 1, 3),
                      -_det3(r0, r1, r2, 0, 1, 2)], axis=-1)
        size = np.sum(np.abs(n) ** 2, axis=-1)
        take = ~done & (size > best)
        S[take], best[take] = n[take], size[take]
        done |= best > 1e-4 * rn[..., rows[0]] * rn[..., rows[1]] * rn[..., rows[2]]
        if np.all(done):  # the other choices would change nothing (``take`` is empty once every orbit is done)
            break
    S = S / np.sqrt(best)[..., None]
    big = np.argmax(np.abs(S), axis=-1)
    top = np.take_along_axis(S, big[..., None], axis=-1)[..., 0]
    phase = np.abs(top) / top * np.where(big == 0, 1.0, 1j)
    return S * phase[..., None]
