"""Shared pieces of the command line: input parsing, one-line errors, progress, summary tables (private).

No mathematics here: everything numerical comes from the public API (``import jetgaudin as jg``).
"""

from __future__ import annotations

import contextlib
import errno
import math
import re
import sys
import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

#: Appendix 2 of the paper: field b, Bäcklund parameter eta, number of steps, (y, x, z)(0)
APPENDIX2_B = 1.0
APPENDIX2_ETA = "5+0.1i"
APPENDIX2_STEPS = 1000
APPENDIX2_INIT = "-2.4,-0.6,-1.2,-2.19,0.89,1.34,1,0,0"

#: largest jet order the command line accepts: the spectral polynomial has degree 2N and its evaluation
#: at |eta| ~ 5 overflows or loses all precision well before N ~ 256 (the library API has no such cap)
MAX_N = 128

EXIT_INPUT = 2  # bad input / unusable directory (click's usage-error code)
EXIT_FAILED = 1  # the run started but failed (singular step, health check)


class Branch(StrEnum):
    """``--branch``: the default root ν(η) of the branch rule, or the opposite one (the inverse map); an su(n) chain
    (``--algebra``): ``r`` = 0..n−1, the r-th largest eigenvalue μ_r (su(2): 0 = default, 1 = opposite)."""

    default = "default"
    opposite = "opposite"
    r0, r1, r2, r3, r4, r5, r6, r7 = "0", "1", "2", "3", "4", "5", "6", "7"


# Options shared by every command that writes a run directory: one definition, one help text.
OverwriteOption = Annotated[
    bool, typer.Option("--overwrite", help="replace the run (or files) in --out instead of refusing (never a run in "
                       "progress)")
]
ProgressOption = Annotated[
    bool | None,
    typer.Option("--progress/--no-progress", help="progress bar [default: on a terminal, for runs over 1 s]"),
]
NoPlotsOption = Annotated[bool, typer.Option("--no-plots", help="do not draw the figures")]
CheckpointOption = Annotated[
    float, typer.Option("--checkpoint-seconds", help="write a checkpoint at most this often (seconds)")
]
SaveEveryOption = Annotated[
    str | None, typer.Option("--save-every", metavar="INTEGER", help="save every k-th step (and the last) [default: 1]")
]
InitFromOption = Annotated[
    str | None,
    typer.Option("--init-from", help="start from the last saved state(s) of this run directory (an orbit run: also "
                 "its b, eta and branch unless given)"),
]
ResumeOption = Annotated[
    str | None, typer.Option("--resume", help="continue the interrupted or killed run in this directory")
]

class CliInputError(Exception):
    """Bad command-line input: reported as one line on stderr, exit code 2."""


#: largest |b| and |eta| the command line accepts: b^2 and the powers of eta in nu(eta)^2 stay representable
MAX_SCALE = 1e150


def complex_text(z) -> str:
    """A complex number with 17 significant digits in each part (round-trips exactly): ``a + b i``."""
    z = complex(z)
    return f"{z.real:.17g} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.17g} i"


def one_line(msg) -> str:
    return re.sub(r"\s+", " ", str(msg)).strip()


def prog() -> str:
    """``jetgaudin <command>`` of the command being run (``jetgaudin`` outside a command)."""
    try:  # typer >= 0.24 vendors click as typer._click (its own context stack)
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover
        from click import get_current_context  # type: ignore[no-redef]

    ctx = get_current_context(silent=True)
    return f"jetgaudin {ctx.info_name}" if ctx is not None and ctx.parent is not None else "jetgaudin"


def fail(msg, code: int = EXIT_INPUT):
    """Print ``jetgaudin <command>: error: <msg>`` (one line) on stderr and exit with ``code``."""
    typer.echo(f"{prog()}: error: {one_line(msg)}", err=True)
    raise typer.Exit(code)


class blame:  # noqa: N801 - a context manager: ``with blame("--b"): ...``
    """Report a library error raised inside as bad input of ``option``: the library decides the rule, the command
    line names the option (``--b: the field strength b must be nonzero ...``)."""

    def __init__(self, option: str):
        self.option = option

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        import jetgaudin as jg

        if exc_type is not None and issubclass(exc_type, jg.JetGaudinError) and not isinstance(
                exc, (jg.RecordingError, jg.KernelSetupError)):
            raise CliInputError(f"{self.option}: {one_line(exc)}") from None
        return False


