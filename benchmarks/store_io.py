"""What one Zarr read or write of the stores costs, by store class and codec chain. Prints JSON.

For each combination of the file store (Zarr's ``LocalStore``, or
:class:`hwbridge.local_store.LocalFileStore`, which reads and writes small files in place) and
the codecs (Zstd then CRC-32C, or CRC-32C alone as the stores' index fields and flags now have
it), the median wall and CPU time per call of: writing one element of a one-element-chunk array
(an index field of one frame of a real capture), reading it back, and writing and reading one
``--side`` px uint16 frame chunk, timed in rounds that visit every combination in turn. Then a
real-backend capture store of ``--steps`` steps written step by step as a session writes it
(frame, index, flag), and its index read back, per step.

Run: .venv/bin/python -m benchmarks.store_io [--steps 300] [--side 256]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import zarr
from zarr.storage import LocalStore

from benchmarks.common import machine_description
from hwbridge.integrity import checksum_only, checksummed_compressors
from hwbridge.local_store import LocalFileStore
from hwbridge.store import CaptureStore, FrameRecord

CALLS = 400
"""Calls of each operation in each combination."""
BATCH = 20
"""Calls timed together."""


def _arrays(
    folder: Path, store_class: type[LocalStore], codecs: tuple[Any, ...], side: int
) -> tuple[zarr.Array[Any], zarr.Array[Any]]:
    """A one-element-chunk field and a frame array in a new group at ``folder``."""
    group = zarr.open_group(store=store_class(folder, read_only=False), mode="w-", zarr_format=3)
    field = group.create_array(
        "field", shape=(CALLS,), chunks=(1,), dtype="float64", compressors=codecs
    )
    frames = group.create_array(
        "frames",
        shape=(CALLS, side, side),
        chunks=(1, side, side),
        dtype="uint16",
        compressors=codecs,
    )
    return field, frames


def _operations(
    field: zarr.Array[Any], frames: zarr.Array[Any], frame: np.ndarray
) -> dict[str, Callable[[int], object]]:
    """The four operations timed, each taking the slot it works on."""
    one = np.ones(1)
    return {
        "write_element": lambda i: field.__setitem__(slice(i, i + 1), one),
        "read_element": lambda i: field[i : i + 1],
        "write_frame": lambda i: frames.__setitem__(slice(i, i + 1), frame),
        "read_frame": lambda i: frames[i : i + 1],
    }


def _primitives(root: Path, side: int) -> dict[str, dict[str, dict[str, float]]]:
    """Median milliseconds per call of each operation in each combination, timed in rounds of
    :data:`BATCH` calls that visit the combinations in turn (the machine's drift is shared)."""
    frame = np.random.default_rng(0).poisson(800, (1, side, side)).astype(np.uint16)
    operations = {}
    for store_class in (LocalStore, LocalFileStore):
        for name, codecs in (
            ("zstd+crc32c", checksummed_compressors()),
            ("crc32c", checksum_only()),
        ):
            key = f"{store_class.__name__}, {name}"
            field, frames = _arrays(root / key, store_class, codecs, side)
            operations[key] = _operations(field, frames, frame)
    times: dict[tuple[str, str], dict[str, list[float]]] = {}
    for start in range(0, CALLS, BATCH):
        for operation in ("write_element", "read_element", "write_frame", "read_frame"):
            for key, timed in operations.items():
                wall, cpu = time.perf_counter(), time.process_time()
                for i in range(start, start + BATCH):
                    timed[operation](i)
                kept = times.setdefault((key, operation), {"wall_ms": [], "cpu_ms": []})
                kept["wall_ms"].append((time.perf_counter() - wall) / BATCH * 1e3)
                kept["cpu_ms"].append((time.process_time() - cpu) / BATCH * 1e3)
    results: dict[str, dict[str, dict[str, float]]] = {}
    for (key, operation), kept in times.items():
        results.setdefault(key, {})[operation] = {
            name: round(statistics.median(values), 3) for name, values in kept.items()
        }
    return results


def _capture(folder: Path, steps: int, side: int) -> dict[str, float]:
    plan = [{"kind": "sample", "camera": "cam", "exposure_s": 0.1} for _ in range(steps)]
    store = CaptureStore.create(
        folder / "real.capture.zarr",
        rig={"rig": "gonio", "program": "gonio-run"},
        backend="real",
        seed=0,
        plan=plan,
        cameras={"cam": (side, side)},
    )
    frame = np.random.default_rng(1).poisson(800, (side, side)).astype(np.uint16)
    wall, cpu = time.perf_counter(), time.process_time()
    for step in range(steps):
        store.write_frame(step, frame, FrameRecord("sample", 0.1, time.time()))
        store.mark_done(step)
    written = {
        "write_step_wall_ms": round((time.perf_counter() - wall) / steps * 1e3, 2),
        "write_step_cpu_ms": round((time.process_time() - cpu) / steps * 1e3, 2),
    }
    reopened = CaptureStore.open(folder / "real.capture.zarr")
    wall, cpu = time.perf_counter(), time.process_time()
    reopened.index("cam")
    return {
        **written,
        "read_index_wall_ms_per_step": round((time.perf_counter() - wall) / steps * 1e3, 3),
        "read_index_cpu_ms_per_step": round((time.process_time() - cpu) / steps * 1e3, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--side", type=int, default=256)
    args = parser.parse_args()
    results: dict[str, object] = {"machine": machine_description(), "side_px": args.side}
    with tempfile.TemporaryDirectory() as temporary:
        root = Path(temporary)
        results.update(_primitives(root, args.side))
        results["real capture store"] = {
            "steps": args.steps,
            **_capture(root, args.steps, args.side),
        }
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
