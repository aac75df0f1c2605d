"""The ``jetgaudin`` command line (Typer).

Commands: ``orbit`` (the real two-point Bäcklund map; Appendix 2 by default), ``flow`` (continuous flows
of ``H_2/2`` or ``G_η``, ``--compare`` with the map), ``info`` (integrals, Casimirs, ``ν(η)``, ``G_η`` of a
state).  Other modules add commands with ``from ._app import app`` and ``@app.command()``; they are imported
at the end of this module if present (``ensemble``, ``bench``, ``verify``).

Errors never show a traceback: bad input prints one line ``jetgaudin <command>: error: ...`` on stderr and exits
with code 2; a run that fails (singular step, health check) exits with 1; SIGINT/SIGTERM exit with
130/143 after saving a checkpoint.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import sys
from collections.abc import Iterator
from typing import Annotated, Any

import typer

try:  # typer >= 0.24 vendors click as typer._click; older typer uses click itself
    from typer._click import exceptions as _click_exc
except ImportError:  # pragma: no cover
    from click import exceptions as _click_exc  # type: ignore[no-redef]

__all__ = ["app", "main"]

from ._app import app  # noqa: E402  (the Typer object, in its own module: the commands import it from there)


@app.callback(invoke_without_command=True)
def _root(
    ctx: typer.Context,
    version: Annotated[
        bool, typer.Option("--version", help="print the package version and exit", is_eager=True)
    ] = False,
) -> None:
    """Jet-extended Gaudin models: Bäcklund orbits (Appendix 2), continuous flows, spectral data of a state."""
    if version:
        import jetgaudin as jg

        typer.echo(jg.__version__)
        raise typer.Exit(0)
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit(0)


def _app_noting_interrupts(args: list[str]):
    """Run the Typer app; a SIGINT outside a run (runs and figure writing install their own handlers, which print
    their own line) is reported here in one line.  Typer turns KeyboardInterrupt into a silent ``Exit(130)``, so
    the signal is noted by a handler that then raises KeyboardInterrupt as Python's default handler would."""
    import signal
    import threading

    seen: list[int] = []

    def note(signum, _frame):
        seen.append(signum)
        raise KeyboardInterrupt

    old = None
    if threading.current_thread() is threading.main_thread():
        old = signal.signal(signal.SIGINT, note)
    try:
        code = app(args=args, prog_name="jetgaudin", standalone_mode=False)
    except KeyboardInterrupt:
        seen.append(signal.SIGINT)
        code = 130
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
    if seen and code == 130:
        typer.echo("jetgaudin: interrupted", err=True)
    return code


def main(argv: list[str] | None = None) -> None:
    """Console entry point ``jetgaudin`` (also ``python -m jetgaudin``)."""
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        sub = _subcommand(args)
        bad = _bad_number(args, sub) or _bad_choice(args, sub)
        if bad is not None:
            typer.echo(bad, err=True)
            sys.exit(2)
        code = _app_noting_interrupts(args)
    except SystemExit as exc:
        # Click answers a closed stdout (EPIPE) with exit 1 after wrapping stdout in PacifyFlushWrapper; our exit
        # code 1 means a failed run, and a reader that left early (`jetgaudin info | head`) is not one
        if exc.code == 1 and type(sys.stdout).__name__ == "PacifyFlushWrapper":
            _silence_stdout()
            sys.exit(0)
        raise
    except _click_exc.NoArgsIsHelpError as exc:
        typer.echo(exc.ctx.get_help() if exc.ctx is not None else "usage: jetgaudin COMMAND --help")
        sys.exit(0)
    except _click_exc.UsageError as exc:
        # one line, never a traceback (click would print the usage block)
        msg = " ".join(exc.format_message().split())
        cmd = f" {exc.ctx.info_name}" if exc.ctx is not None and exc.ctx.parent is not None else ""
        typer.echo(f"jetgaudin{cmd}: error: {msg} (see: jetgaudin{cmd} --help)", err=True)
        sys.exit(2)
    except KeyboardInterrupt:  # Ctrl-C outside a run (runs handle it themselves and save a checkpoint)
        typer.echo("jetgaudin: interrupted", err=True)
        sys.exit(130)
    except typer.Abort:
        typer.echo("jetgaudin: aborted", err=True)
        sys.exit(130)
    except _click_exc.ClickException as exc:
        ctx = getattr(exc, "ctx", None)
        cmd = f" {ctx.info_name}" if ctx is not None and ctx.parent is not None else ""
        typer.echo(f"jetgaudin{cmd}: error: {' '.join(exc.format_message().split())}", err=True)
        sys.exit(exc.exit_code)
    except BrokenPipeError:  # e.g. `jetgaudin info | head`: the reader left; not an error of the run
        _silence_stdout()
        sys.exit(0)
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
    sys.exit(code if isinstance(code, int) else 0)


def _subcommand(args: list[str]) -> Any:
    """The click command of ``args[0]`` (``None``: none, or the lookup failed: the parser then reports it)."""
    if not args:
        return None
    try:
        cmd = typer.main.get_command(app)
        return cmd.commands.get(args[0]) if hasattr(cmd, "commands") else None  # type: ignore[attr-defined]
    except Exception:  # noqa: BLE001 - the checks are an addition; the parser reports anything else
        return None