#: a decimal number as the command line writes it: ASCII digits only (``float`` also reads Unicode digits such as
#: ``١.٥`` and underscores such as ``1_0``, which are refused), an optional sign, fraction and exponent
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:inf|infinity|nan)", re.ASCII | re.IGNORECASE)


def to_float(text, what: str) -> float:
    """``float(text)`` for a plain ASCII decimal number (:data:`_NUMBER`); ``ValueError`` naming ``what`` otherwise."""
    s = str(text).strip()
    if not _NUMBER.fullmatch(s):
        raise ValueError(f"{what}: cannot read {text!r} as a number")
    return float(s)


def parse_eta(text: str, option: str = "--eta", *, pole_at_zero: bool = True) -> complex:
    """``5+0.1i``, ``5+0.1j``, ``5 + 0.1 i``, ``0.1i``, ``5`` -> complex (finite).  ``pole_at_zero=False`` (a chain
    without a site at 0: the map checks ``Re η`` against its sites) accepts ``Re η = 0``."""
    s = re.sub(r"\s+", "", str(text)).lower()
    if s.endswith("i"):
        s = s[:-1] + "j"
    if re.fullmatch(r"(.*[+-])?j", s):  # "5+i" -> "5+1j"
        s = s[:-1] + "1j"
    if s.count("j") > 1 or not re.fullmatch(r"[0-9eE.+\-j]+", s or "x"):
        raise CliInputError(f"{option}: cannot read {text!r} as a complex number; write e.g. 5+0.1i or 5+0.1j")
    try:
        val = complex(s)
    except ValueError:
        raise CliInputError(
            f"{option}: cannot read {text!r} as a complex number; write e.g. 5+0.1i or 5+0.1j"
        ) from None
    if not (math.isfinite(val.real) and math.isfinite(val.imag)):
        raise CliInputError(f"{option}: {text!r} is not finite; give a finite complex number, e.g. 5+0.1i")
    if abs(val) > MAX_SCALE:
        raise CliInputError(f"{option}: |eta| = {abs(val):.3g} is too large (nu(eta)^2 would overflow); "
                            f"give |eta| <= {MAX_SCALE:g}")
    if val.real == 0.0 and pole_at_zero:
        raise CliInputError(
            f"{option}: Re(eta) = 0: the branch of nu(eta) is continued from lambda = Re(eta), here the pole "
            "lambda = 0 of the Lax matrix; give Re(eta) != 0"
        )
    return val


def parse_init(text: str, option: str = "--init", *, multiple: int = 3) -> list[float]:
    """Comma-separated 3N finite numbers (order y_0, y_1, ...); N is inferred from the count (``multiple=1``: any
    count, checked by the caller, e.g. an su(n) chain's (n²−1)M)."""
    parts = [p.strip() for p in str(text).split(",")]
    what = "3N comma-separated numbers" if multiple == 3 else "comma-separated numbers"  # su(n): (n²−1)M
    if not parts or parts == [""]:
        raise CliInputError(f"{option}: no numbers given; give {what} y_0, y_1, ...")
    vals = []
    for i, p in enumerate(parts, 1):
        try:
            v = to_float(p, option)
        except ValueError:
            raise CliInputError(
                f"{option}: value {i} ({p!r}) is not a number; give {what}"
            ) from None
        if not math.isfinite(v):
            raise CliInputError(f"{option}: value {i} ({p!r}) is not finite; give finite numbers")
        vals.append(v)
    if len(vals) % multiple:
        raise CliInputError(
            f"{option}: got {len(vals)} numbers, not a multiple of 3; give 3N numbers (the N vectors y_0, ..., "
            "y_(N-1), 3 components each; 9 for the generalised Lagrange top)"
        )
    if len(vals) > 3 * MAX_N:
        raise CliInputError(
            f"{option}: got {len(vals)} numbers (N = {len(vals) // 3}); the command line accepts N <= {MAX_N} "
            f"({3 * MAX_N} numbers)"
        )
    return vals


def parse_b(text, option: str = "--b") -> float:
    """A real field strength (``1+1i`` is refused: b must be real); the library checks the rest (nonzero, finite)."""
    from jetgaudin._validate import nonzero_field

    try:
        value = to_float(text, option)
    except (TypeError, ValueError):
        try:
            if not str(text).isascii() or not re.search(r"[ij]", str(text)):
                raise ValueError(text)
            complex(str(text).replace("i", "j"))
        except ValueError:
            raise CliInputError(f"{option}: cannot read {text!r} as a number; give a real number, e.g. 1.0") from None
        raise CliInputError(f"{option}: {text!r} is complex; the field strength b must be real (field b e_3)") from None
    with blame(option):
        value = nonzero_field(value)
    if abs(value) > MAX_SCALE:
        raise CliInputError(f"{option}: |b| = {abs(value):.3g} is too large (b^2 enters nu^2 and would overflow); "
                            f"give |b| <= {MAX_SCALE:g}")
    return float(value)


