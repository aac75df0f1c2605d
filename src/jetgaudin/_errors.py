"""One exception hierarchy for jetgaudin.

Every error raised on bad input or at a singular configuration derives from
:class:`JetGaudinError` (itself a :class:`ValueError`, so ``except ValueError``
keeps working).  Messages name the offending quantity and say how to fix it.
"""

from __future__ import annotations

__all__ = [
    "JetGaudinError",
    "InvalidStateError",
    "InvalidParameterError",
    "SingularStepError",
    "BranchPointError",
    "OffLeafError",
    "IntegrationError",
    "RecordingError",
]


class JetGaudinError(ValueError):
    """Base class of every jetgaudin error."""


class InvalidStateError(JetGaudinError):
    """A state array has the wrong shape or non-finite entries."""


class InvalidParameterError(JetGaudinError):
    """A parameter (N, b, eta, c_k, tolerances, ...) is out of its domain."""


class SingularStepError(JetGaudinError):
    """A Bäcklund step hits a vanishing denominator (v(eta) = 0, s + kappa = 0, ...)."""


class BranchPointError(JetGaudinError):
    """nu(lambda) vanishes at, or its continuation path passes through, a branch point."""


class OffLeafError(JetGaudinError):
    """A state is not on the symplectic leaf a map is defined on."""


class IntegrationError(JetGaudinError):
    """A continuous-time integration failed (step size underflow, backend error, ...)."""


class RecordingError(JetGaudinError):
    """A run directory cannot be written, read or resumed (unwritable, corrupted, inconsistent)."""
