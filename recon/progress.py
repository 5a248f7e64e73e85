"""Progress reporting for long reconstructions: a rich progress bar on standard error (standard
output stays free for results, e.g. a command's JSON), or nothing."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

__all__ = ["progress_steps"]


@contextmanager
def progress_steps(description: str, total: int, *, enabled: bool) -> Iterator[Callable[..., None]]:
    """Yield a function that advances a ``total``-step bar labelled ``description`` by one step,
    or by its argument.

    With ``enabled=False`` the function does nothing, so callers never branch on it.
    """
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    with Progress(
        *columns, console=Console(stderr=True), disable=not enabled, transient=False
    ) as progress:
        task = progress.add_task(description, total=total)
        yield lambda steps=1: progress.advance(task, steps)