def parse_count(text, option: str, minimum: int = 0) -> int:
    """An integer count: ``1000``, ``1e6`` or ``2**20`` written out; the library's rule (``check_count``: an integer
    >= minimum that fits in 64 bits) decides."""
    from jetgaudin.maps import check_count

    s = str(text).strip()
    if re.fullmatch(r"[+-]?\d+(?:_\d+)+", s, re.ASCII):  # 1_000_000: underscores between digits only
        s = s.replace("_", "")
    if re.fullmatch(r"[+-]?\d+", s, re.ASCII):
        value = int(s)
    else:  # 1e6, 2.5e3: exact in decimal, never through a float (1e-99999 is not 0, 3.0000000000000001 not 3)
        from decimal import Decimal, InvalidOperation

        if not re.fullmatch(r"[+-]?(?:\d+\.?\d*|\.\d+)[eE][+-]?\d+|[+-]?\d+\.\d*|[+-]?\.\d+", s, re.ASCII):
            raise CliInputError(f"{option}: cannot read {text!r} as an integer")
        try:
            d = Decimal(s)
            whole = d.is_zero() or (d.adjusted() >= 0 and (d.adjusted() > 30 or d == d.to_integral_value()))
        except (InvalidOperation, OverflowError):
            raise CliInputError(f"{option}: cannot read {text!r} as an integer") from None
        if not whole:
            raise CliInputError(f"{option}: {text!r} is not an integer (write the count exactly, e.g. 1000 or 1e3)")
        value = 0 if d.is_zero() else 2**64 if d.adjusted() > 30 else int(d)  # 2**64: refused, not built
    with blame(option):
        return check_count(value, option.lstrip("-").replace("-", "_"), minimum)


def parse_steps(value, option: str = "--steps") -> int:
    return parse_count(value, option, 0)


def eta_label(eta: complex) -> str:
    return f"{eta.real:g}{eta.imag:+g}i"


class LazyProgress:
    """A Rich progress bar on stderr that appears only when the run lasts more than ``delay`` seconds
    and stderr is a terminal (``force=True`` shows it anyway)."""

    def __init__(self, description: str, delay: float = 1.0, force: bool = False):
        self.description, self.delay, self.force = description, delay, force
        self.t0 = time.monotonic()
        self._p: Any = None
        self._task: Any = None

    def __call__(self, n: int, total: int) -> None:
        if self._p is None:
            if time.monotonic() - self.t0 < self.delay or not (self.force or sys.stderr.isatty()):
                return
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn

            self._p = Progress(
                "[progress.description]{task.description}",
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
                console=Console(stderr=True, force_terminal=self.force or None),
                transient=False,
            )
            self._p.start()
            self._task = self._p.add_task(self.description, total=total)
        self._p.update(self._task, completed=n, total=total)

    def close(self) -> None:
        if self._p is not None:
            self._p.stop()
            self._p = None


def console(**kwargs):
    """A Rich console for the command's output.  When the reader of stdout goes away (``jetgaudin info | head``)
    Rich would exit with status 1, which our exit codes reserve for failed runs; this one raises
    :class:`BrokenPipeError` instead, which :func:`jetgaudin.cli.main` turns into a quiet exit 0."""
    from rich.console import Console

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            self.quiet = True
            raise BrokenPipeError

    return _Console(**({"highlight": False, "soft_wrap": True} | kwargs))


#: the relative column of an integral zero to round-off at the start (``nan`` in ``RunResult.max_drift_rel``)
ROUNDOFF_ZERO = "n/a (I(0) at round-off)"


