"""What ``spectwin store check`` costs on a large store of each kind. Prints JSON.

A capture store of ``--frames`` small raw frames (``--side`` px, one camera, a simulated
backend: frames written in runs of 64 steps as a session writes them, index and flags
included) and a BTF store of ``--pairs`` direction pairs (the full glossy gonio sampling has
3192) of ``--texels`` texels and 33 bands, written pair by pair. Each is then opened and
checked (:meth:`hwbridge.store.CaptureStore.check`, :meth:`recon.btf.store.BTFStore.check`, what
``spectwin store check`` runs) ``--repeats`` times; the medians are printed, wall time and CPU
time of this process. The files stay in the page cache (no fsync).

Run: .venv/bin/python -m benchmarks.store_check [--frames 3192] [--pairs 3192]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from hwbridge.store import CaptureStore, FrameRecord
from recon.btf.store import BTFStore
from recon.spectra import DEFAULT_GRID

_RUN = 64  # steps a session writes at once


def _medians(function: Callable[[], object], repeats: int) -> dict[str, float]:
    """Median wall and CPU time of ``function()`` over ``repeats`` calls."""
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        function()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return {"s": round(statistics.median(walls), 3), "cpu_s": round(statistics.median(cpus), 3)}


def capture_store(path: Path, frames: int, side: int) -> tuple[CaptureStore, float]:
    """A complete simulated capture store of ``frames`` noisy frames, and its writing time."""
    rng = np.random.default_rng(0)
    plan = [{"camera": "k4", "kind": "sample", "exposure_s": 0.1}] * frames
    started = time.perf_counter()
    store = CaptureStore.create(
        path, rig={}, backend="sim", seed=0, plan=plan, cameras={"k4": (side, side)}
    )
    for start in range(0, frames, _RUN):
        steps = list(range(start, min(start + _RUN, frames)))
        stack = rng.integers(100, 4000, (len(steps), side, side)).astype(np.uint16)
        store.write_frames(steps, list(stack))
        store.write_index(steps, [FrameRecord("sample", 0.1, float(step)) for step in steps])
        store.mark_done(steps)
    return store, time.perf_counter() - started


def btf_store(path: Path, pairs: int, texels: int) -> tuple[BTFStore, float]:
    """A complete BTF store of ``pairs`` random textures, and its writing time."""
    rng = np.random.default_rng(0)
    theta = np.linspace(0.0, 1.2, pairs)
    directions = np.stack([np.sin(theta), np.zeros(pairs), np.cos(theta)], axis=1)
    started = time.perf_counter()
    store = BTFStore.create(
        path,
        light_dirs=directions,
        view_dirs=directions[::-1],
        texels=texels,
        grid=DEFAULT_GRID,
        material="benchmark",
    )
    for pair in range(pairs):
        store.write_pair(pair, rng.uniform(0.0, 1.0, (texels, texels, DEFAULT_GRID.size)))
    return store, time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=3192)
    parser.add_argument("--side", type=int, default=32, help="frame side, px")
    parser.add_argument("--pairs", type=int, default=3192)
    parser.add_argument("--texels", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    arguments = parser.parse_args()
    root = Path(tempfile.mkdtemp(prefix="spectwin-check-"))
    capture, capture_write_s = capture_store(
        root / "run.capture.zarr", arguments.frames, arguments.side
    )
    btf, btf_write_s = btf_store(root / "run.btf.zarr", arguments.pairs, arguments.texels)
    for report in (capture.check(), btf.check()):
        assert report.healthy and report.complete, report.damage()
    results = {
        "machine": machine_description(),
        "capture": {
            "frames": arguments.frames,
            "frame_px": arguments.side,
            "write_s": round(capture_write_s, 2),
            "open": _medians(lambda: CaptureStore.open(capture.path), arguments.repeats),
            "open_and_check": _medians(
                lambda: CaptureStore.open(capture.path).check(), arguments.repeats
            ),
        },
        "btf": {
            "pairs": arguments.pairs,
            "texels": arguments.texels,
            "write_s": round(btf_write_s, 2),
            "open": _medians(lambda: BTFStore.open(btf.path), arguments.repeats),
            "open_and_check": _medians(lambda: BTFStore.open(btf.path).check(), arguments.repeats),
        },
        "peak_rss_mib": peak_rss_mib(),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
