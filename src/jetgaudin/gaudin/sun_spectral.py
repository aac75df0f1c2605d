r"""The eigenvalue branches ``μ_r`` of an su(n) chain and the interpolating Hamiltonians ``G^{(r)}_η`` (issue 32).

**Branch rule** (the su(2) rule of :mod:`jetgaudin.gaudin._curve` with ``ν`` → the eigenvalues): for a real state
``ℓ(a)``, ``a = Re η`` real and off the sites, is Hermitian, its eigenvalues real; ``μ_r(a)`` is the ``r``-th
largest (``r = 0..n−1``; it must be simple), continued along the vertical segment ``[a, η]`` (at each point the
eigenvalue nearest to the previous one; the grid doubles until every step is unambiguous: the nearest eigenvalue at
most a third as far as the next nearest).  ``n = 2``: ``μ_0 = ν``, ``μ_1 = −ν`` of the su(2) rule.

**Interpolating Hamiltonian.**  ``G^{(r)}_η = i∫_{η̄}^{η} μ_r dλ = −2∫_0^{h} Re μ_r(a + is) ds`` (``h = Im η``;
``μ_r(λ̄) = conj μ_r(λ)`` for a real state).  Its weights ``ω_I = ∂G/∂h_I`` come from ``∂μ_r/∂τ_k``: the
eigenvalues satisfy ``Σ_r μ_r^j = p_j = tr ℓ^j`` (``j = 1..n``, ``p_1 = 0``), so
``Σ_r j μ_r^{j−1} ∂μ_r/∂p_k = δ_{jk}`` (a Vandermonde system) and ``∂μ_r/∂τ_k = k ∂μ_r/∂p_k``; with
``∂τ_k(λ)/∂h^{(k)}_{j,m} = (λ − λ_j)^{−m}``:

.. math:: \omega^{(k)}_{j,m} = -2\int_0^h \operatorname{Re}\Big[\frac{\partial\mu_r}{\partial\tau_k}(\lambda)\,
          (\lambda-\lambda_j)^{-m}\Big]_{\lambda=a+is} ds

(``n = 2``: ``∂ν/∂τ_2 = 1/(2ν)``, today's weights).  Both by composite Gauss–Legendre quadrature (16 panels of 16
nodes: the integrand is analytic on the segment, so the error is at round-off unless a branch point is near it).
"""

from __future__ import annotations

import numpy as np

from .._errors import BranchPointError, InvalidParameterError
from .._validate import spectral_parameter

__all__ = ["branch_index", "eigenvalue_branch", "continue_branch", "interpolating"]

#: relative gap below which an eigenvalue at Re(eta) counts as degenerate
_GAP_TOL = 1e-8


def branch_index(model, branch) -> int:
    """``r`` from ``branch`` (an integer ``0..n−1``; ``"default"`` is 0, and for ``n = 2`` ``"opposite"`` is 1)."""
    n = model.n
    if isinstance(branch, str) or hasattr(branch, "value"):
        name = getattr(branch, "value", branch)
        if name == "default":
            return 0
        if name == "opposite" and n == 2:
            return 1
        raise InvalidParameterError(f"branch must be an integer 0..{n - 1} (the r-th largest eigenvalue of "
                                    f"ell(Re eta)){' or default/opposite' if n == 2 else ''}, got {branch!r}")
    if isinstance(branch, bool) or not isinstance(branch, (int, np.integer)) or not 0 <= branch < n:
        raise InvalidParameterError(f"branch must be an integer 0..{n - 1} (the r-th largest eigenvalue of "
                                    f"ell(Re eta)), got {branch!r}")
    return int(branch)


def check_start(model, eta: complex) -> None:
    """Refuse ``Re η`` at a site (the rule starts at a pole of ``ℓ``)."""
    for p, _ in model.sites:
        if eta.real == p:
            raise InvalidParameterError(
                f"Re(eta) = {eta.real} is a site: the branch rule of the eigenvalues starts at the real point "
                "Re(eta), a pole of the Lax matrix there; choose Re(eta) off the sites")


def _start_values(model, X, a, r):
    """``(all eigenvalues at a (B, n) ascending, μ_r(a) (B,))``; degenerate ones refused."""
    ev = np.linalg.eigvalsh(model.lax_matrix(X, np.full(X.shape[:-1], a, dtype=complex)))
    k = model.n - 1 - r
    scale = 1.0 + np.max(np.abs(ev), axis=-1)
    gaps = np.abs(ev - ev[..., k:k + 1])
    gaps[..., k] = np.inf
    if np.any(np.min(gaps, axis=-1) <= _GAP_TOL * scale):
        raise BranchPointError(
            f"the eigenvalue mu_{r} of ell(Re eta) is degenerate (gap {np.min(gaps):.2e}) at Re(eta) = {a}: the "
            "branch rule needs a simple eigenvalue there; move Re(eta) or the state")
    return ev[..., k]


