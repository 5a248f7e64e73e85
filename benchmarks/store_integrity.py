"""What the stores' checksums cost: capture stores written and read with and without the crc32c
codec, and the integrity check. Prints JSON.

For each frame size (``--sizes``; 2048 is the CoolSNAP K4's full frame, 256 the twin's demo
window) a capture store of ``--frames`` raw frames (12-bit sensor-like data: dark offset, a
smooth signal and its shot noise) is written through :class:`hwbridge.store.CaptureStore`
(``write_frame`` and ``mark_done`` per step, index included), read back (``read_frames``, which
also checks each frame's chunk exists) and checked (:meth:`CaptureStore.check`: checksums over the
compressed bytes; for a store without checksums every chunk is decoded instead). "Without" swaps
the codec chain of new arrays for Zarr's default (Zstd alone), as stores were before checksums.
The two kinds of store are written and read interleaved frame by frame, so that other load on a
shared machine hits both alike; each timing is the median of ``--repeats`` such rounds, as wall
time and as CPU time of this process. The files stay in the page cache (no fsync), so the times
are those of compression, checksums and file system calls, not of a disk.

With ``--pipeline`` it also times the demo-size gonio measurement run (20 direction pairs at 256
px, 64 spp, 33 bands; captured once, with checksums: rendering dominates it and varies by about
10 % from run to run, far more than the checksums cost), the writing of its frames and index into
a store with and one without checksums (the store's share of the capture), the processing of each
into a 64^2-texel BTF (a synthetic linear calibration, as in ``benchmarks.distributed_capture``;
``--repeats`` times, alternately) and the integrity check that ``spectwin process`` runs first.
About 5 minutes on 2 cores.

Run: .venv/bin/python -m benchmarks.store_integrity [--frames N] [--sizes 2048 256] [--pipeline]
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import statistics
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from zarr.codecs import ZstdCodec

import hwbridge.store
import recon.btf.store
from benchmarks.common import machine_description, peak_rss_mib
from hwbridge.schema import GonioRigAttrs
from hwbridge.store import CaptureStore, FrameRecord


@contextlib.contextmanager
def checksums(enabled: bool) -> Iterator[None]:
    """New stores with the crc32c codec (as spectwin makes them) or without (as before)."""
    modules = (hwbridge.store, recon.btf.store)
    original = [module.checksummed_compressors for module in modules]
    if not enabled:
        for module in modules:
            module.checksummed_compressors = lambda: (ZstdCodec(level=0, checksum=False),)
    try:
        yield
    finally:
        for module, function in zip(modules, original, strict=True):
            module.checksummed_compressors = function


def _frames(count: int, side: int, seed: int = 0) -> np.ndarray:
    """``count`` 12-bit frames: offset 100 DN, a smooth signal of 500-3000 e-, shot noise."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:side, 0:side] / side
    signal = 500 + 2500 * (0.5 + 0.5 * np.sin(6 * x) * np.cos(4 * y))
    frames = np.empty((count, side, side), np.uint16)
    for index in range(count):
        frames[index] = np.clip(100 + rng.poisson(signal * (0.8 + 0.4 * rng.random())), 0, 4095)
    return frames


def _timed(function) -> float:
    started = time.perf_counter()
    function()
    return time.perf_counter() - started


def _wall_and_cpu(function) -> tuple[float, float]:
    """Wall time and CPU time (all threads of this process) of ``function()``."""
    wall, cpu = time.perf_counter(), time.process_time()
    function()
    return time.perf_counter() - wall, time.process_time() - cpu


def _write(store: CaptureStore, step: int, frame: np.ndarray, record: FrameRecord) -> None:
    store.write_frame(step, frame, record)
    store.mark_done(step)


