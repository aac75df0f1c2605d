"""The registry of checks behind ``jetgaudin verify`` (data structures and the runner).

A :class:`Check` is one proposition, lemma or displayed formula of the paper.  Its function
receives a :class:`Context` (seeded random source, precision, ``full`` flag) and returns an
:class:`Outcome`: the verdict on the formula **as printed** and, for a misprint, the verdict
on **our correction**.  :func:`run_checks` times each check and returns :class:`CheckResult`
records; ``docs/errata.md`` is generated from the checks that declare an :class:`Erratum`.
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import random
import re
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = [
    "HOLDS",
    "FAILS",
    "UNDECIDED",
    "Verdict",
    "Outcome",
    "Erratum",
    "MISPRINT",
    "INTERPRETATION",
    "Check",
    "CheckResult",
    "Context",
    "REGISTRY",
    "register",
    "run_checks",
    "select",
    "DEFAULT_SEED",
    "MODULES",
    "load_all",
    "errata_entries",
    "exact_for_each",
    "exact_pair_for_each",
]

#: the modules holding the checks, in the paper's order (the order of docs/errata.md)
MODULES = ("structure", "sec2", "sec4", "sec5", "sec6", "maps", "appendix", "chains", "trigonometric",
           "elliptic", "sun")

HOLDS, FAILS, UNDECIDED = "holds", "fails", "undecided"
DEFAULT_SEED = 20261122

#: relative tolerance for "holds" at 50-digit points: round-off of a 50-digit evaluation of a
#: rational expression is ~1e-45; 1e-30 leaves a wide margin while a genuine misprint gives O(1).
NUMERIC_TOL = 1e-30


@dataclass(frozen=True)
class Verdict:
    """``status`` in {holds, fails, undecided}; ``residual`` the largest relative residual of a 50-digit
    check, or for an exact SymPy check 0 (an identity) / 1 (not an identity: a nonzero remainder);
    ``None`` when not measured; ``note`` a short explanation."""

    status: str
    residual: float | None = None
    note: str = ""

    @staticmethod
    def from_residual(residual, tol: float = NUMERIC_TOL, note: str = "") -> Verdict:
        r = float(residual)
        return Verdict(HOLDS if r <= tol else FAILS, r, note)

    @staticmethod
    def exact(flag: bool, note: str = "") -> Verdict:
        """The verdict of an exact (SymPy) check: residual 0 when the identity holds, 1 when it does not."""
        return Verdict(HOLDS if flag else FAILS, 0.0 if flag else 1.0, note)


@dataclass(frozen=True)
class Outcome:
    printed: Verdict
    corrected: Verdict | None = None


def exact_for_each(cases, holds: Callable[[Any], bool], note: str = "") -> Outcome:
    """The outcome of an exact identity decided case by case (e.g. for ``N = 1..5``): it holds iff
    ``holds(case)`` is true for every case (the cases after a failing one are not computed)."""
    return Outcome(Verdict.exact(all(holds(c) for c in cases), note))


def exact_pair_for_each(cases, holds: Callable[[Any], tuple[bool, bool]]) -> Outcome:
    """The outcome of a printed formula and its correction decided case by case: ``holds(case) -> (printed
    holds, corrected holds)``; each verdict holds iff it holds in every case."""
    verdicts = [holds(c) for c in cases]
    return Outcome(Verdict.exact(all(p for p, _ in verdicts)), Verdict.exact(all(c for _, c in verdicts)))


#: the kinds of an erratum: a located misprint (a sign, a factor, an index that the derivation fixes), or an
#: interpretation (a loose phrase read one way, or a correction fitted so that the statement holds: the check shows
#: that the reading works, not that it is what the authors meant)
MISPRINT, INTERPRETATION = "misprint", "interpretation"


@dataclass(frozen=True)
class Erratum:
    """One entry of ``docs/errata.md``: the formula as printed and our correction; ``kind`` :data:`MISPRINT` or
    :data:`INTERPRETATION`."""

    printed: str
    corrected: str
    comment: str = ""
    kind: str = MISPRINT

    def __post_init__(self) -> None:
        if self.kind not in (MISPRINT, INTERPRETATION):
            raise ValueError(f"Erratum kind must be {MISPRINT!r} or {INTERPRETATION!r}, got {self.kind!r}")


@dataclass(frozen=True)
class Context:
    seed: int
    label: str
    full: bool = False
    dps: int = 50

    def rng(self) -> random.Random:
        """A generator seeded by ``(seed, label)``: every check is reproducible on its own."""
        return random.Random(f"{self.seed}:{self.label}")

    @contextlib.contextmanager
    def precise(self) -> Iterator[random.Random]:
        """``with ctx.precise() as rng:`` the check's seeded generator (:meth:`rng`) with mpmath at the run's
        ``dps`` digits inside the block (the preamble of every high-precision check)."""
        import mpmath

        with mpmath.workdps(self.dps):
            yield self.rng()


@dataclass(frozen=True)
class Check:
    label: str
    section: str
    statement: str
    method: str
    func: Callable[[Context], Outcome]
    erratum: Erratum | None = None
    full_only: bool = False
    #: declared verdict on the printed formula (``fails`` for a confirmed misprint); the test suite
    #: asserts the run reproduces it, so a regression in either direction is caught
    expect_printed: str = HOLDS
    corrected_text: str = ""


@dataclass(frozen=True)
class CheckResult:
    label: str
    section: str
    statement: str
    method: str
    seed: int
    printed: str
    printed_residual: float | None
    corrected: str | None
    corrected_residual: float | None
    status: str
    expected_printed: str
    seconds: float
    note: str = ""
    erratum: dict | None = field(default=None)

    def to_dict(self) -> dict:
        return asdict(self)


REGISTRY: dict[str, Check] = {}


def load_all() -> None:
    """Import every check module (each registers its checks in :data:`REGISTRY` on import)."""
    for m in MODULES:
        importlib.import_module(f"{__package__}.{m}")


def paper_order(chk: Check) -> tuple[int, int]:
    """Stable order (module order of :data:`MODULES`, then position in the module), independent of the
    order in which other code happened to import the check modules."""
    func = inspect.unwrap(chk.func)  # the declared function, not a wrapper that a helper registered for it
    mod = func.__module__.rsplit(".", 1)[-1]
    return (MODULES.index(mod) if mod in MODULES else len(MODULES), func.__code__.co_firstlineno)


def erratum_heading(n: int, chk: Check) -> str:
    """The heading of entry ``n`` of ``docs/errata.md``."""
    where = f"Section {chk.section}" if chk.section[:1].isdigit() else chk.section
    kind = ", an interpretation" if chk.erratum is not None and chk.erratum.kind == INTERPRETATION else ""
    return f"{n}. `{chk.label}` ({where}{kind})"


def slug(heading: str) -> str:
    """The anchor GitHub (and most Markdown renderers) give a heading: lower case, punctuation dropped, spaces
    to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")


