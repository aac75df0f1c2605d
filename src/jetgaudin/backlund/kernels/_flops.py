"""Hand-counted floating-point operations of one step of each compiled route (for flop rates in benchmarks)."""

from __future__ import annotations

__all__ = ["flops_per_step"]


def flops_per_step(N: int, route: str = "auto") -> dict[str, int]:
    r"""Floating-point operations of one step, counted by hand from the kernel source (:func:`._n3._step3` for
    ``route="n3"``, :func:`._generic._step_generic` for ``route="generic"``; ``"auto"``: ``n3`` when ``N = 3``).

    Counting rules: one real ``+ − × ÷ √`` = 1 flop, a fused multiply-add (:func:`._scalar._fma`) = 2
    (comparisons, ``max``, negations and conjugations = 0); complex ``±`` = 2, complex × complex = 6, real ×
    complex (:func:`_cr`) = 2, ``|z|²`` = 3, complex ÷ (:func:`_cdiv`) = 14.  Returns the parts and the
    ``total``.
    """
    if route == "auto":
        route = "n3" if N == 3 else "generic"
    if route == "n3":
        if N != 3:
            raise ValueError("route 'n3' is the N = 3 kernel")
        parts = {  # the real form of the step (module docstring of _n3)
            "ell_at_eta": 31 + 4,  # 6 components Σ y_m^a z^m (1 mul + 2 fma; b in Y³'s first fma); v, w from them
            "nu": 13 + 17 + 22,  # u² + vw; Newton update; ν_prev², 1/(2ν_prev) (previous step's ν)
            "eigenvector": 35,  # two |k|², the scale of the branch-point test
            "axis": 16,  # n' = |k|² n̂ from k: 1/|k|², k̄1 k2, |k2|² − |k1|²
            "Z": 29 + 40 + 36,  # K'y_0..K'y_3 (2 + 3 cross products); c/|k|², v_0..v_3; Z'_k = K'v_k (4 cross products)
            "division": 29 + 41,  # 1/|k|² in α, −2c; the recurrence f, g, h; residuals e_A, e_B and their two tests
            "checks_and_state": 14 + 9 + 9,  # max |ℓ_m|² of the residual test (b² per run); ỹ = y − 2cW; finiteness
        }
    elif route == "generic":
        parts = {
            "ell_at_eta": 7 * N + 2 * (8 * (N - 1) + 6),  # Horner (u real parts added as reals)
            "nu": 14 + 9 + 3,  # u² + vw; square root; closest-root test
            "eigenvector": 35,
            "M0": 26,
            # M(λ)[P, ℓ(λ)]: N + 1 commutators (38 each), N + 1 products M0 C (42 each), N sums (6 each)
            "R_products": 80 + 86 * N,
            "division": 24 * N + 38,
            "checks_and_state": 4 * N + 5 + 4 * N + 3 * N + 1 + 5 * N,  # + ℓ_m + Q_m
        }
    else:
        raise ValueError(f"route must be 'auto', 'n3' or 'generic', got {route!r}")
    parts["total"] = sum(parts.values())
    return parts


