"""Hand-counted floating-point operations of one step of each compiled route (for flop rates in benchmarks)."""

from __future__ import annotations

__all__ = ["flops_per_step"]


def flops_per_step(N: int, route: str = "auto") -> dict[str, int]:
    r"""Floating-point operations of one step, counted by hand from the kernel source (:func:`._n3._step3` for
    ``route="n3"``, :func:`._generic._step_generic` for ``route="generic"``; ``"auto"``: ``n3`` when ``N = 3``).

    Counting rules: one real ``+ − × ÷ √`` = 1 flop (comparisons, ``max``, negations and
    conjugations = 0); complex ``±`` = 2, complex × complex = 6, real × complex (:func:`_cr`) = 2,
    ``|z|²`` = 3, complex ÷ (:func:`_cdiv`) = 14.  Returns the parts and the ``total``.
    """
    if route == "auto":
        route = "n3" if N == 3 else "generic"
    if route == "n3":
        if N != 3:
            raise ValueError("route 'n3' is the N = 3 kernel")
        parts = {
            "ell_at_eta": 12 + 22 + 22,  # u: 3 real×complex + 3 adds; v, w: 3 complex products + 2 adds each
            "nu": 14 + 17 + 22,  # u² + vw; Newton update; ν_prev², 1/(2ν_prev) (previous step's ν)
            "eigenvector": 35,  # two |k|², the scale of the branch-point test
            "M0": 26,
            "R_products": 62 + 3 * 118 + 36,  # T1, T2 for ℓ_0 (b real) and ℓ_1..ℓ_3; sums into R_k
            "division": 72 + 38,  # Q_3..Q_0 bottom-up; residual of the two unused equations
            "checks_and_state": 17 + 12 + 9,  # |ℓ| scale of the residual test; new state; finiteness
        }
    elif route == "generic":
        parts = {
            "ell_at_eta": 7 * N + 2 * (8 * (N - 1) + 6),  # Horner (u real parts added as reals)
            "nu": 14 + 9 + 3,  # u² + vw; square root; closest-root test
            "eigenvector": 35,
            "M0": 26,
            "R_products": 62 + 118 * N + 12 * N,
            "division": 24 * N + 38,
            "checks_and_state": 4 * N + 5 + 4 * N + 3 * N + 1,
        }
    else:
        raise ValueError(f"route must be 'auto', 'n3' or 'generic', got {route!r}")
    parts["total"] = sum(parts.values())
    return parts


