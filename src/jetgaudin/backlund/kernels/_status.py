"""Status codes returned by the kernels (they never raise) and the typed exception for each."""

from __future__ import annotations

__all__ = ["STATUS_OK", "STATUS_BRANCH", "STATUS_RESIDUAL", "STATUS_NONFINITE", "STATUS_MESSAGES", "status_error"]

STATUS_OK = 0
STATUS_BRANCH = 1
STATUS_RESIDUAL = 4
STATUS_NONFINITE = 5

STATUS_MESSAGES = {
    STATUS_BRANCH: "l(eta) vanishes (eta is a double branch point of nu): the eigenvector of the Bäcklund step is "
    "undefined; change eta",
    STATUS_RESIDUAL: "the dressing division left a remainder above 1e-8 (relative); the step is numerically "
    "singular (eta close to a branch point or a vanishing denominator)",
    STATUS_NONFINITE: "the step produced non-finite values; change eta",
}


def status_error(status: int, fail: int, orbit: int | None = None) -> Exception:
    """The exception for a kernel status: :class:`jetgaudin.BranchPointError` (``STATUS_BRANCH``) or
    :class:`jetgaudin.SingularStepError` (the others), naming the failing step (and orbit)."""
    from ..._errors import BranchPointError, SingularStepError

    where = f" at step {int(fail)}" + ("" if orbit is None else f" of orbit {int(orbit)}")
    cls = BranchPointError if int(status) == STATUS_BRANCH else SingularStepError
    return cls(f"singular Bäcklund step{where} (compiled route): {STATUS_MESSAGES[int(status)]}")
