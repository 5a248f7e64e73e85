"""Which options a command's user gave on the command line, and how the command spells them
(for refusals that name the option as the user typed it)."""

from __future__ import annotations

import typer

__all__ = ["given", "option_name"]


def given(ctx: typer.Context, name: str) -> bool:
    """Whether the option of parameter ``name`` was given on the command line."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name == "COMMANDLINE"


def option_name(ctx: typer.Context, name: str) -> str:
    """The option of parameter ``name`` as the command spells it (``--white-fill``)."""
    return next(p.opts[0] for p in ctx.command.params if p.name == name)
