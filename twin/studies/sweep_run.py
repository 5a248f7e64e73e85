"""``spectwin sweep``: every design point of a sweep file, as Dask tasks, resumably.

The output folder holds ``sweep.json`` (the sweep and its points' keys), one folder per point
under ``points/`` with its stores, ``result.json`` and ``history.jsonl``
(:mod:`twin.studies.sweep_gonio`), and, once every point is finished, the table, the figures and
the page (:mod:`twin.studies.sweep_report`).

Points run as Dask tasks on a ``LocalCluster`` of one-thread workers (``workers``) or on a
running cluster (``scheduler``), each worker with its own Mitsuba variant
(:class:`twin.devices.cluster.RendererSetup`); with one worker they run in this process, one
after the other. A killed sweep is continued by running it again into the same folder: points
with a result are not run again, the one that was running continues its stores.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.progress import progress_steps
from twin.output_format import dumps
from twin.studies.sweep_file import DesignPoint, Sweep
from twin.studies.sweep_points import point_result, run_point
from twin.studies.sweep_report import (
    pareto_front,
    plot_effects,
    plot_front,
    write_page,
    write_table,
)

__all__ = ["SweepOutcome", "run_sweep"]

Measure = Callable[[DesignPoint, Path], dict]


@dataclass(frozen=True)
class SweepOutcome:
    """A finished sweep: its summary (``summary.json``) and one row per point."""

    summary: dict
    rows: list[dict]


def _identity(sweep: Sweep) -> dict:
    return {"sweep": sweep.name, "point_keys": [point.key for point in sweep.points]}


def _prepare(sweep: Sweep, out: Path) -> None:
    """Create ``out`` for ``sweep``, or check that it holds this sweep (to continue it)."""
    marker = out / "sweep.json"
    if marker.is_file():
        recorded = json.loads(marker.read_text(encoding="utf-8"))
        if {key: recorded.get(key) for key in ("sweep", "point_keys")} != _identity(sweep):
            raise InputError(
                f"--out: {out} holds another sweep ({recorded.get('sweep')!r} with "
                f"{len(recorded.get('point_keys', []))} points) or other settings; choose "
                "another folder"
            )
        return
    if out.exists() and any(out.iterdir()):
        raise InputError(f"--out: {out} is not empty and holds no sweep; choose another")
    (out / "points").mkdir(parents=True, exist_ok=True)
    marker.write_text(dumps(sweep.describe() | _identity(sweep)), encoding="utf-8")


def _run_points(out: Path, pending: list, measure: Measure, client, progress: bool) -> None:
    folders = {point.index: out / "points" / point.key for point in pending}
    label = f"sweep: {len(pending)} design points"
    with progress_steps(label, len(pending), enabled=progress) as advance:
        if client is None:
            for point in pending:
                run_point(measure, point, folders[point.index])
                advance()
            return
        from distributed import as_completed

        from twin.devices.cluster import RendererSetup

        client.register_plugin(RendererSetup(), name=RendererSetup.name)
        futures = [
            client.submit(run_point, measure, point, folders[point.index], pure=False)
            for point in pending
        ]
        for future in as_completed(futures):
            future.result()
            advance()


def run_sweep(
    sweep: Sweep, out: str | Path, measure: Measure, *, client=None, progress: bool = False
) -> SweepOutcome:
    """Run the pending points of ``sweep`` into ``out`` (module docstring) with ``measure``
    (the kind's: :func:`twin.studies.sweep_gonio.measure_gonio_point`,
    :func:`twin.studies.sweep_dome.measure_dome_point`), then write the table, the figures and
    the page; returns the summary and the rows."""
    out = Path(out)
    _prepare(sweep, out)
    started = time.perf_counter()
    pending = [p for p in sweep.points if point_result(out / "points" / p.key) is None]
    _run_points(out, pending, measure, client, progress)
    results = [point_result(out / "points" / point.key) for point in sweep.points]
    rows = [row for row in results if row is not None]
    if len(rows) < len(results):
        unfinished = [p.label for p, row in zip(sweep.points, results, strict=True) if row is None]
        raise RuntimeError(f"points without a result after the run: {unfinished}")
    objectives = np.array([[row["measures"][name] for name in sweep.objectives] for row in rows])
    for row, on_front in zip(rows, pareto_front(objectives), strict=True):
        row["on_front"] = bool(on_front)
    measures = [
        *sweep.objectives,
        *(name for name in sweep.measures if name not in sweep.objectives),
    ]
    point_s = [row["measures"]["point_s"] for row in rows]
    summary = {
        "sweep": sweep.name,
        "file": str(sweep.path),
        "points": len(rows),
        "points_run_now": len(pending),
        "points_already_finished": len(rows) - len(pending),
        "this_run_s": time.perf_counter() - started,
        "mean_point_s": float(np.mean(point_s)),
        "max_point_s": float(np.max(point_s)),
        "total_point_s": float(np.sum(point_s)),
        "workers": len(client.scheduler_info()["workers"]) if client is not None else 1,
        "objectives": list(sweep.objectives),
        "front": [row["label"] for row in rows if row["on_front"]],
        "outputs": ["table.csv", "table.json", "front.png", "effects.png", "index.html"],
    }
    write_table(rows, list(sweep.parameters), measures, out)
    plot_front(rows, sweep.objectives, sweep.measures, out / "front.png")
    plot_effects(rows, sweep.parameters, sweep.objectives, sweep.measures, out / "effects.png")
    write_page(out, summary, rows, measures)
    (out / "summary.json").write_text(dumps(summary), encoding="utf-8")
    return SweepOutcome(summary, rows)
