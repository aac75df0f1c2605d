"""Numerical health of a run: drift of the preserved integrals, the radius ``|y_{N-1}|`` and the imaginary residue
(private; the one home of these checks)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..maps import Map
from .spec import HealthLimits, block_size, integral_names, model_of


@dataclass
class Failure:
    """The first breach met: ``reason`` (one line) and ``index`` of the first bad row in the rows checked."""

    reason: str
    index: int


class Health:
    """Running maxima over the checked states of a run: ``drift`` ``(..., k)`` = ``max |I(X_n) − I(X_0)|``
    (absolute; relative to ``max(1, |I(X_0)|)`` for the check), ``sphere`` = ``max ||y_{N-1}(n)| − |y_{N-1}(0)||``
    (a Casimir, ``√C_N``) and ``imag`` = the largest imaginary residue."""

    def __init__(self, map_: Map, X0: np.ndarray, limits: HealthLimits, *, I0: np.ndarray | None = None,
                 I0_of_X0: np.ndarray | None = None):
        """``I0``: the integrals to compare with (a resume's, from ``run.json``); ``I0_of_X0``: ``map_.integrals(X0)``
        computed already (the run spec's check: :meth:`jetgaudin.run.RunSpec.integrals0`); neither: computed here."""
        self.map, self.limits = map_, limits
        if I0 is None and I0_of_X0 is not None:
            I0 = I0_of_X0
        #: the states ``I0`` was computed from (``None`` when ``I0`` was given): :meth:`check_start` need not recompute
        self._X0 = np.asarray(X0) if I0 is None or I0_of_X0 is not None else None
        self.I0 = np.asarray(map_.integrals(X0), dtype=float) if I0 is None else np.asarray(I0, dtype=float)
        self.scale = np.maximum(1.0, np.abs(self.I0))
        self.drift = np.zeros_like(self.I0)
        self.d = block_size(map_)  # the last block y_{N-1} (3 components; su(n): n² − 1)
        self.r0 = np.linalg.norm(np.asarray(X0)[..., -self.d:], axis=-1)
        self.sphere = 0.0
        self.imag = 0.0
        k = self.I0.shape[-1]
        named = getattr(map_, "integral_names", None)  # a map may name its integrals (the chains: h{i},{m})
        if named is None and model_of(map_) is not None:  # a map of a chain's Hamiltonian (midpoint): the model's
            named = model_of(map_).integral_labels
        self.names = list(named()) if callable(named) else (
            integral_names(k // 2) if k % 2 == 0 else [f"I_{i + 1}" for i in range(k)])

    @property
    def relative(self) -> np.ndarray:
        """``drift / max(1, |I(X_0)|)``, shape ``(..., k)``."""
        return self.drift / self.scale

    def check(self, steps: list[int], S: np.ndarray, *, record: bool = True) -> Failure | None:
        """Check the states ``S`` ``(m, ..., n)`` reached at ``steps``; update the maxima with the rows up to the
        first bad one; return the first breach or ``None``.  ``record=False`` (a state that is not saved, e.g. the
        end of a kernel call off the save grid, where calls end by the clock): checked, but the maxima are updated
        only if it breaches, so the reported drift is that of the saved rows, the same at any call length."""
        if len(steps) == 0:
            return None
        S = np.asarray(S)
        with np.errstate(all="ignore"):
            d = np.abs(self.map.integrals(S) - self.I0)
            sph = np.abs(np.linalg.norm(S[..., -self.d:], axis=-1) - self.r0)
        rel = d / self.scale
        rows = rel.reshape(len(steps), -1)
        bad_row = ~np.all(np.isfinite(rows), axis=1) | np.any(rows > self.limits.max_drift, axis=1)
        first = int(np.argmax(bad_row)) if np.any(bad_row) else len(steps)
        if first == len(steps) and not record:
            return None
        upto = min(first + 1, len(steps))
        fin = np.where(np.isfinite(d[:upto]), d[:upto], 0.0)
        self.drift = np.maximum(self.drift, fin.max(axis=0))
        self.sphere = max(self.sphere, float(np.nan_to_num(sph[:upto]).max()))
        if first == len(steps):
            return None
        where = self._where(rel[first])
        if not np.all(np.isfinite(rel[first])):
            return Failure(f"non-finite integrals{where[0]} at step {steps[first]}", first)
        orbit, k = where[1], where[2]
        return Failure(
            f"integral drift: {self.names[k]}{orbit} drifted by {float(rel[first][where[3]]):.4e} (relative to "
            f"max(1, |I(0)|)) at step {steps[first]} > max_drift {self.limits.max_drift:g}", first)

    def check_start(self, X: np.ndarray) -> Failure | None:
        """Check the run's first row, the states ``X`` at step 0: as :meth:`check` of ``[0]``.  Where ``I0`` and ``r0``
        were computed here from states equal to ``X`` (a new run), that check is known without computing: the same
        function of the same numbers gives the same bits, so every drift and the radius deviation are exactly 0 --
        no breach when ``I0`` and ``r0`` are finite, and no maximum moves (they start at 0).  At 10⁷ orbits this
        saves the integrals of the whole ensemble once more (seconds on the host)."""
        X = np.asarray(X)
        if (self._X0 is not None and X.shape == self._X0.shape and np.array_equal(X, self._X0)
                and np.all(np.isfinite(self.I0)) and np.all(np.isfinite(self.r0))):
            return None
        return self.check([0], X[None])

    def check_end(self, step: int, X: np.ndarray) -> Failure | None:
        """Check the end state ``X`` ``(..., n)`` of a kernel call off the save grid (reached at ``step``): as
        :meth:`check` with ``record=False`` (the maxima move only on a breach).  A separate entry so that a route
        keeping its states elsewhere (the GPU's, :mod:`jetgaudin.gpu._resident`) checks them there."""
        return self.check([step], np.asarray(X)[None], record=False)

    def _where(self, rel_row: np.ndarray):
        bad = ~np.isfinite(rel_row) | (rel_row > self.limits.max_drift)
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        orbit = f" of orbit {idx[0]}" if rel_row.ndim == 2 else ""
        return orbit, orbit, idx[-1], idx

    def check_imag(self, step: int, imag: np.ndarray) -> str | None:
        """Record the imaginary residue of the step to ``step``; the breach of ``max_imag`` or ``None``."""
        im = float(np.max(imag)) if np.size(imag) else 0.0
        self.imag = max(self.imag, im)
        if im > self.limits.max_imag:
            return f"imaginary residue {im:.3e} of the real map at step {step} > max_imag {self.limits.max_imag:g}"
        return None