def integrals_table(names, I0, drift_abs, drift_rel, title: str):
    """The integrals' table of a run: ``drift_rel`` is ``RunResult.max_drift_rel`` (``nan`` where ``I_k(0)`` is zero
    to round-off: :data:`ROUNDOFF_ZERO` there, the absolute drift being the number to read)."""
    import math

    from rich.table import Table

    t = Table(title=title, title_justify="left")
    t.add_column("integral")
    t.add_column("I_k(0)", justify="right")
    t.add_column("max |I_k - I_k(0)|", justify="right")
    t.add_column("relative", justify="right")
    rows: list[int] = list(range(len(names)))
    if len(names) > 12:  # large N: the integrals with the largest relative drift only (n/a ones last)
        rows = sorted(sorted(rows, key=lambda k: -drift_rel[k] if not math.isnan(drift_rel[k]) else math.inf)[:6])
        t.caption = f"{len(names) - 6} more integrals in run.json"
    for k in rows:
        rel = ROUNDOFF_ZERO if math.isnan(drift_rel[k]) else f"{drift_rel[k]:.3e}"
        t.add_row(names[k], f"{I0[k]:.17g}", f"{drift_abs[k]:.3e}", rel)
    return t


def resume_dir(text) -> Path:
    """The directory given to ``--resume`` (an empty string is refused: it would mean the current directory)."""
    if str(text).strip() == "":
        raise CliInputError("--resume: empty path; give the directory of the run to continue")
    return Path(text)


def out_path(text, default: str) -> Path:
    """The ``--out`` directory (an empty string is refused: it would mean the current directory)."""
    if text is None:
        return Path(default)
    if str(text).strip() == "":
        raise CliInputError("--out: empty path; give a directory name (an empty one would write into the current "
                            "directory)")
    return Path(text)


def check_state_scale(X, b, option: str = "--init") -> None:
    """Refuse states whose integrals overflow double precision (they would turn into inf / NaN)."""
    import numpy as np

    import jetgaudin as jg

    with np.errstate(all="ignore"):
        try:
            ok = bool(np.all(np.isfinite(jg.integrals(np.asarray(X, dtype=float), b))))
        except jg.InvalidStateError:  # the library refuses overflowing integrals itself
            ok = False
    if not ok:
        with np.errstate(all="ignore"):
            try:  # the same state in a unit field: is the field the culprit (the term 2 b y^3)?
                state_ok = bool(np.all(np.isfinite(jg.integrals(np.asarray(X, dtype=float), 1.0))))
            except jg.InvalidStateError:
                state_ok = False
        if state_ok:
            raise CliInputError(
                "--b: the field is too large for this state: the integrals H_k = 2 b y^3 + ... overflow double "
                "precision; give a smaller |b|"
            )
        raise CliInputError(
            f"{option}: the state is too large: its integrals (sums of products of components) overflow double "
            "precision; scale the state down"
        )


#: errnos of a failed write (the input was fine: exit 1): full disk, quota, file too large, I/O error
_WRITE_FAILURES = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO}


class reported_errors:  # noqa: N801 - used as a context manager: ``with reported_errors(): ...``
    """Turn expected failures into one-line messages and exit codes (never a traceback):
    bad input (:class:`CliInputError`, :class:`jetgaudin.JetGaudinError`) -> 2, ``OSError`` -> 2.
    NumPy floating-point warnings are silenced inside (results are checked for finiteness instead)."""

    def __enter__(self):
        import numpy as np

        self._err = np.errstate(all="ignore")
        self._err.__enter__()
        return self

    def __exit__(self, exc_type, exc, tb):
        self._err.__exit__(None, None, None)
        if exc_type is None or issubclass(exc_type, (typer.Exit, SystemExit, KeyboardInterrupt)):
            return False
        import jetgaudin as jg

        if issubclass(exc_type, jg.RunIOError):  # writing failed: the input was fine
            fail(exc, EXIT_FAILED)
        if issubclass(exc_type, (CliInputError, jg.JetGaudinError)):
            fail(exc, EXIT_INPUT)
        if issubclass(exc_type, BrokenPipeError):  # the reader of stdout left: handled by main()
            return False
        if issubclass(exc_type, (MemoryError, OSError, SystemError)):  # e.g. LLVM's library unmappable (ulimit -v)
            from jetgaudin._startup import out_of_memory

            memory = out_of_memory(exc)
            if memory:
                fail(memory, EXIT_FAILED)
        if issubclass(exc_type, OSError) and getattr(exc, "errno", None) in _WRITE_FAILURES:  # e.g. stdout is /dev/full
            from jetgaudin._fs import io_failure

            fail(f"{io_failure(exc)} while writing the output", EXIT_FAILED)
        if issubclass(exc_type, OSError):
            fail(f"{exc.strerror or exc}" + (f": {exc.filename}" if getattr(exc, "filename", None) else ""), EXIT_INPUT)
        if issubclass(exc_type, (FloatingPointError, OverflowError, ZeroDivisionError, ValueError)):
            fail(
                f"numerical failure ({exc_type.__name__}: {exc}); the input is out of the range the map handles",
                EXIT_FAILED,
            )
        return False


