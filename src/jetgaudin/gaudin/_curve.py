r"""The spectral curve of a chain: ``ξ(λ)``, the branch points, the default branch of ``ν`` and ``G_η``.

With ``D(λ) = Π_i (λ − λ_i)^{N_i}`` (real), ``Q(λ) = D(λ)² ν²(λ)`` is a polynomial of degree ``2M`` with
leading coefficient ``b²`` (``2M − 2`` and ``|S|²``, ``S = Σ_i y^{(i)}_0``, when ``b = 0``):

.. math:: Q(\lambda) = b^2 D(\lambda)^2 + \sum_{i,m} h_{i,m} (\lambda-\lambda_i)^{2N_i-m}
          \prod_{j\ne i} (\lambda-\lambda_j)^{2N_j}.

**Branch rule** (as for one site, ``docs/backlund.md`` §5): ``ν(λ)`` is the root positive at ``a = Re λ``
(``ν²(a) = |ξ(a)|² ≥ 0`` for a real state), continued along the vertical segment ``[a, λ]``.  With
``Q = lead · Π_k (λ − r_k)`` the continuation is exact,

.. math:: \nu(\lambda) = \nu(a)\,\frac{D(a)}{D(\lambda)} \prod_k \sqrt{\frac{\lambda-r_k}{a-r_k}}
          \quad (\text{principal roots}),

since ``D`` has no zero on the segment (its zeros, the sites, are real and ``a`` is not one) and a straight
segment not through ``r_k`` subtends an angle in ``(−π, π)`` at ``r_k``.  The product only picks the sign of
``±√ν²(λ)``, evaluated directly.  Needs ``Re λ`` off the sites and no branch point on the segment.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .._errors import BranchPointError, InvalidParameterError
from .._validate import spectral_parameter
from ..spectral import _roots, _segment_factor

__all__ = ["lax_vector", "curve_polynomial", "branch_points", "nu", "nu_with_roots", "interpolating_hamiltonian",
           "interpolating_weights"]


def _points(model, lam) -> np.ndarray:
    try:
        lam = np.asarray(lam, dtype=complex)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"lambda must be a (complex) number or array, got {lam!r}") from None
    if not np.all(np.isfinite(lam)):
        raise InvalidParameterError("lambda must be finite (NaN or inf given)")
    for p, _ in model.sites:
        if np.any(lam == p):
            raise InvalidParameterError(f"lambda = {p} is a site (a pole of the Lax matrix); evaluate elsewhere")
    return lam


@cache
def _component_poles(sites) -> tuple[np.ndarray, np.ndarray]:
    pos = np.array([p for p, N in sites for _ in range(N)])
    power = np.array([k + 1 for _, N in sites for k in range(N)])
    return pos, power


@cache
def rational_weights(sites, eta: complex) -> tuple[np.ndarray, np.ndarray]:
    """The weights ``f_c = (η − λ_c)^{−(k_c+1)}`` of ``ℓ(η)`` (rational family) as two words ``(f, flo)``: ``f`` the
    nearest doubles, ``flo`` the rest, from :mod:`mpmath` at 40 digits; read-only (both chain routes sum with them
    compensated: ``docs/reliability.md``, "Drift like round-off")."""
    import mpmath

    pos, power = _component_poles(sites)
    with mpmath.workdps(40):
        e = mpmath.mpc(complex(eta).real, complex(eta).imag)
        exact = [(e - mpmath.mpf(float(p))) ** (-int(k)) for p, k in zip(pos, power, strict=True)]
        f = np.array([complex(z) for z in exact], dtype=complex)
        flo = np.array([complex(z - mpmath.mpc(c.real, c.imag)) for z, c in zip(exact, f, strict=True)],
                       dtype=complex)
    f.setflags(write=False)
    flo.setflags(write=False)
    return f, flo


def lax_vector(model, X, lam) -> np.ndarray:
    r"""``ξ^a(λ) = b δ_{a3} + Σ_i Σ_k y^{(i)a}_k φ_{a,k}(λ − λ_i)``, shape ``(..., 3)`` (rational:
    ``φ_{a,k}(x) = x^{−(k+1)}``; other families: :meth:`jetgaudin.families.Family.phi`)."""
    X = model.check_state(X, allow_complex=True)
    lam = _points(model, lam)
    if not model.family.uniform:
        shape = np.broadcast_shapes(X.shape[:-1], lam.shape)
        xi = np.zeros(shape + (3,), dtype=complex)
        for i, (p, N) in enumerate(model.sites):
            o = model.offsets[i]
            y = X[..., 3 * o:3 * (o + N)].reshape(X.shape[:-1] + (N, 3))
            for a in range(3):
                xi[..., a] += np.einsum("k...,...k->...", model.family.phi(a + 1, lam - p, N), y[..., a])
        xi[..., 2] += model.b
        return xi
    pos, power = _component_poles(model.sites)
    f = (lam[..., None] - pos) ** (-power)  # (..., M)
    y = X.reshape(X.shape[:-1] + (model.M, 3))
    xi = np.einsum("...c,...ca->...a", f, y)
    xi[..., 2] += model.b
    return xi


@cache
def _basis(sites) -> tuple[np.ndarray, np.ndarray]:
    """``(B, D2)``: ``Q = b² D2 + h @ B``, coefficients in descending powers, length ``2M + 1``."""
    M = sum(N for _, N in sites)
    rows = []
    for i, (p, N) in enumerate(sites):
        others = [q for j, (q, Nj) in enumerate(sites) if j != i for _ in range(2 * Nj)]
        for m in range(1, 2 * N + 1):
            c = np.poly(np.array(others + [p] * (2 * N - m), dtype=float)) if others or 2 * N - m else np.ones(1)
            rows.append(np.concatenate([np.zeros(2 * M + 1 - len(c)), c]))
    D2 = np.poly(np.array([p for p, N in sites for _ in range(2 * N)], dtype=float))
    B, D2 = np.array(rows), np.asarray(D2, dtype=float)
    B.setflags(write=False)
    D2.setflags(write=False)
    return B, D2


def _uniform_polynomial(model, X) -> np.ndarray:
    """``Q(z) = ν²(λ(z)) Π_j (z − z_j)^{2N_j}`` (``z`` the family's uniformizer), ascending powers ``(..., 2M + 1)``,
    from ``2M + 1`` samples on the circle ``|z| = e^{−0.3}`` (``Im λ = 0.15/γ``, off the sites' unit circle): the
    discrete Fourier transform of the samples gives the coefficients times ``|z|^k`` exactly (degree ``≤ 2M``:
    ``ν²`` is bounded at ``z = 0`` and ``∞``)."""
    fam = model.family
    K = 2 * model.M + 1
    T = fam.period
    gamma = np.pi / T
    lam = np.arange(K) * T / K + 0.15j / gamma
    z = fam.uniformizer(lam)
    zs = fam.uniformizer(model.positions)
    vals = np.sum(lax_vector(model, X[..., None, :], lam) ** 2, axis=-1)
    for zj, (_, N) in zip(zs, model.sites, strict=True):
        vals = vals * (z - zj) ** (2 * N)
    coef = np.fft.fft(vals, axis=-1) / K
    return coef / np.abs(z[0]) ** np.arange(K)


def curve_polynomial(model, X) -> np.ndarray:
    """Coefficients of ``Q(λ) = D² ν²`` in descending powers, shape ``(..., 2M + 1)`` (``(..., 2M − 1)`` for
    ``b = 0``: the two leading coefficients vanish identically and are dropped)."""
    B, D2 = _basis(model.sites)
    h = model.integrals(X)
    Q = np.einsum("...I,Ip->...p", h, B) + model.b**2 * D2
    if model.b == 0.0:
        Q = Q[..., 2:]
        scale = np.max(np.abs(Q), axis=-1)
        if Q.shape[-1] < 2 or np.any(np.abs(Q[..., 0]) <= 1e-14 * scale):
            raise BranchPointError(
                "with b = 0 the branch rule of nu is normalised by the total spin S = sum of the y_0 of all sites "
                "(nu ~ |S|/lambda at infinity); here S = 0 (or the chain has M = 1): give b != 0 or a state with S != 0"
            )
    return Q


def branch_points(model, X) -> np.ndarray:
    """Roots of :func:`curve_polynomial`, shape ``(..., 2M)`` (``(..., 2M − 2)`` for ``b = 0``); other families:
    the zeros of ``ν²`` as roots ``z_k`` of :func:`_uniform_polynomial` (in the uniformizer ``z``)."""
    if model.family.uniform:
        return _roots(curve_polynomial(model, X))
    if model.family.uniformizer(0.0) is None:  # no exact rule: the continuation is numerical (no roots needed)
        return np.zeros(np.shape(X)[:-1] + (0,), dtype=complex)
    Q = _uniform_polynomial(model, X)[..., ::-1]
    if np.any(np.abs(Q[..., 0]) <= 1e-13 * np.max(np.abs(Q), axis=-1)):
        raise BranchPointError(
            "nu^2 vanishes at Im(lambda) -> -infinity (b + i gamma J = 0: b = 0 and J = sum of the y_0^3 = 0); the "
            "branch rule of nu needs b != 0 or J != 0")
    return _roots(Q)


def _D_phase(model, lam):
    """``D(λ)/|D(λ)|`` as a product of unit factors (no overflow)."""
    out = np.ones(lam.shape, dtype=complex)
    for p, N in model.sites:
        z = lam - p
        out = out * (z / np.abs(z)) ** N
    return out


def _nu_uniformized(model, X, lam, roots, sheet):
    """The branch rule in the uniformizer ``z`` (module docstring with ``λ → z``):
    ``ν(λ) = ν(a) [D(z_a)/D(z)] Π_k √((z − r_k)/(z_a − r_k))``, ``D(z) = Π_j (z − z_j)^{N_j}``; the vertical
    segment ``[a, λ]`` maps to a straight segment (a ray of ``z = e^{2iγλ}``)."""
    fam = model.family
    a = lam.real.astype(complex)
    z, za = fam.uniformizer(lam), fam.uniformizer(a)
    nu2 = np.sum(lax_vector(model, X, lam) ** 2, axis=-1)
    nu_a = np.sqrt(np.sum(lax_vector(model, X, a) ** 2, axis=-1))
    ratio = np.ones(lam.shape, dtype=complex)
    for zj, (_, N) in zip(fam.uniformizer(model.positions), model.sites, strict=True):
        ratio = ratio * ((za - zj) / (z - zj)) ** N
    roots = np.broadcast_to(roots, lam.shape + (roots.shape[-1],))
    ref = nu_a * ratio * _segment_factor(z, za, roots, nu_a)
    direct = np.sqrt(nu2)
    with np.errstate(invalid="ignore", divide="ignore"):
        test = (np.conj(direct / np.abs(direct)) * ref / np.abs(ref)).real
    if not np.all(np.isfinite(test)):
        raise BranchPointError("nu(lambda) is zero or not representable at this lambda (a branch point); move it")
    return sheet * np.where(test >= 0, 1.0, -1.0) * direct


def _nu_numerical(model, X, lam, sheet, n0: int = 64, n_max: int = 2**16):
    """The branch rule by numerical continuation (families without a uniformizer): ``±√ν²`` at ``n`` equally spaced
    points of the segment from ``Re λ`` (``ν > 0`` there for a real state), each time the root nearer to the
    previous one; ``n`` doubles until no step moves ``ν`` by more than a quarter of its size (then the nearer
    root is unambiguous), else :class:`BranchPointError` (a branch point on or near the segment)."""
    a = lam.real
    n = n0
    while n <= n_max:
        t = np.linspace(0.0, 1.0, n + 1)
        pts = a[..., None] + 1j * lam.imag[..., None] * t
        nu2 = np.sum(lax_vector(model, X[..., None, :], pts) ** 2, axis=-1)
        r = np.sqrt(nu2)
        v = r[..., 0]
        ok = np.ones(lam.shape, dtype=bool)
        for k in range(1, n + 1):
            rk = r[..., k]
            rk = np.where(np.abs(rk - v) <= np.abs(rk + v), rk, -rk)
            ok &= np.abs(rk - v) <= 0.25 * np.maximum(np.abs(rk), np.abs(v))
            v = rk
        if np.all(ok) and np.all(v != 0):
            return sheet * v
        n *= 2
    raise BranchPointError("nu could not be continued along the vertical segment from Re(eta) (a branch point on or "
                           "near it); move eta")


def nu_with_roots(model, X, lam, roots, sheet: int = 1):
    """``ν(λ)`` on the default branch given the roots of ``Q`` (``X``, ``lam``, ``roots`` broadcast)."""
    if not model.family.uniform:
        _check_start(model, lam)
        if model.family.uniformizer(0.0) is None:
            return _nu_numerical(model, X, lam, sheet)
        return _nu_uniformized(model, X, lam, roots, sheet)
    a = lam.real
    for p, _ in model.sites:
        if np.any(a == p):
            raise BranchPointError(
                f"the default branch of nu starts at the real point Re(eta) = {p}, which is a site (a pole of L); "
                "move Re(eta) off the sites"
            )
    nu2 = np.sum(lax_vector(model, X, lam) ** 2, axis=-1)
    nu2_a = np.sum(lax_vector(model, X, a.astype(complex)) ** 2, axis=-1)
    direct = np.sqrt(nu2)
    sqrt_Qa = np.sqrt(nu2_a) * np.abs(_D_real(model, a))  # √(D(a)² ν²(a)), D(a) real
    roots = np.broadcast_to(roots, lam.shape + (roots.shape[-1],))
    # the continuation along the vertical segment, with its branch-point test, is the one-site rule's own
    ref = np.sign(_D_real(model, a)) * np.conj(_D_phase(model, lam)) * _segment_factor(lam, a, roots, sqrt_Qa)
    ref = ref * sqrt_Qa / np.abs(sqrt_Qa)
    with np.errstate(invalid="ignore", divide="ignore"):
        test = (np.conj(direct / np.abs(direct)) * ref / np.abs(ref)).real
    if not np.all(np.isfinite(test)):
        raise BranchPointError("nu(lambda) is zero or not representable at this lambda (a branch point); move it")
    return sheet * np.where(test >= 0, 1.0, -1.0) * direct


def _check_start(model, lam):
    T = model.family.period
    for p, _ in model.sites:
        r = (lam.real - p) / T
        if np.any(np.abs(r - np.round(r)) < 1e-14):
            raise BranchPointError(
                f"the default branch of nu starts at the real point Re(eta), equal to the site {p} modulo the "
                f"period {T} (a pole of L); move Re(eta) off the sites")


def _D_real(model, a):
    out = np.ones(np.shape(a))
    for p, N in model.sites:
        out = out * (a - p) ** N
    return out


def nu(model, X, eta, *, sheet: int = 1):
    r"""``ν(η)`` of the chain on the default branch (module docstring), shape broadcast of ``X[..., 0]`` and
    ``eta``; ``sheet=-1`` gives ``−ν``.  For a real state ``ν(η̄) = conj ν(η)``."""
    if sheet not in (1, -1):
        raise InvalidParameterError(f"sheet must be +1 or -1, got {sheet!r}")
    X = model.check_state(X, allow_complex=True)
    lam = _points(model, eta)
    shape = np.broadcast_shapes(X.shape[:-1], lam.shape)
    X = np.broadcast_to(X, shape + X.shape[-1:])
    lam = np.broadcast_to(lam, shape)
    roots = branch_points(model, X)
    return nu_with_roots(model, X, lam, roots, sheet)


def _segment_integral(model, X, eta, integrand, epsabs=1e-15, epsrel=1e-13):
    X = model.check_state(X)
    eta = spectral_parameter(eta)
    a, h = eta.real, eta.imag
    roots = branch_points(model, X)

    def f(s):
        lam = np.full(X.shape[:-1], a + 1j * s)
        return integrand(lam, nu_with_roots(model, X, lam, roots)).real

    if h == 0:
        return np.zeros(np.shape(f(0.0)))
    from scipy.integrate import quad_vec  # lazy: keeps `import jetgaudin` light

    val, _err = quad_vec(f, 0.0, h, epsabs=epsabs, epsrel=epsrel, limit=2000)
    return val


def interpolating_hamiltonian(model, X, eta):
    r"""``G_η = i∫_{η̄}^{η} ν dλ = −2∫_0^{Im η} Re ν(Re η + is) ds``, shape ``(...)``."""
    return -2.0 * _segment_integral(model, X, eta, lambda lam, v: v)


def interpolating_weights(model, X, eta):
    r"""``ω_I = ∂G_η/∂I = −2∫_0^{Im η} Re[(∂ν²/∂I)(λ) / (2ν)] ds``, shape ``(..., n_integrals)``, order of the
    integrals: ``∂ν²/∂h_{i,m} = ψ_m(λ − λ_i)`` (:meth:`jetgaudin.families.Family.nu2_basis`; rational
    ``(λ − λ_i)^{−m}``) and, for the extras, the derivative of the constant term of ``ν²``."""
    if not model.family.uniform:
        fam = model.family
        extra = model.integrals(X)[..., 2 * model.M:]
        dconst = fam.nu2_constant_gradient(model.b, extra)

        def integrand(lam, v):
            cols = [fam.nu2_basis(m, lam - p) for p, N in model.sites for m in range(1, 2 * N + 1)]
            d = np.concatenate([np.stack(cols, -1), np.broadcast_to(dconst, lam.shape + dconst.shape[-1:])], -1)
            return d / (2.0 * v[..., None])

        return -2.0 * _segment_integral(model, X, eta, integrand)
    pos = np.array([p for p, N in model.sites for _ in range(2 * N)])
    m = np.array([m for _, N in model.sites for m in range(1, 2 * N + 1)])
    return -2.0 * _segment_integral(
        model, X, eta, lambda lam, v: (lam[..., None] - pos) ** (-m) / (2.0 * v[..., None])
    )
