"""Compatibility module: the compiled kernels live in the package :mod:`jetgaudin.backlund.kernels`.

Re-exports its drivers and status codes under the old names (``from jetgaudin.backlund import _kernels``); the
raw compiled functions (``run_orbit``, ``run_orbit3``, ``run_lanes3``, ``run_batch_generic``, ``LANES``) are
reached lazily, as attributes of the package.  New code imports :mod:`jetgaudin.backlund.kernels`.
"""

from __future__ import annotations

from typing import Any

from . import kernels as _pkg
from .kernels import (  # noqa: F401
    STATUS_BRANCH,
    STATUS_MESSAGES,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_RESIDUAL,
    check_counts,
    closed_form_orbit,
    flops_per_step,
    iterate_batch,
    iterate_single,
    nu_default,
    run_batch,
    run_ensemble,
    saved_count,
    status_error,
)


def __getattr__(name: str) -> Any:
    return getattr(_pkg, name)
