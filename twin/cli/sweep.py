"""``spectwin sweep``: rig designs explored as virtual captures, with the capture-time versus
error front (:mod:`twin.studies.sweep_run`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from twin.cli.errors import fail, interrupted, require_output_folder
from twin.cli.output import JsonFlag, SchedulerOption, WorkersOption, console, print_summary

__all__ = ["register"]


def sweep(
    sweep_file: Annotated[
        str,
        typer.Argument(
            metavar="SWEEP",
            help="Sweep file: a name in scenes/sweeps (gonio_lamp_filter_sampling, "
            "dome_schedule_tbase_filter) or a path.",
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            help="Folder for the points' stores, table.csv/json, front.png, effects.png and "
            "index.html; run again into the same folder to continue a stopped sweep."
        ),
    ],
    workers: WorkersOption = 1,
    scheduler: SchedulerOption = None,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="List the design points; run nothing.")
    ] = False,
    as_json: JsonFlag = False,
) -> None:
    """Run every design point of a sweep file (a virtual calibration, capture, processing and
    evaluation each, as Dask tasks) and draw the Pareto front of capture time against the BTF's
    error, with the effect of each parameter.

    Every point's rig and plan are checked before anything runs. A stopped or killed sweep
    continues where it stopped when run again with the same --out: finished points are never
    run again.

    Example: spectwin sweep gonio_lamp_filter_sampling --out out/sweep --workers 2
    """
    from twin.kinds.registry import sweep_kind
    from twin.studies.sweep_file import check_points, load_sweep

    loaded = load_sweep(sweep_file, sweep_kind)
    kind = sweep_kind(loaded.kind)
    check_points(loaded, kind.check)
    if dry_run:
        if workers != 1 or scheduler:
            fail("--dry-run runs nothing; leave out --workers and --scheduler")
        summary = loaded.describe() | {
            "designs": [f"{point.index}: {point.label}" for point in loaded.points]
        }
        print_summary(summary, "sweep (dry run)", as_json)
        return
    require_output_folder(out)
    from twin.devices.cluster import dask_client
    from twin.studies.sweep_run import run_sweep

    try:
        with dask_client(workers, scheduler) as client:
            outcome = run_sweep(loaded, out, kind.measure, client=client, progress=not as_json)
    except KeyboardInterrupt:
        interrupted(f"finished points are kept in {out}; run the same command again to continue")
    print_summary(outcome.summary, f"sweep: {loaded.name}", as_json, skip=("outputs",))
    if not as_json:
        console.print(f"front and table: {out / 'index.html'}")


def register(app: typer.Typer) -> None:
    """Add ``sweep`` to ``app``."""
    app.command()(sweep)
