"""What every map of a chain model shares (private): the state length, the integrals and the names the run layer writes,
all the model's (a map with a ``model`` attribute); and the registry through which a model reaches its maps.

**The registry** (issue 33: no import circle through more than two files, function-level imports included).  A model
builds its maps (``model.two_point_backlund``, ``exact_flow``, the su(n) class of ``GaudinModel(..., algebra=)``)
without importing the modules that define them, which import the model: each of those modules registers its class
here when it is imported (:func:`register_model_map`), and :func:`model_map` looks it up.  ``jetgaudin.gaudin``
imports them all, and a model module is only ever imported through that package, so the table is full before a model
exists (a lookup that misses imports the package by name, as :func:`jetgaudin.maps.map_from_description` does)."""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np

__all__ = ["ModelMap", "register_model_map", "model_map"]

_MODEL_MAPS: dict[str, Any] = {}


def register_model_map(kind: str, factory: Any) -> None:
    """Register the class (or factory) ``factory`` under ``kind`` (``"chain_two_point"``, ``"chain_one_point"``,
    ``"sun_model"``, ``"sun_two_point"``, ``"sun_exact"``)."""
    _MODEL_MAPS[kind] = factory


def model_map(kind: str) -> Any:
    """The class registered under ``kind`` (module doc)."""
    if kind not in _MODEL_MAPS:
        importlib.import_module("jetgaudin.gaudin")  # its import registers every kind (by name: no import circle)
    return _MODEL_MAPS[kind]


class ModelMap:
    """Mixin for a :class:`jetgaudin.maps.Map` with a ``model`` (a :class:`~jetgaudin.GaudinModel`, any algebra):
    :attr:`n_state`, :meth:`integrals`, :meth:`integral_names` (the run layer's reports), :meth:`state_labels` (the
    run layer's ``orbit.csv`` columns) are the model's."""

    model: Any

    @property
    def n_state(self) -> int:
        return int(self.model.n_state)

    def integrals(self, X) -> np.ndarray:
        """The model's integrals (its ``integral_labels``), shape ``(..., n_integrals)``."""
        return self.model.integrals(X)

    def integral_names(self) -> list[str]:
        return self.model.integral_labels()

    def state_labels(self) -> list[str]:
        return self.model.labels()
