"""``jetgaudin verify``: the machine-checked account of the paper (see :mod:`jetgaudin.verify`).

Prints a table that fits 80 columns (label, verdict as printed, verdict corrected, errata entry, seconds; with
``--long`` also the statement and the method, wrapped) or, with ``--json``, a JSON array with one object per
check.  ``--coverage`` prints the coverage map of the paper instead (every statement, its status and the checks
that decide it; ``--coverage --json`` as a JSON array).  Exit status 0 iff every check holds as printed or after
its documented correction (``docs/errata.md``), 1 otherwise, 2 on bad input (e.g. an unknown ``--only`` label).
"""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer

from ._app import app

__all__ = ["verify"]

#: width of the tables when stdout is not a terminal (a pipe or a file): readable at 80 columns
PIPE_WIDTH = 80


def _fmt(status: str | None, residual: float | None) -> str:
    if status is None:
        return "-"
    colour = {"holds": "green", "fails": "red", "undecided": "yellow"}.get(status, "white")
    res = "" if residual is None else f" {residual:.0e}"
    return f"[{colour}]{status}[/{colour}]{res}"


def _table(results: list[Any], seed: int, long: bool) -> Any:
    from rich import box
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=f"jetgaudin verify (seed {seed})", box=box.SIMPLE_HEAD, pad_edge=False, expand=False)
    if long:
        t.add_column("check", no_wrap=True)
        t.add_column("statement / method", overflow="fold")
    else:
        for name, kw in (("label", {"no_wrap": True}), ("as printed", {"no_wrap": True}),
                         ("corrected", {"no_wrap": True}), ("errata", {"justify": "right"}),
                         ("s", {"justify": "right"})):
            t.add_column(name, **kw)
    for r in results:
        errata = f"#{r.erratum['entry']}" if r.erratum is not None else ""
        printed, corrected = _fmt(r.printed, r.printed_residual), _fmt(r.corrected, r.corrected_residual)
        if long:
            left = f"{escape(r.label)}\nprinted {printed}\ncorrected {corrected}\n{errata} {r.seconds:.2f} s".strip()
            t.add_row(left, f"{escape(r.statement)}\n[dim]{escape(r.method)}[/dim]")
        else:
            t.add_row(escape(r.label), printed, corrected, errata, f"{r.seconds:.2f}")
    return t


def _coverage_table(entries: list[dict]) -> Any:
    from rich import box
    from rich.markup import escape
    from rich.table import Table

    colour = {"checked": "green", "partly": "yellow", "definition": "blue", "not checkable": "magenta",
              "unchecked": "red"}
    t = Table(title="jetgaudin verify --coverage", box=box.SIMPLE_HEAD, pad_edge=False, show_lines=False)
    t.add_column("sec", no_wrap=True, max_width=6)
    t.add_column("status", no_wrap=True)
    t.add_column("statement / checks / reason", overflow="fold")
    for e in entries:
        body = escape(e["statement"])
        if e["checks"]:
            body += f"\n[cyan]{escape(', '.join(e['checks']))}[/cyan]"
        if e["reason"]:
            body += f"\n[dim]{escape(e['reason'])}[/dim]"
        sec = e["section"].replace("Appendix ", "App")
        t.add_row(sec, f"[{colour[e['status']]}]{e['status']}[/]", body)
    return t


def _console() -> Any:
    import sys

    from ._common import console

    return console(width=None if sys.stdout.isatty() else PIPE_WIDTH)


@app.command("verify")
def verify(
    only: Annotated[
        list[str] | None,
        typer.Option(
            "--only", metavar="LABEL", help="run only this check (exact label, or a family: App1 = App1-*; repeatable)"
        ),
    ] = None,
    full: Annotated[
        bool, typer.Option("--full", help="include the heavier checks (N = 4 with all c_k, 1000 exact steps)")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="print a JSON array, one object per check")] = False,
    long: Annotated[bool, typer.Option("--long", help="also print each statement and method (wrapped)")] = False,
    coverage: Annotated[
        bool, typer.Option("--coverage", help="print the coverage map of the paper (no check is run)")
    ] = False,
    seed: Annotated[int, typer.Option("--seed", help="seed of the random high-precision points")] = 20261122,
) -> None:
    """Check the paper's propositions, lemmas and displayed formulas, as printed and as corrected."""
    import jetgaudin.verify as jv

    if coverage:
        from jetgaudin.verify.coverage import counts
        from jetgaudin.verify.coverage import coverage as cov

        entries = cov()
        if as_json:
            typer.echo(json.dumps(entries, indent=1))
        else:
            _console().print(_coverage_table(entries))
            typer.echo(f"{len(entries)} statements: " + ", ".join(f"{n} {k}" for k, n in counts().items() if n))
        raise typer.Exit(0)
    jv.load_all()
    if only:
        try:
            jv._registry.select(only)
        except KeyError as exc:
            typer.echo(
                f"jetgaudin verify: error: unknown check label(s) {exc.args[0]}; known labels: "
                f"{', '.join(jv.REGISTRY)}",
                err=True,
            )
            raise typer.Exit(2) from None
    results = jv.run_checks(only=only or None, full=full, seed=seed)
    if as_json:
        typer.echo(json.dumps([r.to_dict() for r in results], indent=1))
    else:
        _console().print(_table(results, seed, long))
        n_ok = sum(r.status == "holds" for r in results)
        n_fix = sum(r.printed != "holds" and r.status == "holds" for r in results)
        typer.echo(
            f"{n_ok}/{len(results)} hold ({n_fix} after a documented correction, see docs/errata.md); "
            f"{sum(r.seconds for r in results):.1f} s"
        )
    raise typer.Exit(jv.exit_code(results))
