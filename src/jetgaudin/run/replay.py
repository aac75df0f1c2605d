"""Replay: a resume re-steps the end of the recorded orbit with the recorded map before it continues (private).

A digest detects accidents, not edits: whoever edits ``run.json`` can recompute it.  What an editor cannot make
consistent without running the map themselves is the orbit: every checkpoint records the *anchor* ``(n_a, X_a,
ν_a)``, where the kernel call that produced the last saved row started, and a resume re-steps from the anchor to
the checkpoint with the map rebuilt from ``run.json``, in kernel calls cut as :func:`jetgaudin.run.driver.piece`
cuts them, and requires, bit for bit (``np.array_equal``):

* the last two rows on the recorded save grid (row ``i`` at step ``i · save_every``, the last possibly at the last
  step), and every saved row the replay passes (``n_a ≤ n ≤ n_last``) equal to the stored row (step and state);
* the state and ``ν1`` reached at the checkpoint's step equal to the checkpoint's.

So a checkpoint state moved by one ulp, a checkpoint step moved by one, a checkpoint pushed off its rows, or a map
parameter (``b``, ``η``, the branch, the kernel, a chain's sites, ``save_every``) changed by 1e-12 are refused:
each changes the bits of at least one replayed step.  The maps this applies to are those whose ``advance`` gives
the same bits however a run is cut (``chunk_invariant``, the Bäcklund maps); a flow is replayed in the fixed chunks
of its save grid only where the anchor is on that grid.  Cost: at most one kernel call (about 0.1 s) plus the steps
from the last saved row to the checkpoint (at most one save interval).

A map whose set-up is solved once per run (the su(3) exact step's parameters, :func:`jetgaudin.run.spec.run_map`)
was solved at the start of every kernel call by the code before that: a directory written then does not replay
with the parameters of ``X0``.  It is replayed the old way too, and resumed that way to the end when that way
reproduces its rows (``run.json`` records ``map_setup: "per_chunk"``, so a second resume takes it at once); a run
neither way reproduces is refused.

What replay cannot detect (``docs/reliability.md``): a forgery made by running the map (an anchor and a checkpoint
computed consistently from a changed state between rows), edits of fields that do not change a bit of the orbit
(``steps``, ``max_drift``, ``max_imag``, timings), and rows before the anchor (those are covered by the rows'
SHA-256 digest, which detects accidents only).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from .._errors import JetGaudinError, RecordingError
from .driver import Position, piece
from .spec import RunSpec, binds_per_run, run_map

#: steps of one replayed kernel call, in save intervals (bounds the rows held: at most this many)
_ROWS_PER_CALL = 4096
#: a replay may take this many times longer than the recorded run took for the same steps (its recorded rate), and
#: at least :data:`REPLAY_MIN_SECONDS`, before it is refused as not the recorded map (a kernel edited from compiled
#: to NumPy: about 100 times slower; before, its replay ran for minutes before the rows told it apart)
REPLAY_SLOWDOWN = 20.0
REPLAY_MIN_SECONDS = 3.0


def _same(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(np.asarray(a, dtype=complex), np.asarray(b, dtype=complex)))


class _Mismatch(Exception):
    """The replayed map does not reach the stored rows or the checkpoint, bit for bit."""


def replay(store: Any, spec: RunSpec, pos: Position, anchor: tuple[int, np.ndarray, Any] | None, where: str, *,
           recorded_rate: float | None = None) -> RunSpec:
    """Refuse (:class:`jetgaudin.RecordingError`) a checkpoint ``pos`` that the recorded map does not reach from
    ``anchor`` through the stored rows ``store.dn``/``store.dS`` (``store.rows`` of them), bit for bit; see the
    module doc.  ``where``: the file named in the message.  ``recorded_rate``: the recorded run's steps per second;
    a replay slower than :data:`REPLAY_SLOWDOWN` times it (and than :data:`REPLAY_MIN_SECONDS`) is refused: the map
    is not the one that wrote the rows (e.g. its kernel was edited).

    Returns the spec to resume with: ``spec``, or, for a map whose set-up is solved once per run
    (:func:`jetgaudin.run.spec.binds_per_run`: the su(3) exact step) whose rows that does not reproduce, the spec
    solving it at every kernel call (``_per_chunk_setup``: how such runs were written before) when *that* reproduces
    them bit for bit; a run neither reproduces is refused as above."""
    bad = RecordingError(f"{where}: the checkpoint does not match the saved rows replayed with the recorded map "
                         "(edited or corrupted: state, step or map parameters); cannot resume")
    try:
        _replay(store, spec, pos, anchor, where, recorded_rate)
        return spec
    except _Mismatch:
        if not binds_per_run(spec):
            raise bad from None
    old = dataclasses.replace(spec, _per_chunk_setup=True)
    try:
        _replay(store, old, pos, anchor, where, recorded_rate)
    except _Mismatch:
        raise bad from None
    return old


def _replay(store: Any, spec: RunSpec, pos: Position, anchor: tuple[int, np.ndarray, Any] | None, where: str,
            recorded_rate: float | None) -> None:
    """:func:`replay` with the map :func:`jetgaudin.run.spec.run_map` gives ``spec``: raises :class:`_Mismatch`
    where the bits differ (:class:`jetgaudin.RecordingError` for the other refusals)."""
    bad = _Mismatch()
    rows, every = store.rows, spec.save_every
    if rows < 1:  # nothing durable yet: the run starts again from X0
        if pos.n != 0 or not np.array_equal(pos.X, spec.X0):
            raise bad
        return
    if anchor is None:
        raise RecordingError(f"{where}: the checkpoint has no replay anchor (written by an older jetgaudin, or "
                             "edited); cannot verify it, so cannot resume: start a new run (--init-from DIR)")
    n_a, X, carry = anchor
    n_last = int(store.dn[rows - 1])
    if not (0 <= n_a <= n_last <= pos.n <= spec.steps) or np.shape(X) != np.shape(pos.X):
        raise bad
    # the rows lie on the recorded save grid: row i at step i * save_every, the last one possibly at the last step
    on_grid = n_last == (rows - 1) * every or (n_last == spec.steps and (rows - 2) * every < n_last)
    if not on_grid or (rows >= 2 and int(store.dn[rows - 2]) != (rows - 2) * every):
        raise bad
    if n_a % every == 0 and n_a // every < rows and (int(store.dn[n_a // every]) != n_a or not np.array_equal(
            np.asarray(store.dS[n_a // every]), X)):
        raise bad
    invariant = getattr(spec.map, "chunk_invariant", True)
    # a map that is not chunk invariant (a flow) is replayed in the driver's own fixed cuts
    L, end = (_ROWS_PER_CALL * every, pos.n) if invariant else (every * max(1, 256 // every), spec.steps)
    budget = np.inf if not recorded_rate else max(REPLAY_MIN_SECONDS, REPLAY_SLOWDOWN * (pos.n - n_a) / recorded_rate)
    t0 = time.monotonic()
    grow = 16  # an invariant map is replayed in growing calls: the time budget is checked early
    n = n_a
    try:
        while n < pos.n:
            if time.monotonic() - t0 > budget:
                raise RecordingError(
                    f"{where}: replaying the last {pos.n - n_a} steps takes more than {budget:.3g} s, over "
                    f"{REPLAY_SLOWDOWN:g} times the recorded run's rate: the map or kernel in run.json is not the one "
                    "that wrote the rows (edited?); cannot resume")
            k, se = piece(n, min(L, grow) if invariant else L, end, every)
            grow *= 2
            with np.errstate(all="ignore"):
                adv = run_map(spec).advance(X, carry, k, se)
            whole = se == every and k >= every
            done = range(n + every, n + k + 1, every) if whole else [n + k]
            for m, row in zip(done, adv.rows if whole else adv.rows[-1:], strict=True):
                if m <= n_last and (m % every == 0 or m == spec.steps):
                    i = m // every if m % every == 0 else rows - 1
                    if i >= rows or int(store.dn[i]) != m or not np.array_equal(np.asarray(store.dS[i]), row):
                        raise bad
            n, X, carry = n + k, adv.X, adv.carry
    except RecordingError:
        raise
    except JetGaudinError:
        raise _Mismatch() from None
    if n != pos.n or not np.array_equal(np.asarray(X), pos.X) or not _same(carry, pos.carry):
        raise bad
