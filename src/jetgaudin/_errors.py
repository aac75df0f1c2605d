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
    "KernelSetupError",
    "SingularStepError",
    "BranchPointError",
    "OffLeafError",
    "IntegrationError",
    "StepTooLargeError",
    "MapDescriptionError",
    "OutputTooLargeError",
    "RecordingError",
    "RunDirectoryError",
    "RunLockedError",
    "RunIOError",
]


class JetGaudinError(ValueError):
    """Base class of every jetgaudin error."""


class InvalidStateError(JetGaudinError):
    """A state array has the wrong shape or non-finite entries."""


class InvalidParameterError(JetGaudinError):
    """A parameter (N, b, eta, c_k, tolerances, ...) is out of its domain."""


class KernelSetupError(InvalidParameterError):
    """The compiled kernels cannot start in this environment (Numba rejects a ``NUMBA_*`` setting): not a fault of
    any argument (the CLI names no option for it)."""


class SingularStepError(JetGaudinError):
    """A Bäcklund step hits a vanishing denominator (v(eta) = 0, s + kappa = 0, ...)."""


class BranchPointError(JetGaudinError):
    """nu(lambda) vanishes at, or its continuation path passes through, a branch point."""


class OffLeafError(JetGaudinError):
    """A state is not on the symplectic leaf a map is defined on."""


class IntegrationError(JetGaudinError):
    """A continuous-time integration failed (step size underflow, backend error, ...)."""


class StepTooLargeError(InvalidParameterError):
    """An exact time step (:class:`jetgaudin.ExactFlow`) has no well-conditioned set of Bäcklund parameters on this
    orbit's leaf: ``dt`` is larger than ``dt_max`` (the attribute; ``None`` where it was not computed).  Give a
    smaller ``dt`` or more ``substeps``."""

    def __init__(self, message: str, dt_max: float | None = None):
        super().__init__(message)
        self.dt_max = dt_max


class MapDescriptionError(InvalidParameterError):
    """A map description (:func:`jetgaudin.map_from_description`, ``run.json``'s ``map``) lacks a key or holds a
    value of the wrong kind; ``key`` names it (``None`` where the builder did not say which)."""

    def __init__(self, message: str, key: str | None = None):
        super().__init__(message)
        self.key = key


class OutputTooLargeError(InvalidParameterError):
    """An array a call would return (``solve``, ``iterate``) is larger than the cap (:data:`jetgaudin.maps.
    MAX_OUTPUT_BYTES`, overridable): ``nbytes`` it would take, ``cap`` the limit.  Save fewer rows (``save_every``)
    or a shorter span, or run it through the run layer (``jetgaudin.run``), which streams rows to disk."""

    def __init__(self, message: str, nbytes: int = 0, cap: int = 0):
        super().__init__(message)
        self.nbytes, self.cap = nbytes, cap


class RecordingError(JetGaudinError):
    """A run directory cannot be written, read or resumed (unwritable, corrupted, inconsistent)."""


class RunDirectoryError(RecordingError):
    """A run directory (or a file in it) is refused: it holds another run or foreign files, a file in it is a
    symbolic link, a FIFO or too large, or it cannot be created.  Nothing has been written (CLI exit code 2)."""


class RunLockedError(RunDirectoryError):
    """Another process holds the run directory's lock (one writer per run directory)."""


class RunIOError(RecordingError):
    """Writing a run failed (I/O error, full disk): the run ends as failed with its last durable checkpoint
    (CLI exit code 1, not 2: the input was fine)."""
