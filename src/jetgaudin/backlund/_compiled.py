"""The compiled route of the real two-point map, seen from the method layer (private).

The **only** module that imports the Numba kernels (:mod:`jetgaudin.backlund._kernels`): the maps, the
ensemble driver and the run layer reach them through :func:`kernels`; :func:`kernel_state` tells whether
they are loaded or cached (for :func:`jetgaudin.backlund.auto_kernel`).  Repoint
``_KERNELS_MODULE`` (and the import in :func:`kernels`) when the kernels move.
"""

from __future__ import annotations

import glob
import os
import sys
from types import ModuleType

__all__ = ["kernels", "kernel_names", "kernel_state"]

#: the module holding the compiled drivers (iterate_single, iterate_batch, run_batch, nu_default, status_error)
_KERNELS_MODULE = "jetgaudin.backlund._kernels"


def kernels() -> ModuleType:
    """The compiled kernels' module (imports Numba on first call)."""
    from . import _kernels

    return _kernels


def kernel_names(n_state: int, batch: bool) -> tuple[str, ...]:
    """The compiled functions a run of this shape calls (see ``iterate_single/iterate_batch``)."""
    if batch:
        return ("run_ensemble", "_nu_default_serial")
    return ("run_orbit3" if n_state == 9 else "run_orbit", "_nu_default_serial")


def kernel_state(names: tuple[str, ...]) -> str:
    """``"loaded"`` (compiled in this process), ``"cached"`` (index files in Numba's cache) or ``"cold"``.

    Looks at the files only (no Numba import): Numba caches next to the source in ``__pycache__`` when that
    is writable, else under ``NUMBA_CACHE_DIR`` or the user-wide cache directory.  A wrong guess costs time,
    never correctness: both routes give the same orbits to round-off.
    """
    mod = sys.modules.get(_KERNELS_MODULE)
    if mod is not None and all(getattr(getattr(mod, n, None), "signatures", None) for n in names):
        return "loaded"
    spec_dir = os.path.dirname(os.path.abspath(__file__))
    stem = _KERNELS_MODULE.rsplit(".", 1)[-1]
    in_tree = os.path.join(spec_dir, "__pycache__")
    elsewhere = [d for d in (os.environ.get("NUMBA_CACHE_DIR"), os.path.expanduser("~/.cache/numba")) if d]
    for n in names:
        pattern = f"{stem}.{n}-*.nbi"
        if not (glob.glob(os.path.join(in_tree, pattern))
                or any(glob.glob(os.path.join(d, "**", pattern), recursive=True) for d in elsewhere)):
            return "cold"
    return "cached"