def _store_round(root: Path, frames: np.ndarray, run: int) -> dict[bool, dict[str, float]]:
    """One store of each kind written and read frame by frame, the two kinds interleaved frame by
    frame (so that other load on the machine hits both alike), then each checked."""
    count, side = frames.shape[0], frames.shape[1]
    plan = [{"camera": "k4", "kind": "dark", "exposure_s": 0.1}] * count
    stores, paths = {}, {}
    for enabled in (False, True):
        paths[enabled] = root / f"{'crc' if enabled else 'plain'}_{side}_{run}.capture.zarr"
        with checksums(enabled):
            stores[enabled] = CaptureStore.create(
                paths[enabled],
                rig={},
                backend="sim",
                seed=0,
                plan=plan,
                cameras={"k4": (side, side)},
            )
    times = {
        enabled: dict.fromkeys(("write_s", "write_cpu_s", "read_s", "read_cpu_s"), 0.0)
        for enabled in (False, True)
    }

    def add(enabled: bool, kind: str, function) -> None:
        wall, cpu = _wall_and_cpu(function)
        times[enabled][f"{kind}_s"] += wall
        times[enabled][f"{kind}_cpu_s"] += cpu

    for step in range(count):
        record = FrameRecord("dark", 0.1, float(step))
        for enabled in (False, True) if step % 2 else (True, False):
            add(
                enabled,
                "write",
                functools.partial(_write, stores[enabled], step, frames[step], record),
            )
    reopened = {enabled: CaptureStore.open(path) for enabled, path in paths.items()}
    for step in range(count):
        for enabled in (False, True) if step % 2 else (True, False):
            add(enabled, "read", functools.partial(reopened[enabled].read_frames, "k4", [step]))
    for enabled in (False, True):
        report = None

        def check(store=reopened[enabled]):
            nonlocal report
            report = store.check()

        times[enabled]["check_s"] = _timed(check)
        assert report.healthy and report.checksums == ("yes" if enabled else "no")
        times[enabled]["bytes"] = sum(
            file.stat().st_size for file in (paths[enabled] / "frames").rglob("*")
        )
    return times


def store_benchmark(root: Path, count: int, side: int, repeats: int) -> dict[str, object]:
    frames = _frames(count, side)
    rounds: dict[bool, list[dict[str, float]]] = {True: [], False: []}
    for run in range(repeats):
        for enabled, times in _store_round(root, frames, run).items():
            rounds[enabled].append(times)
    result: dict[str, object] = {"frames": count, "frame_px": [side, side]}
    for enabled, name in ((False, "without_checksums"), (True, "with_checksums")):
        medians = {
            key: statistics.median(r[key] for r in rounds[enabled]) for key in rounds[enabled][0]
        }
        result[name] = {
            "write_s": round(medians["write_s"], 3),
            "write_cpu_s": round(medians["write_cpu_s"], 3),
            "read_s": round(medians["read_s"], 3),
            "read_cpu_s": round(medians["read_cpu_s"], 3),
            "check_s": round(medians["check_s"], 3),
            "frames_mib": round(medians["bytes"] / 2**20, 2),
            "write_ms_per_frame": round(1000 * medians["write_s"] / count, 2),
            "read_ms_per_frame": round(1000 * medians["read_s"] / count, 2),
        }
    plain, crc = result["without_checksums"], result["with_checksums"]
    result["overhead_pct"] = {
        key: round(100 * (crc[key] / plain[key] - 1), 1)
        for key in ("write_s", "write_cpu_s", "read_s", "read_cpu_s")
    }
    result["check_vs_read_pct"] = round(100 * crc["check_s"] / crc["read_s"], 1)
    return result


def _copy_capture(source: CaptureStore, path: Path, enabled: bool) -> CaptureStore:
    """``source`` written again step by step into a new store with or without checksums."""
    attrs = source.attrs
    camera = attrs["plan"][0]["camera"]
    frames = source.frames(camera)
    index = source.index(camera)
    with checksums(enabled):
        copy = CaptureStore.create(
            path,
            rig=attrs["rig"],
            backend=attrs["backend"],
            seed=attrs["seed"],
            plan=attrs["plan"],
            cameras={camera: frames.shape[1:]},
            monitor_samples=index["lamp_monitor"].shape[1] if "lamp_monitor" in index else 0,
        )
    for step in range(frames.shape[0]):
        record = FrameRecord(
            kind=str(index["kind"][step]),
            exposure_s=float(index["exposure_s"][step]),
            timestamp=float(index["timestamp"][step]),
            light_id=int(index["light_id"][step]),
            view_id=int(index["view_id"][step]),
            band_nm=float(index["band_nm"][step]),
            status=str(index["status"][step]),
            pose=tuple(index["pose"][step]),
            lamp_monitor=None if index["kind"][step] == "dark" else index["lamp_monitor"][step],
        )
        copy.write_frame(step, frames[step], record)
        copy.mark_done(step)
    return copy


