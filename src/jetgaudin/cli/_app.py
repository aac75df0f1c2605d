"""The Typer application of the ``jetgaudin`` command line, in a module of its own: the command modules import it from
here and :mod:`jetgaudin.cli` imports them (no import cycle through the package)."""

from __future__ import annotations

import typer

__all__ = ["app"]

app = typer.Typer(
    name="jetgaudin",
    help="Jet-extended Gaudin models: Bäcklund orbits (Appendix 2), continuous flows, spectral data of a state.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)
