"""What every map of a chain model shares (private): the state length, the integrals and the names the run layer writes,
all the model's (a map with a ``model`` attribute)."""

from __future__ import annotations

from typing import Any

import numpy as np


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