def pipeline_benchmark(root: Path, repeats: int) -> dict[str, object]:
    """The demo-size run captured once (with checksums), its frames written again into a store
    with and one without checksums (the store's share of a capture), each processed
    ``repeats`` times, alternately."""
    from recon.btf.processing import process_gonio
    from recon.calibration.gonio import GonioCalibration
    from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
    from twin.components.lctf import LiquidCrystalTunableFilter
    from twin.gonio.capture import run_gonio_measurement
    from twin.render.variant import activate
    from twin.rigs.rig_config import load_rig
    from twin.studies.demo import DEMO_RINGS

    variant = activate().as_dict()["variant"]
    config = load_rig("gonio")
    bands = np.asarray(LiquidCrystalTunableFilter.varispec(config.camera.filter).band_centres_nm)
    exposures = np.full(bands.size, 6 * HMI_FLICKER_PERIOD_S)
    calibration = GonioCalibration.identity(exposures, bands, HMI_FLICKER_PERIOD_S)
    captured = root / "run.capture.zarr"
    capture_s, capture_cpu_s = _wall_and_cpu(
        lambda: run_gonio_measurement(captured, exposures, rings=DEMO_RINGS)
    )
    source = CaptureStore.open(captured)
    result: dict[str, object] = {
        "variant": variant,
        "pairs": len(source.rig_attrs(GonioRigAttrs).light_dirs),
        "frames": source.frames("k4").shape[0],
        "frame_px": list(source.frames("k4").shape[1:]),
        "capture_with_checksums_s": round(capture_s, 2),
        "capture_with_checksums_cpu_s": round(capture_cpu_s, 2),
    }
    stores, timings = {}, {}
    for enabled in (False, True):
        name = "with_checksums" if enabled else "without_checksums"
        path = root / f"{name}.capture.zarr"
        write_s, write_cpu_s = _wall_and_cpu(
            lambda p=path, e=enabled: stores.__setitem__(e, _copy_capture(source, p, e))
        )
        timings[name] = {"store_write_s": write_s, "store_write_cpu_s": write_cpu_s}
        timings[name]["check_s"] = _timed(stores[enabled].check)
    runs: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
    for run in range(repeats):
        for enabled in (False, True):
            btf = root / f"{'crc' if enabled else 'plain'}_{run}.btf.zarr"
            with checksums(enabled):
                runs[enabled].append(
                    _wall_and_cpu(
                        lambda b=btf, e=enabled: process_gonio(stores[e], calibration, b, texels=64)
                    )
                )
    for enabled in (False, True):
        name = "with_checksums" if enabled else "without_checksums"
        result[name] = {
            "store_write_s": round(timings[name]["store_write_s"], 2),
            "store_write_cpu_s": round(timings[name]["store_write_cpu_s"], 2),
            "check_s": round(timings[name]["check_s"], 3),
            "process_s": round(statistics.median(wall for wall, _ in runs[enabled]), 2),
            "process_cpu_s": round(statistics.median(cpu for _, cpu in runs[enabled]), 2),
        }
    plain, crc = result["without_checksums"], result["with_checksums"]
    result["overhead_pct"] = {
        "process": round(100 * (crc["process_s"] / plain["process_s"] - 1), 1),
        "process_cpu": round(100 * (crc["process_cpu_s"] / plain["process_cpu_s"] - 1), 1),
        "store_write_cpu_of_capture_cpu": round(
            100 * (crc["store_write_cpu_s"] - plain["store_write_cpu_s"]) / capture_cpu_s, 2
        ),
        "check_of_process": round(100 * crc["check_s"] / crc["process_s"], 1),
    }
    return result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=32, help="frames per store (2048 px)")
    parser.add_argument("--sizes", type=int, nargs="*", default=[2048, 256])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--pipeline", action="store_true", help="also the demo-size run")
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    arguments = parser.parse_args()
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-bench-"))
    results: dict[str, object] = {"machine": machine_description()}
    for side in arguments.sizes:
        # As many frames of a small size as make the same number of pixels, at most 1024.
        count = min(1024, arguments.frames * max(1, (2048 // side) ** 2 // 8))
        results[f"store_{side}px"] = store_benchmark(root, count, side, arguments.repeats)
    if arguments.pipeline:
        results["demo_pipeline"] = pipeline_benchmark(root, arguments.repeats)
    results["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