def _bad_number(args: list[str], sub: Any) -> str | None:
    """The one-line error for a value of a numeric option (``int``/``float`` typed) that Python's ``float``/``int``
    would read but the command line does not accept: non-ASCII digits (``١.٥``), underscores (``1_``, ``1_0``), or
    a non-finite float (``inf``, ``nan``: every float option wants a finite number); ``None`` if all are fine."""
    import math

    from ._common import _NUMBER

    if sub is None:
        return None
    import typing

    kinds: dict[str, str] = {}
    for p in sub.params:
        ann = getattr(getattr(p, "type_descriptor", None), "annotation", None)
        types = set(typing.get_args(ann)) | {ann}
        kind = "float" if float in types else "integer" if int in types and bool not in types else ""
        if kind:
            for opt in getattr(p, "opts", []):
                if opt.startswith("-"):
                    kinds[opt] = kind
    for opt, value in _values(args, kinds):
        v = value.strip()
        ok = bool(_NUMBER.fullmatch(v)) if kinds[opt] == "float" else v.lstrip("+-").isascii() and \
            v.lstrip("+-").isdigit()
        if ok and kinds[opt] == "float" and not math.isfinite(float(v)):
            return f"jetgaudin {args[0]}: error: {opt}: {value!r} is not finite; give a finite number"
        if not ok:
            return (f"jetgaudin {args[0]}: error: {opt}: cannot read {value!r} as "
                    f"{'a number' if kinds[opt] == 'float' else 'an integer'} (ASCII digits 0-9, no '_')")
    return None


def _values(args: list[str], opts) -> Iterator[tuple[str, str]]:
    """``(option, value)`` of each of ``opts`` given in ``args[1:]`` (``--opt value`` or ``--opt=value``)."""
    i = 1
    while i < len(args):
        a = args[i]
        opt, value = (a.split("=", 1) + [None])[:2] if a.startswith("--") else (a, None)
        if opt is not None and opt in opts:
            if value is None:
                if i + 1 >= len(args):
                    return
                value = args[i + 1]
                i += 1
            yield opt, value
        elif a == "--":
            return
        i += 1


def _bad_choice(args: list[str], sub: Any) -> str | None:
    """The one-line error for a value outside an option's choices (``--backend gpu`` on ``orbit``), in words: the
    option, what the command takes and, for the GPU, the command that has it (``ensemble``); the parser's own
    message read like a validation library's ("Value error, 'gpu' is not one of ...")."""
    import enum
    import typing

    if sub is None:
        return None
    choices: dict[str, list[str]] = {}
    for p in sub.params:
        ann = getattr(getattr(p, "type_descriptor", None), "annotation", None)
        for t in set(typing.get_args(ann)) | {ann}:
            if isinstance(t, type) and issubclass(t, enum.Enum):
                for opt in getattr(p, "opts", []):
                    if opt.startswith("-"):
                        choices[opt] = [str(m.value) for m in t]
    for opt, value in _values(args, choices):
        if value in choices[opt]:
            continue
        takes = choices[opt]
        text = ", ".join(takes[:-1]) + f" or {takes[-1]}" if len(takes) > 1 else takes[0]
        line = f"jetgaudin {args[0]}: error: {opt}: {args[0]} takes {text}, not {value!r}"
        if value.strip().lower() in ("gpu", "cuda") and "gpu" not in takes:
            line += ("; the GPU route is for ensembles of orbits: jetgaudin ensemble --backend gpu (an NVIDIA GPU, "
                     "pip install 'jetgaudin[gpu]')")
        return line
    return None


def entry() -> None:
    """The ``jetgaudin`` console script and ``python -m jetgaudin``: :func:`main`, then the process ends at once with
    its exit code, the standard streams flushed.  Every file a command writes is closed (run files fsynced) before
    :func:`main` returns; what is skipped is the interpreter's teardown, which takes about 0.5 s once the compiled
    kernels are loaded (LLVM's finalizers) and would hold the exit after SIGINT/SIGTERM past the half second the
    project promises (``docs/reliability.md``).  An exception other than ``SystemExit`` (a bug) propagates as usual."""
    import os

    from .. import _startup

    _startup.release()  # from here on main() reports interrupts and errors itself
    for stream in (sys.stdout, sys.stderr):  # an ASCII locale or PYTHONIOENCODING=ascii: η, ν printed as '?'
        with contextlib.suppress(AttributeError, ValueError):
            stream.reconfigure(errors="replace")  # type: ignore[union-attr]
    try:
        main()
        code: Any = 0
    except SystemExit as exc:
        code = exc.code
    except KeyboardInterrupt:  # Ctrl-C between the start-up guard and the command (runs handle it themselves)
        print("jetgaudin: interrupted", file=sys.stderr)
        code = 130
    except (MemoryError, ImportError) as exc:  # out of memory (ulimit -v) while importing or allocating
        text = " ".join(f"{type(exc).__name__}: {exc}".split())[:300]
        print(f"jetgaudin: error: {_startup.out_of_memory(exc) or text + ' (out of memory? check ulimit -v)'}",
              file=sys.stderr)
        code = 1
    if code is None:
        code = 0
    elif not isinstance(code, int):  # as sys.exit("message") would: the message on stderr, exit 1
        print(code, file=sys.stderr)
        code = 1
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except BrokenPipeError:
            _silence_stdout()
        except (OSError, ValueError):
            pass
    os._exit(code)


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again (and exit with 1)."""
    import os

    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())


from . import _flow, _info, _orbit  # noqa: E402,F401  (register the commands)

for _m in ("ensemble", "bench", "verify", "warmup", "animate", "plot"):
    if importlib.util.find_spec(f"jetgaudin.cli.{_m}") is not None:
        try:
            importlib.import_module(f"jetgaudin.cli.{_m}")
        except Exception as _exc:  # a broken optional command must not take down orbit/flow/info
            print(
                f"jetgaudin: warning: the '{_m}' command is unavailable ({type(_exc).__name__}: {_exc})",
                file=sys.stderr,
            )
