"""What every design point of a sweep shares: its folder's history, its stores captured or
continued, its result written last and atomically.

A point's folder holds its stores, ``history.jsonl`` (one line per start and finish of the point,
with the process) and, once finished, ``result.json``: a point with one is never run again.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from hwbridge.store import CaptureStore

if TYPE_CHECKING:
    from twin.studies.sweep_file import DesignPoint

__all__ = ["capture_into", "point_result", "run_point", "storage_mb"]


def record(folder: Path, event: str) -> None:
    """Append ``event`` (``started``, ``finished``) to the point's ``history.jsonl``."""
    line = json.dumps({"event": event, "pid": os.getpid(), "time": time.time()})
    with open(folder / "history.jsonl", "a", encoding="utf-8") as history:
        history.write(line + "\n")


def capture_into(program, path: Path) -> CaptureStore:
    """Capture ``program`` into ``path``, continuing a store a previous attempt left."""
    return program.run(path, resume=path.exists())


def storage_mb(*paths: Path) -> float:
    """Bytes on disk of the stores ``paths``, in MB."""
    return sum(f.stat().st_size for p in paths for f in p.rglob("*") if f.is_file()) / 1e6


def point_result(folder: str | Path) -> dict | None:
    """A finished point's result (its ``result.json``), or ``None`` while it is not finished."""
    path = Path(folder) / "result.json"
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None


def run_point(
    measure: Callable[[DesignPoint, Path], dict], point: DesignPoint, folder: str | Path
) -> dict:
    """Run ``point`` into ``folder`` with ``measure`` (its captures, processing and evaluation,
    returning the measures), add its wall time ``point_s``, write ``result.json`` (atomically: a
    partial file, then a rename) and return the result; a finished point's result is returned
    as it is, without running anything."""
    folder = Path(folder)
    finished = point_result(folder)
    if finished is not None:
        return finished
    folder.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    record(folder, "started")
    measures = measure(point, folder) | {"point_s": time.perf_counter() - started}
    result = {
        "point": point.index,
        "key": point.key,
        "label": point.label,
        "values": point.values,
        "material": point.material,
        "seed": point.seed,
        "measures": measures,
    }
    partial = folder / "result.json.partial"
    partial.write_text(json.dumps(result, indent=1), encoding="utf-8")
    os.replace(partial, folder / "result.json")
    record(folder, "finished")
    return result
