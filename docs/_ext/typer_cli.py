"""Sphinx directive ``typer-cli``: the reference of every ``jetgaudin`` command, generated from the Typer app.

Each command gets a section with its ``--help`` text as Click renders it (so the page cannot drift from the
code).  sphinx-click cannot be used: Typer >= 0.24 vendors its own Click, whose commands are not
``click.Command`` instances.
"""

from __future__ import annotations

from docutils import nodes
from docutils.parsers.rst import Directive


def _help(cmd, name: str, parent=None) -> str:
    ctx = cmd.context_class(cmd, info_name=name, parent=parent, terminal_width=80, max_content_width=80)
    return cmd.get_help(ctx)


class TyperCli(Directive):
    has_content = False

    def run(self):
        import typer.main

        from jetgaudin.cli import app

        root = typer.main.get_command(app)
        root_ctx = root.context_class(root, info_name="jetgaudin", terminal_width=80, max_content_width=80)
        out = [nodes.literal_block(text=_help(root, "jetgaudin"), language="text")]
        for name in sorted(root.commands):
            cmd = root.commands[name]
            sec = nodes.section(ids=[f"cli-{name}"], names=[f"jetgaudin {name}"])
            sec += nodes.title(text=f"jetgaudin {name}")
            sec += nodes.literal_block(text=_help(cmd, name, root_ctx), language="text")
            out.append(sec)
        return out


def setup(app):
    app.add_directive("typer-cli", TyperCli)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
