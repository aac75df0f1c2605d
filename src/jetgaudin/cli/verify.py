"""``jetgaudin verify``: the machine-checked account of the paper (see :mod:`jetgaudin.verify`).

Prints a Rich table (label, statement, as printed, corrected, method, seconds) or, with ``--json``, a JSON
array with one object per check.  Exit status 0 iff every check holds as printed or after its documented
correction (``docs/errata.md``), 1 otherwise, 2 on bad input (e.g. an unknown ``--only`` label).
"""

from __future__ import annotations

import json
from typing import Annotated

import typer

from . import app

__all__ = ["verify"]


def _fmt(status, residual):
    if status is None:
        return "-"
    colour = {"holds": "green", "fails": "red", "undecided": "yellow"}.get(status, "white")
    res = "" if residual is None else f" ({residual:.1e})"
    return f"[{colour}]{status}[/{colour}]{res}"


def _table(results, seed):
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=f"jetgaudin verify (seed {seed})", show_lines=False, expand=False)
    for name, kw in (
        ("label", {"no_wrap": True}),
        ("statement", {"ratio": 3, "min_width": 40}),
        ("as printed", {"no_wrap": True}),
        ("corrected", {"no_wrap": True}),
        ("method", {"ratio": 2, "min_width": 24}),
        ("seconds", {"justify": "right"}),
    ):
        t.add_column(name, **kw)
    for r in results:
        corrected = _fmt(r.corrected, r.corrected_residual)
        if r.erratum is not None:
            corrected += f"  [dim](errata #{r.erratum['entry']})[/dim]"
        t.add_row(
            escape(r.label),
            escape(r.statement),
            _fmt(r.printed, r.printed_residual),
            corrected,
            escape(r.method),
            f"{r.seconds:.2f}",
        )
    return t


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
    seed: Annotated[int, typer.Option("--seed", help="seed of the random high-precision points")] = 20261122,
) -> None:
    """Check the paper's propositions, lemmas and displayed formulas, as printed and as corrected."""
    import jetgaudin.verify as jv

    jv._load_all()
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
        import sys

        from ._common import console

        # a pipe gets a wide table (Rich would otherwise fold it to 80 columns)
        console(width=None if sys.stdout.isatty() else 180).print(_table(results, seed))
        n_ok = sum(r.status == "holds" for r in results)
        n_fix = sum(r.printed != "holds" and r.status == "holds" for r in results)
        typer.echo(
            f"{n_ok}/{len(results)} hold ({n_fix} after a documented correction, see docs/errata.md); "
            f"{sum(r.seconds for r in results):.1f} s"
        )
    raise typer.Exit(jv.exit_code(results))
