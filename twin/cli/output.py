"""What the ``spectwin`` commands print: a table of rounded quantities, or full-precision JSON.

Quantity names carry their unit as a suffix (``exposure_per_pair_s``); the table shows it
with the value ("exposure per pair" | "63.6 s"), rounded by :mod:`twin.output_format`.
``--json`` prints everything unrounded.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from twin.output_format import dumps, format_value, quantity

__all__ = [
    "JsonFlag",
    "SchedulerOption",
    "SeedOption",
    "WorkersOption",
    "console",
    "print_comparison",
    "print_summary",
]

JsonFlag = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]
SeedOption = Annotated[int, typer.Option(min=0, help="Seed of the simulated noise.")]
WorkersOption = Annotated[
    int,
    typer.Option(
        min=0,
        max=256,
        help="Worker processes of a local Dask cluster (one thread each); 0 or 1: run in this "
        "process. Same results either way.",
    ),
]
SchedulerOption = Annotated[
    str | None,
    typer.Option(
        envvar="DASK_SCHEDULER_ADDRESS",
        help="Run on the Dask cluster of this scheduler (tcp://host:8786); its workers must "
        "see the stores under the same paths.",
    ),
]

console = Console()


def print_summary(
    summary: Mapping[str, object],
    title: str,
    as_json: bool = False,
    *,
    skip: Sequence[str] = (),
    unit: str | None = None,
) -> None:
    """``summary`` as JSON (full precision) or as a table of rounded quantities with units.

    With ``unit`` the keys are names (e.g. of methods), shown as they are, and every value is
    in ``unit``."""
    if as_json:
        typer.echo(dumps(summary))
        return
    rows: dict[str, str] = {}
    for key, value in summary.items():
        if key in skip:
            continue
        name, suffix = (str(key), unit) if unit is not None else quantity(str(key))
        text = format_value(value)
        if suffix and isinstance(value, int | float | np.number) and not isinstance(value, bool):
            text = f"{text} {suffix}"
        elif suffix:
            name = f"{name} ({suffix})"
        # One quantity in several units (total_s, total_h): one row, "475862 s = 132.2 h".
        rows[name] = f"{rows[name]} = {text}" if name in rows else text
    table = Table("quantity", "value", title=title)
    for name, text in rows.items():
        table.add_row(escape(name), escape(text))  # values are text, never markup: "[a, b]"
    console.print(table)


def print_comparison(
    rows: Mapping[str, Mapping[str, object]], title: str, columns: Sequence[str]
) -> None:
    """A table of quantities (rows, named with their unit suffix) against ``columns`` (e.g.
    ``real``, ``twin``, ``difference_percent``), each value rounded; a column named with a unit
    suffix shows that unit in its header."""
    headers = [quantity(column) for column in columns]
    table = Table("quantity", *(f"{name} ({unit})" if unit else name for name, unit in headers))
    table.title = title
    for key, row in rows.items():
        name, unit = quantity(key)
        cells = [format_value(row[column]) for column in columns]
        label = f"{name} ({unit})" if unit else name
        table.add_row(escape(label), *(escape(cell) for cell in cells))
    console.print(table)