def compile_message(msg: str) -> None:
    """Where a run's compile messages go (``notify`` of :func:`jetgaudin.run.start`): one line on stderr, before
    the progress bar appears (the library decides what to say and when)."""
    typer.echo(msg, err=True)


def route_notice(m, X0, steps) -> None:
    """One line on stderr naming the route ``--backend auto`` takes where it matters (the map's ``route_notice``:
    the slow NumPy route of a map that has a compiled one; a compile is announced by the run itself)."""
    notice = getattr(m, "route_notice", None)
    text = notice(X0, steps) if notice is not None else None
    if text:
        typer.echo(f"{prog()}: {text}", err=True)


def timing_text(res) -> str:
    """``<s> s stepping (<rate> steps/s)[; kernels compiled or loaded in <s> s, not in the rate]`` of a
    :class:`jetgaudin.run.RunResult`: the time and rate of this session's stepping (compile/load time excluded).
    A resumed run says so: ``<s> s stepping <k> steps in this session (<rate>), <s> s over the whole run``, so
    that the rate is never the whole run's steps over this session's time or the reverse."""
    unit = "steps/s" if res.spec.B == 1 and res.spec.X0.ndim == 1 else "orbit-steps/s"
    rate = res.step_rate
    rate_text = f" ({rate:.3g} {unit})" if math.isfinite(rate) else ""
    if 0 <= res.session_steps < res.last_safe_step:  # resumed: earlier sessions did the other steps
        text = (f"{res.session_seconds:.3g} s stepping {res.session_steps:,} steps in this session{rate_text}, "
                f"{res.elapsed:.3g} s over the whole run")
    else:
        text = f"{res.elapsed:.3g} s stepping{rate_text}"
    if res.compile_seconds > 0:
        text += f"; kernels compiled or loaded in {res.compile_seconds:.1f} s, not in the rate"
    return text


def run_with_progress(description: str, progress: bool | None, run):
    """Call ``run(bar)`` with a :class:`LazyProgress` bar (``None`` with ``--no-progress``); an interrupted run
    (:class:`jetgaudin.run.RunInterrupted`, checkpoint written) prints its one line and exits 130 / 143."""
    from jetgaudin.run import RunInterrupted

    bar = LazyProgress(description, force=bool(progress)) if progress is not False else None
    try:
        return run(bar)
    except RunInterrupted as exc:
        if bar:
            bar.close()
        typer.echo(f"{prog()}: {exc}", err=True)
        if exc.compile_running:  # nothing was written; the abandoned compile would slow the shutdown (~1 s)
            _exit_now(exc.exit_code)
        raise typer.Exit(exc.exit_code) from None
    finally:
        if bar:
            bar.close()


def _exit_now(code: int) -> None:
    """Flush the standard streams and end the process with ``code`` at once (no interpreter shutdown)."""
    import os

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


class _Interrupted(Exception):  # noqa: N818
    def __init__(self, signum: int):
        self.signum = signum


def after_run(out_dir: Path, what: str, work):
    """Run ``work()`` (figures, extra tables) after a run, with the run directory locked; SIGINT/SIGTERM stop it
    with one line saying what was not written (exit 130/143), never a traceback.  Returns ``work()``'s result."""
    import signal
    import threading

    from jetgaudin import _fs

    def handler(signum, _frame):
        raise _Interrupted(signum)

    old = {}
    if threading.current_thread() is threading.main_thread():
        for s in (signal.SIGINT, signal.SIGTERM):
            old[s] = signal.signal(s, handler)
    try:
        with _fs.RunDirLock(out_dir):
            return work()
    except _Interrupted as exc:
        name = signal.Signals(exc.signum).name
        typer.echo(f"{prog()}: interrupted by {name} while writing {what}; the run's data in {out_dir} are complete "
                   f"but {what} are missing or partial", err=True)
        raise typer.Exit(128 + exc.signum) from None
    except (typer.Exit, SystemExit, KeyboardInterrupt):
        raise
    except Exception as exc:  # a figure or table that cannot be drawn: the run itself is complete and kept
        text = " ".join(f"{type(exc).__name__}: {exc}".split())[:300]
        typer.echo(f"{prog()}: error: could not write {what} ({text}); the run's data in {out_dir} are complete "
                   f"(redraw the figures with: jetgaudin plot {out_dir})", err=True)
        raise typer.Exit(EXIT_FAILED) from None
    finally:
        for s, h in old.items():
            signal.signal(s, h)