def errata_entries() -> dict[str, tuple[int, str]]:
    """``{label: (entry number, "docs/errata.md#anchor")}`` for every check with an erratum, in the file's order."""
    load_all()
    out = {}
    n = 0
    for chk in sorted(REGISTRY.values(), key=paper_order):
        if chk.erratum is not None:
            n += 1
            out[chk.label] = (n, "docs/errata.md#" + slug(erratum_heading(n, chk)))
    return out


def _erratum_dict(check: Check) -> dict | None:
    """The erratum as printed / corrected, with its entry in ``docs/errata.md`` (``entry``: number, ``link``)."""
    if check.erratum is None:
        return None
    n, link = errata_entries()[check.label]
    return dict(asdict(check.erratum), entry=n, link=link)


def register(
    label: str,
    section: str,
    statement: str,
    method: str,
    *,
    erratum: Erratum | None = None,
    full_only: bool = False,
):
    """Decorator adding a check to :data:`REGISTRY` (labels are unique).

    A check with an ``erratum`` declares a misprint: the formula as printed is expected to fail
    (``expect_printed = fails``), every other check's formula to hold as printed."""
    expect_printed = HOLDS if erratum is None else FAILS

    def deco(func):
        if label in REGISTRY:
            raise ValueError(f"duplicate check label {label!r}")
        REGISTRY[label] = Check(label, section, statement, method, func, erratum, full_only, expect_printed)
        return func

    return deco


def _overall(out: Outcome) -> str:
    if out.printed.status == HOLDS:
        return HOLDS
    if out.corrected is not None and out.corrected.status == HOLDS:
        return HOLDS
    if out.printed.status == UNDECIDED or (out.corrected is not None and out.corrected.status == UNDECIDED):
        return UNDECIDED
    return FAILS


def select(only) -> list[str]:
    """Labels selected by ``only``: each entry selects the check with exactly that label or, if there is none,
    its family (every label starting with ``entry-``, e.g. ``App1`` -> ``App1-A``, ``App1-B``, ``App1-X0``).
    Raises ``KeyError`` listing the entries that select nothing."""
    if isinstance(only, str):
        only = [only]
    chosen, unknown = set(), []
    for o in only:
        if o in REGISTRY:
            chosen.add(o)
            continue
        fam = [k for k in REGISTRY if k.startswith(o + "-")]
        if not fam:
            unknown.append(o)
        chosen.update(fam)
    if unknown:
        raise KeyError(", ".join(unknown))
    return [k for k in REGISTRY if k in chosen]


def run_checks(only=None, full: bool = False, seed: int = DEFAULT_SEED, dps: int = 50) -> list[CheckResult]:
    """Run the registered checks and return one :class:`CheckResult` per check.

    ``only``: a label or a list of labels (see :func:`select`; unknown labels raise ``KeyError``);
    ``full`` adds the heavier checks; ``seed`` makes the random points reproducible.  The overall
    ``status`` is ``holds`` when the formula holds as printed or after its documented correction.
    """
    load_all()
    chosen = None if only is None else set(select(only))
    results = []
    for check in REGISTRY.values():
        if chosen is not None and check.label not in chosen:
            continue
        if check.full_only and not full and only is None:
            continue
        ctx = Context(seed=seed, label=check.label, full=full, dps=dps)
        t0 = time.perf_counter()
        try:
            out = check.func(ctx)
        except Exception as exc:  # a crashing check is undecided, never silently "holds"
            tb = traceback.format_exception_only(type(exc), exc)[-1].strip()
            out = Outcome(Verdict(UNDECIDED, None, f"check raised {tb}"))
        dt = time.perf_counter() - t0
        note = "; ".join(x for x in (out.printed.note, out.corrected.note if out.corrected else "") if x)
        results.append(
            CheckResult(
                label=check.label,
                section=check.section,
                statement=check.statement,
                method=check.method,
                seed=seed,
                printed=out.printed.status,
                printed_residual=out.printed.residual,
                corrected=out.corrected.status if out.corrected else None,
                corrected_residual=out.corrected.residual if out.corrected else None,
                status=_overall(out),
                expected_printed=check.expect_printed,
                seconds=round(dt, 3),
                note=note,
                erratum=_erratum_dict(check),
            )
        )
    return results
