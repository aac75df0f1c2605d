"""The compiled route of the real two-point map, seen from the method layer (private).

The **only** place outside :mod:`jetgaudin.backlund.kernels` that reaches the Numba kernels: the maps, the
ensemble driver and the run layer call :func:`kernels`.  The ``kernel="auto"`` choice and the loaded / cached /
cold state of the kernels live with the kernels (:mod:`jetgaudin.backlund.kernels._select`).
"""

from __future__ import annotations

from types import ModuleType

__all__ = ["kernels"]


_package: list[ModuleType] = []


def kernels() -> ModuleType:
    """The compiled kernels' package (its drivers import Numba at their first call); imported once, then kept (an
    import statement costs a few µs on every short call)."""
    if not _package:
        from . import kernels as _k

        _package.append(_k)
    return _package[0]