def continue_branch(model, X, eta: complex, r: int, t_nodes: np.ndarray):
    """``(μ_r, all eigenvalues)`` at ``Re η + i t Im η`` for the sorted ``t_nodes ⊂ (0, 1]``, shapes ``(B, T)`` and
    ``(B, T, n)`` with ``μ_r = all[..., index]``; :class:`BranchPointError` where the continuation is ambiguous."""
    a, h = eta.real, eta.imag
    mu0 = _start_values(model, X, a, r)
    for level in range(10):
        grid = np.union1d(t_nodes, np.linspace(0.0, 1.0, 16 * 2**level + 1)[1:])
        lam = a + 1j * h * grid
        ev = np.linalg.eigvals(model.lax_matrix(X[:, None, :], np.broadcast_to(lam, X.shape[:1] + lam.shape)))
        v = mu0.astype(complex)
        ok = np.ones(X.shape[0], dtype=bool)
        idx = np.empty((X.shape[0], grid.size), dtype=int)
        for k in range(grid.size):
            d = np.abs(ev[:, k, :] - v[:, None])
            order = np.argsort(d, axis=-1)
            first = order[:, 0]
            d1 = np.take_along_axis(d, order[:, :1], -1)[:, 0]
            d2 = np.take_along_axis(d, order[:, 1:2], -1)[:, 0]
            ok &= d1 <= d2 / 3.0
            idx[:, k] = first
            v = ev[np.arange(X.shape[0]), k, first]
        if np.all(ok):
            where = np.searchsorted(grid, t_nodes)
            sel = idx[:, where]
            all_ev = ev[:, where, :]
            return np.take_along_axis(all_ev, sel[..., None], -1)[..., 0], all_ev, sel
    raise BranchPointError(f"mu_{r} could not be continued along the vertical segment from Re(eta) to eta "
                           "(eigenvalues collide on or near it); move eta")


def _checked(model, X, eta, branch):
    """``(η, r, batch shape, states (B, n))`` after the checks every branch quantity makes."""
    eta = spectral_parameter(eta)
    r = branch_index(model, branch)
    check_start(model, eta)
    X = model.check_state(X)
    return eta, r, X.shape[:-1], X.reshape(-1, X.shape[-1])


def eigenvalue_branch(model, X, eta, branch=0) -> np.ndarray:
    """``μ_r(η)`` by the branch rule (module docstring), shape ``(...)``; ``η`` real: ``μ_r(Re η)``."""
    eta, r, shape, Xb = _checked(model, X, eta, branch)
    if eta.imag == 0:
        return _start_values(model, Xb, eta.real, r).astype(complex).reshape(shape)
    return continue_branch(model, Xb, eta, r, np.array([1.0]))[0][:, 0].reshape(shape)


def _gauss(panels: int = 16, order: int = 16):
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.linspace(0.0, 1.0, panels + 1)
    t = ((edges[:-1, None] + edges[1:, None]) / 2 + (edges[1:, None] - edges[:-1, None]) / 2 * x).ravel()
    wt = ((edges[1:, None] - edges[:-1, None]) / 2 * w).ravel()
    return t, wt


def interpolating(model, X, eta, branch=0):
    """``(G^{(r)}_η, ω)`` of shapes ``(...)`` and ``(..., n_integrals)`` (module docstring)."""
    eta, r, shape, Xb = _checked(model, X, eta, branch)
    if eta.imag == 0:
        return np.zeros(shape), np.zeros(shape + (model.n_integrals,))
    t, wt = _gauss()
    mu, ev, sel = continue_branch(model, Xb, eta, r, t)
    a, h = eta.real, eta.imag
    G = -2.0 * h * np.einsum("t,bt->b", wt, mu.real)
    n = model.n
    j = np.arange(1, n + 1)
    V = j[:, None] * ev[..., None, :] ** (j[:, None] - 1)  # (B, T, j, r)
    Vinv = np.linalg.inv(V)  # (B, T, r, j)
    dmu = np.take_along_axis(Vinv, sel[..., None, None], -2)[..., 0, :]  # (B, T, j): ∂μ_r/∂p_j
    lam = a + 1j * h * t
    cols = []
    for k in range(2, n + 1):
        for p, N in model.sites:
            for m in range(1, k * N + 1):
                cols.append(k * dmu[..., k - 1] * (lam - p) ** (-m))
    integrand = np.stack(cols, axis=-1).real  # (B, T, I)
    w = -2.0 * h * np.einsum("t,bti->bi", wt, integrand)
    return G.reshape(shape), w.reshape(shape + (model.n_integrals,))
